//! Where results go: JSON-lines records (docs/records.md) to standard output or a file, and the
//! figures and pages made from them.
//!
//! [`records`] defines the records as typed structs (the contract's field names, units in
//! their doc comments); [`json`] writes them one per line. [`results`] reads them back, typed
//! and labelled by run, for [`plot`] (Allan-deviation panels), [`dynamic`] (the time x tau
//! view) and [`report`] (the HTML page); [`page_file`] writes those without overwriting;
//! [`output`] opens result files, [`effect_text`] words a diagnosis's effects and
//! [`band_words`] its ensemble band, [`alternative_words`] the other explanations it found
//! about as good, [`export`] writes the noise model for other tools,
//! [`metrics`] serves live figures, [`status_area`] keeps a live run's status line under its log
//! lines. [`unit_record`] tags the records of a run of several units with their unit's name and
//! takes the tag off again for the readers.

pub mod alternative_words;
pub mod band_words;
#[cfg(feature = "plot")]
pub mod dynamic;
pub mod effect_text;
pub mod export;
pub mod filter_shape_words;
pub mod first_block_words;
pub mod json;
pub mod jump_words;
pub mod metrics;
pub mod output;
pub mod page_file;
#[cfg(feature = "plot")]
pub mod plot;
pub mod records;
#[cfg(feature = "plot")]
pub mod report;
pub mod results;
pub mod status_area;
pub mod step_change_words;
pub mod table;
pub mod taken_out;
pub mod unit_record;

/// A channel's name with its unit for a heading or caption: `g4 [arcsec]`; a name that carries
/// its own unit in brackets (a logger's `ax [m/s^2]`, whose rates were read as increments in
/// m/s) gets the increment unit said, not a second bracket: `ax [m/s^2] (u = m/s)`.
pub fn channel_with_unit(channel: &str, unit: &str) -> String {
    match crate::input::header_unit::bracketed(channel) {
        Some((_, inner)) if inner == unit => channel.to_string(),
        Some(_) => format!("{channel} (u = {unit})"),
        None => format!("{channel} [{unit}]"),
    }
}
