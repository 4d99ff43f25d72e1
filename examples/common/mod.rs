//! Helpers shared by the diagnosis studies (`examples/blind_gap.rs`, `examples/family_gap.rs`):
//! parallel map over draws, empirical quantiles, Wilson intervals, log-uniform draws and the
//! bias jumps the benchmarks add themselves (so that the truth is the realised jumps).
//!
//! Each example that uses it declares `mod common;`; not every example uses every helper.
#![allow(dead_code)]

use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// `f(item)` for each of `items` on `threads` threads (item `k` on thread `k % threads`), in
/// the order of `items`.
pub fn par_map<I: Copy + Sync, T: Send>(
    items: &[I],
    threads: usize,
    f: impl Fn(I) -> T + Sync,
) -> Vec<T> {
    let threads = threads.max(1);
    let f = &f;
    let mut out: Vec<(usize, T)> = std::thread::scope(|s| {
        let hs: Vec<_> = (0..threads)
            .map(|t| {
                s.spawn(move || {
                    items
                        .iter()
                        .enumerate()
                        .filter(|(k, _)| k % threads == t)
                        .map(|(k, &i)| (k, f(i)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        hs.into_iter()
            .flat_map(|h| h.join().expect("thread"))
            .collect()
    });
    out.sort_by_key(|r| r.0);
    out.into_iter().map(|r| r.1).collect()
}

/// Empirical quantile `p` of the finite values: the value of rank `round((n - 1) p)` (0-based)
/// in sorted order; NaN when there are none.
pub fn quantile(v: &[f64], p: f64) -> f64 {
    let mut v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() as f64 - 1.0) * p).round() as usize]
}

/// Standard normal distribution function.
pub fn std_normal_cdf(x: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::new(0.0, 1.0).map_or(f64::NAN, |n| n.cdf(x))
}

/// Standard normal quantile (`Phi^-1(p)`).
pub fn std_normal_quantile(p: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::new(0.0, 1.0).map_or(f64::NAN, |n| n.inverse_cdf(p))
}

/// Wilson score interval (95%) of a share `k / n` (Wilson 1927; Brown, Cai and DasGupta 2001):
/// `(p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)`, `z = 1.96`. `(0, 1)` when
/// `n = 0`.
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.959_963_985;
    let (nf, p) = (n as f64, k as f64 / n as f64);
    let c = p + z * z / (2.0 * nf);
    let h = z * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt();
    let d = 1.0 + z * z / nf;
    (((c - h) / d).max(0.0), ((c + h) / d).min(1.0))
}

/// `k/n (p%, 95% Wilson lo-hi%)`.
pub fn share(k: usize, n: usize) -> String {
    let (lo, hi) = wilson(k, n);
    format!(
        "{k}/{n} ({:.0}%, {:.0}-{:.0}%)",
        100.0 * k as f64 / n.max(1) as f64,
        100.0 * lo,
        100.0 * hi
    )
}

/// A draw log-uniform in `[lo, hi]`.
pub fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.random::<f64>() * (hi.ln() - lo.ln())).exp()
}

/// `count` jumps `(time s, size u/s)` at uniform times in `[0, t_run)`, Gaussian sizes of rms
/// `rms_size`, sorted by time.
pub fn draw_jumps(count: u64, rms_size: f64, t_run: f64, seed: u64) -> Vec<(f64, f64)> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut jumps: Vec<(f64, f64)> = (0..count)
        .map(|_| {
            let t = rng.random::<f64>() * t_run;
            // Box-Muller normal.
            let (u1, u2) = (rng.random::<f64>().max(1e-300), rng.random::<f64>());
            let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
            (t, rms_size * z)
        })
        .collect();
    jumps.sort_by(|a, b| a.0.total_cmp(&b.0));
    jumps
}

/// Adds the rate steps `jumps` (time s, size u/s, sorted by time) to increments of `tau0` s:
/// each increment gains the level reached times its length, split exactly inside the increment
/// where a step falls.
pub fn add_jumps(inc: &mut [f64], tau0: f64, jumps: &[(f64, f64)]) {
    let mut level = 0.0;
    let mut next = 0;
    for (k, o) in inc.iter_mut().enumerate() {
        let (t0, t1) = (k as f64 * tau0, (k + 1) as f64 * tau0);
        let mut add = level * tau0;
        while next < jumps.len() && jumps[next].0 < t1 {
            let (tj, s) = jumps[next];
            add += s * (t1 - tj.max(t0));
            level += s;
            next += 1;
        }
        *o += add;
    }
}

/// The rms of the sizes of `jumps`.
pub fn jumps_rms(jumps: &[(f64, f64)]) -> f64 {
    (jumps.iter().map(|j| j.1 * j.1).sum::<f64>() / jumps.len().max(1) as f64).sqrt()
}
