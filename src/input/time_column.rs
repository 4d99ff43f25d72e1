//! The time column of text input used to find gaps: rows are one sampling step `tau0` apart, so a
//! jump of the time stamps by `k` steps (`k = round(dt / tau0) >= 2`, i.e. a jump of more than
//! about 1.5 tau0) means `k - 1` samples are missing: they become gap steps (NaN rows), exactly
//! as a counter jump of frames does, so the differences that span them are left out of the
//! variances (docs/theory.md section 1) and `t_data` counts them.
//!
//! The column's unit is decided at its first step: seconds, or ms, us or ns when the step is
//! `tau0` in one of those (logged). When the first step is none of these but most of the
//! [`FIRST_STEPS`] after it are `tau0` in one unit (a sample missing right after the first
//! row, the first stamp written twice), that unit is taken and the first step read in it as any
//! later one ([`TimeColumn::unit_from_first_steps`]). A column whose first steps agree on no
//! unit (a wrong `--tau0`, or a column that is not a time) is reported and only skipped, never
//! used. Before (session 42), one odd first step alone ruled the column out: a gap later in the
//! file was joined, unseen.
//!
//! Later steps that go backwards or repeat (`dt <= 0`) and steps that are not whole multiples
//! of `tau0` (more than a quarter step off) are counted and reported with their line numbers; a
//! row stamped backwards is taken as the next sample (the clock moves on one step from where it
//! was) and inserts nothing. When it went back by more than a step and the row after it steps
//! on by one `tau0` from that backward stamp, the clock was reset or wrapped (a 32-bit
//! microsecond counter every 71.6 minutes): the backward step is counted as a discontinuity,
//! not a backward step, and the clock restarts there, so the gaps after it are found again. Before (session 29), every row after a reset
//! was counted backwards and no later gap was found.
//!
//! A row that went backwards or repeated the stamp before it, followed by a row one step on from
//! the stamp before it (`0.010, 0.010, 0.015` or `0.015, 0.012, 0.020` at 5 ms), was an extra
//! row (a stamp written again with other values, a stray stamp): it stays a sample, counted once
//! backwards, and the clock reads on from the row after it. Before, the clock stayed a step
//! ahead of every later stamp: each later row was counted backwards (1998 of 2000 in ms).
//!
//! A clock's step is measured from the stamp before only until the grid its stamps lie on is
//! trusted ([`super::stamp_grid`]: a host's stamps jitter about it); from then on each row is
//! measured from its place on that grid, so jitter of up to about 40% of a step makes no gap
//! and a stamp off its place counts once as not a whole number of steps, not twice. Before
//! (session 50) +-28.5% jitter made 5641 missing samples of a file's 34.

use super::sampling_step::SECONDS_PER_DAY;
use super::stamp_grid::StampGrid;

/// Seconds per unit tried for the column, in order: s, days, ms, 100 us (a column named so), us,
/// ns.
const SCALES: [(f64, &str); 6] = [
    (1.0, "s"),
    // Serial dates (Excel's, MATLAB's datenum): a step of tau0 / 86400 is found only in days.
    (SECONDS_PER_DAY, "day"),
    (1e-3, "ms"),
    (1e-4, "100us"),
    (1e-6, "us"),
    (1e-9, "ns"),
];

/// The name of a time column's unit of `scale` seconds ([`SCALES`]: `ns`, `100us`, `day`);
/// `s` for any other.
pub fn unit_name(scale: f64) -> &'static str {
    SCALES
        .iter()
        .find(|(s, _)| *s == scale)
        .map_or("s", |(_, name)| name)
}

/// The unit ([`SCALES`]) in which a time column named `name` stepping by `dt` steps by
/// `tau0_s` seconds, if any. 100 us only for a column whose name says so (Xsens's
/// `SampleTimeFine`): it would otherwise hide a --tau0 ten times off. Days only within 5%:
/// serial dates printed to too few decimals step by quanta 14% off the step (1e-7 days for
/// 10 ms) and would invent gaps.
pub fn step_scale(name: &str, dt: f64, tau0_s: f64) -> Option<&'static (f64, &'static str)> {
    let fine = crate::input::text::time_column_unit(name) == Some(Some(1e-4));
    SCALES
        .iter()
        .filter(|(s, _)| *s != 1e-4 || fine)
        .find(|(s, _)| {
            let tolerance = if *s == SECONDS_PER_DAY {
                0.05
            } else {
                STEP_TOLERANCE
            };
            (dt * s / tau0_s - 1.0).abs() <= tolerance
        })
}

/// Steps after the first looked at for the column's unit when the first is no `tau0`
/// ([`TimeColumn::unit_from_first_steps`]): a few, so that one odd step among them does not
/// decide, and all within the rows the reader has read ahead at its start.
pub const FIRST_STEPS: usize = 8;

/// How far a step may be from a whole number of `tau0` before it is counted irregular.
const STEP_TOLERANCE: f64 = 0.25;

/// The largest jump taken as a gap (steps); a larger one (a clock reset, a stamp far in the
/// future) is reported as a discontinuity and inserts nothing: 1e9 steps is 11.6 days at 1 kHz.
pub const MAX_GAP_STEPS: u64 = 1_000_000_000;

/// How many problems are logged one by one before the rest are only counted.
const LOGGED: u64 = 10;

/// The state of one time column (see the module doc).
#[derive(Debug, Clone)]
pub struct TimeColumn {
    /// The column's header name, for messages.
    pub name: String,
    tau0_s: f64,
    /// Seconds per unit of the column, once decided; `Some(0.0)` when the column is not used.
    scale: Option<f64>,
    /// The time of the last step handed out, in the column's units.
    last: Option<f64>,
    /// Jumps that became gaps, and the steps they inserted.
    pub jumps: u64,
    pub missing: u64,
    /// Steps backwards or repeated; steps not a whole number of tau0; jumps too large to fill.
    pub backwards: u64,
    pub irregular: u64,
    pub discontinuities: u64,
    /// Rows that repeated the row before them, stamp and values, dropped (a record written
    /// twice is not a sample).
    pub duplicates: u64,
    /// The stamp of the last row, when it went backwards: a restart of the clock if the next
    /// row steps on from it by one tau0 (module doc).
    restart: Option<f64>,
    /// The stamp of the last row before one that went backwards or repeated its stamp: a next
    /// row one step on from it (not from the clock moved on) tells the bad row was an extra row
    /// (module doc).
    behind: Option<f64>,
    /// A counter of samples (`PacketCounter`, `field.header.seq`) stands in for a missing time
    /// column ([`TimeColumn::counter`]).
    counter: bool,
    /// The unit was taken from the steps after the first ([`TimeColumn::unit_from_first_steps`])
    /// and the first step is still to come.
    odd_first: bool,
    /// The grid a jittered clock's stamps lie on ([`StampGrid`]): once locked, a row's steps
    /// are measured from it, not from the stamp before (a clock's only: a counter's is never
    /// given a step, so never locks; not carried over a resumed run, where it locks again).
    grid: StampGrid,
    /// The first and last finite stamps read (column units), the rows stamped and the rows
    /// without a stamp that took a step: the stamps' mean step over the run, against `tau0`
    /// ([`TimeColumn::report`]; since a resume, on a resumed run).
    span: Option<(f64, f64)>,
    stamped: u64,
    unstamped_rows: u64,
    /// `missing` when the span began (a resumed run's count carries the earlier part's).
    missing_before_span: u64,
}

/// The stamps' mean step off `tau0` by more than this fraction is said.
const MEAN_STEP_TOL: f64 = 5e-4;
/// Fewest steps for the mean step to be judged.
const MEAN_STEP_MIN: u64 = 1000;

/// Where a time column stands, for a checkpoint (`TextPosition`), and what it found so far (the
/// `summary` record's `time_column`, docs/records.md): the counts carry over a resumed run.
#[derive(Debug, Clone, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct TimeState {
    pub scale: Option<f64>,
    pub last: Option<f64>,
    /// The column's header name.
    #[serde(default)]
    pub name: String,
    /// Jumps that became gaps, the samples they stood for, steps backwards or repeated, steps
    /// not a whole number of tau0, and jumps too large to fill (see [`TimeColumn`]).
    #[serde(default)]
    pub jumps: u64,
    #[serde(default)]
    pub missing: u64,
    #[serde(default)]
    pub backwards: u64,
    #[serde(default)]
    pub irregular: u64,
    #[serde(default)]
    pub discontinuities: u64,
    /// Rows dropped as written twice (see [`TimeColumn`]).
    #[serde(default)]
    pub duplicates: u64,
    /// A backward stamp waiting to be told a clock restart (see [`TimeColumn`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub restart: Option<f64>,
    /// The stamp before a row that went backwards or repeated (see [`TimeColumn`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub behind: Option<f64>,
    /// The column is a counter of samples, not a clock ([`TimeColumn::counter`]).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub counter: bool,
}

impl TimeState {
    /// Whether the column was used to find gaps (false: its first step ruled it out and it was
    /// only skipped).
    pub fn in_use(&self) -> bool {
        self.scale != Some(0.0)
    }

    /// The column's unit once decided (`s`, `ms`, `us`, `ns`).
    pub fn unit(&self) -> Option<&'static str> {
        let s = self.scale?;
        if self.counter {
            return Some("count");
        }
        SCALES.iter().find(|(x, _)| *x == s).map(|(_, u)| *u)
    }
}

impl TimeColumn {
    pub fn new(name: &str, tau0_s: f64) -> TimeColumn {
        TimeColumn {
            name: name.into(),
            tau0_s,
            scale: None,
            last: None,
            jumps: 0,
            missing: 0,
            backwards: 0,
            irregular: 0,
            discontinuities: 0,
            duplicates: 0,
            restart: None,
            behind: None,
            counter: false,
            odd_first: false,
            grid: StampGrid::default(),
            span: None,
            stamped: 0,
            unstamped_rows: 0,
            missing_before_span: 0,
        }
    }

    /// A counter of samples in place of a time column (a file with no clock but a
    /// `PacketCounter`): one count per sample, so a jump of `k` counts is `k - 1` samples
    /// missing, and a step back to near 0 from near a power of two (a 16-bit counter's 65535 ->
    /// 2) is its wrap, the counts across it missing. Used only when its first step is one.
    pub fn counter(name: &str) -> TimeColumn {
        TimeColumn {
            counter: true,
            ..TimeColumn::new(name, 1.0)
        }
    }

    /// The unit decided from the column's first `stamps` (column units, in the order of the
    /// rows, the first row's first; NaN left out) before the first row is handed out, when its
    /// first step is no `tau0` in any unit: the unit in which the first of the next
    /// [`FIRST_STEPS`] steps that is `tau0` in one is, when most of them (more than half) are
    /// `tau0` in it too. The first step is then read in that unit as a later one is: `k` steps
    /// (`0.00, 0.02, 0.03` at 0.01 s) are `k - 1` missing samples, a gap; a stamp that repeats
    /// the first (`0.00, 0.00, 0.01`, the first written twice with another value) or goes back
    /// is counted backwards and the clock starts again at it (the next step is the first
    /// sample's, not one more missing or repeated). A first step that is `tau0`, a counter, and
    /// steps that agree on no unit (a column stepping 0.02 under `--tau0 0.01`) leave the
    /// decision to the first step, as before.
    pub fn unit_from_first_steps(&mut self, stamps: &[f64], file: &std::path::Path) {
        if self.counter || self.scale.is_some() || stamps.len() < 3 {
            return;
        }
        let (first, later) = (stamps[1] - stamps[0], &stamps[1..]);
        if step_scale(&self.name, first, self.tau0_s).is_some() {
            return;
        }
        let steps: Vec<f64> = later
            .windows(2)
            .take(FIRST_STEPS)
            .map(|w| w[1] - w[0])
            .collect();
        let Some(&(scale, unit)) = steps
            .iter()
            .find_map(|&dt| step_scale(&self.name, dt, self.tau0_s))
        else {
            return;
        };
        let agree = steps
            .iter()
            .filter(|&&dt| step_scale(&self.name, dt, self.tau0_s).is_some_and(|s| s.0 == scale))
            .count();
        if 2 * agree <= steps.len() {
            return;
        }
        tracing::info!(
            "{}: time column `{}` read in {unit}: its first step is {first} {unit} = {:.3} \
             tau0, {agree} of the {} after it are tau0",
            file.display(),
            self.name,
            first * scale / self.tau0_s,
            steps.len()
        );
        self.scale = Some(scale);
        self.odd_first = true;
    }

    /// The state a resumed reader continues from.
    pub fn state(&self) -> TimeState {
        TimeState {
            scale: self.scale,
            last: self.last,
            name: self.name.clone(),
            jumps: self.jumps,
            missing: self.missing,
            backwards: self.backwards,
            irregular: self.irregular,
            discontinuities: self.discontinuities,
            duplicates: self.duplicates,
            restart: self.restart,
            behind: self.behind,
            counter: self.counter,
        }
    }

    pub fn restore(&mut self, s: TimeState) {
        self.scale = s.scale;
        self.last = s.last;
        self.jumps = s.jumps;
        self.missing = s.missing;
        self.backwards = s.backwards;
        self.irregular = s.irregular;
        self.discontinuities = s.discontinuities;
        self.duplicates = s.duplicates;
        self.restart = s.restart;
        self.behind = s.behind;
        self.counter = s.counter;
        self.missing_before_span = s.missing;
    }

    /// A row at `line` repeated the row before it, stamp and values, and was dropped.
    pub fn duplicate(&mut self, file: &std::path::Path, line: u64) {
        self.duplicates += 1;
        if self.duplicates <= LOGGED {
            tracing::warn!(
                "{}: line {line}: the row repeats the one before it, time stamp and values; \
                 dropped as written twice",
                file.display()
            );
        }
    }

    /// Whether the column is used to find gaps (false once its first step ruled it out).
    pub fn in_use(&self) -> bool {
        self.scale != Some(0.0)
    }

    /// One gap step was handed out: the clock moves on by one step.
    pub fn step_inserted(&mut self) {
        if let (Some(s), Some(l)) = (self.scale, self.last.as_mut()) {
            if s > 0.0 {
                *l += self.tau0_s / s;
            }
        }
    }

    /// A row whose stamp is missing (an empty time cell) was handed out: it takes its step, on
    /// the clock and on the grid of its stamps.
    pub fn unstamped(&mut self) {
        self.unstamped_rows += 1;
        self.step_inserted();
        self.grid.skip(1);
    }

    /// The row stamped `t` (column units) was handed out after the gap steps before it.
    pub fn handed_out(&mut self, t: f64) {
        if t.is_finite() && self.in_use() && self.last.is_some() {
            self.last = Some(t);
        }
    }

    /// The missing steps before a row stamped `t` (column units) at `line` of `file`; problems
    /// are logged. A NaN stamp (an empty cell) inserts nothing and leaves the clock as it was.
    pub fn missing_before(&mut self, t: f64, file: &std::path::Path, line: u64) -> u64 {
        if !t.is_finite() || !self.in_use() {
            return 0;
        }
        self.stamped += 1;
        self.span = Some((self.span.map_or(t, |s| s.0), t));
        let Some(last) = self.last.replace(t) else {
            return 0;
        };
        let dt = t - last;
        let scale = match self.scale {
            Some(s) => s,
            // A counter of samples steps by one, or is no use for finding gaps.
            None if self.counter => {
                if dt == 1.0 {
                    tracing::info!(
                        "{}: no time column: the counter `{}` finds missing samples",
                        file.display(),
                        self.name
                    );
                    self.scale = Some(1.0);
                    1.0
                } else {
                    tracing::warn!(
                        "{}: line {line}: the counter `{}` steps by {dt}, not one a sample: not \
                         used to find gaps",
                        file.display(),
                        self.name
                    );
                    self.scale = Some(0.0);
                    return 0;
                }
            }
            None => {
                match step_scale(&self.name, dt, self.tau0_s) {
                    Some((s, unit)) => {
                        if *s != 1.0 {
                            // As read: stamps of a clock since 1970 in ns are resolved to
                            // 256 ns as f64, so the step is shown to that resolution.
                            let shown = super::sampling_step::shortest_within(
                                dt,
                                2.0 * t.abs() * f64::EPSILON,
                            );
                            tracing::info!(
                                "{}: time column `{}` read in {unit} (its first step is {shown} {unit} = tau0)",
                                file.display(),
                                self.name
                            );
                        }
                        self.scale = Some(*s);
                        *s
                    }
                    None => {
                        tracing::warn!(
                            "{}: line {line}: the time column `{}` steps by {dt} where --tau0 is {} s \
                             (nor that in ms, us or ns): it is not used to find gaps; check --tau0, or \
                             name the time column with --time-column",
                            file.display(),
                            self.name,
                            self.tau0_s
                        );
                        self.scale = Some(0.0);
                        return 0;
                    }
                }
            }
        };
        let steps = dt * scale / self.tau0_s;
        // The grid of a clock's stamps, set at the first row once the unit is known.
        if !self.counter && self.grid.step() == 0.0 {
            self.grid = StampGrid::new(self.tau0_s / scale);
            self.grid.set(last);
        }
        // A first step that repeats or goes back, the unit read off the steps after it: the
        // clock starts again at this row (moved on one step, as a later one is, every row
        // after it would repeat its stamp).
        if std::mem::take(&mut self.odd_first) && dt <= 0.0 {
            self.backwards += 1;
            tracing::warn!(
                "{}: line {line}: the time column `{}` goes {} at its first step ({last} -> {t}); \
                 the clock starts at this row, no gap inserted",
                file.display(),
                self.name,
                if dt < 0.0 {
                    "backwards"
                } else {
                    "nowhere (a repeated stamp)"
                }
            );
            self.grid.set(t);
            return 0;
        }
        // A counter's wrap: from near the top of its range (a power of two) to near 0, the
        // counts across the wrap being the samples, so those between are missing.
        if self.counter && dt < 0.0 && t >= 0.0 && last >= 1.0 {
            let range = (last as u64 + 1).next_power_of_two() as f64;
            let across = t + range - last;
            if across >= 1.0 && across <= range / 8.0 {
                let missing = across as u64 - 1;
                if missing > 0 {
                    self.jumps += 1;
                    self.missing += missing;
                }
                return missing;
            }
        }
        let behind = self.behind.take();
        if let Some(back) = self.restart.take() {
            // The row before went back and this one steps on from it, one step or (while still
            // behind the old clock: no glitch's next row) a whole number of them: the clock
            // restarted, and samples right after the restart are missing when more than one.
            let since = (t - back) * scale / self.tau0_s;
            let k = since.round();
            let whole = k >= 1.0 && (since - k).abs() <= STEP_TOLERANCE;
            if whole && (k == 1.0 || (dt < 0.0 && k - 1.0 <= MAX_GAP_STEPS as f64)) {
                self.backwards -= 1;
                self.discontinuities += 1;
                let missing = k as u64 - 1;
                tracing::warn!(
                    "{}: line {line}: the time column `{}` restarted at the row before, at {back} \
                     (a clock reset or a counter's wrap); read on from there, {}",
                    file.display(),
                    self.name,
                    if missing == 0 {
                        "no gap inserted".to_string()
                    } else {
                        format!("{missing} samples missing right after it, a gap")
                    }
                );
                if missing > 0 {
                    self.jumps += 1;
                    self.missing += missing;
                    self.last = Some(back);
                }
                self.grid.set(t);
                return missing;
            }
        }
        if let Some(good) = behind {
            // The rows since `good` went back or repeated their stamps, and this one is no
            // step past the clock they moved on but is past `good`: they were extra rows (a
            // stamp written again with other values, a stray stamp) and this row is on the old
            // clock, which reads on from it. Counted once, at the bad row: before, the clock
            // stayed a step ahead and every later row was counted backwards.
            let since = (t - good) * scale / self.tau0_s;
            if steps < 0.5 && since >= 0.5 {
                self.off_step(since, file, line);
                self.grid.set(t);
                return 0;
            }
        }
        if dt <= 0.0 {
            self.backwards += 1;
            if self.backwards <= LOGGED {
                tracing::warn!(
                    "{}: line {line}: the time column `{}` goes {} ({last} -> {t}); no gap inserted",
                    file.display(),
                    self.name,
                    if dt < 0.0 { "backwards" } else { "nowhere (a repeated stamp)" }
                );
            }
            // The row is taken as the next sample: the clock moves on one step from where it
            // was, so one bad stamp makes no gap; the next row tells a restart (module doc).
            self.last = Some(last + self.tau0_s / scale);
            self.behind = Some(behind.unwrap_or(last));
            // More than a step back (jitter or a swapped pair goes back less).
            if dt * scale < -self.tau0_s {
                self.restart = Some(t);
            }
            self.grid.set(t);
            return 0;
        }
        // A clock's step measured on the grid its stamps lie on once that is trusted (the
        // jitter counted once, not twice: `super::stamp_grid`), else from the stamp before.
        let k = self.off_step(self.grid.steps_to(t).unwrap_or(steps), file, line);
        if k < 2.0 {
            self.grid.place(t);
            return 0;
        }
        let missing = k as u64 - 1;
        if missing > MAX_GAP_STEPS {
            self.discontinuities += 1;
            tracing::warn!(
                "{}: line {line}: the time column `{}` jumps by {:.3e} steps; taken as a \
                 discontinuity, no gap inserted",
                file.display(),
                self.name,
                steps
            );
            self.grid.set(t);
            return 0;
        }
        self.grid.place(t);
        self.jumps += 1;
        self.missing += missing;
        // The clock is at the last step handed out: the gap steps move it on one by one.
        self.last = Some(last);
        missing
    }

    /// A step of `steps` tau0 at `line`, rounded; counted and logged when it is no whole number
    /// of them (more than a quarter off, or less than one).
    fn off_step(&mut self, steps: f64, file: &std::path::Path, line: u64) -> f64 {
        let k = steps.round();
        if (steps - k).abs() > STEP_TOLERANCE || k < 1.0 {
            self.irregular += 1;
            if self.irregular <= LOGGED {
                tracing::warn!(
                    "{}: line {line}: the time column `{}` steps by {:.3} tau0, not a whole number \
                     of steps (stamps that jitter about the sampling grid, or samples not evenly \
                     spaced there; the account at the end of the input tells which)",
                    file.display(),
                    self.name,
                    steps
                );
            }
        }
        k
    }

    /// The account logged at the end of the input.
    pub fn report(&self, file: &std::path::Path) {
        if !self.in_use() {
            return;
        }
        if let Some(step) = self.mean_step_s() {
            if (step / self.tau0_s - 1.0).abs() > MEAN_STEP_TOL {
                tracing::warn!(
                    "{}: time column `{}`: its stamps step {} s on average, {:+.2}% off --tau0 \
                     {} s: the taus are read at --tau0 (check it, or leave it out to read the \
                     step off the stamps)",
                    file.display(),
                    self.name,
                    super::sampling_step::shortest_within(step, 1e-6 * step),
                    100.0 * (step / self.tau0_s - 1.0),
                    self.tau0_s
                );
            }
        }
        if self.jumps + self.backwards + self.irregular + self.discontinuities + self.duplicates
            == 0
        {
            tracing::debug!("{}: time column `{}`: uniform", file.display(), self.name);
            return;
        }
        // Stamps that jitter about a grid it trusts: the rows off their step are that jitter,
        // not samples taken unevenly (`super::stamp_grid`).
        let jitter = if self.irregular > 0 && self.grid.locked() {
            format!(
                " (its stamps jitter about the sampling grid by {:.0}% of a step, root mean \
                 square: rows measured from the grid, the samples taken as evenly spaced)",
                100.0 * self.grid.spread()
            )
        } else {
            String::new()
        };
        tracing::warn!(
            "{}: {} `{}`: {} jumps, {} missing samples counted as gaps; {} steps \
             backwards or repeated, {} not a whole number of tau0{jitter}, {} discontinuities; \
             {} rows written twice dropped",
            file.display(),
            if self.counter {
                "counter"
            } else {
                "time column"
            },
            self.name,
            self.jumps,
            self.missing,
            self.backwards,
            self.irregular,
            self.discontinuities,
            self.duplicates
        );
    }

    /// The stamps' mean step (s) over the rows read, from the first stamp to the last, the
    /// gaps' missing steps and the unstamped rows counted: `None` for a counter, before
    /// [`MEAN_STEP_MIN`] steps, or once a stamp went back or the clock restarted.
    fn mean_step_s(&self) -> Option<f64> {
        let (first, last) = self.span?;
        let scale = self.scale.filter(|s| *s > 0.0)?;
        if self.counter || self.backwards + self.discontinuities > 0 {
            return None;
        }
        let missing = self.missing - self.missing_before_span.min(self.missing);
        let steps = self.stamped.saturating_sub(1) + missing + self.unstamped_rows;
        (steps >= MEAN_STEP_MIN).then(|| (last - first) * scale / steps as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// Stamps 0.15% slower than `--tau0` (199.7 Hz against 200 Hz, 3600 rows, one sample
    /// missing): the mean step is read as 5.0075 ms; at the stated step it is 5 ms to 1e-12.
    #[test]
    fn the_stamps_mean_step_is_read_over_the_run() {
        for (step, want) in [(0.005_007_5, 0.005_007_5), (0.005, 0.005)] {
            let mut c = TimeColumn::new("time", 0.005);
            let stamps: Vec<f64> = (0..3600)
                .filter(|&i| i != 1000)
                .map(|i| i as f64 * step)
                .collect();
            clocked(&mut c, &stamps);
            let got = c.mean_step_s().expect("a mean step");
            assert!((got / want - 1.0).abs() < 1e-12, "{got} vs {want}");
        }
    }

    /// As the reader does after a gap: its `steps` missing steps handed out, then the row
    /// stamped `t`.
    fn hand_out(c: &mut TimeColumn, steps: u64, t: f64) {
        for _ in 0..steps {
            c.step_inserted();
        }
        c.handed_out(t);
    }

    /// `stamps` fed to `c` as the reader does (the gap's steps handed out, then the row after
    /// them sets the clock): the missing samples found before each.
    fn clocked(c: &mut TimeColumn, stamps: &[f64]) -> Vec<u64> {
        let p = Path::new("x.csv");
        let mut got = Vec::new();
        for (i, &t) in stamps.iter().enumerate() {
            let m = c.missing_before(t, p, i as u64 + 2);
            if m > 0 {
                hand_out(c, m, t);
            }
            got.push(m);
        }
        got
    }

    /// A counter of samples: a jump of k counts is k - 1 missing; a 16-bit wrap (65534 -> 1)
    /// has the counts across it missing (65535 and 0); a step back that is no wrap is no gap;
    /// a counter whose first step is not one is not used.
    #[test]
    fn a_counter_of_samples_finds_missing_samples_across_its_wrap() {
        let p = Path::new("x.csv");
        let mut c = TimeColumn::counter("PacketCounter");
        assert_eq!(c.missing_before(65530.0, p, 2), 0);
        assert_eq!(c.missing_before(65531.0, p, 3), 0);
        assert_eq!(c.missing_before(65534.0, p, 4), 2);
        hand_out(&mut c, 2, 65534.0);
        assert_eq!(c.missing_before(1.0, p, 5), 2);
        hand_out(&mut c, 2, 1.0);
        assert_eq!(c.missing_before(2.0, p, 6), 0);
        // From 20000 to 5: no wrap (not near the top of its range), no gap.
        assert_eq!(c.missing_before(20000.0, p, 7), 19997);
        c.handed_out(20000.0);
        assert_eq!(c.missing_before(5.0, p, 8), 0);
        let st = c.state();
        assert_eq!(
            (st.missing, st.jumps, st.unit()),
            (2 + 2 + 19997, 3, Some("count"))
        );
        let mut d = TimeColumn::counter("frame_count");
        assert_eq!(d.missing_before(0.0, p, 2), 0);
        assert_eq!(d.missing_before(4.0, p, 3), 0);
        assert_eq!(d.missing_before(12.0, p, 4), 0);
        assert!(!d.in_use());
    }

    #[test]
    fn jumps_become_missing_steps_and_the_unit_is_found() {
        let p = Path::new("x.csv");
        // Stamps in ms at tau0 = 4 ms: a jump of 12 ms is 3 steps, 2 missing.
        let mut c = TimeColumn::new("t", 0.004);
        assert_eq!(c.missing_before(1000.0, p, 2), 0);
        assert_eq!(c.missing_before(1004.0, p, 3), 0);
        assert_eq!(c.missing_before(1016.0, p, 4), 2);
        hand_out(&mut c, 2, 1016.0);
        assert_eq!(c.missing_before(1020.0, p, 5), 0);
        assert_eq!((c.jumps, c.missing), (1, 2));
        // Backwards: counted, nothing inserted, taken as the next sample (1024).
        assert_eq!(c.missing_before(1010.0, p, 6), 0);
        assert_eq!(c.missing_before(1028.0, p, 7), 0);
        assert_eq!(c.backwards, 1);
        // 1.4 steps: irregular, no gap; 1.6 steps: irregular, one missing.
        assert_eq!(c.missing_before(1033.6, p, 8), 0);
        assert_eq!(c.missing_before(1040.0, p, 9), 1);
        assert_eq!(c.irregular, 2);
    }

    /// A host that stamps each sample as it receives it, uniform jitter of +-30% of the 5 ms
    /// step (neighbouring stamps differ by up to 0.6 step), 6 samples left out in three places:
    /// read on the grid the stamps lie on, the gaps are those and no others, in ten seeds; read
    /// step by step, about 1.4% of the steps went past 1.5 steps and each was a gap (a review's
    /// 100 Hz file: 5641 missing samples for its 34).
    #[test]
    fn a_jittered_clock_counts_only_the_samples_left_out() {
        use rand::{RngExt, SeedableRng};
        let drop = [900u64, 2000, 2001, 2002, 3500, 3502];
        for seed in 0..10 {
            let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
            let stamps: Vec<f64> = (0..5000u64)
                .map(|i| 0.005 * (i as f64 + 0.6 * (rng.random::<f64>() - 0.5)))
                .enumerate()
                .filter(|(i, _)| !drop.contains(&(*i as u64)))
                .map(|(_, t)| t)
                .collect();
            let alone = stamps
                .windows(2)
                .filter(|w| (w[1] - w[0]) / 0.005 > 1.5)
                .count();
            assert!(alone > 30, "seed {seed}: {alone} steps past 1.5 read alone");
            let mut c = TimeColumn::new("time", 0.005);
            // As the reader does: the unit from the first steps when the first is no tau0.
            c.unit_from_first_steps(&stamps[..12], Path::new("x.csv"));
            let got = clocked(&mut c, &stamps);
            let gaps: Vec<(usize, u64)> = got
                .iter()
                .enumerate()
                .filter(|(_, m)| **m > 0)
                .map(|(i, m)| (i, *m))
                .collect();
            // The row after each gap: sample 901 (row 900), 2003 (row 1999), 3501 (row 3496),
            // 3503 (row 3497).
            // (The first `LOCK_ROWS` rows are read step by step, before the grid is trusted.)
            let after: Vec<(usize, u64)> = gaps
                .into_iter()
                .filter(|(i, _)| *i as u64 > super::super::stamp_grid::LOCK_ROWS)
                .collect();
            assert_eq!(
                after,
                [(900, 1), (1999, 3), (3496, 1), (3497, 1)],
                "seed {seed}"
            );
            // The account says the stamps jitter about the grid by their spread: uniform over
            // +-30% of a step has a root mean square of 0.3 / sqrt(3) = 0.173 step.
            assert!(c.grid.locked(), "seed {seed}");
            let spread = c.grid.spread();
            assert!(
                (spread - 0.3 / 3f64.sqrt()).abs() < 0.02,
                "seed {seed}: {spread}"
            );
        }
    }

    #[test]
    fn a_first_step_that_is_not_tau0_rules_the_column_out() {
        let p = Path::new("x.csv");
        let mut c = TimeColumn::new("t", 0.004);
        c.missing_before(0.0, p, 2);
        assert_eq!(c.missing_before(0.5, p, 3), 0);
        assert!(!c.in_use());
        assert_eq!(c.missing_before(100.0, p, 4), 0);
    }

    #[test]
    fn a_resumed_column_inserts_only_the_steps_not_yet_handed_out() {
        let p = Path::new("x.csv");
        let mut c = TimeColumn::new("t", 0.01);
        c.missing_before(0.0, p, 2);
        c.missing_before(0.01, p, 3);
        assert_eq!(c.missing_before(0.11, p, 4), 9);
        // Four gap steps handed out, then a checkpoint: the row at 0.11 is read again.
        for _ in 0..4 {
            c.step_inserted();
        }
        let mut r = TimeColumn::new("t", 0.01);
        r.restore(c.state());
        assert_eq!(r.missing_before(0.11, p, 4), 5);
    }

    /// A 32-bit microsecond counter wraps (every 71.6 minutes at 10 ms steps): the clock
    /// restarts at the wrapped stamp, counted as one discontinuity, and a gap of 2 samples after
    /// it is found. Before, every row after the wrap was counted backwards and the gap was lost.
    /// A single stamp that goes back (a glitch) is still one backward step, no restart.
    #[test]
    fn a_clock_that_wraps_or_resets_restarts_and_a_glitch_does_not() {
        let run = |c: &mut TimeColumn, stamps: &[f64]| clocked(c, stamps);
        let mut c = TimeColumn::new("t_us", 0.01);
        let b = 4_294_967_296.0 - 25_000.0;
        let wrap = [b, b + 1e4, b + 2e4, 5e3, 15e3, 45e3, 55e3];
        assert_eq!(run(&mut c, &wrap), [0, 0, 0, 0, 0, 2, 0]);
        assert_eq!((c.backwards, c.discontinuities, c.missing), (0, 1, 2));
        // A glitch: the stamp after it is on the old clock (0.04, one step after 0.03).
        let mut g = TimeColumn::new("t", 0.01);
        let glitch = [0.0, 0.01, 0.02, 0.005, 0.04, 0.05, 0.07];
        assert_eq!(run(&mut g, &glitch), [0, 0, 0, 0, 0, 0, 1]);
        assert_eq!((g.backwards, g.discontinuities, g.missing), (1, 0, 1));
        // A glitch to a stamp a whole number of steps before the next row, which is on the
        // old clock: still a glitch, no restart.
        let mut g = TimeColumn::new("t", 0.01);
        let glitch = [0.0, 0.01, 0.02, 0.0, 0.04, 0.05];
        assert_eq!(run(&mut g, &glitch), [0, 0, 0, 0, 0, 0]);
        assert_eq!((g.backwards, g.discontinuities), (1, 0));
        // A wrap with two samples missing right after it: the restart and its gap, and the
        // clock reads on (before: every later row "backwards").
        let mut c = TimeColumn::new("t_us", 0.01);
        let wrap = [b, b + 1e4, b + 2e4, 5e3, 35e3, 45e3, 75e3];
        assert_eq!(run(&mut c, &wrap), [0, 0, 0, 0, 2, 0, 2]);
        assert_eq!((c.backwards, c.discontinuities, c.missing), (0, 1, 4));
    }

    /// A row in the middle that repeats the stamp before it with other values (an extra row), or
    /// goes back once, is one step backwards: the rows after it are on the old clock and read
    /// as they are, and a later gap keeps its size. Before, the clock moved on one step at the
    /// bad row and every later row (1998 of 2000 in ms) repeated its stamp, counted backwards.
    #[test]
    fn one_repeated_or_backward_stamp_mid_file_is_one_count() {
        // In ms at 5 ms (exact), a repeat at 10 then a jump of 3 steps (2 missing).
        let mut c = TimeColumn::new("time_ms", 0.005);
        let stamps = [0.0, 5.0, 10.0, 10.0, 15.0, 20.0, 25.0, 40.0, 45.0];
        assert_eq!(clocked(&mut c, &stamps), [0, 0, 0, 0, 0, 0, 0, 2, 0]);
        assert_eq!((c.backwards, c.irregular, c.missing, c.jumps), (1, 0, 2, 1));
        // In s (not exact): 0.010 0.015 0.012 0.020 ...: one backward row, none after it.
        let mut c = TimeColumn::new("time", 0.005);
        let stamps: Vec<f64> = [0, 5, 10, 15, 12, 20, 25, 30, 35, 50, 55]
            .iter()
            .map(|&ms| f64::from(ms) * 1e-3)
            .collect();
        assert_eq!(clocked(&mut c, &stamps), [0, 0, 0, 0, 0, 0, 0, 0, 0, 2, 0]);
        assert_eq!((c.backwards, c.irregular, c.missing), (1, 0, 2));
        // The same stamp three times: two rows backwards, then read on.
        let mut c = TimeColumn::new("time_ms", 0.005);
        let stamps = [0.0, 5.0, 5.0, 5.0, 10.0, 15.0, 20.0];
        assert_eq!(clocked(&mut c, &stamps).iter().sum::<u64>(), 0);
        assert_eq!((c.backwards, c.irregular), (2, 0));
        // An extra row stamped far back (0): one backward step, no restart, no more.
        let mut c = TimeColumn::new("t", 0.01);
        let stamps = [0.0, 0.01, 0.02, 0.0, 0.03, 0.04, 0.05];
        assert_eq!(clocked(&mut c, &stamps).iter().sum::<u64>(), 0);
        assert_eq!((c.backwards, c.discontinuities, c.irregular), (1, 0, 0));
    }

    /// 100 us is a scale only for a column named so (Xsens's `SampleTimeFine`): a `time_ms`
    /// column stepping by 10 under --tau0 0.001 is not read in it, but refused (check --tau0).
    /// A step between ns stamps since 1970 (resolved to 256 ns as f64) is shown as the
    /// stamps resolve it; a step read exactly is shown as it is.
    #[test]
    fn a_step_is_shown_to_the_stamps_resolution() {
        let (a, b) = (1_403_636_579_758_555_392f64, 1_403_636_579_759_555_392f64);
        assert_eq!(b - a, 999_936.0);
        let shown = |x: f64, r: f64| crate::input::sampling_step::shortest_within(x, r);
        assert_eq!(shown(b - a, 2.0 * b * f64::EPSILON), 1_000_000.0);
        assert_eq!(shown(2.5, 2.0 * 10.0 * f64::EPSILON), 2.5);
        assert_eq!(shown(0.0, 1.0), 0.0);
    }

    #[test]
    fn a_scale_of_100_us_only_for_its_name() {
        let p = Path::new("x.csv");
        let mut c = TimeColumn::new("time_ms", 0.001);
        c.missing_before(0.0, p, 2);
        c.missing_before(10.0, p, 3);
        assert!(!c.in_use());
        let mut c = TimeColumn::new("SampleTimeFine", 0.001);
        c.missing_before(0.0, p, 2);
        c.missing_before(10.0, p, 3);
        assert_eq!(c.state().unit(), Some("100us"));
    }

    /// A first step that is no tau0, the steps after it tau0 in one unit: the unit is theirs
    /// and the first step is read in it, a jump of 2 steps one missing sample (s; and ms at
    /// 4 ms), a repeated first stamp one step backwards after which the clock reads on with no
    /// more (before, each row after it repeated its stamp). Steps all 2 tau0, or half of them
    /// odd, decide nothing: the first step rules the column out, as before (session 42: any
    /// odd first step did).
    #[test]
    fn the_unit_from_the_steps_after_an_odd_first_one() {
        let run = |c: &mut TimeColumn, stamps: &[f64]| {
            c.unit_from_first_steps(stamps, Path::new("x.csv"));
            clocked(c, stamps)
        };
        let mut c = TimeColumn::new("time", 0.01);
        assert_eq!(
            run(&mut c, &[0.0, 0.02, 0.03, 0.04, 0.05, 0.08]),
            [0, 1, 0, 0, 0, 2]
        );
        assert_eq!(
            (c.in_use(), c.state().unit(), c.jumps, c.missing),
            (true, Some("s"), 2, 3)
        );
        let mut c = TimeColumn::new("t", 0.004);
        assert_eq!(run(&mut c, &[1000.0, 1008.0, 1012.0, 1016.0]), [0, 1, 0, 0]);
        assert_eq!((c.state().unit(), c.missing), (Some("ms"), 1));
        let mut c = TimeColumn::new("time", 0.01);
        assert_eq!(
            run(&mut c, &[0.0, 0.0, 0.01, 0.02, 0.03, 0.05]),
            [0, 0, 0, 0, 0, 1]
        );
        assert_eq!((c.backwards, c.irregular, c.missing), (1, 0, 1));
        for stamps in [
            &[0.0, 0.02, 0.04, 0.06, 0.08][..],
            &[0.0, 0.02, 0.03, 0.05, 0.07, 0.09],
        ] {
            let mut c = TimeColumn::new("time", 0.01);
            assert_eq!(run(&mut c, stamps).iter().sum::<u64>(), 0, "{stamps:?}");
            assert!(!c.in_use(), "{stamps:?}");
        }
    }
}
