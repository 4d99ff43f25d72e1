//! Feeding a [`FrameBlock`] to a run: each channel takes its stretch of the block at once.
//!
//! The per-frame path ([`Chunk::Frames`](crate::input::Chunk)) visits every channel for every
//! frame and pushes one increment at a time. A block holds each channel's values as a column
//! (`frame::block`), so here a channel's unbroken run of counts is a slice of its column, handed
//! as it is to [`Engine::push_increments`](crate::allan::accum::Engine::push_increments), which
//! does the per-sample bookkeeping a block at a time and gives the same result bit for bit as
//! the single-sample path (tests/allan/streaming.rs). Gaps (the block's list) and holes (missing
//! values, or a real value on a counts channel) end a run and go in exactly as on the per-frame
//! path. The channels' states are independent, so taking them one after the other instead of
//! frame by frame changes nothing in the numbers (tests/pipeline/block_feed.rs).
//!
//! Interim records on the data-second schedule (`--every`) fall due after a given event; the
//! block is cut there, so each record sees exactly the samples it saw on the per-frame path.

use std::ops::Range;

use super::{ChannelState, RunAnalysis};
use crate::allan::accum::ChannelAccumulator;
use crate::frame::{BlockEvent, ChannelValue, ColumnKind, ColumnValues, FrameBlock, Hole};
use crate::sink::records::Record;

impl RunAnalysis {
    /// Feeds a block; interim records that fall due inside it are appended to `out`.
    pub(super) fn push_block(&mut self, block: &FrameBlock, out: &mut Vec<Record>) {
        let events = block.event_list();
        if self.next_emit_s == f64::INFINITY {
            feed(
                &mut self.channels,
                block,
                0..events.len(),
                0..block.frames(),
            );
            return;
        }
        let Some(first) = self.channels.first() else {
            // Nothing to accumulate: only the schedule, as the per-frame path checks it.
            for _ in events {
                self.emit_if_due(out);
            }
            return;
        };
        // Every channel of a run takes one step per frame (a value or a gap), so all have the
        // same step count, and `t_data_s()` after an event is `steps x tau0` exactly as the
        // accumulators compute it.
        let tau0 = self.opts.accum.tau0_s;
        let mut steps = first.acc.steps();
        let (mut lo, mut flo, mut f) = (0, 0, 0);
        for (i, e) in events.iter().enumerate() {
            match e {
                BlockEvent::Frame { .. } => {
                    steps += 1;
                    f += 1;
                }
                BlockEvent::Gap { missing } => steps += missing,
            }
            if steps as f64 * tau0 >= self.next_emit_s {
                feed(&mut self.channels, block, lo..i + 1, flo..f);
                self.emit_if_due(out);
                (lo, flo) = (i + 1, f);
            }
        }
        feed(
            &mut self.channels,
            block,
            lo..events.len(),
            flo..block.frames(),
        );
    }
}

/// Feeds the block's events `ev` (whose frames are `fr`) to every channel.
fn feed(channels: &mut [ChannelState], block: &FrameBlock, ev: Range<usize>, fr: Range<usize>) {
    if ev.is_empty() {
        return;
    }
    let gaps = block.gaps();
    let g0 = gaps.partition_point(|g| g.event < ev.start);
    let g1 = gaps.partition_point(|g| g.event < ev.end);
    let gaps = &gaps[g0..g1];
    let holes = block.holes();
    let h0 = holes.partition_point(|h| h.frame < fr.start);
    let h1 = holes.partition_point(|h| h.frame < fr.end);
    let holes = &holes[h0..h1];
    let mut scratch = Vec::new();
    for ch in channels.iter_mut() {
        let col = ch.setup.column;
        let mut feeder = Feeder {
            ch,
            scratch: &mut scratch,
        };
        if col >= block.width() {
            // A column the frames do not have: every value missing.
            let mut at = fr.start;
            for g in gaps {
                feeder.missing(g.frame - at);
                feeder.gap(g.missing);
                at = g.frame;
            }
            feeder.missing(fr.end - at);
            continue;
        }
        let column = block.column(col);
        let kind = block.kinds()[col];
        let mut mine = holes.iter().filter(|h| h.channel == col).peekable();
        let mut run = |feeder: &mut Feeder, mut a: usize, b: usize| {
            while let Some(h) = mine.next_if(|h| h.frame < b) {
                feeder.stretch(column.slice(a..h.frame), kind);
                feeder.hole(h);
                a = h.frame + 1;
            }
            feeder.stretch(column.slice(a..b), kind);
        };
        let mut at = fr.start;
        for g in gaps {
            run(&mut feeder, at, g.frame);
            feeder.gap(g.missing);
            at = g.frame;
        }
        run(&mut feeder, at, fr.end);
    }
}

/// One channel being fed.
struct Feeder<'a> {
    ch: &'a mut ChannelState,
    scratch: &'a mut Vec<f64>,
}

impl Feeder<'_> {
    /// An unbroken run of values of one column kind, as the column stores them (`i32` counts
    /// of a narrow column are widened as the engine sums them).
    fn stretch(&mut self, values: ColumnValues, kind: ColumnKind) {
        match values {
            ColumnValues::Wide(v) => self.stretch_of(v, kind),
            ColumnValues::Narrow(v) => self.stretch_of(v, kind),
        }
    }

    fn stretch_of<T: Copy + Into<i64>>(&mut self, values: &[T], kind: ColumnKind) {
        if values.is_empty() {
            return;
        }
        let lsb = self.ch.setup.counts_lsb;
        let physical = |raw: i64| match kind {
            ColumnKind::Count | ColumnKind::Count32 => raw as f64 * lsb.unwrap_or(1.0),
            ColumnKind::Real => f64::from_bits(raw as u64),
        };
        if let Some(g) = &mut self.ch.gap {
            for &raw in values {
                g.push_increment(physical(raw.into()));
            }
        }
        match (&mut self.ch.acc, kind) {
            (
                ChannelAccumulator::Counts { engine, .. },
                ColumnKind::Count | ColumnKind::Count32,
            ) => engine.push_increments_from(values),
            // A real value on a counts channel cannot be summed exactly: the descriptor said
            // integers. Each is a gap of one step.
            (ChannelAccumulator::Counts { engine, .. }, ColumnKind::Real) => {
                for _ in values {
                    engine.push_gap(1);
                }
            }
            (ChannelAccumulator::Real(engine), _) => {
                self.scratch.clear();
                self.scratch
                    .extend(values.iter().map(|&raw| physical(raw.into())));
                engine.push_increments(self.scratch);
            }
        }
    }

    /// A value the column does not hold: missing, or of the other kind.
    fn hole(&mut self, h: &Hole) {
        let lsb = self.ch.setup.counts_lsb;
        if let Some(g) = &mut self.ch.gap {
            match h.value {
                Some(v) => g.push_increment(v.physical(lsb)),
                None => g.push_gap(1),
            }
        }
        match (&mut self.ch.acc, h.value) {
            (ChannelAccumulator::Counts { engine, .. }, Some(ChannelValue::Count(c))) => {
                engine.push_increments(&[c])
            }
            (ChannelAccumulator::Counts { engine, .. }, _) => engine.push_gap(1),
            (ChannelAccumulator::Real(engine), Some(ChannelValue::Count(c))) => {
                engine.push_increments(&[c as f64 * lsb.unwrap_or(1.0)])
            }
            (ChannelAccumulator::Real(engine), Some(ChannelValue::Real(x))) => {
                engine.push_increments(&[x])
            }
            (ChannelAccumulator::Real(engine), None) => engine.push_gap(1),
        }
    }

    /// `n` frames without a value.
    fn missing(&mut self, n: usize) {
        for _ in 0..n {
            if let Some(g) = &mut self.ch.gap {
                g.push_gap(1);
            }
            self.ch.acc.push_gap(1);
        }
    }

    /// `missing` frames lost.
    fn gap(&mut self, missing: u64) {
        if let Some(g) = &mut self.ch.gap {
            g.push_gap(missing);
        }
        self.ch.acc.push_gap(missing);
    }
}
