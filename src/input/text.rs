//! Text columns: one row per sample, columns separated by commas, semicolons, tabs or spaces,
//! an optional first row of channel names (otherwise `c1`, `c2`, ...; a UTF-8 byte-order mark
//! before it is dropped, duplicate names are refused; columns after the last name that hold no
//! number in the first rows are trailing separators, no channels:
//! [`Layout::with_unnamed_columns_that_hold_numbers`]), `#` lines skipped (docs/records.md).
//! A field in double quotes may hold the separator, by CSV's rule ([`split_quoted`]:
//! `"ok, nominal"` one label, `"0,25"` a decimal comma, `"2,001.52"` read by [`thousands`]). A `#`
//! line just before the first data row that names as many columns as the row has (`#timestamp
//! [ns],w_RS_S_x [rad s^-1],...`, as EuRoC and TUM datasets write) is that header. A column
//! whose first data row holds text (`imu_link`, `OK`) is a label and no channel unless the run
//! names it. A column named `time`, `t`, `timestamp`, `time_s` (any case, after a `#` or ROS's
//! `%`, a unit after it such as `timestamp [ns]`,
//! `time (s)` or `t_ns` allowed: [`time_column_unit`]) or the one [`TextOptions::time_column`]
//! names is a time stamp, not a channel: with the sampling step ([`TextOptions::tau0_s`]) its
//! jumps become gaps of the missing samples ([`super::time_column`]), else it is skipped;
//! [`TextOptions::columns`] picks and renames channels.
//!
//! Streams: rows are read line by line and handed on in batches; the file is never held in
//! memory. An empty row, or a row whose every field is empty or `nan`, is a gap for every
//! channel; an empty or `nan` field (or `N/A`, `null`, `-`: [`MISSING`]) is a gap for its
//! channel. A row that cannot be read (a
//! token that is not a number, or the wrong number of fields) is counted in `bad_rows`, logged
//! with its line number, and treated as a gap, so nothing already measured is lost.

use std::collections::VecDeque;
use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::error::UsageError;
use crate::input::px4_export;
use crate::input::sampling_step::SECONDS_PER_DAY;
use crate::input::time_column::{TimeColumn, TimeState, FIRST_STEPS};

/// Rows per batch handed to the analysis.
pub const BATCH_ROWS: usize = 8192;

/// The longest line read, in bytes: a row of 256 channels takes a few kB. A longer line (a
/// file with no line ends) is skipped as it streams by, never held whole in memory.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// The most bytes one call of [`read_line_bounded`] consumes of a line without an end: past
/// them the rest of the line is read as the next one (both long, bad rows). A stream with no
/// line ends (`/dev/zero`, a binary file given as text) otherwise held the reader inside one
/// line for ever, and a run told to stop (SIGTERM, Ctrl-C) kept reading it: 9.5 minutes at
/// 90% CPU in a review (session 42) until a second signal.
pub const MAX_LINE_CONSUMED: usize = 64 << 20;

/// Reads one line, through its `\n`, into `buf` (emptied first), keeping at most `max` bytes
/// of it; returns the bytes consumed (0 at the end of the input) and whether the line was
/// longer than `max`. A line is cut after [`MAX_LINE_CONSUMED`] bytes.
fn read_line_bounded<R: BufRead>(
    src: &mut R,
    buf: &mut Vec<u8>,
    max: usize,
) -> std::io::Result<(usize, bool)> {
    buf.clear();
    let (mut consumed, mut long) = (0, false);
    loop {
        let avail = match src.fill_buf() {
            Ok(b) => b,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e),
        };
        if avail.is_empty() {
            return Ok((consumed, long));
        }
        let (n, done) = match avail.iter().position(|&b| b == b'\n') {
            Some(i) => (i + 1, true),
            None => (avail.len(), false),
        };
        let room = max.saturating_sub(buf.len());
        long |= n > room;
        buf.extend_from_slice(&avail[..n.min(room)]);
        src.consume(n);
        consumed += n;
        if done || consumed >= MAX_LINE_CONSUMED {
            return Ok((consumed, long));
        }
    }
}

/// What is wrong with a text input that held no usable value, `invalid` of them numbers out of
/// range (beyond [`super::MAX_ABS_VALUE`], non-zero below [`crate::ranges::MIN_ABS_VALUE`], or
/// infinite).
pub fn no_samples_problem(invalid: u64) -> String {
    if invalid == 0 {
        "no samples: every value is empty, nan or not a number".into()
    } else {
        format!(
            "no samples: {invalid} values are numbers beyond {:e} or non-zero below {:e} in \
             magnitude, or infinite, taken as gaps, and the others are empty, nan or not \
             numbers (are the columns raw counts of a wider type, or time stamps? pick the data \
             columns with --columns; values that small need a larger unit)",
            super::MAX_ABS_VALUE,
            crate::ranges::MIN_ABS_VALUE
        )
    }
}

/// How many bad rows are logged one by one before the rest are only counted.
const BAD_ROWS_LOGGED: u64 = 10;

/// Header names taken as a time column when no `--time-column` is given (case-insensitive),
/// before any other name [`time_column_unit`] reads as a time's.
pub const TIME_COLUMN_NAMES: [&str; 4] = ["time", "t", "timestamp", "time_s"];

/// Words that make a column a time column wherever they stand in its name, split at anything
/// not a letter or digit: `gps_time`, `field.header.stamp`, `Zeit [s]`, `elapsed (ms)`,
/// `sample_time_us`. Other languages' word for time are here as spreadsheets there write them.
const TIME_WORDS: [&str; 13] = [
    "time",
    "timestamp",
    "stamp",
    "datetime",
    "date",
    "datum",
    "fecha",
    "utc",
    "elapsed",
    "zeit",
    "tiempo",
    "tijd",
    "czas",
];

/// Names that are a time column's when they are the whole name (`sec`, `Seconds`), but are a
/// unit inside a channel's (`gyro_deg_sec_x`).
const TIME_ALONE: [&str; 3] = ["sec", "secs", "seconds"];

/// Words that make a name with a time word in it something else: a step between samples
/// (`delta_time`, `dt`), a filter's time constant, a sensor's quantity, not a clock.
const NOT_TIME_WORDS: [&str; 20] = [
    "delta",
    "dt",
    "diff",
    "interval",
    "period",
    "constant",
    "gyro",
    "gyr",
    "gyroscope",
    "acc",
    "accel",
    "accelerometer",
    "rate",
    "deg",
    "rad",
    "dps",
    "mag",
    "temp",
    "temperature",
    "angle",
];

/// What a time column's brackets may hold besides a unit: the clock's scale (`Timestamp (UTC)`).
const TIME_SCALES: [&str; 7] = ["utc", "gps", "tai", "local", "unix", "epoch", "iso"];

/// Seconds per unit of the time units a column name may carry.
const TIME_UNITS: [(&str, f64); 11] = [
    ("s", 1.0),
    ("sec", 1.0),
    ("secs", 1.0),
    ("seconds", 1.0),
    ("ms", 1e-3),
    ("msec", 1e-3),
    ("us", 1e-6),
    ("usec", 1e-6),
    ("\u{b5}s", 1e-6),
    ("ns", 1e-9),
    ("nsec", 1e-9),
];

/// Whether `name` names a time column by itself and the unit's seconds when it gives one
/// (`Some(None)`: a time column without a unit; `None`: not a time column's name). A time
/// column's name is one of [`TIME_COLUMN_NAMES`] (any case), or holds one of [`TIME_WORDS`]
/// and none of [`NOT_TIME_WORDS`]; a unit may follow in brackets (`timestamp [ns]`, `time (s)`,
/// `Zeit [s]`) or as the last word (`t_ns`, `time_ms`, `sample_time_us`). Brackets that hold
/// another unit (`time [deg]`) make it no time column.
pub fn time_column_unit(name: &str) -> Option<Option<f64>> {
    time_name(name).map(|(_, unit)| unit)
}

/// `name` with a `_` where a lower-case letter meets an upper-case one that starts a word
/// (`GpsTime` -> `Gps_Time`), so that the words of a camel-case name are words.
fn camel_words(name: &str) -> String {
    let chars: Vec<char> = name.chars().collect();
    let mut out = String::with_capacity(name.len() + 4);
    for (i, &c) in chars.iter().enumerate() {
        // A word starts at an upper-case letter after a lower-case one and before another
        // (`GpsTime`); `time_mS`, `t_uS` keep their unit whole.
        let prev_lower = i > 0 && (chars[i - 1].is_lowercase() || chars[i - 1].is_ascii_digit());
        let next_lower = chars.get(i + 1).is_some_and(|n| n.is_lowercase());
        if prev_lower && c.is_uppercase() && next_lower {
            out.push('_');
        }
        out.push(c);
    }
    out
}

/// Words that make a column a counter of samples or packets (`PacketCounter`,
/// `field.header.seq`, `frame_count`), not a channel: it steps by one and wraps.
const COUNTER_WORDS: [&str; 7] = ["counter", "count", "cnt", "seq", "sequence", "index", "idx"];

/// A column's name as the word rules read it: without a comment's `#` or `%` and its unit in
/// brackets, camel-case words split with `_`, in lower case (`PacketCounter` ->
/// `packet_counter`, `gx (count)` -> `gx`).
fn lower_words(name: &str) -> String {
    camel_words(base_name(name.trim_start_matches(['#', '%']))).to_ascii_lowercase()
}

/// Whether `name` names a counter of samples or packets ([`COUNTER_WORDS`]), not the counts of
/// an axis: a name that also holds an axis or a sensor (`gz_cnt`, `cnt_x`, `accel_count`) is
/// that sensor's pulse count, a channel. Before (session 42) `gz_cnt` was taken for the file's
/// sample counter: a gyro counting 0-3 pulses a row invented 19,703 missing samples and broke
/// the other channel into 13,639 stretches.
pub fn counter_column(name: &str) -> bool {
    // `gx (count)`, `gx [cnt]`: counts are the unit there, not a counter.
    let lower = lower_words(name);
    let words: Vec<&str> = lower
        .split(|c: char| !c.is_alphanumeric())
        .filter(|w| !w.is_empty())
        .collect();
    words.iter().any(|w| COUNTER_WORDS.contains(w)) && !words.iter().any(|w| axis_word(w))
}

/// An axis (`x`, `gz`, `wy`, `ax`) or a sensor's quantity (`gyro`, `accel`, `dtheta`) in a
/// column's name ([`counter_column`]).
fn axis_word(w: &str) -> bool {
    const SENSOR: [&str; 14] = [
        "gyro",
        "gyr",
        "acc",
        "accel",
        "gyroscope",
        "accelerometer",
        "dtheta",
        "dvel",
        "theta",
        "angle",
        "omega",
        "rate",
        "vel",
        "velocity",
    ];
    match w.as_bytes() {
        [b'x' | b'y' | b'z'] => true,
        [b'g' | b'a' | b'w', b'x' | b'y' | b'z'] => true,
        _ => SENSOR.contains(&w),
    }
}

/// Whether `name` names the number of the sensor a row is of ([`INSTANCE_NAMES`]); a bare `I`
/// only where `bare_i` (ArduPilot's messages: elsewhere it may be a current or an in-phase
/// signal).
fn instance_column(name: &str, bare_i: bool) -> bool {
    match lower_words(name).as_str() {
        "i" => bare_i,
        n => INSTANCE_NAMES.contains(&n),
    }
}

/// Words that make a column something other than an inertial channel, and what it holds: a
/// status word (Xsens's `Status`, a logger's `flags`), a magnetometer's field (`Mag_X`, `magY`,
/// `compass_z`), a vector's magnitude (`Magnitude`, phyphox's `Absolute (rad/s)`: the norm of
/// the three axes, not an axis; not `norm`, which `gx_norm` may use for a normalised channel).
const QUANTITY_WORDS: [(&str, &str); 9] = [
    ("status", "a status word"),
    ("flags", "a status word"),
    ("mag", "a magnetic field"),
    ("magn", "a magnetic field"),
    ("magnetometer", "a magnetic field"),
    ("magnetic", "a magnetic field"),
    ("compass", "a magnetic field"),
    ("magnitude", "a vector's magnitude"),
    ("absolute", "a vector's magnitude"),
];

/// What a column holds by its name when that is no inertial channel ([`QUANTITY_WORDS`]; a
/// word may end in its axis, `magx`; or one of [`INSTANCE_NAMES`], the number of the sensor
/// the rows are of, but a bare `I`, which may as well be a current or an in-phase signal, only
/// in ArduPilot's messages, `super::format_units`); `None` for any other name.
pub fn named_quantity(name: &str) -> Option<&'static str> {
    if instance_column(name, false) {
        return Some("the number of the sensor its rows are of");
    }
    lower_words(name)
        .split(|c: char| !c.is_alphanumeric())
        .find_map(|w| {
            let bare = w.strip_suffix(['x', 'y', 'z']).filter(|b| b.len() >= 3);
            QUANTITY_WORDS
                .iter()
                .find(|(k, _)| w == *k || bare == Some(*k))
                .map(|(_, q)| *q)
        })
}

/// [`time_column_unit`], and whether the name is one of [`TIME_COLUMN_NAMES`] (preferred
/// when several columns are named as time columns: `gps_time,time` reads `time`).
fn time_name(name: &str) -> Option<(bool, Option<f64>)> {
    let original = name.trim().trim_start_matches(['#', '%']).trim();
    // Xsens MT Manager's `SampleTimeFine` counts 100 us.
    if original.eq_ignore_ascii_case("sampletimefine") {
        return Some((false, Some(1e-4)));
    }
    let unit_of = |u: &str| {
        let u = u.trim();
        TIME_UNITS.iter().find(|(x, _)| *x == u).map(|(_, s)| *s)
    };
    // HBM catman's time channel: `Time  1 - default sample rate`, its unit in the row under
    // (`[s]` after it then).
    let (bare, unit) = match super::header_unit::bracketed(original) {
        Some((b, u)) => (b, Some(u)),
        None => (original, None),
    };
    let lower = bare.to_ascii_lowercase();
    if lower.starts_with("time") && lower.ends_with("default sample rate") {
        return Some((true, unit.and_then(unit_of)));
    }
    // LabVIEW's x axis (`super::lvm`), in seconds: the first x column is the time column, the
    // others (`X_Columns Multi`) clocks beside it.
    if let Some(k) = super::lvm::x_column_number(original) {
        return Some((k == 1, Some(1.0)));
    }
    // An Arduino sketch's clocks, by the functions that read them: `millis()`, `micros()`;
    // ArduPilot's log stamps (`TimeUS`, older logs' `TimeMS`; its batch messages' `SampleUS`).
    for (clock, unit) in [
        ("millis", 1e-3),
        ("micros", 1e-6),
        ("TimeUS", 1e-6),
        ("TimeMS", 1e-3),
        ("SampleUS", 1e-6),
    ] {
        if original.eq_ignore_ascii_case(clock) {
            return Some((false, Some(unit)));
        }
    }
    let n = camel_words(original).to_ascii_lowercase();
    // `timestamp [ns]`, `time (s)`: the unit in brackets.
    let (base, bracket) = match n.find(['[', '(']) {
        Some(open) => {
            let (base, rest) = n.split_at(open);
            let close = if rest.starts_with('[') { ']' } else { ')' };
            let inner = rest[1..].strip_suffix(close)?.trim();
            let unit = match unit_of(inner) {
                Some(u) => Some(u),
                None if TIME_SCALES.contains(&inner) => None,
                None => return None,
            };
            (base.trim(), Some(unit))
        }
        None => (n.as_str(), None),
    };
    if let Some(unit) = bracket {
        if base == "time_s" {
            return None;
        }
        if TIME_COLUMN_NAMES.contains(&base) {
            return Some((true, unit));
        }
    } else if TIME_COLUMN_NAMES.contains(&base) {
        return Some((true, (base == "time_s").then_some(1.0)));
    }
    let words: Vec<&str> = base
        .split(|c: char| !c.is_alphanumeric())
        .filter(|w| !w.is_empty())
        .collect();
    // `t_ns`, `time_ms`, `timestamp_us`, `sample_time_us`: the unit as the last word.
    let (words, unit) = match (bracket, words.split_last()) {
        (Some(unit), _) => (&words[..], unit),
        (None, Some((last, rest))) if !rest.is_empty() && unit_of(last).is_some() => {
            (rest, unit_of(last))
        }
        _ => (&words[..], None),
    };
    if words == ["t"] && unit.is_some() {
        return Some((true, unit));
    }
    let timeish = (words.iter().any(|w| TIME_WORDS.contains(w))
        || (words.len() == 1 && TIME_ALONE.contains(&words[0])))
        && !words.iter().any(|w| NOT_TIME_WORDS.contains(w));
    let plain = words.len() == 1 && TIME_COLUMN_NAMES.contains(&words[0]);
    timeish.then_some((plain, unit))
}

/// One `--columns` item: the input column `source`, called `name` in the analysis
/// (`gx=g1`, or `gy` to keep the name).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColumnPick {
    pub source: String,
    pub name: String,
}

impl FromStr for ColumnPick {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let (source, name) = s.split_once('=').unwrap_or((s, s));
        let (source, name) = (source.trim(), name.trim());
        if source.is_empty() || name.is_empty() {
            return Err(format!("`{s}`: expected NAME or NAME=NEW_NAME"));
        }
        Ok(ColumnPick {
            source: source.into(),
            name: name.into(),
        })
    }
}

/// `--time-column none`: a column named as a time's is still no channel, but the rows are
/// taken as consecutive samples at `--tau0` and its stamps are not read (a clock in a unit this
/// reader cannot tell, whose step is not `--tau0` in s, ms, us or ns).
pub const NO_TIME_COLUMN: &str = "none";

/// How the columns of a text input become channels.
#[derive(Debug, Clone, Default)]
pub struct TextOptions {
    /// The header name of the time column (skipped); `None` looks for [`TIME_COLUMN_NAMES`];
    /// [`NO_TIME_COLUMN`] looks for them too but does not read their stamps.
    pub time_column: Option<String>,
    /// Only these columns, in this order, renamed; `None` keeps every column but the time one.
    pub columns: Option<Vec<ColumnPick>>,
    /// The sampling step (s): with it, jumps of the time column become gaps
    /// ([`super::time_column`]); without it the time column is only skipped.
    pub tau0_s: Option<f64>,
    /// The channels the run analyses (`--channels`), when it picks some: a cell that is not a
    /// number in any other column is no reason to lose the row (it is read as a gap of a column
    /// nobody looks at). `None`: every column is a channel the run may analyse.
    pub channels: Option<Vec<String>>,
    /// The channels the run analyses hold values on every k-th row only (k >= 2: a file that
    /// merges a slower stream with faster ones, [`super::sampling_step`] finds it): a row where
    /// they are all empty is no sample, and the time column spaces the others (a missing one is
    /// a gap, as ever). Without a time column it does nothing.
    pub sparse_rows: bool,
    /// The values are phase (`--phase`, the running sum of increments): a pulse counter that
    /// turns one pulse a sample counts up by one a row, so no column is taken for the rows'
    /// index ([`Layout::without_index_columns`]).
    pub phase: bool,
}

/// Which input columns are read, and under which names.
#[derive(Debug, Clone)]
struct Layout {
    /// Fields per input row.
    width_in: usize,
    /// The separator of the header (or first data row), tried first on every row.
    sep: Sep,
    /// Input column (0-based) of each channel.
    keep: Vec<usize>,
    /// Per channel: whether a cell that is not a number makes its row a bad row (a channel the
    /// run analyses), or is only a gap of that channel (one `--channels` leaves out).
    strict: Vec<bool>,
    /// Input column names (header or `c1..cn`).
    source_names: Vec<String>,
    /// Channel names.
    names: Vec<String>,
    /// Input column (0-based) of the time stamps, if any.
    time: Option<usize>,
    /// The header is PX4's CSV export's ([`px4_export::is_export`]).
    px4: bool,
    /// `time` is a counter of samples, not a clock ([`TimeColumn::counter`]).
    counter_clock: bool,
    /// How the time column's open dates are read, as its rows have decided so far.
    dates: std::cell::Cell<DateOrder>,
    /// The first time cell that was neither a number nor a time this reads (for a refusal to
    /// quote it).
    unread_stamp: std::cell::RefCell<Option<String>>,
    /// The format the header (and the file's name) tells, which fixes some columns' units and
    /// roles (`super::format_units`).
    format: Option<super::format_units::FileFormat>,
    /// The file has no header row: its columns are named `c1..cn` by their numbers.
    headerless: bool,
}

fn input_error(path: &Path, line: u64, problem: String) -> UsageError {
    UsageError::Input {
        file: path.into(),
        line,
        problem,
    }
}

impl Layout {
    fn new(
        mut source_names: Vec<String>,
        header: bool,
        sep: Sep,
        opts: &TextOptions,
        path: &Path,
        line: u64,
    ) -> Result<Layout, UsageError> {
        let err = |p: String| input_error(path, line, p);
        // Header fields left empty: those after the last name are trailing separators
        // (`g1,g2,`, a spreadsheet's `gx;gy;;;`), their columns no channels unless the rows
        // hold values there ([`Layout::with_unnamed_columns_that_hold_numbers`]); another is
        // named by its column number, as without a header. Before (session 42), only the last
        // was left out: `gx;gy;;;` gave channels `c3` and `c4` with empty curves.
        let named_width = source_names
            .iter()
            .rposition(|n| !n.is_empty())
            .map_or(source_names.len(), |j| j + 1);
        let unnamed_tail = |j: usize| header && j >= named_width;
        for (j, n) in source_names.iter_mut().enumerate() {
            if n.is_empty() && !unnamed_tail(j) {
                *n = format!("c{}", j + 1);
                tracing::warn!(
                    "{}: line {line}: column {} has no name in the header; called `{n}`",
                    path.display(),
                    j + 1
                );
            }
        }
        for (j, n) in source_names
            .iter()
            .enumerate()
            .filter(|(_, n)| !n.is_empty())
        {
            if let Some(i) = source_names[..j].iter().position(|m| m == n) {
                // A DataFlash text log's first line (`FMT, 128, 89, FMT, BBnNZ, ...`) read as
                // a header names `FMT` twice: say what the file is, as its start's sniff does.
                if source_names[0] == "FMT" {
                    return Err(err(format!(
                        "{}, not text columns; {}",
                        super::format_units::DATAFLASH_TEXT,
                        super::format_units::MAVLOGDUMP
                    )));
                }
                return Err(err(format!(
                    "duplicate column name `{n}`: columns {} and {}",
                    i + 1,
                    j + 1
                )));
            }
        }
        // A name as the header writes it, or without its unit when that is unambiguous
        // (`--columns gx` for `gx [deg/s]`).
        let find = |n: &str| {
            source_names.iter().position(|m| m == n).or_else(|| {
                let mut by_base = source_names
                    .iter()
                    .enumerate()
                    .filter(|(_, m)| base_name(m) == n);
                match (by_base.next(), by_base.next()) {
                    (Some((i, _)), None) => Some(i),
                    _ => None,
                }
            })
        };
        // The fields a format fixes (ArduPilot's error counts and health flags beside its
        // `GyrX`, its temperature `T`, which is no clock).
        let format = header
            .then(|| super::format_units::file_format(&source_names, path))
            .flatten();
        let clock =
            |n: &str| time_name(n).filter(|_| format.and_then(|f| f.temperature(n)).is_none());
        // (Not when the run names the stamp as a channel.)
        let ros_echo_stamp = source_names
            .iter()
            .any(|n| n == "%time")
            .then(|| {
                source_names
                    .iter()
                    .position(|n| n == "field.header.stamp" && !named_by_run(n, opts))
            })
            .flatten();
        let time = match opts.time_column.as_deref().filter(|t| *t != NO_TIME_COLUMN) {
            Some(t) => Some(find(t).ok_or_else(|| {
                err(format!(
                    "--time-column `{t}`: no such column (the header has {})",
                    source_names.join(", ")
                ))
            })?),
            // ArduPilot's batch messages (`GYR`, `ACC`): each sample's own stamp, `SampleUS`
            // (their `TimeUS` and `timestamp` are the batch's).
            None if header
                && format == Some(super::format_units::FileFormat::ArduPilot)
                && source_names.iter().any(|n| n == "SampleUS") =>
            {
                source_names.iter().position(|n| n == "SampleUS")
            }
            // A ROS 1 `rostopic echo -p` export: the message's own stamp, `field.header.stamp`
            // (the driver's time of the sample), before `%time`, the time the recorder received
            // it. A review's 1 kHz exports were refused on `%time`'s latency jitter, and those
            // read on it had their step 0.1-0.4% off and thousands of samples called missing.
            // Else a column named `time` before one whose name only holds a time word.
            None if header => ros_echo_stamp
                .or_else(|| {
                    source_names
                        .iter()
                        .position(|n| clock(n).is_some_and(|(plain, _)| plain))
                })
                .or_else(|| source_names.iter().position(|n| clock(n).is_some())),
            None => None,
        };
        // A column `--channels` names is a channel, whatever its name says.
        let named = |n: &str| {
            opts.channels
                .as_ref()
                .is_some_and(|c| c.iter().any(|x| x == n || x == base_name(n)))
        };
        // No time column, but a counter of samples (`PacketCounter`): it finds the missing
        // samples (`TimeColumn::counter`), once the run knows its step.
        let counter_clock = time.is_none() && header && opts.tau0_s.is_some();
        let (time, counter_clock) = match counter_clock
            .then(|| {
                // (Not a count of events: errors, clippings, calibrations, drops.)
                let events = |n: &String| {
                    let n = n.to_ascii_lowercase();
                    ["error", "clip", "calib", "overflow", "drop", "fail", "retr"]
                        .iter()
                        .any(|w| n.contains(w))
                };
                source_names
                    .iter()
                    .position(|n| counter_column(n) && !named(n) && !events(n))
            })
            .flatten()
        {
            Some(i) => (Some(i), true),
            None => (time, false),
        };
        // Every other column named as a time column (ROS's `field.header.stamp` beside `%time`)
        // is a clock too, not a channel, unless the run names it.
        // PX4's CSV export: its fields that describe samples (intervals, relative stamps,
        // clipping, ids) are no channels either (`super::px4_export`).
        let px4 = header && px4_export::is_export(&source_names);
        let bookkeeping = |i: usize| px4 && px4_export::bookkeeping(&source_names[i]);
        // A magnetometer's or a barometer's column by its unit (`mag_x [uT]`), a status word, a
        // magnetic field or a magnitude by its name (`Status`, `Mag_X`, `Absolute`), and the
        // fields a format fixes, are no channels: `(what it holds, what says so)`.
        let other_quantity = |i: usize| {
            let n = &source_names[i];
            header
                .then(|| {
                    super::header_unit::other_quantity(n)
                        .map(|q| (q, "its unit"))
                        .or_else(|| named_quantity(n).map(|q| (q, "its name")))
                        .or_else(|| format.and_then(|f| Some((f.other_column(n)?, f.source()))))
                })
                .flatten()
        };
        let other_clock = |i: usize| {
            Some(i) != time
                && ((time.is_some() && clock(&source_names[i]).is_some())
                    || counter_column(&source_names[i])
                    || bookkeeping(i)
                    || other_quantity(i).is_some())
                && !named(&source_names[i])
        };
        let (keep, names) = match &opts.columns {
            Some(picks) => {
                let mut keep = Vec::new();
                let mut names: Vec<String> = Vec::new();
                for p in picks {
                    let i = find(&p.source).ok_or_else(|| {
                        err(format!(
                            "--columns: no column named `{}` (the input has {})",
                            p.source,
                            source_names.join(", ")
                        ))
                    })?;
                    if names.contains(&p.name) {
                        return Err(err(format!(
                            "--columns: the name `{}` is given twice",
                            p.name
                        )));
                    }
                    keep.push(i);
                    names.push(p.name.clone());
                }
                // The unit's temperature, when the input has one the list leaves out, is still
                // read beside the channels it names (it is no channel: the diagnosis fits the
                // bias's dependence on it). A review's `--columns "gx=gx [rad/s],..."` lost the
                // file's `temperature_c` without a word.
                for (i, n) in source_names.iter().enumerate() {
                    let temperature = input_temperature(n, format).is_some();
                    let listed = keep.contains(&i) || names.contains(n);
                    if !header || !temperature || listed || Some(i) == time {
                        continue;
                    }
                    tracing::info!(
                        "{}: column {} `{n}` holds the unit's temperature: read beside the \
                         channels --columns names",
                        path.display(),
                        i + 1
                    );
                    keep.push(i);
                    names.push(n.clone());
                }
                (keep, names)
            }
            None => {
                for i in (0..source_names.len()).filter(|&i| other_clock(i)) {
                    let (what, how) = if counter_column(&source_names[i]) {
                        ("is a counter".to_string(), "")
                    } else if bookkeeping(i) {
                        ("is a PX4 field that describes samples".to_string(), "")
                    } else if let Some((q, by)) = other_quantity(i) {
                        let how = if by == "its unit" {
                            ", with --unit U,"
                        } else {
                            ""
                        };
                        (format!("holds {q}, by {by}"), how)
                    } else {
                        ("is a second time column".to_string(), "")
                    };
                    tracing::info!(
                        "{}: column {} `{}` {what}: not a channel (name it in --channels{how} \
                         to analyse it)",
                        path.display(),
                        i + 1,
                        source_names[i]
                    );
                }
                (0..source_names.len())
                    .filter(|&i| Some(i) != time && !unnamed_tail(i) && !other_clock(i))
                    .map(|i| (i, source_names[i].clone()))
                    .unzip()
            }
        };
        if keep.is_empty() {
            // Say which columns were left out and why, when some were.
            let out: Vec<String> = (0..source_names.len())
                .filter(|&i| other_clock(i))
                .map(|i| match other_quantity(i) {
                    Some((q, _)) => format!("`{}` ({q})", source_names[i]),
                    None => format!("`{}`", source_names[i]),
                })
                .collect();
            let problem = if out.is_empty() {
                "no data column (only a time column)".to_string()
            } else {
                format!(
                    "no data column: {}only columns that are no channels: {} (name one in \
                     --channels, with --unit U for a unit allanscope does not read, to analyse \
                     it)",
                    if time.is_some() {
                        "beside the time, "
                    } else {
                        ""
                    },
                    out.join(", ")
                )
            };
            return Err(err(problem));
        }
        let strict = names.iter().map(|n| analysed(n, opts)).collect();
        Ok(Layout {
            width_in: source_names.len(),
            sep,
            keep,
            strict,
            source_names,
            names,
            time,
            px4,
            counter_clock,
            dates: Default::default(),
            unread_stamp: Default::default(),
            format,
            headerless: !header,
        })
    }

    /// The layout with a row of units under the header read (`units`, one per input column):
    /// each column's name takes its unit in brackets (`gx` -> `gx [deg/s]`, where the header
    /// gave none), so that it is read as a unit in the header is, and a column in seconds named
    /// as a time column is the time column; the channels keep the names the header gives.
    fn with_units(
        self,
        units: &[String],
        opts: &TextOptions,
        path: &Path,
        line: u64,
    ) -> Result<Layout, UsageError> {
        let bare = self.source_names.clone();
        let named: Vec<String> = bare
            .iter()
            .zip(units)
            .map(|(n, u)| {
                if u.is_empty() || parse_field(u).is_ok() || base_name(n) != n.trim() {
                    n.clone()
                } else {
                    format!("{n} [{u}]")
                }
            })
            .collect();
        let mut l = Layout::new(named, true, self.sep, opts, path, line)?;
        if opts.columns.is_none() {
            l.names = l.keep.iter().map(|&i| bare[i].clone()).collect();
            l.strict = l.names.iter().map(|n| analysed(n, opts)).collect();
        }
        Ok(l)
    }

    /// The first data row `t` read with this layout, and the layout without the label columns
    /// it shows: when a column it analyses holds text there, the next [`AHEAD_LINES`] lines of
    /// `src` are read into `ahead` to tell labels from flagged samples
    /// ([`Layout::without_label_columns`]). A row of the wrong width, or a damaged number, is
    /// a bad row, as later.
    fn first_row<R: BufRead>(
        self,
        t: &str,
        src: &mut R,
        ahead: &mut VecDeque<(Vec<u8>, usize, bool)>,
        opts: &TextOptions,
        path: &Path,
        line: u64,
    ) -> Result<(Row, Layout), UsageError> {
        fill_ahead(src, ahead, AHEAD_LINES)
            .map_err(|e| input_error(path, line + 1, e.to_string()))?;
        let rows_ahead = ahead_text(ahead);
        let l = self.with_unnamed_columns_that_hold_numbers(t, &rows_ahead, opts, path, line);
        let l = if l.has_text_cells(t) {
            l.without_label_columns(t, &rows_ahead, opts, path, line)?
        } else {
            l
        };
        let l = l.without_index_columns(t, &rows_ahead, opts, path, line);
        let l = l.with_unnamed_clock(t, &rows_ahead, opts, path, line);
        l.check_interleaved(t, &rows_ahead, opts, path, line)?;
        Ok(match l.parse(t) {
            Ok((v, time)) => ((Ok(v), time), l),
            Err(problem) => ((Err(problem), f64::NAN), l),
        })
    }

    /// The layout with the columns after the header's last name ([`Layout::new`]: no name, so
    /// far no channel) that hold a number in the first data row `t` or a row `ahead` made
    /// channels, named by their column number (`c3`) as an unnamed column before a name is. The
    /// others are trailing separators and stay no channel (text in them, as a LabVIEW file's
    /// `Comment` column or a second segment's names, is no number): a number in them after the
    /// rows read ahead is not read.
    fn with_unnamed_columns_that_hold_numbers(
        mut self,
        t: &str,
        ahead: &[String],
        opts: &TextOptions,
        path: &Path,
        line: u64,
    ) -> Layout {
        if opts.columns.is_some() || self.sep == Sep::Labelled {
            return self;
        }
        let rows = self.full_rows(t, ahead);
        for j in 0..self.width_in {
            let held = |f: &Vec<&str>| parse_field(f[j]).is_ok_and(|v| !v.is_nan());
            if !self.source_names[j].is_empty() || !rows.iter().any(held) {
                continue;
            }
            let n = format!("c{}", j + 1);
            tracing::warn!(
                "{}: line {line}: column {} has no name in the header but holds numbers; \
                 called `{n}`",
                path.display(),
                j + 1
            );
            self.source_names[j] = n.clone();
            self.keep.push(j);
            self.strict.push(analysed(&n, opts));
            self.names.push(n);
        }
        self
    }

    /// Whether a column the run analyses holds in the first data row `t` a cell that is not a
    /// number (nor empty or a missing-value marker): a label column, or a channel whose first
    /// sample is flagged, told apart by the rows after it ([`Layout::without_label_columns`]).
    fn has_text_cells(&self, t: &str) -> bool {
        let fields = self.split(t);
        fields.len() == self.width_in
            && self
                .keep
                .iter()
                .zip(&self.strict)
                .any(|(&i, &strict)| strict && parse_field(fields[i]).is_err())
    }

    /// The layout without the columns whose cell in the first data row `t` is text, not a
    /// number, and which hold no number in the rows read ahead (`ahead`, the next lines of the
    /// input): a ROS `rostopic echo -p` export's `field.header.frame_id` (`imu_link`), a
    /// logger's status word. Such a column holds labels, not samples; it is left out, said in
    /// the log, unless the run named it (`--columns`, or `--channels`), which is an error as
    /// before. A column with numbers ahead is a channel whose first cell is flagged (`ERR`: a
    /// gap of it) or damaged (a bad row). Columns `--channels` leaves out are kept: their cells
    /// are never needed.
    fn without_label_columns(
        mut self,
        t: &str,
        ahead: &[String],
        opts: &TextOptions,
        path: &Path,
        line: u64,
    ) -> Result<Layout, UsageError> {
        let fields = self.split(t);
        let mut k = 0;
        while k < self.keep.len() {
            let i = self.keep[k];
            let cell = fields[i].trim();
            if !self.strict[k] || parse_field(cell).is_ok() {
                k += 1;
                continue;
            }
            let numbers_ahead = ahead.iter().any(|row| {
                let f = self.split(row.trim());
                f.len() == self.width_in && parse_field(f[i]).is_ok_and(|v| !v.is_nan())
            });
            if numbers_ahead {
                k += 1;
                continue;
            }
            let named = opts.columns.is_some()
                || opts
                    .channels
                    .as_ref()
                    .is_some_and(|c| c.contains(&self.names[k]));
            let only_text = cell.bytes().any(|b| b.is_ascii_alphabetic() || b == b'_');
            if named || !only_text {
                return Err(input_error(
                    path,
                    line,
                    format!(
                        "the first data row: column {} `{}`: `{cell}` is not a number",
                        i + 1,
                        self.source_names[i]
                    ),
                ));
            }
            tracing::warn!(
                "{}: line {line}: column {} `{}` holds text (`{cell}`), not numbers: left out, \
                 not a channel",
                path.display(),
                i + 1,
                self.source_names[i]
            );
            self.keep.remove(k);
            self.names.remove(k);
            self.strict.remove(k);
        }
        if self.keep.is_empty() {
            return Err(input_error(
                path,
                line,
                "no data column: the first data row holds text in every column but the time".into(),
            ));
        }
        Ok(self)
    }

    /// The layout without the columns that number the rows: whole numbers stepping by exactly
    /// one from the first data row `t` through each of the rows read ahead (at least
    /// [`INDEX_ROWS`] rows in all), with no unit in the name, as pandas' unnamed index
    /// (`,time,gx`), a dataset's `id` or a logger's `Sample` column hold. No sensor's samples
    /// count up so; such a column is left out, said in the log, unless the run names it
    /// (`--columns`, `--channels`) or reads phase (`--phase`: a pulse counter may count one a
    /// row). It is not taken as a clock: an index that skips or restarts (rows dropped, files
    /// concatenated) need not count samples.
    fn without_index_columns(
        mut self,
        t: &str,
        ahead: &[String],
        opts: &TextOptions,
        path: &Path,
        line: u64,
    ) -> Layout {
        if opts.columns.is_some() || opts.phase || self.sep == Sep::Labelled {
            return self;
        }
        let Some(rows) = self.rows_to_judge(t, ahead) else {
            return self;
        };
        let counts_rows = |i: usize| {
            let mut last: Option<f64> = None;
            rows.iter().all(|f| match parse_field(f[i]) {
                Ok(v) if v.is_finite() && v.fract() == 0.0 && v.abs() < 1e15 => {
                    let one = last.is_none_or(|l| v - l == 1.0);
                    last = Some(v);
                    one
                }
                _ => false,
            })
        };
        let index: Vec<bool> = self
            .keep
            .iter()
            .zip(&self.names)
            .map(|(&i, n)| {
                let named = opts
                    .channels
                    .as_ref()
                    .is_some_and(|c| c.iter().any(|x| super::header_unit::names_channel(x, n)));
                let unit = super::header_unit::bracketed(&self.source_names[i]).is_some();
                !named && !unit && counts_rows(i)
            })
            .collect();
        // A file of nothing but such columns is analysed as it is.
        if index.iter().all(|&x| x) {
            return self;
        }
        for k in (0..index.len()).rev().filter(|&k| index[k]) {
            let i = self.keep[k];
            tracing::info!(
                "{}: line {line}: column {} `{}` numbers the rows (whole numbers stepping by one): \
                 an index, not a channel (name it in --channels to analyse it)",
                path.display(),
                i + 1,
                self.source_names[i],
            );
            self.keep.remove(k);
            self.names.remove(k);
            self.strict.remove(k);
        }
        self
    }

    /// The layout with a headerless file's first column read as its clock when it steps like
    /// one: every step from the first data row `t` through the rows `ahead` (at least
    /// [`INDEX_ROWS`]) positive and within [`CLOCK_STEP_SPREAD`] of their median or of a whole
    /// number of it (samples missing), nine in ten of them one median, and that
    /// median `tau0` in seconds, milliseconds, microseconds or nanoseconds (within
    /// [`CLOCK_TAU0_MATCH`]). No sensor's increments or rates rise so evenly, and by the step
    /// the run gave; a running sum (`--phase`) may, and is never judged. Before (session 49),
    /// such a column (`t,gx` exported without its names) was analysed as a channel whose
    /// covariance was not positive definite. A column that steps as evenly by another step is
    /// left a channel, and the log says the run's tau0 may be wrong. `--columns`,
    /// `--channels` naming the column, or `--time-column` (a name, or `none`) leave it alone.
    fn with_unnamed_clock(
        mut self,
        t: &str,
        ahead: &[String],
        opts: &TextOptions,
        path: &Path,
        line: u64,
    ) -> Layout {
        let Some(tau0) = opts.tau0_s else {
            return self;
        };
        if !self.headerless
            || self.time.is_some()
            || self.keep.len() < 2
            || opts.columns.is_some()
            || opts.phase
            || opts.time_column.is_some()
            || self.sep == Sep::Labelled
            || opts
                .channels
                .as_ref()
                .is_some_and(|c| c.contains(&self.names[0]))
        {
            return self;
        }
        let Some(rows) = self.rows_to_judge(t, ahead) else {
            return self;
        };
        let i = self.keep[0];
        let Some(values) = rows
            .iter()
            .map(|f| parse_field(f[i]).ok().filter(|v| v.is_finite()))
            .collect::<Option<Vec<f64>>>()
        else {
            return self;
        };
        let mut steps: Vec<f64> = values.windows(2).map(|p| p[1] - p[0]).collect();
        if steps.iter().any(|&d| d <= 0.0 || !d.is_finite()) {
            return self;
        }
        steps.sort_by(f64::total_cmp);
        let median = steps[steps.len() / 2];
        // A step over missing samples is a whole number `k` of steps; the clock's step is the
        // span over the steps so counted (stamps that jitter leave the median off by their
        // jitter, the span by a share of it).
        let ks: Vec<f64> = steps
            .iter()
            .map(|&d| (d / median).round().max(1.0))
            .collect();
        let whole = steps
            .iter()
            .zip(&ks)
            .all(|(&d, &k)| (d - k * median).abs() <= CLOCK_STEP_SPREAD * median);
        let single = ks.iter().filter(|&&k| k == 1.0).count();
        if !whole || 10 * single < 9 * steps.len() {
            return self;
        }
        let mean = (values[values.len() - 1] - values[0]) / ks.iter().sum::<f64>();
        let scale = [1.0, 1e3, 1e6, 1e9]
            .into_iter()
            .find(|s| (mean / s - tau0).abs() <= CLOCK_TAU0_MATCH * tau0);
        // The step to six digits, as the stamps print it (not `0.0050000000000000044`).
        let step = crate::ranges::show(super::sampling_step::round_significant(mean, 6));
        match scale {
            Some(_) => {
                tracing::info!(
                    "{}: line {line}: column {} `{}` rises by {step} a row, as a clock stepping \
                     by tau0 ({tau0} s) does: read as the time column, not a channel (name it \
                     in --channels, or pass --time-column none, to analyse it)",
                    path.display(),
                    i + 1,
                    self.source_names[i],
                );
                self.time = Some(i);
                self.keep.remove(0);
                self.names.remove(0);
                self.strict.remove(0);
            }
            None => tracing::warn!(
                "{}: line {line}: column {} `{}` rises by {step} on every row, as a clock \
                 does, but --tau0 is {tau0} s: analysed as a channel; if it is the time, check \
                 the sampling step",
                path.display(),
                i + 1,
                self.source_names[i],
            ),
        }
        self
    }

    /// The first data row `t` and the rows `ahead` of this layout's width, split, when there
    /// are [`INDEX_ROWS`] of them to judge a column's role by; `None` with fewer.
    fn rows_to_judge<'a>(&self, t: &'a str, ahead: &'a [String]) -> Option<Vec<Vec<&'a str>>> {
        let rows = self.full_rows(t, ahead);
        (rows.len() >= INDEX_ROWS).then_some(rows)
    }

    /// The fields of the first data row `t` and of the rows read `ahead` that have the layout's
    /// full width (a short or long row is left out).
    fn full_rows<'a>(&self, t: &'a str, ahead: &'a [String]) -> Vec<Vec<&'a str>> {
        std::iter::once(t)
            .chain(ahead.iter().map(String::as_str))
            .map(|r| self.split(r.trim()))
            .filter(|f| f.len() == self.width_in)
            .collect()
    }

    /// An error when a column named as an instance number ([`INSTANCE_NAMES`]: ArduPilot's `I`
    /// in a `mavlogdump.py` CSV, a `sensor_id`) holds 2 to [`INSTANCE_MAX`] whole numbers, each
    /// on several of the first row `t` and the rows `ahead`: the rows of as many sensors
    /// interleave, and a channel would hold their samples in turn (one curve of two units, its
    /// step read between them). The same column holding one number (one sensor) is no error.
    fn check_interleaved(
        &self,
        t: &str,
        ahead: &[String],
        opts: &TextOptions,
        path: &Path,
        line: u64,
    ) -> Result<(), UsageError> {
        if self.sep == Sep::Labelled {
            return Ok(());
        }
        let ardupilot = self.format == Some(super::format_units::FileFormat::ArduPilot);
        // A column the run names is a channel, as the run says.
        let named = |n: &str| named_by_run(n, opts);
        let Some(rows) = self.rows_to_judge(t, ahead) else {
            return Ok(());
        };
        for (i, name) in self.source_names.iter().enumerate() {
            if !instance_column(name, ardupilot) || named(name) {
                continue;
            }
            let mut seen: Vec<(i64, usize)> = Vec::new();
            for f in &rows {
                // Sensor numbers: small whole numbers from 0.
                let Some(v) = parse_field(f[i])
                    .ok()
                    .filter(|v| v.fract() == 0.0 && (0.0..=255.0).contains(v))
                else {
                    return Ok(());
                };
                let v = v as i64;
                match seen.iter_mut().find(|(x, _)| *x == v) {
                    Some((_, k)) => *k += 1,
                    None => seen.push((v, 1)),
                }
            }
            if (2..=INSTANCE_MAX).contains(&seen.len()) && seen.iter().all(|&(_, k)| k >= 2) {
                let values: Vec<String> = seen.iter().map(|(v, _)| v.to_string()).collect();
                let sep = match self.sep {
                    Sep::Comma => " -F,",
                    Sep::Semicolon => " -F';'",
                    Sep::Tab => " -F'\\t'",
                    _ => "",
                };
                // The path as a shell reads it: in single quotes unless it needs none.
                let shown = path.display().to_string();
                let quoted = if shown
                    .bytes()
                    .all(|b| b.is_ascii_alphanumeric() || b"._/-+".contains(&b))
                {
                    shown
                } else {
                    format!("'{}'", shown.replace('\'', "'\\''"))
                };
                return Err(input_error(
                    path,
                    line,
                    format!(
                        "column {} `{name}` numbers {} sensors ({}) whose rows share the file \
                         (interleaved or one after another): a channel would hold the samples of \
                         all. Analyse one sensor's rows at a time: `awk{sep} '!/^[-+0-9.]/ || ${} == {}' {quoted} > one.csv` keeps \
                         the lines that are no rows (the header, notes) and the first sensor's \
                         rows; or name the column in --channels to read it as a channel",
                        i + 1,
                        seen.len(),
                        values.join(", "),
                        i + 1,
                        seen[0].0,
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The channel values of a row and its time stamp (NaN without a time column or where the
    /// stamp is not a number), or what is wrong with the row.
    fn parse(&self, t: &str) -> Result<(Vec<f64>, f64), String> {
        let fields = match self.labelled_fields(t) {
            Some(fields) => fields?,
            None => self.split(t),
        };
        if fields.len() != self.width_in {
            return Err(format!(
                "{} fields, expected {}",
                fields.len(),
                self.width_in
            ));
        }
        let values = self
            .keep
            .iter()
            .zip(&self.strict)
            .map(|(&i, &strict)| {
                let v = parse_field(fields[i]);
                if !strict {
                    // A column the run does not analyse: what is not a number is a gap.
                    return Ok(v.unwrap_or(f64::NAN));
                }
                v.or_else(|()| {
                    if word_cell(fields[i]) {
                        Ok(f64::from_bits(WORD_CELL_BITS))
                    } else {
                        Err(())
                    }
                })
                .map_err(|()| {
                    format!(
                        "column {} `{}`: `{}` is not a number",
                        i + 1,
                        self.source_names[i],
                        fields[i].trim()
                    )
                })
            })
            .collect::<Result<Vec<f64>, String>>()?;
        // A row whose every analysed cell is a word holds no sample: text where the data
        // should be (another file's header joined in, a log line), a bad row.
        let analysed = self.strict.iter().filter(|&&s| s).count();
        let words = values
            .iter()
            .zip(&self.strict)
            .filter(|(x, &s)| s && x.to_bits() == WORD_CELL_BITS)
            .count();
        if analysed > 0 && words == analysed {
            return Err(format!(
                "no number in the row, only words (`{}`)",
                self.keep
                    .iter()
                    .map(|&i| fields[i].trim())
                    .collect::<Vec<_>>()
                    .join("`, `")
            ));
        }
        let time = self.time.and_then(|i| {
            let t = parse_field(fields[i])
                .ok()
                .or_else(|| self.stamp(fields[i]));
            let cell = fields[i].trim();
            if t.is_none() && !cell.is_empty() {
                let mut first = self.unread_stamp.borrow_mut();
                if first.is_none() {
                    *first = Some(cell.chars().take(40).collect());
                }
            }
            t
        });
        Ok((values, time.unwrap_or(f64::NAN)))
    }
}

impl Layout {
    /// The stamps of the first rows that are samples, as the reader meets them: `first` (the
    /// first data row's) and those of the rows `ahead` ([`TextReader::not_a_sample`]'s rows
    /// and rows that cannot be read left out, as are empty stamps), at most
    /// [`FIRST_STEPS`]` + 1`. The rows are read again as they come: the order of the dates
    /// read so far is left as it was.
    fn first_stamps(&self, first: f64, ahead: &[String], sparse: bool) -> Vec<f64> {
        let (dates, unread) = (self.dates.get(), self.unread_stamp.borrow().clone());
        let mut stamps = vec![first];
        for row in ahead {
            if stamps.len() > FIRST_STEPS {
                break;
            }
            let Ok((v, t)) = self.parse(row) else {
                continue;
            };
            let p: Row = (Ok(v), t);
            if t.is_nan() || (sparse && empty_row(&p, &self.strict)) {
                continue;
            }
            stamps.push(t);
        }
        self.dates.set(dates);
        *self.unread_stamp.borrow_mut() = unread;
        stamps.retain(|t| !t.is_nan());
        stamps
    }

    /// A time stamp written as a date and time ([`date_time`]), an open date (`03/12/2026`)
    /// read in the order the file's rows decide ([`DateOrder`]).
    fn stamp(&self, field: &str) -> Option<f64> {
        let mut order = self.dates.get();
        let t = order.stamp(field);
        self.dates.set(order);
        t
    }

    /// The fields of a row: split at the header's separator, or, when that does not give the
    /// header's width, as the row itself suggests (a row written with spaces in a comma file).
    fn split<'a>(&self, t: &'a str) -> Vec<&'a str> {
        // A row of labelled values that cannot be laid out: a row of the wrong width (a bad
        // row), whose problem `parse` says.
        match self.labelled_fields(t) {
            Some(Ok(fields)) => return fields,
            Some(Err(_)) => return vec![""; self.width_in + 1],
            None => {}
        }
        let mut fields = self.sep.split(t);
        // Last columns with no name and no values (LabVIEW's `Comment`, a spreadsheet's
        // `gx;gy;;;`): the separators before their empty cells were trimmed off with the line's
        // white space, or the row leaves them out.
        if fields.len() < self.width_in
            && self.source_names[fields.len()..]
                .iter()
                .all(String::is_empty)
        {
            fields.resize(self.width_in, "");
        }
        if fields.len() == self.width_in {
            fields
        } else {
            split(t)
        }
    }

    /// The input column and text of the last cell of the row `t` as written (the one a line
    /// cut while written ends in), `None` for a row not of the header's width. Last columns
    /// with no name that the row leaves out ([`Layout::split`]) are not its cells.
    fn last_cell<'a>(&self, t: &'a str) -> Option<(usize, &'a str)> {
        if let Some(fields) = self.labelled_fields(t) {
            fields.ok()?;
            let (label, value) = *labelled_cells(t)?.last()?;
            let i = self.source_names.iter().position(|n| n == label)?;
            return Some((i, value));
        }
        let raw = self.sep.split(t);
        let fields = if raw.len() < self.width_in
            && self.source_names[raw.len()..].iter().all(String::is_empty)
        {
            raw
        } else {
            self.split(t)
        };
        if fields.is_empty() || fields.len() > self.width_in {
            return None;
        }
        Some((fields.len() - 1, *fields.last()?))
    }

    /// The cell of input column `i` in the row `t`, if it has one.
    fn cell_at<'a>(&self, t: &'a str, i: usize) -> Option<&'a str> {
        match self.labelled_fields(t) {
            Some(fields) => fields.ok()?.get(i).copied(),
            None => self.split(t).get(i).copied(),
        }
    }

    /// A row of labelled values ([`Sep::Labelled`]) laid out under the names, in their order:
    /// each value under its label, a label left out an empty field (a gap); or what keeps it
    /// from being laid out (more values than names, a label none of the names, a label twice).
    /// `None` for a layout of another separator, or a line that is not labelled values (split
    /// as the line itself suggests).
    fn labelled_fields<'a>(&self, t: &'a str) -> Option<Result<Vec<&'a str>, String>> {
        if self.sep != Sep::Labelled {
            return None;
        }
        let pairs = labelled_cells(t)?;
        if pairs.len() > self.width_in {
            return Some(Err(format!(
                "{} labelled values, more than the {} names",
                pairs.len(),
                self.width_in
            )));
        }
        let known = |l: &&str| self.source_names.iter().any(|n| n == l);
        if let Some((l, _)) = pairs.iter().find(|(l, _)| !known(l)) {
            return Some(Err(format!(
                "label `{l}` is none of the names ({})",
                self.source_names.join(", ")
            )));
        }
        if let Some((i, (l, _))) = pairs
            .iter()
            .enumerate()
            .find(|(i, (l, _))| pairs[..*i].iter().any(|(m, _)| m == l))
        {
            return Some(Err(format!("label `{l}` twice (pair {})", i + 1)));
        }
        Some(Ok(self
            .source_names
            .iter()
            .map(|n| pairs.iter().find(|(l, _)| l == n).map_or("", |(_, v)| *v))
            .collect()))
    }
}

/// Lines read past the first data row when a column holds text there, to see whether it
/// holds numbers later (a flagged first sample) or never (a label).
const AHEAD_LINES: usize = 256;

/// Rows (the first data row and those read ahead) a column must number one by one to be taken
/// as the rows' index ([`Layout::without_index_columns`]).
const INDEX_ROWS: usize = 16;

/// How far a clock's steps may stray from their median, as a share of it
/// ([`Layout::with_unnamed_clock`]): a logger's stamps jitter by a few percent of a step, and
/// a step between two of them by twice that.
const CLOCK_STEP_SPREAD: f64 = 0.25;

/// How close a headerless clock's median step must come to tau0 (in one of the units
/// [`Layout::with_unnamed_clock`] tries), as a share of tau0.
const CLOCK_TAU0_MATCH: f64 = 0.02;

/// Names (lower case, camel case split with `_`) of a column that numbers the sensor a row is
/// of, when one file holds several ([`Layout::check_interleaved`]): ArduPilot's `I` (`IMU`,
/// `GYR`, `ACC` messages: [`instance_column`]), `instance`, `sensor_id`, `imu_id`.
const INSTANCE_NAMES: [&str; 9] = [
    "inst",
    "instance",
    "imu_id",
    "imu_index",
    "imu_instance",
    "sensor_id",
    "sensor_index",
    "sensor_instance",
    "device_id",
];

/// The most sensors an instance column numbers ([`Layout::check_interleaved`]).
const INSTANCE_MAX: usize = 8;

/// The next line into `buf`: the first of those read ahead, else one of `src`; the bytes it
/// took in the input and whether it was longer than [`MAX_LINE_BYTES`] (0 bytes: the end).
fn next_line<R: BufRead>(
    src: &mut R,
    ahead: &mut VecDeque<(Vec<u8>, usize, bool)>,
    buf: &mut Vec<u8>,
) -> std::io::Result<(usize, bool)> {
    match ahead.pop_front() {
        Some((bytes, got, long)) => {
            *buf = bytes;
            Ok((got, long))
        }
        None => read_line_bounded(src, buf, MAX_LINE_BYTES),
    }
}

/// Lines of `src` added to `ahead` (as [`TextReader::ahead`] holds them) until it holds `n`,
/// or the input ends.
fn fill_ahead<R: BufRead>(
    src: &mut R,
    ahead: &mut VecDeque<(Vec<u8>, usize, bool)>,
    n: usize,
) -> std::io::Result<()> {
    while ahead.len() < n {
        let mut buf = Vec::new();
        let (got, long) = read_line_bounded(src, &mut buf, MAX_LINE_BYTES)?;
        if got == 0 {
            break;
        }
        ahead.push_back((buf, got, long));
    }
    Ok(())
}

/// The data lines among lines read ahead (comments and empty lines left out).
fn ahead_text(ahead: &VecDeque<(Vec<u8>, usize, bool)>) -> Vec<String> {
    ahead
        .iter()
        .map(|(b, _, _)| String::from_utf8_lossy(b).trim().to_string())
        .filter(|t| !t.is_empty() && !is_note(t))
        .collect()
}

/// A column's name without the unit in brackets at its end (`gx [deg/s]` -> `gx`).
fn base_name(n: &str) -> &str {
    super::header_unit::bracketed(n).map_or(n.trim(), |(base, _)| base)
}

/// A line of notes, not of data: `#` (a commented header is looked for before the first data
/// row) or `//` (an exporter's notes, as Xsens MT Manager writes them).
fn is_note(t: &str) -> bool {
    t.starts_with('#') || t.starts_with("//")
}

/// The temperature scale of an input column named `n` that holds the unit's temperature: by
/// its name ([`super::temperature_column`]) or by the file's `format` (ArduPilot's `T`).
fn input_temperature(
    n: &str,
    format: Option<super::format_units::FileFormat>,
) -> Option<super::temperature_column::TemperatureScale> {
    super::temperature_column::temperature_column(n).or_else(|| format?.temperature(n))
}

/// Whether the run names the column `n` in `--channels` or `--columns`.
fn named_by_run(n: &str, opts: &TextOptions) -> bool {
    opts.channels
        .as_ref()
        .is_some_and(|c| c.iter().any(|x| x == n))
        || opts
            .columns
            .as_ref()
            .is_some_and(|c| c.iter().any(|p| p.source == n))
}

/// Whether a column named `n` is one the run analyses (`--channels`, or every column).
fn analysed(n: &str, opts: &TextOptions) -> bool {
    opts.channels
        .as_ref()
        .is_none_or(|c| c.iter().any(|x| super::header_unit::names_channel(x, n)))
}

/// Whether a row holds no value in any column the run analyses (`strict`): empty cells, `nan`
/// or missing-value markers (a word is a value that was flagged, not an empty cell).
fn empty_row(p: &Row, strict: &[bool]) -> bool {
    let Ok(v) = &p.0 else { return false };
    v.iter()
        .zip(strict)
        .all(|(x, &s)| !s || (x.is_nan() && x.to_bits() != WORD_CELL_BITS))
}

/// A row as read: its values or what is wrong with it, and its time stamp (NaN if none).
type Row = (Result<Vec<f64>, String>, f64);

/// Whether two rows' values and stamps are the same record written twice: a finite stamp equal
/// to the other's, and the values bit for bit (NaN equal to NaN).
fn same_record((a, ta): (&[f64], f64), (b, tb): (&[f64], f64)) -> bool {
    let same = |x: &f64, y: &f64| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan());
    ta.is_finite() && ta == tb && a.len() == b.len() && a.iter().zip(b).all(|(x, y)| same(x, y))
}

/// A row's time stamp (NaN when it has none) and which analysed channels hold a value there
/// ([`TextReader::take_stamps`]).
pub type RowStamp = (f64, Vec<bool>);

pub struct TextReader<R> {
    src: R,
    path: PathBuf,
    line_no: u64,
    layout: Layout,
    names: Vec<String>,
    /// The next row to hand out: the first data row, read while looking for a header, or the
    /// row after a jump of the time column, held while the gap steps before it go out.
    pending: Option<Row>,
    /// [`TextOptions::sparse_rows`].
    sparse: bool,
    /// The header's fields (and a units row's): a line that repeats one later is skipped (logs
    /// joined into one file), counted.
    header_rows: Vec<Vec<String>>,
    header_repeats: u64,
    /// Lines read ahead of the first data row to tell label columns from channels: each line's
    /// bytes (at most [`MAX_LINE_BYTES`]), the bytes it took in the input, whether it was longer.
    ahead: VecDeque<(Vec<u8>, usize, bool)>,
    /// Cells of channels that held a word, not a number (`ERR`), read as gaps.
    words: u64,
    /// The time column used to find gaps, and the gap steps still to hand out.
    time: Option<TimeColumn>,
    gap_left: u64,
    /// The next row read is the pending one of the reader this one resumes
    /// ([`TextPosition::clocked`]).
    clocked_next: bool,
    /// The time column's account was logged (at the end of the input).
    time_reported: bool,
    /// The values and stamp of the last row handed out, to tell a row written twice.
    last_row: Option<(Vec<f64>, f64)>,
    /// Rows that repeat the one before in every column, a logger's ([`super::row_ties`]).
    ties: super::row_ties::RowTies,
    /// The values are phase (`--phase`): no column is judged by [`super::phase_hint`].
    phase: bool,
    /// Each column's account of how far its values move ([`super::phase_hint`]), filled as
    /// rows are handed out; empty with `--phase`.
    hints: Vec<super::phase_hint::PhaseHint>,
    line: Vec<u8>,
    /// The text of the last data row read whole, to tell a last line cut while the file was
    /// written ([`TextReader::cut_last_line`]).
    prev_text: String,
    /// The last line, without its line end, was cut: its bad row is logged however many were.
    cut_last: bool,
    bad_rows: u64,
    /// Values infinite or beyond `MAX_ABS_VALUE`, read as gaps.
    invalid_values: u64,
    /// Cells of the analysed channels that were empty or not a number (`NaN`, `N/A`), gaps.
    missing_cells: u64,
    rows: u64,
    /// Values that are numbers (not gaps) read so far.
    samples: u64,
    /// Bytes of the input consumed so far (header and comment lines included).
    offset: u64,
    /// A LabVIEW Measurement file's headers ([`super::lvm`]): a segment's header between rows
    /// is skipped, not read as rows.
    lvm: Option<super::lvm::LvmHeader>,
}

/// Where a [`TextReader`] stands, for a checkpoint: continuing from `offset` with these counts
/// reads the rest of the input as the reader would have.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TextPosition {
    /// Bytes consumed (the next row starts here).
    pub offset: u64,
    pub line_no: u64,
    pub rows: u64,
    pub bad_rows: u64,
    /// Values that were numbers (not gaps) so far.
    #[serde(default)]
    pub samples: u64,
    /// Values infinite or beyond [`super::MAX_ABS_VALUE`], read as gaps.
    #[serde(default)]
    pub invalid_values: u64,
    /// Cells that held a word, not a number (`ERR`), read as gaps.
    #[serde(default)]
    pub words: u64,
    /// Cells of the analysed channels that were empty or not a number, read as gaps.
    #[serde(default)]
    pub missing_cells: u64,
    /// The time column's clock, when it is used to find gaps.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time: Option<TimeState>,
    /// Gap steps the time column found that were not handed out yet (a checkpoint inside a
    /// long gap), and whether the row at `offset` is the one after them (or the first row),
    /// already on the clock: it is handed out as it is, not clocked again. Before session 32 a
    /// resume there dropped the rest of the gap and counted the row's stamp as a step back.
    #[serde(default)]
    pub gap_left: u64,
    #[serde(default)]
    pub clocked: bool,
    /// The last row handed out, to tell a row written twice across the checkpoint.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub last_row: Option<(Vec<f64>, f64)>,
    /// How the time column's open dates (`03/12/2026`) are read, as the rows so far decided.
    #[serde(default)]
    pub dates: DateOrder,
    /// The text of the last data row read whole, that a last line without its end is judged
    /// against ([`TextReader::cut_last_line`]) after a resume as in one reading.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub last_text: String,
    /// The account of rows tied to the one before in every column ([`super::row_ties`]).
    #[serde(default)]
    pub ties: super::row_ties::RowTies,
    /// Each column's account of how far its values move ([`super::phase_hint`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub hints: Vec<super::phase_hint::PhaseHint>,
}

/// Cells that mark a value as missing, read as gaps like an empty cell (any case): a logger's
/// `N/A` before its sensor is ready, and the NaN of C runtimes (`-nan`, MSVC's `-nan(ind)`,
/// `1.#QNAN`), are not text that makes a column a label.
const MISSING: [&str; 13] = [
    "nan",
    "n/a",
    "na",
    "null",
    "none",
    "-",
    "--",
    "-nan",
    "nan(ind)",
    "-nan(ind)",
    "1.#qnan",
    "1.#ind",
    "-1.#ind",
];

/// Whether the number `cell` is written shorter than `before`, the same column's in the row
/// before, as a number cut while written is: its exponent lost or with fewer digits, or fewer
/// digits after its decimal point (or comma). Numbers written to a fixed width (`%.6f`, `%e`)
/// never are; a writer of the shortest digits (`0.5` after `0.123`) may be.
fn shorter_number(cell: &str, before: &str) -> bool {
    let form = |s: &str| {
        let s = s.trim_matches('"');
        let (mantissa, exponent) = match s.find(['e', 'E', 'd', 'D']) {
            Some(at) => (&s[..at], Some(&s[at + 1..])),
            None => (s, None),
        };
        let digits = |x: &str| x.bytes().filter(u8::is_ascii_digit).count();
        let decimals = mantissa
            .rfind(['.', ','])
            .map_or(0, |p| digits(&mantissa[p + 1..]));
        (decimals, exponent.map(digits))
    };
    let ((decimals, exponent), (before_decimals, before_exponent)) = (form(cell), form(before));
    match (exponent, before_exponent) {
        (None, Some(_)) => true,
        (Some(e), Some(b)) if e < b => true,
        _ => decimals < before_decimals,
    }
}

fn parse_field(t: &str) -> Result<f64, ()> {
    let mut t = t.trim();
    // `"0.25"`: a spreadsheet that quotes every field.
    if let Some(q) = t.strip_prefix('"').and_then(|q| q.strip_suffix('"')) {
        t = q.trim();
    }
    if t.is_empty() || MISSING.iter().any(|m| t.eq_ignore_ascii_case(m)) {
        return Ok(f64::NAN);
    }
    t.parse::<f64>()
        .or_else(|e| decimal_comma(t).ok_or(e))
        .or_else(|e| thousands(t).ok_or(e))
        .or_else(|e| fortran_exponent(t).ok_or(e))
        .map_err(|_| ())
}

/// `1.5D-03` read as `1.5e-03`: Fortran's double-precision exponent, as Fortran programs and
/// some MathCad and instrument exports write it. Only a `D` (or `d`) after a digit or point and
/// before a digit or sign is taken, once.
fn fortran_exponent(t: &str) -> Option<f64> {
    let at = t.find(['D', 'd'])?;
    let before = t[..at].bytes().last()?;
    let after = *t.as_bytes().get(at + 1)?;
    let fits = (before.is_ascii_digit() || before == b'.')
        && (after.is_ascii_digit() || after == b'-' || after == b'+')
        && !t[at + 1..].contains(['D', 'd', 'e', 'E']);
    fits.then(|| format!("{}e{}", &t[..at], &t[at + 1..]).parse().ok())
        .flatten()
}

/// A time stamp written as a date and time, in seconds since 1970-01-01 00:00 UTC: ISO 8601
/// (`2026-12-03T01:02:03.456Z`, `2026-12-03 01:02:03.456+01:00`), with slashes
/// (`2026/12/03 01:02:03`), day first with points (`03.12.2026 01:02:03,456`), with the
/// month's name (MATLAB's `03-Dec-2026 01:02:03.456`), or `03/12/2026` and `03-12-2026`, whose
/// order (day or month first) a row alone does not tell: read here day first when that is a
/// date, else month first (`12/31/2026`); a file's rows decide it ([`DateOrder`]). Short dates
/// with a two-digit year (`12/3/26`, `03.12.26`, `03-Dec-26`) are read as POSIX reads `%y`
/// (69-99 in the 1900s, 00-68 in the 2000s); after a date a clock may stop at the minute
/// (`2026-12-03 10:41`). A clock of
/// 12 hours takes `AM` or `PM` (`12/3/2026 7:51:28.665 PM`, as Excel and LabVIEW write in the
/// US). Without a zone the clock's own time, read as UTC (only steps matter). A time of day
/// alone (`01:02:03.456`) is seconds since its midnight. `None` for anything else.
fn date_time(t: &str) -> Option<f64> {
    DateOrder::default().stamp(t)
}

/// The date of a stamp, as far as its row tells it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum DatePart {
    /// A time of day alone.
    None,
    /// Days since 1970-01-01.
    Days(i64),
    /// `a/b/yyyy` or `a-b-yyyy`, day or month first.
    Open(OpenDate),
}

/// A date written `a/b/yyyy` or `a-b-yyyy`: day first (`03/12/2026`, most of Europe) or month
/// first (the US); which, only a file's rows tell ([`DateOrder`]). A short date (`a/b/yy`,
/// `short`) may also be year first (`26/12/03`, as some East Asian loggers write it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
struct OpenDate {
    a: i64,
    b: i64,
    y: i64,
    #[serde(default)]
    short: bool,
}

impl OpenDate {
    /// Days since 1970-01-01, read day first or month first; `None` when that is no date.
    fn days(self, day_first: bool) -> Option<i64> {
        let (d, m) = if day_first {
            (self.a, self.b)
        } else {
            (self.b, self.a)
        };
        ((1..=12).contains(&m) && (1..=31).contains(&d)).then(|| days_since_1970(self.y, m, d))
    }

    /// Days since 1970-01-01 of a short date read year first (`26/12/03`: 2026-12-03); `None`
    /// for a date with four digits of year or when that is no date.
    fn days_year_first(self) -> Option<i64> {
        let (m, d) = (self.b, self.y % 100);
        (self.short && (1..=12).contains(&m) && (1..=31).contains(&d))
            .then(|| days_since_1970(two_digit_year(self.a), m, d))
    }
}

/// How a file's open dates ([`OpenDate`]) are read: day first until a row decides, which one
/// does when only one order makes it a date (`13/12/2026`, `12/13/2026`) or when the date
/// moves and only one order makes that a step of one day (`03/12` to `04/12`, or `12/03` to
/// `12/04`, at midnight). A file decided month first after rows read day first goes on from
/// where those left off (`offset_days`): only steps matter, and they stay right.
///
/// A time of day alone (`23:59:59.99`, then `00:00:00.00`) goes on past midnight the same way:
/// a step back to a clock at most an hour after midnight from one at most an hour before it
/// is the next day (`clock_days`), not a restart; and a step from such a clock after midnight
/// to one before it (a late row, a clock set back a little) is the day before again.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default)]
pub struct DateOrder {
    day_first: Option<bool>,
    last: Option<OpenDate>,
    offset_days: i64,
    last_clock: Option<f64>,
    clock_days: i64,
    /// Short dates read year first, decided when the date moved at midnight by a day only so.
    year_first: bool,
}

impl DateOrder {
    /// A time stamp written as a date and time ([`date_time`]), in seconds, its open date and
    /// its time of day alone read as the rows before it decided (which it may decide further).
    fn stamp(&mut self, field: &str) -> Option<f64> {
        let (date, secs) = date_time_parts(field)?;
        let days = match date {
            DatePart::None => self.clock_days(secs),
            DatePart::Days(d) => d,
            DatePart::Open(d) => self.days(d)?,
        };
        Some(days as f64 * SECONDS_PER_DAY + secs)
    }

    /// The days a time of day alone (`secs`, seconds since its midnight) has passed since the
    /// first row: one more at each midnight.
    fn clock_days(&mut self, secs: f64) -> i64 {
        const HOUR: f64 = 3600.0;
        if let Some(last) = self.last_clock {
            if last >= SECONDS_PER_DAY - HOUR && secs <= HOUR {
                self.clock_days += 1;
            } else if last <= HOUR && secs >= SECONDS_PER_DAY - HOUR && self.clock_days > 0 {
                self.clock_days -= 1;
            }
        }
        self.last_clock = Some(secs);
        self.clock_days
    }

    /// The days of `d` read in the file's order (deciding it if `d` does), since 1970-01-01
    /// (plus the offset of a late decision); `None` when `d` is no date in that order.
    fn days(&mut self, d: OpenDate) -> Option<i64> {
        if self.year_first {
            self.last = Some(d);
            return Some(d.days_year_first()? + self.offset_days);
        }
        if self.day_first.is_none() {
            let decided = match (d.days(true), d.days(false)) {
                (None, None) => return None,
                (Some(_), None) => Some(true),
                (None, Some(_)) => Some(false),
                (Some(x), Some(y)) => self.last.filter(|l| *l != d).and_then(|l| {
                    if l.days(true).is_some_and(|p| x - p == 1) {
                        Some(true)
                    } else if l.days(false).is_some_and(|p| y - p == 1) {
                        Some(false)
                    } else {
                        None
                    }
                }),
            };
            if decided == Some(false) {
                // The rows before were read day first (both orders were dates then).
                if let Some(l) = self.last {
                    self.offset_days = l.days(true)? - l.days(false)?;
                }
            }
            self.day_first = decided;
        }
        let read = |o: &Self, x: OpenDate| match o.day_first {
            Some(false) => x.days(false).map(|v| v + o.offset_days),
            _ => x.days(true),
        };
        // A short date that moves by other than a day in the order read but by one day read
        // year first (`26/12/03` to `26/12/04` at midnight, a year's jump read day first): year
        // first from here on, going on from where the rows before left off.
        if let Some(l) = self.last.filter(|l| d.short && *l != d) {
            let moved = read(self, l).zip(read(self, d)).map(|(p, q)| q - p);
            if let (Some(p), Some(py), Some(qy)) =
                (read(self, l), l.days_year_first(), d.days_year_first())
            {
                if moved != Some(1) && qy - py == 1 {
                    self.year_first = true;
                    self.offset_days = p - py;
                    self.last = Some(d);
                    return Some(qy + self.offset_days);
                }
            }
        }
        self.last = Some(d);
        read(self, d)
    }
}

/// A date and time's date part ([`DatePart`]) and its seconds of the day (the zone applied).
fn date_time_parts(t: &str) -> Option<(DatePart, f64)> {
    let t = t.trim().trim_matches('"').trim();
    // Every form has a clock `HH:MM:SS`, and all of it is ASCII.
    if !t.contains(':') || !t.is_ascii() {
        return None;
    }
    // The date ends at a space, or at ISO's `T` between digits (not the `T` of `OCT`).
    let b = t.as_bytes();
    let split = (0..b.len()).find(|&i| {
        b[i] == b' '
            || (b[i] == b'T'
                && i > 0
                && b[i - 1].is_ascii_digit()
                && b.get(i + 1).is_some_and(u8::is_ascii_digit))
    });
    let (date, time) = match split {
        // A date's part holds no `:` (a time of day with `AM` is not a date).
        Some(i) if !t[..i].contains(':') => (Some(&t[..i]), t[i + 1..].trim()),
        _ => (None, t),
    };
    let date = match date {
        Some(d) => {
            let parts: Vec<&str> = d.split(['-', '/', '.']).collect();
            let [a, b, c] = parts[..] else { return None };
            let num = |x: &str| {
                (!x.is_empty() && x.len() <= 4 && x.bytes().all(|b| b.is_ascii_digit()))
                    .then(|| x.parse::<i64>().ok())
                    .flatten()
            };
            // MATLAB's `03-Dec-2026`: the month's English name.
            let month = |x: &str| {
                const MONTHS: [&str; 12] = [
                    "jan", "feb", "mar", "apr", "may", "jun", "jul", "aug", "sep", "oct", "nov",
                    "dec",
                ];
                let x = x.to_ascii_lowercase();
                MONTHS.iter().position(|m| *m == x).map(|i| i as i64 + 1)
            };
            let (y, m, dd) = if a.len() == 4 {
                (num(a)?, num(b)?, num(c)?)
            } else if c.len() == 4 && d.contains('.') {
                (num(c)?, num(b)?, num(a)?)
            } else if c.len() == 4 && num(b).is_none() {
                // A month by name: day first.
                (num(c)?, month(b)?, num(a)?)
            } else if c.len() == 2 && a.len() == 2 && num(a)? > 31 && num(b).is_some() {
                // `27/01/03`: a first field no day or month can be is a two-digit year (year
                // first, as East Asian loggers write the short date).
                (two_digit_year(num(a)?), num(b)?, num(c)?)
            } else if c.len() == 2 && a.len() <= 2 && d.contains('.') {
                // `03.12.26`: day first with a two-digit year, as Europe writes the short date.
                (two_digit_year(num(c)?), num(b)?, num(a)?)
            } else if c.len() == 2 && a.len() <= 2 && num(b).is_none() {
                // `03-Dec-26`: a month by name, day first, a two-digit year.
                (two_digit_year(num(c)?), month(b)?, num(a)?)
            } else if (c.len() == 4 || c.len() == 2) && a.len() <= 2 && b.len() <= 2 {
                // `12/3/2026`, or the short date `12/3/26` (Excel's in the US, `03/12/26` in
                // Europe): day or month first, as the file's rows decide.
                let y = num(c)?;
                let open = OpenDate {
                    a: num(a)?,
                    b: num(b)?,
                    y: if c.len() == 2 { two_digit_year(y) } else { y },
                    short: c.len() == 2,
                };
                open.days(true).or_else(|| open.days(false))?;
                return Some((DatePart::Open(open), clock_seconds(time, true)?));
            } else {
                return None;
            };
            if !(1..=12).contains(&m) || !(1..=31).contains(&dd) {
                return None;
            }
            DatePart::Days(days_since_1970(y, m, dd))
        }
        None => DatePart::None,
    };
    let dated = date != DatePart::None;
    Some((date, clock_seconds(time, dated)?))
}

/// The year of a two-digit year `yy`: 1969-1999 for 69-99, 2000-2068 for 00-68 (POSIX
/// `strptime`'s `%y`, as spreadsheets read a short date too).
fn two_digit_year(yy: i64) -> i64 {
    if yy >= 69 {
        1900 + yy
    } else {
        2000 + yy
    }
}

/// The seconds of the day of a clock `HH:MM:SS[.fff]`, with `AM` or `PM` after it or a zone
/// (`Z`, `+01:00`, `-0500`), UTC. After a date (`dated`) a clock may stop at the minute
/// (`2026-12-03 10:41`, a logger's stamp each minute); alone, `10:41` could as well be
/// minutes and seconds, and is not read.
fn clock_seconds(time: &str, dated: bool) -> Option<f64> {
    // A clock of 12 hours: `7:51:28 PM`, `12:00:01 AM` (just after midnight).
    let upper = time.to_ascii_uppercase();
    let (time, half) = match ["AM", "PM"].iter().find(|h| upper.ends_with(*h)) {
        Some(h) => (time[..time.len() - 2].trim_end(), Some(*h == "PM")),
        None => (time, None),
    };
    // The zone: `Z`, `+01:00`, `-0500` after the seconds.
    let (clock, offset_s) = match time.find(['Z', 'z', '+']).or_else(|| {
        // A `-` after the seconds (not in a date: the date is split off).
        time.rfind('-')
    }) {
        Some(at) => {
            let zone = &time[at..];
            let off = if zone.eq_ignore_ascii_case("z") {
                0.0
            } else {
                let sign = if zone.starts_with('-') { -1.0 } else { 1.0 };
                let digits: String = zone[1..].chars().filter(|c| *c != ':').collect();
                if digits.len() != 4 && digits.len() != 2 {
                    return None;
                }
                let h: f64 = digits[..2].parse().ok()?;
                let mm: f64 = if digits.len() == 4 {
                    digits[2..].parse().ok()?
                } else {
                    0.0
                };
                sign * (h * 3600.0 + mm * 60.0)
            };
            (&time[..at], off)
        }
        None => (time, 0.0),
    };
    let parts: Vec<&str> = clock.split(':').collect();
    let (h, m, sec) = match parts[..] {
        [h, m, sec] => (h, m, sec),
        [h, m] if dated => (h, m, "0"),
        _ => return None,
    };
    let int = |x: &str, max: i64| {
        (!x.is_empty() && x.len() <= 2 && x.bytes().all(|b| b.is_ascii_digit()))
            .then(|| x.parse::<i64>().ok())
            .flatten()
            .filter(|v| *v <= max)
    };
    let (h, m) = (int(h, 24)?, int(m, 59)?);
    let h = match half {
        None => h,
        Some(_) if !(1..=12).contains(&h) => return None,
        Some(pm) => h % 12 + if pm { 12 } else { 0 },
    };
    let sec = sec.replacen(',', ".", 1);
    let digits_and_point = sec.bytes().next().is_some_and(|b| b.is_ascii_digit())
        && sec.bytes().all(|b| b.is_ascii_digit() || b == b'.');
    if !digits_and_point {
        return None;
    }
    let sec: f64 = sec.parse().ok().filter(|s: &f64| *s < 61.0)?;
    Some((h * 3600 + m * 60) as f64 + sec - offset_s)
}

/// Days from 1970-01-01 to the proleptic Gregorian date `y-m-d`: the days of the years before
/// (365 each and a leap day every 4th year but centuries not divisible by 400), counted from
/// March so that the leap day falls last, as Hinnant's `days_from_civil` reasons.
fn days_since_1970(y: i64, m: i64, d: i64) -> i64 {
    // Years begin in March: January and February belong to the year before.
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let year_of_era = y - era * 400;
    // Days from March 1 to the first of month m (153 days per five months from March).
    let month_from_march = (m + 9) % 12;
    let day_of_year = (153 * month_from_march + 2) / 5 + d - 1;
    let day_of_era = year_of_era * 365 + year_of_era / 4 - year_of_era / 100 + day_of_year;
    // 719468: days from 0000-03-01 to 1970-01-01.
    era * 146_097 + day_of_era - 719_468
}

/// The NaN a word in a data column is read as (`ERR`, `OVF`, `#N/A`, `Error`: a logger's flag
/// where the sample is not valid): a gap of that channel only, told from an empty cell by its
/// bits so that [`TextReader`] counts and logs it, then an ordinary NaN.
const WORD_CELL_BITS: u64 = 0x7ff8_0000_0000_5707;

/// Whether a cell that is not a number is a word, not a damaged number: letters and no digit
/// (`ERR`, `#VALUE!`, `Sensor fault`). `12a` or `0.1.2` is damage: its row is a bad row.
fn word_cell(t: &str) -> bool {
    let t = t.trim().trim_matches('"');
    t.chars().any(char::is_alphabetic) && !t.chars().any(|c| c.is_ascii_digit())
}

/// Whether a row's fields are a row of units under the header (`s;deg/s;g`, as spreadsheets and
/// some loggers write them): no number among them, and at least half of the cells that are not
/// empty a unit of time, of an inertial quantity or of temperature.
fn units_row(fields: &[&str]) -> bool {
    let cells: Vec<&str> = fields
        .iter()
        .map(|f| f.trim().trim_matches('"').trim())
        .filter(|f| !f.is_empty())
        .collect();
    let known = |u: &str| {
        TIME_UNITS.iter().any(|(x, _)| x.eq_ignore_ascii_case(u))
            || matches!(
                super::header_unit::header_unit(&format!("x [{u}]")),
                Some(Ok(_))
            )
            || super::temperature_column::temperature_column(&format!("temp [{u}]")).is_some()
    };
    // `-` for a column without a unit: a missing-value marker, neither number nor unit.
    let cells: Vec<&str> = cells
        .into_iter()
        .filter(|c| !parse_field(c).is_ok_and(f64::is_nan))
        .collect();
    let units = cells.iter().filter(|c| known(c)).count();
    units > 0 && cells.iter().all(|c| parse_field(c).is_err()) && 2 * units >= cells.len()
}

/// `0,25` or `-1,5e-3` read as `0.25`, `-1.5e-3`: a decimal comma, as spreadsheets in many
/// languages write it. Only a comma between two digits, with no point in the field, is taken;
/// such a field can only arise where the columns are separated by semicolons or tabs, or in
/// double quotes (`"0,25"`, [`split_quoted`]).
fn decimal_comma(t: &str) -> Option<f64> {
    let (int, frac) = t.split_once(',')?;
    let digit_before = int.bytes().last().is_some_and(|b| b.is_ascii_digit());
    let digit_after = frac.bytes().next().is_some_and(|b| b.is_ascii_digit());
    if !digit_before || !digit_after || t.contains('.') || frac.contains(',') {
        return None;
    }
    format!("{int}.{frac}").parse().ok()
}

/// `2,001.52` or `-1,234,567.5` (and `2.001,52`, as a decimal-comma spreadsheet writes it)
/// read as `2001.52`, `-1234567.5`: digits grouped by thousands, as spreadsheets export them in
/// double quotes (`"2,001.52"`). Taken only where it cannot be read otherwise: both marks
/// stand, the last one is the decimal mark, and the other one groups the digits in threes
/// after one to three leading ones. `2,001` (no point) stays a decimal comma, 2.001
/// ([`decimal_comma`]), and `2,00.5` or `20,01.5` are no numbers: a decimal comma is never read
/// as a thousands separator. Before (session 42), `"2,001.52"` was no number.
fn thousands(t: &str) -> Option<f64> {
    let (sign, body) = match t.strip_prefix(['-', '+']) {
        Some(b) => (&t[..1], b),
        None => ("", t),
    };
    let (point, group) = match (body.rfind('.'), body.rfind(',')) {
        (Some(p), Some(c)) if p > c => ('.', ','),
        (Some(_), Some(_)) => (',', '.'),
        _ => return None,
    };
    let (int, frac) = body.rsplit_once(point)?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if int.contains(point) || !digits(frac) {
        return None;
    }
    let mut groups = int.split(group);
    let lead = groups.next()?;
    if !digits(lead) || lead.len() > 3 {
        return None;
    }
    let mut whole = lead.to_string();
    for g in groups {
        if g.len() != 3 || !digits(g) {
            return None;
        }
        whole += g;
    }
    format!("{sign}{whole}.{frac}").parse().ok()
}

/// The column names of a `#` line taken as the header of data rows `width` wide: as many
/// fields as the rows, none empty, at least one not a number (so a commented-out data row is not
/// a header). `None` when the line is an ordinary comment.
fn commented_header(line: &str, width: usize) -> Option<Vec<String>> {
    let fields = Sep::of(line).split(line);
    let names: Vec<String> = fields
        .iter()
        .map(|f| f.trim().trim_matches('"').trim().to_string())
        .collect();
    let ok = width > 1
        && names.len() == width
        && names.iter().all(|n| !n.is_empty())
        && fields.iter().any(|f| parse_field(f).is_err());
    ok.then_some(names)
}

/// The column separator of a file, read off its header or first data row: a semicolon where
/// there is one (so `0,25;1,5` is two columns with decimal commas), else a tab where the tabs
/// leave no field empty, else a comma, else runs of spaces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Sep {
    Semicolon,
    Tab,
    Comma,
    Spaces,
    /// Each value after its label, as an Arduino's serial monitor prints them
    /// ([`labelled_cells`]): `ax:0.012 ay:-0.003` or `ax=0.012, ay=-0.003`.
    Labelled,
}

/// A line of labelled values, `label:value` or `label=value` (spaces allowed around the `:` or
/// `=`), the pairs separated by commas, semicolons, tabs or spaces, as an Arduino sketch prints
/// them for its serial plotter (`ax:0.012 ay:-0.003 gz:0.0001`): the (label, value) pairs, or
/// `None` when the line is not such. A label starts with a letter and holds no space (`12:03:04`
/// is a time of day, not a label).
fn labelled_cells(line: &str) -> Option<Vec<(&str, &str)>> {
    let is_sep = |c: char| c.is_whitespace() || c == ',' || c == ';';
    let mut out = Vec::new();
    let mut rest = line.trim();
    while !rest.is_empty() {
        let end = rest.find([':', '='])?;
        let label = rest[..end].trim();
        if !label.starts_with(char::is_alphabetic) || label.contains(is_sep) {
            return None;
        }
        rest = rest[end + 1..].trim_start();
        let value_end = rest.find(is_sep).unwrap_or(rest.len());
        if value_end == 0 {
            return None;
        }
        out.push((label, &rest[..value_end]));
        rest = rest[value_end..].trim_start_matches(is_sep);
    }
    (!out.is_empty()).then_some(out)
}

impl Sep {
    /// The separator of `line`, told by the characters outside its double quotes
    /// ([`unquoted`]): `"0,25";"1,5"` is two columns, `0.00,"ok; nominal",1.72` three.
    fn of(line: &str) -> Sep {
        let line = &*unquoted(line);
        if line.contains(';') {
            Sep::Semicolon
        } else if line.contains('\t') && line.trim().split('\t').all(|f| !f.trim().is_empty()) {
            Sep::Tab
        } else if line.contains(',') {
            Sep::Comma
        } else {
            Sep::Spaces
        }
    }

    /// The fields of `line`, a separator inside double quotes part of its field
    /// ([`split_quoted`]).
    fn split(self, line: &str) -> Vec<&str> {
        let quoted = line.contains('"');
        match self {
            Sep::Semicolon if !quoted => line.split(';').collect(),
            Sep::Tab if !quoted => line.split('\t').collect(),
            Sep::Comma if !quoted => line.split(',').collect(),
            Sep::Spaces if !quoted => line.split_whitespace().collect(),
            Sep::Semicolon => split_quoted(line, |c| c == ';', false),
            Sep::Tab => split_quoted(line, |c| c == '\t', false),
            Sep::Comma => split_quoted(line, |c| c == ',', false),
            Sep::Spaces => split_quoted(line, char::is_whitespace, true),
            // Laid out by [`Layout::labelled_fields`]; a line that is not such, as it suggests.
            Sep::Labelled => split(line),
        }
    }
}

/// The fields of `line` between separators (`is_sep`; with `runs`, a run of them is one and
/// those at the ends are dropped, as `split_whitespace` does), by the CSV quoting rule (RFC
/// 4180): a field that starts with `"` (after spaces) runs to the next `"` that is not doubled,
/// the separators inside it its own, and is handed on without its quotes (`"ok, nominal"` ->
/// `ok, nominal`, `"0,25"` -> `0,25`, read as a decimal comma, `"2,001.52"` -> `2,001.52`,
/// read as [`thousands`]). A doubled `""` inside stays doubled in the field: only text holds
/// one, and a header name is unescaped where it is made ([`header_name`]). A `"` inside a field
/// that did not start with one is a character of it (`12"`). A line whose quotes do not close
/// is split as if it had none. Before (session 42) every separator split: each row of
/// `0.00,"ok, nominal",1.72` or `"0,00","1,727921"` was a bad row of 4 fields where the
/// header has 3 (or 2), and the run stopped with no sample.
fn split_quoted<'a>(line: &'a str, is_sep: impl Fn(char) -> bool, runs: bool) -> Vec<&'a str> {
    let mut out = Vec::new();
    let (mut start, mut at_start, mut in_quotes) = (0, true, false);
    let mut chars = line.char_indices().peekable();
    let push = |field: &'a str, out: &mut Vec<&'a str>| {
        if !(runs && field.is_empty()) {
            out.push(field);
        }
    };
    while let Some((i, c)) = chars.next() {
        if in_quotes {
            if c == '"' {
                if chars.peek().is_some_and(|&(_, n)| n == '"') {
                    chars.next();
                } else {
                    in_quotes = false;
                }
            }
        } else if is_sep(c) {
            push(&line[start..i], &mut out);
            start = i + c.len_utf8();
            at_start = true;
        } else if c == '"' && at_start {
            in_quotes = true;
            at_start = false;
        } else if !c.is_whitespace() {
            at_start = false;
        }
    }
    if in_quotes {
        return if runs {
            line.split_whitespace().collect()
        } else {
            line.split(is_sep).collect()
        };
    }
    push(&line[start..], &mut out);
    out.into_iter()
        .map(|f| {
            let t = f.trim();
            match t.strip_prefix('"').and_then(|q| q.strip_suffix('"')) {
                Some(inner) if t.len() >= 2 => inner,
                _ => f,
            }
        })
        .collect()
}

/// `line` with the characters inside its double-quoted fields (as [`split_quoted`] reads them,
/// a quote opening a field at the line's start or after a space or a separator) replaced by
/// `x`, so that the separator is told by the characters outside them; `line` itself when it
/// has no quotes or they do not close.
fn unquoted(line: &str) -> std::borrow::Cow<'_, str> {
    if !line.contains('"') {
        return line.into();
    }
    let mut out = String::with_capacity(line.len());
    let (mut in_quotes, mut prev) = (false, ' ');
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        if in_quotes {
            if c == '"' {
                if chars.peek() == Some(&'"') {
                    chars.next();
                    out.push('x');
                } else {
                    in_quotes = false;
                    out.push(c);
                }
            } else {
                out.push('x');
            }
        } else {
            in_quotes = c == '"' && (prev.is_whitespace() || [',', ';'].contains(&prev));
            out.push(c);
        }
        prev = c;
    }
    if in_quotes {
        line.into()
    } else {
        out.into()
    }
}

/// A header's name as its field holds it: without the quotes around it, a doubled `""` inside
/// them one `"` (CSV's escape, [`split_quoted`]).
fn header_name(field: &str) -> String {
    let n = field.trim();
    if n.contains("\"\"") {
        n.replace("\"\"", "\"")
    } else {
        n.trim_matches('"').trim().to_string()
    }
}

/// Lines read ahead to find the header below an instrument's notes ([`notes_before_header`]).
const NOTES_LOOK: usize = 64;

/// Data rows in a row that mark where the rows start ([`notes_before_header`]).
const NOTES_BLOCK: usize = 8;

/// How many lines, from `first` on, come before the header when they are notes: `first` and the
/// lines after it (`ahead`: blank, `#` and `//` lines are not counted) up to the header of the
/// rows below, when those lines do not have its columns. The rows are found as
/// [`NOTES_BLOCK`] lines in a row of one separator and as many fields, most of them numbers;
/// the header is the line above them with as many fields and fewer numbers (above a row of
/// units, when there is one); with no such header, the lines above the rows are notes when
/// none has their columns (the rows are then read without a header). `None` when `first` is
/// the header or a row, or a line above could head the rows too (the reader's own rules then
/// read the lines).
fn notes_before_header(first: &str, ahead: &[String]) -> Option<usize> {
    let lines: Vec<&str> = std::iter::once(first)
        .chain(ahead.iter().map(String::as_str))
        .map(|l| l.trim_start_matches('\u{feff}').trim())
        .filter(|l| !l.is_empty() && !l.starts_with('#') && !l.starts_with("//"))
        .collect();
    let numbers = |f: &[&str]| {
        f.iter()
            .filter(|x| !x.trim().is_empty() && (parse_field(x).is_ok() || date_time(x).is_some()))
            .count()
    };
    for d in 1..lines.len().saturating_sub(NOTES_BLOCK - 1) {
        let sep = Sep::of(lines[d]);
        let n = sep.split(lines[d]).len();
        if n < 2 {
            continue;
        }
        let row = |l: &str| {
            let f = sep.split(l);
            f.len() == n && 2 * numbers(&f) > n
        };
        if !lines[d..d + NOTES_BLOCK].iter().all(|l| row(l)) {
            continue;
        }
        let names = |l: &str| {
            let f = sep.split(l);
            f.len() == n && 2 * numbers(&f) < n && f.iter().any(|x| !x.trim().is_empty())
        };
        // A line that could head these rows, by the rows' separator or (when it is not free
        // text between spaces) its own: as many fields, or one more or fewer (a header or rows
        // ending in a separator, an index column without a name).
        let near = |w: usize| w == n || w == n + 1 || (w + 1 == n && w >= 2);
        let shaped = |l: &str| {
            near(sep.split(l).len()) || {
                let own = Sep::of(l);
                own != Sep::Spaces && own != sep && near(own.split(l).len())
            }
        };
        let mut h = d - 1;
        if h >= 1 && units_row(&sep.split(lines[h])) && names(lines[h - 1]) {
            h -= 1;
        }
        if names(lines[h]) {
            // Kept whole (the reader's own rules then read them) when a line above could
            // head the rows too; but not when this line names the time column and none above
            // names one (catman's `File`, `Comment`, `T0` notes over a two-column header are
            // as many fields as its rows).
            let times = |l: &str| sep.split(l).iter().any(|x| time_name(x).is_some());
            let time_header = times(lines[h]) && !lines[..h].iter().any(|l| times(l));
            if h == 0 || (!time_header && lines[..h].iter().any(|l| shaped(l))) {
                return None;
            }
            return Some(h);
        }
        // No header right above the rows: the lines above them are notes too (an Arduino
        // sketch's greetings, a first row cut short by the capture's start) when none has
        // their shape, nor is the line right above them words as many as their columns (a
        // header split otherwise, `time gx gy` over rows between tabs).
        let above = lines[d - 1];
        let words = Sep::of(above).split(above);
        let header_otherwise = near(words.len()) && numbers(&words) == 0;
        if header_otherwise || lines[..d].iter().any(|l| shaped(l)) {
            return None;
        }
        return Some(d);
    }
    None
}

/// The labels of a line of labelled values ([`labelled_cells`]), when at least one labels a
/// number (a `st=OK` beside them is a label column), no label comes twice and there are no more
/// than a run takes channels.
fn labelled_names(t: &str) -> Option<Vec<String>> {
    let pairs = labelled_cells(t)?;
    if pairs.len() > crate::ranges::MAX_CHANNELS
        || !pairs.iter().any(|(_, v)| parse_field(v).is_ok())
    {
        return None;
    }
    let mut seen = std::collections::HashSet::new();
    pairs
        .iter()
        .all(|(l, _)| seen.insert(*l))
        .then(|| pairs.iter().map(|(l, _)| l.to_string()).collect())
}

/// Lines looked at, from the first line before a header, to tell labelled values.
const LABELLED_LOOK: usize = 16;

/// What the lines from the first one before a header show of labelled values.
#[derive(Debug, PartialEq)]
enum Labelled {
    /// They start here, under these names.
    Here(Vec<String>),
    /// They start on a later line: this one greets (`MPU6050 connection successful`).
    Later,
}

/// Whether labelled values start at `t` or a few lines after it (`ahead`: the next lines, notes
/// and empty ones left out): from the first labelled line on, at least two in three of the
/// lines looked at must be labelled, and two in three of those must hold no label outside the
/// names, which are the labels of the commonest labelled line (a first line cut short by the
/// start of a capture does not name them). Lines of `key=value` notes, each key its own, are
/// no labelled values.
fn labelled_start(t: &str, ahead: &[String]) -> Option<Labelled> {
    let lines: Vec<&str> = std::iter::once(t)
        .chain(ahead.iter().map(String::as_str))
        .take(LABELLED_LOOK + 1)
        .collect();
    let read: Vec<Option<Vec<String>>> = lines.iter().map(|l| labelled_names(l)).collect();
    let first = read.iter().position(Option::is_some)?;
    let from = &read[first..];
    let labelled: Vec<Vec<String>> = from.iter().flatten().cloned().collect();
    if 3 * labelled.len() < 2 * from.len() {
        return None;
    }
    let count = |n: &Vec<String>| labelled.iter().filter(|m| *m == n).count();
    let names = labelled.iter().max_by_key(|n| (count(n), n.len()))?.clone();
    let within = labelled
        .iter()
        .filter(|m| m.iter().all(|l| names.contains(l)))
        .count();
    if 3 * within < 2 * labelled.len() {
        return None;
    }
    Some(if first == 0 {
        Labelled::Here(names)
    } else {
        Labelled::Later
    })
}

/// The names of a header split at spaces, a unit in brackets kept with the name before it:
/// `ax [m/s^2]` is one column, `gx [rad s^-1] gy [rad s^-1]` two, as a person reads them.
fn spaced_names(words: &[&str]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    // The bracket a unit opened and has not closed yet.
    let mut open: Option<char> = None;
    for w in words {
        let w = w.trim().trim_matches('"');
        let starts_unit = w.starts_with(['[', '(']) && !names.is_empty();
        match (open, names.last_mut()) {
            (Some(close), Some(last)) => {
                last.push(' ');
                last.push_str(w);
                if w.ends_with(close) {
                    open = None;
                }
            }
            (None, Some(last)) if starts_unit => {
                last.push(' ');
                last.push_str(w);
                let close = if w.starts_with('[') { ']' } else { ')' };
                if !w.ends_with(close) {
                    open = Some(close);
                }
            }
            _ => names.push(w.to_string()),
        }
    }
    names
}

/// A row's fields by the row alone: commas, else semicolons, else spaces and tabs (outside
/// double quotes, [`Sep::split`]).
fn split(line: &str) -> Vec<&str> {
    let bare = unquoted(line);
    if bare.contains(',') {
        Sep::Comma.split(line)
    } else if bare.contains(';') {
        Sep::Semicolon.split(line)
    } else {
        Sep::Spaces.split(line)
    }
}

impl<R: BufRead> TextReader<R> {
    /// Opens the stream with every column but a time column as a channel
    /// ([`TextReader::with_options`] with the defaults).
    pub fn new(src: R, path: &Path) -> Result<Self, UsageError> {
        Self::with_options(src, path, &TextOptions::default())
    }

    /// Opens the stream and reads up to the first data row (taking a header row if present).
    /// Fails with a usage error (exit status 2) when there is no data row at all, when the
    /// header names a column twice, when `opts` names a column the input does not have, or when
    /// a column the run names (`--columns`, `--channels`) is not a number in the first data row
    /// (a row of the wrong width is a counted bad row, as later). A column the run does not
    /// name whose first cell is text (`imu_link`, `OK`) is left out as a label column, logged.
    pub fn with_options(mut src: R, path: &Path, opts: &TextOptions) -> Result<Self, UsageError> {
        let mut raw = Vec::new();
        let mut line_no = 0u64;
        let mut offset = 0u64;
        let mut layout: Option<Layout> = None;
        // The last `#` line before the first data row (a commented header, see the module doc).
        let mut hash_line: Option<String> = None;
        let mut latin1_logged = false;
        // A row of units under the header was read (only the first row after it may be one).
        let mut units_read = false;
        // The header's (and units row's) fields: found again later, files joined into one.
        let mut header_rows: Vec<Vec<String>> = Vec::new();
        // Lines read past the first data row to tell label columns (handed out as rows later).
        let mut ahead = VecDeque::new();
        // The line the header (or a title taken for one) was on, for messages.
        let mut layout_line = 0u64;
        // A LabVIEW Measurement file's headers (`super::lvm`), from its first line on.
        let mut lvm: Option<super::lvm::LvmHeader> = None;
        // Lines of notes before the header still to skip ([`notes_before_header`]).
        let mut notes_left = 0usize;
        loop {
            // Lines looked at ahead (for labelled values) are read again from there first.
            let (n, long) = next_line(&mut src, &mut ahead, &mut raw)
                .map_err(|e| input_error(path, line_no + 1, e.to_string()))?;
            if n == 0 {
                return Err(input_error(path, line_no, "no data rows".into()));
            }
            line_no += 1;
            offset += n as u64;
            let mut body: &[u8] = &raw;
            if let Some(b) = body.strip_suffix(b"\n") {
                body = b;
            }
            if let Some(b) = body.strip_suffix(b"\r") {
                body = b;
            }
            if body.contains(&b'\r') {
                return Err(input_error(
                    path,
                    line_no,
                    "the lines end with a bare carriage return (CR, no line feed): convert the \
                     file to LF or CRLF line ends first, e.g. `tr '\\r' '\\n' < IN > OUT`"
                        .into(),
                ));
            }
            if long {
                return Err(input_error(
                    path,
                    line_no,
                    format!(
                        "a line longer than {} MiB: not text columns (a capture of frames needs \
                         --format NAME)",
                        MAX_LINE_BYTES >> 20
                    ),
                ));
            }
            // A header saved in a Windows code page (`Temp (\u{b0}C)` in Latin-1) is read as
            // Latin-1; data rows are numbers, ASCII either way.
            let line: String = match std::str::from_utf8(&raw) {
                Ok(t) => t.to_string(),
                Err(_) => {
                    if !latin1_logged {
                        latin1_logged = true;
                        tracing::warn!(
                            "{}: line {line_no}: not UTF-8; read as Latin-1 (Windows-1252)",
                            path.display()
                        );
                    }
                    raw.iter().map(|&b| char::from(b)).collect()
                }
            };
            // A byte-order mark (spreadsheets write one) is not part of the first name, nor of
            // a line of a file joined after the first.
            let t = line.trim_start_matches('\u{feff}').trim();
            if t.is_empty() {
                continue;
            }
            if layout.is_none() && lvm.is_none() && t.starts_with(super::lvm::MAGIC) {
                tracing::info!(
                    "{}: a LabVIEW Measurement file: its header lines skipped",
                    path.display()
                );
                lvm = Some(super::lvm::LvmHeader::default());
            }
            if let Some(h) = &mut lvm {
                if h.take(t) {
                    continue;
                }
            }
            if let Some(c) = t.strip_prefix('#') {
                if layout.is_none() {
                    hash_line = Some(c.trim().to_string());
                }
                continue;
            }
            // `// Update Rate: 100.0Hz`: an exporter's notes (Xsens MT Manager), comments too.
            if t.starts_with("//") {
                continue;
            }
            // `sep=;`: Excel's note of the separator before the header.
            if layout.is_none() && t.len() <= 6 && t.to_ascii_lowercase().starts_with("sep=") {
                continue;
            }
            // An instrument's notes before the header (`Start time: ...`, `Sample rate: 1000
            // Hz`, `File<TAB>C:\run1.BIN`): lines without the columns of the header and rows
            // below them.
            if layout.is_none() && lvm.is_none() {
                if notes_left > 0 {
                    notes_left -= 1;
                    continue;
                }
                fill_ahead(&mut src, &mut ahead, NOTES_LOOK)
                    .map_err(|e| input_error(path, line_no + 1, e.to_string()))?;
                if let Some(h) = notes_before_header(t, &ahead_text(&ahead)) {
                    tracing::info!(
                        "{}: line {line_no}: `{t}`{} before the data: skipped",
                        path.display(),
                        match h {
                            1 => " is a note".to_string(),
                            2 => " and the line after it are notes".to_string(),
                            _ => format!(" and the {} lines after it are notes", h - 1),
                        }
                    );
                    notes_left = h - 1;
                    continue;
                }
            }
            // A title line before the header (`IMU log 2026-12-03 S/N 1234`, then `time,gx,gy`):
            // one field or words between spaces, and after it a line of several fields split
            // otherwise that is itself names.
            if let Some(l) = &layout {
                let sep = Sep::of(t);
                let fields = sep.split(t);
                if (l.width_in == 1 || (l.sep == Sep::Spaces && sep != Sep::Spaces))
                    && fields.len() > 1
                    && fields
                        .iter()
                        .any(|f| parse_field(f).is_err() && date_time(f).is_none())
                {
                    tracing::info!(
                        "{}: line {layout_line}: `{}` is a title, not a header: skipped",
                        path.display(),
                        l.source_names.join(" ")
                    );
                    layout = None;
                    header_rows.clear();
                }
            }
            let (values, found) = match layout.take() {
                Some(l) => {
                    let fields = l.split(t);
                    if !units_read && fields.len() == l.width_in && units_row(&fields) {
                        // `s;deg/s;g` under `time;gx;ax`: each column's unit, as if in brackets.
                        units_read = true;
                        let units: Vec<String> = fields
                            .iter()
                            .map(|f| f.trim().trim_matches('"').trim().to_string())
                            .collect();
                        header_rows.push(units.clone());
                        tracing::info!(
                            "{}: line {line_no}: a row of units under the header ({})",
                            path.display(),
                            units.join(", ")
                        );
                        layout = Some(l.with_units(&units, opts, path, line_no)?);
                        continue;
                    }
                    l.first_row(t, &mut src, &mut ahead, opts, path, line_no)?
                }
                None => {
                    // `ax:0.012 ay:-0.003`: labelled values, when most lines from here on are
                    // such (a `SampleRate=100` note before a header is not); a greeting before
                    // them (`MPU6050 connection successful`) is skipped.
                    fill_ahead(&mut src, &mut ahead, LABELLED_LOOK)
                        .map_err(|e| input_error(path, line_no + 1, e.to_string()))?;
                    match labelled_start(t, &ahead_text(&ahead)) {
                        Some(Labelled::Here(names)) => {
                            tracing::info!(
                                "{}: line {line_no}: labelled values ({}): the labels are the \
                                 names",
                                path.display(),
                                names.join(", ")
                            );
                            Layout::new(names, true, Sep::Labelled, opts, path, line_no)?
                                .first_row(t, &mut src, &mut ahead, opts, path, line_no)?
                        }
                        Some(Labelled::Later) => {
                            tracing::info!(
                                "{}: line {line_no}: `{t}` comes before labelled values: skipped",
                                path.display()
                            );
                            continue;
                        }
                        None => {
                            let sep = Sep::of(t);
                            let fields = sep.split(t);
                            // A row most of whose fields are numbers is data, not names: ROS 2's
                            // `ros2 topic echo --csv` writes no header, and a `frame_id` among numbers.
                            let numbers = fields
                                .iter()
                                .filter(|f| {
                                    !f.trim().is_empty()
                                        && (parse_field(f).is_ok() || date_time(f).is_some())
                                })
                                .count();
                            // (Unless a text cell names a time column: `time,0,1,2` is pandas' header
                            // of integer-labelled columns.)
                            let names_time = fields.iter().any(|f| {
                                parse_field(f).is_err()
                                    && time_name(f.trim().trim_matches('"'))
                                        .is_some_and(|(plain, _)| plain)
                            });
                            if fields.iter().all(|f| parse_field(f).is_ok())
                                || (2 * numbers > fields.len() && !names_time)
                            {
                                let commented = hash_line
                                    .as_deref()
                                    .and_then(|h| commented_header(h, fields.len()));
                                let header = commented.is_some();
                                let names = commented.unwrap_or_else(|| {
                                    (1..=fields.len()).map(|i| format!("c{i}")).collect()
                                });
                                Layout::new(names, header, sep, opts, path, line_no)?
                                    .first_row(t, &mut src, &mut ahead, opts, path, line_no)?
                            } else {
                                let mut names: Vec<String> = if sep == Sep::Spaces {
                                    spaced_names(&fields)
                                } else {
                                    fields.iter().map(|f| header_name(f)).collect()
                                };
                                header_rows.push(names.clone());
                                layout_line = line_no;
                                // A LabVIEW file's names made the reader's, its units read.
                                let units = lvm.as_ref().and_then(|h| h.columns(&mut names));
                                // Laid out again with the units: what the first layout would
                                // say is said then, once.
                                let mut l = if units.is_some() {
                                    tracing::subscriber::with_default(
                                        tracing::subscriber::NoSubscriber::default(),
                                        || Layout::new(names, true, sep, opts, path, line_no),
                                    )?
                                } else {
                                    Layout::new(names, true, sep, opts, path, line_no)?
                                };
                                if let Some(units) = units {
                                    let given: Vec<&str> = units
                                        .iter()
                                        .filter(|u| !u.is_empty())
                                        .map(String::as_str)
                                        .collect();
                                    tracing::info!(
                                        "{}: the LabVIEW header's Y_Unit_Label: {}",
                                        path.display(),
                                        given.join(", ")
                                    );
                                    units_read = true;
                                    l = l.with_units(&units, opts, path, line_no)?;
                                }
                                layout = Some(l);
                                continue;
                            }
                        }
                    }
                }
            };
            // With a time column, a first row with no value and no stamp (an empty line), or
            // with no value in a file of sparse rows, is no sample: the clock starts at the
            // first that is.
            let skip_first = found.time.is_some()
                && opts.tau0_s.is_some()
                && (opts.sparse_rows || values.1.is_nan())
                && empty_row(&values, &found.strict);
            if skip_first {
                layout = Some(found);
                continue;
            }
            let layout = found;
            // `--time-column none`: a time column is skipped, never read as a clock.
            let read_clock = opts.time_column.as_deref() != Some(NO_TIME_COLUMN);
            let mut time = match (layout.time.filter(|_| read_clock), opts.tau0_s) {
                (Some(i), Some(_)) if layout.counter_clock => {
                    Some(TimeColumn::counter(&layout.source_names[i]))
                }
                (Some(i), Some(tau0)) => Some(TimeColumn::new(&layout.source_names[i], tau0)),
                _ => None,
            };
            if let Some(c) = &mut time {
                // The clock's unit from the first steps when the first is no tau0 (a sample
                // missing right after the first, the first stamp written twice); then the
                // first stamp starts the clock.
                let first = layout.first_stamps(values.1, &ahead_text(&ahead), opts.sparse_rows);
                c.unit_from_first_steps(&first, path);
                c.missing_before(values.1, path, line_no);
            }
            return Ok(TextReader {
                src,
                path: path.into(),
                line_no,
                names: layout.names.clone(),
                layout,
                pending: Some(values),
                clocked_next: false,
                header_rows,
                header_repeats: 0,
                sparse: opts.sparse_rows,
                ahead,
                words: 0,
                time,
                gap_left: 0,
                time_reported: false,
                last_row: None,
                ties: Default::default(),
                phase: opts.phase,
                hints: Vec::new(),
                prev_text: String::from_utf8_lossy(&raw).trim().to_string(),
                cut_last: false,
                line: raw,
                bad_rows: 0,
                invalid_values: 0,
                missing_cells: 0,
                rows: 0,
                samples: 0,
                offset,
                lvm,
            });
        }
    }

    /// Continues reading `src`, positioned at `pos.offset` of the same input, with this
    /// reader's columns, as a reader that had stopped at `pos` (no header is looked for).
    pub fn resume<S: BufRead>(self, src: S, pos: &TextPosition) -> TextReader<S> {
        self.layout.dates.set(pos.dates);
        let mut time = self.time;
        if let (Some(c), Some(st)) = (&mut time, pos.time.clone()) {
            c.restore(st);
        }
        TextReader {
            src,
            path: self.path,
            line_no: pos.line_no,
            names: self.names,
            layout: self.layout,
            pending: None,
            clocked_next: pos.clocked,
            header_rows: self.header_rows,
            header_repeats: 0,
            sparse: self.sparse,
            ahead: VecDeque::new(),
            words: pos.words,
            time,
            gap_left: pos.gap_left,
            time_reported: false,
            last_row: pos.last_row.clone(),
            ties: pos.ties.clone(),
            phase: self.phase,
            hints: pos.hints.clone(),
            line: Vec::new(),
            prev_text: pos.last_text.clone(),
            cut_last: false,
            bad_rows: pos.bad_rows,
            invalid_values: pos.invalid_values,
            missing_cells: pos.missing_cells,
            rows: pos.rows,
            samples: pos.samples,
            offset: pos.offset,
            lvm: self.lvm,
        }
    }

    /// Where the reader stands: every row before it has been handed out by
    /// [`TextReader::read_rows`].
    pub fn position(&self) -> TextPosition {
        TextPosition {
            offset: self.offset - self.pending.as_ref().map_or(0, |_| self.line.len() as u64),
            line_no: self.line_no - u64::from(self.pending.is_some()),
            rows: self.rows,
            bad_rows: self.bad_rows,
            samples: self.samples,
            invalid_values: self.invalid_values,
            missing_cells: self.missing_cells,
            words: self.words,
            time: self.time.as_ref().map(TimeColumn::state),
            gap_left: self.gap_left,
            clocked: self.pending.is_some(),
            last_row: self.last_row.clone(),
            ties: self.ties.clone(),
            hints: self.hints.clone(),
            dates: self.layout.dates.get(),
            last_text: self.prev_text.clone(),
        }
    }

    /// Values read so far that were numbers (gaps and bad rows left out).
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// Whether the header is that of PX4's CSV export (`super::px4_export`): its `timestamp`
    /// counts us since boot.
    pub fn px4_export(&self) -> bool {
        self.layout.px4
    }

    /// Every column's name in the input (the header's, or `c1..cn`), used or not.
    pub fn header_names(&self) -> &[String] {
        &self.layout.source_names
    }

    /// The format the header (and the file's name) tells, fixing some columns' units and roles
    /// (`super::format_units::file_format`).
    pub fn file_format(&self) -> Option<super::format_units::FileFormat> {
        self.layout.format
    }

    /// The sampling step a LabVIEW Measurement file's header gives (`Delta_X`, s), if it is one.
    pub fn lvm_delta_x(&self) -> Option<f64> {
        self.lvm.as_ref().and_then(|h| h.delta_x)
    }

    /// The first time cell read so far that was neither a number nor a time this reads (at
    /// most 40 characters of it).
    pub fn unread_stamp(&self) -> Option<String> {
        self.layout.unread_stamp.borrow().clone()
    }

    /// The header name of the time column, if the input has one.
    pub fn time_column_name(&self) -> Option<&str> {
        self.layout
            .time
            .map(|i| self.layout.source_names[i].as_str())
    }

    /// The time stamps of the next `max_rows` rows (NaN where a row has none), and for each
    /// row which channels the run analyses hold a value there (in the order of
    /// [`TextReader::names`]; a bad row holds none), consuming them: for a look at the start of
    /// an input (`super::sampling_step`), not for a run. Rows written twice (the same stamp and
    /// values as the row before) are passed over as the run passes them over; the second value
    /// is how many were.
    pub fn take_stamps(&mut self, max_rows: usize) -> std::io::Result<(Vec<RowStamp>, usize)> {
        let present = |row: &Result<Vec<f64>, String>, strict: &[bool]| match row {
            Ok(v) => v
                .iter()
                .zip(strict)
                .map(|(x, &s)| s && !x.is_nan())
                .collect(),
            Err(_) => vec![false; strict.len()],
        };
        let mut rows = Vec::new();
        // The row before, to pass over a row written twice (the same stamp and values) as the
        // run does ([`TextReader::is_repeat`]).
        let mut last: Option<Row> = None;
        let mut repeats = 0;
        let same_row = |a: &Row, b: &Row| match (&a.0, &b.0) {
            (Ok(x), Ok(y)) => same_record((x, a.1), (y, b.1)),
            _ => false,
        };
        if let Some(p) = self.pending.take() {
            rows.push((p.1, present(&p.0, &self.layout.strict)));
            last = Some(p);
        }
        while rows.len() < max_rows {
            match self.next_row()? {
                // An empty line in a file with a time column is no row of it (the run skips
                // it too: [`TextReader::not_a_sample`]).
                Some(p)
                    if self.layout.time.is_some()
                        && p.1.is_nan()
                        && empty_row(&p, &self.layout.strict) => {}
                Some(p) if last.as_ref().is_some_and(|l| same_row(l, &p)) => repeats += 1,
                Some(p) => {
                    rows.push((p.1, present(&p.0, &self.layout.strict)));
                    last = Some(p);
                }
                None => break,
            }
        }
        Ok((rows, repeats))
    }

    /// Whether the line `t` is the header (or the row of units under it) again.
    fn repeats_header(&self, t: &str) -> bool {
        let t = t.trim_start_matches('\u{feff}');
        // A data row starts with a digit, a sign or a point: only a line starting otherwise is
        // compared, so rows of numbers cost nothing here.
        if self.header_rows.is_empty()
            || t.starts_with(|c: char| c.is_ascii_digit() || matches!(c, '-' | '+' | '.'))
        {
            return false;
        }
        let fields = self.layout.split(t);
        self.header_rows.iter().any(|h| {
            h.len() == fields.len()
                && h.iter()
                    .zip(&fields)
                    .all(|(a, b)| a == b.trim().trim_matches('"').trim())
        })
    }

    /// Whether the row `p` is no sample of this run, where a time column is in use (it spaces
    /// the rows kept, and a missing one is a gap): an empty line (no stamp, no value), and
    /// in a file whose channels hold values on every k-th row only
    /// ([`TextOptions::sparse_rows`]) a row where every channel the run analyses is empty.
    fn not_a_sample(&self, p: &Row) -> bool {
        let in_use = self.time.as_ref().is_some_and(TimeColumn::in_use);
        in_use && (self.sparse || p.1.is_nan()) && empty_row(p, &self.layout.strict)
    }

    /// Each channel's temperature scale where it holds the unit's temperature
    /// ([`super::temperature_column`]): read off its name in the input (`board_temp (K)`, or
    /// `Temp [K]` with a row of units) or the name the run gives it (`--columns
    /// "c9=temp [degF]"`), the one that names a unit first, or the format's (ArduPilot's `T`,
    /// [`super::format_units::FileFormat::temperature`]); `None` for the other channels.
    pub fn temperatures(&self) -> Vec<Option<super::temperature_column::TemperatureScale>> {
        self.layout
            .keep
            .iter()
            .zip(&self.names)
            .map(|(&i, name)| {
                let source = input_temperature(&self.layout.source_names[i], self.layout.format);
                let given = super::temperature_column::temperature_column(name);
                match (source, given) {
                    (Some(s), _) if s.named => Some(s),
                    (_, Some(g)) if g.named => Some(g),
                    (s, g) => g.or(s),
                }
            })
            .collect()
    }

    /// Channel names, from the header row or `c1..cn`.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Each channel's input column (1-based) and its name there (the header's, or `c1..cn`),
    /// in the order of [`TextReader::names`]: where a message points a person to.
    pub fn channel_columns(&self) -> Vec<(usize, &str)> {
        self.layout
            .keep
            .iter()
            .map(|&i| (i + 1, self.layout.source_names[i].as_str()))
            .collect()
    }

    pub fn bad_rows(&self) -> u64 {
        self.bad_rows
    }

    /// Data rows read so far (bad rows included).
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Appends up to `max_rows` rows to `out` (row-major, NaN for missing). Returns the number of
    /// rows appended; 0 at the end of the input.
    pub fn read_rows(&mut self, out: &mut Vec<f64>, max_rows: usize) -> std::io::Result<usize> {
        let width = self.names.len();
        let mut n = 0;
        while n < max_rows {
            if self.gap_left > 0 {
                // Steps the time column says are missing: gaps in every channel.
                let k = self.gap_left.min((max_rows - n) as u64);
                out.extend(std::iter::repeat_n(f64::NAN, k as usize * width));
                // A gap breaks each column's chain of changes.
                for h in &mut self.hints {
                    h.push(f64::NAN);
                }
                if let Some(c) = &mut self.time {
                    for _ in 0..k {
                        c.step_inserted();
                    }
                }
                self.gap_left -= k;
                n += k as usize;
                continue;
            }
            let (row, stamp) = match self.pending.take() {
                Some((row, t)) => {
                    // The first row, or the row after a gap: the clock is set to its stamp.
                    if let Some(c) = &mut self.time {
                        c.handed_out(t);
                    }
                    (row, t)
                }
                None => {
                    let Some(p) = self.next_row()? else {
                        break;
                    };
                    if std::mem::take(&mut self.clocked_next) {
                        // The pending row of the reader this one resumes.
                        self.pending = Some(p);
                        continue;
                    }
                    if self.not_a_sample(&p) {
                        continue;
                    }
                    if self.is_repeat(&p) {
                        // The same stamp and values as the row before: a record written twice
                        // (a logger or a driver's repeat), not a sample. Taken as one, it
                        // would put the clock a step ahead of every stamp after it.
                        if let Some(c) = &mut self.time {
                            c.duplicate(&self.path, self.line_no);
                        }
                        continue;
                    }
                    if let Ok(v) = &p.0 {
                        if self.ties.observe(v, &self.layout.strict) {
                            // A logger's repeat (super::row_ties): not a sample, and no gap
                            // either. Its stamp goes on the clock (with any gap before it), so
                            // the next row is a step on and the slot it held is gone.
                            if let Some(c) = &mut self.time {
                                self.gap_left = c.missing_before(p.1, &self.path, self.line_no);
                            }
                            continue;
                        }
                    }
                    let gap = match &mut self.time {
                        // A sample whose stamp is missing (an empty time cell) takes its step:
                        // the next stamp is then one step on, not a gap of one.
                        Some(c) if p.1.is_nan() => {
                            c.unstamped();
                            0
                        }
                        Some(c) => c.missing_before(p.1, &self.path, self.line_no),
                        None => 0,
                    };
                    if gap > 0 {
                        self.gap_left = gap;
                        self.pending = Some(p);
                        continue;
                    }
                    p
                }
            };
            // Kept only where a repeat can be told (`is_repeat`): a time column in use.
            let keep = self.time.as_ref().is_some_and(TimeColumn::in_use);
            match (&row, &mut self.last_row) {
                (Ok(_), last) if !keep => *last = None,
                (Ok(v), Some((lv, lt))) => {
                    lv.clear();
                    lv.extend_from_slice(v);
                    *lt = stamp;
                }
                (Ok(v), last) => *last = Some((v.clone(), stamp)),
                (Err(_), last) => *last = None,
            }
            self.push_row(out, row);
            n += 1;
        }
        if n == 0 && !self.time_reported {
            self.time_reported = true;
            if self.words > BAD_ROWS_LOGGED {
                tracing::warn!(
                    "{}: {} cells held a word, not a number (the first {BAD_ROWS_LOGGED} logged \
                     above): gaps of their channels",
                    self.path.display(),
                    self.words
                );
            }
            if let Some(c) = &self.time {
                c.report(&self.path);
            }
            self.report_ties();
            self.report_phase_hints();
            if self.missing_cells > 0 && !self.sparse {
                let (what, were) = if self.missing_cells == 1 {
                    ("cell", "was")
                } else {
                    ("cells", "were")
                };
                tracing::info!(
                    "{}: {} {what} of the analysed channels {were} empty or not a number: gaps \
                     of their channels",
                    self.path.display(),
                    self.missing_cells
                );
            }
        }
        Ok(n)
    }

    /// Warns, at the end of the input, of each analysed column read as increments or rate
    /// samples whose values look like an accumulated angle or velocity ([`super::phase_hint`]);
    /// a temperature column is left alone.
    fn report_phase_hints(&self) {
        let temperatures = self.temperatures();
        for (k, h) in self.hints.iter().enumerate() {
            let judged = self.layout.strict.get(k).copied().unwrap_or(false)
                && temperatures.get(k).is_some_and(Option::is_none);
            if let Some((first, last, ratio)) = h.looks_like_phase().filter(|_| judged) {
                tracing::warn!(
                    "{}: channel {}: its values move steadily from {first:.4e} to {last:.4e}, \
                     {ratio:.0e} times their change from one sample to the next: an accumulated \
                     angle or velocity? Read as increments or rate samples; give --phase if it \
                     is one",
                    self.path.display(),
                    self.names.get(k).map_or("?", String::as_str),
                );
            }
        }
    }

    /// Says, at the end of the input, what [`super::row_ties`] made of rows tied to the one
    /// before in every column.
    fn report_ties(&self) {
        use super::row_ties::TieVerdict;
        let share = 100.0 * self.ties.share();
        let chance = 100.0 * self.ties.chance_share;
        match self.ties.verdict {
            TieVerdict::Chance => {}
            TieVerdict::Logger => tracing::warn!(
                "{}: {} rows repeat the row before them in every column ({share:.2}% of rows, \
                 where chance gives {chance:.1e}%): a logger's stale or doubled sample, dropped \
                 as not samples of the unit (no gap; the run is that many samples shorter)",
                self.path.display(),
                self.ties.dropped
            ),
            TieVerdict::HeldOutput => tracing::warn!(
                "{}: {share:.1}% of rows repeat the row before them in every column (chance \
                 gives {chance:.1e}%): the unit's output may be slower than the rows (each \
                 sample held for more than one row); kept as they are, and the shortest taus \
                 then show the hold, not the unit",
                self.path.display()
            ),
        }
    }

    /// Whether `p` repeats the last row handed out, stamp and values (NaN equal to NaN), where
    /// a time column is in use (without one a repeated row cannot be told from a channel whose
    /// value stood still).
    fn is_repeat(&self, p: &Row) -> bool {
        let (Some(c), Some((lv, lt)), Ok(v)) = (&self.time, &self.last_row, &p.0) else {
            return false;
        };
        c.in_use() && same_record((v, p.1), (lv, *lt))
    }

    /// The next row of the input, `None` at its end (comment lines skipped).
    fn next_row(&mut self) -> std::io::Result<Option<Row>> {
        let width = self.names.len();
        loop {
            let (got, long) = next_line(&mut self.src, &mut self.ahead, &mut self.line)?;
            if got == 0 {
                return Ok(None);
            }
            self.offset += got as u64;
            self.line_no += 1;
            if long {
                let problem = format!("a line of {got} bytes, longer than any row of text columns");
                return Ok(Some((Err(problem), f64::NAN)));
            }
            // A line that is not UTF-8 is read as Latin-1 (Windows-1252), as the header and the
            // first row are: a label cell saved in a Windows code page is a label there too,
            // and a damaged stretch of the file is then a row whose cells are not numbers (a
            // bad row, not the end of the run).
            let latin1: String;
            let text = match std::str::from_utf8(&self.line) {
                Ok(t) => t,
                Err(_) => {
                    latin1 = self.line.iter().map(|&b| char::from(b)).collect();
                    &latin1
                }
            };
            // A byte-order mark starts the file (a reader resumed at its start reads it here)
            // and each file joined into it.
            let t = text.trim_start_matches('\u{feff}').trim();
            if is_note(t) {
                continue;
            }
            // A LabVIEW file's next segment: its header and the blank lines around it (the
            // format writes no empty row) are no rows; its column names again, below, are its
            // own (said for files joined into one).
            if self.lvm.is_some() && (t.is_empty() || super::lvm::is_tag_line(t)) {
                continue;
            }
            if self.repeats_header(t) {
                self.header_repeats += 1;
                if self.header_repeats == 1 && self.lvm.is_none() {
                    tracing::warn!(
                        "{}: line {}: the header again (files joined into one?): skipped, not a \
                         row",
                        self.path.display(),
                        self.line_no
                    );
                }
                continue;
            }
            if t.is_empty() {
                return Ok(Some((Ok(vec![f64::NAN; width]), f64::NAN)));
            }
            let mut row = match self.layout.parse(t) {
                Ok((v, time)) => (Ok(v), time),
                Err(e) => (Err(e), f64::NAN),
            };
            // Only the last line of the input can lack its end (a longer one is cut above).
            if self.line.last() != Some(&b'\n') {
                if let Some(why) = self.cut_last_line(t, &row) {
                    self.cut_last = true;
                    row = (
                        Err(format!(
                            "{why} (the last line, without its line end: cut while the file \
                             was written?)"
                        )),
                        f64::NAN,
                    );
                }
            }
            if row.0.is_ok() {
                self.prev_text.clear();
                self.prev_text.push_str(t);
            }
            return Ok(Some(row));
        }
    }

    /// What tells that the last line `t` of the input, read as `row`, was cut while the file
    /// was written (the line has no end), if anything: a field short (any row's problem), its
    /// last cell empty or no number where its column is read as one (a channel the run
    /// analyses, or the time column), or that number shorter than the same column's in the row
    /// before: fewer decimals, or its exponent lost or shorter (`0.00` of `0.001234`, `3.7` of
    /// `3.75e-03`). A row whose last cell is read in full is used: many writers end a file
    /// without a line end.
    fn cut_last_line(&self, t: &str, row: &Row) -> Option<String> {
        let values = match &row.0 {
            Ok(v) => v,
            Err(e) => return Some(e.clone()),
        };
        let (i, cell) = self.layout.last_cell(t)?;
        let l = &self.layout;
        let read = if l.time == Some(i) {
            !row.1.is_nan()
        } else {
            let k = l.keep.iter().position(|&c| c == i)?;
            if !l.strict[k] {
                return None;
            }
            !values[k].is_nan() && values[k].to_bits() != WORD_CELL_BITS
        };
        let column = format!("column {} `{}`", i + 1, l.source_names[i]);
        let cell = cell.trim();
        if !read {
            return Some(format!("{column}: `{cell}` is no number"));
        }
        let before = l.cell_at(&self.prev_text, i)?.trim();
        // Numbers only: a date's form changes with its month's name (`30-Nov`, `01-Dec`).
        let numbers = parse_field(cell).is_ok() && parse_field(before).is_ok();
        (numbers && shorter_number(cell, before)).then(|| {
            format!("{column}: `{cell}` is written shorter than `{before}` in the row before")
        })
    }

    fn push_row(&mut self, out: &mut Vec<f64>, row: Result<Vec<f64>, String>) {
        self.rows += 1;
        match row {
            Ok(v) => {
                // `inf`, `1e308`, `1e-300`: counted, and a gap like `nan`.
                let start = out.len();
                out.extend_from_slice(&v);
                if !self.phase {
                    self.hints.resize(v.len(), Default::default());
                    for (h, &x) in self.hints.iter_mut().zip(&v) {
                        // A value out of range is a gap (a word cell's marker is a NaN too).
                        h.push(super::plausible(x).unwrap_or(f64::NAN));
                    }
                }
                // Only the columns the run analyses are counted (`--channels`).
                for (k, (x, &counted)) in
                    out[start..].iter_mut().zip(&self.layout.strict).enumerate()
                {
                    if x.to_bits() == WORD_CELL_BITS {
                        *x = f64::NAN;
                        self.words += 1;
                        if self.words <= BAD_ROWS_LOGGED {
                            let i = self.layout.keep[k];
                            let text = String::from_utf8_lossy(&self.line);
                            let fields = self.layout.split(text.trim());
                            let cell = fields.get(i).map_or("", |f| f.trim());
                            tracing::warn!(
                                "{}: line {}: column {} `{}` holds `{cell}`, not a number: a gap \
                                 of that channel",
                                self.path.display(),
                                self.line_no,
                                i + 1,
                                self.layout.source_names[i]
                            );
                        }
                    } else if super::plausible(*x).is_none() {
                        *x = f64::NAN;
                        self.invalid_values += u64::from(counted);
                    } else if !x.is_nan() {
                        self.samples += u64::from(counted);
                    } else {
                        self.missing_cells += u64::from(counted);
                    }
                }
            }
            Err(problem) => {
                self.bad_rows += 1;
                for h in &mut self.hints {
                    h.push(f64::NAN);
                }
                if self.bad_rows <= BAD_ROWS_LOGGED || self.cut_last {
                    tracing::warn!(
                        "{}: line {}: {problem}; row skipped as a gap",
                        self.path.display(),
                        self.line_no
                    );
                }
                out.extend(std::iter::repeat_n(f64::NAN, self.names.len()));
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A stream with no line end (`/dev/zero`) gives back a long line after
    /// `MAX_LINE_CONSUMED` bytes instead of reading for ever, keeping only `max` of them; the
    /// rest is the next line.
    #[test]
    fn a_line_without_an_end_is_cut() {
        let mut src = std::io::BufReader::new(std::io::Read::take(std::io::repeat(0), 1 << 40));
        let mut buf = Vec::new();
        let (got, long) = read_line_bounded(&mut src, &mut buf, 1000).unwrap();
        assert_eq!((got, long, buf.len()), (MAX_LINE_CONSUMED, true, 1000));
        let (got, long) = read_line_bounded(&mut src, &mut buf, 1000).unwrap();
        assert_eq!((got, long), (MAX_LINE_CONSUMED, true));
        // A line with its end is read whole, as before.
        let mut src = std::io::BufReader::new(&b"1,2\n3,4\n"[..]);
        assert_eq!(
            read_line_bounded(&mut src, &mut buf, 1000).unwrap(),
            (4, false)
        );
        assert_eq!(buf, b"1,2\n");
    }

    fn read_all(text: &str) -> (Vec<String>, Vec<f64>, u64) {
        let mut r = TextReader::new(text.as_bytes(), Path::new("t.csv")).unwrap();
        let mut out = Vec::new();
        while r.read_rows(&mut out, 2).unwrap() > 0 {}
        (r.names().to_vec(), out, r.bad_rows())
    }

    /// `text` read whole at `--tau0 0.01`: the reader at its end, and the values.
    fn read_stepped(text: &str) -> (TextReader<&[u8]>, Vec<f64>) {
        read_at(text, 0.01)
    }

    /// `text` read whole at `--tau0 tau0_s`: the reader at its end, and the values.
    fn read_at(text: &str, tau0_s: f64) -> (TextReader<&[u8]>, Vec<f64>) {
        let opts = TextOptions {
            tau0_s: Some(tau0_s),
            ..TextOptions::default()
        };
        let mut r = TextReader::with_options(text.as_bytes(), Path::new("t.csv"), &opts).unwrap();
        let mut out = Vec::new();
        while r.read_rows(&mut out, 8).unwrap() > 0 {}
        (r, out)
    }

    /// A file of `header` over the stamps `rows`, each with its row number as the value.
    fn stamped(header: &str, rows: &[&str]) -> String {
        let mut text = format!("{header}\n");
        for (i, r) in rows.iter().enumerate() {
            text += &format!("{r},{i}\n");
        }
        text
    }

    #[test]
    fn header_separators_gaps_and_bad_rows() {
        let (names, v, bad) = read_all("# c\ngx, gy\n1,2\n\n3,nan\n4 5\nx,6\n2.5.1,8\n7,\n");
        assert_eq!(names, ["gx", "gy"]);
        // rows: (1,2) (gap) (3,-) (4,5: spaces also separate) (-,6: the word `x` a gap of gx)
        // (bad: `2.5.1` a damaged number) (7,-)
        let nan = f64::NAN;
        let expected = [
            1.0, 2.0, nan, nan, 3.0, nan, 4.0, 5.0, nan, 6.0, nan, nan, 7.0, nan,
        ];
        assert_eq!(v.len(), expected.len());
        for (a, b) in v.iter().zip(expected) {
            assert!(a == &b || (a.is_nan() && b.is_nan()), "{v:?}");
        }
        assert_eq!(bad, 1);
    }

    /// A last line without its line end, cut while the file was written: a field short, its
    /// last cell empty or no number, or its last number shorter than the same column's in the
    /// row before (fewer decimals, the exponent lost or cut) is a bad row, counted, its values
    /// gaps; complete, it is read as any row. Before, every one of them was read as a sample
    /// but the row a field short (`3.7` for `3.75e-03`, 1000 times too large).
    #[test]
    fn a_last_line_cut_while_written_is_a_bad_row() {
        let head = "t,gx,gy\n0.000,0.001234,1.25e-03\n0.005,-0.002345,2.50e-03\n";
        for (tail, bad) in [
            ("0.010,0.003456,3.75e-03", 0),
            ("0.010,0.003456,3.75e-03\n", 0),
            ("0.010,0.003456,3.75e-03\r\n", 0),
            ("0.010,0.003456", 1),
            ("0.010,0.003456,", 1),
            ("0.010,0.003456,-", 1),
            ("0.010,0.003456,3.75e-0", 1),
            ("0.010,0.003456,3.7", 1),
        ] {
            let (_, v, got) = read_all(&format!("{head}{tail}"));
            assert_eq!((got, v.len()), (bad, 6), "{tail:?}");
            let last = (v[4], v[5]);
            if bad == 0 {
                assert_eq!(last, (0.003456, 3.75e-3), "{tail:?}");
            } else {
                assert!(last.0.is_nan() && last.1.is_nan(), "{tail:?}: {v:?}");
            }
        }
        // Fixed decimals, no exponent: `0.00` cut from a number of six decimals; a row with a
        // line end keeps what it holds.
        let (_, v, bad) = read_all("gx,gy\n0.001234,0.002345\n0.003456,0.00");
        assert_eq!((bad, v.len()), (1, 4));
        assert!(v[2].is_nan() && v[3].is_nan(), "{v:?}");
        let (_, v, bad) = read_all("gx,gy\n0.001234,0.002345\n0.003456,0.00\n");
        assert_eq!((bad, v), (0, vec![0.001234, 0.002345, 0.003456, 0.0]));
        let (_, v, bad) = read_all("gx,gy\n0.001234,0.002345\n0.003456,0.004567");
        assert_eq!((bad, v[3]), (0, 0.004567));
        // A run resumed right before the cut line judges it as one reading does.
        let text = "gx,gy\n0.001234,0.002345\n0.003456,0.004567\n0.005678,0.00";
        let open = || TextReader::new(text.as_bytes(), Path::new("t.csv")).unwrap();
        let mut r = open();
        let mut out = Vec::new();
        r.read_rows(&mut out, 2).unwrap();
        let pos = r.position();
        let mut r2 = r.resume(&text.as_bytes()[pos.offset as usize..], &pos);
        while r2.read_rows(&mut out, 2).unwrap() > 0 {}
        assert_eq!((r2.bad_rows(), out.len()), (1, 6));
        assert!(out[4].is_nan() && out[5].is_nan(), "{out:?}");
    }

    #[test]
    fn a_unit_in_brackets_stays_with_its_name_between_spaces() {
        // One column whose name holds a space: one column, not two (the rows were all bad).
        let (names, v, bad) = read_all("ax [m/s^2]\n0.25\n-0.5\n");
        assert_eq!(names, ["ax [m/s^2]"]);
        assert_eq!((v, bad), (vec![0.25, -0.5], 0));
        // Units with spaces inside their brackets, columns between spaces.
        let (names, v, bad) = read_all("t gx [rad s^-1] gy (deg/s)\n0 1 2\n0.01 3 4\n");
        // (`t` is the time column, not a channel.)
        assert_eq!(names, ["gx [rad s^-1]", "gy (deg/s)"]);
        assert_eq!(v, [1.0, 2.0, 3.0, 4.0]);
        assert_eq!(bad, 0);
    }

    #[test]
    fn a_line_that_is_not_utf8_is_a_bad_row_not_the_end() {
        let mut bytes = b"c\n1\n".to_vec();
        bytes.extend_from_slice(&[0xff, 0xfe, b'\n']);
        bytes.extend_from_slice(b"3\n");
        let mut r = TextReader::new(bytes.as_slice(), Path::new("u.csv")).unwrap();
        let mut out = Vec::new();
        while r.read_rows(&mut out, 8).unwrap() > 0 {}
        assert_eq!(out.len(), 3);
        assert_eq!((out[0], out[2]), (1.0, 3.0));
        assert!(out[1].is_nan());
        assert_eq!(r.bad_rows(), 1);
    }

    /// A ROS `rostopic echo -p` export: a label column (`frame_id`) is left out, not a reason
    /// to refuse the file; with `--channels`, a cell that is not a number in a column the run
    /// does not analyse loses no row and is not counted, and its huge stamps are not counted
    /// invalid; a label column the run names is refused.
    #[test]
    fn label_columns_and_columns_the_run_leaves_out() {
        let text = "%time,field.header.stamp,field.header.frame_id,field.w.x,field.w.y\n\
                    1,1700000000000000000,imu_link,0.5,1.5\n\
                    2,1700000000005000000,imu_link,ERR,2.5\n\
                    3,1700000000010000000,imu_link,0.25,3.5\n";
        let read = |opts: &TextOptions| {
            let mut r = TextReader::with_options(text.as_bytes(), Path::new("r.csv"), opts)?;
            let mut out = Vec::new();
            while r.read_rows(&mut out, 8).unwrap() > 0 {}
            Ok::<_, UsageError>((r.names().to_vec(), out, r.bad_rows(), r.invalid_values))
        };
        // Every column: the label column is no channel, nor `%time` (a second time column:
        // the time the recorder received the message; the message's own `field.header.stamp`
        // is the time); `ERR` is a gap of its channel alone, counted.
        let (names, v, bad, invalid) = read(&TextOptions::default()).unwrap();
        assert_eq!(names, ["field.w.x", "field.w.y"]);
        assert_eq!((v.len(), bad, invalid), (6, 0, 0));
        assert_eq!((v[0], v[1], v[3], v[4], v[5]), (0.5, 1.5, 2.5, 0.25, 3.5));
        assert!(v[2].is_nan());
        let mut r = TextReader::new(text.as_bytes(), Path::new("r.csv")).unwrap();
        assert_eq!(r.time_column_name(), Some("field.header.stamp"));
        while r.read_rows(&mut Vec::new(), 8).unwrap() > 0 {}
        assert_eq!(r.position().words, 1);
        // `--channels field.w.y`: nothing counted; the columns the run leaves out stay in the
        // rows (read as gaps where not numbers).
        let opts = TextOptions {
            channels: Some(vec!["field.w.y".into()]),
            ..TextOptions::default()
        };
        let (names, v, bad, invalid) = read(&opts).unwrap();
        assert_eq!(names, ["field.header.frame_id", "field.w.x", "field.w.y"]);
        assert_eq!((bad, invalid), (0, 0));
        let y: Vec<f64> = v.chunks(3).map(|r| r[2]).collect();
        assert_eq!(y, [1.5, 2.5, 3.5]);
        // Named in --channels, the second time column is read (its huge stamps counted
        // invalid, gaps).
        let opts = TextOptions {
            channels: Some(vec!["field.header.stamp".into()]),
            ..TextOptions::default()
        };
        let (names, _, _, invalid) = read(&opts).unwrap();
        assert_eq!(names[0], "field.header.stamp");
        assert_eq!(invalid, 3);
        // Named, the label column is an error saying what it holds.
        for opts in [
            TextOptions {
                channels: Some(vec!["field.header.frame_id".into()]),
                ..TextOptions::default()
            },
            TextOptions {
                columns: Some(vec![
                    "field.w.x".parse().unwrap(),
                    "field.header.frame_id".parse().unwrap(),
                ]),
                ..TextOptions::default()
            },
        ] {
            let e = read(&opts).unwrap_err().to_string();
            assert!(
                e.contains("column 3 `field.header.frame_id`: `imu_link` is not a number"),
                "{e}"
            );
        }
    }

    /// ROS 2's `ros2 topic echo --csv` writes no header and a `frame_id` among the numbers: the
    /// first row is data, its text column a label left out; the other columns keep their
    /// numbers as names (`c4` is the fourth column).
    #[test]
    fn a_row_of_numbers_with_a_label_is_data_not_a_header() {
        let (names, v, bad) = read_all(
            "1664780446,971418804,imu_link,0.0,0.25\n1664780446,981418804,imu_link,0.0,0.5\n",
        );
        assert_eq!(names, ["c1", "c2", "c4", "c5"]);
        assert_eq!(bad, 0);
        assert_eq!((v[3], v[7]), (0.25, 0.5));
        // pandas' header of integer-labelled columns after a time column is a header.
        let (names, v, _) = read_all("time,0,1\n0.0,0.5,0.25\n0.01,1,2\n");
        assert_eq!(names, ["0", "1"]);
        assert_eq!(v, [0.5, 0.25, 1.0, 2.0]);
        // A row of names with a number among them is still a header.
        let (names, v, _) = read_all("gx,gy,1\n0.5,0.25,2\n");
        assert_eq!(
            (names, v),
            (
                vec!["gx".to_string(), "gy".into(), "1".into()],
                vec![0.5, 0.25, 2.0]
            )
        );
    }

    /// `N/A`, `null`, `-` in a data column are gaps like an empty cell, not a label's text.
    #[test]
    fn missing_value_markers_are_gaps() {
        let (names, v, bad) = read_all("gx,gy\nN/A,0.5\n0.25,NULL\n-,1\n");
        assert_eq!((names, bad), (vec!["gx".to_string(), "gy".into()], 0));
        let shown: Vec<String> = v.iter().map(|x| format!("{x}")).collect();
        assert_eq!(shown, ["NaN", "0.5", "0.25", "NaN", "NaN", "1"]);
    }

    #[test]
    fn no_header_gives_default_names() {
        let (names, v, _) = read_all("1\t2\t3\n4 5 6\n");
        assert_eq!(names, ["c1", "c2", "c3"]);
        assert_eq!(v, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    }

    #[test]
    fn empty_input_is_a_usage_error() {
        assert!(TextReader::new("# only a comment\n".as_bytes(), Path::new("e.csv")).is_err());
    }

    /// Numbers as Fortran writes them, and stamps as dates and times, against values worked
    /// out by hand (Python's `datetime(...).timestamp()` agrees).
    #[test]
    fn fortran_exponents_and_dates_and_times() {
        assert_eq!(parse_field("1.5D-03"), Ok(1.5e-3));
        assert_eq!(parse_field("-2.25d+02"), Ok(-225.0));
        assert!(parse_field("D-03").is_err());
        assert!(parse_field("1.5D-03D").is_err());
        for (text, secs) in [
            ("2026-12-03T01:02:03.5Z", 1_796_259_723.5),
            ("2026-12-03 01:02:03.500", 1_796_259_723.5),
            ("2026/12/03 01:02:03.5", 1_796_259_723.5),
            ("03.12.2026 01:02:03,5", 1_796_259_723.5),
            ("2000-02-29T23:59:59", 951_868_799.0),
            ("1969-12-31T00:00:00Z", -86_400.0),
            ("2024-03-01T12:00:00+01:00", 1_709_290_800.0),
            ("2024-03-01T12:00:00+0100", 1_709_290_800.0),
            ("2024-03-01T05:00:00-05", 1_709_290_800.0 - 3600.0),
            ("01:02:03.25", 3723.25),
        ] {
            let got = date_time(text).unwrap_or_else(|| panic!("{text}"));
            assert!((got - secs).abs() < 1e-6, "{text}: {got} vs {secs}");
        }
        for text in [
            "12.5",
            "2026-13-03 01:02:03",
            "01:62:03",
            "1:2",
            "abc",
            "2026-12-03",
        ] {
            assert!(date_time(text).is_none(), "{text}");
        }
        // A time column of dates: the steps are the sampling step.
        let (names, v, bad) =
            read_all("timestamp,gx\n2026-12-03 23:59:59.995,1\n2026-12-04 00:00:00.000,2\n");
        assert_eq!((names, v, bad), (vec!["gx".to_string()], vec![1.0, 2.0], 0));
        let mut r = TextReader::with_options(
            "stamp,gx\n2026-12-03 23:59:59.990,0\n2026-12-03 23:59:59.995,1\n\
             2026-12-04 00:00:00.005,2\n"
                .as_bytes(),
            Path::new("d.csv"),
            &TextOptions {
                tau0_s: Some(0.005),
                ..TextOptions::default()
            },
        )
        .unwrap();
        let mut out = Vec::new();
        while r.read_rows(&mut out, 8).unwrap() > 0 {}
        // A step of 10 ms across midnight: one sample of 5 ms missing there.
        assert_eq!(out.len(), 4);
        assert!(out[2].is_nan());
    }

    /// The names of time columns beyond `time`: a word for time anywhere in the name, in other
    /// languages too, with its unit; a step or a time constant is no clock; `time` is preferred
    /// to `gps_time`; a headerless file's time column is named by its number.
    #[test]
    fn time_columns_by_the_words_in_their_names() {
        for (name, unit) in [
            ("Zeit [s]", Some(1.0)),
            ("elapsed (ms)", Some(1e-3)),
            ("sample_time_us", Some(1e-6)),
            ("gps_time", None),
            ("field.header.stamp", None),
            ("Timestamp (UTC)", None),
            ("time (seconds)", Some(1.0)),
            ("t_ns", Some(1e-9)),
            ("time_s", Some(1.0)),
        ] {
            assert_eq!(time_column_unit(name), Some(unit), "{name}");
        }
        for name in [
            "delta_time",
            "dt",
            "time [deg]",
            "gx",
            "temp",
            "tc_constant_time",
            "acc_t",
        ] {
            assert_eq!(time_column_unit(name), None, "{name}");
        }
        let (names, _, _) = read_all("gps_time,time,gx\n1,0.0,5\n2,0.01,6\n");
        assert_eq!(names, ["gx"]);
        let mut r =
            TextReader::new("gps_time,time,gx\n1,0.0,5\n".as_bytes(), Path::new("g.csv")).unwrap();
        assert_eq!(r.time_column_name(), Some("time"));
        assert_eq!(r.read_rows(&mut Vec::new(), 1).unwrap(), 1);
        let r = TextReader::with_options(
            "0.0 1.0D-02\n0.005 2.0D-02\n".as_bytes(),
            Path::new("f.dat"),
            &TextOptions {
                time_column: Some("c1".into()),
                ..TextOptions::default()
            },
        )
        .unwrap();
        assert_eq!(
            (r.names(), r.time_column_name()),
            (&["c2".to_string()][..], Some("c1"))
        );
    }

    /// A row of units under the header: the columns' units as if in brackets, the channels
    /// named as the header names them, `--columns` by the header's names, the time column by
    /// its unit; a row of words that are not units is a first data row, as before.
    #[test]
    fn a_row_of_units_under_the_header() {
        let text = "Zeit;Gyro X;Acc X;Temp\ns;deg/s;g;degC\n0,000;0,5;0,25;20\n0,005;1,5;0,5;21\n";
        let r = TextReader::new(text.as_bytes(), Path::new("u.csv")).unwrap();
        assert_eq!(r.names(), ["Gyro X", "Acc X", "Temp"]);
        assert_eq!(r.time_column_name(), Some("Zeit [s]"));
        let cols: Vec<&str> = r.channel_columns().into_iter().map(|(_, n)| n).collect();
        assert_eq!(cols, ["Gyro X [deg/s]", "Acc X [g]", "Temp [degC]"]);
        let r = TextReader::with_options(
            text.as_bytes(),
            Path::new("u.csv"),
            &TextOptions {
                columns: Some(vec!["Acc X=ax".parse().unwrap()]),
                ..TextOptions::default()
            },
        )
        .unwrap();
        // The unit's temperature is read beside the column --columns names.
        assert_eq!(r.names(), ["ax", "Temp [degC]"]);
        assert_eq!(r.channel_columns()[0], (3, "Acc X [g]"));
        assert_eq!(r.temperatures()[1].map(|t| t.named), Some(true));
        // `ok;ok` is no units row: a first data row of text, an error naming it.
        let e = TextReader::new("a;b\nok;ok\n1;2\n".as_bytes(), Path::new("w.csv"));
        assert!(e.is_ok_and(|r| r.names() == ["a", "b"]));
    }

    /// A word in a channel's first cell (`ERR`) makes it no label column when numbers follow:
    /// the word is a gap of that channel alone; a checkpoint taken while the rows read ahead
    /// to tell this are still to come resumes to the same rows.
    #[test]
    fn a_flagged_first_sample_is_a_gap_not_a_label() {
        let mut text = String::from("time,gx,ax,frame\n0.000,0.5,ERR,imu\n");
        for i in 1..300 {
            text.push_str(&format!("{:.3},{i},{},imu\n", i as f64 * 0.005, 2 * i));
        }
        let (names, v, bad) = read_all(&text);
        assert_eq!(names, ["gx", "ax"]);
        assert_eq!(bad, 0);
        assert_eq!((v[0], v[2], v[3], v.len()), (0.5, 1.0, 2.0, 600));
        assert!(v[1].is_nan());
        // Stopped after 5 rows (its position inside the rows read ahead), resumed.
        let mut r = TextReader::new(text.as_bytes(), Path::new("e.csv")).unwrap();
        let mut head = Vec::new();
        r.read_rows(&mut head, 5).unwrap();
        let pos = r.position();
        let rest_src = &text.as_bytes()[pos.offset as usize..];
        let mut r2 = r.resume(rest_src, &pos);
        let mut tail = Vec::new();
        while r2.read_rows(&mut tail, 64).unwrap() > 0 {}
        head.extend(tail);
        assert_eq!(head.len(), v.len());
        assert!(head
            .iter()
            .zip(&v)
            .all(|(a, b)| a == b || (a.is_nan() && b.is_nan())));
        assert_eq!(r2.position().words, 1);
    }

    /// Logs joined into one file: the header (and its row of units) found again is skipped,
    /// no row and no gap.
    #[test]
    fn the_header_again_is_skipped() {
        let (names, v, bad) =
            read_all("time,gx\n0,1\n0.01,2\ntime,gx\n0.02,3\n\u{feff}time,gx\n0.03,4\n");
        assert_eq!(
            (names, v, bad),
            (vec!["gx".to_string()], vec![1.0, 2.0, 3.0, 4.0], 0)
        );
        let (_, v, _) = read_all("t;gx\ns;deg/s\n0;1\nt;gx\ns;deg/s\n0,005;2\n");
        assert_eq!(v, [1.0, 2.0]);
    }

    /// Xsens MT Manager's export: `//` notes before a tab header, a packet counter that wraps
    /// (no channel), `SampleTimeFine` in 100 us (the time column, gaps found in it); camel-case
    /// names' words are words (`GpsTime` is a clock).
    #[test]
    fn an_xsens_export() {
        let text = "// General information:\n//  MT Manager version: 2022.0.0\n\
                    // Update Rate: 100.0Hz\n\
                    PacketCounter\tSampleTimeFine\tAcc_X\tGyr_X\n\
                    65534\t1000000\t0.5\t0.25\n65535\t1000100\t0.5\t0.25\n\
                    0\t1000200\t0.5\t0.25\n2\t1000400\t0.5\t0.25\n";
        let opts = TextOptions {
            tau0_s: Some(0.01),
            ..TextOptions::default()
        };
        let mut r = TextReader::with_options(text.as_bytes(), Path::new("x.txt"), &opts).unwrap();
        assert_eq!(r.names(), ["Acc_X", "Gyr_X"]);
        assert_eq!(r.time_column_name(), Some("SampleTimeFine"));
        let mut out = Vec::new();
        while r.read_rows(&mut out, 8).unwrap() > 0 {}
        // Four rows and the one missing between 1000200 and 1000400.
        assert_eq!(out.len(), 10);
        assert!(out[6].is_nan() && out[7].is_nan());
        assert_eq!(time_column_unit("GpsTime"), Some(None));
        assert!(counter_column("field.header.seq") && counter_column("frame_count"));
        assert!(!counter_column("gyro_x_counts") && !counter_column("gx"));
        // An axis's pulse counts are a channel, not the sample counter.
        for n in ["gz_cnt", "cnt_x", "accel_count", "GyroZCount", "dtheta_cnt"] {
            assert!(!counter_column(n), "{n}");
        }
        for n in ["PacketCounter", "sample_idx", "seq", "frame_count"] {
            assert!(counter_column(n), "{n}");
        }
    }

    /// Names that say a column holds no inertial channel, and names that only look alike:
    /// words, not substrings; an axis letter may end the word (`magX`); an instance number only
    /// by its whole name. ArduPilot's clocks are in us and ms.
    #[test]
    fn names_of_other_quantities() {
        for (n, q) in [
            ("Status", "a status word"),
            ("imu.flags", "a status word"),
            ("Mag_X", "a magnetic field"),
            ("magY", "a magnetic field"),
            ("compass_z [raw]", "a magnetic field"),
            ("Magnitude", "a vector's magnitude"),
            ("Absolute (m/s^2)", "a vector's magnitude"),
            ("sensor_id", "the number of the sensor its rows are of"),
            ("imuId", "the number of the sensor its rows are of"),
        ] {
            assert_eq!(named_quantity(n), Some(q), "{n}");
        }
        for n in [
            "gyro_x",
            "max_rate",
            "magic",
            "image_x",
            "normal_acc",
            "flag_count",
            "Ix",
            "id",
            "I",
            "gx (abs)",
            "gx_norm",
        ] {
            assert_eq!(named_quantity(n), None, "{n}");
        }
        assert_eq!(time_name("TimeUS"), Some((false, Some(1e-6))));
        assert_eq!(time_name("TimeMS"), Some((false, Some(1e-3))));
    }

    /// Rows of two sensors, numbered in `sensor_id` (or ArduPilot's `I`), interleave: refused
    /// with the line to keep one (a path with a space quoted). Not: the same column with one
    /// number, a column named otherwise, a bare `I` outside ArduPilot's messages (a quantized
    /// in-phase signal), negative numbers, or the column named in `--channels`.
    #[test]
    fn interleaved_sensors() {
        let rows = |head: &str, sensors: i64, from: i64| {
            let mut s = format!("{head}\n");
            for i in 0..40i64 {
                s += &format!("{},{},{}\n", i / sensors, from + i % sensors, i % 7);
            }
            s
        };
        let refused = |text: &str, path: &str, opts: &TextOptions| {
            TextReader::with_options(text.as_bytes(), Path::new(path), opts)
                .err()
                .map(|e| e.to_string())
        };
        let opts = TextOptions::default();
        let e = refused(&rows("t,sensor_id,gx", 2, 0), "m.csv", &opts).unwrap();
        assert!(
            e.contains("column 2 `sensor_id` numbers 2 sensors (0, 1) whose rows share the file")
                && e.contains("`awk -F, '!/^[-+0-9.]/ || $2 == 0' m.csv > one.csv`"),
            "{e}"
        );
        let e = refused(&rows("TimeUS,I,GyrX", 3, 0), "my run.csv", &opts).unwrap();
        assert!(
            e.contains("numbers 3 sensors (0, 1, 2)") && e.contains("'my run.csv' > one.csv"),
            "{e}"
        );
        for (head, sensors, from, names) in [
            ("t,instance,gx", 1, 0, &["gx"][..]),
            ("t,I,gx", 2, 0, &["I", "gx"]),
            ("t,mode,gx", 2, 0, &["mode", "gx"]),
            ("t,sensor_id,gx", 2, -1, &["gx"]),
        ] {
            let text = rows(head, sensors, from);
            let r = TextReader::with_options(text.as_bytes(), Path::new("m.csv"), &opts).unwrap();
            assert_eq!(r.names(), names, "{head}");
        }
        let named = TextOptions {
            channels: Some(vec!["sensor_id".into(), "gx".into()]),
            ..TextOptions::default()
        };
        assert_eq!(
            refused(&rows("t,sensor_id,gx", 2, 0), "m.csv", &named),
            None
        );
    }

    /// PX4's `ulog2csv` export of sensor_combined: the fields that describe samples
    /// (integration intervals, a relative stamp, clipping flags, calibration counts) are no
    /// channels; `timestamp` in us finds a missing sample; `--channels` still reads such a field.
    #[test]
    fn a_px4_export() {
        let mut text = String::from(
            "timestamp,gyro_rad[0],gyro_integral_dt,accelerometer_timestamp_relative,\
             accelerometer_m_s2[0],accelerometer_clipping,gyro_calibration_count\n",
        );
        for (k, t) in [0u64, 1, 2, 4, 5].iter().enumerate() {
            let us = 20_313_000 + 5000 * t + [0, 2, 1, 3, 2][k];
            text.push_str(&format!("{us},0.0{k},5000,0,9.8{k},0,1\n"));
        }
        let opts = TextOptions {
            tau0_s: Some(0.005),
            ..TextOptions::default()
        };
        let mut r = TextReader::with_options(text.as_bytes(), Path::new("p.csv"), &opts).unwrap();
        assert!(r.px4_export());
        assert_eq!(r.names(), ["gyro_rad[0]", "accelerometer_m_s2[0]"]);
        let mut out = Vec::new();
        while r.read_rows(&mut out, 8).unwrap() > 0 {}
        // Five rows and the one missing between steps 2 and 4.
        assert_eq!(out.len(), 12);
        assert!(out[6].is_nan() && out[7].is_nan());
        assert_eq!((out[8], out[9]), (0.03, 9.83));
        let opts = TextOptions {
            tau0_s: Some(0.005),
            channels: Some(vec!["gyro_integral_dt".into()]),
            ..TextOptions::default()
        };
        let r = TextReader::with_options(text.as_bytes(), Path::new("p.csv"), &opts).unwrap();
        assert!(r.names().contains(&"gyro_integral_dt".to_string()));
        // A logger's own `timestamp,gx` is no PX4 export.
        let r = TextReader::new("timestamp,gx\n0,1\n".as_bytes(), Path::new("l.csv")).unwrap();
        assert!(!r.px4_export());
    }

    /// An Arduino sketch's serial output: greetings, then labelled values (`ax:0.5 ay:-1`,
    /// `ax=0.5, ay=-1`); the labels are the names, each value goes under its label whatever
    /// the order, a label left out is a gap, an unknown label makes a bad row. A time of day
    /// (`12:03:04`) is no label.
    #[test]
    fn labelled_values() {
        let text = "Initializing I2C devices...\nMPU6050 connection successful\n\
                    ax:0.5 ay:-1 gz:2e-3\nax: 0.25, ay: -2, gz: 1e-3\nay=-3 ax=0.125 gz=0\n\
                    ax:1 gz:5\nax:1 ay:2 mx:7\n";
        let (names, v, bad) = read_all(text);
        assert_eq!(names, ["ax", "ay", "gz"]);
        assert_eq!(bad, 1);
        let expect = [0.5, -1.0, 2e-3, 0.25, -2.0, 1e-3, 0.125, -3.0, 0.0, 1.0];
        assert_eq!(&v[..10], &expect);
        assert!(v[10].is_nan() && v[11] == 5.0);
        // `millis()` stamps: the time column, in ms; a missing sample found.
        let opts = TextOptions {
            tau0_s: Some(0.01),
            ..TextOptions::default()
        };
        let text = "millis:1000 gz:1\nmillis:1010 gz:2\nmillis:1030 gz:3\n";
        let mut r = TextReader::with_options(text.as_bytes(), Path::new("a.txt"), &opts).unwrap();
        assert_eq!(r.time_column_name(), Some("millis"));
        let mut out = Vec::new();
        while r.read_rows(&mut out, 8).unwrap() > 0 {}
        assert_eq!(out.len(), 4);
        assert!(out[2].is_nan());
        assert_eq!(labelled_cells("12:03:04.5,1,2"), None);
        assert_eq!(labelled_cells("gx [deg/s],gy"), None);
        let (names, _, _) = read_all("time,gx\n12:03:04.5,1\n12:03:04.6,2\n");
        assert_eq!(names, ["gx"]);
    }

    /// A checkpoint may be taken anywhere: at the first row, inside a long gap the time column
    /// found (the rest of the gap and the row after it still to hand out), right after a row
    /// written twice. A reader resumed from each position gives the rows of one reading on.
    /// Before, a resume inside a gap dropped the rest of the gap and counted the row after it as
    /// a step backwards.
    #[test]
    fn a_resume_inside_a_gap_keeps_the_gap() {
        let mut text = String::from("time,gx\n");
        for k in [0u32, 1, 2, 3, 53, 54, 54, 55, 56] {
            text.push_str(&format!("{:.2},{}\n", f64::from(k) * 0.01, k % 7));
        }
        let opts = TextOptions {
            tau0_s: Some(0.01),
            ..TextOptions::default()
        };
        let open = || TextReader::with_options(text.as_bytes(), Path::new("g.csv"), &opts).unwrap();
        let mut whole = Vec::new();
        let mut r = open();
        while r.read_rows(&mut whole, 7).unwrap() > 0 {}
        // 57 steps: 0..=56, the row 54 written twice dropped.
        assert_eq!(whole.len(), 57);
        for cut in 0..=whole.len() {
            let mut r = open();
            let mut head = Vec::new();
            r.read_rows(&mut head, cut).unwrap();
            let pos = r.position();
            let mut r2 = r.resume(&text.as_bytes()[pos.offset as usize..], &pos);
            while r2.read_rows(&mut head, 7).unwrap() > 0 {}
            let same = head.len() == whole.len()
                && head
                    .iter()
                    .zip(&whole)
                    .all(|(a, b)| a == b || (a.is_nan() && b.is_nan()));
            assert!(same, "cut {cut}: {head:?}");
            let st = r2.position().time.unwrap();
            assert_eq!(
                (st.missing, st.backwards, st.duplicates),
                (49, 0, 1),
                "cut {cut}"
            );
        }
    }

    /// What a review of the labelled values found: a `key=value` note before a header is a
    /// title, not labelled values; a first line cut short by the start of a capture does not
    /// name the channels (the commonest line does); greetings holding numbers are skipped; a
    /// `st=OK` beside the values is a label column; a label twice in a row makes a bad row; a
    /// header of words between spaces followed by a line of words keeps its names.
    #[test]
    fn labelled_values_a_review_found() {
        let mut csv = String::from("SampleRate=100\ntime,gx,gy\n");
        let mut cut = String::from("y:0.3 gz:0.1\n");
        let mut greet =
            String::from("MPU6050 found!\nCalibrating with 500 samples\nOffsets: 12 -3 5\n");
        let mut kv = String::new();
        for k in 0..40 {
            csv.push_str(&format!("{:.2},{k},{}\n", k as f64 * 0.01, k + 1));
            cut.push_str(&format!("ax:{k} ay:1 gz:2\n"));
            greet.push_str(&format!("ax:{k}, ay:1, gz:2\n"));
            kv.push_str(&format!("t={:.2} gx={k} st=OK\n", k as f64 * 0.01));
        }
        let (names, v, bad) = read_all(&csv);
        assert_eq!(
            (names, v.len(), bad),
            (vec!["gx".to_string(), "gy".into()], 80, 0)
        );
        let (names, v, bad) = read_all(&cut);
        assert_eq!((names.len(), v.len(), bad), (3, 123, 1));
        let (names, v, bad) = read_all(&greet);
        assert_eq!((names.len(), v.len(), bad, v[3]), (3, 120, 0, 1.0));
        let (names, v, _) = read_all(&kv);
        assert_eq!((names, v.len()), (vec!["gx".to_string()], 40));
        let (_, v, bad) = read_all("ax:1 ay:2\nax:3 ay:4 ax:5\nax:6 ay:7\n");
        assert_eq!((v.len(), bad), (6, 1));
        let (names, v, bad) = read_all("time gx gy\nX Y Z\n0 1 2\n0.01 3 4\n");
        assert_eq!(
            (names, v.len(), bad),
            (vec!["gx".to_string(), "gy".into()], 6, 1)
        );
    }

    /// An export with no time column but a packet counter (`PacketCounter`, 16 bits): with
    /// `--tau0`, the counter finds the missing samples, across its wrap too; named in
    /// `--channels` it is a channel and finds nothing; without `--tau0` it is no clock (the step
    /// is asked for).
    #[test]
    fn a_packet_counter_finds_missing_samples_without_a_time_column() {
        let text = "PacketCounter\tGyr_X\n65533\t1\n65534\t2\n1\t3\n2\t4\n5\t5\n";
        let opts = TextOptions {
            tau0_s: Some(0.01),
            ..TextOptions::default()
        };
        let mut r = TextReader::with_options(text.as_bytes(), Path::new("x.txt"), &opts).unwrap();
        assert_eq!(r.names(), ["Gyr_X"]);
        let mut out = Vec::new();
        while r.read_rows(&mut out, 8).unwrap() > 0 {}
        // 65533, 65534, (65535, 0), 1, 2, (3, 4), 5.
        assert_eq!(out.len(), 9);
        assert_eq!(out.iter().filter(|x| x.is_nan()).count(), 4);
        assert_eq!(r.position().time.unwrap().unit(), Some("count"));
        let opts = TextOptions {
            channels: Some(vec!["PacketCounter".into(), "Gyr_X".into()]),
            ..opts
        };
        let mut r = TextReader::with_options(text.as_bytes(), Path::new("x.txt"), &opts).unwrap();
        let mut out = Vec::new();
        while r.read_rows(&mut out, 8).unwrap() > 0 {}
        assert_eq!(out.len(), 10);
        assert!(r.time_column_name().is_none());
        let r = TextReader::new(text.as_bytes(), Path::new("x.txt")).unwrap();
        assert!(r.time_column_name().is_none());
    }

    /// A LabVIEW Measurement file as "Write To Measurement File" leaves it: a file header, a
    /// segment header with the channels' units, `X_Value` first, an empty `Comment` column
    /// last (each row's trailing tab), CRLF; a second segment's header and column names between
    /// rows. Read as the plain file of the same numbers with the units in the names: the same
    /// values, the x column the time column (a row left out a gap), nothing a bad row.
    #[test]
    fn a_labview_measurement_file_reads_as_the_plain_file() {
        let head = "LabVIEW Measurement\t\r\nWriter_Version\t2\r\nSeparator\tTab\r\n\
                    Decimal_Separator\t.\r\nX_Columns\tOne\r\nTime_Pref\tRelative\r\n\
                    Date\t2026/12/03\r\nTime\t07:51:28.665\r\n***End_of_Header***\t\r\n\t\r\n";
        let segment = "Channels\t2\t\t\r\nSamples\t8\t8\t\r\nY_Unit_Label\tdeg/s\tg\t\r\n\
                       X_Dimension\tTime\tTime\t\r\nX0\t0.0000000000000000E+0\t0.0E+0\t\r\n\
                       Delta_X\t1.000000E-2\t1.000000E-2\t\r\n***End_of_Header***\t\t\t\r\n\
                       X_Value\tgx\taz\tComment\r\n";
        let mut lvm = format!("{head}{segment}");
        let mut plain = String::from("time,gx [deg/s],az [g]\n");
        for i in (0..40u64).filter(|&i| i != 25) {
            if i == 20 {
                lvm += &format!("\t\r\n{segment}");
            }
            let (g, a) = (
                ((i * 37) % 11) as f64 * 1e-3,
                1.0 + ((i * 7) % 5) as f64 * 1e-4,
            );
            lvm += &format!("{:.6}\t{g:.6}\t{a:.6}\t\r\n", i as f64 * 0.01);
            plain += &format!("{:.6},{g:.6},{a:.6}\n", i as f64 * 0.01);
        }
        let read = |text: &str| {
            let (r, out) = read_stepped(text);
            let columns: Vec<String> = r
                .channel_columns()
                .iter()
                .map(|(_, n)| n.to_string())
                .collect();
            (columns, out, r.bad_rows(), r.lvm_delta_x())
        };
        let (names, v, bad, dx) = read(&lvm);
        let (pnames, pv, _, pdx) = read(&plain);
        // The units where the headers' units are read (the channels keep the bare names).
        assert_eq!(names, ["gx [deg/s]", "az [g]"]);
        assert_eq!(names, pnames);
        assert_eq!((bad, dx, pdx), (0, Some(0.01), None));
        assert_eq!(v.len(), 80);
        assert_eq!(v.iter().filter(|x| x.is_nan()).count(), 2);
        // An x column per channel (`X_Columns Multi`): the later ones no channels, each unit on
        // its channel; a channel called as a tag is (`Time`) is a channel.
        let multi = format!(
            "{head}Channels\t2\t\r\nY_Unit_Label\tdeg/s\tg\t\r\n***End_of_Header***\t\r\n\
             X_Value\tgx\tX_Value\tTime\tComment\r\n0.00\t1\t0.00\t2\t\r\n0.01\t3\t0.01\t4\t\r\n"
        );
        let (cols, _, _, _) = read(&multi);
        assert_eq!(cols, ["gx [deg/s]", "Time [g]"]);
        let (_, out) = read_stepped(&multi);
        assert_eq!(out, [1.0, 2.0, 3.0, 4.0]);
        assert_eq!(
            v.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
            pv.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
        );
    }

    /// An instrument's notes before the header are skipped, whatever they hold: DEWESoft's
    /// `Start time: ...` lines (a clock and a colon that read as labelled values or a header
    /// before), catman's tab-separated `File`/`Comment` lines with a row of units under its
    /// header; the rows read as the plain file's. A title the old rule skipped still is; a
    /// header with its rows right under it is not touched.
    #[test]
    fn notes_before_the_header_are_skipped() {
        let mut plain = String::from("time,gx\n");
        let mut dewe = String::from(
            "Start time: 03.12.2026 07:51:28.665\nSample rate: 100 Hz\nSetup: stand.dxs\n\n\
             Time [s];Gx [deg/s]\n",
        );
        let mut catman = String::from(
            "File\tC:\\data\\run1.BIN\nComment\tIMU stand\nT0\t03.12.2026 07:51:28\n\n\
             Time  1 - default sample rate\tGx\tGy\tGz\ns\tdeg/s\tdeg/s\tdeg/s\n",
        );
        for i in 0..30u64 {
            let g = ((i * 37) % 11) as f64 * 1e-3;
            plain += &format!("{:.2},{g}\n", i as f64 * 0.01);
            dewe += &format!(
                "{};{}\n",
                format!("{:.2}", i as f64 * 0.01).replace('.', ","),
                format!("{g}").replace('.', ",")
            );
            catman += &format!("{:.2}\t{g}\t{g}\t{g}\n", i as f64 * 0.01);
        }
        let read = |text: &str| {
            let (r, out) = read_stepped(text);
            (
                out.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                r.bad_rows(),
                r.time_column_name().map(str::to_string),
            )
        };
        let (want, _, _) = read(&plain);
        assert_eq!(want.len(), 30);
        let (v, bad, time) = read(&dewe);
        assert_eq!(
            (v, bad, time.as_deref()),
            (want.clone(), 0, Some("Time [s]"))
        );
        let (v, bad, time) = read(&catman);
        let thrice: Vec<u64> = want.iter().flat_map(|&x| [x, x, x]).collect();
        assert_eq!(
            (v, bad, time.as_deref()),
            (thrice, 0, Some("Time  1 - default sample rate [s]"))
        );
        // Two columns: the notes have as many fields as the rows, and only the header names
        // the time column.
        let mut two = String::from(
            "File\tC:\\data\\run1.BIN\nComment\tIMU stand\nT0\t03.12.2026 07:51:28\n\n\
             Time  1 - default sample rate\tGx\ns\tdeg/s\n",
        );
        for l in plain.lines().skip(1) {
            two += &format!("{}\n", l.replace(',', "\t"));
        }
        let (v, bad, time) = read(&two);
        assert_eq!(
            (v, bad, time.as_deref()),
            (want.clone(), 0, Some("Time  1 - default sample rate [s]"))
        );
        let lines: Vec<String> = plain.lines().skip(1).map(String::from).collect();
        assert_eq!(
            notes_before_header("IMU log stand 3 S/N 1234", &{
                let mut l = vec!["time,gx".to_string()];
                l.extend(lines.iter().cloned());
                l
            }),
            Some(1)
        );
        assert_eq!(notes_before_header("time,gx", &lines), None);
        assert_eq!(notes_before_header(&lines[0], &lines[1..]), None);
        // No header: greetings above the rows (an Arduino sketch's MPU6050_raw), or a first row
        // cut short by the capture's start, are notes; a header of one field fewer is not.
        let raw: Vec<String> = (0..20)
            .map(|i| format!("a/g:\t{}\t-256\t16212\t-296\t145\t-33", -1540 + i))
            .collect();
        let mut greeted = vec!["MPU6050 connection successful".to_string()];
        greeted.extend(raw.iter().cloned());
        assert_eq!(
            notes_before_header("Initializing I2C devices...", &greeted),
            Some(2)
        );
        assert_eq!(notes_before_header("256\t16212", &raw), Some(1));
        let ending: Vec<String> = lines.iter().map(|l| format!("{l},")).collect();
        assert_eq!(notes_before_header("time,gx", &ending), None);
        // What a review found skipped as notes: a header split otherwise than its rows, a
        // header of one field more, a two-column header over a line of words or of `ERR`s,
        // a header over a few rows and the header again (files joined).
        let tabbed: Vec<String> = lines.iter().map(|l| l.replace(',', "\t")).collect();
        assert_eq!(notes_before_header("time gx", &tabbed), None);
        assert_eq!(notes_before_header("time,gx,", &lines), None);
        for second in ["ERR,ERR", "starting logging", ",", "Gyro X,Gyro Y"] {
            let mut l = vec![second.to_string()];
            l.extend(lines.iter().cloned());
            assert_eq!(notes_before_header("gx,gy", &l), None, "{second}");
        }
        let mut joined: Vec<String> = lines[..5].to_vec();
        joined.push("time,gx".into());
        joined.extend(lines.iter().cloned());
        assert_eq!(notes_before_header("time,gx", &joined), None);
    }

    /// A file of only columns that are no channels (a magnetometer's) says which and why, and
    /// speaks of a time column only when there is one.
    #[test]
    fn only_columns_that_are_no_channels_are_said() {
        let err = |text: &str| {
            TextReader::new(text.as_bytes(), Path::new("m.csv"))
                .err()
                .expect("refused")
                .to_string()
        };
        let e = err("mag_x [uT],mag_y [uT]\n1,2\n3,4\n");
        assert!(
            e.contains("no data column: only columns that are no channels: `mag_x [uT]` (a magnetic field)"),
            "{e}"
        );
        let e = err("time,mag_x [uT]\n0.0,2\n0.1,4\n");
        assert!(
            e.contains("no data column: beside the time, only columns that are no channels"),
            "{e}"
        );
    }

    /// Dates as spreadsheets and MATLAB write them: the same instant however written; an order
    /// a row alone cannot tell (`03/12/2026`, `03-12-2026`: day or month first) is read day
    /// first when that is a date; short dates with a two-digit year; a clock at the minute
    /// after a date, not alone.
    #[test]
    fn dates_with_month_names() {
        let iso = date_time("2026-12-03 07:51:28.665").unwrap();
        for t in [
            "2026-12-03T07:51:28.665",
            "03-Dec-2026 07:51:28.665",
            "03-DEC-2026 07:51:28.665",
            "03.12.2026 07:51:28,665",
        ] {
            assert_eq!(date_time(t), Some(iso), "{t}");
        }
        let oct = date_time("2026-10-03 07:51:28").unwrap();
        assert_eq!(date_time("03-OCT-2026 07:51:28"), Some(oct));
        // A clock alone at the minute (`07:51` could be minutes and seconds) is not read.
        for t in [
            "03-Foo-2026 07:51:28",
            "13/13/2026 07:51:28",
            "07:51",
            "12/3/2026 13:51:28 PM",
            "12/3/2026 0:51:28 AM",
            "03/12/126 07:51:28",
        ] {
            assert_eq!(date_time(t), None, "{t}");
        }
        // Short dates with a two-digit year (POSIX's `%y`: 69-99 the 1900s), and a clock at
        // the minute after a date.
        for t in [
            "03/12/26 07:51:28.665",
            "3/12/26 7:51:28.665 AM",
            "03.12.26 07:51:28,665",
            "03-Dec-26 07:51:28.665",
        ] {
            assert_eq!(date_time(t), Some(iso), "{t}");
        }
        assert_eq!(
            date_time("31/12/99 23:59:59"),
            date_time("1999-12-31 23:59:59")
        );
        assert_eq!(
            date_time("32/01/03 10:00:00"),
            date_time("2032-01-03 10:00:00")
        );
        assert_eq!(
            date_time("2026-12-03 07:51"),
            date_time("2026-12-03 07:51:00")
        );
        assert_eq!(
            date_time("03/12/2026 19:51"),
            date_time("2026-12-03 19:51:00")
        );
        assert_eq!(
            date_time("3/12/2026 7:51 PM"),
            date_time("2026-12-03 19:51:00")
        );
        // A row alone reads an open date day first, or month first when only that is a date;
        // a clock of 12 hours.
        let dec3 = date_time("2026-12-03 19:51:28.665").unwrap();
        assert_eq!(date_time("03/12/2026 19:51:28.665"), Some(dec3));
        assert_eq!(date_time("03-12-2026 7:51:28.665 PM"), Some(dec3));
        assert_eq!(
            date_time("12/31/2026 00:00:00"),
            date_time("2026-12-31 00:00:00")
        );
        assert_eq!(
            date_time("12/31/2026 12:00:00 AM"),
            date_time("2026-12-31 00:00:00")
        );
        assert_eq!(
            date_time("12/31/2026 12:00:00 pm"),
            date_time("2026-12-31 12:00:00")
        );
    }

    /// A file's open dates (`03/12/2026`) are read in the order its rows decide: a day above
    /// 12 in either place, or the date moving one day at midnight in one order only. Rows read
    /// day first before a file turns out month first go on without a jump; a date that moves
    /// by a month in either order (no midnight) decides nothing.
    #[test]
    fn open_dates_take_the_order_the_rows_show() {
        let steps = |rows: &[&str]| {
            let text = stamped("time,gx", rows);
            // With the step, a jump of the stamps would be a gap of missing samples.
            let (r, out) = read_at(&text, if rows.len() > 2 { 0.25 } else { 1.0 });
            assert_eq!(out.len(), rows.len(), "{rows:?}");
            let l = &r.layout;
            let stamps: Vec<f64> = rows.iter().map(|x| l.stamp(x).unwrap()).collect();
            (
                stamps.windows(2).map(|w| w[1] - w[0]).collect::<Vec<f64>>(),
                l.dates.get().day_first,
            )
        };
        let us = [
            "12/03/2026 11:59:59.5 PM",
            "12/03/2026 11:59:59.75 PM",
            "12/04/2026 12:00:00 AM",
            "12/04/2026 12:00:00.25 AM",
        ];
        let (d, order) = steps(&us);
        assert_eq!((d, order), (vec![0.25, 0.25, 0.25], Some(false)));
        let eu = [
            "03/12/2026 23:59:59.5",
            "03/12/2026 23:59:59.75",
            "04/12/2026 00:00:00",
        ];
        assert_eq!(steps(&eu), (vec![0.25, 0.25], Some(true)));
        // Short dates across the year's end in all three orders: day first, month first, and
        // year first (decided when only that reads the midnight as one day).
        for rows in [
            [
                "31/12/26 23:59:59.5",
                "31/12/26 23:59:59.75",
                "01/01/27 00:00:00",
            ],
            [
                "12/31/26 23:59:59.5",
                "12/31/26 23:59:59.75",
                "01/01/27 00:00:00",
            ],
            [
                "26/12/31 23:59:59.5",
                "26/12/31 23:59:59.75",
                "27/01/01 00:00:00",
            ],
            [
                "26/12/03 23:59:59.5",
                "26/12/03 23:59:59.75",
                "26/12/04 00:00:00",
            ],
        ] {
            assert_eq!(steps(&rows).0, vec![0.25, 0.25], "{rows:?}");
        }
        let (d, order) = steps(&["12/13/2026 10:00:00", "12/13/2026 10:00:01"]);
        assert_eq!((d, order), (vec![1.0], Some(false)));
        let (d, order) = steps(&["03/12/2026 10:00:00", "03/12/2026 10:00:01"]);
        assert_eq!((d, order), (vec![1.0], None));
        // A checkpoint keeps the order: a run resumed after the US file's midnight reads the
        // next day's date month first too (from its first row alone it could not tell 12/05
        // from 12/03 in either order).
        let text = format!("time,gx\n{},0\n{},1\n{},2\n", us[1], us[2], us[3]);
        let mut r = TextReader::new(text.as_bytes(), Path::new("d.csv")).unwrap();
        let mut out = Vec::new();
        while r.read_rows(&mut out, 64).unwrap() > 0 {}
        let pos = r.position();
        let day = |r: &TextReader<&[u8]>| {
            r.layout.stamp("12/05/2026 12:00:00 AM").unwrap() - r.layout.stamp(us[2]).unwrap()
        };
        assert_eq!(day(&r), 86_400.0);
        let fresh = || TextReader::new(text.as_bytes(), Path::new("d.csv")).unwrap();
        let end = text.len();
        let resumed = fresh().resume(&text.as_bytes()[end..], &pos);
        assert_eq!(day(&resumed), 86_400.0);
        let forgot = TextPosition {
            dates: DateOrder::default(),
            ..pos.clone()
        };
        assert_ne!(
            day(&fresh().resume(&text.as_bytes()[end..], &forgot)),
            86_400.0
        );
    }

    /// A sample whose time cell is empty takes its step: the row after it is one step on, no
    /// gap (a review found one missing sample inserted after it, every later sample a step
    /// late); a row empty in every cell is no sample, and the gap it leaves is one.
    #[test]
    fn a_sample_without_its_stamp_takes_its_step() {
        let (r, out) = read_at("time,gx\n0.00,1\n0.01,2\n,3\n0.03,4\n0.04,5\n", 0.01);
        assert_eq!(out, [1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(r.position().time.unwrap().missing, 0);
        let (r, out) = read_at("time,gx\n0.00,1\n0.01,2\n,\n0.03,4\n", 0.01);
        assert_eq!(out.len(), 4);
        assert!(out[2].is_nan());
        assert_eq!(r.position().time.unwrap().missing, 1);
    }

    /// A time of day alone goes on past midnight (no step back, no gap); a clock set back to
    /// midnight from the afternoon is a restart still.
    #[test]
    fn a_time_of_day_goes_on_past_midnight() {
        let read = |rows: &[&str]| {
            let text = stamped("Time,gx", rows);
            let (r, out) = read_at(&text, 0.25);
            let st = r.position().time.unwrap();
            (out.len(), st.backwards, st.discontinuities)
        };
        let night = ["23:59:59.50", "23:59:59.75", "00:00:00.00", "00:00:00.25"];
        assert_eq!(read(&night), (4, 0, 0));
        // A row late across midnight is a step back of a quarter second, not a day's gap.
        let late = ["23:59:59.50", "00:00:00.00", "23:59:59.75", "00:00:00.25"];
        let (n, _, restarts) = read(&late);
        assert_eq!((n < 8, restarts), (true, 0), "{n}");
        // Across midnight with 45 minutes missing on each side: the next day, a gap.
        let (n, back, restarts) = read(&["23:15:00.00", "23:15:00.25", "00:45:00.00"]);
        // 5399.75 s from the second row to the third: 21598 samples missing.
        assert_eq!((n, back, restarts), (3 + 21_598, 0, 0));
        let reset = ["15:00:00.00", "15:00:00.25", "00:00:00.00", "00:00:00.25"];
        let (n, _, restarts) = read(&reset);
        assert_eq!((n, restarts), (4, 1));
    }

    /// A column that numbers the rows (pandas' unnamed index, a dataset's `id`) is no channel.
    /// Kept: a column named in `--channels`, a file of only that column, phase values (a pulse
    /// counter may count one a row), fewer than `INDEX_ROWS` rows to judge by, a column with a
    /// unit in its name, and one that once stays, falls or skips (an encoder, an index with rows
    /// dropped: a review found such read as a clock with gaps). No index is a clock.
    #[test]
    fn a_column_that_numbers_the_rows_is_an_index() {
        let rows = |n: u64, skip: u64| {
            let mut t = String::from(",time,gx\n");
            for i in (0..n).filter(|&i| i != skip) {
                t += &format!("{i},{:.2},{}\n", i as f64 * 0.01, (i * 7919) % 13);
            }
            t
        };
        let (names, v, _) = read_all(&rows(40, 99));
        assert_eq!((names, v.len()), (vec!["gx".to_string()], 40));
        let (names, _, _) = read_all(&rows(INDEX_ROWS as u64 - 1, 99));
        assert_eq!(names, ["c1", "gx"]);
        // No time column, --tau0 given: left out, and no clock (a row left out is not found).
        let no_time = rows(40, 99).replace(",time,gx", "id,gy,gx");
        let opts = TextOptions {
            tau0_s: Some(0.01),
            ..TextOptions::default()
        };
        let mut r =
            TextReader::with_options(no_time.as_bytes(), Path::new("x.txt"), &opts).unwrap();
        assert_eq!(r.names(), ["gy", "gx"]);
        assert!(r.time_column_name().is_none());
        let mut out = Vec::new();
        while r.read_rows(&mut out, 8).unwrap() > 0 {}
        assert_eq!(out.len(), 2 * 40);
        for opts in [
            TextOptions {
                phase: true,
                ..TextOptions::default()
            },
            TextOptions {
                channels: Some(vec!["c1".into(), "gx".into()]),
                ..TextOptions::default()
            },
        ] {
            let text = rows(40, 99);
            let r = TextReader::with_options(text.as_bytes(), Path::new("x.txt"), &opts).unwrap();
            assert_eq!(r.names(), ["c1", "gx"]);
        }
        let (names, _, _) =
            read_all("n\n1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n11\n12\n13\n14\n15\n16\n17\n");
        assert_eq!(names, ["n"]);
        // Once the same twice, a row left out, a unit in the name: a channel.
        assert_eq!(
            read_all(&rows(40, 99).replace("\n7,", "\n6,")).0,
            ["c1", "gx"]
        );
        assert_eq!(read_all(&rows(40, 5)).0, ["c1", "gx"]);
        assert_eq!(
            read_all(&rows(40, 99).replace(",time,gx", "enc [deg],time,gx")).0,
            ["enc [deg]", "gx"]
        );
    }

    /// A headerless file whose first column steps by tau0 (`t,gx` written without its names)
    /// reads that column as its clock: a row left out is a missing sample, found, and the
    /// values are the other column's. In milliseconds and with stamps jittered by 4% too. Kept a
    /// channel: a step that is not tau0 (the log says so), `--phase`, `--time-column none`, a
    /// column `--channels` names, fewer than `INDEX_ROWS` rows, one step backwards, a file of
    /// that column alone, and a header (names are read by their words, not their values).
    #[test]
    fn a_headerless_column_stepping_by_tau0_is_the_clock() {
        let rows = |n: usize, skip: usize, scale: f64, jitter: f64| {
            let mut t = String::new();
            for i in (0..n).filter(|&i| i != skip) {
                let wobble = if i % 2 == 0 { jitter } else { -jitter };
                let stamp = (i as f64 + wobble) * 0.01 * scale;
                t += &format!("{stamp:.6},{}\n", 0.25 * ((i * 7919) % 13) as f64);
            }
            t
        };
        let opts = |f: fn(&mut TextOptions)| {
            let mut o = TextOptions {
                tau0_s: Some(0.01),
                ..TextOptions::default()
            };
            f(&mut o);
            o
        };
        let read = |text: &str, o: &TextOptions| {
            let mut r = TextReader::with_options(text.as_bytes(), Path::new("t.csv"), o).unwrap();
            let mut out = Vec::new();
            while r.read_rows(&mut out, 8).unwrap() > 0 {}
            let missing = r.position().time.map(|t| t.missing);
            (r.names().to_vec(), out, missing)
        };
        let plain = opts(|_| {});
        for (scale, jitter) in [(1.0, 0.0), (1e3, 0.0), (1.0, 0.04)] {
            let (names, v, missing) = read(&rows(40, 17, scale, jitter), &plain);
            assert_eq!(names, ["c2"], "scale {scale} jitter {jitter}");
            assert_eq!(missing, Some(1), "scale {scale} jitter {jitter}");
            // 39 rows and the missing sample between rows 16 and 18 as a gap.
            assert_eq!(v.len(), 40);
            assert_eq!(
                (v[3], v[16], v[18]),
                (
                    0.25 * ((3 * 7919) % 13) as f64,
                    0.25 * ((16 * 7919) % 13) as f64,
                    0.25 * ((18 * 7919) % 13) as f64
                )
            );
            assert!(v[17].is_nan());
        }
        let two = vec!["c1".to_string(), "c2".to_string()];
        let at_002 = TextOptions {
            tau0_s: Some(0.02),
            ..TextOptions::default()
        };
        assert_eq!(read(&rows(40, 99, 1.0, 0.0), &at_002).0, two);
        assert_eq!(
            read(&rows(40, 99, 1.0, 0.0), &opts(|o| o.phase = true)).0,
            two
        );
        let none = opts(|o| o.time_column = Some(NO_TIME_COLUMN.into()));
        assert_eq!(read(&rows(40, 99, 1.0, 0.0), &none).0, two);
        let named = opts(|o| o.channels = Some(vec!["c1".into(), "c2".into()]));
        assert_eq!(read(&rows(40, 99, 1.0, 0.0), &named).0, two);
        assert_eq!(read(&rows(INDEX_ROWS - 1, 99, 1.0, 0.0), &plain).0, two);
        let back = rows(40, 99, 1.0, 0.0).replacen("0.070000", "0.050000", 1);
        assert_eq!(read(&back, &plain).0, two);
        let alone: String = (0..40)
            .map(|i| format!("{:.2}\n", i as f64 * 0.01))
            .collect();
        assert_eq!(read(&alone, &plain).0, ["c1"]);
        let headed = format!("a,b\n{}", rows(40, 99, 1.0, 0.0));
        assert_eq!(read(&headed, &plain).0, ["a", "b"]);
    }

    /// What a review of the first version found, each a file that read wrongly or crashed:
    /// units in mixed case, non-ASCII headers, unit words inside channel names, counts as a
    /// unit, a label that is a time word in a headerless file, `--channels` with a units row, a
    /// `-` in a units row, an empty line after every row, a row of words.
    #[test]
    fn names_and_rows_a_review_found() {
        assert_eq!(time_column_unit("time_mS"), Some(Some(1e-3)));
        assert_eq!(time_column_unit("Time (mS)"), Some(Some(1e-3)));
        assert_eq!(time_column_unit("timestamp_uS"), Some(Some(1e-6)));
        let (names, v, _) = read_all("time,acc_x_\u{b5}g,a-1\u{b0}C\n0.00,1,2\n0.01,3,4\n");
        assert_eq!((names.len(), v.len()), (2, 4));
        assert!(!counter_column("gx (count)") && !counter_column("gx [cnt]"));
        for name in ["gyro_deg_sec_x", "gyro_time_x", "acc_z"] {
            assert_eq!(time_column_unit(name), None, "{name}");
        }
        assert_eq!(time_column_unit("Seconds"), Some(None));
        let (names, v, _) =
            read_all("1700000000.00,UTC,-1.1788,-1.1482\n1700000000.01,UTC,-1.2,-1.1\n");
        assert_eq!(names, ["c1", "c3", "c4"]);
        assert_eq!(v.len(), 6);
        let opts = TextOptions {
            channels: Some(vec!["seq".into(), "gx".into()]),
            ..TextOptions::default()
        };
        let r = TextReader::with_options(
            "time,seq,gx\ns,#,deg/s\n0,1,0.5\n".as_bytes(),
            Path::new("s.csv"),
            &opts,
        )
        .unwrap();
        assert_eq!(r.names(), ["seq", "gx"]);
        let r = TextReader::new(
            "time;gx;ax;n\ns;deg/s;g;-\n0;1;2;3\n".as_bytes(),
            Path::new("d.csv"),
        )
        .unwrap();
        assert_eq!(r.time_column_name(), Some("time [s]"));
        assert_eq!(r.channel_columns()[2], (4, "n"));
        // An empty line after every row, with a time column in use: no gaps, no extra samples.
        let mut text = String::from("time,gx\n");
        for k in 0..50 {
            text.push_str(&format!("{:.2},{k}\n\n", k as f64 * 0.01));
        }
        let (_, out) = read_stepped(&text);
        assert_eq!(out.len(), 50);
        assert!(out.iter().all(|x| !x.is_nan()));
        // A row of words where numbers belong: a bad row, not gaps.
        let (_, v, bad) = read_all("gx,gy\n1,2\nERR,OVF\n3,4\n");
        assert_eq!((v.len(), bad), (6, 1));
    }

    /// Excel's `sep=;` before the header, and a title line before it: skipped; a one-column
    /// file keeps its header, also when its numbers have a decimal comma.
    #[test]
    fn a_separator_note_and_a_title_before_the_header() {
        let (names, v, bad) = read_all("sep=;\ngx;gy\n0,5;1,5\n2;3\n");
        assert_eq!(
            (names, v, bad),
            (vec!["gx".into(), "gy".into()], vec![0.5, 1.5, 2.0, 3.0], 0)
        );
        let (names, v, _) =
            read_all("IMU log 2026-12-03 S/N 1234\ntime,gx,gy\n0.0,1,2\n0.01,3,4\n");
        assert_eq!(
            (names, v),
            (vec!["gx".into(), "gy".into()], vec![1.0, 2.0, 3.0, 4.0])
        );
        let (names, v, _) = read_all("gx\n0,5\n1,5\n");
        assert_eq!((names, v), (vec!["gx".to_string()], vec![0.5, 1.5]));
    }

    /// CSV's quoting: a separator inside double quotes is the field's, the quotes are dropped,
    /// a `""` inside stays in the (text) field and is one `"` in a header name; a `"` that
    /// does not open a field is a character of it; quotes that do not close leave the line
    /// split as if it had none. Quoted numbers read with a decimal comma or thousands; an
    /// unquoted `2,001` in a `;` file stays a decimal comma. Before (session 42), each of
    /// these rows was a bad row of too many fields.
    #[test]
    fn quoted_fields_keep_their_separators() {
        assert_eq!(
            Sep::Comma.split(r#"0.00,"ok, nominal",1.72"#),
            ["0.00", "ok, nominal", "1.72"]
        );
        assert_eq!(
            Sep::Comma.split(r#" "a ""b"", c" ,12",3"#),
            [r#"a ""b"", c"#, "12\"", "3"]
        );
        assert_eq!(Sep::Comma.split(r#""a,b,c"#), [r#""a"#, "b", "c"]);
        assert_eq!(Sep::Spaces.split(r#"  1 "a b"   2 "#), ["1", "a b", "2"]);
        assert_eq!(Sep::of(r#""0,5";"1,5""#), Sep::Semicolon);
        assert_eq!(Sep::of(r#"1,"a;b",2"#), Sep::Comma);
        assert_eq!(split(r#""0,00","1,727921""#), ["0,00", "1,727921"]);
        assert_eq!(header_name(r#"gx ""raw"""#), r#"gx "raw""#);
        let (names, v, bad) =
            read_all("time,status,gx\n0.00,\"ok, nominal\",1.72\n0.01,\"ok, nominal\",-0.5\n");
        assert_eq!(
            (names, v, bad),
            (vec!["gx".to_string()], vec![1.72, -0.5], 0)
        );
        let (names, v, bad) =
            read_all("gx,gy\n\"0,25\",\"2,001.52\"\n\"-1,5e-3\",\"1,234,567.5\"\n");
        assert_eq!(
            (names, v, bad),
            (
                vec!["gx".to_string(), "gy".to_string()],
                vec![0.25, 2001.52, -1.5e-3, 1234567.5],
                0
            )
        );
        assert_eq!(
            ["2.001,52", "-1.234.567,5", "2,001", "+2,001.5"].map(|t| parse_field(t).ok()),
            [Some(2001.52), Some(-1234567.5), Some(2.001), Some(2001.5)]
        );
        // No grouping in threes, or two decimal marks: no number.
        for t in [
            "2,00.5",
            "20,01.5",
            "1234,567.5",
            "2,001.5.2",
            "2,001.",
            ",001.5",
        ] {
            assert!(parse_field(t).is_err(), "{t}");
        }
    }

    /// Columns after the header's last name with no values are no channels (any number of
    /// them, the rows ending in fewer separators too); one holding numbers is a channel named
    /// by its number. Before (session 42), `gx;gy;;;` gave `c3` and `c4`.
    #[test]
    fn trailing_empty_columns_are_no_channels() {
        let (names, v, bad) = read_all("gx;gy;;;\r\n0,5;1,5;;;\r\n2;3;;\r\n4;5\r\n");
        assert_eq!(
            (names, v, bad),
            (
                vec!["gx".to_string(), "gy".into()],
                vec![0.5, 1.5, 2.0, 3.0, 4.0, 5.0],
                0
            )
        );
        let (names, v, bad) = read_all("gx,gy,,\n1,2,,7\n3,4,,\n");
        assert_eq!(
            (names, &v[..5], bad),
            (
                vec!["gx".to_string(), "gy".into(), "c4".into()],
                &[1.0, 2.0, 7.0, 3.0, 4.0][..],
                0
            )
        );
        assert!(v[5].is_nan());
    }
}
