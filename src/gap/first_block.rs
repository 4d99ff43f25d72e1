//! A first block far off the rest of the run: a start-up transient that decays within the
//! block tests' first block, or one block's excursion of slower noise, which the block cannot
//! tell apart (docs/gap.md, "A first block far off (session 45)").
//!
//! The warm-up test scans its time constant from half a block up, and a warm-up found at that
//! edge is not named: it shows in the first block mean alone, so only the product of its
//! amplitude and time constant is measured, and one block's excursion of the noise looks the
//! same ("A warm-up at the scan's edge (session 43)"). The block mean itself is still measured
//! and still far off, which a person signing the run wants to see: the record's `first_block`
//! says where that block lies, how far its mean departs from the blocks after it and at what
//! p-value, and names no effect.

use super::warmup::WarmupFinding;

/// Blocks after the first whose mean the first block's is compared with.
pub const NEXT_BLOCKS: usize = 4;

/// The record's `first_block` object.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FirstBlock {
    /// Where the block begins, s from the start of the run (the block tests leave out short
    /// blocks at the start).
    pub start_s: f64,
    /// The block's length, s.
    pub seconds: f64,
    /// How far the block's mean rate departs from the mean of the [`NEXT_BLOCKS`] blocks after
    /// it (fewer when the run has fewer), u/s: measured, not the fitted transient's, whose
    /// amplitude and time constant the one block cannot tell apart (an exponential at half a
    /// block puts 13% of its area in the second block, and the fit took 1.03 of a first block
    /// raised by 1.2 alone).
    pub offset: f64,
    /// The warm-up test's p-value on this run's own null ([`WarmupFinding::p_value`]).
    pub p_value: f64,
}

impl FirstBlock {
    /// The first of `block_means` (rate, u/s; blocks `block_s` long, the first beginning
    /// `start_s` into the run) when the warm-up test found `w` at its scan's edge; `None` with
    /// fewer than two blocks.
    pub fn from_edge_warmup(
        w: &WarmupFinding,
        block_means: &[f64],
        block_s: f64,
        start_s: f64,
    ) -> Option<Self> {
        let (&first, rest) = block_means.split_first()?;
        let next = &rest[..rest.len().min(NEXT_BLOCKS)];
        if next.is_empty() {
            return None;
        }
        let after = next.iter().sum::<f64>() / next.len() as f64;
        Some(FirstBlock {
            start_s,
            seconds: block_s,
            offset: first - after,
            p_value: w.p_value,
        })
    }
}
