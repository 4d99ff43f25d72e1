//! Throughput of the live pipeline's stages on the 5-minute siu8 fixture (75,000 frames,
//! 3.15 MB): the decode stage alone (bytes -> frame events, in 64 KiB blocks as a file source
//! delivers them), and a whole replay (file source, decode thread, analysis thread with all
//! three statistics on 8 channels and the fit, record writer into a sink).
//!
//! `cargo bench --bench pipeline`. The 3-hour figures of BENCHMARKS.md ("Live pipeline") come
//! from the binary, with the commands given there.

use std::path::Path;
use std::time::Instant;

use allanscope::allan::accum::AccumConfig;
use allanscope::analysis::{AnalysisOptions, ChannelSetup, InputKind, RunAnalysis};
use allanscope::frame::FrameDescriptor;
use allanscope::model::fit::FitOptions;
use allanscope::pipeline::decode::DecodeStage;
use allanscope::pipeline::{run_frames, RecordWriter, RunControl};
use allanscope::source::{Pace, SourceEvent, SourceSpec};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

fn capture_path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/captures/siu8_stand_5min_seed1.siu8")
}

fn decode_stage(c: &mut Criterion) {
    let desc = FrameDescriptor::load("siu8").expect("siu8");
    let bytes = std::fs::read(capture_path()).expect("fixture");
    let blocks: Vec<bytes::Bytes> = bytes
        .chunks(1 << 16)
        .map(bytes::Bytes::copy_from_slice)
        .collect();
    let mut g = c.benchmark_group("decode_stage");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("siu8_5min", |b| {
        b.iter(|| {
            let mut stage = DecodeStage::new(desc.clone(), false);
            let mut out = Vec::with_capacity(2048);
            let mut frames = 0;
            for blk in &blocks {
                frames += stage.push(
                    SourceEvent::Data {
                        bytes: blk.clone(),
                        at: Instant::now(),
                    },
                    &mut out,
                );
                out.clear();
            }
            frames += stage.finish(&mut out);
            assert_eq!(frames, 75_000);
        })
    });
    g.finish();
}

fn replay(c: &mut Criterion) {
    let desc = FrameDescriptor::load("siu8").expect("siu8");
    let channels: Vec<ChannelSetup> = ChannelSetup::for_frames(&desc);
    let mut g = c.benchmark_group("replay");
    g.sample_size(10);
    g.throughput(Throughput::Bytes(
        std::fs::metadata(capture_path()).expect("fixture").len(),
    ));
    g.bench_function("siu8_5min_all_stats_8ch", |b| {
        b.iter(|| {
            let opts = AnalysisOptions {
                accum: AccumConfig::new(desc.tau0_s()),
                kind: InputKind::Increments,
                every_s: None,
                fit: Some(FitOptions::default()),
                run: None,
                limits: Vec::new(),
                diagnose: false,
            };
            let analysis = RunAnalysis::new("bench", channels.clone(), opts);
            let writer = RecordWriter::spawn(Box::new(std::io::sink()));
            let spec = SourceSpec::File {
                path: capture_path(),
                pace: Pace::Max,
            };
            let out = run_frames(
                spec,
                &desc,
                analysis,
                writer.queue(),
                &RunControl::default(),
            )
            .expect("replay");
            writer.finish().expect("writer");
            assert_eq!(out.health.map(|h| h.frames), Some(75_000));
        })
    });
    g.finish();
}

criterion_group!(benches, decode_stage, replay);
criterion_main!(benches);
