//! One run's analysis: per-channel accumulators fed with [`Chunk`]s, read into curves, fitted,
//! and diagnosed: per channel a typed [`ChannelReport`] (channel_report.rs), which the writer
//! turns into records. Plain synchronous code: the pipeline runs it on a worker thread and
//! tests and benchmarks call it directly. It never knows where the samples came from.
//!
//! Files: setup.rs (input kind, channel setups, options), block.rs (frame blocks in),
//! channel_fit.rs (a channel's curves and two-pass fit), channel_report.rs (the typed report and
//! its records), state.rs (the checkpointed state); here, [`RunAnalysis`]: feeding, the interim
//! schedule, reports, the summary, splitting a run over threads.

mod block;
mod channel_fit;
mod channel_report;
mod setup;
mod state;

use channel_fit::analyze_channel;
pub use channel_report::ChannelReport;
pub use setup::{AnalysisOptions, ChannelSetup, InputKind, AUXILIARY_COLUMNS};
pub use state::{AnalysisState, ChannelSnapshot};

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

use crate::allan::accum::{ChannelAccumulator, Overlap};
use crate::allan::curve::{build_curves, AlphaSource};
use crate::allan::{Curve, Stat};
use crate::frame::{ChannelValue, FrameEvent};
use crate::gap::{GapConfig, GapEvidence};
use crate::input::Chunk;
use crate::model::fit::{FitResult, Fitter};
use crate::sink::records::{Record, SummaryRecord};

struct ChannelState {
    setup: ChannelSetup,
    acc: ChannelAccumulator,
    /// The diagnosis' evidence (dense curve, segments, block means), when asked for.
    gap: Option<GapEvidence>,
    /// Last phase value (phase input), to feed the evidence increments.
    last_phase: Option<f64>,
    fitter: Fitter,
    last_fit: Option<FitResult>,
}

/// The first of `next, next + every, next + 2 every, ...` (summed one by one, as the records'
/// data-seconds always were) that lies after `t`. The sum is taken at most a few thousand times;
/// past that (a long gap, a tiny interval against a huge time, a restored `next` far behind),
/// the multiple of `every` after `t` is computed directly, so the time this takes is bounded
/// whatever the numbers; an `every` too small to move `next` at all gives infinity (no more
/// interim records) rather than a loop that never ends.
fn next_after(mut next: f64, every: f64, t: f64) -> f64 {
    const SUMMED: u32 = 4096;
    for _ in 0..SUMMED {
        if next > t {
            return next;
        }
        let moved = next + every;
        if moved <= next || moved.is_nan() {
            return f64::INFINITY;
        }
        next = moved;
    }
    if next > t {
        return next;
    }
    let mut after = next + ((t - next) / every).floor() * every;
    for _ in 0..4 {
        if after > t && after.is_finite() {
            return after;
        }
        after += every;
    }
    f64::INFINITY
}

/// A run in progress.
pub struct RunAnalysis {
    input: String,
    opts: AnalysisOptions,
    channels: Vec<ChannelState>,
    next_emit_s: f64,
    bad_rows: u64,
    /// Text values infinite or out of range, read as gaps (from the reader, like `bad_rows`).
    invalid_values: u64,
    /// Text cells that held a word, read as gaps (from the reader, like `bad_rows`).
    flagged_cells: u64,
    /// What the text input's time column found (from the reader, like `bad_rows`).
    time_column: Option<crate::sink::records::TimeColumnRecord>,
    started: Instant,
    /// Set when the run is being stopped ([`RunAnalysis::stop_interim_when`]): interim records
    /// fall due as before but are not made.
    stopping: Arc<AtomicBool>,
}

impl RunAnalysis {
    pub fn new(input: &str, channels: Vec<ChannelSetup>, opts: AnalysisOptions) -> RunAnalysis {
        let channels = channels
            .into_iter()
            .map(|setup| ChannelState {
                acc: match setup.counts_lsb {
                    Some(lsb) => ChannelAccumulator::counts(opts.accum.clone(), lsb),
                    None => ChannelAccumulator::real(opts.accum.clone()),
                },
                gap: opts
                    .diagnose
                    .then(|| GapEvidence::new(GapConfig::new(opts.accum.tau0_s))),
                last_phase: None,
                setup,
                fitter: Fitter::new(),
                last_fit: None,
            })
            .collect();
        RunAnalysis {
            input: input.into(),
            next_emit_s: opts.every_s.unwrap_or(f64::INFINITY),
            opts,
            channels,
            bad_rows: 0,
            invalid_values: 0,
            flagged_cells: 0,
            time_column: None,
            started: Instant::now(),
            stopping: Arc::default(),
        }
    }

    /// Once `flag` is set (the run is being stopped: SIGINT/SIGTERM), the data already read is
    /// still analysed, to the last frame, but no interim record is made any more (their
    /// schedule still advances, so a checkpoint is as without the stop). A replay held by a
    /// stalled consumer would otherwise spend seconds on interim records nobody reads before
    /// its final ones.
    pub fn stop_interim_when(&mut self, flag: Arc<AtomicBool>) {
        self.stopping = flag;
    }

    /// Ends every channel's phase segment without accounting for time: what follows is not
    /// contiguous with what came before (a live run resumed after a stop), so no difference
    /// spans the break.
    pub fn break_segments(&mut self) {
        for ch in &mut self.channels {
            ch.acc.break_segment();
            ch.last_phase = None;
        }
    }

    /// Sampling step in seconds.
    pub fn tau0_s(&self) -> f64 {
        self.opts.accum.tau0_s
    }

    pub fn channel_names(&self) -> Vec<String> {
        self.channels.iter().map(|c| c.setup.name.clone()).collect()
    }

    /// Seconds of data consumed (the longest channel).
    pub fn t_data_s(&self) -> f64 {
        self.channels
            .iter()
            .map(|c| c.acc.t_data_s())
            .fold(0.0, f64::max)
    }

    /// Counts rows the input could not read (they were fed as gaps).
    /// The text reader's time column at the end of the input, for the summary.
    pub fn set_time_column(&mut self, t: Option<&crate::input::time_column::TimeState>) {
        self.time_column = t.map(|t| crate::sink::records::TimeColumnRecord {
            name: t.name.clone(),
            used: t.in_use(),
            unit: t.unit().filter(|_| t.in_use()).map(String::from),
            gaps: t.jumps,
            missing_samples: t.missing,
            backwards: t.backwards,
            irregular: t.irregular,
            discontinuities: t.discontinuities,
            duplicates: t.duplicates,
        });
    }

    pub fn add_bad_rows(&mut self, n: u64) {
        self.bad_rows += n;
    }

    /// Counts text values that were infinite or out of range (they were fed as gaps).
    pub fn add_invalid_values(&mut self, n: u64) {
        self.invalid_values += n;
    }

    /// Counts text cells that held a word, not a number (they were fed as gaps).
    pub fn add_flagged_cells(&mut self, n: u64) {
        self.flagged_cells += n;
    }

    /// Feeds a chunk; interim records that fall due inside it are appended to `out`.
    pub fn push_chunk(&mut self, chunk: &Chunk, out: &mut Vec<Record>) {
        let tau0 = self.opts.accum.tau0_s;
        match chunk {
            Chunk::Rows { values, width } => {
                for row in values.chunks_exact(*width) {
                    self.push_row(row, tau0);
                    self.emit_if_due(out);
                }
            }
            Chunk::Frames(events) => {
                for ev in events {
                    match ev {
                        FrameEvent::Frame(f) => {
                            for ch in &mut self.channels {
                                let value = f.values.get(ch.setup.column).copied().flatten();
                                if let Some(g) = &mut ch.gap {
                                    match value {
                                        Some(v) => {
                                            g.push_increment(v.physical(ch.setup.counts_lsb))
                                        }
                                        None => g.push_gap(1),
                                    }
                                }
                                match value {
                                    Some(ChannelValue::Count(c)) => match &mut ch.acc {
                                        ChannelAccumulator::Counts { engine, .. } => {
                                            engine.push_increment(c)
                                        }
                                        ChannelAccumulator::Real(e) => e.push_increment(
                                            c as f64 * ch.setup.counts_lsb.unwrap_or(1.0),
                                        ),
                                    },
                                    Some(ChannelValue::Real(v)) => match &mut ch.acc {
                                        ChannelAccumulator::Real(e) => e.push_increment(v),
                                        // A real value on a counts channel cannot be summed
                                        // exactly: the descriptor said integers.
                                        ChannelAccumulator::Counts { engine, .. } => {
                                            engine.push_gap(1)
                                        }
                                    },
                                    None => ch.acc.push_gap(1),
                                }
                            }
                        }
                        FrameEvent::Gap { missing } => {
                            for ch in &mut self.channels {
                                ch.acc.push_gap(*missing);
                                if let Some(g) = &mut ch.gap {
                                    g.push_gap(*missing);
                                }
                            }
                        }
                    }
                    self.emit_if_due(out);
                }
            }
            Chunk::Block(b) => self.push_block(b, out),
            // The pipeline saves the state at this mark; nothing to accumulate.
            Chunk::Checkpoint(_) => {}
        }
    }

    #[inline]
    fn push_row(&mut self, row: &[f64], tau0: f64) {
        let kind = self.opts.kind;
        for ch in &mut self.channels {
            let v = row[ch.setup.column];
            if let Some(g) = &mut ch.gap {
                match kind.step(v, tau0, &mut ch.last_phase) {
                    Some(d) if d.is_finite() => g.push_increment(d),
                    Some(_) => g.push_gap(1),
                    None => {}
                }
            }
            match &mut ch.acc {
                ChannelAccumulator::Real(e) => match kind {
                    InputKind::Phase => e.push_phase_f64(v),
                    _ if v.is_nan() => e.push_gap(1),
                    InputKind::Increments => e.push_increment(v),
                    InputKind::Rate => e.push_increment(v * tau0),
                },
                ChannelAccumulator::Counts { engine, .. } => {
                    if v.is_finite() && v.fract() == 0.0 && v.abs() < 9.0e15 {
                        engine.push_increment(v as i64)
                    } else {
                        engine.push_gap(1)
                    }
                }
            }
        }
    }

    fn emit_if_due(&mut self, out: &mut Vec<Record>) {
        // No interim schedule (a replay without --every, or a live run, whose interim records
        // the pipeline times): skip the fold over the channels after every frame (profiled:
        // 6.6% of a replay's instructions, BENCHMARKS.md).
        if self.next_emit_s == f64::INFINITY {
            return;
        }
        if self.t_data_s() >= self.next_emit_s {
            if !self.stopping.load(Ordering::Relaxed) {
                out.extend(self.records(false));
            }
            let every = self.opts.every_s.unwrap_or(f64::INFINITY);
            self.next_emit_s = next_after(self.next_emit_s, every, self.t_data_s());
        }
    }

    /// Every channel's results as of now, in channel order: its curves, fit, read-outs and
    /// diagnosis ([`ChannelReport`]), for a program that uses them directly.
    ///
    /// The final reports of several channels are made on as many threads as the machine has
    /// cores (channels split in consecutive parts, put back in channel order): each channel's
    /// curves, fit and diagnosis depend on that channel alone, so they are the same, and the end
    /// of a replay (the fits are most of it) takes a fraction of the wall time.
    pub fn reports(&mut self, final_: bool) -> Vec<ChannelReport> {
        let opts = &self.opts;
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        let parts = if final_ {
            cores.min(self.channels.len())
        } else {
            1
        };
        if parts <= 1 {
            return channel_report::channel_reports(&mut self.channels, opts, final_);
        }
        let per = self.channels.len().div_ceil(parts);
        std::thread::scope(|s| {
            let handles: Vec<_> = self
                .channels
                .chunks_mut(per)
                .map(|chs| s.spawn(move || channel_report::channel_reports(chs, opts, final_)))
                .collect();
            handles
                .into_iter()
                .flat_map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                .collect()
        })
    }

    /// The records of every channel's [`reports`](RunAnalysis::reports), in the order the
    /// writer prints them (per channel: its curves, fit, diagnosis).
    pub fn records(&mut self, final_: bool) -> Vec<Record> {
        self.reports(final_)
            .iter()
            .flat_map(ChannelReport::records)
            .collect()
    }

    /// The final fits, one per channel (`None` where no fit could be made), after [`records`].
    ///
    /// [`records`]: RunAnalysis::records
    pub fn last_fits(&self) -> Vec<(String, String, Option<FitResult>)> {
        self.channels
            .iter()
            .map(|c| {
                (
                    c.setup.name.clone(),
                    c.setup.unit.clone(),
                    c.last_fit.clone(),
                )
            })
            .collect()
    }

    /// The `summary` record of the run, with the per-run datasheet limits judged on the last
    /// fits (call after the final [`records`](RunAnalysis::records)).
    pub fn summary(&self) -> SummaryRecord {
        let fits: Vec<crate::model::limits::ChannelFit> = self
            .channels
            .iter()
            .map(|c| crate::model::limits::ChannelFit {
                channel: &c.setup.name,
                unit: &c.setup.unit,
                fit: c.last_fit.as_ref(),
            })
            .collect();
        let judgement = crate::model::limits::judge(&self.opts.limits, &fits);
        SummaryRecord {
            input: self.input.clone(),
            run: self.opts.run,
            channels: self.channel_names(),
            tau0: self.opts.accum.tau0_s,
            t_data: self.t_data_s(),
            samples: self.channels.iter().map(|c| c.acc.phase_points()).collect(),
            segments: self.channels.iter().map(|c| c.acc.segments()).collect(),
            bad_rows: self.bad_rows,
            invalid_values: self.invalid_values,
            flagged_cells: self.flagged_cells,
            time_column: self.time_column.clone(),
            overlap: match self.opts.accum.overlap {
                Overlap::Full => "full".into(),
                Overlap::Bounded(l) => l.to_string(),
            },
            elapsed_s: self.started.elapsed().as_secs_f64(),
            limits: judgement.results.clone(),
            pass: judgement.pass,
            // Filled in by the pipeline, which knows how the input ended.
            read_to_end: false,
            stopped_by: None,
            capture_error: None,
        }
    }

    /// Splits the run into `parts` runs of consecutive channels (same options and schedule), so
    /// the pipeline can feed them on separate threads; [`RunAnalysis::join`] puts them back.
    /// Channels are independent, so the split changes no number.
    pub fn split(self, parts: usize) -> Vec<RunAnalysis> {
        let parts = parts.clamp(1, self.channels.len().max(1));
        let per = self.channels.len().div_ceil(parts).max(1);
        let mut channels = self.channels.into_iter();
        let mut out = Vec::with_capacity(parts);
        for i in 0..parts {
            out.push(RunAnalysis {
                input: self.input.clone(),
                opts: self.opts.clone(),
                channels: channels.by_ref().take(per).collect(),
                next_emit_s: self.next_emit_s,
                bad_rows: if i == 0 { self.bad_rows } else { 0 },
                invalid_values: if i == 0 { self.invalid_values } else { 0 },
                flagged_cells: if i == 0 { self.flagged_cells } else { 0 },
                time_column: if i == 0 {
                    self.time_column.clone()
                } else {
                    None
                },
                started: self.started,
                stopping: self.stopping.clone(),
            });
        }
        out
    }

    /// The inverse of [`RunAnalysis::split`]: the parts' channels in order.
    pub fn join(parts: Vec<RunAnalysis>) -> Option<RunAnalysis> {
        let mut it = parts.into_iter();
        let mut first = it.next()?;
        for p in it {
            first.channels.extend(p.channels);
            first.bad_rows += p.bad_rows;
            first.invalid_values += p.invalid_values;
            first.flagged_cells += p.flagged_cells;
            first.next_emit_s = first.next_emit_s.max(p.next_emit_s);
        }
        Some(first)
    }

    /// Current curves of one channel (for tests and the diagnosis).
    pub fn curves(&mut self, channel: usize) -> Vec<Curve> {
        let ch = &mut self.channels[channel];
        analyze_channel(ch, &self.opts).0
    }
}
