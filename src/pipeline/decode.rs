//! The decode stage: [`SourceEvent`]s -> decoded frames (a [`crate::frame::FrameBlock`], or
//! [`crate::frame::FrameEvent`]s), on its own thread (plain sync code).
//!
//! It owns the [`Decoder`] and adds what only a live stream has:
//!
//! - UDP datagrams go through the [`Reorder`] window first (frames back in counter order,
//!   duplicate datagrams dropped).
//! - **Outages.** When a serial port comes back, or a live stream has been silent for longer
//!   than half the counter's period (`modulus / 2` frame periods: 131 s for siu8, 64 ms for
//!   kvh1750), the counter alone cannot say how many frames were lost: it may have wrapped. The
//!   stage then finishes the decoder (a frame cut by the outage is skipped and counted), starts a
//!   fresh one, and places the first frame after the outage by **both** the counter and the wall
//!   time since the last frame before it: of the advances that agree with the counter
//!   (`r + j M`, `r` the counter's advance modulo `M`, `j >= 0`), the one nearest to
//!   `silence_s x rate_hz` is taken ([`outage_advance`]). `advance - 1` frames are recorded as a
//!   gap (in `missing`, and in the health record's `outage_missing`); an advance of 0 is a
//!   repeated frame (a duplicate). This is exact as long as the wall-clock estimate is within
//!   `M / 2` frame periods of the truth, i.e. always for siu8 (262 s) and to +-64 ms for
//!   kvh1750. Formats without a counter (or whose counter is shared with other messages, as
//!   hg4930's) use the time alone.
//! - **Backlogs are not silences.** A host that did not read for a while (a loaded machine, a
//!   stalled thread) finds the frames of that while waiting in the port's buffer and gets them in
//!   one read. The silence is measured to the *first* frame of a read, whose latest possible
//!   emission is the read time less `(n - 1)` frame periods for the `n` whole frames the read can
//!   hold ([`DecodeStage::backlog_s`]). So a stall of the reader is no outage, and an outage
//!   followed by a burst from the adapter's buffer is not sized too long by that burst.
//! - **A backlog comes in pieces.** The terminal layer hands over at most its line buffer per
//!   read (4095 bytes on Linux: 113 kvh1750 frames), so a stall longer than that leaves the
//!   rest for the reads right behind. A read that would end a silence is therefore held with the
//!   reads that follow it ([`Held`]) while they bring frames faster than real time (each one
//!   moves the latest possible emission of the held reads' first frame back by more than half a
//!   frame period); the silence is the shortest any of them bounds. Once it is below the limit the
//!   reads go on as one stretch; once the reads no longer shorten it (the stream has caught up,
//!   or went quiet, reopened or ended), it is the outage's silence.

use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use bytes::Bytes;

use super::reorder::{Reorder, ReorderStats};
use crate::frame::{BlockEvent, Decoder, DecoderState, FrameDescriptor, FrameSink, Health};
use crate::source::SourceEvent;

/// Frames lost in an outage: the advance of the frame counter from the last frame before the
/// outage (`prev`) to the first after it (`next`), both modulo `modulus`, made consistent with
/// the silence of `silence_s` seconds at `rate_hz`. Returns the advance (frames lost + 1; 0 for
/// a repeated frame). Without counters, the advance is the silence in frame periods (at least 1).
pub fn outage_advance(
    prev: Option<u64>,
    next: Option<u64>,
    modulus: u64,
    silence_s: f64,
    rate_hz: f64,
) -> u64 {
    let est = (silence_s * rate_hz).max(0.0);
    match (prev, next) {
        (Some(p), Some(n)) if modulus > 1 => {
            let m = modulus;
            let r = (n % m + m - p % m) % m;
            let j = ((est - r as f64) / m as f64).round().max(0.0) as u64;
            r + j * m
        }
        _ => (est.round() as u64).max(1),
    }
}

/// Outage counters (added to the `health` record).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct OutageStats {
    /// Outages: reconnections of the port, or silences longer than half the counter period.
    pub outages: u64,
    /// Frames lost in outages (included in `missing`).
    pub missing: u64,
    /// First frames after an outage that repeated the last one (included in `duplicates`).
    pub duplicates: u64,
}

/// What a [`DecodeStage`] holds, for a checkpoint (`super::checkpoint`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DecodeStageState {
    pub decoder: DecoderState,
    /// Health of decoders replaced after outages.
    pub retired: Health,
    pub outage: OutageStats,
    /// UDP reorder window's counters.
    pub reorder: Option<ReorderStats>,
    /// Counter of the last frame (`Some(None)`: a frame without a usable counter), and when it
    /// arrived, in seconds since the Unix epoch (live sources place the first frame after a
    /// resume by both).
    pub last_counter: Option<Option<u64>>,
    pub last_frame_unix_s: Option<f64>,
}

/// Seconds since the Unix epoch of an `Instant` in the past.
fn unix_s(at: Instant) -> f64 {
    let now = SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64());
    now - at.elapsed().as_secs_f64()
}

struct Pending {
    prev_counter: Option<u64>,
    since: Instant,
    /// The silence to the first frame after the outage, when held reads have bounded it.
    silence_s: Option<f64>,
}

/// Reads held while they may still be the pieces of one backlog (module docs).
struct Held {
    events: Vec<SourceEvent>,
    /// The last frame before the silence (or the outage's `Pending::since`).
    since: Instant,
    /// An outage already counted (a reconnection): the held reads only place its first frame.
    counted: bool,
    /// Bytes of the held reads.
    bytes: usize,
    /// The shortest silence any held read bounds: its arrival less the frames held up to it.
    silence_s: f64,
}

/// Bytes -> frame events for one run.
pub struct DecodeStage {
    desc: FrameDescriptor,
    decoder: Decoder,
    /// Health of decoders replaced after outages.
    retired: Health,
    reorder: Option<Reorder>,
    /// Counter modulus of the frame (1: no usable counter).
    modulus: u64,
    silence_limit_s: f64,
    /// Bytes of the longest message kind (a read of `b` bytes holds at most `b / max_len` whole
    /// frames of it, so the backlog is never overestimated).
    max_len: usize,
    /// Seconds before the current read that its first frame was due at the latest.
    backlog_s: f64,
    last_frame: Option<(Option<u64>, Instant)>,
    pending: Option<Pending>,
    held: Option<Held>,
    pieces: Vec<Bytes>,
    /// Live source: silences are measured in wall time.
    live: bool,
    pub outage: OutageStats,
}

impl DecodeStage {
    /// A stage for `desc`; `live` for serial and UDP sources (silences count as outages).
    pub fn new(desc: FrameDescriptor, live: bool) -> DecodeStage {
        let counter_ok = desc.interleave.is_none();
        let modulus = desc
            .frame()
            .counter
            .as_ref()
            .filter(|_| counter_ok)
            .map_or(1, |c| c.modulus);
        let silence_limit_s = if modulus > 1 {
            modulus as f64 / 2.0 / desc.rate_hz
        } else {
            f64::INFINITY
        };
        let max_len = desc
            .messages
            .iter()
            .map(|m| m.length)
            .max()
            .unwrap_or(1)
            .max(1);
        DecodeStage {
            max_len,
            decoder: Decoder::new(desc.clone()),
            reorder: Reorder::new(&desc),
            desc,
            retired: Health::default(),
            modulus,
            silence_limit_s,
            backlog_s: 0.0,
            last_frame: None,
            pending: None,
            held: None,
            pieces: Vec::new(),
            live,
            outage: OutageStats::default(),
        }
    }

    /// Takes one source event; decoded events are appended to `out`. Returns the good frames
    /// added.
    pub fn push(&mut self, ev: SourceEvent, out: &mut impl FrameSink) -> u64 {
        match &ev {
            SourceEvent::Data { bytes, at } | SourceEvent::Datagram { bytes, at } => {
                let (len, at) = (bytes.len(), *at);
                if let Some(h) = &mut self.held {
                    h.bytes += len;
                    let held_s =
                        (h.bytes / self.max_len).saturating_sub(1) as f64 / self.desc.rate_hz;
                    let silence =
                        (at.saturating_duration_since(h.since).as_secs_f64() - held_s).max(0.0);
                    if silence < h.silence_s - 0.5 / self.desc.rate_hz {
                        // Still the backlog: frames faster than real time.
                        h.silence_s = silence;
                        h.events.push(ev);
                        if !h.counted && silence <= self.silence_limit_s {
                            return self.release(out);
                        }
                        return 0;
                    }
                    h.bytes -= len;
                    let n = self.release(out);
                    return n + self.push(ev, out);
                }
                if let Some(since) = self.opens_silence(len, at) {
                    self.backlog_s = self.backlog_s(len);
                    self.held = Some(Held {
                        events: vec![ev],
                        since,
                        counted: self.pending.is_some(),
                        bytes: len,
                        silence_s: self.silence_to(at, since),
                    });
                    return 0;
                }
                self.read(ev, out)
            }
            SourceEvent::Idle => {
                let n = self.release(out);
                n + self.read(ev, out)
            }
            SourceEvent::Reconnected { .. } => {
                let n = self.release(out);
                n + self.restart(out)
            }
        }
    }

    /// When a read of `len` bytes at `at` may be the first after an outage (a reconnection, or
    /// a silence longer than the limit before it): the instant the silence is measured from.
    fn opens_silence(&self, len: usize, at: Instant) -> Option<Instant> {
        if !self.live {
            return None;
        }
        if let Some(p) = &self.pending {
            return Some(p.since);
        }
        let (_, t) = self.last_frame?;
        let backlog = self.backlog_s(len);
        let silence = (at.saturating_duration_since(t).as_secs_f64() - backlog).max(0.0);
        (silence > self.silence_limit_s).then_some(t)
    }

    /// The held reads go on: as one stretch with the frames before them when their silence is
    /// below the limit, else after an outage whose first frame is placed by their silence.
    fn release(&mut self, out: &mut impl FrameSink) -> u64 {
        let Some(h) = self.held.take() else {
            return 0;
        };
        let mut n = 0;
        if h.counted || h.silence_s > self.silence_limit_s {
            if !h.counted {
                n += self.restart(out);
            }
            if let Some(p) = &mut self.pending {
                p.silence_s = Some(h.silence_s);
            }
        }
        for ev in h.events {
            n += self.read(ev, out);
        }
        if let Some(p) = &mut self.pending {
            // No whole frame in the held reads: the first frame is timed by its own read.
            p.silence_s = None;
        }
        n
    }

    /// One source event, after any outage before it has been decided.
    fn read(&mut self, ev: SourceEvent, out: &mut impl FrameSink) -> u64 {
        match ev {
            SourceEvent::Data { bytes, at } => {
                self.backlog_s = self.backlog_s(bytes.len());
                self.decoder.push(&bytes);
                self.collect(at, out)
            }
            SourceEvent::Datagram { bytes, at } => {
                self.backlog_s = self.backlog_s(bytes.len());
                match &mut self.reorder {
                    Some(r) => {
                        r.push(&bytes, &mut self.pieces);
                        for p in self.pieces.drain(..) {
                            self.decoder.push(&p);
                        }
                    }
                    None => self.decoder.push(&bytes),
                }
                self.collect(at, out)
            }
            SourceEvent::Idle => {
                self.backlog_s = 0.0;
                if let Some(r) = &mut self.reorder {
                    r.flush(&mut self.pieces);
                    for p in self.pieces.drain(..) {
                        self.decoder.push(&p);
                    }
                }
                self.collect(Instant::now(), out)
            }
            SourceEvent::Reconnected { .. } => self.restart(out),
        }
    }

    /// Seconds by which the first frame of a read of `len` bytes came before the read at least:
    /// `(n - 1) / rate_hz` for the `n` whole frames it can hold (0 for a read of one frame or
    /// less).
    fn backlog_s(&self, len: usize) -> f64 {
        (len / self.max_len).saturating_sub(1) as f64 / self.desc.rate_hz
    }

    /// Seconds from `since` to the first frame of the read that arrived at `at`.
    fn silence_to(&self, at: Instant, since: Instant) -> f64 {
        (at.saturating_duration_since(since).as_secs_f64() - self.backlog_s).max(0.0)
    }

    /// End of input: frames held for reordering and a frame cut off by the end.
    pub fn finish(&mut self, out: &mut impl FrameSink) -> u64 {
        let mut n = self.release(out);
        if let Some(r) = &mut self.reorder {
            r.flush(&mut self.pieces);
            for p in self.pieces.drain(..) {
                self.decoder.push(&p);
            }
        }
        self.decoder.finish();
        n += self.collect(Instant::now(), out);
        n
    }

    /// Ends the current stretch of the stream; the next frame is placed by counter and time.
    fn restart(&mut self, out: &mut impl FrameSink) -> u64 {
        if let Some(r) = &mut self.reorder {
            r.reset(&mut self.pieces);
            for p in self.pieces.drain(..) {
                self.decoder.push(&p);
            }
        }
        self.decoder.finish();
        // Frames released here arrived before the outage: they keep the time of the last one.
        let at = self.last_frame.map_or_else(Instant::now, |(_, t)| t);
        let n = self.collect(at, out);
        add_health(&mut self.retired, self.decoder.health());
        self.decoder = Decoder::new(self.desc.clone());
        if let Some((prev_counter, since)) = self.last_frame {
            self.outage.outages += 1;
            self.pending = Some(Pending {
                prev_counter,
                since,
                silence_s: None,
            });
        }
        n
    }

    fn collect(&mut self, at: Instant, out: &mut impl FrameSink) -> u64 {
        let mut frames = 0;
        let m = self.modulus;
        let rate = self.desc.rate_hz;
        if let (None, Some(block)) = (&self.pending, self.decoder.block()) {
            // No outage to place: the decoder's block goes on whole (one copy, not per frame).
            let last = block.event_list().iter().rev().find_map(|e| match e {
                BlockEvent::Frame { seq, .. } => Some(*seq),
                BlockEvent::Gap { .. } => None,
            });
            if let Some(seq) = last {
                self.last_frame = Some(((m > 1).then_some(seq % m), at));
            }
            let frames = block.frames() as u64;
            self.decoder.take_events(out);
            return frames;
        }
        for (ev, values) in self.decoder.events() {
            match ev {
                BlockEvent::Frame { seq, .. } => {
                    let counter = (m > 1).then_some(seq % m);
                    if let Some(p) = self.pending.take() {
                        let silence = p.silence_s.unwrap_or_else(|| self.silence_to(at, p.since));
                        let adv = outage_advance(p.prev_counter, counter, m, silence, rate);
                        if adv == 0 {
                            self.outage.duplicates += 1;
                            self.last_frame = Some((counter, at));
                            continue;
                        }
                        if adv > 1 {
                            self.outage.missing += adv - 1;
                            out.push_gap(adv - 1);
                        }
                    }
                    self.last_frame = Some((counter, at));
                    frames += 1;
                    out.push_frame(ev, &values);
                }
                BlockEvent::Gap { missing } => out.push_gap(missing),
            }
        }
        self.decoder.clear_events();
        frames
    }

    /// Decoder health over the whole run: every decoder's counters, the outages, the reorder
    /// window's duplicates.
    pub fn health(&self) -> Health {
        let mut h = self.retired.clone();
        add_health(&mut h, self.decoder.health());
        h.missing += self.outage.missing;
        h.frames -= self.outage.duplicates.min(h.frames);
        h.duplicates += self.outage.duplicates;
        if let Some(r) = &self.reorder {
            h.duplicates += r.stats.duplicates;
        }
        h
    }

    /// The stage's state between two source events, or `None` while decoded events wait (or
    /// reads are held).
    pub fn state(&self) -> Option<DecodeStageState> {
        if self.held.is_some() {
            return None;
        }
        Some(DecodeStageState {
            decoder: self.decoder.state()?,
            retired: self.retired.clone(),
            outage: self.outage,
            reorder: self.reorder_stats(),
            last_counter: self.last_frame.map(|(c, _)| c),
            last_frame_unix_s: self.last_frame.map(|(_, t)| unix_s(t)),
        })
    }

    /// A stage continuing a replay from `st`: the decoder exactly as it was, so the bytes that
    /// followed give the same events and counters.
    pub fn restore_replay(desc: FrameDescriptor, st: &DecodeStageState) -> DecodeStage {
        let mut stage = DecodeStage::new(desc.clone(), false);
        stage.decoder = Decoder::restore(desc, &st.decoder);
        stage.retired = st.retired.clone();
        stage.outage = st.outage;
        stage
    }

    /// A stage continuing a live stream from `st` after the program stopped: the counters go
    /// on, and the stream restarts as after an outage, the first frame placed by its counter and
    /// the wall time since the last frame saved (so the lost frames are a gap).
    pub fn restore_live(desc: FrameDescriptor, live: bool, st: &DecodeStageState) -> DecodeStage {
        let mut stage = DecodeStage::new(desc, live);
        stage.retired = st.retired.clone();
        add_health(&mut stage.retired, &st.decoder.health);
        stage.outage = st.outage;
        if let (Some(r), Some(saved)) = (&mut stage.reorder, st.reorder) {
            r.stats = saved;
        }
        if let Some(prev_counter) = st.last_counter {
            let now = SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0.0, |d| d.as_secs_f64());
            let ago = (now - st.last_frame_unix_s.unwrap_or(now)).max(0.0);
            let since = Instant::now()
                .checked_sub(Duration::from_secs_f64(ago))
                .unwrap_or_else(Instant::now);
            stage.outage.outages += 1;
            stage.pending = Some(Pending {
                prev_counter,
                since,
                silence_s: None,
            });
        }
        stage
    }

    pub fn reorder_stats(&self) -> Option<ReorderStats> {
        self.reorder.as_ref().map(|r| r.stats)
    }
}

fn add_health(a: &mut Health, b: &Health) {
    a.frames += b.frames;
    a.crc_errors += b.crc_errors;
    a.resyncs += b.resyncs;
    a.missing += b.missing;
    a.duplicates += b.duplicates;
    a.bytes_skipped += b.bytes_skipped;
    a.bytes_in += b.bytes_in;
    a.bytes_accepted += b.bytes_accepted;
    a.other_messages += b.other_messages;
    a.invalid_values += b.invalid_values;
    a.counter_breaks += b.counter_breaks;
    a.stale_frames += b.stale_frames;
    a.counter_rejects += b.counter_rejects;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hand-worked cases of the outage rule.
    #[test]
    fn outage_rule() {
        // siu8 (M = 65536, 250 Hz): counter 100 -> 200 after 0.4 s (100 periods): advance 100,
        // 99 frames lost; the counter decides.
        assert_eq!(outage_advance(Some(100), Some(200), 65536, 0.4, 250.0), 100);
        // Same counters after 262.544 s (65636 periods): the counter has wrapped once.
        assert_eq!(
            outage_advance(Some(100), Some(200), 65536, 262.544, 250.0),
            65636
        );
        // kvh1750 (M = 128, 1000 Hz): 5 -> 10 after 0.7 s (700 periods): 5 + 128 j nearest
        // 700 is 645 (j = 5; 773 is farther).
        assert_eq!(outage_advance(Some(5), Some(10), 128, 0.7, 1000.0), 645);
        // The same frame again right away: advance 0, a duplicate.
        assert_eq!(outage_advance(Some(7), Some(7), 128, 0.01, 1000.0), 0);
        // No counter: the time alone, at least one period.
        assert_eq!(outage_advance(None, None, 1, 0.0104, 100.0), 1);
        assert_eq!(outage_advance(None, None, 1, 2.0, 100.0), 200);
    }

    /// kvh1750 frames `from..to` of the shipped one-minute capture (1000 Hz, counter mod 128).
    fn kvh(from: usize, to: usize) -> Bytes {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/fixtures/captures/kvh1750_stand_1min_seed1.kvh1750"
        );
        let all = std::fs::read(path).expect("kvh1750 fixture");
        Bytes::copy_from_slice(&all[from * 36..to * 36])
    }

    /// Feeds `reads` (first frame, end frame, arrival in ms after t0) to a live kvh1750 stage:
    /// (good frames, frames recorded as lost, outages).
    fn live_run(reads: &[(usize, usize, u64)]) -> (u64, u64, u64) {
        let reads: Vec<(usize, usize, f64)> =
            reads.iter().map(|&(a, b, ms)| (a, b, ms as f64)).collect();
        live_run_f(&reads)
    }

    /// Reads of 10 frames, each arriving when its last frame is due (1 ms per frame).
    fn steady(from: usize, to: usize) -> Vec<(usize, usize, u64)> {
        (from..to)
            .step_by(10)
            .map(|k| (k, k + 10, k as u64 + 9))
            .collect()
    }

    /// A reader that stalls for 200 ms (four times the 64 ms that half of kvh1750's counter
    /// period allows) finds 200 frames waiting and reads them at once: nothing was lost, and
    /// it is no outage. Before the backlog was counted, the silence of 200 ms made the counter's
    /// advance of 1 into 1 + 128 j with j = 2: 256 phantom frames lost.
    #[test]
    fn a_stalled_reader_is_not_an_outage() {
        let mut reads = steady(0, 100);
        // Frames 100..300 were due by 299 ms; the reader's last read was at 99 ms.
        reads.push((100, 300, 299));
        reads.extend(steady(300, 400));
        assert_eq!(live_run(&reads), (400, 0, 0));
    }

    /// A real outage (frames 100..600 never arrive) followed by the adapter's buffered burst
    /// of 200 frames in one read at 799 ms: the silence ends at the burst's first frame (600,
    /// due at 600 ms), so 500 frames are lost; timed by the read instead (700 ms), the
    /// counter's advance 117 + 128 j would be placed at j = 5 (757).
    #[test]
    fn an_outage_is_sized_to_the_first_frame_of_a_burst() {
        let mut reads = steady(0, 100);
        reads.push((600, 800, 799));
        reads.extend(steady(800, 900));
        assert_eq!(live_run(&reads), (400, 500, 1));
    }

    /// Frames `from..to` handed over as the terminal layer does after a stall: reads of at most
    /// 113 frames (its 4095-byte line buffer), the first at `ms`, each a quarter of a
    /// millisecond after the one before.
    fn pieces(from: usize, to: usize, ms: f64) -> Vec<(usize, usize, f64)> {
        (from..to)
            .step_by(113)
            .enumerate()
            .map(|(i, k)| (k, (k + 113).min(to), ms + 0.25 * i as f64))
            .collect()
    }

    /// [`live_run`] with arrivals in fractional ms.
    fn live_run_f(reads: &[(usize, usize, f64)]) -> (u64, u64, u64) {
        let desc = FrameDescriptor::load("kvh1750").expect("kvh1750");
        assert_eq!(desc.frame_len(), 36);
        let mut stage = DecodeStage::new(desc, true);
        let mut out: Vec<crate::frame::FrameEvent> = Vec::new();
        let t0 = Instant::now();
        let mut frames = 0;
        for &(from, to, ms) in reads {
            let ev = SourceEvent::Data {
                bytes: kvh(from, to),
                at: t0 + Duration::from_secs_f64(ms / 1000.0),
            };
            frames += stage.push(ev, &mut out);
        }
        frames += stage.finish(&mut out);
        let lost = out
            .iter()
            .map(|e| match e {
                crate::frame::FrameEvent::Gap { missing } => *missing,
                crate::frame::FrameEvent::Frame(_) => 0,
            })
            .sum();
        (frames, lost, stage.outage.outages)
    }

    fn steady_f(from: usize, to: usize) -> Vec<(usize, usize, f64)> {
        steady(from, to)
            .into_iter()
            .map(|(a, b, ms)| (a, b, ms as f64))
            .collect()
    }

    /// A reader that stalls for 450 ms finds 450 frames waiting, more than one read holds: the
    /// terminal hands them over in four reads of up to 113 frames. Nothing was lost. Seen in the
    /// pipeline tests under load (reads of 4095 bytes 0.5 ms apart after a 450 ms stall): timed
    /// by its own read, the first piece's frame 100 ended a silence of 450 - 112 = 338 ms, an
    /// outage of 1 + 128 j frames (j = 3: 384 phantom frames lost).
    #[test]
    fn a_backlog_in_pieces_is_not_an_outage() {
        let mut reads = steady_f(0, 100);
        reads.extend(pieces(100, 550, 549.0));
        reads.extend(steady_f(550, 650));
        assert_eq!(live_run_f(&reads), (650, 0, 0));
    }

    /// A real outage (frames 100..600 never arrive) followed by a buffered burst of 400 frames
    /// handed over in four pieces at 999 ms: the silence ends at the burst's first frame (600,
    /// due at 600 ms), so 500 frames are lost. Timed by the first piece alone (999 - 99 - 112 =
    /// 788 ms), the counter's advance 117 + 128 j would be placed at j = 5 (757).
    #[test]
    fn an_outage_is_sized_to_the_first_frame_of_a_burst_in_pieces() {
        let mut reads = steady_f(0, 100);
        reads.extend(pieces(600, 1000, 999.0));
        reads.extend(steady_f(1000, 1100));
        assert_eq!(live_run_f(&reads), (600, 500, 1));
    }

    /// A read that may be the first piece of a backlog is held until the next read, or until
    /// the source reports it quiet: then it is decided with what it bounds (here an outage of
    /// 450 - 112 = 338 ms: 1 + 128 * 3 frames) and its frames go on.
    #[test]
    fn a_held_read_goes_on_when_the_source_is_quiet() {
        let desc = FrameDescriptor::load("kvh1750").expect("kvh1750");
        let mut stage = DecodeStage::new(desc, true);
        let mut out: Vec<crate::frame::FrameEvent> = Vec::new();
        let t0 = Instant::now();
        let at = |ms: u64| t0 + Duration::from_millis(ms);
        for (from, to, ms) in steady(0, 100) {
            stage.push(
                SourceEvent::Data {
                    bytes: kvh(from, to),
                    at: at(ms),
                },
                &mut out,
            );
        }
        let held = SourceEvent::Data {
            bytes: kvh(100, 213),
            at: at(549),
        };
        assert_eq!(stage.push(held, &mut out), 0);
        assert!(
            stage.state().is_none(),
            "no checkpoint while reads are held"
        );
        assert_eq!(stage.push(SourceEvent::Idle, &mut out), 113);
        assert_eq!(stage.outage.outages, 1);
        assert_eq!(stage.outage.missing, 384);
        assert!(stage.state().is_some());
    }
}
