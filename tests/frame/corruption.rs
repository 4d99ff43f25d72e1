//! The decoder against a damaged stream whose truth is known exactly.
//!
//! A seeded generator writes a few thousand frames (through the encoder) and damages the
//! stream as it goes: bit flips at 1e-4 per bit, truncated frames, dropped frames, duplicated
//! frames, garbage bursts, channels marked invalid, and (kvh1750) built-in-test messages. It
//! keeps a list of segments, each intact or not, and from it derives every expected count:
//!
//! - frames: intact original frames; duplicates: intact copies; other_messages: intact BIT
//!   messages; bytes_skipped: all bytes of non-intact segments;
//! - crc_errors: damaged segments that still start with the frame header (sync + id) -- the
//!   only places the decoder can try a checksum, because the generator redraws any segment that
//!   would put a sync pattern anywhere else (so the truth does not depend on chance syncs);
//! - resyncs: runs of non-intact segments followed by an intact message;
//! - missing and the gap events: from the seqs of the intact frames.
//!
//! The decoded events must equal the truth event for event (every intact frame recovered with
//! its exact values, no damaged one accepted), and the health counters must equal the truth.
//!
//! kvh1750's counter is 7 bits (modulus 128): a loss of 128 or more consecutive frames would be
//! invisible, so the generator never drops more than 8 in a row (the longest run here is far
//! below 128).

use allanscope::frame::decoder::checksum_ok;
use allanscope::frame::descriptor::{FrameDescriptor, MessageSpec};
use allanscope::frame::encoder::encode_message;
use allanscope::frame::{encode, ChannelValue, Decoder, FrameEvent, Health};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Per-bit flip probability (the brief's 1e-4).
const BIT_FLIP_RATE: f64 = 1e-4;
const P_DROP: f64 = 0.01;
const P_TRUNCATE: f64 = 0.005;
const P_DUPLICATE: f64 = 0.005;
const P_GARBAGE: f64 = 0.005;
const P_INVALID_CHANNEL: f64 = 0.01;
const P_BIT_MESSAGE: f64 = 0.003;
const MAX_GARBAGE_BYTES: usize = 80;
/// Longest run of dropped frames the generator allows (kvh1750 sees runs < 128 only).
const MAX_DROP_RUN: u32 = 8;

#[derive(Debug, Clone)]
enum Seg {
    /// An intact frame: seq and the expected values.
    Frame {
        seq: u64,
        values: Vec<Option<ChannelValue>>,
        len: usize,
    },
    /// An intact copy of the previous frame.
    Duplicate { len: usize },
    /// An intact message without increments.
    Other { len: usize },
    /// Damaged bytes: a flipped or truncated frame (candidate: it starts with the frame header)
    /// or garbage.
    Damaged {
        start: usize,
        len: usize,
        candidate: bool,
        garbage: bool,
    },
}

impl Seg {
    fn intact(&self) -> bool {
        !matches!(self, Seg::Damaged { .. })
    }
    fn len(&self) -> usize {
        match self {
            Seg::Frame { len, .. } | Seg::Duplicate { len } | Seg::Other { len } => *len,
            Seg::Damaged { len, .. } => *len,
        }
    }
}

struct Generator<'a> {
    desc: &'a FrameDescriptor,
    rng: Xoshiro256PlusPlus,
    stream: Vec<u8>,
    segs: Vec<Seg>,
    header: Vec<u8>,
}

impl Generator<'_> {
    /// Appends `bytes` unless that would create a sync pattern anywhere but at the start of a
    /// message segment (or a header of another kind at that start); true when appended.
    fn try_append(&mut self, bytes: &[u8], seg: Seg) -> bool {
        // Garbage may not start with a sync; messages (intact or damaged) may.
        let message_seg = !matches!(
            seg,
            Seg::Damaged {
                candidate: false,
                garbage: true,
                ..
            }
        );
        let sync = &self.desc.sync.bytes;
        let base = self.stream.len();
        let lo = base.saturating_sub(sync.len() - 1);
        let mut joined = self.stream[lo..].to_vec();
        joined.extend_from_slice(bytes);
        if joined.len() >= sync.len() {
            for p in 0..=joined.len() - sync.len() {
                if joined[p..p + sync.len()] == sync[..] {
                    let at_start = lo + p == base;
                    if !(at_start && message_seg) {
                        return false;
                    }
                }
            }
        }
        // A damaged start must not turn into another kind's header.
        if let Seg::Damaged { .. } = seg {
            if bytes.starts_with(sync) && !bytes.starts_with(&self.header) {
                let io = self.desc.sync.id_offset;
                let other_kind =
                    self.desc.messages.iter().any(|m| {
                        !m.id.is_empty() && bytes.get(io..io + m.id.len()) == Some(&m.id[..])
                    });
                if other_kind {
                    return false;
                }
            }
        }
        self.stream.extend_from_slice(bytes);
        self.segs.push(seg);
        true
    }

    fn random_values(&mut self) -> (Vec<ChannelValue>, Vec<Option<ChannelValue>>, u64) {
        let f = self.desc.frame();
        let mut status = self.desc.status_all_valid();
        let mut sent = Vec::new();
        let mut truth = Vec::new();
        for c in &f.channels {
            let (v, t) = if c.is_count() {
                let n = i64::from(self.rng.random::<i32>());
                (ChannelValue::Count(n), ChannelValue::Count(n))
            } else {
                // A random f32 raw value; sent as its physical increment, kept raw as truth.
                let r = self.rng.random_range(-2.0f32..2.0) * 1e-3;
                let phys = f64::from(r) * c.scale * self.desc.kind_factor(c.kind);
                (ChannelValue::Real(phys), ChannelValue::Real(f64::from(r)))
            };
            sent.push(v);
            truth.push(Some(t));
        }
        if self.rng.random_bool(P_INVALID_CHANNEL) {
            let k = self.rng.random_range(0..f.channels.len());
            if let (Some(bit), Some(st)) = (f.channels[k].status_bit, &f.status) {
                use allanscope::frame::descriptor::BitMeaning;
                match st.bit_set_means {
                    BitMeaning::Fault => status |= 1 << bit,
                    BitMeaning::Valid => status &= !(1 << bit),
                }
                truth[k] = None;
            }
        }
        (sent, truth, status)
    }

    fn flip_bits(&mut self, bytes: &mut [u8]) -> usize {
        let mut flips = 0;
        for b in bytes.iter_mut() {
            for bit in 0..8 {
                if self.rng.random_bool(BIT_FLIP_RATE) {
                    *b ^= 1 << bit;
                    flips += 1;
                }
            }
        }
        flips
    }

    fn garbage(&mut self) {
        loop {
            let n = self.rng.random_range(1..=MAX_GARBAGE_BYTES);
            let g: Vec<u8> = (0..n).map(|_| self.rng.random()).collect();
            let start = self.stream.len();
            if self.try_append(
                &g,
                Seg::Damaged {
                    start,
                    len: n,
                    candidate: false,
                    garbage: true,
                },
            ) {
                return;
            }
        }
    }

    /// One original frame with its fate; returns true when it was dropped.
    fn frame(&mut self, seq: u64, must_be_intact: bool, may_drop: bool) -> bool {
        if !must_be_intact && may_drop && self.rng.random_bool(P_DROP) {
            return true;
        }
        let truncate = !must_be_intact && self.rng.random_bool(P_TRUNCATE);
        loop {
            let (sent, truth, status) = self.random_values();
            let mut bytes = encode(self.desc, seq, &sent, status).expect("encode");
            let len = bytes.len();
            let start = self.stream.len();
            let damaged = if truncate {
                let keep = self.rng.random_range(1..len);
                bytes.truncate(keep);
                true
            } else if must_be_intact {
                false
            } else {
                self.flip_bits(&mut bytes) > 0
            };
            let seg = if damaged {
                Seg::Damaged {
                    start,
                    len: bytes.len(),
                    candidate: bytes.starts_with(&self.header),
                    garbage: false,
                }
            } else {
                Seg::Frame {
                    seq,
                    values: truth,
                    len,
                }
            };
            if !self.try_append(&bytes, seg) {
                continue;
            }
            if !damaged && !must_be_intact && self.rng.random_bool(P_DUPLICATE) {
                // The duplicate repeats the same bytes; they cannot create a new sync.
                let copy = self.stream[start..start + len].to_vec();
                assert!(self.try_append(&copy, Seg::Duplicate { len }));
            }
            return false;
        }
    }

    fn other_message(&mut self, kind: usize) {
        let m: &MessageSpec = &self.desc.messages[kind];
        let mut bytes = encode_message(self.desc, kind, 0, &[], 0, None).expect("encode");
        // Give the built-in-test data bytes the "all pass" value of the KVH manual (0x7F).
        let s = self.desc.sync.id_offset + m.id.len();
        for b in bytes.iter_mut().take(m.checksum.at).skip(s) {
            *b = 0x7F;
        }
        let bytes = encode_fix_checksum(m, bytes);
        let len = bytes.len();
        assert!(self.try_append(&bytes, Seg::Other { len }));
    }
}

fn encode_fix_checksum(m: &MessageSpec, mut bytes: Vec<u8>) -> Vec<u8> {
    let c = &m.checksum;
    let sum = c.algorithm.compute(&bytes[c.start..=c.end], c.order);
    let w = c.algorithm.width();
    for i in 0..w {
        let shift = match c.order {
            allanscope::frame::field::ByteOrder::Big => 8 * (w - 1 - i),
            allanscope::frame::field::ByteOrder::Little => 8 * i,
        };
        bytes[c.at + i] = (sum >> shift) as u8;
    }
    assert!(checksum_ok(m, &bytes));
    bytes
}

struct Truth {
    events: Vec<TruthEvent>,
    health: Health,
    longest_drop_run: u64,
}

#[derive(Debug)]
enum TruthEvent {
    Gap(u64),
    Frame(u64, Vec<Option<ChannelValue>>),
}

/// Builds a damaged stream of `n` frames from `first_seq`, and its truth.
fn build(desc: &FrameDescriptor, seed: u64, first_seq: u64, n: u64) -> (Vec<u8>, Truth) {
    let io = desc.sync.id_offset;
    let mut header = desc.sync.bytes.clone();
    let f = desc.frame();
    if !f.id.is_empty() {
        header.resize(io, 0);
        header.extend(&f.id);
    }
    let mut g = Generator {
        desc,
        rng: Xoshiro256PlusPlus::seed_from_u64(seed),
        stream: Vec::new(),
        segs: Vec::new(),
        header,
    };
    let other_kinds: Vec<usize> = (0..desc.messages.len())
        .filter(|&k| k != desc.frame_kind)
        .collect();
    g.garbage(); // the stream starts mid-way through something
    let mut drop_run = 0;
    for i in 0..n {
        let seq = first_seq + i;
        // The first and last few frames are intact so every loss is bracketed by good frames.
        let edge = i < 3 || i + 5 >= n;
        let dropped = g.frame(seq, edge, drop_run < MAX_DROP_RUN);
        drop_run = if dropped { drop_run + 1 } else { 0 };
        if !edge && g.rng.random_bool(P_GARBAGE) {
            g.garbage();
        }
        if !edge && !other_kinds.is_empty() && g.rng.random_bool(P_BIT_MESSAGE) {
            let k = other_kinds[g.rng.random_range(0..other_kinds.len())];
            g.other_message(k);
        }
    }

    // Every damaged candidate's window must fail its checksum (else no decoder could tell).
    for s in &g.segs {
        if let Seg::Damaged {
            start,
            candidate: true,
            ..
        } = s
        {
            let w = &g.stream[*start..*start + f.length];
            assert!(
                !checksum_ok(f, w),
                "seed {seed}: a damaged window passes; pick another seed"
            );
        }
    }

    // The truth, from the segment list.
    let mut h = Health::default();
    let mut events = Vec::new();
    let mut prev_seq: Option<u64> = None;
    let mut in_damage = false;
    let mut longest_drop_run = 0;
    for s in &g.segs {
        if s.intact() {
            h.bytes_accepted += s.len() as u64;
            if in_damage {
                h.resyncs += 1;
                in_damage = false;
            }
        } else {
            h.bytes_skipped += s.len() as u64;
            in_damage = true;
        }
        match s {
            Seg::Frame { seq, values, .. } => {
                if let Some(p) = prev_seq {
                    let missing = seq - p - 1;
                    if missing > 0 {
                        events.push(TruthEvent::Gap(missing));
                        h.missing += missing;
                        longest_drop_run = longest_drop_run.max(missing);
                    }
                }
                prev_seq = Some(*seq);
                h.frames += 1;
                h.invalid_values += values.iter().filter(|v| v.is_none()).count() as u64;
                events.push(TruthEvent::Frame(*seq, values.clone()));
            }
            Seg::Duplicate { .. } => h.duplicates += 1,
            Seg::Other { .. } => h.other_messages += 1,
            Seg::Damaged { candidate, .. } => h.crc_errors += u64::from(*candidate),
        }
    }
    h.bytes_in = g.stream.len() as u64;
    (
        g.stream,
        Truth {
            events,
            health: h,
            longest_drop_run,
        },
    )
}

/// Decodes at seeded random splits of up to `max_piece` bytes (small pieces keep the decoder
/// joining pending bytes to the next push; large ones let it decode most bytes where they lie).
fn decode_split(
    desc: &FrameDescriptor,
    stream: &[u8],
    seed: u64,
    max_piece: usize,
) -> (Vec<FrameEvent>, Health) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut d = Decoder::new(desc.clone());
    let mut ev = Vec::new();
    let mut i = 0;
    while i < stream.len() {
        let k = rng.random_range(0..=max_piece).min(stream.len() - i);
        d.push(&stream[i..i + k]);
        ev.extend(d.drain());
        i += k;
    }
    d.finish();
    ev.extend(d.drain());
    (ev, d.health().clone())
}

/// Compares decoded events with the truth: integer counts exactly; float fields by their raw
/// f32 (the decoded physical value divided by scale and kind factor rounds back to the sent f32).
fn assert_events(desc: &FrameDescriptor, got: &[FrameEvent], want: &[TruthEvent]) {
    assert_eq!(got.len(), want.len(), "number of events");
    let chans = &desc.frame().channels;
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        match (g, w) {
            (FrameEvent::Gap { missing }, TruthEvent::Gap(m)) => {
                assert_eq!(missing, m, "event {k}")
            }
            (FrameEvent::Frame(f), TruthEvent::Frame(seq, vals)) => {
                assert_eq!(f.seq, *seq, "event {k}");
                for (i, (gv, wv)) in f.values.iter().zip(vals).enumerate() {
                    match (gv, wv) {
                        (None, None) => {}
                        (Some(ChannelValue::Count(a)), Some(ChannelValue::Count(b))) => {
                            assert_eq!(a, b, "event {k} channel {i}")
                        }
                        (Some(ChannelValue::Real(x)), Some(ChannelValue::Real(raw))) => {
                            let c = &chans[i];
                            let back = (x / (c.scale * desc.kind_factor(c.kind))) as f32;
                            assert_eq!(back, *raw as f32, "event {k} channel {i}");
                        }
                        other => panic!("event {k} channel {i}: {other:?}"),
                    }
                }
            }
            other => panic!("event {k}: {other:?}"),
        }
    }
}

fn run_case(name: &str, seed: u64, first_seq: u64, n: u64) {
    let desc = FrameDescriptor::load(name).unwrap_or_else(|e| panic!("{e}"));
    let (stream, truth) = build(&desc, seed, first_seq, n);
    let t = &truth.health;
    println!(
        "{name}: {} bytes, frames {}, crc_errors {}, resyncs {}, missing {}, duplicates {}, \
         bytes_skipped {}, other_messages {}, invalid_values {}, longest loss {}",
        stream.len(),
        t.frames,
        t.crc_errors,
        t.resyncs,
        t.missing,
        t.duplicates,
        t.bytes_skipped,
        t.other_messages,
        t.invalid_values,
        truth.longest_drop_run
    );
    // The damage must actually be there for the test to mean something.
    assert!(t.crc_errors >= 20 && t.missing >= 20 && t.duplicates >= 5 && t.resyncs >= 20);
    assert!(truth.longest_drop_run < desc.frame().counter.as_ref().expect("counter").modulus);

    for (split_seed, max_piece) in [(1u64, 300), (2, 300), (3, 300), (4, 5000), (5, usize::MAX)] {
        let (ev, h) = decode_split(&desc, &stream, split_seed, max_piece);
        assert_events(&desc, &ev, &truth.events);
        let gaps: u64 = ev
            .iter()
            .map(|e| match e {
                FrameEvent::Gap { missing } => *missing,
                FrameEvent::Frame(_) => 0,
            })
            .sum();
        assert_eq!(gaps, t.missing, "gap events sum to the truth");
        assert_eq!(
            h, *t,
            "{name}: health equals the truth (split seed {split_seed})"
        );
    }
}

#[test]
fn siu8_damaged_stream() {
    // 3000 frames from seq 64000: the u16 counter wraps at 65536 on the way.
    run_case("siu8", 20240611, 64_000, 3000);
}

#[test]
fn kvh1750_damaged_stream() {
    // 3000 frames: the 7-bit counter wraps 23 times; BIT messages interleaved.
    run_case("kvh1750", 77, 0, 3000);
}

#[test]
fn kvh1750b_damaged_stream() {
    run_case("kvh1750b", 5, 10, 3000);
}
