//! File and standard-input sources: a byte stream read in blocks of [`READ_BLOCK`], as fast as
//! the analysis takes it or paced at the data's own rate.
//!
//! A file replayed as fast as possible without `--capture` is read by [`read_file`] on a
//! blocking thread of its own, with `std::fs` straight into recycled buffers: one copy of the
//! bytes (the kernel's) and one hand-off per read. Everything else goes through the async
//! [`read_stream`] (tokio's file and standard input read on a blocking thread into a buffer of
//! their own and copy from there, and wake the source task per read).

use std::io::Read;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use bytes::{Bytes, BytesMut};
use tokio::io::{AsyncRead, AsyncReadExt};

use super::{Pace, SourceContext, SourceEvent};

/// Bytes per read: 256 KiB (6240 siu8 frames), large enough that per-read overhead (a blocking
/// task per read, wake-ups of the decode and analysis threads per chunk) is small, small enough
/// that the decode stage starts at once. 64 KiB cost a 3-hour siu8 replay about 0.03-0.05 s more
/// CPU time, a tenth of the whole (BENCHMARKS.md "Decoding at the speed of the statistics").
pub const READ_BLOCK: usize = 1 << 18;

/// Reads `r` to its end (or until shutdown), passing each block on.
pub async fn read_stream<R: AsyncRead + Unpin>(
    mut r: R,
    pace: Pace,
    ctx: &mut SourceContext,
) -> Result<()> {
    let started = Instant::now();
    let mut total: u64 = 0;
    // In realtime mode, read in blocks of about 20 ms of data so the stream stays smooth.
    let block = match pace {
        Pace::Max => read_block(),
        Pace::Realtime { bytes_per_s } => ((bytes_per_s * 0.02) as usize).clamp(1, READ_BLOCK),
    };
    loop {
        let mut buf = BytesMut::with_capacity(block);
        let n = tokio::select! {
            biased;
            _ = ctx.shutdown.cancelled() => break,
            n = r.read_buf(&mut buf) => n.context("reading the input")?,
        };
        if n == 0 {
            ctx.progress
                .input_ended
                .store(true, std::sync::atomic::Ordering::SeqCst);
            break;
        }
        total += n as u64;
        let ev = SourceEvent::Data {
            bytes: buf.freeze(),
            at: Instant::now(),
        };
        if !ctx.deliver(ev).await? {
            break;
        }
        if let Pace::Realtime { bytes_per_s } = pace {
            // Each byte is due at its offset divided by the data rate.
            let due = started + Duration::from_secs_f64(total as f64 / bytes_per_s);
            tokio::select! {
                _ = ctx.shutdown.cancelled() => break,
                _ = tokio::time::sleep_until(due.into()) => {}
            }
        }
    }
    Ok(())
}

/// Read buffers kept for reuse by [`read_file`]: the reads in the source queue, the one being
/// decoded and the one being filled, plus one.
const SPARE_BUFFERS: usize = super::SOURCE_QUEUE_FILE + 3;

/// A read's buffer inside the [`Bytes`] handed to the decode stage; when the last handle is
/// dropped (the decode thread, once the read is decoded) the buffer goes back to the reader
/// instead of being freed, so a replay allocates a few buffers, not one per read (fresh
/// buffers cost page faults and cross-thread frees).
struct Recycled {
    buf: Vec<u8>,
    home: crossbeam_channel::Sender<Vec<u8>>,
}

impl AsRef<[u8]> for Recycled {
    fn as_ref(&self) -> &[u8] {
        &self.buf
    }
}

impl Drop for Recycled {
    fn drop(&mut self) {
        // A full pool (or a reader gone) frees the buffer instead.
        let _ = self.home.try_send(std::mem::take(&mut self.buf));
    }
}

/// Reads the file `f` to its end (or until shutdown) with blocking reads of [`READ_BLOCK`],
/// passing each block on; for a blocking thread (`spawn_blocking`), with no pacing and no
/// capture (those take [`read_stream`]).
pub fn read_file(mut f: std::fs::File, ctx: &mut SourceContext) -> Result<()> {
    let block = read_block();
    let (home, spare) = crossbeam_channel::bounded::<Vec<u8>>(SPARE_BUFFERS);
    loop {
        if ctx.shutdown.is_cancelled() {
            break;
        }
        // A recycled buffer is still `block` bytes long (initialized once, when it was made):
        // reads go straight into it, whole, with no zeroing and no growing.
        let mut buf = spare.try_recv().unwrap_or_default();
        buf.resize(block, 0);
        let n = fill(&mut f, &mut buf).context("reading the input")?;
        buf.truncate(n);
        if n == 0 {
            ctx.progress
                .input_ended
                .store(true, std::sync::atomic::Ordering::SeqCst);
            break;
        }
        ctx.progress
            .bytes
            .fetch_add(n as u64, std::sync::atomic::Ordering::Relaxed);
        let ev = SourceEvent::Data {
            bytes: Bytes::from_owner(Recycled {
                buf,
                home: home.clone(),
            }),
            at: Instant::now(),
        };
        if ctx.tx.blocking_send(ev).is_err() {
            break;
        }
    }
    Ok(())
}

/// Reads into `buf` until it is full or the file ends; the bytes read.
fn fill(f: &mut std::fs::File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match f.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

/// [`READ_BLOCK`], or `ALLANSCOPE_READ_BLOCK` bytes (a measurement knob, 4 KiB to 64 MiB).
fn read_block() -> usize {
    std::env::var("ALLANSCOPE_READ_BLOCK")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
        .map_or(READ_BLOCK, |n| n.clamp(1 << 12, 1 << 26))
}
