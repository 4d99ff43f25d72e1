//! Homogeneity of the curve across the run's segments (docs/theory.md section 5, "Where in time"):
//! the per-segment AVAR at each octave tau against the segments' weighted mean, scaled by the
//! model's relative variance. Part of [`super::diagnose`](mod@super::diagnose)'s record; decides nothing.

use super::evidence::{EvidenceSnapshot, OVERLAP_L};
use crate::model::avar_cov::{AvarCovariance, CovPoint};
use crate::model::terms::basis;
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// Homogeneity of one tau across the segments (docs/theory.md section 5, "Where in time").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentTest {
    pub tau_s: f64,
    /// `sum_k (ln v_k - mean)^2 / Var(ln v_k)` over `K - 1`: about 1 when homogeneous.
    pub stat: f64,
    /// Probability of a larger statistic under homogeneity (chi-squared with K - 1 dof).
    pub p_value: f64,
    /// The segment that departs most, and its ADEV over the segments' geometric mean.
    pub worst_segment: usize,
    pub worst_ratio: f64,
}

/// Homogeneity across the segments of each octave tau with enough differences per segment:
/// `ln v_k` against its weighted mean, scaled by the model's relative variance at the
/// segment's count (docs/theory.md section 5, "Where in time"). Segments shorter than half the
/// longest are left out.
pub fn segment_tests(snap: &EvidenceSnapshot, c: &[f64; 5]) -> Vec<SegmentTest> {
    let longest = snap.segments.iter().map(|s| s.len).max().unwrap_or(0);
    let segs: Vec<_> = snap
        .segments
        .iter()
        .filter(|s| s.len * 2 >= longest)
        .collect();
    if segs.len() < 3 {
        return Vec::new();
    }
    let shortest = segs.iter().map(|s| s.len).min().unwrap_or(0);
    let tau0 = snap.tau0_s;
    let mut cov = AvarCovariance::new();
    let mut out = Vec::new();
    let mut m = 1u64;
    while m * 16 <= shortest {
        let tau = m as f64 * tau0;
        let a: f64 = basis(tau).iter().zip(c).map(|(b, c)| b * c).sum();
        let vals: Vec<(f64, f64)> = segs
            .iter()
            .filter_map(|s| {
                let (v, _) = s.avar(m)?;
                // The segments' levels are taken at the evidence's bounded overlap, stride
                // `m / L` at these octave sizes (powers of two), and the count is the span's
                // full one (`matrix_strided`). Full overlap at every level made the variance far
                // too small where white phase noise rules: every clean two-hour run of the seed
                // paper's MA4 had a p-value of 0 (docs/gap.md, "The segments' variance").
                let count = (s.len + 1).saturating_sub(2 * m).max(1);
                let stride = (m / OVERLAP_L).max(1);
                let var = cov.matrix_strided(tau0, &[CovPoint { m, count }], &[stride], c)[(0, 0)]
                    / (a * a);
                (v > 0.0 && var > 0.0).then_some((v.ln(), var))
            })
            .collect();
        if vals.len() >= 3 && a > 0.0 {
            let wsum: f64 = vals.iter().map(|(_, w)| 1.0 / w).sum();
            let mean = vals.iter().map(|(l, w)| l / w).sum::<f64>() / wsum;
            let h: f64 = vals.iter().map(|(l, w)| (l - mean).powi(2) / w).sum();
            let k1 = (vals.len() - 1) as f64;
            let p = ChiSquared::new(k1).map_or(f64::NAN, |d| 1.0 - d.cdf(h));
            let (wi, wl) = vals
                .iter()
                .enumerate()
                .max_by(|x, y| (x.1 .0 - mean).abs().total_cmp(&(y.1 .0 - mean).abs()))
                .map(|(i, v)| (i, v.0))
                .unwrap_or((0, mean));
            out.push(SegmentTest {
                tau_s: tau,
                stat: h / k1,
                p_value: p,
                worst_segment: wi,
                worst_ratio: ((wl - mean) / 2.0).exp(),
            });
        }
        m *= 2;
    }
    out
}
