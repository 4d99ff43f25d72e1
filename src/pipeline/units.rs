//! Several units in one process (a stand config's `[[unit]]` tables): each unit's source is a
//! tokio task, and a small pool of worker threads, as many as the machine has cores, decodes
//! and analyses every unit — not a thread per unit or per channel.
//!
//! ```text
//!  unit source tasks (tokio)  --(unit, SourceEvent)-->  worker threads (available_parallelism)
//!  file/serial/udp, one each    mpsc, WORK_QUEUE         each owns a fixed share of the units:
//!                                                        DecodeStage + RunAnalysis per unit
//!                                                         --(unit, Record)--> writer thread
//! ```
//!
//! - A unit belongs to one worker for the whole run (unit `i` to worker `i % workers`), so its
//!   frames are decoded and analysed in order, on one thread, by the same code as a one-unit
//!   run ([`super::decode::DecodeStage`], [`crate::analysis::RunAnalysis`]): its records carry
//!   the same numbers as its frames analysed alone.
//! - Every channel is bounded. A unit's source waits when its worker is behind (a file:
//!   back-pressure; a socket or serial port: the kernel buffer takes the slack).
//! - A live unit silent for `quiet_after` wall-seconds is recorded as out (an `outage` record,
//!   `event: "quiet"`), and as back (`"resumed"`) when bytes come again; a unit whose source
//!   stops with an error is recorded (`"failed"`) and the others go on. Each unit ends with its
//!   own final records, health and summary, every record tagged with its name
//!   ([`crate::sink::unit_record`]).
//! - Interim records of live units come every `every_wall` of wall time (one timer for all);
//!   replayed units keep their data-second schedule.
//! - Checkpoints are per unit (`OUTPUT.NAME.ckpt`, [`crate::plan::run::RunPlan::from_stand`]):
//!   the worker that owns a unit writes its decoder state, byte offset and analysis state
//!   together (one thread holds all three, so no marks travel between threads as in the one-unit
//!   pipeline), every `every_s` of data (a file) or wall time (live), and once more at the end.
//!   The `--abort-after-frames` test hook ([`UnitsControl::crash_hook`]) fires once the units
//!   together have decoded that many frames and each has a checkpoint on disk.
//! - A live unit's frames reach its analysis in blocks of [`LIVE_BLOCK_EVENTS`] (and whenever
//!   records or a checkpoint are due), a replay's whenever its worker's queue runs dry.

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use tokio::sync::mpsc;
use tokio_util::sync::CancellationToken;

use super::checkpoint::{Checkpoint, CheckpointPlan, Position};
use super::decode::DecodeStage;
use super::{stage_health_record, CrashHook, RecordQueue, SourceFlags};
use crate::analysis::RunAnalysis;
use crate::frame::{FrameBlock, FrameDescriptor};
use crate::input::Chunk;
use crate::sink::metrics::MetricsTap;
use crate::sink::records::{OutageRecord, Record};
use crate::source::{Capture, CaptureSlot, Progress, SourceContext, SourceEvent, SourceSpec};

/// Capacity of each worker's queue, in source events (a datagram or a read of a few frames):
/// 4096 events are about 0.2 s of 100 units sending 10-frame datagrams at 2 kHz, enough to ride
/// out a scheduling hiccup of a worker on a loaded machine without the kernel dropping any.
pub const WORK_QUEUE: usize = 4096;

/// Frames of one unit gathered before they go to its analysis when the worker has more events
/// waiting: bounds the block's memory, as the one-unit pipeline's chunk limit does.
const MAX_BLOCK_EVENTS: usize = 4096;

/// Frames (events) of a live unit gathered before they go to its analysis. A live unit's
/// datagrams are a few frames each; handing them to the accumulators one datagram at a time
/// touched every level of 600 channels' state (cold in the cache) for 10 samples each, and cost
/// several times the replay's statistics per sample (BENCHMARKS.md, "Several units live"). A
/// live block is analysed when it holds this many events, and whenever its records or a
/// checkpoint are due and at the end, so no record misses a frame: 1024 events are 0.5 s of a
/// 2 kHz unit, 100 KB of a 6-channel one.
pub const LIVE_BLOCK_EVENTS: usize = 1024;

/// How often the workers look for quiet units: a tenth of a second is well inside any
/// `quiet_after` a user may give (at least `crate::ranges::MIN_INTERVAL_S`).
const WATCH_PERIOD: Duration = Duration::from_millis(100);

/// One unit of the run, ready to start.
pub struct UnitRun {
    /// The unit's name (its records carry it).
    pub name: Arc<str>,
    pub spec: SourceSpec,
    pub desc: FrameDescriptor,
    pub analysis: RunAnalysis,
    /// Every received byte also written here.
    pub capture: Option<CaptureSlot>,
    /// The unit's metrics (label `unit`).
    pub metrics: Option<MetricsTap>,
    /// Counters of this unit (frames, bytes, input read to its end).
    pub progress: Arc<Progress>,
    /// The unit's checkpoints, and the position to resume from.
    pub checkpoint: Option<Arc<CheckpointPlan>>,
}

/// How a run of several units is driven and stopped.
#[derive(Debug, Clone)]
pub struct UnitsControl {
    /// Cancelled by the caller (SIGINT, SIGTERM, `--duration`): every source stops reading.
    pub shutdown: CancellationToken,
    /// Why the run was stopped, for the summaries (`Progress::set_stopped_by`).
    pub progress: Arc<Progress>,
    /// Wall-seconds between interim records of live units.
    pub every_wall: Option<Duration>,
    /// A live unit silent this long is recorded as out.
    pub quiet_after: Duration,
    /// Worker threads; `None`: the machine's cores, at most one per unit.
    pub workers: Option<usize>,
    /// Called once the units together have decoded
    /// [`CheckpointPlan::abort_after_frames`] frames and every unit with checkpoints has one on
    /// disk (so `--resume` can continue each of them); the binary's `--abort-after-frames` test
    /// hook aborts the process there, as a crash would. Without a hook the run goes on.
    pub crash_hook: Option<CrashHook>,
}

/// The crash point of a run of several units ([`UnitsControl::crash_hook`]), shared by the
/// workers: the frames of every unit, and the units still without a checkpoint on disk.
struct CrashWatch {
    limit: u64,
    hook: CrashHook,
    frames: AtomicU64,
    without_checkpoint: AtomicUsize,
    fired: AtomicBool,
}

impl CrashWatch {
    /// The watch of `units`, when a hook is given and the units' checkpoint plans ask for one.
    fn new(units: &[UnitRun], hook: Option<&CrashHook>) -> Option<Arc<CrashWatch>> {
        let plans: Vec<&CheckpointPlan> = units
            .iter()
            .filter_map(|u| u.checkpoint.as_deref())
            .collect();
        let limit = plans.iter().filter_map(|p| p.abort_after_frames).min()?;
        Some(Arc::new(CrashWatch {
            limit,
            hook: hook?.clone(),
            frames: AtomicU64::new(0),
            without_checkpoint: AtomicUsize::new(plans.len()),
            fired: AtomicBool::new(false),
        }))
    }

    /// Runs the hook (once) when both conditions hold.
    fn check(&self) {
        if self.frames.load(Ordering::SeqCst) >= self.limit
            && self.without_checkpoint.load(Ordering::SeqCst) == 0
            && !self.fired.swap(true, Ordering::SeqCst)
        {
            (self.hook.0)();
        }
    }
}

/// How one unit ended.
#[derive(Debug, Clone, PartialEq)]
pub struct UnitOutcome {
    pub name: String,
    /// Frames decoded.
    pub frames: u64,
    /// The unit's input was read to its end (a file).
    pub read_to_end: bool,
    /// Times the unit went quiet.
    pub quiet: u64,
    /// The source's error, if it failed.
    pub failed: Option<String>,
}

/// Events a unit's forwarding task gathers into one message to its worker, when that many
/// are waiting (fewer channel operations and wake-ups when the worker is behind).
const FORWARD_BATCH: usize = 64;

/// How long a worker waits after its queue runs dry before it blocks on it again: events
/// gather meanwhile and are taken in one go, so a worker wakes at most ~500 times a second
/// instead of once per datagram (the wake-ups, not the statistics, were most of its CPU in the
/// 100-unit benchmark, BENCHMARKS.md). 2 ms of 100 units' datagrams are well inside
/// [`WORK_QUEUE`].
const WORKER_PAUSE: Duration = Duration::from_millis(2);

/// What goes to a worker.
enum Work {
    /// Events of unit `.0` (the worker's index of it), in order.
    Events(usize, Vec<SourceEvent>),
    /// Unit `.0`'s source has ended (with its error, if it failed).
    Ended(usize, Option<String>),
    /// Interim records of the live units are due.
    Tick,
    /// Look for quiet units.
    Watch,
}

/// A unit as a worker holds it.
struct UnitState {
    run: UnitRun,
    stage: DecodeStage,
    block: FrameBlock,
    width: usize,
    flags: SourceFlags,
    /// When the watch last saw the source's byte count move (the start, before the first).
    last_data: Instant,
    /// The source's byte count then.
    seen_bytes: u64,
    /// Out since this wall time (recorded as quiet).
    quiet_since: Option<Instant>,
    quiet: u64,
    ended: bool,
    failed: Option<String>,
    /// Bytes of the input consumed (from its start: a resumed replay starts at its offset).
    offset: u64,
    /// Checkpoints written (the resumed one's sequence included).
    sequence: u64,
    /// When the next checkpoint is due: data-seconds (a file) or wall time (live).
    next_data_s: f64,
    next_wall: Instant,
    /// A checkpoint of this run is on disk.
    checkpointed: bool,
    /// The run's crash point, if any.
    crash: Option<Arc<CrashWatch>>,
}

impl UnitState {
    fn new(mut run: UnitRun, crash: Option<Arc<CrashWatch>>) -> UnitState {
        let live = run.spec.is_live();
        let replay = matches!(run.spec, SourceSpec::File { .. });
        let width = run.desc.frame().channels.len();
        let (mut offset, mut sequence) = (0, 0);
        let resume = run.checkpoint.as_ref().and_then(|p| p.resume.clone());
        let stage = match resume {
            Some((Position::Frames { offset: o, stage }, seq)) => {
                sequence = seq;
                if replay {
                    offset = o;
                    DecodeStage::restore_replay(run.desc.clone(), &stage)
                } else {
                    // A stream that cannot be rewound: the time it was down is a gap that no
                    // difference spans (as in the one-unit pipeline).
                    run.analysis.break_segments();
                    DecodeStage::restore_live(run.desc.clone(), live, &stage)
                }
            }
            _ => DecodeStage::new(run.desc.clone(), live),
        };
        let every = run.checkpoint.as_ref().map_or(0.0, |p| p.every_s);
        UnitState {
            offset,
            sequence,
            next_data_s: run.analysis.t_data_s() + every,
            next_wall: Instant::now() + Duration::from_secs_f64(every),
            stage,
            block: FrameBlock::with_kinds(&crate::frame::column_kinds(&run.desc), 64),
            width,
            flags: SourceFlags {
                live,
                udp: matches!(run.spec, SourceSpec::Udp { .. }),
                replay: matches!(run.spec, SourceSpec::File { .. }),
            },
            last_data: Instant::now(),
            seen_bytes: 0,
            quiet_since: None,
            quiet: 0,
            ended: false,
            failed: None,
            checkpointed: false,
            crash,
            run,
        }
    }

    fn push_records(&self, out: &mut Vec<Record>, queue: &RecordQueue) {
        for r in out.drain(..) {
            if let Some(m) = &self.run.metrics {
                m.observe(&r);
            }
            queue.push_interim_of(Some(&self.run.name), r);
        }
    }

    /// The decoded frames so far go to the analysis.
    fn flush(&mut self, out: &mut Vec<Record>, queue: &RecordQueue) {
        if self.block.is_empty() {
            return;
        }
        let chunk = Chunk::Block(std::mem::take(&mut self.block));
        self.run.analysis.push_chunk(&chunk, out);
        if let Chunk::Block(mut b) = chunk {
            b.reset(self.width);
            self.block = b;
        }
        self.push_records(out, queue);
    }

    /// Writes a checkpoint now if one is due (`force`: at the end, `complete` as given).
    fn checkpoint(&mut self, out: &mut Vec<Record>, queue: &RecordQueue, end: Option<bool>) {
        let Some(plan) = self.run.checkpoint.clone() else {
            return;
        };
        if plan.every_s <= 0.0 && end.is_none() {
            return;
        }
        let due = if plan.data_seconds {
            self.run.analysis.t_data_s() + self.block.frames() as f64 * self.run.desc.tau0_s()
                >= self.next_data_s
        } else {
            Instant::now() >= self.next_wall
        };
        if !due && end.is_none() {
            return;
        }
        self.flush(out, queue);
        let Some(stage) = self.stage.state() else {
            return;
        };
        self.next_data_s = self.run.analysis.t_data_s() + plan.every_s;
        self.next_wall = Instant::now() + Duration::from_secs_f64(plan.every_s);
        self.sequence += 1;
        let ck = Checkpoint {
            header: plan.header.clone(),
            every_s: plan.every_s,
            sequence: self.sequence,
            complete: end.unwrap_or(false),
            saved_unix_s: super::checkpoint::unix_now_s(),
            position: Position::Frames {
                offset: self.offset,
                stage: Box::new(stage),
            },
            analysis: self.run.analysis.snapshot(),
        };
        match ck.write_atomic(&plan.path) {
            Ok(_) if !self.checkpointed => {
                self.checkpointed = true;
                if let Some(c) = &self.crash {
                    c.without_checkpoint.fetch_sub(1, Ordering::SeqCst);
                    c.check();
                }
            }
            Ok(_) => {}
            Err(e) => tracing::warn!(
                "unit {}: checkpoint {} not written: {e:#}",
                self.run.name,
                plan.path.display()
            ),
        }
    }

    fn outage(&self, event: &str, silent: Duration, error: Option<String>) -> Record {
        Record::Outage(OutageRecord {
            event: event.into(),
            at_unix_s: super::checkpoint::unix_now_s(),
            t_data: self.run.analysis.t_data_s(),
            silent_s: silent.as_secs_f64(),
            error,
        })
    }
}

/// Runs every unit until its input ends (files) or shutdown (live sources); then queues each
/// unit's final records, health and summary, in the order of `units`.
///
/// Blocks the calling thread on a tokio runtime of its own; inside a runtime, await
/// [`run_units_async`].
pub fn run_units(
    units: Vec<UnitRun>,
    queue: &RecordQueue,
    ctl: &UnitsControl,
) -> Result<Vec<UnitOutcome>> {
    super::block_on(run_units_async(units, queue, ctl))
}

/// [`run_units`] in the caller's tokio runtime: the sources are tasks of that runtime.
pub async fn run_units_async(
    units: Vec<UnitRun>,
    queue: &RecordQueue,
    ctl: &UnitsControl,
) -> Result<Vec<UnitOutcome>> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let n_workers = ctl.workers.unwrap_or(cores).clamp(1, units.len().max(1));
    let n_units = units.len();
    let crash = CrashWatch::new(&units, ctl.crash_hook.as_ref());
    // Unit i goes to worker i % n_workers, as its (i / n_workers)-th unit.
    let mut shares: Vec<Vec<UnitState>> = (0..n_workers).map(|_| Vec::new()).collect();
    let mut sources = Vec::new();
    for (i, u) in units.into_iter().enumerate() {
        sources.push((
            i % n_workers,
            i / n_workers,
            u.spec.clone(),
            u.capture.clone(),
            u.progress.clone(),
            start_offset(&u),
        ));
        u.progress.input_ended.store(false, Ordering::SeqCst);
        shares[i % n_workers].push(UnitState::new(u, crash.clone()));
    }
    let mut txs = Vec::new();
    let mut workers = Vec::new();
    for (w, share) in shares.into_iter().enumerate() {
        let (tx, rx) = mpsc::channel::<Work>(WORK_QUEUE);
        txs.push(tx);
        let queue = queue.clone();
        let quiet_after = ctl.quiet_after;
        let h = std::thread::Builder::new()
            .name(format!("allanscope-units-{w}"))
            .spawn(move || work(share, rx, &queue, quiet_after))
            .context("cannot start a worker thread")?;
        workers.push(h);
    }
    // One timer for all: interim records of live units, and the watch for quiet ones.
    let timers_stop = CancellationToken::new();
    let timers = {
        let txs = txs.clone();
        let stop = timers_stop.clone();
        let every = ctl.every_wall;
        tokio::spawn(async move {
            let mut watch = tokio::time::interval(WATCH_PERIOD);
            watch.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
            let mut tick = every.map(|e| {
                let mut t = tokio::time::interval_at(tokio::time::Instant::now() + e, e);
                t.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
                t
            });
            loop {
                let work = tokio::select! {
                    _ = stop.cancelled() => break,
                    _ = watch.tick() => Work::Watch,
                    _ = async { tick.as_mut().unwrap().tick().await }, if tick.is_some() => Work::Tick,
                };
                for tx in &txs {
                    let w = match work {
                        Work::Tick => Work::Tick,
                        _ => Work::Watch,
                    };
                    if tx.send(w).await.is_err() {
                        return;
                    }
                }
            }
        })
    };
    let mut tasks = Vec::new();
    for (w, index, spec, capture, progress, start_offset) in sources {
        let wtx = txs[w].clone();
        let shutdown = ctl.shutdown.clone();
        tasks.push(tokio::spawn(async move {
            let (tx, mut rx) = mpsc::channel(spec.queue_capacity());
            let capture = capture
                .as_ref()
                .and_then(CaptureSlot::take)
                .map(|f| Capture::new(f, progress.capture.clone()));
            let ctx = SourceContext {
                start_offset,
                tx,
                shutdown,
                capture,
                progress,
            };
            let forward = async {
                let mut batch = Vec::new();
                while rx.recv_many(&mut batch, FORWARD_BATCH).await > 0 {
                    let evs = std::mem::take(&mut batch);
                    if wtx.send(Work::Events(index, evs)).await.is_err() {
                        break;
                    }
                }
            };
            let (res, ()) = tokio::join!(crate::source::run(spec, ctx), forward);
            let _ = wtx
                .send(Work::Ended(index, res.err().map(|e| format!("{e:#}"))))
                .await;
        }));
    }
    drop(txs);
    for t in tasks {
        t.await
            .map_err(|_| anyhow::anyhow!("a unit's source task panicked"))?;
    }
    timers_stop.cancel();
    let _ = timers.await;
    let (queue, ctl) = (queue.clone(), ctl.clone());
    let finish = move || -> Result<Vec<UnitOutcome>> {
        let mut states: Vec<Option<UnitState>> = (0..n_units).map(|_| None).collect();
        for (w, h) in workers.into_iter().enumerate() {
            let share = h
                .join()
                .map_err(|_| anyhow::anyhow!("a worker thread panicked"))?;
            for (k, s) in share.into_iter().enumerate() {
                states[k * n_workers + w] = Some(s);
            }
        }
        Ok(states
            .into_iter()
            .flatten()
            .map(|s| finish_unit(s, &queue, &ctl))
            .collect())
    };
    tokio::task::spawn_blocking(finish)
        .await
        .map_err(|_| anyhow::anyhow!("the thread finishing the run panicked"))?
}

/// A worker: decodes and analyses its units' events until every source has ended.
fn work(
    mut units: Vec<UnitState>,
    mut rx: mpsc::Receiver<Work>,
    queue: &RecordQueue,
    quiet_after: Duration,
) -> Vec<UnitState> {
    let stopping = queue.stopping();
    for u in &mut units {
        u.run.analysis.stop_interim_when(stopping.clone());
    }
    let mut out = Vec::new();
    let mut dirty: Vec<usize> = Vec::new();
    while let Some(w) = rx.blocking_recv() {
        match w {
            Work::Events(i, evs) => {
                let u = &mut units[i];
                for ev in evs {
                    if let SourceEvent::Data { bytes, .. } | SourceEvent::Datagram { bytes, .. } =
                        &ev
                    {
                        u.offset += bytes.len() as u64;
                    }
                    let before = u.block.len();
                    let n = u.stage.push(ev, &mut u.block);
                    u.run.progress.frames.fetch_add(n, Ordering::Relaxed);
                    if let Some(c) = &u.crash {
                        c.frames.fetch_add(n, Ordering::SeqCst);
                    }
                    // A replay's block goes to the analysis when the queue runs dry; a live
                    // unit's when it is full (LIVE_BLOCK_EVENTS).
                    if before == 0 && !u.block.is_empty() && !u.flags.live {
                        dirty.push(i);
                    }
                    let full = if u.flags.live {
                        LIVE_BLOCK_EVENTS
                    } else {
                        MAX_BLOCK_EVENTS
                    };
                    if u.block.len() >= full {
                        u.flush(&mut out, queue);
                    }
                    u.checkpoint(&mut out, queue, None);
                }
                if let Some(m) = &u.run.metrics {
                    m.health(&u.stage.health());
                }
                if let Some(c) = &u.crash {
                    c.check();
                }
            }
            Work::Ended(i, error) => {
                let u = &mut units[i];
                let n = u.stage.finish(&mut u.block);
                u.run.progress.frames.fetch_add(n, Ordering::Relaxed);
                u.flush(&mut out, queue);
                u.ended = true;
                if let Some(e) = error {
                    tracing::warn!("unit {}: the source failed: {e}", u.run.name);
                    let r = u.outage("failed", u.last_data.elapsed(), Some(e.clone()));
                    queue.push_final_of(Some(&u.run.name), r);
                    u.failed = Some(e);
                }
            }
            Work::Tick => {
                for u in units.iter_mut().filter(|u| u.flags.live && !u.ended) {
                    u.flush(&mut out, queue);
                    if !stopping.load(Ordering::Relaxed) {
                        out.extend(u.run.analysis.records(false));
                        u.push_records(&mut out, queue);
                    }
                }
            }
            Work::Watch => {
                let now = Instant::now();
                for u in units.iter_mut() {
                    if !u.ended {
                        // A quiet live unit still gets its checkpoints on wall time.
                        u.checkpoint(&mut out, queue, None);
                    }
                    // Silence is judged where the bytes arrive (the source's byte count), not
                    // by what this worker has decoded: a worker behind its queue is not a
                    // quiet unit.
                    let bytes = u.run.progress.bytes();
                    if bytes != u.seen_bytes {
                        u.seen_bytes = bytes;
                        u.last_data = now;
                        if let Some(since) = u.quiet_since.take() {
                            u.flush(&mut out, queue);
                            let r = u.outage("resumed", now.saturating_duration_since(since), None);
                            queue.push_final_of(Some(&u.run.name), r);
                        }
                        continue;
                    }
                    let silent = now.saturating_duration_since(u.last_data);
                    if u.flags.live && !u.ended && u.quiet_since.is_none() && silent >= quiet_after
                    {
                        tracing::warn!(
                            "unit {}: no data for {:.1} s",
                            u.run.name,
                            silent.as_secs_f64()
                        );
                        u.quiet_since = Some(u.last_data);
                        u.quiet += 1;
                        // Its record says how far its data reached: every frame decoded.
                        u.flush(&mut out, queue);
                        let r = u.outage("quiet", silent, None);
                        queue.push_final_of(Some(&u.run.name), r);
                    }
                }
            }
        }
        if rx.is_empty() {
            for i in dirty.drain(..) {
                units[i].flush(&mut out, queue);
            }
            std::thread::sleep(WORKER_PAUSE);
        }
    }
    for u in &mut units {
        u.flush(&mut out, queue);
    }
    units
}

/// Where a unit's source starts reading: a resumed replay at its checkpoint's offset.
fn start_offset(u: &UnitRun) -> u64 {
    match (
        &u.spec,
        u.checkpoint.as_ref().and_then(|p| p.resume.as_ref()),
    ) {
        (SourceSpec::File { .. }, Some((Position::Frames { offset, .. }, _))) => *offset,
        _ => 0,
    }
}

/// A unit's end: its last checkpoint, its final records, its health and its summary.
fn finish_unit(mut s: UnitState, queue: &RecordQueue, ctl: &UnitsControl) -> UnitOutcome {
    let name = s.run.name.clone();
    // A replay stopped before its end can be resumed; a live unit's last checkpoint too.
    let complete = !s.flags.replay || s.run.progress.input_ended();
    let mut out = Vec::new();
    s.checkpoint(&mut out, queue, Some(complete));
    let tag = Some(&name);
    for r in s.run.analysis.records(true) {
        if let Some(m) = &s.run.metrics {
            m.observe(&r);
        }
        queue.push_final_of(tag, r);
    }
    let capture = s.run.capture.is_some().then_some(&*s.run.progress.capture);
    let mut health = stage_health_record(&s.stage, None, s.flags, capture);
    if s.flags.live {
        health.quiet_outages = Some(s.quiet);
    }
    if let Some(e) = &s.failed {
        health.source_error = Some(e.clone());
    }
    if let Some(m) = &s.run.metrics {
        m.health(&s.stage.health());
    }
    queue.push_final_of(tag, Record::Health(health));
    let mut summary = s.run.analysis.summary();
    let p = &s.run.progress;
    summary.read_to_end = p.input_ended();
    summary.stopped_by = if summary.read_to_end {
        None
    } else if s.failed.is_some() {
        Some("source_error".into())
    } else {
        ctl.progress.stopped_by().map(String::from)
    };
    if s.run.capture.is_some() {
        summary.capture_error = p.capture.error();
    }
    queue.push_final_of(tag, Record::Summary(summary));
    UnitOutcome {
        name: name.to_string(),
        frames: p.frames(),
        read_to_end: p.input_ended(),
        quiet: s.quiet,
        failed: s.failed,
    }
}
