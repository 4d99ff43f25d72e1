//! `run --config FILE`: the pipeline with source, channels, statistics, outputs and limits from
//! a stand config (`allanscope::stand`; `config/stand.toml` is the example).

use std::path::PathBuf;
use std::time::Duration;

use anyhow::Result;
use clap::Args;

use super::process::SignalWatch;
use super::select_channels;
use allanscope::allan::accum::AccumConfig;
use allanscope::analysis::{AnalysisOptions, InputKind};
use allanscope::error::UsageError;
use allanscope::model::fit::FitOptions;
use allanscope::pipeline::{RecordWriter, RunControl};
use allanscope::sink::output::OutputMode;
use allanscope::source::{Pace, SourceSpec};
use allanscope::stand::StandConfig;

#[derive(Debug, Args)]
pub struct RunArgs {
    /// The stand config (TOML; see config/stand.toml).
    #[arg(long)]
    pub config: PathBuf,
    /// Continue the run saved in the checkpoint beside the config's output (`[run]
    /// checkpoint_every`): a replayed file from where it stood, a live source from now on with
    /// the outage as a gap; records are appended to the output.
    #[arg(long)]
    pub resume: bool,
    /// Overwrite a non-empty output or capture file of the config: without it an earlier
    /// result is never touched.
    #[arg(long)]
    pub force: bool,
    /// Test hook: abort once this many frames are decoded and a checkpoint is on disk.
    #[arg(long, hide = true, value_name = "N")]
    pub abort_after_frames: Option<u64>,
    /// Serve /metrics here (overrides the config's `run.metrics`); a bare PORT is on 127.0.0.1.
    #[arg(long, value_name = "ADDR:PORT")]
    pub metrics: Option<String>,
    /// JSON lines even when standard output is a terminal (which otherwise gets a readable
    /// table); pipes and files always get JSON lines.
    #[arg(long)]
    pub json: bool,
}

pub fn run(r: &RunArgs) -> Result<()> {
    let cfg = StandConfig::load(&r.config).map_err(anyhow::Error::new)?;
    let desc = super::load_descriptor(&cfg.format).map_err(|e| {
        anyhow::Error::new(UsageError::Config {
            file: cfg.file.clone(),
            line: None,
            key: "source.format".into(),
            problem: e.to_string(),
        })
    })?;
    let limits =
        allanscope::model::limits::from_tables(&cfg.limits_raw, &cfg.file).map_err(|errs| {
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
        allanscope::analysis::ChannelSetup::for_frames(&desc),
        &cfg.channels,
        &spec.name(),
    )
    .map_err(|e| {
        anyhow::Error::new(UsageError::Config {
            file: cfg.file.clone(),
            line: None,
            key: "channels.include".into(),
            problem: e.to_string(),
        })
    })?;
    let header = super::checkpoint_header(&spec.name(), &cfg.format, &opts, &setups);
    let replay = matches!(spec, SourceSpec::File { .. });
    let ckpt = super::checkpoint_setup(
        cfg.checkpoint_every_s,
        r.resume,
        r.abort_after_frames,
        cfg.output.as_deref(),
        header,
        !live,
        replay,
    )
    .map_err(|e| e.context(format!("stand config {}", cfg.file.display())))?;
    let saved = ckpt.as_ref().and_then(|c| c.1.as_ref());
    let ck_path = ckpt.as_ref().map(|c| c.0.path.clone());
    let server = match (&r.metrics, cfg.metrics) {
        (Some(_), _) => super::metrics::start_option(r.metrics.as_deref())?,
        (None, Some(addr)) => Some(super::metrics::MetricsServer::start(addr)?),
        (None, None) => None,
    };
    let metrics = server.as_ref().map(|s| s.tap(&spec.name(), &opts.limits));
    let analysis = super::start_analysis(&spec.name(), setups, opts, saved, ck_path.as_deref())?;
    // Outputs last: every option has been accepted; they are only emptied once the source
    // is open and delivers (allanscope::sink::output).
    let mode = OutputMode::new(r.force, r.resume);
    let capture = super::capture_output(cfg.capture.as_deref(), mode, "[run] capture")
        .map_err(|e| e.context(format!("stand config {}", cfg.file.display())))?;
    let (out, dest) = super::records_output(cfg.output.as_deref(), mode, "[output] path", r.json)
        .map_err(|e| e.context(format!("stand config {}", cfg.file.display())))?;
    let ctl = RunControl {
        checkpoint: ckpt.map(|c| std::sync::Arc::new(c.0)),
        capture,
        every_wall: if live {
            cfg.every_s.map(Duration::from_secs_f64)
        } else {
            None
        },
        metrics,
        crash_hook: super::process::abort_hook(r.abort_after_frames),
        ..RunControl::default()
    };
    // Live: interim records coalesced for a slow consumer; a replay waits for it instead.
    let writer = if live {
        RecordWriter::spawn_coalescing(out)
    } else {
        RecordWriter::spawn(out)
    };
    let signals = SignalWatch::start(
        ctl.shutdown.clone(),
        writer.queue().clone(),
        ctl.progress.clone(),
        cfg.duration_s.map(Duration::from_secs_f64),
    );
    let _bar = (replay && std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .then(|| super::process::ProgressBar::start(ctl.progress.clone()));
    let name = spec.name();
    let result = allanscope::pipeline::run_frames(spec, &desc, analysis, writer.queue(), &ctl);
    let written = super::finish_records(writer, &dest, &signals);
    let outcome = result?;
    written?;
    if !live && !outcome.read_to_end {
        return Err(super::interrupted(&name, &ctl.progress));
    }
    Ok(())
}
