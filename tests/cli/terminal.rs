//! A terminal is not a pipe (docs/records.md): `analyze` run on a real pseudo-terminal (util-linux
//! `script`, Debian's essential package bsdutils) prints the readable table; with `--json` it
//! prints the same JSON lines a pipe gets, record for record; a pipe gets JSON lines only.

use crate::common::{exe, fixtures};
use std::process::Command;

fn fixture() -> String {
    fixtures()
        .join("captures/kvh1750_stand_1min_seed1.kvh1750")
        .display()
        .to_string()
}

/// Runs the binary with `args` with its standard output on a pseudo-terminal (standard error
/// discarded, so the progress bar does not mix in); returns what the terminal showed.
fn on_a_terminal(args: &str) -> String {
    let bin = env!("CARGO_BIN_EXE_allanscope");
    let out = Command::new("script")
        .args(["-qec", &format!("{bin} {args} 2>/dev/null"), "/dev/null"])
        .env("NO_COLOR", "1")
        .output()
        .unwrap_or_else(|e| {
            panic!("this test needs util-linux `script` (Debian package bsdutils): {e}")
        });
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The terminal turns each newline into CR LF.
    String::from_utf8_lossy(&out.stdout).replace("\r\n", "\n")
}

/// The JSON lines of a piped run, the summary's wall time left out (it differs run to run).
fn comparable(text: &str) -> Vec<serde_json::Value> {
    text.lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let mut v: serde_json::Value =
                serde_json::from_str(l).unwrap_or_else(|e| panic!("not JSON: {l}: {e}"));
            if let Some(o) = v.as_object_mut() {
                o.remove("elapsed_s");
            }
            v
        })
        .collect()
}

#[test]
fn a_terminal_gets_the_table_and_json_with_the_option_and_a_pipe_json() {
    let args = format!("analyze {} --format kvh1750", fixture());
    let table = on_a_terminal(&args);
    assert!(!table.contains("{\""), "JSON on a terminal:\n{table}");
    // The heading, a gyro's terms in datasheet units, an accelerometer's, the read-outs column.
    assert!(
        table.contains("kvh1750_stand_1min_seed1.kvh1750: 60.0 s of data at tau0 = 1.00 ms"),
        "{table}"
    );
    assert!(
        table.contains("angle random walk") && table.contains("deg/sqrt(h)"),
        "{table}"
    );
    assert!(
        table.contains("velocity random walk") && table.contains("micro-g"),
        "{table}"
    );
    assert!(table.contains("IEEE 952 read-out"), "{table}");
    assert!(table.contains("decoder: 60000 frames"), "{table}");

    let piped = exe()
        .args(["analyze", &fixture(), "--format", "kvh1750"])
        .output()
        .unwrap();
    assert!(piped.status.success());
    let piped = String::from_utf8(piped.stdout).unwrap();
    let json = on_a_terminal(&format!("{args} --json"));
    let (a, b) = (comparable(&piped), comparable(&json));
    assert!(a.len() > 10, "{piped}");
    assert_eq!(a, b, "--json on a terminal must give the piped records");
    // The pipe's records are typed records of docs/records.md, the last one the summary.
    assert_eq!(a.last().unwrap()["type"], "summary");
}
