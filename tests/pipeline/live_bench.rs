//! Live benchmarks (ignored by default; BENCHMARKS.md, "Live pipeline", gives the commands).
//!
//! Both spawn the built binary `allanscope listen --udp 127.0.0.1:PORT --format siu8` and feed
//! it siu8 frames, one frame per datagram, on a fixed schedule from this test program:
//!
//! - `live_250hz_cpu`: the unit's own rate, 250 frames/s, for `ALLANSCOPE_BENCH_S` seconds
//!   (default 60), interim records every 10 s; reports the listener's CPU time over the feed
//!   (from /proc/PID/stat) as a share of one core. Target: under 1%.
//! - `udp_20k_frames_per_s`: 20,000 frames/s (80 times the unit's rate), in bursts of 20 every
//!   millisecond, for the same time; the health record must show every frame received and none
//!   missing. Target: zero lost.
//!
//! `cargo test --release --test pipeline -- live_bench:: --ignored --nocapture --test-threads 1`

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::pipeline::*;
use allanscope::frame::{encode, ChannelValue};

fn bench_seconds() -> f64 {
    std::env::var("ALLANSCOPE_BENCH_S")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(60.0)
}

/// CPU seconds (user + system) used so far by process `pid`.
fn cpu_seconds(pid: u32) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).expect("/proc stat");
    // Fields after the command name (which is in parentheses): state is field 3; utime and
    // stime are fields 14 and 15, in clock ticks (100 per second on Linux).
    let rest = &stat[stat.rfind(')').expect("stat format") + 2..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: u64 = f[11].parse::<u64>().expect("utime") + f[12].parse::<u64>().expect("stime");
    ticks as f64 / 100.0
}

fn spawn_listener(port: u16, extra: &[&str]) -> Child {
    let mut args = vec![
        "listen".to_string(),
        "--udp".into(),
        format!("127.0.0.1:{port}"),
        "--format".into(),
        "siu8".into(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    let mut child = Command::new(env!("CARGO_BIN_EXE_allanscope"))
        .args(&args)
        .env("ALLANSCOPE_LOG", "info")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn allanscope");
    let err = BufReader::new(child.stderr.take().expect("stderr"));
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        for l in err.lines().map_while(Result::ok) {
            if l.contains("listening on udp") {
                let _ = tx.send(());
            }
        }
    });
    rx.recv_timeout(Duration::from_secs(30))
        .expect("the listener did not start");
    child
}

/// Sends `n` frames at `rate_hz`, `burst` per send slot; returns the feed's wall time.
fn feed(port: u16, n: u64, rate_hz: f64, burst: u64) -> f64 {
    let desc = siu8();
    let status = desc.status_all_valid();
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").expect("bind");
    let t0 = Instant::now();
    let mut k = 0u64;
    while k < n {
        let due = t0 + Duration::from_secs_f64(k as f64 / rate_hz);
        let now = Instant::now();
        if due > now {
            std::thread::sleep(due - now);
        }
        for _ in 0..burst.min(n - k) {
            // Counts like a quiet gyro and a 1 g accelerometer.
            let g = (k % 7) as i64 - 3;
            let a = 186 + (k % 3) as i64;
            let values = [g, g, g, g, a, a, a, a].map(ChannelValue::Count);
            let f = encode(&desc, k, &values, status).expect("encode");
            sock.send_to(&f, ("127.0.0.1", port)).expect("send");
            k += 1;
        }
    }
    t0.elapsed().as_secs_f64()
}

fn stop(child: Child) -> Vec<serde_json::Value> {
    let kill = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(kill.success());
    let out = child.wait_with_output().expect("wait");
    assert_eq!(out.status.code(), Some(0));
    parse_lines(&out.stdout)
}

#[test]
#[ignore = "benchmark: 60 s; see BENCHMARKS.md"]
fn live_250hz_cpu() {
    let secs = bench_seconds();
    let port = free_udp_port();
    let child = spawn_listener(port, &["--every", "10"]);
    let n = (secs * 250.0) as u64;
    let cpu0 = cpu_seconds(child.id());
    let wall = feed(port, n, 250.0, 1);
    std::thread::sleep(Duration::from_millis(100));
    let cpu = cpu_seconds(child.id()) - cpu0;
    let recs = stop(child);
    let h = last_of(&recs, "health");
    let share = cpu / wall;
    println!(
        "live 250 Hz: {n} frames in {wall:.1} s; listener CPU {cpu:.2} s = {:.2}% of one core; health frames {} missing {}",
        100.0 * share,
        h["frames"],
        h["missing"]
    );
    assert_eq!(h["frames"], n);
    assert!(share < 0.01, "CPU share {share}");
}

#[test]
#[ignore = "benchmark: 60 s; see BENCHMARKS.md"]
fn udp_20k_frames_per_s() {
    let secs = bench_seconds();
    let port = free_udp_port();
    let child = spawn_listener(port, &[]);
    let n = (secs * 20_000.0) as u64;
    let cpu0 = cpu_seconds(child.id());
    let wall = feed(port, n, 20_000.0, 20);
    std::thread::sleep(Duration::from_millis(300));
    let cpu = cpu_seconds(child.id()) - cpu0;
    let recs = stop(child);
    let h = last_of(&recs, "health");
    println!(
        "UDP 20k/s: {n} frames in {wall:.1} s; listener CPU {cpu:.2} s = {:.1}% of one core; health {h}",
        100.0 * cpu / wall
    );
    assert_eq!(h["frames"], n, "frames received");
    assert_eq!(h["missing"], 0);
}
