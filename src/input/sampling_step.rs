//! The sampling step of text columns read off their time column, for a run given no `--tau0`.
//!
//! Datasets as they come (EuRoC's `#timestamp [ns]`, a logger's `time_s`, a ROS bag exported to
//! CSV) carry their clock. The step is the median of the first [`LOOK_ROWS`] steps of the time
//! column (robust to a few gaps and jitter), in the unit the column's name gives (`[ns]`, `(s)`,
//! `_ms`), else the unit its stamps' size says for a clock since 1970 (about 1.7e18 in ns, 1.7e15
//! in us, 1.7e12 in ms, 1.7e9 in s), else seconds. A time column that is irregular (fewer than
//! half of its steps within a quarter of the median) or whose step is not a plausible sampling
//! step gets a usage error asking for `--tau0`, never a guess.

use std::io::BufRead;
use std::path::Path;

use super::text::{time_column_unit, TextOptions, TextReader};
use crate::error::UsageError;

/// Rows looked at.
pub const LOOK_ROWS: usize = 4001;

/// A step farther than this share of the median from it counts as irregular.
const TOLERANCE: f64 = 0.25;

/// A sampling step read off a time column.
#[derive(Debug, Clone, PartialEq)]
pub struct InferredStep {
    /// The step, in seconds.
    pub tau0_s: f64,
    /// The time column's header name.
    pub column: String,
    /// Seconds per unit of the column, and how that unit was decided.
    pub unit_s: f64,
    pub unit_from: &'static str,
    /// Steps looked at, and those within [`TOLERANCE`] of the median.
    pub steps: usize,
    pub regular: usize,
}

impl std::fmt::Display for InferredStep {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = [(1e-9, "ns"), (1e-6, "us"), (1e-3, "ms")]
            .into_iter()
            .find(|(u, _)| *u == self.unit_s)
            .map_or("s", |(_, name)| name);
        write!(
            f,
            "tau0 {} s from the time column `{}` (median of {} steps, {} of them within {}% of it; \
             unit {unit} from {})",
            crate::ranges::show(self.tau0_s),
            self.column,
            self.steps,
            self.regular,
            TOLERANCE * 100.0,
            self.unit_from
        )
    }
}

/// The unit a clock since 1970 has for a stamp of this size, if it looks like one.
fn epoch_unit(stamp: f64) -> Option<f64> {
    // 1e9 s is 2001; 4e9 s is 2096.
    [1.0, 1e-3, 1e-6, 1e-9]
        .into_iter()
        .find(|&u| (1e9..4e9).contains(&(stamp * u)))
}

/// `x` rounded to `digits` significant decimal digits.
fn round_significant(x: f64, digits: i32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let scale = 10f64.powi(digits - 1 - x.abs().log10().floor() as i32);
    (x * scale).round() / scale
}

/// Reads the start of `src` (text columns, as `opts` lay them out) and returns the sampling step
/// its time column shows (see the module doc).
pub fn infer_tau0<R: BufRead>(
    src: R,
    path: &Path,
    opts: &TextOptions,
) -> Result<InferredStep, UsageError> {
    let usage = |p: String| UsageError::Option(format!("{}: {p}", path.display()));
    let mut reader = TextReader::with_options(src, path, opts)?;
    let Some(column) = reader.time_column_name().map(str::to_string) else {
        return Err(usage(
            "--tau0 is required: the text columns have no time column (a header name time, t, \
             timestamp or time_s, with or without a unit, or --time-column NAME)"
                .into(),
        ));
    };
    let stamps = reader
        .take_stamps(LOOK_ROWS)
        .map_err(|e| usage(e.to_string()))?;
    let mut steps: Vec<f64> = stamps
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| d.is_finite() && *d > 0.0)
        .collect();
    if steps.len() < 2 {
        return Err(usage(format!(
            "--tau0 is required: the time column `{column}` has fewer than two steps forward in \
             its first {} rows",
            stamps.len()
        )));
    }
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    let regular = steps
        .iter()
        .filter(|d| ((*d - median) / median).abs() <= TOLERANCE)
        .count();
    if 2 * regular < steps.len() {
        return Err(usage(format!(
            "--tau0 is required: the time column `{column}` is irregular (median step {}, only \
             {regular} of {} steps within {}% of it)",
            crate::ranges::show(median),
            steps.len(),
            TOLERANCE * 100.0
        )));
    }
    let first = stamps
        .iter()
        .copied()
        .find(|t| t.is_finite())
        .unwrap_or(0.0);
    let (unit_s, unit_from) = match time_column_unit(&column).flatten() {
        Some(u) => (u, "its name"),
        None => match epoch_unit(first) {
            Some(u) => (u, "its stamps, a clock since 1970"),
            None => (1.0, "no unit given: seconds"),
        },
    };
    // The shortest decimal step within the stamps' resolution: stamps read as f64 (a clock
    // since 1970 in ns is resolved to 256 ns) make 5,000,000 ns steps look like 4,999,936, and
    // seconds from 0 printed to the ms make 0.005 s steps 0.00499999999999989 by 18 s. The
    // resolution is that of the stamps looked at (the first alone is 0 on such a clock): their
    // 90th percentile in size, so that one wild stamp does not coarsen it.
    let mut sizes: Vec<f64> = stamps
        .iter()
        .filter(|t| t.is_finite())
        .map(|t| t.abs())
        .collect();
    sizes.sort_by(f64::total_cmp);
    let large = sizes.get(sizes.len() * 9 / 10).copied().unwrap_or(0.0);
    let resolution = 2.0 * large * f64::EPSILON;
    let step = (1..=15)
        .map(|digits| round_significant(median, digits))
        .find(|r| (r - median).abs() <= resolution)
        .unwrap_or(median);
    let tau0_s = round_significant(step * unit_s, 15);
    if crate::ranges::check_tau0(tau0_s).is_err() || tau0_s > 10.0 {
        return Err(usage(format!(
            "--tau0 is required: the time column `{column}` gives a step of {} s ({unit_from}), \
             not a sampling step; name the column's unit (`{column} [ms]`) or give --tau0",
            crate::ranges::show(tau0_s)
        )));
    }
    Ok(InferredStep {
        tau0_s,
        column,
        unit_s,
        unit_from,
        steps: steps.len(),
        regular,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn infer(text: &str) -> Result<InferredStep, UsageError> {
        infer_tau0(text.as_bytes(), Path::new("t.csv"), &TextOptions::default())
    }

    /// EuRoC's header (commented, units in brackets) and nanosecond stamps with a 2-step gap.
    #[test]
    fn euroc_nanoseconds() {
        let mut t = String::from("#timestamp [ns],w_RS_S_x [rad s^-1],a_RS_S_x [m s^-2]\n");
        let mut ns: u64 = 1_403_636_579_758_555_392;
        for k in 0..50 {
            ns += if k == 20 { 15_000_000 } else { 5_000_000 };
            t.push_str(&format!("{ns},0.001,9.81\n"));
        }
        let s = infer(&t).unwrap();
        assert_eq!(s.tau0_s, 0.005);
        assert_eq!(s.column, "timestamp [ns]");
        assert_eq!((s.steps, s.regular), (49, 48));
        assert_eq!(s.unit_from, "its name");
    }

    /// No unit in the name: a clock since 1970 in microseconds is told by its size; plain
    /// seconds from 0 are seconds.
    #[test]
    fn unit_from_the_stamps() {
        let mut t = String::from("time,gx\n");
        for k in 0..20u64 {
            t.push_str(&format!("{},1\n", 1_700_000_000_000_000u64 + 2500 * k));
        }
        let s = infer(&t).unwrap();
        assert_eq!(s.tau0_s, 0.0025);
        assert_eq!(s.unit_s, 1e-6);
        let s = infer("t gx\n0 1\n0.01 1\n0.02 1\n0.03 1\n").unwrap();
        assert_eq!(s.tau0_s, 0.01);
        assert_eq!(s.unit_s, 1.0);
        let s = infer("t_ms,gx\n0,1\n4,1\n8,1\n12,1\n").unwrap();
        assert_eq!(s.tau0_s, 0.004);
        // Seconds from 0 printed to the ms: by 18 s a 5-ms step reads 0.00499999999999989 as
        // f64 (the first stamp, 0, has no rounding to judge by); the step is 0.005.
        let mut t = String::from("time,gx\n");
        for k in 0..4000u64 {
            t.push_str(&format!("{:.3},1\n", k as f64 * 0.005));
        }
        assert_eq!(infer(&t).unwrap().tau0_s, 0.005);
    }

    /// What is refused: no time column, an irregular one, and one whose step is not a sampling
    /// step in seconds (nanoseconds from 0 with no unit named).
    #[test]
    fn refusals_ask_for_tau0() {
        let e = infer("gx,gy\n1,2\n3,4\n").unwrap_err().to_string();
        assert!(e.contains("no time column"), "{e}");
        let e = infer("time,gx\n0,1\n1,1\n3,1\n7,1\n15,1\n31,1\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("irregular"), "{e}");
        let e = infer("time,gx\n0,1\n5000000,1\n10000000,1\n15000000,1\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a sampling step"), "{e}");
    }
}
