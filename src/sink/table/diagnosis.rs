//! A channel's diagnosis in one line (its verdict, the effects with their parameters in units, the
//! gap before and after), and the channels diagnosed without a fit (the `diagnose` command's).

use super::*;

/// An effect in a few words with its parameters named and in units, rates in datasheet units
/// beside the record's u/s (sink::effect_text).
pub fn effect_brief(effect: &RecordedEffect, unit: &str) -> String {
    crate::sink::effect_text::effect_bracketed(effect, unit, &sig3, " ")
}

/// The diagnosis in one line: the verdict, what explains the gap, and the gap before and after.
pub fn diagnosis_line(d: &DiagnosisRecord, unit: &str, style: &TableStyle) -> String {
    let gap = if d.effects.is_empty() {
        format!("gap {}", sig3(d.gap_before))
    } else if d.gap_after == d.gap_before {
        // Effects found in time alone (a warm-up, jumps, a temperature kept on the block
        // means' evidence) leave the curve's gap as it was: "explained" would read as if the
        // curve had been mended.
        format!(
            "gap {}, unchanged: seen in the block means over time, not on the Allan curve",
            sig3(d.gap_before)
        )
    } else {
        format!("gap {} -> {}", sig3(d.gap_before), sig3(d.gap_after))
    };
    // When the curve was judged beyond its filter's stretch, the unit's filter is the one the
    // whole curve named (said after the verdict); a filter named beyond it fitted only its
    // tail, and is left to the record.
    let shape = d.filter_shape.is_some();
    let mut effects: Vec<String> = d
        .effects
        .iter()
        .filter(|e| {
            !shape || !matches!(&e.effect, RecordedEffect::Known(p) if p.kind().is_filter())
        })
        .map(|e| effect_brief(&e.effect, unit))
        .collect();
    if shape {
        effects.insert(0, "the unit's filter".into());
    }
    let misses = || -> String {
        d.regions
            .iter()
            .map(|r| {
                format!(
                    "tau {} to {} ({} the model, up to {}x)",
                    tau_text(r.tau_lo),
                    tau_text(r.tau_hi),
                    if r.sign > 0 { "above" } else { "below" },
                    sig3(r.worst_ratio)
                )
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    let mut line = match d.verdict {
        crate::gap::diagnose::Verdict::Consistent => {
            format!("consistent: the five-term model explains the curve ({gap})")
        }
        crate::gap::diagnose::Verdict::Explained => {
            format!("explained by {} ({gap})", effects.join(" + "))
        }
        crate::gap::diagnose::Verdict::Unexplained => {
            let mut s = style.yellow("UNEXPLAINED");
            let m = misses();
            if !m.is_empty() {
                let _ = write!(s, ": the model misses at {m}");
            }
            if !effects.is_empty() {
                let _ = write!(s, "; best try {}", effects.join(" + "));
            }
            let _ = write!(s, " ({gap})");
            s
        }
    };
    // A moving average and a first or second order named together are one filter in series
    // (docs/gap.md, "A low-pass behind a decimator (session 46)").
    let named = |kinds: &[&str]| {
        d.effects
            .iter()
            .any(|e| kinds.contains(&e.effect.kind_name()))
    };
    if named(&["moving_average"]) && named(&["output_filter", "second_order_filter"]) {
        let _ = write!(
            line,
            "; the moving average and the low-pass are one filter in series, the average first"
        );
    }
    if let Some(w) = crate::sink::filter_shape_words::filter_shape_words(d, unit, &sig3, " ") {
        let _ = write!(line, "; {w}");
    }
    if let Some(w) = crate::sink::jump_words::jump_words(d, unit, &sig3) {
        let _ = write!(line, "; {w}");
    }
    if let Some(w) = crate::sink::taken_out::taken_out_words(d, unit, &sig3) {
        let _ = write!(line, "; set aside: {w}");
    }
    if let Some(w) = crate::sink::first_block_words::first_block_words(d, unit, &sig3) {
        let _ = write!(line, "; {w}");
    }
    if let Some(w) = crate::sink::alternative_words::alternative_words(d, unit, &sig3, " ") {
        let _ = write!(line, "; about as well: {w}");
    }
    if let Some(w) = crate::sink::alternative_words::temperature_check_words(d, unit, &sig3) {
        let _ = write!(line, "; {w}");
    }
    if let Some(ho) = &d.holdout {
        let _ = write!(
            line,
            "; on the held-out run gap {} -> {}",
            sig3(ho.gap_before),
            sig3(ho.gap_after)
        );
        // Which effects carried: one carried in time (a warm-up, a temperature) leaves the
        // held-out gap as it was, so the gaps alone do not say it.
        let kinds = |carried: bool| -> String {
            ho.effects
                .iter()
                .filter(|e| e.carried == carried)
                .map(|e| crate::sink::effect_text::kind_words(&e.kind))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (yes, no) = (kinds(true), kinds(false));
        // Effects the held-out run could not judge (too weak there to show, or no temperature):
        // neither carried nor disowned.
        let unjudged = ho
            .not_judged
            .iter()
            .map(|k| crate::sink::effect_text::kind_words(k))
            .collect::<Vec<_>>()
            .join(", ");
        let _ = match (yes.is_empty(), no.is_empty()) {
            (true, true) if !ho.carried && unjudged.is_empty() => write!(line, " (did not carry)"),
            (true, true) => Ok(()),
            (false, true) => write!(line, " (carried: {yes})"),
            (true, false) => write!(line, " (did not carry: {no})"),
            (false, false) => write!(line, " (carried: {yes}; did not carry: {no})"),
        };
        if !unjudged.is_empty() {
            let _ = write!(line, " (not judged there: {unjudged})");
        }
    }
    // `diagnose --ensemble N`: how far the five terms alone and the twin match the curve.
    if let (Some(e), Some(words)) = (&d.ensemble, crate::sink::band_words::band_sentence(d)) {
        let _ = write!(line, "; against {} simulated runs: {words}", e.runs);
    }
    line
}

/// Diagnoses of channels that have no fit (the `diagnose` command writes only diagnoses).
pub(super) fn diagnosis_only(
    h: &mut String,
    res: &Results,
    k: RunKey,
    fitted: &[&str],
    style: &TableStyle,
) {
    let mut seen: Vec<&str> = Vec::new();
    for d in res.diagnoses.iter().filter(|d| (d.file, d.run) == k) {
        let ch = d.rec.channel.as_str();
        if fitted.contains(&ch) || seen.contains(&ch) {
            continue;
        }
        seen.push(ch);
        let d = res.diagnosis_in(k, ch).unwrap_or(&d.rec);
        let unit = d.unit.as_deref().unwrap_or("u");
        let _ = writeln!(
            h,
            "\n{}  diagnosis: {}",
            style.bold(
                &d.unit
                    .as_deref()
                    .map_or(ch.to_string(), |u| crate::sink::channel_with_unit(ch, u))
            ),
            diagnosis_line(d, unit, style)
        );
        // The five terms refitted with the effects in, in datasheet units when the unit is known
        // (in records before session 40, without intervals, terms the fit set to zero left out).
        let (factors, units) = match IncrementUnit::parse(unit) {
            Some(iu) => (
                datasheet_factors(&iu),
                datasheet_units(iu.kind).map(String::from),
            ),
            None => ([1.0; 5], native_units(unit)),
        };
        // With intervals (records since session 40): a determined term with its 95% interval,
        // the others by their upper end.
        let terms: Vec<String> = match &d.final_terms {
            Some(t) => (0..5)
                .filter_map(|i| {
                    let c = t.by_index(i);
                    let f = factors[i];
                    let text = match (c.value, c.lo, c.hi) {
                        (Some(v), lo, hi) => format!(
                            "{} {} {}",
                            sig3(v * f),
                            interval(lo.map(|x| x * f), hi.map(|x| x * f)),
                            units[i]
                        ),
                        (None, _, Some(h)) if h > 0.0 => format!("< {} {}", sig3(h * f), units[i]),
                        _ => return None,
                    };
                    Some(format!("{} {text}", TERM_NAMES[i]))
                })
                .collect(),
            None => (0..5)
                .filter(|&i| d.final_coef[i] > 0.0)
                .map(|i| {
                    format!(
                        "{} {} {}",
                        TERM_NAMES[i],
                        sig3(d.final_coef[i] * factors[i]),
                        units[i]
                    )
                })
                .collect(),
        };
        let _ = writeln!(
            h,
            "  {}",
            style.dim(&format!(
                "five-term model with the effects: {}; taus {} to {}",
                if terms.is_empty() {
                    "-".to_string()
                } else {
                    terms.join(", ")
                },
                tau_text(d.tau_span[0]),
                tau_text(d.tau_span[1])
            ))
        );
    }
}
