//! Any input through the decoder and the descriptor checker (proptest, modest case counts so
//! CI stays in seconds): any byte stream through every shipped descriptor, any edit of a
//! shipped descriptor's text, any value of the numeric option types. Nothing may panic, the
//! decoder's held bytes stay within a message, and every event accounts for bytes it was given.

use allanscope::frame::descriptor::BUILTIN;
use allanscope::frame::FrameDescriptor;
use allanscope::frame::{Decoder, FrameEvent};
use proptest::prelude::*;

fn shipped() -> Vec<FrameDescriptor> {
    BUILTIN
        .iter()
        .map(|(n, _)| {
            FrameDescriptor::builtin(n)
                .expect("listed")
                .unwrap_or_else(|e| panic!("{e}"))
        })
        .collect()
}

/// The longest message of a descriptor, in bytes.
fn max_len(d: &FrameDescriptor) -> usize {
    d.messages.iter().map(|m| m.length).max().unwrap_or(0)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Random bytes, fed in random-sized pieces, with sync bytes sprinkled in so that the
    /// decoder also tries (and rejects) many candidate messages.
    #[test]
    fn any_bytes_through_every_descriptor(
        bytes in proptest::collection::vec(any::<u8>(), 0..6000),
        syncs in proptest::collection::vec(0usize..6000, 0..200),
        cuts in proptest::collection::vec(1usize..700, 1..20),
    ) {
        for desc in shipped() {
            let mut data = bytes.clone();
            for &at in &syncs {
                if at + desc.sync.bytes.len() <= data.len() {
                    data[at..at + desc.sync.bytes.len()].copy_from_slice(&desc.sync.bytes);
                }
            }
            let limit = max_len(&desc);
            let mut dec = Decoder::new(desc.clone());
            let mut frames = 0u64;
            let mut rest = &data[..];
            let mut k = 0;
            while !rest.is_empty() {
                let n = cuts[k % cuts.len()].min(rest.len());
                k += 1;
                dec.push(&rest[..n]);
                rest = &rest[n..];
                while let Some(e) = dec.next_event() {
                    if matches!(e, FrameEvent::Frame(_)) {
                        frames += 1;
                    }
                }
                prop_assert!(dec.pending() < 2 * limit, "{} held", dec.pending());
            }
            dec.finish();
            for e in dec.drain() {
                if matches!(e, FrameEvent::Frame(_)) {
                    frames += 1;
                }
            }
            prop_assert_eq!(dec.pending(), 0);
            let h = dec.health();
            prop_assert_eq!(h.bytes_in, data.len() as u64);
            prop_assert!(frames * desc.frame_len() as u64 <= data.len() as u64);
        }
    }

    /// Any small edit of a shipped descriptor's text (a deleted, duplicated or replaced
    /// stretch, a number changed) is either a descriptor or a list of problems, never a panic;
    /// an accepted one stays within the ranges the decoder relies on.
    #[test]
    fn any_edit_of_a_descriptor(
        which in 0usize..4,
        at in 0usize..4000,
        len in 0usize..40,
        insert in "[ -~\n]{0,30}",
        number in prop_oneof![
            Just("0".to_string()), Just("-1".to_string()), Just("1e308".to_string()),
            Just("1e-300".to_string()), Just("nan".to_string()), Just("inf".to_string()),
            Just("9223372036854775807".to_string()), Just("65537".to_string()),
            any::<i64>().prop_map(|v| v.to_string()), any::<f64>().prop_map(|v| format!("{v:e}")),
        ],
        use_number in any::<bool>(),
    ) {
        let (_, text) = BUILTIN[which % BUILTIN.len()];
        let mut t = text.to_string();
        let a = at.min(t.len());
        let a = (0..=a).rev().find(|&i| t.is_char_boundary(i)).unwrap_or(0);
        let b = (a + len).min(t.len());
        let b = (b..=t.len()).find(|&i| t.is_char_boundary(i)).unwrap_or(t.len());
        t.replace_range(a..b, if use_number { &number } else { &insert });
        if let Ok(d) = FrameDescriptor::from_toml_str(&t, std::path::Path::new("edit.toml")) {
            prop_assert!(d.rate_hz >= allanscope::ranges::MIN_RATE_HZ);
            prop_assert!(d.rate_hz <= allanscope::ranges::MAX_RATE_HZ);
            prop_assert!(d.frame().channels.len() <= allanscope::ranges::MAX_CHANNELS);
            prop_assert!(max_len(&d) as u64 <= allanscope::ranges::MAX_MESSAGE_BYTES);
            for c in &d.frame().channels {
                prop_assert!(c.scale.abs() >= allanscope::ranges::MIN_SCALE);
                prop_assert!(c.scale.abs() <= allanscope::ranges::MAX_SCALE);
            }
            // And it decodes whatever it is given.
            let mut dec = Decoder::new(d.clone());
            dec.push(&text.as_bytes()[..text.len().min(2000)]);
            dec.finish();
            prop_assert_eq!(dec.drain().count() as u64 <= 2000, true);
        }
    }

    /// Any number given as a duration, an interval or a sampling step is accepted only inside
    /// its range, and never panics (the parsers behind clap, the stand config and simulate).
    #[test]
    fn any_option_value(v in any::<f64>(), text in "[0-9eE.+-]{0,12}(s|min|h|d)?") {
        use allanscope::ranges::*;
        if let Ok(x) = check_interval(v) {
            prop_assert!((MIN_INTERVAL_S..=MAX_SECONDS).contains(&x));
            // Such a value always makes a timer.
            let _ = std::time::Instant::now() + std::time::Duration::from_secs_f64(x);
        }
        if let Ok(x) = check_tau0(v) {
            prop_assert!((MIN_TAU0_S..=MAX_TAU0_S).contains(&x));
        }
        for t in [text.clone(), format!("{v}"), format!("{v}d")] {
            if let Ok(x) = parse_duration(&t) {
                prop_assert!(x > 0.0 && x <= MAX_SECONDS, "{t} -> {x}");
                let _ = std::time::Instant::now() + std::time::Duration::from_secs_f64(x);
            }
        }
    }
}
