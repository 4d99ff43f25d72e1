//! One accumulator configuration over 2 M counts, for instruction counting with callgrind:
//! `valgrind --tool=callgrind target/release/examples/kernel_probe all [--per-sample]`
use allanscope::allan::accum::{AccumConfig, Engine, IntRepr, Overlap, StatSet};
use allanscope::allan::Stat;

fn main() {
    let which = std::env::args().nth(1).unwrap_or_else(|| "all".into());
    let mut cfg = AccumConfig::new(0.004);
    cfg.overlap = Overlap::Bounded(16);
    cfg.noise_id = which == "all";
    cfg.stats = match which.as_str() {
        "avar" => StatSet::only(Stat::Avar),
        "hvar" => StatSet::only(Stat::Hvar),
        "mvar" => StatSet::only(Stat::Mvar),
        _ => StatSet::ALL,
    };
    let mut e: Engine<IntRepr> = Engine::new(cfg);
    let mut s: u64 = 0x9E3779B97F4A7C15;
    let d: Vec<i64> = (0..2_000_000)
        .map(|_| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            186 + (s % 15) as i64 - 7
        })
        .collect();
    // `--reps N` repeats the run (for sampling profilers such as `perf record`).
    let args: Vec<String> = std::env::args().collect();
    let reps: usize = args
        .iter()
        .position(|a| a == "--reps")
        .and_then(|i| args.get(i + 1)?.parse().ok())
        .unwrap_or(1);
    for _ in 1..reps {
        let mut e2: Engine<IntRepr> = Engine::new(e.config().clone());
        e2.push_increments(&d);
        std::hint::black_box(e2.read());
    }
    if args.iter().any(|a| a == "--per-sample") {
        d.iter().for_each(|&v| e.push_increment(v));
    } else {
        e.push_increments(&d);
    }
    println!("{}", e.read().len());
}
