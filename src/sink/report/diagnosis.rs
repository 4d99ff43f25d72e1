//! The diagnosis section: each channel's final diagnosis in words, its effects' parameters named
//! and in units, and the interim diagnoses in a small time table.

use super::*;

/// An effect's name and parameters in words and units, rates in datasheet units beside the
/// record's u/s (sink::effect_text).
pub fn effect_words(effect: &RecordedEffect, unit: &str) -> String {
    crate::sink::effect_text::effect_line(effect, unit, &tick)
}

pub(super) fn diagnosis(h: &mut String, res: &Results) {
    if res.diagnoses.is_empty() {
        return;
    }
    let several = res.several_runs();
    h.push_str("<h2>Sim-to-real gap (diagnosis)</h2>\n<p>The gap statistic is near 1 when the model explains the curve. Final diagnosis of each channel; effect parameters named, rates in datasheet units with the channel's own unit in brackets:</p>\n<table class=\"diagnosis\"><tr>");
    if several {
        h.push_str("<th class=\"l\">run</th>");
    }
    h.push_str("<th class=\"l\">channel</th><th class=\"l\">verdict</th><th>gap before</th><th>gap after</th><th class=\"l\">effects (in the order added; gap after each)</th><th class=\"l\">where the base model misses</th></tr>\n");
    // The final (or last) diagnosis per run and channel.
    let mut keys: Vec<(usize, Option<usize>, String)> = Vec::new();
    for d in &res.diagnoses {
        let k = (d.file, d.run, d.rec.channel.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    // The channel's unit: its curve's, else the one the record names (`diagnose` writes no curve).
    let unit_of = |d: &Labelled<DiagnosisRecord>| {
        res.curves
            .iter()
            .find(|c| c.file == d.file && c.rec.channel == d.rec.channel)
            .map(|c| c.rec.unit.clone())
            .or_else(|| d.rec.unit.clone())
            .unwrap_or_else(|| "u".to_string())
    };
    let mut interim: Vec<&Labelled<DiagnosisRecord>> = Vec::new();
    let mut bands: Vec<String> = Vec::new();
    for (file, run, ch) in &keys {
        let mine: Vec<&Labelled<DiagnosisRecord>> = res
            .diagnoses
            .iter()
            .filter(|d| d.file == *file && d.run == *run && &d.rec.channel == ch)
            .collect();
        let Some(last) = mine
            .iter()
            .rev()
            .find(|d| d.rec.is_final)
            .or(mine.last())
            .copied()
        else {
            continue;
        };
        // Interim diagnoses, less one written at the same data time as the final (its copy).
        interim.extend(mine.iter().filter(|d| {
            let copy_of_final = last.rec.is_final && d.rec.t_data == last.rec.t_data;
            !std::ptr::eq(**d, last) && !copy_of_final
        }));
        let d = &last.rec;
        let unit = unit_of(last);
        bands.extend(band_words(d).map(|w| {
            if several {
                format!("<b>{}</b> ({}): {w}", esc(ch), esc(&last.label))
            } else {
                format!("<b>{}</b>: {w}", esc(ch))
            }
        }));
        // An effect found in the block means alone leaves the gap as it was: said so, not as
        // a gap it brought.
        let mut prev = d.gap_before;
        let effects: Vec<String> = d
            .effects
            .iter()
            .map(|e| {
                let words = esc(&effect_words(&e.effect, &unit));
                let text = if e.gap_after == prev {
                    format!(
                        "{words} (seen in the block means over time; gap {:.2} unchanged)",
                        e.gap_after
                    )
                } else {
                    format!("{words} (gap {:.2})", e.gap_after)
                };
                prev = e.gap_after;
                text
            })
            .collect();
        // The four regions the model misses most; the count of the others.
        let mut worst: Vec<&crate::gap::record::RegionRecord> = d.regions.iter().collect();
        worst.sort_by(|a, b| {
            b.worst_ratio
                .ln()
                .abs()
                .total_cmp(&a.worst_ratio.ln().abs())
        });
        let more = worst.len().saturating_sub(4);
        worst.truncate(4);
        worst.sort_by(|a, b| a.tau_lo.total_cmp(&b.tau_lo));
        let mut regions: Vec<String> = worst
            .iter()
            .map(|r| {
                let taus = if r.tau_lo == r.tau_hi {
                    format!("&#964; = {} s", tick(r.tau_lo))
                } else {
                    format!("&#964; {}&ndash;{} s", tick(r.tau_lo), tick(r.tau_hi))
                };
                format!(
                    "{taus}: data {} the model (&#215;{} at worst)",
                    if r.sign > 0 { "above" } else { "below" },
                    ratio_text(r.worst_ratio)
                )
            })
            .collect();
        if more > 0 {
            regions.push(format!("and {more} more, closer to the model"));
        }
        let verdict = d.verdict.name();
        let mut shape = d
            .residual_shape
            .as_ref()
            .map(|s| {
                format!(
                    "<br><span class=\"small\">what is left unexplained: {}</span>",
                    esc(s)
                )
            })
            .unwrap_or_default();
        if let Some(w) = crate::sink::jump_words::jump_words(d, &unit, &tick) {
            let _ = write!(shape, "<br><span class=\"small\">bias {}</span>", esc(&w));
        }
        if let Some(w) = crate::sink::taken_out::taken_out_words(d, &unit, &tick) {
            let _ = write!(
                shape,
                "<br><span class=\"small\">set aside before the curve: {}</span>",
                esc(&w)
            );
        }
        if let Some(w) = crate::sink::first_block_words::first_block_words(d, &unit, &tick) {
            let _ = write!(shape, "<br><span class=\"small\">{}</span>", esc(&w));
        }
        let mut effects_cell = if effects.is_empty() {
            "none".to_string()
        } else {
            effects.join("<br>")
        };
        if let Some(w) = crate::sink::filter_shape_words::filter_shape_words(d, &unit, &tick, " = ")
        {
            let _ = write!(effects_cell, "<br><span class=\"small\">{}</span>", esc(&w));
        }
        if let Some(w) = crate::sink::alternative_words::alternative_words(d, &unit, &tick, " = ") {
            let _ = write!(
                effects_cell,
                "<br><span class=\"small\">about as well: {}</span>",
                esc(&w)
            );
        }
        if let Some(w) = crate::sink::alternative_words::temperature_check_words(d, &unit, &tick) {
            let _ = write!(effects_cell, "<br><span class=\"small\">{}</span>", esc(&w));
        }
        let _ = writeln!(
            h,
            "<tr>{}<td class=\"l\">{}</td><td class=\"l\"><b>{}</b>{shape}</td><td>{:.2}</td><td>{:.2}</td><td class=\"l\">{}</td><td class=\"l\">{}</td></tr>",
            if several {
                format!("<td class=\"l\">{}</td>", esc(&last.label))
            } else {
                String::new()
            },
            esc(ch),
            esc(verdict),
            d.gap_before,
            d.gap_after,
            effects_cell,
            if regions.is_empty() { "nowhere".into() } else { regions.join("<br>") }
        );
    }
    h.push_str("</table>\n");
    if !bands.is_empty() {
        h.push_str("<h3>How far the twin matches the unit (ensemble band)</h3>\n<p>The fitted unit simulated as long as the input, many times: its five terms alone (the base band, grey hatching in the figure) and with the accepted effects (the twin's band, in the curve's colour). Each band holds 2.5% to 97.5% of the simulated Allan deviations at each &#964;. A run of the model itself would fall outside its band at a few of the &#964;s by chance (the share given with each channel).</p>\n<ul class=\"bands\">\n");
        for b in &bands {
            let _ = writeln!(h, "<li>{b}</li>");
        }
        h.push_str("</ul>\n");
    }
    interim_table(h, &interim, several);
}

/// The ensemble band of a diagnosis in words: how far the five terms alone miss and how far
/// the twin matches, with the runs and the twin's effects.
fn band_words(d: &DiagnosisRecord) -> Option<String> {
    let e = d.ensemble.as_ref()?;
    let sentence = band_sentence(d)?;
    let names = effect_names(d);
    let twin = if names.is_empty() {
        "no effect was kept, so the twin is the five terms".to_string()
    } else {
        format!("the twin is the five terms with {}", names.join(", "))
    };
    Some(format!(
        "the measured curve is {}. Bands of {} simulated runs each (a run of the model itself would be outside at about {} by chance); {twin}.",
        esc(&sentence),
        e.runs,
        esc(&percent(chance_share(e.runs)))
    ))
}

/// The interim diagnoses as a small time table: one row per data time (per run), one column
/// per channel, each cell the verdict, the gap before and after and the effects' names. At
/// most [`INTERIM_ROWS`] rows per run: a long run shows every k-th time, and says so.
pub(super) fn interim_table(h: &mut String, interim: &[&Labelled<DiagnosisRecord>], several: bool) {
    if interim.is_empty() {
        return;
    }
    let mut channels: Vec<&str> = Vec::new();
    let mut runs: Vec<(usize, Option<usize>)> = Vec::new();
    for d in interim {
        if !channels.contains(&d.rec.channel.as_str()) {
            channels.push(&d.rec.channel);
        }
        if !runs.contains(&(d.file, d.run)) {
            runs.push((d.file, d.run));
        }
    }
    h.push_str("<h3>Interim diagnoses</h3>\n<p class=\"small\">Each cell: the verdict, the gap before &rarr; after the effects, and the effects added.</p>\n<table class=\"interim small\"><tr>");
    if several {
        h.push_str("<th class=\"l\">run</th>");
    }
    h.push_str("<th>data (s)</th>");
    for c in &channels {
        let _ = write!(h, "<th class=\"l\">{}</th>", esc(c));
    }
    h.push_str("</tr>\n");
    let mut thinned = 0usize;
    for key in runs {
        let mine: Vec<&&Labelled<DiagnosisRecord>> =
            interim.iter().filter(|d| (d.file, d.run) == key).collect();
        let mut times: Vec<f64> = mine.iter().map(|d| d.rec.t_data).collect();
        times.sort_by(f64::total_cmp);
        times.dedup();
        let step = times.len().div_ceil(INTERIM_ROWS).max(1);
        if step > 1 {
            thinned = thinned.max(step);
        }
        let label = mine.first().map(|d| d.label.clone()).unwrap_or_default();
        for (n, t) in times.iter().enumerate() {
            // Every step-th time, and always the last.
            if n % step != 0 && n + 1 != times.len() {
                continue;
            }
            h.push_str("<tr>");
            if several {
                let _ = write!(h, "<td class=\"l\">{}</td>", esc(&label));
            }
            let _ = write!(h, "<td>{}</td>", tick(*t));
            for c in &channels {
                match mine
                    .iter()
                    .find(|d| d.rec.t_data == *t && d.rec.channel == *c)
                {
                    Some(d) => {
                        let verdict = d.rec.verdict.name();
                        let kinds: Vec<&str> = d
                            .rec
                            .effects
                            .iter()
                            .map(|e| effect_name(e.effect.kind_name()))
                            .collect();
                        let _ = write!(
                            h,
                            "<td class=\"l\">{} {:.2}&rarr;{:.2}{}</td>",
                            esc(verdict),
                            d.rec.gap_before,
                            d.rec.gap_after,
                            if kinds.is_empty() {
                                String::new()
                            } else {
                                format!("<br>{}", esc(&kinds.join(", ")))
                            }
                        );
                    }
                    None => h.push_str("<td>&ndash;</td>"),
                }
            }
            h.push_str("</tr>\n");
        }
    }
    h.push_str("</table>\n");
    if thinned > 1 {
        let _ = writeln!(
            h,
            "<p class=\"small\">Every {thinned}th interim time shown (and the last); the JSON lines hold them all.</p>"
        );
    }
}

/// Rows of the interim-diagnosis table per run.
pub(super) const INTERIM_ROWS: usize = 24;
