//! The run-to-run table of several runs (the seed paper's table 2: each run's final fit as a row,
//! then the mean, its 95% interval and the sd from the `aggregate` records), the run-to-run limits,
//! and the overall verdict of the datasheet limits.

use super::*;

/// The seed paper's column order in table 2 (R, K, B, N, Q), as the report has it.
pub(super) const PAPER_ORDER: [usize; 5] = [4, 3, 2, 1, 0];

/// The run-to-run statistics of every channel in the seed paper's table 2 layout, as the
/// report shows it: one table per channel, one row per run labelled by its input (values from
/// `runs`' final fits), the coefficients as columns (R, K, B, N, Q) in datasheet units where the
/// channel's unit is known, then the mean, the 95% interval of the mean (mean +- 1.96 sd/sqrt(n),
/// as the paper), the sd and the number of runs that determined each coefficient (from `res`'s
/// `aggregate` records). `-` = not determined.
pub(super) fn aggregates(h: &mut String, res: &Results, runs: &Results, style: &TableStyle) {
    if res.aggregates.is_empty() {
        return;
    }
    let _ = writeln!(
        h,
        "\n{}",
        style.bold("Run to run, the seed paper's table 2 (95% interval of the mean: mean +- 1.96 sd/sqrt(n))")
    );
    let mut channels: Vec<(String, String)> = Vec::new();
    for a in &res.aggregates {
        let k = (a.rec.channel.clone(), a.rec.unit.clone());
        if !channels.contains(&k) {
            channels.push(k);
        }
    }
    for (ch, unit) in channels {
        let inc = IncrementUnit::parse(&unit);
        let (factors, units): ([f64; 5], [String; 5]) = match inc {
            Some(u) => (
                datasheet_factors(&u),
                datasheet_units(u.kind).map(String::from),
            ),
            None => ([1.0; 5], native_units(&unit)),
        };
        let agg = |i: usize| {
            res.aggregates
                .iter()
                .find(|a| a.rec.channel == ch && a.rec.coef == TERM_NAMES[i])
        };
        let mut rows = vec![
            std::iter::once("run".to_string())
                .chain(PAPER_ORDER.iter().map(|&i| TERM_NAMES[i].to_string()))
                .collect::<Vec<_>>(),
            std::iter::once(String::new())
                .chain(PAPER_ORDER.iter().map(|&i| units[i].clone()))
                .collect(),
        ];
        // One row per run: its final fit of this channel.
        for k in runs_in_order(runs) {
            let Some(f) = fits_of(runs, k).into_iter().find(|f| f.rec.channel == ch) else {
                continue;
            };
            let mut row = vec![f.label.clone()];
            for &i in &PAPER_ORDER {
                let c = f.rec.coef.by_index(i);
                let v = c.value.filter(|_| c.determined);
                row.push(v.map_or("-".into(), |v| sig3(v * factors[i])));
            }
            rows.push(row);
        }
        let stat =
            |name: &str, cell: &dyn Fn(&AggregateRecord, f64) -> Option<String>| -> Vec<String> {
                std::iter::once(name.to_string())
                    .chain(PAPER_ORDER.iter().map(|&i| {
                        agg(i)
                            .and_then(|a| cell(&a.rec, factors[i]))
                            .unwrap_or_else(|| "-".into())
                    }))
                    .collect()
            };
        // As JSON shows it: a number that is not finite is `null`, shown as a dash.
        let fin = |v: f64| v.is_finite().then_some(v);
        rows.push(stat("mean", &|a, f| {
            a.mean.and_then(fin).map(|m| sig3(m * f))
        }));
        rows.push(stat("95% interval", &|a, f| {
            let [lo, hi] = a.ci_z?;
            Some(interval(fin(lo).map(|x| x * f), fin(hi).map(|x| x * f)))
        }));
        rows.push(stat("sd", &|a, f| a.sd.and_then(fin).map(|m| sig3(m * f))));
        rows.push(stat("runs determined", &|a, _| Some(a.n.to_string())));
        let _ = writeln!(
            h,
            "\n{}",
            style.bold(&crate::sink::channel_with_unit(&ch, &unit))
        );
        h.push_str(&aligned_right(&rows, "  "));
    }
    let run_limits: Vec<&LimitResult> = res
        .limits
        .iter()
        .filter(|l| l.rec.over != Scope::Run)
        .map(|l| &l.rec)
        .collect();
    for c in limit_cells(&run_limits, style) {
        let _ = writeln!(h, "  limit: {c}");
    }
}

/// The overall verdict of the datasheet limits: every judged bound, and the runs' `pass`.
pub(super) fn verdict_line(res: &Results, style: &TableStyle) -> Option<String> {
    let verdicts: Vec<&str> = res.limits.iter().map(|l| l.rec.verdict.name()).collect();
    let pass: Vec<Option<bool>> = res.summaries.iter().map(|s| s.rec.record.pass).collect();
    if verdicts.is_empty() && pass.iter().all(Option::is_none) {
        return None;
    }
    let judged = verdicts.len();
    let failed = verdicts.iter().filter(|v| **v == "fail").count();
    Some(if failed > 0 || pass.contains(&Some(false)) {
        format!(
            "{}: {failed} of {judged} datasheet limits exceeded",
            style.red("FAIL")
        )
    } else if verdicts.iter().all(|v| *v == "pass") {
        format!(
            "{}: all {judged} datasheet limits met (97.5% one-sided confidence)",
            style.green("PASS")
        )
    } else {
        format!(
            "{}: no limit exceeded, but {} cannot be decided from these intervals (a longer run \
             narrows them)",
            style.yellow("UNDECIDED"),
            judged - verdicts.iter().filter(|v| **v == "pass").count()
        )
    })
}
