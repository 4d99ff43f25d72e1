//! Checkpoints (`--checkpoint-every`, `--resume`): an accumulator saved and restored mid-run
//! continues exactly as one that never stopped (integer and float paths, bounded and full
//! overlap, with gaps); a replay killed part way and resumed gives the final records of an
//! uninterrupted run; a live stream resumed has the outage as a segment break; mismatched
//! options, damaged checkpoints and unsafe starts are refused with exit status 2.
//!
//! The crash of the binary-level test is made deterministic with the hidden test hook
//! `--abort-after-frames N` (the process aborts, without flushing anything, once N frames are
//! decoded and a checkpoint is on disk); a second test kills a realtime-paced replay with
//! SIGKILL wherever it happens to be after its first checkpoint.

use crate::common::exe;
use crate::common::pipeline::same_record as same;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};
use std::time::{Duration, Instant};

use allanscope::allan::accum::{AccumConfig, ChannelAccumulator, LevelReading, Overlap};
use allanscope::pipeline::checkpoint::{path_for, Checkpoint};

const SIU8: &str = "fixtures/captures/siu8_stand_5min_seed1.siu8";
const SIU8_FRAME: usize = 42;

fn tmp(name: &str) -> PathBuf {
    let p = crate::common::tmp_in("ckpt", name);
    let _ = std::fs::remove_file(&p);
    let _ = std::fs::remove_file(path_for(&p));
    p
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

// ---------------------------------------------------------------------------------------------
// Library level: an accumulator's state saved and restored

/// Deterministic pseudo-random increments: white noise plus a slow drift, as integer counts
/// (`ints`) and as floats; `None` marks a lost sample (a gap of that many steps).
fn series(n: usize, seed: u64) -> Vec<Option<i64>> {
    let mut s = seed;
    let mut next = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (s >> 33) as i64
    };
    (0..n)
        .map(|k| {
            // Gaps: a single lost sample, then a run of 37, inside the run.
            if k == n / 3 || (n / 2..n / 2 + 37).contains(&k) {
                None
            } else {
                Some(next() % 2001 - 1000 + (k as i64 / 5000))
            }
        })
        .collect()
}

fn feed(acc: &mut ChannelAccumulator, data: &[Option<i64>]) {
    for v in data {
        match (v, &mut *acc) {
            (None, a) => a.push_gap(1),
            (Some(c), ChannelAccumulator::Counts { engine, .. }) => engine.push_increment(*c),
            (Some(c), ChannelAccumulator::Real(e)) => e.push_increment(*c as f64 * 1.0e-3 + 0.25),
        }
    }
}

fn save(acc: &ChannelAccumulator) -> Vec<u8> {
    let mut b = Vec::new();
    ciborium::into_writer(acc, &mut b).unwrap();
    b
}

fn load(b: &[u8]) -> ChannelAccumulator {
    ciborium::from_reader(b).unwrap()
}

fn make(integer: bool, overlap: Overlap) -> ChannelAccumulator {
    let mut cfg = AccumConfig::new(0.004);
    cfg.overlap = overlap;
    if integer {
        ChannelAccumulator::counts(cfg, 0.01)
    } else {
        ChannelAccumulator::real(cfg)
    }
}

/// Readings taken at the same points of the run (an interim read processes pending points,
/// so both runs read at the same places), then at the end.
fn run_with_restore(
    integer: bool,
    overlap: Overlap,
    data: &[Option<i64>],
    cut: usize,
    interim: usize,
) -> (Vec<LevelReading>, Vec<LevelReading>) {
    let mut straight = make(integer, overlap);
    feed(&mut straight, &data[..interim]);
    let _ = straight.read();
    feed(&mut straight, &data[interim..]);
    let a = straight.read();

    let mut first = make(integer, overlap);
    feed(&mut first, &data[..interim]);
    let _ = first.read();
    feed(&mut first, &data[interim..cut]);
    let bytes = save(&first);
    drop(first);
    let mut resumed = load(&bytes);
    feed(&mut resumed, &data[cut..]);
    (a, resumed.read())
}

#[test]
fn restored_accumulators_continue_exactly() {
    let data = series(60_000, 7);
    for integer in [true, false] {
        for overlap in [Overlap::Bounded(16), Overlap::Bounded(3), Overlap::Full] {
            // Cuts inside a block, inside the gap run, and right after the single gap.
            for cut in [23_457, 30_010, 20_001] {
                let (a, b) = run_with_restore(integer, overlap, &data, cut, 9_999);
                assert!(!a.is_empty());
                let n_avar: u64 = a.iter().filter_map(|r| r.avar).map(|x| x.1).sum();
                assert!(n_avar > 50_000, "the run has differences to compare");
                // Bit for bit: the restored state is the state.
                assert_eq!(
                    a, b,
                    "integer={integer} overlap={overlap:?} cut={cut}: readings differ"
                );
            }
        }
    }
}

#[test]
fn restored_accumulators_keep_segments_and_time() {
    let data = series(40_000, 3);
    let mut a = make(true, Overlap::Bounded(16));
    feed(&mut a, &data[..25_000]);
    let mut b = load(&save(&a));
    assert_eq!(a.segments(), b.segments());
    assert_eq!(a.phase_points(), b.phase_points());
    assert_eq!(a.t_data_s().to_bits(), b.t_data_s().to_bits());
    feed(&mut a, &data[25_000..]);
    feed(&mut b, &data[25_000..]);
    // Two gaps: three segments; every step (gaps included) is 4 ms of data.
    assert_eq!(b.segments(), 3);
    assert_eq!(b.t_data_s(), 40_000.0 * 0.004);
    assert_eq!(a.read(), b.read());
}

#[test]
fn a_bounded_state_stays_bounded_and_a_full_one_grows() {
    let size_after = |overlap: Overlap, n: usize| {
        let mut a = make(true, overlap);
        let data: Vec<Option<i64>> = series(n, 11).into_iter().map(|v| v.or(Some(0))).collect();
        feed(&mut a, &data);
        save(&a).len()
    };
    let (b1, b4) = (
        size_after(Overlap::Bounded(16), 100_000),
        size_after(Overlap::Bounded(16), 400_000),
    );
    let (f1, f4) = (
        size_after(Overlap::Full, 100_000),
        size_after(Overlap::Full, 400_000),
    );
    // Bounded: a few new levels' worth of points (each ~4L per stream) for 4x the data.
    assert!(
        b4 < b1 * 3 / 2,
        "bounded state grew from {b1} to {b4} bytes"
    );
    // Full overlap keeps stream 1 whole: 4x the data is about 4x the state.
    assert!(f4 > f1 * 3, "full state {f1} -> {f4} bytes");
    assert!(b4 < f4 / 10, "bounded {b4} vs full {f4} bytes");
}

// ---------------------------------------------------------------------------------------------
// The binary: a replay killed part way and resumed

/// The final records of a JSON-lines file, keyed by type, channel and statistic.
fn finals(path: &Path) -> Vec<((String, String, String), serde_json::Value)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut out: Vec<((String, String, String), serde_json::Value)> = Vec::new();
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        let ty = v["type"].as_str().unwrap().to_string();
        let is_final = v["final"].as_bool() == Some(true) || ty == "health" || ty == "summary";
        if !is_final {
            continue;
        }
        let key = (
            ty,
            v["channel"].as_str().unwrap_or("").to_string(),
            v["stat"].as_str().unwrap_or("").to_string(),
        );
        // A record of the same key later in the file replaces an earlier one.
        out.retain(|(k, _)| k != &key);
        out.push((key, v));
    }
    out
}

fn assert_same_finals(reference: &Path, resumed: &Path) {
    let (a, b) = (finals(reference), finals(resumed));
    // 8 channels x 3 statistics + 8 fits + health + summary.
    assert_eq!(a.len(), 34, "reference final records");
    assert_eq!(
        a.iter().map(|x| &x.0).collect::<Vec<_>>(),
        b.iter().map(|x| &x.0).collect::<Vec<_>>()
    );
    for ((k, x), (_, y)) in a.iter().zip(&b) {
        same(x, y, &format!("{k:?}"));
    }
}

fn analyze(input: &str, out: &Path, extra: &[&str]) -> Output {
    exe()
        .args([
            "analyze", input, "--format", "siu8", "--every", "60", "--out",
        ])
        .arg(out)
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn a_replay_aborted_part_way_and_resumed_gives_the_uninterrupted_records() {
    let reference = tmp("straight.jsonl");
    let o = analyze(SIU8, &reference, &[]);
    assert!(o.status.success(), "{}", stderr(&o));

    let out = tmp("crashed.jsonl");
    let ck = path_for(&out);
    // 40,000 frames is 160 s of the 300 s capture.
    let o = analyze(
        SIU8,
        &out,
        &["--checkpoint-every", "20", "--abort-after-frames", "40000"],
    );
    assert!(!o.status.success(), "the hook aborts: {}", stderr(&o));
    let saved = Checkpoint::load(&ck).expect("a checkpoint was left behind");
    assert!(!saved.complete);
    let t_saved = saved.analysis.channels[0].acc.t_data_s();
    assert!(t_saved > 0.0 && t_saved < 300.0, "saved at {t_saved} s");
    assert!(saved.position.offset() > 0 && saved.position.offset() < 3_150_000);

    // Starting afresh over it is refused: the saved run would be lost.
    let o = analyze(SIU8, &out, &["--checkpoint-every", "20"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--resume"), "{}", stderr(&o));

    let o = analyze(SIU8, &out, &["--resume"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_same_finals(&reference, &out);

    // The final checkpoint says the run is complete: nothing is left to resume.
    assert!(Checkpoint::load(&ck).unwrap().complete);
    let o = analyze(SIU8, &out, &["--resume"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains(&ck.display().to_string()));
}

#[test]
fn a_realtime_replay_killed_with_sigkill_and_resumed_gives_the_uninterrupted_records() {
    // The first 8 s of the capture (2000 frames), replayed at the data's own rate.
    let cut = tmp("cut8s.siu8");
    let bytes = std::fs::read(SIU8).unwrap();
    std::fs::write(&cut, &bytes[..2000 * SIU8_FRAME]).unwrap();
    let cut_s = cut.to_str().unwrap();
    let reference = tmp("cut_straight.jsonl");
    let o = analyze(cut_s, &reference, &[]);
    assert!(o.status.success(), "{}", stderr(&o));

    let out = tmp("cut_killed.jsonl");
    let ck = path_for(&out);
    let mut child = exe()
        .args(["analyze", cut_s, "--format", "siu8", "--every", "60"])
        .args(["--pace", "realtime", "--checkpoint-every", "1", "--out"])
        .arg(&out)
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let until = Instant::now() + Duration::from_secs(30);
    while !ck.exists() && Instant::now() < until {
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(ck.exists(), "no checkpoint within 30 s");
    std::thread::sleep(Duration::from_millis(700));
    let finished_first = child.try_wait().unwrap().is_some();
    child.kill().unwrap(); // SIGKILL
    let _ = child.wait();
    assert!(
        !finished_first,
        "the 8 s realtime replay ended before it was killed"
    );
    assert!(!Checkpoint::load(&ck).unwrap().complete);

    let o = analyze(cut_s, &out, &["--resume"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_same_finals(&reference, &out);
}

#[test]
fn text_columns_resume_from_the_saved_byte_offset() {
    let csv = "fixtures/captures/vog4_2min_seed7.csv";
    let run = |out: &Path, extra: &[&str]| {
        exe()
            .args(["analyze", csv, "--tau0", "0.004", "--rate", "--every", "10"])
            .arg("--out")
            .arg(out)
            .args(extra)
            .output()
            .unwrap()
    };
    let reference = tmp("vog4_straight.jsonl");
    assert!(run(&reference, &[]).status.success());
    let out = tmp("vog4_crashed.jsonl");
    let o = run(
        &out,
        &["--checkpoint-every", "5", "--abort-after-frames", "20000"],
    );
    assert!(!o.status.success());
    let o = run(&out, &["--resume"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (a, b) = (finals(&reference), finals(&out));
    assert_eq!(a.len(), 5, "3 curves, a fit and the summary");
    for ((k, x), (_, y)) in a.iter().zip(&b) {
        same(x, y, &format!("{k:?}"));
    }
}

#[test]
fn a_stand_config_checkpoints_and_resumes() {
    let out = tmp("stand_run.jsonl");
    let reference = tmp("stand_ref.jsonl");
    assert!(analyze(SIU8, &reference, &[]).status.success());
    let cfg = tmp("stand_ckpt.toml");
    std::fs::write(
        &cfg,
        format!(
            "[source]\nkind = \"file\"\npath = \"{SIU8}\"\nformat = \"siu8\"\n\
             [run]\nevery_s = 60.0\ncheckpoint_every = 20\n[output]\npath = \"{}\"\n",
            out.display()
        ),
    )
    .unwrap();
    let run = |extra: &[&str]| {
        exe()
            .args(["run", "--config"])
            .arg(&cfg)
            .args(extra)
            .output()
            .unwrap()
    };
    assert!(!run(&["--abort-after-frames", "50000"]).status.success());
    assert!(!Checkpoint::load(&path_for(&out)).unwrap().complete);
    let o = run(&["--resume"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_same_finals(&reference, &out);
}

// ---------------------------------------------------------------------------------------------
// A stream that cannot be rewound: the outage is a segment break

#[test]
fn a_live_stream_resumed_has_the_outage_as_a_segment_break() {
    let bytes = std::fs::read(SIU8).unwrap();
    let (n1, n2) = (3000usize, 2000usize);
    let first = &bytes[..n1 * SIU8_FRAME];
    let second = &bytes[n1 * SIU8_FRAME..(n1 + n2) * SIU8_FRAME];
    let out = tmp("live.jsonl");
    let listen = |data: &[u8], extra: &[&str]| {
        let mut child = exe()
            .args(["listen", "-", "--format", "siu8", "--channels", "g1"])
            .args(["--taus", "1,2", "--fit", "none", "--out"])
            .arg(&out)
            .args(extra)
            .stdin(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        child.stdin.take().unwrap().write_all(data).unwrap();
        child.wait_with_output().unwrap()
    };
    let o = listen(first, &["--checkpoint-every", "0.05"]);
    assert!(o.status.success(), "{}", stderr(&o));
    // A live run's final checkpoint can be continued (the stand run goes on).
    let o = listen(second, &["--resume"]);
    assert!(o.status.success(), "{}", stderr(&o));

    let recs = finals(&out);
    let get = |ty: &str, stat: &str| {
        recs.iter()
            .find(|(k, _)| k.0 == ty && k.2 == stat)
            .map(|x| x.1.clone())
            .unwrap()
    };
    let health = get("health", "");
    assert_eq!(
        health["frames"],
        (n1 + n2) as u64,
        "frames counted across the stop"
    );
    let summary = get("summary", "");
    assert_eq!(summary["segments"][0], 2, "the outage breaks the segment");
    assert_eq!(summary["samples"][0], (n1 + 1 + n2 + 1) as u64);
    // AVAR at m = 1 takes P - 2 differences in each segment of P phase points, none across.
    let avar = get("curve", "avar");
    assert_eq!(avar["count"][0], ((n1 + 1 - 2) + (n2 + 1 - 2)) as u64);
    assert_eq!(avar["count"][1], ((n1 + 1 - 4) + (n2 + 1 - 4)) as u64);
}

// ---------------------------------------------------------------------------------------------
// Refusals

#[test]
fn mismatched_options_and_damaged_checkpoints_are_usage_errors_naming_the_file() {
    let out = tmp("refuse.jsonl");
    let ck = path_for(&out);
    let o = analyze(
        SIU8,
        &out,
        &["--checkpoint-every", "20", "--abort-after-frames", "30000"],
    );
    assert!(!o.status.success());
    let good = std::fs::read(&ck).unwrap();
    let ck_name = ck.display().to_string();

    // Other options: refused, every difference named.
    let o = analyze(
        SIU8,
        &out,
        &["--resume", "--overlap", "8", "--channels", "g1"],
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(
        e.contains(&ck_name) && e.contains("--overlap") && e.contains("--channels"),
        "{e}"
    );
    let o = analyze(SIU8, &out, &["--resume", "--tau0", "0.002"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--tau0"), "{}", stderr(&o));

    // Damaged: one byte flipped in the body, the file cut short, not a checkpoint at all.
    let mut flipped = good.clone();
    let mid = flipped.len() / 2;
    flipped[mid] ^= 0x40;
    for (bytes, what) in [
        (flipped, "CRC-32"),
        (good[..good.len() - 100].to_vec(), "truncated"),
        (b"{\"type\":\"curve\"}\n".to_vec(), "magic"),
    ] {
        std::fs::write(&ck, &bytes).unwrap();
        let o = analyze(SIU8, &out, &["--resume"]);
        assert_eq!(o.status.code(), Some(2), "{what}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(e.contains(&ck_name) && e.contains(what), "{what}: {e}");
        assert!(!e.contains("panicked"), "{e}");
        // Nothing is overwritten by the refused run.
        assert_eq!(std::fs::read(&ck).unwrap(), bytes);
    }

    // No checkpoint to resume from; no output to put one beside.
    std::fs::remove_file(&ck).unwrap();
    let o = analyze(SIU8, &out, &["--resume"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("not found"), "{}", stderr(&o));
    let o = exe()
        .args([
            "analyze",
            SIU8,
            "--format",
            "siu8",
            "--checkpoint-every",
            "10",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--out"), "{}", stderr(&o));
}

#[test]
fn running_sums_beyond_64_bits_survive_the_round_trip() {
    // Increments of 3e10 counts: the running sum of phase C passes 2^64 within the run, so the
    // saved i128 values need CBOR's big integers; MVAR at every m reads C differences across
    // the restore point.
    let n = 400_000usize;
    let data: Vec<Option<i64>> = (0..n)
        .map(|k| Some(30_000_000_000 + (k as i64 * 7919) % 1000))
        .collect();
    let mut a = make(true, Overlap::Bounded(16));
    feed(&mut a, &data[..200_001]);
    let mut b = load(&save(&a));
    feed(&mut a, &data[200_001..]);
    feed(&mut b, &data[200_001..]);
    let (ra, rb) = (a.read(), b.read());
    assert!(ra.iter().filter(|r| r.mvar.is_some()).count() >= 15);
    assert_eq!(ra, rb);
}
