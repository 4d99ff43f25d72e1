//! The pipeline inside a program that owns its tokio runtime and its shutdown, as a ROS node, a
//! GUI or a lab service would embed it: no command line, no signal handling, no progress bar from
//! the library; the program builds its own multi-thread runtime, awaits
//! [`run_frames_async`] there, and ends the run from its own timer through the run's
//! `CancellationToken`. The final records come out as they do at the end of any run.
//!
//! ```sh
//! cargo run --release --example embed                       # the siu8 fixture, stopped after 2 s
//! cargo run --release --example embed -- CAPTURE.siu8 5     # another siu8 capture, 5 s
//! ```
//!
//! The capture is replayed at the data's own rate (250 frames/s), so the run is stopped by the
//! program, not by the end of the file. `tests/pipeline/embed.rs` runs this example's code.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use allanscope::allan::accum::AccumConfig;
use allanscope::analysis::{AnalysisOptions, ChannelSetup, InputKind, RunAnalysis};
use allanscope::frame::FrameDescriptor;
use allanscope::model::fit::FitOptions;
use allanscope::pipeline::{run_frames_async, RecordWriter, RunControl};
use allanscope::source::{Pace, SourceSpec};

/// What an embedded run left: the frames decoded and the JSON lines written.
pub struct Embedded {
    pub frames: u64,
    pub lines: Vec<String>,
}

/// JSON lines gathered in memory instead of a file.
#[derive(Clone, Default)]
struct Lines(Arc<Mutex<Vec<u8>>>);

impl Write for Lines {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().expect("lock").extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Replays a siu8 capture at its own rate on the caller's runtime and stops it after
/// `stop_after` of wall time by cancelling the run's token.
pub async fn replay_for(capture: &Path, stop_after: Duration) -> anyhow::Result<Embedded> {
    let desc = FrameDescriptor::load("siu8")?;
    let opts = AnalysisOptions {
        accum: AccumConfig::new(desc.tau0_s()),
        kind: InputKind::Increments,
        every_s: None,
        fit: Some(FitOptions::default()),
        run: None,
        limits: Vec::new(),
        diagnose: false,
    };
    let analysis = RunAnalysis::new(
        &capture.display().to_string(),
        ChannelSetup::for_frames(&desc),
        opts,
    );
    let spec = SourceSpec::File {
        path: capture.to_path_buf(),
        pace: Pace::Realtime {
            bytes_per_s: desc.frame_len() as f64 * desc.rate_hz,
        },
    };
    let ctl = RunControl::default();
    // The program's own shutdown: here a timer; a node would cancel on its own stop request.
    let (stop, progress) = (ctl.shutdown.clone(), ctl.progress.clone());
    tokio::spawn(async move {
        tokio::time::sleep(stop_after).await;
        // Why, for the summary record's `stopped_by`.
        progress.set_stopped_by("the program's timer");
        stop.cancel();
    });
    let out = Lines::default();
    let writer = RecordWriter::spawn(Box::new(out.clone()));
    let outcome = run_frames_async(spec, &desc, analysis, writer.queue(), &ctl).await;
    // The writer thread drains its queue; joining it blocks, so it goes to the blocking pool.
    tokio::task::spawn_blocking(move || writer.finish()).await??;
    let outcome = outcome?;
    let text = String::from_utf8(out.0.lock().expect("lock").clone())?;
    Ok(Embedded {
        frames: outcome.health.map_or(0, |h| h.frames),
        lines: text.lines().map(String::from).collect(),
    })
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let capture = args.first().map(PathBuf::from).unwrap_or_else(|| {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/captures/siu8_stand_5min_seed1.siu8")
    });
    let seconds: f64 = match args.get(1) {
        Some(s) => s.parse()?,
        None => 2.0,
    };
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let run = rt.block_on(replay_for(&capture, Duration::from_secs_f64(seconds)))?;
    println!(
        "{} frames decoded in {seconds} s; {} records:",
        run.frames,
        run.lines.len()
    );
    for l in &run.lines {
        let v: serde_json::Value = serde_json::from_str(l)?;
        println!(
            "  {} {} {}",
            v["type"].as_str().unwrap_or("?"),
            v["channel"].as_str().unwrap_or(""),
            v["stat"].as_str().unwrap_or("")
        );
    }
    Ok(())
}
