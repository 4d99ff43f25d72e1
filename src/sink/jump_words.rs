//! The bias jumps a diagnosis named (the record's `jumps`: docs/records.md), in words: when each
//! happened, its size in the channel's datasheet unit beside u/s, and how plainly the search saw
//! it (its z score). The `bias_jumps` effect gives only their count and rms size; a test engineer
//! wants to look at the run where the unit stepped. The terminal table (sink::table) and the
//! report (sink::report) both say them through [`jump_words`].

use crate::gap::record::DiagnosisRecord;
use crate::sink::effect_text::rate_words;

/// Steps listed one by one; past these, the rest are counted.
const LISTED: usize = 5;

/// `jumps (times to within 40 s): at 6000 s, +30 micro-g (2.94e-4 m/s^2), z 7.9; at ...`, or
/// `None` when no jump was named. `unit` is the channel's unit; `number` formats a value.
pub fn jump_words(
    d: &DiagnosisRecord,
    unit: &str,
    number: &dyn Fn(f64) -> String,
) -> Option<String> {
    let j = d.jumps.as_ref().filter(|j| !j.steps.is_empty())?;
    let mut parts: Vec<String> = j
        .steps
        .iter()
        .take(LISTED)
        .map(|s| {
            let sign = if s.size >= 0.0 { "+" } else { "" };
            let z = if s.z.is_finite() {
                format!(", z {:.1}", s.z)
            } else {
                String::new()
            };
            format!(
                "at {} s, {sign}{}{z}",
                number(s.time_s),
                rate_words(s.size, unit, number)
            )
        })
        .collect();
    if j.steps.len() > LISTED {
        parts.push(format!("and {} more", j.steps.len() - LISTED));
    }
    Some(format!(
        "jump{} (times to within {} s): {}",
        if j.steps.len() == 1 { "" } else { "s" },
        number(j.block_s),
        parts.join("; ")
    ))
}
