//! The command-line binary end to end (`analyze`, `diagnose` and its `--model-out`, `aggregate`, `limits`), run as a
//! child process and its JSON lines parsed back.
//! One test binary per stage; each topic is a module of it.

#[path = "../common/mod.rs"]
mod common;

mod aggregate;
mod analyze;
mod diagnose;
mod export;
mod format_units;
mod header_units;
mod limits_summary;
mod malformed;
mod model_out;
mod odd_inputs;
mod outputs;
mod plot_report;
mod scratch;
mod stop;
mod terminal;
mod text_input;
