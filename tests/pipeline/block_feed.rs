//! The flat path (a `FrameBlock` per chunk, what the pipeline sends) against the one-frame-at-a-
//! time path (`Chunk::Frames`): the same events must give the same interim and final records,
//! bit for bit, with gaps, missing values, a real value on a counts channel, interim records
//! falling due inside blocks and blocks cut at arbitrary places, in narrow (`i32`) and wide
//! (`i64`) count columns alike.

use allanscope::frame::{ChannelValue, ColumnKind, Decoder, FrameBlock, FrameEvent, FrameSink};
use allanscope::input::Chunk;
use allanscope::sink::records::Record;

use crate::common::pipeline::{analysis, siu8, siu8_capture};

/// The fixture's first 20,000 frames with damage of every kind the analysis sees.
fn damaged_events() -> Vec<FrameEvent> {
    let desc = siu8();
    let bytes = siu8_capture();
    let mut dec = Decoder::new(desc);
    dec.push(&bytes[..20_000 * 42]);
    dec.finish();
    let mut events = Vec::new();
    for (i, ev) in dec.drain().enumerate() {
        let FrameEvent::Frame(mut f) = ev else {
            panic!("the clean fixture has no gaps");
        };
        match i % 997 {
            // frames lost: a gap instead of the frame
            5 => {
                events.push(FrameEvent::Gap {
                    missing: 1 + i as u64 % 7,
                });
                continue;
            }
            // a channel marked invalid
            300 => f.values[i % 8] = None,
            // a value a counts channel cannot take exactly
            600 => f.values[(i + 3) % 8] = Some(ChannelValue::Real(0.25)),
            // a count beyond 32 bits (a hole in a narrow column, an entry of a wide one)
            800 => f.values[(i + 5) % 8] = Some(ChannelValue::Count(-(1 << 40))),
            _ => {}
        }
        events.push(FrameEvent::Frame(f));
    }
    events
}

fn to_json(records: &[Record]) -> Vec<String> {
    records
        .iter()
        .map(|r| serde_json::to_string(r).expect("serialize"))
        .collect::<Vec<_>>()
}

/// Interim records every 7 data-seconds (due inside blocks) and the final records: the same
/// strings through either path, through blocks of 1, 333 and 4096 events, of narrow and of
/// wide count columns.
#[test]
fn blocks_give_the_records_of_single_frames() {
    let desc = siu8();
    let events = damaged_events();
    assert!(events.iter().any(|e| matches!(e, FrameEvent::Gap { .. })));

    let mut single = analysis(&desc, Some(7.0));
    let mut want = Vec::new();
    single.push_chunk(&Chunk::Frames(events.clone()), &mut want);
    want.extend(single.records(true));
    let want = to_json(&want);
    // 20,000 frames at 4 ms plus the gaps: 80 data-seconds, 11 interim sets of 8 channels.
    let interim = want
        .iter()
        .filter(|r| r.contains("\"final\":false"))
        .count();
    assert!(interim >= 8 * 2 * 11, "interim records: {interim}");

    let cases = [1, 333, 4096]
        .into_iter()
        .flat_map(|size| [(size, ColumnKind::Count32), (size, ColumnKind::Count)]);
    for (size, kind) in cases {
        let mut flat = analysis(&desc, Some(7.0));
        let mut got = Vec::new();
        for part in events.chunks(size) {
            let mut block = FrameBlock::with_kinds(&[kind; 8], part.len());
            for ev in part {
                match ev {
                    FrameEvent::Gap { missing } => block.push_gap(*missing),
                    FrameEvent::Frame(f) => block.push_frame(
                        allanscope::frame::BlockEvent::Frame {
                            seq: f.seq,
                            temperature_c: f.temperature_c,
                            status: f.status,
                        },
                        &f.values,
                    ),
                }
            }
            flat.push_chunk(&Chunk::Block(block), &mut got);
        }
        got.extend(flat.records(true));
        let got = to_json(&got);
        assert_eq!(got.len(), want.len(), "blocks of {size}, {kind:?}");
        for (g, w) in got.iter().zip(&want) {
            assert_eq!(g, w, "blocks of {size}, {kind:?}");
        }
    }
}
