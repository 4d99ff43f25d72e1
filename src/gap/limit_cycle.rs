//! The counter's limit cycle: a unit whose angle is counted with carry at a coarse LSB while
//! its rate is nearly constant has a periodic quantization error, a sawtooth of period
//! `LSB / |rate|`. It is real structure in the output (a line at `f = |rate| / LSB` and its
//! harmonics, aliased into `[0, 1 / (2 tau0)]`) which the diagnosis may name a `sinusoid`, but
//! its cause is the counter, not a vibration of the unit. [`attribute`] finds the named
//! sinusoids that are such a line and says so ([`LimitCycle`]; the record's effect `cause`);
//! they do not count as effects of the unit in the verdict (docs/gap.md, "The counter's limit
//! cycle").
//!
//! The signature (docs/gap.md): the angle error `e(t) = Quant(theta(t)) - theta(t)` of a
//! counter with carry under a constant rate `w` is the sawtooth `LSB (1/2 - frac(w t / LSB))`,
//! whose `n`-th harmonic has phase amplitude `LSB / (n pi)` at `n f`, `f = |w| / LSB`. Its
//! increments over `tau0` are those of a rate line of amplitude `2 f_a LSB / n` at the aliased
//! frequency `f_a` (the sinusoid column's convention: a rate `A sin` integrated over each step),
//! so a tone the counter makes is never larger than that (dither and noise only shrink it).

use super::diagnose::{Diagnosis, Verdict};
use super::effects::EffectParams;
use super::evidence::EvidenceSnapshot;
use super::quantization::QuantKind;

/// Harmonics of the sawtooth checked (their amplitudes fall as `1 / n` in phase).
pub const MAX_HARMONIC: u32 = 3;
/// Slack on the largest amplitude the counter can make at a harmonic (`2 f_a LSB / n`).
pub const AMPLITUDE_SLACK: f64 = 1.25;
/// Least frequency window, relative to the expected frequency (the named line's own interval
/// may be narrower than the offset of the run's mean rate from the rate the line follows).
pub const MIN_REL_WINDOW: f64 = 0.01;

/// The widest line, relative to its frequency, whose half-width ([`line_half_width`]) widens
/// the window: beyond it the random walk has spread the counter's tone into noise.
pub const MAX_REL_LINE_WIDTH: f64 = 0.1;

/// A named sinusoid attributed to the counter's limit cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LimitCycle {
    /// Index of the sinusoid in `Diagnosis::effects`.
    pub effect: usize,
    /// The harmonic `n` of the sawtooth it matches.
    pub harmonic: u32,
    /// The line's expected frequency `n |mean rate| / LSB`, aliased (Hz).
    pub expected_hz: f64,
    /// The run's mean rate (u/s) and the counter's LSB (u) it was computed from.
    pub mean_rate: f64,
    pub lsb: f64,
}

/// Half-width at half maximum (Hz) of the counter's `n`-th harmonic line broadened by the
/// angle's random walk (white rate noise `N`, u/sqrt(s)): the line's phase `2 pi n theta / LSB`
/// diffuses, `E exp(i 2 pi n (theta(t) - theta(0)) / LSB) = exp(-2 pi^2 n^2 N^2 t / LSB^2)`,
/// so the line is a Lorentzian of half-width `pi n^2 N^2 / LSB^2` (the phase-diffusion
/// linewidth of an oscillator, e.g. Rubiola, "Phase Noise and Frequency Stability in
/// Oscillators", 2009, section 1.4). A sinusoid fitted to it sits within about that of its
/// centre.
pub fn line_half_width(n: u32, n_arw: f64, lsb: f64) -> f64 {
    let x = n as f64 * n_arw / lsb;
    std::f64::consts::PI * x * x
}

/// `f` folded into `[0, 1 / (2 tau0)]` (sampling at `1 / tau0`).
pub fn alias(f_hz: f64, tau0_s: f64) -> f64 {
    let fs = 1.0 / tau0_s;
    let r = f_hz.abs().rem_euclid(fs);
    r.min(fs - r)
}

/// The run's mean rate (u/s) and the spread of its block means (u/s), from the evidence.
pub(crate) fn rate_stats(snap: &EvidenceSnapshot) -> Option<(f64, f64)> {
    let v: Vec<f64> = snap
        .block_means
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    if v.len() < 2 {
        return None;
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    Some((mean, sd))
}

/// The block means' spread `sd` (u/s) beyond their own white noise at white angle `Q^2 = q2`
/// and white rate `N^2 = n2` (`N^2 / T_b + 2 Q^2 / T_b^2` over a block of `T_b` s): the rate's
/// slow wander (u/s), which smears the counter's line.
pub(crate) fn slow_spread(snap: &EvidenceSnapshot, sd: f64, q2: f64, n2: f64) -> f64 {
    let block_s = snap.block_len as f64 * snap.tau0_s;
    let white_var = if block_s > 0.0 {
        n2 / block_s + 2.0 * q2 / (block_s * block_s)
    } else {
        0.0
    };
    (sd * sd - white_var).max(0.0).sqrt()
}

/// The limit cycles among `d`'s named sinusoids: the values are whole multiples of an LSB
/// (`snap.lsb`) and not rate samples rounded on their own (`d.quantization` not `rate`: only a
/// counter with carry cycles), a sinusoid's frequency is within its 95% interval (widened to
/// [`MIN_REL_WINDOW`], plus the line's half-width [`line_half_width`] at the fitted `N` when it
/// is at most [`MAX_REL_LINE_WIDTH`] of the frequency) of an
/// aliased harmonic `n |mean rate| / LSB` (`n <= MAX_HARMONIC`), the
/// rate's slow spread over the run (the block means' standard deviation `sd` beyond their white
/// noise at the fitted `N` and `Q`) keeps that harmonic
/// inside the same window (`n sd / LSB`: a wandering rate smears the counter's line, and a sharp
/// line there is not it), and its amplitude is at most [`AMPLITUDE_SLACK`] times the
/// `2 f_a LSB / n` the counter can make there.
pub fn find(d: &Diagnosis, snap: &EvidenceSnapshot) -> Vec<LimitCycle> {
    let Some(lsb) = snap.lsb.filter(|l| *l > 0.0 && l.is_finite()) else {
        return Vec::new();
    };
    if d.quantization.is_some_and(|q| q.kind == QuantKind::Rate) {
        return Vec::new();
    }
    let Some((mean, sd)) = rate_stats(snap) else {
        return Vec::new();
    };
    let tau0 = snap.tau0_s;
    // The block means' spread beyond their own white noise (the fitted white rate `N` and white
    // angle `Q` over a block): the slow wander that smears the line. The white rate's share
    // widens the line as its phase diffusion does, which `line_half_width` carries.
    let [q, n_arw] = [d.final_coef[0], d.final_coef[1]];
    let sd = slow_spread(snap, sd, q * q, n_arw * n_arw);
    let mut out = Vec::new();
    for (i, e) in d.effects.iter().enumerate() {
        let EffectParams::Sinusoid {
            amplitude,
            frequency_hz,
        } = e.params
        else {
            continue;
        };
        let iv = d
            .effect_intervals
            .get(i)
            .and_then(|v| v.iter().find(|(k, _)| *k == "frequency"))
            .map(|(_, iv)| *iv)
            .filter(|iv| iv.iter().all(|x| x.is_finite()));
        let half_iv = iv.map_or(0.0, |[lo, hi]| {
            (frequency_hz - lo).max(hi - frequency_hz).max(0.0)
        });
        let hit = (1..=MAX_HARMONIC).find_map(|n| {
            let nf = n as f64;
            let expected = alias(nf * mean / lsb, tau0);
            // the line's own width, where the angle's random walk leaves a line at all
            // (`line_half_width`; a half-width beyond MAX_REL_LINE_WIDTH of its frequency is
            // noise, not a tone, and widens nothing)
            let hw = line_half_width(n, n_arw, lsb);
            let widen = if hw <= MAX_REL_LINE_WIDTH * expected {
                hw
            } else {
                0.0
            };
            let window = half_iv.max(MIN_REL_WINDOW * expected) + widen;
            // The line is sharp only while the rate holds still: the block means' slow wander
            // moves it by `n sd / LSB`.
            let sharp = nf * sd / lsb <= window;
            let max_amp = AMPLITUDE_SLACK * 2.0 * expected * lsb / nf;
            tracing::debug!(
                n,
                frequency_hz,
                expected,
                window,
                spread_hz = nf * sd / lsb,
                amplitude,
                max_amp,
                "the counter's limit cycle: a named line against harmonic n"
            );
            (sharp && (frequency_hz - expected).abs() <= window && amplitude <= max_amp).then_some(
                LimitCycle {
                    effect: i,
                    harmonic: n,
                    expected_hz: expected,
                    mean_rate: mean,
                    lsb,
                },
            )
        });
        out.extend(hit);
    }
    out
}

/// Sets `d.limit_cycles` ([`find`]) and, when every named effect is such a line and the
/// verdict is `explained`, the verdict to `consistent`: the five terms and the counter account
/// for the curve, the unit shows no effect of its own. The effects stay in the record, each
/// with its cause.
pub fn attribute(d: &mut Diagnosis, snap: &EvidenceSnapshot) {
    d.limit_cycles = find(d, snap);
    let all_counter = !d.effects.is_empty()
        && (0..d.effects.len()).all(|i| d.limit_cycles.iter().any(|c| c.effect == i));
    if all_counter && d.verdict == Verdict::Explained && d.outliers.count == 0 {
        d.verdict = Verdict::Consistent;
    }
}

/// The effects of `d` that belong to the unit (not the counter's limit cycles), for scoring.
pub fn unit_effects(d: &Diagnosis) -> impl Iterator<Item = &super::diagnose::AddedEffect> {
    d.effects
        .iter()
        .enumerate()
        .filter(|(i, _)| !d.limit_cycles.iter().any(|c| c.effect == *i))
        .map(|(_, e)| e)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn alias_folds_into_the_first_nyquist_zone() {
        let tau0 = 0.01; // fs 100 Hz
        assert!((alias(30.0, tau0) - 30.0).abs() < 1e-12);
        assert!((alias(70.0, tau0) - 30.0).abs() < 1e-12);
        assert!((alias(130.0, tau0) - 30.0).abs() < 1e-12);
        assert!((alias(-20.0, tau0) - 20.0).abs() < 1e-12);
        assert!((alias(250.0, tau0) - 50.0).abs() < 1e-12);
    }
}
