//! `listen`: live from a serial port, a UDP socket or standard input, through the pipeline,
//! until SIGINT/SIGTERM or `--duration`; then the final records.

use std::path::PathBuf;
use std::time::Duration;

use anyhow::Result;
use clap::{ArgGroup, Args};

use super::process::SignalWatch;
use super::{
    analysis_options, capture_output, finish_records, parse_duration_s, records_output, usage,
    DataArgs,
};
use allanscope::pipeline::{RecordWriter, RunControl};
use allanscope::plan::unit::{InputPlan, UnitPlan};
use allanscope::sink::output::OutputMode;
use allanscope::source::{Pace, SourceSpec};

/// `listen` reads frames only: its `--format` shows no default (the shared one, `csv`, is text
/// columns, which `listen` refuses; left out, the refusal says what to give).
#[derive(Debug, Args)]
#[command(group(ArgGroup::new("source").required(true).args(["serial", "udp", "input"])))]
#[command(mut_arg("format", |a| a.hide_default_value(true).help(
    "A frame descriptor (a name from config/frames, or a path); required: listen reads frames, \
     not text columns"
)))]
pub struct ListenArgs {
    /// Serial port (e.g. /dev/ttyUSB0), 8N1; reopened with backoff when it disappears.
    #[arg(long)]
    pub serial: Option<PathBuf>,
    /// Baud rate of the serial port.
    #[arg(long, default_value_t = 230_400)]
    pub baud: u32,
    /// UDP socket to bind: ADDR:PORT, or PORT alone for 127.0.0.1:PORT.
    #[arg(long)]
    pub udp: Option<String>,
    /// `-`: read frames from standard input.
    #[arg(value_name = "-")]
    pub input: Option<String>,
    /// Stop after this long (seconds, or with s, min, h, d).
    #[arg(long)]
    pub duration: Option<String>,
    /// Also write every received byte to this file, for replay later. An existing non-empty
    /// file is refused unless --force (or --resume, which appends). A write error stops the
    /// capture, not the run (reported in `health` and `summary`).
    #[arg(long)]
    pub capture: Option<PathBuf>,
    #[command(flatten)]
    pub data: DataArgs,
}

/// The source named by the options.
fn source_spec(l: &ListenArgs) -> Result<SourceSpec> {
    if let Some(p) = &l.serial {
        return Ok(SourceSpec::Serial {
            path: p.clone(),
            baud: l.baud,
        });
    }
    if let Some(u) = &l.udp {
        let bind =
            allanscope::source::udp::parse_bind(u).map_err(|e| usage(format!("--udp {e}")))?;
        return Ok(SourceSpec::Udp { bind });
    }
    match l.input.as_deref() {
        Some("-") => Ok(SourceSpec::Stdin { pace: Pace::Max }),
        Some(other) => Err(usage(format!(
            "listen reads `-` (standard input), --serial or --udp, not `{other}` (use analyze \
             for capture files)"
        ))),
        None => Err(usage("listen needs --serial PATH, --udp ADDR:PORT or -")),
    }
}

pub fn run(l: &ListenArgs) -> Result<()> {
    let d = &l.data;
    if d.format == "csv" {
        return Err(usage(
            "listen reads frames: give --format NAME (siu8, kvh1750, hg4930 or a descriptor file)",
        ));
    }
    let desc = super::load_descriptor(&d.format).map_err(anyhow::Error::new)?;
    let spec = source_spec(l)?;
    // Live: --every is wall-seconds, kept by the pipeline, not data-seconds (the plan's
    // wall clock).
    let opts = analysis_options(d, d.tau0.unwrap_or_else(|| desc.tau0_s()))?;
    let plan = UnitPlan::with_options(
        InputPlan::Frames {
            spec: spec.clone(),
            desc: Box::new(desc.clone()),
        },
        &d.format,
        allanscope::analysis::ChannelSetup::for_frames(&desc),
        &d.channels,
        opts,
        &d.unit_request(true),
    )?;
    let server = super::metrics::start_option(d.metrics.as_deref())?;
    // The status line on a terminal reads the same figures the metrics endpoint serves.
    let watched = server.as_ref().map(|s| s.metrics.clone()).or_else(|| {
        super::status::wanted()
            .then(|| std::sync::Arc::new(allanscope::sink::metrics::Metrics::new()))
    });
    let metrics = watched
        .as_ref()
        .map(|m| m.tap(&spec.name(), &plan.analysis.limits));
    let analysis = plan.start_analysis()?;
    let duration = match &l.duration {
        Some(s) => Some(Duration::from_secs_f64(parse_duration_s(s)?)),
        None => None,
    };
    let mode = OutputMode::new(d.force, d.resume);
    // Outputs last: every option has been accepted; they are only emptied once the source
    // is open and delivers (allanscope::sink::output).
    let capture = capture_output(l.capture.as_deref(), mode, "--capture")?;
    let (out, dest) = records_output(d.out.as_deref(), mode, "--out", d.json)?;
    let ctl = RunControl {
        metrics,
        checkpoint: plan.checkpoint.map(|c| std::sync::Arc::new(c.0)),
        capture,
        every_wall: d.every.map(Duration::from_secs_f64),
        crash_hook: super::process::abort_hook(d.abort_after_frames),
        ..RunControl::default()
    };
    // Live: a consumer that falls behind gets the newest interim records (coalesced), and
    // ingestion never waits for it.
    let writer = RecordWriter::spawn_coalescing(out);
    let signals = SignalWatch::start(
        ctl.shutdown.clone(),
        writer.queue().clone(),
        ctl.progress.clone(),
        duration,
    );
    let status = super::status::wanted()
        .then_some(watched)
        .flatten()
        .map(|m| super::status::StatusLine::start(ctl.progress.clone(), ctl.shutdown.clone(), m));
    let result = allanscope::pipeline::run_frames(spec, &desc, analysis, writer.queue(), &ctl);
    drop(status);
    let written = finish_records(writer, &dest, &signals);
    result?;
    written
}
