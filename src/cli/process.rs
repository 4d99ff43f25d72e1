//! What the binary owns while a command runs, which the library leaves to its caller: SIGINT and
//! SIGTERM (Ctrl-C off Unix) and the end of `--duration` stopping the run, the progress bar of a
//! file replay, and the crash of the `--abort-after-frames` test hook.
//!
//! Once a signal handler is installed the default action (ending the process) is gone, so a
//! signal that arrives while the run is finishing (the analysis waiting for room in a replay's
//! record queue, the writer blocked on a consumer that stopped reading) must still be acted on.
//! A [`SignalWatch`] listens on a thread of its own from the start of the command to its end:
//!
//! - the first signal cancels the run's shutdown token (the library's source stops reading) and
//!   lifts the record queue's back-pressure ([`RecordQueue::release`]); the final records are
//!   then written if the output takes them within [`STOP_GRACE`] of silence;
//! - a second signal stops waiting for the output at once ([`SignalWatch::grace`], handed to
//!   [`allanscope::pipeline::RecordWriter::finish_within`]);
//! - a run still waiting to open a FIFO that no writer has opened (a blocking `open(2)`, which
//!   no token reaches) is let through by the first signal: the watch opens each input named with
//!   [`SignalWatch::release_fifos`] for writing and closes it again, so the run's open returns,
//!   its first read sees the end of the input and the run ends as stopped;
//! - the end of `--duration` cancels the token as a first signal would, and the output is then
//!   waited for without a limit (nothing asked the command to hurry).

use std::sync::atomic::{AtomicBool, AtomicU32, Ordering};
use std::sync::Arc;
use std::time::Duration;

use allanscope::pipeline::{CrashHook, RecordQueue};
use allanscope::source::Progress;
use tokio_util::sync::CancellationToken;

/// How long the writer may go without writing anything, once a signal asked the run to stop,
/// before the command gives up on its output (a consumer that no longer reads).
pub const STOP_GRACE: Duration = Duration::from_secs(3);

/// The signals received so far; see the module documentation.
#[derive(Debug, Clone, Default)]
pub struct SignalWatch {
    count: Arc<AtomicU32>,
    fifos: Arc<std::sync::Mutex<Vec<std::path::PathBuf>>>,
}

impl SignalWatch {
    /// Starts listening: each signal cancels `token`, lifts `queue`'s back-pressure and is
    /// recorded in `progress` (the `summary` record's `stopped_by`); after `duration` (from
    /// now) the token is cancelled and `--duration` recorded. The signals are caught from the
    /// moment this returns.
    pub fn start(
        token: CancellationToken,
        queue: RecordQueue,
        progress: Arc<Progress>,
        duration: Option<Duration>,
    ) -> SignalWatch {
        let watch = SignalWatch::default();
        let count = watch.count.clone();
        let fifos = watch.fifos.clone();
        let (ready_tx, ready_rx) = std::sync::mpsc::channel::<()>();
        let spawned = std::thread::Builder::new()
            .name("allanscope-signals".into())
            .spawn(move || {
                let rt = match tokio::runtime::Builder::new_current_thread()
                    .enable_all()
                    .build()
                {
                    Ok(rt) => rt,
                    Err(e) => {
                        let _ = ready_tx.send(());
                        return tracing::warn!("cannot watch SIGINT/SIGTERM: {e}");
                    }
                };
                rt.block_on(async move {
                    let mut signals = Signals::register();
                    let _ = ready_tx.send(());
                    let timer = async {
                        match duration {
                            Some(d) => tokio::time::sleep(d).await,
                            None => std::future::pending().await,
                        }
                    };
                    tokio::pin!(timer);
                    let mut timed_out = false;
                    loop {
                        let name = tokio::select! {
                            _ = &mut timer, if !timed_out => {
                                timed_out = true;
                                tracing::info!("--duration reached; finishing");
                                progress.set_stopped_by("--duration");
                                token.cancel();
                                continue;
                            }
                            name = signals.recv() => name,
                        };
                        let n = count.fetch_add(1, Ordering::SeqCst) + 1;
                        progress.set_stopped_by(name);
                        token.cancel();
                        queue.release();
                        if n == 1 {
                            tracing::info!(
                                "{name}; finishing (a second signal stops waiting for the output)"
                            );
                            let names = fifos.lock().map(|f| f.clone()).unwrap_or_default();
                            release_fifos(&names);
                        } else {
                            tracing::warn!("{name} again; not waiting for the output any longer");
                            if n == 2 {
                                exit_unless_ended(name);
                            }
                        }
                    }
                });
            });
        match spawned {
            Ok(_) => {
                let _ = ready_rx.recv();
            }
            Err(e) => tracing::warn!("cannot watch SIGINT/SIGTERM: {e}"),
        }
        watch
    }

    /// Names the command's input files, so that the first signal can let through a run blocked
    /// opening one of them that is a FIFO with no writer yet (see the module documentation).
    /// Inputs that are not FIFOs are left alone.
    pub fn release_fifos<P: AsRef<std::path::Path>>(&self, inputs: &[P]) {
        if let Ok(mut f) = self.fifos.lock() {
            f.extend(inputs.iter().map(|p| p.as_ref().to_path_buf()));
        }
    }

    /// Signals received so far.
    pub fn count(&self) -> u32 {
        self.count.load(Ordering::SeqCst)
    }

    /// How long the output may stay silent before the command gives up on it: unbounded while
    /// no signal came, [`STOP_GRACE`] after one, nothing after two.
    pub fn grace(&self) -> Option<Duration> {
        match self.count() {
            0 => None,
            1 => Some(STOP_GRACE),
            _ => Some(Duration::ZERO),
        }
    }
}

/// Opens each of `inputs` that is a FIFO for writing and closes it again, each on a thread of its
/// own: a reader blocked opening it returns at once and then reads the end of the input. Where
/// no reader is waiting the open blocks that thread alone, which ends with the process.
fn release_fifos(inputs: &[std::path::PathBuf]) {
    #[cfg(unix)]
    for p in inputs {
        use std::os::unix::fs::FileTypeExt;
        let is_fifo = std::fs::metadata(p).is_ok_and(|m| m.file_type().is_fifo());
        if !is_fifo {
            continue;
        }
        let p = p.clone();
        let _ = std::thread::Builder::new()
            .name("allanscope-fifo-release".into())
            .spawn(move || drop(std::fs::OpenOptions::new().write(true).open(&p)));
    }
    #[cfg(not(unix))]
    let _ = inputs;
}

/// How long the command may go on after a second signal before the process exits anyway.
pub const FORCE_EXIT_AFTER: Duration = Duration::from_secs(5);

/// After a second signal: exits the process with status 1 unless the command has ended within
/// [`FORCE_EXIT_AFTER`]. A thread blocked in a system call, such as opening a FIFO no writer
/// has opened yet or reading a terminal, cannot see the shutdown token; without this the signals
/// would be ignored (their default action is gone once they are caught).
fn exit_unless_ended(name: &'static str) {
    let _ = std::thread::Builder::new()
        .name("allanscope-force-exit".into())
        .spawn(move || {
            std::thread::sleep(FORCE_EXIT_AFTER);
            eprintln!(
                "allanscope: {name} twice and the command has not ended in {} s (blocked on its \
                 input or output?); exiting, the records written so far are kept",
                FORCE_EXIT_AFTER.as_secs()
            );
            std::process::exit(1);
        });
}

/// The signals that stop a run: SIGINT and SIGTERM.
#[cfg(unix)]
struct Signals {
    int: Option<tokio::signal::unix::Signal>,
    term: Option<tokio::signal::unix::Signal>,
}

#[cfg(unix)]
impl Signals {
    fn register() -> Signals {
        use tokio::signal::unix::{signal, SignalKind};
        match (
            signal(SignalKind::interrupt()),
            signal(SignalKind::terminate()),
        ) {
            (Ok(int), Ok(term)) => Signals {
                int: Some(int),
                term: Some(term),
            },
            _ => {
                tracing::warn!("cannot watch SIGINT/SIGTERM");
                Signals {
                    int: None,
                    term: None,
                }
            }
        }
    }

    /// The next signal's name (never, when they could not be watched).
    async fn recv(&mut self) -> &'static str {
        match (&mut self.int, &mut self.term) {
            (Some(int), Some(term)) => tokio::select! {
                _ = int.recv() => "SIGINT",
                _ = term.recv() => "SIGTERM",
            },
            _ => std::future::pending().await,
        }
    }
}

/// Off Unix: Ctrl-C.
#[cfg(not(unix))]
struct Signals;

#[cfg(not(unix))]
impl Signals {
    fn register() -> Signals {
        Signals
    }

    async fn recv(&mut self) -> &'static str {
        match tokio::signal::ctrl_c().await {
            Ok(()) => "Ctrl-C",
            Err(_) => std::future::pending().await,
        }
    }
}

/// A progress bar on standard error over a file replay, drawn from the run's [`Progress`]
/// counters by a thread of its own; cleared when dropped.
pub struct ProgressBar {
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl ProgressBar {
    /// Starts drawing once the file's length is known, 4 times a second.
    pub fn start(progress: Arc<Progress>) -> ProgressBar {
        let stop = Arc::new(AtomicBool::new(false));
        let draw = {
            let stop = stop.clone();
            move || {
                let mut bar: Option<indicatif::ProgressBar> = None;
                loop {
                    let done = stop.load(Ordering::Relaxed);
                    if let Some((pos, len)) = progress.file_position() {
                        let b = bar.get_or_insert_with(|| new_bar(len));
                        b.set_length(len);
                        b.set_position(pos.min(len));
                    }
                    if done {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(250));
                }
                if let Some(b) = bar {
                    b.finish_and_clear();
                }
            }
        };
        let thread = std::thread::Builder::new()
            .name("allanscope-progress".into())
            .spawn(draw)
            .ok();
        ProgressBar { stop, thread }
    }
}

fn new_bar(len: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::with_draw_target(
        Some(len),
        indicatif::ProgressDrawTarget::stderr_with_hz(4),
    );
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{bar:40} {bytes}/{total_bytes} {bytes_per_sec} eta {eta}",
    ) {
        bar.set_style(style);
    }
    bar
}

impl Drop for ProgressBar {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The `--abort-after-frames` test hook: the process aborts as a crash would (no final records,
/// no flush), once the library reaches the crash point with a checkpoint on disk.
pub fn abort_hook(after_frames: Option<u64>) -> Option<CrashHook> {
    after_frames?;
    Some(CrashHook(Arc::new(|| {
        eprintln!("allanscope: --abort-after-frames reached: aborting (test hook)");
        std::process::abort();
    })))
}
