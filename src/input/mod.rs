//! Inputs that are not frames: text columns (docs/records.md, "Text columns").
//!
//! A reader turns bytes into [`Chunk`]s of rows; it knows nothing of statistics.

pub mod format_units;
pub mod header_unit;
pub mod lvm;
pub mod phase_hint;
pub mod px4_export;
pub mod row_ties;
pub mod sampling_step;
pub mod stamp_grid;
pub mod temperature_column;
pub mod text;
pub mod time_column;

use crate::frame::{FrameBlock, FrameEvent};

pub use crate::ranges::{plausible, MAX_ABS_VALUE};

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
    /// it; the analysis saves its state here (`crate::pipeline::checkpoint`).
    Checkpoint(u64),
}
