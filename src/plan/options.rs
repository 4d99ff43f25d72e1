//! The values of the run options, parsed once: durations, `--taus`, `--overlap`, `--stats`,
//! `--fit` and `--pace`. Each type implements [`FromStr`], so the command line (clap) and the
//! stand config read the same text the same way; the error is a plain sentence about the value
//! that the caller prefixes with the option or key it came from.

use std::str::FromStr;

use crate::allan::accum::{Overlap, StatSet, TauSpec};
use crate::model::fit::FitMethod;

/// A positive, finite number of seconds, written as a number or with a unit suffix `s`, `min`,
/// `h` or `d` (`3h`, `90min`, `0.5`). Used by `--duration`, `run.duration` and `simulate`.
#[derive(Debug, Clone, Copy, PartialEq, PartialOrd)]
pub struct Seconds(pub f64);

impl FromStr for Seconds {
    type Err = String;
    /// Within `(0, crate::ranges::MAX_SECONDS]`, so that any accepted value makes a timer.
    fn from_str(s: &str) -> Result<Self, String> {
        crate::ranges::parse_duration(s).map(Seconds)
    }
}

/// Parses a duration in seconds (see [`Seconds`]); the message names the value.
pub fn parse_duration_s(s: &str) -> Result<f64, String> {
    s.parse::<Seconds>()
        .map(|d| d.0)
        .map_err(|e| format!("duration `{s}`: {e}"))
}

impl FromStr for TauSpec {
    type Err = String;
    /// `octave`, `decade`, or a comma list of cluster sizes `m >= 1`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "octave" => Ok(TauSpec::Octave),
            "decade" => Ok(TauSpec::Decade),
            list => {
                let ms: Result<Vec<u64>, _> =
                    list.split(',').map(|t| t.trim().parse::<u64>()).collect();
                match ms {
                    Ok(v) if !v.is_empty() && v.iter().all(|&m| m >= 1) => Ok(TauSpec::List(v)),
                    _ => Err(
                        "expected octave, decade or a comma list of cluster sizes m >= 1".into(),
                    ),
                }
            }
        }
    }
}

impl FromStr for Overlap {
    type Err = String;
    /// `full`, or an integer `L >= 1`.
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "full" => Ok(Overlap::Full),
            l => match l.parse::<u64>() {
                Ok(l) if l >= 1 => Ok(Overlap::Bounded(l)),
                _ => Err("expected `full` or an integer L >= 1".into()),
            },
        }
    }
}

impl FromStr for StatSet {
    type Err = String;
    /// A comma list of `avar`, `hvar`, `mvar` (at least one).
    fn from_str(s: &str) -> Result<Self, String> {
        StatSet::from_names(s.split(','))
    }
}

impl StatSet {
    /// The set named by `names` (`avar`, `hvar`, `mvar`; at least one).
    pub fn from_names<'a>(names: impl IntoIterator<Item = &'a str>) -> Result<StatSet, String> {
        let mut set = StatSet {
            avar: false,
            hvar: false,
            mvar: false,
        };
        for s in names {
            match s.trim() {
                "avar" => set.avar = true,
                "hvar" => set.hvar = true,
                "mvar" => set.mvar = true,
                other => {
                    return Err(format!(
                        "unknown statistic `{other}` (allowed: avar, hvar, mvar)"
                    ))
                }
            }
        }
        if !(set.avar || set.hvar || set.mvar) {
            return Err("at least one statistic".into());
        }
        Ok(set)
    }
}

/// `--fit`: a fit method, or `none`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FitChoice(pub Option<FitMethod>);

impl FromStr for FitChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "none" => Ok(FitChoice(None)),
            m => m.parse::<FitMethod>().map(|m| FitChoice(Some(m))),
        }
    }
}

/// `--pace`: as fast as the analysis takes the data, or at the data's own rate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Replay {
    #[default]
    Max,
    Realtime,
}

impl FromStr for Replay {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "max" => Ok(Replay::Max),
            "realtime" => Ok(Replay::Realtime),
            _ => Err("expected max or realtime".into()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_with_units() {
        assert_eq!("3h".parse::<Seconds>(), Ok(Seconds(10_800.0)));
        assert_eq!("90min".parse::<Seconds>(), Ok(Seconds(5_400.0)));
        assert_eq!("2d".parse::<Seconds>(), Ok(Seconds(172_800.0)));
        assert_eq!(" 12.5 s".parse::<Seconds>(), Ok(Seconds(12.5)));
        for bad in ["0", "-1h", "inf", "NaN", "h", "1e308d", ""] {
            assert!(bad.parse::<Seconds>().is_err(), "{bad}");
        }
    }

    #[test]
    fn taus_overlap_stats() {
        assert_eq!("octave".parse::<TauSpec>(), Ok(TauSpec::Octave));
        assert_eq!(
            "1, 3,9".parse::<TauSpec>(),
            Ok(TauSpec::List(vec![1, 3, 9]))
        );
        assert!("0,2".parse::<TauSpec>().is_err());
        assert_eq!("full".parse::<Overlap>(), Ok(Overlap::Full));
        assert_eq!("16".parse::<Overlap>(), Ok(Overlap::Bounded(16)));
        assert!("0".parse::<Overlap>().is_err());
        let s: StatSet = "avar,mvar".parse().unwrap();
        assert!(s.avar && !s.hvar && s.mvar);
        assert!("tdev".parse::<StatSet>().is_err());
        assert_eq!("none".parse::<FitChoice>(), Ok(FitChoice(None)));
    }
}
