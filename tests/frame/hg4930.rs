//! hg4930's documented loss limit, shown: inertial messages (the frames) share a 2-bit counter
//! with five control messages each, so the counter and the kind repeat every
//! `L = lcm(4, 6) = 12` messages. The decoder tells a repeated message from a loss of 11 by its
//! bytes (a repeat is the same message; HG4930 control messages carry the 600 Hz control-rate
//! data, so two of them 12 slots apart differ), and so sees a loss of up to 11 consecutive
//! messages (`frame/decoder.rs`, module documentation).
//!
//! Every run of 1 to 12 consecutive messages is deleted at each of the 12 positions of a cycle,
//! from a stream of 40 frames with varying control payloads: 1 to 11 lost messages are counted
//! exactly (`missing` = the frames among them, no duplicate, every other frame delivered with
//! its seq); 12 lost messages (the real limit) are undercounted by the 2 frames among them. With
//! constant control payloads (as the encoder writes them), a loss of 11 between two control
//! messages cannot be told from a repeat: then only the losses bounded by a frame are seen.

use allanscope::frame::decoder::checksum_ok;
use allanscope::frame::field::ByteOrder;
use allanscope::frame::{encode, ChannelValue, Decoder, FrameDescriptor, FrameEvent};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

const FRAMES: u64 = 40;
/// Messages per frame: the inertial message and 5 controls.
const CYCLE: usize = 6;
const CONTROL_LEN: usize = 20;

/// The stream as a list of messages, slot by slot; control payloads (bytes 2..14) random when
/// `varying`.
fn messages(desc: &FrameDescriptor, varying: bool) -> Vec<Vec<u8>> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(4930);
    let control = &desc.messages[desc.interleave.as_ref().unwrap().message];
    let mut out = Vec::new();
    for seq in 0..FRAMES {
        let values: Vec<ChannelValue> = (0..6)
            .map(|_| ChannelValue::Count(rng.random_range(-100_000..100_000)))
            .collect();
        let bytes = encode(desc, seq, &values, 0).unwrap();
        let (frame, controls) = bytes.split_at(bytes.len() - 5 * CONTROL_LEN);
        out.push(frame.to_vec());
        for c in controls.chunks(CONTROL_LEN) {
            let mut c = c.to_vec();
            if varying {
                for b in &mut c[2..14] {
                    *b = rng.random();
                }
                let ck = &control.checksum;
                let sum = ck.algorithm.compute(&c[ck.start..=ck.end], ck.order);
                let w = ck.algorithm.width();
                for i in 0..w {
                    let shift = match ck.order {
                        ByteOrder::Big => 8 * (w - 1 - i),
                        ByteOrder::Little => 8 * i,
                    };
                    c[ck.at + i] = (sum >> shift) as u8;
                }
                assert!(checksum_ok(control, &c));
            }
            out.push(c);
        }
    }
    out
}

/// Deletes messages `start..start + len`, decodes: (missing, frames, duplicates, seqs right).
fn delete_and_decode(
    desc: &FrameDescriptor,
    msgs: &[Vec<u8>],
    start: usize,
    len: usize,
) -> (u64, u64, u64, bool) {
    let mut d = Decoder::new(desc.clone());
    for (i, m) in msgs.iter().enumerate() {
        if !(start..start + len).contains(&i) {
            d.push(m);
        }
    }
    d.finish();
    let mut seqs_right = true;
    let mut expect_seq = 0u64;
    for e in d.drain() {
        match e {
            FrameEvent::Gap { missing } => expect_seq += missing,
            FrameEvent::Frame(f) => {
                seqs_right &= f.seq == expect_seq;
                expect_seq += 1;
            }
        }
    }
    let h = d.health();
    (h.missing, h.frames, h.duplicates, seqs_right)
}

/// Frame slots (multiples of CYCLE) in `start..start + len`.
fn frames_in(start: usize, len: usize) -> u64 {
    (start..start + len).filter(|s| s % CYCLE == 0).count() as u64
}

#[test]
fn losses_of_up_to_11_messages_are_counted_exactly() {
    let desc = FrameDescriptor::load("hg4930").unwrap();
    let msgs = messages(&desc, true);
    assert_eq!(msgs.len(), FRAMES as usize * CYCLE);
    for len in 1..=11 {
        for start in 60..72 {
            let lost = frames_in(start, len);
            let got = delete_and_decode(&desc, &msgs, start, len);
            assert_eq!(
                got,
                (lost, FRAMES - lost, 0, true),
                "{len} messages lost from slot {start}"
            );
        }
    }
    // 12 (= lcm(4, 6)): counter and kind are where they were 12 slots before; the decoder takes
    // the smallest consistent advance and undercounts the 2 frames lost.
    for start in 60..72 {
        let (missing, frames, dups, _) = delete_and_decode(&desc, &msgs, start, 12);
        assert_eq!(frames_in(start, 12), 2);
        assert_eq!(
            (missing, frames, dups),
            (0, FRAMES - 2, 0),
            "from slot {start}"
        );
    }
}

#[test]
fn with_constant_control_payloads_only_frame_bounded_losses_of_11_are_seen() {
    let desc = FrameDescriptor::load("hg4930").unwrap();
    let msgs = messages(&desc, false);
    let mut exact = Vec::new();
    for start in 60..72 {
        let lost = frames_in(start, 11);
        let (missing, frames, dups, _) = delete_and_decode(&desc, &msgs, start, 11);
        if (missing, frames, dups) == (lost, FRAMES - lost, 0) {
            exact.push(start);
        }
    }
    // The message before the loss and the one after it (12 slots on, the same kind) are both
    // frames only when the loss starts right after a frame: slots 61 (frames at 60 and 72) and
    // 67 (66 and 78).
    assert_eq!(exact, vec![61, 67]);
    // Losses of 10 or fewer are exact whatever the payloads.
    for len in 1..=10 {
        for start in 60..72 {
            let lost = frames_in(start, len);
            assert_eq!(
                delete_and_decode(&desc, &msgs, start, len),
                (lost, FRAMES - lost, 0, true)
            );
        }
    }
}
