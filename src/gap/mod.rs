//! The sim-to-real gap (the seed paper, docs/theory.md section 6; docs/theory.md sections 3-5): where a
//! channel's measured Allan curve departs from the fitted five-term model, which effect closes
//! the departure, and by how much.
//!
//! Layout: [`evidence`] gathers, in one streaming pass over increments, the dense AVAR curve,
//! per-segment curves and block means ([`GapEvidence`]); [`effects`] holds the candidate effects
//! and their AVAR columns; [`problem`] is the GLS fit on the curve ([`filter_cov`]: its covariance
//! with an output filter), [`block_cov`] the noise model
//! of the time-domain tests [`warmup`] and [`steps`] ([`jump_mixture`]: statistics measured and
//! not adopted); [`segments`] tests homogeneity in time; [`diagnose`](mod@diagnose) orchestrates
//! them and decides ([`Diagnosis`]) by [`thresholds`]; [`holdout`] judges a held-out run;
//! [`oracle`] bounds what any test could do; [`quant_limit`] tells a unit whose coarse LSB
//! is not white phase noise; [`limit_cycle`] tells a named line that is the counter's limit
//! cycle, [`sawtooth`] carries the counter's whole sawtooth in the base model; [`record`]
//! writes docs/records.md's `diagnosis` record;
//! [`unit_model`] turns a diagnosis into the simulator model of the fitted unit (with the LSB
//! that [`lsb`] reads off the values).
//! Everything is pure and synchronous.
//!
//! Wiring: feed a [`GapEvidence`] (from [`GapConfig::new`], with `expected_increments` when the
//! run length is known) with `push_increment` / `push_gap`; at the end (or any time) call
//! `snapshot()`, then [`diagnose::diagnose`], and [`record::DiagnosisRecord::new`]; with a
//! held-out run, [`holdout::holdout_gap`] on its snapshot.

pub mod alternatives;
pub mod band_noise;
pub mod block_cov;
pub mod column_memo;
pub mod diagnose;
pub mod discrepancy;
pub mod effects;
pub mod ensemble;
pub mod evidence;
pub mod filter_cov;
pub mod filter_scan;
pub mod filter_shape;
pub mod first_block;
pub mod holdout;
pub mod intervals;
pub mod jump_mixture;
pub mod k_profile;
pub mod limit_cycle;
pub mod lsb;
pub mod oracle;
pub mod outliers;
pub mod problem;
pub mod quant_limit;
pub mod quantization;
pub mod record;
pub mod rounding;
pub mod sawtooth;
pub mod segments;
pub(crate) mod simplex;
pub mod step_null;
pub mod steps;
pub mod stuck;
pub mod temperature;
pub mod temperature_check;
pub mod thresholds;
pub mod unit_model;
pub mod warmup;
pub mod warmup_profile;

pub use diagnose::{diagnose, DiagnoseOptions, Diagnosis, Verdict};
pub use effects::{EffectKind, EffectParams};
pub use evidence::{EvidenceSnapshot, GapConfig, GapEvidence};
pub use holdout::{holdout_gap, holdout_gap_with_temperature};
pub use record::DiagnosisRecord;
pub use thresholds::Thresholds;
