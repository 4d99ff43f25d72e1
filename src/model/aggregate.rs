//! Run-to-run statistics of fitted coefficients (docs/theory.md section 2, the seed paper's table 2):
//! over the runs where a coefficient is determined, the mean, the sample standard deviation
//! (n - 1), the Student 95% interval of the mean, and the paper's `mean +- 1.96 sd / sqrt(n)`.

use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Two-sided 95% normal quantile, as the seed paper used it.
const Z95: f64 = 1.96;

/// Statistics of one coefficient over runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RunStats {
    /// Runs where the value is determined (not "-").
    pub n: usize,
    pub mean: f64,
    /// Sample standard deviation (divisor n - 1); `None` for one run.
    pub sd: Option<f64>,
    /// Student-t 95% interval of the mean, `mean +- t_{0.975, n-1} sd / sqrt(n)`.
    pub ci_t: Option<[f64; 2]>,
    /// The seed paper's interval, `mean +- 1.96 sd / sqrt(n)`.
    pub ci_z: Option<[f64; 2]>,
}

/// Statistics over the determined values (`None` entries are the paper's "-" runs). `None` when
/// no run determined the coefficient.
pub fn run_stats(values: &[Option<f64>]) -> Option<RunStats> {
    let v: Vec<f64> = values
        .iter()
        .flatten()
        .copied()
        .filter(|x| x.is_finite())
        .collect();
    let n = v.len();
    if n == 0 {
        return None;
    }
    let mean = v.iter().sum::<f64>() / n as f64;
    if n == 1 {
        return Some(RunStats {
            n,
            mean,
            sd: None,
            ci_t: None,
            ci_z: None,
        });
    }
    let sd = (v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1) as f64).sqrt();
    let se = sd / (n as f64).sqrt();
    let t = StudentsT::new(0.0, 1.0, (n - 1) as f64)
        .map(|d| d.inverse_cdf(0.975))
        .unwrap_or(f64::NAN);
    Some(RunStats {
        n,
        mean,
        sd: Some(sd),
        ci_t: t.is_finite().then_some([mean - t * se, mean + t * se]),
        ci_z: Some([mean - Z95 * se, mean + Z95 * se]),
    })
}

/// Statistics for each of Q, N, B, K, R over runs; `runs[r][i]` is run r's coefficient i when
/// determined.
pub fn aggregate(runs: &[[Option<f64>; 5]]) -> [Option<RunStats>; 5] {
    std::array::from_fn(|i| run_stats(&runs.iter().map(|r| r[i]).collect::<Vec<_>>()))
}

/// One run's determined values from a fit (the `value` of docs/records.md's `coef`).
pub fn determined_values(fit: &crate::model::fit::FitResult) -> [Option<f64>; 5] {
    std::array::from_fn(|i| fit.coef[i].determined.then_some(fit.coef[i].value))
}

/// One run's determined coefficients of one channel (the `value`s of a `fit` record's `coef`;
/// `None` where the paper prints "-").
#[derive(Debug, Clone, PartialEq)]
pub struct RunCoefs {
    pub channel: String,
    pub unit: String,
    /// Q, N, B, K, R.
    pub values: [Option<f64>; 5],
}

impl RunCoefs {
    /// From a fit (the channel's name and unit given by the caller).
    pub fn from_fit(channel: &str, unit: &str, fit: &crate::model::fit::FitResult) -> RunCoefs {
        RunCoefs {
            channel: channel.into(),
            unit: unit.into(),
            values: determined_values(fit),
        }
    }
}

/// Run-to-run statistics of one coefficient of one channel (docs/records.md's `aggregate` record).
#[derive(Debug, Clone, PartialEq)]
pub struct CoefAggregate {
    pub channel: String,
    pub unit: String,
    /// "Q" .. "R".
    pub coef: &'static str,
    /// `None` when no run determined it.
    pub stats: Option<RunStats>,
}

/// A channel in one unit in one run and another in a later run (deg and rad, u and rad): its
/// coefficients cannot be averaged, nor labelled with either unit. Runs are indices into the
/// caller's runs, which it names (a file, an input).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("channel {channel} is in {unit} in run {run} where run {first_run} has it in {first_unit}")]
pub struct UnitMismatch {
    pub channel: String,
    /// The first run with the channel, and its unit there.
    pub first_run: usize,
    pub first_unit: String,
    /// The first run with the channel in another unit, and that unit.
    pub run: usize,
    pub unit: String,
}

/// The seed paper's table 2 for every channel and coefficient: `runs[r]` holds run r's channels.
/// Channels are matched by name across runs and listed in the order they first appear; a run
/// without a channel counts as "-" for it. A channel whose unit differs between runs is refused
/// ([`UnitMismatch`]): before (session 42) its runs were averaged under the first run's unit.
pub fn aggregate_channels(runs: &[Vec<RunCoefs>]) -> Result<Vec<CoefAggregate>, UnitMismatch> {
    // Each channel: its name, unit and the first run that has it.
    let mut channels: Vec<(&str, &str, usize)> = Vec::new();
    for (r, run) in runs.iter().enumerate() {
        for c in run {
            match channels.iter().find(|(n, _, _)| *n == c.channel) {
                None => channels.push((&c.channel, &c.unit, r)),
                Some(&(_, unit, first_run)) if unit != c.unit => {
                    return Err(UnitMismatch {
                        channel: c.channel.clone(),
                        first_run,
                        first_unit: unit.to_string(),
                        run: r,
                        unit: c.unit.clone(),
                    })
                }
                Some(_) => {}
            }
        }
    }
    let mut out = Vec::with_capacity(channels.len() * 5);
    for (name, unit, _) in channels {
        let per_run: Vec<[Option<f64>; 5]> = runs
            .iter()
            .map(|run| {
                run.iter()
                    .find(|c| c.channel == name)
                    .map_or([None; 5], |c| c.values)
            })
            .collect();
        let stats = aggregate(&per_run);
        for (i, s) in stats.into_iter().enumerate() {
            out.push(CoefAggregate {
                channel: name.to_string(),
                unit: unit.to_string(),
                coef: crate::model::terms::TERM_NAMES[i],
                stats: s,
            });
        }
    }
    Ok(out)
}
