//! SIGINT and SIGTERM for the whole of a command, not only while a source is read.
//!
//! Once a signal handler is installed the default action (ending the process) is gone, so a
//! signal that arrives while the run is finishing (the analysis waiting for room in a replay's
//! record queue, the writer blocked on a consumer that stopped reading) must still be acted on.
//! A [`SignalWatch`] listens on a thread of its own from the start of the command to its end:
//!
//! - the first signal fires the run's shutdown token (the source stops reading) and lifts the
//!   record queue's back-pressure ([`RecordQueue::release`]); the final records are then written
//!   if the output takes them within [`STOP_GRACE`] of silence;
//! - a second signal stops waiting for the output at once.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;
use std::time::Duration;

use tokio_util::sync::CancellationToken;

use super::RecordQueue;
use crate::source::Progress;

/// How long the writer may go without writing anything, once a signal asked the run to stop,
/// before the command gives up on its output (a consumer that no longer reads).
pub const STOP_GRACE: Duration = Duration::from_secs(3);

/// The signals received so far; see the module documentation.
#[derive(Debug, Clone, Default)]
pub struct SignalWatch {
    count: Arc<AtomicU32>,
}

impl SignalWatch {
    /// Starts listening: each signal fires `token`, lifts `queue`'s back-pressure and is
    /// recorded in `progress` (the `summary` record's `stopped_by`).
    pub fn start(
        token: CancellationToken,
        queue: RecordQueue,
        progress: Arc<Progress>,
    ) -> SignalWatch {
        let watch = SignalWatch::default();
        let count = watch.count.clone();
        let spawned = std::thread::Builder::new()
            .name("allanscope-signals".into())
            .spawn(move || {
                let rt = match tokio::runtime::Builder::new_current_thread()
                    .enable_all()
                    .build()
                {
                    Ok(rt) => rt,
                    Err(e) => return tracing::warn!("cannot watch SIGINT/SIGTERM: {e}"),
                };
                rt.block_on(async move {
                    use tokio::signal::unix::{signal, SignalKind};
                    let (Ok(mut int), Ok(mut term)) = (
                        signal(SignalKind::interrupt()),
                        signal(SignalKind::terminate()),
                    ) else {
                        return tracing::warn!("cannot watch SIGINT/SIGTERM");
                    };
                    loop {
                        let name = tokio::select! {
                            _ = int.recv() => "SIGINT",
                            _ = term.recv() => "SIGTERM",
                        };
                        let n = count.fetch_add(1, Ordering::SeqCst) + 1;
                        progress.set_stopped_by(name);
                        token.cancel();
                        queue.release();
                        if n == 1 {
                            tracing::info!(
                                "{name}; finishing (a second signal stops waiting for the output)"
                            );
                        } else {
                            tracing::warn!("{name} again; not waiting for the output any longer");
                        }
                    }
                });
            });
        if let Err(e) = spawned {
            tracing::warn!("cannot watch SIGINT/SIGTERM: {e}");
        }
        // The handlers are installed by the thread: wait briefly so a signal sent right after
        // the command starts is not lost to the default action.
        std::thread::sleep(Duration::from_millis(5));
        watch
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
