//! `diagnose`: the sim-to-real gap of each channel of a run (text columns or a capture):
//! where the measured curve leaves the five-term model, which effect closes it, and how far;
//! with `--holdout`, the effects fitted on INPUT judged on a second run of the same unit.

use std::io::{BufReader, Read};
use std::path::Path;

use anyhow::{Context, Result};

use super::{format_and_tau0, open_input, usage, DiagnoseArgs};
use crate::analysis::InputKind;
use crate::frame::{Decoder, FrameDescriptor, FrameEvent};
use crate::gap::{diagnose, holdout_gap, DiagnoseOptions, DiagnosisRecord, GapConfig, GapEvidence};
use crate::input::text::{TextReader, BATCH_ROWS};

/// One channel's evidence, gathered from a whole input.
struct Gathered {
    names: Vec<String>,
    evidence: Vec<GapEvidence>,
}

/// Reads a run and feeds every selected channel's increments to its evidence.
fn gather(
    input: &str,
    a: &DiagnoseArgs,
    desc: Option<&FrameDescriptor>,
    tau0: f64,
) -> Result<Gathered> {
    let cfg = GapConfig::new(tau0);
    let mut names = Vec::new();
    let mut evidence = Vec::new();
    let mut columns = Vec::new();
    let wanted = |n: &str| a.channel.as_ref().is_none_or(|c| c.iter().any(|w| w == n));
    match desc {
        None => {
            let kind = if a.data.rate {
                InputKind::Rate
            } else if a.data.phase {
                InputKind::Phase
            } else {
                InputKind::Increments
            };
            let path = Path::new(input);
            let mut reader =
                TextReader::new(BufReader::with_capacity(1 << 16, open_input(input)?), path)
                    .map_err(anyhow::Error::new)?;
            for (i, n) in reader.names().iter().enumerate() {
                if n != "temperature_c" && wanted(n) {
                    names.push(n.clone());
                    columns.push(i);
                    evidence.push(GapEvidence::new(cfg.clone()));
                }
            }
            if names.len() > crate::ranges::MAX_CHANNELS {
                return Err(super::usage(format!(
                    "{input}: {} channels; at most {} are diagnosed in one run (choose some \
                     with --channel)",
                    names.len(),
                    crate::ranges::MAX_CHANNELS
                )));
            }
            let width = reader.names().len();
            let mut last_phase: Vec<Option<f64>> = vec![None; columns.len()];
            let mut rows = Vec::with_capacity(BATCH_ROWS * width);
            loop {
                rows.clear();
                if reader
                    .read_rows(&mut rows, BATCH_ROWS)
                    .with_context(|| format!("reading {input}"))?
                    == 0
                {
                    break;
                }
                for row in rows.chunks_exact(width) {
                    for (k, (&col, ev)) in columns.iter().zip(evidence.iter_mut()).enumerate() {
                        let v = row[col];
                        match kind {
                            InputKind::Phase => {
                                match (last_phase[k], v.is_finite()) {
                                    (Some(p), true) => ev.push_increment(v - p),
                                    (_, false) => ev.push_gap(1),
                                    (None, true) => {}
                                }
                                last_phase[k] = v.is_finite().then_some(v);
                            }
                            _ if v.is_nan() => ev.push_gap(1),
                            InputKind::Increments => ev.push_increment(v),
                            InputKind::Rate => ev.push_increment(v * tau0),
                        }
                    }
                }
            }
        }
        Some(desc) => {
            let chans = desc.channels();
            for (i, c) in chans.iter().enumerate() {
                if wanted(&c.name) {
                    names.push(c.name.clone());
                    columns.push(i);
                    evidence.push(GapEvidence::new(cfg.clone()));
                }
            }
            let scales: Vec<Option<f64>> = chans.iter().map(|c| c.scale).collect();
            let mut src = open_input(input)?;
            let mut decoder = Decoder::new(desc.clone());
            let mut buf = vec![0u8; 1 << 16];
            loop {
                let n = src
                    .read(&mut buf)
                    .with_context(|| format!("reading {input}"))?;
                if n == 0 {
                    decoder.finish();
                } else {
                    decoder.push(&buf[..n]);
                }
                for ev in decoder.drain() {
                    match ev {
                        FrameEvent::Frame(f) => {
                            for (&col, e) in columns.iter().zip(evidence.iter_mut()) {
                                match f.values.get(col).copied().flatten() {
                                    Some(v) => e.push_increment(v.physical(scales[col])),
                                    None => e.push_gap(1),
                                }
                            }
                        }
                        FrameEvent::Gap { missing } => {
                            evidence.iter_mut().for_each(|e| e.push_gap(missing))
                        }
                    }
                }
                if n == 0 {
                    break;
                }
            }
        }
    }
    if let Some(c) = &a.channel {
        for w in c {
            if !names.contains(w) {
                return Err(usage(format!(
                    "--channel: `{w}` is not a channel of {input}"
                )));
            }
        }
    }
    Ok(Gathered { names, evidence })
}

pub fn run(a: &DiagnoseArgs) -> Result<()> {
    let d = &a.data;
    if d.checkpoint_every.is_some() || d.resume {
        return Err(usage(
            "diagnose reads its input in one pass and keeps no checkpoints: --checkpoint-every \
             and --resume are for analyze, listen and run",
        ));
    }
    let mut sink = crate::sink::json::JsonLines::new(super::analyze::output_writer(d)?);
    let (desc, tau0) = format_and_tau0(d)?;
    let opts = DiagnoseOptions::default();
    let mut main = gather(&a.input, a, desc.as_ref(), tau0)?;
    let mut held = match &a.holdout {
        Some(h) => Some(gather(h, a, desc.as_ref(), tau0)?),
        None => None,
    };
    for (i, name) in main.names.iter().enumerate() {
        let snap = main.evidence[i].snapshot();
        let diag = match diagnose(&snap, &opts) {
            Ok(x) => x,
            Err(e) => {
                tracing::warn!("{}: channel {name}: {e}", a.input);
                continue;
            }
        };
        let holdout = held.as_mut().and_then(|h| {
            let j = h.names.iter().position(|n| n == name)?;
            let snap2 = h.evidence[j].snapshot();
            holdout_gap(&diag, &snap2, &opts)
                .map_err(|e| tracing::warn!("{}: holdout channel {name}: {e}", a.input))
                .ok()
        });
        let rec = DiagnosisRecord::new(name, &diag, holdout, true);
        sink.write(&rec)?;
    }
    sink.flush()?;
    Ok(())
}
