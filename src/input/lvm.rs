//! LabVIEW Measurement files (`.lvm`, written by LabVIEW's "Write To Measurement File"): text
//! columns behind a file header and a segment header of tagged lines, one tag and its values per
//! line (NI, "Specification for the LabVIEW Measurement File (.lvm)"). The first line is
//! `LabVIEW Measurement`; each header ends at `***End_of_Header***`; then a line of column names
//! (`X_Value`, the channels, `Comment`) and the rows. A new segment (another call of the VI)
//! may start its own header between rows.
//!
//! The reader ([`super::text`]) skips every tagged line, before the rows and between them, and
//! takes from them what the columns do not say: `Delta_X`, the step of the x axis (the sampling
//! step when the file has no `X_Value` column), and `Y_Unit_Label`, each channel's unit (read as
//! a row of units under the header is). `X_Value` is the time column (seconds); the `Comment`
//! column is no channel.

/// The first line's tag.
pub const MAGIC: &str = "LabVIEW Measurement";

/// Tags of the file header (NI's specification, LVM 2.0).
const FILE_TAGS: [&str; 13] = [
    MAGIC,
    "Writer_Version",
    "Reader_Version",
    "Separator",
    "Decimal_Separator",
    "Multi_Headings",
    "X_Columns",
    "Time_Pref",
    "Operator",
    "Description",
    "Project",
    "Date",
    "Time",
];

/// Tags of a segment header (it may repeat `Date` and `Time` of the file header's).
const SEGMENT_TAGS: [&str; 14] = [
    "Notes",
    "Test_Name",
    "Test_Numbers",
    "Test_Series",
    "UUT_Part_Number",
    "UUT_Name",
    "UUT_Serial_Number",
    "Channels",
    "Samples",
    "Y_Unit_Label",
    "X_Dimension",
    "X0",
    "Delta_X",
    "Channel_Name",
];

/// What an LVM file's headers say of its columns, gathered line by line.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LvmHeader {
    /// The first segment's `Delta_X` (s when its x axis is time): the sampling step.
    pub delta_x: Option<f64>,
    /// The first segment's `Y_Unit_Label`: one unit per channel, in order (empty where none).
    pub y_units: Vec<String>,
    /// Inside a `***Start_Special***` block (free text to its `***End_Special***`).
    special: bool,
    /// Inside a segment header (a segment's tag seen since the last `***End_of_Header***`).
    segment: bool,
    /// A segment header just ended: the next line is the column names, whatever they are
    /// (a channel may be called `Time` or `Samples`).
    names_next: bool,
    /// Segment headers read to their end.
    headers_ended: usize,
}

/// The fields of a tagged line: split at tabs, or at commas when it has no tab (the header's
/// `Separator` may be `Comma`).
fn fields(t: &str) -> Vec<&str> {
    let f: Vec<&str> = if t.contains('\t') {
        t.split('\t').collect()
    } else {
        t.split(',').collect()
    };
    f.into_iter().map(str::trim).collect()
}

/// Whether the line `t` (trimmed) is a line of an LVM header: a known tag first, or a
/// `***...***` marker.
pub fn is_tag_line(t: &str) -> bool {
    let first = fields(t)[0];
    (first.starts_with("***") && first.ends_with("***") && first.len() > 6)
        || FILE_TAGS.contains(&first)
        || SEGMENT_TAGS.contains(&first)
}

impl LvmHeader {
    /// Takes in the line `t` (trimmed) when it is header: a tagged line, a marker or a line of
    /// a special block; `false` for anything else (the column names, a row).
    pub fn take(&mut self, t: &str) -> bool {
        if self.special {
            if t.starts_with("***End_Special***") {
                self.special = false;
            }
            return true;
        }
        let marker = t.starts_with("***");
        if std::mem::take(&mut self.names_next) && !marker {
            return false;
        }
        if !is_tag_line(t) {
            return false;
        }
        let f = fields(t);
        if SEGMENT_TAGS.contains(&f[0]) {
            self.segment = true;
        }
        match f[0] {
            "***Start_Special***" => self.special = true,
            "***End_of_Header***" => {
                self.headers_ended += 1;
                self.names_next = std::mem::take(&mut self.segment);
            }
            // The first segment's: a later segment of the same run repeats them.
            "Delta_X" if self.delta_x.is_none() => {
                self.delta_x = f[1..]
                    .iter()
                    .find_map(|v| v.replace(',', ".").parse::<f64>().ok())
                    .filter(|d| d.is_finite() && *d > 0.0);
            }
            "Y_Unit_Label" if self.y_units.is_empty() => {
                self.y_units = f[1..].iter().map(|u| u.to_string()).collect();
                // The trailing separator LabVIEW writes leaves an empty last field.
                while self.y_units.last().is_some_and(String::is_empty) {
                    self.y_units.pop();
                }
            }
            _ => {}
        }
        true
    }

    /// The line of column names `names` made the reader's: the last `Comment` column unnamed
    /// (no channel, as a trailing separator's empty name is not), and with an x column per
    /// channel (`X_Columns Multi`) the later ones numbered (`X_Value_2`: clocks, not
    /// channels); and each input column's unit ([`LvmHeader::column_units`], read before the
    /// names change).
    pub fn columns(&self, names: &mut [String]) -> Option<Vec<String>> {
        let units = self.column_units(names);
        if let Some(last) = names.last_mut().filter(|n| is_comment(n)) {
            last.clear();
        }
        for (k, n) in names.iter_mut().filter(|n| is_x_column(n)).enumerate() {
            if k > 0 {
                *n = format!("X_Value_{}", k + 1);
            }
        }
        units
    }

    /// The units of the input columns named `names` (the line of column names): the
    /// `Y_Unit_Label` units in order over the columns that are not `X_Value` nor the `Comment`,
    /// an empty unit for those; `None` when the header gives no unit.
    pub fn column_units(&self, names: &[String]) -> Option<Vec<String>> {
        if self.y_units.iter().all(String::is_empty) {
            return None;
        }
        let mut units = self.y_units.iter();
        Some(
            names
                .iter()
                .map(|n| {
                    if is_x_column(n) || is_comment(n) {
                        String::new()
                    } else {
                        units.next().cloned().unwrap_or_default()
                    }
                })
                .collect(),
        )
    }
}

/// Whether a column name is LabVIEW's x column (`X_Value`).
pub fn is_x_column(name: &str) -> bool {
    name.trim().eq_ignore_ascii_case("X_Value")
}

/// Which of LabVIEW's x columns a name is, as [`LvmHeader::columns`] names them: 1 for
/// `X_Value`, k for `X_Value_k`; `None` for any other name.
pub fn x_column_number(name: &str) -> Option<usize> {
    if is_x_column(name) {
        return Some(1);
    }
    let k = name.trim().to_ascii_lowercase();
    let k = k.strip_prefix("x_value_")?;
    (!k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()))
        .then(|| k.parse().ok())
        .flatten()
}

/// Whether a column name is the `Comment` column LabVIEW writes last.
pub fn is_comment(name: &str) -> bool {
    name.trim() == "Comment"
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file header and a segment header as LabVIEW 2020 writes them (tabs, a trailing tab),
    /// with a special block: every line taken; `Delta_X` and `Y_Unit_Label` read from the
    /// first segment only; the column names and rows not taken.
    #[test]
    fn headers_are_taken_and_read() {
        let lines = [
            "LabVIEW Measurement\t",
            "Writer_Version\t2",
            "Separator\tTab",
            "Decimal_Separator\t.",
            "X_Columns\tOne",
            "***Start_Special***",
            "free text, 0.5 1.5",
            "***End_Special***",
            "***End_of_Header***\t",
            "Channels\t2\t",
            "Y_Unit_Label\tdeg/s\tg\t",
            "X_Dimension\tTime\tTime\t",
            "X0\t0.0000000000000000E+0\t0.0000000000000000E+0\t",
            "Delta_X\t2.000000E-3\t2.000000E-3\t",
            "***End_of_Header***\t",
        ];
        let mut h = LvmHeader::default();
        for l in lines {
            assert!(h.take(l.trim()), "{l}");
        }
        assert!(!h.take("X_Value\tgx\taz\tComment"));
        // After a segment header, the column names are names, even a tag's (`Time`).
        let mut n = LvmHeader::default();
        for l in ["Channels\t2", "Delta_X\t0.01\t0.01", "***End_of_Header***"] {
            assert!(n.take(l));
        }
        assert!(!n.take("Time\tgx\tComment"));
        assert!(n.take("Time\t07:51:28"), "a tag again after the names");
        assert!(!h.take("0.000000\t1.2E-3\t0.99"));
        assert!(h.take("Delta_X\t5.0E-3"), "a later segment's");
        assert_eq!(h.delta_x, Some(2e-3));
        assert_eq!(h.y_units, ["deg/s", "g"]);
        assert_eq!(h.headers_ended, 2);
        let names: Vec<String> = ["X_Value", "gx", "az", "Comment"]
            .map(String::from)
            .to_vec();
        assert_eq!(
            h.column_units(&names).unwrap(),
            ["", "deg/s", "g", ""].map(String::from)
        );
        // A header split at commas; one split at tabs with decimal commas.
        let mut c = LvmHeader::default();
        assert!(c.take("Delta_X,0.001,0.001,"));
        assert_eq!(c.delta_x, Some(0.001));
        let mut d = LvmHeader::default();
        assert!(d.take("Delta_X\t1,000000E-3\t1,000000E-3"));
        assert_eq!(d.delta_x, Some(0.001));
        assert!(LvmHeader::default().column_units(&names).is_none());
    }
}
