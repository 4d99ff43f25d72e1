//! Malformed inputs, one table: option values, frame descriptors, stand configs, model files,
//! limits files, checkpoints and input files, each run through the real binary. Every one must
//! end with exit status 2 and exactly the message written here (logging off, so standard error
//! holds only the error): the file, line and key or the option, and what is wrong, once.
//!
//! `ALLANSCOPE_BLESS=1 cargo test --release --test cli malformed -- --nocapture` prints the
//! messages the binary gives now, to review when a message is changed on purpose.

use std::path::{Path, PathBuf};
use std::process::Command;

const SIU8: &str = include_str!("../../config/frames/siu8.toml");
const MODEL: &str = include_str!("../../config/models/siu8_stand.toml");

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

/// The output of an earlier run, which a refused `--resume` must leave as it is.
fn earlier() -> (&'static str, Vec<u8>) {
    text("o.jsonl", "{\"type\":\"curve\",\"channel\":\"g1\"}\n")
}

fn small_csv() -> (&'static str, Vec<u8>) {
    text("small.csv", "g1,g2\n1,2\n3,4\n5,6\n7,8\n")
}

/// A stand config reading a capture file, with `extra` appended.
fn stand(extra: &str) -> (&'static str, Vec<u8>) {
    text(
        "stand.toml",
        &format!("[source]\nkind = \"file\"\npath = \"cap.siu8\"\nformat = \"siu8\"\n{extra}"),
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
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        std::fs::read(dir.join("o.jsonl.ckpt")).expect("checkpoint written")
    })
    .clone()
}

fn scratch(tag: &str) -> PathBuf {
    // Emptied at each call (a case writes exactly its own files).
    let d = crate::common::fresh_dir(&format!("malformed-{tag}"));
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
        "analyze",
        "small.csv",
        "--tau0",
        "1",
        "--out",
        "o.jsonl",
        "--resume",
    ];
    vec![
        // Option values.
        case("tau0 huge", vec![small_csv()], &["analyze", "small.csv", "--tau0", "1e308"], "allanscope: error: invalid value '1e308' for '--tau0 <TAU0>': 1e308: must be a number of seconds from 1e-9 to 1e6\n\nFor more information, try '--help'."),
        case("tau0 zero", vec![small_csv()], &["analyze", "small.csv", "--tau0", "0"], "allanscope: error: invalid value '0' for '--tau0 <TAU0>': 0: must be a number of seconds from 1e-9 to 1e6\n\nFor more information, try '--help'."),
        case("tau0 text", vec![small_csv()], &["analyze", "small.csv", "--tau0", "fast"], "allanscope: error: invalid value 'fast' for '--tau0 <TAU0>': `fast` is not a number\n\nFor more information, try '--help'."),
        case("tau0 missing", vec![small_csv()], &["analyze", "small.csv"], "allanscope: small.csv: --tau0 is required: the text columns have no time column (a header name time, t, timestamp or time_s, with or without a unit, or --time-column NAME)"),
        case("every tiny", vec![capture()], &["analyze", "cap.siu8", "--format", "siu8", "--every", "1e-300"], "allanscope: error: invalid value '1e-300' for '--every <EVERY>': 1e-300: must be a number of seconds from 0.001 to 1e9\n\nFor more information, try '--help'."),
        case("every huge", vec![capture()], &["analyze", "cap.siu8", "--format", "siu8", "--every", "1e20"], "allanscope: error: invalid value '1e20' for '--every <EVERY>': 1e20: must be a number of seconds from 0.001 to 1e9\n\nFor more information, try '--help'."),
        case("every nan", vec![capture()], &["analyze", "cap.siu8", "--format", "siu8", "--every", "NaN"], "allanscope: error: invalid value 'NaN' for '--every <EVERY>': NaN: must be a number of seconds from 0.001 to 1e9\n\nFor more information, try '--help'."),
        case("checkpoint-every tiny", vec![capture()], &["analyze", "cap.siu8", "--format", "siu8", "--checkpoint-every", "1e-300", "--out", "o.jsonl"], "allanscope: error: invalid value '1e-300' for '--checkpoint-every <S>': 1e-300: must be a number of seconds from 0.001 to 1e9\n\nFor more information, try '--help'."),
        case("checkpoint-every huge", vec![], &["listen", "--udp", "127.0.0.1:9", "--format", "siu8", "--checkpoint-every", "1e20", "--out", "o.jsonl"], "allanscope: error: invalid value '1e20' for '--checkpoint-every <S>': 1e20: must be a number of seconds from 0.001 to 1e9\n\nFor more information, try '--help'."),
        case("listen duration huge", vec![], &["listen", "--udp", "127.0.0.1:9", "--format", "siu8", "--duration", "1e20"], "allanscope: --duration `1e20` is 1.000e20 s: must be from 0 to 1e9 s"),
        case("listen duration 1e300d", vec![], &["listen", "--udp", "127.0.0.1:9", "--format", "siu8", "--duration", "1e300d"], "allanscope: --duration `1e300d` is 8.640e304 s: must be from 0 to 1e9 s"),
        case("listen duration unit", vec![], &["listen", "--udp", "127.0.0.1:9", "--format", "siu8", "--duration", "3 weeks"], "allanscope: --duration `3 weeks`: expected a positive number of seconds, or one with s, min, h or d"),
        case("taus zero", vec![small_csv()], &["analyze", "small.csv", "--tau0", "1", "--taus", "0,1"], "allanscope: --taus `0,1`: expected octave, decade or a comma list of cluster sizes m >= 1"),
        case("overlap zero", vec![small_csv()], &["analyze", "small.csv", "--tau0", "1", "--overlap", "0"], "allanscope: --overlap `0`: expected `full` or an integer L >= 1"),
        case("stats unknown", vec![small_csv()], &["analyze", "small.csv", "--tau0", "1", "--stats", "tdev"], "allanscope: --stats: unknown statistic `tdev` (allowed: avar, hvar, mvar)"),
        case("channels unknown", vec![small_csv()], &["analyze", "small.csv", "--tau0", "1", "--channels", "g9"], "allanscope: --channels: `g9` is not a channel of small.csv (it has: g1, g2)"),
        case("listen text columns", vec![], &["listen", "--udp", "127.0.0.1:9"], "allanscope: listen reads frames: give --format NAME (siu8, kvh1750, hg4930 or a descriptor file)"),
        case("simulate duration 1e300d", vec![], &["simulate", "--model", "m.toml", "--duration", "1e300d", "-o", "x.csv"], "allanscope: --duration `1e300d` is 8.640e304 s: must be from 0 to 1e9 s"),
        case("simulate too big", vec![text("m.toml", MODEL)], &["simulate", "--model", "m.toml", "--duration", "1000d", "--format", "siu8", "-o", "x.siu8"], "allanscope: --duration 1000d: 2.160e10 steps of 42 bytes would write about 9.072e11 bytes, more than the 64 GiB one simulated file may hold; simulate a shorter run"),
        case("simulate exists", vec![text("m.toml", MODEL), text("x.csv", "keep me\n")], &["simulate", "--model", "m.toml", "--duration", "1", "-o", "x.csv"], "allanscope: x.csv: exists; give --force to replace it, or another -o"),
        // Input files.
        case("input missing", vec![], &["analyze", "nothere.csv", "--tau0", "1"], "allanscope: nothere.csv: cannot open: No such file or directory (os error 2)"),
        case("input directory", vec![text("sub/keep", "")], &["analyze", "sub", "--tau0", "1"], "allanscope: sub: is a directory, not an input file"),
        case("binary read as text", vec![capture()], &["analyze", "cap.siu8", "--tau0", "1"], "allanscope: cap.siu8: binary data, not text columns; for a capture of frames give --format NAME (siu8, kvh1750, kvh1750b, hg4930)"),
        case("text read as frames", vec![small_csv()], &["analyze", "small.csv", "--format", "siu8"], "allanscope: small.csv: text, not siu8 frames; for text columns give --format csv with --tau0"),
        case("frames of another unit", vec![("cap.bin", std::fs::read(fixtures().join("kvh1750_stand_1min_seed1.kvh1750")).expect("fixture"))], &["analyze", "cap.bin", "--format", "siu8"], "allanscope: cap.bin: no siu8 frame found in 1048576 bytes: is it a siu8 capture? (another unit's frames need their --format; text columns need --format csv)"),
        // Binary data that holds no frame: refused before the run starts, so a forced --out
        // keeps the earlier result (the folder check below).
        case("binary garbage as frames over an earlier result", vec![("noise.bin", (0..5000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8).collect()), earlier()], &["analyze", "noise.bin", "--format", "siu8", "--out", "o.jsonl", "--force"], "allanscope: noise.bin: no siu8 frame found in 5000 bytes: is it a siu8 capture? (another unit's frames need their --format; text columns need --format csv)"),
        case("diagnose binary garbage as frames", vec![("noise.bin", (0..5000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8).collect())], &["diagnose", "noise.bin", "--format", "siu8"], "allanscope: noise.bin: no siu8 frame found in 5000 bytes: is it a siu8 capture? (another unit's frames need their --format; text columns need --format csv)"),
        case("diagnose of a run too short for any channel", vec![text("ten.csv", "g4\n1\n2\n3\n4\n5\n6\n7\n8\n9\n10\n")], &["diagnose", "ten.csv", "--tau0", "0.004"], "allanscope: ten.csv: no channel could be diagnosed (see the warnings above)"),
        case("report of an empty file", vec![text("e.jsonl", "")], &["report", "e.jsonl", "-o", "r.html"], "allanscope: e.jsonl: no allanscope record in it (curve, fit, diagnosis, health, aggregate, summary); give the JSON lines of `analyze`, `listen`, `run` or `diagnose`"),
        case("binary garbage as frames to a new output", vec![("noise.bin", (0..5000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8).collect())], &["analyze", "noise.bin", "--format", "siu8", "--out", "new.jsonl"], "allanscope: noise.bin: no siu8 frame found in 5000 bytes: is it a siu8 capture? (another unit's frames need their --format; text columns need --format csv)"),
        case("300 columns", vec![text("wide.csv", &(long_header + "1\n"))], &["analyze", "wide.csv", "--tau0", "1"], "allanscope: wide.csv: 301 channels; at most 256 are analysed in one run (choose some with --channels, or check the column separator)"),
        case("plot input missing", vec![], &["plot", "nothere.jsonl", "-o", "x.svg"], "allanscope: nothere.jsonl: cannot open: No such file or directory (os error 2)"),
        case("plot input binary", vec![capture()], &["plot", "cap.siu8", "-o", "x.svg"], "allanscope: cap.siu8: line 1: not text (stream did not contain valid UTF-8); give a file of JSON lines written by allanscope"),
        // Inputs the project had not met before (session 10, docs/robustness.md).
        case("text with bare CR line ends", vec![text("cr.csv", "g1,g2\r1,2\r3,4\r")], &["analyze", "cr.csv", "--tau0", "1"], "allanscope: cr.csv: line 1: the lines end with a bare carriage return (CR, no line feed): convert the file to LF or CRLF line ends first, e.g. `tr '\\r' '\\n' < IN > OUT`"),
        case("only values beyond 1e15", vec![text("big.csv", "g1\n1e300\n9223372036854775807\n-2e20\n")], &["analyze", "big.csv", "--tau0", "1"], "allanscope: big.csv: line 4: no samples: 3 values are numbers beyond 1e15 or non-zero below 1e-100 in magnitude, or infinite, taken as gaps, and the others are empty, nan or not numbers (are the columns raw counts of a wider type, or time stamps? pick the data columns with --columns; values that small need a larger unit)"),
        case("UTF-16 text", vec![("u16.csv", utf16("g1,g2\n1,2\n3,4\n"))], &["analyze", "u16.csv", "--tau0", "1"], "allanscope: u16.csv: UTF-16 text (as Windows tools write it); convert it to UTF-8 first, e.g. `iconv -f UTF-16 -t UTF-8 u16.csv > OUT.csv`"),
        case("gzip text columns", vec![("s.csv.gz", gzip(&small_csv().1))], &["analyze", "s.csv.gz", "--tau0", "1"], "allanscope: s.csv.gz: gzip-compressed; decompress it first, or read it through a pipe: `zcat s.csv.gz | allanscope ... -` (standard input)"),
        // Without --tau0 the look for a time column refused it as having none (session 33).
        case("gzip text columns, no --tau0", vec![("s.csv.gz", gzip(&small_csv().1))], &["diagnose", "s.csv.gz"], "allanscope: s.csv.gz: gzip-compressed; decompress it first, or read it through a pipe: `zcat s.csv.gz | allanscope ... -` (standard input)"),
        case("gzip capture", vec![("cap.siu8.gz", gzip(&capture().1[..200_000]))], &["analyze", "cap.siu8.gz", "--format", "siu8"], "allanscope: cap.siu8.gz: gzip-compressed; decompress it first, or read it through a pipe: `zcat cap.siu8.gz | allanscope ... -` (standard input)"),
        // Containers handed over in place of text columns (session 31): what it is, and how to get columns out.
        case("an Excel workbook", vec![("run.xlsx", b"PK\x03\x04\x14\x00\x06\x00\x08\x00\x00\x00!\x00[Content_Types].xml".to_vec())], &["analyze", "run.xlsx", "--tau0", "1"], "allanscope: run.xlsx: a ZIP archive (an Excel .xlsx or LibreOffice .ods workbook is one), not text columns or a capture of frames; save the sheet as CSV (File > Save As > CSV) and analyse that"),
        case("a ROS 1 bag", vec![("imu.bag", [b"#ROSBAG V2.0\n".to_vec(), vec![0u8; 64]].concat())], &["diagnose", "imu.bag", "--tau0", "0.005"], "allanscope: imu.bag: a ROS 1 bag, not text columns or a capture of frames; export the IMU topic first: `rostopic echo -b F -p /imu > imu.csv` (README, ROS 1)"),
        case("a PX4 ULog", vec![("log.ulg", [b"ULog\x01\x12\x35\x01".to_vec(), vec![0u8; 64]].concat())], &["analyze", "log.ulg", "--format", "siu8"], "allanscope: log.ulg: a PX4 ULog, not text columns or a capture of frames; convert it with pyulog's `ulog2csv F` and analyse the sensor_combined CSV with --tau0 (README, PX4)"),
        case("empty capture", vec![text("e.siu8", "")], &["analyze", "e.siu8", "--format", "siu8"], "allanscope: e.siu8: empty (0 bytes): no siu8 frame to analyse"),
        case("directory as a capture", vec![text("sub/keep", "")], &["analyze", "sub", "--format", "siu8"], "allanscope: sub: is a directory, not an input file"),
        case("a header line of 2 MiB", vec![text("wide.csv", &("g".repeat(2 << 20) + "\n1\n"))], &["analyze", "wide.csv", "--tau0", "1"], "allanscope: wide.csv: line 1: a line longer than 1 MiB: not text columns (a capture of frames needs --format NAME)"),
        case("standard input twice", vec![], &["analyze", "-", "-", "--tau0", "1"], "allanscope: standard input `-` is given twice, but it can be read only once (each input is one run)"),
        case("report into a missing folder", vec![earlier()], &["report", "o.jsonl", "-o", "none/r.html"], "allanscope: -o none/r.html: the folder none does not exist; create it first"),
        case("plot into a directory", vec![earlier(), text("sub/keep", "")], &["plot", "o.jsonl", "-o", "sub"], "allanscope: -o sub: is a directory; give a file name"),
        case("export into a missing folder", vec![earlier()], &["export", "o.jsonl", "--to", "csv", "-o", "none/x.csv"], "allanscope: -o none/x.csv: the folder none does not exist; create it first"),
        case("simulate into a missing folder", vec![text("m.toml", MODEL)], &["simulate", "--model", "m.toml", "--duration", "1", "-o", "none/x.csv"], "allanscope: -o none/x.csv: the folder none does not exist; create it first"),
        case("aggregate over an earlier result", vec![("r.jsonl", results()), text("keep.jsonl", "keep\n")], &["aggregate", "r.jsonl", "--out", "keep.jsonl"], "allanscope: aggregate --out keep.jsonl: exists and holds 5 bytes (an earlier result?); pass --force to overwrite it"),
        case("export of another version's records", vec![("r.jsonl", String::from_utf8(results()).unwrap().replace("\"sigma\"", "\"sigmas\"").into_bytes())], &["export", "r.jsonl", "--to", "csv", "-o", "x.csv"], "allanscope: r.jsonl: line 1: a curve record that does not read (missing field `sigma`): a file written by another version of allanscope? rerun the analysis"),
        // Frame descriptors.
        case("descriptor rate tiny", vec![capture(), siu8_with("rate_hz = 250.0", "rate_hz = 1e-306")], &["analyze", "cap.siu8", "--format", "./d.toml"], "allanscope: frame descriptor: 1 problem\n  ./d.toml:6: key `rate_hz`: must be from 1e-6 to 1e9 Hz, found 1e-306"),
        case("descriptor rate huge", vec![capture(), siu8_with("rate_hz = 250.0", "rate_hz = 1e308")], &["analyze", "cap.siu8", "--format", "./d.toml"], "allanscope: frame descriptor: 1 problem\n  ./d.toml:6: key `rate_hz`: must be from 1e-6 to 1e9 Hz, found 1e308"),
        case("descriptor scale huge", vec![capture(), siu8_with("scale = 0.004", "scale = 1e308")], &["analyze", "cap.siu8", "--format", "./d.toml"], "allanscope: frame descriptor: 1 problem\n  ./d.toml:39: key `channels[0].scale`: 1e308: the magnitude must be from 1e-20 to 1e20 units per LSB"),
        case("descriptor scale tiny", vec![capture(), siu8_with("scale = 0.004", "scale = 1e-300")], &["analyze", "cap.siu8", "--format", "./d.toml"], "allanscope: frame descriptor: 1 problem\n  ./d.toml:39: key `channels[0].scale`: 1e-300: the magnitude must be from 1e-20 to 1e20 units per LSB"),
        case("descriptor length huge", vec![capture(), siu8_with("length = 42", "length = 9223372036854775807")], &["analyze", "cap.siu8", "--format", "./d.toml"], "allanscope: frame descriptor: 1 problem\n  ./d.toml:8: key `length`: 9223372036854775807 bytes: a message may have at most 65536 bytes"),
        case("descriptor overlapping fields", vec![capture(), siu8_with("offset = 8\n", "offset = 6\n")], &["analyze", "cap.siu8", "--format", "./d.toml"], "allanscope: frame descriptor: 1 problem\n  ./d.toml:44: key `channels[1]`: bytes 6..9 overlap channels[0] (bytes 4..7)"),
        case("descriptor unknown key", vec![capture(), siu8_with("rate_hz = 250.0", "rate_hz = 250.0\ncolour = \"red\"")], &["analyze", "cap.siu8", "--format", "./d.toml"], "allanscope: frame descriptor: 1 problem\n  ./d.toml:7: key `colour`: unknown key (allowed here: name, description, rate_hz, byte_order, sync, length, checksum, counter, status, temperature, channels)"),
        case("descriptor two problems", vec![capture(), siu8_with("type = \"u16\"\nmodulus", "type = \"u17\"\nmodulus").1.pipe(|b| text("d.toml", &String::from_utf8(b).unwrap().replacen("kind = \"increment\"", "kind = \"velocity\"", 1)))], &["analyze", "cap.siu8", "--format", "./d.toml"], "allanscope: frame descriptor: 2 problems\n  ./d.toml:21: key `counter.type`: unknown type `u17` (allowed: u8, i8, u16, i16, u32, i32, f32, f64)\n  ./d.toml:41: key `channels[0].kind`: unknown kind `velocity` (allowed: increment, rate, accel_g)"),
        case("descriptor syntax", vec![capture(), text("d.toml", "rate_hz = = 3\n")], &["analyze", "cap.siu8", "--format", "./d.toml"], "allanscope: frame descriptor: 1 problem\n  ./d.toml:1: key `(syntax)`: not valid TOML: extra `=`, expected nothing"),
        case("descriptor missing file", vec![capture()], &["analyze", "cap.siu8", "--format", "./none.toml"], "allanscope: frame descriptor: 1 problem\n  ./none.toml: key `(file)`: cannot read: No such file or directory (os error 2)"),
        case("descriptor 300 channels", vec![capture(), text("d.toml", &many_channels(300))], &["analyze", "cap.siu8", "--format", "./d.toml"], "allanscope: frame descriptor: 1 problem\n  ./d.toml:9: key `channels`: 300 channels: at most 256 are analysed in one run"),
        // Stand configs.
        case("stand duration 1e300d", vec![capture(), stand("[run]\nduration = \"1e300d\"\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:6: key `run.duration`: `1e300d` is 8.640e304 s: must be from 0 to 1e9 s"),
        case("stand every tiny", vec![capture(), stand("[run]\nevery_s = 1e-300\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:6: key `run.every_s`: 1e-300: must be a number of seconds from 0.001 to 1e9"),
        case("stand checkpoint negative", vec![capture(), stand("[run]\ncheckpoint_every = -1\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:6: key `run.checkpoint_every`: -1: must be a number of seconds from 0.001 to 1e9"),
        case("stand two problems", vec![capture(), stand("[statistics]\nstats = [\"adev\"]\noverlap = 0\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 2 problems\n  stand.toml:6: key `statistics.stats`: unknown statistic \"adev\" (allowed: avar, hvar, mvar)\n  stand.toml:7: key `statistics.overlap`: 0: expected \"full\" or an integer L >= 1"),
        case("stand no source", vec![text("stand.toml", "[run]\nevery_s = 10\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml: key `source`: missing: the [source] table (or [[unit]] tables)"),
        case("stand syntax", vec![text("stand.toml", "[source]\nkind = \"file\"\npath = \n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:3: key `(syntax)`: not valid TOML: string values must be quoted, expected literal string"),
        case("stand limit key", vec![capture(), stand("[[limits]]\nchannel = \"g4\"\ncoef = \"N\"\nmax = 1\ncolour = 1\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:9: key `limits[0].colour`: unknown key (allowed here: channel, coef, max, min, unit, over)"),
        case("stand limit no channel", vec![capture(), stand("[[limits]]\nchannel = \"g9\"\ncoef = \"N\"\nmax = 1\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:6: key `limits[0].channel`: `g9` matches no channel of cap.siu8 (it has: g1, g2, g3, g4, a1, a2, a3, a4)"),
        case("stand limit two problems", vec![capture(), stand("[[limits]]\nchannel = \"g4\"\ncoef = \"Z\"\nmax = \"big\"\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 2 problems\n  stand.toml:7: key `limits[0].coef`: unknown coefficient `Z` (allowed: Q, N, B, K, R)\n  stand.toml:8: key `limits[0].max`: expected a number, found string"),
        case("stand limit no bound", vec![capture(), stand("[[limits]]\nchannel = \"g4\"\ncoef = \"N\"\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:5: key `limits[0].max`: a limit needs `max` or `min`"),
        case("stand limit unit", vec![capture(), stand("[[limits]]\nchannel = \"g4\"\ncoef = \"N\"\nmax = 1\nunit = \"furlong\"\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:9: key `limits[0].unit`: unknown unit `furlong`"),
        case("stand limits not tables", vec![capture(), text("stand.toml", "limits = 3\n[source]\nkind = \"file\"\npath = \"cap.siu8\"\nformat = \"siu8\"\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:1: key `limits`: must be an array of tables ([[limits]]), not 3"),
        case("stand format unknown", vec![capture(), text("stand.toml", "[source]\nkind = \"file\"\npath = \"cap.siu8\"\nformat = \"siu9\"\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:4: key `source.format`: unknown frame format `siu9`: no siu9.toml in config/frames, <crate>/config/frames and no built-in of that name (built-in: siu8, kvh1750, kvh1750b, hg4930)"),
        case("stand format bad descriptor", vec![capture(), siu8_with("rate_hz = 250.0", "rate_hz = 1e-306"), text("stand.toml", "[source]\nkind = \"file\"\npath = \"cap.siu8\"\nformat = \"./d.toml\"\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  ./d.toml:6: key `rate_hz`: must be from 1e-6 to 1e9 Hz, found 1e-306"),
        case("stand limit unit of another dimension", vec![capture(), stand("[[limits]]\nchannel = \"g4\"\ncoef = \"N\"\nmax = 1\nunit = \"m/s/sqrt(h)\"\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:9: key `limits[0].unit`: limit on N of `g4` (in arcsec): `m/s/sqrt(h)` is not a unit of N for a channel in arcsec"),
        case("stand channels unknown", vec![capture(), stand("[channels]\ninclude = [\"g1\", \"g9\"]\n")], &["run", "--config", "stand.toml"], "allanscope: stand.toml:6: key `channels.include`: `g9` is not a channel of cap.siu8 (it has: g1, g2, g3, g4, a1, a2, a3, a4)"),
        case("stand source missing", vec![text("stand.toml", "[source]\nkind = \"file\"\npath = \"none.siu8\"\nformat = \"siu8\"\n")], &["run", "--config", "stand.toml"], "allanscope: stand config: 1 problem\n  stand.toml:3: key `source.path`: no such file `none.siu8` (a relative path is taken from the working directory)"),
        // Relative to the working directory, not to the config's folder (src/stand/mod.rs).
        case("stand source beside the config", vec![("sub/cap.siu8", capture().1), text("sub/stand.toml", "[source]\nkind = \"file\"\npath = \"cap.siu8\"\nformat = \"siu8\"\n")], &["run", "--config", "sub/stand.toml"], "allanscope: stand config: 1 problem\n  sub/stand.toml:3: key `source.path`: no such file `cap.siu8` (a relative path is taken from the working directory)"),
        case("stand missing file", vec![], &["run", "--config", "none.toml"], "allanscope: stand config: 1 problem\n  none.toml: key `(file)`: cannot read: No such file or directory (os error 2)"),
        // Model files.
        case("model syntax", vec![text("m.toml", "rate_hz = \n")], &["simulate", "--model", "m.toml", "--duration", "10", "-o", "x.csv"], "allanscope: model file: 1 problem\n  m.toml:1: key `(syntax)`: not valid TOML: string values must be quoted, expected literal string"),
        case("model unknown key", vec![model_with("rate_hz = 250.0", "rate_hz = 250.0\ncolour = 1")], &["simulate", "--model", "m.toml", "--duration", "10", "-o", "x.csv"], "allanscope: model file: 1 problem\n  m.toml:8: key `colour`: unknown key (allowed: description, rate_hz, tau0_s, stand, temperature, channel)"),
        case("model two problems", vec![model_with("N = 0.254", "N = -1\nQ = \"x\"")], &["simulate", "--model", "m.toml", "--duration", "10", "-o", "x.csv"], "allanscope: model file: 2 problems\n  m.toml:24: key `channel[0].N`: must be >= 0, got -1\n  m.toml:25: key `channel[0].Q`: expected a number, found string"),
        case("model no rate", vec![model_with("rate_hz = 250.0\n", "")], &["simulate", "--model", "m.toml", "--duration", "10", "-o", "x.csv"], "allanscope: model file: 1 problem\n  m.toml: key `rate_hz`: missing (or give tau0_s)"),
        case("model channel not a table", vec![text("m.toml", "rate_hz = 100\nchannel = 3\n")], &["simulate", "--model", "m.toml", "--duration", "10", "-o", "x.csv"], "allanscope: model file: 1 problem\n  m.toml:2: key `channel`: expected a table or a list of tables, found integer"),
        // Limits files.
        case("limits unknown channel", vec![small_csv(), text("l.toml", "[[limits]]\nchannel = \"g9\"\ncoef = \"N\"\nmax = 1\n")], &["analyze", "small.csv", "--tau0", "1", "--limits", "l.toml"], "allanscope: limits file: 1 problem\n  l.toml:2: key `limits[0].channel`: `g9` matches no channel of small.csv (it has: g1, g2)"),
        case("limits not tables", vec![small_csv(), text("l.toml", "limits = 3\n")], &["analyze", "small.csv", "--tau0", "1", "--limits", "l.toml"], "allanscope: limits file: 1 problem\n  l.toml:1: key `limits`: expected an array of tables ([[limits]])"),
        case("limits bad coef", vec![small_csv(), text("l.toml", "[[limits]]\nchannel = \"g1\"\ncoef = \"Z\"\nmax = 1\n")], &["analyze", "small.csv", "--tau0", "1", "--limits", "l.toml"], "allanscope: limits file: 1 problem\n  l.toml:3: key `limits[0].coef`: unknown coefficient `Z` (allowed: Q, N, B, K, R)"),
        case("limits scope and bound", vec![small_csv(), text("l.toml", "[[limits]]\nchannel = \"g1\"\ncoef = \"N\"\nmax = inf\nover = \"weekly\"\n")], &["analyze", "small.csv", "--tau0", "1", "--limits", "l.toml"], "allanscope: limits file: 2 problems\n  l.toml:4: key `limits[0].max`: inf is not a finite number\n  l.toml:5: key `limits[0].over`: unknown scope `weekly` (allowed: run, runs_sd, runs_mean)"),
        case("limits no coef", vec![small_csv(), text("l.toml", "[[limits]]\nchannel = \"g1\"\nmax = 1\n")], &["analyze", "small.csv", "--tau0", "1", "--limits", "l.toml"], "allanscope: limits file: 1 problem\n  l.toml:1: key `limits[0].coef`: missing: Q, N, B, K or R"),
        // Checkpoints.
        case("checkpoint missing", vec![small_csv(), earlier()], &resume, "allanscope: checkpoint o.jsonl.ckpt: not found (nothing to resume: run without --resume to start)"),
        case("checkpoint bad magic", vec![small_csv(), earlier(), ("o.jsonl.ckpt", ck_magic)], &resume, "allanscope: checkpoint o.jsonl.ckpt: not an allanscope checkpoint (bad magic bytes)"),
        case("checkpoint bad crc", vec![small_csv(), earlier(), ("o.jsonl.ckpt", ck_crc)], &resume, "allanscope: checkpoint o.jsonl.ckpt: damaged: the CRC-32 of its contents does not match"),
        case("checkpoint other options", vec![small_csv(), earlier(), ("o.jsonl.ckpt", checkpoint_bytes())], &["analyze", "small.csv", "--tau0", "2", "--out", "o.jsonl", "--resume"], "allanscope: checkpoint o.jsonl.ckpt: saved with other options than given now (--tau0: saved 1.0 s, now 2.0 s); resume with the options of the saved run, or start a new run without --resume"),
        case("checkpoint other taus", vec![small_csv(), earlier(), ("o.jsonl.ckpt", checkpoint_bytes())], &["analyze", "small.csv", "--tau0", "1", "--taus", "1,2", "--out", "o.jsonl", "--resume"], "allanscope: checkpoint o.jsonl.ckpt: saved with other options than given now (--taus: saved [1, 2, ..., 1099511627776] (41 sizes), now [1, 2]); resume with the options of the saved run, or start a new run without --resume"),
    ]
}

/// `t` as UTF-16 little-endian text with its byte-order mark, as Windows tools save it.
fn utf16(t: &str) -> Vec<u8> {
    let mut b = vec![0xff, 0xfe];
    for u in t.encode_utf16() {
        b.extend_from_slice(&u.to_le_bytes());
    }
    b
}

fn gzip(bytes: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let mut e = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    e.write_all(bytes).expect("gzip");
    e.finish().expect("gzip")
}

/// The JSON lines of a real run (once per test process).
fn results() -> Vec<u8> {
    static R: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    R.get_or_init(|| {
        let csv: String = std::iter::once("g1\n".to_string())
            .chain((0..400u32).map(|i| format!("{}\n", (i.wrapping_mul(2_654_435_761) >> 20) % 97)))
            .collect();
        let dir = scratch("results-source");
        std::fs::write(dir.join("r.csv"), csv).expect("write");
        crate::common::stdout_of(
            crate::common::exe()
                .current_dir(&dir)
                .env("ALLANSCOPE_LOG", "off")
                .args(["analyze", "r.csv", "--tau0", "0.01", "--json"]),
        )
        .into_bytes()
    })
    .clone()
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
        // The descriptor search path names the crate's folder, wherever it is checked out.
        let err =
            String::from_utf8_lossy(&out.stderr).replace(env!("CARGO_MANIFEST_DIR"), "<crate>");
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
        // A refused command leaves the folder as it was (no empty outputs, no partial files, a
        // refused resume neither truncates the output nor touches the checkpoint).
        let after = listing(&dir);
        if after != before {
            failures.push(format!(
                "{}: files changed: {before:?} -> {after:?}",
                c.name
            ));
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

/// `listen --help` shows no `--format` default that `listen` refuses: it said `[default: csv]`
/// and "or `csv` for text columns", and `listen` given no `--format` (or `--format csv`) then
/// refused "listen reads frames". The refusal is kept (the table above); the help now says a
/// descriptor is required. `analyze --help` keeps its default, which analyze reads.
#[test]
fn listen_help_shows_no_format_default_it_refuses() {
    let help = |cmd: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
            .args([cmd, "--help"])
            .output()
            .expect("run");
        assert_eq!(out.status.code(), Some(0), "{cmd} --help");
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        text.lines()
            .find(|l| l.trim_start().starts_with("--format "))
            .unwrap_or_else(|| panic!("{cmd} --help has no --format: {text}"))
            .to_string()
    };
    let listen = help("listen");
    assert!(
        !listen.contains("[default:") && !listen.contains("csv"),
        "{listen}"
    );
    assert!(listen.contains("required"), "{listen}");
    let analyze = help("analyze");
    assert!(analyze.contains("[default: csv]"), "{analyze}");
}
