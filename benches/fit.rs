//! Refit time of the five-term model (BENCHMARKS.md, "Noise-model fit"): an octave AVAR curve
//! of 21 taus (2^21 increments at tau0 = 4 ms, 2.3 h, m = 1 .. 2^20), fitted with the default
//! method. `cargo bench --bench fit`.
//!
//! - `refit_same_counts`: the curve's counts have not changed since the last fit (the second fit
//!   of the analysis' two passes).
//! - `refit_growing_counts`: every refit sees 250 more increments (1 s of data at 250 Hz), the
//!   live case: the covariance lag sums are updated, not recomputed.
//! - `first_fit`: a fresh fitter (every lag sum computed).

use allanscope::allan::CurvePoint;
use allanscope::model::fit::{FitOptions, Fitter};
use allanscope::model::terms::avar;
use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use std::hint::black_box;

const TAU0_S: f64 = 0.004;
/// The seed paper's MA4 run-3 magnitudes (SEED.md table 2), m/s units.
const COEF: [f64; 5] = [7.741e-4, 2.706e-4, 0.477e-4, 2.413e-6, 5.982e-8];

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
            }
        })
        .collect()
}

fn bench_fit(c: &mut Criterion) {
    let opts = FitOptions::default();
    let n0 = 1u64 << 21;
    let pts = curve(n0);

    let mut fitter = Fitter::new();
    fitter.fit(&pts, &opts).expect("fit");
    c.bench_function("refit_same_counts", |b| {
        b.iter(|| black_box(fitter.fit(black_box(&pts), &opts).expect("fit")))
    });

    let mut live = Fitter::new();
    let mut n = n0;
    live.fit(&curve(n), &opts).expect("fit");
    c.bench_function("refit_growing_counts", |b| {
        b.iter_batched(
            || {
                n += 250;
                curve(n)
            },
            |p| black_box(live.fit(&p, &opts).expect("fit")),
            BatchSize::SmallInput,
        )
    });

    let mut g = c.benchmark_group("cold");
    g.sample_size(10);
    g.bench_function("first_fit", |b| {
        b.iter(|| black_box(Fitter::new().fit(black_box(&pts), &opts).expect("fit")))
    });
    g.finish();
}

criterion_group!(benches, bench_fit);
criterion_main!(benches);
