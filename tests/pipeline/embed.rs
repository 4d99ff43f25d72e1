//! The library inside a caller's tokio runtime (examples/embed.rs, whose code this runs): the run
//! is stopped by the caller's own token, not by a signal or the end of the input, and still
//! writes its final records; the blocking `run_frames` refuses to run inside a runtime instead of
//! panicking.

#[allow(dead_code)]
#[path = "../../examples/embed.rs"]
mod example;

use std::time::Duration;

use crate::common::pipeline::*;
use allanscope::pipeline::{run_frames, RecordWriter, RunControl};
use allanscope::source::{Pace, SourceSpec};

/// Frames in the fixture (5 min at 250 Hz): a run stopped after 1.5 s at the data's own rate
/// decodes about 375 of them, far from all.
const FRAMES: u64 = 75_000;
const RATE_HZ: f64 = 250.0;
const STOP_AFTER: Duration = Duration::from_millis(1500);

#[test]
fn a_callers_runtime_and_token_stop_the_run_with_final_records() {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .expect("runtime");
    let capture = fixtures().join("captures/siu8_stand_5min_seed1.siu8");
    let run = rt
        .block_on(example::replay_for(&capture, STOP_AFTER))
        .expect("embedded run");
    // Stopped by the caller: some frames, nowhere near the file's end (paced at 250 Hz, 1.5 s
    // is ~375 frames; the bound leaves room for a slow machine's start-up).
    let expected = STOP_AFTER.as_secs_f64() * RATE_HZ;
    assert!(
        run.frames > 0 && (run.frames as f64) < 10.0 * expected,
        "frames {}",
        run.frames
    );
    assert!(run.frames < FRAMES);
    // The final records of a finished run: a final curve per channel and statistic, whose data
    // time is the frames decoded, then health and summary.
    let recs: Vec<serde_json::Value> = run
        .lines
        .iter()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect();
    let finals: Vec<&serde_json::Value> = recs
        .iter()
        .filter(|r| r["type"] == "curve" && r["final"] == true)
        .collect();
    assert_eq!(finals.len(), 8 * 3, "8 channels x avar, hvar, mvar");
    for c in &finals {
        let t = c["t_data"].as_f64().expect("t_data");
        assert!(
            (t - run.frames as f64 / RATE_HZ).abs() < 1.5 / RATE_HZ,
            "t_data {t} for {} frames",
            run.frames
        );
    }
    assert_eq!(recs.iter().filter(|r| r["type"] == "health").count(), 1);
    let summary = recs.last().expect("records");
    assert_eq!(summary["type"], "summary");
    // The caller's reason, and the input not read to its end.
    assert_eq!(summary["read_to_end"], false);
    assert_eq!(summary["stopped_by"], "the program's timer");
}

#[test]
fn the_blocking_entry_point_refuses_inside_a_runtime() {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    let desc = siu8();
    let err = rt.block_on(async {
        let writer = RecordWriter::spawn(Box::new(SharedBuf::default()));
        let spec = SourceSpec::File {
            path: fixtures().join("captures/siu8_stand_5min_seed1.siu8"),
            pace: Pace::Max,
        };
        let r = run_frames(
            spec,
            &desc,
            analysis(&desc, None),
            writer.queue(),
            &RunControl::default(),
        );
        drop(writer);
        r.err().expect("an error, not a run or a panic")
    });
    assert!(err.to_string().contains("run_frames_async"), "{err}");
}
