//! The shape scans of the filter candidates with more than one shape parameter (docs/gap.md,
//! "Low-pass filters beyond first order"): the moving average (taps, whole, and one to four
//! stages; and run faster than the output: CIC decimators and decimated Bartletts) and the
//! second-order low-pass (natural frequency and damping, in three forms: pole-mapped, bilinear,
//! and sampled with its zero). Each grid point is the GLS fit of
//! [`GapProblem::gls`] with the N column taken through the filter; the best point is then
//! polished (neighbouring whole taps; golden sections in `ln f_n` and `ln zeta` in turn, then a
//! simplex in both, [`super::simplex`]).

use super::effects::{EffectKind, EffectParams};
use super::problem::{golden_section, GapProblem, GlsFit, ModelSpec};
use super::simplex::nelder_mead;
use crate::model::lowpass::{
    sampled_zero, LowPass, SecondOrderForm, CONTINUOUS_DECIMATION, MAX_ZERO,
};
use std::f64::consts::PI;

/// Longest moving average scanned (taps).
pub const MAX_TAPS: u32 = 256;
/// Stages of the moving average scanned: one (boxcar), two (triangular, Bartlett), three (the
/// sinc^3 of a third-order CIC decimator, the commonest MEMS decimation filter) and four, all the
/// model and the simulator take (docs/gap.md, "Low-pass filters beyond first order").
pub const STAGES: [u32; 4] = [1, 2, 3, 4];
/// Decimations of the averages run faster than the output that are scanned (a moving average
/// of `D` taps at `D` times the output rate read every `D`-th sample is a CIC decimator; two to
/// four stages, spans of [`DECIMATED_SPANS`]: docs/gap.md, "Averages run faster than the output
/// (session 44)"). At the output rate a CIC spans as many samples as it has stages whatever
/// `D`, and its shape tends to a B-spline's as `D` grows (within 1e-4 from 256), so a few
/// decimations per octave to 64 cover them.
pub const CIC_DECIMATIONS: [u32; 12] = [2, 3, 4, 5, 6, 8, 10, 12, 16, 24, 32, 64];
/// Damping range of the second-order scan, and points per decade.
pub const DAMPING_RANGE: (f64, f64) = (0.1, 5.0);
const DAMPING_PER_DECADE: f64 = 6.0;
/// Golden-section steps per coordinate, and rounds over the two coordinates.
const GOLDEN_STEPS: usize = 16;
const POLISH_ROUNDS: usize = 3;
/// Evaluations of the second-order scan's closing simplex ([`nelder_mead`]), and its stop:
/// the simplex's `r' S^-1 r` values within this of each other.
const SIMPLEX_EVALS: usize = 120;
const SIMPLEX_TOL: f64 = 1e-3;

/// Whether the filter `p` was fitted at the long-memory end of its scan (within [`END_TOL`] of
/// it; the polish converges onto the bound when the curve asks for more): the first order's or
/// zero phase's longest time constant, the moving average's most taps, the second order's
/// lowest natural frequency or highest damping (an overdamped second order's slow pole is its
/// memory). There the curve asks for a longer memory than the scan spans, so the filter is not
/// located: the diagnosis then weighs it against the other kinds by their whole fit
/// (docs/gap.md, "Filters and Gauss-Markov terms"). False for the other kinds.
pub fn at_memory_end(prob: &GapProblem, p: &EffectParams) -> bool {
    let grid = prob.grid(p.kind());
    let near = |x: f64, bound: f64| (x / bound).ln().abs() <= END_TOL.ln_1p();
    match *p {
        EffectParams::OutputFilter { time_constant_s }
        | EffectParams::ZeroPhaseFilter { time_constant_s } => {
            time_constant_s >= grid.hi || near(time_constant_s, grid.hi)
        }
        EffectParams::MovingAverage {
            taps, decimation, ..
        } => {
            let m_max = prob.ms.last().copied().unwrap_or(1);
            decimation == 1 && taps as u64 >= (MAX_TAPS as u64).min(m_max / 10).max(2)
        }
        // the lowest cut-off: the longest memory
        EffectParams::FirFilter { cutoff_hz, .. }
        | EffectParams::ButterworthFilter { cutoff_hz, .. } => {
            cutoff_hz <= grid.lo || near(cutoff_hz, grid.lo)
        }
        EffectParams::SecondOrderFilter {
            natural_frequency_hz,
            damping,
            ..
        } => {
            natural_frequency_hz <= grid.lo
                || near(natural_frequency_hz, grid.lo)
                || damping >= DAMPING_RANGE.1
                || near(damping, DAMPING_RANGE.1)
        }
        _ => false,
    }
}

/// Relative distance to a scan's bound within which a fitted filter is at it
/// ([`at_memory_end`]).
pub const END_TOL: f64 = 0.02;

/// Best parameters of `kind` (moving average or second order) on top of `base`, with the fit.
pub fn scan(
    prob: &GapProblem,
    base: &ModelSpec,
    kind: EffectKind,
) -> Option<(EffectParams, GlsFit)> {
    let fit = |lp: LowPass| fit_with(prob, base, lp);
    let best = match kind {
        EffectKind::MovingAverage => scan_moving_average(prob, &fit),
        EffectKind::SecondOrderFilter => scan_second_order(prob, &fit),
        EffectKind::FirFilter => scan_fir(prob, &fit),
        EffectKind::ButterworthFilter => scan_butterworth(prob, &fit),
        _ => None,
    }?;
    Some((EffectParams::from_lowpass(best.0), best.1))
}

/// The fit of `base` with the filter `lp` (behind or in front of the filter of `base` when the
/// two make a cascade, [`LowPass::compose`]).
fn fit_with(prob: &GapProblem, base: &ModelSpec, lp: LowPass) -> Option<GlsFit> {
    prob.gls(&ModelSpec {
        filter: Some(LowPass::compose(base.filter, lp)),
        ..base.clone()
    })
}

/// The FIR's highest cut-off scanned, times `tau0` (below Nyquist's 0.5).
pub const FIR_TOP: f64 = 0.45;

/// The highest cut-off (Hz) of a FIR run at `decimation` times the output rate (`tau0_s` the
/// output step): [`FIR_TOP`] of the rate it runs at.
pub fn fir_top_hz(decimation: u32, tau0_s: f64) -> f64 {
    FIR_TOP * f64::from(decimation.max(1)) / tau0_s
}

/// The Butterworth's highest cut-off scanned, times `tau0` (below Nyquist's 0.5, where the
/// prewarping's `tan` grows without bound).
pub const BUTTERWORTH_TOP: f64 = 0.45;

/// The Butterworth orders scanned: from 3 (order 1 is near the first order, order 2 the
/// bilinear second order at damping `1/sqrt 2`, both scanned as their own kinds) to
/// [`MAX_BUTTERWORTH_ORDER`](crate::model::lowpass::MAX_BUTTERWORTH_ORDER).
pub const BUTTERWORTH_ORDERS: std::ops::RangeInclusive<u32> =
    3..=crate::model::lowpass::MAX_BUTTERWORTH_ORDER;

/// The decimations of a Butterworth run faster than the output that are tried
/// ([`scan_butterworth`]): a part filtering at its internal rate, 2 to 32 times the output's.
/// At the output rate the shapes of neighbouring decimations differ little (as a CIC's tend to
/// a B-spline's), so a factor of four between them serves: a 16x third order is named at 8x
/// or 32x with its cut-off within 0.3%.
pub const BUTTERWORTH_DECIMATIONS: [u32; 3] = [2, 8, 32];

/// Grid steps each side of the output-rate cut-off scanned at each decimation.
const BUTTERWORTH_AROUND: i32 = 3;

/// The gap of the model with the output-rate Butterworth above which the decimated forms are
/// tried ([`scan_butterworth`]): the critical gap beside a filter (`gap_crit_filtered`'s
/// default). The first pass's covariance, the base model's, leaves nearly every filtered run's
/// model flagged; the gate spares the later passes, where the output-rate form leaves the gap
/// near 1 on the seventeenth review's output-rate files.
pub const BUTTERWORTH_DECIMATION_GATE: f64 = 2.2;

/// The n-th order Butterworth ([`LowPass::Butterworth`]): for each order of
/// [`BUTTERWORTH_ORDERS`] its cut-off over the grid at the output rate, then a golden section in
/// `ln f_c` within a grid step of the best; the order with the least chi-squared is taken.
/// Where that leaves the model's gap above [`BUTTERWORTH_DECIMATION_GATE`], the same order is
/// tried run at each of [`BUTTERWORTH_DECIMATIONS`] times the output rate and read every so many
/// samples, its cut-off scanned within [`BUTTERWORTH_AROUND`] grid steps of the output rate's
/// and polished the same way; the best decimation is taken where it lowers the chi-squared by
/// more than [`SPAN_PARAMETER_CHI2`] (one more discrete choice), as the FIR's half-band
/// decimator is (docs/gap.md, "An n-th order Butterworth (session 54)").
fn scan_butterworth(
    prob: &GapProblem,
    fit: &dyn Fn(LowPass) -> Option<GlsFit>,
) -> Option<(LowPass, GlsFit)> {
    let cutoffs = prob.grid(EffectKind::ButterworthFilter).points();
    if cutoffs.len() < 2 {
        return None;
    }
    let dc = (cutoffs[1] / cutoffs[0]).ln();
    let logs: Vec<f64> = cutoffs.iter().map(|c| c.ln()).collect();
    let mut best: Option<(u32, f64, f64)> = None;
    for order in BUTTERWORTH_ORDERS {
        if let Some((lc, v)) = butterworth_cutoff(prob, fit, order, 1, &logs, dc) {
            if best.is_none_or(|(_, _, b)| v < b) {
                best = Some((order, lc, v));
            }
        }
    }
    let (order, lc, v) = best?;
    let output_rate = butterworth_at(prob, order, 1, lc);
    let output_fit = fit(output_rate);
    // the decimated forms only where the output-rate form leaves the model flagged
    let flagged = output_fit
        .as_ref()
        .is_some_and(|f| f.gap() > BUTTERWORTH_DECIMATION_GATE);
    let decimations = if flagged {
        &BUTTERWORTH_DECIMATIONS[..]
    } else {
        &[]
    };
    let mut chosen = (1u32, lc, v);
    let around = about(lc, dc);
    for &d in decimations {
        if let Some((x, vx)) = butterworth_cutoff(prob, fit, order, d, &around, dc) {
            if vx < chosen.2 {
                chosen = (d, x, vx);
            }
        }
    }
    if chosen.0 == 1 || chosen.2 + SPAN_PARAMETER_CHI2 >= v {
        return output_fit.map(|f| (output_rate, f));
    }
    let lp = butterworth_at(prob, order, chosen.0, chosen.1);
    fit(lp).map(|f| (lp, f))
}

/// The Butterworth of `order` and `decimation` at the log cut-off `lc`, the cut-off held below
/// [`BUTTERWORTH_TOP`] of the rate it runs at.
fn butterworth_at(prob: &GapProblem, order: u32, decimation: u32, lc: f64) -> LowPass {
    LowPass::Butterworth {
        order,
        cutoff_hz: lc
            .exp()
            .min(BUTTERWORTH_TOP * f64::from(decimation) / prob.tau0_s),
        decimation,
    }
}

/// The log cut-offs within [`BUTTERWORTH_AROUND`] steps of `dc` each side of `lc`.
fn about(lc: f64, dc: f64) -> Vec<f64> {
    (-BUTTERWORTH_AROUND..=BUTTERWORTH_AROUND)
        .map(|i| lc + f64::from(i) * dc)
        .collect()
}

/// The best log cut-off of the Butterworth of `order` and `decimation` over the log cut-offs
/// `logs`, polished by a golden section in `ln f_c` within `dc` of it, with its chi-squared
/// (None where no point fits).
fn butterworth_cutoff(
    prob: &GapProblem,
    fit: &dyn Fn(LowPass) -> Option<GlsFit>,
    order: u32,
    decimation: u32,
    logs: &[f64],
    dc: f64,
) -> Option<(f64, f64)> {
    let at = |lc: f64| butterworth_at(prob, order, decimation, lc);
    let chi2 = |lc: f64| fit(at(lc)).map_or(f64::INFINITY, |f| f.chi2);
    let (mut lc, mut v) = (f64::NAN, f64::INFINITY);
    for &x in logs {
        let here = chi2(x);
        if here < v {
            (lc, v) = (x, here);
        }
    }
    if !v.is_finite() {
        return None;
    }
    let x = golden(|x| fit(at(x)), lc - dc, lc + dc);
    let vx = chi2(x);
    Some(if vx < v { (x, vx) } else { (lc, v) })
}

/// The Butterworth of `order` and `decimation` with its cut-off scanned within
/// [`BUTTERWORTH_AROUND`] grid steps of `cutoff_hz` and polished by a golden section in
/// `ln f_c` ([`scan_in_form`]: a cascade's named back refitted behind each front tried, a tenth
/// of [`scan_butterworth`]'s work).
fn scan_butterworth_about(
    prob: &GapProblem,
    fit: &dyn Fn(LowPass) -> Option<GlsFit>,
    order: u32,
    decimation: u32,
    cutoff_hz: f64,
) -> Option<(LowPass, GlsFit)> {
    let dc = std::f64::consts::LN_10 / prob.grid(EffectKind::ButterworthFilter).per_decade;
    let around = about(cutoff_hz.ln(), dc);
    let (lc, _) = butterworth_cutoff(prob, fit, order, decimation, &around, dc)?;
    let lp = butterworth_at(prob, order, decimation, lc);
    fit(lp).map(|f| (lp, f))
}

/// The FIR's taps on the scan's grid (whole numbers, about four per octave); the polish then
/// tries every whole number between the best one's neighbours.
const FIR_TAPS: [u32; 13] = [5, 7, 9, 11, 15, 19, 23, 31, 39, 47, 63, 95, 127];

/// The linear-phase FIR ([`LowPass::Fir`]) at the output rate ([`scan_fir_at`]); when its best
/// cut-off is at the scan's top, also the FIR run at twice the output rate and read every
/// second sample with its cut-off about the output's Nyquist frequency (a half-band
/// decimator), taken when it lowers the chi-squared by more than [`SPAN_PARAMETER_CHI2`] (the
/// decimation is one more discrete choice). A half-band decimator's aliasing leaves the
/// output's spectrum nearly flat to Nyquist, which no output-rate low-pass reaches: a 31-tap
/// half-band at 1 kHz read at 500 Hz was named a bilinear second order at the grid's top with
/// a sinusoid at Nyquist (docs/gap.md, "A FIR read every so many samples (session 47)").
fn scan_fir(
    prob: &GapProblem,
    fit: &dyn Fn(LowPass) -> Option<GlsFit>,
) -> Option<(LowPass, GlsFit)> {
    let cutoffs = prob.grid(EffectKind::FirFilter).points();
    if cutoffs.len() < 2 {
        return None;
    }
    let c_top = fir_top_hz(1, prob.tau0_s);
    let out = scan_fir_at(prob, fit, 1, &cutoffs, c_top);
    let (cutoff_hz, chi2) = match &out {
        Some((LowPass::Fir { cutoff_hz, .. }, f)) => (*cutoff_hz, f.chi2),
        _ => return out,
    };
    if cutoff_hz < HALF_BAND_GATE * c_top {
        return out;
    }
    // the same log steps as the output rate's grid, about the output's Nyquist frequency
    let ratio = cutoffs[1] / cutoffs[0];
    let (lo, hi) = (
        HALF_BAND_CUTOFFS.0 / prob.tau0_s,
        HALF_BAND_CUTOFFS.1 / prob.tau0_s,
    );
    let around: Vec<f64> = std::iter::successors(Some(lo), |c| Some(c * ratio))
        .take_while(|&c| c <= hi)
        .collect();
    let half = scan_fir_at(prob, fit, 2, &around, fir_top_hz(2, prob.tau0_s));
    match half {
        Some(h) if h.1.chi2 + SPAN_PARAMETER_CHI2 < chi2 => {
            tracing::trace!(lp = ?h.0, chi2 = h.1.chi2, output_rate = chi2, "a half-band FIR");
            Some(h)
        }
        _ => out,
    }
}

/// The output-rate FIR's best cut-off, as a share of the scan's top, from which the half-band
/// decimator is tried too ([`scan_fir`]).
const HALF_BAND_GATE: f64 = 0.99;

/// The half-band decimator's cut-offs on its grid, times the output step `tau0` (the output's
/// Nyquist frequency is 0.5; the polish may leave the range, up to [`FIR_TOP`] of the
/// internal rate, 0.9 of its Nyquist frequency).
const HALF_BAND_CUTOFFS: (f64, f64) = (0.35, 0.75);

/// The FIR run at `decimation` times the output rate: for each of [`FIR_TAPS`] (no more than a
/// tenth of the curve's longest cluster, times the decimation), the cut-offs `cutoffs` (Hz)
/// and a golden section on `ln f_c` within a grid step of its best point, below `c_top` (Hz);
/// then a golden section on whole taps between the best count's neighbours, the cut-off
/// polished at each. The cut-off is polished for every count because the curve is steep in
/// it: on an hour at 1 kHz, the grid's steps of 21% left every point far from the truth's fit,
/// and their order said nothing about the taps (a 47-tap filter at 131 Hz was named with 111
/// taps and a sinusoid; docs/gap.md, "A linear-phase FIR low-pass (session 46)").
fn scan_fir_at(
    prob: &GapProblem,
    fit: &dyn Fn(LowPass) -> Option<GlsFit>,
    decimation: u32,
    cutoffs: &[f64],
    c_top: f64,
) -> Option<(LowPass, GlsFit)> {
    let m_max = prob.ms.last().copied().unwrap_or(1);
    let taps: Vec<u32> = FIR_TAPS
        .into_iter()
        .filter(|&t| u64::from(t) * 10 <= m_max * u64::from(decimation))
        .collect();
    if taps.is_empty() || cutoffs.len() < 2 {
        return None;
    }
    let at = |taps: u32, lc: f64| LowPass::Fir {
        taps,
        cutoff_hz: lc.exp().min(c_top),
        decimation,
    };
    let dc = (cutoffs[1] / cutoffs[0]).ln();
    // the best cut-off (its log) for `t` taps, with the chi-squared there
    let polished = |t: u32| -> (f64, f64) {
        let chi2 = |lc: f64| fit(at(t, lc)).map_or(f64::INFINITY, |f| f.chi2);
        let (mut lc, mut best) = (cutoffs[0].ln(), f64::INFINITY);
        for &c in cutoffs {
            let v = chi2(c.ln());
            if v < best {
                (lc, best) = (c.ln(), v);
            }
        }
        let x = golden(|x| fit(at(t, x)), lc - dc, lc + dc);
        let v = chi2(x);
        if v < best {
            (x, v)
        } else {
            (lc, best)
        }
    };
    // each count's polished cut-off, once
    let memo: std::cell::RefCell<Vec<(u32, (f64, f64))>> = Default::default();
    let for_taps = |t: u32| -> (f64, f64) {
        let known = memo.borrow().iter().find(|(k, _)| *k == t).map(|&(_, r)| r);
        known.unwrap_or_else(|| {
            let r = polished(t);
            memo.borrow_mut().push((t, r));
            r
        })
    };
    let mut best_i = 0;
    let mut best_chi2 = f64::INFINITY;
    for (i, &t) in taps.iter().enumerate() {
        let (_, v) = for_taps(t);
        if v < best_chi2 {
            (best_i, best_chi2) = (i, v);
        }
    }
    let t_lo = taps[best_i.saturating_sub(1)];
    let t_hi = taps[(best_i + 1).min(taps.len() - 1)];
    let known = (taps[best_i], best_chi2);
    let t = golden_whole(|x| for_taps(x).1, t_lo, t_hi, known);
    let (lc, _) = for_taps(t);
    let lp = at(t, lc);
    fit(lp).map(|f| (lp, f))
}

/// The second order's scan in the form of `p` alone, and the sampled form as the pole-mapped
/// one it holds (its zero left to the full scan: a tenth of [`scan`]'s work, for the cascade's
/// starts, [`super::diagnose`]); the other kinds' whole scan.
pub fn scan_in_form(
    prob: &GapProblem,
    base: &ModelSpec,
    p: &EffectParams,
) -> Option<(EffectParams, GlsFit)> {
    if let Some(LowPass::Butterworth {
        order,
        cutoff_hz,
        decimation,
    }) = p.lowpass()
    {
        // its order and decimation kept, its cut-off scanned about the named one
        let fit = |lp: LowPass| fit_with(prob, base, lp);
        let best = scan_butterworth_about(prob, &fit, order, decimation, cutoff_hz)?;
        return Some((EffectParams::from_lowpass(best.0), best.1));
    }
    let Some(LowPass::SecondOrder { form, .. }) = p.lowpass() else {
        return prob.scan_params(base, p.kind());
    };
    let fit = |lp: LowPass| fit_with(prob, base, lp);
    let form = match form {
        SecondOrderForm::Sampled { .. } => SecondOrderForm::PoleMapped,
        f => f,
    };
    let best = scan_second_order_form(prob, &fit, form)?;
    Some((EffectParams::from_lowpass(best.0), best.1))
}

fn better(
    a: Option<(LowPass, GlsFit)>,
    lp: LowPass,
    f: Option<GlsFit>,
) -> Option<(LowPass, GlsFit)> {
    match (a, f) {
        (Some(a), Some(f)) if f.chi2 < a.1.chi2 => Some((lp, f)),
        (None, Some(f)) => Some((lp, f)),
        (a, _) => a,
    }
}

/// Whole taps on a log grid from 2 to [`MAX_TAPS`] (no longer than a tenth of the curve's
/// longest cluster), for each stage count; then, for each stage count, every whole number between
/// that count's best grid point's neighbours. The polish is per stage count because averages of
/// different stage counts have nearly the same curve (a 12-tap Bartlett and a 10-tap sinc^3):
/// polishing only the overall best count never tries a true 12 x 2 whose grid neighbours lost
/// to 10 x 3 (a Bartlett of 12 taps, off the grid, with angle counting: docs/gap.md "Taps off
/// the grid (session 12)").
fn scan_moving_average(
    prob: &GapProblem,
    fit: &dyn Fn(LowPass) -> Option<GlsFit>,
) -> Option<(LowPass, GlsFit)> {
    let m_max = prob.ms.last().copied().unwrap_or(1);
    let hi = (MAX_TAPS as u64).min(m_max / 10).max(2) as f64;
    let grid = prob.grid(EffectKind::MovingAverage);
    let mut taps: Vec<u32> = grid
        .points()
        .into_iter()
        .filter(|&t| t <= hi)
        .map(|t| t.round() as u32)
        .collect();
    taps.dedup();
    if taps.len() < 2 {
        return None;
    }
    let mut best: Option<(LowPass, GlsFit)> = None;
    // Each stage count's best grid index, by its own chi-squared.
    let mut per_stage: Vec<(u32, usize)> = Vec::with_capacity(STAGES.len());
    for &stages in &STAGES {
        let mut own: Option<(usize, f64)> = None;
        for (i, &t) in taps.iter().enumerate() {
            let lp = LowPass::MovingAverage {
                taps: t,
                stages,
                decimation: 1,
            };
            on_grid(fit, lp, i, &mut own, &mut best);
        }
        if let Some((i, _)) = own {
            per_stage.push((stages, i));
        }
    }
    for (stages, best_i) in per_stage {
        let lo = taps[best_i.saturating_sub(1)];
        let hi = taps[(best_i + 1).min(taps.len() - 1)];
        for t in lo..=hi {
            if taps.contains(&t) {
                continue;
            }
            let lp = LowPass::MovingAverage {
                taps: t,
                stages,
                decimation: 1,
            };
            best = better(best, lp, fit(lp));
        }
    }
    // The averages run faster than the output: CIC decimators (taps = D) and averages of a
    // few output samples' span counted at the internal rate (an ADIS16405's Bartlett window
    // of 16 taps at 819.2 Hz read every 4th). With more than one stage their output shapes
    // are not an average of whole output samples': a sinc^3 read every D-th sample spans three
    // samples, and a decimated Bartlett of four samples' span gives 12% less AVAR at one
    // sample than the output-rate one. Without them a CIC unit was named a bilinear second
    // order at the scan's top frequency (session 43's review, 0 of 5). One stage needs none:
    // a boxcar of `w D` taps read every D-th sample is the boxcar of `w` output samples.
    // Each stage count's best span on the grid (its index in DECIMATED_SPANS). Grid points
    // of more than half POLISH_TAPS taps are left to the polish (the long spans at the finest
    // decimations: 72 of them cost a fifth of a filtered unit's diagnosis).
    let mut spans: Vec<(u32, usize)> = Vec::with_capacity(STAGES.len());
    for stages in 2..=*STAGES.last().unwrap_or(&1) {
        let mut own: Option<(usize, f64)> = None;
        for d in CIC_DECIMATIONS {
            for (i, span) in DECIMATED_SPANS.into_iter().enumerate() {
                let taps = span * f64::from(d);
                if taps.fract() != 0.0 || taps < 1.0 || taps > f64::from(POLISH_TAPS) / 2.0 {
                    continue;
                }
                let lp = LowPass::MovingAverage {
                    taps: taps as u32,
                    stages,
                    decimation: d,
                };
                on_grid(fit, lp, i, &mut own, &mut best);
            }
        }
        if let Some((i, _)) = own {
            spans.push((stages, i));
        }
    }
    // Spans between the powers of two (an ADIS16405 sets its taps apart from its output rate:
    // 26 taps read every 8th): for each stage count, a golden section on the taps at the
    // finest decimation, between its best span's neighbours. The finest decimation, not the
    // best one: the curve is steep in the span (31 taps read every 4th fitted a simulated
    // record at chi-squared 60, 32 at 572) and at a decimation of 2 the span moves by halves;
    // at 64 the decimation barely shows in the shape (495 taps read every 64th fitted that
    // record at 60). Long spans take a coarser one, for at most [`POLISH_TAPS`] taps (a span
    // of 32 at 32, a resolution of 0.1%). The span is one more free parameter than the grid's,
    // so the best polished average is taken only when it lowers the chi-squared by more than
    // [`SPAN_PARAMETER_CHI2`] (a sinc^3 CIC of 10 and a Bartlett of 1.25 output samples fit
    // one record within 0.03; the CIC, on the grid, stays).
    let mut polished: Option<(LowPass, GlsFit)> = None;
    for (stages, i) in spans {
        let span_hi = DECIMATED_SPANS[(i + 1).min(DECIMATED_SPANS.len() - 1)];
        let d = CIC_DECIMATIONS
            .into_iter()
            .filter(|&d| span_hi * f64::from(d) <= f64::from(POLISH_TAPS))
            .max()
            .unwrap_or(1);
        let df = f64::from(d);
        let at = |taps: u32| {
            let lp = LowPass::MovingAverage {
                taps,
                stages,
                decimation: d,
            };
            (lp, fit(lp))
        };
        let chi2_at = |taps: u32| at(taps).1.map_or(f64::INFINITY, |f| f.chi2);
        let mid = (DECIMATED_SPANS[i] * df) as u32;
        let lo = (DECIMATED_SPANS[i.saturating_sub(1)] * df).ceil().max(1.0) as u32;
        let found = golden_whole(chi2_at, lo, (span_hi * df) as u32, (mid, chi2_at(mid)));
        let (lp, f) = at(found);
        tracing::trace!(?lp, chi2 = ?f.as_ref().map(|f| f.chi2), "the span between the grid's");
        polished = better(polished, lp, f);
    }
    match (polished, best) {
        (Some(p), Some(b)) if p.1.chi2 + SPAN_PARAMETER_CHI2 >= b.1.chi2 => Some(b),
        (p, b) => p.or(b),
    }
}

/// Fits the grid point `lp` (index `i` of its grid): kept in `best` when it fits better, and
/// in `own` as `(i, chi-squared)` when it is the best of its own stage count so far.
fn on_grid(
    fit: &dyn Fn(LowPass) -> Option<GlsFit>,
    lp: LowPass,
    i: usize,
    own: &mut Option<(usize, f64)>,
    best: &mut Option<(LowPass, GlsFit)>,
) {
    let f = fit(lp);
    if let Some(chi2) = f.as_ref().map(|f| f.chi2) {
        if own.is_none_or(|(_, c)| chi2 < c) {
            *own = Some((i, chi2));
        }
    }
    *best = better(best.take(), lp, f);
}

/// The drop of chi-squared a span between the grid's must bring over the best average on the
/// grid: AIC's price of one parameter.
const SPAN_PARAMETER_CHI2: f64 = 2.0;

/// The most taps the span polish of the averages run faster than the output tries.
const POLISH_TAPS: u32 = 1024;

/// The whole number in `lo..=hi` that minimises `f`, by a golden section on whole numbers
/// (every point once the bracket holds four or fewer), starting from the known point `known`
/// `(x, f(x))`. `f` is taken as unimodal in the bracket.
fn golden_whole(f: impl Fn(u32) -> f64, lo: u32, hi: u32, known: (u32, f64)) -> u32 {
    let mut memo: Vec<(u32, f64)> = vec![known];
    let mut eval = |x: u32| -> f64 {
        if let Some(&(_, v)) = memo.iter().find(|(k, _)| *k == x) {
            return v;
        }
        let v = f(x);
        memo.push((x, v));
        v
    };
    let (mut a, mut b) = (lo.min(hi), hi.max(lo));
    let g = (5f64.sqrt() - 1.0) / 2.0;
    // The interior points at the golden ratios of [a, b], apart by at least one; each step
    // keeps one of them and evaluates one new point.
    let inner = |a: u32, b: u32| {
        let w = f64::from(b - a);
        let x1 = a + (w * (1.0 - g)).round() as u32;
        (x1, (a + (w * g).round() as u32).max(x1 + 1))
    };
    let (mut x1, mut x2) = inner(a, b);
    while b - a > 3 {
        if eval(x1) <= eval(x2) {
            b = x2;
            x2 = x1;
            x1 = inner(a, b).0.min(x2 - 1);
        } else {
            a = x1;
            x1 = x2;
            x2 = inner(a, b).1.max(x1 + 1);
        }
    }
    let mut best = known;
    for x in a..=b {
        let v = eval(x);
        if v < best.1 {
            best = (x, v);
        }
    }
    best.0
}

/// The spans (taps over the decimation, in output samples) of the averages run faster than the
/// output that the scan tries at each decimation of [`CIC_DECIMATIONS`] (up to half
/// [`POLISH_TAPS`] taps): 1 is the CIC; parts that set their taps and output rate apart (the
/// ADIS16405's) are reached between them by the span polish (docs/gap.md, "Spans between the
/// powers of two (session 45)").
pub const DECIMATED_SPANS: [f64; 7] = [0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0];

/// A grid in `ln f_n` (the first order's range of time constants, `1 / (2 pi f_n)`) by
/// `ln zeta` over [`DAMPING_RANGE`]; then golden sections in each coordinate in turn, within one
/// grid step of the best point.
fn scan_second_order(
    prob: &GapProblem,
    fit: &dyn Fn(LowPass) -> Option<GlsFit>,
) -> Option<(LowPass, GlsFit)> {
    // Both forms, each scanned and polished on its own (the pole-mapped one and the bilinear
    // biquad: docs/gap.md, "The bilinear second order (session 42)"): on the grid alone the
    // bilinear form beat a pole-mapped unit's own form at 8 Hz of 250 Hz and at 28 Hz of 200 Hz,
    // and its polished point then left a band beside it.
    //
    // The third form, a filter run at an internal rate and read every few samples (docs/gap.md,
    // "Filters run faster than the output (session 43)"), is scanned with the continuous
    // filter's zero at each grid point, and its zero then polished with the frequency and
    // damping. The zero is a third shape parameter and the form holds the pole-mapped one (zero
    // 0), so it is taken only when it lowers `r' S^-1 r` by more than [`EXTRA_SHAPE_CHI2`]: a
    // pole-mapped or bilinear unit stays named as such.
    let mut best: Option<(LowPass, GlsFit)> = None;
    for form in [SecondOrderForm::PoleMapped, SecondOrderForm::Bilinear] {
        if let Some((lp, f)) = scan_second_order_form(prob, fit, form) {
            best = better(best, lp, Some(f));
        }
    }
    let sampled = SecondOrderForm::Sampled { zero: f64::NAN };
    let sampled = scan_second_order_form(prob, fit, sampled);
    tracing::trace!(
        pole_mapped_or_bilinear = ?best.as_ref().map(|b| (b.0, b.1.chi2)),
        sampled = ?sampled.as_ref().map(|s| (s.0, s.1.chi2)),
        "second-order forms"
    );
    match (sampled, best) {
        (Some(s), Some(b)) if s.1.chi2 < b.1.chi2 - EXTRA_SHAPE_CHI2 => Some(s),
        (Some(s), None) => Some(s),
        (_, b) => b,
    }
}

/// The bilinear second order's highest natural frequency scanned, times `tau0` (its form is
/// defined below Nyquist, [`LowPass::check`]: `f tau0 < 0.49`).
pub const BILINEAR_TOP: f64 = 0.47;

/// The drop in `r' S^-1 r` a third shape parameter must bring to be taken: chi-squared with one
/// degree of freedom at 99%.
const EXTRA_SHAPE_CHI2: f64 = 6.63;

/// [`scan_second_order`] in one form: the grid, golden sections, then the simplex. The sampled
/// form (its zero not read: NaN) is run with the continuous filter's zero at each point, and
/// its zero is then polished too.
fn scan_second_order_form(
    prob: &GapProblem,
    fit: &dyn Fn(LowPass) -> Option<GlsFit>,
    form: SecondOrderForm,
) -> Option<(LowPass, GlsFit)> {
    let mut fgrid = prob.grid(EffectKind::SecondOrderFilter).points();
    let (z_lo, z_hi) = DAMPING_RANGE;
    let nz = ((z_hi / z_lo).log10() * DAMPING_PER_DECADE).ceil() as usize;
    let zgrid: Vec<f64> = (0..=nz)
        .map(|i| z_lo * (z_hi / z_lo).powf(i as f64 / nz as f64))
        .collect();
    // The pole-mapped poles leave the unit circle's useful part at 2 pi f tau0 = 2.5 (0.40 of
    // the output rate); the bilinear biquad is defined up to Nyquist, and consumer parts set
    // their low-pass up to 0.4-0.45 of the output rate (a Butterworth at 40 Hz read at 100 Hz
    // was named one at the grid's top, 39.8 Hz, with damping 1.5). Its grid goes on at the
    // same step to BILINEAR_TOP.
    let f_max = match form {
        SecondOrderForm::Bilinear => BILINEAR_TOP / prob.tau0_s,
        _ => 2.5 / (2.0 * PI * prob.tau0_s),
    };
    if let (SecondOrderForm::Bilinear, [.., a, b]) = (form, &fgrid[..]) {
        let (a, b) = (*a, *b);
        let mut f = b * (b / a);
        while f < f_max {
            fgrid.push(f);
            f *= b / a;
        }
        if fgrid.last().is_some_and(|&l| l < f_max) {
            fgrid.push(f_max);
        }
    }
    // The polish stays within the grid's frequencies: below them a lightly damped filter's
    // memory runs to millions of samples, and each of its columns costs as many (a ring-laser
    // gyro's record took 193 s, its simplex walking the frequency down; 4.0 s within them, the
    // record the same), where the scan's end is `at_memory_end` anyway.
    let f_min = fgrid.first().copied().unwrap_or(0.0).min(f_max);
    // (natural frequency, damping) at `(ln f, ln zeta)`, held within the scan's ranges
    let clamped = |lf: f64, lz: f64| (lf.exp().max(f_min).min(f_max), lz.exp().clamp(z_lo, z_hi));
    let lp_at = |lf: f64, lz: f64, form: SecondOrderForm| {
        let (natural_frequency_hz, damping) = clamped(lf, lz);
        LowPass::SecondOrder {
            natural_frequency_hz,
            damping,
            form,
        }
    };
    let tau0_s = prob.tau0_s;
    let lp_of = |lf: f64, lz: f64| match form {
        SecondOrderForm::Sampled { .. } => {
            let (f, z) = clamped(lf, lz);
            let zero = sampled_zero(f, z, tau0_s, CONTINUOUS_DECIMATION).clamp(0.0, MAX_ZERO);
            lp_at(lf, lz, SecondOrderForm::Sampled { zero })
        }
        _ => lp_at(lf, lz, form),
    };
    let mut best: Option<(LowPass, GlsFit)> = None;
    for &f in &fgrid {
        for &z in &zgrid {
            let lp = lp_of(f.ln(), z.ln());
            best = better(best, lp, fit(lp));
        }
    }
    let (
        LowPass::SecondOrder {
            natural_frequency_hz,
            damping,
            ..
        },
        _,
    ) = best.as_ref()?.clone()
    else {
        return best;
    };
    let df = (fgrid.get(1).copied().unwrap_or(1.0) / fgrid[0]).ln();
    let dz = (zgrid[1] / zgrid[0]).ln();
    let (mut lf, mut lz) = (natural_frequency_hz.ln(), damping.ln());
    for _ in 0..POLISH_ROUNDS {
        lf = golden(|x| fit(lp_of(x, lz)), lf - df, lf + df);
        lz = golden(|x| fit(lp_of(lf, x)), lz - dz, lz + dz);
    }
    // The valley of r' S^-1 r runs diagonally in (ln f, ln zeta) (a lower frequency with a lower
    // damping keeps the resonance's shape), so narrow on a long precise curve that the golden
    // sections stop far from its floor (a consumer IMU's filter at 2 pi f tau0 ~ 1: G 45 at the
    // polished point, 2.5 at the true one): a simplex follows it from there. Its best is never
    // worse than the polished point it starts from, so that point needs no fit of its own here.
    let ([lf, lz], _) = nelder_mead(
        |p| fit(lp_of(p[0], p[1])).map_or(f64::INFINITY, |r| r.chi2),
        [lf, lz],
        [df / 4.0, dz / 4.0],
        SIMPLEX_EVALS,
        SIMPLEX_TOL,
    );
    let lp = lp_of(lf, lz);
    let best = better(best, lp, fit(lp));
    let SecondOrderForm::Sampled { .. } = form else {
        return best;
    };
    // The zero by golden sections (0: the pole-mapped form), the frequency and damping again
    // by the simplex at it, then all three by a simplex in three parameters. Zero, frequency and
    // damping trade off along one valley: one round of the first two left a Butterworth at 219
    // Hz run at 2 kHz and read every 2nd sample at zero 0.29, 199 Hz and damping 0.64 (`r'
    // S^-1 r` 1737), and six rounds at 0.35 (785), where the form's best is near 0.48, 225 Hz
    // and 0.69 (docs/gap.md, "The sampled form's zero in one simplex with its poles (session
    // 44)").
    let with = |c: f64| SecondOrderForm::Sampled {
        zero: c.clamp(0.0, MAX_ZERO),
    };
    let c = golden(|x| fit(lp_at(lf, lz, with(x))), 0.0, MAX_ZERO);
    let ([lf, lz], _) = nelder_mead(
        |p| fit(lp_at(p[0], p[1], with(c))).map_or(f64::INFINITY, |r| r.chi2),
        [lf, lz],
        [df / 8.0, dz / 8.0],
        SIMPLEX_EVALS,
        SIMPLEX_TOL,
    );
    let ([lf, lz, c], _) = nelder_mead(
        |p| fit(lp_at(p[0], p[1], with(p[2]))).map_or(f64::INFINITY, |r| r.chi2),
        [lf, lz, c],
        [df / 8.0, dz / 8.0, ZERO_STEP],
        SIMPLEX_EVALS_3,
        SIMPLEX_TOL,
    );
    let lp = lp_at(lf, lz, with(c));
    better(best, lp, fit(lp))
}

/// The sampled form's closing simplex in frequency, damping and zero: its first step in the
/// zero, and its evaluations at most.
const ZERO_STEP: f64 = 0.05;
const SIMPLEX_EVALS_3: usize = 300;

/// The minimiser of `chi2(f(x))` on `[lo, hi]` by golden section.
fn golden(f: impl Fn(f64) -> Option<GlsFit>, lo: f64, hi: f64) -> f64 {
    let c = |x: f64| f(x).map_or(f64::INFINITY, |r| r.chi2);
    golden_section(c, lo, hi, GOLDEN_STEPS).best()
}

#[cfg(test)]
mod tests {
    use super::golden_whole;
    use std::cell::Cell;

    /// A unimodal function of whole numbers: its minimiser found exactly, at either end of the
    /// bracket too, with far fewer evaluations than the bracket holds (a golden section takes
    /// about `log(n) / log(1.618)`), and the known point never evaluated again.
    #[test]
    fn golden_whole_finds_the_whole_minimiser() {
        let sweep = (0..=40u32).flat_map(|t| [(t, 0u32, 40u32), (t, t.saturating_sub(3), t + 2)]);
        for (target, lo, hi) in [
            (37u32, 1u32, 1000u32),
            (1, 1, 1000),
            (1000, 1, 1000),
            (5, 4, 6),
        ]
        .into_iter()
        .chain(sweep)
        {
            let calls = Cell::new(0u32);
            let f = |x: u32| {
                calls.set(calls.get() + 1);
                (f64::from(x) - f64::from(target)).powi(2)
            };
            let mid = (lo + hi) / 2;
            let known = (mid, (f64::from(mid) - f64::from(target)).powi(2));
            assert_eq!(
                golden_whole(f, lo, hi, known),
                target,
                "{target} in {lo}..={hi}"
            );
            assert!(calls.get() <= 20, "{} evaluations", calls.get());
        }
    }
}
