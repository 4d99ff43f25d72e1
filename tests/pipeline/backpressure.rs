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
/// leaves the queue bounded: without their key, every interim diagnosis would pile up beside the
/// capacity. The diagnoses are those of a real run of the fixture (final, one per channel),
/// pushed again as 100 interim sets, each set marked by its `t_data`.
#[test]
fn stalled_writer_with_diagnoses_keeps_the_queue_bounded() {
    const SETS: usize = 100;
    let desc = siu8();
    let mut opts = options(&desc, None);
    opts.diagnose = true;
    opts.fit = Some(allanscope::model::fit::FitOptions::default());
    let analysis = allanscope::analysis::RunAnalysis::new("test", channels(&desc), opts);
    let buf = SharedBuf::default();
    let free_writer = RecordWriter::spawn(Box::new(buf.clone()));
    run_frames(
        spec(),
        &desc,
        analysis,
        free_writer.queue(),
        &RunControl::default(),
    )
    .expect("run");
    free_writer.finish().expect("writer");
    let free = buf.records();
    let diagnoses: Vec<allanscope::gap::DiagnosisRecord> = free
        .iter()
        .filter(|r| r["type"] == "diagnosis")
        .map(|r| serde_json::from_value(r.clone()).expect("a diagnosis record"))
        .collect();
    assert_eq!(diagnoses.len(), 8, "one final diagnosis per channel");

    let gate = Arc::new((Mutex::new(false), std::sync::Condvar::new()));
    let blocked = Arc::new(AtomicBool::new(false));
    let out = SharedBuf::default();
    let writer = RecordWriter::spawn_coalescing(Box::new(Gated {
        gate: gate.clone(),
        blocked: blocked.clone(),
        out: out.clone(),
    }));
    // A first record, and the writer stuck writing it, before the sets arrive.
    let mut first = diagnoses[0].clone();
    first.t_data = -1.0;
    writer
        .queue()
        .push_interim(allanscope::sink::records::Record::Diagnosis(Box::new(
            first,
        )));
    let until = std::time::Instant::now() + std::time::Duration::from_secs(30);
    while !blocked.load(Ordering::SeqCst) && std::time::Instant::now() < until {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    assert!(
        blocked.load(Ordering::SeqCst),
        "the writer should be blocked"
    );
    for set in 0..SETS {
        for d in &diagnoses {
            let mut d = d.clone();
            d.is_final = false;
            d.t_data = set as f64;
            writer
                .queue()
                .push_interim(allanscope::sink::records::Record::Diagnosis(Box::new(d)));
        }
    }
    // 800 interim diagnoses against a queue of 256: the newest per channel replace older ones
    // (plus at most the one record the blocked writer holds).
    let queued = writer.queue().len();
    assert!(queued <= RECORD_QUEUE + 8, "queue grew to {queued} records");
    {
        let (m, cv) = &*gate;
        *m.lock().expect("lock") = true;
        cv.notify_all();
    }
    let stats = writer.finish().expect("writer");
    assert_eq!(stats.written + stats.coalesced, (SETS * 8 + 1) as u64);
    assert!(stats.coalesced > 0);
    // Each channel's newest diagnosis (the last set) is delivered.
    let recs = out.records();
    for d in &diagnoses {
        let last = recs
            .iter()
            .rfind(|r| r["type"] == "diagnosis" && r["channel"] == d.channel.as_str())
            .expect("a diagnosis of the channel");
        assert_eq!(last["t_data"], (SETS - 1) as f64, "{}", d.channel);
    }
}
