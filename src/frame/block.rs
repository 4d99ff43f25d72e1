//! A flat batch of decoded frames: what the decoder fills and the analysis reads, with no
//! allocation per frame.
//!
//! A [`FrameBlock`] holds the events of a stretch of stream in order ([`BlockEvent`]: a frame's
//! counter, temperature and status, or a gap) and the channel values of its frames in one
//! frame-major vector, `width` values per frame. The decoder appends to one block that lives as
//! long as it does; the pipeline hands whole blocks to the analysis and gets them back to reuse,
//! so a replay allocates per chunk of 64 KiB, not per frame (profiled: a `Vec` per decoded
//! frame and its `free` on the analysis thread were a third of a replay's instructions,
//! BENCHMARKS.md "Decoding at the speed of the statistics").
//!
//! [`FrameEvent`] and [`DecodedFrame`] remain the one-frame-at-a-time view of the same data
//! ([`FrameBlock::events`], [`crate::frame::Decoder::next_event`]).

use super::{ChannelValue, DecodedFrame, FrameEvent};

/// One event of a block. A `Frame`'s channel values are the block's next `width` values.
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

/// Decoded frames and the gaps between them, flat (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FrameBlock {
    width: usize,
    events: Vec<BlockEvent>,
    /// Frame-major: the values of the `i`-th frame are `values[i * width..(i + 1) * width]`.
    values: Vec<Option<ChannelValue>>,
}

/// Where decoded frames go: a [`FrameBlock`], or (tests, one-frame-at-a-time callers) a
/// vector of [`FrameEvent`]s.
pub trait FrameSink {
    fn push_gap(&mut self, missing: u64);
    /// A frame and its values (`values.len()` is the block's width).
    fn push_frame(&mut self, frame: BlockEvent, values: &[Option<ChannelValue>]);
    /// Every event of `block`, in order; `block` is left empty.
    fn take_all(&mut self, block: &mut FrameBlock) {
        for (e, v) in block.iter() {
            match e {
                BlockEvent::Gap { missing } => self.push_gap(missing),
                frame => self.push_frame(frame, v),
            }
        }
        block.clear();
    }
}

impl FrameBlock {
    /// An empty block for frames of `width` channels, with room for `frames` frames.
    pub fn with_capacity(width: usize, frames: usize) -> FrameBlock {
        FrameBlock {
            width,
            events: Vec::with_capacity(frames),
            values: Vec::with_capacity(frames * width),
        }
    }

    /// Channels per frame.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Sets the width of an empty block (a recycled block given to another format).
    pub fn reset(&mut self, width: usize) {
        self.clear();
        self.width = width;
    }

    pub fn clear(&mut self) {
        self.events.clear();
        self.values.clear();
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
        self.values.len().checked_div(self.width).unwrap_or(0)
    }

    /// The events in order.
    pub fn event_list(&self) -> &[BlockEvent] {
        &self.events
    }

    /// All values, frame-major.
    pub fn values(&self) -> &[Option<ChannelValue>] {
        &self.values
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

    /// Appends a frame whose values the iterator gives (exactly `width` of them).
    pub fn push_frame_with(
        &mut self,
        frame: BlockEvent,
        values: impl IntoIterator<Item = Option<ChannelValue>>,
    ) {
        let before = self.values.len();
        self.values.extend(values);
        debug_assert_eq!(self.values.len() - before, self.width);
        self.events.push(frame);
    }

    /// The events and the values of each frame, in order.
    pub fn iter(&self) -> impl Iterator<Item = (BlockEvent, &[Option<ChannelValue>])> + '_ {
        let mut at = 0;
        let w = self.width;
        self.events.iter().map(move |e| match e {
            BlockEvent::Frame { .. } => {
                let v = &self.values[at..at + w];
                at += w;
                (*e, v)
            }
            BlockEvent::Gap { .. } => (*e, &self.values[0..0]),
        })
    }

    /// The block as one-frame-at-a-time events.
    pub fn events(&self) -> Vec<FrameEvent> {
        self.iter().map(|(e, v)| to_event(e, v)).collect()
    }
}

/// One event of a block as a [`FrameEvent`] (its values copied into the frame's own vector).
pub fn to_event(e: BlockEvent, values: &[Option<ChannelValue>]) -> FrameEvent {
    match e {
        BlockEvent::Frame {
            seq,
            temperature_c,
            status,
        } => FrameEvent::Frame(DecodedFrame {
            seq,
            values: values.to_vec(),
            temperature_c,
            status,
        }),
        BlockEvent::Gap { missing } => FrameEvent::Gap { missing },
    }
}

impl FrameSink for FrameBlock {
    fn push_gap(&mut self, missing: u64) {
        self.events.push(BlockEvent::Gap { missing });
    }

    fn push_frame(&mut self, frame: BlockEvent, values: &[Option<ChannelValue>]) {
        self.values.extend_from_slice(values);
        self.events.push(frame);
    }

    /// An empty block trades places with `block` (no copy); otherwise the events are copied.
    fn take_all(&mut self, block: &mut FrameBlock) {
        if self.is_empty() && self.width == block.width {
            std::mem::swap(self, block);
        } else {
            self.events.extend_from_slice(&block.events);
            self.values.extend_from_slice(&block.values);
            block.clear();
        }
    }
}

impl FrameSink for Vec<FrameEvent> {
    fn push_gap(&mut self, missing: u64) {
        self.push(FrameEvent::Gap { missing });
    }

    fn push_frame(&mut self, frame: BlockEvent, values: &[Option<ChannelValue>]) {
        self.push(to_event(frame, values));
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
                frame => v.push_frame(frame, vals),
            }
        }
        assert_eq!(v, ev);
    }
}
