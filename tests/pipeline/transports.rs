//! The same frames through every transport give the same final records.
//!
//! 30 s of the siu8 fixture (7,500 frames) go through a file, standard input (the built
//! binary, `analyze -`), a pseudo-terminal pair (`listen --serial` on the slave side, through
//! the library pipeline) and a loopback UDP socket (datagrams of 5 frames, some pairs of
//! datagrams swapped and some sent twice, to exercise the reorder window). The final curve and
//! fit records must be equal field by field (they hold no wall-clock field), the summaries
//! equal but for `elapsed_s` and `input`, and the health counters equal the truth: 7,500
//! frames, nothing missing, and for UDP exactly the duplicated frames sent.

use std::io::Write;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::pipeline::*;
use allanscope::pipeline::RunControl;
use allanscope::source::{Pace, SourceSpec};
use rand::{RngExt, SeedableRng};

/// 30 s of data at 250 Hz.
const FRAMES: usize = 7_500;
const FRAME_LEN: usize = 42;
/// Frames per UDP datagram.
const PER_DATAGRAM: usize = 5;
/// How long a live transport may take to deliver everything.
const DELIVERY_TIMEOUT: Duration = Duration::from_secs(60);

fn frames() -> Vec<u8> {
    siu8_capture()[..FRAMES * FRAME_LEN].to_vec()
}

fn wait_for_frames(ctl: &RunControl, n: u64) {
    let t0 = Instant::now();
    while ctl.progress.frames() < n {
        assert!(
            t0.elapsed() < DELIVERY_TIMEOUT,
            "only {} of {n} frames arrived",
            ctl.progress.frames()
        );
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn via_file(bytes: &[u8]) -> Vec<serde_json::Value> {
    let dir = std::env::temp_dir().join(format!("allanscope-transports-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let path = dir.join("frames.siu8");
    std::fs::write(&path, bytes).expect("write");
    let (recs, _) = run_to_records(
        SourceSpec::File {
            path,
            pace: Pace::Max,
        },
        &siu8(),
        &RunControl::default(),
    );
    let _ = std::fs::remove_dir_all(&dir);
    recs
}

fn via_stdin(bytes: &[u8]) -> Vec<serde_json::Value> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .args(["analyze", "-", "--format", "siu8"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn allanscope");
    let mut stdin = child.stdin.take().expect("stdin");
    let data = bytes.to_vec();
    let feeder = std::thread::spawn(move || stdin.write_all(&data).expect("feed stdin"));
    let out = child.wait_with_output().expect("wait");
    feeder.join().expect("feeder");
    assert!(out.status.success(), "analyze - exited with {}", out.status);
    parse_lines(&out.stdout)
}

fn via_serial(bytes: &[u8]) -> Vec<serde_json::Value> {
    use tokio::io::AsyncWriteExt;
    use tokio_serial::SerialPort;
    let rt = tokio::runtime::Runtime::new().expect("runtime");
    let (mut master, slave) = rt
        .block_on(async { tokio_serial::SerialStream::pair() })
        .expect("pty pair");
    let path = slave.name().expect("pty name");
    let ctl = RunControl::default();
    let spec = SourceSpec::Serial {
        path: path.into(),
        baud: 230_400,
    };
    let ctl2 = ctl.clone();
    let listener = std::thread::spawn(move || run_to_records(spec, &siu8(), &ctl2).0);
    // Let the listener open the port before the first byte is written.
    std::thread::sleep(Duration::from_millis(300));
    rt.block_on(async {
        for chunk in bytes.chunks(4096) {
            AsyncWriteExt::write_all(&mut master, chunk)
                .await
                .expect("write pty");
        }
        AsyncWriteExt::flush(&mut master).await.expect("flush pty");
    });
    wait_for_frames(&ctl, FRAMES as u64);
    ctl.shutdown.cancel();
    let recs = listener.join().expect("listener");
    drop(slave);
    recs
}

/// Returns the records and the number of duplicated frames sent.
fn via_udp(bytes: &[u8]) -> (Vec<serde_json::Value>, u64) {
    let port = free_udp_port();
    let ctl = RunControl::default();
    let spec = SourceSpec::Udp {
        bind: ([127, 0, 0, 1], port).into(),
    };
    let ctl2 = ctl.clone();
    let listener = std::thread::spawn(move || run_to_records(spec, &siu8(), &ctl2).0);
    std::thread::sleep(Duration::from_millis(200));
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").expect("bind sender");
    let mut datagrams: Vec<&[u8]> = bytes.chunks(PER_DATAGRAM * FRAME_LEN).collect();
    // Swap some neighbouring datagrams (never the first: it anchors the counter) and send some
    // twice; seeded, so the counts are fixed.
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
    let mut i = 2;
    while i + 1 < datagrams.len() {
        if rng.random_bool(0.1) {
            datagrams.swap(i, i + 1);
            i += 2;
        } else {
            i += 1;
        }
    }
    let mut dups = 0u64;
    let mut sent = 0u64;
    for d in &datagrams {
        // Keep at most ~400 frames in flight, well inside the socket's default buffer.
        let t0 = Instant::now();
        while sent > ctl.progress.frames() + 400 {
            assert!(t0.elapsed() < DELIVERY_TIMEOUT, "UDP delivery stalled");
            std::thread::sleep(Duration::from_millis(1));
        }
        sock.send_to(d, ("127.0.0.1", port)).expect("send");
        sent += (d.len() / FRAME_LEN) as u64;
        if rng.random_bool(0.02) {
            sock.send_to(d, ("127.0.0.1", port)).expect("send");
            dups += (d.len() / FRAME_LEN) as u64;
        }
    }
    wait_for_frames(&ctl, FRAMES as u64);
    // Let the duplicates that follow the last new frame arrive too.
    std::thread::sleep(Duration::from_millis(100));
    ctl.shutdown.cancel();
    (listener.join().expect("listener"), dups)
}

#[test]
fn same_frames_same_records_over_every_transport() {
    let bytes = frames();
    let file = via_file(&bytes);
    let reference = final_curves_and_fits(&file);
    // 8 channels x (3 curves + 1 fit).
    assert_eq!(reference.len(), 32);
    let stdin = via_stdin(&bytes);
    let serial = via_serial(&bytes);
    let (udp, udp_dups) = via_udp(&bytes);
    assert!(udp_dups > 0, "the UDP run should send some duplicates");
    for (name, recs) in [("stdin", &stdin), ("serial", &serial), ("udp", &udp)] {
        let got = final_curves_and_fits(recs);
        assert_eq!(got.len(), reference.len(), "{name}: record count");
        for (g, r) in got.iter().zip(&reference) {
            assert_eq!(g, r, "{name}: final record differs from the file's");
        }
        assert_eq!(
            summary_core(last_of(recs, "summary")),
            summary_core(last_of(&file, "summary")),
            "{name}: summary"
        );
        let h = last_of(recs, "health");
        assert_eq!(h["frames"], FRAMES as u64, "{name}: frames");
        assert_eq!(h["missing"], 0, "{name}: missing");
        assert_eq!(h["crc_errors"], 0, "{name}: crc_errors");
        let want_dups = if name == "udp" { udp_dups } else { 0 };
        assert_eq!(h["duplicates"], want_dups, "{name}: duplicates");
    }
    eprintln!("udp health: {}", last_of(&udp, "health"));
    // The swapped datagrams were put back in order (counted by the window).
    assert!(
        last_of(&udp, "health")["udp_reordered"]
            .as_u64()
            .unwrap_or(0)
            > 0
    );
    assert_eq!(last_of(&udp, "health")["udp_late"], 0);
}

/// The direct file reader (`source::file::read_file`, what a replay as fast as possible uses)
/// hands on exactly the file's bytes, in order, once each, while its buffers are recycled many
/// times over and the last read is short: 3 MB of patterned bytes (12 reads of 256 KiB, more
/// reads than the reader keeps buffers; a buffer reused without being cut to its read would
/// repeat stale bytes) arrive whole, the progress counts them and the end of input is marked.
#[test]
fn direct_file_reads_deliver_every_byte_once() {
    use allanscope::source::file::{read_file, READ_BLOCK};
    use allanscope::source::{Progress, SourceContext, SourceEvent};
    let len = 3_000_017usize;
    let bytes: Vec<u8> = (0..len as u64)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 11) as u8)
        .collect();
    let path = crate::common::tmp_in("direct-reads", "bytes.bin");
    std::fs::write(&path, &bytes).unwrap();
    let (tx, mut rx) = tokio::sync::mpsc::channel(4);
    let progress = std::sync::Arc::new(Progress::default());
    let mut ctx = SourceContext {
        start_offset: 0,
        tx,
        shutdown: tokio_util::sync::CancellationToken::new(),
        capture: None,
        progress: progress.clone(),
    };
    let file = std::fs::File::open(&path).unwrap();
    let reader = std::thread::spawn(move || read_file(file, &mut ctx));
    let (mut got, mut reads) = (Vec::with_capacity(len), 0);
    while let Some(ev) = rx.blocking_recv() {
        if let SourceEvent::Data { bytes, .. } = ev {
            got.extend_from_slice(&bytes);
            reads += 1;
        }
        // The read's buffer goes back to the reader here.
    }
    reader.join().unwrap().unwrap();
    assert_eq!(got.len(), len);
    assert!(got == bytes, "the bytes differ from the file's");
    if std::env::var_os("ALLANSCOPE_READ_BLOCK").is_none() {
        assert_eq!(reads, len.div_ceil(READ_BLOCK));
    }
    assert_eq!(progress.bytes(), len as u64);
    assert!(progress.input_ended());
}
