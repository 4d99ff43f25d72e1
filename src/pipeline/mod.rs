//! The pipeline of one run: tasks, threads, channels and shutdown.
//!
//! ```text
//!  source task (tokio)  --SourceEvent-->  decode thread  --Chunk-->  analysis thread  --Record-->  writer thread
//!  file/stdin/serial/udp  mpsc, 4 | 1024   DecodeStage     crossbeam, 4   RunAnalysis     RecordQueue     JSON lines
//! ```
//!
//! - I/O is async: the source runs in the caller's tokio runtime ([`run_frames_async`]) or in a
//!   current-thread runtime built for the run ([`run_frames`]); decoding and statistics are plain
//!   sync code on threads of their own; no stage awaits numerical work and no numerical stage
//!   awaits. Signals, `--duration` and the progress bar belong to the binary (`src/cli/`).
//! - Every channel is bounded. The source waits when the decode stage is behind (for a file
//!   that is back-pressure; for a socket the kernel buffer takes the slack), the decode thread
//!   waits when the analysis is behind: **frames are never dropped**. The record writer is the
//!   exception by design: its queue never blocks the analysis and coalesces interim records when
//!   full ([`writer`]), so a stalled consumer of the JSON lines never stalls ingestion.
//! - One shutdown token goes to the source. The caller cancels it (the binary on SIGINT, SIGTERM
//!   or the end of `--duration`; an embedding program when it likes); the source stops reading,
//!   and each stage after it finishes when its input channel closes: the decoder is finished,
//!   the analysis writes its final curve, fit, health and summary records, the writer drains its
//!   queue. A caller that must not wait for a stalled consumer of the records lifts the queue's
//!   back-pressure ([`RecordQueue::release`]) and bounds the writer's last wait
//!   ([`RecordWriter::finish_within`]): the library never ends the process.
//!
//! Text columns (`--format csv`) enter the same analysis and writer stages from a reader
//! thread instead of the source task and decode thread.

pub mod checkpoint;
pub mod checkpointing;
pub mod decode;
pub mod reorder;
pub mod units;
pub mod writer;

use std::io::BufRead;
use std::path::PathBuf;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use tokio_util::sync::CancellationToken;

use crate::analysis::RunAnalysis;
use crate::error::UsageError;
use crate::frame::{FrameBlock, FrameDescriptor, Health};
use crate::input::text::{TextReader, BATCH_ROWS};
use crate::input::Chunk;
use crate::sink::metrics::MetricsTap;
use crate::sink::records::{HealthRecord, Record};
use crate::source::{Capture, CaptureSlot, Progress, SourceContext, SourceEvent, SourceSpec};
use checkpoint::{Checkpoint, CheckpointPlan, Position};
use checkpointing::{Collector, Piece, Schedule};
use decode::DecodeStage;
pub use writer::{Delivery, RecordQueue, RecordWriter, WriterStats, RECORD_QUEUE};

/// Capacity of the channel from the decode (or text reader) thread to the analysis, in
/// chunks. A replayed chunk is one 256 KiB read (about 6240 siu8 frames, 450 KB decoded: a
/// 40-byte event and 32 bytes of narrow columns per frame), so reading runs ahead of the
/// analysis by a few megabytes at most; live chunks are a few frames.
pub const CHUNK_QUEUE: usize = 4;

/// A chunk this large goes to the analysis at once, even while more input waits: this bounds a
/// chunk's memory when many small reads are gathered while the analysis is busy, and a
/// replay's next read then goes into a fresh block (swapped in whole) instead of being copied
/// behind these frames (profiled: that copy was 8% of a replay's decode thread).
const SEND_CHUNK_EVENTS: usize = 1024;

/// Events a new chunk has room for at first (a 64 KiB read of siu8 is 1560 frames); blocks are
/// recycled, so a replay's blocks grow to a whole read once and keep that room (profiled:
/// regrowing was 3% of the decode thread).
const CHUNK_EVENTS_RESERVE: usize = 1600;

/// How a run is driven and stopped. The caller owns the process: it cancels `shutdown` (the
/// binary does on SIGINT, SIGTERM or the end of `--duration`; an embedding program when it
/// likes), and may watch `progress` (the binary's progress bar).
#[derive(Debug, Clone)]
pub struct RunControl {
    /// Cancelled by the caller: the source stops reading, and the stages after it finish. The
    /// caller also records why in `progress` ([`Progress::set_stopped_by`]) for the summary.
    pub shutdown: CancellationToken,
    /// Also write every received byte to this file (opened by the command, see
    /// [`crate::sink::output`]).
    pub capture: Option<CaptureSlot>,
    /// Counters the caller may watch.
    pub progress: Arc<Progress>,
    /// Wall-seconds between interim records (live sources); `None`: the analysis's own
    /// data-second schedule (`AnalysisOptions::every_s`).
    pub every_wall: Option<Duration>,
    /// Checkpoints (`--checkpoint-every`, `--resume`): where, how often, and the position to
    /// continue from.
    pub checkpoint: Option<Arc<CheckpointPlan>>,
    /// Metrics for monitoring (`--metrics`): every fit record and the decoder's health, as the
    /// run goes.
    pub metrics: Option<MetricsTap>,
    /// Called once [`CheckpointPlan::abort_after_frames`] frames (rows) are read and a
    /// checkpoint is on disk; the binary's `--abort-after-frames` test hook aborts the process
    /// there, as a crash would. Without a hook the run goes on.
    pub crash_hook: Option<CrashHook>,
}

impl Default for RunControl {
    fn default() -> Self {
        RunControl {
            shutdown: CancellationToken::new(),
            capture: None,
            progress: Arc::new(Progress::default()),
            every_wall: None,
            checkpoint: None,
            metrics: None,
            crash_hook: None,
        }
    }
}

/// The callback of [`RunControl::crash_hook`].
#[derive(Clone)]
pub struct CrashHook(pub Arc<dyn Fn() + Send + Sync>);

impl std::fmt::Debug for CrashHook {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("CrashHook")
    }
}

/// What a run leaves behind: the analysis (for aggregate records) and the decoder's health.
pub struct RunOutcome {
    pub analysis: RunAnalysis,
    pub health: Option<Health>,
    /// The input was read to its end (false for a replay stopped by SIGINT, and for live
    /// sources, which have no end).
    pub read_to_end: bool,
}

/// Runs a source of frames through decoding and analysis until the input ends or shutdown;
/// then queues the final curve and fit records, the health record and the summary.
///
/// Blocks the calling thread on a current-thread tokio runtime of its own. Inside a tokio
/// runtime it returns an error instead: await [`run_frames_async`] there.
pub fn run_frames(
    spec: SourceSpec,
    desc: &FrameDescriptor,
    analysis: RunAnalysis,
    queue: &RecordQueue,
    ctl: &RunControl,
) -> Result<RunOutcome> {
    block_on(run_frames_async(spec, desc, analysis, queue, ctl))
}

/// [`run_frames`] inside the caller's tokio runtime: the source runs in the awaiting task,
/// decoding and analysis on threads of their own, and the end of the run (joining those
/// threads, the last checkpoint, the final records) on the runtime's blocking pool.
pub async fn run_frames_async(
    spec: SourceSpec,
    desc: &FrameDescriptor,
    analysis: RunAnalysis,
    queue: &RecordQueue,
    ctl: &RunControl,
) -> Result<RunOutcome> {
    ctl.progress.input_ended.store(false, Ordering::SeqCst);
    ctl.progress.input_len.store(0, Ordering::Relaxed);
    let (src_tx, mut src_rx) = tokio::sync::mpsc::channel(spec.queue_capacity());
    // Chunks come back from the analysis to be cleared and reused here: the decoded frames are
    // freed by the thread that allocated them, and the chunk vectors are not reallocated
    // (profiled: fewer page faults and allocator calls than a fresh vector per chunk).
    let (recycle_tx, recycle_rx) = crossbeam_channel::bounded::<Chunk>(CHUNK_QUEUE + 2);
    let live = spec.is_live();
    let udp = matches!(spec, SourceSpec::Udp { .. });
    let replay = matches!(spec, SourceSpec::File { .. });
    let plan = ctl.checkpoint.clone();
    let mut analysis = analysis;
    let mut start_offset = 0;
    let mut stage = match plan.as_ref().and_then(|p| p.resume.as_ref()) {
        None => DecodeStage::new(desc.clone(), live),
        Some((Position::Frames { offset, stage }, _)) if replay => {
            start_offset = *offset;
            DecodeStage::restore_replay(desc.clone(), stage)
        }
        Some((Position::Frames { stage, .. }, _)) => {
            // A stream that cannot be rewound: what was lost while the program was down is a
            // gap (the first frame is placed by counter and time), and no difference spans it.
            analysis.break_segments();
            DecodeStage::restore_live(desc.clone(), live, stage)
        }
        Some((Position::Text(_), _)) => {
            anyhow::bail!("the checkpoint is of text columns, this run reads frames")
        }
    };
    let parts = if live { 1 } else { replay_threads() };
    let (chunk_tx, workers, collector) = spawn_analysis(
        analysis,
        parts,
        Some(recycle_tx),
        queue.clone(),
        ctl.every_wall,
        plan.as_deref(),
        ctl.metrics.clone(),
    )?;
    let progress = ctl.progress.clone();
    let mut schedule = plan.as_deref().map(|p| Schedule::new(p, desc.tau0_s()));
    let ck = collector
        .as_ref()
        .map(|c| (c.sender(), c.in_flight.clone(), c.written.clone()));
    let abort_after = plan.as_ref().and_then(|p| p.abort_after_frames);
    let metrics = ctl.metrics.clone();
    let kinds = crate::frame::column_kinds(desc);
    let hook = ctl.crash_hook.clone();
    let decode = std::thread::Builder::new()
        .name("allanscope-decode".into())
        .spawn(move || {
            let mut offset = start_offset;
            // Blocks with the decoder's column kinds, so its frames join them column by column.
            let fresh = || match recycle_rx.try_recv() {
                Ok(Chunk::Block(mut b)) => {
                    b.reset_kinds(&kinds);
                    b
                }
                _ => FrameBlock::with_kinds(&kinds, CHUNK_EVENTS_RESERVE),
            };
            let mut events = fresh();
            let mut open = true;
            let mut crashed = false;
            while let Some(ev) = src_rx.blocking_recv() {
                if let SourceEvent::Data { bytes, .. } | SourceEvent::Datagram { bytes, .. } = &ev {
                    offset += bytes.len() as u64;
                }
                let before = events.len();
                let n = stage.push(ev, &mut events);
                progress.frames.fetch_add(n, Ordering::Relaxed);
                if let Some(m) = &metrics {
                    m.health(&stage.health());
                }
                let due = match (&mut schedule, &ck) {
                    (Some(s), Some((_, in_flight, _))) => {
                        s.add_steps(events.steps_from(before));
                        s.due(in_flight)
                    }
                    _ => false,
                };
                if !events.is_empty()
                    && (due || events.len() >= SEND_CHUNK_EVENTS || src_rx.is_empty())
                {
                    let chunk = Chunk::Block(std::mem::replace(&mut events, fresh()));
                    if !chunk_tx.send(chunk) {
                        open = false;
                        break;
                    }
                }
                if let (true, Some(s), Some((tx, in_flight, _))) = (due, &schedule, &ck) {
                    // Every step before this point has been sent: the mark follows them.
                    match stage.state() {
                        Some(st) => {
                            let position = Position::Frames {
                                offset,
                                stage: Box::new(st),
                            };
                            let _ = tx.send(Piece::Position {
                                seq: s.seq,
                                position: Box::new(position),
                            });
                            if !chunk_tx.send(Chunk::Checkpoint(s.seq)) {
                                open = false;
                                break;
                            }
                        }
                        None => in_flight.store(false, Ordering::SeqCst),
                    }
                }
                if let (Some(limit), Some((_, _, written))) = (abort_after, &ck) {
                    if !crashed && progress.frames() >= limit {
                        crash_point(written, hook.as_ref());
                        crashed = true;
                    }
                }
            }
            let n = stage.finish(&mut events);
            progress.frames.fetch_add(n, Ordering::Relaxed);
            if open && !events.is_empty() {
                chunk_tx.send(Chunk::Block(events));
            }
            (stage, offset)
        })
        .context("cannot start the decode thread")?;
    let source_result = async {
        let capture = ctl
            .capture
            .as_ref()
            .and_then(CaptureSlot::take)
            .map(|f| Capture::new(f, ctl.progress.capture.clone()));
        let ctx = SourceContext {
            start_offset,
            tx: src_tx,
            shutdown: ctl.shutdown.clone(),
            capture,
            progress: ctl.progress.clone(),
        };
        crate::source::run(spec, ctx).await
    }
    .await;
    let (ctl, queue) = (ctl.clone(), queue.clone());
    let finish = move || -> Result<RunOutcome> {
        let (stage, offset) = decode
            .join()
            .map_err(|_| anyhow::anyhow!("the decode thread panicked"))?;
        let analysis = join_analysis(workers)?;
        let written = collector.map(Collector::finish);
        source_result?;
        let flags = SourceFlags { live, udp, replay };
        let end = FramesEnd {
            stage,
            offset,
            written,
            plan,
        };
        finish_frames(end, flags, analysis, &queue, &ctl)
    };
    tokio::task::spawn_blocking(finish)
        .await
        .map_err(|_| anyhow::anyhow!("the thread finishing the run panicked"))?
}

/// What kind of source a run of frames read, for its closing records.
#[derive(Clone, Copy)]
struct SourceFlags {
    live: bool,
    udp: bool,
    replay: bool,
}

/// Where the decode stage of a run of frames ended, for its last checkpoint.
struct FramesEnd {
    stage: DecodeStage,
    /// Bytes read from the input, from its start.
    offset: u64,
    /// Checkpoints written during the run (`None` without checkpoints).
    written: Option<u64>,
    plan: Option<Arc<CheckpointPlan>>,
}

/// The end of a run of frames: the last checkpoint, the health record, the final records.
fn finish_frames(
    end: FramesEnd,
    flags: SourceFlags,
    mut analysis: RunAnalysis,
    queue: &RecordQueue,
    ctl: &RunControl,
) -> Result<RunOutcome> {
    let replay = flags.replay;
    let FramesEnd {
        stage,
        offset,
        written,
        plan,
    } = end;
    if let (Some(plan), Some(written), Some(st)) = (&plan, written, stage.state()) {
        let complete = !(replay && ctl.shutdown.is_cancelled());
        let position = Position::Frames {
            offset,
            stage: Box::new(st),
        };
        final_checkpoint(plan, written, complete, position, &analysis);
    }
    let health = stage.health();
    let capture = ctl.capture.is_some().then_some(&*ctl.progress.capture);
    let record = stage_health_record(&stage, analysis.summary().run, flags, capture);
    if let Some(m) = &ctl.metrics {
        m.health(&health);
    }
    let read_to_end = ctl.progress.input_ended();
    finish_records(&mut analysis, Some(record), queue, ctl);
    Ok(RunOutcome {
        analysis,
        health: Some(health),
        read_to_end,
    })
}

/// Runs text columns (rows of `width` values) through the analysis; `rows_per_s` paces the
/// reading at the data's own rate. Then queues the final records and the summary.
///
/// Blocks like [`run_frames`]; inside a tokio runtime, await [`run_text_async`].
pub fn run_text<R: BufRead + Send + 'static>(
    reader: TextReader<R>,
    path: PathBuf,
    rows_per_s: Option<f64>,
    analysis: RunAnalysis,
    queue: &RecordQueue,
    ctl: &RunControl,
) -> Result<RunOutcome> {
    block_on(run_text_async(
        reader, path, rows_per_s, analysis, queue, ctl,
    ))
}

/// [`run_text`] inside the caller's tokio runtime: the reader runs on the runtime's blocking
/// pool, the analysis on a thread of its own.
pub async fn run_text_async<R: BufRead + Send + 'static>(
    reader: TextReader<R>,
    path: PathBuf,
    rows_per_s: Option<f64>,
    analysis: RunAnalysis,
    queue: &RecordQueue,
    ctl: &RunControl,
) -> Result<RunOutcome> {
    let width = reader.names().len();
    let plan = ctl.checkpoint.clone();
    let tau0 = analysis.tau0_s();
    let (tx, workers, collector) = spawn_analysis(
        analysis,
        1,
        None,
        queue.clone(),
        ctl.every_wall,
        plan.as_deref(),
        ctl.metrics.clone(),
    )?;
    let mut schedule = plan.as_deref().map(|p| Schedule::new(p, tau0));
    let ck = collector
        .as_ref()
        .map(|c| (c.sender(), c.in_flight.clone(), c.written.clone()));
    let abort_after = plan.as_ref().and_then(|p| p.abort_after_frames);
    let hook = ctl.crash_hook.clone();
    let shutdown = ctl.shutdown.clone();
    let path_shown = path.clone();
    let progress = ctl.progress.clone();
    progress.input_ended.store(false, Ordering::SeqCst);
    let read = move || -> Result<crate::input::text::TextPosition> {
        let mut reader = reader;
        let mut crashed = false;
        let started = Instant::now();
        let batch = rows_per_s.map_or(BATCH_ROWS, |r| ((r * 0.02) as usize).clamp(1, BATCH_ROWS));
        while !shutdown.is_cancelled() {
            let mut values = Vec::with_capacity(batch * width);
            let n = reader
                .read_rows(&mut values, batch)
                .with_context(|| format!("reading {}", path.display()))?;
            if n == 0 {
                progress.input_ended.store(true, Ordering::SeqCst);
                break;
            }
            if !tx.send(Chunk::Rows { values, width }) {
                break;
            }
            if let (Some(s), Some((ptx, in_flight, _))) = (&mut schedule, &ck) {
                s.add_steps(n as u64);
                if s.due(in_flight) {
                    let position = Position::Text(Box::new(reader.position()));
                    let _ = ptx.send(Piece::Position {
                        seq: s.seq,
                        position: Box::new(position),
                    });
                    if !tx.send(Chunk::Checkpoint(s.seq)) {
                        break;
                    }
                }
            }
            if let (Some(limit), Some((_, _, written))) = (abort_after, &ck) {
                if !crashed && reader.rows() >= limit {
                    crash_point(written, hook.as_ref());
                    crashed = true;
                }
            }
            if let Some(r) = rows_per_s {
                let due = started + Duration::from_secs_f64(reader.rows() as f64 / r);
                std::thread::sleep(due.saturating_duration_since(Instant::now()));
            }
        }
        Ok(reader.position())
    };
    let result = tokio::task::spawn_blocking(read)
        .await
        .map_err(|_| anyhow::anyhow!("the reader thread panicked"))
        .and_then(|r| r);
    let (ctl, queue) = (ctl.clone(), queue.clone());
    let finish = move || finish_text(result, path_shown, workers, collector, plan, &queue, &ctl);
    tokio::task::spawn_blocking(finish)
        .await
        .map_err(|_| anyhow::anyhow!("the thread finishing the run panicked"))?
}

/// The end of a run of text columns: the reader's position checked (no samples at all is an
/// error), the last checkpoint, the final records.
fn finish_text(
    result: Result<crate::input::text::TextPosition>,
    path_shown: PathBuf,
    workers: Vec<std::thread::JoinHandle<RunAnalysis>>,
    collector: Option<Collector>,
    plan: Option<Arc<CheckpointPlan>>,
    queue: &RecordQueue,
    ctl: &RunControl,
) -> Result<RunOutcome> {
    let mut analysis = join_analysis(workers)?;
    let written = collector.map(Collector::finish);
    let position = result?;
    if position.samples == 0 && !ctl.shutdown.is_cancelled() {
        return Err(UsageError::Input {
            file: path_shown,
            line: position.line_no,
            problem: crate::input::text::no_samples_problem(position.invalid_values),
        }
        .into());
    }
    analysis.set_time_column(position.time.as_ref());
    if let (Some(plan), Some(written)) = (&plan, written) {
        // The analysis state leaves the reader's bad rows out (the position holds them).
        let complete = !(plan.data_seconds && ctl.shutdown.is_cancelled());
        let bad_rows = position.bad_rows;
        let invalid = position.invalid_values;
        let words = position.words;
        final_checkpoint(
            plan,
            written,
            complete,
            Position::Text(Box::new(position)),
            &analysis,
        );
        analysis.add_bad_rows(bad_rows);
        analysis.add_invalid_values(invalid);
        analysis.add_flagged_cells(words);
    } else {
        analysis.add_bad_rows(position.bad_rows);
        analysis.add_invalid_values(position.invalid_values);
        analysis.add_flagged_cells(position.words);
    }
    let read_to_end = ctl.progress.input_ended();
    finish_records(&mut analysis, None, queue, ctl);
    Ok(RunOutcome {
        analysis,
        health: None,
        read_to_end,
    })
}

/// Analysis threads for a replay: the decode thread is the third busy thread on the
/// project's 2-core machine, and the accumulators are the critical path (BENCHMARKS.md, "Live
/// pipeline"): two analysis threads, each with half the channels, cut the replay's wall time.
/// Live sources use one (their rate is low, and fewer threads wake per frame).
pub const REPLAY_ANALYSIS_THREADS: usize = 2;

/// [`REPLAY_ANALYSIS_THREADS`], at most the cores available; `ALLANSCOPE_ANALYSIS_THREADS`
/// overrides it (for measurements).
fn replay_threads() -> usize {
    if let Some(n) = std::env::var("ALLANSCOPE_ANALYSIS_THREADS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
    {
        return n.max(1);
    }
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    REPLAY_ANALYSIS_THREADS.min(cores)
}

/// Hands every chunk to each analysis thread (shared, not copied).
#[derive(Clone)]
struct ChunkSender(Vec<crossbeam_channel::Sender<Arc<Chunk>>>);

impl ChunkSender {
    /// False when the analysis has gone.
    fn send(&self, c: Chunk) -> bool {
        let c = Arc::new(c);
        self.0.iter().all(|tx| tx.send(c.clone()).is_ok())
    }
}

/// The analysis threads, `parts` of them, each with consecutive channels of `analysis`: chunks
/// in, interim records out (on the data-second schedule of the options, or every `every_wall`
/// of wall time). A consumed chunk goes back on `recycle` from the thread that drops it last.
#[allow(clippy::type_complexity)]
fn spawn_analysis(
    analysis: RunAnalysis,
    parts: usize,
    recycle: Option<crossbeam_channel::Sender<Chunk>>,
    queue: RecordQueue,
    every_wall: Option<Duration>,
    plan: Option<&CheckpointPlan>,
    metrics: Option<MetricsTap>,
) -> Result<(
    ChunkSender,
    Vec<std::thread::JoinHandle<RunAnalysis>>,
    Option<Collector>,
)> {
    let mut txs = Vec::new();
    let mut handles = Vec::new();
    let split = analysis.split(parts);
    let collector = match plan {
        Some(p) => Some(Collector::spawn(p, split.len())?),
        None => None,
    };
    for (index, mut part) in split.into_iter().enumerate() {
        let (tx, rx) = crossbeam_channel::bounded::<Arc<Chunk>>(CHUNK_QUEUE);
        txs.push(tx);
        let (queue, recycle) = (queue.clone(), recycle.clone());
        let pieces = collector.as_ref().map(Collector::sender);
        let metrics = metrics.clone();
        let h = std::thread::Builder::new()
            .name("allanscope-analysis".into())
            .spawn(move || {
                // Stopped by a signal: the frames read still count, their interim records are
                // not made (RunAnalysis::stop_interim_when).
                let stopping = queue.stopping();
                part.stop_interim_when(stopping.clone());
                let mut out = Vec::new();
                let tick =
                    every_wall.map_or_else(crossbeam_channel::never, crossbeam_channel::tick);
                loop {
                    crossbeam_channel::select! {
                        recv(rx) -> chunk => match chunk {
                            Ok(c) => {
                                if let (Chunk::Checkpoint(seq), Some(p)) = (&*c, &pieces) {
                                    let _ = p.send(Piece::Part {
                                        seq: *seq,
                                        index,
                                        state: part.snapshot(),
                                    });
                                }
                                part.push_chunk(&c, &mut out);
                                if let (Some(r), Ok(c)) = (&recycle, Arc::try_unwrap(c)) {
                                    let _ = r.try_send(c);
                                }
                            }
                            Err(_) => break,
                        },
                        recv(tick) -> _ => if !stopping.load(Ordering::Relaxed) {
                            out.extend(part.records(false));
                        },
                    }
                    for r in out.drain(..) {
                        if let Some(m) = &metrics {
                            m.observe(&r);
                        }
                        queue.push_interim(r);
                    }
                }
                part
            })
            .context("cannot start an analysis thread")?;
        handles.push(h);
    }
    Ok((ChunkSender(txs), handles, collector))
}

/// The crash point of [`RunControl::crash_hook`]: once a checkpoint is on disk (waiting up to a
/// minute for one), the hook runs; the binary's hook aborts the process as a crash would.
fn crash_point(written: &std::sync::atomic::AtomicU64, hook: Option<&CrashHook>) {
    let Some(hook) = hook else { return };
    let until = Instant::now() + Duration::from_secs(60);
    while written.load(Ordering::SeqCst) == 0 && Instant::now() < until {
        std::thread::sleep(Duration::from_millis(2));
    }
    (hook.0)();
}

/// The checkpoint at the end of a run (after the collector has stopped, so no older one can
/// overwrite it).
fn final_checkpoint(
    plan: &CheckpointPlan,
    written: u64,
    complete: bool,
    position: Position,
    analysis: &RunAnalysis,
) {
    let ck = Checkpoint {
        header: plan.header.clone(),
        every_s: plan.every_s,
        sequence: plan.resume.as_ref().map_or(0, |r| r.1).max(written) + 1,
        complete,
        saved_unix_s: checkpoint::unix_now_s(),
        position,
        analysis: analysis.snapshot(),
    };
    let t = Instant::now();
    match ck.write_atomic(&plan.path) {
        Ok(n) => tracing::info!(
            "checkpoint {} written ({} bytes, {:.1} ms){}",
            plan.path.display(),
            n,
            t.elapsed().as_secs_f64() * 1e3,
            if complete {
                ""
            } else {
                "; the run can be resumed with --resume"
            }
        ),
        Err(e) => tracing::warn!("final checkpoint not written: {e:#}"),
    }
}

/// Waits for the analysis threads and puts their channels back together.
fn join_analysis(handles: Vec<std::thread::JoinHandle<RunAnalysis>>) -> Result<RunAnalysis> {
    let mut parts = Vec::new();
    for h in handles {
        parts.push(
            h.join()
                .map_err(|_| anyhow::anyhow!("an analysis thread panicked"))?,
        );
    }
    RunAnalysis::join(parts).ok_or_else(|| anyhow::anyhow!("no analysis thread"))
}

/// Runs a run's future on a current-thread tokio runtime built here, for callers outside any
/// runtime; inside one it refuses (blocking there would stall the caller's runtime).
pub(crate) fn block_on<F, T>(fut: F) -> Result<T>
where
    F: std::future::Future<Output = Result<T>>,
{
    if tokio::runtime::Handle::try_current().is_ok() {
        anyhow::bail!(
            "run_frames and run_text block the calling thread: inside a tokio runtime, await \
             run_frames_async or run_text_async instead"
        );
    }
    tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .context("cannot start the I/O runtime")?
        .block_on(fut)
}

/// The final curve and fit records, the health record and the summary, never coalesced. The
/// summary says whether the input was read to its end, what stopped the run otherwise, and
/// whether the capture file failed.
fn finish_records(
    analysis: &mut RunAnalysis,
    health: Option<HealthRecord>,
    queue: &RecordQueue,
    ctl: &RunControl,
) {
    let metrics = ctl.metrics.as_ref();
    for r in analysis.records(true) {
        if let Some(m) = metrics {
            m.observe(&r);
        }
        queue.push_final(r);
    }
    if let Some(h) = health {
        queue.push_final(Record::Health(h));
    }
    let mut summary = analysis.summary();
    let p = &ctl.progress;
    summary.read_to_end = p.input_ended();
    summary.stopped_by = (!summary.read_to_end)
        .then(|| p.stopped_by())
        .flatten()
        .map(String::from);
    if ctl.capture.is_some() {
        summary.capture_error = p.capture.error();
    }
    queue.push_final(Record::Summary(summary));
}

/// The `health` record of a decode stage at the end of a run: the decoder's counts
/// ([`HealthRecord::new`]), the UDP reorder window's and the live outages' counters, and the
/// capture's bytes and error.
fn stage_health_record(
    stage: &DecodeStage,
    run: Option<usize>,
    flags: SourceFlags,
    capture: Option<&crate::source::CaptureStatus>,
) -> HealthRecord {
    let mut record = HealthRecord::new(&stage.health(), run);
    if let Some(r) = stage.reorder_stats().filter(|_| flags.udp) {
        record.udp_reordered = Some(r.reordered);
        record.udp_duplicates = Some(r.duplicates);
        record.udp_late = Some(r.late);
    }
    if flags.live {
        record.outages = Some(stage.outage.outages);
        record.outage_missing = Some(stage.outage.missing);
    }
    if let Some(c) = capture {
        record.capture_bytes = Some(c.bytes());
        record.capture_error = c.error();
    }
    record
}
