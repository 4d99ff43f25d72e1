//! The table of one run: its heading (input, data length, whether it was read to its end, the
//! decoder's health), and per channel the five terms in datasheet units with their 95% intervals,
//! the IEEE 952 read-outs beside N, B and K, and the datasheet limits judged on it.

use super::*;

/// The name of each term for a kind of sensor (IEEE 952's names for a gyro; the velocity and
/// acceleration names for an accelerometer).
pub(super) fn term_names(kind: Option<SensorKind>) -> [&'static str; 5] {
    match kind {
        Some(SensorKind::Accel) => [
            "quantization",
            "velocity random walk",
            "bias instability",
            "accel. random walk",
            "accel. ramp",
        ],
        _ => [
            "quantization",
            "angle random walk",
            "bias instability",
            "rate random walk",
            "rate ramp",
        ],
    }
}

/// One coefficient as shown: value and interval in the shown unit.
pub(super) struct Shown {
    value: Option<f64>,
    lo: Option<f64>,
    hi: Option<f64>,
    unit: String,
}

/// A fit's coefficient `i` in datasheet units when the record has them, else native.
pub(super) fn coef_shown(f: &FitRecord, i: usize) -> Shown {
    let c = f.coef.by_index(i);
    let determined = c.determined;
    if let Some(d) = f.datasheet.as_ref().map(|d| d.by_index(i)) {
        return Shown {
            value: d.value.filter(|_| determined),
            lo: d.lo,
            hi: d.hi,
            unit: d.unit.clone(),
        };
    }
    Shown {
        value: c.value.filter(|_| determined),
        lo: c.lo,
        hi: c.hi,
        unit: native_units(&f.unit)[i].clone(),
    }
}

/// A fit cell: `0.00420 [0.00416, 0.00424]`, or `not determined (< 3.42)`.
pub(super) fn fit_cell(s: &Shown) -> String {
    match s.value {
        Some(v) => format!("{} {}", sig3(v), interval(s.lo, s.hi)),
        None => match s.hi.filter(|h| *h > 0.0) {
            Some(h) => format!("not determined (< {})", sig3(h)),
            None => "not determined".into(),
        },
    }
}

/// A read-out cell in the fit's shown unit (datasheet when the read-out has it).
pub(super) fn readout_cell(r: Option<&ReadoutRecord>, which: usize) -> String {
    let Some(r) = r else {
        return match which {
            1 => "no -1/2 slope".into(),
            2 => "no minimum inside the curve".into(),
            _ => "no +1/2 slope".into(),
        };
    };
    let (v, lo, hi) = match &r.datasheet {
        Some(d) => (d.value.unwrap_or(f64::NAN), d.lo, d.hi),
        None => (r.value, r.lo, r.hi),
    };
    let at = if which == 2 {
        format!("min at {}", tau_text(r.tau))
    } else {
        format!("at {}", tau_text(r.tau))
    };
    let bound = r
        .upper_bound_reason()
        .map(|why| format!("; an upper bound on B: {why}"))
        .unwrap_or_default();
    format!("{} {} {at}{bound}", sig3(v), interval(Some(lo), Some(hi)))
}

/// The heading of a run: what was read, how much, whether to its end, and the decoder's health.
pub(super) fn run_heading(h: &mut String, res: &Results, k: RunKey, style: &TableStyle) {
    let summary = summary_of(res, k);
    let label = res
        .fits
        .iter()
        .find(|f| (f.file, f.run) == k)
        .map(|f| f.label.clone())
        .or_else(|| {
            res.diagnoses
                .iter()
                .find(|d| (d.file, d.run) == k)
                .map(|d| d.label.clone())
        })
        .unwrap_or_default();
    let input = match summary.map(|s| s.record.input.as_str()) {
        Some("-") => "standard input".to_string(),
        Some(i) => i.to_string(),
        None => label,
    };
    if summary.is_none() && input.is_empty() && k.1.is_none() {
        // Records of no named run (the `diagnose` command's): no heading to show.
        return;
    }
    let run = k.1.map(|r| format!("run {}: ", r + 1)).unwrap_or_default();
    let mut line = style.bold(&format!("{run}{input}"));
    if let Some(RunSummary {
        record: s,
        completion: c,
    }) = summary
    {
        let (t, tau0) = (s.t_data, s.tau0);
        let nch = s.channels.len();
        let _ = write!(
            line,
            ": {} of data at tau0 = {}, {nch} channel{}",
            duration_text(t),
            tau_text(tau0),
            if nch == 1 { "" } else { "s" }
        );
        let phrase = c.phrase();
        let _ = write!(
            line,
            ", {}",
            if c.is_warning() {
                style.red(&phrase)
            } else {
                phrase
            }
        );
        let gaps: u64 = s
            .segments
            .iter()
            .map(|n| n.saturating_sub(1))
            .max()
            .unwrap_or(0);
        let bad = s.bad_rows;
        let mut notes = Vec::new();
        if gaps > 0 {
            notes.push(format!("{gaps} gap{}", if gaps == 1 { "" } else { "s" }));
        }
        if bad > 0 {
            notes.push(format!(
                "{bad} unreadable row{}",
                if bad == 1 { "" } else { "s" }
            ));
        }
        if s.invalid_values > 0 {
            notes.push(format!(
                "{} implausible values read as gaps",
                s.invalid_values
            ));
        }
        if let Some(tc) = &s.time_column {
            let name = &tc.name;
            if !tc.used {
                notes.push(style.yellow(&format!(
                    "time column `{name}` not used: its step is not tau0"
                )));
            } else if tc.gaps + tc.backwards + tc.irregular + tc.discontinuities + tc.duplicates > 0
            {
                notes.push(format!(
                    "time column `{name}`: {} jumps = {} missing samples, {} backwards, {} off-step, \
                     {} rows written twice dropped",
                    tc.gaps,
                    tc.missing_samples,
                    tc.backwards,
                    tc.irregular + tc.discontinuities,
                    tc.duplicates
                ));
            }
        }
        if let Some(e) = &s.capture_error {
            notes.push(style.red(&format!("capture stopped: {e}")));
        }
        if !notes.is_empty() {
            let _ = write!(line, " ({})", notes.join(", "));
        }
    }
    h.push_str(&line);
    h.push('\n');
    if let Some(hl) = res.health.iter().rev().find(|x| (x.file, x.run) == k) {
        let v = &hl.rec;
        let mut parts = vec![format!("{} frames", v.frames)];
        let lost = v.missing;
        parts.push(if lost > 0 {
            style.yellow(&format!("{lost} lost"))
        } else {
            "none lost".into()
        });
        for (n, name) in [
            (v.crc_errors, "checksum errors"),
            (v.resyncs, "resyncs"),
            (v.duplicates, "duplicates"),
            (v.bytes_skipped, "bytes skipped"),
        ] {
            if n > 0 {
                parts.push(format!("{n} {name}"));
            }
        }
        let _ = writeln!(h, "  decoder: {}", parts.join(", "));
    }
}

/// The limits judged on one channel of a run, one cell each: `N max 0.005 deg/sqrt(h): PASS`.
pub(super) fn limit_cells(limits: &[&LimitResult], style: &TableStyle) -> Vec<String> {
    limits
        .iter()
        .map(|l| {
            let coef = l.coef.name();
            let op = if l.bound == "min" { ">=" } else { "<=" };
            let unit = &l.unit;
            let v = match l.verdict {
                Verdict::Pass => style.green("PASS"),
                Verdict::Fail => style.red("FAIL"),
                Verdict::Undecided => style.yellow("UNDECIDED"),
                Verdict::Invalid => style.yellow("NOT JUDGED"),
            };
            let over = match l.over {
                Scope::RunsSd => "sd over runs of ",
                Scope::RunsMean => "mean over runs of ",
                Scope::Run => "",
            };
            let value = match (l.value, l.lo, l.hi) {
                (Some(v), lo, hi) => format!(" (fit {} {})", sig3(v), interval(lo, hi)),
                (None, _, Some(hi)) => format!(" (not determined, < {})", sig3(hi)),
                _ => String::new(),
            };
            let note = l
                .note
                .as_deref()
                .map(|n| format!(": {n}"))
                .unwrap_or_default();
            format!(
                "{v} {over}{coef} {op} {} {unit}{value}{note}",
                sig3(l.limit)
            )
        })
        .collect()
}

/// A `gof` above this says the five-term model does not hold: when it holds, `gof` is about
/// chi-squared over its `nu = J - p` degrees of freedom (docs/fit.md: mean 1.00, 95th
/// percentile 1.6-1.7 at `nu` near 16), and 3 is beyond its 99.99th percentile there. Seen:
/// a real MEMS gyro's internal filter over all taus (10^3-10^4, docs/fit.md) and a counter
/// whose LSB is tens of times its noise (3e5, with `B` 32 times the truth).
const GOF_MISFIT: f64 = 3.0;

pub(super) fn channel_block(
    h: &mut String,
    res: &Results,
    k: RunKey,
    f: &FitRecord,
    style: &TableStyle,
) {
    let kind = IncrementUnit::parse(&f.unit).map(|u| u.kind);
    let what = match kind {
        Some(SensorKind::Gyro) => "gyro",
        Some(SensorKind::Accel) => "accelerometer",
        None => "unit not known, native units",
    };
    let gof = f.gof.map_or("-".into(), sig3);
    let stage = if f.r#final {
        String::new()
    } else {
        format!(", interim at {}", duration_text(f.t_data))
    };
    let _ = writeln!(
        h,
        "\n{} [{}, {what}]   five-term fit ({}), gof {gof}{stage}",
        style.bold(&f.channel),
        f.unit,
        f.method
    );
    let names = term_names(kind);
    // A record without read-outs (an older writer) leaves the column empty.
    let ro: Option<&ReadoutsRecord> = f.readouts.as_deref();
    let mut rows = vec![vec![
        String::new(),
        "term".into(),
        "unit".into(),
        "fit: value [95% interval]".into(),
        "IEEE 952 read-out [95%]".into(),
    ]];
    for i in 0..5 {
        let s = coef_shown(f, i);
        let readout = match (ro, i) {
            (Some(ro), 1) => readout_cell(ro.arw.as_ref(), 1),
            (Some(ro), 2) => readout_cell(ro.bias_instability.as_ref(), 2),
            (Some(ro), 3) => readout_cell(ro.rrw.as_ref(), 3),
            _ => String::new(),
        };
        rows.push(vec![
            TERM_NAMES[i].to_string(),
            names[i].to_string(),
            s.unit.clone(),
            fit_cell(&s),
            readout,
        ]);
    }
    h.push_str(&aligned(&rows, "  "));
    if let Some(g) = f.gof.filter(|g| *g > GOF_MISFIT) {
        let _ = writeln!(
            h,
            "  {}",
            style.bold(&format!(
                "gof {}: the five-term model does not describe this curve (about 1 when it \
                 does), so the fit's values can be far off and its intervals too narrow; the \
                 read-outs come from the curve alone, and `diagnose` says where the curve \
                 departs and why",
                sig3(g)
            ))
        );
    }
    if let Some(q) = f.q_over_lsb {
        let _ = writeln!(
            h,
            "  Q is {} x the quantization of the LSB alone (LSB/sqrt(12))",
            sig3(q)
        );
    }
    let limits: Vec<&LimitResult> = res
        .limits
        .iter()
        .filter(|l| (l.file, l.run) == k && l.rec.channel == f.channel)
        .filter(|l| l.rec.over == Scope::Run)
        .map(|l| &l.rec)
        .collect();
    for (j, c) in limit_cells(&limits, style).iter().enumerate() {
        let _ = writeln!(
            h,
            "  {} {c}",
            if j == 0 { "limits:   " } else { "          " }
        );
    }
    if let Some(d) = res.diagnosis_in(k, &f.channel) {
        let _ = writeln!(h, "  diagnosis: {}", diagnosis_line(d, &f.unit, style));
    }
}
