//! The rounding of rate samples after a unit's filter (docs/gap.md, "Rounding after a
//! filter"): `gap::rounding::rounding_avar` against the white floor where the step is fine and
//! against a simulation where it is not.

use allanscope::gap::rounding::{filtered_sigma, rounding_avar};
use allanscope::model::lowpass::LowPass;

/// Overlapping AVAR of rate samples `r` at cluster size `m` (rate units squared).
fn avar(r: &[f64], m: usize) -> f64 {
    let mut c = vec![0.0; r.len() + 1];
    for (i, v) in r.iter().enumerate() {
        c[i + 1] = c[i] + v;
    }
    let yb: Vec<f64> = (0..=r.len() - m)
        .map(|i| (c[i + m] - c[i]) / m as f64)
        .collect();
    let d: Vec<f64> = (0..yb.len() - m).map(|i| yb[i + m] - yb[i]).collect();
    0.5 * d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64
}

/// An 8-tap moving average of white rate, 400 000 samples, rounded to a step of 2 filtered
/// sigmas (the mean at a quarter step): the rounding error's AVAR is the model's within 6% at
/// m = 1, 4, 64 (its own sampling spread is about 1-3%), where the white floor `L^2 / 12 / m`
/// is off by 18% at m = 1 and 45% at m = 64. A step of half a sigma is the white floor.
#[test]
fn the_rounding_after_a_moving_average_has_the_modelled_curve() {
    use rand::{RngExt, SeedableRng};
    use rand_distr::StandardNormal;
    let tau0 = 0.001;
    let n2 = 1e-4;
    let lp = LowPass::MovingAverage { taps: 8, stages: 1 };
    let sigma = filtered_sigma(&lp, tau0, n2);
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
    let sd_x = (n2 / tau0).sqrt();
    let x: Vec<f64> = (0..400_007)
        .map(|_| sd_x * rng.sample::<f64, _>(StandardNormal))
        .collect();
    let s: Vec<f64> = x.windows(8).map(|w| w.iter().sum::<f64>() / 8.0).collect();
    let ms = [1u64, 4, 64];
    for (k, tol) in [(2.0, 0.06), (0.5, 0.03)] {
        let step = k * sigma;
        let e: Vec<f64> = s
            .iter()
            .map(|v| step * ((v + 0.25 * step) / step).round() - 0.25 * step - v)
            .collect();
        let model = rounding_avar(&lp, tau0, step, n2, &ms);
        for (mo, &m) in model.iter().zip(&ms) {
            let sim = avar(&e, m as usize);
            assert!(
                (sim / mo - 1.0).abs() < tol,
                "step {k} sigma, m {m}: {sim} vs {mo}"
            );
            if k == 2.0 && m != 4 {
                let white = step * step / 12.0 / m as f64;
                assert!(
                    (sim / white - 1.0).abs() > 0.15,
                    "m {m}: {sim} vs white {white}"
                );
            }
        }
    }
}
