//! A stalled consumer of the JSON lines never stalls the ingestion of a live source.
//!
//! The writer coalesces interim records as it does for live sources (`spawn_coalescing`; a
//! replay's writer applies back-pressure instead, tested in `tests/cli/stop.rs`).
//! The record writer's output blocks on its first write until the test releases it. The
//! 5-minute siu8 fixture is replayed with interim records every 5 data-seconds (60 sets of 32
//! records, 1,920 in all, against a queue of 256): ingestion must finish while the writer is
//! still blocked, with every frame decoded (75,000, none dropped); interim records are coalesced
//! (the newest per channel and statistic kept); once released, the writer delivers every final
//! record, equal to those of a run with a free-flowing writer.

use std::io::Write;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

use crate::common::pipeline::*;
use allanscope::pipeline::{run_frames, RecordWriter, RunControl, RECORD_QUEUE};
use allanscope::source::{Pace, SourceSpec};

/// Frames in the fixture (5 min at 250 Hz).
const FRAMES: u64 = 75_000;
/// Data-seconds between interim records: 60 sets of 32 records over the 300 s, 1,920 records
/// against a queue of 256.
const EVERY_S: f64 = 5.0;
const INTERIM_SETS: u64 = 60;

/// A writer that blocks until the gate opens.
struct Gated {
    gate: Arc<(Mutex<bool>, std::sync::Condvar)>,
    blocked: Arc<AtomicBool>,
    out: SharedBuf,
}

impl Write for Gated {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        let (m, cv) = &*self.gate;
        let mut open = m.lock().expect("lock");
        while !*open {
            self.blocked.store(true, Ordering::SeqCst);
            open = cv.wait(open).expect("wait");
        }
        self.out.write(b)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

fn spec() -> SourceSpec {
    SourceSpec::File {
        path: fixtures().join("captures/siu8_stand_5min_seed1.siu8"),
        pace: Pace::Max,
    }
}

#[test]
fn stalled_writer_does_not_stall_ingestion() {
    let desc = siu8();
    let gate = Arc::new((Mutex::new(false), std::sync::Condvar::new()));
    let blocked = Arc::new(AtomicBool::new(false));
    let out = SharedBuf::default();
    let writer = RecordWriter::spawn_coalescing(Box::new(Gated {
        gate: gate.clone(),
        blocked: blocked.clone(),
        out: out.clone(),
    }));
    let ctl = RunControl::default();
    let outcome = run_frames(
        spec(),
        &desc,
        analysis(&desc, Some(EVERY_S)),
        writer.queue(),
        &ctl,
    )
    .expect("run");
    // Ingestion is complete while the writer is still stuck in its first write.
    assert!(
        blocked.load(Ordering::SeqCst),
        "the writer should be blocked"
    );
    assert!(out.0.lock().expect("lock").is_empty());
    assert_eq!(outcome.health.as_ref().map(|h| h.frames), Some(FRAMES));
    assert_eq!(ctl.progress.frames(), FRAMES);
    // The queue stayed bounded: capacity + one interim record per key (24 curves + 8 fits)
    // + the final records (32 + health + summary), plus the batch the writer holds.
    let queued = writer.queue().len();
    assert!(
        queued <= RECORD_QUEUE + 32 + 34,
        "queue grew to {queued} records"
    );
    {
        let (m, cv) = &*gate;
        *m.lock().expect("lock") = true;
        cv.notify_all();
    }
    let stats = writer.finish().expect("writer");
    let recs = out.records();
    eprintln!("writer {stats:?}, {} records delivered", recs.len());
    assert!(
        stats.coalesced > 0,
        "interim records should have been coalesced"
    );
    // INTERIM_SETS interim sets of 32 were produced; the written ones plus the coalesced ones are all
    // of them, and the 34 final records.
    assert_eq!(stats.written + stats.coalesced, INTERIM_SETS * 32 + 34);

    // The final records equal those of a run whose writer never blocks.
    let (free, _) = run_to_records(spec(), &desc, &RunControl::default());
    let want = final_curves_and_fits(&free);
    assert_eq!(want.len(), 32);
    assert_eq!(final_curves_and_fits(&recs), want);
    assert_eq!(last_of(&recs, "health")["frames"], FRAMES);
    assert_eq!(
        summary_core(last_of(&recs, "summary")),
        summary_core(last_of(&free, "summary"))
    );
}

/// With `--diagnose`, each interim set also carries a diagnosis per channel. Those are coalesced
/// like curves and fits (the newest per channel), so a stalled consumer of a live run still
/// leaves the queue bounded: without their key, 60 sets x 8 diagnoses would pile up beside the capacity.
#[test]
fn stalled_writer_with_diagnoses_keeps_the_queue_bounded() {
    let desc = siu8();
    let gate = Arc::new((Mutex::new(false), std::sync::Condvar::new()));
    let blocked = Arc::new(AtomicBool::new(false));
    let out = SharedBuf::default();
    let writer = RecordWriter::spawn_coalescing(Box::new(Gated {
        gate: gate.clone(),
        blocked: blocked.clone(),
        out: out.clone(),
    }));
    let mut opts = options(&desc, Some(EVERY_S));
    opts.diagnose = true;
    let analysis = allanscope::analysis::RunAnalysis::new("test", channels(&desc), opts);
    let outcome = run_frames(
        spec(),
        &desc,
        analysis,
        writer.queue(),
        &RunControl::default(),
    )
    .expect("run");
    assert!(
        blocked.load(Ordering::SeqCst),
        "the writer should be blocked"
    );
    assert_eq!(outcome.health.as_ref().map(|h| h.frames), Some(FRAMES));
    // Capacity + one interim record per key (24 curves + 8 fits + 8 diagnoses) + the final
    // records (24 curves, 8 fits, at most 8 diagnoses, health, summary).
    let queued = writer.queue().len();
    assert!(
        queued <= RECORD_QUEUE + 40 + 42,
        "queue grew to {queued} records"
    );
    {
        let (m, cv) = &*gate;
        *m.lock().expect("lock") = true;
        cv.notify_all();
    }
    let stats = writer.finish().expect("writer");
    let recs = out.records();
    let diagnoses = recs.iter().filter(|r| r["type"] == "diagnosis").count();
    eprintln!("writer {stats:?}; {diagnoses} diagnosis records delivered");
    assert!(diagnoses >= 8, "the final diagnoses are delivered");
    assert!(stats.coalesced > 0);
}
