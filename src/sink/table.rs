//! The readable table a person sees when standard output is a terminal (docs/records.md: pipes
//! and files always get JSON lines). [`render`] is a pure function from typed results
//! ([`Results`]) to text: per run a heading (input, data length, whether it was read to its end,
//! the decoder's health), per channel the five terms in datasheet units with their 95% intervals
//! or `not determined` (with the interval's upper bound), the IEEE 952 read-outs beside the
//! fitted N, B and K (model::readout), the datasheet limits with PASS/FAIL, and the diagnosis in
//! one line; then the run-to-run statistics of several runs and the overall verdict.
//! [`TableWriter`] is the adapter the binary puts in place of standard output: it takes the JSON
//! lines the record writer produces, keeps the final records and prints a run's table when its
//! `summary` arrives (the rest when it is dropped). Whether standard output is a terminal is the
//! binary's business.

use std::fmt::Write as _;
use std::io::Write;

use serde_json::Value;

use crate::gap::record::RecordedEffect;
use crate::gap::DiagnosisRecord;
use crate::model::limits::{LimitResult, Scope, Verdict};
use crate::model::terms::TERM_NAMES;
use crate::model::units::{
    datasheet_factors, datasheet_units, native_units, IncrementUnit, SensorKind,
};
use crate::sink::records::{AggregateRecord, FitRecord, ReadoutRecord, ReadoutsRecord};
use crate::sink::results::{Labelled, ResultFile, Results, RunSummary};

/// How the text is dressed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TableStyle {
    /// ANSI colours for PASS/FAIL and warnings (a terminal that has not asked for `NO_COLOR`).
    pub color: bool,
}

impl TableStyle {
    fn paint(&self, code: &str, text: &str) -> String {
        if self.color {
            format!("\x1b[{code}m{text}\x1b[0m")
        } else {
            text.to_string()
        }
    }
    fn red(&self, t: &str) -> String {
        self.paint("1;31", t)
    }
    fn green(&self, t: &str) -> String {
        self.paint("1;32", t)
    }
    fn yellow(&self, t: &str) -> String {
        self.paint("1;33", t)
    }
    fn bold(&self, t: &str) -> String {
        self.paint("1", t)
    }
    fn dim(&self, t: &str) -> String {
        self.paint("2", t)
    }
}

/// A number with three significant digits: plain between 1e-3 and 1e5, else in e-notation.
pub fn sig3(x: f64) -> String {
    if !x.is_finite() {
        return "-".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        // Trailing zeros are kept, so a column of one coefficient reads evenly.
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

/// A duration in s for the headings: `300 s`, `2.5 min`, `3.0 h`.
fn duration_text(s: f64) -> String {
    if s >= 2.0 * 3600.0 {
        format!("{:.1} h", s / 3600.0)
    } else if s >= 120.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{} s", sig3(s))
    }
}

/// A tau in s: `16 ms`, `16.4 s`.
fn tau_text(s: f64) -> String {
    if s < 1.0 {
        format!("{} ms", sig3(s * 1e3))
    } else {
        format!("{} s", sig3(s))
    }
}

/// The name of each term for a kind of sensor (IEEE 952's names for a gyro; the velocity and
/// acceleration names for an accelerometer).
fn term_names(kind: Option<SensorKind>) -> [&'static str; 5] {
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
struct Shown {
    value: Option<f64>,
    lo: Option<f64>,
    hi: Option<f64>,
    unit: String,
}

/// A fit's coefficient `i` in datasheet units when the record has them, else native.
fn coef_shown(f: &FitRecord, i: usize) -> Shown {
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

fn interval(lo: Option<f64>, hi: Option<f64>) -> String {
    match (lo, hi) {
        (Some(l), Some(h)) => format!("[{}, {}]", sig3(l), sig3(h)),
        _ => String::new(),
    }
}

/// A fit cell: `0.00420 [0.00416, 0.00424]`, or `not determined (< 3.42)`.
fn fit_cell(s: &Shown) -> String {
    match s.value {
        Some(v) => format!("{} {}", sig3(v), interval(s.lo, s.hi)),
        None => match s.hi.filter(|h| *h > 0.0) {
            Some(h) => format!("not determined (< {})", sig3(h)),
            None => "not determined".into(),
        },
    }
}

/// A read-out cell in the fit's shown unit (datasheet when the read-out has it).
fn readout_cell(r: Option<&ReadoutRecord>, which: usize) -> String {
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
    format!("{} {} {at}", sig3(v), interval(Some(lo), Some(hi)))
}

/// The widest cell of each column, in characters.
fn column_widths(rows: &[Vec<String>]) -> Vec<usize> {
    let n = rows.iter().map(Vec::len).max().unwrap_or(0);
    (0..n)
        .map(|j| {
            rows.iter()
                .filter_map(|r| r.get(j))
                .map(|c| c.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect()
}

/// Columns padded to their widest cell (the last column is not padded).
fn aligned(rows: &[Vec<String>], indent: &str) -> String {
    let widths = column_widths(rows);
    let mut out = String::new();
    for r in rows {
        let mut line = indent.to_string();
        for (j, c) in r.iter().enumerate() {
            line.push_str(c);
            if j + 1 < r.len() {
                let pad = widths[j] - c.chars().count() + 2;
                line.extend(std::iter::repeat_n(' ', pad));
            }
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

/// A run: its file and its `run` index inside the file.
type RunKey = (usize, Option<usize>);

fn runs_in_order(res: &Results) -> Vec<RunKey> {
    let mut keys: Vec<RunKey> = Vec::new();
    let mut add = |k: RunKey| {
        if !keys.contains(&k) {
            keys.push(k);
        }
    };
    for f in &res.fits {
        add((f.file, f.run));
    }
    for d in &res.diagnoses {
        add((d.file, d.run));
    }
    for s in &res.summaries {
        // The closing summary of several runs (run-to-run limits) has no channels.
        if !s.rec.record.channels.is_empty() {
            add((s.file, s.run));
        }
    }
    keys
}

fn summary_of(res: &Results, k: RunKey) -> Option<&RunSummary> {
    res.summaries
        .iter()
        .rev()
        .find(|s| (s.file, s.run) == k)
        .map(|s| &s.rec)
}

/// The heading of a run: what was read, how much, whether to its end, and the decoder's health.
fn run_heading(h: &mut String, res: &Results, k: RunKey, style: &TableStyle) {
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
            } else if tc.gaps + tc.backwards + tc.irregular + tc.discontinuities > 0 {
                notes.push(format!(
                    "time column `{name}`: {} jumps = {} missing samples, {} backwards, {} off-step",
                    tc.gaps,
                    tc.missing_samples,
                    tc.backwards,
                    tc.irregular + tc.discontinuities
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

/// The final fit of each channel of a run (the last one written when none is final).
fn fits_of(res: &Results, k: RunKey) -> Vec<&Labelled<FitRecord>> {
    let mut out: Vec<&Labelled<FitRecord>> = Vec::new();
    for f in res.fits.iter().filter(|f| (f.file, f.run) == k) {
        match out.iter_mut().find(|g| g.rec.channel == f.rec.channel) {
            Some(g) => {
                if f.rec.r#final || !g.rec.r#final {
                    *g = f;
                }
            }
            None => out.push(f),
        }
    }
    out
}

fn diagnosis_of<'a>(res: &'a Results, k: RunKey, channel: &str) -> Option<&'a DiagnosisRecord> {
    let mine: Vec<&Labelled<DiagnosisRecord>> = res
        .diagnoses
        .iter()
        .filter(|d| (d.file, d.run) == k && d.rec.channel == channel)
        .collect();
    mine.iter()
        .rev()
        .find(|d| d.rec.is_final)
        .or(mine.last())
        .map(|d| &d.rec)
}

/// An effect in a few words with its parameters named and in units, rates in datasheet units
/// beside the record's u/s (sink::effect_text).
pub fn effect_brief(effect: &RecordedEffect, unit: &str) -> String {
    let (name, ps) = crate::sink::effect_text::effect_parts(effect, unit, &sig3);
    if ps.is_empty() {
        return name;
    }
    let list: Vec<String> = ps
        .iter()
        .map(|p| format!("{} {}", p.name, p.value))
        .collect();
    format!("{name} [{}]", list.join(", "))
}

/// The diagnosis in one line: the verdict, what explains the gap, and the gap before and after.
pub fn diagnosis_line(d: &DiagnosisRecord, unit: &str, style: &TableStyle) -> String {
    let gap = if d.effects.is_empty() {
        format!("gap {}", sig3(d.gap_before))
    } else {
        format!("gap {} -> {}", sig3(d.gap_before), sig3(d.gap_after))
    };
    let effects: Vec<String> = d
        .effects
        .iter()
        .map(|e| effect_brief(&e.effect, unit))
        .collect();
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
    if let Some(ho) = &d.holdout {
        let _ = write!(
            line,
            "; on the held-out run gap {} -> {}{}",
            sig3(ho.gap_before),
            sig3(ho.gap_after),
            if ho.carried { "" } else { " (did not carry)" }
        );
    }
    line
}

/// The limits judged on one channel of a run, one cell each: `N max 0.005 deg/sqrt(h): PASS`.
fn limit_cells(limits: &[&LimitResult], style: &TableStyle) -> Vec<String> {
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

fn channel_block(h: &mut String, res: &Results, k: RunKey, f: &FitRecord, style: &TableStyle) {
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
    if let Some(d) = diagnosis_of(res, k, &f.channel) {
        let _ = writeln!(h, "  diagnosis: {}", diagnosis_line(d, &f.unit, style));
    }
}

/// Diagnoses of channels that have no fit (the `diagnose` command writes only diagnoses).
fn diagnosis_only(h: &mut String, res: &Results, k: RunKey, fitted: &[&str], style: &TableStyle) {
    let mut seen: Vec<&str> = Vec::new();
    for d in res.diagnoses.iter().filter(|d| (d.file, d.run) == k) {
        let ch = d.rec.channel.as_str();
        if fitted.contains(&ch) || seen.contains(&ch) {
            continue;
        }
        seen.push(ch);
        let d = diagnosis_of(res, k, ch).unwrap_or(&d.rec);
        let unit = d.unit.as_deref().unwrap_or("u");
        let _ = writeln!(
            h,
            "\n{}{}  diagnosis: {}",
            style.bold(ch),
            d.unit
                .as_deref()
                .map(|u| format!(" [{u}]"))
                .unwrap_or_default(),
            diagnosis_line(d, unit, style)
        );
        // The five terms refitted with the effects in, in datasheet units when the unit is known
        // (terms the fit set to zero are left out).
        let (factors, units) = match IncrementUnit::parse(unit) {
            Some(iu) => (
                datasheet_factors(&iu),
                datasheet_units(iu.kind).map(String::from),
            ),
            None => ([1.0; 5], native_units(unit)),
        };
        let terms: Vec<String> = (0..5)
            .filter(|&i| d.final_coef[i] > 0.0)
            .map(|i| {
                format!(
                    "{} {} {}",
                    TERM_NAMES[i],
                    sig3(d.final_coef[i] * factors[i]),
                    units[i]
                )
            })
            .collect();
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

/// The seed paper's column order in table 2 (R, K, B, N, Q), as the report has it.
const PAPER_ORDER: [usize; 5] = [4, 3, 2, 1, 0];

/// The run-to-run statistics of every channel in the seed paper's table 2 layout, as the
/// report shows it: one table per channel, one row per run labelled by its input (values from
/// `runs`' final fits), the coefficients as columns (R, K, B, N, Q) in datasheet units where the
/// channel's unit is known, then the mean, the 95% interval of the mean (mean +- 1.96 sd/sqrt(n),
/// as the paper), the sd and the number of runs that determined each coefficient (from `res`'s
/// `aggregate` records). `-` = not determined.
fn aggregates(h: &mut String, res: &Results, runs: &Results, style: &TableStyle) {
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
        let _ = writeln!(h, "\n{} [{unit}]", style.bold(&ch));
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

/// Columns padded to their widest cell, the first left-aligned and the others right-aligned
/// (numbers line up on their last digit).
fn aligned_right(rows: &[Vec<String>], indent: &str) -> String {
    let widths = column_widths(rows);
    let mut out = String::new();
    for r in rows {
        let mut line = indent.to_string();
        for (j, c) in r.iter().enumerate() {
            let pad = widths[j] - c.chars().count();
            if j == 0 {
                line.push_str(c);
                line.extend(std::iter::repeat_n(' ', pad));
            } else {
                line.push_str("  ");
                line.extend(std::iter::repeat_n(' ', pad));
                line.push_str(c);
            }
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

/// The overall verdict of the datasheet limits: every judged bound, and the runs' `pass`.
fn verdict_line(res: &Results, style: &TableStyle) -> Option<String> {
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

/// The whole table of `res` (every run in it, then the run-to-run statistics and the verdict).
pub fn render(res: &Results, style: &TableStyle) -> String {
    render_with_runs(res, res, style)
}

/// As [`render`], with the rows of the run-to-run table taken from `runs`' final fits (records
/// printed earlier, or the `aggregate` command's input files).
pub fn render_with_runs(res: &Results, runs: &Results, style: &TableStyle) -> String {
    let mut h = String::new();
    for k in runs_in_order(res) {
        if !h.is_empty() {
            h.push('\n');
        }
        run_heading(&mut h, res, k, style);
        let fits = fits_of(res, k);
        for f in &fits {
            channel_block(&mut h, res, k, &f.rec, style);
        }
        let fitted: Vec<&str> = fits.iter().map(|f| f.rec.channel.as_str()).collect();
        diagnosis_only(&mut h, res, k, &fitted, style);
    }
    aggregates(&mut h, res, runs, style);
    if let Some(v) = verdict_line(res, style) {
        let _ = writeln!(h, "\n{v}");
    }
    h
}

/// The status line of a live run: time running, frames per second, frames lost and the newest
/// N of each channel (`latest`: `(channel, N, unit)`), the unit written once when all share it.
pub fn status_line(
    elapsed_s: f64,
    frames: u64,
    frames_per_s: f64,
    lost: Option<u64>,
    latest: &[(String, f64, String)],
) -> String {
    let running = if elapsed_s < 120.0 {
        format!("{elapsed_s:.0} s")
    } else {
        duration_text(elapsed_s)
    };
    let mut s = format!(
        "{running} running, {frames} frames, {} frames/s",
        sig3(frames_per_s.round())
    );
    if let Some(l) = lost {
        let _ = write!(s, ", {l} lost");
    }
    if !latest.is_empty() {
        let same = latest.iter().all(|x| x.2 == latest[0].2);
        let parts: Vec<String> = latest
            .iter()
            .map(|(c, v, u)| {
                if same {
                    format!("{c} {}", sig3(*v))
                } else {
                    format!("{c} {} {u}", sig3(*v))
                }
            })
            .collect();
        let _ = write!(s, " | N: {}", parts.join("  "));
        if same {
            let _ = write!(s, " {}", latest[0].2);
        }
    }
    s
}

/// Whether a [`TableWriter`] keeps a record: everything typed but the curves, which a table
/// does not show.
fn kept(v: &Value) -> bool {
    v.get("type")
        .and_then(Value::as_str)
        .is_some_and(|t| t != "curve")
}

/// A `Write` that takes JSON lines and prints tables ([`render`]) to `out`: a run's table when its
/// `summary` arrives, and whatever is left (run-to-run statistics, the `diagnose` command's
/// diagnoses) when it is dropped or [`TableWriter::finish`]ed.
pub struct TableWriter<W: Write> {
    out: W,
    style: TableStyle,
    line: Vec<u8>,
    pending: Vec<Value>,
    /// A hint under the first table: where the JSON lines are.
    hint: Option<String>,
    printed: bool,
    /// Called before a table is printed (the binary clears and stops its status line there).
    before_print: Option<Box<dyn FnMut() + Send>>,
    /// The final fits and summaries of the runs printed so far, for the rows of the run-to-run
    /// table when the `aggregate` records come.
    seen: Vec<Value>,
    /// Result files given by [`TableWriter::with_runs`] (the `aggregate` command's inputs): the
    /// rows of the run-to-run table instead of `seen`.
    run_files: Vec<ResultFile>,
}

impl<W: Write> TableWriter<W> {
    /// `hint` is printed once, dimmed, after the first table.
    pub fn new(out: W, style: TableStyle, hint: Option<String>) -> TableWriter<W> {
        TableWriter {
            out,
            style,
            line: Vec::new(),
            pending: Vec::new(),
            hint,
            printed: false,
            before_print: None,
            seen: Vec::new(),
            run_files: Vec::new(),
        }
    }

    /// The runs whose final fits fill the rows of the run-to-run table (one file each, named
    /// by its file name), when the records written are `aggregate` records only.
    pub fn with_runs(mut self, files: Vec<ResultFile>) -> Self {
        self.run_files = files;
        self
    }

    /// Calls `f` before each table is printed.
    pub fn before_print(mut self, f: Box<dyn FnMut() + Send>) -> Self {
        self.before_print = Some(f);
        self
    }

    fn take_line(&mut self, line: &[u8]) -> std::io::Result<()> {
        let Ok(v) = serde_json::from_slice::<Value>(line) else {
            // Not a record: shown as it came.
            self.out.write_all(line)?;
            return self.out.write_all(b"\n");
        };
        let summary = v.get("type").and_then(Value::as_str) == Some("summary");
        if kept(&v) {
            // Only the newest interim fit or diagnosis of a channel is kept.
            if v.get("final").and_then(Value::as_bool) == Some(false) {
                let same = |w: &Value| {
                    w.get("type") == v.get("type")
                        && w.get("channel") == v.get("channel")
                        && w.get("run") == v.get("run")
                        && w.get("unit") == v.get("unit")
                        && w.get("final").and_then(Value::as_bool) == Some(false)
                };
                self.pending.retain(|w| !same(w));
            }
            self.pending.push(v);
        }
        if summary {
            self.print_pending()?;
        }
        Ok(())
    }

    fn print_pending(&mut self) -> std::io::Result<()> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let records = std::mem::take(&mut self.pending);
        // A run of several units prints each unit's table as its summary comes, under its name.
        let unit = records
            .iter()
            .find_map(|r| crate::sink::unit_record::untag(&mut r.clone()));
        let res = Results::from_files(&[ResultFile {
            name: String::new(),
            records: records.clone(),
        }]);
        let is = |v: &Value, t: &str| v.get("type").and_then(Value::as_str) == Some(t);
        let text = if res.aggregates.is_empty() {
            render(&res, &self.style)
        } else {
            let runs = if self.run_files.is_empty() {
                let mut all = self.seen.clone();
                all.extend(records.iter().cloned());
                Results::from_files(&[ResultFile {
                    name: String::new(),
                    records: all,
                }])
            } else {
                Results::from_files(&self.run_files)
            };
            render_with_runs(&res, &runs, &self.style)
        };
        // Final fits and summaries are kept for a run-to-run table printed later.
        self.seen.extend(records.into_iter().filter(|v| {
            is(v, "summary")
                || (is(v, "fit") && v.get("final").and_then(Value::as_bool) == Some(true))
        }));
        if text.trim().is_empty() {
            return Ok(());
        }
        if let Some(f) = &mut self.before_print {
            f();
        }
        if self.printed {
            self.out.write_all(b"\n")?;
        }
        if let Some(u) = unit {
            writeln!(self.out, "unit {u}")?;
        }
        self.out.write_all(text.as_bytes())?;
        if !self.printed {
            if let Some(hint) = &self.hint {
                let t = self.style.dim(hint);
                writeln!(self.out, "{t}")?;
            }
        }
        self.printed = true;
        self.out.flush()
    }

    /// Prints what is left and flushes.
    pub fn finish(&mut self) -> std::io::Result<()> {
        if !self.line.is_empty() {
            let line = std::mem::take(&mut self.line);
            self.take_line(&line)?;
        }
        self.print_pending()?;
        self.out.flush()
    }
}

impl<W: Write> Write for TableWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let mut rest = buf;
        while let Some(i) = rest.iter().position(|&b| b == b'\n') {
            self.line.extend_from_slice(&rest[..i]);
            let line = std::mem::take(&mut self.line);
            if !line.iter().all(u8::is_ascii_whitespace) {
                self.take_line(&line)?;
            }
            rest = &rest[i + 1..];
        }
        self.line.extend_from_slice(rest);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

impl<W: Write> Drop for TableWriter<W> {
    fn drop(&mut self) {
        // The end of the records: a terminal has nowhere to report a failure to but itself.
        let _ = self.finish();
    }
}
