//! UDP datagrams -> frames in counter order, duplicates dropped, before the decoder sees them.
//!
//! Datagrams carry whole frames, so each frame can be checked (sync, id, checksum) and its
//! counter read on arrival. A frame is released to the decoder as soon as it is the next one
//! expected; otherwise it is held, for at most [`REORDER_DATAGRAMS`] further datagrams (or until
//! the source goes idle), then the held frames are released in counter order and the ones still
//! missing are the decoder's gap. A frame whose counter was already released is a duplicate
//! (dropped, counted) or, if its slot was given up as lost, a late frame (dropped, counted: its
//! place in the stream is already a gap).
//!
//! Bytes of a datagram that are not a good frame (damage, other message kinds) are passed on
//! in arrival order for the decoder to count. Formats without a counter, or with interleaved
//! messages sharing the counter (hg4930), are passed through untouched.

use std::collections::{BTreeMap, BTreeSet};

use bytes::Bytes;

use crate::frame::decoder::checksum_ok;
use crate::frame::descriptor::FrameDescriptor;
use crate::frame::field::read_bits;

/// How many datagrams a frame may arrive late and still be put back in its place: a few, as
/// the issue asks; loopback and a switched LAN reorder over one or two.
pub const REORDER_DATAGRAMS: u64 = 8;

/// How far back released counters are remembered, to tell duplicates from late frames.
const REMEMBER_FRAMES: u64 = 4096;

/// Counters of the reorder stage (added to the `health` record).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ReorderStats {
    /// Frames that waited in the window for an earlier one (arrived out of order, or after a
    /// loss), then released in order.
    pub reordered: u64,
    /// Frames dropped because their counter was already delivered.
    pub duplicates: u64,
    /// Frames dropped because they arrived after their slot was given up.
    pub late: u64,
}

/// What becomes of a good frame ([`Reorder::place`]).
enum Place {
    /// It goes on now, in arrival order.
    Now,
    /// It waits in the window, at this unwrapped counter.
    Hold(u64),
    /// A duplicate or a late frame (counted).
    Drop,
}

/// Adds `next` (bytes of `dg` going on in order) to the stretch `run`, which goes out first
/// when the two do not touch.
fn extend_run(
    dg: &Bytes,
    run: &mut std::ops::Range<usize>,
    next: std::ops::Range<usize>,
    out: &mut Vec<Bytes>,
) {
    if run.start == run.end || run.end != next.start {
        flush_run(dg, run, out);
        run.start = next.start;
    }
    run.end = next.end;
}

/// The stretch `run` of `dg` goes out (one slice); it is then empty.
fn flush_run(dg: &Bytes, run: &mut std::ops::Range<usize>, out: &mut Vec<Bytes>) {
    if run.start < run.end {
        out.push(dg.slice(run.clone()));
    }
    *run = 0..0;
}

struct Held {
    bytes: Bytes,
    datagram: u64,
}

/// The reorder window of one UDP stream.
pub struct Reorder {
    frame_len: usize,
    modulus: u64,
    desc: FrameDescriptor,
    /// Unwrapped counter of the next frame to release.
    next: Option<u64>,
    held: BTreeMap<u64, Held>,
    /// Counters skipped (released past) recently: a frame arriving with one of them is late.
    skipped: BTreeSet<u64>,
    datagrams: u64,
    pub stats: ReorderStats,
}

impl Reorder {
    /// A reorder window for `desc`, or None when the format cannot be reordered by frame.
    pub fn new(desc: &FrameDescriptor) -> Option<Reorder> {
        let f = desc.frame();
        let c = f.counter.as_ref()?;
        if desc.interleave.is_some() || c.modulus < 4 {
            return None;
        }
        Some(Reorder {
            frame_len: f.length,
            modulus: c.modulus,
            desc: desc.clone(),
            next: None,
            held: BTreeMap::new(),
            skipped: BTreeSet::new(),
            datagrams: 0,
            stats: ReorderStats::default(),
        })
    }

    /// The counter of a good frame at the start of `b`, if it is one.
    fn frame_counter(&self, b: &[u8]) -> Option<u64> {
        let d = &self.desc;
        let f = d.frame();
        if b.len() < self.frame_len {
            return None;
        }
        let s = &d.sync;
        if b.get(s.offset..s.offset + s.bytes.len())? != s.bytes.as_slice() {
            return None;
        }
        if !f.id.is_empty() && b.get(s.id_offset..s.id_offset + f.id.len())? != f.id.as_slice() {
            return None;
        }
        let msg = &b[..self.frame_len];
        if !checksum_ok(f, msg) {
            return None;
        }
        let c = f.counter.as_ref()?;
        let raw = read_bits(msg, c.offset, c.ty, c.order)?;
        Some((raw >> c.shift) % c.modulus)
    }

    /// Takes one datagram; bytes ready for the decoder are appended to `out` (in order).
    ///
    /// Bytes of the datagram that go on in arrival order (frames that are the next expected,
    /// and bytes that are no good frame) go out as one slice per unbroken stretch, not one per
    /// frame: a datagram of in-order frames is one piece, decoded in one go (the 100-unit live
    /// benchmark, BENCHMARKS.md, spent more on ten decoder calls per datagram than on its frames).
    pub fn push(&mut self, dg: &Bytes, out: &mut Vec<Bytes>) {
        self.datagrams += 1;
        let mut pos = 0;
        let mut other_from = 0;
        // The stretch of `dg` going on in order, not yet in `out`.
        let mut run = 0..0;
        while pos < dg.len() {
            let Some(c) = self.frame_counter(&dg[pos..]) else {
                pos += 1;
                continue;
            };
            if other_from < pos {
                extend_run(dg, &mut run, other_from..pos, out);
            }
            let end = pos + self.frame_len;
            match self.place(c) {
                Place::Now => extend_run(dg, &mut run, pos..end, out),
                Place::Drop => {}
                Place::Hold(s) => {
                    // Whatever went on before this frame goes out before anything it releases.
                    flush_run(dg, &mut run, out);
                    self.held.insert(
                        s,
                        Held {
                            bytes: dg.slice(pos..end),
                            datagram: self.datagrams,
                        },
                    );
                    self.release_ready(out);
                }
            }
            pos = end;
            other_from = pos;
        }
        if other_from < dg.len() {
            extend_run(dg, &mut run, other_from..dg.len(), out);
        }
        flush_run(dg, &mut run, out);
        // Frames held longer than the window are released, in order.
        while let Some((_, h)) = self.held.first_key_value() {
            if h.datagram + REORDER_DATAGRAMS >= self.datagrams {
                break;
            }
            self.release_first(out);
        }
    }

    /// The source went idle or ended: release everything held, in order.
    pub fn flush(&mut self, out: &mut Vec<Bytes>) {
        while !self.held.is_empty() {
            self.release_first(out);
        }
    }

    /// After an outage: releases everything held and forgets the counter (it may have wrapped
    /// any number of times), so the next frame anchors the window afresh.
    pub fn reset(&mut self, out: &mut Vec<Bytes>) {
        self.flush(out);
        self.next = None;
        self.skipped.clear();
    }

    /// Where a good frame with counter `c` goes: on now (the next expected, nothing held; the
    /// window moves past it), into the window at its unwrapped counter, or nowhere (a duplicate
    /// or a late frame, counted).
    fn place(&mut self, c: u64) -> Place {
        let m = self.modulus;
        let Some(next) = self.next else {
            self.next = Some(c + 1);
            return Place::Now;
        };
        // Signed distance from the next expected counter, in [-M/2, M/2).
        let d = (c + m - next % m) % m;
        let s = if d >= m / 2 {
            (next + d).checked_sub(m)
        } else {
            Some(next + d)
        };
        let Some(s) = s else {
            self.stats.late += 1;
            return Place::Drop;
        };
        if s < next {
            if self.skipped.remove(&s) {
                self.stats.late += 1;
            } else {
                self.stats.duplicates += 1;
            }
            return Place::Drop;
        }
        if s == next && self.held.is_empty() {
            self.next = Some(next + 1);
            return Place::Now;
        }
        if self.held.contains_key(&s) {
            self.stats.duplicates += 1;
            return Place::Drop;
        }
        Place::Hold(s)
    }

    /// Releases held frames while they are the next expected.
    fn release_ready(&mut self, out: &mut Vec<Bytes>) {
        while let Some(next) = self.next {
            match self.held.first_key_value() {
                Some((&s, _)) if s == next => {
                    if let Some(h) = self.held.remove(&s) {
                        self.stats.reordered += 1;
                        out.push(h.bytes);
                    }
                    self.next = Some(s + 1);
                }
                _ => break,
            }
        }
    }

    /// Gives up on the frames before the first held one and releases it (and what follows it).
    fn release_first(&mut self, out: &mut Vec<Bytes>) {
        let Some((s, h)) = self.held.pop_first() else {
            return;
        };
        let next = self.next.unwrap_or(s);
        for lost in next.max(s.saturating_sub(REMEMBER_FRAMES))..s {
            self.skipped.insert(lost);
        }
        let keep_from = s.saturating_sub(REMEMBER_FRAMES);
        while self.skipped.first().is_some_and(|&x| x < keep_from) {
            self.skipped.pop_first();
        }
        out.push(h.bytes);
        self.next = Some(s + 1);
        self.release_ready(out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::{encode, ChannelValue};

    fn frame(desc: &FrameDescriptor, seq: u64) -> Bytes {
        let v = [ChannelValue::Count(seq as i64); 8];
        Bytes::from(encode(desc, seq, &v, 0).expect("encode"))
    }

    fn counters(desc: &FrameDescriptor, out: &[Bytes]) -> Vec<u64> {
        let r = Reorder::new(desc).expect("siu8 has a counter");
        out.iter()
            .map(|b| r.frame_counter(b).expect("a good frame"))
            .collect()
    }

    /// Hand-made arrival orders: swaps within the window are undone, repeats dropped, a frame
    /// arriving after its slot was given up is dropped as late.
    #[test]
    fn window_orders_dedups_and_gives_up() {
        let desc = FrameDescriptor::load("siu8").expect("siu8");
        let mut r = Reorder::new(&desc).expect("reorder");
        let mut out = Vec::new();
        // One frame per datagram: 0, 2, 1 (swap), 1 again (repeat), 3.
        for s in [0, 2, 1, 1, 3] {
            r.push(&frame(&desc, s), &mut out);
        }
        assert_eq!(counters(&desc, &out), [0, 1, 2, 3]);
        assert_eq!(r.stats.duplicates, 1);
        // Frame 4 is lost: 5.. are held while the window lasts (a frame may wait through
        // REORDER_DATAGRAMS further datagrams), then 4 is given up and 5.. go out in order;
        // when 4 finally arrives it is late.
        out.clear();
        // Frame 5 arrives with datagram 6 and waits through datagrams 7..=14.
        let last = 6 + REORDER_DATAGRAMS;
        for s in 5..last {
            r.push(&frame(&desc, s), &mut out);
        }
        assert!(out.is_empty(), "held while 4 may still come");
        r.push(&frame(&desc, last), &mut out);
        let want: Vec<u64> = (5..=last).collect();
        assert_eq!(counters(&desc, &out), want);
        r.push(&frame(&desc, 4), &mut out);
        assert_eq!(r.stats.late, 1);
        r.flush(&mut out);
        assert_eq!(out.len(), want.len());
        assert_eq!(r.stats.duplicates, 1);
    }

    /// Datagrams of several frames: the in-order stretches of a datagram go out as one piece
    /// each (damage bytes included, in arrival order), and frames put back in order go out
    /// one by one; the bytes that reach the decoder are those of the frames in counter order.
    #[test]
    fn in_order_stretches_go_out_whole() {
        let desc = FrameDescriptor::load("siu8").expect("siu8");
        let len = desc.frame_len();
        let frames = |r: std::ops::Range<u64>| -> Vec<u8> {
            r.flat_map(|s| frame(&desc, s).to_vec()).collect()
        };
        let garbage = vec![0x13u8; 5];
        let mut r = Reorder::new(&desc).expect("reorder");
        let mut out = Vec::new();
        // Frames 0..5 in one datagram: one piece.
        r.push(&Bytes::from(frames(0..5)), &mut out);
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].len(), 5 * len);
        // 7, 8, damage, 9: the frames wait for 5 and 6; the damage goes on at once.
        let b: Vec<u8> = [frames(7..9), garbage.clone(), frames(9..10)].concat();
        r.push(&Bytes::from(b), &mut out);
        assert_eq!(out.len(), 2);
        assert_eq!(out[1].as_ref(), garbage.as_slice());
        // 5, 6, 10, 11: 5 and 6 go on one by one with the held 7..=9 after them; 10 and 11
        // are one piece.
        r.push(
            &Bytes::from(
                frames(5..7)
                    .into_iter()
                    .chain(frames(10..12))
                    .collect::<Vec<u8>>(),
            ),
            &mut out,
        );
        let lens: Vec<usize> = out.iter().map(|b| b.len()).collect();
        assert_eq!(lens, [5 * len, 5, len, len, len, len, len, 2 * len]);
        let got: Vec<u8> = out.iter().flat_map(|b| b.to_vec()).collect();
        let want: Vec<u8> = [frames(0..5), garbage, frames(5..12)].concat();
        assert_eq!(got, want);
        // 5..=9 waited in the window (5 and 6 behind the held 7, 8, 9).
        assert_eq!(r.stats.reordered, 5);
        assert_eq!((r.stats.duplicates, r.stats.late), (0, 0));
    }
}
