//! A serial port that disappears and comes back (and a UDP stream that goes silent): the outage
//! is recorded as a gap sized by the frame counter and the wall time together.
//!
//! The test plays a KVH 1750 (kvh1750 frames at 1000 Hz, counter modulo 128) in real time into
//! a pseudo-terminal reached through a symlink, the way a stand reaches a USB adapter through a
//! udev name. After 0.5 s it closes the terminal (the port disappears; the unit keeps running
//! and its frames are lost), opens a new one behind the same symlink, and once the listener has
//! reopened it goes on with the frame that is due by then. The outage spans several hundred
//! frames, more than the counter's modulus, so the counter alone cannot size it: the health
//! record must show exactly the frames the unit produced while the port was gone.
//!
//! A play is played again when the host stalled it: the writer, the watch thread, or the
//! delivery of a phase's last frames to the listener (see [`WRITER_STALL`]); the stream as
//! received is then not a unit's.

use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

use crate::common::pipeline::*;
use allanscope::frame::FrameDescriptor;
use allanscope::pipeline::RunControl;
use allanscope::source::SourceSpec;
use tokio::io::AsyncWriteExt;
use tokio_serial::SerialPort;

const FRAME_LEN: usize = 36;
const RATE_HZ: f64 = 1000.0;
/// Frames before and after the outage.
const PHASE_FRAMES: usize = 500;
/// The port is gone for at least this long (the listener's backoff adds to it).
const OUTAGE: Duration = Duration::from_millis(300);
const TIMEOUT: Duration = Duration::from_secs(30);

fn wait_until(what: &str, f: impl Fn() -> bool) {
    let t0 = Instant::now();
    while !f() {
        assert!(t0.elapsed() < TIMEOUT, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// A pause of the test's own writer longer than this (the host did not run it) makes the
/// played stream unlike a unit's: the frames of the pause leave in one burst. The listener
/// reads such a burst as a backlog, not a silence, also when the pseudo-terminal hands it over
/// in pieces (since session 25: the pieces' reads are held together); the scenario is still
/// played again, as its stream is not a unit's. A pause
/// shorter than this cannot: it is below the 64 ms silence (half of kvh1750's counter period at
/// 1 kHz) that makes an outage.
///
/// The same bound holds for the **delivery** of a phase's last frames (see
/// [`phase_delivered`]): frames that reach the listener late in the middle of a phase come with
/// the frames written meanwhile, a backlog; at the end of a phase no frame follows them, and a
/// silence they end is an outage by the listener's rule.
const WRITER_STALL: Duration = Duration::from_millis(50);
/// Plays of a scenario before the host is declared too loaded to run it.
const ATTEMPTS: u32 = 6;
/// A phase whose frames the listener has not all decoded this long after they were written is
/// played again (its last read may have been cut by a silence the listener counted, so the
/// count may never be reached).
const DELIVERY_DEADLINE: Duration = Duration::from_secs(5);

/// A thread that sleeps 2 ms at a time and keeps its longest oversleep: how long the host left
/// this thread unscheduled. It sees a stall of the whole process (or of both cores); a stall of
/// one core, or of one thread (the listener's among them), it may not see, and it does not see
/// the kernel's work that moves a pseudo-terminal's bytes to its reader: those show in
/// [`phase_delivered`].
struct HostWatch {
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
    thread: std::thread::JoinHandle<Duration>,
}

impl HostWatch {
    fn start() -> HostWatch {
        let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
        let flag = stop.clone();
        let thread = std::thread::spawn(move || {
            let tick = Duration::from_millis(2);
            let mut worst = Duration::ZERO;
            while !flag.load(Ordering::Relaxed) {
                let t = Instant::now();
                std::thread::sleep(tick);
                worst = worst.max(t.elapsed().saturating_sub(tick));
            }
            worst
        });
        HostWatch { stop, thread }
    }

    /// The longest oversleep since [`HostWatch::start`].
    fn stop(self) -> Duration {
        self.stop.store(true, Ordering::Relaxed);
        self.thread.join().unwrap_or(Duration::MAX)
    }
}

/// Writes frames `from..to` of `bytes` at their real-time instants after `t0`. Returns the
/// longest pause between two writes.
async fn play(
    port: &mut tokio_serial::SerialStream,
    bytes: &[u8],
    t0: Instant,
    from: usize,
    to: usize,
) -> Duration {
    let mut next = from;
    let mut last_write = Instant::now();
    let mut longest = Duration::ZERO;
    while next < to {
        let due = ((t0.elapsed().as_secs_f64() * RATE_HZ) as usize).min(to);
        if due > next {
            longest = longest.max(last_write.elapsed());
            AsyncWriteExt::write_all(port, &bytes[next * FRAME_LEN..due * FRAME_LEN])
                .await
                .expect("write pty");
            last_write = Instant::now();
            next = due;
        }
        tokio::time::sleep(Duration::from_millis(2)).await;
    }
    longest
}

/// Waits until the listener has decoded `frames` frames in all, the last of them written at
/// `written`: how long after that it had them, or `None` when it had not after
/// [`DELIVERY_DEADLINE`].
///
/// Longer than [`WRITER_STALL`], the phase's last frames reached the listener late (measured
/// under load in the full test binary: 155 ms after the writer's last write, with the
/// listener's idle timer running on time, i.e. in the kernel between the pseudo-terminal's two
/// ends; and 365 ms and 1.5 s in which the listener's own thread did not run, while
/// [`HostWatch`] saw at most 41 ms), or the listener held its last read as the possible end of
/// a silence, which only the source's idle report (50 ms) decides when no frame follows.
/// In the middle of a phase such a delay is harmless: the frames written meanwhile come with
/// the late ones, a backlog. At the end of a phase the writer stops, so the late frames bound
/// the silence before them only by their own number: 6 frames 158 ms after the frame before
/// them are an outage of 128 frames to the listener, as they would be on a stand (a unit that
/// stops right after a silence), and the scenario is played again.
fn phase_delivered(ctl: &RunControl, frames: u64, written: Instant) -> Option<Duration> {
    while ctl.progress.frames() < frames {
        if written.elapsed() > DELIVERY_DEADLINE {
            return None;
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    Some(written.elapsed())
}

#[test]
fn outage_longer_than_the_counter_is_sized_by_time() {
    let mut replays = Vec::new();
    for attempt in 1..=ATTEMPTS {
        match outage_scenario(attempt) {
            Ok((recs, lost)) => return check_outage(&recs, lost),
            Err(why) => {
                eprintln!("attempt {attempt}: {why}; playing again");
                replays.push(format!("attempt {attempt}: {why}"));
            }
        }
    }
    panic!(
        "the host stalled the scenario in all {ATTEMPTS} attempts:\n{}",
        replays.join("\n")
    );
}

/// What the listener must report for an outage of `lost` frames.
fn check_outage(recs: &[serde_json::Value], lost: u64) {
    eprintln!("lost {lost} frames in the outage");
    assert!(lost > 128, "the outage should exceed the counter's modulus");
    let h = last_of(recs, "health");
    assert_eq!(h["frames"], 2 * PHASE_FRAMES as u64);
    assert_eq!(h["outages"], 1);
    assert_eq!(h["outage_missing"], lost);
    assert_eq!(h["missing"], lost);
    // Data time covers the gap: (500 + lost + 500) frames of 1 ms.
    let s = last_of(recs, "summary");
    let t = s["t_data"].as_f64().expect("t_data");
    let want = (2 * PHASE_FRAMES as u64 + lost) as f64 / RATE_HZ;
    assert!((t - want).abs() < 1e-9, "t_data {t} != {want}");
    assert_eq!(s["segments"][0], 2);
}

/// Why a play's stream was not a unit's, if it was not: the writer or [`HostWatch`] paused, or
/// a phase's last frames reached the listener late ([`phase_delivered`]; `lags` in phase order).
fn stalled(pause: Duration, host: Duration, lags: &[Option<Duration>]) -> Option<String> {
    if pause > WRITER_STALL || host > WRITER_STALL {
        return Some(format!(
            "the writer paused for {pause:?}, a thread of this process for {host:?}"
        ));
    }
    for (phase, lag) in lags.iter().enumerate() {
        match lag {
            None => {
                return Some(format!(
                    "the listener had not decoded phase {}'s frames {DELIVERY_DEADLINE:?} after \
                     they were written",
                    phase + 1
                ))
            }
            Some(lag) if *lag > WRITER_STALL => {
                return Some(format!(
                    "phase {}'s last frames reached the listener {lag:?} after they were written",
                    phase + 1
                ))
            }
            Some(_) => {}
        }
    }
    None
}

/// Plays the outage once: the listener's records and the frames lost, or why the played stream
/// was not a unit's ([`stalled`]).
fn outage_scenario(attempt: u32) -> Result<(Vec<serde_json::Value>, u64), String> {
    let bytes =
        std::fs::read(fixtures().join("captures/kvh1750_stand_1min_seed1.kvh1750")).expect("kvh");
    let desc = FrameDescriptor::load("kvh1750").expect("kvh1750");
    let dir = std::env::temp_dir().join(format!(
        "allanscope-outage-{}-{attempt}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).expect("tmp");
    let link = dir.join("ttyIMU");
    let rt = tokio::runtime::Runtime::new().expect("runtime");
    let repoint = |target: &str| {
        let tmp = dir.join("ttyIMU.new");
        let _ = std::fs::remove_file(&tmp);
        std::os::unix::fs::symlink(target, &tmp).expect("symlink");
        std::fs::rename(&tmp, &link).expect("rename symlink");
    };

    let (mut master, slave) = rt
        .block_on(async { tokio_serial::SerialStream::pair() })
        .expect("pty");
    repoint(&slave.name().expect("pty name"));
    let ctl = RunControl::default();
    let watch = HostWatch::start();
    let (ctl2, desc2, link2) = (ctl.clone(), desc.clone(), link.clone());
    let listener = std::thread::spawn(move || {
        let spec = SourceSpec::Serial {
            path: link2,
            baud: 921_600,
        };
        run_to_records(spec, &desc2, &ctl2).0
    });
    std::thread::sleep(Duration::from_millis(300));

    let t0 = Instant::now();
    let mut pause = rt.block_on(play(&mut master, &bytes, t0, 0, PHASE_FRAMES));
    let lag1 = phase_delivered(&ctl, PHASE_FRAMES as u64, Instant::now());
    let mut lags = vec![lag1];
    let mut k1 = 0;
    // The port disappears.
    drop(master);
    drop(slave);
    // A late phase 1 is played again at once (its stream is decided).
    let slave = lag1.filter(|lag| *lag <= WRITER_STALL).map(|_| {
        std::thread::sleep(OUTAGE);
        let (mut master, slave) = rt
            .block_on(async { tokio_serial::SerialStream::pair() })
            .expect("pty");
        repoint(&slave.name().expect("pty name"));
        wait_until("the reconnection", || {
            ctl.progress.reconnects.load(Ordering::Relaxed) == 1
        });
        // The unit has been running all along: go on with the frame due now.
        k1 = (t0.elapsed().as_secs_f64() * RATE_HZ) as usize;
        pause = pause.max(rt.block_on(play(&mut master, &bytes, t0, k1, k1 + PHASE_FRAMES)));
        lags.push(phase_delivered(
            &ctl,
            2 * PHASE_FRAMES as u64,
            Instant::now(),
        ));
        slave
    });
    ctl.shutdown.cancel();
    let recs = listener.join().expect("listener");
    drop(slave);
    let _ = std::fs::remove_dir_all(&dir);

    let host = watch.stop();
    if let Some(why) = stalled(pause, host, &lags) {
        return Err(why);
    }
    // Frames 0..500 arrived, then k1.. : the lost ones are 500..k1.
    Ok((recs, (k1 - PHASE_FRAMES) as u64))
}

/// The same rule for a UDP stream that goes silent (the unit's Ethernet link down for a
/// while): kvh1750 frames at 1000 Hz, one per datagram; the sender stops for 400 ms while the
/// unit keeps counting, then goes on with the frame due. The silence exceeds half the counter
/// period (64 ms), so the listener sizes the gap by counter and time: the lost frames exactly.
#[test]
fn udp_silence_longer_than_the_counter_is_sized_by_time() {
    for attempt in 1..=ATTEMPTS {
        match udp_silence_scenario() {
            Some((recs, lost)) => {
                eprintln!("lost {lost} frames in the silence");
                assert!(
                    lost > 128,
                    "the silence should exceed the counter's modulus"
                );
                let h = last_of(&recs, "health");
                assert_eq!(h["frames"], 2 * PHASE_FRAMES as u64);
                assert_eq!(h["outages"], 1);
                assert_eq!(h["missing"], lost);
                assert_eq!(h["udp_late"], 0);
                return;
            }
            None => eprintln!("attempt {attempt}: the sender paused; sending again"),
        }
    }
    panic!("the test's sender paused for more than {WRITER_STALL:?} in {ATTEMPTS} attempts");
}

/// Sends the silence once: the listener's records and the frames lost, or `None` when the
/// sender itself (or the watch thread, [`HostWatch`]) paused for longer than
/// [`WRITER_STALL`] (one frame per datagram: a burst of
/// them after such a pause is a silence to the listener, as a real one would be).
fn udp_silence_scenario() -> Option<(Vec<serde_json::Value>, u64)> {
    let bytes =
        std::fs::read(fixtures().join("captures/kvh1750_stand_1min_seed1.kvh1750")).expect("kvh");
    let desc = FrameDescriptor::load("kvh1750").expect("kvh1750");
    let port = free_udp_port();
    let ctl = RunControl::default();
    let watch = HostWatch::start();
    let (ctl2, desc2) = (ctl.clone(), desc.clone());
    let listener = std::thread::spawn(move || {
        let spec = SourceSpec::Udp {
            bind: ([127, 0, 0, 1], port).into(),
        };
        run_to_records(spec, &desc2, &ctl2).0
    });
    std::thread::sleep(Duration::from_millis(200));
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").expect("bind");
    let send = |t0: Instant, from: usize, to: usize| -> Duration {
        let mut next = from;
        let mut last_send = Instant::now();
        let mut longest = Duration::ZERO;
        while next < to {
            let due = ((t0.elapsed().as_secs_f64() * RATE_HZ) as usize).min(to);
            if due > next {
                longest = longest.max(last_send.elapsed());
            }
            while next < due {
                sock.send_to(
                    &bytes[next * FRAME_LEN..(next + 1) * FRAME_LEN],
                    ("127.0.0.1", port),
                )
                .expect("send");
                next += 1;
                last_send = Instant::now();
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        longest
    };
    let t0 = Instant::now();
    let pause1 = send(t0, 0, PHASE_FRAMES);
    std::thread::sleep(Duration::from_millis(400));
    let k1 = (t0.elapsed().as_secs_f64() * RATE_HZ) as usize;
    let pause2 = send(t0, k1, k1 + PHASE_FRAMES);
    wait_until("all frames", || {
        ctl.progress.frames() == 2 * PHASE_FRAMES as u64
    });
    ctl.shutdown.cancel();
    let recs = listener.join().expect("listener");
    let host = watch.stop();
    if pause1.max(pause2).max(host) > WRITER_STALL {
        eprintln!(
            "the sender paused for {:?}, a thread of this process for {host:?}",
            pause1.max(pause2)
        );
        return None;
    }
    Some((recs, (k1 - PHASE_FRAMES) as u64))
}
