//! cargo-fuzz target: [`harness::configs`] (the entry points and what they check are in harness.rs).
#![no_main]

#[path = "../harness.rs"]
mod harness;

libfuzzer_sys::fuzz_target!(|data: &[u8]| harness::configs(data));
