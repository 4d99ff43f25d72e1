//! JSON-lines records (work in progress).
