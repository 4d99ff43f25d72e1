//! The unit's filter's own stretch of the curve. A unit's low-pass shapes the shortest taus,
//! and its exact shape is one of endless designs (Kaiser or Blackman windows, half-band
//! decimators with a recursive stage behind them, Bessel and Chebyshev sections, chains of
//! three parts) of which the diagnosis fits the nearest kind. At the precision of a long run
//! the nearest kind's misfit there is many times the curve's error, and the search then names
//! a Gauss-Markov term of a few samples, a band or a line beside the filter: effects the unit
//! does not have (the seventh blind review, session 48).
//!
//! Beyond a few of the filter's memories every low-pass leaves the white rate and a term in
//! `1 / tau^2` (white phase noise of either sign; docs/gap.md, "A filter's tail is white phase
//! noise"), whatever its shape. So when the whole curve's diagnosis names a filter and is left
//! unexplained, or names a Gauss-Markov term or a broad band whose signature lies within
//! [`REGION_MEMORIES`] memories of the filter (a line or a narrow band there is the unit's:
//! `shape_like`), the curve is diagnosed again from there on with that filter in every model
//! ([`judge_beyond`]); that diagnosis stands when it is not unexplained and needs fewer of the
//! unit's effects, and the record says from which tau it was judged, which filter the whole
//! curve named, and what was set aside (docs/gap.md, "The filter's own stretch of the curve
//! (session 48)").

use super::diagnose::{diagnose_curve, AddedEffect, DiagnoseOptions, Diagnosis, Verdict};
use super::effects::EffectParams;
use super::evidence::EvidenceSnapshot;
use crate::model::lowpass::LowPass;

/// The filter's stretch of the curve, in its memories ([`LowPass::memory_s`]).
pub const REGION_MEMORIES: f64 = 5.0;

/// Where a Gauss-Markov term's AVAR peaks, in correlation times (`tau ~ 1.89 tau_c`; IEEE Std
/// 952-1997, annex C).
const GM_PEAK: f64 = 1.89;

/// Where a sinusoid's AVAR peaks, in periods (`tau ~ 0.371 / f`; IEEE Std 952-1997, annex C).
const LINE_PEAK: f64 = 0.371;

/// What the record says when the curve was judged beyond the filter's stretch.
#[derive(Debug, Clone, PartialEq)]
pub struct FilterShape {
    /// The filter the whole curve named (its effects, a cascade's two), the unit's own.
    pub named: Vec<AddedEffect>,
    /// The shortest tau judged (s).
    pub from_tau_s: f64,
    /// The whole curve's final gap and verdict.
    pub gap_whole: f64,
    pub verdict_whole: Verdict,
    /// The whole curve's other effects whose signature lies within the stretch, set aside.
    pub set_aside: Vec<AddedEffect>,
}

/// The end of the filter `lp`'s stretch of the curve (s).
pub fn region_tau_s(lp: &LowPass, tau0_s: f64) -> f64 {
    REGION_MEMORIES * lp.memory_s(tau0_s)
}

/// A band at least this wide against its centre is a broad hump a filter's shape can make
/// (the seventh review's Kaiser FIR: a band of 21.7 Hz at 26.9 Hz); a narrower one is line-like.
const BROAD_BAND: f64 = 0.5;

/// Whether the effect's AVAR peaks within the stretch that ends at `tau_r_s`.
fn within(p: &EffectParams, tau_r_s: f64) -> bool {
    match *p {
        EffectParams::GaussMarkov { tau_c_s, .. } => GM_PEAK * tau_c_s < tau_r_s,
        EffectParams::Sinusoid { frequency_hz, .. }
        | EffectParams::BandNoise { frequency_hz, .. } => {
            frequency_hz > 0.0 && LINE_PEAK / frequency_hz < tau_r_s
        }
        _ => false,
    }
}

/// Whether the effect, within the stretch, is one a filter's shape can pose as: a
/// Gauss-Markov term or a broad band. A line, or a narrow band, is the unit's (a 20 Hz line
/// behind a 2-tap average at 100 Hz, tests/gap/sinusoid_behind_filter.rs), and the whole curve
/// is judged beyond the stretch for it only when the whole curve is left `unexplained`.
fn shape_like(p: &EffectParams, tau_r_s: f64) -> bool {
    match *p {
        EffectParams::GaussMarkov { .. } => within(p, tau_r_s),
        EffectParams::BandNoise {
            frequency_hz,
            width_hz,
            ..
        } => within(p, tau_r_s) && width_hz >= BROAD_BAND * frequency_hz,
        _ => false,
    }
}

/// The unit's effects of `d` (not its filters).
fn unit_effects(d: &Diagnosis) -> usize {
    d.effects
        .iter()
        .filter(|e| !e.params.kind().is_filter())
        .count()
}

/// `d`, the whole curve's diagnosis, or the diagnosis from the end of its filter's stretch on
/// (see the module doc).
pub fn judge_beyond(
    snap: &EvidenceSnapshot,
    temperature: Option<&EvidenceSnapshot>,
    opts: &DiagnoseOptions,
    d: Diagnosis,
) -> Diagnosis {
    let Some(lp) = EffectParams::unit_filter(d.effects.iter().map(|e| &e.params)) else {
        return d;
    };
    let tau_r = region_tau_s(&lp, snap.tau0_s);
    if d.verdict != Verdict::Unexplained && !d.effects.iter().any(|e| shape_like(&e.params, tau_r))
    {
        return d;
    }
    // The filter stays in every model beyond its stretch (its tail is there), and in the
    // covariance with the five terms the whole curve fitted through it, as the diagnosis's
    // pass after a filter has them.
    let m_cut = (tau_r / snap.tau0_s).ceil().max(1.0) as u64;
    let beyond = DiagnoseOptions {
        min_m: opts.min_m.max(m_cut),
        base_filter: Some(lp),
        cov_filter: Some(lp),
        cov_coef: d.fitted_cov_coef(),
        cov_counter: d.read_a_counter(),
        ..opts.clone()
    };
    let d2 = match diagnose_curve(snap, temperature, &beyond) {
        Ok(d2) => d2,
        Err(e) => {
            tracing::debug!(%e, m_cut, "no diagnosis beyond the filter's stretch");
            return d;
        }
    };
    let better = d2.verdict != Verdict::Unexplained
        && (d.verdict == Verdict::Unexplained || unit_effects(&d2) < unit_effects(&d));
    tracing::debug!(
        tau_r,
        whole = ?d.verdict,
        beyond = ?d2.verdict,
        effects_whole = unit_effects(&d),
        effects_beyond = unit_effects(&d2),
        better,
        "the curve beyond the filter's stretch"
    );
    if !better {
        return d;
    }
    let named = d
        .effects
        .iter()
        .filter(|e| e.params.kind().is_filter())
        .copied()
        .collect();
    // the whole curve's effects within the stretch that the curve beyond it did not name
    let set_aside = d
        .effects
        .iter()
        .filter(|e| within(&e.params, tau_r) && !d2.names(e.params.kind()))
        .copied()
        .collect();
    let mut d2 = d2;
    // The unit's filter explains the stretch set aside: the verdict is `explained` at least.
    if d2.verdict == Verdict::Consistent {
        d2.verdict = Verdict::Explained;
    }
    d2.filter_shape = Some(FilterShape {
        named,
        from_tau_s: d2.tau_span_s.0,
        gap_whole: d.gap_after,
        verdict_whole: d.verdict,
        set_aside,
    });
    d2
}
