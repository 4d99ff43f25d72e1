//! File and standard-input sources: a byte stream read in blocks of [`READ_BLOCK`], as fast as
//! the analysis takes it or paced at the data's own rate.

use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use bytes::BytesMut;
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
        Pace::Max => READ_BLOCK,
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
