//! `analyze`: replays text columns or captures of frames through the live pipeline
//! (`crate::pipeline`), one run per input: the same source, decode, analysis and writer stages
//! as `listen`, with a file or standard input as the source.

use std::io::{BufReader, IsTerminal, Write};
use std::path::PathBuf;

use anyhow::{Context, Result};

use super::{
    analysis_options, format_and_tau0, open_input, select_channels, usage, AnalyzeArgs, DataArgs,
};
use crate::analysis::{AnalysisOptions, ChannelSetup, RunAnalysis};
use crate::frame::FrameDescriptor;
use crate::input::text::TextReader;
use crate::model::aggregate::{aggregate_channels, RunCoefs};
use crate::pipeline::{RecordQueue, RecordWriter, RunControl};
use crate::sink::records::Record;
use crate::source::{Pace, SourceSpec};

/// Text columns the analysis does not treat as channels (the simulator's temperature column).
const AUXILIARY_COLUMNS: [&str; 1] = ["temperature_c"];

pub fn run(a: &AnalyzeArgs) -> Result<()> {
    let writer = RecordWriter::spawn(output_writer(&a.data)?);
    let result = analyze_all(a, writer.queue());
    let written = writer.finish();
    result?;
    written.context("writing the JSON lines")?;
    Ok(())
}

/// Where the JSON lines go: `--out FILE` or standard output.
pub(crate) fn output_writer(d: &DataArgs) -> Result<Box<dyn Write + Send>> {
    Ok(match &d.out {
        Some(p) => {
            let f = std::fs::File::create(p)
                .with_context(|| format!("cannot create output {}", p.display()))?;
            Box::new(std::io::BufWriter::new(f))
        }
        None => Box::new(std::io::BufWriter::new(std::io::stdout())),
    })
}

/// Parses `--pace`.
pub(crate) fn parse_pace(s: &str) -> Result<bool> {
    match s {
        "max" => Ok(false),
        "realtime" => Ok(true),
        other => Err(usage(format!("--pace `{other}`: expected max or realtime"))),
    }
}

fn analyze_all(a: &AnalyzeArgs, queue: &RecordQueue) -> Result<()> {
    let d = &a.data;
    let realtime = parse_pace(&a.pace)?;
    let (descriptor, tau0) = format_and_tau0(d)?;
    let base = analysis_options(d, tau0)?;
    let several = a.inputs.len() > 1;
    let ctl = RunControl {
        handle_signals: true,
        show_progress: std::io::stderr().is_terminal(),
        ..RunControl::default()
    };
    let mut fits = Vec::new();
    for (run, input) in a.inputs.iter().enumerate() {
        if ctl.shutdown.is_cancelled() {
            break;
        }
        let mut opts = base.clone();
        opts.run = several.then_some(run);
        let analysis = match &descriptor {
            None => analyze_text(input, d, opts, realtime, queue, &ctl)?,
            Some(desc) => analyze_frames(input, desc, d, opts, realtime, queue, &ctl)?,
        };
        fits.push(analysis.last_fits());
    }
    if several {
        let aggregates = aggregate_channels(&run_coefs(&fits));
        for a in &aggregates {
            queue.push_final(Record::Aggregate(super::aggregate::record(a)));
        }
        // Run-to-run datasheet limits (e.g. the sd of B over runs) in a closing summary.
        let j = crate::model::limits::judge_runs(&base.limits, &aggregates);
        if !j.results.is_empty() {
            queue.push_final(Record::Summary(crate::sink::records::SummaryRecord {
                kind: "summary".into(),
                input: a.inputs.join(" "),
                run: None,
                channels: Vec::new(),
                tau0,
                t_data: 0.0,
                samples: Vec::new(),
                segments: Vec::new(),
                bad_rows: 0,
                overlap: d.overlap.clone(),
                elapsed_s: 0.0,
                limits: j.limits_json(),
                pass: j.pass,
            }));
        }
    }
    Ok(())
}

/// Text columns: a reader thread feeds the analysis.
fn analyze_text(
    input: &str,
    d: &DataArgs,
    opts: AnalysisOptions,
    realtime: bool,
    queue: &RecordQueue,
    ctl: &RunControl,
) -> Result<RunAnalysis> {
    let path = PathBuf::from(input);
    let tau0 = opts.accum.tau0_s;
    let reader = TextReader::new(BufReader::with_capacity(1 << 16, open_input(input)?), &path)
        .map_err(anyhow::Error::new)?;
    let setups: Vec<ChannelSetup> = reader
        .names()
        .iter()
        .enumerate()
        .filter(|(_, n)| !AUXILIARY_COLUMNS.contains(&n.as_str()))
        .map(|(i, n)| ChannelSetup {
            name: n.clone(),
            unit: d.unit.clone(),
            column: i,
            counts_lsb: None,
        })
        .collect();
    let setups = select_channels(setups, &d.channels, input)?;
    let analysis = RunAnalysis::new(input, setups, opts);
    let rows_per_s = realtime.then_some(1.0 / tau0);
    Ok(crate::pipeline::run_text(reader, path, rows_per_s, analysis, queue, ctl)?.analysis)
}

/// A capture of frames (a file, or `-`): the file source, the decode stage, the analysis.
fn analyze_frames(
    input: &str,
    desc: &FrameDescriptor,
    d: &DataArgs,
    opts: AnalysisOptions,
    realtime: bool,
    queue: &RecordQueue,
    ctl: &RunControl,
) -> Result<RunAnalysis> {
    let setups = select_channels(ChannelSetup::for_frames(desc), &d.channels, input)?;
    let analysis = RunAnalysis::new(input, setups, opts);
    let pace = if realtime {
        Pace::Realtime {
            bytes_per_s: desc.frame_len() as f64 * desc.rate_hz,
        }
    } else {
        Pace::Max
    };
    let spec = if input == "-" {
        SourceSpec::Stdin { pace }
    } else {
        SourceSpec::File {
            path: input.into(),
            pace,
        }
    };
    Ok(crate::pipeline::run_frames(spec, desc, analysis, queue, ctl)?.analysis)
}

/// Each run's determined coefficients, for the run-to-run statistics.
fn run_coefs(
    runs: &[Vec<(String, String, Option<crate::model::fit::FitResult>)>],
) -> Vec<Vec<RunCoefs>> {
    runs.iter()
        .map(|run| {
            run.iter()
                .filter_map(|(name, unit, fit)| Some(RunCoefs::from_fit(name, unit, fit.as_ref()?)))
                .collect()
        })
        .collect()
}
