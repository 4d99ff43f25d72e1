//! Serial source: reads a port (8N1 at the given baud) and reopens it with backoff when it
//! disappears (a USB adapter pulled, a pseudo-terminal closed).
//!
//! An outage is the time from the read that failed to the first read after the port came
//! back. It is reported as [`SourceEvent::Reconnected`]; the decode stage then records the
//! frames lost in it as a gap, from the frame counter and the outage's length (see
//! `pipeline::decode`).

use std::path::Path;
use std::sync::atomic::Ordering;
use std::time::Instant;

use anyhow::Result;
use bytes::BytesMut;
use tokio::io::AsyncReadExt;
use tokio_serial::SerialPortBuilderExt;

use super::{SourceContext, SourceEvent, BACKOFF_FIRST, BACKOFF_MAX};

/// Bytes per read: 4 KiB, a few hundred ms of siu8 at 230400 baud; reads return as soon as
/// anything arrived, so this bounds the chunk, not the latency.
const READ_BLOCK: usize = 4096;

/// After this long without a byte the source reports [`SourceEvent::Idle`] (once), so reads the
/// decode stage holds while they may be the first pieces of a backlog are decided without
/// waiting for the next byte. The pieces of one backlog follow each other within a millisecond.
pub const IDLE_AFTER: std::time::Duration = std::time::Duration::from_millis(50);

fn open(path: &Path, baud: u32) -> std::io::Result<tokio_serial::SerialStream> {
    tokio_serial::new(path.to_string_lossy(), baud)
        .data_bits(tokio_serial::DataBits::Eight)
        .parity(tokio_serial::Parity::None)
        .stop_bits(tokio_serial::StopBits::One)
        .flow_control(tokio_serial::FlowControl::None)
        .open_native_async()
        .map_err(std::io::Error::from)
}

/// Reads the port until shutdown; a port that cannot be opened at the start is an error, one
/// that disappears later is waited for.
pub async fn run(path: &Path, baud: u32, ctx: &mut SourceContext) -> Result<()> {
    let mut port = match open(path, baud) {
        Ok(p) => p,
        Err(e) => {
            return Err(anyhow::Error::new(crate::error::UsageError::Input {
                file: path.into(),
                line: 0,
                problem: format!("cannot open serial port: {e}"),
            }))
        }
    };
    tracing::info!("reading serial port {} at {baud} baud", path.display());
    loop {
        // Read until the port fails or reports its end.
        let mut idle_at = None;
        let lost_at = loop {
            let mut buf = BytesMut::with_capacity(READ_BLOCK);
            let r = tokio::select! {
                biased;
                _ = ctx.shutdown.cancelled() => return Ok(()),
                // Cancel-safe: bytes are only taken by a read that completes.
                r = port.read_buf(&mut buf) => r,
                _ = tokio::time::sleep_until(idle_at.unwrap_or_else(tokio::time::Instant::now)),
                    if idle_at.is_some() =>
                {
                    idle_at = None;
                    if ctx.tx.send(SourceEvent::Idle).await.is_err() {
                        return Ok(());
                    }
                    continue;
                }
            };
            match r {
                Ok(0) => break Instant::now(),
                Ok(_) => {
                    idle_at = Some(tokio::time::Instant::now() + IDLE_AFTER);
                    let ev = SourceEvent::Data {
                        bytes: buf.freeze(),
                        at: Instant::now(),
                    };
                    if !ctx.deliver(ev).await? {
                        return Ok(());
                    }
                }
                Err(e) => {
                    tracing::warn!("{}: {e}; reopening", path.display());
                    break Instant::now();
                }
            }
        };
        drop(port);
        // Reopen with backoff.
        let mut wait = BACKOFF_FIRST;
        port = loop {
            tokio::select! {
                biased;
                _ = ctx.shutdown.cancelled() => return Ok(()),
                _ = tokio::time::sleep(wait) => {}
            }
            match open(path, baud) {
                Ok(p) => break p,
                Err(e) => {
                    tracing::debug!("{}: {e}", path.display());
                    wait = (wait * 2).min(BACKOFF_MAX);
                }
            }
        };
        ctx.progress.reconnects.fetch_add(1, Ordering::Relaxed);
        let outage_s = lost_at.elapsed().as_secs_f64();
        tracing::info!("{}: reopened after {outage_s:.3} s", path.display());
        if ctx
            .tx
            .send(SourceEvent::Reconnected { outage_s })
            .await
            .is_err()
        {
            return Ok(());
        }
    }
}
