//! The other explanations a diagnosis found about as good as its choice (the record's
//! `alternatives`: docs/gap.md, "Alternatives"), in words a person reads beside the verdict: the
//! terminal table (sink::table) and the report (sink::report) say them through
//! [`alternative_words`], so the ambiguity is not left in the JSON alone; and, beside them, why
//! the unit's temperature was not named ([`temperature_check_words`]).

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
            // A model with more in it that fits better (`delta_chi2` < 0) was short of the bar
            // for naming what it adds (docs/gap.md, "Alternatives"): said, so that a lower gap
            // is not read as a better choice missed.
            let short = if a.delta_chi2 < 0.0 && !new.is_empty() {
                ", short of the bar to be named"
            } else {
                ""
            };
            format!("{change} (gap {:.2}{short})", a.gap)
        })
        .collect();
    (!parts.is_empty()).then(|| parts.join("; "))
}

/// The temperature's check when no temperature is named (the record's `temperature_check`;
/// docs/gap.md, "The temperature's check"), in words: `temperature not named (z 1.30, under the
/// bar 4):
/// coefficient 9.53 [-4.87, 23.9] deg/h per deg C (4.62e-5 [-2.36e-5, 1.16e-4] rad/s per deg C)`,
/// `temperature not determined: it changed as a straight line (bend 0.192% of its 1.86 deg C),
/// which a rate ramp takes as well: coefficient ...`, `temperature shown in time (z 5.10) but not
/// kept by the curve: coefficient ...`, `temperature constant: ...`; `None` when the record has
/// no check or names the temperature (its effect says it).
pub fn temperature_check_words(
    d: &DiagnosisRecord,
    unit: &str,
    number: &dyn Fn(f64) -> String,
) -> Option<String> {
    use crate::gap::temperature_check::TemperatureOutcome as O;
    let t = d.temperature_check.as_ref()?;
    let coefficient = || -> String {
        match (t.coefficient, t.interval) {
            (Some(c), Some([lo, hi])) => {
                let e = RecordedEffect::Known(crate::gap::effects::EffectParams::Temperature {
                    coefficient: c,
                    lo,
                    hi,
                    quadratic: None,
                    lag: None,
                });
                let (_, params) = effect_parts(&e, unit, number);
                params
                    .first()
                    .map(|p| format!("coefficient {}", p.value))
                    .unwrap_or_default()
            }
            _ => String::new(),
        }
    };
    let z = || t.z.map(|z| format!("{z:.2}")).unwrap_or_default();
    Some(match t.outcome {
        O::Named => return None,
        O::NotShown => format!(
            "temperature not named (z {}, under the bar {}): {}",
            z(),
            crate::gap::temperature::TEMPERATURE_Z,
            coefficient()
        ),
        O::Straight => format!(
            "temperature not determined: it changed as a straight line (bend {}% of its {} deg \
             C), which a rate ramp takes as well: {}",
            number(100.0 * t.bend.unwrap_or(0.0)),
            number(t.change_c),
            coefficient()
        ),
        O::NotKept => format!(
            "temperature shown in time (z {}) but not kept by the curve: {}",
            z(),
            coefficient()
        ),
        O::Constant => "temperature constant: its coefficient cannot be told".to_string(),
        O::TooShort => "temperature not judged: too few blocks".to_string(),
    })
}
