//! 95% intervals of the accepted effects' parameters and of the five terms (docs/gap.md,
//! "Parameter intervals"; the terms: [`term_interval`]), from
//! the Fisher information of the final GLS fit on the curve: with `theta` the logs of the
//! active five-term coefficients, of each effect column's amplitude squared and of each shape
//! parameter, `J = d ln AVAR_model / d theta` (shapes by central differences), the covariance
//! of `theta_hat` is `(J' S^-1 J)^-1`, scaled up (never down) by the final gap `G` as a
//! residual variance. Each interval is `p exp(+-1.96 sd(ln p))`, so it stays positive. Where a
//! sinusoid is in the model each tau's standard deviation is widened by its cross term with
//! the noise (`sqrt(1 + 2 A_s / A_n)`, below), which the noise's covariance lacks.
//! The temperature's interval is its own (gap::temperature); warm-ups and jumps get none. The
//! filters' shapes get theirs the same way (the covariance is exact for them since
//! [`super::filter_cov`]; coverage in docs/gap.md), the moving average's whole taps by the
//! profile of `r' S^-1 r` ([`taps_profile`]).

use super::diagnose::AddedEffect;
use super::effects::{EffectKind, EffectParams};
use super::problem::{GapProblem, GlsFit, ModelSpec};
use crate::model::fit::QUANTITATION_FRACTION;
use nalgebra::{DMatrix, DVector};

/// Two-sided 95% normal quantile.
const Z95: f64 = 1.959_963_984_540_054;
/// Relative step of the central differences in `ln shape`.
const H: f64 = 1e-3;

/// One effect's intervals: `(parameter name of docs/records.md, [lo, hi])`.
pub type Intervals = Vec<(&'static str, [f64; 2])>;

/// One of the five terms of the final fit with its 95% interval (docs/theory.md section 2 units).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TermInterval {
    /// The estimate (0 when the fit set the term to zero).
    pub value: f64,
    /// The interval; `lo` 0 when the curve does not exclude zero.
    pub lo: f64,
    pub hi: f64,
    /// Its interval excludes zero and reaches no lower than `QUANTITATION_FRACTION` of the
    /// value, as in the `fit` record (docs/fit.md, "Which terms are determined").
    pub determined: bool,
}

/// The 95% intervals of the final fit: each accepted effect's parameters and the five terms'
/// (`[Q, N, B, K, R]`; `None` where no fit could be made).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FitIntervals {
    pub effects: Vec<Intervals>,
    pub terms: [Option<TermInterval>; 5],
}

/// The shape parameters of an effect that the Fisher information covers, with their values.
fn shapes(p: &EffectParams) -> Vec<(&'static str, f64)> {
    match *p {
        EffectParams::GaussMarkov { tau_c_s, .. } => vec![("tau_c", tau_c_s)],
        EffectParams::Sinusoid { frequency_hz, .. } => vec![("frequency", frequency_hz)],
        EffectParams::OutputFilter { time_constant_s }
        | EffectParams::ZeroPhaseFilter { time_constant_s } => {
            vec![("time_constant", time_constant_s)]
        }
        EffectParams::SecondOrderFilter {
            natural_frequency_hz,
            damping,
            zero,
            ..
        } => {
            let mut v = vec![
                ("natural_frequency", natural_frequency_hz),
                ("damping", damping),
            ];
            // the sampled form's zero, a third shape (in its logarithm: above 0 only)
            if let Some(c) = zero.filter(|&c| c > 0.0) {
                v.push(("zero", c));
            }
            v
        }
        EffectParams::BandNoise {
            frequency_hz,
            width_hz,
            ..
        } => vec![("frequency", frequency_hz), ("width", width_hz)],
        // (its taps are a whole number, as a moving average's)
        // (the Butterworth's order too)
        EffectParams::FirFilter { cutoff_hz, .. }
        | EffectParams::ButterworthFilter { cutoff_hz, .. } => vec![("cutoff", cutoff_hz)],
        _ => Vec::new(),
    }
}

/// `iv`, an interval of shape `name` of `p`, held to the values the kind can take where it is
/// bounded: a second order's damping to the scan's range, its natural frequency to the scan's
/// grid (the polish is held within it, docs/gap.md "The second-order polish within the grid
/// (session 44)"), its zero to `[0, MAX_ZERO]`. Where the frequency, the damping and the
/// zero trade off along one valley the Fisher information is nearly singular, and the three
/// intervals of a review's accelerometer behind a CIC and a first order ran from 1e-47 to
/// 1e50 (docs/gap.md, "Intervals within the second order's range (session 45)"); held, they
/// say the curve leaves the shape open within the model's range. Other shapes are returned as
/// they are.
fn within_model(prob: &GapProblem, p: &EffectParams, name: &str, iv: [f64; 2]) -> [f64; 2] {
    if p.kind() != EffectKind::SecondOrderFilter {
        return iv;
    }
    let (lo, hi) = match name {
        "damping" => super::filter_scan::DAMPING_RANGE,
        "zero" => (0.0, crate::model::lowpass::MAX_ZERO),
        "natural_frequency" => {
            let g = prob.grid(EffectKind::SecondOrderFilter);
            // (the bilinear form's grid goes on towards Nyquist)
            let top = match p {
                EffectParams::SecondOrderFilter { bilinear: true, .. } => {
                    super::filter_scan::BILINEAR_TOP / prob.tau0_s
                }
                _ => g.hi,
            };
            (g.lo, top)
        }
        _ => return iv,
    };
    // A zero's interval is formed in its logarithm, so it never reaches 0 (no zero, the
    // bilinear form); one that reaches below 1e-6 does, in effect.
    let floor = if name == "zero" && iv[0] < ZERO_NEGLIGIBLE {
        0.0
    } else {
        iv[0]
    };
    [floor.clamp(lo, hi), iv[1].clamp(lo, hi)]
}

/// A sampled form's zero below this is no zero ([`within_model`]).
const ZERO_NEGLIGIBLE: f64 = 1e-6;

/// `p` with shape `i` multiplied by `f`.
fn scaled(p: &EffectParams, i: usize, f: f64) -> EffectParams {
    let mut q = *p;
    match &mut q {
        EffectParams::GaussMarkov { tau_c_s: x, .. }
        | EffectParams::Sinusoid {
            frequency_hz: x, ..
        }
        | EffectParams::OutputFilter { time_constant_s: x }
        | EffectParams::ZeroPhaseFilter { time_constant_s: x }
        | EffectParams::FirFilter { cutoff_hz: x, .. }
        | EffectParams::ButterworthFilter { cutoff_hz: x, .. } => *x *= f,
        EffectParams::SecondOrderFilter { zero: Some(c), .. } if i == 2 => *c *= f,
        EffectParams::SecondOrderFilter {
            natural_frequency_hz: a,
            damping: b,
            ..
        }
        | EffectParams::BandNoise {
            frequency_hz: a,
            width_hz: b,
            ..
        } => {
            if i == 0 {
                *a *= f
            } else {
                *b *= f
            }
        }
        _ => {}
    }
    q
}

/// The spec of `effects` (stationary ones; warm-ups and jumps are in `offset`).
fn spec_of(prob: &GapProblem, effects: &[EffectParams], offset: &Option<Vec<f64>>) -> ModelSpec {
    let mut spec = ModelSpec {
        offset: offset.clone(),
        ..ModelSpec::default()
    };
    for p in effects.iter().filter(|p| p.kind().is_stationary()) {
        spec = prob.spec_with_params(&spec, p);
    }
    spec
}

/// The intervals of each of `effects` (in order; empty for those without) and of the five
/// terms, from the final fit `fit` of the spec `spec` they make. A term's interval has the
/// effects' amplitudes and shapes as nuisance parameters, so a flicker term beside a
/// Gauss-Markov hump it trades with shows how little the curve fixes it.
pub fn fit_intervals(
    prob: &GapProblem,
    spec: &ModelSpec,
    fit: &GlsFit,
    effects: &[AddedEffect],
) -> FitIntervals {
    let params: Vec<EffectParams> = effects.iter().map(|e| e.params).collect();
    let j = prob.len();
    let scale = fit.gap().max(1.0);
    let m0: Vec<f64> = prob.model_of(spec, &fit.coef);
    if m0.iter().any(|v| v.is_nan() || *v <= 0.0) {
        return FitIntervals {
            effects: vec![Vec::new(); effects.len()],
            terms: [None; 5],
        };
    }
    // Columns of J: active coefficients, then the shapes.
    let mut cols: Vec<Vec<f64>> = Vec::new();
    let mut coef_col: Vec<Option<usize>> = vec![None; fit.coef.len()];
    let no_offset = ModelSpec {
        offset: None,
        ..spec.clone()
    };
    for (c, &v) in fit.coef.iter().enumerate() {
        if v > 0.0 {
            let mut unit = vec![0.0; fit.coef.len()];
            unit[c] = v;
            // The column's own part, without the fixed part (the offset and a filter's
            // rounding, `GapProblem::filter_floor`).
            let part = prob.linear_part(&no_offset, &unit);
            coef_col[c] = Some(cols.len());
            cols.push(part.iter().zip(&m0).map(|(a, m)| a / m).collect());
        }
    }
    let mut shape_col: Vec<Vec<usize>> = vec![Vec::new(); params.len()];
    for (e, p) in params.iter().enumerate() {
        for (i, _) in shapes(p).iter().enumerate() {
            let curve = |f: f64| {
                let mut ps = params.clone();
                ps[e] = scaled(p, i, f);
                prob.model_of(&spec_of(prob, &ps, &spec.offset), &fit.coef)
            };
            let (up, dn) = (curve(H.exp()), curve((-H).exp()));
            if up.iter().chain(&dn).any(|v| v.is_nan() || *v <= 0.0) {
                continue;
            }
            shape_col[e].push(cols.len());
            cols.push(
                up.iter()
                    .zip(&dn)
                    .map(|(a, b)| (a.ln() - b.ln()) / (2.0 * H))
                    .collect(),
            );
        }
    }
    // A sinusoid is a fixed signal, not noise: its AVAR estimate's error is the cross term of
    // the signal with the noise, which the curve's covariance (of the noise's five terms) lacks.
    // For a signal of AVAR `A_s` beside noise of AVAR `A_n` the estimate's variance is about
    // `(2 A_n^2 + 4 A_s A_n) / M` (M differences; the noise part `2 A_n^2 / M`), so each tau's
    // standard deviation is widened by `sqrt(1 + 2 A_s / A_n)`. Without it a sinusoid of about
    // the noise's ADEV at its hump (a MEMS gyro at 200 Hz, 0.05 Hz, two hours) had its amplitude
    // covered in 23 of 30 runs, the estimates' spread 1.8 times the interval's standard error
    // (docs/gap.md, "Parameter intervals", session 39).
    // Each effect's amplitude column in `cols`: the extra coefficients follow the five terms
    // in the order of the stationary non-filter effects.
    let mut extra = 5;
    let amp_col: Vec<Option<usize>> = params
        .iter()
        .map(|p| {
            let kind = p.kind();
            if !kind.is_stationary() || kind.is_filter() {
                return None;
            }
            extra += 1;
            coef_col.get(extra - 1).copied().flatten()
        })
        .collect();
    let mut sine_share = vec![0.0; j];
    for (p, c) in params.iter().zip(&amp_col) {
        if let (EffectKind::Sinusoid, Some(c)) = (p.kind(), *c) {
            for (sh, v) in sine_share.iter_mut().zip(&cols[c]) {
                *sh += v.max(0.0);
            }
        }
    }
    let widen: Vec<f64> = sine_share
        .iter()
        .map(|&sh| {
            let sh = sh.min(0.99);
            (1.0 + 2.0 * sh / (1.0 - sh)).sqrt()
        })
        .collect();
    let k = cols.len();
    let mut jw = DMatrix::zeros(j, k);
    for (c, col) in cols.iter().enumerate() {
        let scaled: Vec<f64> = col.iter().zip(&widen).map(|(v, w)| v / w).collect();
        let w = prob.whiten(&DVector::from_vec(scaled));
        jw.set_column(c, &w);
    }
    let cov = (jw.transpose() * &jw).try_inverse();
    let sd = |c: usize| {
        cov.as_ref()
            .map_or(f64::NAN, |m| (m[(c, c)].max(0.0) * scale).sqrt())
    };
    let interval = |v: f64, s: f64| [v * (-Z95 * s).exp(), v * (Z95 * s).exp()];
    // ln term = ln c / 2, as the amplitudes below.
    let fisher: [Option<[f64; 2]>; 5] = std::array::from_fn(|c| {
        let col = coef_col.get(c).copied().flatten()?;
        let iv = interval(fit.coef[c].sqrt(), sd(col) / 2.0);
        iv.iter().all(|x| x.is_finite()).then_some(iv)
    });
    let terms = std::array::from_fn(|c| term_interval(prob, spec, fit, c, fisher[c], scale));
    let effects = params
        .iter()
        .enumerate()
        .map(|(e, p)| {
            let mut out: Intervals = Vec::new();
            let kind = p.kind();
            if let Some(c) = amp_col[e] {
                let amp_name = if matches!(kind, EffectKind::GaussMarkov | EffectKind::BandNoise) {
                    "sigma"
                } else {
                    "amplitude"
                };
                // ln amplitude = ln c / 2
                out.push((amp_name, interval(p.amplitude(), sd(c) / 2.0)));
            }
            for (i, (name, v)) in shapes(p).iter().enumerate() {
                if let Some(&c) = shape_col[e].get(i) {
                    out.push((name, within_model(prob, p, name, interval(*v, sd(c)))));
                }
            }
            if let EffectParams::MovingAverage {
                taps,
                stages,
                decimation,
            } = *p
            {
                out.push((
                    "taps",
                    taps_profile(prob, spec, fit, (taps, stages, decimation), scale),
                ));
            }
            if let EffectParams::Temperature {
                lo,
                hi,
                quadratic,
                lag,
                ..
            } = *p
            {
                out.push(("coefficient", [lo, hi]));
                if let Some(q) = quadratic {
                    out.push(("quadratic", [q.lo, q.hi]));
                }
                if let Some(l) = lag {
                    out.push(("lag", [l.lo, l.hi]));
                }
            }
            out
        })
        .collect();
    FitIntervals { effects, terms }
}

/// The 95% interval of the five-term coefficient `term` of the final fit `fit` of `spec`, in
/// the term's own units (the square root of the coefficient `c`). Two readings are joined,
/// the wider at each end:
/// - the profile of `r' S^-1 r` in `c` (the other terms and the effects' amplitudes refitted,
///   non-negative; the effects' shapes held; [`GapProblem::lower_bound`],
///   [`GapProblem::upper_bound`]): the values where it rises by `3.84 scale`, the
///   two-sided 95% likelihood-ratio interval (Wilks; Pawitan, "In All Likelihood", section
///   2.6), scaled by the final gap as the Fisher covariance is. It holds where the Fisher
///   reading does not: a term beside another the fit set to zero (a rate random walk K whose
///   flicker B went to zero took the long taus with an interval three times too narrow), a term
///   near its bound, a term set to zero itself (its upper end only);
/// - the Fisher interval `fisher`, whose covariance has the effects' shapes as nuisance, its
///   upper end, for a term the profile does not resolve, no higher than the term alone at the
///   data's 97.5% upper limits ([`GapProblem::term_ceiling`]).
fn term_interval(
    prob: &GapProblem,
    spec: &ModelSpec,
    fit: &GlsFit,
    term: usize,
    fisher: Option<[f64; 2]>,
    scale: f64,
) -> Option<TermInterval> {
    let c_hat = fit.coef.get(term).copied()?.max(0.0);
    let delta = Z95 * Z95 * scale;
    let hi_c = prob.upper_bound(spec, fit, term, delta)?;
    let lo_c = prob.lower_bound(spec, fit, term, delta);
    let value = c_hat.sqrt();
    let (mut lo, mut hi) = (lo_c.sqrt(), hi_c.max(c_hat).sqrt());
    if let Some([f_lo, f_hi]) = fisher {
        // The log-normal upper end of a term the curve hardly fixes runs off to absurd values
        // (30000 u for the Q of a real gyro whose curve allows 0.002): for a term the profile
        // does not resolve, no further than the term alone at the data's 97.5% upper limits. A
        // resolved term keeps its Fisher end: the least of many points' limits is no 97.5%
        // statement about it (it cut N's interval below the truth on 3 of 40 runs), as in the
        // `fit` record.
        let resolved = lo_c > 0.0 && lo_c.sqrt() >= QUANTITATION_FRACTION * value;
        let ceiling = if resolved {
            f64::INFINITY
        } else {
            prob.term_ceiling(spec, term, Z95)
                .map_or(f64::INFINITY, f64::sqrt)
        };
        lo = lo.min(f_lo);
        hi = hi.max(f_hi.min(ceiling));
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    Some(TermInterval {
        value,
        lo,
        hi,
        determined: value > 0.0 && lo > 0.0 && lo >= QUANTITATION_FRACTION * value,
    })
}

/// Whole taps whose fit's `r' S^-1 r` is within `3.84 scale` of the best, around `taps` (of
/// the average `(taps, stages, decimation)`). A CIC's decimation is its taps and moves with
/// them (at least 2: one tap read every sample is no filter); otherwise the decimation is kept.
fn taps_profile(
    prob: &GapProblem,
    spec: &ModelSpec,
    fit: &GlsFit,
    (taps, stages, decimation): (u32, u32, u32),
    scale: f64,
) -> [f64; 2] {
    let limit = fit.chi2 + 3.84 * scale;
    let cic = decimation > 1 && decimation == taps;
    let ok = |t: u32| {
        t >= if cic { 2 } else { 1 }
            && prob
                .gls(&ModelSpec {
                    filter: Some(crate::model::lowpass::LowPass::MovingAverage {
                        taps: t,
                        stages,
                        decimation: if cic { t } else { decimation },
                    }),
                    ..spec.clone()
                })
                .is_some_and(|f| f.chi2 <= limit)
    };
    let mut lo = taps;
    while lo > 1 && ok(lo - 1) && taps - lo < 64 {
        lo -= 1;
    }
    let mut hi = taps;
    while ok(hi + 1) && hi - taps < 64 {
        hi += 1;
    }
    [lo as f64, hi as f64]
}
