//! The stand-run benchmark and its peer: 8 channels x 2.7 M samples (a 3-hour 250 Hz run of the
//! stand's unit, simulated from config/models/siu8_stand.toml), all three statistics at octave
//! taus with edf and intervals, in memory, on one core. With `--write FILE` it also writes the
//! rate samples (f64, little-endian, channel after channel) for benches/compare_allantools.py.
//! With `--stream` it generates samples on the fly instead of holding them (peak-memory run).
//!
//! `cargo run --release --example stand_run [-- --write /tmp/stand.f64 | --stream]`
use std::io::Write;
use std::time::Instant;

use allanscope::allan::accum::{AccumConfig, ChannelAccumulator, Overlap, StatSet};
use allanscope::allan::curve::{build_curves, AlphaSource};
use allanscope::sim::{SimModel, Simulator};

const N: usize = 2_700_000;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let model = SimModel::load(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/config/models/siu8_stand.toml"
    )))?;
    let tau0 = model.tau0_s;
    let lsbs: Vec<f64> = model
        .channels
        .iter()
        .map(|c| c.lsb.unwrap_or(1.0))
        .collect();
    let mut cfg = AccumConfig::new(tau0);
    cfg.stats = StatSet::ALL;
    cfg.overlap = Overlap::Bounded(16);
    let mut sim = Simulator::new(&model, 1);
    let nch = model.channels.len();
    if args.iter().any(|a| a == "--stream") {
        let mut acc: Vec<ChannelAccumulator> = lsbs
            .iter()
            .map(|&l| ChannelAccumulator::counts(cfg.clone(), l))
            .collect();
        let t = Instant::now();
        for _ in 0..N {
            let step = sim.next_step();
            for (a, c) in acc.iter_mut().zip(step.counts) {
                if let ChannelAccumulator::Counts { engine, .. } = a {
                    engine.push_increment(c.unwrap_or(0));
                }
            }
        }
        let points: usize = acc.iter_mut().map(|a| a.read().len()).sum();
        println!(
            "streamed {nch} x {N} samples (simulation included) in {:.3} s, {points} levels",
            t.elapsed().as_secs_f64()
        );
        return Ok(());
    }
    let mut data: Vec<Vec<i64>> = vec![Vec::with_capacity(N); nch];
    for _ in 0..N {
        let step = sim.next_step();
        for (d, c) in data.iter_mut().zip(step.counts) {
            d.push(c.unwrap_or(0));
        }
    }
    if let Some(i) = args.iter().position(|a| a == "--write") {
        let path = &args[i + 1];
        let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
        for (d, lsb) in data.iter().zip(&lsbs) {
            for &c in d {
                f.write_all(&(c as f64 * lsb / tau0).to_le_bytes())?;
            }
        }
        f.flush()?;
    }
    let t = Instant::now();
    let cpu0 = cpu_seconds();
    let mut points = 0;
    let mut t_acc = 0.0;
    for (d, &lsb) in data.iter().zip(&lsbs) {
        let ta = Instant::now();
        let mut acc = ChannelAccumulator::counts(cfg.clone(), lsb);
        if let ChannelAccumulator::Counts { engine, .. } = &mut acc {
            engine.push_increments(d);
        }
        let readings = acc.read();
        t_acc += ta.elapsed().as_secs_f64();
        let curves = build_curves(
            &readings,
            cfg.stats,
            tau0,
            acc.phase_points(),
            acc.t_data_s(),
            AlphaSource::Lag1,
        );
        points += curves.iter().map(|c| c.points.len()).sum::<usize>();
    }
    let dt = t.elapsed().as_secs_f64();
    let cpu = cpu0.zip(cpu_seconds()).map(|(a, b)| b - a);
    eprintln!(
        "  of which accumulators {t_acc:.3} s, curves (edf, intervals) {:.3} s (wall)",
        dt - t_acc
    );
    // The last field is what benches/compare_allantools.sh reads: CPU time of this thread when
    // the kernel reports it (robust to other load on the machine), wall time otherwise.
    let (what, secs) = match cpu {
        Some(c) => (format!("wall {dt:.3} s, cpu"), c),
        None => ("wall".to_string(), dt),
    };
    println!(
        "allanscope: {nch} channels x {N} samples, avar+hvar+mvar, {points} points: {what}: {secs:.3} s"
    );
    Ok(())
}

/// CPU time this thread has run, in seconds, from Linux's `/proc/thread-self/schedstat`
/// (nanoseconds on the CPU, first field); `None` elsewhere.
fn cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}
