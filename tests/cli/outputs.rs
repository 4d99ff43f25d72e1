//! Nothing measured is lost through the output files (issue 11, "Data loss"): the built binary on
//! real files.
//!
//! - A start that fails (serial port absent, input missing, `--tau0` missing) leaves an earlier
//!   `--out`, `--capture` and stand-config output byte for byte as they were, even with
//!   `--force`, and creates no empty file where there was none.
//! - An existing non-empty `--out`/`--capture` is refused (exit 2, the file and `--force` named);
//!   `--force` replaces it once the run produces data: the capture then holds exactly the bytes
//!   received.
//! - A capture that cannot be written (`/dev/full`) stops the capture, not the run: exit 0, every
//!   frame analysed, the failure in `health`, `summary` and the log.
//! - JSON lines to a full standard output: the error says it is standard output.

use std::io::Write;
use std::path::Path;
use std::process::{Output, Stdio};

use crate::common::{exe, fixtures, tmp_in};

/// siu8 frames are 42 bytes at 250 Hz (4 ms).
const FRAME_LEN: usize = 42;
const TAU0_S: f64 = 0.004;

fn siu8_fixture() -> Vec<u8> {
    std::fs::read(fixtures().join("captures/siu8_stand_5min_seed1.siu8")).expect("siu8 fixture")
}

fn run(args: &[&str], stdin: Option<&[u8]>) -> Output {
    let mut cmd = exe();
    cmd.args(args)
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd.spawn().expect("spawn allanscope");
    if let Some(bytes) = stdin {
        let mut w = child.stdin.take().expect("stdin");
        let bytes = bytes.to_vec();
        std::thread::spawn(move || {
            let _ = w.write_all(&bytes);
        });
    }
    child.wait_with_output().expect("wait")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn records(path: &Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(path)
        .expect("output")
        .lines()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect()
}

fn last_of<'a>(recs: &'a [serde_json::Value], kind: &str) -> &'a serde_json::Value {
    recs.iter()
        .rev()
        .find(|r| r["type"] == kind)
        .unwrap_or_else(|| panic!("no {kind} record"))
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// An earlier result: 3000 distinct bytes.
fn earlier(tag: u8) -> Vec<u8> {
    (0..3000u32)
        .map(|i| (i as u8).wrapping_mul(7) ^ tag)
        .collect()
}

#[test]
fn a_failed_start_leaves_earlier_results_untouched() {
    let out = tmp_in("outputs-failed", "out.jsonl");
    let cap = tmp_in("outputs-failed", "cap.siu8");
    let fresh = tmp_in("outputs-failed", "never.jsonl");
    let fresh_cap = tmp_in("outputs-failed", "never.siu8");
    let csv = fixtures().join("captures/vog4_2min_seed7.csv");
    let config = tmp_in("outputs-failed", "stand.toml");
    std::fs::write(
        &config,
        format!(
            "[source]\nkind = \"serial\"\npath = \"/dev/nonexist\"\nformat = \"siu8\"\n\n\
             [run]\ncapture = {cap:?}\n\n[output]\npath = {out:?}\n"
        ),
    )
    .unwrap();
    let tries: Vec<Vec<&str>> = vec![
        vec!["run", "--config", s(&config), "--force"],
        vec![
            "listen",
            "--serial",
            "/dev/nonexist",
            "--format",
            "siu8",
            "--out",
            s(&out),
            "--capture",
            s(&cap),
            "--force",
        ],
        vec![
            "analyze",
            "missing.csv",
            "--tau0",
            "1",
            "--out",
            s(&out),
            "--force",
        ],
        vec!["analyze", s(&csv), "--out", s(&out), "--force"],
    ];
    for args in &tries {
        std::fs::write(&out, earlier(1)).unwrap();
        std::fs::write(&cap, earlier(2)).unwrap();
        let o = run(args, None);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert_eq!(
            std::fs::read(&out).unwrap(),
            earlier(1),
            "{args:?} changed --out"
        );
        assert_eq!(
            std::fs::read(&cap).unwrap(),
            earlier(2),
            "{args:?} changed --capture"
        );
    }
    // Where there was no file, a failed start leaves none (not an empty one).
    let o = run(
        &[
            "listen",
            "--serial",
            "/dev/nonexist",
            "--format",
            "siu8",
            "--out",
            s(&fresh),
            "--capture",
            s(&fresh_cap),
        ],
        None,
    );
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!fresh.exists() && !fresh_cap.exists());
    // Without --force, the stand config's earlier capture is refused by name.
    let o = run(&["run", "--config", s(&config)], None);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains(s(&cap)) && e.contains("--force") && e.contains("3000 bytes"),
        "{e}"
    );
    assert_eq!(std::fs::read(&out).unwrap(), earlier(1));
}

#[test]
fn a_rerun_over_the_last_capture_is_refused_unless_forced() {
    let out = tmp_in("outputs-rerun", "out.jsonl");
    let cap = tmp_in("outputs-rerun", "cap.siu8");
    let _ = std::fs::remove_file(&out);
    let _ = std::fs::remove_file(&cap);
    let frames = siu8_fixture();
    let first = &frames[..1000 * FRAME_LEN];
    let second = &frames[1000 * FRAME_LEN..1500 * FRAME_LEN];
    let args = [
        "listen",
        "-",
        "--format",
        "siu8",
        "--out",
        s(&out),
        "--capture",
        s(&cap),
    ];
    let o = run(&args, Some(first));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(
        std::fs::read(&cap).unwrap() == first,
        "the capture holds the bytes received"
    );
    let out_first = std::fs::read(&out).unwrap();
    assert_eq!(last_of(&records(&out), "health")["frames"], 1000);

    // The same command again: refused, both files as they were.
    let o = run(&args, Some(second));
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(e.contains(s(&cap)) && e.contains("--force"), "{e}");
    assert!(std::fs::read(&cap).unwrap() == first);
    assert_eq!(std::fs::read(&out).unwrap(), out_first);
    // Only the output in the way: still refused.
    let keep = tmp_in("outputs-rerun", "keep.siu8");
    std::fs::rename(&cap, &keep).unwrap();
    let o = run(&args, Some(second));
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains(s(&out)), "{}", stderr(&o));
    assert_eq!(std::fs::read(&out).unwrap(), out_first);
    assert!(!cap.exists(), "a refused run leaves no capture file");
    std::fs::rename(&keep, &cap).unwrap();

    // With --force: both replaced by this run's data (not appended to).
    let mut forced = args.to_vec();
    forced.push("--force");
    let o = run(&forced, Some(second));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(std::fs::read(&cap).unwrap().len(), 500 * FRAME_LEN);
    assert!(std::fs::read(&cap).unwrap() == second);
    let recs = records(&out);
    assert_eq!(recs.iter().filter(|r| r["type"] == "summary").count(), 1);
    assert_eq!(last_of(&recs, "health")["frames"], 500);
    assert_eq!(last_of(&recs, "summary")["t_data"], 500.0 * TAU0_S);
}

#[test]
fn a_full_capture_disk_stops_the_capture_not_the_run() {
    if !Path::new("/dev/full").exists() {
        eprintln!("NOTE: no /dev/full here; test skipped");
        return;
    }
    let out = tmp_in("outputs-full", "out.jsonl");
    let _ = std::fs::remove_file(&out);
    // 5000 frames, 210,000 bytes: more than the capture's 64 KiB buffer.
    let frames = &siu8_fixture()[..5000 * FRAME_LEN];
    let o = run(
        &[
            "listen",
            "-",
            "--format",
            "siu8",
            "--out",
            s(&out),
            "--capture",
            "/dev/full",
        ],
        Some(frames),
    );
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{e}");
    assert!(
        e.contains("capture file /dev/full") && e.contains("No space left"),
        "{e}"
    );
    let recs = records(&out);
    let h = last_of(&recs, "health");
    assert_eq!(h["frames"], 5000);
    assert_eq!(h["missing"], 0);
    let written = h["capture_bytes"].as_u64().expect("capture_bytes");
    assert!(written < 5000 * FRAME_LEN as u64, "{written}");
    assert!(h["capture_error"].as_str().unwrap().contains("/dev/full"));
    let sm = last_of(&recs, "summary");
    assert!(sm["capture_error"]
        .as_str()
        .unwrap()
        .contains("No space left"));
    assert_eq!(sm["t_data"], 5000.0 * TAU0_S);
    assert_eq!(sm["read_to_end"], true);
    // The final records are all there: 8 channels x 3 statistics + 8 fits.
    let finals = recs
        .iter()
        .filter(|r| (r["type"] == "curve" || r["type"] == "fit") && r["final"] == true)
        .count();
    assert_eq!(finals, 32);
}

#[test]
fn json_lines_to_a_full_standard_output_say_so() {
    if !Path::new("/dev/full").exists() {
        eprintln!("NOTE: no /dev/full here; test skipped");
        return;
    }
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let o = exe()
        .args([
            "analyze",
            s(&fixtures().join("captures/vog4_2min_seed7.csv")),
            "--tau0",
            "0.01",
        ])
        .stdout(Stdio::from(full))
        .stderr(Stdio::piped())
        .output()
        .unwrap();
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("writing the JSON lines to standard output"),
        "{e}"
    );
    assert!(e.contains("No space left on device"), "{e}");
}

/// 3000 rows (30 s at 10 ms) of white increments in one column `gx`: a recording to protect.
fn recording(path: &Path) -> Vec<u8> {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut text = String::from("gx\n");
    for _ in 0..3000 {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let u = (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
        text += &format!("{:e}\n", u * 1e-3);
    }
    std::fs::write(path, &text).unwrap();
    text.into_bytes()
}

/// `o` was refused (exit 2) before it wrote or truncated anything: `data` still holds `bytes`,
/// and the message names the output option, the file the run reads and why.
fn refused_over_input(o: &Output, data: &Path, bytes: &[u8], needles: &[&str]) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(2), "{e}");
    for n in needles {
        assert!(e.contains(n), "`{n}` not in: {e}");
    }
    assert!(
        e.contains("--force replaces an earlier result, never the data"),
        "{e}"
    );
    assert!(
        std::fs::read(data).unwrap() == bytes,
        "the recording changed"
    );
    assert!(o.stdout.is_empty(), "records written before the refusal");
}

#[test]
fn an_output_that_is_an_input_is_refused_even_with_force() {
    let dir = crate::common::fresh_dir("outputs-self");
    let data = dir.join("self.csv");
    let bytes = recording(&data);
    let analyze = |out: &Path, extra: &[&str]| {
        let mut cmd = exe();
        cmd.args(["analyze", s(&data), "--tau0", "0.01", "--every", "10"])
            .args(extra)
            .arg("--out")
            .arg(out)
            .arg("--force")
            .current_dir(&dir)
            .stderr(Stdio::piped())
            .stdout(Stdio::piped())
            .output()
            .unwrap()
    };
    // Named as given: before, the first interim record truncated the file being read, and
    // the run ended with exit 0 and `read_to_end: true` over part of it.
    let o = analyze(&data, &[]);
    let named = format!(
        "--out {}: is the same file as the input {}",
        s(&data),
        s(&data)
    );
    refused_over_input(&o, &data, &bytes, &[&named]);
    // By a relative path through a folder, a hard link and a symbolic link.
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    let hard = dir.join("hard.csv");
    let soft = dir.join("soft.csv");
    let _ = std::fs::remove_file(&hard);
    let _ = std::fs::remove_file(&soft);
    std::fs::hard_link(&data, &hard).unwrap();
    std::os::unix::fs::symlink(&data, &soft).unwrap();
    for out in [Path::new("sub/../self.csv"), &hard, &soft] {
        let o = analyze(out, &[]);
        let named = format!("--out {}: is the same file as the input", out.display());
        refused_over_input(&o, &data, &bytes, &[&named]);
    }
    // Standard input redirected from the file.
    let o = exe()
        .args([
            "analyze",
            "-",
            "--tau0",
            "0.01",
            "--force",
            "--out",
            s(&data),
        ])
        .stdin(std::fs::File::open(&data).unwrap())
        .output()
        .unwrap();
    refused_over_input(&o, &data, &bytes, &["is the same file as standard input"]);
    // The checkpoint beside --out (`--out x` -> `x.ckpt`).
    let ckpt = dir.join("x.ckpt");
    std::fs::write(&ckpt, &bytes).unwrap();
    let o = exe()
        .args(["analyze", s(&ckpt), "--tau0", "0.01", "--force"])
        .args(["--checkpoint-every", "10", "--out", s(&dir.join("x"))])
        .output()
        .unwrap();
    refused_over_input(&o, &ckpt, &bytes, &["checkpoint"]);

    // diagnose: --out over its --holdout, --model-out is new by rule (refused when it exists).
    let held = dir.join("held.csv");
    std::fs::write(&held, &bytes).unwrap();
    let o = exe()
        .args([
            "diagnose",
            s(&data),
            "--tau0",
            "0.01",
            "--holdout",
            s(&held),
        ])
        .args(["--out", s(&held), "--force"])
        .output()
        .unwrap();
    refused_over_input(&o, &held, &bytes, &["is the same file as --holdout"]);

    // The commands that read JSON lines: aggregate, plot, report, export.
    let results = dir.join("results.jsonl");
    let o = exe()
        .args(["analyze", s(&data), "--tau0", "0.01", "--out", s(&results)])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let kept = std::fs::read(&results).unwrap();
    let r = s(&results);
    for args in [
        vec!["aggregate", r, r, "--out", r, "--force"],
        vec!["plot", r, "-o", r, "--force"],
        vec!["report", r, "-o", r, "--force"],
        vec!["export", r, "--to", "csv", "-o", r, "--force"],
    ] {
        let o = exe().args(&args).output().unwrap();
        refused_over_input(&o, &results, &kept, &["is the same file as the input"]);
    }
    // simulate over its own model file.
    let model = dir.join("model.toml");
    crate::common::write_vog4_model(&model, "");
    let model_bytes = std::fs::read(&model).unwrap();
    let o = exe()
        .args(["simulate", "--model", s(&model), "--duration", "10s"])
        .args(["-o", s(&model), "--force"])
        .output()
        .unwrap();
    refused_over_input(&o, &model, &model_bytes, &["is the same file as --model"]);
    // run: a stand config whose capture is its own replayed source.
    let capture = dir.join("cap.siu8");
    std::fs::write(&capture, siu8_fixture()).unwrap();
    let cap_bytes = std::fs::read(&capture).unwrap();
    let config = dir.join("stand.toml");
    std::fs::write(
        &config,
        format!(
            "[source]\nkind = \"file\"\npath = \"{}\"\nformat = \"siu8\"\n\n[run]\ncapture = \
             \"{}\"\n",
            s(&capture),
            s(&capture)
        ),
    )
    .unwrap();
    let o = exe()
        .args(["run", "--config", s(&config), "--force"])
        .output()
        .unwrap();
    refused_over_input(
        &o,
        &capture,
        &cap_bytes,
        &["capture", "is the same file as"],
    );
}
