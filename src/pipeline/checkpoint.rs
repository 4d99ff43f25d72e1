//! Checkpoints: the state of a run saved beside its output (`--checkpoint-every S`), so that
//! `--resume` continues it after a crash.
//!
//! # What is saved
//!
//! A [`Checkpoint`] holds a [`Header`] (the options that decide what the accumulators mean:
//! input, format, tau0, cluster sizes, overlap, statistics, input kind, channels, diagnosis),
//! the position in the input ([`Position`]: the byte offset and the frame decoder's state, or the
//! text reader's place), and the analysis state ([`AnalysisState`]: each channel's accumulator
//! with its retained stream points, level sums and counts, spread and segment state, and the
//! diagnosis evidence when it is on). Fits are not saved: they are recomputed from the curves.
//! In bounded-memory mode every part is bounded, so the checkpoint is too; with `--overlap
//! full` it grows with the run like the accumulators themselves.
//!
//! # How a consistent cut is taken
//!
//! The stage that reads the input (the decode thread, or the text reader thread) decides when a
//! checkpoint is due: every S data-seconds when a file is replayed (deterministic, like
//! `--every`), every S wall-seconds for live sources. Between two source events it hands the
//! collector thread its position, then sends a [`Chunk::Checkpoint`] mark down the same
//! channel as the data; each analysis thread, on reaching the mark, has consumed exactly the
//! steps before it and hands over a snapshot of its channels. The collector assembles the
//! pieces and writes the file. Only one checkpoint is in flight at a time, so memory stays
//! bounded however small S is.
//!
//! This module is the file and what it holds; the threads that take the cut (the schedule and
//! the collector) are in [`super::checkpointing`].
//!
//! # File format
//!
//! `ALLANSCOPE-CKPT\n`, the format version (u32, little-endian), the body length (u64), the
//! CRC-32 of the body (u32), then the body: the [`Checkpoint`] in CBOR (exact binary floats and
//! 128-bit integers). It is written to `FILE.tmp`, flushed to disk, then renamed over `FILE`,
//! so a crash while writing leaves the previous checkpoint whole.
//!
//! [`Chunk::Checkpoint`]: crate::input::Chunk::Checkpoint

use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{SystemTime, UNIX_EPOCH};

use serde::{Deserialize, Serialize};

use super::decode::DecodeStageState;
use crate::analysis::AnalysisState;
use crate::error::UsageError;
use crate::input::text::TextPosition;

/// Version of the checkpoint format; a file of another version is refused.
pub const FORMAT_VERSION: u32 = 1;

const MAGIC: &[u8; 16] = b"ALLANSCOPE-CKPT\n";
const PREFIX_LEN: usize = 16 + 4 + 8 + 4;
const CRC32: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Bytes of a replayed file hashed into [`Header::input_fingerprint`].
pub const FINGERPRINT_BYTES: usize = 1 << 16;

/// The checkpoint beside an output file: `FILE.ckpt`.
pub fn path_for(out: &Path) -> PathBuf {
    let mut s = out.as_os_str().to_owned();
    s.push(".ckpt");
    PathBuf::from(s)
}

/// The options a checkpoint's state depends on; resuming with different ones is refused.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Header {
    /// The input: a file path, `-`, `serial:PATH@BAUD` or `udp:ADDR`.
    pub input: String,
    /// CRC-32 of the first [`FINGERPRINT_BYTES`] of a replayed file (so a different file under
    /// the same name is noticed).
    pub input_fingerprint: Option<u32>,
    /// `csv`, or the frame descriptor's name.
    pub format: String,
    /// `increments`, `rate` or `phase`.
    pub kind: String,
    pub tau0_s: f64,
    /// The cluster sizes m.
    pub taus: Vec<u64>,
    /// `full` or L.
    pub overlap: String,
    /// Statistics accumulated.
    pub stats: Vec<String>,
    /// Channel names, in order.
    pub channels: Vec<String>,
    pub diagnose: bool,
}

impl Header {
    /// The differences between the saved header (`self`) and the one of the options now given.
    pub fn mismatches(&self, now: &Header) -> Vec<String> {
        let mut out = Vec::new();
        let mut cmp = |what: &str, saved: String, given: String| {
            if saved != given {
                out.push(format!("{what}: saved {saved}, now {given}"));
            }
        };
        cmp("input", self.input.clone(), now.input.clone());
        if let (Some(a), Some(b)) = (self.input_fingerprint, now.input_fingerprint) {
            cmp(
                "input content (CRC-32 of its first 64 KiB)",
                format!("{a:08x}"),
                format!("{b:08x}"),
            );
        }
        cmp("--format", self.format.clone(), now.format.clone());
        cmp("input kind", self.kind.clone(), now.kind.clone());
        if self.tau0_s.to_bits() != now.tau0_s.to_bits() {
            cmp(
                "--tau0",
                format!("{:?} s", self.tau0_s),
                format!("{:?} s", now.tau0_s),
            );
        }
        cmp("--taus", short_list(&self.taus), short_list(&now.taus));
        cmp("--overlap", self.overlap.clone(), now.overlap.clone());
        cmp("--stats", self.stats.join(","), now.stats.join(","));
        cmp(
            "--channels",
            self.channels.join(","),
            now.channels.join(","),
        );
        cmp(
            "--diagnose",
            self.diagnose.to_string(),
            now.diagnose.to_string(),
        );
        out
    }
}

fn short_list(v: &[u64]) -> String {
    if v.len() <= 8 {
        format!("{v:?}")
    } else {
        format!(
            "[{}, {}, ..., {}] ({} sizes)",
            v[0],
            v[1],
            v[v.len() - 1],
            v.len()
        )
    }
}

/// Where the run stood in its input.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Position {
    /// Frames: `offset` bytes of the input had reached the decoder, whose state is `stage`.
    Frames {
        offset: u64,
        stage: Box<DecodeStageState>,
    },
    /// Text columns.
    Text(Box<TextPosition>),
}

impl Position {
    pub fn offset(&self) -> u64 {
        match self {
            Position::Frames { offset, .. } => *offset,
            Position::Text(p) => p.offset,
        }
    }
}

/// One saved checkpoint.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    pub header: Header,
    /// Seconds between checkpoints of the run that wrote it (data-seconds for a replay,
    /// wall-seconds live); a resume without `--checkpoint-every` keeps it.
    pub every_s: f64,
    /// Checkpoints written by the run so far (this one included).
    pub sequence: u64,
    /// Written at the end of the run (input read to its end, or a live run stopped): a replay
    /// has nothing left to resume.
    pub complete: bool,
    /// When it was written, seconds since the Unix epoch.
    pub saved_unix_s: f64,
    pub position: Position,
    pub analysis: AnalysisState,
}

fn bad(file: &Path, problem: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(UsageError::Checkpoint {
        file: file.into(),
        problem: problem.into(),
    })
}

/// Seconds since the Unix epoch.
pub fn unix_now_s() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

impl Checkpoint {
    /// The file's bytes: prefix, then the CBOR body.
    pub fn encode(&self) -> anyhow::Result<Vec<u8>> {
        let mut body = Vec::new();
        ciborium::into_writer(self, &mut body)
            .map_err(|e| anyhow::anyhow!("cannot encode the checkpoint: {e}"))?;
        let mut out = Vec::with_capacity(PREFIX_LEN + body.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(body.len() as u64).to_le_bytes());
        out.extend_from_slice(&CRC32.checksum(&body).to_le_bytes());
        out.extend_from_slice(&body);
        Ok(out)
    }

    /// Reads a checkpoint file; every problem is a usage error naming the file.
    pub fn load(path: &Path) -> anyhow::Result<Checkpoint> {
        let bytes = std::fs::read(path).map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                bad(
                    path,
                    "not found (nothing to resume: run without --resume to start)",
                )
            } else {
                bad(path, format!("cannot read: {e}"))
            }
        })?;
        Self::decode(&bytes).map_err(|p| bad(path, p))
    }

    /// Parses a checkpoint file's bytes.
    pub fn decode(bytes: &[u8]) -> Result<Checkpoint, String> {
        if bytes.len() < PREFIX_LEN || &bytes[..16] != MAGIC {
            return Err("not an allanscope checkpoint (bad magic bytes)".into());
        }
        let word = |from: usize, n: usize| -> u64 {
            let mut b = [0u8; 8];
            b[..n].copy_from_slice(&bytes[from..from + n]);
            u64::from_le_bytes(b)
        };
        let version = word(16, 4) as u32;
        if version != FORMAT_VERSION {
            return Err(format!(
                "format version {version}, this program reads version {FORMAT_VERSION}"
            ));
        }
        let len = word(20, 8);
        let crc = word(28, 4) as u32;
        let body = &bytes[PREFIX_LEN..];
        if body.len() as u64 != len {
            return Err(format!(
                "truncated or padded: the body has {} bytes, the header says {len}",
                body.len()
            ));
        }
        if CRC32.checksum(body) != crc {
            return Err("damaged: the CRC-32 of its contents does not match".into());
        }
        let ck: Checkpoint =
            ciborium::from_reader(body).map_err(|e| format!("cannot decode its contents: {e}"))?;
        // The numbers a resume drives timers and loops with (the accumulators are checked when
        // restored, against the options of the resuming run).
        crate::ranges::check_interval(ck.every_s)
            .map_err(|e| format!("damaged: saved checkpoint interval {e}"))?;
        if ck.analysis.next_emit_s.is_nan() || ck.analysis.next_emit_s < 0.0 {
            return Err(format!(
                "damaged: the next interim record is due at {} data-seconds",
                crate::ranges::show(ck.analysis.next_emit_s)
            ));
        }
        Ok(ck)
    }

    /// Writes the checkpoint atomically: `FILE.tmp`, flushed to disk, renamed over `FILE`.
    /// Returns the bytes written.
    pub fn write_atomic(&self, path: &Path) -> anyhow::Result<usize> {
        let bytes = self.encode()?;
        write_atomic(path, &bytes)?;
        Ok(bytes.len())
    }
}

/// Writes `bytes` to `path` by a temporary file beside it and a rename.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    use anyhow::Context;
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    {
        let mut f = std::fs::File::create(&tmp)
            .with_context(|| format!("cannot create checkpoint {}", tmp.display()))?;
        f.write_all(bytes)
            .and_then(|_| f.sync_all())
            .with_context(|| format!("cannot write checkpoint {}", tmp.display()))?;
    }
    std::fs::rename(&tmp, path)
        .with_context(|| format!("cannot rename {} to {}", tmp.display(), path.display()))?;
    // Make the rename itself durable (best effort: not every file system allows it).
    if let Some(dir) = path.parent() {
        let dir = if dir.as_os_str().is_empty() {
            Path::new(".")
        } else {
            dir
        };
        if let Ok(d) = std::fs::File::open(dir) {
            let _ = d.sync_all();
        }
    }
    Ok(())
}

/// CRC-32 of the first [`FINGERPRINT_BYTES`] of a file.
pub fn fingerprint(path: &Path) -> Option<u32> {
    use std::io::Read;
    let f = std::fs::File::open(path).ok()?;
    let mut buf = Vec::with_capacity(FINGERPRINT_BYTES);
    f.take(FINGERPRINT_BYTES as u64)
        .read_to_end(&mut buf)
        .ok()?;
    Some(CRC32.checksum(&buf))
}

/// Checks a loaded checkpoint against the options of the resuming command (usage error naming
/// the file and every mismatch), and that a replay has something left to do.
pub fn check_resume(
    path: &Path,
    ck: &Checkpoint,
    now: &Header,
    replay: bool,
) -> anyhow::Result<()> {
    let m = ck.header.mismatches(now);
    if !m.is_empty() {
        return Err(bad(
            path,
            format!(
                "saved with other options than given now ({}); resume with the options of the \
                 saved run, or start a new run without --resume",
                m.join("; ")
            ),
        ));
    }
    if replay && ck.complete {
        return Err(bad(
            path,
            "the run it saved read its input to the end; its final records are in the output, \
             nothing is left to resume",
        ));
    }
    Ok(())
}

/// Refuses to start a fresh run over a checkpoint of an unfinished one (it would be lost).
pub fn check_fresh_start(path: &Path) -> anyhow::Result<()> {
    if !path.exists() {
        return Ok(());
    }
    match Checkpoint::load(path) {
        Ok(ck) if ck.complete => Ok(()),
        Ok(ck) => Err(bad(
            path,
            format!(
                "holds an unfinished run ({} at {:.1} s of data); pass --resume to continue it, \
                 or delete the file to start over",
                ck.header.input,
                ck.analysis
                    .channels
                    .iter()
                    .map(|c| c.acc.t_data_s())
                    .fold(0.0, f64::max)
            ),
        )),
        Err(e) => Err(bad(
            path,
            format!("exists and cannot be read ({e:#}); delete it to start a new run"),
        )),
    }
}

/// How a run checkpoints, handed to the pipeline in `RunControl`.
#[derive(Debug)]
pub struct CheckpointPlan {
    pub path: PathBuf,
    /// Seconds between checkpoints.
    pub every_s: f64,
    /// `every_s` counts data-seconds (replay) rather than wall-seconds (live).
    pub data_seconds: bool,
    pub header: Header,
    /// The position to continue from (`--resume`), and the sequence number reached.
    pub resume: Option<(Position, u64)>,
    /// Test hook (`--abort-after-frames`, hidden): once this many frames (rows) have been read
    /// and a checkpoint is on disk, the pipeline calls `RunControl::crash_hook` (the binary's
    /// aborts the process, as a crash would).
    pub abort_after_frames: Option<u64>,
}
