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
//! After a good frame of a format with its own counter and no interleave, the frames that
//! follow it where it ended are checked four at a time without the search (their checksums
//! side by side) for as long as each is complete, good and one counter on: exactly what the
//! search would accept next, without its per-frame cost (`Decoder::run_locked`; BENCHMARKS.md,
//! issue 15 session 10). Anything else stops the run and the search takes over.
//!
//! # Counter rules
//!
//! Frames carry a counter modulo `M`. A frame whose counter equals the previous frame's is a
//! duplicate (dropped, `duplicates` + 1); an advance of `d` (mod `M`) means `d - 1` frames were
//! lost, reported as a [`FrameEvent::Gap`] before the next frame and added to `missing`. A
//! loss of `M` or more consecutive frames is invisible to the counter (it wraps).
//!
//! # Counter plausibility (formats without interleave)
//!
//! A checksum lets a few damaged messages through (a 16-bit CRC passes about one random
//! corruption in 65 536), and a link or a capture tool can repeat an earlier frame whole. Either
//! shows as a counter jump: a stale frame 500 frames back reads as an advance of `M - 500`, a
//! flipped high counter bit as thousands of lost frames. So a frame whose counter advanced by
//! anything but 0 or 1 is **held** until the next frame says whether the jump was real:
//!
//! - the next frame continues the held one (advance 1), or lies beyond it: the jump was real,
//!   the gap and the held frame are delivered as before (one frame later);
//! - the next frame lies between the last delivered frame and the held one (it continues the
//!   stream the held frame left): the held frame is dropped, counted in `stale_frames` when its
//!   counter stepped back (an advance over `M / 2`: an earlier frame repeated) and in
//!   `counter_rejects` otherwise (a damaged counter); no frame is counted lost for it.
//!
//! At the end of the input a held frame is delivered (nothing contradicts it). Clean data
//! (advances of 1) never takes this path, so it costs nothing there.
//!
//! With `[interleave]` (hg4930) the frame and `count` other messages share one counter that
//! advances once per message, the frame being every `count + 1`-th. The decoder then places
//! every message in a slot: the smallest advance consistent with the counter *and* with the
//! kind (frames only on slots that are multiples of `count + 1`). This combines the 2-bit
//! counter with the count of control messages between two frames. An advance of
//! `L = lcm(M, count + 1)` slots (12 for hg4930) leaves counter and kind as they were, so it
//! looks like a repeated message; a repeat is byte for byte the same message, so a message whose
//! counter and kind repeat but whose bytes differ is placed `L` slots on. The decoder so sees a
//! loss of up to `L - 1` consecutive messages (11 for hg4930; tested in `tests/frame_hg4930.rs`);
//! a loss of `L` or more is undercounted by a multiple of `L` slots. Messages before the first
//! frame are only checked and skipped.

use serde::{Deserialize, Serialize};

use super::block::{BlockEvent, FrameBlock, FrameSink};
use super::checksum::ChecksumAlgorithm;
use super::crc_msb::{self, MsbCrc};
use super::descriptor::{FrameDescriptor, MessageSpec};
use super::field::read_bits;
use super::plan::FramePlan;
use super::seq_tracker::{Placement, SeqTracker};
use super::{ChannelValue, FrameEvent};

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
    /// Channel values marked invalid by their status bit, or not finite or beyond
    /// `ranges::MAX_ABS_VALUE` (delivered as missing values).
    pub invalid_values: u64,
    /// Interleaved formats: counter values inconsistent with the message schedule (the
    /// decoder re-anchored and assumed no loss).
    pub counter_breaks: u64,
    /// Frames dropped because their counter stepped back and the next frame continued the
    /// stream before them: an earlier frame repeated (see "Counter plausibility").
    #[serde(default)]
    pub stale_frames: u64,
    /// Frames dropped because their counter jumped forward and the next frame did not confirm
    /// the jump: a damaged counter that passed the checksum.
    #[serde(default)]
    pub counter_rejects: u64,
}

/// Clean frames whose columns are filled together (see `Decoder::deferred`): 256 siu8 frames
/// are 11 KB, still in the first-level cache from the scan that just checked them, where
/// filling once per 256 KiB read fetched every frame again from the second level for each
/// column. A small gain: the column fill of the 3-hour siu8 replay 5% cheaper, its decode
/// thread 2-3% (BENCHMARKS.md, issue 15, session 9).
const FILL_BATCH: usize = 256;

/// What a [`Decoder`] holds between two pushes, for a checkpoint (`crate::pipeline::checkpoint`): the
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
    /// A frame held until the next one confirms its counter jump (its bytes).
    #[serde(default)]
    pub held: Option<Vec<u8>>,
    /// Interleaved formats: the bytes of the last tracked message.
    #[serde(default)]
    pub last_msg: Vec<u8>,
}

/// Streaming decoder for one descriptor. Feed it with [`Decoder::push`], take events with
/// [`Decoder::next_event`] (or [`Decoder::drain`]), call [`Decoder::finish`] at end of input.
pub struct Decoder {
    desc: FrameDescriptor,
    /// The frame message's reads, compiled once.
    plan: FramePlan,
    buf: Vec<u8>,
    /// First unconsumed byte of `buf`.
    pos: usize,
    /// Decoded events not yet taken, flat (no allocation per frame).
    out: FrameBlock,
    /// Events and frames of `out` already taken one at a time by [`Decoder::next_event`].
    taken: (usize, usize),
    health: Health,
    /// Bytes were skipped since the last good message.
    skipping: bool,
    tracker: SeqTracker,
    /// Running index for formats without a counter.
    next_index: u64,
    finished: bool,
    /// A frame whose counter jumped, held for the next frame to confirm (its bytes).
    held: Option<Vec<u8>>,
    /// Clean frames begun in `out` whose channels are still to be read: where each message
    /// starts in the bytes being decoded ([`FramePlan::fill_columns`], every [`FILL_BATCH`]
    /// frames, at the end of each [`Decoder::run`] and before any other frame's values).
    deferred: Vec<usize>,
    /// Bytes of a push joined to the pending ones ([`Decoder::push`]): twice the longest
    /// message and its sync offset, so the message they share is complete in the join.
    stitch: usize,
    /// How a run of clean frames is checked without the search, when the format allows it
    /// ([`Decoder::run_locked`]).
    lock: Option<Lock>,
}

/// What [`Decoder::run_locked`] needs to check the frames that follow a good frame where they
/// must be (a format with one frame counter and no interleave): the frame's length, its sync
/// and id where the search would find them, and its checksum.
struct Lock {
    len: usize,
    sync_at: usize,
    sync: Vec<u8>,
    /// The frame message (its checksum).
    spec: MessageSpec,
    /// The frame's id and where it sits (none: the format has one message and no id).
    id: Option<(usize, Vec<u8>)>,
    /// An MSB-first CRC, computed four frames side by side; other checksums one by one.
    crc: Option<&'static MsbCrc>,
}

impl Lock {
    /// The lock for `desc`, or None when a frame's place is not that simple: interleaved
    /// messages, no counter, or an id the search could match to another kind first.
    fn new(desc: &FrameDescriptor) -> Option<Lock> {
        let f = desc.frame();
        if desc.interleave.is_some() || f.counter.is_none() {
            return None;
        }
        let sync_end = desc.sync.offset + desc.sync.bytes.len();
        let c = &f.checksum;
        if desc.sync.bytes.is_empty() || sync_end > f.length || c.end >= f.length {
            return None;
        }
        let id = if desc.messages.len() == 1 && f.id.is_empty() {
            None
        } else {
            let at = desc.sync.id_offset;
            // The search reads `messages[0].id.len()` bytes and takes the first kind whose id
            // they are.
            let unique = desc.messages[..desc.frame_kind]
                .iter()
                .all(|m| m.id != f.id);
            if !unique || f.id.len() != desc.messages[0].id.len() || at + f.id.len() > f.length {
                return None;
            }
            Some((at, f.id.clone()))
        };
        let crc = match c.algorithm {
            ChecksumAlgorithm::Crc16Ibm3740 => Some(&crc_msb::CRC16_IBM_3740),
            ChecksumAlgorithm::Crc16Xmodem => Some(&crc_msb::CRC16_XMODEM),
            ChecksumAlgorithm::Crc32Mpeg2 => Some(&crc_msb::CRC32_MPEG2),
            _ => None,
        };
        Some(Lock {
            len: f.length,
            sync_at: desc.sync.offset,
            sync: desc.sync.bytes.clone(),
            spec: f.clone(),
            id,
            crc,
        })
    }
}

impl Decoder {
    pub fn new(desc: FrameDescriptor) -> Self {
        let cycle = desc.interleave.as_ref().map_or(1, |i| i.count + 1);
        let modulus = desc.frame().counter.as_ref().map_or(1, |c| c.modulus);
        let plan = FramePlan::new(&desc);
        let longest = desc.messages.iter().map(|m| m.length).max().unwrap_or(0);
        let stitch = 2 * (longest + desc.sync.offset + desc.sync.bytes.len());
        Decoder {
            out: FrameBlock::with_kinds(&plan.kinds, 0),
            plan,
            buf: Vec::new(),
            pos: 0,
            taken: (0, 0),
            health: Health::default(),
            skipping: false,
            tracker: SeqTracker {
                modulus,
                cycle,
                last: None,
                last_seq: None,
                last_msg: Vec::new(),
            },
            next_index: 0,
            finished: false,
            held: None,
            deferred: Vec::new(),
            stitch,
            lock: Lock::new(&desc),
            desc,
        }
    }

    pub fn descriptor(&self) -> &FrameDescriptor {
        &self.desc
    }

    /// The decoder's state, or `None` while decoded events are still waiting to be taken.
    pub fn state(&self) -> Option<DecoderState> {
        (self.taken.0 == self.out.len()).then(|| DecoderState {
            pending: self.buf[self.pos..].to_vec(),
            health: self.health.clone(),
            skipping: self.skipping,
            last: self.tracker.last,
            last_seq: self.tracker.last_seq,
            next_index: self.next_index,
            held: self.held.clone(),
            last_msg: self.tracker.last_msg.clone(),
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
        d.held = st.held.clone();
        d.tracker.last_msg = st.last_msg.clone();
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
    ///
    /// The bytes are decoded where they lie, not copied into the decoder: only the pending
    /// bytes (at most about one message) and the first [`Decoder::stitch`] bytes of `bytes`
    /// are joined in the buffer to finish the message they share; once the scan is past the
    /// pending bytes it goes on in `bytes` itself, and only what is left at the end is kept.
    /// The scan stops only where the bytes run out (a message or sync not complete), so going
    /// on from there with more bytes gives exactly what one pass over all of them gives.
    pub fn push(&mut self, bytes: &[u8]) {
        self.finished = false;
        self.health.bytes_in += bytes.len() as u64;
        let pending = self.buf.len() - self.pos;
        self.buf.drain(..self.pos);
        self.pos = 0;
        if pending > 0 {
            let k = bytes.len().min(self.stitch);
            self.buf.extend_from_slice(&bytes[..k]);
            self.run_buffered();
            if self.pos < pending {
                // Still inside the pending bytes (a short push): the rest joins them.
                self.buf.extend_from_slice(&bytes[k..]);
                self.run_buffered();
                return;
            }
            self.pos -= pending;
        }
        self.run(bytes);
        self.buf.clear();
        self.buf.extend_from_slice(&bytes[self.pos..]);
        self.pos = 0;
    }

    /// [`Decoder::run`] on the decoder's own buffer.
    fn run_buffered(&mut self) {
        let buf = std::mem::take(&mut self.buf);
        self.run(&buf);
        self.buf = buf;
    }

    /// End of input: a message cut off by the end is skipped, and whatever follows it is still
    /// searched. Afterwards `pending()` is 0.
    pub fn finish(&mut self) {
        self.finished = true;
        self.run_buffered();
        let rest = self.buf.len() - self.pos;
        self.skip(rest);
        // Nothing follows to contradict a held frame's jump.
        if let Some(msg) = self.held.take() {
            self.commit_frame(&msg);
        }
    }

    /// The next decoded event, if any.
    pub fn next_event(&mut self) -> Option<FrameEvent> {
        let (e, f) = self.taken;
        let ev = *self.out.event_list().get(e)?;
        let (values, n) = match ev {
            BlockEvent::Frame { .. } => {
                let mut v = Vec::with_capacity(self.out.width());
                self.out.frame_values(f, &mut v);
                (v, 1)
            }
            BlockEvent::Gap { .. } => (Vec::new(), 0),
        };
        let event = super::block::to_event(ev, values);
        self.taken = (e + 1, f + n);
        if self.taken.0 == self.out.len() {
            self.clear_events();
        }
        Some(event)
    }

    /// All events decoded so far.
    pub fn drain(&mut self) -> impl Iterator<Item = FrameEvent> + '_ {
        std::iter::from_fn(move || self.next_event())
    }

    /// The events decoded and not yet taken, with each frame's values (then call
    /// [`Decoder::clear_events`]).
    pub fn events(&self) -> impl Iterator<Item = (BlockEvent, Vec<Option<ChannelValue>>)> + '_ {
        let (e, f) = self.taken;
        let mut frame = f;
        self.out.event_list()[e..].iter().map(move |ev| match ev {
            BlockEvent::Frame { .. } => {
                let mut v = Vec::with_capacity(self.out.width());
                self.out.frame_values(frame, &mut v);
                frame += 1;
                (*ev, v)
            }
            BlockEvent::Gap { .. } => (*ev, Vec::new()),
        })
    }

    /// The events decoded so far as one block, when none has been taken one at a time.
    pub fn block(&self) -> Option<&FrameBlock> {
        (self.taken == (0, 0)).then_some(&self.out)
    }

    /// Hands every event decoded so far to `sink` at once (an empty [`FrameBlock`] takes the
    /// decoder's block whole and gives its own storage back).
    pub fn take_events(&mut self, sink: &mut impl FrameSink) {
        if self.taken == (0, 0) {
            sink.take_all(&mut self.out);
            if self.out.kinds() != self.plan.kinds.as_slice() {
                // The storage given back was made for other columns.
                self.out.reset_kinds(&self.plan.kinds);
            }
        } else {
            for (e, v) in self.events() {
                match e {
                    BlockEvent::Gap { missing } => sink.push_gap(missing),
                    frame => sink.push_frame(frame, &v),
                }
            }
            self.clear_events();
        }
    }

    /// Drops the events decoded so far (after [`Decoder::events`]).
    pub fn clear_events(&mut self) {
        self.out.clear();
        self.taken = (0, 0);
    }

    fn skip(&mut self, n: usize) {
        if n > 0 {
            self.pos += n;
            self.health.bytes_skipped += n as u64;
            self.skipping = true;
        }
    }

    /// Decodes `data` (the buffer, or a pushed read when nothing was pending) from `self.pos`
    /// as far as it allows, every begun frame's values filled in at the end.
    fn run(&mut self, data: &[u8]) {
        self.scan(data);
        self.fill_deferred(data);
    }

    /// The deferred frames' channels, read column by column from `data`.
    fn fill_deferred(&mut self, data: &[u8]) {
        if !self.deferred.is_empty() {
            self.plan.fill_columns(data, &self.deferred, &mut self.out);
            self.deferred.clear();
        }
    }

    fn scan(&mut self, data: &[u8]) {
        let sync_len = self.desc.sync.bytes.len();
        let sync_off = self.desc.sync.offset;
        loop {
            let from = self.pos + sync_off;
            let found = find(data, from, &self.desc.sync.bytes);
            let Some(q) = found else {
                // No sync: keep only the bytes that could still begin one.
                let keep_from = if self.finished {
                    data.len()
                } else {
                    (data.len() + 1).saturating_sub(sync_len + sync_off)
                };
                let n = keep_from.saturating_sub(self.pos);
                self.skip(n);
                return;
            };
            let start = q - sync_off;
            self.skip(start - self.pos);
            let avail = data.len() - start;
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
                let id = &data[start + id_off..start + id_off + id_len];
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
            let msg = &data[start..start + len];
            if !checksum_ok(&self.desc.messages[kind], msg) {
                self.health.crc_errors += 1;
                self.skip(1);
                continue;
            }
            self.accept(kind, data, start, len);
            self.pos = start + len;
            self.run_locked(data);
        }
    }

    /// After a good frame: the frames that follow it directly, four at a time, as long as each
    /// is where the last one ended, complete, with its sync, id and checksum, and its counter
    /// one on (clean data). Each such frame is exactly what the search would find next and
    /// goes through the same direct path of [`Decoder::accept_counted_frame`]; the saving is
    /// the search and the four checksums computed side by side (independent chains of table
    /// lookups). Stops, leaving `self.pos` at the first frame it did not take, at anything
    /// else (fewer than four frames left, a bad byte, a counter jump), where the search
    /// takes over.
    fn run_locked(&mut self, data: &[u8]) {
        if let Some(lock) = self.lock.take() {
            self.locked_frames(&lock, data);
            self.lock = Some(lock);
        }
    }

    /// [`Decoder::run_locked`] with the lock taken out of `self`.
    fn locked_frames(&mut self, lock: &Lock, data: &[u8]) {
        let len = lock.len;
        let spec = &lock.spec;
        let sync = lock.sync.as_slice();
        let c = &spec.checksum;
        let stored_ty = width_type(c.algorithm.width());
        while self.held.is_none() && !self.skipping && self.pos + 4 * len <= data.len() {
            let p = self.pos;
            let msgs: [&[u8]; 4] = [
                &data[p..p + len],
                &data[p + len..p + 2 * len],
                &data[p + 2 * len..p + 3 * len],
                &data[p + 3 * len..p + 4 * len],
            ];
            // Compared byte by byte: a call to memcmp costs more than these few bytes.
            let same = |a: &[u8], b: &[u8]| a.iter().zip(b).all(|(x, y)| x == y);
            let placed = msgs.iter().all(|m| {
                same(&m[lock.sync_at..lock.sync_at + sync.len()], sync)
                    && lock
                        .id
                        .as_ref()
                        .is_none_or(|(at, id)| same(&m[*at..*at + id.len()], id))
            });
            if !placed {
                return;
            }
            let mut good = [false; 4];
            match lock.crc {
                Some(crc) => {
                    let sums = crc.checksums4([
                        &msgs[0][c.start..=c.end],
                        &msgs[1][c.start..=c.end],
                        &msgs[2][c.start..=c.end],
                        &msgs[3][c.start..=c.end],
                    ]);
                    for k in 0..4 {
                        good[k] = read_bits(msgs[k], c.at, stored_ty, c.order)
                            == Some(u64::from(sums[k]));
                    }
                }
                None => {
                    for k in 0..4 {
                        good[k] = checksum_ok(spec, msgs[k]);
                    }
                }
            }
            for (k, msg) in msgs.iter().enumerate() {
                if !good[k] {
                    return;
                }
                let Some((slot, prev, true)) = self.tracker.last else {
                    return;
                };
                let m = self.tracker.modulus;
                let counter = self.plan.counter(msg);
                let p = if prev < m { prev } else { prev % m };
                if counter != if p + 1 == m { 0 } else { p + 1 } {
                    return;
                }
                self.health.bytes_accepted += len as u64;
                self.accept_next(data, self.pos, msg, slot + 1, counter);
                self.pos += len;
            }
        }
    }

    fn accept(&mut self, kind: usize, data: &[u8], start: usize, len: usize) {
        self.health.bytes_accepted += len as u64;
        if self.skipping {
            self.health.resyncs += 1;
            self.skipping = false;
        }
        let is_frame = kind == self.desc.frame_kind;
        if is_frame && self.tracker.cycle == 1 && self.desc.messages[kind].counter.is_some() {
            return self.accept_counted_frame(data, start, len);
        }
        let spec = &self.desc.messages[kind];
        let msg = &data[start..start + len];
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
                    .observe_msg(is_frame, counter, msg, &mut self.health.counter_breaks)
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
                    self.out.push_gap(missing);
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
        self.fill_deferred(data);
        self.plan
            .decode(msg, seq, &mut self.health.invalid_values, &mut self.out);
        self.health.frames += 1;
    }
}

impl Decoder {
    /// The frame at `buf[start..start + len]`, of a format with its own counter (no
    /// interleave): the counter rules with the plausibility check of the module documentation.
    fn accept_counted_frame(&mut self, data: &[u8], start: usize, len: usize) {
        let m = self.tracker.modulus;
        let msg = &data[start..start + len];
        let c = self.plan.counter(msg);
        if self.held.is_none() {
            if let Some((slot, prev, true)) = self.tracker.last {
                // Clean data: the counter advanced by one. What `commit` does for an advance
                // of 1 without interleave (no gap, the next slot), without its search.
                // `prev` is a counter already reduced modulo `m` (no division on this path).
                let p = if prev < m { prev } else { prev % m };
                let next = if p + 1 == m { 0 } else { p + 1 };
                if c == next {
                    return self.accept_next(data, start, msg, slot + 1, c);
                }
            }
        }
        // Every frame before this one has its values before any other path adds frames.
        self.fill_deferred(data);
        if let Some(held) = self.held.take() {
            let h = self.plan.counter(&held);
            let prev = self.tracker.last.map_or(h, |l| l.1);
            if c == prev % m {
                // A repeat of the last frame delivered: the held frame waits on.
                self.health.duplicates += 1;
                self.held = Some(held);
                return;
            }
            let adv = |from: u64, to: u64| (to + m - from % m) % m;
            let (jump, from_held, from_prev) = (adv(prev, h), adv(h, c), adv(prev, c));
            if from_held != 1 && from_prev < jump {
                // `c` continues the stream before the held frame: the jump was not real.
                if jump > m / 2 {
                    self.health.stale_frames += 1;
                } else {
                    self.health.counter_rejects += 1;
                }
            } else {
                self.commit_frame(&held);
            }
        }
        let jumped = self
            .tracker
            .last
            .is_some_and(|(_, prev, _)| !matches!((c + m - prev % m) % m, 0 | 1));
        if jumped {
            self.held = Some(msg.to_vec());
        } else {
            commit(
                &self.plan,
                &mut self.tracker,
                &mut self.health,
                &mut self.out,
                &mut self.next_index,
                msg,
            );
        }
    }

    /// The frame `msg` (at `data[start..]`) continues the last one: frame `seq`, counter `c`.
    #[inline(always)]
    fn accept_next(&mut self, data: &[u8], start: usize, msg: &[u8], seq: u64, c: u64) {
        self.tracker.last = Some((seq, c, true));
        self.tracker.last_seq = Some(seq);
        self.next_index = seq + 1;
        let bad = self.plan.begin(msg, seq, &mut self.out);
        if self.plan.deferrable(msg, bad, &self.out) {
            self.deferred.push(start);
            if self.deferred.len() >= FILL_BATCH {
                self.fill_deferred(data);
            }
        } else {
            self.fill_deferred(data);
            self.plan
                .read_channels(msg, bad, &mut self.health.invalid_values, &mut self.out);
        }
        self.health.frames += 1;
    }

    /// Delivers a held frame (see [`commit`]).
    fn commit_frame(&mut self, msg: &[u8]) {
        commit(
            &self.plan,
            &mut self.tracker,
            &mut self.health,
            &mut self.out,
            &mut self.next_index,
            msg,
        );
    }
}

/// Places a frame message by its counter and delivers it (with the gap before it), or counts it
/// as a duplicate.
fn commit(
    plan: &FramePlan,
    tracker: &mut SeqTracker,
    health: &mut Health,
    out: &mut FrameBlock,
    next_index: &mut u64,
    msg: &[u8],
) {
    let c = plan.counter(msg);
    match tracker.observe(true, c, &mut health.counter_breaks) {
        Placement::Duplicate => health.duplicates += 1,
        Placement::Advanced { missing, seq } => {
            if missing > 0 {
                health.missing += missing;
                out.push_gap(missing);
            }
            *next_index = seq + 1;
            plan.decode(msg, seq, &mut health.invalid_values, out);
            health.frames += 1;
        }
        Placement::Untracked => {}
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
        // Compared byte by byte: sync patterns are 1 to 4 bytes, shorter than a call to memcmp.
        if hay[i..i + pat.len()].iter().zip(pat).all(|(a, b)| a == b) {
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
            last_msg: Vec::new(),
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

    /// The run of clean frames taken without the search (`Decoder::run_locked`) gives what the
    /// search alone gives, event for event and counter for counter, on streams that leave the
    /// run in every way: bit flips (bad checksums), a byte lost (the next frame off its place),
    /// repeats of the last frame, a stale frame from far back, a damaged counter that passes
    /// the checksum (a held frame), lost frames, garbage, the end in the middle of a frame;
    /// for siu8 (CRC-16, no id) and kvh1750 (CRC-32, an id, built-in-test messages between
    /// frames), fed whole and in pieces of many sizes.
    #[test]
    fn locked_runs_match_the_search_alone() {
        use crate::frame::encoder::encode_message;
        for name in ["siu8", "kvh1750"] {
            let desc = FrameDescriptor::builtin(name).unwrap().unwrap();
            let n = desc.frame().channels.len();
            let counts = desc.frame().channels[0].is_count();
            let values = |seq: u64| -> Vec<ChannelValue> {
                (0..n as i64)
                    .map(|c| (seq as i64 * 7919 + c * 104_729) % 2001 - 1000)
                    .map(|v| {
                        if counts {
                            ChannelValue::Count(v)
                        } else {
                            ChannelValue::Real(v as f64 * 1e-7)
                        }
                    })
                    .collect()
            };
            let valid = desc.status_all_valid();
            let frames: Vec<Vec<u8>> = (0..3000u64)
                .map(|seq| crate::frame::encode(&desc, seq, &values(seq), valid).unwrap())
                .collect();
            let mut stream = Vec::new();
            let mut x = 12345u64;
            let mut rnd = |m: u64| {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                x % m
            };
            let mut i = 0;
            while i < frames.len() {
                let mut f = frames[i].clone();
                match rnd(60) {
                    0 => {
                        let b = rnd(f.len() as u64 * 8) as usize;
                        f[b / 8] ^= 1 << (b % 8);
                    }
                    1 => {
                        f.remove(rnd(f.len() as u64) as usize);
                    }
                    2 => stream.extend_from_slice(&frames[i.saturating_sub(1)]),
                    3 => stream.extend_from_slice(&frames[i.saturating_sub(500)]),
                    4 => i += 1 + rnd(5) as usize,
                    5 => {
                        for _ in 0..rnd(50) {
                            stream.push(rnd(256) as u8);
                        }
                    }
                    6 if desc.messages.len() > 1 => {
                        let other = (desc.frame_kind + 1) % desc.messages.len();
                        let m = encode_message(&desc, other, i as u64, &[], 0, None);
                        stream.extend(m.unwrap());
                    }
                    _ => {}
                }
                stream.extend_from_slice(&f);
                i += 1;
            }
            // A frame whose counter jumped yet passes its checksum: its counter rewritten and
            // the frame encoded again.
            let jumped = crate::frame::encode(&desc, 1000 + 60, &values(7), valid).unwrap();
            let at = frames[..1000].iter().map(Vec::len).sum::<usize>();
            stream.splice(at..at, jumped);
            stream.truncate(stream.len() - 5);
            for piece in [stream.len(), 7, 100, 333, 4096, 65_536] {
                let decode = |locked: bool| {
                    let mut d = Decoder::new(desc.clone());
                    if !locked {
                        d.lock = None;
                    }
                    let mut ev = Vec::new();
                    for p in stream.chunks(piece) {
                        d.push(p);
                        ev.extend(d.drain());
                    }
                    d.finish();
                    ev.extend(d.drain());
                    (ev, d.health().clone())
                };
                let (with, without) = (decode(true), decode(false));
                let h = &with.1;
                assert!(
                    h.crc_errors > 0 && h.missing > 0 && h.duplicates > 0,
                    "{h:?}"
                );
                assert!(h.stale_frames + h.counter_rejects > 0, "{h:?}");
                assert_eq!(with.1, without.1, "{name}, pieces of {piece}");
                assert_eq!(with.0, without.0, "{name}, pieces of {piece}");
            }
        }
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
