//! The Allan-family statistics (src/allan/): streaming accumulators against batch formulas and
//! published tables, precision, edf and noise identification.
//! One test binary per stage; each topic is a module of it.

#[path = "../common/mod.rs"]
mod common;

mod edf_choice;
mod edf_stable32;
mod noise_id;
mod precision;
mod stable32;
mod streaming;
