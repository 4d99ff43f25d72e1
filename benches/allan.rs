//! Accumulator throughput (BENCHMARKS.md, "Allan engine"). `cargo bench --bench allan`
use allanscope::allan::accum::{AccumConfig, Engine, FloatRepr, IntRepr, Overlap, StatSet};
use allanscope::allan::Stat;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

/// Counts like a 1 g accelerometer at 4 ms: 186 +- 7 LSB.
fn counts(n: usize, seed: u64) -> Vec<i64> {
    let mut s = seed | 1;
    (0..n)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            186 + (s % 15) as i64 - 7
        })
        .collect()
}

fn cfg(stats: StatSet, noise_id: bool) -> AccumConfig {
    let mut c = AccumConfig::new(0.004);
    c.stats = stats;
    c.noise_id = noise_id;
    c.overlap = Overlap::Bounded(16);
    c
}

fn single_channel(c: &mut Criterion) {
    let n = 10_000_000;
    let d = counts(n, 1);
    let df: Vec<f64> = d.iter().map(|&v| v as f64 * 2.104e-4).collect();
    let mut g = c.benchmark_group("one channel, 1e7 samples, L=16");
    g.throughput(Throughput::Elements(n as u64));
    g.sample_size(10);
    for (name, stats, nid) in [
        ("avar counts", StatSet::only(Stat::Avar), false),
        ("avar counts + noise id", StatSet::only(Stat::Avar), true),
        ("all three counts + noise id", StatSet::ALL, true),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut e: Engine<IntRepr> = Engine::new(cfg(stats, nid));
                d.iter().for_each(|&v| e.push_increment(v));
                e.read()
            })
        });
    }
    for (name, stats, nid) in [
        ("avar float", StatSet::only(Stat::Avar), false),
        ("all three float + noise id", StatSet::ALL, true),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                let mut e: Engine<FloatRepr> = Engine::new(cfg(stats, nid));
                df.iter().for_each(|&v| e.push_increment(v));
                e.read()
            })
        });
    }
    g.finish();
}

fn stand_run(c: &mut Criterion) {
    // 8 channels x 2.7 M samples: a 3-hour 250 Hz run of the stand's unit, in memory.
    let n = 2_700_000;
    let data: Vec<Vec<i64>> = (0..8).map(|k| counts(n, 11 + k)).collect();
    let mut g = c.benchmark_group("8 channels x 2.7e6 samples, all three, L=16");
    g.throughput(Throughput::Elements(8 * n as u64));
    g.sample_size(10);
    g.bench_function("counts + noise id, one sample at a time", |b| {
        b.iter(|| {
            data.iter()
                .map(|d| {
                    let mut e: Engine<IntRepr> = Engine::new(cfg(StatSet::ALL, true));
                    d.iter().for_each(|&v| e.push_increment(v));
                    e.read().len()
                })
                .sum::<usize>()
        })
    });
    g.bench_function("counts + noise id, arrays (push_increments)", |b| {
        b.iter(|| {
            data.iter()
                .map(|d| {
                    let mut e: Engine<IntRepr> = Engine::new(cfg(StatSet::ALL, true));
                    e.push_increments(d);
                    e.read().len()
                })
                .sum::<usize>()
        })
    });
    g.finish();
}

criterion_group!(benches, single_channel, stand_run);
criterion_main!(benches);
