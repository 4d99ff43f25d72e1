//! The runs table (input, data length, tau0, channels, whether the input was read to its end, what
//! a time column found) and the datasheet limits table with their units and verdicts.

use super::*;

pub(super) fn runs_table(h: &mut String, res: &Results) {
    if res.summaries.is_empty() {
        // The `diagnose` command writes diagnoses only, by design; other records without a
        // summary are a run that stopped before writing its last record.
        if !(res.curves.is_empty() && res.fits.is_empty()) {
            h.push_str("<p class=\"warn\">No summary record: the run may have been cut short before its end.</p>\n");
        } else if res.diagnoses.iter().any(|d| d.rec.ensemble.is_some()) {
            h.push_str("<p class=\"meta\">Diagnosis records only (the output of <code>allanscope diagnose --ensemble</code>): no curve records, fit or summary; the figure draws the measured Allan deviation the diagnosis judged against its ensemble bands.</p>\n");
        } else if !res.diagnoses.is_empty() {
            h.push_str("<p class=\"meta\">Diagnosis records only (the output of <code>allanscope diagnose</code>): no curves, fit or summary to show.</p>\n");
        }
        return;
    }
    h.push_str("<h2>Runs</h2>\n<table><tr><th class=\"l\">run</th><th class=\"l\">input</th><th>data (s)</th><th>&#964;0 (s)</th><th class=\"l\">channels</th><th>unreadable rows</th><th class=\"l\">input read</th></tr>\n");
    for s in &res.summaries {
        let v = &s.rec.record;
        let c = &s.rec.completion;
        let chans = v.channels.join(", ");
        let _ = writeln!(
            h,
            "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>{}</td><td class=\"l\">{}</td><td>{}</td><td class=\"l{}\">{}{}</td></tr>",
            esc(&s.label),
            esc(&v.input),
            tick(v.t_data),
            tick(v.tau0),
            esc(&chans),
            v.bad_rows,
            if c.is_warning() { " warn" } else { "" },
            esc(&c.phrase()),
            v.time_column.as_ref().map(time_column_note).unwrap_or_default()
        );
    }
    h.push_str("</table>\n");
}

/// What a text input's time column found (summary `time_column`), under the run's "input read".
pub(super) fn time_column_note(tc: &TimeColumnRecord) -> String {
    let name = esc(&tc.name);
    let text = if !tc.used {
        format!("time column `{name}` not used: its step is not &tau;0")
    } else {
        format!(
            "time column `{name}`: {} jumps = {} missing samples (gaps), {} steps backwards, {} off-step, {} rows written twice dropped",
            tc.gaps,
            tc.missing_samples,
            tc.backwards,
            tc.irregular + tc.discontinuities,
            tc.duplicates
        )
    };
    format!(
        "<br><span class=\"small\">{}</span>",
        text.replace('`', "&quot;")
    )
}

pub(super) fn limits_table(h: &mut String, res: &Results) {
    if res.limits.is_empty() {
        return;
    }
    let several = res.summaries.len() > 1;
    h.push_str("<h2>Datasheet limits</h2>\n<table><tr>");
    if several {
        h.push_str("<th class=\"l\">run</th>");
    }
    h.push_str("<th class=\"l\">channel</th><th>coefficient</th><th class=\"l\">over</th><th class=\"l\">bound</th><th>limit</th><th class=\"l\">unit</th><th>value</th><th>95% interval</th><th class=\"l\">verdict</th></tr>\n");
    for l in &res.limits {
        let v = &l.rec;
        let verdict = v.verdict.name();
        let class = match verdict {
            "pass" => "pass",
            "fail" => "fail",
            _ => "und",
        };
        h.push_str("<tr>");
        if several {
            let _ = write!(h, "<td class=\"l\">{}</td>", esc(&l.label));
        }
        let note = v
            .note
            .as_deref()
            .map(|n| format!("<br><span class=\"small\">{}</span>", esc(n)))
            .unwrap_or_default();
        let _ = writeln!(
            h,
            "<td class=\"l\">{}</td><td>{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td class=\"l\">{}</td><td>{}</td><td>[{}, {}]</td><td class=\"l {class}\">{}{note}</td></tr>",
            esc(&v.channel),
            esc(v.coef.name()),
            esc(v.over.name()),
            esc(&v.bound),
            tick(v.limit),
            esc(&limit_unit(res, v)),
            opt(v.value),
            opt(v.lo),
            opt(v.hi),
            esc(&verdict.to_uppercase())
        );
    }
    h.push_str("</table>\n");
}

/// A limit's unit; `native` spelt out as the coefficient's unit for the channel's unit.
pub(super) fn limit_unit(res: &Results, l: &LimitResult) -> String {
    if l.unit != "native" {
        return l.unit.clone();
    }
    match res.fits.iter().find(|f| f.rec.channel == l.channel) {
        Some(f) => coef_units(&f.rec.unit)[l.coef.index()].clone(),
        None => "native".into(),
    }
}
