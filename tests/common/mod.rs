//! Helpers shared by the integration tests: where the reference data lives, a reader for
//! Stable32 result tables, and the named tolerances.
#![allow(dead_code)]

pub mod fit;
pub mod pipeline;

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

/// Relative agreement of the streaming estimate with the batch formulas (issue: 1e-12).
pub const STREAM_VS_BATCH_REL: f64 = 1e-12;

/// The `allanscope` binary built for these tests.
pub fn exe() -> std::process::Command {
    std::process::Command::new(env!("CARGO_BIN_EXE_allanscope"))
}

/// `allanscope analyze PATH EXTRA...` of text columns with the Allan deviation alone, no fit,
/// JSON lines and the log at info level: the run the tests of what a header says compare.
pub fn analyze_avar(path: &Path, extra: &[&str]) -> std::process::Output {
    exe()
        .arg("analyze")
        .arg(path)
        .args(["--fit", "none", "--stats", "avar", "--json"])
        .args(extra)
        .env("ALLANSCOPE_LOG", "info")
        .output()
        .unwrap()
}

/// The final curve records of a run's standard output.
pub fn final_curve_records(
    out: &std::process::Output,
) -> Vec<allanscope::sink::records::CurveRecord> {
    records_of(out)
        .into_iter()
        .filter_map(|r| match r {
            allanscope::sink::records::Record::Curve(c) if c.r#final => Some(c),
            _ => None,
        })
        .collect()
}

/// Runs `cmd` and returns its standard output; fails the test, showing the command's standard
/// error, unless it exits 0.
pub fn stdout_of(cmd: &mut std::process::Command) -> String {
    let out = cmd.output().expect("run allanscope");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The JSON lines of a successful command's standard output.
/// The records a successful run wrote to standard output, typed (a failed run's standard error
/// is the panic message).
pub fn records_of(out: &std::process::Output) -> Vec<allanscope::sink::records::Record> {
    if !out.status.success() {
        panic!("{:?}: {}", out.status, String::from_utf8_lossy(&out.stderr));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let record = |l: &str| serde_json::from_str(l).unwrap_or_else(|e| panic!("{l}: {e}"));
    text.lines().map(record).collect()
}

pub fn parse_lines_of(cmd: &mut std::process::Command) -> Vec<serde_json::Value> {
    pipeline::parse_lines(stdout_of(cmd).as_bytes())
}

/// The first JSON line of a successful command's standard output.
pub fn first_record(cmd: &mut std::process::Command) -> serde_json::Value {
    let text = stdout_of(cmd);
    let line = text.lines().next().expect("a JSON line on standard output");
    serde_json::from_str(line).unwrap_or_else(|e| panic!("{line}: {e}"))
}

/// The seed paper's VOG4 gyro (its table 2 means: N 0.254 arcsec/sqrt(s), B 0.225 arcsec/s,
/// K 1.826e-2 arcsec/s/sqrt(s); 250 Hz, LSB 0.004 arcsec) written as the model file `path`,
/// one channel `g4`, with the `extra` lines (a bias, an effect) added to the channel.
pub fn write_vog4_model(path: &Path, extra: &str) {
    let text = format!(
        "rate_hz = 250\n[[channel]]\nname = \"g4\"\nunit = \"arcsec\"\nlsb = 0.004\nN = 0.254\n\
         B = 0.225\nK = 1.826e-2\nflicker_band_s = [0.004, 1.0e4]\n{extra}"
    );
    std::fs::write(path, text).unwrap();
}

/// `simulate --model MODEL ARGS... -o OUT`, an earlier `out` removed first; fails the test
/// unless the command succeeds.
pub fn simulate_to(model: &Path, args: &[&str], out: &Path) {
    let _ = std::fs::remove_file(out);
    let st = exe()
        .args(["simulate", "--model", model.to_str().unwrap()])
        .args(args)
        .arg("-o")
        .arg(out)
        .status()
        .unwrap();
    assert!(st.success());
}

/// A name for this test process: its id and the time it first asked (ns). Process ids alone are
/// reused (32768 of them here, with several test runs at once), and a reused one used to hand a
/// test an earlier run's outputs, which the commands then refuse to overwrite: `analyze --out`
/// failing with exit 2 under load, seen in the plot and report tests.
pub fn process_token() -> String {
    static TOKEN: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TOKEN
        .get_or_init(|| {
            let ns = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos());
            format!("{}-{ns}", std::process::id())
        })
        .clone()
}

/// A scratch folder of this test process for `tag` (named by [`process_token`]), emptied the
/// first time this process asks for it. A test run's folders stay after it ends, for a look at a
/// failure; the first folder asked for in a later run removes those of processes gone by then
/// ([`sweep_stale_scratch`]), so runs do not pile up in the temporary folder (a full run leaves
/// about 300 MB, most of it the model-file and diagnosis tests' captures).
pub fn fresh_dir(tag: &str) -> PathBuf {
    static SEEN: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    static SWEPT: std::sync::Once = std::sync::Once::new();
    SWEPT.call_once(|| sweep_stale_scratch(&std::env::temp_dir()));
    let d = std::env::temp_dir().join(format!("allanscope-{tag}-{}", process_token()));
    let mut seen = SEEN.lock().unwrap_or_else(|e| e.into_inner());
    if !seen.iter().any(|t| t == tag) {
        let _ = std::fs::remove_dir_all(&d);
        seen.push(tag.to_string());
    }
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The process id in a scratch folder's name `allanscope-TAG-PID-NS` ([`fresh_dir`]), or `None`
/// for any other name.
pub fn scratch_owner(name: &str) -> Option<u32> {
    let rest = name.strip_prefix("allanscope-")?;
    let mut parts = rest.rsplitn(3, '-');
    let ns = parts.next()?;
    let pid = parts.next()?;
    let tag = parts.next()?;
    let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if tag.is_empty() || !digits(pid) || !digits(ns) || ns.len() < 15 {
        return None;
    }
    pid.parse().ok()
}

/// Removes the scratch folders in `temp` of test processes no longer running: by `/proc` where
/// there is one (a process id in use again keeps its folder, harmlessly); elsewhere, those not
/// touched for a day.
pub fn sweep_stale_scratch(temp: &Path) {
    let Ok(entries) = std::fs::read_dir(temp) else {
        return;
    };
    let proc_fs = Path::new("/proc/self").exists();
    let me = std::process::id();
    for e in entries.flatten() {
        let Some(pid) = e.file_name().to_str().and_then(scratch_owner) else {
            continue;
        };
        let stale = if proc_fs {
            pid != me && !Path::new("/proc").join(pid.to_string()).exists()
        } else {
            e.metadata()
                .and_then(|m| m.modified())
                .ok()
                .and_then(|t| t.elapsed().ok())
                .is_some_and(|age| age > std::time::Duration::from_secs(86_400))
        };
        if stale && e.file_type().is_ok_and(|t| t.is_dir()) {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// `name` in a scratch folder of this test process, `tag` telling the test files apart.
pub fn tmp_in(tag: &str, name: &str) -> PathBuf {
    fresh_dir(tag).join(name)
}

/// The crate's own fixtures folder.
pub fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures")
}

/// `../shared/reference` beside the repository, for the few tests whose recordings are too
/// large for fixtures/. Those tests are `#[ignore]`d (`.ci/run` runs them when the folder is
/// there); run without it, they fail with this message instead of passing unchecked.
pub fn shared_reference() -> PathBuf {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/reference");
    assert!(
        p.is_dir(),
        "{} does not exist: this test needs the shared reference recordings",
        p.display()
    );
    p
}

/// Numbers of a text file, one per line (first column), `#` lines and blank lines skipped;
/// gzip when the name ends in `.gz`.
pub fn read_column(path: &Path) -> Vec<f64> {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let reader: Box<dyn Read> = if path.extension().is_some_and(|e| e == "gz") {
        Box::new(flate2::read::GzDecoder::new(file))
    } else {
        Box::new(file)
    };
    let mut out = Vec::new();
    for line in BufReader::new(reader).lines() {
        let line = line.unwrap();
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let first = t.split_whitespace().next().unwrap();
        out.push(
            first
                .parse::<f64>()
                .unwrap_or_else(|e| panic!("{}: {t}: {e}", path.display())),
        );
    }
    out
}

/// One row of a Stable32 table: `AF Tau # Alpha MinSigma Sigma MaxSigma`.
#[derive(Debug, Clone, Copy)]
pub struct Stable32Row {
    pub af: u64,
    pub tau: f64,
    pub n: u64,
    pub alpha: i32,
    pub min_sigma: f64,
    pub sigma: f64,
    pub max_sigma: f64,
}

/// Reads a Stable32 table (Latin-1 text, `#` header lines).
pub fn read_stable32(path: &Path) -> Vec<Stable32Row> {
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let text: String = bytes.iter().map(|&b| b as char).collect();
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| {
            let c: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(c.len(), 7, "{}: {l}", path.display());
            Stable32Row {
                af: c[0].parse().unwrap(),
                tau: c[1].parse().unwrap(),
                n: c[2].parse().unwrap(),
                alpha: c[3].parse().unwrap(),
                min_sigma: c[4].parse().unwrap(),
                sigma: c[5].parse().unwrap(),
                max_sigma: c[6].parse().unwrap(),
            }
        })
        .collect()
}

/// Half a unit in the last of `digits` significant digits of `printed`: the most a correctly
/// rounded print can differ from the value behind it.
pub fn half_unit(printed: f64, digits: i32) -> f64 {
    let exp = printed.abs().log10().floor() as i32;
    0.5 * 10f64.powi(exp - (digits - 1))
}
