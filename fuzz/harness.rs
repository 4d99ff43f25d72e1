//! The fuzzing entry points: what each target feeds through the library and what must hold
//! afterwards. Used by the cargo-fuzz targets (`fuzz/fuzz_targets/`, nightly and libFuzzer)
//! and, on the stable toolchain, by the regression test that replays every input a fuzzer ever
//! crashed on (`tests/pipeline/fuzz_regressions.rs`, inputs in `fuzz/regressions/TARGET/`).
//!
//! Every entry point takes arbitrary bytes. A refusal (an error value) is a fine outcome; a
//! panic, an unbounded loop or a broken invariant (asserted here) is a finding.
#![allow(dead_code)]

use std::io::Cursor;
use std::path::{Path, PathBuf};

use allanscope::allan::accum::AccumConfig;
use allanscope::analysis::{AnalysisOptions, ChannelSetup, InputKind, RunAnalysis};
use allanscope::frame::descriptor::BUILTIN;
use allanscope::frame::{Decoder, FrameDescriptor, FrameEvent};
use allanscope::input::text::{TextOptions, TextReader};
use allanscope::input::{Chunk, MAX_ABS_VALUE};
use allanscope::pipeline::checkpoint::{Checkpoint, Position, FORMAT_VERSION};

/// The crate's root (this file is compiled from `fuzz/` and from the crate's tests).
fn root() -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    if here.join("fixtures").is_dir() {
        here.to_path_buf()
    } else {
        here.join("..")
    }
}

/// The first 400 frames (1.6 s) of the siu8 fixture: data a restored decoder continues with.
fn siu8_frames() -> &'static [u8] {
    static B: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    B.get_or_init(|| {
        let b = std::fs::read(root().join("fixtures/captures/siu8_stand_5min_seed1.siu8"))
            .expect("the siu8 fixture");
        b[..400 * 42].to_vec()
    })
}

fn shipped() -> &'static [FrameDescriptor] {
    static D: std::sync::OnceLock<Vec<FrameDescriptor>> = std::sync::OnceLock::new();
    D.get_or_init(|| {
        BUILTIN
            .iter()
            .map(|(n, _)| {
                FrameDescriptor::builtin(n)
                    .expect("listed")
                    .expect("a shipped descriptor loads")
            })
            .collect()
    })
}

/// The options of a plain run (all statistics, octave taus, no fit), records every `every_s`
/// data-seconds.
fn options(tau0_s: f64, every_s: f64, diagnose: bool) -> AnalysisOptions {
    AnalysisOptions {
        accum: AccumConfig::new(tau0_s),
        kind: InputKind::Increments,
        every_s: Some(every_s),
        fit: None,
        run: None,
        limits: Vec::new(),
        diagnose,
    }
}

/// Whether this input also runs the diagnosis: one input in 16 (by its last byte). The
/// diagnosis on every input held libFuzzer to about 2 inputs per second (the recorded run of
/// 09:01); the decoder and the statistics are what untrusted bytes reach first, and every seed
/// and regression input still runs it in the stable test.
fn deep(data: &[u8]) -> bool {
    cfg!(not(fuzzing)) || data.last().is_some_and(|b| b % 16 == 0)
}

/// Every record is finite where the records promise numbers: serialising them must not fail.
fn check_records(records: &[allanscope::sink::records::Record]) {
    for r in records {
        serde_json::to_string(r).expect("a record serialises");
    }
}

/// Decodes `data` through every shipped descriptor, in pieces of a size taken from the first
/// byte, and analyses what it decoded. Checks: the decoder holds less than two messages, every
/// byte is accounted for (accepted or skipped), frames go forward and the gaps between them
/// equal the counter's steps, values are usable or missing, and the analysis gives records.
pub fn frames(data: &[u8]) {
    let piece = 1 + 3 * usize::from(data.first().copied().unwrap_or(0));
    for desc in shipped() {
        let max_len = desc.messages.iter().map(|m| m.length).max().unwrap_or(0);
        let mut dec = Decoder::new(desc.clone());
        let mut events = Vec::new();
        for part in data.chunks(piece) {
            dec.push(part);
            events.extend(dec.drain());
            assert!(dec.pending() < 2 * max_len, "{} bytes held", dec.pending());
        }
        dec.finish();
        events.extend(dec.drain());
        assert_eq!(dec.pending(), 0);
        let h = dec.health().clone();
        assert_eq!(h.bytes_in, data.len() as u64);
        assert_eq!(
            h.bytes_accepted + h.bytes_skipped,
            h.bytes_in,
            "{}: {h:?}",
            desc.name
        );
        let mut last: Option<u64> = None;
        let mut missing = 0u64;
        let mut frames = 0u64;
        for e in &events {
            match e {
                FrameEvent::Gap { missing: m } => missing += m,
                FrameEvent::Frame(f) => {
                    frames += 1;
                    if let Some(prev) = last {
                        assert!(f.seq > prev, "{}: seq {} after {prev}", desc.name, f.seq);
                        assert_eq!(f.seq - prev - 1, missing, "{}: gap", desc.name);
                    }
                    missing = 0;
                    last = Some(f.seq);
                    for v in f.values.iter().flatten() {
                        if let allanscope::frame::ChannelValue::Real(x) = v {
                            assert!(x.is_finite() && x.abs() <= MAX_ABS_VALUE, "value {x}");
                        }
                    }
                }
            }
        }
        assert_eq!(frames, h.frames, "{}: {h:?}", desc.name);
        assert!(frames * desc.frame_len() as u64 <= data.len() as u64);
        if frames > 0 {
            let channels = ChannelSetup::for_frames(desc);
            let mut run =
                RunAnalysis::new("fuzz", channels, options(desc.tau0_s(), 0.5, deep(data)));
            let mut out = Vec::new();
            run.push_chunk(&Chunk::Frames(events), &mut out);
            out.extend(run.records(true));
            check_records(&out);
        }
    }
}

/// Reads `data` as a frame descriptor's TOML. An accepted descriptor stays within the ranges
/// the decoder relies on (`allanscope::ranges`) and decodes any bytes (the siu8 frames and the
/// text itself).
pub fn descriptor(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(d) = FrameDescriptor::from_toml_str(text, Path::new("fuzz.toml")) else {
        return;
    };
    use allanscope::ranges::*;
    assert!((MIN_RATE_HZ..=MAX_RATE_HZ).contains(&d.rate_hz));
    assert!(d.frame().channels.len() <= MAX_CHANNELS);
    for m in &d.messages {
        assert!(m.length as u64 <= MAX_MESSAGE_BYTES);
    }
    for c in &d.frame().channels {
        assert!((MIN_SCALE..=MAX_SCALE).contains(&c.scale.abs()));
    }
    let mut dec = Decoder::new(d.clone());
    dec.push(siu8_frames());
    dec.push(data);
    dec.finish();
    let n = dec.drain().count() as u64;
    assert!(n <= (siu8_frames().len() + data.len()) as u64);
    assert_eq!(dec.pending(), 0);
}

/// Reads `data` as the body of a checkpoint file (CBOR) given a valid header and CRC, as a
/// forged or damaged file with a right CRC would be; a checkpoint that decodes is restored
/// and the run continued (its decoder fed more siu8 frames, or more text rows), then the
/// final records made. Every out-of-range index or count must be refused, not panic.
pub fn checkpoint(data: &[u8]) {
    let _ = resume(&with_header(data));
}

/// A checkpoint file around `body`: magic, format version, length and CRC-32 right.
pub fn with_header(body: &[u8]) -> Vec<u8> {
    let mut f = b"ALLANSCOPE-CKPT\n".to_vec();
    f.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    f.extend_from_slice(&(body.len() as u64).to_le_bytes());
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(body);
    f.extend_from_slice(&crc.to_le_bytes());
    f.extend_from_slice(body);
    f
}

fn resume(file: &[u8]) -> Result<usize, String> {
    let ck = Checkpoint::decode(file)?;
    let setups: Vec<ChannelSetup> = ck
        .analysis
        .channels
        .iter()
        .map(|c| c.setup.clone())
        .collect();
    let first = ck.analysis.channels.first().ok_or("no channels")?;
    let accum = first.acc.config().clone();
    allanscope::ranges::check_tau0(accum.tau0_s)?;
    let opts = AnalysisOptions {
        accum,
        diagnose: first.gap.is_some(),
        ..options(1.0, 0.5, false)
    };
    let mut run = RunAnalysis::restore(ck.analysis.clone(), &setups, opts)?;
    let mut out = Vec::new();
    match &ck.position {
        Position::Frames { stage, .. } => {
            let desc = FrameDescriptor::builtin(&ck.header.format)
                .unwrap_or_else(|| FrameDescriptor::builtin("siu8").expect("siu8"))
                .map_err(|e| e.to_string())?;
            let mut dec = Decoder::restore(desc, &stage.decoder);
            dec.push(siu8_frames());
            dec.finish();
            let events: Vec<_> = dec.drain().collect();
            run.push_chunk(&Chunk::Frames(events), &mut out);
        }
        Position::Text(_) => {
            let width = setups.iter().map(|s| s.column + 1).max().unwrap_or(1);
            if width > allanscope::ranges::MAX_CHANNELS + 1 {
                return Err("too wide".into());
            }
            let values: Vec<f64> = (0..200 * width).map(|i| (i % 17) as f64 * 0.1).collect();
            run.push_chunk(&Chunk::Rows { values, width }, &mut out);
        }
    }
    out.extend(run.records(true));
    check_records(&out);
    Ok(out.len())
}

/// Reads `data` as text columns (`analyze FILE --tau0 1`): header sniffing, separators, gaps,
/// bad rows. Every value read is a usable sample or a gap (NaN), rows have the reader's width,
/// and the analysis of the rows gives records.
pub fn text(data: &[u8]) {
    let Ok(mut reader) = TextReader::with_options(
        Cursor::new(data),
        Path::new("fuzz.csv"),
        &TextOptions::default(),
    ) else {
        return;
    };
    let width = reader.names().len();
    assert!((1..=allanscope::ranges::MAX_CHANNELS).contains(&width));
    let mut values = Vec::new();
    let mut rows = 0usize;
    // Each call reads at least one line until the end: at most one call per byte, and one more.
    for _ in 0..=data.len() + 1 {
        let before = values.len();
        match reader.read_rows(&mut values, 64) {
            Ok(0) | Err(_) => break,
            Ok(n) => {
                rows += n;
                assert_eq!(values.len() - before, n * width);
            }
        }
    }
    assert!(rows as u64 <= reader.rows());
    for v in &values {
        assert!(v.is_nan() || v.abs() <= MAX_ABS_VALUE, "value {v}");
    }
    let channels: Vec<ChannelSetup> = reader
        .names()
        .iter()
        .enumerate()
        .map(|(i, n)| ChannelSetup {
            name: n.clone(),
            unit: "u".into(),
            column: i,
            counts_lsb: None,
        })
        .collect();
    let mut run = RunAnalysis::new("fuzz.csv", channels, options(1.0, 8.0, deep(data)));
    let mut out = Vec::new();
    run.push_chunk(&Chunk::Rows { values, width }, &mut out);
    out.extend(run.records(true));
    check_records(&out);
}

/// Reads `data` as each of the other TOML files: a stand config, a model file and a limits
/// file. Each is a value or a list of problems; every problem names the file.
pub fn configs(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let file = Path::new("fuzz.toml");
    // Every problem names a file and a key (this one's, or a descriptor's it names).
    let names = |e: &allanscope::toml_check::ConfigErrors| {
        assert!(!e.problems.is_empty());
        for p in &e.problems {
            assert!(
                matches!(p, allanscope::error::UsageError::Config { .. }),
                "{p}"
            );
        }
    };
    if let Err(e) = allanscope::stand::StandConfig::from_toml_str(text, file) {
        names(&e);
    }
    if let Err(e) = allanscope::sim::model_file::SimModel::from_toml_str(text, file) {
        names(&e);
    }
    let mut c = allanscope::toml_check::Collector::new(file, text);
    if let Some(t) = c.parse(text) {
        if let Some(toml::Value::Array(a)) = t.get("limits") {
            let specs = allanscope::model::limits::from_tables(a, "limits", &mut c, "limits file");
            let _ = allanscope::model::limits::check_channels(
                &specs,
                "fuzz",
                &[("g1", "arcsec"), ("a1", "m/s")],
            );
        }
    }
    if !c.is_empty() {
        names(&c.into_errors("limits file"));
    }
}
