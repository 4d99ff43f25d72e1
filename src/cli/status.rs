//! The status line of a live run (`listen`, live `run`) on standard error when it is a terminal:
//! time running, frames per second, frames lost and the newest N of each channel
//! (`allanscope::sink::table::status_line`), redrawn in place twice a second, never scrolled, and
//! cleared before the final records are written. A standard error that is not a terminal (a log
//! file, a pipe) never gets it. Log lines go through [`LogWriter`], which writes them above the
//! status line (`allanscope::sink::status_area`), so the two never share a line. The line is cut
//! to the terminal's width (its size from the `console` crate; `COLUMNS` when that cannot tell).

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use allanscope::sink::metrics::Metrics;
use allanscope::sink::status_area::StatusArea;
use allanscope::source::Progress;
use tokio_util::sync::CancellationToken;

/// The terminal's last line; held while the line is drawn or cleared and while a log line is
/// written, so a log line or a table never lands in the middle of a draw.
static AREA: Mutex<StatusArea> = Mutex::new(StatusArea::new());

fn area() -> std::sync::MutexGuard<'static, StatusArea> {
    AREA.lock().unwrap_or_else(|p| p.into_inner())
}

/// Clears the status line for good (before a table is printed on the same terminal).
pub fn suspend() {
    let _ = area().suspend(&mut std::io::stderr().lock());
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

/// Terminal width for the line: the terminal's own, else `COLUMNS`, else 100 (a longer line
/// would wrap and scroll). Read at each draw, so a resized window is followed.
fn width() -> usize {
    console::Term::stderr()
        .size_checked()
        .map(|(_, cols)| cols as usize)
        .or_else(|| {
            std::env::var("COLUMNS")
                .ok()
                .and_then(|c| c.parse::<usize>().ok())
        })
        .filter(|w| *w >= 20)
        .unwrap_or(100)
}

/// The log writer of the binary (`tracing_subscriber::fmt().with_writer(LogWriter)`): each log
/// message is written to standard error in one piece, above the status line when one is shown.
pub struct LogWriter;

/// One log message, written when dropped (the formatter writes a whole event, then drops it).
pub struct LogMessage(Vec<u8>);

impl Write for LogMessage {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.0.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Drop for LogMessage {
    fn drop(&mut self) {
        if !self.0.is_empty() {
            let _ = area().log(&mut std::io::stderr().lock(), &self.0);
        }
    }
}

impl<'a> tracing_subscriber::fmt::MakeWriter<'a> for LogWriter {
    type Writer = LogMessage;
    fn make_writer(&'a self) -> LogMessage {
        LogMessage(Vec::new())
    }
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
                    let w = width();
                    let mut shown = area();
                    if shown.is_suspended() {
                        break;
                    }
                    let _ = shown.draw(&mut std::io::stderr().lock(), &line, w);
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
