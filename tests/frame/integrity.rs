//! Integrity of what the decoder accepts (issue 11), on real files through the built binary and
//! on the live decode stage:
//!
//! - one stale frame (an earlier frame repeated whole, valid checksum) in 120 s of siu8 is
//!   dropped and counted (`stale_frames` 1), not read as a counter wrap: `missing` 0,
//!   `t_data` 120 s, one segment per channel, in a file and in a serial-like live stream;
//! - a frame whose counter was damaged but whose checksum still passes (a flipped high counter
//!   bit, checksum recomputed) is dropped (`counter_rejects` 1) and its slot is one lost frame,
//!   not a gap of 4096;
//! - NaN in a kvh1750 float field every 1000 frames: counted in `invalid_values` (60), a gap of
//!   that channel, its sigmas finite and its fit present;
//! - `inf` and `1e308` in text columns: counted (`invalid_values` 2 in `summary`) and read
//!   exactly as `nan` would be: the final curves equal those of the file with `nan` there.

use std::path::Path;
use std::process::Stdio;

use crate::common::{exe, fixtures, tmp_in};
use allanscope::frame::decoder::checksum_ok;
use allanscope::frame::descriptor::MessageSpec;
use allanscope::frame::field::ByteOrder;
use allanscope::frame::{FrameDescriptor, FrameEvent};
use allanscope::pipeline::decode::DecodeStage;
use allanscope::source::SourceEvent;

const SIU8_LEN: usize = 42;
/// 120 s of siu8 at 250 Hz.
const FRAMES_120S: usize = 30_000;

fn siu8_120s() -> Vec<u8> {
    let all = std::fs::read(fixtures().join("captures/siu8_stand_5min_seed1.siu8")).unwrap();
    all[..FRAMES_120S * SIU8_LEN].to_vec()
}

fn fix_checksum(m: &MessageSpec, bytes: &mut [u8]) {
    let c = &m.checksum;
    let sum = c.algorithm.compute(&bytes[c.start..=c.end], c.order);
    let w = c.algorithm.width();
    for i in 0..w {
        let shift = match c.order {
            ByteOrder::Big => 8 * (w - 1 - i),
            ByteOrder::Little => 8 * i,
        };
        bytes[c.at + i] = (sum >> shift) as u8;
    }
    assert!(checksum_ok(m, bytes));
}

/// `analyze FILE --format F [extra]`: the records.
fn analyze(path: &Path, format: &str, extra: &[&str]) -> Vec<serde_json::Value> {
    let o = exe()
        .arg("analyze")
        .arg(path)
        .args(["--format", format])
        .args(extra)
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

fn last_of<'a>(recs: &'a [serde_json::Value], kind: &str) -> &'a serde_json::Value {
    recs.iter().rev().find(|r| r["type"] == kind).unwrap()
}

fn final_curves(recs: &[serde_json::Value]) -> Vec<&serde_json::Value> {
    recs.iter()
        .filter(|r| r["type"] == "curve" && r["final"] == true)
        .collect()
}

/// Runs `bytes` through a live decode stage (the serial path) in 4 KiB reads: frames, gaps
/// and health.
fn live_decode(desc: &FrameDescriptor, bytes: &[u8]) -> (u64, u64, allanscope::frame::Health) {
    let mut stage = DecodeStage::new(desc.clone(), true);
    let mut out = Vec::new();
    for b in bytes.chunks(4096) {
        stage.push(
            SourceEvent::Data {
                bytes: bytes::Bytes::copy_from_slice(b),
                at: std::time::Instant::now(),
            },
            &mut out,
        );
    }
    stage.finish(&mut out);
    let frames = out
        .iter()
        .filter(|e| matches!(e, FrameEvent::Frame(_)))
        .count() as u64;
    let gaps = out
        .iter()
        .map(|e| match e {
            FrameEvent::Gap { missing } => *missing,
            FrameEvent::Frame(_) => 0,
        })
        .sum();
    (frames, gaps, stage.health())
}

#[test]
fn a_stale_frame_is_not_a_counter_wrap() {
    let clean = siu8_120s();
    // Frame 1000 again after frame 20000: valid checksum, counter 19,000 behind.
    let mut stream = clean[..20_001 * SIU8_LEN].to_vec();
    stream.extend_from_slice(&clean[1000 * SIU8_LEN..1001 * SIU8_LEN]);
    stream.extend_from_slice(&clean[20_001 * SIU8_LEN..]);
    let path = tmp_in("integrity-stale", "stale.siu8");
    std::fs::write(&path, &stream).unwrap();
    let recs = analyze(&path, "siu8", &[]);
    let h = last_of(&recs, "health");
    assert_eq!(h["frames"], FRAMES_120S as u64);
    assert_eq!(h["missing"], 0);
    assert_eq!(h["stale_frames"], 1);
    assert_eq!(h["duplicates"], 0);
    assert_eq!(h["bytes_skipped"], 0);
    let s = last_of(&recs, "summary");
    assert_eq!(s["t_data"], 120.0);
    assert_eq!(s["segments"], serde_json::json!([1, 1, 1, 1, 1, 1, 1, 1]));
    // The final curves are those of the clean capture.
    let clean_path = tmp_in("integrity-stale", "clean.siu8");
    std::fs::write(&clean_path, &clean).unwrap();
    let reference = analyze(&clean_path, "siu8", &[]);
    let strip = |v: &serde_json::Value| v["sigma"].clone();
    assert_eq!(
        final_curves(&recs)
            .iter()
            .map(|v| strip(v))
            .collect::<Vec<_>>(),
        final_curves(&reference)
            .iter()
            .map(|v| strip(v))
            .collect::<Vec<_>>()
    );

    // The same bytes as a live (serial) stream.
    let desc = FrameDescriptor::load("siu8").unwrap();
    let (frames, gaps, h) = live_decode(&desc, &stream);
    assert_eq!((frames, gaps), (FRAMES_120S as u64, 0));
    assert_eq!((h.missing, h.stale_frames, h.duplicates), (0, 1, 0));
}

#[test]
fn a_damaged_counter_that_passes_the_checksum_is_rejected() {
    let desc = FrameDescriptor::load("siu8").unwrap();
    let mut stream = siu8_120s();
    // Frame 15000: its u16 counter moved 16384 ahead (one or two high bits changed) and the
    // checksum recomputed, as an unlucky multi-bit corruption would.
    let k = 15_000;
    let f = &mut stream[k * SIU8_LEN..(k + 1) * SIU8_LEN];
    let c = desc.frame().counter.as_ref().unwrap();
    let at = c.offset;
    let old = match c.order {
        ByteOrder::Little => u16::from_le_bytes([f[at], f[at + 1]]),
        ByteOrder::Big => u16::from_be_bytes([f[at], f[at + 1]]),
    };
    let new = old.wrapping_add(0x4000);
    let b = match c.order {
        ByteOrder::Little => new.to_le_bytes(),
        ByteOrder::Big => new.to_be_bytes(),
    };
    f[at..at + 2].copy_from_slice(&b);
    fix_checksum(desc.frame(), f);
    let path = tmp_in("integrity-counter", "flipped.siu8");
    std::fs::write(&path, &stream).unwrap();
    let recs = analyze(&path, "siu8", &[]);
    let h = last_of(&recs, "health");
    // The frame is dropped and its slot is one lost frame (not 16,383 lost and a wrap back).
    assert_eq!(h["frames"], FRAMES_120S as u64 - 1);
    assert_eq!(h["missing"], 1);
    assert_eq!(h["counter_rejects"], 1);
    assert_eq!(h["stale_frames"], 0);
    let s = last_of(&recs, "summary");
    assert_eq!(s["t_data"], 120.0);
    assert_eq!(s["segments"], serde_json::json!([2, 2, 2, 2, 2, 2, 2, 2]));

    let (frames, gaps, h) = live_decode(&desc, &stream);
    assert_eq!((frames, gaps), (FRAMES_120S as u64 - 1, 1));
    assert_eq!(h.counter_rejects, 1);
}

#[test]
fn nan_in_kvh1750_float_fields_is_counted_and_a_gap() {
    let desc = FrameDescriptor::load("kvh1750").unwrap();
    let all = std::fs::read(fixtures().join("captures/kvh1750_stand_1min_seed1.kvh1750")).unwrap();
    let len = desc.frame().length;
    assert_eq!(all.len() % len, 0, "whole frames");
    let n = all.len() / len;
    assert_eq!(n, 60_000);
    let clean_path = tmp_in("integrity-nan", "clean.kvh1750");
    std::fs::write(&clean_path, &all).unwrap();
    let base = analyze(&clean_path, "kvh1750", &[]);
    let base_invalid = last_of(&base, "health")["invalid_values"].as_u64().unwrap();

    // gx (a big-endian f32) becomes NaN in every 1000th frame; +inf in one more frame of gy.
    let mut bytes = all.clone();
    let gx = &desc.frame().channels[0];
    let gy = &desc.frame().channels[1];
    let put = |f: &mut [u8], off: usize, v: f32| {
        let b = match gx.order {
            ByteOrder::Big => v.to_be_bytes(),
            ByteOrder::Little => v.to_le_bytes(),
        };
        f[off..off + 4].copy_from_slice(&b);
    };
    for k in (500..n).step_by(1000) {
        let f = &mut bytes[k * len..(k + 1) * len];
        put(f, gx.offset, f32::NAN);
        fix_checksum(desc.frame(), f);
    }
    let f = &mut bytes[777 * len..778 * len];
    put(f, gy.offset, f32::INFINITY);
    fix_checksum(desc.frame(), f);
    let path = tmp_in("integrity-nan", "nan.kvh1750");
    std::fs::write(&path, &bytes).unwrap();
    let recs = analyze(&path, "kvh1750", &[]);
    let h = last_of(&recs, "health");
    assert_eq!(h["frames"], 60_000);
    assert_eq!(h["crc_errors"], 0);
    assert_eq!(h["invalid_values"].as_u64().unwrap(), base_invalid + 60 + 1);
    for ch in ["gx", "gy"] {
        let curves: Vec<_> = final_curves(&recs)
            .into_iter()
            .filter(|c| c["channel"] == ch)
            .collect();
        assert_eq!(curves.len(), 3, "{ch}");
        for c in curves {
            let sig = c["sigma"].as_array().unwrap();
            assert!(!sig.is_empty());
            assert!(
                sig.iter().all(|x| x.as_f64().is_some_and(f64::is_finite)),
                "{ch}: {sig:?}"
            );
        }
        let fit = recs
            .iter()
            .find(|r| r["type"] == "fit" && r["final"] == true && r["channel"] == ch)
            .unwrap_or_else(|| panic!("{ch}: no final fit"));
        assert_eq!(fit["coef"]["N"]["determined"], true, "{ch}");
    }
}

#[test]
fn inf_and_huge_text_values_are_counted_gaps_like_nan() {
    let csv = std::fs::read_to_string(fixtures().join("captures/vog4_2min_seed7.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    // Line 0 is the header `g4`; rows 1000 and 7000 replaced.
    let with = |a: &str, b: &str| {
        let mut l: Vec<&str> = lines.clone();
        l[1000] = a;
        l[7000] = b;
        l.join("\n") + "\n"
    };
    let bad = tmp_in("integrity-text", "inf.csv");
    let nan = tmp_in("integrity-text", "nan.csv");
    std::fs::write(&bad, with("inf", "1e308")).unwrap();
    std::fs::write(&nan, with("nan", "nan")).unwrap();
    let tau0 = ["--tau0", "0.01"];
    let got = analyze(&bad, "csv", &tau0);
    let want = analyze(&nan, "csv", &tau0);
    let s = last_of(&got, "summary");
    assert_eq!(s["invalid_values"], 2);
    assert_eq!(s["bad_rows"], 0);
    assert!(last_of(&want, "summary").get("invalid_values").is_none());
    let fc = final_curves(&got);
    assert_eq!(fc.len(), 3);
    assert_eq!(fc, final_curves(&want));
    for c in fc {
        assert!(c["sigma"]
            .as_array()
            .unwrap()
            .iter()
            .all(|x| x.as_f64().is_some_and(f64::is_finite)));
    }
    let fit = last_of(&got, "fit");
    assert_eq!(fit["final"], true);
    assert_eq!(fit["coef"]["N"]["determined"], true);
}
