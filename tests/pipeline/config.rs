//! `run --config`: the shipped example parses; a bad config exits 2 naming the file, each bad
//! key and its problem (all of them at once); a config replaying a capture gives the records
//! `analyze` gives.

use std::path::Path;
use std::process::Command;

use crate::common::pipeline::*;
use allanscope::source::SourceSpec;
use allanscope::stand::StandConfig;

fn tmp(name: &str) -> std::path::PathBuf {
    crate::common::fresh_dir("config").join(name)
}

#[test]
fn shipped_example_parses() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/stand.toml");
    let cfg = StandConfig::load(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        cfg.units[0].source,
        SourceSpec::Serial {
            path: "/dev/ttyUSB0".into(),
            baud: 230_400
        }
    );
    assert_eq!(cfg.units[0].format, "siu8");
    // 3 h and 60 s as written in the example.
    assert_eq!(cfg.duration_s, Some(10_800.0));
    assert_eq!(cfg.every_s, Some(60.0));
    assert_eq!(cfg.checkpoint_every_s, Some(300.0));
    // The four [[limits]] tables, each a valid limit spec that knows the line of its channel.
    assert_eq!(cfg.units[0].limits.len(), 4);
    assert_eq!(cfg.units[0].limits[0].channel, "g4");
    assert_eq!(cfg.units[0].limits[3].channel, "g*");
    assert_eq!(cfg.units[0].limits[3].unit.as_deref(), Some("deg/sqrt(h)"));
    let lines: Vec<Option<usize>> = cfg.units[0]
        .limits
        .iter()
        .map(|l| l.origin.as_ref().and_then(|o| o.line))
        .collect();
    assert_eq!(lines, [Some(52), Some(57), Some(62), Some(67)]);
}

#[test]
fn bad_config_exits_2_naming_file_keys_and_problems() {
    let path = tmp("bad_stand.toml");
    std::fs::write(
        &path,
        r#"
[source]
kind = "udp"
address = "127.0.0.1:5000"
format = "siu8"
baud = 9600

[statistics]
stats = ["avar", "adev"]
overlap = -3

[output]
file = "x.jsonl"
"#,
    )
    .expect("write");
    let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .args(["run", "--config", path.to_str().expect("utf-8")])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    eprintln!("{err}");
    assert_eq!(out.status.code(), Some(2));
    assert!(
        err.contains("4 problems"),
        "all four problems reported together"
    );
    for (key, problem) in [
        ("source.baud", "only for kind = \"serial\""),
        ("statistics.stats", "unknown statistic \"adev\""),
        (
            "statistics.overlap",
            "expected \"full\" or an integer L >= 1",
        ),
        ("output.file", "unknown key"),
    ] {
        let line = err
            .lines()
            .find(|l| l.contains(&format!("key `{key}`")))
            .unwrap_or_else(|| panic!("no line for {key}"));
        assert!(
            line.contains(path.to_str().expect("utf-8")),
            "{key}: file named"
        );
        assert!(line.contains(problem), "{key}: problem stated: {line}");
    }
}

#[test]
fn syntax_error_names_the_line() {
    let path = tmp("syntax.toml");
    std::fs::write(&path, "[source]\nkind = \"file\"\npath = \n").expect("write");
    let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .args(["run", "--config", path.to_str().expect("utf-8")])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2));
    // The value is missing on line 3.
    assert!(err.contains("syntax.toml:3: key `(syntax)`"), "{err}");
    // Given once, not repeated by the error chain.
    assert_eq!(err.matches("not valid TOML").count(), 1, "{err}");
}

#[test]
fn file_config_gives_the_records_of_analyze() {
    let capture = fixtures().join("captures/siu8_stand_5min_seed1.siu8");
    let out_path = tmp("run_out.jsonl");
    let cfg = tmp("replay.toml");
    std::fs::write(
        &cfg,
        format!(
            "[source]\nkind = \"file\"\npath = {:?}\nformat = \"siu8\"\n\n[statistics]\nstats = [\"avar\", \"mvar\"]\n\n[channels]\ninclude = [\"g4\", \"a4\"]\n\n[output]\npath = {:?}\n",
            capture.to_str().expect("utf-8"),
            out_path.to_str().expect("utf-8")
        ),
    )
    .expect("write");
    let run = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .args(["run", "--config", cfg.to_str().expect("utf-8")])
        .output()
        .expect("run");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let got = parse_lines(&std::fs::read(&out_path).expect("output"));
    let analyze = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .args([
            "analyze",
            capture.to_str().expect("utf-8"),
            "--format",
            "siu8",
            "--stats",
            "avar,mvar",
            "--channels",
            "g4,a4",
        ])
        .output()
        .expect("analyze");
    assert!(analyze.status.success());
    let want = parse_lines(&analyze.stdout);
    // 2 channels x (2 curves + 1 fit).
    assert_eq!(final_curves_and_fits(&want).len(), 6);
    assert_eq!(final_curves_and_fits(&got), final_curves_and_fits(&want));
    assert_eq!(last_of(&got, "health")["frames"], 75_000);
}

#[test]
fn run_metrics_key_takes_a_port_or_an_address_and_names_a_bad_one() {
    let base = "[source]\nkind = \"udp\"\naddress = \"127.0.0.1:5000\"\nformat = \"siu8\"\n[run]\n";
    let load = |m: &str| {
        allanscope::stand::StandConfig::from_toml_str(
            &format!("{base}metrics = {m}\n"),
            Path::new("lab.toml"),
        )
    };
    let port = load("9464").expect("a port");
    assert_eq!(port.metrics, Some(([127, 0, 0, 1], 9464).into()));
    let addr = load("\"0.0.0.0:9100\"").expect("an address");
    assert_eq!(addr.metrics, Some(([0, 0, 0, 0], 9100).into()));
    for bad in ["\"localhost\"", "70000", "true"] {
        let e = load(bad).expect_err(bad).to_string();
        assert!(
            e.contains("run.metrics") && e.contains("lab.toml"),
            "{bad}: {e}"
        );
    }
}

#[test]
fn a_bad_metrics_option_exits_2() {
    let fixture =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/captures/siu8_stand_5min_seed1.siu8");
    let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .args([
            "analyze",
            fixture.to_str().expect("utf-8"),
            "--format",
            "siu8",
        ])
        .args(["--metrics", "nowhere"])
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--metrics") && err.contains("nowhere"),
        "{err}"
    );
    assert!(
        out.stdout.is_empty(),
        "nothing analysed before the option is checked"
    );
}
