//! The record writer: JSON lines written on a thread of their own, behind a bounded queue that
//! never blocks the analysis.
//!
//! A slow or stalled consumer of the JSON lines (a full pipe, a stuck monitor) must not stall
//! ingestion: frames keep being decoded and accumulated. The queue holds at most
//! [`RECORD_QUEUE`] records; when it is full, an *interim* record replaces the queued interim
//! records of the same key (record type, channel, statistic, run): only the newest interim
//! curve of each channel and statistic survives, which is all a monitor would look at. Final
//! records (and health and summary records) are never dropped: they are few (one set per run),
//! so the queue's size stays bounded by `RECORD_QUEUE` plus the number of keys plus the final
//! records.

use std::collections::VecDeque;
use std::io::Write;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;

use crate::allan::Stat;
use crate::sink::json::JsonLines;
use crate::sink::records::Record;

/// Records the queue holds before interim records start to be coalesced: a few full sets of
/// interim records (8 channels x 3 statistics + 8 fits = 32 per set).
pub const RECORD_QUEUE: usize = 256;

/// What the writer thread did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct WriterStats {
    /// Records written.
    pub written: u64,
    /// Interim records replaced by a newer one of the same key while the queue was full.
    pub coalesced: u64,
}

#[derive(Default)]
struct QueueState {
    items: VecDeque<(Record, bool)>,
    closed: bool,
    coalesced: u64,
    /// The writer failed (e.g. the consumer closed the pipe); records are discarded from then on.
    failed: bool,
}

/// The sending side of the record queue; cheap to clone.
#[derive(Clone)]
pub struct RecordQueue {
    inner: Arc<(Mutex<QueueState>, Condvar)>,
    capacity: usize,
}

/// The coalescing key of an interim record: type, channel, statistic, run.
fn key(r: &Record) -> Option<(&'static str, &str, Option<Stat>, Option<usize>)> {
    match r {
        Record::Curve(c) => Some(("curve", c.channel.as_str(), Some(c.stat), c.run)),
        Record::Fit(f) => Some(("fit", f.channel.as_str(), None, f.run)),
        _ => None,
    }
}

impl RecordQueue {
    fn lock(&self) -> MutexGuard<'_, QueueState> {
        // A poisoned lock means the writer panicked; the state is still usable.
        self.inner.0.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Queues an interim record; never blocks. When the queue is full, older interim records
    /// of the same key are removed first.
    pub fn push_interim(&self, rec: Record) {
        let mut st = self.lock();
        if st.failed {
            return;
        }
        if st.items.len() >= self.capacity {
            if let Some(k) = key(&rec) {
                let before = st.items.len();
                st.items
                    .retain(|(r, is_final)| *is_final || key(r) != Some(k));
                st.coalesced += (before - st.items.len()) as u64;
            }
        }
        st.items.push_back((rec, false));
        drop(st);
        self.inner.1.notify_one();
    }

    /// Queues a final record (final curves and fits, health, summary, aggregate); never
    /// dropped, never blocks.
    pub fn push_final(&self, rec: Record) {
        let mut st = self.lock();
        if st.failed {
            return;
        }
        st.items.push_back((rec, true));
        drop(st);
        self.inner.1.notify_one();
    }

    /// Records waiting to be written.
    pub fn len(&self) -> usize {
        self.lock().items.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The writer thread and its queue.
pub struct RecordWriter {
    queue: RecordQueue,
    thread: JoinHandle<std::io::Result<u64>>,
}

impl RecordWriter {
    /// Starts a writer thread over `out` with the default capacity.
    pub fn spawn(out: Box<dyn Write + Send>) -> RecordWriter {
        Self::with_capacity(out, RECORD_QUEUE)
    }

    pub fn with_capacity(out: Box<dyn Write + Send>, capacity: usize) -> RecordWriter {
        let queue = RecordQueue {
            inner: Arc::new((Mutex::new(QueueState::default()), Condvar::new())),
            capacity: capacity.max(1),
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
        {
            let mut st = self.queue.lock();
            st.closed = true;
        }
        self.queue.inner.1.notify_all();
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
                st = q.inner.1.wait(st).unwrap_or_else(|p| p.into_inner());
            }
            if st.items.is_empty() && st.closed {
                break;
            }
            batch.extend(st.items.drain(..));
        }
        let res = (|| {
            for (r, _) in batch.drain(..) {
                sink.write(&r)?;
                written += 1;
            }
            sink.flush()
        })();
        if let Err(e) = res {
            let mut st = q.lock();
            st.failed = true;
            st.items.clear();
            return Err(e);
        }
    }
    sink.flush()?;
    Ok(written)
}
