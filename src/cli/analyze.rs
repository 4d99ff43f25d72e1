//! `analyze`: replays text columns or captures of frames through the analysis, one run per
//! input; a reader thread decodes, the analysis runs on this one.

use std::io::{BufReader, Read};
use std::path::PathBuf;

use anyhow::{Context, Result};

use super::{
    analysis_options, format_and_tau0, open_input, output, select_channels, AnalyzeArgs, DataArgs,
};
use crate::analysis::{AnalysisOptions, ChannelSetup, RunAnalysis};
use crate::frame::{Decoder, FrameDescriptor};
use crate::input::text::{TextReader, BATCH_ROWS};
use crate::input::Chunk;
use crate::model::aggregate::{aggregate_channels, RunCoefs};
use crate::sink::json::JsonLines;
use crate::sink::records::{HealthRecord, Record};

/// Capacity of the channel between the reader thread and the analysis: a few chunks, so
/// reading runs ahead of the analysis by at most that much memory.
const CHUNK_QUEUE: usize = 4;

/// Text columns the analysis does not treat as channels (the simulator's temperature column).
const AUXILIARY_COLUMNS: [&str; 1] = ["temperature_c"];

pub fn run(a: &AnalyzeArgs) -> Result<()> {
    let d = &a.data;
    let mut sink = output(d)?;
    let (descriptor, tau0) = format_and_tau0(d)?;
    let base = analysis_options(d, tau0)?;
    let several = a.inputs.len() > 1;
    let mut fits = Vec::new();
    for (run, input) in a.inputs.iter().enumerate() {
        let mut opts = base.clone();
        opts.run = several.then_some(run);
        let analysis = match &descriptor {
            None => analyze_text(input, d, opts, &mut sink)?,
            Some(desc) => analyze_frames(input, desc, d, opts, &mut sink)?,
        };
        fits.push(analysis.last_fits());
    }
    if several {
        for r in aggregate_records(&fits) {
            sink.write(&r)?;
        }
    }
    sink.flush()?;
    Ok(())
}

/// Reads a text input on a thread of its own and feeds the analysis on this one.
fn analyze_text(
    input: &str,
    d: &DataArgs,
    opts: AnalysisOptions,
    sink: &mut JsonLines,
) -> Result<RunAnalysis> {
    let path = PathBuf::from(input);
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
    let width = reader.names().len();
    let mut analysis = RunAnalysis::new(input, setups, opts);
    let (tx, rx) = crossbeam_channel::bounded::<Chunk>(CHUNK_QUEUE);
    let reader_thread = std::thread::spawn(move || -> Result<u64> {
        let mut reader = reader;
        loop {
            let mut values = Vec::with_capacity(BATCH_ROWS * width);
            let n = reader
                .read_rows(&mut values, BATCH_ROWS)
                .with_context(|| format!("reading {}", path.display()))?;
            if n == 0 {
                return Ok(reader.bad_rows());
            }
            if tx.send(Chunk::Rows { values, width }).is_err() {
                return Ok(reader.bad_rows());
            }
        }
    });
    run_chunks(&mut analysis, rx, sink)?;
    let bad = reader_thread
        .join()
        .map_err(|_| anyhow::anyhow!("the reader thread panicked"))??;
    analysis.add_bad_rows(bad);
    finish_run(&mut analysis, None, sink)?;
    Ok(analysis)
}

/// Replays a capture of frames: a reader thread decodes, the analysis runs here.
fn analyze_frames(
    input: &str,
    desc: &FrameDescriptor,
    d: &DataArgs,
    opts: AnalysisOptions,
    sink: &mut JsonLines,
) -> Result<RunAnalysis> {
    let setups: Vec<ChannelSetup> = desc
        .channels()
        .into_iter()
        .enumerate()
        .map(|(i, c)| ChannelSetup {
            name: c.name,
            unit: c.unit,
            column: i,
            counts_lsb: c.scale,
        })
        .collect();
    let setups = select_channels(setups, &d.channels, input)?;
    let mut analysis = RunAnalysis::new(input, setups, opts);
    let mut src = open_input(input)?;
    let mut decoder = Decoder::new(desc.clone());
    let (tx, rx) = crossbeam_channel::bounded::<Chunk>(CHUNK_QUEUE);
    let path = input.to_string();
    let reader_thread = std::thread::spawn(move || -> Result<Decoder> {
        let mut buf = vec![0u8; 1 << 16];
        loop {
            let n = src
                .read(&mut buf)
                .with_context(|| format!("reading {path}"))?;
            if n == 0 {
                decoder.finish();
            } else {
                decoder.push(&buf[..n]);
            }
            let events: Vec<_> = decoder.drain().collect();
            if !events.is_empty() && tx.send(Chunk::Frames(events)).is_err() {
                return Ok(decoder);
            }
            if n == 0 {
                return Ok(decoder);
            }
        }
    });
    run_chunks(&mut analysis, rx, sink)?;
    let decoder = reader_thread
        .join()
        .map_err(|_| anyhow::anyhow!("the reader thread panicked"))??;
    let h = decoder.health();
    let mut health = HealthRecord {
        kind: "health".into(),
        frames: h.frames,
        crc_errors: h.crc_errors,
        resyncs: h.resyncs,
        missing: h.missing,
        duplicates: h.duplicates,
        bytes_skipped: h.bytes_skipped,
        extra: serde_json::Map::new(),
        run: analysis.summary().run,
    };
    if let Ok(serde_json::Value::Object(all)) = serde_json::to_value(h) {
        for (k, v) in all {
            if !matches!(
                k.as_str(),
                "frames" | "crc_errors" | "resyncs" | "missing" | "duplicates" | "bytes_skipped"
            ) {
                health.extra.insert(k, v);
            }
        }
    }
    finish_run(&mut analysis, Some(health), sink)?;
    Ok(analysis)
}

fn run_chunks(
    analysis: &mut RunAnalysis,
    rx: crossbeam_channel::Receiver<Chunk>,
    sink: &mut JsonLines,
) -> Result<()> {
    let mut out = Vec::new();
    for chunk in rx {
        analysis.push_chunk(&chunk, &mut out);
        if !out.is_empty() {
            for r in out.drain(..) {
                sink.write(&r)?;
            }
            sink.flush()?;
        }
    }
    Ok(())
}

fn finish_run(
    analysis: &mut RunAnalysis,
    health: Option<HealthRecord>,
    sink: &mut JsonLines,
) -> Result<()> {
    for r in analysis.records(true) {
        sink.write(&r)?;
    }
    if let Some(h) = health {
        sink.write(&h)?;
    }
    sink.write(&analysis.summary())?;
    sink.flush()?;
    Ok(())
}

/// `aggregate` records (the seed paper's table 2) from the final fits of several runs.
pub fn aggregate_records(
    runs: &[Vec<(String, String, Option<crate::model::fit::FitResult>)>],
) -> Vec<Record> {
    let coefs: Vec<Vec<RunCoefs>> = runs
        .iter()
        .map(|run| {
            run.iter()
                .filter_map(|(name, unit, fit)| Some(RunCoefs::from_fit(name, unit, fit.as_ref()?)))
                .collect()
        })
        .collect();
    aggregate_channels(&coefs)
        .iter()
        .map(|a| Record::Aggregate(super::aggregate::record(a)))
        .collect()
}
