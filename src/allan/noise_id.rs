//! Power-law noise identification (work in progress).
