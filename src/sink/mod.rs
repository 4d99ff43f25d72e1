//! Where results go: JSON-lines records (docs/records.md) to standard output or a file.
//!
//! [`records`] defines the records as typed structs (the contract's field names, units in
//! their doc comments); [`json`] writes them one per line.

pub mod export;
pub mod json;
pub mod metrics;
pub mod output;
pub mod plot;
pub mod records;
pub mod report;
