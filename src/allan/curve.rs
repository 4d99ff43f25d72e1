//! Turns accumulator readings into curves: per tau, the noise type, the equivalent degrees of
//! freedom (Greenhall and Riley 2003) and a 95% chi-squared interval (docs/theory.md section 4).

use super::accum::{LevelReading, StatSet};
use super::edf::{edf, sigma_interval};
use super::noise_id::{alpha_from_lag1, dmax_for, Lag1};
use super::{Curve, CurvePoint, Stat};

/// Confidence of the intervals written in `curve` records (docs/records.md: 95%).
pub const CONFIDENCE: f64 = 0.95;

/// Where the power-law noise type at each tau comes from.
#[derive(Debug, Clone, Copy)]
pub enum AlphaSource<'a> {
    /// Identified from the data at each tau by the lag-1 autocorrelation (Riley and Greenhall
    /// 2004); taus with too few blocks take the type of the nearest shorter tau.
    Lag1,
    /// Given per tau (e.g. from the fitted model's dominant term), in the order of the readings.
    Given(&'a [i32]),
}

/// The curves of the statistics in `stats`, from one reading of a channel's accumulator.
///
/// `n_phase` is the number of phase points (Greenhall's N); `t_data_s` the data seconds consumed.
pub fn build_curves(
    readings: &[LevelReading],
    stats: StatSet,
    tau0_s: f64,
    n_phase: u64,
    t_data_s: f64,
    alpha: AlphaSource,
) -> Vec<Curve> {
    Stat::ALL
        .into_iter()
        .filter(|&s| stats.contains(s))
        .map(|stat| {
            let mut last_alpha = 0; // white rate noise until the data say otherwise
            let points = readings
                .iter()
                .enumerate()
                .filter_map(|(i, r)| {
                    let (var, count) = r.get(stat)?;
                    let a = match alpha {
                        AlphaSource::Given(list) => list.get(i).copied().unwrap_or(last_alpha),
                        AlphaSource::Lag1 => {
                            let lag = Lag1 { r1: r.lag1 };
                            alpha_from_lag1(&lag, dmax_for(stat))
                                .map(|e| e.alpha)
                                .unwrap_or(last_alpha)
                        }
                    };
                    last_alpha = a;
                    Some(point(stat, r, var, count, a, n_phase))
                })
                .collect();
            Curve {
                stat,
                tau0_s,
                t_data_s,
                points,
            }
        })
        .collect()
}

/// One point: its edf for noise `alpha` and its 95% interval (NaN where the edf is undefined,
/// e.g. a run too short for Greenhall's algorithm at that tau).
fn point(
    stat: Stat,
    r: &LevelReading,
    var: f64,
    count: u64,
    alpha: i32,
    n_phase: u64,
) -> CurvePoint {
    // The edf is defined for the noise types the statistic converges for; a type it cannot
    // take (e.g. alpha = -3 for AVAR) falls back to the nearest it can.
    let lowest = if stat == Stat::Hvar { -4 } else { -2 };
    let a = alpha.clamp(lowest, 2);
    let dof = edf(stat, a, r.m, r.stride, n_phase).unwrap_or(f64::NAN);
    let sigma = var.sqrt();
    let (lo, hi) = sigma_interval(sigma, dof, CONFIDENCE).unwrap_or((f64::NAN, f64::NAN));
    CurvePoint {
        m: r.m,
        tau_s: r.tau_s,
        var,
        count,
        edf: dof,
        alpha: a,
        sigma_lo: lo,
        sigma_hi: hi,
        stride: r.stride,
        n_phase,
    }
}
