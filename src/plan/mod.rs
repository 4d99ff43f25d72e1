//! What a run is asked to do, checked before anything starts (the way Vector turns a config
//! into a checked plan): every option parsed and in range, descriptors loaded, channels chosen,
//! checkpoints found and matched, before a byte is read or an output is touched.
//!
//! - [`run::RunPlan`]: a whole run — its units, and what the run as a whole does (duration,
//!   interim records on wall time, capture, output, metrics). Built from a stand config
//!   ([`run::RunPlan::from_stand`]); the binary builds the same units from its options.
//! - [`unit::UnitPlan`]: one unit's part — its input ([`unit::InputPlan`]: frames of a
//!   descriptor from a source, or text columns), the channels analysed, the analysis options,
//!   the checkpoint plan. `analyze`, `listen`, `run` and `diagnose` all plan their input through
//!   [`unit::UnitPlan::new`], so the same options mean the same thing in each command.
//! - [`settings::DataSettings`]: the data and analysis settings as the command line and a stand
//!   config give them, turned into the analysis options in one place.
//! - [`checkpoint_setup`]: the checkpoint header, path and resume checks of a unit.
//! - [`channels`]: the channel choice.
//! - [`options`]: the option values with `FromStr`, shared by clap and the stand config.
//!
//! A run holds a list of units: a stand config with `[[unit]]` tables describes several, each
//! with its own source, format, channels, limits and capture (one [`unit::UnitPlan`] each, named;
//! the run-wide settings stay in [`run::RunPlan`]); the commands and a one-unit config plan one.

pub mod channels;
pub mod checkpoint_setup;
pub mod options;
pub mod run;
pub mod settings;
pub mod unit;
