//! Malformed inputs, one table: option values, frame descriptors, stand configs, model files,
//! limits files, checkpoints and input files, each run through the real binary. Every one must
//! end with exit status 2 and exactly the message written here (logging off, so standard error
//! holds only the error): the file, line and key or the option, and what is wrong, once.
//!
//! `ALLANSCOPE_BLESS=1 cargo test --release --test cli_malformed -- --nocapture` prints the
//! messages the binary gives now, to review when a message is changed on purpose.

use std::path::{Path, PathBuf};
use std::process::Command;

const SIU8: &str = include_str!("../config/frames/siu8.toml");
const MODEL: &str = include_str!("../config/models/siu8_stand.toml");

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/captures")
}

/// One malformed input: the files it needs (name, bytes) in a fresh folder, the arguments run
/// there, and the exact standard error expected.
struct Case {
    name: &'static str,
    files: Vec<(&'static str, Vec<u8>)>,
    args: Vec<String>,
    stderr: &'static str,
}

fn case(
    name: &'static str,
    files: Vec<(&'static str, Vec<u8>)>,
    args: &[&str],
    stderr: &'static str,
) -> Case {
    Case {
        name,
        files,
        args: args.iter().map(|s| s.to_string()).collect(),
        stderr,
    }
}

fn text(name: &'static str, t: &str) -> (&'static str, Vec<u8>) {
    (name, t.as_bytes().to_vec())
}

/// The siu8 descriptor with `from` replaced by `to` (which must occur).
fn siu8_with(from: &str, to: &str) -> (&'static str, Vec<u8>) {
    assert!(SIU8.contains(from), "{from}");
    text("d.toml", &SIU8.replacen(from, to, 1))
}

/// The siu8 stand model with `from` replaced by `to`.
fn model_with(from: &str, to: &str) -> (&'static str, Vec<u8>) {
    assert!(MODEL.contains(from), "{from}");
    text("m.toml", &MODEL.replacen(from, to, 1))
}

fn capture() -> (&'static str, Vec<u8>) {
    (
        "cap.siu8",
        std::fs::read(fixtures().join("siu8_stand_5min_seed1.siu8")).expect("fixture"),
    )
}

fn small_csv() -> (&'static str, Vec<u8>) {
    text("small.csv", "g1,g2\n1,2\n3,4\n5,6\n7,8\n")
}

/// A stand config reading a capture file, with `extra` appended.
fn stand(extra: &str) -> (&'static str, Vec<u8>) {
    text(
        "stand.toml",
        &format!(
            "[source]\nkind = \"file\"\npath = \"cap.siu8\"\nformat = \"siu8\"\n{extra}"
        ),
    )
}

/// A checkpoint written by a real run (once per test process), for the damaged variants.
fn checkpoint_bytes() -> Vec<u8> {
    static CK: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    CK.get_or_init(|| {
        let dir = scratch("ckpt-source");
        std::fs::write(dir.join("small.csv"), small_csv().1).expect("write");
        let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
            .current_dir(&dir)
            .env("ALLANSCOPE_LOG", "off")
            .args([
                "analyze",
                "small.csv",
                "--tau0",
                "1",
                "--out",
                "o.jsonl",
                "--checkpoint-every",
                "1",
            ])
            .output()
            .expect("run");
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        std::fs::read(dir.join("o.jsonl.ckpt")).expect("checkpoint written")
    })
    .clone()
}

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("allanscope-malformed-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("scratch");
    d
}

fn cases() -> Vec<Case> {
    let long_header: String = (0..300).map(|i| format!("c{i},")).collect::<String>() + "x\n";
    let mut ck_magic = checkpoint_bytes();
    ck_magic[0] ^= 0xff;
    let mut ck_crc = checkpoint_bytes();
    let last = ck_crc.len() - 1;
    ck_crc[last] ^= 0x01;
    let resume = [
        "analyze", "small.csv", "--tau0", "1", "--out", "o.jsonl", "--resume",
    ];
    vec![
        // Option values.
        case("tau0 huge", vec![small_csv()], &["analyze", "small.csv", "--tau0", "1e308"], ""),
        case("tau0 zero", vec![small_csv()], &["analyze", "small.csv", "--tau0", "0"], ""),
        case("tau0 text", vec![small_csv()], &["analyze", "small.csv", "--tau0", "fast"], ""),
        case("tau0 missing", vec![small_csv()], &["analyze", "small.csv"], ""),
        case("every tiny", vec![capture()], &["analyze", "cap.siu8", "--format", "siu8", "--every", "1e-300"], ""),
        case("every huge", vec![capture()], &["analyze", "cap.siu8", "--format", "siu8", "--every", "1e20"], ""),
        case("every nan", vec![capture()], &["analyze", "cap.siu8", "--format", "siu8", "--every", "NaN"], ""),
        case("checkpoint-every tiny", vec![capture()], &["analyze", "cap.siu8", "--format", "siu8", "--checkpoint-every", "1e-300", "--out", "o.jsonl"], ""),
        case("checkpoint-every huge", vec![], &["listen", "--udp", "127.0.0.1:9", "--format", "siu8", "--checkpoint-every", "1e20", "--out", "o.jsonl"], ""),
        case("listen duration huge", vec![], &["listen", "--udp", "127.0.0.1:9", "--format", "siu8", "--duration", "1e20"], ""),
        case("listen duration 1e300d", vec![], &["listen", "--udp", "127.0.0.1:9", "--format", "siu8", "--duration", "1e300d"], ""),
        case("listen duration unit", vec![], &["listen", "--udp", "127.0.0.1:9", "--format", "siu8", "--duration", "3 weeks"], ""),
        case("taus zero", vec![small_csv()], &["analyze", "small.csv", "--tau0", "1", "--taus", "0,1"], ""),
        case("overlap zero", vec![small_csv()], &["analyze", "small.csv", "--tau0", "1", "--overlap", "0"], ""),
        case("stats unknown", vec![small_csv()], &["analyze", "small.csv", "--tau0", "1", "--stats", "tdev"], ""),
        case("channels unknown", vec![small_csv()], &["analyze", "small.csv", "--tau0", "1", "--channels", "g9"], ""),
        case("format unknown", vec![capture()], &["analyze", "cap.siu8", "--format", "siu9"], ""),
        case("simulate duration 1e300d", vec![], &["simulate", "--model", "m.toml", "--duration", "1e300d", "-o", "x.csv"], ""),
        case("simulate too big", vec![text("m.toml", MODEL)], &["simulate", "--model", "m.toml", "--duration", "1000d", "--format", "siu8", "-o", "x.siu8"], ""),
        case("simulate exists", vec![text("m.toml", MODEL), text("x.csv", "keep me\n")], &["simulate", "--model", "m.toml", "--duration", "1", "-o", "x.csv"], ""),
        // Input files.
        case("input missing", vec![], &["analyze", "nothere.csv", "--tau0", "1"], ""),
        case("input directory", vec![text("sub/keep", "")], &["analyze", "sub", "--tau0", "1"], ""),
        case("binary read as text", vec![capture()], &["analyze", "cap.siu8", "--tau0", "1"], ""),
        case("text read as frames", vec![small_csv()], &["analyze", "small.csv", "--format", "siu8"], ""),
        case("frames of another unit", vec![("cap.bin", std::fs::read(fixtures().join("kvh1750_stand_1min_seed1.kvh1750")).expect("fixture"))], &["analyze", "cap.bin", "--format", "siu8"], ""),
        case("300 columns", vec![text("wide.csv", &(long_header + "1\n"))], &["analyze", "wide.csv", "--tau0", "1"], ""),
        case("plot input missing", vec![], &["plot", "nothere.jsonl", "-o", "x.svg"], ""),
        case("plot input binary", vec![capture()], &["plot", "cap.siu8", "-o", "x.svg"], ""),
        // Frame descriptors.
        case("descriptor rate tiny", vec![capture(), siu8_with("rate_hz = 250.0", "rate_hz = 1e-306")], &["analyze", "cap.siu8", "--format", "./d.toml"], ""),
        case("descriptor rate huge", vec![capture(), siu8_with("rate_hz = 250.0", "rate_hz = 1e308")], &["analyze", "cap.siu8", "--format", "./d.toml"], ""),
        case("descriptor scale huge", vec![capture(), siu8_with("scale = 0.004", "scale = 1e308")], &["analyze", "cap.siu8", "--format", "./d.toml"], ""),
        case("descriptor scale tiny", vec![capture(), siu8_with("scale = 0.004", "scale = 1e-300")], &["analyze", "cap.siu8", "--format", "./d.toml"], ""),
        case("descriptor length huge", vec![capture(), siu8_with("length = 42", "length = 9223372036854775807")], &["analyze", "cap.siu8", "--format", "./d.toml"], ""),
        case("descriptor overlapping fields", vec![capture(), siu8_with("offset = 8\n", "offset = 6\n")], &["analyze", "cap.siu8", "--format", "./d.toml"], ""),
        case("descriptor unknown key", vec![capture(), siu8_with("rate_hz = 250.0", "rate_hz = 250.0\ncolour = \"red\"")], &["analyze", "cap.siu8", "--format", "./d.toml"], ""),
        case("descriptor two problems", vec![capture(), siu8_with("type = \"u16\"\nmodulus", "type = \"u17\"\nmodulus").1.pipe(|b| text("d.toml", &String::from_utf8(b).unwrap().replacen("kind = \"increment\"", "kind = \"velocity\"", 1)))], &["analyze", "cap.siu8", "--format", "./d.toml"], ""),
        case("descriptor syntax", vec![capture(), text("d.toml", "rate_hz = = 3\n")], &["analyze", "cap.siu8", "--format", "./d.toml"], ""),
        case("descriptor missing file", vec![capture()], &["analyze", "cap.siu8", "--format", "./none.toml"], ""),
        case("descriptor 300 channels", vec![capture(), text("d.toml", &many_channels(300))], &["analyze", "cap.siu8", "--format", "./d.toml"], ""),
        // Stand configs.
        case("stand duration 1e300d", vec![capture(), stand("[run]\nduration = \"1e300d\"\n")], &["run", "--config", "stand.toml"], ""),
        case("stand every tiny", vec![capture(), stand("[run]\nevery_s = 1e-300\n")], &["run", "--config", "stand.toml"], ""),
        case("stand checkpoint negative", vec![capture(), stand("[run]\ncheckpoint_every = -1\n")], &["run", "--config", "stand.toml"], ""),
        case("stand two problems", vec![capture(), stand("[statistics]\nstats = [\"adev\"]\noverlap = 0\n")], &["run", "--config", "stand.toml"], ""),
        case("stand no source", vec![text("stand.toml", "[run]\nevery_s = 10\n")], &["run", "--config", "stand.toml"], ""),
        case("stand syntax", vec![text("stand.toml", "[source]\nkind = \"file\"\npath = \n")], &["run", "--config", "stand.toml"], ""),
        case("stand limit key", vec![capture(), stand("[[limits]]\nchannel = \"g4\"\ncoef = \"N\"\nmax = 1\ncolour = 1\n")], &["run", "--config", "stand.toml"], ""),
        case("stand limit no channel", vec![capture(), stand("[[limits]]\nchannel = \"g9\"\ncoef = \"N\"\nmax = 1\n")], &["run", "--config", "stand.toml"], ""),
        case("stand missing file", vec![], &["run", "--config", "none.toml"], ""),
        // Model files.
        case("model syntax", vec![text("m.toml", "rate_hz = \n")], &["simulate", "--model", "m.toml", "--duration", "10", "-o", "x.csv"], ""),
        case("model unknown key", vec![model_with("rate_hz = 250.0", "rate_hz = 250.0\ncolour = 1")], &["simulate", "--model", "m.toml", "--duration", "10", "-o", "x.csv"], ""),
        case("model two problems", vec![model_with("N = 0.254", "N = -1\nQ = \"x\"")], &["simulate", "--model", "m.toml", "--duration", "10", "-o", "x.csv"], ""),
        // Limits files.
        case("limits unknown channel", vec![small_csv(), text("l.toml", "[[limits]]\nchannel = \"g9\"\ncoef = \"N\"\nmax = 1\n")], &["analyze", "small.csv", "--tau0", "1", "--limits", "l.toml"], ""),
        case("limits not tables", vec![small_csv(), text("l.toml", "limits = 3\n")], &["analyze", "small.csv", "--tau0", "1", "--limits", "l.toml"], ""),
        case("limits bad coef", vec![small_csv(), text("l.toml", "[[limits]]\nchannel = \"g1\"\ncoef = \"Z\"\nmax = 1\n")], &["analyze", "small.csv", "--tau0", "1", "--limits", "l.toml"], ""),
        // Checkpoints.
        case("checkpoint missing", vec![small_csv()], &resume, ""),
        case("checkpoint bad magic", vec![small_csv(), ("o.jsonl.ckpt", ck_magic)], &resume, ""),
        case("checkpoint bad crc", vec![small_csv(), ("o.jsonl.ckpt", ck_crc)], &resume, ""),
        case("checkpoint other options", vec![small_csv(), ("o.jsonl.ckpt", checkpoint_bytes())], &["analyze", "small.csv", "--tau0", "2", "--out", "o.jsonl", "--resume"], ""),
        case("checkpoint other taus", vec![small_csv(), ("o.jsonl.ckpt", checkpoint_bytes())], &["analyze", "small.csv", "--tau0", "1", "--taus", "1,2", "--out", "o.jsonl", "--resume"], ""),
    ]
}

/// A descriptor of `n` i16 channels after a 2-byte sync, with a CRC over them.
fn many_channels(n: usize) -> String {
    let len = 2 + 2 * n + 2;
    let mut t = format!(
        "rate_hz = 100.0\nlength = {len}\n[sync]\nbytes = [0xAA, 0x55]\n[checksum]\n\
         algorithm = \"CRC-16/XMODEM\"\nrange = [2, {}]\nat = {}\n",
        len - 3,
        len - 2
    );
    for i in 0..n {
        t += &format!(
            "[[channels]]\nname = \"c{i}\"\noffset = {}\ntype = \"i16\"\nscale = 1.0\n\
             unit = \"u\"\nkind = \"increment\"\n",
            2 + 2 * i
        );
    }
    t
}

trait Pipe: Sized {
    fn pipe<T>(self, f: impl FnOnce(Self) -> T) -> T {
        f(self)
    }
}
impl<T> Pipe for T {}

#[test]
fn every_malformed_input_is_a_usage_error_with_its_message() {
    let bless = std::env::var_os("ALLANSCOPE_BLESS").is_some();
    let all = cases();
    assert!(all.len() >= 40, "{} cases", all.len());
    let mut failures = Vec::new();
    for (i, c) in all.iter().enumerate() {
        let dir = scratch(&format!("case{i}"));
        for (name, bytes) in &c.files {
            let p = dir.join(name);
            std::fs::create_dir_all(p.parent().expect("parent")).expect("dir");
            std::fs::write(&p, bytes).expect("write");
        }
        let before: Vec<_> = listing(&dir);
        let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
            .current_dir(&dir)
            .env("ALLANSCOPE_LOG", "off")
            .args(&c.args)
            .output()
            .expect("run");
        let err = String::from_utf8_lossy(&out.stderr);
        let err = err.trim_end();
        if bless {
            println!("        // {}\n        {:?}", c.name, err);
        }
        if out.status.code() != Some(2) || err != c.stderr {
            failures.push(format!(
                "{}: status {:?}\n  got:  {err:?}\n  want: {:?}",
                c.name,
                out.status.code(),
                c.stderr
            ));
        }
        // A refused command leaves the folder as it was (no empty outputs, no partial files).
        let after = listing(&dir);
        if after != before {
            failures.push(format!("{}: files changed: {before:?} -> {after:?}", c.name));
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The folder's files with their sizes.
fn listing(dir: &Path) -> Vec<(String, u64)> {
    let mut v: Vec<(String, u64)> = std::fs::read_dir(dir)
        .expect("list")
        .map(|e| {
            let e = e.expect("entry");
            (
                e.file_name().to_string_lossy().into_owned(),
                e.metadata().map_or(0, |m| m.len()),
            )
        })
        .collect();
    v.sort();
    v
}
