//! allanscope: live, exact Allan-family statistics for inertial sensors on a test stand.
//!
//! # Layout
//!
//! The modules follow the flow of data, one stage each, and name the type that crosses
//! each boundary:
//!
//! ```text
//! input (text columns) / frame (descriptor, decoder)      bytes -> Sample
//!   -> allan (accumulators, batch reference, edf)         Sample -> Curve
//!   -> model (terms, fit, aggregate)                      Curve -> Fit
//!   -> sink (JSON lines)                                  Curve/Fit -> record
//! sim (noise, effects, writer)                            model file -> capture
//! source (file, stdin, serial, udp) -> pipeline (decode, analysis and writer threads)
//!                                                         bytes -> records, live or replayed
//! stand (the stand config of `run`)                       TOML -> sources, options, limits
//! ```
//!
//! Numerical stages (`allan`, `model`, `sim`) are plain synchronous code: they never know where
//! samples came from and never await. I/O lives at the edges (`input`, `frame`, `sink`, `cli`).
#![forbid(unsafe_code)]

pub mod allan;
pub mod analysis;
pub mod cli;
pub mod error;
pub mod frame;
pub mod gap;
pub mod input;
pub mod model;
pub mod pipeline;
pub mod sim;
pub mod sink;
pub mod source;
pub mod stand;
