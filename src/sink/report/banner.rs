//! The PASS/FAIL banner at the top of the report: the overall verdict of the datasheet limits,
//! the limits that decided it, and a warning for every run whose input was not read to its end.

use super::*;

/// The overall verdict of the limits over every run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Banner {
    Pass,
    Fail,
    /// Some limit straddles its interval, none fails.
    Undecided,
    /// No limit was given.
    NoLimits,
}

/// PASS when every judged limit passes, FAIL when any fails, else undecided.
pub fn banner_of(res: &Results) -> Banner {
    let verdicts: Vec<&str> = res.limits.iter().map(|l| l.rec.verdict.name()).collect();
    let summary_pass: Vec<Option<bool>> = res.summaries.iter().map(|s| s.rec.record.pass).collect();
    if verdicts.is_empty() && summary_pass.iter().all(Option::is_none) {
        Banner::NoLimits
    } else if verdicts.contains(&"fail") || summary_pass.contains(&Some(false)) {
        Banner::Fail
    } else if verdicts.iter().all(|v| *v == "pass") && !summary_pass.is_empty() {
        Banner::Pass
    } else {
        Banner::Undecided
    }
}

pub(super) fn banner(h: &mut String, res: &Results) {
    let b = banner_of(res);
    let (class, word, note) = match b {
        Banner::Pass => (
            "b-pass",
            "PASS",
            "every datasheet limit is met at 97.5% one-sided confidence",
        ),
        Banner::Fail => (
            "b-fail",
            "FAIL",
            "at least one datasheet limit is exceeded (table below)",
        ),
        Banner::Undecided => (
            "b-und",
            "NOT DECIDED",
            "no limit fails, but some interval straddles its limit: more data needed",
        ),
        Banner::NoLimits => (
            "b-none",
            "NO LIMITS JUDGED",
            "no datasheet limits were given (--limits or a stand config's [[limits]])",
        ),
    };
    let warn: Vec<String> = res
        .summaries
        .iter()
        .filter_map(|s| {
            let c = &s.rec.completion;
            c.is_warning()
                .then(|| format!("{}: {}", s.label, c.phrase()))
        })
        .collect();
    let _ = write!(
        h,
        "<div class=\"banner {class}\" data-verdict=\"{word}\">{word}<small>{note}</small>"
    );
    // The limits that decided the banner, named: those exceeded, and those left undecided.
    let named = |verdict: &str| -> Vec<String> {
        res.limits
            .iter()
            .filter(|l| l.rec.verdict.name() == verdict)
            .map(|l| {
                let interval = match (l.rec.lo, l.rec.hi) {
                    (Some(lo), Some(hi)) => format!(" [{}, {}]", tick(lo), tick(hi)),
                    _ => String::new(),
                };
                format!(
                    "{} {} {} {} {} (measured {}{interval}{})",
                    esc(&l.rec.channel),
                    esc(l.rec.coef.name()),
                    if l.rec.bound == "min" { "&ge;" } else { "&le;" },
                    tick(l.rec.limit),
                    esc(&limit_unit(res, &l.rec)),
                    match l.rec.value {
                        Some(v) => tick(v),
                        None => "not determined".into(),
                    },
                    if res.summaries.len() > 1 {
                        format!(", {}", esc(&l.label))
                    } else {
                        String::new()
                    }
                )
            })
            .collect()
    };
    let failed = named("fail");
    if !failed.is_empty() {
        let _ = write!(h, "<small>failed: {}</small>", failed.join("; "));
    }
    let undecided = named("undecided");
    if !undecided.is_empty() {
        let _ = write!(
            h,
            "<small>not decided (the interval straddles the limit): {}</small>",
            undecided.join("; ")
        );
    }
    for w in &warn {
        let _ = write!(h, "<small class=\"warn\">{}</small>", esc(w));
    }
    h.push_str("</div>\n");
}
