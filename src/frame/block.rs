//! A flat batch of decoded frames: what the decoder fills and the analysis reads, with no
//! allocation per frame.
//!
//! A [`FrameBlock`] holds the events of a stretch of stream in order ([`BlockEvent`]: a frame's
//! counter, temperature and status, or a gap) and the channel values of its frames **column by
//! column**: one vector per channel, one entry per frame. A column holds one kind of value
//! ([`ColumnKind`]: exact counts, or real increments as their f64 bit patterns), so a run of a
//! channel's counts is a plain `&[i64]` the accumulators take as it is. A value that is missing,
//! or of the other kind (a real value handed to a counts column), is a [`Hole`]: the column
//! keeps a placeholder and the block lists the hole, in frame order. Clean data has none.
//!
//! The decoder appends to one block that lives as long as it does; the pipeline hands whole
//! blocks to the analysis and gets them back to reuse, so a replay allocates per chunk of
//! 64 KiB, not per frame (profiled: a `Vec` per decoded frame and its `free` on the analysis
//! thread were a third of a replay's instructions; frame-major `Option` values cost the
//! analysis a tag test per value; BENCHMARKS.md "Decoding at the speed of the statistics").
//!
//! [`FrameEvent`] and [`DecodedFrame`] remain the one-frame-at-a-time view of the same data
//! ([`FrameBlock::events`], [`crate::frame::Decoder::next_event`]).

use super::{ChannelValue, DecodedFrame, FrameEvent};

/// One event of a block. A `Frame`'s values are the next entry of every column.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BlockEvent {
    /// A good frame (see [`DecodedFrame`] for the fields).
    Frame {
        seq: u64,
        temperature_c: Option<f64>,
        status: Option<u64>,
    },
    /// `missing` frames were lost before the next frame.
    Gap { missing: u64 },
}

/// What a column's entries are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ColumnKind {
    /// [`ChannelValue::Count`]s, as they are.
    #[default]
    Count,
    /// [`ChannelValue::Real`]s, as `f64::to_bits` (reinterpreted as `i64`).
    Real,
}

/// A value a column cannot hold as it is: missing, or of the other [`ColumnKind`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hole {
    /// Index of the frame in the block (0 = the block's first frame).
    pub frame: usize,
    pub channel: usize,
    pub value: Option<ChannelValue>,
}

/// A gap's place among the frames: before the block's `frame`-th frame, as its `event`-th event.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GapAt {
    pub event: usize,
    pub frame: usize,
    pub missing: u64,
}

/// Decoded frames and the gaps between them, flat (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameBlock {
    events: Vec<BlockEvent>,
    /// One per channel; `columns[c][i]` is channel `c` of the `i`-th frame.
    columns: Vec<Vec<i64>>,
    kinds: Vec<ColumnKind>,
    /// In frame order, then channel order.
    holes: Vec<Hole>,
    /// Every column holds counts.
    all_counts: bool,
    /// The gaps, in event order.
    gaps: Vec<GapAt>,
    frames: usize,
}

/// Where decoded frames go: a [`FrameBlock`], or (tests, one-frame-at-a-time callers) a
/// vector of [`FrameEvent`]s.
pub trait FrameSink {
    fn push_gap(&mut self, missing: u64);
    /// A frame and its values (`values.len()` is the block's width).
    fn push_frame(&mut self, frame: BlockEvent, values: &[Option<ChannelValue>]);
    /// Every event of `block`, in order; `block` is left empty.
    fn take_all(&mut self, block: &mut FrameBlock) {
        push_each_event(self, block);
    }
}

/// Every event of `block` handed to `sink` one at a time, in order; `block` is left empty
/// ([`FrameSink::take_all`]'s default, and a block's fallback when the value kinds differ).
fn push_each_event<S: FrameSink + ?Sized>(sink: &mut S, block: &mut FrameBlock) {
    let mut values = Vec::with_capacity(block.width());
    let mut frame = 0;
    for e in &block.events {
        match *e {
            BlockEvent::Gap { missing } => sink.push_gap(missing),
            ev => {
                block.frame_values(frame, &mut values);
                sink.push_frame(ev, &values);
                frame += 1;
            }
        }
    }
    block.clear();
}

impl FrameBlock {
    /// An empty block for frames of `width` count channels, with room for `frames` frames.
    pub fn with_capacity(width: usize, frames: usize) -> FrameBlock {
        Self::with_kinds(&vec![ColumnKind::Count; width], frames)
    }

    /// An empty block whose columns hold `kinds`, with room for `frames` frames.
    pub fn with_kinds(kinds: &[ColumnKind], frames: usize) -> FrameBlock {
        FrameBlock {
            events: Vec::with_capacity(frames),
            columns: kinds.iter().map(|_| Vec::with_capacity(frames)).collect(),
            kinds: kinds.to_vec(),
            all_counts: kinds.iter().all(|k| *k == ColumnKind::Count),
            holes: Vec::new(),
            gaps: Vec::new(),
            frames: 0,
        }
    }

    /// Channels per frame.
    pub fn width(&self) -> usize {
        self.columns.len()
    }

    /// The kind of every column.
    pub fn kinds(&self) -> &[ColumnKind] {
        &self.kinds
    }

    /// Empties the block and gives its columns `kinds` (and so its width).
    pub fn reset_kinds(&mut self, kinds: &[ColumnKind]) {
        self.clear();
        self.columns.resize_with(kinds.len(), Vec::new);
        self.kinds.clear();
        self.kinds.extend_from_slice(kinds);
        self.all_counts = kinds.iter().all(|k| *k == ColumnKind::Count);
    }

    /// Sets the width of an empty block (a recycled block given to another format); the
    /// columns keep their kinds when the width is unchanged, and hold counts otherwise.
    pub fn reset(&mut self, width: usize) {
        self.clear();
        if width != self.width() {
            self.columns.resize_with(width, Vec::new);
            self.kinds = vec![ColumnKind::Count; width];
            self.all_counts = true;
        }
    }

    pub fn clear(&mut self) {
        self.events.clear();
        for c in &mut self.columns {
            c.clear();
        }
        self.holes.clear();
        self.gaps.clear();
        self.frames = 0;
    }

    /// Events (frames and gaps) held.
    pub fn len(&self) -> usize {
        self.events.len()
    }

    pub fn is_empty(&self) -> bool {
        self.events.is_empty()
    }

    /// Frames held.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// The events in order.
    pub fn event_list(&self) -> &[BlockEvent] {
        &self.events
    }

    /// Channel `channel` of every frame, as its column's kind says (holes hold 0).
    pub fn column(&self, channel: usize) -> &[i64] {
        &self.columns[channel]
    }

    /// The values the columns cannot hold, in frame order.
    pub fn holes(&self) -> &[Hole] {
        &self.holes
    }

    /// The gaps and where they fall, in order.
    pub fn gaps(&self) -> &[GapAt] {
        &self.gaps
    }

    /// Channel `channel` of frame `frame`.
    pub fn value(&self, frame: usize, channel: usize) -> Option<ChannelValue> {
        let key = (frame, channel);
        if let Ok(i) = self
            .holes
            .binary_search_by(|h| (h.frame, h.channel).cmp(&key))
        {
            return self.holes[i].value;
        }
        let raw = self.columns[channel][frame];
        Some(match self.kinds[channel] {
            ColumnKind::Count => ChannelValue::Count(raw),
            ColumnKind::Real => ChannelValue::Real(f64::from_bits(raw as u64)),
        })
    }

    /// The values of frame `frame` into `out` (cleared first), in channel order.
    pub fn frame_values(&self, frame: usize, out: &mut Vec<Option<ChannelValue>>) {
        out.clear();
        out.extend((0..self.width()).map(|c| self.value(frame, c)));
    }

    /// Steps of the data the events from `from` on stand for (a frame is one, a gap its
    /// missing frames).
    pub fn steps_from(&self, from: usize) -> u64 {
        self.events[from.min(self.events.len())..]
            .iter()
            .map(|e| match e {
                BlockEvent::Frame { .. } => 1,
                BlockEvent::Gap { missing } => *missing,
            })
            .sum()
    }

    /// Starts a frame: its values follow, one [`FrameBlock::push_count`],
    /// [`FrameBlock::push_real`] or [`FrameBlock::push_missing`] per channel in channel order.
    #[inline]
    pub fn begin_frame(&mut self, frame: BlockEvent) {
        self.events.push(frame);
        self.frames += 1;
    }

    /// The frame begun last: every channel is the count `value(channel)`. False (and nothing
    /// pushed) unless every column holds counts.
    #[inline]
    pub fn push_counts(&mut self, mut value: impl FnMut(usize) -> i64) -> bool {
        if !self.all_counts {
            return false;
        }
        for (ch, col) in self.columns.iter_mut().enumerate() {
            col.push(value(ch));
        }
        true
    }

    /// Appends the counts `values` to every column, channel by channel (`values(channel,
    /// column)` extends one column), for frames already begun whose values were left to be
    /// filled column by column (the decoder's batch of clean frames). False (and nothing
    /// pushed) unless every column holds counts.
    #[inline]
    pub(crate) fn extend_count_columns(
        &mut self,
        mut values: impl FnMut(usize, &mut Vec<i64>),
    ) -> bool {
        if !self.all_counts {
            return false;
        }
        for (ch, col) in self.columns.iter_mut().enumerate() {
            values(ch, col);
        }
        true
    }

    /// Every column holds counts.
    #[inline]
    pub(crate) fn all_counts(&self) -> bool {
        self.all_counts
    }

    /// Channel `channel` of the frame begun last is the count `c`.
    #[inline]
    pub fn push_count(&mut self, channel: usize, c: i64) {
        match self.kinds[channel] {
            ColumnKind::Count => self.columns[channel].push(c),
            ColumnKind::Real => self.push_hole(channel, Some(ChannelValue::Count(c))),
        }
    }

    /// Channel `channel` of the frame begun last is the real increment `x`.
    #[inline]
    pub fn push_real(&mut self, channel: usize, x: f64) {
        match self.kinds[channel] {
            ColumnKind::Real => self.columns[channel].push(x.to_bits() as i64),
            ColumnKind::Count => self.push_hole(channel, Some(ChannelValue::Real(x))),
        }
    }

    /// Channel `channel` of the frame begun last has no value.
    #[inline]
    pub fn push_missing(&mut self, channel: usize) {
        self.push_hole(channel, None);
    }

    /// Channel `channel` of the frame begun last is `v`.
    #[inline]
    pub fn push_value(&mut self, channel: usize, v: Option<ChannelValue>) {
        match v {
            Some(ChannelValue::Count(c)) => self.push_count(channel, c),
            Some(ChannelValue::Real(x)) => self.push_real(channel, x),
            None => self.push_missing(channel),
        }
    }

    #[cold]
    fn push_hole(&mut self, channel: usize, value: Option<ChannelValue>) {
        self.columns[channel].push(0);
        self.holes.push(Hole {
            frame: self.frames - 1,
            channel,
            value,
        });
    }

    /// Appends a frame whose values the iterator gives (exactly `width` of them).
    pub fn push_frame_with(
        &mut self,
        frame: BlockEvent,
        values: impl IntoIterator<Item = Option<ChannelValue>>,
    ) {
        self.begin_frame(frame);
        let mut n = 0;
        for (c, v) in values.into_iter().enumerate() {
            self.push_value(c, v);
            n += 1;
        }
        debug_assert_eq!(n, self.width());
    }

    /// The events and the values of each frame, in order.
    pub fn iter(&self) -> impl Iterator<Item = (BlockEvent, Vec<Option<ChannelValue>>)> + '_ {
        let mut frame = 0;
        self.events.iter().map(move |e| match e {
            BlockEvent::Frame { .. } => {
                let mut v = Vec::with_capacity(self.width());
                self.frame_values(frame, &mut v);
                frame += 1;
                (*e, v)
            }
            BlockEvent::Gap { .. } => (*e, Vec::new()),
        })
    }

    /// The block as one-frame-at-a-time events.
    pub fn events(&self) -> Vec<FrameEvent> {
        self.iter().map(|(e, v)| to_event(e, v)).collect()
    }
}

/// One event of a block as a [`FrameEvent`] (`values`: the frame's own).
pub fn to_event(e: BlockEvent, values: Vec<Option<ChannelValue>>) -> FrameEvent {
    match e {
        BlockEvent::Frame {
            seq,
            temperature_c,
            status,
        } => FrameEvent::Frame(DecodedFrame {
            seq,
            values,
            temperature_c,
            status,
        }),
        BlockEvent::Gap { missing } => FrameEvent::Gap { missing },
    }
}

impl FrameSink for FrameBlock {
    fn push_gap(&mut self, missing: u64) {
        self.gaps.push(GapAt {
            event: self.events.len(),
            frame: self.frames,
            missing,
        });
        self.events.push(BlockEvent::Gap { missing });
    }

    fn push_frame(&mut self, frame: BlockEvent, values: &[Option<ChannelValue>]) {
        self.push_frame_with(frame, values.iter().copied());
    }

    /// An empty block trades places with `block` (no copy); otherwise the events are appended,
    /// column by column when the kinds agree.
    fn take_all(&mut self, block: &mut FrameBlock) {
        if self.is_empty() && self.width() == block.width() {
            std::mem::swap(self, block);
            block.clear();
            return;
        }
        if self.kinds != block.kinds {
            push_each_event(self, block);
            return;
        }
        let (e0, f0) = (self.events.len(), self.frames);
        self.events.extend_from_slice(&block.events);
        for (to, from) in self.columns.iter_mut().zip(&block.columns) {
            to.extend_from_slice(from);
        }
        self.holes.extend(block.holes.iter().map(|h| Hole {
            frame: h.frame + f0,
            ..*h
        }));
        self.gaps.extend(block.gaps.iter().map(|g| GapAt {
            event: g.event + e0,
            frame: g.frame + f0,
            missing: g.missing,
        }));
        self.frames += block.frames;
        block.clear();
    }
}

impl FrameSink for Vec<FrameEvent> {
    fn push_gap(&mut self, missing: u64) {
        self.push(FrameEvent::Gap { missing });
    }

    fn push_frame(&mut self, frame: BlockEvent, values: &[Option<ChannelValue>]) {
        self.push(to_event(frame, values.to_vec()));
    }
}
#[cfg(test)]
mod tests {
    use super::*;

    /// Frames and gaps come back in order with their own values; steps count a gap's frames.
    #[test]
    fn order_values_and_steps() {
        let mut b = FrameBlock::with_capacity(2, 4);
        let f = |seq| BlockEvent::Frame {
            seq,
            temperature_c: None,
            status: Some(seq * 10),
        };
        b.push_frame(f(0), &[Some(ChannelValue::Count(1)), None]);
        b.push_gap(3);
        b.push_frame_with(
            f(4),
            [Some(ChannelValue::Count(-2)), Some(ChannelValue::Real(0.5))],
        );
        assert_eq!((b.len(), b.frames()), (3, 2));
        assert_eq!(b.steps_from(0), 5);
        assert_eq!(b.steps_from(1), 4);
        assert_eq!(b.steps_from(9), 0);
        let ev = b.events();
        assert_eq!(ev[1], FrameEvent::Gap { missing: 3 });
        match &ev[2] {
            FrameEvent::Frame(d) => {
                assert_eq!(d.seq, 4);
                assert_eq!(d.status, Some(40));
                assert_eq!(
                    d.values,
                    vec![Some(ChannelValue::Count(-2)), Some(ChannelValue::Real(0.5))]
                );
            }
            other => panic!("expected a frame, got {other:?}"),
        }
        let mut v: Vec<FrameEvent> = Vec::new();
        for (e, vals) in b.iter() {
            match e {
                BlockEvent::Gap { missing } => v.push_gap(missing),
                frame => v.push_frame(frame, &vals),
            }
        }
        assert_eq!(v, ev);
    }

    /// A block appended behind a non-empty one (`take_all` without the swap): its holes and gaps
    /// move to the right frames and events, in a real column and a count column alike; the
    /// result reads as the two event lists one after the other.
    #[test]
    fn appending_moves_holes_and_gaps() {
        let kinds = [ColumnKind::Count, ColumnKind::Real];
        let f = |seq| BlockEvent::Frame {
            seq,
            temperature_c: Some(20.5),
            status: None,
        };
        let mut a = FrameBlock::with_kinds(&kinds, 2);
        a.push_frame(f(0), &[Some(ChannelValue::Count(5)), None]);
        a.push_gap(2);
        a.push_frame(
            f(3),
            &[Some(ChannelValue::Count(-7)), Some(ChannelValue::Real(1.5))],
        );
        let mut b = FrameBlock::with_kinds(&kinds, 2);
        b.push_gap(1);
        b.push_frame(f(5), &[None, Some(ChannelValue::Real(-0.25))]);
        b.push_frame(
            f(6),
            &[Some(ChannelValue::Real(2.0)), Some(ChannelValue::Count(3))],
        );
        let mut want = a.events();
        want.extend(b.events());
        a.take_all(&mut b);
        assert!(b.is_empty());
        assert_eq!(a.events(), want);
        assert_eq!((a.frames(), a.len()), (4, 6));
        // Holes: frame 0 channel 1 (missing), frame 2 channel 0 (missing), frame 3 channel 0 (a
        // real value on a count column), frame 3 channel 1 (a count on a real column).
        let holes: Vec<(usize, usize)> = a.holes().iter().map(|h| (h.frame, h.channel)).collect();
        assert_eq!(holes, vec![(0, 1), (2, 0), (3, 0), (3, 1)]);
        let gaps: Vec<(usize, usize, u64)> = a
            .gaps()
            .iter()
            .map(|g| (g.event, g.frame, g.missing))
            .collect();
        assert_eq!(gaps, vec![(1, 1, 2), (3, 2, 1)]);
        assert_eq!(a.column(1)[1], 1.5f64.to_bits() as i64);
        assert_eq!(a.value(3, 1), Some(ChannelValue::Count(3)));
        // Into a block of other kinds: value by value, the same events.
        let mut c = FrameBlock::with_capacity(2, 0);
        c.push_gap(4);
        let mut want_c = c.events();
        want_c.extend(a.events());
        c.take_all(&mut a);
        assert_eq!(c.events(), want_c);
    }
}
