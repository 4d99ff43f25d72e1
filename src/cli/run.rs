//! `run --config FILE`: the pipeline with source, channels, statistics, outputs and limits from
//! a stand config (`allanscope::stand`; `config/stand.toml` is the example).

use std::path::PathBuf;
use std::time::Duration;

use anyhow::Result;
use clap::Args;

use super::process::SignalWatch;
use allanscope::pipeline::{RecordWriter, RunControl};
use allanscope::plan::run::{RunFlags, RunPlan};
use allanscope::plan::unit::InputPlan;
use allanscope::sink::output::OutputMode;
use allanscope::source::SourceSpec;
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
    // The descriptor is checked with the config, searched in the binary's folders.
    let cfg =
        StandConfig::load_in(&r.config, &super::descriptor_dirs()).map_err(anyhow::Error::new)?;
    let flags = RunFlags {
        resume: r.resume,
        abort_after_frames: r.abort_after_frames,
    };
    let mut plan = RunPlan::from_stand(&cfg, &super::descriptor_dirs(), &flags)?;
    refuse_outputs_over_inputs(r, &plan)?;
    if plan.named {
        return run_units(r, &cfg, plan);
    }
    // A stand config with [source] at the top: one unit, records as they always were.
    let unit = plan.units.remove(0);
    let InputPlan::Frames { spec, desc } = &unit.input else {
        anyhow::bail!("a stand config's source gives frames of a descriptor");
    };
    let (spec, desc) = (spec.clone(), desc.clone());
    let live = spec.is_live();
    let replay = matches!(spec, SourceSpec::File { .. });
    let server = match (&r.metrics, plan.metrics) {
        (Some(_), _) => super::metrics::start_option(r.metrics.as_deref())?,
        (None, Some(addr)) => Some(super::metrics::MetricsServer::start(addr)?),
        (None, None) => None,
    };
    // A live run on a terminal: the status line reads the figures the metrics endpoint serves.
    let watched = server.as_ref().map(|s| s.metrics.clone()).or_else(|| {
        (live && super::status::wanted())
            .then(|| std::sync::Arc::new(allanscope::sink::metrics::Metrics::new()))
    });
    let metrics = watched
        .as_ref()
        .map(|m| m.tap(&spec.name(), &unit.analysis.limits));
    let analysis = unit.start_analysis()?;
    // Outputs last: every option has been accepted; they are only emptied once the source
    // is open and delivers (allanscope::sink::output).
    let mode = OutputMode::new(r.force, r.resume);
    let capture = super::capture_output(unit.capture.as_deref(), mode, "[run] capture")
        .map_err(|e| e.context(format!("stand config {}", cfg.file.display())))?;
    let (out, dest) = super::records_output(plan.output.as_deref(), mode, "[output] path", r.json)
        .map_err(|e| e.context(format!("stand config {}", cfg.file.display())))?;
    let ctl = RunControl {
        checkpoint: unit.checkpoint.map(|c| std::sync::Arc::new(c.0)),
        capture,
        every_wall: plan.every_wall_s.map(Duration::from_secs_f64),
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
        plan.duration_s.map(Duration::from_secs_f64),
    );
    if let SourceSpec::File { path, .. } = &spec {
        signals.release_fifos(std::slice::from_ref(path));
    }
    let _bar = (replay && std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .then(|| super::process::ProgressBar::start(ctl.progress.clone()));
    let status = (live && super::status::wanted())
        .then_some(watched)
        .flatten()
        .map(|m| super::status::StatusLine::start(ctl.progress.clone(), ctl.shutdown.clone(), m));
    let name = spec.name();
    let result = allanscope::pipeline::run_frames(spec, &desc, analysis, writer.queue(), &ctl);
    drop(status);
    let written = super::finish_records(writer, &dest, &signals);
    let outcome = result?;
    written?;
    if !live && !outcome.read_to_end {
        return Err(super::interrupted(&name, &ctl.progress));
    }
    Ok(())
}

/// No output of the stand config (`[output] path`, a unit's capture or checkpoint) may be a file
/// the run reads (the config, a replayed source): checked as `main_with_args` checks the other
/// commands, before anything is opened.
fn refuse_outputs_over_inputs(r: &RunArgs, plan: &RunPlan) -> Result<()> {
    use allanscope::sink::output::{ReadFile, WrittenFile};
    let mut inputs = vec![ReadFile {
        named: format!("the stand config {}", r.config.display()),
        path: r.config.clone(),
    }];
    let mut outputs: Vec<WrittenFile> = plan
        .output
        .iter()
        .map(|p| WrittenFile {
            option: "[output] path".into(),
            path: p.clone(),
        })
        .collect();
    for u in &plan.units {
        // Named as the config names them: `[run] capture` of one unit, `unit `imu07` capture`
        // of a `[[unit]]` table.
        let (source, capture) = match &u.unit_name {
            Some(n) => (format!("unit `{n}` source"), format!("unit `{n}` capture")),
            None => ("[source] path".to_string(), "[run] capture".to_string()),
        };
        match &u.input {
            InputPlan::Frames {
                spec: SourceSpec::File { path, .. },
                ..
            } => inputs.push(ReadFile {
                named: format!("{source} {}", path.display()),
                path: path.clone(),
            }),
            InputPlan::Frames {
                spec: SourceSpec::Stdin { .. },
                ..
            } => inputs.push(ReadFile {
                named: "standard input".into(),
                path: "/dev/stdin".into(),
            }),
            _ => {}
        }
        if let Some(c) = &u.capture {
            outputs.push(WrittenFile {
                option: capture,
                path: c.clone(),
            });
        }
        if let Some(c) = u.checkpoint_path() {
            outputs.push(WrittenFile {
                option: "the checkpoint".into(),
                path: c.to_path_buf(),
            });
        }
    }
    allanscope::sink::output::refuse_outputs_over_inputs(&outputs, &inputs)?;
    Ok(())
}

/// A stand config with `[[unit]]` tables: every unit in this process
/// (`allanscope::pipeline::units`), every record tagged with its unit's name. Exit status 1
/// when a unit's source failed or a unit went quiet (after every final record is written).
fn run_units(r: &RunArgs, cfg: &StandConfig, plan: RunPlan) -> Result<()> {
    use allanscope::pipeline::units::{UnitRun, UnitsControl};
    let at = |e: anyhow::Error| e.context(format!("stand config {}", cfg.file.display()));
    let server = match (&r.metrics, plan.metrics) {
        (Some(_), _) => super::metrics::start_option(r.metrics.as_deref())?,
        (None, Some(addr)) => Some(super::metrics::MetricsServer::start(addr)?),
        (None, None) => None,
    };
    let metrics = server.as_ref().map(|s| s.metrics.clone());
    let live = plan.units.iter().any(|u| u.is_live());
    let mode = OutputMode::new(r.force, r.resume);
    let mut units = Vec::new();
    let mut captures = Vec::new();
    for u in plan.units {
        let InputPlan::Frames { spec, desc } = &u.input else {
            anyhow::bail!("a stand config's source gives frames of a descriptor");
        };
        let name = u.label().to_string();
        units.push(UnitRun {
            name: name.as_str().into(),
            spec: spec.clone(),
            desc: (**desc).clone(),
            analysis: u.start_analysis()?,
            capture: None,
            metrics: metrics.as_ref().map(|m| m.tap(&name, &u.analysis.limits)),
            progress: std::sync::Arc::new(allanscope::source::Progress::default()),
            checkpoint: u.checkpoint.map(|c| std::sync::Arc::new(c.0)),
        });
        captures.push((name, u.capture));
    }
    // Outputs last: every unit was accepted; each is only emptied once its source delivers.
    for (run, (name, capture)) in units.iter_mut().zip(&captures) {
        let what = format!("unit `{name}` capture");
        run.capture = super::capture_output(capture.as_deref(), mode, &what).map_err(at)?;
    }
    let (out, dest) =
        super::records_output(plan.output.as_deref(), mode, "[output] path", r.json).map_err(at)?;
    let ctl = UnitsControl {
        shutdown: tokio_util::sync::CancellationToken::new(),
        progress: std::sync::Arc::new(allanscope::source::Progress::default()),
        every_wall: plan.every_wall_s.map(Duration::from_secs_f64),
        quiet_after: Duration::from_secs_f64(plan.quiet_after_s),
        workers: None,
        crash_hook: super::process::abort_hook(r.abort_after_frames),
    };
    // Records of many units: room for a full set of interim records of each before a live
    // run coalesces them (allanscope::pipeline::writer).
    let capacity = allanscope::pipeline::RECORD_QUEUE.max(32 * units.len());
    let delivery = if live {
        allanscope::pipeline::Delivery::Coalesce
    } else {
        allanscope::pipeline::Delivery::Backpressure
    };
    let writer = RecordWriter::with_capacity(out, capacity, delivery);
    let signals = SignalWatch::start(
        ctl.shutdown.clone(),
        writer.queue().clone(),
        ctl.progress.clone(),
        plan.duration_s.map(Duration::from_secs_f64),
    );
    let files: Vec<&PathBuf> = units
        .iter()
        .filter_map(|u| match &u.spec {
            SourceSpec::File { path, .. } => Some(path),
            _ => None,
        })
        .collect();
    signals.release_fifos(&files);
    let result = allanscope::pipeline::units::run_units(units, writer.queue(), &ctl);
    let written = super::finish_records(writer, &dest, &signals);
    let outcomes = result?;
    written?;
    let mut bad = Vec::new();
    for o in &outcomes {
        if let Some(e) = &o.failed {
            bad.push(format!("unit `{}`: the source failed: {e}", o.name));
        } else if o.quiet > 0 {
            bad.push(format!(
                "unit `{}` went quiet {} time{} (see its `outage` records)",
                o.name,
                o.quiet,
                if o.quiet == 1 { "" } else { "s" }
            ));
        } else if !o.read_to_end && !live {
            bad.push(format!(
                "unit `{}`: stopped by {} before the end of its input",
                o.name,
                ctl.progress.stopped_by().unwrap_or("a signal")
            ));
        }
    }
    if !bad.is_empty() {
        anyhow::bail!(
            "{} of {} units did not run to the end; their final records are written:\n  {}",
            bad.len(),
            outcomes.len(),
            bad.join("\n  ")
        );
    }
    Ok(())
}
