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

/// The output rates of an Xsens DOT (Hz), whose `SampleTimeFine` counts us: a step of
/// `1e6 / rate` is a DOT's, read in us, not in an MTi's 100 us (its 1 Hz steps by 10000, which
/// no DOT rate gives).
const DOT_RATES_HZ: [f64; 9] = [1.0, 4.0, 10.0, 12.0, 15.0, 20.0, 30.0, 60.0, 120.0];

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
    /// The channels the run analyses hold values on every `every`-th row only (1: on every
    /// row): rows where all are empty are no samples ([`TextOptions::sparse_rows`]), and the
    /// step is read between the others.
    pub every: usize,
    /// Channels with values on every k-th row only beside channels with values on every row
    /// (name, k): analysed together with those, they have one-sample stretches and no curve.
    pub slow: Vec<(String, usize)>,
}

impl std::fmt::Display for InferredStep {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let unit = super::time_column::unit_name(self.unit_s);
        if self.steps == 0 {
            // Not read off stamps: a header's step (`Delta_X`).
            return write!(
                f,
                "tau0 {} s from {}'s {}",
                crate::ranges::show(self.tau0_s),
                self.unit_from,
                self.column
            );
        }
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
        )?;
        if self.every > 1 {
            write!(
                f,
                "; the channels hold a value on every {} row only: the rows between are no samples",
                ordinal(self.every)
            )?;
        }
        Ok(())
    }
}

/// `2nd`, `3rd`, `4th`, ...
pub fn ordinal(k: usize) -> String {
    let suffix = match (k % 10, k % 100) {
        (1, x) if x != 11 => "st",
        (2, x) if x != 12 => "nd",
        (3, x) if x != 13 => "rd",
        _ => "th",
    };
    format!("{k}{suffix}")
}

/// The unit a clock since 1970 has for a stamp of this size, if it looks like one.
fn epoch_unit(stamp: f64) -> Option<f64> {
    // 1e9 s is 2001; 4e9 s is 2096.
    [1.0, 1e-3, 1e-6, 1e-9]
        .into_iter()
        .find(|&u| (1e9..4e9).contains(&(stamp * u)))
}

/// Seconds in a day: the unit of serial dates ([`serial_days`]).
pub const SECONDS_PER_DAY: f64 = 86_400.0;

/// What stamps without a unit say of serial dates in days ([`serial_days`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Serial {
    /// Not serial dates.
    No,
    /// Serial dates, printed finely enough to tell the step.
    Days,
    /// Serial dates printed to too few decimals: their steps are whole quanta near the step
    /// itself (7 decimals of a day are 8.6 ms), or 0.
    TooCoarse,
}

/// Whether stamps without a unit are serial dates in days, as Excel (days since 1900, about
/// 46000 in 2026) and MATLAB's `datenum` (days since year 0, about 740000) write a time:
/// fractions of a day between 1e4 and 1e6 whose median step (`median`, of the steps forward),
/// read as seconds, would be a rate above 50 kHz, and read as days a step between 0.1 ms and
/// 1.728 s (a rate of 0.58 Hz to 10 kHz); and whether they tell the step: hardly a step of 0,
/// and nine steps in ten within 10% of the median.
fn serial_days(stamps: &[f64], median: f64) -> Serial {
    let finite: Vec<f64> = stamps.iter().copied().filter(|t| t.is_finite()).collect();
    let looks = !finite.is_empty()
        && finite.iter().all(|t| (1e4..1e6).contains(t))
        && finite.iter().any(|t| t.fract() != 0.0)
        && median < 2e-5
        && (1e-4..=1.728).contains(&(median * SECONDS_PER_DAY));
    if !looks {
        return Serial::No;
    }
    let steps: Vec<f64> = finite.windows(2).map(|w| w[1] - w[0]).collect();
    let zero = steps.iter().filter(|d| **d == 0.0).count();
    let close = steps
        .iter()
        .filter(|d| ((*d - median) / median).abs() <= 0.1)
        .count();
    if zero * 100 > steps.len() || close * 10 < steps.len() * 9 {
        Serial::TooCoarse
    } else {
        Serial::Days
    }
}

/// The step a LabVIEW Measurement file's `Delta_X` gives (s), when it is a sampling step.
fn lvm_step(dx: f64) -> Result<InferredStep, String> {
    let tau0_s = round_significant(dx, 12);
    if crate::ranges::check_tau0(tau0_s).is_err() || tau0_s > 10.0 {
        return Err(format!(
            "--tau0 is required: the LabVIEW header's Delta_X is {} s, not a sampling step",
            crate::ranges::show(tau0_s)
        ));
    }
    Ok(InferredStep {
        tau0_s,
        column: "Delta_X".into(),
        unit_s: 1.0,
        unit_from: "the LabVIEW header",
        steps: 0,
        regular: 0,
        every: 1,
        slow: Vec::new(),
    })
}

/// `x` rounded to `digits` significant decimal digits. A power of ten at or above one
/// divides, one below it multiplies: each exact, so `999936` to one digit is `1000000`, not
/// `999999.9999999999`.
pub(crate) fn round_significant(x: f64, digits: i32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let power = x.abs().log10().floor() as i32 + 1 - digits;
    if power >= 0 {
        let p = 10f64.powi(power);
        (x / p).round() * p
    } else {
        let p = 10f64.powi(-power);
        (x * p).round() / p
    }
}

/// `x` with the fewest significant digits (up to 15) that stay within `resolution` of it
/// (itself when none do): a step read off stamps, as their resolution or jitter tells it.
pub(crate) fn shortest_within(x: f64, resolution: f64) -> f64 {
    (1..=15)
        .map(|digits| round_significant(x, digits))
        .find(|r| (r - x).abs() <= resolution)
        .unwrap_or(x)
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
        // A LabVIEW Measurement file without an x column: its header's `Delta_X`.
        if let Some(dx) = reader.lvm_delta_x() {
            return lvm_step(dx).map_err(usage);
        }
        return Err(usage(
            "--tau0 is required: the text columns have no time column (a header name time, t, \
             timestamp or time_s, with or without a unit, or --time-column NAME)"
                .into(),
        ));
    };
    let (rows, repeats) = reader
        .take_stamps(LOOK_ROWS)
        .map_err(|e| usage(e.to_string()))?;
    // A file that merges a slower stream with faster ones: channels with a value on every k-th
    // row only. When every channel the run analyses is such (`--channels ax` of a merged file)
    // the rows where all are empty are no samples and the step is read between the others.
    let names = reader.names().to_vec();
    let width = names.len();
    let strides: Vec<usize> = (0..width)
        .map(|c| row_stride(rows.iter().map(|(_, p)| p[c])))
        .collect();
    let every = row_stride(rows.iter().map(|(_, p)| p.iter().any(|&x| x)));
    let slow: Vec<(String, usize)> = if every == 1 {
        names
            .iter()
            .zip(&strides)
            .filter(|(_, &k)| k > 1)
            .map(|(n, &k)| (n.clone(), k))
            .collect()
    } else {
        Vec::new()
    };
    let stamps: Vec<f64> = rows
        .iter()
        .filter(|(_, p)| every == 1 || p.iter().any(|&x| x))
        .map(|(t, _)| *t)
        .collect();
    let mut steps: Vec<f64> = stamps
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| d.is_finite() && *d > 0.0)
        .collect();
    // Steps of 0 between rows that are not the same row twice (those are passed over): stamps
    // written more coarsely than the rows come (to the second at 100 Hz; a host's stamp on
    // each packet of samples), whose steps forward are not the sampling step. A burst of rows
    // under the first stamp (a buffer flushed at the start) is not counted when the stamps
    // after it do not repeat.
    let zeros_in = |s: &[f64]| s.windows(2).filter(|w| w[1] == w[0]).count();
    let lead = stamps
        .windows(2)
        .take_while(|w| w[1] == w[0] || !w[0].is_finite())
        .count();
    let after_lead = zeros_in(&stamps[lead..]);
    let zeros = if lead > 0 && after_lead * 100 <= steps.len() + after_lead {
        after_lead
    } else {
        zeros_in(&stamps)
    };
    if steps.len() < 2 {
        let read = stamps.iter().filter(|t| t.is_finite()).count();
        let problem = match reader.unread_stamp() {
            Some(cell) if read < 2 => format!(
                "its stamps are neither numbers nor times this reads (the first: `{cell}`; a \
                 time of day is read with its seconds, `10:41:07.25`, or at the minute after a \
                 date, `2026-12-03 10:41`)"
            ),
            _ if zeros > 0 => format!(
                "it repeats its stamps ({zeros} of the steps between its first {} rows are 0, \
                 fewer than two forward): it is written more coarsely than the rows come",
                stamps.len()
            ),
            _ => format!(
                "it has fewer than two steps forward in its first {} rows",
                stamps.len()
            ),
        };
        return Err(usage(format!(
            "--tau0 is required: the time column `{column}`: {problem}"
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
    // `unit_guessed`: seconds for want of anything that says so.
    let (unit_s, unit_from, unit_guessed) = match time_column_unit(&column).flatten() {
        Some(u) => (u, "its name", false),
        // uORB's `timestamp`: us since boot (`super::px4_export`).
        None if reader.px4_export() && super::px4_export::boot_stamps(&column, &stamps) => (
            super::px4_export::TIMESTAMP_UNIT_S,
            "a PX4 export's timestamp, since boot",
            false,
        ),
        None => match epoch_unit(first) {
            Some(u) => (u, "its stamps, a clock since 1970", false),
            None => match serial_days(&stamps, median) {
                Serial::Days => (
                    SECONDS_PER_DAY,
                    "its stamps: serial dates in days (Excel's, MATLAB's datenum)",
                    false,
                ),
                Serial::TooCoarse => {
                    return Err(usage(format!(
                        "--tau0 is required: the time column `{column}` holds serial dates in \
                         days (Excel's, MATLAB's datenum) printed to too few decimals to tell \
                         the step (its steps are 0 or whole quanta near the step itself; 1e-7 \
                         days is 8.64 ms); give --tau0, or write the stamps with more decimals"
                    )))
                }
                Serial::No => (1.0, "no unit given: seconds", true),
            },
        },
    };
    // Stamps that repeat where the rows go on (more than 1 step in 100 of 0) and whose mean
    // step, zeros counted, is below their median step forward: the steps forward are the
    // stamps' resolution, not the sampling step (a clock jittering about its step, with steps of
    // 0 and of two steps, keeps its mean at the median and is read as before). The mean is that
    // of the steps of 0 and those forward up to three median steps: a dropout or a clock's
    // restart among the rows looked at is no step of the rows. Where stamps repeat so, rows that
    // repeat a stamp with the same values (passed over as written twice) are counted as steps of
    // 0 too: on a channel of few values (a counter), two samples under one stamp often agree.
    let total_of = |zeros: usize| {
        let near: Vec<f64> = steps
            .iter()
            .copied()
            .filter(|d| *d <= 3.0 * median)
            .collect();
        let n = near.len() + zeros;
        (n, near.iter().sum::<f64>() / n as f64)
    };
    if zeros * 100 > steps.len() + zeros {
        let (total, mean) = total_of(zeros + repeats);
        let zeros = zeros + repeats;
        if mean > 0.0 && mean < median * (1.0 - 0.005) {
            let s = |x: f64| crate::ranges::show(round_significant(x, 4));
            return Err(usage(format!(
                "--tau0 is required: the time column `{column}` repeats its stamps ({zeros} of \
                 the {total} steps between its first rows are 0, the median step forward {} \
                 s): the rows come about one each {} s by the mean step ({} Hz), more often \
                 than the stamps resolve (their smallest step forward {} s); give --tau0",
                s(median * unit_s),
                s(mean * unit_s),
                s(1.0 / (mean * unit_s)),
                s(steps[0] * unit_s),
            )));
        }
    }
    // Stamps that step by one or two of their resolution (833 Hz stamped to the ms: steps of
    // 1 ms, and of 2 ms one in five): the median is the resolution, and each longer step would
    // be read as a missing sample. When more than one step in ten is longer than the median
    // beyond the tolerance (up to three medians) and the mean step, zeros counted, is 5% above
    // it, the rows do not come at the median step: refused, as a file missing one sample in a
    // few would be (its step is then for the user to say).
    let longer = steps
        .iter()
        .filter(|d| **d > median * (1.0 + TOLERANCE) && **d <= 3.0 * median)
        .count();
    let (total, mean_step) = total_of(zeros);
    if longer * 10 > total && mean_step > median * 1.05 {
        let s = |x: f64| crate::ranges::show(round_significant(x, 4));
        return Err(usage(format!(
            "--tau0 is required: the time column `{column}` steps by its median {} s in only \
             {regular} of {total} steps and by up to three times that in {longer}: the rows \
             come about one each {} s by the mean step ({} Hz), with stamps written to {} s, \
             or one sample in {} is missing; give --tau0",
            s(median * unit_s),
            s(mean_step * unit_s),
            s(1.0 / (mean_step * unit_s)),
            s(median * unit_s),
            (total as f64 / longer as f64).round()
        )));
    }
    // Stamps that alternate about the step (4 and 6 ms for a 5 ms stream: a clock of 1 ms
    // stamping 200 Hz, or two stamps a packet): the median is the longer of the two, half the
    // steps are then within the tolerance of it, and each shorter one would be read as a
    // sample off its step. When more than one step in ten is shorter than the median beyond
    // the tolerance and the mean step is 5% below it: refused. Before (session 42) a `time_ms`
    // of 4, 6, 4, 6 read as 6 ms, N 9% low and the run 20% long.
    let shorter = steps
        .iter()
        .filter(|d| **d < median * (1.0 - TOLERANCE))
        .count();
    if shorter * 10 > total && mean_step < median * 0.95 {
        let s = |x: f64| crate::ranges::show(round_significant(x, 4));
        return Err(usage(format!(
            "--tau0 is required: the time column `{column}` steps by its median {} s in only \
             {regular} of {total} steps and by less in {shorter}: the rows come about one each \
             {} s by the mean step ({} Hz); give --tau0",
            s(median * unit_s),
            s(mean_step * unit_s),
            s(1.0 / (mean_step * unit_s)),
        )));
    }
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
    // A clock with jitter (a phone's, a host's stamps: 0.0025 s steps +- 20 us) gives a median
    // step such as 0.002499751 whose last digits are noise: the step is then the shortest
    // decimal within three standard errors of the mean of the regular steps (sd / n for n steps
    // of standard deviation sd between jittered stamps), 0.0025 there; 104 Hz stays 0.0096154.
    // The steps telescope only when none is left out: where every step is under 1.5 medians
    // (no sample missing) and none is 0, all of them are the regular ones, so a jitter wide
    // enough to throw some past the tolerance leaves the mean exact. Before (session 42) stamps
    // jittered by +-20% kept only 3430 of 4000 steps, whose mean, no longer telescoping, was off
    // by far more than sd / n: tau0 read 0.010007 s where the stamps' span gives 0.0100000.
    let all_regular = zeros == 0 && steps.iter().all(|d| *d < 1.5 * median);
    let near: Vec<f64> = steps
        .iter()
        .copied()
        .filter(|d| all_regular || ((d - median) / median).abs() <= TOLERANCE)
        .collect();
    let n = near.len() as f64;
    let near_mean = near.iter().sum::<f64>() / n;
    let sd =
        (near.iter().map(|d| (d - near_mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0)).sqrt();
    // Jitter past a quarter step leaves steps out, and the mean of those kept no longer
    // telescopes: a review's 100 Hz stamps jittered by +-28.5% read 0.00999 s. Each stamp is
    // then placed on the grid the stamps lie on (`super::stamp_grid`, the jitter counted once,
    // missing samples counted as whole steps) and the step is the stamps' span over the
    // samples it holds, which telescopes again.
    let rising = stamps.len() > 2 && stamps.windows(2).all(|w| w[1] > w[0]);
    let on_grid = (zeros == 0 && !all_regular && rising)
        .then(|| super::stamp_grid::sample_numbers(&stamps, median))
        .flatten()
        .and_then(|k| {
            let samples = *k.last()? as f64;
            let span = stamps[stamps.len() - 1] - stamps[0];
            let step = span / samples;
            (samples > 0.0 && ((step - median) / median).abs() <= TOLERANCE).then_some(step)
        });
    let mean = on_grid.unwrap_or(near_mean);
    // Where the jitter is what limits, the mean step is the estimate (the steps of jittered
    // stamps telescope: their mean's error is about sd / n, not sd / sqrt(n)), and the median
    // only tells whether a round number is within reach.
    let jitter = 3.0 * sd / n;
    // Serial dates printed to a few decimals of a day step by whole quanta (1e-10 days is
    // 8.6 us): the median step is a quantum off, the mean of the steps is not.
    // The mean of n steps is off by about twice a stamp's resolution over n (they telescope).
    let (center, resolution) = if unit_s == SECONDS_PER_DAY {
        (mean, (2.0 * jitter).max(2.0 * resolution / n))
    } else if jitter > resolution || sd > resolution {
        // Steps that scatter beyond the stamps' resolution are a jittered clock's, whose median
        // step is no estimate (a review's EuRoC stamps in ns since 1970, resolved to 737 ns,
        // jittered by about +-18%: median 4995712 ns, read 0.004996 s; their mean 5000028 ns).
        (mean, jitter.max(resolution))
    } else {
        (median, resolution)
    };
    // Days are no power of ten of a second: the step is rounded in seconds (1.1574e-7 days
    // is 0.01 s, whose shortest decimal in days would not be).
    let scale = if unit_s == SECONDS_PER_DAY {
        unit_s
    } else {
        1.0
    };
    let step = shortest_within(center * scale, resolution * scale) / scale;
    // `SampleTimeFine` counts 100 us on an Xsens MTi (1-2000 Hz: steps of 5 to 10000) but us
    // on an Xsens DOT (1 to 120 Hz at its own rates: steps of 1e6 / rate, 8333 or more).
    let dot = unit_s == 1e-4
        && column.trim() == "SampleTimeFine"
        && DOT_RATES_HZ
            .iter()
            .any(|r| (step * r / 1e6 - 1.0).abs() <= 0.01);
    let (unit_s, unit_from) = if dot {
        (
            1e-6,
            "its steps: an Xsens DOT's clock counts us (an MTi's counts 100 us and never \
             steps by 1e6 / a DOT's rate)",
        )
    } else {
        (unit_s, unit_from)
    };
    let tau0_s = round_significant(step * unit_s, 15);
    if crate::ranges::check_tau0(tau0_s).is_err() || tau0_s > 10.0 {
        return Err(usage(format!(
            "--tau0 is required: the time column `{column}` gives a step of {} s ({unit_from}), \
             not a sampling step; name the column's unit (`{column} [ms]`) or give --tau0",
            crate::ranges::show(tau0_s)
        )));
    }
    // Whole-number stamps read as seconds for want of a unit (a counter of ms since boot
    // stepping by 4 reads as tau0 4 s): no inertial unit samples each 2 s or slower, so the
    // step is asked for. Before (session 42) this was a warning and the run went on, every
    // tau 1000 times too long for a `time` counting ms.
    let whole = stamps
        .iter()
        .filter(|t| t.is_finite())
        .all(|t| t.fract() == 0.0);
    if unit_guessed && whole && tau0_s >= 2.0 {
        return Err(usage(format!(
            "--tau0 is required: the time column `{column}` holds whole numbers stepping by {}, \
             which read as seconds would be a step of {} s: if they count ms or us, name the \
             unit (`{column} [ms]`) or give --tau0 (--tau0 {} for ms)",
            crate::ranges::show(step),
            crate::ranges::show(tau0_s),
            crate::ranges::show(tau0_s * 1e-3)
        )));
    }
    Ok(InferredStep {
        tau0_s,
        column,
        unit_s,
        unit_from,
        steps: steps.len(),
        regular,
        every,
        slow,
    })
}

/// Every how many rows a column holds a value, from whether it does in each row looked at:
/// `k >= 2` when at least nine in ten of the steps between its values are `k` rows (a stream
/// logged at 1/k of the file's row rate), else 1 (a value on every row, or gaps that come as
/// stretches). Fewer than 16 values say 1.
pub fn row_stride(present: impl Iterator<Item = bool>) -> usize {
    let at: Vec<usize> = present
        .enumerate()
        .filter(|(_, p)| *p)
        .map(|(i, _)| i)
        .collect();
    if at.len() < 16 {
        return 1;
    }
    let mut steps: Vec<usize> = at.windows(2).map(|w| w[1] - w[0]).collect();
    steps.sort_unstable();
    let k = steps[steps.len() / 2];
    let at_k = steps.iter().filter(|&&d| d == k).count();
    if k >= 2 && 10 * at_k >= 9 * steps.len() {
        k
    } else {
        1
    }
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

    /// PX4's CSV export: `timestamp` counts us since boot (a whole number with no unit in its
    /// name, far below a clock since 1970), jittered by a few us about a 4-ms step.
    #[test]
    fn px4_timestamps_are_microseconds() {
        let mut t = String::from("timestamp,gyro_rad[0],gyro_integral_dt\n");
        for k in 0..400u64 {
            t.push_str(&format!(
                "{},0.001,4000\n",
                81_220_117 + 4000 * k + (k * 7) % 5
            ));
        }
        let s = infer(&t).unwrap();
        assert_eq!(s.tau0_s, 0.004);
        assert_eq!(s.unit_s, 1e-6);
        assert!(s.unit_from.contains("PX4"), "{}", s.unit_from);
        // A logger's `gyro[0]` beside seconds is no PX4 export: seconds stay seconds.
        let mut l = String::from("timestamp,gyro[0],gyro[1]\n");
        for k in 0..40 {
            l.push_str(&format!("{:.2},0.1,0.2\n", k as f64 * 0.01));
        }
        assert_eq!(infer(&l).unwrap().tau0_s, 0.01);
        // The same stamps under a logger's header are seconds: no sampling step, refused.
        let t = t.replacen("gyro_rad[0],gyro_integral_dt", "gx,gy", 1);
        let e = infer(&t).unwrap_err().to_string();
        assert!(e.contains("not a sampling step"), "{e}");
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

    /// A LabVIEW Measurement file without an x column: the step is its header's `Delta_X`; a
    /// `Delta_X` that is no sampling step (1 h) asks for --tau0.
    #[test]
    fn a_labview_file_gives_its_delta_x() {
        let lvm = |dx: &str| {
            format!(
                "LabVIEW Measurement\t\nX_Columns\tNo\n***End_of_Header***\t\n\nChannels\t2\t\n\
                 Delta_X\t{dx}\t{dx}\t\n***End_of_Header***\t\ngx\tgy\tComment\n\
                 0.1\t0.2\t\n0.3\t0.4\t\n"
            )
        };
        let s = infer(&lvm("4.000000E-3")).unwrap();
        assert_eq!((s.tau0_s, s.column.as_str()), (0.004, "Delta_X"));
        assert_eq!(
            s.to_string(),
            "tau0 0.004 s from the LabVIEW header's Delta_X"
        );
        let e = infer(&lvm("3600")).unwrap_err().to_string();
        assert!(e.contains("Delta_X is 3600 s, not a sampling step"), "{e}");
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

    /// A merged multi-rate file: `ax` on every other row beside `gx` on every row is said to be
    /// slow; analysed alone, its rows are the samples and the step is read between them.
    #[test]
    fn a_stream_on_every_other_row() {
        let mut t = String::from("time,gx,ax\n");
        for k in 0..400 {
            let ax = if k % 2 == 0 { "0.5" } else { "" };
            t.push_str(&format!("{:.3},1,{ax}\n", k as f64 * 0.005));
        }
        let s = infer(&t).unwrap();
        assert_eq!((s.tau0_s, s.every), (0.005, 1));
        assert_eq!(s.slow, [("ax".to_string(), 2)]);
        let opts = TextOptions {
            channels: Some(vec!["ax".into()]),
            ..TextOptions::default()
        };
        let s = infer_tau0(t.as_bytes(), Path::new("m.csv"), &opts).unwrap();
        assert_eq!((s.tau0_s, s.every, s.slow.len()), (0.01, 2, 0));
        // Read so, its 200 values are 200 samples, no gap; a missing one is a gap.
        let read = |t: &str| {
            let opts = TextOptions {
                channels: Some(vec!["ax".into()]),
                tau0_s: Some(0.01),
                sparse_rows: true,
                ..TextOptions::default()
            };
            let mut r = TextReader::with_options(t.as_bytes(), Path::new("m.csv"), &opts).unwrap();
            let mut out = Vec::new();
            while r.read_rows(&mut out, 64).unwrap() > 0 {}
            out.chunks(2).map(|c| c[1]).collect::<Vec<f64>>()
        };
        let ax = read(&t);
        assert_eq!(ax.len(), 200);
        assert!(ax.iter().all(|&x| x == 0.5));
        let cut = t.replacen("0.500,1,0.5\n", "0.500,1,\n", 1);
        let ax = read(&cut);
        assert_eq!(ax.len(), 200);
        assert_eq!(ax.iter().filter(|x| x.is_nan()).count(), 1);
        // Stretches of empty rows are gaps, not a slower stream.
        assert_eq!(row_stride((0..100).map(|i| !(40..60).contains(&i))), 1);
        assert_eq!(row_stride((0..100).map(|i| i % 3 == 0)), 3);
        assert_eq!(row_stride((0..10).map(|i| i % 2 == 0)), 1);
    }

    /// Whole-number stamps stepping by 4, which read as seconds would be a 4-s step, ask for
    /// the step (were a warning before session 42); a 1-s clock is read.
    #[test]
    fn whole_number_stamps_are_doubted() {
        let e = infer("time,gx\n1000,1\n1004,2\n1008,1\n1012,2\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`time [ms]`") && e.contains("--tau0 0.004 for ms"),
            "{e}"
        );
        let s = infer("time,gx\n0,1\n1,2\n2,1\n3,2\n").unwrap();
        assert_eq!(s.tau0_s, 1.0);
        let s = infer("time_ms,gx\n0,1\n4,2\n8,1\n12,2\n").unwrap();
        assert_eq!(s.tau0_s, 0.004);
    }

    /// Serial dates in days (Excel's near 46000, MATLAB's datenum near 740000, printed to 10
    /// decimals): tau0 read in seconds, rounded there (0.01 s, not 0.0099999x); a gap of one
    /// sample found in them. Seconds from 0 at 20 kHz, or in the same range stepping by 2 ms,
    /// stay seconds.
    #[test]
    fn serial_dates_are_days() {
        for (start, gyro) in [(46_000.3, "gx"), (739_954.25, "gyro_x")] {
            let mut t = format!("time,{gyro}\n");
            for k in (0..400u64).filter(|&k| k != 200) {
                t.push_str(&format!("{:.10},1\n", start + k as f64 * 0.01 / 86_400.0));
            }
            let s = infer(&t).unwrap();
            assert_eq!((s.tau0_s, s.unit_s), (0.01, SECONDS_PER_DAY), "{start}");
            assert!(
                s.to_string()
                    .contains("unit day from its stamps: serial dates"),
                "{s}"
            );
            let opts = TextOptions {
                tau0_s: Some(s.tau0_s),
                ..TextOptions::default()
            };
            let mut r = TextReader::with_options(t.as_bytes(), Path::new("t.csv"), &opts).unwrap();
            let mut out = Vec::new();
            while r.read_rows(&mut out, 64).unwrap() > 0 {}
            assert_eq!(out.len(), 400, "{start}: the missing sample a gap");
            assert!(out[200].is_nan());
        }
        let fast: String = std::iter::once("time,gx\n".to_string())
            .chain((0..400).map(|k| format!("{:.5},1\n", k as f64 * 5e-5)))
            .collect();
        assert_eq!(infer(&fast).unwrap().unit_s, 1.0);
        // Seconds since boot, 3 h in, at 10 and 20 kHz: seconds, not days (a review found
        // them read in days, tau0 8.64 and 4.32 s).
        for step in [1e-4, 5e-5] {
            let boot: String = std::iter::once("time,gx\n".to_string())
                .chain((0..400).map(|k| format!("{:.6},1\n", 10_800.0 + k as f64 * step)))
                .collect();
            let s = infer(&boot).unwrap();
            assert_eq!((s.unit_s, s.tau0_s), (1.0, step), "{step}");
        }
        // Excel's dates to 7 decimals at 100 Hz step by 8.64 or 17.28 ms: refused, not read
        // as a step of 8.64 ms; to 8 decimals they tell 0.01 s. MATLAB's at 104 Hz keep the
        // step's digits.
        let excel =
            |decimals: usize, start: f64, rate: f64| -> String {
                std::iter::once("time,gx\n".to_string())
                    .chain((0..2000).map(|k| {
                        format!("{:.*},1\n", decimals, start + k as f64 / rate / 86_400.0)
                    }))
                    .collect()
            };
        let e = infer(&excel(7, 46_000.3, 100.0)).unwrap_err().to_string();
        assert!(e.contains("printed to too few decimals"), "{e}");
        assert_eq!(infer(&excel(8, 46_000.3, 100.0)).unwrap().tau0_s, 0.01);
        let s = infer(&excel(10, 739_954.25, 104.0)).unwrap();
        assert!((s.tau0_s * 104.0 - 1.0).abs() < 1e-5, "{}", s.tau0_s);
        let slow: String = std::iter::once("time,gx\n".to_string())
            .chain((0..400).map(|k| format!("{:.3},1\n", 20_000.0 + k as f64 * 2e-3)))
            .collect();
        assert_eq!(infer(&slow).unwrap().tau0_s, 0.002);
    }

    /// Stamps of a clock with jitter: the step is the nominal one the jitter cannot tell from
    /// the median, not the median's noisy digits; a rate truly off the round number (0.00251 s)
    /// beyond three standard errors is kept.
    #[test]
    fn a_jittery_clock_gives_its_nominal_step() {
        let jittered = |step: f64| {
            let mut t = String::from("Time (s),gx\n");
            for k in 0..4000u64 {
                // A deterministic jitter of each stamp by +-20 us (a Weyl sequence), no
                // generator needed.
                let u = ((k as f64 * 0.618_033_988_75) % 1.0) - 0.5;
                let x = k as f64 * step + 4e-5 * u;
                t.push_str(&format!("{x:.9},1\n"));
            }
            t
        };
        assert_eq!(infer(&jittered(0.0025)).unwrap().tau0_s, 0.0025);
        assert_eq!(infer(&jittered(0.00251)).unwrap().tau0_s, 0.00251);
        // 104 Hz, not a round step: kept to the digits the stamps tell (0.0096154 s).
        let s = infer(&jittered(1.0 / 104.0)).unwrap();
        assert!((s.tau0_s * 104.0 - 1.0).abs() < 1e-5, "{}", s.tau0_s);
    }

    /// Stamps of a host that stamps each sample as it receives it, uniform jitter of +-28.5% of
    /// the step (a review's 100 Hz file, read 0.00999 s: the steps past a quarter of it were
    /// left out and the mean of the rest no longer telescoped): 0.01 s, also with samples
    /// missing among them, in five seeds.
    #[test]
    fn stamps_jittered_past_a_quarter_step_give_the_nominal_step() {
        use rand::{RngExt, SeedableRng};
        for seed in 0..5 {
            let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
            let mut t = String::from("time,gx\n");
            for k in 0..4000u64 {
                let x = 0.01 * (k as f64 + 0.57 * (rng.random::<f64>() - 0.5));
                if k % 997 != 500 {
                    t.push_str(&format!("{x:.6},1\n"));
                }
            }
            assert_eq!(infer(&t).unwrap().tau0_s, 0.01, "seed {seed}");
        }
    }

    /// EuRoC stamps in ns since 1970 (resolved to 737 ns as read), 200 Hz, a host's jitter of
    /// +-18% (the mean step's uncertainty, 3 sd / n, under that resolution): the steps' median
    /// is off the step by many resolutions, their mean is not: 0.005 s in five seeds (a
    /// review's file read 0.004996 s).
    #[test]
    fn epoch_nanoseconds_jittered_give_the_nominal_step() {
        use rand::{RngExt, SeedableRng};
        for seed in 0..5 {
            let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
            let mut t = String::from("#timestamp [ns],w_RS_S_x [rad s^-1]\n");
            for k in 0..4000u64 {
                let x = 1_662_259_107_000_000_000u64 as f64
                    + 5e6 * (k as f64 + 0.36 * (rng.random::<f64>() - 0.5));
                t.push_str(&format!("{},0.1\n", x.round() as u64));
            }
            assert_eq!(infer(&t).unwrap().tau0_s, 0.005, "seed {seed}");
        }
    }

    /// Stamps written more coarsely than the rows come are refused with the rate their mean
    /// step gives; a clock at its resolution, rows written twice and a burst at the start keep
    /// their step; stamps that are no time say which.
    #[test]
    fn stamps_coarser_than_the_rows_are_refused() {
        let file = |n: usize, stamp: &dyn Fn(usize) -> String| {
            let mut t = String::from("time,gx\n");
            for k in 0..n {
                t.push_str(&format!("{},{}\n", stamp(k), k % 7));
            }
            t
        };
        // 100 Hz stamped to the second (`2026-12-03 10:00:07`): the median step forward is 1 s.
        let clock = |s: f64| {
            format!(
                "2026-12-03 {:02}:{:02}:{:02}",
                10 + (s / 3600.0) as u64,
                (s % 3600.0 / 60.0) as u64,
                (s % 60.0) as u64
            )
        };
        let e = infer(&file(5000, &|k| clock(k as f64 * 0.01)))
            .unwrap_err()
            .to_string();
        assert!(e.contains("repeats its stamps"), "{e}");
        assert!(e.contains("their smallest step forward 1 s"), "{e}");
        assert!(
            e.contains("about one each 0.01 s") && e.contains("100 Hz"),
            "{e}"
        );
        // 2 kHz stamped to the ms: half the steps 0, the others 1 ms (was read as 1 ms).
        let e = infer(&file(4001, &|k| format!("{:.3}", (k / 2) as f64 * 0.001)))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("about one each 5e-4 s") && e.contains("2000 Hz"),
            "{e}"
        );
        // 1 kHz stamped to the ms with a jitter of up to a ms: steps of 0, 1 and 2 ms whose
        // median forward is 2 ms (read as the step before); the span tells 1000 Hz.
        let jitter = |k: usize| ((k as f64 * 0.618_033_988_75) % 1.0) * 0.0009;
        let e = infer(&file(4001, &|k| {
            format!("{:.3}", k as f64 * 0.001 + jitter(k))
        }))
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("about one each 0.001 s") && e.contains("(1000 Hz)"),
            "{e}"
        );
        // A clock at 1 kHz stamped to the ms without jitter is read as before.
        let s = infer(&file(4001, &|k| format!("{:.3}", k as f64 * 0.001))).unwrap();
        assert_eq!(s.tau0_s, 0.001);
        // Every row written twice (a logger's repeat, the same stamp and values): passed over
        // as the run does; two rows to a stamp with their own values are two samples.
        let pairs = infer(&file(4000, &|k| format!("{:.2}", (k / 2) as f64 * 0.01)));
        let twice = {
            let mut t = String::from("time,gx\n");
            for k in 0..2000 {
                let row = format!("{:.2},{}\n", k as f64 * 0.01, k % 7);
                t.push_str(&row);
                t.push_str(&row);
            }
            t
        };
        assert!(
            pairs.is_err(),
            "rows with one stamp and two values are not a repeat"
        );
        assert_eq!(infer(&twice).unwrap().tau0_s, 0.01);
        // 104 Hz stamped to 0.01 s: 4 steps in 100 of 0 (was read as 0.01 s, 4% off).
        let e = infer(&file(4001, &|k| {
            format!("{:.2}", (k as f64 / 104.0 * 100.0).floor() / 100.0)
        }))
        .unwrap_err()
        .to_string();
        assert!(e.contains("(104 Hz)"), "{e}");
        // 1.5 kHz stamped to the ms with 2300 samples missing, and 1.1 kHz with a clock that
        // restarts: neither the dropout nor the restart is a step of the rows (the first
        // version's span read them as such).
        let mut t = String::from("time,gx\n");
        for k in (0..6000).filter(|k| !(1000..3300).contains(k)) {
            t.push_str(&format!(
                "{:.3},{}\n",
                (k as f64 / 1.5).floor() / 1000.0,
                k % 7
            ));
        }
        let e = infer(&t).unwrap_err().to_string();
        assert!(e.contains("(1500 Hz)"), "{e}");
        let e = infer(&file(4001, &|k| {
            let k = if k < 3000 { k } else { k - 3000 };
            format!("{:.3}", (k as f64 / 1.1).floor() / 1000.0)
        }))
        .unwrap_err()
        .to_string();
        assert!(e.contains("(1100 Hz)"), "{e}");
        // 2 kHz stamped to the ms on a channel of few values: two samples under one stamp often
        // agree, and count as samples, not as a row written twice.
        let e = infer(
            &file(4001, &|k| format!("{:.3}", (k / 2) as f64 * 0.001)).replace(",1\n", ",0\n"),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("(2000 Hz)"), "{e}");
        // 833 Hz stamped to the ms: steps of 1 and 2 ms, no zeros (was read as 1 ms, with a
        // missing sample at each 2 ms step); a clean file missing one sample in a hundred is
        // read as before.
        let e = infer(&file(4001, &|k| {
            format!("{:.3}", (k as f64 / 833.0 * 1000.0).floor() / 1000.0)
        }))
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("(833") && e.contains("one sample in 5 is missing"),
            "{e}"
        );
        let s = infer(&file(4001, &|k| {
            format!("{:.3}", (k + k / 99) as f64 * 0.001)
        }))
        .unwrap();
        assert_eq!(s.tau0_s, 0.001);
        // Stamps jittered by +-20% of the step (printed to 10 us): 0.01 s, as their span says
        // (was 0.010007 from the steps within a quarter of the median alone).
        let s = infer(&file(4001, &|k| {
            // splitmix64 of k: uniform in [0, 1)
            let mut z = (k as u64)
                .wrapping_add(1)
                .wrapping_mul(0x9e37_79b9_7f4a_7c15);
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            let u = ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64;
            format!("{:.5}", k as f64 * 0.01 + 0.002 * (2.0 * u - 1.0))
        }))
        .unwrap();
        assert_eq!(s.tau0_s, 0.01);
        // Stamps alternating 4 and 6 ms about a 5 ms stream (was read as 6 ms: half the steps
        // within a quarter of the median passed): refused with the mean step's rate.
        let e = infer(&file(4001, &|k| {
            format!("{:.3}", (5 * k - k % 2) as f64 * 0.001)
        }))
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("about one each 0.005 s") && e.contains("(200 Hz)"),
            "{e}"
        );
        // A clock jittering about its step keeps its step.
        let s = infer(&file(4001, &|k| {
            format!("{:.4}", k as f64 * 0.005 + [0.0, 0.0003, -0.0002][k % 3])
        }))
        .unwrap();
        assert_eq!(s.tau0_s, 0.005);
        // A burst of rows under the first stamp (a buffer flushed at the start), then 100 Hz:
        // read as 100 Hz.
        let s = infer(&file(4001, &|k| {
            format!("{:.3}", k.saturating_sub(250) as f64 * 0.01)
        }))
        .unwrap();
        assert_eq!(s.tau0_s, 0.01);
        // A time this does not read: said, with the cell.
        let e = infer(&file(100, &|k| format!("day {k}:x")))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("neither numbers nor times") && e.contains("`day 0:x`"),
            "{e}"
        );
    }

    /// Short dates with a two-digit year (Excel's `12/3/26 10:41:07.250`, Europe's
    /// `03.12.26`) give the step as the four-digit ones do, across midnight.
    #[test]
    fn two_digit_years_give_the_step() {
        for (fmt, day) in [("12/{d}/26", "3"), ("{d}.12.26", "03")] {
            let mut t = String::from("time,gx\n");
            for k in 0..3000u64 {
                // From 23:59:50 on the 3rd, 100 Hz: midnight after 1000 rows.
                let ms = (86_390_000 + k * 10) % 86_400_000;
                let d = if k < 1000 {
                    day.to_string()
                } else {
                    format!("{:0w$}", 4, w = day.len())
                };
                t.push_str(&format!(
                    "{} {:02}:{:02}:{:02}.{:03},1\n",
                    fmt.replace("{d}", &d),
                    ms / 3_600_000,
                    ms / 60_000 % 60,
                    ms / 1000 % 60,
                    ms % 1000
                ));
            }
            let s = infer(&t).unwrap();
            assert_eq!((s.tau0_s, s.regular), (0.01, s.steps), "{fmt}");
            assert_eq!(s.steps, 2999, "{fmt}: the step over midnight is one step");
        }
    }

    /// A slow stream on the odd rows (the first row empty) with a 1-s dropout: its own step,
    /// the dropout one gap of 100 samples (a review found the empty first row started the clock
    /// and ruled the time column out).
    #[test]
    fn a_slow_stream_on_odd_rows_keeps_its_gaps() {
        let mut t = String::from("time,gx,ax\n");
        for k in 0..800 {
            let present = k % 2 == 1 && !(401..=599).contains(&k);
            let ax = if present { "0.5" } else { "" };
            t.push_str(&format!("{:.3},1,{ax}\n", k as f64 * 0.005));
        }
        let opts = TextOptions {
            channels: Some(vec!["ax".into()]),
            ..TextOptions::default()
        };
        let s = infer_tau0(t.as_bytes(), Path::new("o.csv"), &opts).unwrap();
        assert_eq!((s.tau0_s, s.every), (0.01, 2));
        let opts = TextOptions {
            tau0_s: Some(0.01),
            sparse_rows: true,
            ..opts
        };
        let mut r = TextReader::with_options(t.as_bytes(), Path::new("o.csv"), &opts).unwrap();
        let mut out = Vec::new();
        while r.read_rows(&mut out, 64).unwrap() > 0 {}
        let ax: Vec<f64> = out.chunks(2).map(|c| c[1]).collect();
        assert_eq!(ax.len(), 400);
        assert_eq!(ax.iter().filter(|x| x.is_nan()).count(), 100);
    }
}
