//! Text-column input (work in progress).
