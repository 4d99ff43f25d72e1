//! The other explanations a diagnosis found about as good as its choice (the record's
//! `alternatives`: docs/gap.md, "Alternatives"), in words a person reads beside the verdict: the
//! terminal table (sink::table) and the report (sink::report) say them through
//! [`alternative_words`], so the ambiguity is not left in the JSON alone.

use crate::gap::record::{DiagnosisRecord, RecordedEffect};
use crate::sink::effect_text::{effect_bracketed, effect_parts};

/// Each alternative as the change from the chosen model and its gap, `; `-joined: `warm-up drift
/// [amplitude -271 deg/h (-271 arcsec/s), time constant 1798 s] in place of temperature
/// sensitivity (gap 1.21)`, `without Gauss-Markov ... (gap 1.04)`, `with temperature sensitivity
/// [...] (gap 0.73)`, `the five terms alone (gap ...)`; `None` when the record lists none.
/// `pair` joins a parameter's name and value, as the effects beside it are written (" " in the
/// terminal's table, " = " in the report). `unit` is the channel's unit; `number` formats a value.
pub fn alternative_words(
    d: &DiagnosisRecord,
    unit: &str,
    number: &dyn Fn(f64) -> String,
    pair: &str,
) -> Option<String> {
    let bracketed = |e: &RecordedEffect| effect_bracketed(e, unit, number, pair);
    let chosen: Vec<&RecordedEffect> = d.effects.iter().map(|e| &e.effect).collect();
    let name = |e: &RecordedEffect| effect_parts(e, unit, number).0;
    let parts: Vec<String> = d
        .alternatives
        .iter()
        .map(|a| {
            let in_alt = |k: &str| a.effects.iter().any(|e| e.kind_name() == k);
            let in_chosen = |k: &str| chosen.iter().any(|e| e.kind_name() == k);
            let new: Vec<String> = a
                .effects
                .iter()
                .filter(|e| !in_chosen(e.kind_name()))
                .map(bracketed)
                .collect();
            let gone: Vec<String> = chosen
                .iter()
                .filter(|e| !in_alt(e.kind_name()))
                .map(|e| name(e))
                .collect();
            let change = match (new.is_empty(), gone.is_empty()) {
                (false, false) => format!("{} in place of {}", new.join(" + "), gone.join(" + ")),
                (false, true) => format!("with {}", new.join(" + ")),
                (true, false) if a.effects.is_empty() => "the five terms alone".to_string(),
                (true, false) => format!("without {}", gone.join(" + ")),
                // The same kinds with other parameters.
                (true, true) => a
                    .effects
                    .iter()
                    .map(bracketed)
                    .collect::<Vec<_>>()
                    .join(" + "),
            };
            // Two decimals, as the chosen effects' gaps are given in the table and the report.
            format!("{change} (gap {:.2})", a.gap)
        })
        .collect();
    (!parts.is_empty()).then(|| parts.join("; "))
}
