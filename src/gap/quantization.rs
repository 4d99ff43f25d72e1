//! Which quantization the channel's values show: an angle (or velocity) counter that carries
//! its remainder, or a rate sample rounded on its own (docs/gap.md, "Rate-sample
//! quantization").
//!
//! Both deliver values that are whole multiples of one step `delta` (u per increment; read off
//! the values by [`super::lsb`]), but they leave different noise on the curve:
//! - a counter with carry errs on the integrated signal by at most half a step: white *phase*
//!   noise of variance `delta^2 / 12`, `Q_q = delta / sqrt(12)`, AVAR `3 Q_q^2 / tau^2`;
//! - a rate sample rounded without carry errs on each increment independently: white *rate*
//!   noise of variance `delta^2 / 12` per step, `N_q^2 = delta^2 / (12 tau0)`, AVAR
//!   `N_q^2 / tau` (the rounding error is uniform and independent of the signal when the
//!   sample's own noise is above about half a step: Widrow and Kollar, "Quantization Noise",
//!   2008, ch. 4-5, the quantization theorem; a finer-grained noise makes it a slow wander
//!   that neither term describes).
//!
//! The test puts each one into the final model as a floor the fit must keep (a fixed offset,
//! the free Q or N above it) and compares `r' S^-1 r` with the free fit: the hypothesis the
//! curve cannot carry raises it by more than [`QUANT_CHI2`]. The rounding of rate samples is
//! then its own white-rate contribution: its share of the fitted `N^2`, and the unit's own `N`
//! is what is left (`sqrt(N^2 - N_q^2)`).

use super::effects::nullable_f64;
use super::problem::{GapProblem, GlsFit, ModelSpec};
use serde::{Deserialize, Serialize};

/// Rise of `r' S^-1 r` (one constraint) beyond which a hypothesis is rejected: 3 standard
/// deviations of a chi-square with one degree of freedom at the boundary.
pub const QUANT_CHI2: f64 = 9.0;

/// Least ratio of the whole white rate's per-sample deviation to the step,
/// `sqrt(N^2 tau0) / lsb`, at which the unit's own white rate is told from the rounding's
/// (`n_unit`). The inversion `N_unit^2 = N^2 - N_q^2` holds where the rounding error is
/// uniform and independent of the signal; for a Gaussian sample of deviation `r` steps that
/// fails as `exp(-2 pi^2 r^2)` grows (the quantization theorem's first term, Widrow and Kollar
/// 2008, ch. 4), and how it fails depends on where the mean sits on the grid: a sample of
/// 0.3 steps on a mean half a step off the grid takes two values, equally often, whose
/// deviation is half a step whatever the unit's is (the inversion reads 1.37 times the truth),
/// and on a mean on the grid reads 0.37 times it. Worked through the Gaussian's level
/// probabilities: at an output ratio of 0.55 or more (the unit's own 0.45 or more) the
/// inversion is within 4% wherever the mean sits; at 0.52 it is 9% off (a rev15 review's two
/// value data read 1.5-1.6 times the truth). Below it `n_unit` is not determined.
pub const UNIFORM_MIN_RATIO: f64 = 0.55;

/// The verdict on the values' step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum QuantKind {
    /// A counter with carry: white phase `Q_q`.
    Angle,
    /// Rate samples rounded: white rate `N_q`.
    Rate,
    /// The curve cannot tell (the step is fine against the noise).
    Either,
    /// Neither floor fits (the step is coarse against the noise, or the values were rounded
    /// after some other processing).
    Neither,
}

/// What the values' step does to the curve: docs/records.md's `quantization` object of the
/// diagnosis record. The fields are declared in alphabetical order, the order earlier versions
/// wrote them in (through a sorted JSON map); a share that is not finite (no white rate fitted)
/// is written `null` and read back as NaN.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct QuantizationFinding {
    /// Rise of `r' S^-1 r` with each floor forced in.
    #[serde(deserialize_with = "nullable_f64")]
    pub delta_chi2_angle: f64,
    #[serde(deserialize_with = "nullable_f64")]
    pub delta_chi2_rate: f64,
    pub kind: QuantKind,
    /// The step of the increments, u.
    #[serde(deserialize_with = "nullable_f64")]
    pub lsb: f64,
    /// White rate of rounded rate samples, `lsb / sqrt(12 tau0)` (u/sqrt(s)).
    #[serde(deserialize_with = "nullable_f64")]
    pub n_q: f64,
    /// The unit's own white rate: `sqrt(N^2 - N_q^2)` (u/sqrt(s)); `N` itself when the kind is
    /// `angle` (nothing rounds the rate); not determined (NaN, `null`) when the step is coarse
    /// against the whole white rate ([`UNIFORM_MIN_RATIO`]), since session 53.
    #[serde(deserialize_with = "nullable_f64")]
    pub n_unit: f64,
    /// White phase of a counter with carry, `lsb / sqrt(12)` (u).
    #[serde(deserialize_with = "nullable_f64")]
    pub q_q: f64,
    /// The same step as a rate, `lsb / tau0` (u/s).
    #[serde(deserialize_with = "nullable_f64")]
    pub rate_lsb: f64,
    /// `N_q^2 / N^2` of the final fit (the share of the white rate that is rounding), at most 1
    /// (since session 52); not a number (`null`) when the kind is `angle`.
    #[serde(deserialize_with = "nullable_f64")]
    pub share_of_n2: f64,
}

/// Judges the step `lsb` (u) against the final model (`spec`, fitted as `fit`).
pub fn judge_quantization(
    prob: &GapProblem,
    spec: &ModelSpec,
    fit: &GlsFit,
    lsb: f64,
) -> Option<QuantizationFinding> {
    if !(lsb > 0.0 && lsb.is_finite()) {
        return None;
    }
    let tau0 = prob.tau0_s;
    let q_q = lsb / 12f64.sqrt();
    let n_q = lsb / (12.0 * tau0).sqrt();
    let with_floor = |col: &dyn Fn(f64) -> f64| -> Option<f64> {
        let mut s = spec.clone();
        let base = s.offset.clone().unwrap_or_else(|| vec![0.0; prob.len()]);
        s.offset = Some(
            base.iter()
                .zip(&prob.tau)
                .map(|(o, &t)| o + col(t))
                .collect(),
        );
        prob.gls(&s).map(|f| f.chi2 - fit.chi2)
    };
    // A model that carries the counter's sawtooth ([`super::sawtooth`]) is the counter with
    // carry already, its error's correlation at the short lags included: the angle hypothesis is
    // then the fitted model itself. The white floor `3 Q_q^2 / tau^2` forced on top counted the
    // error twice and was rejected, and the kind read `rate` by elimination: an accelerometer
    // counting its velocity at 2.7 times the per-sample noise (80 Hz, 4 h) read `rate` in 9 of
    // 40 runs of a review, and `--model-out` wrote rounded rate samples with N 37% low.
    let d_angle = if prob.sawtooth.is_some() {
        0.0
    } else {
        with_floor(&|t| 3.0 * q_q * q_q / (t * t))?.max(0.0)
    };
    // A filtered model may carry the rounding floor already (`GapProblem::filter_floor`): the
    // rate hypothesis is then the fitted model itself.
    let d_rate = if spec.filter.is_some() && prob.filter_floor.is_some() {
        0.0
    } else {
        with_floor(&|t| n_q * n_q / t)?.max(0.0)
    };
    let kind = match (d_angle > QUANT_CHI2, d_rate > QUANT_CHI2) {
        (false, false) => QuantKind::Either,
        (true, false) => QuantKind::Rate,
        (false, true) => QuantKind::Angle,
        (true, true) => QuantKind::Neither,
    };
    // With the floor in, the N column is the unit's own white rate and the rounding is beside
    // it; the whole white rate is their sum.
    let floor_in = spec.filter.is_some() && prob.filter_floor.is_some();
    let n2_col = fit.coef.get(1).copied().unwrap_or(0.0).max(0.0);
    let n2 = if floor_in { n2_col + n_q * n_q } else { n2_col };
    // A counter with carry (`angle`) rounds no rate sample: none of its white rate is rounding,
    // so the share is not a number and the unit's own white rate is all of it (the share was
    // 2000-7000 on the review's pulse counters, N fitted near zero, which read as nonsense).
    let angle = kind == QuantKind::Angle;
    let share = if angle {
        f64::NAN
    } else if n2 > 0.0 {
        // At most 1: a white rate fitted below `N_q` (a step coarse against the noise, two or
        // three values in all: the rounding error is then no uniform one of variance
        // `lsb^2 / 12`) is all rounding, not 139% of it (a rev15 review's reading).
        (n_q * n_q / n2).min(1.0)
    } else {
        f64::INFINITY
    };
    Some(QuantizationFinding {
        kind,
        lsb,
        rate_lsb: lsb / tau0,
        q_q,
        n_q,
        delta_chi2_angle: d_angle,
        delta_chi2_rate: d_rate,
        share_of_n2: share,
        n_unit: if angle {
            n2.sqrt()
        } else if (n2 * tau0).sqrt() < UNIFORM_MIN_RATIO * lsb {
            f64::NAN
        } else {
            (n2 - n_q * n_q).max(0.0).sqrt()
        },
    })
}
