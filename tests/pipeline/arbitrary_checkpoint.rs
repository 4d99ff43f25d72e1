//! Any checkpoint bytes with a valid CRC (proptest): real checkpoints (text columns with the
//! diagnosis on, and siu8 frames) with a few body bytes changed and the CRC made right again, as
//! a damaged disk or a forged file would give. Decoding, restoring and continuing the run
//! (more rows, or the decoder's saved state fed more bytes, then the final records) must end in
//! an error or in records, never a panic, and in bounded time.

use std::path::{Path, PathBuf};
use std::process::Command;

use allanscope::analysis::{AnalysisOptions, InputKind, RunAnalysis};
use allanscope::frame::{Decoder, FrameDescriptor};
use allanscope::input::Chunk;
use allanscope::pipeline::checkpoint::{Checkpoint, Position};
use proptest::prelude::*;

const PREFIX_LEN: usize = 16 + 4 + 8 + 4;

fn scratch() -> PathBuf {
    crate::common::fresh_dir("arbck")
}

/// A checkpoint written by the binary, `args` after `analyze`, in a scratch folder.
fn written(tag: &str, args: &[&str]) -> Vec<u8> {
    let dir = scratch().join(tag);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    let csv: String = (0..3000)
        .map(|i| format!("{},{}\n", ((i * 7919) % 101) as f64 * 0.01, (i % 13) as f64))
        .collect();
    std::fs::write(dir.join("in.csv"), format!("g1,g2\n{csv}")).expect("write");
    let cap =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/captures/siu8_stand_5min_seed1.siu8");
    std::fs::copy(cap, dir.join("cap.siu8")).expect("copy");
    let out = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .current_dir(&dir)
        .env("ALLANSCOPE_LOG", "off")
        .arg("analyze")
        .args(args)
        .args([
            "--out",
            "o.jsonl",
            "--abort-after-frames",
            "1000",
            "--checkpoint-every",
            "1",
        ])
        .output()
        .expect("run");
    // The abort hook ends the run as a crash would, with a checkpoint on disk.
    assert!(!out.status.success());
    std::fs::read(dir.join("o.jsonl.ckpt")).expect("checkpoint")
}

fn text_checkpoint() -> &'static [u8] {
    static B: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    B.get_or_init(|| {
        written(
            "text",
            &["in.csv", "--tau0", "0.01", "--diagnose", "--fit", "none"],
        )
    })
}

fn frames_checkpoint() -> &'static [u8] {
    static B: std::sync::OnceLock<Vec<u8>> = std::sync::OnceLock::new();
    B.get_or_init(|| written("frames", &["cap.siu8", "--format", "siu8", "--fit", "none"]))
}

/// `bytes` with `edits` applied to the body and the CRC recomputed.
fn damaged(bytes: &[u8], edits: &[(usize, u8)]) -> Vec<u8> {
    let mut b = bytes.to_vec();
    let body_len = b.len() - PREFIX_LEN;
    for &(at, x) in edits {
        let i = PREFIX_LEN + at % body_len;
        b[i] ^= x.max(1);
    }
    let crc = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC).checksum(&b[PREFIX_LEN..]);
    b[28..32].copy_from_slice(&crc.to_le_bytes());
    b
}

/// Decodes, restores and continues a run from `bytes`; `Err` is a refusal (fine), a panic fails.
fn resume(bytes: &[u8]) -> Result<usize, String> {
    let ck = Checkpoint::decode(bytes)?;
    let setups: Vec<_> = ck
        .analysis
        .channels
        .iter()
        .map(|c| c.setup.clone())
        .collect();
    let Some(first) = ck.analysis.channels.first() else {
        return Err("no channels".into());
    };
    let opts = AnalysisOptions {
        accum: first.acc.config().clone(),
        kind: InputKind::Increments,
        every_s: Some(0.5),
        fit: None,
        run: None,
        limits: Vec::new(),
        diagnose: first.gap.is_some(),
    };
    if allanscope::ranges::check_tau0(opts.accum.tau0_s).is_err() {
        return Err("tau0".into());
    }
    let mut run = RunAnalysis::restore(ck.analysis.clone(), &setups, opts)?;
    let mut out = Vec::new();
    match &ck.position {
        Position::Frames { stage, .. } => {
            let desc = FrameDescriptor::load("siu8").map_err(|e| e.to_string())?;
            let cap = std::fs::read(
                Path::new(env!("CARGO_MANIFEST_DIR"))
                    .join("fixtures/captures/siu8_stand_5min_seed1.siu8"),
            )
            .expect("capture");
            let mut dec = Decoder::restore(desc, &stage.decoder);
            dec.push(&cap[..8400]);
            dec.finish();
            let events: Vec<_> = dec.drain().collect();
            run.push_chunk(&Chunk::Frames(events), &mut out);
        }
        Position::Text(_) => {
            let width = setups.iter().map(|s| s.column + 1).max().unwrap_or(1);
            let values: Vec<f64> = (0..500 * width).map(|i| (i % 17) as f64 * 0.1).collect();
            run.push_chunk(&Chunk::Rows { values, width }, &mut out);
        }
    }
    out.extend(run.records(true));
    Ok(out.len())
}

#[test]
fn the_checkpoints_resume_as_written() {
    // Undamaged, both resume and give records (so the damaged cases test the checks, not a
    // harness that never gets past decoding).
    assert!(resume(text_checkpoint()).expect("text resumes") > 0);
    assert!(resume(frames_checkpoint()).expect("frames resume") > 0);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 150, ..ProptestConfig::default() })]

    #[test]
    fn any_checkpoint_with_a_valid_crc(
        edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..4),
        frames in any::<bool>(),
    ) {
        let base = if frames { frames_checkpoint() } else { text_checkpoint() };
        let _ = resume(&damaged(base, &edits));
    }
}
