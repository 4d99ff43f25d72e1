//! The streaming frame decoder: bytes in arbitrary chunks -> [`FrameEvent`]s, plus the
//! [`Health`] counters. Pure and synchronous; the caller owns the source and the clock.
//!
//! # How it reads a stream
//!
//! From the first unconsumed byte it searches for the sync bytes; the message would start
//! `sync.offset` bytes before them. The id bytes pick the message kind (no match: a false
//! sync, skip one byte). With the kind's full length in the buffer the checksum is checked:
//! good -> the message is consumed whole; bad -> `crc_errors` + 1 and the search restarts one
//! byte after the failed start, so an intact frame that follows garbage or a damaged frame is
//! never lost. Bytes the search passes over are `bytes_skipped`. "Not enough bytes yet" is a
//! state: the decoder waits for the next [`Decoder::push`]. Every byte is accounted for:
//! `bytes_accepted + bytes_skipped + pending() == bytes_in`.
//!
//! # Counter rules
//!
//! Frames carry a counter modulo `M`. A frame whose counter equals the previous frame's is a
//! duplicate (dropped, `duplicates` + 1); an advance of `d` (mod `M`) means `d - 1` frames were
//! lost, reported as a [`FrameEvent::Gap`] before the next frame and added to `missing`. A
//! loss of `M` or more consecutive frames is invisible to the counter (it wraps).
//!
//! With `[interleave]` (hg4930) the frame and `count` other messages share one counter that
//! advances once per message, the frame being every `count + 1`-th. The decoder then places
//! every message in a slot: the smallest advance consistent with the counter *and* with the
//! kind (frames only on slots that are multiples of `count + 1`). This combines the 2-bit
//! counter with the count of control messages between two frames, and so sees a loss of up to
//! `lcm(M, count + 1) - 1` consecutive messages. Messages before the first frame are only
//! checked and skipped.

use std::collections::VecDeque;

use serde::{Deserialize, Serialize};

use super::descriptor::{BitMeaning, FrameDescriptor, MessageSpec};
use super::field::{read, read_bits, RawValue};
use super::{ChannelValue, DecodedFrame, FrameEvent};

/// Decoder health: the docs/records.md `health` fields first, then extra detail.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Health {
    /// Good frames delivered (duplicates not included).
    pub frames: u64,
    /// Candidate messages (sync and a known id, full length present) whose checksum failed.
    pub crc_errors: u64,
    /// Times the decoder regained lock: a good message accepted after one or more skipped bytes.
    pub resyncs: u64,
    /// Frames lost, by the counter.
    pub missing: u64,
    /// Frames dropped because they repeated the previous frame's counter.
    pub duplicates: u64,
    /// Bytes passed over while searching for a good message.
    pub bytes_skipped: u64,
    /// Bytes pushed in.
    pub bytes_in: u64,
    /// Bytes of good messages (frames, duplicates and messages without increments).
    pub bytes_accepted: u64,
    /// Good messages without increments (e.g. KVH built-in-test, hg4930 control), skipped.
    pub other_messages: u64,
    /// Channel values marked invalid by their status bit (delivered as missing values).
    pub invalid_values: u64,
    /// Interleaved formats: counter values inconsistent with the message schedule (the
    /// decoder re-anchored and assumed no loss).
    pub counter_breaks: u64,
}

/// Where a message landed in the counter sequence.
enum Placement {
    /// Not tracked (no counter, or before the first frame of an interleaved format).
    Untracked,
    Duplicate,
    /// Advanced; `missing` frames lost before it; `seq` set for frames.
    Advanced {
        missing: u64,
        seq: u64,
    },
}

/// Unwraps the counter into message slots; see the module documentation.
struct SeqTracker {
    modulus: u64,
    /// Slots per frame (1 without interleave).
    cycle: u64,
    /// Last tracked message: (slot, counter, is_frame).
    last: Option<(u64, u64, bool)>,
    /// Seq of the last frame, kept across a re-anchor.
    last_seq: Option<u64>,
}

impl SeqTracker {
    fn observe(&mut self, is_frame: bool, counter: u64, breaks: &mut u64) -> Placement {
        let m = self.modulus;
        let Some((slot, c_prev, prev_is_frame)) = self.last else {
            if !is_frame {
                return Placement::Untracked;
            }
            // Anchor: the first frame (or the first after a break) keeps seq continuity.
            // Without interleave the first seq is the counter itself; with it the counter says
            // little about the frame number, so frames count from 0.
            let seq = match self.last_seq {
                None if self.cycle == 1 => counter,
                None => 0,
                Some(s) => s + 1,
            };
            self.last = Some((seq * self.cycle, counter, true));
            self.last_seq = Some(seq);
            return Placement::Advanced { missing: 0, seq };
        };
        let d = (counter + m - c_prev % m) % m;
        let mut found = None;
        // lcm(m, cycle) <= m * cycle bounds the search for a consistent advance.
        let mut a = d;
        while a <= m * self.cycle {
            let on_frame_slot = (slot + a).is_multiple_of(self.cycle);
            let ok = if a == 0 {
                is_frame == prev_is_frame
            } else {
                on_frame_slot == is_frame
            };
            if ok {
                found = Some(a);
                break;
            }
            a += m;
        }
        match found {
            Some(0) => Placement::Duplicate,
            Some(a) => {
                let new_slot = slot + a;
                // Frame slots strictly between the two messages.
                let missing = (new_slot - 1) / self.cycle - slot / self.cycle;
                self.last = Some((new_slot, counter, is_frame));
                let seq = new_slot / self.cycle;
                if is_frame {
                    self.last_seq = Some(seq);
                }
                Placement::Advanced { missing, seq }
            }
            None => {
                *breaks += 1;
                self.last = None;
                if is_frame {
                    self.observe(true, counter, breaks)
                } else {
                    Placement::Untracked
                }
            }
        }
    }
}

/// What a [`Decoder`] holds between two pushes, for a checkpoint (`crate::checkpoint`): the
/// bytes of a message not yet complete, the counters, and where the frame counter stands.
/// Taken when every decoded event has been collected.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct DecoderState {
    /// Unconsumed bytes (at most about one message).
    pub pending: Vec<u8>,
    pub health: Health,
    pub skipping: bool,
    /// The counter tracker's last message: (slot, counter, is_frame).
    pub last: Option<(u64, u64, bool)>,
    pub last_seq: Option<u64>,
    pub next_index: u64,
}

/// Streaming decoder for one descriptor. Feed it with [`Decoder::push`], take events with
/// [`Decoder::next_event`] (or [`Decoder::drain`]), call [`Decoder::finish`] at end of input.
pub struct Decoder {
    desc: FrameDescriptor,
    buf: Vec<u8>,
    /// First unconsumed byte of `buf`.
    pos: usize,
    events: VecDeque<FrameEvent>,
    health: Health,
    /// Bytes were skipped since the last good message.
    skipping: bool,
    tracker: SeqTracker,
    /// Running index for formats without a counter.
    next_index: u64,
    finished: bool,
}

/// Compact the buffer once this many consumed bytes sit at its front.
const COMPACT_AT_BYTES: usize = 1 << 16;

impl Decoder {
    pub fn new(desc: FrameDescriptor) -> Self {
        let cycle = desc.interleave.as_ref().map_or(1, |i| i.count + 1);
        let modulus = desc.frame().counter.as_ref().map_or(1, |c| c.modulus);
        Decoder {
            desc,
            buf: Vec::new(),
            pos: 0,
            events: VecDeque::new(),
            health: Health::default(),
            skipping: false,
            tracker: SeqTracker {
                modulus,
                cycle,
                last: None,
                last_seq: None,
            },
            next_index: 0,
            finished: false,
        }
    }

    pub fn descriptor(&self) -> &FrameDescriptor {
        &self.desc
    }

    /// The decoder's state, or `None` while decoded events are still waiting to be taken.
    pub fn state(&self) -> Option<DecoderState> {
        self.events.is_empty().then(|| DecoderState {
            pending: self.buf[self.pos..].to_vec(),
            health: self.health.clone(),
            skipping: self.skipping,
            last: self.tracker.last,
            last_seq: self.tracker.last_seq,
            next_index: self.next_index,
        })
    }

    /// A decoder for `desc` in the state `st` ([`Decoder::state`]): fed the bytes that followed,
    /// it gives the events and counters the original decoder would have given.
    pub fn restore(desc: FrameDescriptor, st: &DecoderState) -> Self {
        let mut d = Decoder::new(desc);
        d.buf = st.pending.clone();
        d.health = st.health.clone();
        d.skipping = st.skipping;
        d.tracker.last = st.last;
        d.tracker.last_seq = st.last_seq;
        d.next_index = st.next_index;
        d
    }

    pub fn health(&self) -> &Health {
        &self.health
    }

    /// Bytes held while waiting for the rest of a possible message.
    pub fn pending(&self) -> usize {
        self.buf.len() - self.pos
    }

    /// Appends bytes and decodes as far as they allow. Bytes pushed after [`Decoder::finish`]
    /// start a new stretch of the same stream.
    pub fn push(&mut self, bytes: &[u8]) {
        self.finished = false;
        self.health.bytes_in += bytes.len() as u64;
        if self.pos >= COMPACT_AT_BYTES || (self.pos > 0 && self.pos == self.buf.len()) {
            self.buf.drain(..self.pos);
            self.pos = 0;
        }
        self.buf.extend_from_slice(bytes);
        self.run();
    }

    /// End of input: a message cut off by the end is skipped, and whatever follows it is still
    /// searched. Afterwards `pending()` is 0.
    pub fn finish(&mut self) {
        self.finished = true;
        self.run();
        let rest = self.buf.len() - self.pos;
        self.skip(rest);
    }

    /// The next decoded event, if any.
    pub fn next_event(&mut self) -> Option<FrameEvent> {
        self.events.pop_front()
    }

    /// All events decoded so far.
    pub fn drain(&mut self) -> impl Iterator<Item = FrameEvent> + '_ {
        self.events.drain(..)
    }

    fn skip(&mut self, n: usize) {
        if n > 0 {
            self.pos += n;
            self.health.bytes_skipped += n as u64;
            self.skipping = true;
        }
    }

    fn run(&mut self) {
        let sync_len = self.desc.sync.bytes.len();
        let sync_off = self.desc.sync.offset;
        loop {
            let from = self.pos + sync_off;
            let found = find(&self.buf, from, &self.desc.sync.bytes);
            let Some(q) = found else {
                // No sync: keep only the bytes that could still begin one.
                let keep_from = if self.finished {
                    self.buf.len()
                } else {
                    (self.buf.len() + 1).saturating_sub(sync_len + sync_off)
                };
                let n = keep_from.saturating_sub(self.pos);
                self.skip(n);
                return;
            };
            let start = q - sync_off;
            self.skip(start - self.pos);
            let avail = self.buf.len() - start;
            // Which kind? (id bytes)
            let kind = if self.desc.messages.len() == 1 && self.desc.messages[0].id.is_empty() {
                Some(0)
            } else {
                let id_off = self.desc.sync.id_offset;
                let id_len = self.desc.messages[0].id.len();
                if avail < id_off + id_len {
                    if self.finished {
                        self.skip(1);
                        continue;
                    }
                    return;
                }
                let id = &self.buf[start + id_off..start + id_off + id_len];
                self.desc.messages.iter().position(|m| m.id == id)
            };
            let Some(kind) = kind else {
                self.skip(1);
                continue;
            };
            let len = self.desc.messages[kind].length;
            if avail < len {
                if self.finished {
                    self.skip(1);
                    continue;
                }
                return;
            }
            let msg = &self.buf[start..start + len];
            if !checksum_ok(&self.desc.messages[kind], msg) {
                self.health.crc_errors += 1;
                self.skip(1);
                continue;
            }
            self.accept(kind, start, len);
            self.pos = start + len;
        }
    }

    fn accept(&mut self, kind: usize, start: usize, len: usize) {
        self.health.bytes_accepted += len as u64;
        if self.skipping {
            self.health.resyncs += 1;
            self.skipping = false;
        }
        let is_frame = kind == self.desc.frame_kind;
        let spec = &self.desc.messages[kind];
        let msg = &self.buf[start..start + len];
        let tracked = is_frame
            || self
                .desc
                .interleave
                .as_ref()
                .is_some_and(|i| i.message == kind);
        let placement = match (&spec.counter, tracked) {
            (Some(c), true) => {
                let raw = read_bits(msg, c.offset, c.ty, c.order).unwrap_or(0);
                let counter = (raw >> c.shift) % c.modulus;
                self.tracker
                    .observe(is_frame, counter, &mut self.health.counter_breaks)
            }
            _ => Placement::Untracked,
        };
        let seq = match placement {
            Placement::Duplicate => {
                if is_frame {
                    self.health.duplicates += 1;
                } else {
                    self.health.other_messages += 1;
                }
                return;
            }
            Placement::Advanced { missing, seq } => {
                if missing > 0 {
                    self.health.missing += missing;
                    self.events.push_back(FrameEvent::Gap { missing });
                }
                seq
            }
            Placement::Untracked => self.next_index,
        };
        if !is_frame {
            self.health.other_messages += 1;
            return;
        }
        self.next_index = seq + 1;
        let frame = decode_frame(&self.desc, spec, msg, seq, &mut self.health.invalid_values);
        self.health.frames += 1;
        self.events.push_back(FrameEvent::Frame(frame));
    }
}

/// First index `>= from` where `pat` starts in `buf`.
fn find(buf: &[u8], from: usize, pat: &[u8]) -> Option<usize> {
    let hay = buf.get(from..)?;
    let first = *pat.first()?;
    let mut i = 0;
    while i + pat.len() <= hay.len() {
        let off = hay[i..].iter().position(|&b| b == first)?;
        i += off;
        if i + pat.len() > hay.len() {
            return None;
        }
        if &hay[i..i + pat.len()] == pat {
            return Some(from + i);
        }
        i += 1;
    }
    None
}

/// True when the message's stored checksum matches the covered bytes.
pub fn checksum_ok(spec: &MessageSpec, msg: &[u8]) -> bool {
    let c = &spec.checksum;
    let Some(covered) = msg.get(c.start..=c.end) else {
        return false;
    };
    let computed = c.algorithm.compute(covered, c.order);
    let stored = read_bits(msg, c.at, width_type(c.algorithm.width()), c.order);
    stored == Some(computed)
}

/// The unsigned field type of a checksum width.
pub(crate) fn width_type(width: usize) -> super::field::FieldType {
    use super::field::FieldType;
    match width {
        1 => FieldType::U8,
        2 => FieldType::U16,
        _ => FieldType::U32,
    }
}

/// Reads the channels, validity and temperature of a good frame.
fn decode_frame(
    desc: &FrameDescriptor,
    spec: &MessageSpec,
    msg: &[u8],
    seq: u64,
    invalid: &mut u64,
) -> DecodedFrame {
    let status = spec
        .status
        .as_ref()
        .and_then(|s| read_bits(msg, s.offset, s.ty, s.order));
    let valid = |bit: Option<u32>| -> bool {
        match (bit, status, spec.status.as_ref()) {
            (Some(b), Some(st), Some(s)) => {
                let set = (st >> b) & 1 == 1;
                match s.bit_set_means {
                    BitMeaning::Fault => !set,
                    BitMeaning::Valid => set,
                }
            }
            _ => true,
        }
    };
    let values = spec
        .channels
        .iter()
        .map(|c| {
            if !valid(c.status_bit) {
                *invalid += 1;
                return None;
            }
            let raw = read(msg, c.offset, c.ty, c.order)?;
            Some(match raw {
                RawValue::Int(n) if c.is_count() => ChannelValue::Count(n),
                r => ChannelValue::Real(r.as_f64() * c.scale * desc.kind_factor(c.kind)),
            })
        })
        .collect();
    let temperature_c = spec.temperature.as_ref().and_then(|t| {
        if !valid(t.status_bit) {
            return None;
        }
        read(msg, t.offset, t.ty, t.order).map(|r| r.as_f64() * t.scale)
    });
    DecodedFrame {
        seq,
        values,
        temperature_c,
        status,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-worked searches: the pattern at 0, in the middle, split by the end, absent.
    #[test]
    fn find_sync() {
        let b = [0xAA, 0x55, 0x00, 0xAA, 0xAA, 0x55, 0xAA];
        assert_eq!(find(&b, 0, &[0xAA, 0x55]), Some(0));
        assert_eq!(find(&b, 1, &[0xAA, 0x55]), Some(4));
        assert_eq!(find(&b, 5, &[0xAA, 0x55]), None);
        assert_eq!(find(&b, 9, &[0xAA, 0x55]), None);
    }

    /// The slot rule with M = 4 and 6 slots per frame (hg4930): losses worked by hand.
    #[test]
    fn interleaved_slots() {
        let mut t = SeqTracker {
            modulus: 4,
            cycle: 6,
            last: None,
            last_seq: None,
        };
        let mut br = 0;
        // A control before any frame is not tracked.
        assert!(matches!(t.observe(false, 3, &mut br), Placement::Untracked));
        // The first frame anchors seq 0 at slot 0 (its counter 0).
        assert!(matches!(
            t.observe(true, 0, &mut br),
            Placement::Advanced { missing: 0, seq: 0 }
        ));
        // Controls at slots 1..=5 (counters 1,2,3,0,1), then the frame at slot 6 is lost and the
        // control at slot 7 (counter 3) arrives: advance 2 from slot 5 -> one frame missing.
        for c in [1, 2, 3, 0, 1] {
            assert!(matches!(
                t.observe(false, c, &mut br),
                Placement::Advanced { missing: 0, .. }
            ));
        }
        assert!(matches!(
            t.observe(false, 3, &mut br),
            Placement::Advanced { missing: 1, .. }
        ));
        // Everything up to slot 17 lost; the frame at slot 18 (counter 2) arrives: from slot 7
        // the advance must be = 3 (mod 4) and land on a multiple of 6 -> 11, slot 18, seq 3;
        // the frame at slot 12 was missing.
        assert!(matches!(
            t.observe(true, 2, &mut br),
            Placement::Advanced { missing: 1, seq: 3 }
        ));
        // The same frame again: a duplicate.
        assert!(matches!(t.observe(true, 2, &mut br), Placement::Duplicate));
        assert_eq!(br, 0);
    }

    /// The `health` record carries the docs/records.md field names.
    #[test]
    fn health_serializes_contract_fields() {
        let v = serde_json::to_value(Health::default()).expect("serialize");
        for k in [
            "frames",
            "crc_errors",
            "resyncs",
            "missing",
            "duplicates",
            "bytes_skipped",
        ] {
            assert_eq!(v[k], serde_json::json!(0), "{k}");
        }
    }
}
