//! How runs end (issue 11, "Data loss"), on the built binary:
//!
//! - A replay's output does not depend on timing: with a consumer that reads nothing for the
//!   first second, `analyze` still writes every interim record (back-pressure, never coalesced):
//!   the same 30 interim `t_data` values (10, 20, ... 300 s) in two runs, 994 records in all.
//! - A replay stopped by SIGINT (`--pace realtime`) writes its final records for the data read,
//!   says `read_to_end: false, stopped_by: "SIGINT"` in `summary`, and exits 1.
//! - A live run whose standard output is no longer read ends within a bounded time after SIGINT
//!   (the writer's grace, 3 s), at once after a second SIGINT, with an error naming standard
//!   output; with `--out FILE` the final records are in the file.
//! - A replay held by back-pressure (its standard output not read) ends the same way after
//!   SIGINT; a consumer that reads again after the signal gets the final records at once.
//! - A listener on a UDP port that never receives anything ends at once on SIGINT or SIGTERM,
//!   exit 0, with its (empty) final records, health and summary; so does a serial listener on a
//!   pseudo-terminal whose line went quiet, with the final records of the frames it received.
//! - A run waiting to open a FIFO no writer has opened ends on the first signal, within 2 s,
//!   exit 1, saying nothing was analysed (text and frames); a run blocked reading a FIFO whose
//!   writer holds it open and sends nothing cannot see the first signal, and a second one ends
//!   it within 5 s, exit 1 (both hung through any number of signals).

use std::io::{BufRead, BufReader, Read};
use std::process::{Child, Stdio};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use crate::common::pipeline::{free_udp_port, last_of, parse_lines};
use crate::common::{exe, fixtures, tmp_in};

const FRAME_LEN: usize = 42;
const TAU0_S: f64 = 0.004;

fn siu8_path() -> String {
    fixtures()
        .join("captures/siu8_stand_5min_seed1.siu8")
        .to_str()
        .expect("utf-8")
        .to_string()
}

fn signal(child: &Child, sig: &str) {
    let ok = std::process::Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(ok.success());
}

/// Waits for the child at most `limit`; its exit status and the time it took.
fn wait_at_most(child: &mut Child, limit: Duration) -> (Option<i32>, Duration) {
    let t0 = Instant::now();
    loop {
        if let Some(s) = child.try_wait().expect("try_wait") {
            return (s.code(), t0.elapsed());
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            panic!("allanscope did not end within {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// One SIGINT to a run whose standard output is not read: it waits out the writer's grace
/// (3 s without progress), then exits 1 with a message naming `what` and "not being read".
fn ends_after_the_grace(child: &mut Child, rx: &mpsc::Receiver<String>, what: &str) {
    signal(child, "-INT");
    let (code, took) = wait_at_most(child, Duration::from_secs(15));
    assert_eq!(code, Some(1));
    assert!(
        took >= Duration::from_millis(2900) && took < Duration::from_secs(6),
        "{took:?}"
    );
    std::thread::sleep(Duration::from_millis(100));
    let err: Vec<String> = rx.try_iter().collect();
    assert!(
        err.iter()
            .any(|l| l.contains(what) && l.contains("not being read")),
        "{err:?}"
    );
}

/// Standard error lines, forwarded to a channel.
fn stderr_lines(child: &mut Child) -> mpsc::Receiver<String> {
    let err = BufReader::new(child.stderr.take().expect("stderr"));
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for l in err.lines().map_while(Result::ok) {
            let _ = tx.send(l);
        }
    });
    rx
}

/// Spawns `cmd` logging at `info`, standard output to `stdout`, standard error forwarded to the
/// channel returned.
fn spawn_logged(cmd: &mut std::process::Command, stdout: Stdio) -> (Child, mpsc::Receiver<String>) {
    let mut child = cmd
        .env("ALLANSCOPE_LOG", "info")
        .stdout(stdout)
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let rx = stderr_lines(&mut child);
    (child, rx)
}

/// Everything written to one of the child's pipes (`child.stdout.take()` or
/// `child.stderr.take()`), until the child closes it.
fn read_pipe(pipe: Option<impl Read>) -> String {
    let mut text = String::new();
    pipe.expect("a piped stream")
        .read_to_string(&mut text)
        .expect("read");
    text
}

/// How many final records of the `types` there are.
fn finals(recs: &[serde_json::Value], types: &[&str]) -> usize {
    recs.iter()
        .filter(|r| types.iter().any(|t| r["type"] == *t) && r["final"] == true)
        .count()
}

fn wait_for_line(rx: &mpsc::Receiver<String>, what: &str) -> Vec<String> {
    let mut seen = Vec::new();
    let t0 = Instant::now();
    while t0.elapsed() < Duration::from_secs(30) {
        if let Ok(l) = rx.recv_timeout(Duration::from_millis(100)) {
            let hit = l.contains(what);
            seen.push(l);
            if hit {
                return seen;
            }
        }
    }
    panic!("no `{what}` on standard error: {seen:?}");
}

/// The interim `t_data` values of g1's avar curve, and the record count, of a replay whose
/// consumer starts reading only after `pause`.
fn replay_interims(pause: Duration) -> (Vec<f64>, usize) {
    let mut child = exe()
        .args(["analyze", &siu8_path(), "--format", "siu8", "--every", "10"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    std::thread::sleep(pause);
    let text = read_pipe(child.stdout.take());
    assert!(child.wait().expect("wait").success());
    let recs = parse_lines(text.as_bytes());
    let t = recs
        .iter()
        .filter(|r| {
            r["type"] == "curve"
                && r["channel"] == "g1"
                && r["stat"] == "avar"
                && r["final"] == false
        })
        .map(|r| r["t_data"].as_f64().expect("t_data"))
        .collect();
    let s = recs.last().expect("records");
    assert_eq!(s["type"], "summary");
    assert_eq!(s["read_to_end"], true);
    (t, recs.len())
}

#[test]
fn a_replay_writes_every_interim_record_whatever_the_consumer() {
    // 300 s of data, an interim set every 10 data-seconds.
    let want: Vec<f64> = (1..=30).map(|k| 10.0 * k as f64).collect();
    let (slow, n_slow) = replay_interims(Duration::from_millis(1000));
    let (fast, n_fast) = replay_interims(Duration::ZERO);
    assert_eq!(slow, want);
    assert_eq!(fast, want);
    // 30 sets of 8 channels x 3 statistics + 8 fits, then 32 finals, health and summary.
    assert_eq!(n_slow, 30 * 32 + 34);
    assert_eq!(n_fast, n_slow);
}

#[test]
fn a_replay_stopped_by_sigint_says_so_and_exits_1() {
    let out = tmp_in("stop-replay", "out.jsonl");
    let _ = std::fs::remove_file(&out);
    let mut child = exe()
        .args([
            "analyze",
            &siu8_path(),
            "--format",
            "siu8",
            "--pace",
            "realtime",
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    let rx = stderr_lines(&mut child);
    std::thread::sleep(Duration::from_millis(1500));
    signal(&child, "-INT");
    // The replay had about 298 s of real time left: it must stop within seconds. The bound is
    // wide because the end of the run (eight channels' fits) takes seconds on a loaded host.
    let (code, took) = wait_at_most(&mut child, Duration::from_secs(30));
    assert_eq!(code, Some(1));
    assert!(took < Duration::from_secs(15), "{took:?}");
    let err: Vec<String> = rx.try_iter().collect();
    assert!(
        err.iter()
            .any(|l| l.contains("stopped by SIGINT before the end")),
        "{err:?}"
    );
    let recs = records_of(&out);
    let s = recs.last().unwrap();
    assert_eq!(s["type"], "summary");
    assert_eq!(s["read_to_end"], false);
    assert_eq!(s["stopped_by"], "SIGINT");
    // About 1.5 s of the 300 s were read in real time, every frame of it analysed.
    let t = s["t_data"].as_f64().unwrap();
    assert!(t > 0.5 && t < 10.0, "t_data {t}");
    let h = last_of(&recs, "health");
    assert_eq!(h["frames"].as_f64().unwrap() * TAU0_S, t);
    assert_eq!(finals(&recs, &["curve"]), 24);
}

/// A live listener with `--every 0.05` fed 10 s of frames over UDP; standard output piped and
/// never read, `--out` when given.
fn stalled_listener(out: Option<&str>) -> (Child, mpsc::Receiver<String>) {
    let port = free_udp_port();
    let mut args = vec![
        "listen".to_string(),
        "--udp".into(),
        format!("127.0.0.1:{port}"),
        "--format".into(),
        "siu8".into(),
        "--every".into(),
        "0.05".into(),
    ];
    if let Some(o) = out {
        args.extend(["--out".into(), o.into()]);
    }
    let (child, rx) = spawn_logged(exe().args(&args), Stdio::piped());
    wait_for_line(&rx, "listening on udp");
    let bytes = std::fs::read(siu8_path()).unwrap();
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    for d in bytes[..2500 * FRAME_LEN].chunks(5 * FRAME_LEN) {
        sock.send_to(d, ("127.0.0.1", port)).unwrap();
        std::thread::sleep(Duration::from_micros(300));
    }
    // Interim sets every 50 ms fill the pipe (64 KiB) long before this.
    std::thread::sleep(Duration::from_millis(1000));
    (child, rx)
}

#[test]
fn sigint_ends_a_run_whose_output_is_not_read() {
    // One SIGINT: the writer's grace (3 s without progress), then exit 1 naming standard output.
    let (mut child, rx) = stalled_listener(None);
    ends_after_the_grace(&mut child, &rx, "writing the JSON lines to standard output");
    drop(child);

    // Two SIGINTs: no grace after the second.
    let (mut child, _rx) = stalled_listener(None);
    signal(&child, "-INT");
    std::thread::sleep(Duration::from_millis(300));
    signal(&child, "-INT");
    let (code, took) = wait_at_most(&mut child, Duration::from_secs(15));
    assert_eq!(code, Some(1));
    assert!(took < Duration::from_millis(1500), "{took:?}");

    // With --out, the final records are in the file, and the run ends at once with 0.
    let out = tmp_in("stop-live", "out.jsonl");
    let _ = std::fs::remove_file(&out);
    let (mut child, _rx) = stalled_listener(Some(out.to_str().unwrap()));
    signal(&child, "-INT");
    let (code, took) = wait_at_most(&mut child, Duration::from_secs(15));
    assert_eq!(code, Some(0));
    assert!(took < Duration::from_secs(2), "{took:?}");
    let recs = records_of(&out);
    assert_eq!(finals(&recs, &["curve", "fit"]), 32);
    let h = last_of(&recs, "health");
    assert_eq!(h["frames"], 2500);
    let s = recs.last().unwrap();
    assert_eq!(s["stopped_by"], "SIGINT");
    assert_eq!(s["t_data"], 2500.0 * TAU0_S);
}

/// A replay (`analyze` at full speed, an interim set every 50 ms of data) whose standard output
/// is piped and not read: back-pressure holds the analysis once the pipe is full.
fn stalled_replay() -> (Child, mpsc::Receiver<String>) {
    let (child, rx) = spawn_logged(
        exe().args([
            "analyze",
            &siu8_path(),
            "--format",
            "siu8",
            "--every",
            "0.05",
        ]),
        Stdio::piped(),
    );
    // 32 records of ~1 KB per interim set: the 64 KiB pipe is full after a few sets, long
    // before this (the whole replay at full speed takes about a second).
    std::thread::sleep(Duration::from_millis(1000));
    (child, rx)
}

#[test]
fn sigint_ends_a_replay_held_by_back_pressure() {
    // Never read: the grace (3 s without progress), then exit 1 naming standard output.
    let (mut child, rx) = stalled_replay();
    assert!(child.try_wait().expect("try_wait").is_none(), "ended early");
    ends_after_the_grace(&mut child, &rx, "standard output");

    // Read again after the signal: the back-pressure is lifted, the final records of the data
    // read so far follow at once, and the summary says the replay did not reach its end.
    let (mut child, _rx) = stalled_replay();
    signal(&child, "-INT");
    let t0 = Instant::now();
    let text = read_pipe(child.stdout.take());
    let (code, _) = wait_at_most(&mut child, Duration::from_secs(10));
    assert!(t0.elapsed() < Duration::from_secs(2), "{:?}", t0.elapsed());
    assert_eq!(code, Some(1));
    let recs = parse_lines(text.as_bytes());
    let s = recs.last().expect("records");
    assert_eq!(s["type"], "summary");
    assert_eq!(s["read_to_end"], false);
    assert_eq!(s["stopped_by"], "SIGINT");
    let t = s["t_data"].as_f64().expect("t_data");
    assert!(t > 0.0 && t < 300.0, "t_data {t}");
    // The finals describe every frame the analysis took: health frames x tau0 = t_data (to
    // the rounding of t_data's own sum).
    let h = last_of(&recs, "health");
    let frames_s = h["frames"].as_f64().unwrap() * TAU0_S;
    assert!(
        (frames_s - t).abs() <= 1e-9 * t,
        "{frames_s} s of frames, t_data {t}"
    );
    let finals: Vec<&serde_json::Value> = recs
        .iter()
        .filter(|r| r["type"] == "curve" && r["final"] == true)
        .collect();
    assert_eq!(finals.len(), 24);
    assert!(finals.iter().all(|r| r["t_data"].as_f64() == Some(t)));
}

/// The records of `--out`, parsed.
fn records_of(out: &std::path::Path) -> Vec<serde_json::Value> {
    std::fs::read_to_string(out)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn a_signal_ends_a_listener_on_a_quiet_udp_port_at_once() {
    for sig in ["-INT", "-TERM"] {
        let port = free_udp_port();
        let out = tmp_in("stop-quiet-udp", "out.jsonl");
        let _ = std::fs::remove_file(&out);
        let (mut child, rx) = spawn_logged(
            exe()
                .args(["listen", "--udp", &format!("127.0.0.1:{port}")])
                .args(["--format", "siu8", "--every", "1", "--out"])
                .arg(&out),
            Stdio::null(),
        );
        wait_for_line(&rx, "listening on udp");
        // Nothing is ever sent.
        std::thread::sleep(Duration::from_millis(300));
        signal(&child, sig);
        let (code, took) = wait_at_most(&mut child, Duration::from_secs(10));
        assert_eq!(code, Some(0), "{sig}");
        assert!(took < Duration::from_secs(2), "{sig}: {took:?}");
        // The final records (empty curves: no data), health with nothing received, summary.
        let recs = records_of(&out);
        assert_eq!(finals(&recs, &["curve"]), 24, "{sig}");
        let h = last_of(&recs, "health");
        assert_eq!(h["frames"], 0);
        assert_eq!(h["bytes_in"], 0);
        let s = recs.last().unwrap();
        assert_eq!(s["type"], "summary");
        assert_eq!(
            s["stopped_by"],
            if sig == "-INT" { "SIGINT" } else { "SIGTERM" }
        );
        assert_eq!(s["t_data"], 0.0);
    }
}

#[test]
fn sigint_ends_a_serial_listener_on_a_pseudo_terminal() {
    use tokio::io::AsyncWriteExt;
    use tokio_serial::SerialPort;
    const FRAMES: usize = 2500;
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .expect("runtime");
    let (mut master, slave) = rt
        .block_on(async { tokio_serial::SerialStream::pair() })
        .expect("pseudo-terminal pair");
    let port = slave.name().expect("pty name");
    let out = tmp_in("stop-serial", "out.jsonl");
    let _ = std::fs::remove_file(&out);
    let (mut child, rx) = spawn_logged(
        exe()
            .args([
                "listen", "--serial", &port, "--format", "siu8", "--every", "1",
            ])
            .arg("--out")
            .arg(&out),
        Stdio::null(),
    );
    wait_for_line(&rx, "reading serial port");
    // 10 s of frames, then the line stays quiet (a unit that stopped sending).
    let bytes = std::fs::read(siu8_path()).unwrap();
    rt.block_on(async {
        for chunk in bytes[..FRAMES * FRAME_LEN].chunks(4096) {
            master.write_all(chunk).await.expect("write pty");
        }
        master.flush().await.expect("flush pty");
    });
    std::thread::sleep(Duration::from_millis(500));
    signal(&child, "-INT");
    let (code, took) = wait_at_most(&mut child, Duration::from_secs(10));
    assert_eq!(code, Some(0));
    assert!(took < Duration::from_secs(2), "{took:?}");
    drop(slave);
    let recs = records_of(&out);
    let h = last_of(&recs, "health");
    assert_eq!(h["frames"], FRAMES as u64);
    assert_eq!(h["missing"], 0);
    assert_eq!(finals(&recs, &["curve", "fit"]), 32);
    let s = recs.last().unwrap();
    assert_eq!(s["stopped_by"], "SIGINT");
    assert_eq!(s["t_data"], FRAMES as f64 * TAU0_S);
}

/// A FIFO made in a fresh temporary directory.
#[cfg(unix)]
fn fifo(name: &str) -> std::path::PathBuf {
    let fifo = tmp_in(name, "fifo");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .expect("mkfifo");
    assert!(made.success());
    fifo
}

#[cfg(unix)]
#[test]
fn the_first_sigint_ends_a_run_waiting_to_open_its_fifo() {
    for (format, dir) in [(None, "stop-fifo-text"), (Some("siu8"), "stop-fifo-frames")] {
        let fifo = fifo(dir);
        let mut args = vec!["analyze", fifo.to_str().expect("utf-8"), "--tau0", "1"];
        if let Some(f) = format {
            args.extend(["--format", f]);
        }
        let mut child = exe()
            .args(&args)
            .env("ALLANSCOPE_LOG", "warn")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn");
        std::thread::sleep(Duration::from_millis(500));
        signal(&child, "-INT");
        let (code, took) = wait_at_most(&mut child, Duration::from_secs(15));
        let err = read_pipe(child.stderr.take());
        assert_eq!(code, Some(1), "{format:?}: {err}");
        assert!(took < Duration::from_secs(2), "{format:?}: {took:?}");
        assert!(
            err.contains("stopped by SIGINT before the pipe delivered any data"),
            "{format:?}: {err}"
        );
        assert!(!err.contains("SIGINT twice"), "{format:?}: {err}");
    }
}

#[cfg(unix)]
#[test]
fn a_second_sigint_ends_a_run_blocked_reading_an_idle_fifo() {
    let fifo = fifo("stop-fifo-idle");
    let mut child = exe()
        .args(["analyze", fifo.to_str().expect("utf-8"), "--tau0", "1"])
        .env("ALLANSCOPE_LOG", "warn")
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    // The writer opens the FIFO (this returns once the run has opened it too) and then sends
    // nothing: the run waits in read(2), which no token reaches.
    let writer = std::fs::OpenOptions::new()
        .write(true)
        .open(&fifo)
        .expect("open the FIFO for writing");
    std::thread::sleep(Duration::from_millis(500));
    signal(&child, "-INT");
    std::thread::sleep(Duration::from_millis(500));
    assert!(
        child.try_wait().expect("wait").is_none(),
        "the run ended on the first signal although its read cannot be interrupted"
    );
    signal(&child, "-INT");
    let (code, took) = wait_at_most(&mut child, Duration::from_secs(15));
    drop(writer);
    assert_eq!(code, Some(1));
    assert!(took < Duration::from_secs(8), "{took:?}");
    let err = read_pipe(child.stderr.take());
    assert!(err.contains("SIGINT twice"), "{err}");
}
