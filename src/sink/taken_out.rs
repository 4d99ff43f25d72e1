//! What a diagnosis took out of a channel's evidence before it computed the curve, in words a
//! person signs: the outliers replaced (docs/gap.md, "Outliers") and the stretches where the
//! channel did not move, taken out as gaps ("Stuck stretches"). The records hold them
//! (`outliers`, `stuck`: docs/records.md); the terminal table (sink::table) and the report
//! (sink::report) say them through [`taken_out_words`], so a reader sees that data were set
//! aside without opening the JSON.

use crate::gap::record::DiagnosisRecord;
use crate::sink::effect_text::rate_words;

/// `3 outliers replaced (rms 2.10 deg/h (5.83e-4 deg/s), the largest ...); 1 stuck stretch
/// taken out as a gap (60.0 s in all, the longest 60.0 s, the first at 600 s)`, or `None` when
/// nothing was taken out. `unit` is the channel's unit; `number` formats a value.
pub fn taken_out_words(
    d: &DiagnosisRecord,
    unit: &str,
    number: &dyn Fn(f64) -> String,
) -> Option<String> {
    let mut parts = Vec::new();
    let o = &d.outliers;
    if o.count > 0 && o.heavy_tail {
        parts.push(format!(
            "a heavy-tailed white noise, not glitches: {} sample{} beyond 6 standard deviations \
             (replaced; rms {}, the largest {}) and {} between 4 and 6 where a normal law gives \
             {}",
            o.count,
            if o.count == 1 { "" } else { "s" },
            rate_words(o.rms_size, unit, number),
            rate_words(o.max_size, unit, number),
            o.shoulder,
            number(o.shoulder_normal)
        ));
    } else if o.count > 0 {
        parts.push(format!(
            "{} outlier{} replaced (rms {}, the largest {})",
            o.count,
            if o.count == 1 { "" } else { "s" },
            rate_words(o.rms_size, unit, number),
            rate_words(o.max_size, unit, number)
        ));
    }
    if let Some(s) = &d.stuck {
        let one = s.stretches == 1;
        parts.push(format!(
            "{} stuck stretch{} taken out as {} ({} s in all, {}the first at {} s)",
            s.stretches,
            if one { "" } else { "es" },
            if one { "a gap" } else { "gaps" },
            number(s.seconds),
            if one {
                String::new()
            } else {
                format!("the longest {} s, ", number(s.longest_s))
            },
            number(s.first_at_s)
        ));
    }
    (!parts.is_empty()).then(|| parts.join("; "))
}
