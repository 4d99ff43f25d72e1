//! Inputs that are not frames: text columns (docs/records.md, "Text columns").
//!
//! A reader turns bytes into [`Chunk`]s of rows; it knows nothing of statistics.

pub mod text;
pub mod time_column;

use crate::frame::{FrameBlock, FrameEvent};

/// Largest magnitude accepted for a sample (an increment, rate or phase, in the channel's
/// unit); anything larger, and any infinite value, is invalid: counted (`invalid_values`) and
/// taken as a gap, like a NaN. It is far above any sensor's output (a phase of 1e15 counts is
/// 30 years of a 1 MHz counter) and keeps every sum the accumulators form finite: a square is
/// at most 1e30, a run of 1e12 of them 1e42, against f64's 1.8e308. One `inf` or `1e308` would
/// otherwise turn every sigma of its channel into NaN and drop its fit.
pub const MAX_ABS_VALUE: f64 = 1e15;

/// `v` when it is a usable sample; `None` when it is infinite or beyond [`MAX_ABS_VALUE`]
/// (NaN, a marked gap, is passed through).
#[inline]
pub fn plausible(v: f64) -> Option<f64> {
    (v.abs() <= MAX_ABS_VALUE || v.is_nan()).then_some(v)
}

/// What an input stage hands to the analysis: a batch of steps.
#[derive(Debug, Clone)]
pub enum Chunk {
    /// Row-major values, `width` per row, one row per step; NaN marks a missing value.
    Rows { values: Vec<f64>, width: usize },
    /// Decoded frames and the gaps between them.
    Frames(Vec<FrameEvent>),
    /// The same, flat (what the pipeline's decode thread sends: no allocation per frame).
    Block(FrameBlock),
    /// A checkpoint mark (its sequence number): every step before it has been sent, none after
    /// it; the analysis saves its state here (`crate::checkpoint`).
    Checkpoint(u64),
}
