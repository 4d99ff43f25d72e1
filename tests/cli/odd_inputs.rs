//! Files as other tools and damaged runs leave them (docs/robustness.md), on the built binary.
//! Each variant of a text file is read as the plain file it stands for: the same final curves,
//! to the last bit. Results files cut short are read up to their last whole line.
//!
//! - Quoted fields, `;` or tab columns with decimal commas, a Latin-1 header, a trailing
//!   separator: the plain file's curves.
//! - A FIFO (as `<(zcat run.csv.gz)` gives) is read whole, once: the plain file's curves (it
//!   lost its first 4 KiB to the format check, or hung, before), with `--tau0` or, from a time
//!   column, without (refused before: the look at the start took its bytes).
//! - A line of 3 MiB inside the rows is one bad row, read as a gap: the curves of the file with
//!   an empty row there (it was held whole in memory before).
//! - A result file whose last line is cut short (a run killed while writing) exports and
//!   aggregates as the whole file.
//! - A second run given the output file of a run still going is refused; the first run's file
//!   holds only its own whole records.
//! - `simulate -o -` writes to standard output the bytes `-o FILE` writes.
//! - Values of 1e-90 give the plain file's deviations times 1e-90; values of 1e-300 (squares
//!   below f64's range: a deviation of exactly 0 before) are refused, saying why.

use std::path::Path;
use std::process::{Child, Stdio};
use std::time::{Duration, Instant};

use crate::common::pipeline::parse_lines;
use crate::common::{exe, fixtures, fresh_dir, stdout_of};

/// 3000 rows of two channels, three decimals (a deterministic scramble, no randomness).
fn rows() -> Vec<[String; 2]> {
    (0..3000u64)
        .map(|i| {
            let a = (i.wrapping_mul(2_654_435_761) >> 7) % 20_001;
            let b = (i.wrapping_mul(40_503) ^ (i << 3)) % 9_973;
            [
                format!("{}.{:03}", a / 1000, a % 1000),
                format!("-{}.{:03}", b / 1000, b % 1000),
            ]
        })
        .collect()
}

/// The plain file: a header `g1,g2`, comma separated.
fn plain() -> String {
    let mut t = "g1,g2\n".to_string();
    for [a, b] in rows() {
        t += &format!("{a},{b}\n");
    }
    t
}

/// Each final curve record's (channel, stat, sigma) of a successful run.
fn final_curves(out: &std::process::Output) -> Vec<(String, String, Vec<f64>)> {
    assert!(
        out.status.success(),
        "{:?}: {}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    parse_lines(&out.stdout)
        .into_iter()
        .filter(|r| r["type"] == "curve" && r["final"] == true)
        .map(|r| {
            let sigma = r["sigma"].as_array().expect("sigma").iter();
            (
                r["channel"].as_str().expect("channel").to_string(),
                r["stat"].as_str().expect("stat").to_string(),
                sigma.map(|s| s.as_f64().expect("number")).collect(),
            )
        })
        .collect()
}

fn analyze(dir: &Path, input: &str, extra: &[&str]) -> std::process::Output {
    exe()
        .current_dir(dir)
        .env("ALLANSCOPE_LOG", "off")
        .args(["analyze", input, "--tau0", "0.01", "--json"])
        .args(extra)
        .output()
        .expect("run")
}

#[test]
fn text_as_other_tools_write_it_reads_as_the_plain_file() {
    let dir = fresh_dir("odd-text");
    std::fs::write(dir.join("plain.csv"), plain()).unwrap();
    let want = final_curves(&analyze(&dir, "plain.csv", &[]));
    assert_eq!(want.len(), 6);
    assert!(want.iter().all(|(_, _, s)| s.len() >= 8 && s[0] > 0.0));
    let mut variants: Vec<(&str, Vec<u8>)> = Vec::new();
    let each = |f: &dyn Fn(&str, &str) -> String| -> String {
        rows().iter().map(|[a, b]| f(a, b)).collect()
    };
    variants.push((
        "quoted",
        format!(
            "\"g1\",\"g2\"\n{}",
            each(&|a, b| format!("\"{a}\",\"{b}\"\n"))
        )
        .into_bytes(),
    ));
    let comma = |x: &str| x.replace('.', ",");
    variants.push((
        "semicolon decimal comma",
        format!(
            "g1;g2\r\n{}",
            each(&|a, b| format!("{};{}\r\n", comma(a), comma(b)))
        )
        .into_bytes(),
    ));
    variants.push((
        "tab decimal comma",
        format!(
            "g1\tg2\n{}",
            each(&|a, b| format!("{}\t{}\n", comma(a), comma(b)))
        )
        .into_bytes(),
    ));
    variants.push((
        "trailing separator",
        format!("g1,g2,\n{}", each(&|a, b| format!("{a},{b},\n"))).into_bytes(),
    ));
    // `g1` and `g2` in a Windows code page: a degree sign (0xb0) after each name.
    let mut latin1 = b"g1\xb0,g2\xb0\n".to_vec();
    latin1.extend(each(&|a, b| format!("{a},{b}\n")).into_bytes());
    variants.push(("latin-1 header", latin1));
    for (name, bytes) in variants {
        std::fs::write(dir.join("v.csv"), &bytes).unwrap();
        let got = final_curves(&analyze(&dir, "v.csv", &[]));
        let names: Vec<&str> = got.iter().map(|(c, _, _)| c.as_str()).collect();
        let expected_names = if name == "latin-1 header" {
            ["g1\u{b0}"; 3]
                .into_iter()
                .chain(["g2\u{b0}"; 3])
                .collect::<Vec<_>>()
        } else {
            ["g1"; 3].into_iter().chain(["g2"; 3]).collect()
        };
        assert_eq!(names, expected_names, "{name}");
        for ((_, stat, s), (_, stat_w, w)) in got.iter().zip(&want) {
            assert_eq!((stat, s), (stat_w, w), "{name}");
        }
    }
}

#[test]
fn a_line_of_3_mib_is_one_bad_row_read_as_a_gap() {
    let dir = fresh_dir("odd-long-line");
    let text = plain();
    let lines: Vec<&str> = text.lines().collect();
    let long = "7".repeat(3 << 20);
    let with = |row: &str| {
        let mut l = lines.clone();
        l[1500] = row;
        l.join("\n") + "\n"
    };
    std::fs::write(dir.join("long.csv"), with(&long)).unwrap();
    std::fs::write(dir.join("gap.csv"), with("")).unwrap();
    let out = analyze(&dir, "long.csv", &[]);
    let summary = parse_lines(&out.stdout)
        .into_iter()
        .find(|r| r["type"] == "summary")
        .expect("summary");
    assert_eq!(summary["bad_rows"], 1);
    assert_eq!(summary["segments"][0], 2);
    assert_eq!(
        final_curves(&out),
        final_curves(&analyze(&dir, "gap.csv", &[]))
    );
}

#[cfg(unix)]
#[test]
fn a_fifo_is_read_whole_once() {
    let dir = fresh_dir("odd-fifo");
    std::fs::write(dir.join("plain.csv"), plain()).unwrap();
    let want = final_curves(&analyze(&dir, "plain.csv", &[]));
    let fifo = dir.join("fifo");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo");
    assert!(made.success());
    // Without --tau0 the step is read off the start of the stream, which the run then reads
    // first: the curves of the plain file with its time column (before: refused).
    let mut stamped = "t,g1,g2\n".to_string();
    for (i, [a, b]) in rows().into_iter().enumerate() {
        stamped += &format!("{:.2},{a},{b}\n", i as f64 * 0.01);
    }
    std::fs::write(dir.join("stamped.csv"), &stamped).unwrap();
    let plain_stamped = {
        let mut c = exe();
        c.current_dir(&dir).env("ALLANSCOPE_LOG", "off");
        final_curves(
            &c.args(["analyze", "stamped.csv", "--json"])
                .output()
                .expect("run"),
        )
    };
    assert_eq!(plain_stamped, want, "the time column changes nothing");
    assert_eq!(final_curves(&through_fifo(&dir, &fifo, stamped, &[])), want);
    let with_tau0 = through_fifo(&dir, &fifo, plain(), &["--tau0", "0.01"]);
    assert_eq!(final_curves(&with_tau0), want);
}

/// `analyze fifo ARGS --json` in `dir` while a thread writes `text` into the FIFO `fifo`.
fn through_fifo(dir: &Path, fifo: &Path, text: String, args: &[&str]) -> std::process::Output {
    let writer = {
        let fifo = fifo.to_path_buf();
        // Errors are ignored: a reader that closes early makes the write fail, and the test
        // then fails on the records, not here.
        std::thread::spawn(move || {
            let _ = std::fs::write(&fifo, text);
        })
    };
    let child = exe()
        .current_dir(dir)
        .env("ALLANSCOPE_LOG", "off")
        .args(["analyze", "fifo", "--json"])
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let out = output_within(child, Duration::from_secs(20));
    writer.join().expect("writer");
    out
}

/// The child's output, killing it (and failing) if it runs longer than `limit`.
fn output_within(mut child: Child, limit: Duration) -> std::process::Output {
    let t0 = Instant::now();
    while child.try_wait().expect("try_wait").is_none() {
        if t0.elapsed() > limit {
            let _ = child.kill();
            panic!("allanscope did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("output")
}

#[test]
fn a_result_file_cut_short_reads_as_its_whole_lines() {
    let dir = fresh_dir("odd-torn");
    std::fs::write(dir.join("plain.csv"), plain()).unwrap();
    let full = analyze(&dir, "plain.csv", &["--unit", "deg"]);
    assert!(full.status.success());
    std::fs::write(dir.join("full.jsonl"), &full.stdout).unwrap();
    // A run killed while writing: half of a record after the last whole line.
    let mut torn = full.stdout.clone();
    torn.extend_from_slice(&full.stdout[..100]);
    std::fs::write(dir.join("torn.jsonl"), &torn).unwrap();
    let run = |args: &[&str]| {
        stdout_of(
            exe()
                .current_dir(&dir)
                .env("ALLANSCOPE_LOG", "off")
                .args(args),
        )
        .into_bytes()
    };
    for (input, out) in [("full.jsonl", "full.csv"), ("torn.jsonl", "torn.csv")] {
        run(&["export", input, "--to", "csv", "-o", out]);
    }
    let csv = std::fs::read(dir.join("full.csv")).unwrap();
    assert!(csv.len() > 200);
    assert_eq!(std::fs::read(dir.join("torn.csv")).unwrap(), csv);
    let agg = |f: &str| run(&["aggregate", f, f, "--json"]);
    assert_eq!(agg("torn.jsonl"), agg("full.jsonl"));
    run(&["report", "torn.jsonl", "-o", "r.html"]);
    run(&["plot", "torn.jsonl", "-o", "p.svg"]);
}

#[test]
fn a_second_run_on_an_output_in_use_is_refused() {
    let dir = fresh_dir("odd-lock");
    std::fs::write(dir.join("plain.csv"), plain()).unwrap();
    let cap = fixtures().join("captures/siu8_stand_5min_seed1.siu8");
    let mut first = exe()
        .current_dir(&dir)
        .env("ALLANSCOPE_LOG", "off")
        .args(["analyze", cap.to_str().unwrap(), "--format", "siu8"])
        .args(["--pace", "realtime", "--every", "1", "--out", "o.jsonl"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    // The first run has written records (and so holds the file).
    let t0 = Instant::now();
    while std::fs::metadata(dir.join("o.jsonl")).map_or(0, |m| m.len()) == 0 {
        assert!(t0.elapsed() < Duration::from_secs(20), "no record written");
        std::thread::sleep(Duration::from_millis(20));
    }
    let second = analyze(&dir, "plain.csv", &["--out", "o.jsonl", "--force"]);
    let _ = std::process::Command::new("kill")
        .args(["-INT", &first.id().to_string()])
        .status();
    let status = first.wait().expect("wait");
    assert_eq!(second.status.code(), Some(2));
    let err = String::from_utf8_lossy(&second.stderr);
    assert!(err.contains("another writer has it open"), "{err}");
    assert_eq!(
        status.code(),
        Some(1),
        "the first run was stopped by SIGINT"
    );
    let recs = parse_lines(&std::fs::read(dir.join("o.jsonl")).unwrap());
    let last = recs.last().expect("records");
    assert_eq!(last["type"], "summary");
    assert_eq!(last["stopped_by"], "SIGINT");
    // The second run's records (and its summary, input plain.csv) are nowhere in it.
    let summaries: Vec<_> = recs.iter().filter(|r| r["type"] == "summary").collect();
    assert_eq!(summaries.len(), 1);
    assert!(last["input"].as_str().expect("input").ends_with(".siu8"));
}

#[test]
fn simulate_to_standard_output_writes_the_files_bytes() {
    let dir = fresh_dir("odd-sim-stdout");
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/models/vog4.toml");
    let args = [
        "simulate",
        "--model",
        model.to_str().unwrap(),
        "--duration",
        "2",
    ];
    let piped = exe()
        .current_dir(&dir)
        .args(args)
        .args(["-o", "-"])
        .output();
    let piped = piped.expect("run");
    assert!(piped.status.success());
    let to_file = exe()
        .current_dir(&dir)
        .args(args)
        .args(["-o", "s.csv"])
        .status();
    assert!(to_file.expect("run").success());
    let bytes = std::fs::read(dir.join("s.csv")).unwrap();
    assert!(bytes.len() > 1000);
    assert_eq!(piped.stdout, bytes);
    assert!(!dir.join("-").exists(), "no file named `-`");
}

/// The plain file with `offset` added to every value and the sum multiplied by `scale` (printed
/// with 17 significant digits).
fn scaled(offset: f64, scale: f64) -> String {
    let mut t = "g1,g2\n".to_string();
    for [a, b] in rows() {
        let a: f64 = a.parse().expect("a");
        let b: f64 = b.parse().expect("b");
        t += &format!(
            "{:.16e},{:.16e}\n",
            (a + offset) * scale,
            (b + offset) * scale
        );
    }
    t
}

/// Values of 1e-90 are analysed exactly as values of 1 (every deviation 1e-90 times the plain
/// file's, to a few ulps: powers of ten are not exact in binary); values of 1e-300, whose
/// squares underflow, are refused with the reason (a deviation of exactly 0 before).
#[test]
fn tiny_values_scale_down_to_1e_minus_100_and_below_are_refused() {
    let dir = fresh_dir("odd-tiny");
    std::fs::write(dir.join("plain.csv"), scaled(0.0, 1.0)).expect("write");
    std::fs::write(dir.join("small.csv"), scaled(0.0, 1e-90)).expect("write");
    std::fs::write(dir.join("tiny.csv"), scaled(0.0005, 1e-300)).expect("write");
    let plain = final_curves(&analyze(&dir, "plain.csv", &[]));
    let small = final_curves(&analyze(&dir, "small.csv", &[]));
    assert_eq!(plain.len(), small.len());
    for ((c, s, p), (c2, s2, q)) in plain.iter().zip(&small) {
        assert_eq!((c, s), (c2, s2));
        assert_eq!(p.len(), q.len());
        for (x, y) in p.iter().zip(q) {
            assert!(*x > 0.0, "{c} {s}: {p:?}");
            let r = y / (x * 1e-90);
            assert!((r - 1.0).abs() < 1e-12, "{c} {s}: {y} vs {x} x 1e-90");
        }
    }
    let out = analyze(&dir, "tiny.csv", &[]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("6000 values are numbers beyond"), "{err}");
    assert!(err.contains("non-zero below 1e-100"), "{err}");
}

/// A stream with no line end given as text (`/dev/zero`): refused as no text columns (exit 2)
/// once its first line passes the reader's cut, instead of being read for ever (session 42: the
/// run kept reading through a SIGTERM). The process is killed and the test fails if it has not
/// ended within two minutes.
#[test]
fn a_stream_without_line_ends_is_refused_not_read_for_ever() {
    let mut child = exe()
        .args(["analyze", "/dev/zero", "--tau0", "0.01"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if start.elapsed() > std::time::Duration::from_secs(120) {
            let _ = child.kill();
            break None;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    };
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(status.and_then(|s| s.code()), Some(2), "{err}");
    assert!(
        err.contains("/dev/zero: line 1: a line longer than 1 MiB"),
        "{err}"
    );
}
