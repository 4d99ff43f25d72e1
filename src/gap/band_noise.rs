//! The narrow-band noise candidate of the diagnosis (docs/gap.md, "Narrow-band noise (session
//! 11)"): a resonance driven by white noise, with centre `f0`, width `w` (full width at half
//! power) and rms `sigma`, whose exact AVAR column is [`crate::sim::band_noise::band_noise_avar`].
//! Where a sinusoid's AVAR has zeros at `tau = k / f0`, a band's is smoothed over `~1 / w`, and
//! where a first-order Gauss-Markov hump is one-sided in frequency, a band is centred away from
//! zero: neither closes the gap a band leaves (held2's real ADIS16405 gyro z, session 10).
//!
//! The scan: a grid in `ln f0` (from the longest tau's frequency to Nyquist) by `ln (w / f0)`
//! (from [`RELATIVE_WIDTH`]'s narrow end, nearly a line, to bands as wide as twice their
//! centre, nearly a Gauss-Markov term), each point the GLS fit of the column; the best point is
//! then polished by golden sections in `ln f0` and `ln w` in turn. Three parameters are added
//! (`sigma`, `f0`, `w`), so per parameter a pure line, which the sinusoid fits with two, still
//! scores higher as a sinusoid.

use super::effects::{EffectKind, EffectParams, Grid};
use super::problem::{golden_section, GapProblem, GlsFit, ModelSpec};
use crate::sim::band_noise::band_noise_avar;

/// Width over centre of the one-shape column ([`super::effects::effect_column`]), a moderate
/// band.
pub const CANONICAL_RELATIVE_WIDTH: f64 = 0.1;
/// Range of `w / f0` scanned, and grid points per decade of it.
pub const RELATIVE_WIDTH: (f64, f64) = (0.02, 2.0);
const WIDTH_PER_DECADE: f64 = 3.0;
/// Grid points per decade of the centre.
pub const CENTRE_PER_DECADE: f64 = 24.0;
/// Highest centre scanned, as a fraction of Nyquist (at Nyquist the pole pair is real).
pub const MAX_CENTRE_OF_NYQUIST: f64 = 0.98;
/// The band's likelihood-ratio threshold (the drop of `r' S^-1 r` per parameter that flags a
/// model not flagged by `G`; [`super::thresholds::Thresholds::lr_crit_of`]), set on clean runs
/// of the unit families (docs/gap.md, "Narrow-band noise (session 11)").
pub const LR_CRIT: f64 = 7.0;
const GOLDEN_STEPS: usize = 16;
const POLISH_ROUNDS: usize = 3;

/// The band's AVAR column of unit rms at centre `f0` (Hz) and width `w` (Hz) at each cluster
/// size of `ms`.
pub fn column(frequency_hz: f64, width_hz: f64, ms: &[u64], tau0_s: f64) -> Vec<f64> {
    ms.iter()
        .map(|&m| band_noise_avar(1.0, frequency_hz, width_hz, tau0_s, m))
        .collect()
}

/// The centre grid over a curve from `tmin` to `tmax` (s) at step `tau0_s`.
pub fn centre_grid(tmin: f64, tmax: f64, tau0_s: f64) -> Grid {
    let nyq = 0.5 / tau0_s;
    Grid {
        lo: 1.0 / tmax,
        hi: (MAX_CENTRE_OF_NYQUIST * nyq).min(2.0 / tmin),
        per_decade: CENTRE_PER_DECADE,
    }
}

fn relative_widths() -> Vec<f64> {
    Grid {
        lo: RELATIVE_WIDTH.0,
        hi: RELATIVE_WIDTH.1,
        per_decade: WIDTH_PER_DECADE,
    }
    .points()
}

/// The spec `base` with a band column at `(f0, w)`.
fn spec_at(prob: &GapProblem, base: &ModelSpec, f0: f64, w: f64) -> ModelSpec {
    let mut s = base.clone();
    s.extra.push(column(f0, w, &prob.ms, prob.tau0_s));
    s
}

/// Best band on top of `base`, with the fit (its amplitude the last column's).
pub fn scan(prob: &GapProblem, base: &ModelSpec) -> Option<(EffectParams, GlsFit)> {
    let grid = prob.grid(EffectKind::BandNoise);
    let fs = grid.points();
    let qs = relative_widths();
    if fs.len() < 2 || qs.len() < 2 {
        return None;
    }
    let f_max = grid.hi;
    let eval = |lf: f64, lw: f64| prob.gls(&spec_at(prob, base, lf.exp().min(f_max), lw.exp()));
    let mut best: Option<(f64, f64, GlsFit)> = None;
    for &f in &fs {
        for &q in &qs {
            let (lf, lw) = (f.ln(), (q * f).ln());
            if let Some(fit) = eval(lf, lw) {
                if best.as_ref().is_none_or(|b| fit.chi2 < b.2.chi2) {
                    best = Some((lf, lw, fit));
                }
            }
        }
    }
    let (mut lf, mut lw, mut fit) = best?;
    let df = (fs[1] / fs[0]).ln();
    let dq = (qs[1] / qs[0]).ln();
    let chi = |x: Option<GlsFit>| x.map_or(f64::INFINITY, |f| f.chi2);
    // The width stays within [`RELATIVE_WIDTH`] of the centre: narrower, a band is a line
    // over the curve (the sinusoid's); wider, a hump (the Gauss-Markov term's).
    let w_range = |lf: f64| {
        (
            (RELATIVE_WIDTH.0 * lf.exp()).ln(),
            (RELATIVE_WIDTH.1 * lf.exp()).ln(),
        )
    };
    for _ in 0..POLISH_ROUNDS {
        let lw0 = lw;
        let f_hi = (lf + df).min(f_max.ln());
        let nf = golden_section(|x| chi(eval(x, lw0)), lf - df, f_hi, GOLDEN_STEPS).best();
        let (w_lo, w_hi) = w_range(nf);
        let (a, b) = ((lw - dq).max(w_lo), (lw + dq).min(w_hi));
        let nw = if b > a {
            golden_section(|x| chi(eval(nf, x)), a, b, GOLDEN_STEPS).best()
        } else {
            lw.clamp(w_lo, w_hi)
        };
        if let Some(f) = eval(nf, nw).filter(|f| f.chi2 < fit.chi2) {
            lf = nf;
            lw = nw;
            fit = f;
        }
    }
    let sigma = fit.coef.last().copied().unwrap_or(0.0).max(0.0).sqrt();
    let p = EffectParams::BandNoise {
        frequency_hz: lf.exp().min(f_max),
        sigma,
        width_hz: lw.exp(),
    };
    // A band at the narrow end of its width range is a line over this curve (a counter's
    // limit cycle, a wandering tone): the sinusoid's to name, not a band's.
    if at_narrow_end(&p) {
        return None;
    }
    Some((p, fit))
}

/// Kinds a band is weighed against by its whole fit: a line (its narrow limit), a first-order
/// Gauss-Markov hump (its wide limit at a low centre) and a resonant second-order filter. Not
/// the other filters: a wide band at a low centre fits a first-order filter's curve by chance
/// better on some runs (tests/gap/sinusoid_behind_filter.rs's first-order twin).
fn nested(kind: EffectKind) -> bool {
    matches!(
        kind,
        EffectKind::Sinusoid | EffectKind::GaussMarkov | EffectKind::SecondOrderFilter
    )
}

/// Margin (in units of the band's residual scale) by which a band that passed its test must
/// fit better than a nested kind chosen per parameter to replace it, beyond the two per extra
/// parameter of Akaike's criterion: [`super::alternatives::AIC_MARGIN`].
pub const PREFER_MARGIN: f64 = super::alternatives::AIC_MARGIN;

/// The choice of one step of the stationary search with the band weighed against the kind
/// chosen per parameter (`best`, among `passed`, each `(params, fit, score)`; a filter's
/// score is its family's best).
///
/// Per parameter, a kind with fewer parameters wins whenever its drop is nearly the band's: a
/// line takes most of a strong band's excess (its AVAR peaks at the same tau) and leaves a gap
/// the band would have closed (held2's synthetic gyro z: a 20.5 Hz sinusoid, G 3241 -> 114,
/// where the band alone gives 0.92). So when `best` is a kind the band nests and the band
/// passed, the band replaces it when its `r' S^-1 r` is lower by more than
/// `PREFER_MARGIN + 2 (3 - k)` (`k` the chosen kind's parameters: Akaike's price of the extra
/// ones) in units of `max(1, G_band)`, the band model's residual scale (the scaling of
/// [`super::thresholds::Thresholds::lr_stat`]): on a pure line the band at its narrow end
/// fits only by chance better, and the sinusoid stays. A band at the narrow end of its width
/// range ([`at_narrow_end`]) never replaces anything.
pub fn prefer_band(
    best: Option<(EffectParams, GlsFit, f64)>,
    passed: &[(EffectParams, GlsFit, f64)],
) -> Option<(EffectParams, GlsFit, f64)> {
    let b = best?;
    let kind = b.0.kind();
    if !nested(kind) {
        return Some(b);
    }
    // Only a band that is located in width: one at the narrow end of its scan is a line
    // over this curve (a counter's limit cycle, a wandering tone), which the sinusoid names.
    let Some(band) = passed
        .iter()
        .find(|p| p.0.kind() == EffectKind::BandNoise && !at_narrow_end(&p.0))
    else {
        return Some(b);
    };
    let extra = (EffectKind::BandNoise.n_params() as f64 - kind.n_params() as f64).max(0.0);
    let gain = (b.1.chi2 - band.1.chi2) / band.1.gap().max(1.0);
    if gain > PREFER_MARGIN + 2.0 * extra {
        Some(band.clone())
    } else {
        Some(b)
    }
}

/// Relative distance to the narrow end of the width range within which a band is at it.
pub const NARROW_TOL: f64 = 0.25;

/// Whether the band `p` was fitted at (within [`NARROW_TOL`] of) the narrow end of its width
/// range, `RELATIVE_WIDTH.0` centres: there it is not told from a line.
pub fn at_narrow_end(p: &EffectParams) -> bool {
    match *p {
        EffectParams::BandNoise {
            frequency_hz,
            width_hz,
            ..
        } => width_hz <= RELATIVE_WIDTH.0 * frequency_hz * (1.0 + NARROW_TOL),
        _ => false,
    }
}
