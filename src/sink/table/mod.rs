//! The readable table a person sees when standard output is a terminal (docs/records.md: pipes
//! and files always get JSON lines). [`render`] is a pure function from typed results
//! ([`Results`]) to text: per run a heading (input, data length, whether it was read to its end,
//! the decoder's health), per channel the five terms in datasheet units with their 95% intervals
//! or `not determined` (with the interval's upper bound), the IEEE 952 read-outs beside the
//! fitted N, B and K (model::readout), the datasheet limits with PASS/FAIL, and the diagnosis in
//! one line; then the run-to-run statistics of several runs and the overall verdict.
//! [`TableWriter`] is the adapter the binary puts in place of standard output: it takes the JSON
//! lines the record writer produces, each parsed once into its typed record, keeps the final
//! records and prints a run's table when its `summary` arrives (the rest when it is dropped). Whether standard output is a terminal is the
//! binary's business.
//!
//! Files: layout.rs (style, number formats, padded columns), channel.rs (a run's heading and
//! per-channel rows), diagnosis.rs (the diagnosis line), runs.rs (the several-runs table and the
//! verdict), writer.rs ([`TableWriter`]), status.rs (the live status line); here, the order of
//! the runs and [`render`].

use crate::gap::record::RecordedEffect;
use crate::gap::DiagnosisRecord;
use crate::model::limits::{LimitResult, Scope, Verdict};
use crate::model::terms::TERM_NAMES;
use crate::model::units::{
    datasheet_factors, datasheet_units, native_units, IncrementUnit, SensorKind,
};
use crate::sink::records::{AggregateRecord, FitRecord, ReadoutRecord, ReadoutsRecord, Record};
use crate::sink::results::{Labelled, ResultFile, Results, RunSummary};
use std::fmt::Write as _;
use std::io::Write;

mod channel;
mod diagnosis;
mod layout;
mod runs;
mod status;
mod writer;

use channel::*;
use diagnosis::*;
use layout::*;
use runs::*;

pub use diagnosis::{diagnosis_line, effect_brief};
pub use layout::{sig3, TableStyle};
pub use status::status_line;
pub use writer::TableWriter;

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
    if !res.diagnoses.is_empty() {
        let _ = writeln!(h, "{}", style.dim(GAP_LEGEND));
    }
    h
}

/// What a diagnosis's `gap` means, under a table that holds one (a blind review's reader saw
/// gaps in the thousands and near 1 and no scale for them; `G` in docs/gap.md, "Method in one
/// screen").
pub const GAP_LEGEND: &str = "(gap: how far the model's Allan curve is from the measured one \
     against the curve's own noise, r' S^-1 r over its expected value; about 1 where the model \
     holds, above 1.9 it does not)";
