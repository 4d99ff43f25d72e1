//! IEEE Std 952-1997 annex C read-outs of an Allan-deviation curve, the numbers engineers quote
//! beside (or instead of) a fitted model: angle/velocity random walk read on the -1/2 slope at
//! tau = 1 s, bias instability from the curve's minimum, rate random walk read on the +1/2 slope
//! at tau = 3 s. They come from the curve alone, not from the five-term fit (model::fit), so the
//! two can be compared. Units are native (u/sqrt(s), u/s, u/s/sqrt(s)); model::units converts.
//!
//! The rules (docs/theory.md section 2; IEEE 952 annex C.1 to C.3):
//! - a white-rate term alone gives `sigma(tau) = N / sqrt(tau)`: N is the -1/2 line at tau = 1 s;
//! - a flicker term alone gives the flat `sigma = B sqrt(2 ln 2 / pi) = 0.664 B`: B is the curve's
//!   minimum over 0.664 (the minimum being where the flicker floor shows; where white rate and
//!   rate random walk meet without a flicker floor the minimum still gives a number, an upper
//!   bound on B, as it does on a datasheet);
//! - a rate random walk alone gives `sigma(tau) = K sqrt(tau / 3)`: K is the +1/2 line at 3 s.
//!
//! A slope line is read where the curve runs closest to that slope: at each point the local
//! log-log slope is taken over its two neighbours, the point whose slope is nearest the target is
//! chosen (within [`SLOPE_TOLERANCE`]; otherwise the read-out is absent), and the line of the
//! target slope through that point is read at the reference tau. The 95% interval is the chosen
//! point's interval carried along the same line (the point's relative uncertainty); when the
//! chosen point is the reference tau itself (the usual case for ARW at 1 s) it is that point's
//! own value and interval.

use serde::{Deserialize, Serialize};

use crate::allan::CurvePoint;

/// `sqrt(2 ln 2 / pi)` = 0.6643: the flat Allan deviation of flicker rate noise per unit B.
pub fn flicker_floor_factor() -> f64 {
    (2.0 * std::f64::consts::LN_2 / std::f64::consts::PI).sqrt()
}

/// Largest distance between the local slope and the target for a slope read-out to be made:
/// halfway to the next power-law slope (-1, -1/2, 0, +1/2, +1 are 1/2 apart), less a margin.
pub const SLOPE_TOLERANCE: f64 = 0.2;

/// Reference tau of the ARW read-out (s).
pub const ARW_TAU_S: f64 = 1.0;
/// Reference tau of the RRW read-out (s).
pub const RRW_TAU_S: f64 = 3.0;

/// One read-out: the value, its 95% interval, and where on the curve it was read.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Readout {
    /// The read-out in its native unit.
    pub value: f64,
    pub lo: f64,
    pub hi: f64,
    /// The curve point read (s), and its deviation (u/s).
    pub tau: f64,
    pub sigma: f64,
    /// The curve's local log-log slope at that point.
    pub slope: f64,
}

/// The three read-outs of one curve (`None` where the curve does not show that slope).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
pub struct Readouts {
    /// sigma(1 s) on the -1/2 line: N, u/sqrt(s).
    pub arw: Option<Readout>,
    /// min sigma / 0.664: B, u/s (`tau` and `sigma` are the minimum and where it is).
    pub bias_instability: Option<Readout>,
    /// sigma(3 s) on the +1/2 line: K, u/s/sqrt(s).
    pub rrw: Option<Readout>,
}

/// Local log-log slope at each point, over its neighbours (one-sided at the ends); NaN where
/// fewer than two usable points.
fn local_slopes(p: &[CurvePoint]) -> Vec<f64> {
    let n = p.len();
    (0..n)
        .map(|i| {
            if n < 2 {
                return f64::NAN;
            }
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            let (ta, tb) = (p[a].tau_s.ln(), p[b].tau_s.ln());
            (p[b].sigma().ln() - p[a].sigma().ln()) / (tb - ta)
        })
        .collect()
}

fn usable(p: &CurvePoint) -> bool {
    p.tau_s > 0.0 && p.var > 0.0 && p.var.is_finite()
}

/// The line of slope `target` through the point nearest that slope, read at `tau_ref_s`.
fn slope_readout(p: &[CurvePoint], slopes: &[f64], target: f64, tau_ref_s: f64) -> Option<Readout> {
    let (i, s) = slopes
        .iter()
        .enumerate()
        .filter(|(_, s)| s.is_finite())
        .min_by(|a, b| (a.1 - target).abs().total_cmp(&(b.1 - target).abs()))?;
    if (s - target).abs() > SLOPE_TOLERANCE {
        return None;
    }
    let q = &p[i];
    let scale = (tau_ref_s / q.tau_s).powf(target);
    Some(Readout {
        value: q.sigma() * scale,
        lo: q.sigma_lo * scale,
        hi: q.sigma_hi * scale,
        tau: q.tau_s,
        sigma: q.sigma(),
        slope: *s,
    })
}

/// The read-outs of an Allan-deviation curve (module doc). Points with no positive finite
/// variance are left out.
pub fn readouts(points: &[CurvePoint]) -> Readouts {
    let p: Vec<CurvePoint> = points.iter().filter(|q| usable(q)).cloned().collect();
    if p.len() < 2 {
        return Readouts::default();
    }
    let slopes = local_slopes(&p);
    let arw = slope_readout(&p, &slopes, -0.5, ARW_TAU_S);
    let rrw = slope_readout(&p, &slopes, 0.5, RRW_TAU_S);
    let (i, q) = p
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.var.total_cmp(&b.1.var))
        .expect("two points");
    let f = flicker_floor_factor();
    // A minimum at either end of the curve is no floor: the curve was still falling (or rising
    // from the start), so the bias instability is not shown.
    let bias_instability = (i > 0 && i + 1 < p.len()).then(|| Readout {
        value: q.sigma() / f,
        lo: q.sigma_lo / f,
        hi: q.sigma_hi / f,
        tau: q.tau_s,
        sigma: q.sigma(),
        slope: slopes[i],
    });
    Readouts {
        arw,
        bias_instability,
        rrw,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(tau: f64, sigma: f64) -> CurvePoint {
        CurvePoint {
            m: 1,
            tau_s: tau,
            var: sigma * sigma,
            count: 100,
            edf: 50.0,
            alpha: 0,
            sigma_lo: sigma * 0.9,
            sigma_hi: sigma * 1.1,
            stride: 1,
            n_phase: 102,
        }
    }

    #[test]
    fn exact_curve_gives_the_coefficients() {
        // sigma^2 = N^2/tau + (2 ln2/pi) B^2 + K^2 tau/3 with N = 0.1, B = 0.01, K = 1e-4:
        // the -1/2 line through tau = 0.01 s (N^2/tau dominates 1e4-fold) reads N at 1 s.
        let (n, b, k) = (0.1f64, 0.01f64, 1e-4f64);
        let c = 2.0 * std::f64::consts::LN_2 / std::f64::consts::PI;
        let curve: Vec<CurvePoint> = (0..40)
            .map(|j| 0.001 * 2f64.powf(j as f64 * 0.75))
            .map(|t| pt(t, (n * n / t + c * b * b + k * k * t / 3.0).sqrt()))
            .collect();
        let r = readouts(&curve);
        let arw = r.arw.unwrap();
        assert!((arw.value / n - 1.0).abs() < 0.01, "{arw:?}");
        let rrw = r.rrw.unwrap();
        assert!((rrw.value / k - 1.0).abs() < 0.05, "{rrw:?}");
        // The minimum of the curve is at tau = sqrt(3) N / K, where N and K add 2 N K / sqrt(3)
        // to the flicker floor c B^2; the grid (steps of 2^0.75) finds it within 1%.
        let bi = r.bias_instability.unwrap();
        let min = (c * b * b + 2.0 * n * k / 3f64.sqrt()).sqrt();
        assert!((bi.sigma / min - 1.0).abs() < 0.01, "{bi:?}");
        assert!((bi.value - bi.sigma / c.sqrt()).abs() < 1e-15);
        assert!((bi.lo - bi.value * 0.9).abs() < 1e-15);
    }

    #[test]
    fn minimum_at_the_end_is_not_a_floor() {
        let curve: Vec<CurvePoint> = (0..8)
            .map(|j| 2f64.powi(j))
            .map(|t| pt(t, 1.0 / t.sqrt()))
            .collect();
        let r = readouts(&curve);
        assert!(r.bias_instability.is_none());
        assert!(r.rrw.is_none());
        assert!((r.arw.unwrap().value - 1.0).abs() < 1e-12);
    }
}
