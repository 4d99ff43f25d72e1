//! Text columns: one row per sample, columns separated by commas, semicolons, tabs or spaces,
//! an optional first row of channel names (otherwise `c1`, `c2`, ...; a UTF-8 byte-order mark
//! before it is dropped, duplicate names are refused), `#` lines skipped (docs/records.md). A `#`
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

use std::io::BufRead;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::error::UsageError;
use crate::input::time_column::{TimeColumn, TimeState};

/// Rows per batch handed to the analysis.
pub const BATCH_ROWS: usize = 8192;

/// The longest line read, in bytes: a row of 256 channels takes a few kB. A longer line (a
/// file with no line ends) is skipped as it streams by, never held whole in memory.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Reads one line, through its `\n`, into `buf` (emptied first), keeping at most `max` bytes
/// of it; returns the bytes consumed (0 at the end of the input) and whether the line was
/// longer than `max`.
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
        if done {
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

/// Header names taken as a time column when no `--time-column` is given (case-insensitive).
pub const TIME_COLUMN_NAMES: [&str; 4] = ["time", "t", "timestamp", "time_s"];

/// Seconds per unit of the time units a column name may carry.
const TIME_UNITS: [(&str, f64); 6] = [
    ("s", 1.0),
    ("sec", 1.0),
    ("ms", 1e-3),
    ("us", 1e-6),
    ("\u{b5}s", 1e-6),
    ("ns", 1e-9),
];

/// Whether `name` names a time column by itself ([`TIME_COLUMN_NAMES`], any case, with or
/// without a unit: `timestamp [ns]`, `time (s)`, `t_ns`), and the unit's seconds when it gives
/// one (`Some(None)`: a time column without a unit; `None`: not a time column's name).
pub fn time_column_unit(name: &str) -> Option<Option<f64>> {
    let n = name
        .trim()
        .trim_start_matches(['#', '%'])
        .trim()
        .to_ascii_lowercase();
    let unit_of = |u: &str| {
        let u = u.trim();
        TIME_UNITS.iter().find(|(x, _)| *x == u).map(|(_, s)| *s)
    };
    // `timestamp [ns]`, `time (s)`: the unit in brackets.
    if let Some(open) = n.find(['[', '(']) {
        let (base, rest) = n.split_at(open);
        let close = if rest.starts_with('[') { ']' } else { ')' };
        let inner = rest[1..].strip_suffix(close)?;
        let base = base.trim();
        return (TIME_COLUMN_NAMES.contains(&base) && base != "time_s")
            .then(|| unit_of(inner))
            .flatten()
            .map(Some);
    }
    if TIME_COLUMN_NAMES.contains(&n.as_str()) {
        return Some((n == "time_s").then_some(1.0));
    }
    // `t_ns`, `time_ms`, `timestamp_us`.
    let (base, unit) = n.rsplit_once('_')?;
    (["t", "time", "timestamp"].contains(&base))
        .then(|| unit_of(unit))
        .flatten()
        .map(Some)
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

/// How the columns of a text input become channels.
#[derive(Debug, Clone, Default)]
pub struct TextOptions {
    /// The header name of the time column (skipped); `None` looks for [`TIME_COLUMN_NAMES`].
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
        // A header field left empty: the last one is a trailing separator (`g1,g2,`), its
        // column no channel; another is named by its column number, as without a header.
        let trailing_empty =
            header && source_names.len() > 1 && source_names.last().is_some_and(String::is_empty);
        let last = source_names.len() - 1;
        for (j, n) in source_names.iter_mut().enumerate() {
            if n.is_empty() && !(trailing_empty && j == last) {
                *n = format!("c{}", j + 1);
                tracing::warn!(
                    "{}: line {line}: column {} has no name in the header; called `{n}`",
                    path.display(),
                    j + 1
                );
            }
        }
        for (j, n) in source_names.iter().enumerate() {
            if let Some(i) = source_names[..j].iter().position(|m| m == n) {
                return Err(err(format!(
                    "duplicate column name `{n}`: columns {} and {}",
                    i + 1,
                    j + 1
                )));
            }
        }
        let find = |n: &str| source_names.iter().position(|m| m == n);
        let time = match &opts.time_column {
            Some(t) if !header => {
                return Err(err(format!(
                    "--time-column `{t}`: the input has no header row"
                )))
            }
            Some(t) => Some(find(t).ok_or_else(|| {
                err(format!(
                    "--time-column `{t}`: no such column (the header has {})",
                    source_names.join(", ")
                ))
            })?),
            None if header => source_names
                .iter()
                .position(|n| time_column_unit(n).is_some()),
            None => None,
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
                (keep, names)
            }
            None => (0..source_names.len())
                .filter(|&i| Some(i) != time && !(trailing_empty && i == last))
                .map(|i| (i, source_names[i].clone()))
                .unzip(),
        };
        if keep.is_empty() {
            return Err(err("no data column (only a time column)".into()));
        }
        let strict = names
            .iter()
            .map(|n| opts.channels.as_ref().is_none_or(|c| c.contains(n)))
            .collect();
        Ok(Layout {
            width_in: source_names.len(),
            sep,
            keep,
            strict,
            source_names,
            names,
            time,
        })
    }

    /// The layout without the columns whose cell in the first data row `t` is text, not a
    /// number: a ROS `rostopic echo -p` export's `field.header.frame_id` (`imu_link`), a
    /// logger's status word. Such a column holds labels, not samples; it is left out, said in
    /// the log, unless the run named it (`--columns`, or `--channels`), which is an error as
    /// before. Columns `--channels` leaves out are kept: their cells are never needed.
    fn without_label_columns(
        mut self,
        t: &str,
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

    /// The channel values of a row and its time stamp (NaN without a time column or where the
    /// stamp is not a number), or what is wrong with the row.
    fn parse(&self, t: &str) -> Result<(Vec<f64>, f64), String> {
        let fields = self.split(t);
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
                v.map_err(|()| {
                    format!(
                        "column {} `{}`: `{}` is not a number",
                        i + 1,
                        self.source_names[i],
                        fields[i].trim()
                    )
                })
            })
            .collect::<Result<Vec<f64>, String>>()?;
        let time = self
            .time
            .and_then(|i| parse_field(fields[i]).ok())
            .unwrap_or(f64::NAN);
        Ok((values, time))
    }
}

impl Layout {
    /// The fields of a row: split at the header's separator, or, when that does not give the
    /// header's width, as the row itself suggests (a row written with spaces in a comma file).
    fn split<'a>(&self, t: &'a str) -> Vec<&'a str> {
        let fields = self.sep.split(t);
        if fields.len() == self.width_in {
            fields
        } else {
            split(t)
        }
    }
}

/// A row as read: its values or what is wrong with it, and its time stamp (NaN if none).
type Row = (Result<Vec<f64>, String>, f64);

pub struct TextReader<R> {
    src: R,
    path: PathBuf,
    line_no: u64,
    layout: Layout,
    names: Vec<String>,
    /// The next row to hand out: the first data row, read while looking for a header, or the
    /// row after a jump of the time column, held while the gap steps before it go out.
    pending: Option<Row>,
    /// The time column used to find gaps, and the gap steps still to hand out.
    time: Option<TimeColumn>,
    gap_left: u64,
    /// The time column's account was logged (at the end of the input).
    time_reported: bool,
    /// The values and stamp of the last row handed out, to tell a row written twice.
    last_row: Option<(Vec<f64>, f64)>,
    line: Vec<u8>,
    bad_rows: u64,
    /// Values infinite or beyond `MAX_ABS_VALUE`, read as gaps.
    invalid_values: u64,
    rows: u64,
    /// Values that are numbers (not gaps) read so far.
    samples: u64,
    /// Bytes of the input consumed so far (header and comment lines included).
    offset: u64,
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
    /// The time column's clock, when it is used to find gaps.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time: Option<TimeState>,
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
        .map_err(|_| ())
}

/// `0,25` or `-1,5e-3` read as `0.25`, `-1.5e-3`: a decimal comma, as spreadsheets in many
/// languages write it. Only a comma between two digits, with no point in the field, is taken;
/// such a field can only arise where the columns are separated by semicolons or tabs.
fn decimal_comma(t: &str) -> Option<f64> {
    let (int, frac) = t.split_once(',')?;
    let digit_before = int.bytes().last().is_some_and(|b| b.is_ascii_digit());
    let digit_after = frac.bytes().next().is_some_and(|b| b.is_ascii_digit());
    if !digit_before || !digit_after || t.contains('.') || frac.contains(',') {
        return None;
    }
    format!("{int}.{frac}").parse().ok()
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
}

impl Sep {
    fn of(line: &str) -> Sep {
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

    fn split(self, line: &str) -> Vec<&str> {
        match self {
            Sep::Semicolon => line.split(';').collect(),
            Sep::Tab => line.split('\t').collect(),
            Sep::Comma => line.split(',').collect(),
            Sep::Spaces => line.split_whitespace().collect(),
        }
    }
}

/// A row's fields by the row alone: commas, else semicolons, else spaces and tabs.
fn split(line: &str) -> Vec<&str> {
    if line.contains(',') {
        line.split(',').collect()
    } else if line.contains(';') {
        line.split(';').collect()
    } else {
        line.split_whitespace().collect()
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
        loop {
            let (n, long) = read_line_bounded(&mut src, &mut raw, MAX_LINE_BYTES)
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
            // A byte-order mark (spreadsheets write one) is not part of the first name.
            let t = if line_no == 1 {
                line.trim_start_matches('\u{feff}').trim()
            } else {
                line.trim()
            };
            if t.is_empty() {
                continue;
            }
            if let Some(c) = t.strip_prefix('#') {
                if layout.is_none() {
                    hash_line = Some(c.trim().to_string());
                }
                continue;
            }
            let (values, layout) = match layout.take() {
                Some(l) => match l.parse(t) {
                    Ok((v, time)) => ((Ok(v), time), l),
                    // A row of the wrong width is a bad row, as later ones are.
                    Err(problem) if l.split(t).len() != l.width_in => ((Err(problem), f64::NAN), l),
                    Err(_) => {
                        let l = l.without_label_columns(t, opts, path, line_no)?;
                        let (v, time) = l.parse(t).map_err(|p| {
                            input_error(path, line_no, format!("the first data row: {p}"))
                        })?;
                        ((Ok(v), time), l)
                    }
                },
                None => {
                    let sep = Sep::of(t);
                    let fields = sep.split(t);
                    // A row most of whose fields are numbers is data, not names: ROS 2's
                    // `ros2 topic echo --csv` writes no header, and a `frame_id` among numbers.
                    let numbers = fields
                        .iter()
                        .filter(|f| !f.trim().is_empty() && parse_field(f).is_ok())
                        .count();
                    // (Unless a text cell names a time column: `time,0,1,2` is pandas' header
                    // of integer-labelled columns.)
                    let names_time = fields.iter().any(|f| {
                        parse_field(f).is_err()
                            && time_column_unit(f.trim().trim_matches('"')).is_some()
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
                        let mut l = Layout::new(names, header, sep, opts, path, line_no)?;
                        if l.parse(t).is_err() {
                            l = l.without_label_columns(t, opts, path, line_no)?;
                        }
                        let (v, time) = l.parse(t).map_err(|p| input_error(path, line_no, p))?;
                        ((Ok(v), time), l)
                    } else {
                        let names = fields
                            .iter()
                            .map(|f| f.trim().trim_matches('"').trim().to_string())
                            .collect();
                        layout = Some(Layout::new(names, true, sep, opts, path, line_no)?);
                        continue;
                    }
                }
            };
            let mut time = match (layout.time, opts.tau0_s) {
                (Some(i), Some(tau0)) => Some(TimeColumn::new(&layout.source_names[i], tau0)),
                _ => None,
            };
            if let Some(c) = &mut time {
                // The first stamp starts the clock.
                c.missing_before(values.1, path, line_no);
            }
            return Ok(TextReader {
                src,
                path: path.into(),
                line_no,
                names: layout.names.clone(),
                layout,
                pending: Some(values),
                time,
                gap_left: 0,
                time_reported: false,
                last_row: None,
                line: raw,
                bad_rows: 0,
                invalid_values: 0,
                rows: 0,
                samples: 0,
                offset,
            });
        }
    }

    /// Continues reading `src`, positioned at `pos.offset` of the same input, with this
    /// reader's columns, as a reader that had stopped at `pos` (no header is looked for).
    pub fn resume<S: BufRead>(self, src: S, pos: &TextPosition) -> TextReader<S> {
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
            time,
            gap_left: 0,
            time_reported: false,
            last_row: None,
            line: Vec::new(),
            bad_rows: pos.bad_rows,
            invalid_values: pos.invalid_values,
            rows: pos.rows,
            samples: pos.samples,
            offset: pos.offset,
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
            time: self.time.as_ref().map(TimeColumn::state),
        }
    }

    /// Values read so far that were numbers (gaps and bad rows left out).
    pub fn samples(&self) -> u64 {
        self.samples
    }

    /// The header name of the time column, if the input has one.
    pub fn time_column_name(&self) -> Option<&str> {
        self.layout
            .time
            .map(|i| self.layout.source_names[i].as_str())
    }

    /// The time stamps of the next `max_rows` rows (NaN where a row has none), consuming them:
    /// for a look at the start of an input (`super::sampling_step`), not for a run.
    pub fn take_stamps(&mut self, max_rows: usize) -> std::io::Result<Vec<f64>> {
        let mut stamps = Vec::new();
        if let Some((_, t)) = self.pending.take() {
            stamps.push(t);
        }
        while stamps.len() < max_rows {
            match self.next_row()? {
                Some((_, t)) => stamps.push(t),
                None => break,
            }
        }
        Ok(stamps)
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
                    if self.is_repeat(&p) {
                        // The same stamp and values as the row before: a record written twice
                        // (a logger or a driver's repeat), not a sample. Taken as one, it
                        // would put the clock a step ahead of every stamp after it.
                        if let Some(c) = &mut self.time {
                            c.duplicate(&self.path, self.line_no);
                        }
                        continue;
                    }
                    let gap = match &mut self.time {
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
            if let Some(c) = &self.time {
                c.report(&self.path);
            }
        }
        Ok(n)
    }

    /// Whether `p` repeats the last row handed out, stamp and values (NaN equal to NaN), where
    /// a time column is in use (without one a repeated row cannot be told from a channel whose
    /// value stood still).
    fn is_repeat(&self, p: &Row) -> bool {
        let (Some(c), Some((lv, lt)), Ok(v)) = (&self.time, &self.last_row, &p.0) else {
            return false;
        };
        let same = |a: f64, b: f64| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan());
        c.in_use()
            && p.1.is_finite()
            && p.1 == *lt
            && v.len() == lv.len()
            && v.iter().zip(lv).all(|(a, b)| same(*a, *b))
    }

    /// The next row of the input, `None` at its end (comment lines skipped).
    fn next_row(&mut self) -> std::io::Result<Option<Row>> {
        let width = self.names.len();
        loop {
            let (got, long) = read_line_bounded(&mut self.src, &mut self.line, MAX_LINE_BYTES)?;
            if got == 0 {
                return Ok(None);
            }
            self.offset += got as u64;
            self.line_no += 1;
            if long {
                let problem = format!("a line of {got} bytes, longer than any row of text columns");
                return Ok(Some((Err(problem), f64::NAN)));
            }
            // A line that is not UTF-8 (a damaged stretch of the file) is a bad row, not the
            // end of the run.
            let Ok(text) = std::str::from_utf8(&self.line) else {
                return Ok(Some((Err("not UTF-8 text".to_string()), f64::NAN)));
            };
            let t = text.trim();
            if t.starts_with('#') {
                continue;
            }
            return Ok(Some(if t.is_empty() {
                (Ok(vec![f64::NAN; width]), f64::NAN)
            } else {
                match self.layout.parse(t) {
                    Ok((v, time)) => (Ok(v), time),
                    Err(e) => (Err(e), f64::NAN),
                }
            }));
        }
    }

    fn push_row(&mut self, out: &mut Vec<f64>, row: Result<Vec<f64>, String>) {
        self.rows += 1;
        match row {
            Ok(v) => {
                // `inf`, `1e308`, `1e-300`: counted, and a gap like `nan`.
                let start = out.len();
                out.extend_from_slice(&v);
                // Only the columns the run analyses are counted (`--channels`).
                for (x, &counted) in out[start..].iter_mut().zip(&self.layout.strict) {
                    if super::plausible(*x).is_none() {
                        *x = f64::NAN;
                        self.invalid_values += u64::from(counted);
                    } else if !x.is_nan() {
                        self.samples += u64::from(counted);
                    }
                }
            }
            Err(problem) => {
                self.bad_rows += 1;
                if self.bad_rows <= BAD_ROWS_LOGGED {
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

    fn read_all(text: &str) -> (Vec<String>, Vec<f64>, u64) {
        let mut r = TextReader::new(text.as_bytes(), Path::new("t.csv")).unwrap();
        let mut out = Vec::new();
        while r.read_rows(&mut out, 2).unwrap() > 0 {}
        (r.names().to_vec(), out, r.bad_rows())
    }

    #[test]
    fn header_separators_gaps_and_bad_rows() {
        let (names, v, bad) = read_all("# c\ngx, gy\n1,2\n\n3,nan\n4 5\nx,6\n7,\n");
        assert_eq!(names, ["gx", "gy"]);
        // rows: (1,2) (gap) (3,-) (4,5: spaces also separate) (bad: x) (7,-)
        let nan = f64::NAN;
        let expected = [1.0, 2.0, nan, nan, 3.0, nan, 4.0, 5.0, nan, nan, 7.0, nan];
        assert_eq!(v.len(), expected.len());
        for (a, b) in v.iter().zip(expected) {
            assert!(a == &b || (a.is_nan() && b.is_nan()), "{v:?}");
        }
        assert_eq!(bad, 1);
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
        // Every column: the label column is no channel, the `ERR` row is a bad row (a gap of
        // every channel), the stamps beyond 1e15 are counted invalid; `%time` is the time.
        let (names, v, bad, invalid) = read(&TextOptions::default()).unwrap();
        assert_eq!(names, ["field.header.stamp", "field.w.x", "field.w.y"]);
        assert_eq!((v.len(), bad, invalid), (9, 1, 2));
        assert_eq!((v[1], v[2], v[7], v[8]), (0.5, 1.5, 0.25, 3.5));
        assert!(v[3..6].iter().all(|x| x.is_nan()));
        // `--channels field.w.y`: the row with `ERR` in field.w.x is read, nothing counted.
        let opts = TextOptions {
            channels: Some(vec!["field.w.y".into()]),
            ..TextOptions::default()
        };
        let (_, v, bad, invalid) = read(&opts).unwrap();
        assert_eq!((bad, invalid), (0, 0));
        // The columns the run leaves out stay in the rows (read as gaps where not numbers).
        let y: Vec<f64> = v.chunks(4).map(|r| r[3]).collect();
        assert_eq!(y, [1.5, 2.5, 3.5]);
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
}
