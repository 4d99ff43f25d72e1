//! SIGTERM to a live `listen`: it stops reading, writes the final curve, fit, health and
//! summary records, and exits 0.
//!
//! The built binary listens on a loopback UDP port; the test sends the first 10 s of the siu8
//! fixture (2,500 frames), waits until an interim record shows all of it consumed
//! (`t_data` = 2,500 x 4 ms = 10 s), then sends SIGTERM with the `kill` command. With
//! `--capture FILE` the listener also writes every byte it received: FILE must be the bytes
//! sent.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::common::pipeline::*;

const FRAMES: usize = 2_500;
const FRAME_LEN: usize = 42;
/// Data-seconds in those frames: 2,500 x 0.004 s.
const T_DATA_S: f64 = 10.0;
const TIMEOUT: Duration = Duration::from_secs(30);

#[test]
fn sigterm_writes_final_records_and_exits_0() {
    let port = free_udp_port();
    let capture =
        std::env::temp_dir().join(format!("allanscope-signal-{}.siu8", std::process::id()));
    let mut child = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .args([
            "listen",
            "--udp",
            &format!("127.0.0.1:{port}"),
            "--format",
            "siu8",
            "--every",
            "0.2",
            "--capture",
            capture.to_str().expect("utf-8 path"),
        ])
        .env("ALLANSCOPE_LOG", "info")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn allanscope");
    let (tx, rx) = mpsc::channel::<(bool, String)>();
    let out = BufReader::new(child.stdout.take().expect("stdout"));
    let err = BufReader::new(child.stderr.take().expect("stderr"));
    let tx2 = tx.clone();
    let out_thread = std::thread::spawn(move || {
        let mut lines = Vec::new();
        for l in out.lines().map_while(Result::ok) {
            let _ = tx2.send((true, l.clone()));
            lines.push(l);
        }
        lines
    });
    std::thread::spawn(move || {
        for l in err.lines().map_while(Result::ok) {
            let _ = tx.send((false, l));
        }
    });
    let wait_for = |pred: &dyn Fn(bool, &str) -> bool| {
        let t0 = Instant::now();
        loop {
            let left = TIMEOUT.saturating_sub(t0.elapsed());
            match rx.recv_timeout(left) {
                Ok((is_out, l)) if pred(is_out, &l) => return,
                Ok(_) => {}
                Err(_) => panic!("timed out waiting for allanscope"),
            }
        }
    };
    wait_for(&|is_out, l| !is_out && l.contains("listening on udp"));

    let bytes = siu8_capture();
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").expect("bind");
    for d in bytes[..FRAMES * FRAME_LEN].chunks(5 * FRAME_LEN) {
        sock.send_to(d, ("127.0.0.1", port)).expect("send");
        std::thread::sleep(Duration::from_micros(200));
    }
    wait_for(&|is_out, l| {
        is_out
            && serde_json::from_str::<serde_json::Value>(l)
                .is_ok_and(|v| v["type"] == "curve" && v["t_data"] == T_DATA_S)
    });

    let kill = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(kill.success());
    let status = child.wait().expect("wait");
    assert_eq!(status.code(), Some(0), "exit status after SIGTERM");
    let lines = out_thread.join().expect("stdout reader");
    let recs: Vec<serde_json::Value> = lines
        .iter()
        .map(|l| serde_json::from_str(l).expect("JSON line"))
        .collect();
    let finals = final_curves_and_fits(&recs);
    // 8 channels x 3 statistics + 8 fits.
    assert_eq!(finals.len(), 32);
    let final_curve = recs
        .iter()
        .find(|r| r["type"] == "curve" && r["final"] == true)
        .expect("final curve");
    assert_eq!(final_curve["t_data"], T_DATA_S);
    let h = last_of(&recs, "health");
    assert_eq!(h["frames"], FRAMES as u64);
    assert_eq!(h["missing"], 0);
    let s = last_of(&recs, "summary");
    assert_eq!(s["t_data"], T_DATA_S);
    // Every received byte is in the capture, in order.
    let captured = std::fs::read(&capture).expect("capture file");
    let _ = std::fs::remove_file(&capture);
    assert_eq!(captured.len(), FRAMES * FRAME_LEN);
    assert!(
        captured == bytes[..FRAMES * FRAME_LEN],
        "capture differs from the bytes sent"
    );
    // The summary is the last line.
    assert_eq!(
        recs.last().map(|r| r["type"].clone()),
        Some("summary".into())
    );
}
