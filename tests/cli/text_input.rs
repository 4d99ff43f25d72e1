//! Text columns as they come (issue 14): a byte-order mark, `;` separators, a time column,
//! `--columns` to pick and rename, and the errors (exit 2) for duplicate names, unknown columns,
//! a text column, and an input without one sample. Each file is written here and read through
//! the binary; the curves are compared with those of the same numbers written plainly.

use crate::common::exe;
use std::path::{Path, PathBuf};
use std::process::Output;

use allanscope::sink::records::{CurveRecord, Record, SummaryRecord};

fn tmp(name: &str) -> PathBuf {
    crate::common::tmp_in("cli_text", name)
}

/// 400 rows (401 phase points, the summary's `samples`) of two deterministic, unequal columns (no generator needed: the test compares two
/// readings of the same numbers, so any values that are not constant do).
fn columns() -> (Vec<f64>, Vec<f64>) {
    let a = (0..400)
        .map(|i| ((i * 37 % 101) as f64 - 50.0) * 1e-3)
        .collect();
    let b = (0..400)
        .map(|i| ((i * 53 % 89) as f64 - 44.0) * 2e-3)
        .collect();
    (a, b)
}

fn write(name: &str, text: &[u8]) -> PathBuf {
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn rows(sep: &str, with_time: bool) -> String {
    let (a, b) = columns();
    let mut s = String::new();
    for i in 0..a.len() {
        if with_time {
            s += &format!("{:.3}{sep}", i as f64 * 0.01);
        }
        s += &format!("{:e}{sep}{:e}\n", a[i], b[i]);
    }
    s
}

fn analyze(path: &Path, extra: &[&str]) -> Output {
    exe()
        .args([
            "analyze",
            path.to_str().unwrap(),
            "--tau0",
            "0.01",
            "--fit",
            "none",
        ])
        .args(["--stats", "avar"])
        .args(extra)
        .output()
        .unwrap()
}

fn parsed(out: &Output) -> (Vec<CurveRecord>, SummaryRecord) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let recs: Vec<Record> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let curves = recs
        .iter()
        .filter_map(|r| match r {
            Record::Curve(c) if c.r#final => Some(c.clone()),
            _ => None,
        })
        .collect();
    let Some(Record::Summary(s)) = recs.last() else {
        panic!("summary last")
    };
    (curves, s.clone())
}

fn plain() -> (Vec<CurveRecord>, SummaryRecord) {
    let p = write(
        "plain.csv",
        format!("gx,gy\n{}", rows(",", false)).as_bytes(),
    );
    parsed(&analyze(&p, &[]))
}

fn usage_error(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
}

#[test]
fn bom_semicolons_and_a_time_column_read_as_the_plain_file() {
    let (pc, ps) = plain();
    assert_eq!(ps.channels, ["gx", "gy"]);
    assert_eq!(ps.samples, [401, 401]);
    let mut text = b"\xef\xbb\xbf".to_vec();
    text.extend_from_slice(format!("Time;gx;gy\n{}", rows(";", true)).as_bytes());
    let p = write("bom_semicolon_time.csv", &text);
    let (c, s) = parsed(&analyze(&p, &[]));
    assert_eq!(s.channels, ["gx", "gy"]);
    assert_eq!(s.samples, [401, 401]);
    assert_eq!(c.len(), pc.len());
    for (a, b) in c.iter().zip(&pc) {
        assert_eq!(a.channel, b.channel);
        assert_eq!(a.sigma, b.sigma);
    }
    // A BOM before the first name of a file without a time column.
    let mut text = b"\xef\xbb\xbf".to_vec();
    text.extend_from_slice(format!("gx\tgy\n{}", rows("\t", false)).as_bytes());
    let (c, s) = parsed(&analyze(&write("bom_tab.csv", &text), &[]));
    assert_eq!(s.channels, ["gx", "gy"]);
    assert_eq!(c[0].sigma, pc[0].sigma);
}

#[test]
fn a_named_time_column_and_columns_picked_and_renamed() {
    let (pc, _) = plain();
    let p = write(
        "stamp.csv",
        format!("stamp,gx,gy\n{}", rows(",", true)).as_bytes(),
    );
    let (c, s) = parsed(&analyze(&p, &["--time-column", "stamp"]));
    assert_eq!(s.channels, ["gx", "gy"]);
    assert_eq!(c[1].sigma, pc[1].sigma);
    // Without --time-column, `stamp` is a channel like any other.
    let (_, s) = parsed(&analyze(&p, &[]));
    assert_eq!(s.channels, ["stamp", "gx", "gy"]);
    // Picked in another order, one renamed.
    let (c, s) = parsed(&analyze(&p, &["--columns", "gy,gx=g1"]));
    assert_eq!(s.channels, ["gy", "g1"]);
    assert_eq!(s.samples, [401, 401]);
    assert_eq!(c[0].channel, "gy");
    assert_eq!(c[0].sigma, pc[1].sigma);
    assert_eq!(c[1].channel, "g1");
    assert_eq!(c[1].sigma, pc[0].sigma);
}

#[test]
fn bad_headers_and_columns_are_usage_errors_naming_them() {
    let p = write(
        "dup.csv",
        format!("gx,gy,gx\n{}", rows(",", true)).as_bytes(),
    );
    usage_error(
        &analyze(&p, &[]),
        &[
            "dup.csv",
            "line 1",
            "duplicate column name `gx`: columns 1 and 3",
        ],
    );
    let p = write(
        "cols.csv",
        format!("gx,gy\n{}", rows(",", false)).as_bytes(),
    );
    usage_error(
        &analyze(&p, &["--columns", "gx,gz=g3"]),
        &["--columns: no column named `gz`", "gx, gy"],
    );
    usage_error(
        &analyze(&p, &["--time-column", "clock"]),
        &["--time-column `clock`: no such column"],
    );
}

#[test]
fn a_text_column_and_an_input_without_samples_are_usage_errors() {
    let p = write(
        "status.csv",
        b"# log\ngx,status,gy\n0.1,OK,0.2\n0.3,OK,0.4\n",
    );
    usage_error(
        &analyze(&p, &[]),
        &[
            "status.csv",
            "line 3",
            "column 2 `status`: `OK` is not a number",
        ],
    );
    // Picking the numeric columns reads it.
    let (_, s) = parsed(&analyze(&p, &["--columns", "gx,gy"]));
    assert_eq!(s.samples, [3, 3]);
    let p = write("empty_values.csv", b"gx,gy\nnan,nan\n,\nnan,\n");
    usage_error(&analyze(&p, &[]), &["empty_values.csv", "no samples"]);
    let p = write("header_only.csv", b"gx,gy\n");
    usage_error(&analyze(&p, &[]), &["header_only.csv", "no data rows"]);
}
