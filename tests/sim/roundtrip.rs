//! Round trip: simulate -> frames -> decode -> analysis gives the same curves as analyzing the
//! simulated samples directly (issue "Simulator"), through the library and through the binary.

use std::process::Command;

use allanscope::allan::accum::{AccumConfig, ChannelAccumulator};
use allanscope::analysis::{AnalysisOptions, ChannelSetup, InputKind, RunAnalysis};
use allanscope::frame::{Decoder, FrameDescriptor};
use allanscope::input::Chunk;
use allanscope::sim::capture::simulate_to_frames;
use allanscope::sim::{SimModel, Simulator};
use allanscope::sink::records::Record;

const DURATION_S: f64 = 120.0;

fn model() -> SimModel {
    SimModel::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/config/models/siu8_stand.toml"
    )))
    .unwrap()
}

#[test]
fn frames_decode_to_the_simulated_counts_and_the_same_curves() {
    let model = model();
    let desc = FrameDescriptor::load("siu8").unwrap();
    let mut bytes = Vec::new();
    let frames = simulate_to_frames(&model, &desc, DURATION_S, 5, &mut bytes).unwrap();
    assert_eq!(frames, (DURATION_S / model.tau0_s).round() as u64);
    assert_eq!(bytes.len() as u64, frames * 42);

    // Direct: the simulator's own counts into one accumulator per channel.
    let cfg = AccumConfig::new(model.tau0_s);
    let chans = desc.channels();
    let mut direct: Vec<ChannelAccumulator> = chans
        .iter()
        .map(|c| ChannelAccumulator::counts(cfg.clone(), c.scale.unwrap()))
        .collect();
    let index: Vec<usize> = chans
        .iter()
        .map(|c| {
            model
                .channels
                .iter()
                .position(|m| m.name == c.name)
                .unwrap()
        })
        .collect();
    let mut sim = Simulator::new(&model, 5);
    for _ in 0..frames {
        let step = sim.next_step();
        for (acc, &i) in direct.iter_mut().zip(&index) {
            if let ChannelAccumulator::Counts { engine, .. } = acc {
                engine.push_increment(step.counts[i].unwrap());
            }
        }
    }

    // Through the frames: decode at odd chunk sizes, feed the analysis.
    let mut decoder = Decoder::new(desc.clone());
    let setups = ChannelSetup::for_frames(&desc);
    let opts = AnalysisOptions {
        accum: cfg.clone(),
        kind: InputKind::Increments,
        every_s: None,
        fit: None,
        run: None,
        limits: Vec::new(),
        diagnose: false,
    };
    let mut analysis = RunAnalysis::new("roundtrip", setups, opts);
    let mut out = Vec::new();
    for piece in bytes.chunks(4093) {
        decoder.push(piece);
        let events: Vec<_> = decoder.drain().collect();
        analysis.push_chunk(&Chunk::Frames(events), &mut out);
    }
    decoder.finish();
    assert_eq!(decoder.health().frames, frames);
    assert_eq!(decoder.health().crc_errors + decoder.health().missing, 0);

    for (ch, acc) in direct.iter_mut().enumerate() {
        let want = acc.read();
        let got = analysis.curves(ch);
        for curve in &got {
            assert_eq!(
                curve.points.len(),
                want.iter().filter(|r| r.get(curve.stat).is_some()).count()
            );
            for p in &curve.points {
                let r = want.iter().find(|r| r.m == p.m).unwrap();
                let (var, n) = r.get(curve.stat).unwrap();
                // Same integers, same order of operations: identical to the last bit.
                assert_eq!(
                    (p.var, p.count),
                    (var, n),
                    "{} {:?} m={}",
                    chans[ch].name,
                    curve.stat,
                    p.m
                );
            }
        }
    }
}

#[test]
fn the_binary_round_trips_csv_and_frames_to_the_same_curves() {
    let exe = env!("CARGO_BIN_EXE_allanscope");
    let dir = std::env::temp_dir().join(format!("allanscope-rt-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = concat!(env!("CARGO_MANIFEST_DIR"), "/config/models/siu8_stand.toml");
    let run = |args: &[&str]| {
        let out = Command::new(exe).args(args).output().unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        out.stdout
    };
    let csv = dir.join("s.csv");
    let cap = dir.join("s.siu8");
    for (fmt, path) in [("csv", &csv), ("siu8", &cap)] {
        run(&[
            "simulate",
            "--model",
            model,
            "--duration",
            "60",
            "--seed",
            "9",
            "--format",
            fmt,
            "-o",
            path.to_str().unwrap(),
        ]);
    }
    let from_csv = run(&[
        "analyze",
        csv.to_str().unwrap(),
        "--tau0",
        "0.004",
        "--fit",
        "none",
    ]);
    let from_frames = run(&[
        "analyze",
        cap.to_str().unwrap(),
        "--format",
        "siu8",
        "--fit",
        "none",
    ]);
    let curves = |bytes: &[u8]| -> Vec<(String, String, Vec<f64>, Vec<u64>)> {
        String::from_utf8_lossy(bytes)
            .lines()
            .filter_map(|l| match serde_json::from_str::<Record>(l).unwrap() {
                Record::Curve(c) => Some((c.channel, c.stat.name().to_string(), c.sigma, c.count)),
                _ => None,
            })
            .collect()
    };
    let (a, b) = (curves(&from_csv), curves(&from_frames));
    assert_eq!(a.len(), 24, "8 channels x 3 statistics");
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(&b) {
        assert_eq!((&x.0, &x.1, &x.3), (&y.0, &y.1, &y.3));
        for (s, t) in x.2.iter().zip(&y.2) {
            // The CSV carries count * LSB as decimals, each parsed to the nearest double (an
            // accelerometer's 0.04 m/s increment to ~7e-18 m/s); the frames carry the counts
            // exactly. At long taus MVAR sums m^2 such rounding errors against a small signal,
            // which was seen to move it by 2.8e-12 relative: allow 1e-9.
            assert!((s - t).abs() <= 1e-9 * t, "{} {}: {s:e} vs {t:e}", x.0, x.1);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
