//! The fuzz targets' entry points on the stable toolchain (`fuzz/harness.rs`, shared with the
//! cargo-fuzz targets of `fuzz/`): every input a fuzzer ever crashed on, kept in
//! `fuzz/regressions/TARGET/`, must now pass through its target; and the seeds the corpus
//! starts from (the shipped fixtures, descriptors, configs and a checkpoint written by the
//! binary) pass too, so the harness itself is exercised in CI and cannot rot.

use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "../../fuzz/harness.rs"]
mod harness;

/// A fuzz target's entry point.
type Target = fn(&[u8]);

const TARGETS: [(&str, Target); 5] = [
    ("frames", harness::frames),
    ("descriptor", harness::descriptor),
    ("checkpoint", harness::checkpoint),
    ("text", harness::text),
    ("configs", harness::configs),
];

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every input kept under `fuzz/regressions/TARGET/` (none yet: the first recorded run,
/// fuzz/README.md, found no crash), through its target.
fn replay_regressions() -> usize {
    let mut n = 0;
    for (target, run) in TARGETS {
        let dir = root().join("fuzz/regressions").join(target);
        let Ok(entries) = std::fs::read_dir(&dir) else {
            continue;
        };
        let mut files: Vec<PathBuf> = entries.map(|e| e.expect("entry").path()).collect();
        files.sort();
        for f in files {
            let bytes = std::fs::read(&f).expect("read");
            eprintln!("{target}: {}", f.display());
            run(&bytes);
            n += 1;
        }
    }
    n
}

#[test]
fn the_seeds_and_every_crash_input_pass_every_target() {
    // Frames: the head of every shipped capture, and a capture read as the wrong unit.
    let captures = root().join("fixtures/captures");
    for name in [
        "siu8_stand_5min_seed1.siu8",
        "kvh1750_stand_1min_seed1.kvh1750",
    ] {
        let b = std::fs::read(captures.join(name)).expect("fixture");
        harness::frames(&b[..b.len().min(20_000)]);
    }
    // Descriptors and configs: the shipped ones.
    for (_, text) in allanscope::frame::descriptor::BUILTIN {
        harness::descriptor(text.as_bytes());
    }
    for f in ["config/stand.toml", "config/models/siu8_stand.toml"] {
        harness::configs(&std::fs::read(root().join(f)).expect("config"));
    }
    // Text: a small csv with a header, a gap and a bad row.
    harness::text(b"time,g1,g2\n0,1,2\n1,,3\n2,x,4\n3,1e308,5\n4,6,7\n");
    // A checkpoint written by the binary, its body as the checkpoint target takes it.
    let body = &checkpoint_file()[32..];
    assert_eq!(harness::with_header(body), checkpoint_file());
    harness::checkpoint(body);
    eprintln!("{} regression inputs replayed", replay_regressions());
}

/// A checkpoint of `analyze` on a csv, written by the binary.
fn checkpoint_file() -> &'static [u8] {
    static B: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    B.get_or_init(|| {
        let dir = std::env::temp_dir().join(format!("allanscope-fuzzseed-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("dir");
        let csv: String = (0..2000)
            .map(|i| format!("{},{}\n", i % 7, i % 5))
            .collect();
        std::fs::write(dir.join("in.csv"), format!("g1,g2\n{csv}")).expect("write");
        let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
            .current_dir(&dir)
            .env("ALLANSCOPE_LOG", "off")
            .args([
                "analyze",
                "in.csv",
                "--tau0",
                "0.01",
                "--diagnose",
                "--out",
                "o.jsonl",
            ])
            .args(["--checkpoint-every", "1"])
            .output()
            .expect("run");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let b = std::fs::read(dir.join("o.jsonl.ckpt")).expect("checkpoint");
        let _ = std::fs::remove_dir_all(&dir);
        b
    })
}
