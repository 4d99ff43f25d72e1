//! The status line of a live run (`listen`, live `run`) on standard error when it is a terminal:
//! time running, frames per second, frames lost and the newest N of each channel
//! (`allanscope::sink::table::status_line`), redrawn in place twice a second, never scrolled, and
//! cleared before the final records are written. A standard error that is not a terminal (a log
//! file, a pipe) never gets it.

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use allanscope::sink::metrics::Metrics;
use allanscope::source::Progress;
use tokio_util::sync::CancellationToken;

/// Set once standard output starts printing a table: the line is cleared and not drawn again.
static SUSPENDED: AtomicBool = AtomicBool::new(false);
/// Held while the line is drawn or cleared, so a table never lands in the middle of a draw.
static DRAWING: std::sync::Mutex<bool> = std::sync::Mutex::new(false);

/// Clears the status line for good (before a table is printed on the same terminal).
pub fn suspend() {
    let mut drawn = DRAWING.lock().unwrap_or_else(|p| p.into_inner());
    SUSPENDED.store(true, Ordering::SeqCst);
    if *drawn {
        let mut err = std::io::stderr().lock();
        let _ = write!(err, "\r\x1b[2K");
        let _ = err.flush();
        *drawn = false;
    }
}

/// Redraws per second.
const PERIOD: Duration = Duration::from_millis(500);

/// The drawing thread; stops and clears the line when dropped.
pub struct StatusLine {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

/// Whether a live run gets a status line: standard error is a terminal.
pub fn wanted() -> bool {
    std::io::stderr().is_terminal()
}

/// Terminal width for the line: `COLUMNS`, else 100 (a longer line would wrap and scroll).
fn width() -> usize {
    std::env::var("COLUMNS")
        .ok()
        .and_then(|c| c.parse::<usize>().ok())
        .filter(|w| *w >= 20)
        .unwrap_or(100)
}

impl StatusLine {
    /// Starts drawing from the run's counters and `metrics` (fed by the run's tap); stops by
    /// itself once the run is being stopped or its input has ended, before the final records.
    pub fn start(
        progress: Arc<Progress>,
        shutdown: CancellationToken,
        metrics: Arc<Metrics>,
    ) -> StatusLine {
        let stop = Arc::new(AtomicBool::new(false));
        let draw = {
            let stop = stop.clone();
            move || {
                let started = Instant::now();
                let (mut last_t, mut last_frames) = (started, 0u64);
                let mut rate = 0.0;
                let w = width();
                loop {
                    std::thread::sleep(PERIOD);
                    if stop.load(Ordering::Relaxed)
                        || shutdown.is_cancelled()
                        || progress.input_ended()
                    {
                        break;
                    }
                    let now = Instant::now();
                    let frames = progress.frames();
                    let dt = now.duration_since(last_t).as_secs_f64();
                    if dt > 0.0 {
                        rate = (frames - last_frames.min(frames)) as f64 / dt;
                    }
                    (last_t, last_frames) = (now, frames);
                    let latest = metrics.latest();
                    let lost = (!latest.missing.is_empty())
                        .then(|| latest.missing.iter().map(|x| x.1).sum());
                    let line = allanscope::sink::table::status_line(
                        now.duration_since(started).as_secs_f64(),
                        frames,
                        rate,
                        lost,
                        &latest.n,
                    );
                    let line: String = line.chars().take(w - 1).collect();
                    let mut drawn = DRAWING.lock().unwrap_or_else(|p| p.into_inner());
                    if SUSPENDED.load(Ordering::SeqCst) {
                        break;
                    }
                    let mut err = std::io::stderr().lock();
                    let _ = write!(err, "\r\x1b[2K{line}");
                    let _ = err.flush();
                    *drawn = true;
                }
                suspend();
            }
        };
        let thread = std::thread::Builder::new()
            .name("allanscope-status".into())
            .spawn(draw)
            .ok();
        StatusLine { stop, thread }
    }
}

impl Drop for StatusLine {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
