//! Feeding a [`FrameBlock`] to a run: each channel takes its stretch of the block at once.
//!
//! The per-frame path ([`Chunk::Frames`](crate::input::Chunk)) visits every channel for every
//! frame and pushes one increment at a time. Here each channel walks the block's events on its
//! own: unbroken runs of counts (or real values) are gathered into a scratch and handed to
//! [`Engine::push_increments`](crate::allan::accum::Engine::push_increments), which does the
//! per-sample bookkeeping a block at a time and gives the same result bit for bit as the
//! single-sample path (tests/allan/streaming.rs); missing values and gaps end a run and go in as
//! gaps exactly as before. The channels' states are independent, so taking them one after the
//! other instead of frame by frame changes nothing in the numbers.
//!
//! Interim records on the data-second schedule (`--every`) fall due after a given event; the
//! block is cut there, so each record sees exactly the samples it saw on the per-frame path.

use super::{ChannelState, RunAnalysis};
use crate::allan::accum::ChannelAccumulator;
use crate::frame::{BlockEvent, ChannelValue, FrameBlock};
use crate::sink::records::Record;

impl RunAnalysis {
    /// Feeds a block; interim records that fall due inside it are appended to `out`.
    pub(super) fn push_block(&mut self, block: &FrameBlock, out: &mut Vec<Record>) {
        let events = block.event_list();
        let values = block.values();
        let width = block.width();
        if self.next_emit_s == f64::INFINITY {
            feed(&mut self.channels, events, values, width);
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
        let (mut lo, mut vlo, mut v) = (0, 0, 0);
        for (i, e) in events.iter().enumerate() {
            match e {
                BlockEvent::Frame { .. } => {
                    steps += 1;
                    v += width;
                }
                BlockEvent::Gap { missing } => steps += missing,
            }
            if steps as f64 * tau0 >= self.next_emit_s {
                feed(&mut self.channels, &events[lo..=i], &values[vlo..v], width);
                self.emit_if_due(out);
                (lo, vlo) = (i + 1, v);
            }
        }
        feed(&mut self.channels, &events[lo..], &values[vlo..], width);
    }
}

/// Feeds `events` (whose frames' values are `values`, `width` per frame) to every channel.
fn feed(
    channels: &mut [ChannelState],
    events: &[BlockEvent],
    values: &[Option<ChannelValue>],
    width: usize,
) {
    if events.is_empty() {
        return;
    }
    let mut counts: Vec<i64> = Vec::with_capacity(events.len());
    let mut reals: Vec<f64> = Vec::new();
    for ch in channels.iter_mut() {
        let col = ch.setup.column;
        let lsb = ch.setup.counts_lsb;
        let value_at = |at: usize| values.get(at + col).copied().flatten();
        if let Some(g) = &mut ch.gap {
            let mut at = 0;
            for e in events {
                match e {
                    BlockEvent::Frame { .. } => {
                        match value_at(at) {
                            Some(v) => g.push_increment(v.physical(lsb)),
                            None => g.push_gap(1),
                        }
                        at += width;
                    }
                    BlockEvent::Gap { missing } => g.push_gap(*missing),
                }
            }
        }
        match &mut ch.acc {
            ChannelAccumulator::Counts { engine, .. } => {
                counts.clear();
                let mut at = 0;
                for e in events {
                    match e {
                        BlockEvent::Frame { .. } => {
                            match value_at(at) {
                                Some(ChannelValue::Count(c)) => counts.push(c),
                                // A real value on a counts channel cannot be summed exactly:
                                // the descriptor said integers. Missing: a gap.
                                Some(ChannelValue::Real(_)) | None => {
                                    engine.push_increments(&counts);
                                    counts.clear();
                                    engine.push_gap(1);
                                }
                            }
                            at += width;
                        }
                        BlockEvent::Gap { missing } => {
                            engine.push_increments(&counts);
                            counts.clear();
                            engine.push_gap(*missing);
                        }
                    }
                }
                engine.push_increments(&counts);
            }
            ChannelAccumulator::Real(engine) => {
                reals.clear();
                let mut at = 0;
                for e in events {
                    match e {
                        BlockEvent::Frame { .. } => {
                            match value_at(at) {
                                Some(ChannelValue::Count(c)) => {
                                    reals.push(c as f64 * lsb.unwrap_or(1.0))
                                }
                                Some(ChannelValue::Real(x)) => reals.push(x),
                                None => {
                                    engine.push_increments(&reals);
                                    reals.clear();
                                    engine.push_gap(1);
                                }
                            }
                            at += width;
                        }
                        BlockEvent::Gap { missing } => {
                            engine.push_increments(&reals);
                            reals.clear();
                            engine.push_gap(*missing);
                        }
                    }
                }
                engine.push_increments(&reals);
            }
        }
    }
}
