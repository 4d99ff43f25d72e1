//! The threads of checkpointing: the [`Schedule`] the reading stage keeps (when the next
//! checkpoint is due) and the [`Collector`] thread that assembles the pieces of a consistent cut
//! (the reader's position, each analysis thread's snapshot) and writes the file through
//! [`super::checkpoint`], which owns the format.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Instant;

use super::checkpoint::{unix_now_s, Checkpoint, CheckpointPlan, Position};
use crate::analysis::AnalysisState;

/// One piece of a checkpoint on its way to the collector.
pub enum Piece {
    Position {
        seq: u64,
        position: Box<Position>,
    },
    Part {
        seq: u64,
        index: usize,
        state: AnalysisState,
    },
}

/// The collector thread: assembles the pieces of each checkpoint and writes it.
pub struct Collector {
    tx: crossbeam_channel::Sender<Piece>,
    handle: std::thread::JoinHandle<()>,
    /// Cleared when the checkpoint in flight has been written (or failed).
    pub in_flight: Arc<AtomicBool>,
    /// Checkpoints written.
    pub written: Arc<AtomicU64>,
}

/// What a run's checkpointing did (logged at the end).
#[derive(Debug, Clone, Copy, Default)]
pub struct CollectorStats {
    pub written: u64,
    pub failed: u64,
    pub last_bytes: usize,
    pub last_write_s: f64,
}

impl Collector {
    /// Starts the collector for a run with `parts` analysis threads.
    pub fn spawn(plan: &CheckpointPlan, parts: usize) -> anyhow::Result<Collector> {
        let (tx, rx) = crossbeam_channel::unbounded::<Piece>();
        let in_flight = Arc::new(AtomicBool::new(false));
        let written = Arc::new(AtomicU64::new(0));
        let (flag, count) = (in_flight.clone(), written.clone());
        let (path, header, every_s) = (plan.path.clone(), plan.header.clone(), plan.every_s);
        let handle = std::thread::Builder::new()
            .name("allanscope-checkpoint".into())
            .spawn(move || {
                let mut seq = 0;
                let mut position = None;
                let mut states: Vec<Option<AnalysisState>> = vec![None; parts];
                for piece in rx {
                    match piece {
                        Piece::Position {
                            seq: s,
                            position: p,
                        } => {
                            seq = s;
                            position = Some(*p);
                            states.iter_mut().for_each(|x| *x = None);
                        }
                        Piece::Part {
                            seq: s,
                            index,
                            state,
                        } if s == seq && index < parts => states[index] = Some(state),
                        Piece::Part { .. } => continue,
                    }
                    if position.is_none() || states.iter().any(Option::is_none) {
                        continue;
                    }
                    let parts_done: Vec<AnalysisState> =
                        states.iter_mut().filter_map(Option::take).collect();
                    let ck = Checkpoint {
                        header: header.clone(),
                        every_s,
                        sequence: seq,
                        complete: false,
                        saved_unix_s: unix_now_s(),
                        position: position.take().expect("checked above"),
                        analysis: join_states(parts_done),
                    };
                    let t = Instant::now();
                    match ck.write_atomic(&path) {
                        Ok(n) => {
                            count.fetch_add(1, Ordering::SeqCst);
                            tracing::debug!(
                                "checkpoint {seq}: {} ({n} bytes, {:.1} ms)",
                                path.display(),
                                t.elapsed().as_secs_f64() * 1e3
                            );
                        }
                        Err(e) => tracing::warn!("checkpoint not written: {e:#}"),
                    }
                    flag.store(false, Ordering::SeqCst);
                }
            })
            .map_err(|e| anyhow::anyhow!("cannot start the checkpoint thread: {e}"))?;
        Ok(Collector {
            tx,
            handle,
            in_flight,
            written,
        })
    }

    /// The sending side, for the stages.
    pub fn sender(&self) -> crossbeam_channel::Sender<Piece> {
        self.tx.clone()
    }

    /// Waits for the checkpoint in flight, if any, and stops the thread.
    pub fn finish(self) -> u64 {
        drop(self.tx);
        let _ = self.handle.join();
        self.written.load(Ordering::SeqCst)
    }
}

/// The analysis parts of one run (consecutive channels) put back together.
pub fn join_states(parts: Vec<AnalysisState>) -> AnalysisState {
    let mut it = parts.into_iter();
    let mut first = it.next().unwrap_or(AnalysisState {
        input: String::new(),
        channels: Vec::new(),
        next_emit_s: f64::INFINITY,
        bad_rows: 0,
        elapsed_s: 0.0,
    });
    for p in it {
        first.channels.extend(p.channels);
        first.bad_rows += p.bad_rows;
        first.next_emit_s = first.next_emit_s.max(p.next_emit_s);
    }
    first
}

/// When the next checkpoint is due: after `every_s` data-seconds (counted in steps) or
/// wall-seconds.
pub struct Schedule {
    every_s: f64,
    data_seconds: bool,
    tau0_s: f64,
    steps: u64,
    next_steps: u64,
    next_wall: Instant,
    pub seq: u64,
}

impl Schedule {
    pub fn new(plan: &CheckpointPlan, tau0_s: f64) -> Schedule {
        // Checked against `crate::ranges` where parsed; clamped here too, so that no value can
        // overflow the clock or make the wall-clock advance below a loop that never ends.
        let every_s = if plan.every_s.is_finite() {
            plan.every_s
                .clamp(crate::ranges::MIN_INTERVAL_S, crate::ranges::MAX_SECONDS)
        } else {
            crate::ranges::MAX_SECONDS
        };
        let every_steps = ((every_s / tau0_s).round() as u64).max(1);
        Schedule {
            every_s,
            data_seconds: plan.data_seconds,
            tau0_s,
            steps: 0,
            next_steps: every_steps,
            next_wall: Instant::now() + std::time::Duration::from_secs_f64(every_s),
            seq: plan.resume.as_ref().map_or(0, |r| r.1),
        }
    }

    /// Counts steps read (frames and lost frames, or rows).
    pub fn add_steps(&mut self, n: u64) {
        self.steps += n;
    }

    /// True when a checkpoint is due and none is in flight; then the next is scheduled and the
    /// sequence number advanced.
    pub fn due(&mut self, in_flight: &AtomicBool) -> bool {
        let now = Instant::now();
        let due = if self.data_seconds {
            self.steps >= self.next_steps
        } else {
            now >= self.next_wall
        };
        if !due || in_flight.swap(true, Ordering::SeqCst) {
            return false;
        }
        let every_steps = ((self.every_s / self.tau0_s).round() as u64).max(1);
        if self.next_steps <= self.steps {
            // The first multiple of the interval after the steps read, without a loop (a long
            // gap of lost frames can jump the count by many intervals).
            let behind = (self.steps - self.next_steps) / every_steps + 1;
            self.next_steps = self
                .next_steps
                .saturating_add(behind.saturating_mul(every_steps));
        }
        if self.next_wall <= now {
            let wall = std::time::Duration::from_secs_f64(self.every_s);
            let behind = now.duration_since(self.next_wall).as_secs_f64() / wall.as_secs_f64();
            self.next_wall += wall.mul_f64(behind.floor() + 1.0);
        }
        self.seq += 1;
        true
    }
}
