//! Command-line interface (work in progress).
