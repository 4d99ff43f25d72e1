//! Sources: where the bytes come from. One async task per source (tokio), owning its file,
//! port or socket; each hands what it reads to the decode stage as [`SourceEvent`]s over a
//! bounded channel, and stops when its input ends or the shutdown token fires.
//!
//! - [`file`]: a capture file or standard input, as fast as possible or paced at the data's
//!   own rate, with a progress bar when standard error is a terminal. A file replayed as fast
//!   as possible (no `--capture`) is read by plain blocking reads on a thread of its own.
//! - [`serial`]: a serial port, reopened with backoff when it disappears; each outage is
//!   reported so the decode stage can record it as a gap.
//! - [`udp`]: a UDP socket (bound to 127.0.0.1 unless told otherwise); each datagram holds
//!   whole frames and is passed on whole, so the decode stage can put reordered frames back.
//!
//! Sources do no decoding and no numerical work. With `--capture FILE` every received byte is
//! also written to FILE, in arrival order, for replay later.

pub mod file;
#[cfg(feature = "serial")]
pub mod serial;
pub mod udp;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use bytes::Bytes;
use tokio::io::AsyncWriteExt;
use tokio::sync::mpsc;
use tokio_util::sync::CancellationToken;

use crate::sink::output::OutputFile;

/// How fast a file is replayed.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Pace {
    /// As fast as the analysis takes it.
    #[default]
    Max,
    /// At the data's own rate: `bytes_per_s` (frame length x frame rate).
    Realtime { bytes_per_s: f64 },
}

/// Where the bytes come from.
#[derive(Debug, Clone, PartialEq)]
pub enum SourceSpec {
    /// A capture file, read to its end.
    File { path: PathBuf, pace: Pace },
    /// Standard input, read to its end.
    Stdin { pace: Pace },
    /// A serial port at `baud`, 8N1.
    Serial { path: PathBuf, baud: u32 },
    /// A UDP socket bound to `bind`.
    Udp { bind: SocketAddr },
}

impl SourceSpec {
    /// True for sources that run until stopped (serial, UDP): their silences are measured in
    /// wall time.
    pub fn is_live(&self) -> bool {
        matches!(self, SourceSpec::Serial { .. } | SourceSpec::Udp { .. })
    }

    /// Capacity of the channel from this source to the decode stage.
    pub fn queue_capacity(&self) -> usize {
        if self.is_live() {
            SOURCE_QUEUE_LIVE
        } else {
            SOURCE_QUEUE_FILE
        }
    }

    /// A name for the `summary` record's `input`.
    pub fn name(&self) -> String {
        match self {
            SourceSpec::File { path, .. } => path.display().to_string(),
            SourceSpec::Stdin { .. } => "-".into(),
            SourceSpec::Serial { path, baud } => format!("serial:{}@{baud}", path.display()),
            SourceSpec::Udp { bind } => format!("udp:{bind}"),
        }
    }
}

/// What a source hands to the decode stage.
#[derive(Debug, Clone)]
pub enum SourceEvent {
    /// Bytes of a stream, as they arrived at `at`.
    Data { bytes: Bytes, at: Instant },
    /// One UDP datagram (whole frames), as it arrived at `at`.
    Datagram { bytes: Bytes, at: Instant },
    /// The source went quiet (no datagram or byte for a while): frames held for reordering, and
    /// reads held as the possible first pieces of a backlog, can go.
    Idle,
    /// The port came back after an outage: bytes before and after it are not contiguous.
    Reconnected { outage_s: f64 },
}

/// Capacity of the channel from a live source task to the decode stage, in events. A datagram
/// or a serial read is one or a few frames: 1024 datagrams are 50 ms of siu8 at 20,000
/// frames/s, enough to ride out a scheduling hiccup of the decode thread without the kernel
/// dropping any.
pub const SOURCE_QUEUE_LIVE: usize = 1024;

/// Capacity for file and standard-input sources, in blocks of `file::READ_BLOCK` (256 KiB): the
/// file waits (back-pressure), so a few blocks keep the decoder busy and memory at a megabyte.
pub const SOURCE_QUEUE_FILE: usize = 4;

/// Counters a source and the stages after it share with whoever watches the run (tests, the
/// binary's progress bar).
#[derive(Debug, Default)]
pub struct Progress {
    /// Bytes received by the source.
    pub bytes: AtomicU64,
    /// Good frames decoded so far.
    pub frames: AtomicU64,
    /// Serial: times the port was reopened.
    pub reconnects: AtomicU64,
    /// The input reached its end (a file or standard input read to its last byte).
    pub input_ended: std::sync::atomic::AtomicBool,
    /// Why the run was stopped before its input ended: `SIGINT`, `SIGTERM`, `--duration`.
    pub stopped_by: Mutex<Option<&'static str>>,
    /// The `--capture` file's bytes and error.
    pub capture: Arc<CaptureStatus>,
    /// File replay: the file's length in bytes (0 until known, and for other sources).
    pub input_len: AtomicU64,
    /// File replay: the byte offset reading started at (a resumed run's checkpoint position).
    pub input_start: AtomicU64,
    /// File replay: bytes received before this file was opened (the counters run on across the
    /// inputs of one command).
    pub input_base: AtomicU64,
}

impl Progress {
    pub fn frames(&self) -> u64 {
        self.frames.load(Ordering::Relaxed)
    }
    pub fn bytes(&self) -> u64 {
        self.bytes.load(Ordering::Relaxed)
    }

    /// True once the input has been read to its end.
    pub fn input_ended(&self) -> bool {
        self.input_ended.load(Ordering::SeqCst)
    }

    /// Records why the run is being stopped (the first reason given wins).
    pub fn set_stopped_by(&self, why: &'static str) {
        let mut s = self.stopped_by.lock().unwrap_or_else(|p| p.into_inner());
        s.get_or_insert(why);
    }

    pub fn stopped_by(&self) -> Option<&'static str> {
        *self.stopped_by.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// File replay: `(offset reached, file length)` in bytes, once the length is known.
    pub fn file_position(&self) -> Option<(u64, u64)> {
        let len = self.input_len.load(Ordering::Relaxed);
        let read = self
            .bytes()
            .saturating_sub(self.input_base.load(Ordering::Relaxed));
        (len > 0).then(|| (self.input_start.load(Ordering::Relaxed) + read, len))
    }
}

/// Everything a source task needs besides its spec.
pub struct SourceContext {
    /// Byte offset to start a file at (a resumed replay); 0 otherwise.
    pub start_offset: u64,
    pub tx: mpsc::Sender<SourceEvent>,
    pub shutdown: CancellationToken,
    pub capture: Option<Capture>,
    pub progress: Arc<Progress>,
}

impl SourceContext {
    /// Records received bytes (progress, capture) and passes them on; false when the decode
    /// stage has gone.
    async fn deliver(&mut self, ev: SourceEvent) -> Result<bool> {
        let bytes = match &ev {
            SourceEvent::Data { bytes, .. } | SourceEvent::Datagram { bytes, .. } => Some(bytes),
            _ => None,
        };
        if let Some(b) = bytes {
            self.progress
                .bytes
                .fetch_add(b.len() as u64, Ordering::Relaxed);
            if let Some(c) = &mut self.capture {
                c.write(b).await;
            }
        }
        Ok(self.tx.send(ev).await.is_ok())
    }
}

/// A capture file the command has opened (refused if it holds an earlier capture, see
/// [`crate::sink::output`]), handed to the source task, which takes it when the run starts.
#[derive(Debug, Clone)]
pub struct CaptureSlot(Arc<Mutex<Option<OutputFile>>>);

impl CaptureSlot {
    pub fn new(file: OutputFile) -> CaptureSlot {
        CaptureSlot(Arc::new(Mutex::new(Some(file))))
    }

    /// The file, once (later calls: `None`).
    pub fn take(&self) -> Option<OutputFile> {
        self.0.lock().unwrap_or_else(|p| p.into_inner()).take()
    }
}

/// What became of the capture file (reported in the `health` and `summary` records).
#[derive(Debug, Default)]
pub struct CaptureStatus {
    /// Bytes written to the capture file.
    pub bytes: AtomicU64,
    /// The first write error; the capture stopped there, the run went on.
    pub error: Mutex<Option<String>>,
}

impl CaptureStatus {
    pub fn bytes(&self) -> u64 {
        self.bytes.load(Ordering::Relaxed)
    }

    pub fn error(&self) -> Option<String> {
        self.error.lock().unwrap_or_else(|p| p.into_inner()).clone()
    }
}

/// `--capture FILE`: every received byte, in arrival order. A write error (a full disk, a
/// removed drive) stops the capture, not the run: the analysis goes on, the error is logged once
/// and reported in [`CaptureStatus`].
pub struct Capture {
    path: PathBuf,
    /// The file until the first byte arrives (an earlier capture is only replaced then).
    pending: Option<OutputFile>,
    out: Option<tokio::io::BufWriter<tokio::fs::File>>,
    status: Arc<CaptureStatus>,
    failed: bool,
}

impl Capture {
    pub fn new(file: OutputFile, status: Arc<CaptureStatus>) -> Capture {
        Capture {
            path: file.path().to_path_buf(),
            pending: Some(file),
            out: None,
            status,
            failed: false,
        }
    }

    fn fail(&mut self, e: &std::io::Error) {
        let msg = format!(
            "capture file {}: {e}; the capture stopped after {} bytes, the analysis goes on",
            self.path.display(),
            self.status.bytes()
        );
        tracing::error!("{msg}");
        *self.status.error.lock().unwrap_or_else(|p| p.into_inner()) = Some(msg);
        self.failed = true;
        self.out = None;
    }

    async fn write(&mut self, b: &[u8]) {
        if self.failed || b.is_empty() {
            return;
        }
        if let Some(f) = self.pending.take() {
            match f.into_started() {
                Ok(f) => {
                    self.out = Some(tokio::io::BufWriter::with_capacity(
                        1 << 16,
                        tokio::fs::File::from_std(f),
                    ))
                }
                Err(e) => return self.fail(&e),
            }
        }
        let Some(out) = &mut self.out else { return };
        match out.write_all(b).await {
            // Counted when handed to the buffer; a later flush error is reported all the same.
            Ok(()) => {
                self.status
                    .bytes
                    .fetch_add(b.len() as u64, Ordering::Relaxed);
            }
            Err(e) => self.fail(&e),
        }
    }

    pub async fn finish(&mut self) {
        if let Some(out) = &mut self.out {
            if let Err(e) = out.flush().await {
                self.fail(&e);
            }
        }
    }
}

/// Runs a source until its input ends or `ctx.shutdown` fires.
pub async fn run(spec: SourceSpec, mut ctx: SourceContext) -> Result<()> {
    let res = match spec {
        SourceSpec::File { path, pace } => {
            let f = tokio::fs::File::open(&path).await.map_err(|e| {
                anyhow::Error::new(crate::error::UsageError::Input {
                    file: path.clone(),
                    line: 0,
                    problem: format!("cannot open: {e}"),
                })
            })?;
            let mut f = f;
            let len = f.metadata().await.ok().map(|m| m.len());
            if ctx.start_offset > 0 {
                use tokio::io::AsyncSeekExt;
                if len.is_some_and(|l| l < ctx.start_offset) {
                    return Err(anyhow::Error::new(crate::error::UsageError::Input {
                        file: path.clone(),
                        line: 0,
                        problem: format!(
                            "shorter ({} bytes) than the checkpoint's position ({} bytes)",
                            len.unwrap_or(0),
                            ctx.start_offset
                        ),
                    }));
                }
                f.seek(std::io::SeekFrom::Start(ctx.start_offset))
                    .await
                    .with_context(|| format!("cannot seek in {}", path.display()))?;
            }
            let p = &ctx.progress;
            p.input_base.store(p.bytes(), Ordering::Relaxed);
            p.input_start.store(ctx.start_offset, Ordering::Relaxed);
            ctx.progress
                .input_len
                .store(len.unwrap_or(0), Ordering::Relaxed);
            if pace == Pace::Max && ctx.capture.is_none() && direct_file_reads() {
                // As fast as possible: plain blocking reads on a thread of their own.
                let f = f.into_std().await;
                let (res, back) = tokio::task::spawn_blocking(move || {
                    let res = file::read_file(f, &mut ctx);
                    (res, ctx)
                })
                .await
                .map_err(|_| anyhow::anyhow!("the file reader panicked"))?;
                ctx = back;
                res
            } else {
                file::read_stream(f, pace, &mut ctx).await
            }
        }
        SourceSpec::Stdin { pace } => file::read_stream(tokio::io::stdin(), pace, &mut ctx).await,
        #[cfg(feature = "serial")]
        SourceSpec::Serial { path, baud } => serial::run(&path, baud, &mut ctx).await,
        #[cfg(not(feature = "serial"))]
        SourceSpec::Serial { .. } => Err(anyhow::Error::new(crate::error::UsageError::Option(
            "serial ports need allanscope built with the `serial` feature".into(),
        ))),
        SourceSpec::Udp { bind } => udp::run(bind, &mut ctx).await,
    };
    if let Some(c) = &mut ctx.capture {
        c.finish().await;
    }
    res
}

/// Measurement knob: `ALLANSCOPE_FILE_READS=tokio` reads replayed files through tokio.
fn direct_file_reads() -> bool {
    std::env::var("ALLANSCOPE_FILE_READS").map_or(true, |v| v != "tokio")
}

/// Backoff between attempts to reopen a serial port: doubling from the first to the last.
pub const BACKOFF_FIRST: Duration = Duration::from_millis(50);
pub const BACKOFF_MAX: Duration = Duration::from_secs(2);
