//! A first block far off the rest of the run (the record's `first_block`: docs/records.md,
//! docs/gap.md "A first block far off (session 45)"), in words a person signs; the terminal
//! table (sink::table) and the report (sink::report) say it through [`first_block_words`], so
//! a start-up transient too short to name as a warm-up is not seen only in the JSON.

use crate::gap::record::DiagnosisRecord;
use crate::sink::effect_text::rate_words;

/// `the block from 0 s to 8.19 s averages 1.20 u/s above the rest of the run (p 0.001): a
/// start-up transient or one block's excursion of slower noise, too short to name as a
/// warm-up`, or `None` when the record has no
/// `first_block`. `unit` is the channel's unit; `number` formats a value.
pub fn first_block_words(
    d: &DiagnosisRecord,
    unit: &str,
    number: &dyn Fn(f64) -> String,
) -> Option<String> {
    let b = d.first_block?;
    Some(format!(
        "the block from {} s to {} s averages {} {} the rest of the run (p {}): a start-up \
         transient or one block's excursion of slower noise, too short to name as a warm-up",
        number(b.start_s),
        number(b.start_s + b.seconds),
        rate_words(b.offset.abs(), unit, number),
        if b.offset >= 0.0 { "above" } else { "below" },
        number(b.p_value)
    ))
}
