//! Helpers shared by the pipeline tests: the fixture captures, an in-memory record sink, the
//! records parsed back, and runs of the library pipeline.
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use allanscope::allan::accum::AccumConfig;
use allanscope::analysis::{AnalysisOptions, ChannelSetup, InputKind, RunAnalysis};
use allanscope::frame::FrameDescriptor;
use allanscope::model::fit::FitOptions;
use allanscope::pipeline::{run_frames, RecordWriter, RunControl, RunOutcome};
use allanscope::sink::records::Record;
use allanscope::source::SourceSpec;

/// The siu8 fixture: 5 minutes, 75,000 frames of 42 bytes (fixtures/captures/ORIGIN.md).
pub fn siu8_capture() -> Vec<u8> {
    std::fs::read(fixtures().join("captures/siu8_stand_5min_seed1.siu8")).expect("siu8 fixture")
}

pub fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures")
}

pub fn siu8() -> FrameDescriptor {
    FrameDescriptor::load("siu8").expect("siu8 descriptor")
}

pub fn channels(desc: &FrameDescriptor) -> Vec<ChannelSetup> {
    ChannelSetup::for_frames(desc)
}

/// The default options of `analyze` (all three statistics, octave taus, L = 16, model fit).
pub fn options(desc: &FrameDescriptor, every_s: Option<f64>) -> AnalysisOptions {
    AnalysisOptions {
        accum: AccumConfig::new(desc.tau0_s()),
        kind: InputKind::Increments,
        every_s,
        fit: Some(FitOptions::default()),
        run: None,
        limits: Vec::new(),
        diagnose: false,
    }
}

pub fn analysis(desc: &FrameDescriptor, every_s: Option<f64>) -> RunAnalysis {
    RunAnalysis::new("test", channels(desc), options(desc, every_s))
}

/// A `Write` into a shared buffer.
#[derive(Clone, Default)]
pub struct SharedBuf(pub Arc<Mutex<Vec<u8>>>);

impl Write for SharedBuf {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.lock().expect("lock").extend_from_slice(b);
        Ok(b.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl SharedBuf {
    pub fn records(&self) -> Vec<serde_json::Value> {
        parse_lines(&self.0.lock().expect("lock"))
    }
}

pub fn parse_lines(bytes: &[u8]) -> Vec<serde_json::Value> {
    String::from_utf8_lossy(bytes)
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("not JSON: {e}: {l}")))
        .collect()
}

/// Runs `spec` through the library pipeline into memory; returns the records and the outcome.
pub fn run_to_records(
    spec: SourceSpec,
    desc: &FrameDescriptor,
    ctl: &RunControl,
) -> (Vec<serde_json::Value>, RunOutcome) {
    let buf = SharedBuf::default();
    let writer = RecordWriter::spawn(Box::new(buf.clone()));
    let outcome = run_frames(spec, desc, analysis(desc, None), writer.queue(), ctl).expect("run");
    writer.finish().expect("writer");
    (buf.records(), outcome)
}

/// Final `curve` and `fit` records, as typed records (every field compared, none wall-clock).
pub fn final_curves_and_fits(recs: &[serde_json::Value]) -> Vec<Record> {
    recs.iter()
        .filter(|r| (r["type"] == "curve" || r["type"] == "fit") && r["final"] == true)
        .map(|r| serde_json::from_value(r.clone()).expect("record"))
        .collect()
}

/// The record of `type` (the last one).
pub fn last_of<'a>(recs: &'a [serde_json::Value], ty: &str) -> &'a serde_json::Value {
    recs.iter()
        .rev()
        .find(|r| r["type"] == ty)
        .unwrap_or_else(|| panic!("no {ty} record"))
}

/// A free loopback UDP port (bound and released; the race with other processes is small).
pub fn free_udp_port() -> u16 {
    let s = std::net::UdpSocket::bind("127.0.0.1:0").expect("bind");
    s.local_addr().expect("addr").port()
}

/// The summary fields that do not depend on the wall clock, the input's name or its kind (a
/// live source is never "read to its end").
pub fn summary_core(s: &serde_json::Value) -> serde_json::Value {
    let mut s = s.clone();
    if let Some(o) = s.as_object_mut() {
        o.remove("elapsed_s");
        o.remove("input");
        o.remove("read_to_end");
        o.remove("stopped_by");
    }
    s
}

/// Compares two records field by field: numbers to 1e-12 relative, integers (counts) and
/// everything else exactly; `elapsed_s` (wall time) is left out.
pub fn same_record(a: &serde_json::Value, b: &serde_json::Value, at: &str) {
    use serde_json::Value as V;
    match (a, b) {
        (V::Object(x), V::Object(y)) => {
            let mut kx: Vec<_> = x.keys().collect();
            let mut ky: Vec<_> = y.keys().collect();
            kx.sort();
            ky.sort();
            assert_eq!(kx, ky, "{at}: fields differ");
            for (k, v) in x {
                if k != "elapsed_s" {
                    same_record(v, &y[k], &format!("{at}.{k}"));
                }
            }
        }
        (V::Array(x), V::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: lengths differ");
            for (i, (u, v)) in x.iter().zip(y).enumerate() {
                same_record(u, v, &format!("{at}[{i}]"));
            }
        }
        (V::Number(x), V::Number(y)) if x.is_f64() || y.is_f64() => {
            let (u, v) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!(
                (u - v).abs() <= 1e-12 * u.abs().max(v.abs()),
                "{at}: {u} vs {v}"
            );
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}
