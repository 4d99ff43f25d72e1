//! The SVG figures the page embeds: the Allan-deviation plots (one panel per channel unit, runs
//! labelled) and the dynamic Allan view where interim curves exist.

use super::*;

pub(super) fn figures(h: &mut String, res: &Results) {
    let all = |_: &str| true;
    let finals = final_curves(res, "avar", &all);
    let series = figure_series(res, &finals, "avar", &all, true);
    if series.is_empty() {
        return;
    }
    let several = res.several_runs();
    h.push_str("<h2>Allan deviation</h2>\n");
    if !several {
        h.push_str(&render_svg(
            series,
            "Final Allan deviation curves, fitted model and diagnosis",
        ));
        return;
    }
    // Several runs: one figure per channel, its runs overlaid and named by file (the seed
    // paper's figure 2), so each run's model and asymptotes stay readable.
    let mut channels: Vec<String> = Vec::new();
    for s in &series {
        if !channels.contains(&s.curve.channel) {
            channels.push(s.curve.channel.clone());
        }
    }
    let mut series = series;
    for ch in channels {
        let (mine, rest): (Vec<Series>, Vec<Series>) =
            series.into_iter().partition(|s| s.curve.channel == ch);
        series = rest;
        let unit = mine[0].curve.unit.clone();
        h.push_str(&render_svg(
            mine,
            &format!("{ch} [{unit}]: the runs overlaid"),
        ));
    }
}

pub(super) fn dynamic_view(h: &mut String, res: &Results) {
    let finals: Vec<_> = res
        .curves
        .iter()
        .filter(|c| c.rec.r#final && c.rec.stat.name() == "avar")
        .collect();
    let mut first = true;
    for c in finals {
        let all = res.history_of(c);
        if all.len() < 3 {
            continue;
        }
        if first {
            h.push_str("<h2>Where in the run (dynamic Allan view)</h2>\n<p>Each column is the stretch of the run between two interim records; its colour is that stretch's Allan deviation divided by the whole run's, at each &#964;. Red: noisier than the run as a whole; blue: quieter.</p>\n");
            first = false;
        }
        let label = res.curve_caption(c);
        h.push_str(&render_dynamic_svg(&all, &label));
    }
}
