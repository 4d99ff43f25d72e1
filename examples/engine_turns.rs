//! What it costs the statistics to be fed the way a replay feeds them: four channels' engines
//! taking turns every 6,200 samples (one 256 KiB read of siu8 frames, as on one of the replay's
//! two analysis threads), against each engine fed all its samples at once (as
//! `examples/stand_run` does). Same samples (four channels of the siu8 stand model, 2.7 M each),
//! same settings, same results (the levels are compared); thread CPU time of each way, several
//! rounds side by side. BENCHMARKS.md, issue 15 session 9, item (a).
//!
//! `cargo run --release --example engine_turns [-- TURN]` (TURN samples per turn, default 6,200)
use allanscope::allan::accum::{AccumConfig, ChannelAccumulator, LevelReading, Overlap, StatSet};
use allanscope::sim::{SimModel, Simulator};

const N: usize = 2_700_000;
const CHANNELS: usize = 4;
/// Frames in one 256 KiB read of 42-byte siu8 frames.
const TURN: usize = 6_200;
const ROUNDS: usize = 5;

fn main() -> anyhow::Result<()> {
    let model = SimModel::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/config/models/siu8_stand.toml"
    )))?;
    let mut cfg = AccumConfig::new(model.tau0_s);
    cfg.stats = StatSet::ALL;
    cfg.overlap = Overlap::Bounded(16);
    let mut sim = Simulator::new(&model, 1);
    let mut data: Vec<Vec<i64>> = (0..CHANNELS).map(|_| Vec::with_capacity(N)).collect();
    for _ in 0..N {
        let step = sim.next_step();
        for (d, c) in data.iter_mut().zip(step.counts) {
            d.push(c.unwrap_or(0));
        }
    }
    let turn: usize = match std::env::args().nth(1) {
        Some(a) => a.parse()?,
        None => TURN,
    };
    let mut ratios = Vec::new();
    for round in 1..=ROUNDS {
        let (whole, a) = feed(&cfg, &data, N);
        let (turns, b) = feed(&cfg, &data, turn);
        anyhow::ensure!(a == b, "the two ways gave different levels");
        ratios.push(turns / whole);
        println!(
            "round {round}: whole {whole:.4} s, taking turns every {turn} samples {turns:.4} s, ratio {:.3}",
            turns / whole
        );
    }
    ratios.sort_by(f64::total_cmp);
    println!(
        "ratio turns / whole: median {:.3}, range {:.3}-{:.3}",
        ratios[ratios.len() / 2],
        ratios[0],
        ratios[ratios.len() - 1]
    );
    Ok(())
}

/// Feeds every channel's samples in pieces of `piece`, the channels taking turns; returns the
/// thread CPU seconds it took and the levels read at the end.
fn feed(cfg: &AccumConfig, data: &[Vec<i64>], piece: usize) -> (f64, Vec<Vec<LevelReading>>) {
    let mut acc: Vec<ChannelAccumulator> = data
        .iter()
        .map(|_| ChannelAccumulator::counts(cfg.clone(), 1.0))
        .collect();
    let t0 = cpu_seconds();
    let mut at = 0;
    while at < N {
        let end = (at + piece).min(N);
        for (a, d) in acc.iter_mut().zip(data) {
            if let ChannelAccumulator::Counts { engine, .. } = a {
                engine.push_increments(&d[at..end]);
            }
        }
        at = end;
    }
    let levels = acc.iter_mut().map(|a| a.read()).collect();
    (cpu_seconds() - t0, levels)
}

/// CPU time this thread has run, in seconds (Linux `/proc/thread-self/schedstat`, first field,
/// nanoseconds); 0 elsewhere, where the ratios mean nothing.
fn cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns * 1e-9)
}
