//! A flat batch of decoded frames: what the decoder fills and the analysis reads, with no
//! allocation per frame.
//!
//! A [`FrameBlock`] holds the events of a stretch of stream in order ([`BlockEvent`]: a frame's
//! counter, temperature and status, or a gap) and the channel values of its frames **column by
//! column**: one vector per channel, one entry per frame. A column holds one kind of value
//! ([`ColumnKind`]: exact counts of up to 32 bits as `i32`, wider counts as `i64`, or real
//! increments as their f64 bit patterns), so a run of a channel's counts is a plain `&[i32]` or
//! `&[i64]` ([`ColumnValues`]) the accumulators take as it is. The narrow columns halve the bytes
//! the decoder stores and the analysis reads for the usual 32-bit increments (BENCHMARKS.md,
//! issue 15, sessions 10 and 11). A value that is missing,
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
    /// [`ChannelValue::Count`]s, as they are (`i64`).
    #[default]
    Count,
    /// [`ChannelValue::Count`]s of a field of at most 32 bits whose values all fit an `i32`
    /// (`i8`, `u8`, `i16`, `u16`, `i32` fields), stored as `i32`; a count outside that range is a
    /// [`Hole`] holding its value.
    Count32,
    /// [`ChannelValue::Real`]s, as `f64::to_bits` (reinterpreted as `i64`).
    Real,
}

impl ColumnKind {
    /// The column holds counts (of either width).
    pub fn is_count(self) -> bool {
        matches!(self, ColumnKind::Count | ColumnKind::Count32)
    }
}

/// A column's storage: `i32` entries for [`ColumnKind::Count32`], `i64` for the others.
#[derive(Debug, Clone, PartialEq)]
enum Column {
    Wide(Vec<i64>),
    Narrow(Vec<i32>),
}

impl Column {
    fn new(kind: ColumnKind, frames: usize) -> Column {
        match kind {
            ColumnKind::Count32 => Column::Narrow(Vec::with_capacity(frames)),
            ColumnKind::Count | ColumnKind::Real => Column::Wide(Vec::with_capacity(frames)),
        }
    }

    /// Storage for `kind`: this one (emptied) when its width fits, a new one otherwise.
    fn remake(&mut self, kind: ColumnKind) {
        match (&mut *self, kind) {
            (Column::Narrow(v), ColumnKind::Count32) => v.clear(),
            (Column::Wide(v), ColumnKind::Count | ColumnKind::Real) => v.clear(),
            _ => *self = Column::new(kind, 0),
        }
    }

    fn clear(&mut self) {
        match self {
            Column::Wide(v) => v.clear(),
            Column::Narrow(v) => v.clear(),
        }
    }

    /// A placeholder entry (a hole's).
    fn push_zero(&mut self) {
        match self {
            Column::Wide(v) => v.push(0),
            Column::Narrow(v) => v.push(0),
        }
    }

    fn values(&self) -> ColumnValues<'_> {
        match self {
            Column::Wide(v) => ColumnValues::Wide(v),
            Column::Narrow(v) => ColumnValues::Narrow(v),
        }
    }

    /// Appends `other`'s entries (of the same width).
    fn extend_from(&mut self, other: &Column) {
        match (self, other) {
            (Column::Wide(a), Column::Wide(b)) => a.extend_from_slice(b),
            (Column::Narrow(a), Column::Narrow(b)) => a.extend_from_slice(b),
            _ => unreachable!("columns of one kind have one width"),
        }
    }
}

/// A stretch of one column's entries, as stored: `i32` ([`ColumnKind::Count32`]) or `i64`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ColumnValues<'a> {
    Wide(&'a [i64]),
    Narrow(&'a [i32]),
}

impl<'a> ColumnValues<'a> {
    pub fn len(self) -> usize {
        match self {
            ColumnValues::Wide(v) => v.len(),
            ColumnValues::Narrow(v) => v.len(),
        }
    }

    pub fn is_empty(self) -> bool {
        self.len() == 0
    }

    /// The entries `range`.
    pub fn slice(self, range: std::ops::Range<usize>) -> ColumnValues<'a> {
        match self {
            ColumnValues::Wide(v) => ColumnValues::Wide(&v[range]),
            ColumnValues::Narrow(v) => ColumnValues::Narrow(&v[range]),
        }
    }

    /// Entry `i`, widened to `i64` (the raw entry: a count, or a real value's bits).
    pub fn get(self, i: usize) -> i64 {
        match self {
            ColumnValues::Wide(v) => v[i],
            ColumnValues::Narrow(v) => i64::from(v[i]),
        }
    }
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
    /// One per channel; entry `i` of column `c` is channel `c` of the `i`-th frame.
    columns: Vec<Column>,
    kinds: Vec<ColumnKind>,
    /// In frame order, then channel order.
    holes: Vec<Hole>,
    /// Every column holds counts of this one kind ([`ColumnKind::Count`] or
    /// [`ColumnKind::Count32`]); `None` otherwise.
    all_counts: Option<ColumnKind>,
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
            columns: kinds.iter().map(|&k| Column::new(k, frames)).collect(),
            kinds: kinds.to_vec(),
            all_counts: uniform_counts(kinds),
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
        self.columns
            .resize_with(kinds.len(), || Column::Wide(Vec::new()));
        for (c, &k) in self.columns.iter_mut().zip(kinds) {
            c.remake(k);
        }
        self.kinds.clear();
        self.kinds.extend_from_slice(kinds);
        self.all_counts = uniform_counts(kinds);
    }

    /// Sets the width of an empty block (a recycled block given to another format); the
    /// columns keep their kinds when the width is unchanged, and hold counts otherwise.
    pub fn reset(&mut self, width: usize) {
        self.clear();
        if width != self.width() {
            self.reset_kinds(&vec![ColumnKind::Count; width]);
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
    pub fn column(&self, channel: usize) -> ColumnValues<'_> {
        self.columns[channel].values()
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
        let raw = self.column(channel).get(frame);
        Some(match self.kinds[channel] {
            ColumnKind::Count | ColumnKind::Count32 => ChannelValue::Count(raw),
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

    /// Appends counts to every column, channel by channel (`values(channel, column)` extends
    /// one column), for frames already begun whose values were left to be filled column by
    /// column (the decoder's batch of clean frames). False (and nothing pushed) unless every
    /// column holds [`ColumnKind::Count`]s.
    #[inline]
    pub(crate) fn extend_count_columns(
        &mut self,
        mut values: impl FnMut(usize, &mut Vec<i64>),
    ) -> bool {
        if self.all_counts != Some(ColumnKind::Count) {
            return false;
        }
        for (ch, col) in self.columns.iter_mut().enumerate() {
            if let Column::Wide(v) = col {
                values(ch, v);
            }
        }
        true
    }

    /// [`FrameBlock::extend_count_columns`] for blocks whose columns all hold
    /// [`ColumnKind::Count32`]s.
    #[inline]
    pub(crate) fn extend_count32_columns(
        &mut self,
        mut values: impl FnMut(usize, &mut Vec<i32>),
    ) -> bool {
        if self.all_counts != Some(ColumnKind::Count32) {
            return false;
        }
        for (ch, col) in self.columns.iter_mut().enumerate() {
            if let Column::Narrow(v) = col {
                values(ch, v);
            }
        }
        true
    }

    /// The kind of every column when all hold counts of one width ([`ColumnKind::Count`] or
    /// [`ColumnKind::Count32`]).
    #[inline]
    pub(crate) fn all_counts(&self) -> Option<ColumnKind> {
        self.all_counts
    }

    /// Channel `channel` of the frame begun last is the count `c`.
    #[inline]
    pub fn push_count(&mut self, channel: usize, c: i64) {
        match &mut self.columns[channel] {
            Column::Wide(v) if self.kinds[channel] == ColumnKind::Count => v.push(c),
            Column::Narrow(v) => match i32::try_from(c) {
                Ok(n) => v.push(n),
                Err(_) => self.push_hole(channel, Some(ChannelValue::Count(c))),
            },
            Column::Wide(_) => self.push_hole(channel, Some(ChannelValue::Count(c))),
        }
    }

    /// Channel `channel` of the frame begun last is the real increment `x`.
    #[inline]
    pub fn push_real(&mut self, channel: usize, x: f64) {
        match &mut self.columns[channel] {
            Column::Wide(v) if self.kinds[channel] == ColumnKind::Real => {
                v.push(x.to_bits() as i64)
            }
            _ => self.push_hole(channel, Some(ChannelValue::Real(x))),
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
        self.columns[channel].push_zero();
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

/// The one counts kind of `kinds`, when every column holds counts of one width.
fn uniform_counts(kinds: &[ColumnKind]) -> Option<ColumnKind> {
    let first = *kinds.first().unwrap_or(&ColumnKind::Count);
    (first.is_count() && kinds.iter().all(|k| *k == first)).then_some(first)
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
            to.extend_from(from);
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
        assert_eq!(a.column(1).get(1), 1.5f64.to_bits() as i64);
        assert_eq!(a.value(3, 1), Some(ChannelValue::Count(3)));
        // Into a block of other kinds: value by value, the same events.
        let mut c = FrameBlock::with_capacity(2, 0);
        c.push_gap(4);
        let mut want_c = c.events();
        want_c.extend(a.events());
        c.take_all(&mut a);
        assert_eq!(c.events(), want_c);
    }

    /// A narrow counts column: counts within `i32` are stored as they are, a count beyond it
    /// and a real value are holes that keep their value; appended blocks and a block of wide
    /// columns receiving it read back the same events.
    #[test]
    fn narrow_columns_keep_every_count() {
        let kinds = [ColumnKind::Count32, ColumnKind::Count];
        let f = |seq| BlockEvent::Frame {
            seq,
            temperature_c: None,
            status: None,
        };
        let big = i64::from(i32::MAX) + 1;
        let small = i64::from(i32::MIN);
        let mut a = FrameBlock::with_kinds(&kinds, 4);
        a.push_frame(
            f(0),
            &[
                Some(ChannelValue::Count(small)),
                Some(ChannelValue::Count(big)),
            ],
        );
        a.push_frame(
            f(1),
            &[
                Some(ChannelValue::Count(big)),
                Some(ChannelValue::Count(-1)),
            ],
        );
        a.push_gap(2);
        a.push_frame(f(4), &[Some(ChannelValue::Real(0.5)), None]);
        a.push_frame(
            f(5),
            &[
                Some(ChannelValue::Count(i64::from(i32::MAX))),
                Some(ChannelValue::Count(3)),
            ],
        );
        assert_eq!(
            a.column(0),
            ColumnValues::Narrow(&[i32::MIN, 0, 0, i32::MAX])
        );
        assert_eq!(a.column(1), ColumnValues::Wide(&[big, -1, 0, 3]));
        let holes: Vec<(usize, usize)> = a.holes().iter().map(|h| (h.frame, h.channel)).collect();
        assert_eq!(holes, vec![(1, 0), (2, 0), (2, 1)]);
        assert_eq!(a.value(1, 0), Some(ChannelValue::Count(big)));
        assert_eq!(a.value(2, 0), Some(ChannelValue::Real(0.5)));
        assert_eq!(a.value(0, 0), Some(ChannelValue::Count(small)));
        let want = a.events();
        // Behind another narrow block: column by column.
        let mut b = FrameBlock::with_kinds(&kinds, 0);
        b.push_frame(
            f(9),
            &[Some(ChannelValue::Count(7)), Some(ChannelValue::Count(8))],
        );
        let mut want_b = b.events();
        want_b.extend(want.clone());
        let mut a2 = a.clone();
        b.take_all(&mut a2);
        assert_eq!(b.events(), want_b);
        assert_eq!(
            b.column(0),
            ColumnValues::Narrow(&[7, i32::MIN, 0, 0, i32::MAX])
        );
        // Into wide columns (other kinds): value by value, the same events; the big count is
        // now an entry of its column, not a hole.
        let mut w = FrameBlock::with_capacity(2, 0);
        w.push_gap(1);
        let mut want_w = w.events();
        want_w.extend(want);
        w.take_all(&mut a);
        assert_eq!(w.events(), want_w);
        assert_eq!(w.column(0).get(1), big);
        // The kinds change with the storage: reset to wide and back.
        w.reset_kinds(&kinds);
        assert_eq!((w.len(), w.column(0)), (0, ColumnValues::Narrow(&[])));
    }
}
