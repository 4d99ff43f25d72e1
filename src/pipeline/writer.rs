//! The record writer: JSON lines written on a thread of their own, behind a bounded queue.
//!
//! What a full queue does depends on the source ([`Delivery`]):
//!
//! - **Live** (serial, UDP: [`Delivery::Coalesce`]). A slow or stalled consumer of the JSON lines
//!   (a full pipe, a stuck monitor) must not stall ingestion: frames keep being decoded and
//!   accumulated. The queue holds at most [`RECORD_QUEUE`] records; when it is full, an *interim*
//!   record replaces the queued interim records of the same key (record type, channel,
//!   statistic, run): only the newest interim curve of each channel and statistic survives,
//!   which is all a monitor would look at.
//! - **Replay** (files, standard input: [`Delivery::Backpressure`]). A replay has no deadline:
//!   the analysis waits for room instead, so every interim record is written and the output of
//!   a replay never depends on how fast it was read. Once the run is being stopped (SIGINT,
//!   [`RecordQueue::release`]) it coalesces like a live run, so a consumer that stopped reading
//!   cannot hold the stop up.
//!
//! Final records (and health and summary records) are never dropped: they are few (one set per
//! run), so the queue's size stays bounded by `RECORD_QUEUE` plus the number of keys plus the
//! final records.

use std::collections::VecDeque;
use std::io::Write;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::allan::Stat;
use crate::sink::json::JsonLines;
use crate::sink::records::Record;
use crate::sink::unit_record::UnitRecord;

/// Records the queue holds before interim records start to be coalesced (live) or the analysis
/// waits (replay): a few full sets of interim records (8 channels x 3 statistics + 8 fits = 32
/// per set).
pub const RECORD_QUEUE: usize = 256;

/// What the writer thread did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WriterStats {
    /// Records written.
    pub written: u64,
    /// Interim records replaced by a newer one of the same key while the queue was full.
    pub coalesced: u64,
}

/// What a full queue does to the next interim record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Delivery {
    /// The analysis waits until there is room (a replay: no deadline, so every interim record
    /// is written and the output does not depend on how fast the consumer reads).
    Backpressure,
    /// Older interim records of the same key are replaced (a live source: ingestion must never
    /// wait for the consumer).
    Coalesce,
}

#[derive(Default)]
struct QueueState {
    /// Each record, whether it is final, and the named unit it belongs to (a run of several
    /// units, [`crate::sink::unit_record`]).
    items: VecDeque<(Record, bool, Option<Arc<str>>)>,
    closed: bool,
    coalesced: u64,
    /// The writer failed (e.g. the consumer closed the pipe); records are discarded from then on.
    failed: bool,
    /// Back-pressure lifted (the run is being stopped): a full queue coalesces from now on.
    released: bool,
}

struct Shared {
    state: Mutex<QueueState>,
    /// Signalled when records arrive or the queue closes.
    items: Condvar,
    /// Signalled when the writer has taken records (room in the queue) or failed.
    room: Condvar,
    /// Records written so far (the writer's progress, watched by [`RecordWriter::finish_within`]).
    written: AtomicU64,
    /// Set with `QueueState::released`, for the analysis to read without the lock
    /// ([`RecordQueue::stopping`]).
    stopping: Arc<AtomicBool>,
}

/// The sending side of the record queue; cheap to clone.
#[derive(Clone)]
pub struct RecordQueue {
    inner: Arc<Shared>,
    capacity: usize,
    delivery: Delivery,
}

/// The coalescing key of an interim record: type, channel, statistic, run, and the named
/// unit. Interim diagnoses have one too (the newest of a channel is all a monitor needs), so
/// `--diagnose` with a stalled consumer keeps the queue bounded.
type Key<'a> = (
    &'static str,
    &'a str,
    Option<Stat>,
    Option<usize>,
    Option<&'a str>,
);

fn key<'a>(r: &'a Record, unit: &'a Option<Arc<str>>) -> Option<Key<'a>> {
    let u = unit.as_deref();
    match r {
        Record::Curve(c) => Some(("curve", c.channel.as_str(), Some(c.stat), c.run, u)),
        Record::Fit(f) => Some(("fit", f.channel.as_str(), None, f.run, u)),
        Record::Diagnosis(d) => Some(("diagnosis", d.channel.as_str(), None, d.run, u)),
        _ => None,
    }
}

impl RecordQueue {
    fn lock(&self) -> MutexGuard<'_, QueueState> {
        // A poisoned lock means the writer panicked; the state is still usable.
        self.inner.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Queues an interim record. With [`Delivery::Coalesce`] it never blocks: when the queue is
    /// full, older interim records of the same key are removed first. With
    /// [`Delivery::Backpressure`] it waits for room, until [`RecordQueue::release`].
    pub fn push_interim(&self, rec: Record) {
        self.push_interim_of(None, rec)
    }

    /// [`RecordQueue::push_interim`] for a record of the named unit `unit` (written with
    /// `"unit": NAME`, [`crate::sink::unit_record`]); `None`: a one-unit run's record.
    pub fn push_interim_of(&self, unit: Option<&Arc<str>>, rec: Record) {
        let unit = unit.cloned();
        let mut st = self.lock();
        if self.delivery == Delivery::Backpressure {
            while st.items.len() >= self.capacity && !st.failed && !st.released && !st.closed {
                st = self
                    .inner
                    .room
                    .wait_timeout(st, Duration::from_millis(100))
                    .unwrap_or_else(|p| p.into_inner())
                    .0;
            }
        }
        if st.failed {
            return;
        }
        if st.items.len() >= self.capacity {
            if let Some(k) = key(&rec, &unit) {
                let before = st.items.len();
                st.items
                    .retain(|(r, is_final, u)| *is_final || key(r, u) != Some(k));
                st.coalesced += (before - st.items.len()) as u64;
            }
        }
        st.items.push_back((rec, false, unit));
        drop(st);
        self.inner.items.notify_one();
    }

    /// Queues a final record (final curves and fits, health, summary, aggregate); never
    /// dropped, never blocks.
    pub fn push_final(&self, rec: Record) {
        self.push_final_of(None, rec)
    }

    /// [`RecordQueue::push_final`] for a record of the named unit `unit`.
    pub fn push_final_of(&self, unit: Option<&Arc<str>>, rec: Record) {
        let mut st = self.lock();
        if st.failed {
            return;
        }
        st.items.push_back((rec, true, unit.cloned()));
        drop(st);
        self.inner.items.notify_one();
    }

    /// Lifts back-pressure for good: a run being stopped (SIGINT) must not wait for a consumer
    /// that may never read again. Full queues coalesce from then on.
    pub fn release(&self) {
        self.lock().released = true;
        self.inner.stopping.store(true, Ordering::SeqCst);
        self.inner.room.notify_all();
    }

    /// Set once [`RecordQueue::release`] was called (the run is being stopped); the analysis
    /// watches it (`RunAnalysis::stop_interim_when`).
    pub fn stopping(&self) -> Arc<AtomicBool> {
        self.inner.stopping.clone()
    }

    /// Records waiting to be written.
    pub fn len(&self) -> usize {
        self.lock().items.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// How a full queue treats interim records.
    pub fn delivery(&self) -> Delivery {
        self.delivery
    }
}

/// The writer thread and its queue.
pub struct RecordWriter {
    queue: RecordQueue,
    thread: JoinHandle<std::io::Result<u64>>,
}

impl RecordWriter {
    /// Starts a writer thread over `out` with the default capacity and back-pressure (for
    /// replays and anything without a deadline).
    pub fn spawn(out: Box<dyn Write + Send>) -> RecordWriter {
        Self::with_capacity(out, RECORD_QUEUE, Delivery::Backpressure)
    }

    /// Starts a writer thread whose full queue coalesces interim records (live sources).
    pub fn spawn_coalescing(out: Box<dyn Write + Send>) -> RecordWriter {
        Self::with_capacity(out, RECORD_QUEUE, Delivery::Coalesce)
    }

    pub fn with_capacity(
        out: Box<dyn Write + Send>,
        capacity: usize,
        delivery: Delivery,
    ) -> RecordWriter {
        let queue = RecordQueue {
            inner: Arc::new(Shared {
                state: Mutex::new(QueueState::default()),
                items: Condvar::new(),
                room: Condvar::new(),
                written: AtomicU64::new(0),
                stopping: Arc::new(AtomicBool::new(false)),
            }),
            capacity: capacity.max(1),
            delivery,
        };
        let q = queue.clone();
        let thread = std::thread::Builder::new()
            .name("allanscope-writer".into())
            .spawn(move || write_loop(q, JsonLines::new(out)))
            .unwrap_or_else(|e| panic!("cannot start the writer thread: {e}"));
        RecordWriter { queue, thread }
    }

    pub fn queue(&self) -> &RecordQueue {
        &self.queue
    }

    /// Closes the queue, waits until every queued record is written, and reports.
    pub fn finish(self) -> std::io::Result<WriterStats> {
        self.finish_within(|| None)
    }

    /// [`RecordWriter::finish`], but gives up once the writer has written nothing for as long
    /// as `grace()` allows (`None`: no limit; asked again as time passes, so a signal that
    /// arrives while waiting counts): a consumer that stopped reading cannot hold up the end of
    /// a stopped run. The error says how many records were not written.
    pub fn finish_within(
        self,
        grace: impl Fn() -> Option<Duration>,
    ) -> std::io::Result<WriterStats> {
        {
            let mut st = self.queue.lock();
            st.closed = true;
        }
        self.queue.inner.items.notify_all();
        self.queue.inner.room.notify_all();
        let mut seen = self.queue.inner.written.load(Ordering::SeqCst);
        let mut since = Instant::now();
        while !self.thread.is_finished() {
            std::thread::sleep(Duration::from_millis(10));
            let now = self.queue.inner.written.load(Ordering::SeqCst);
            if now != seen {
                (seen, since) = (now, Instant::now());
            } else if grace().is_some_and(|g| since.elapsed() >= g) {
                let mut st = self.queue.lock();
                let left = st.items.len();
                st.failed = true;
                st.items.clear();
                return Err(std::io::Error::other(format!(
                    "the output is not being read: gave up after {:.1} s without progress, {left} \
                     records queued and the batch being written lost ({seen} written)",
                    since.elapsed().as_secs_f64()
                )));
            }
        }
        let written = self
            .thread
            .join()
            .map_err(|_| std::io::Error::other("the record writer thread panicked"))??;
        let coalesced = self.queue.lock().coalesced;
        Ok(WriterStats { written, coalesced })
    }
}

fn write_loop(q: RecordQueue, mut sink: JsonLines) -> std::io::Result<u64> {
    let mut written = 0u64;
    let mut batch = Vec::new();
    loop {
        {
            let mut st = q.lock();
            while st.items.is_empty() && !st.closed {
                st = q.inner.items.wait(st).unwrap_or_else(|p| p.into_inner());
            }
            if st.items.is_empty() && st.closed {
                break;
            }
            batch.extend(st.items.drain(..));
        }
        q.inner.room.notify_all();
        let res = (|| {
            for (r, _, unit) in batch.drain(..) {
                match unit {
                    None => sink.write(&r)?,
                    Some(u) => sink.write(&UnitRecord {
                        unit: &u,
                        record: &r,
                    })?,
                }
                written += 1;
                q.inner.written.store(written, Ordering::SeqCst);
            }
            sink.flush()
        })();
        if let Err(e) = res {
            let mut st = q.lock();
            st.failed = true;
            st.items.clear();
            drop(st);
            q.inner.room.notify_all();
            return Err(e);
        }
    }
    sink.flush()?;
    Ok(written)
}
