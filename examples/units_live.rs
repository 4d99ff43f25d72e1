//! The live benchmark of several units in one process (BENCHMARKS.md, "Several units live"):
//! this program plays UNITS inertial units on loopback UDP, each sending 6-channel frames
//! (32 bytes with a 16-bit counter, at RATE frames/s) in datagrams of several frames, to one
//! `allanscope run --config` process with a `[[unit]]` table per unit; it measures that
//! process's CPU over the steady part of the run (per thread, from /proc), then stops it with
//! SIGINT and counts the frames each unit received against the frames sent.
//!
//! ```sh
//! cargo build --release
//! cargo run --release --example units_live                   # 100 units, 60 s, 10 frames/datagram, 2000 Hz
//! cargo run --release --example units_live -- 10 20 10 2000  # UNITS SECONDS FRAMES_PER_DATAGRAM RATE_HZ
//! ```
//!
//! The receiver is the release binary (`target/release/allanscope`, or `ALLANSCOPE_BIN`). The
//! sender is this program, on the same machine: its own CPU is printed too. Linux only (/proc).

use std::io::Write;
use std::net::UdpSocket;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use allanscope::frame::encoder::encode;
use allanscope::frame::{ChannelValue, FrameDescriptor};
use rand::{RngExt, SeedableRng};

/// Counter periods in the block of frames each unit sends over and over (times the frames per
/// datagram): a whole number of periods of the frame counter (modulo 65536) and of datagrams,
/// so the counter goes on without a break when the block repeats.
const BLOCK_PERIODS: usize = 1;
/// The counter's modulus (16 bits).
const COUNTER_MODULUS: usize = 65536;
/// The steady window starts this long after the first datagram (start-up excluded).
const WARM_UP: Duration = Duration::from_secs(5);

fn arg(i: usize, default: f64) -> f64 {
    std::env::args()
        .nth(i)
        .map(|a| {
            a.parse()
                .unwrap_or_else(|_| panic!("argument {i}: {a} is not a number"))
        })
        .unwrap_or(default)
}

/// CPU seconds (user + system) of every thread of `pid`, by thread name.
fn thread_cpu(pid: u32, tick_hz: f64) -> Vec<(String, f64)> {
    let mut out: Vec<(String, f64)> = Vec::new();
    let Ok(dir) = std::fs::read_dir(format!("/proc/{pid}/task")) else {
        return out;
    };
    for t in dir.flatten() {
        let Ok(stat) = std::fs::read_to_string(t.path().join("stat")) else {
            continue;
        };
        let (Some(open), Some(close)) = (stat.find('('), stat.rfind(')')) else {
            continue;
        };
        let name = stat[open + 1..close].to_string();
        let f: Vec<&str> = stat[close + 2..].split_whitespace().collect();
        // Fields 14 and 15 of stat (utime, stime) are the 12th and 13th after the name.
        let ticks: f64 = f[11].parse::<f64>().unwrap_or(0.0) + f[12].parse::<f64>().unwrap_or(0.0);
        // Workers are numbered; tokio's threads share a name: group them.
        let group = name
            .trim_end_matches(|c: char| c.is_ascii_digit())
            .to_string();
        match out.iter_mut().find(|(n, _)| *n == group) {
            Some(e) => e.1 += ticks / tick_hz,
            None => out.push((group, ticks / tick_hz)),
        }
    }
    out
}

/// The start of the steady window: when, allanscope's CPU per thread, this program's CPU.
type Steady = (Instant, Vec<(String, f64)>, f64);

fn total(v: &[(String, f64)]) -> f64 {
    v.iter().map(|x| x.1).sum()
}

fn process_cpu(pid: &str, tick_hz: f64) -> f64 {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).unwrap_or_default();
    let close = stat.rfind(')').unwrap_or(0);
    let f: Vec<&str> = stat
        .get(close + 2..)
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let t = |i: usize| f.get(i).and_then(|x| x.parse::<f64>().ok()).unwrap_or(0.0);
    (t(11) + t(12)) / tick_hz
}

/// The kernel's count of UDP datagrams dropped because a socket's receive buffer was full
/// (`RcvbufErrors` in /proc/net/snmp): datagrams the receiving process did not read in time.
fn udp_rcvbuf_errors() -> u64 {
    let text = std::fs::read_to_string("/proc/net/snmp").unwrap_or_default();
    let rows: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| l.starts_with("Udp:"))
        .map(|l| l.split_whitespace().collect())
        .collect();
    match rows.as_slice() {
        [names, values, ..] => names
            .iter()
            .position(|n| *n == "RcvbufErrors")
            .and_then(|i| values.get(i))
            .and_then(|v| v.parse().ok())
            .unwrap_or(0),
        _ => 0,
    }
}

fn loadavg() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .unwrap_or_default()
        .split_whitespace()
        .take(3)
        .collect::<Vec<_>>()
        .join(" ")
}

fn main() {
    let units = arg(1, 100.0) as usize;
    let seconds = arg(2, 60.0);
    let per_datagram = arg(3, 10.0) as usize;
    let rate = arg(4, 2000.0);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let bin = std::env::var_os("ALLANSCOPE_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target/release/allanscope"));
    assert!(
        bin.is_file(),
        "{}: build it first (cargo build --release)",
        bin.display()
    );
    let tick_hz: f64 = Command::new("getconf")
        .arg("CLK_TCK")
        .output()
        .ok()
        .and_then(|o| String::from_utf8_lossy(&o.stdout).trim().parse().ok())
        .unwrap_or(100.0);
    let dir = std::env::temp_dir().join(format!("allanscope-units-live-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("work dir");

    // A 6-channel unit at RATE frames/s: 32-byte frames (sync, 16-bit counter, 3 gyro and 3
    // accelerometer increments, status, CRC-16), laid out as siu8's. A 16-bit counter places
    // a frame after a scheduling stall by the counter alone (a 7-bit one, as kvh1750's, wraps
    // in 64 ms at 2 kHz: a stall of a loaded host then reads as an outage sized by wall time).
    let mut text = format!(
        "name = \"imu6\"\nrate_hz = {rate:.1}\nbyte_order = \"little\"\nlength = 32\n\
         [sync]\nbytes = [0xAA, 0x55]\noffset = 0\n\
         [checksum]\nalgorithm = \"CRC-16/IBM-3740\"\nrange = [2, 29]\nat = 30\n\
         [counter]\noffset = 2\ntype = \"u16\"\nmodulus = 65536\n\
         [status]\noffset = 28\ntype = \"u16\"\nbit_set_means = \"fault\"\n"
    );
    for (k, (name, scale, unit)) in [
        ("g1", 0.004, "arcsec"),
        ("g2", 0.004, "arcsec"),
        ("g3", 0.004, "arcsec"),
        ("a1", 2.104e-4, "m/s"),
        ("a2", 2.104e-4, "m/s"),
        ("a3", 2.104e-4, "m/s"),
    ]
    .iter()
    .enumerate()
    {
        text += &format!(
            "[[channels]]\nname = \"{name}\"\noffset = {}\ntype = \"i32\"\nscale = {scale}\n\
             unit = \"{unit}\"\nkind = \"increment\"\nstatus_bit = {k}\n",
            4 + 4 * k
        );
    }
    let desc_path = dir.join("imu6.toml");
    std::fs::write(&desc_path, text).expect("descriptor");
    let desc = FrameDescriptor::load(desc_path.to_str().expect("utf-8 path")).expect("descriptor");

    // One block of frames with white noise, sent by every unit over and over.
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(1);
    let mut block = Vec::new();
    let block_frames = COUNTER_MODULUS * BLOCK_PERIODS * per_datagram;
    for seq in 0..block_frames as u64 {
        let values: Vec<ChannelValue> = (0..6)
            .map(|_| ChannelValue::Count(rng.random_range(-1000..=1000)))
            .collect();
        block.extend(encode(&desc, seq, &values, desc.status_all_valid()).expect("encode"));
    }
    let frame_len = block.len() / block_frames;

    // The ports, and the stand config of UNITS units.
    // All held at once while picking, so no port is handed out twice.
    let held: Vec<UdpSocket> = (0..units)
        .map(|_| UdpSocket::bind("127.0.0.1:0").expect("bind"))
        .collect();
    let ports: Vec<u16> = held
        .iter()
        .map(|s| s.local_addr().expect("addr").port())
        .collect();
    drop(held);
    let mut config = String::from(
        "[run]\nevery_s = 10.0\nquiet_after = 5.0\n[statistics]\noverlap = 16\n[output]\npath = \"units.jsonl\"\n",
    );
    for (i, p) in ports.iter().enumerate() {
        config += &format!(
            "[[unit]]\nname = \"u{i:03}\"\nsource = {{ kind = \"udp\", address = \"127.0.0.1:{p}\", format = \"{}\" }}\n",
            desc_path.display()
        );
    }
    std::fs::write(dir.join("units.toml"), config).expect("config");
    let log = std::fs::File::create(dir.join("stderr.log")).expect("log");
    let mut child = Command::new(&bin)
        .current_dir(&dir)
        .args(["run", "--config", "units.toml"])
        .stdout(Stdio::null())
        .stderr(log)
        .spawn()
        .expect("start allanscope");
    let pid = child.id();
    // Wait until every socket is bound.
    let t0 = Instant::now();
    loop {
        let text = std::fs::read_to_string(dir.join("stderr.log")).unwrap_or_default();
        if text.matches("listening on udp").count() >= units {
            break;
        }
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "allanscope did not bind: {text}"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let load_start = loadavg();
    let drops0 = udp_rcvbuf_errors();

    // Send: every period, one datagram of PER_DATAGRAM frames to each unit, on an absolute
    // schedule (a late round is caught up at once).
    let sock = UdpSocket::bind("127.0.0.1:0").expect("sender");
    let dgram = per_datagram * frame_len;
    let period = Duration::from_secs_f64(per_datagram as f64 / rate);
    let rounds = (seconds * rate / per_datagram as f64).round() as u64;
    let start = Instant::now();
    let mut sent_frames = 0u64;
    let mut at = 0usize;
    let mut steady: Option<Steady> = None;
    let own0 = process_cpu("self", tick_hz);
    for r in 0..rounds {
        let due = start + period * r as u32;
        if let Some(wait) = due.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
        if steady.is_none() && start.elapsed() >= WARM_UP {
            steady = Some((
                Instant::now(),
                thread_cpu(pid, tick_hz),
                process_cpu("self", tick_hz),
            ));
        }
        let d = &block[at..at + dgram];
        for p in &ports {
            sock.send_to(d, ("127.0.0.1", *p)).expect("send");
        }
        sent_frames += per_datagram as u64;
        at = (at + dgram) % block.len();
    }
    let send_wall = start.elapsed().as_secs_f64();
    let (t_steady, cpu0, own_steady0) = steady.expect("a run longer than the warm-up");
    let cpu1 = thread_cpu(pid, tick_hz);
    let window = t_steady.elapsed().as_secs_f64();
    let own1 = process_cpu("self", tick_hz);
    let load_end = loadavg();
    let drops = udp_rcvbuf_errors() - drops0;
    std::thread::sleep(Duration::from_millis(500));
    let _ = Command::new("kill")
        .args(["-INT", &pid.to_string()])
        .status();
    let status = child.wait().expect("wait");

    // What each unit received, from its health record.
    let text = std::fs::read_to_string(dir.join("units.jsonl")).expect("output");
    let (mut frames, mut missing, mut healths, mut outages) = (0u64, 0u64, 0usize, 0usize);
    let mut short_units = 0usize;
    for line in text.lines() {
        let v: serde_json::Value = serde_json::from_str(line).expect("JSON line");
        match v["type"].as_str() {
            Some("health") => {
                healths += 1;
                let f = v["frames"].as_u64().unwrap_or(0);
                frames += f;
                missing += v["missing"].as_u64().unwrap_or(0);
                if f < sent_frames {
                    short_units += 1;
                }
            }
            Some("outage") => outages += 1,
            _ => {}
        }
    }
    let cpu = total(&cpu1) - total(&cpu0);
    println!(
        "units {units} x 6 channels x {rate} Hz, {per_datagram} frames per datagram ({:.0} datagrams/s), {seconds} s (sent in {send_wall:.2} s)",
        units as f64 * rate / per_datagram as f64
    );
    println!(
        "frames sent {} | received {frames} | lost {} | missing by counter {missing} | units short {short_units} | health records {healths} | outage records {outages} | exit {:?}",
        sent_frames * units as u64,
        (sent_frames * units as u64).saturating_sub(frames),
        status.code()
    );
    println!(
        "UDP datagrams dropped by the kernel (receive buffers full) during the run: {drops} (= {} frames)",
        drops * per_datagram as u64
    );
    println!(
        "allanscope CPU over the steady {window:.1} s: {cpu:.2} s = {:.1}% of one core",
        100.0 * cpu / window
    );
    for (name, c1) in &cpu1 {
        let c0 = cpu0.iter().find(|(n, _)| n == name).map_or(0.0, |x| x.1);
        if c1 - c0 > 0.0 {
            println!(
                "  thread {name:<24} {:.2} s = {:.1}% of one core",
                c1 - c0,
                100.0 * (c1 - c0) / window
            );
        }
    }
    println!(
        "sender (this program) CPU: {:.1}% of one core (whole run {:.2} s)",
        100.0 * (own1 - own_steady0) / window,
        own1 - own0
    );
    println!(
        "load average (1, 5, 15 min): at start {load_start}; at end {load_end}; cores {}",
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    let _ = std::io::stdout().flush();
    let _ = std::fs::remove_dir_all(&dir);
}
