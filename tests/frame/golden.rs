//! Golden frames for the shipped descriptors, and split invariance of the decoder.
//!
//! - kvh1750: the sample frame printed in the KVH ICD (SPEC-frames.md), decoded to the printed
//!   digits, and re-encoded byte for byte.
//! - siu8 and hg4930: frames assembled here byte by byte from the layout tables of
//!   SPEC-frames.md (and, for hg4930, the HG4930 manual's tables 3 and 7), with checksums
//!   computed by the small independent implementations below, not by the crate.
//! - The same stream fed whole, one byte at a time and at seeded random splits gives the same
//!   events and the same health.

use allanscope::frame::descriptor::G0_M_S2;
use allanscope::frame::{
    encode, encode_frame, ChannelValue, Decoder, FrameDescriptor, FrameEvent, FrameInput, Health,
};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

fn builtin(name: &str) -> FrameDescriptor {
    FrameDescriptor::load(name).unwrap_or_else(|e| panic!("{e}"))
}

fn decode_all(desc: &FrameDescriptor, bytes: &[u8]) -> (Vec<FrameEvent>, Health) {
    let mut d = Decoder::new(desc.clone());
    d.push(bytes);
    d.finish();
    let ev = d.drain().collect();
    (ev, d.health().clone())
}

fn frames(ev: &[FrameEvent]) -> Vec<&allanscope::frame::DecodedFrame> {
    ev.iter()
        .filter_map(|e| match e {
            FrameEvent::Frame(f) => Some(f),
            FrameEvent::Gap { .. } => None,
        })
        .collect()
}

/// Asserts `actual` equals a printed decimal to its printed digits: within half a unit of the
/// last printed digit.
fn assert_printed(actual: f64, printed: &str) {
    let (mant, exp) = match printed.split_once(['e', 'E']) {
        Some((m, e)) => (m, e.parse::<i32>().expect("exponent")),
        None => (printed, 0),
    };
    let decimals = mant.split_once('.').map_or(0, |(_, d)| d.len()) as i32;
    let half_unit = 0.5 * 10f64.powi(exp - decimals);
    let value: f64 = printed.parse().expect("number");
    assert!(
        (actual - value).abs() <= half_unit,
        "{actual} is not {printed} to the printed digits (+- {half_unit:e})"
    );
}

/// CRC-16/IBM-3740 bit by bit (poly 0x1021, init 0xFFFF, no reflection, xorout 0), written
/// from its definition for these tests.
fn crc16_ibm_3740(data: &[u8]) -> u16 {
    let mut crc: u16 = 0xFFFF;
    for &b in data {
        crc ^= u16::from(b) << 8;
        for _ in 0..8 {
            crc = if crc & 0x8000 != 0 {
                (crc << 1) ^ 0x1021
            } else {
                crc << 1
            };
        }
    }
    crc
}

/// The 16-bit little-endian word sum without carry of the HG4930 manual (tables 3 and 7).
fn hg_word_sum(data: &[u8]) -> u16 {
    data.chunks(2)
        .map(|w| u16::from_le_bytes([w[0], w[1]]))
        .fold(0u16, u16::wrapping_add)
}

/// The reference CRC implementation reproduces the catalogue check value 0x29B1 of
/// CRC-16/IBM-3740 over "123456789" (reveng catalogue).
#[test]
fn reference_crc_matches_catalogue() {
    assert_eq!(crc16_ibm_3740(b"123456789"), 0x29B1);
}

/// The KVH ICD sample frame (SPEC-frames.md): CRC 0x4BFA34D8, seq 61, 40 degC, status 0x77,
/// delta-angles (2.0196e-5, 5.1599e-5, -1.3111e-5) rad, accelerations (-1.00191, -0.0034950,
/// 0.0021090) g.
#[test]
fn kvh1750_icd_sample_frame() {
    let hex = "FE 81 FF 55 37 A9 6A 6E 38 58 6C 1F B7 5B F8 62 BF 80 3E 78 BB 65 0D 28 \
               3B 0A 37 AC 77 3D 00 28 4B FA 34 D8";
    let bytes: Vec<u8> = hex
        .split_whitespace()
        .map(|h| u8::from_str_radix(h, 16).expect("hex"))
        .collect();
    assert_eq!(bytes.len(), 36);
    let desc = builtin("kvh1750");
    assert_eq!(desc.tau0_s(), 1e-3);
    // The stored CRC, and the CRC the crate computes over bytes 0-31.
    let stored = u32::from_be_bytes([bytes[32], bytes[33], bytes[34], bytes[35]]);
    assert_eq!(stored, 0x4BFA_34D8);
    let ck = &desc.frame().checksum;
    assert_eq!(
        ck.algorithm.compute(&bytes[ck.start..=ck.end], ck.order),
        0x4BFA_34D8
    );

    let (ev, h) = decode_all(&desc, &bytes);
    assert_eq!(ev.len(), 1);
    let f = frames(&ev)[0];
    assert_eq!(f.seq, 61);
    assert_eq!(f.status, Some(0x77));
    assert_eq!(f.temperature_c, Some(40.0));
    let real = |i: usize| match f.values[i] {
        Some(ChannelValue::Real(x)) => x,
        ref other => panic!("channel {i}: {other:?}"),
    };
    assert_printed(real(0), "2.0196e-5");
    assert_printed(real(1), "5.1599e-5");
    assert_printed(real(2), "-1.3111e-5");
    // Accelerations come out as delta-velocity (m/s) = g x g0 x tau0; back to g for the check.
    let to_g = G0_M_S2 * desc.tau0_s();
    assert_printed(real(3) / to_g, "-1.00191");
    assert_printed(real(4) / to_g, "-0.0034950");
    assert_printed(real(5) / to_g, "0.0021090");
    assert_eq!(
        (h.frames, h.crc_errors, h.bytes_skipped, h.bytes_accepted),
        (1, 0, 0, 36)
    );

    // The encoder rebuilds the sample byte for byte from the decoded values.
    let values: Vec<ChannelValue> = f.values.iter().map(|v| v.expect("valid")).collect();
    let again = encode_frame(
        &desc,
        &FrameInput {
            seq: 61,
            values: &values,
            status: 0x77,
            temperature_c: Some(40.0),
        },
    )
    .expect("encode");
    assert_eq!(again, bytes);
}

/// KVH built-in-test messages (the 1775 manual's samples: the normal `?bit` output and the
/// `?bit,2` sample) between frames are checked and skipped: no increments, no skipped bytes, no
/// checksum errors. A status byte with gyro Y invalid (0x75) gives a missing gy value.
#[test]
fn kvh1750_bit_messages_and_validity() {
    let desc = builtin("kvh1750");
    let bit = [
        0xFE, 0x81, 0x00, 0xAA, 0x7F, 0x7F, 0x7F, 0x7F, 0x7F, 0x7F, 0x23,
    ];
    let bit2 = [
        0xFE, 0x81, 0x00, 0xAB, 0x7F, 0x7F, 0x7F, 0x7F, 0x7F, 0x7F, 0x37, 0x7F, 0xDA,
    ];
    let vals = [ChannelValue::Real(1e-6); 6];
    let mut s = Vec::new();
    s.extend(encode(&desc, 126, &vals, 0x77).expect("encode"));
    s.extend(bit);
    s.extend(encode(&desc, 127, &vals, 0x75).expect("encode"));
    s.extend(bit2);
    s.extend(encode(&desc, 128, &vals, 0x77).expect("encode"));
    let (ev, h) = decode_all(&desc, &s);
    let fr = frames(&ev);
    assert_eq!(ev.len(), 3, "no gaps: {ev:?}");
    // seq unwraps across the 7-bit counter: 126, 127, 128 (counter 0).
    assert_eq!(
        fr.iter().map(|f| f.seq).collect::<Vec<_>>(),
        vec![126, 127, 128]
    );
    assert_eq!(fr[1].values[1], None);
    assert!(fr[1].values[0].is_some() && fr[1].values[2].is_some());
    assert_eq!(h.other_messages, 2);
    assert_eq!(h.invalid_values, 1);
    assert_eq!((h.crc_errors, h.bytes_skipped, h.resyncs), (0, 0, 0));
    assert_eq!(h.bytes_accepted, s.len() as u64);
}

/// One siu8 frame per the SPEC-frames.md table, assembled by hand.
fn siu8_by_hand(counter: u16, g: [i32; 4], a: [i32; 4], temp_lsb: i16, status: u16) -> Vec<u8> {
    let mut f = vec![0xAA, 0x55];
    f.extend(counter.to_le_bytes());
    for v in g.iter().chain(a.iter()) {
        f.extend(v.to_le_bytes());
    }
    f.extend(temp_lsb.to_le_bytes());
    f.extend(status.to_le_bytes());
    let crc = crc16_ibm_3740(&f[2..40]);
    f.extend(crc.to_le_bytes());
    assert_eq!(f.len(), 42);
    f
}

/// siu8 frames built from the specification decode to the exact counts, the fault bits give
/// missing values, bit 8 hides the temperature, and the encoder writes the same bytes.
#[test]
fn siu8_golden_frames() {
    let desc = builtin("siu8");
    assert_eq!(desc.tau0_s(), 0.004);
    let g = [1000, -2, 123_456, -7_890_123];
    let a = [46_600, -1, 0, i32::MAX];
    let f1 = siu8_by_hand(0xFFFF, g, a, 2345, 0x0000);
    // Gyro 2 and accelerometer 4 faulty, temperature not settled.
    let f2 = siu8_by_hand(0x0000, g, a, -150, 0x0182);
    let mut s = f1.clone();
    s.extend(&f2);
    let (ev, h) = decode_all(&desc, &s);
    let fr = frames(&ev);
    assert_eq!(fr.len(), 2);
    // The counter wraps 65535 -> 0: seq 65535, 65536.
    assert_eq!((fr[0].seq, fr[1].seq), (65535, 65536));
    let counts: Vec<ChannelValue> = g
        .iter()
        .chain(a.iter())
        .map(|&n| ChannelValue::Count(i64::from(n)))
        .collect();
    let expect1: Vec<Option<ChannelValue>> = counts.iter().copied().map(Some).collect();
    assert_eq!(fr[0].values, expect1);
    assert_eq!(fr[0].temperature_c, Some(23.45));
    let mut expect2 = expect1.clone();
    expect2[1] = None;
    expect2[7] = None;
    assert_eq!(fr[1].values, expect2);
    assert_eq!(fr[1].temperature_c, None);
    assert_eq!(fr[1].status, Some(0x0182));
    assert_eq!(
        (h.frames, h.missing, h.invalid_values, h.crc_errors),
        (2, 0, 2, 0)
    );
    // LSBs as the SPEC lists them.
    let info = desc.channels();
    assert_eq!(info[0].scale, Some(0.004));
    assert_eq!(info[0].unit, "arcsec");
    assert_eq!(info[4].scale, Some(2.104e-4));
    assert_eq!(info[4].unit, "m/s");

    let e1 = encode_frame(
        &desc,
        &FrameInput {
            seq: 0xFFFF,
            values: &counts,
            status: 0,
            temperature_c: Some(23.45),
        },
    )
    .expect("encode");
    assert_eq!(e1, f1);
    let e2 = encode_frame(
        &desc,
        &FrameInput {
            seq: 0x1_0000,
            values: &counts,
            status: 0x0182,
            temperature_c: Some(-1.5),
        },
    )
    .expect("encode");
    assert_eq!(e2, f2);
}

/// One HG4930 message by hand (manual tables 3 and 7): address 0x0E, id, control data (zeros
/// here), status word 1 carrying the 2-bit counter, status word 2, for id 0x02 the six i32
/// increments, then the word sum.
fn hg_by_hand(id: u8, counter: u16, incs: Option<[i32; 6]>) -> Vec<u8> {
    let mut m = vec![0x0E, id];
    m.extend([0u8; 12]); // angular rates, linear accelerations (i16 x 6)
    m.extend((counter & 3).to_le_bytes()); // status word 1, bits 0-1 counter
    m.extend(0u16.to_le_bytes()); // status word 2A
    if let Some(v) = incs {
        for x in v {
            m.extend(x.to_le_bytes());
        }
    }
    let sum = hg_word_sum(&m);
    m.extend(sum.to_le_bytes());
    m
}

/// hg4930: inertial messages among control messages decode to exact counts with LSBs 2^-33 rad
/// and 2^-27 ft/s; a lost inertial message is found from the counter and the control count;
/// the encoder writes the same bytes (inertial then five controls per frame).
#[test]
fn hg4930_golden_messages() {
    let desc = builtin("hg4930");
    assert_eq!(desc.tau0_s(), 0.01);
    let incs = [
        [1 << 20, -(1 << 20), 7, 0, 123_456_789, -5],
        [3, 2, 1, -1, -2, -3],
        [0, 0, 0, 100, 200, 300],
    ];
    // Slots 0..17: inertial on 0, 6, 12; the counter is slot mod 4.
    let mut whole = Vec::new();
    let mut without_second = Vec::new();
    for slot in 0u16..18 {
        let m = if slot % 6 == 0 {
            hg_by_hand(0x02, slot, Some(incs[usize::from(slot / 6)]))
        } else {
            hg_by_hand(0x01, slot, None)
        };
        assert_eq!(m.len(), if slot % 6 == 0 { 44 } else { 20 });
        whole.extend(&m);
        if slot != 6 {
            without_second.extend(&m);
        }
    }
    let (ev, h) = decode_all(&desc, &whole);
    let fr = frames(&ev);
    assert_eq!(ev.len(), 3);
    for (k, f) in fr.iter().enumerate() {
        assert_eq!(f.seq, k as u64);
        let want: Vec<Option<ChannelValue>> = incs[k]
            .iter()
            .map(|&n| Some(ChannelValue::Count(i64::from(n))))
            .collect();
        assert_eq!(f.values, want);
    }
    assert_eq!((h.frames, h.other_messages, h.missing), (3, 15, 0));
    let info = desc.channels();
    assert_eq!(info[0].scale, Some(2f64.powi(-33)));
    assert_eq!(info[3].scale, Some(2f64.powi(-27) * 0.3048));

    // The second inertial message lost: one gap of 1 before frame seq 2.
    let (ev, h) = decode_all(&desc, &without_second);
    assert_eq!(ev.len(), 3);
    assert_eq!(ev[1], FrameEvent::Gap { missing: 1 });
    assert!(matches!(&ev[2], FrameEvent::Frame(f) if f.seq == 2));
    assert_eq!((h.frames, h.missing, h.crc_errors), (2, 1, 0));

    // A control message lost (slot 3) costs no frame; a damaged inertial message (slot 12, one
    // bit flipped in delta-angle X) is one checksum error and one missing frame, reported by
    // the first control message after it; the frame at slot 18 is seq 3.
    let mut damaged = Vec::new();
    for slot in 0u16..19 {
        let mut m = if slot % 6 == 0 {
            hg_by_hand(0x02, slot, Some(incs[usize::from(slot / 6) % 3]))
        } else {
            hg_by_hand(0x01, slot, None)
        };
        if slot == 12 {
            m[20] ^= 0x04;
        }
        if slot != 3 {
            damaged.extend(&m);
        }
    }
    let (ev, h) = decode_all(&desc, &damaged);
    assert_eq!(ev.len(), 4, "{ev:?}");
    assert_eq!(ev[2], FrameEvent::Gap { missing: 1 });
    assert!(matches!(&ev[3], FrameEvent::Frame(f) if f.seq == 3));
    assert_eq!(
        (
            h.frames,
            h.missing,
            h.crc_errors,
            h.bytes_skipped,
            h.resyncs
        ),
        (3, 1, 1, 44, 1)
    );

    // Encoder: frame k = inertial at slot 6k followed by the controls at slots 6k+1..6k+5.
    let mut enc = Vec::new();
    for (k, v) in incs.iter().enumerate() {
        let vals: Vec<ChannelValue> = v.iter().map(|&n| ChannelValue::Count(n.into())).collect();
        enc.extend(encode(&desc, k as u64, &vals, 0).expect("encode"));
    }
    assert_eq!(enc, whole);
}

/// A mixed stream for the split test: frames, garbage, a damaged frame, a duplicate, a gap.
fn mixed_stream(desc: &FrameDescriptor, seed: u64) -> Vec<u8> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let n = desc.frame().channels.len();
    let status = desc.status_all_valid();
    let mut s = Vec::new();
    s.extend([0x12, 0x34, 0x56]);
    for seq in 0..200u64 {
        let vals: Vec<ChannelValue> = (0..n)
            .map(|_| {
                if desc.channels()[0].scale.is_some() {
                    ChannelValue::Count(rng.random_range(-100_000..100_000))
                } else {
                    ChannelValue::Real(rng.random_range(-1e-4..1e-4))
                }
            })
            .collect();
        let f = encode(desc, seq, &vals, status).expect("encode");
        match seq % 23 {
            3 => {} // lost
            5 => {
                let mut d = f.clone();
                let i = rng.random_range(0..d.len());
                d[i] ^= 0x10;
                s.extend(d);
            }
            7 => {
                s.extend(&f);
                s.extend(&f);
            }
            11 => {
                s.extend(&f[..f.len() / 2]);
            }
            13 => {
                s.extend(&f);
                for _ in 0..rng.random_range(1..40) {
                    s.push(rng.random());
                }
            }
            _ => s.extend(&f),
        }
    }
    s
}

/// Whole, byte by byte, and at random splits (seeded): identical events and health.
#[test]
fn split_invariance() {
    for name in ["siu8", "kvh1750", "kvh1750b", "hg4930"] {
        let desc = builtin(name);
        let stream = mixed_stream(&desc, 7);
        let (ev_whole, h_whole) = decode_all(&desc, &stream);
        assert!(h_whole.frames > 150, "{name}: {h_whole:?}");
        assert_eq!(
            h_whole.bytes_accepted + h_whole.bytes_skipped,
            stream.len() as u64,
            "{name}: every byte accounted for"
        );

        let mut d = Decoder::new(desc.clone());
        let mut ev = Vec::new();
        for b in &stream {
            d.push(std::slice::from_ref(b));
            ev.extend(d.drain());
            let h = d.health();
            assert_eq!(
                h.bytes_accepted + h.bytes_skipped + d.pending() as u64,
                h.bytes_in
            );
        }
        d.finish();
        ev.extend(d.drain());
        assert_eq!(ev, ev_whole, "{name}: byte by byte");
        assert_eq!(*d.health(), h_whole, "{name}: byte by byte");

        for seed in 0..5u64 {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(1000 + seed);
            let mut d = Decoder::new(desc.clone());
            let mut ev = Vec::new();
            let mut i = 0;
            while i < stream.len() {
                let k = rng.random_range(0..=97usize).min(stream.len() - i);
                d.push(&stream[i..i + k]);
                ev.extend(d.drain());
                i += k;
            }
            d.finish();
            ev.extend(d.drain());
            assert_eq!(ev, ev_whole, "{name}: random splits, seed {seed}");
            assert_eq!(*d.health(), h_whole, "{name}: random splits, seed {seed}");
        }
    }
}
