//! The Allan family: overlapping Allan (AVAR), overlapping Hadamard (HVAR) and modified Allan
//! (MVAR) variances (docs/theory.md section 1), streamed sample by sample, with their degrees of
//! freedom and confidence intervals (docs/theory.md section 4).
//!
//! This stage is pure: it takes increments or phase points and knows nothing about where they
//! came from. [`accum`] holds the streaming accumulators, [`batch`] the textbook formulas they
//! are tested against, [`edf`] Greenhall's equivalent degrees of freedom and the chi-squared
//! intervals, [`noise_id`] the per-tau power-law noise identification.

pub mod accum;
pub mod batch;
pub mod curve;
pub mod edf;
pub mod noise_id;

use serde::{Deserialize, Serialize};

/// One statistic of the Allan family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Stat {
    /// Overlapping Allan variance, second differences of phase.
    Avar,
    /// Overlapping Hadamard variance, third differences of phase.
    Hvar,
    /// Modified Allan variance, second differences of phase averaged over `m`.
    Mvar,
}

impl Stat {
    pub const ALL: [Stat; 3] = [Stat::Avar, Stat::Hvar, Stat::Mvar];

    pub fn name(self) -> &'static str {
        match self {
            Stat::Avar => "avar",
            Stat::Hvar => "hvar",
            Stat::Mvar => "mvar",
        }
    }

    /// Order `d` of the phase difference (Greenhall and Riley 2003): 2 for AVAR and MVAR, 3 for HVAR.
    pub fn diff_order(self) -> u32 {
        match self {
            Stat::Avar | Stat::Mvar => 2,
            Stat::Hvar => 3,
        }
    }
}

/// One point of a variance curve.
#[derive(Debug, Clone, PartialEq)]
pub struct CurvePoint {
    /// Cluster size (averaging factor): `tau = m * tau0`.
    pub m: u64,
    /// Averaging time in seconds.
    pub tau_s: f64,
    /// The variance estimate in u^2/s^2.
    pub var: f64,
    /// Number of differences averaged.
    pub count: u64,
    /// Equivalent degrees of freedom (Greenhall's algorithm for `alpha`).
    pub edf: f64,
    /// Power-law noise exponent of S_y used for the edf (+2 white PM ... -2 random-walk FM).
    pub alpha: i32,
    /// 95% interval of the deviation (u/s).
    pub sigma_lo: f64,
    pub sigma_hi: f64,
    /// Step between the differences averaged: 1 at full overlap; with `--overlap L` the
    /// accumulator takes every `stride`-th difference for `m >= 2L` (docs/theory.md section 1).
    pub stride: u64,
    /// Phase points of the run the estimate was read from (Greenhall's `N`: increments + 1 per
    /// contiguous segment), for the edf and the covariance between taus.
    pub n_phase: u64,
}

impl CurvePoint {
    /// The deviation in u/s.
    pub fn sigma(&self) -> f64 {
        self.var.sqrt()
    }
}

/// A variance curve of one channel and one statistic.
#[derive(Debug, Clone, PartialEq)]
pub struct Curve {
    pub stat: Stat,
    /// Sampling step in seconds.
    pub tau0_s: f64,
    /// Seconds of data consumed (samples seen times tau0, gaps included).
    pub t_data_s: f64,
    pub points: Vec<CurvePoint>,
}
