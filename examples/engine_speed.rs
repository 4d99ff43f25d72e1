//! Quick timing of the accumulators (the criterion bench in benches/allan.rs is the record).
//! `cargo run --release --example engine_speed`
use allanscope::allan::accum::{AccumConfig, Engine, FloatRepr, IntRepr, Overlap, StatSet};
use allanscope::allan::Stat;
use std::time::Instant;

fn data(n: usize) -> Vec<i64> {
    let mut s: u64 = 0x9E3779B97F4A7C15;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            186 + (s % 15) as i64 - 7
        })
        .collect()
}

fn main() {
    let n = 20_000_000;
    let d = data(n);
    let df: Vec<f64> = d.iter().map(|&v| v as f64 * 2.104e-4).collect();
    for (label, stats, nid) in [
        ("avar only, no noise id", StatSet::only(Stat::Avar), false),
        ("avar only, noise id", StatSet::only(Stat::Avar), true),
        ("hvar only", StatSet::only(Stat::Hvar), false),
        ("mvar only", StatSet::only(Stat::Mvar), false),
        ("all three, noise id", StatSet::ALL, true),
    ] {
        let mut cfg = AccumConfig::new(0.004);
        cfg.stats = stats;
        cfg.noise_id = nid;
        cfg.overlap = Overlap::Bounded(16);
        let t = Instant::now();
        let mut e: Engine<IntRepr> = Engine::new(cfg.clone());
        for &v in &d {
            e.push_increment(v);
        }
        let r = e.read();
        let dt = t.elapsed().as_secs_f64();
        let t2 = Instant::now();
        let mut ef: Engine<FloatRepr> = Engine::new(cfg.clone());
        for &v in &df {
            ef.push_increment(v);
        }
        let rf = ef.read();
        let dt2 = t2.elapsed().as_secs_f64();
        println!(
            "{label}: int {:.1} M/s, float {:.1} M/s ({} levels, {} levels)",
            n as f64 / dt / 1e6,
            n as f64 / dt2 / 1e6,
            r.len(),
            rf.len()
        );
    }
}
