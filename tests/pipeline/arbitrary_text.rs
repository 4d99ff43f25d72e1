//! Text columns as any file might hold them (proptest, modest case counts so CI stays in
//! seconds): lines built from the pieces the reader's rules look for (time, counter and PX4
//! names, units in brackets, labelled values, dates, words where numbers belong, `sep=`, notes,
//! byte-order marks, Latin-1 bytes), in any order and mix, read with the option sets a run can
//! give (`--tau0` or not, `--channels`, `--time-column`, sparse rows), and the step read off the
//! start as a run without `--tau0` does. Nothing may panic; a reader that opens hands out rows
//! of its width, every value a number within range or a gap, and reading ends; a position taken
//! part way resumes to the same rows.

use std::io::Cursor;
use std::path::Path;

use allanscope::input::sampling_step::infer_tau0;
use allanscope::input::text::{TextOptions, TextReader};
use allanscope::input::MAX_ABS_VALUE;
use proptest::prelude::*;

/// The pieces lines are made of: what the reader's rules act on, and what breaks them.
const PIECES: [&str; 48] = [
    "0",
    "1",
    "-0.5",
    "2.5e-3",
    "1e308",
    "1.5D-03",
    "0,25",
    "nan",
    "",
    "-",
    "ERR",
    "#N/A",
    "time",
    "t",
    "timestamp",
    "time [ms]",
    "Zeit [s]",
    "millis",
    "SampleTimeFine",
    "PacketCounter",
    "field.header.seq",
    "gx [deg/s]",
    "wx [deg/h]",
    "az [\u{b5}g]",
    "mag_x [uT]",
    "temp [\u{b0}C]",
    "gyro_rad[0]",
    "gyro_integral_dt",
    "timestamp_sample",
    "x",
    "imu_link",
    "s",
    "deg/s",
    "2026-12-03 01:02:03.456",
    "2026-12-03T01:02:03Z",
    "03.12.2026 01:02:03,456",
    "12:03:04",
    "ax:0.01",
    "gz: -2e-3",
    "ay=1",
    "a:",
    ":1",
    "=",
    "sep=;",
    "#",
    "//",
    "\u{feff}",
    "\u{e4}\u{df}",
];

const SEPS: [&str; 6] = [",", ";", "\t", " ", "  ", ", "];

/// A file: lines of pieces joined by one separator each, some lines ending in CR LF, and a few
/// raw bytes (a Latin-1 degree sign, a stray CR, a NUL) put in.
fn file() -> impl Strategy<Value = Vec<u8>> {
    let line = (
        proptest::collection::vec(0..PIECES.len(), 1..7),
        0..SEPS.len(),
        any::<bool>(),
    )
        .prop_map(|(pieces, sep, crlf)| {
            let mut l = pieces
                .iter()
                .map(|&i| PIECES[i])
                .collect::<Vec<_>>()
                .join(SEPS[sep]);
            l.push_str(if crlf { "\r\n" } else { "\n" });
            l
        });
    let numbers = (1..5usize, 0..SEPS.len(), 0u64..1000).prop_map(|(n, sep, k)| {
        // Rows of numbers with a clock, so the time rules and gaps are reached too.
        let mut l = format!("{}", 0.01 * k as f64);
        for j in 0..n {
            l.push_str(SEPS[sep]);
            l.push_str(&format!("{}", (k * 7 + j as u64) % 13));
        }
        l.push('\n');
        l
    });
    (
        proptest::collection::vec(prop_oneof![line, numbers], 1..40),
        proptest::collection::vec((0usize..4000, 0usize..3), 0..4),
    )
        .prop_map(|(lines, bytes)| {
            let mut b = lines.concat().into_bytes();
            for (at, which) in bytes {
                let at = at % (b.len() + 1);
                b.insert(at, [0xb0u8, b'\r', 0][which]);
            }
            b
        })
}

/// The option sets a run can give.
fn options(which: usize) -> TextOptions {
    let mut o = TextOptions::default();
    match which {
        0 => {}
        1 => o.tau0_s = Some(0.01),
        2 => {
            o.tau0_s = Some(0.01);
            o.channels = Some(vec!["x".into(), "gx [deg/s]".into(), "ax".into()]);
        }
        3 => {
            o.tau0_s = Some(0.01);
            o.time_column = Some("c1".into());
        }
        _ => {
            o.tau0_s = Some(0.01);
            o.sparse_rows = true;
        }
    }
    o
}

/// Rows read at most: a stamp far ahead (a date among seconds) is a gap of up to
/// `MAX_GAP_STEPS` steps, handed out in batches, which a test need not follow to its end.
const MAX_ROWS: usize = 100_000;

/// The rows a reader hands out until the end (or an error, or [`MAX_ROWS`] rows), checked as
/// the module doc says; and whether it reached the end.
fn read_out<R: std::io::BufRead>(reader: &mut TextReader<R>) -> (Vec<f64>, bool) {
    let width = reader.names().len();
    assert!(width >= 1);
    let mut values = Vec::new();
    let mut ended = false;
    while values.len() < MAX_ROWS * width {
        let before = values.len();
        match reader.read_rows(&mut values, 7) {
            Ok(0) | Err(_) => {
                ended = true;
                break;
            }
            Ok(n) => assert_eq!(values.len() - before, n * width),
        }
    }
    for v in &values {
        assert!(v.is_nan() || v.abs() <= MAX_ABS_VALUE, "value {v}");
    }
    (values, ended)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn any_text_through_the_reader(bytes in file(), which in 0usize..5, cut in 0usize..40) {
        let opts = options(which);
        let path = Path::new("any.csv");
        // The step from the start, as a run without --tau0 looks for it.
        let _ = infer_tau0(Cursor::new(&bytes[..]), path, &TextOptions { tau0_s: None, ..opts.clone() });
        let Ok(mut reader) = TextReader::with_options(Cursor::new(&bytes[..]), path, &opts) else {
            return Ok(());
        };
        let _ = reader.temperatures();
        let width = reader.names().len();
        // Read `cut` rows, take the position, and resume from it: the rest is what one reader
        // reading on gives.
        let mut head = Vec::new();
        let _ = reader.read_rows(&mut head, cut);
        let pos = reader.position();
        let (whole, whole_ended) = {
            let mut r = TextReader::with_options(Cursor::new(&bytes[..]), path, &opts)
                .expect("opened once");
            read_out(&mut r)
        };
        let offset = (pos.offset as usize).min(bytes.len());
        let mut resumed = reader.resume(Cursor::new(&bytes[offset..]), &pos);
        let (mut rest, rest_ended) = read_out(&mut resumed);
        head.append(&mut rest);
        prop_assert_eq!(head.len() % width, 0);
        if whole_ended && rest_ended {
            prop_assert_eq!(head.len(), whole.len());
        }
        prop_assert!(head
            .iter()
            .zip(&whole)
            .all(|(a, b)| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())));
    }
}
