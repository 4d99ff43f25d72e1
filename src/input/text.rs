//! Text columns: one row per sample, columns separated by commas, tabs or spaces, an optional
//! first row of channel names (otherwise `c1`, `c2`, ...), `#` lines skipped (docs/records.md).
//!
//! Streams: rows are read line by line and handed on in batches; the file is never held in
//! memory. An empty row, or a row whose every field is empty or `nan`, is a gap for every
//! channel; an empty or `nan` field is a gap for its channel. A row that cannot be read (a
//! token that is not a number, or the wrong number of fields) is counted in `bad_rows`, logged
//! with its line number, and treated as a gap, so nothing already measured is lost.

use std::io::BufRead;
use std::path::{Path, PathBuf};

use crate::error::UsageError;

/// Rows per batch handed to the analysis.
pub const BATCH_ROWS: usize = 8192;

/// How many bad rows are logged one by one before the rest are only counted.
const BAD_ROWS_LOGGED: u64 = 10;

pub struct TextReader<R> {
    src: R,
    path: PathBuf,
    line_no: u64,
    names: Vec<String>,
    /// The first data row, read while looking for a header.
    pending: Option<Vec<f64>>,
    line: Vec<u8>,
    bad_rows: u64,
    /// Values infinite or beyond `MAX_ABS_VALUE`, read as gaps.
    invalid_values: u64,
    rows: u64,
    /// Bytes of the input consumed so far (header and comment lines included).
    offset: u64,
}

/// Where a [`TextReader`] stands, for a checkpoint: continuing from `offset` with these counts
/// reads the rest of the input as the reader would have.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct TextPosition {
    /// Bytes consumed (the next row starts here).
    pub offset: u64,
    pub line_no: u64,
    pub rows: u64,
    pub bad_rows: u64,
    /// Values infinite or beyond [`super::MAX_ABS_VALUE`], read as gaps.
    #[serde(default)]
    pub invalid_values: u64,
}

fn parse_field(t: &str) -> Result<f64, ()> {
    let t = t.trim();
    if t.is_empty() || t.eq_ignore_ascii_case("nan") {
        return Ok(f64::NAN);
    }
    t.parse::<f64>().map_err(|_| ())
}

fn split(line: &str) -> Vec<&str> {
    if line.contains(',') {
        line.split(',').collect()
    } else {
        line.split_whitespace().collect()
    }
}

impl<R: BufRead> TextReader<R> {
    /// Opens the stream and reads up to the first data row (taking a header row if present).
    /// Fails with a usage error (exit status 2) when there is no data row at all.
    pub fn new(mut src: R, path: &Path) -> Result<Self, UsageError> {
        let mut line = String::new();
        let mut line_no = 0u64;
        let mut offset = 0u64;
        loop {
            line.clear();
            let n = src.read_line(&mut line).map_err(|e| UsageError::Input {
                file: path.into(),
                line: line_no + 1,
                problem: e.to_string(),
            })?;
            if n == 0 {
                return Err(UsageError::Input {
                    file: path.into(),
                    line: line_no,
                    problem: "no data rows".into(),
                });
            }
            line_no += 1;
            offset += n as u64;
            let t = line.trim();
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            let fields = split(t);
            let parsed: Result<Vec<f64>, ()> = fields.iter().map(|f| parse_field(f)).collect();
            let (names, pending) = match parsed {
                Ok(v) => ((1..=v.len()).map(|i| format!("c{i}")).collect(), Some(v)),
                Err(()) => (fields.iter().map(|f| f.trim().to_string()).collect(), None),
            };
            return Ok(TextReader {
                src,
                path: path.into(),
                line_no,
                names,
                pending,
                line: line.into_bytes(),
                bad_rows: 0,
                invalid_values: 0,
                rows: 0,
                offset,
            });
        }
    }

    /// Continues reading `src`, positioned at `pos.offset` of the input whose channels are
    /// `names`, as a reader that had stopped at `pos` (no header is looked for).
    pub fn resume(src: R, path: &Path, names: Vec<String>, pos: &TextPosition) -> Self {
        TextReader {
            src,
            path: path.into(),
            line_no: pos.line_no,
            names,
            pending: None,
            line: Vec::new(),
            bad_rows: pos.bad_rows,
            invalid_values: pos.invalid_values,
            rows: pos.rows,
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
            invalid_values: self.invalid_values,
        }
    }

    /// Channel names, from the header row or `c1..cn`.
    pub fn names(&self) -> &[String] {
        &self.names
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
        if let Some(first) = self.pending.take() {
            self.push_row(out, Ok(first));
            n += 1;
        }
        while n < max_rows {
            self.line.clear();
            let got = self.src.read_until(b'\n', &mut self.line)?;
            if got == 0 {
                break;
            }
            self.offset += got as u64;
            self.line_no += 1;
            // A line that is not UTF-8 (a damaged stretch of the file) is a bad row, not the
            // end of the run.
            let Ok(text) = std::str::from_utf8(&self.line) else {
                let row = Err("not UTF-8 text".to_string());
                self.push_row(out, row);
                n += 1;
                continue;
            };
            let t = text.trim();
            if t.starts_with('#') {
                continue;
            }
            let row = if t.is_empty() {
                Ok(vec![f64::NAN; width])
            } else {
                let fields = split(t);
                if fields.len() != width {
                    Err(format!("{} fields, expected {width}", fields.len()))
                } else {
                    fields
                        .iter()
                        .map(|f| parse_field(f))
                        .collect::<Result<Vec<f64>, ()>>()
                        .map_err(|()| "a field is not a number".to_string())
                }
            };
            self.push_row(out, row);
            n += 1;
        }
        Ok(n)
    }

    fn push_row(&mut self, out: &mut Vec<f64>, row: Result<Vec<f64>, String>) {
        self.rows += 1;
        match row {
            Ok(v) => {
                // `inf`, `1e308`: counted, and a gap like `nan`.
                let start = out.len();
                out.extend_from_slice(&v);
                for x in &mut out[start..] {
                    if super::plausible(*x).is_none() {
                        *x = f64::NAN;
                        self.invalid_values += 1;
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
