//! `run --config FILE`: the pipeline with source, channels, statistics, outputs and limits from
//! a stand config (`crate::stand`; `config/stand.toml` is the example).

use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result};
use clap::Args;

use super::select_channels;
use crate::allan::accum::AccumConfig;
use crate::analysis::{AnalysisOptions, InputKind, RunAnalysis};
use crate::error::UsageError;
use crate::frame::FrameDescriptor;
use crate::model::fit::FitOptions;
use crate::pipeline::{RecordWriter, RunControl};
use crate::source::{Pace, SourceSpec};
use crate::stand::StandConfig;

#[derive(Debug, Args)]
pub struct RunArgs {
    /// The stand config (TOML; see config/stand.toml).
    #[arg(long)]
    pub config: PathBuf,
}

pub fn run(r: &RunArgs) -> Result<()> {
    let cfg = StandConfig::load(&r.config).map_err(anyhow::Error::new)?;
    let desc = FrameDescriptor::load(&cfg.format).map_err(|e| {
        anyhow::Error::new(UsageError::Config {
            file: cfg.file.clone(),
            key: "source.format".into(),
            problem: e.to_string(),
        })
    })?;
    let limits = crate::model::limits::from_tables(&cfg.limits_raw, &cfg.file).map_err(|errs| {
        let all = errs
            .iter()
            .map(|e| e.to_string())
            .collect::<Vec<_>>()
            .join("\n");
        anyhow::Error::new(UsageError::Option(all))
    })?;
    let mut spec = cfg.source.clone();
    let live = spec.is_live();
    if let SourceSpec::File { pace, .. } | SourceSpec::Stdin { pace } = &mut spec {
        if let Pace::Realtime { bytes_per_s } = pace {
            *bytes_per_s = desc.frame_len() as f64 * desc.rate_hz;
        }
    }
    let mut accum = AccumConfig::new(desc.tau0_s());
    accum.stats = cfg.stats;
    accum.taus = cfg.taus.clone();
    accum.overlap = cfg.overlap;
    let opts = AnalysisOptions {
        accum,
        kind: InputKind::Increments,
        // Live: interim records on wall time (the pipeline); replay: on data time.
        every_s: if live { None } else { cfg.every_s },
        fit: cfg.fit.map(|method| FitOptions {
            method,
            ..FitOptions::default()
        }),
        run: None,
        limits,
        diagnose: cfg.diagnose,
    };
    let setups = select_channels(
        crate::analysis::ChannelSetup::for_frames(&desc),
        &cfg.channels,
        &spec.name(),
    )
    .map_err(|e| {
        anyhow::Error::new(UsageError::Config {
            file: cfg.file.clone(),
            key: "channels.include".into(),
            problem: e.to_string(),
        })
    })?;
    let analysis = RunAnalysis::new(&spec.name(), setups, opts);
    let out: Box<dyn Write + Send> = match &cfg.output {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p)
                .with_context(|| format!("cannot create output {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout())),
    };
    let ctl = RunControl {
        duration: cfg.duration_s.map(Duration::from_secs_f64),
        capture: cfg.capture.clone(),
        handle_signals: true,
        every_wall: if live {
            cfg.every_s.map(Duration::from_secs_f64)
        } else {
            None
        },
        show_progress: !live && std::io::IsTerminal::is_terminal(&std::io::stderr()),
        ..RunControl::default()
    };
    let writer = RecordWriter::spawn(out);
    let result = crate::pipeline::run_frames(spec, &desc, analysis, writer.queue(), &ctl);
    let written = writer.finish();
    result?;
    written?;
    Ok(())
}
