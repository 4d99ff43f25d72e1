//! A channel's curves and fit, in two passes: the curves with each tau's noise type read off the
//! data (lag-1 autocorrelation), the five-term fit, then the curves and the fit once more with the
//! noise type the fitted model gives at each tau (the term that dominates there), for the edf.

use super::*;

/// The power-law exponent of S_y for the term that dominates the model at a tau: Q is white
/// phase (+2), N white rate (0), B flicker rate (-1), K random-walk rate (-2); the ramp R is
/// deterministic and is given the random-walk type, the steepest AVAR supports.
pub(super) const TERM_ALPHA: [i32; 5] = [2, 0, -1, -2, -2];

/// Reads a channel's accumulator into curves, fits the AVAR curve, and re-derives each tau's
/// noise type from the fitted model (the term that dominates there) for the final edf.
pub(super) fn analyze_channel(
    ch: &mut ChannelState,
    opts: &AnalysisOptions,
) -> (Vec<Curve>, Option<FitResult>) {
    let readings = ch.acc.read();
    let cfg = &opts.accum;
    let (n, t) = (ch.acc.phase_points(), ch.acc.t_data_s());
    let curves = build_curves(&readings, cfg.stats, cfg.tau0_s, n, t, AlphaSource::Lag1);
    let Some(fit_opts) = &opts.fit else {
        return (curves, None);
    };
    let Some(avar) = curves.iter().find(|c| c.stat == Stat::Avar) else {
        return (curves, None);
    };
    let first = match ch.fitter.fit(&avar.points, fit_opts) {
        Ok(f) => f,
        Err(e) => {
            tracing::debug!("{}: {e}", ch.setup.name);
            return (curves, None);
        }
    };
    // The noise type at each tau from the model, then the curves and the fit once more with
    // the edf that type gives.
    let alphas: Vec<i32> = readings
        .iter()
        .map(|r| {
            let b = crate::model::terms::basis(r.tau_s);
            let (i, _) = (0..5)
                .map(|i| (i, b[i] * first.c[i]))
                .fold((1, f64::MIN), |a, x| if x.1 > a.1 { x } else { a });
            TERM_ALPHA[i]
        })
        .collect();
    let curves = build_curves(
        &readings,
        cfg.stats,
        cfg.tau0_s,
        n,
        t,
        AlphaSource::Given(&alphas),
    );
    let fit = curves
        .iter()
        .find(|c| c.stat == Stat::Avar)
        .and_then(|c| ch.fitter.fit(&c.points, fit_opts).ok())
        .unwrap_or(first);
    (curves, Some(fit))
}
