//! Streaming accumulators (work in progress).
