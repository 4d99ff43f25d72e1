//! The sim-to-real gap (SEED.md, "The gap they left open"; THEORY.md sections 3-5): where a
//! channel's measured Allan curve departs from the fitted five-term model, which effect closes
//! the departure, and by how much.
//!
//! Layout: [`evidence`] gathers, in one streaming pass over increments, the dense AVAR curve,
//! per-segment curves and block means ([`GapEvidence`]); [`effects`] holds the candidate effects
//! and their AVAR columns; [`diagnose`](mod@diagnose) fits them and decides ([`Diagnosis`]); [`record`]
//! writes CONTRACT.md's `diagnosis` record. Everything is pure and synchronous.
//!
//! Wiring: feed a [`GapEvidence`] (from [`GapConfig::new`], with `expected_increments` when the
//! run length is known) with `push_increment` / `push_gap`; at the end (or any time) call
//! `snapshot()`, then [`diagnose::diagnose`], and [`record::DiagnosisRecord::new`]; with a
//! held-out run, [`diagnose::holdout_gap`] on its snapshot.

pub mod diagnose;
pub mod effects;
pub mod evidence;
pub mod lsb;
pub mod oracle;
pub mod record;
pub mod unit_model;

pub use diagnose::{diagnose, holdout_gap, DiagnoseOptions, Diagnosis, Thresholds, Verdict};
pub use effects::{EffectKind, EffectParams};
pub use evidence::{EvidenceSnapshot, GapConfig, GapEvidence};
pub use record::DiagnosisRecord;
