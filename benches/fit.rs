//! Refit time of the five-term model (BENCHMARKS.md, "Noise-model fit"), default method.
//! `cargo bench --bench fit`.
//!
//! - `live_refit`: the refit `src/analysis.rs` does for one channel on each `--every` tick: fit
//!   the AVAR curve whose edfs use the lag-1 noise types, take each tau's noise type from the
//!   fitted model's dominant term, rebuild the curve with those edfs, and fit again with the
//!   same fitter (same counts, other edfs). Only the two fits are timed. The curve is a real
//!   one: the seed paper's MA4 terms simulated at 250 Hz (tau0 = 4 ms) for 2^21 steps (2.3 h)
//!   into the default accumulator (octave taus, bounded overlap), 250 more steps (1 s) per tick.
//! - `live_tick_with_curves`: the same tick with the accumulator read and both curves built
//!   (each point's 95% limits included): the whole per-channel cost of an interim record.
//! - `refit_same_counts`: a synthetic octave curve of 21 taus (m = 1 .. 2^20) whose counts and
//!   edfs have not changed since the last fit.
//! - `refit_growing_counts`: the same curve with 250 more increments per refit: the covariance
//!   lag sums are updated, not recomputed.
//! - `first_fit`: a fresh fitter with the process-wide cache of lag sums emptied (every lag
//!   sum computed).

use allanscope::allan::accum::{AccumConfig, ChannelAccumulator, LevelReading, StatSet};
use allanscope::allan::curve::{build_curves, AlphaSource};
use allanscope::allan::{CurvePoint, Stat};
use allanscope::model::fit::{FitOptions, Fitter};
use allanscope::model::terms::{avar, basis};
use allanscope::sim::{SimModel, Simulator};
use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use std::hint::black_box;
use std::time::{Duration, Instant};

const TAU0_S: f64 = 0.004;
/// The seed paper's MA4 run-3 magnitudes (the seed paper's table 2 (docs/theory.md section 6)), m/s units.
const COEF: [f64; 5] = [7.741e-4, 2.706e-4, 0.477e-4, 2.413e-6, 5.982e-8];
/// The same terms as a simulator model (Q, N, B, K, R), 250 Hz.
const MA4: &str = "rate_hz = 250\n[[channel]]\nname = \"a\"\nunit = \"m/s\"\n\
    Q = 7.741e-4\nN = 2.706e-4\nB = 0.477e-4\nK = 2.413e-6\nR = 5.982e-8\n";
/// The noise type (alpha of S_y) of each term when it dominates, as src/analysis.rs assigns it.
const TERM_ALPHA: [i32; 5] = [2, 0, -1, -2, -2];

fn curve(n_incr: u64) -> Vec<CurvePoint> {
    (0..21)
        .map(|k| {
            let m = 1u64 << k;
            let tau = m as f64 * TAU0_S;
            CurvePoint {
                m,
                tau_s: tau,
                var: avar(COEF, tau),
                count: n_incr - 2 * m + 1,
                edf: 1.5 * (n_incr - 2 * m + 1) as f64 / m as f64,
                alpha: 0,
                sigma_lo: f64::NAN,
                sigma_hi: f64::NAN,
                stride: 1,
                n_phase: n_incr + 1,
            }
        })
        .collect()
}

/// One channel's live data: simulator and accumulator.
struct Live {
    sim: Simulator,
    acc: ChannelAccumulator,
    buf: Vec<f64>,
}

impl Live {
    fn new(steps: usize) -> Live {
        let model = SimModel::from_toml_str(MA4, std::path::Path::new("bench.toml")).unwrap();
        let mut cfg = AccumConfig::new(TAU0_S);
        cfg.stats = StatSet::only(Stat::Avar);
        let mut live = Live {
            sim: Simulator::new(&model, 7),
            acc: ChannelAccumulator::real(cfg),
            buf: vec![0.0; steps],
        };
        live.push();
        live.buf = vec![0.0; 250];
        live
    }

    fn push(&mut self) {
        self.sim.fill_channel(0, &mut self.buf);
        if let ChannelAccumulator::Real(e) = &mut self.acc {
            e.push_increments(&self.buf);
        }
    }

    /// The accumulator's readings and the first (lag-1 noise type) AVAR curve.
    fn read(&mut self) -> (Vec<LevelReading>, Vec<CurvePoint>, u64, f64) {
        let readings = self.acc.read();
        let (n, t) = (self.acc.phase_points(), self.acc.t_data_s());
        let stats = StatSet::only(Stat::Avar);
        let c = build_curves(&readings, stats, TAU0_S, n, t, AlphaSource::Lag1);
        let pts = c.into_iter().next().map(|c| c.points).unwrap_or_default();
        (readings, pts, n, t)
    }
}

/// What `src/analysis.rs` (`analyze_channel`) does on a tick after reading the accumulator:
/// fit the first curve, take the noise types from the model, rebuild the curve with their edfs,
/// fit again. Returns the time spent in the two fits alone.
fn live_tick(
    fitter: &mut Fitter,
    readings: &[LevelReading],
    first: &[CurvePoint],
    n: u64,
    t: f64,
    opts: &FitOptions,
) -> Duration {
    let t0 = Instant::now();
    let f1 = fitter.fit(first, opts).expect("fit");
    let mut in_fits = t0.elapsed();
    let alphas: Vec<i32> = readings
        .iter()
        .map(|r| {
            let b = basis(r.tau_s);
            let (i, _) = (0..5)
                .map(|i| (i, b[i] * f1.c[i]))
                .fold((1, f64::MIN), |a, x| if x.1 > a.1 { x } else { a });
            TERM_ALPHA[i]
        })
        .collect();
    let stats = StatSet::only(Stat::Avar);
    let c = build_curves(readings, stats, TAU0_S, n, t, AlphaSource::Given(&alphas));
    let t1 = Instant::now();
    black_box(fitter.fit(&c[0].points, opts).unwrap_or(f1));
    in_fits += t1.elapsed();
    in_fits
}

fn bench_fit(c: &mut Criterion) {
    let opts = FitOptions::default();

    let mut live = Live::new(1 << 21);
    let mut live_fitter = Fitter::new();
    {
        let (r, p, n, t) = live.read();
        live_tick(&mut live_fitter, &r, &p, n, t, &opts);
    }
    // The two fits of a tick only (timed inside; data, reading and curves outside).
    c.bench_function("live_refit", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                live.push();
                let (r, p, n, t) = live.read();
                total += live_tick(&mut live_fitter, &r, &p, n, t, &opts);
            }
            total
        })
    });
    // The whole tick of one channel: read the accumulator, build the first curve, both fits
    // and the second curve (the curves' own 95% limits included).
    c.bench_function("live_tick_with_curves", |b| {
        b.iter_custom(|iters| {
            let mut total = Duration::ZERO;
            for _ in 0..iters {
                live.push();
                let t0 = Instant::now();
                let (r, p, n, t) = live.read();
                live_tick(&mut live_fitter, &r, &p, n, t, &opts);
                total += t0.elapsed();
            }
            total
        })
    });

    let n0 = 1u64 << 21;
    let pts = curve(n0);
    let mut fitter = Fitter::new();
    fitter.fit(&pts, &opts).expect("fit");
    c.bench_function("refit_same_counts", |b| {
        b.iter(|| black_box(fitter.fit(black_box(&pts), &opts).expect("fit")))
    });

    let mut grow = Fitter::new();
    let mut n = n0;
    grow.fit(&curve(n), &opts).expect("fit");
    c.bench_function("refit_growing_counts", |b| {
        b.iter_batched(
            || {
                n += 250;
                curve(n)
            },
            |p| black_box(grow.fit(&p, &opts).expect("fit")),
            BatchSize::SmallInput,
        )
    });

    let mut g = c.benchmark_group("cold");
    g.sample_size(10);
    g.bench_function("first_fit", |b| {
        b.iter(|| {
            // Cold: the process-wide cache of pair sums would otherwise answer every pair.
            allanscope::model::avar_cov::clear_shared_cache();
            black_box(Fitter::new().fit(black_box(&pts), &opts).expect("fit"))
        })
    });
    g.finish();
}

criterion_group!(benches, bench_fit);
criterion_main!(benches);
