//! End to end: a damaged siu8 capture through `allanscope analyze` (the built binary).
//!
//! The 5-minute siu8 fixture (75,000 frames) is damaged by a seeded generator that keeps a list
//! of what it did: bit flips at 1e-4 per bit, truncated frames, dropped frames, duplicated
//! frames and garbage bursts (random bytes). The truth follows from that list alone:
//!
//! - the final curves and fits must equal those of the *clean* frames with a gap wherever a
//!   frame was lost or damaged (fed straight to the analysis, no decoder involved);
//! - `frames` = intact originals, `duplicates` = copies sent, `missing` = originals not intact,
//!   `bytes_skipped` = every byte not in an intact frame or copy, `resyncs` = runs of damaged
//!   bytes followed by an intact frame, `crc_errors` = sync patterns (`AA 55`) inside the
//!   damaged bytes with a whole frame's length of stream after them (where the decoder must try
//!   a checksum; a chance pass, 2^-16 per try, would break this count and the curve equality).

use std::process::Command;

use crate::common::pipeline::*;
use allanscope::frame::{Decoder, FrameEvent};
use allanscope::input::Chunk;
use allanscope::sink::records::Record;
use rand::{RngExt, SeedableRng};

const FRAME_LEN: usize = 42;
/// Per-bit flip probability (the 1e-4): about 3.3% of frames damaged.
const BIT_FLIP_RATE: f64 = 1e-4;
const P_DROP: f64 = 0.005;
const P_TRUNCATE: f64 = 0.002;
const P_DUPLICATE: f64 = 0.002;
const P_GARBAGE: f64 = 0.002;
const MAX_GARBAGE_BYTES: usize = 80;
/// Frames kept intact at both ends: a loss there is invisible to any counter.
const INTACT_ENDS: usize = 10;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Seg {
    Intact,
    Copy,
    Damaged,
}

struct Damage {
    stream: Vec<u8>,
    /// (start, len, kind) in stream order.
    segs: Vec<(usize, usize, Seg)>,
    /// Per original frame: delivered intact?
    intact: Vec<bool>,
}

fn damage(clean: &[u8], seed: u64) -> Damage {
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
    let n = clean.len() / FRAME_LEN;
    let mut d = Damage {
        stream: Vec::with_capacity(clean.len() + clean.len() / 50),
        segs: Vec::new(),
        intact: vec![false; n],
    };
    let push = |d: &mut Damage, bytes: &[u8], kind: Seg| {
        if !bytes.is_empty() {
            d.segs.push((d.stream.len(), bytes.len(), kind));
            d.stream.extend_from_slice(bytes);
        }
    };
    for k in 0..n {
        let frame = &clean[k * FRAME_LEN..(k + 1) * FRAME_LEN];
        let protected = k < INTACT_ENDS || k + INTACT_ENDS >= n;
        if protected {
            push(&mut d, frame, Seg::Intact);
            d.intact[k] = true;
            continue;
        }
        if rng.random_bool(P_DROP) {
            continue;
        }
        if rng.random_bool(P_TRUNCATE) {
            let keep = rng.random_range(1..FRAME_LEN);
            push(&mut d, &frame[..keep], Seg::Damaged);
        } else {
            let mut f = frame.to_vec();
            let mut flipped = false;
            for b in f.iter_mut() {
                for bit in 0..8 {
                    if rng.random_bool(BIT_FLIP_RATE) {
                        *b ^= 1 << bit;
                        flipped = true;
                    }
                }
            }
            if flipped {
                push(&mut d, &f, Seg::Damaged);
            } else {
                push(&mut d, &f, Seg::Intact);
                d.intact[k] = true;
                if rng.random_bool(P_DUPLICATE) {
                    push(&mut d, &f, Seg::Copy);
                }
            }
        }
        if rng.random_bool(P_GARBAGE) {
            let g: Vec<u8> = (0..rng.random_range(1..=MAX_GARBAGE_BYTES))
                .map(|_| rng.random())
                .collect();
            push(&mut d, &g, Seg::Damaged);
        }
    }
    d
}

/// The health counters the damage list implies (see the module documentation).
fn truth(d: &Damage) -> [(&'static str, u64); 6] {
    let count = |s: Seg| d.segs.iter().filter(|x| x.2 == s).count() as u64;
    let frames = count(Seg::Intact);
    let duplicates = count(Seg::Copy);
    let missing = d.intact.iter().filter(|&&i| !i).count() as u64;
    let bytes_skipped = d.stream.len() as u64 - FRAME_LEN as u64 * (frames + duplicates);
    let mut crc_errors = 0;
    let mut resyncs = 0;
    let mut in_damage = false;
    for &(start, len, kind) in &d.segs {
        if kind == Seg::Damaged {
            in_damage = true;
            for p in start..start + len {
                if d.stream.get(p..p + 2) == Some(&[0xAA, 0x55][..])
                    && p + FRAME_LEN <= d.stream.len()
                {
                    crc_errors += 1;
                }
            }
        } else if in_damage {
            resyncs += 1;
            in_damage = false;
        }
    }
    [
        ("frames", frames),
        ("duplicates", duplicates),
        ("missing", missing),
        ("bytes_skipped", bytes_skipped),
        ("crc_errors", crc_errors),
        ("resyncs", resyncs),
    ]
}

/// The final records of the clean frames with a gap wherever a frame did not arrive intact.
fn expected_records(clean: &[u8], intact: &[bool]) -> Vec<Record> {
    let desc = siu8();
    let mut dec = Decoder::new(desc.clone());
    dec.push(clean);
    dec.finish();
    let frames: Vec<FrameEvent> = dec.drain().collect();
    assert_eq!(frames.len(), intact.len());
    let mut events = Vec::new();
    let mut gap = 0u64;
    for (ev, &ok) in frames.into_iter().zip(intact) {
        if ok {
            if gap > 0 {
                events.push(FrameEvent::Gap { missing: gap });
                gap = 0;
            }
            events.push(ev);
        } else {
            gap += 1;
        }
    }
    let mut a = analysis(&desc, None);
    let mut interim = Vec::new();
    a.push_chunk(&Chunk::Frames(events), &mut interim);
    a.records(true)
}

#[test]
fn damaged_capture_gives_the_clean_curve_with_gaps_and_true_health() {
    let clean = siu8_capture();
    let d = damage(&clean, 20261122);
    let dir = std::env::temp_dir().join(format!("allanscope-corrupt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let path = dir.join("damaged.siu8");
    std::fs::write(&path, &d.stream).expect("write");
    let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .args([
            "analyze",
            path.to_str().expect("utf-8 path"),
            "--format",
            "siu8",
        ])
        .output()
        .expect("run allanscope");
    let _ = std::fs::remove_dir_all(&dir);
    assert!(out.status.success(), "exit {}", out.status);
    let recs = parse_lines(&out.stdout);

    let health = last_of(&recs, "health");
    let t = truth(&d);
    eprintln!("truth {t:?}");
    for (k, v) in t {
        assert_eq!(health[k], v, "health.{k}");
    }
    // The damage is substantial in every kind.
    for (k, v) in t {
        assert!(v > 0, "{k} should be > 0 in this damaged capture");
    }

    let got = final_curves_and_fits(&recs);
    let want: Vec<Record> = expected_records(&clean, &d.intact)
        .into_iter()
        .filter(|r| matches!(r, Record::Curve(_) | Record::Fit(_)))
        // Through JSON text as the binary's records were (serde_json's float parsing is not
        // always the exact inverse of its printing; the printed text is what must agree).
        .map(|r| {
            let text = serde_json::to_string(&r).expect("serialize");
            serde_json::from_str(&text).expect("parse")
        })
        .collect();
    assert_eq!(got.len(), 32);
    assert_eq!(got.len(), want.len());
    for (g, w) in got.iter().zip(&want) {
        assert_eq!(g, w);
    }
    // The summary's segments: one more than the gaps, on every channel.
    let gaps = d.intact.windows(2).filter(|w| w[0] && !w[1]).count() as u64;
    let s = last_of(&recs, "summary");
    assert_eq!(s["segments"][0], gaps + 1);
}
