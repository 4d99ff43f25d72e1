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

/// `f` folded into `[0, 1 / (2 tau0)]` (sampling at `1 / tau0`).
pub fn alias(f_hz: f64, tau0_s: f64) -> f64 {
    let fs = 1.0 / tau0_s;
    let r = f_hz.abs().rem_euclid(fs);
    r.min(fs - r)
}

/// The run's mean rate (u/s) and the spread of its block means (u/s), from the evidence.
fn rate_stats(snap: &EvidenceSnapshot) -> Option<(f64, f64)> {
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

/// The limit cycles among `d`'s named sinusoids: the values are whole multiples of an LSB
/// (`snap.lsb`) and not rate samples rounded on their own (`d.quantization` not `rate`: only a
/// counter with carry cycles), a sinusoid's frequency is within its 95% interval (widened to
/// [`MIN_REL_WINDOW`]) of an aliased harmonic `n |mean rate| / LSB` (`n <= MAX_HARMONIC`), the
/// rate's spread over the run (the block means' standard deviation `sd`) keeps that harmonic
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
            let window = half_iv.max(MIN_REL_WINDOW * expected);
            // The line is sharp only while the rate holds still: the block means' spread
            // (its slow wander, with their white noise an upper bound) moves it by `n sd / LSB`.
            let sharp = nf * sd / lsb <= window;
            let max_amp = AMPLITUDE_SLACK * 2.0 * expected * lsb / nf;
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

/// One line of the counter's limit cycle taken into the base model ([`counter_lines`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CounterLine {
    /// The sawtooth's harmonic `n`.
    pub harmonic: u32,
    /// Its frequency, aliased (Hz).
    pub frequency_hz: f64,
    /// Its expected frequency from the run's mean rate alone (Hz), as [`LimitCycle`] gives it.
    pub expected_hz: f64,
    /// The diffusion of its phase (rad^2/s): the white rate noise `N` moves the angle, hence
    /// the sawtooth's phase `2 pi n theta / LSB`, as a random walk, `(2 pi n N / LSB)^2`.
    pub diffusion: f64,
}

/// The AVAR at each cluster size of `ms` of the counter's line `l` at unit amplitude (a rate
/// `sin(2 pi f t + phi(t))` integrated over each step, `phi` a random walk of diffusion `D`):
/// the increments' autocovariance over `tau0` is `tau0 sinc^2(pi f tau0) cos(2 pi f k tau0)
/// exp(-D k tau0 / 2) / 2` (the phase's characteristic function; exact for a pure line, `D = 0`,
/// and while `D tau0` is small), through
/// [`avar_from_autocovariance`](crate::model::lowpass::avar_from_autocovariance). The pure line's
/// AVAR oscillates with `sin^4(pi f tau)` to the longest taus; the counter's line loses its
/// phase over `2 / D` and its AVAR there is smooth, which a sinusoid column cannot follow
/// (docs/gap.md, "The counter's limit cycle").
pub fn line_avar(l: &CounterLine, ms: &[u64], tau0_s: f64) -> Vec<f64> {
    let m_max = ms.iter().copied().max().unwrap_or(1) as usize;
    let x = std::f64::consts::PI * l.frequency_hz * tau0_s;
    let sinc2 = if x == 0.0 { 1.0 } else { (x.sin() / x).powi(2) };
    let decay = 0.5 * l.diffusion.max(0.0) * tau0_s;
    // Lags up to 2 m_max, or until the envelope is below 1e-12.
    let n_env = if decay > 0.0 {
        (27.7 / decay).ceil() as usize
    } else {
        usize::MAX
    };
    let len = (2 * m_max + 1).min(n_env.max(2));
    let w = 2.0 * std::f64::consts::PI * l.frequency_hz * tau0_s;
    let cov: Vec<f64> = (0..len)
        .map(|k| {
            let kf = k as f64;
            0.5 * tau0_s * sinc2 * (w * kf).cos() * (-decay * kf).exp()
        })
        .collect();
    crate::model::lowpass::avar_from_autocovariance(&cov, tau0_s, ms)
}

/// The counter's lines to take into the base model when `d` named a line that is the
/// counter's ([`find`]) and the counter does not account for the whole of the diagnosis (an
/// effect beside it that is not such a line, or a gap left: `unexplained`): the sawtooth's
/// harmonics `n = 1..=MAX_HARMONIC`, aliased. A sawtooth is one waveform, so once one of its
/// lines is found the others are where the counter puts them, and a candidate that stands in
/// for one (a resonant second-order filter at the second harmonic, typically) is not an effect
/// of the unit. The fundamental is the one of the line named (its fitted frequency, more
/// precise than the run's mean rate: `alias(n_a F) = f_named` solved for `F` near
/// `|mean rate| / LSB`); the amplitudes are left free (dither and noise shrink each harmonic
/// differently). `None` otherwise.
///
/// The phase diffusion of each line is that of the fitted white rate `N` (`d.final_coef`).
pub fn counter_lines(d: &Diagnosis, snap: &EvidenceSnapshot) -> Option<Vec<CounterLine>> {
    let c = *d.limit_cycles.first()?;
    let all_counter = (0..d.effects.len()).all(|i| d.limit_cycles.iter().any(|l| l.effect == i));
    if all_counter && d.verdict != Verdict::Unexplained {
        return None;
    }
    let f_named = d.effects.get(c.effect)?.params.shape();
    let tau0 = snap.tau0_s;
    let n_a = c.harmonic as f64;
    let f0 = c.mean_rate.abs() / c.lsb;
    // The fold's slope at n_a f0: +1 where alias() follows its argument, -1 where it mirrors.
    let eps = 1e-6 * f0.max(1e-12);
    let slope = if alias(n_a * (f0 + eps), tau0) >= alias(n_a * f0, tau0) {
        1.0
    } else {
        -1.0
    };
    let fund = f0 + slope * (f_named - c.expected_hz) / n_a;
    let nyquist = 0.5 / tau0;
    let mut out: Vec<CounterLine> = Vec::new();
    for n in 1..=MAX_HARMONIC {
        let f = alias(n as f64 * fund, tau0);
        // A line at 0 or at Nyquist has no column (its AVAR is not a sinusoid's there), and
        // two harmonics folded onto one frequency are one column.
        if !(f > 0.0 && f < nyquist) || out.iter().any(|l| (l.frequency_hz - f).abs() < 1e-9 * f) {
            continue;
        }
        let k = 2.0 * std::f64::consts::PI * n as f64 * d.final_coef[1] / c.lsb;
        out.push(CounterLine {
            harmonic: n,
            frequency_hz: f,
            expected_hz: alias(n as f64 * f0, tau0),
            diffusion: k * k,
        });
    }
    (!out.is_empty()).then_some(out)
}

/// The diagnosis `d` made again with the counter's `lines` in the base model (`d2`, whose
/// effects are the unit's), as one diagnosis: the five terms alone as `d` had them (its
/// `gap_before`, regions and base curve), then the counter's lines as attributed sinusoids
/// (their fitted amplitudes, zero ones left out, each with the gap of the five terms and the
/// lines), then `d2`'s effects and verdict. `d` is kept when the lines do not lower the base
/// gap (a safeguard: the bookkeeping's final gap is never above the base's).
pub fn with_counter_lines(
    d: Diagnosis,
    d2: Diagnosis,
    lines: &[CounterLine],
    snap: &EvidenceSnapshot,
) -> Diagnosis {
    if !(d2.gap_before.is_finite() && d2.gap_before <= d.gap_before)
        || d2.counter_line_amplitudes.len() != lines.len()
    {
        return d;
    }
    let Some(lsb) = snap.lsb else {
        return d;
    };
    let mean = d.limit_cycles.first().map_or(0.0, |c| c.mean_rate);
    let mut effects = Vec::new();
    let mut intervals = Vec::new();
    let mut cycles = Vec::new();
    for (l, &a) in lines.iter().zip(&d2.counter_line_amplitudes) {
        if !(a > 0.0) {
            continue;
        }
        cycles.push(LimitCycle {
            effect: effects.len(),
            harmonic: l.harmonic,
            expected_hz: l.expected_hz,
            mean_rate: mean,
            lsb,
        });
        effects.push(super::diagnose::AddedEffect {
            params: EffectParams::Sinusoid {
                amplitude: a,
                frequency_hz: l.frequency_hz,
            },
            gap_after: d2.gap_before,
            delta_chi2: f64::NAN,
        });
        intervals.push(Vec::new());
    }
    let shift = effects.len();
    effects.extend(d2.effects.iter().copied());
    intervals.extend(d2.effect_intervals.iter().cloned());
    let mut out = Diagnosis {
        gap_before: d.gap_before,
        regions: d.regions,
        base_coef: d.base_coef,
        model_base_avar: d.model_base_avar,
        effects,
        effect_intervals: intervals,
        limit_cycles: Vec::new(),
        ..d2
    };
    // A line of the unit's own search that is the counter's too (a harmonic beyond the ones
    // taken in).
    let own: Vec<LimitCycle> = find(&out, snap)
        .into_iter()
        .filter(|c| c.effect >= shift)
        .collect();
    cycles.extend(own);
    out.limit_cycles = cycles;
    // As in `attribute`: explained by the counter's lines alone is consistent.
    let all_counter =
        (0..out.effects.len()).all(|i| out.limit_cycles.iter().any(|c| c.effect == i));
    if all_counter && out.verdict == Verdict::Explained && out.outliers.count == 0 {
        out.verdict = Verdict::Consistent;
    }
    out
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

    /// Without diffusion the line's column is the sinusoid's closed form
    /// (`terms::sinusoid_avar`, docs/theory.md section 3) at every cluster size.
    #[test]
    fn a_line_without_diffusion_is_the_sinusoid_column() {
        let tau0 = 0.004;
        let ms = [1u64, 2, 3, 7, 16, 100, 1000, 5000];
        for f in [0.37, 6.48, 47.0, 124.0] {
            let l = CounterLine {
                harmonic: 1,
                frequency_hz: f,
                expected_hz: f,
                diffusion: 0.0,
            };
            let got = line_avar(&l, &ms, tau0);
            for (&m, g) in ms.iter().zip(&got) {
                let want = crate::model::terms::sinusoid_avar(1.0, f, m as f64 * tau0);
                assert!(
                    (g - want).abs() <= 1e-9 * (1.0 + want) + 1e-6 * want,
                    "f {f} m {m}: {g} vs {want}"
                );
            }
        }
    }

    /// With diffusion, far beyond the phase's memory `2 / D` the line's AVAR is that of white
    /// rate noise of its spectral density at 0 Hz, no longer oscillating: `S(0) = 2 * (1/2) * 2
    /// (D/2) / ((D/2)^2 + (2 pi f)^2)` (two-sided Lorentzians at +-f), `sigma^2 = S(0) / tau`.
    #[test]
    fn a_diffusing_line_is_white_far_beyond_its_memory() {
        let tau0 = 0.004;
        let (f, d) = (6.48, 0.5);
        let l = CounterLine {
            harmonic: 1,
            frequency_hz: f,
            expected_hz: f,
            diffusion: d,
        };
        let ms = [250_000u64, 500_000];
        let got = line_avar(&l, &ms, tau0);
        let g = d / 2.0;
        let w = 2.0 * std::f64::consts::PI * f;
        let s0 = 2.0 * 0.5 * g / (g * g + w * w);
        for (&m, v) in ms.iter().zip(&got) {
            let want = s0 / (m as f64 * tau0);
            assert!((v / want - 1.0).abs() < 0.02, "m {m}: {v} vs {want}");
        }
    }

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
