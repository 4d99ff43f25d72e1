//! The terminal table's look: its style (colours on a terminal), numbers to three significant
//! digits, durations and taus in words, intervals, and columns padded to their widest cell.

/// How the text is dressed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TableStyle {
    /// ANSI colours for PASS/FAIL and warnings (a terminal that has not asked for `NO_COLOR`).
    pub color: bool,
}

impl TableStyle {
    pub(super) fn paint(&self, code: &str, text: &str) -> String {
        if self.color {
            format!("\x1b[{code}m{text}\x1b[0m")
        } else {
            text.to_string()
        }
    }
    pub(super) fn red(&self, t: &str) -> String {
        self.paint("1;31", t)
    }
    pub(super) fn green(&self, t: &str) -> String {
        self.paint("1;32", t)
    }
    pub(super) fn yellow(&self, t: &str) -> String {
        self.paint("1;33", t)
    }
    pub(super) fn bold(&self, t: &str) -> String {
        self.paint("1", t)
    }
    pub(super) fn dim(&self, t: &str) -> String {
        self.paint("2", t)
    }
}

/// A number with three significant digits: plain between 1e-3 and 1e5, else in e-notation.
pub fn sig3(x: f64) -> String {
    if !x.is_finite() {
        return "-".into();
    }
    if x == 0.0 {
        return "0".into();
    }
    let a = x.abs();
    if (1e-3..1e5).contains(&a) {
        // Trailing zeros are kept, so a column of one coefficient reads evenly.
        let decimals = (2 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.2e}")
    }
}

/// A duration in s for the headings: `300 s`, `2.5 min`, `3.0 h`.
pub(super) fn duration_text(s: f64) -> String {
    if s >= 2.0 * 3600.0 {
        format!("{:.1} h", s / 3600.0)
    } else if s >= 120.0 {
        format!("{:.1} min", s / 60.0)
    } else {
        format!("{} s", sig3(s))
    }
}

/// A tau in s: `16 ms`, `16.4 s`.
pub(super) fn tau_text(s: f64) -> String {
    if s < 1.0 {
        format!("{} ms", sig3(s * 1e3))
    } else {
        format!("{} s", sig3(s))
    }
}

pub(super) fn interval(lo: Option<f64>, hi: Option<f64>) -> String {
    match (lo, hi) {
        (Some(l), Some(h)) => format!("[{}, {}]", sig3(l), sig3(h)),
        _ => String::new(),
    }
}

/// The widest cell of each column, in characters.
pub(super) fn column_widths(rows: &[Vec<String>]) -> Vec<usize> {
    let n = rows.iter().map(Vec::len).max().unwrap_or(0);
    (0..n)
        .map(|j| {
            rows.iter()
                .filter_map(|r| r.get(j))
                .map(|c| c.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect()
}

/// Columns padded to their widest cell (the last column is not padded).
pub(super) fn aligned(rows: &[Vec<String>], indent: &str) -> String {
    let widths = column_widths(rows);
    let mut out = String::new();
    for r in rows {
        let mut line = indent.to_string();
        for (j, c) in r.iter().enumerate() {
            line.push_str(c);
            if j + 1 < r.len() {
                let pad = widths[j] - c.chars().count() + 2;
                line.extend(std::iter::repeat_n(' ', pad));
            }
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

/// Columns padded to their widest cell, the first left-aligned and the others right-aligned
/// (numbers line up on their last digit).
pub(super) fn aligned_right(rows: &[Vec<String>], indent: &str) -> String {
    let widths = column_widths(rows);
    let mut out = String::new();
    for r in rows {
        let mut line = indent.to_string();
        for (j, c) in r.iter().enumerate() {
            let pad = widths[j] - c.chars().count();
            if j == 0 {
                line.push_str(c);
                line.extend(std::iter::repeat_n(' ', pad));
            } else {
                line.push_str("  ");
                line.extend(std::iter::repeat_n(' ', pad));
                line.push_str(c);
            }
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}
