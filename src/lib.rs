//! allanscope: live, exact Allan-family statistics for inertial sensors on a test stand.
//!
//! # Layout
//!
//! The modules follow the flow of data, one stage each, and name the type that crosses
//! each boundary:
//!
//! ```text
//! source (file, stdin, serial, udp)                       bytes            (tokio tasks)
//!   -> frame (descriptor, decoder) | input (text columns)  bytes -> Chunk  (decode thread)
//!   -> analysis: one run, per channel       Chunk -> ChannelReport -> records (worker threads)
//!        allan (accumulators, batch reference, edf, noise id)   samples -> Curve
//!        model (terms, covariance, fit, aggregate, limits)      Curve -> FitResult
//!        gap (evidence, effects, diagnosis)                     increments -> Diagnosis
//!   -> sink (typed JSON-lines records, plot, report, table, metrics, export)  records -> bytes
//! pipeline: the threads and bounded channels between those stages, back-pressure, and
//!   checkpointing (checkpointing.rs: the schedule and the collector threads; checkpoint.rs: the
//!   file: header, atomic write, fingerprint, resume checks); run_frames_async /
//!   run_text_async in the caller's tokio runtime, stopped by its token
//! sim (model files, generators, capture writer)           model file -> capture
//! stand (the stand config of `run`: one unit, or several) TOML -> StandConfig
//! plan: the checked plan of a run (RunPlan of UnitPlans: input, channels, analysis options,
//!   checkpoint setup), from a stand config or the command line; option values (`FromStr`)
//! stats: the chi-squared quantile behind every interval
//! toml_check: the one error collector of every TOML file read (file, line, key, problem)
//! ranges: the bounds every user-given number is checked against where it is parsed, and the
//!   largest sample accepted
//! error: the errors that reach the user and their exit statuses
//! ```
//!
//! Dependencies point one way. A module uses (names `crate::X` of) only modules listed below it
//! here; the `layout_check` test reads the sources and fails on a use against this order, on an
//! import cycle, and on a module missing from the list:
//!
//! ```text
//! Dependencies (users first):
//! plan: builds the run's pipeline inputs and its checkpoint setup
//! pipeline: runs analysis, source, sink; owns the checkpoint file format
//! analysis: drives allan, model, gap; yields typed ChannelReports and sink's records
//! stand: reads the stand config (frame descriptors, sources)
//! source: bytes in (writes a capture through sink)
//! sink: the typed records and what is made of them
//! gap: the diagnosis (simulates with sim)
//! sim: model files and generators
//! input: text columns into chunks (of frame events too)
//! frame: descriptors and decoder
//! model: the five-term model, its fit, units and limits
//! allan: the accumulators and curves
//! stats: the chi-squared quantile
//! toml_check: the TOML error collector
//! error: user-facing errors
//! ranges: bounds of numbers
//! ```
//!
//! The command line is not part of the library: `src/cli/` (one file per subcommand, clap) is a
//! module of the `allanscope` binary (`src/main.rs`), which also owns the process: signals and
//! `--duration` (`cli/process.rs`), the progress bar, the crash test hook, the descriptor search
//! path and the exit statuses. Cargo features `cli`, `serial` and `plot` (default on) pull in
//! clap, indicatif, tokio-serial and plotters; the library builds without them
//! (`--no-default-features`), and `examples/embed.rs` runs the pipeline in a program's own
//! runtime.
//!
//! Numerical stages (`allan`, `model`, `gap`, `sim`) are plain synchronous code: they never know
//! where samples came from and never await. I/O lives at the edges (`source`, `input`, `sink`,
//! and the binary's `cli`); `pipeline` connects them with bounded crossbeam channels.
#![forbid(unsafe_code)]

pub mod allan;
pub mod analysis;
pub mod error;
pub mod frame;
pub mod gap;
pub mod input;
pub mod model;
pub mod pipeline;
pub mod plan;
pub mod ranges;
pub mod sim;
pub mod sink;
pub mod source;
pub mod stand;
pub mod stats;
pub mod toml_check;

#[cfg(test)]
mod layout_check;
