//! One accumulator configuration over 2 M counts, for instruction counting with callgrind:
//! `valgrind --tool=callgrind target/release/examples/kernel_probe all`
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
    for _ in 0..2_000_000 {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        e.push_increment(186 + (s % 15) as i64 - 7);
    }
    println!("{}", e.read().len());
}
