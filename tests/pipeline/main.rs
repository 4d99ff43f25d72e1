//! The live pipeline (src/pipeline/, src/source/, checkpoints): transports, backpressure,
//! outages, signals, damaged captures, stand configs.
//! One test binary per stage; each topic is a module of it.

#[path = "../common/mod.rs"]
mod common;

mod arbitrary_checkpoint;
mod arbitrary_text;
mod backpressure;
mod block_feed;
mod checkpoint;
mod config;
mod corruption;
mod embed;
mod fuzz_regressions;
mod live_bench;
mod serial_outage;
mod signal;
mod transports;
mod units;
