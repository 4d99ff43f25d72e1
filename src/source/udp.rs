//! UDP source: one socket, each datagram one or more whole frames, passed on whole. Reordering
//! and duplicate datagrams are the decode stage's business (`pipeline::reorder`); this task
//! only receives, so the socket's buffer drains as fast as the kernel fills it.

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use bytes::Bytes;
use tokio::net::UdpSocket;

use super::{SourceContext, SourceEvent};

/// Largest datagram accepted (the UDP maximum).
const MAX_DATAGRAM: usize = 65_536;

/// After this long without a datagram the source reports [`SourceEvent::Idle`], so frames held
/// for reordering are released: 20 ms is 5 siu8 frames, far longer than loopback or LAN
/// reordering spans.
pub const IDLE_AFTER: Duration = Duration::from_millis(20);

/// Datagrams taken from the socket after one has arrived, before waiting with a timeout again.
const DRAIN_AT_ONCE: usize = 64;

/// Parses `--udp`: `ADDR:PORT`, or a bare `PORT` (bound to 127.0.0.1).
pub fn parse_bind(s: &str) -> Result<SocketAddr, String> {
    let s = s.trim();
    if let Ok(port) = s.parse::<u16>() {
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    s.parse::<SocketAddr>().map_err(|_| {
        format!("`{s}`: expected ADDR:PORT (e.g. 127.0.0.1:5000, 0.0.0.0:5000) or a port number")
    })
}

/// Receives datagrams until shutdown.
pub async fn run(bind: SocketAddr, ctx: &mut SourceContext) -> Result<()> {
    let sock = UdpSocket::bind(bind)
        .await
        .with_context(|| format!("cannot bind UDP socket {bind}"))?;
    tracing::info!("listening on udp {}", sock.local_addr()?);
    let mut buf = vec![0u8; MAX_DATAGRAM];
    let mut idle_sent = true;
    loop {
        let r = tokio::select! {
            biased;
            _ = ctx.shutdown.cancelled() => return Ok(()),
            r = tokio::time::timeout(IDLE_AFTER, sock.recv_from(&mut buf)) => r,
        };
        match r {
            Err(_elapsed) => {
                if !idle_sent {
                    idle_sent = true;
                    if ctx.tx.send(SourceEvent::Idle).await.is_err() {
                        return Ok(());
                    }
                }
            }
            Ok(Ok((n, _from))) => {
                idle_sent = false;
                let ev = SourceEvent::Datagram {
                    bytes: Bytes::copy_from_slice(&buf[..n]),
                    at: Instant::now(),
                };
                if !ctx.deliver(ev).await? {
                    return Ok(());
                }
                // Datagrams already waiting are taken now, without a timer each (many units
                // in one process: fewer wake-ups per datagram).
                for _ in 0..DRAIN_AT_ONCE {
                    let Ok((n, _from)) = sock.try_recv_from(&mut buf) else {
                        break;
                    };
                    let ev = SourceEvent::Datagram {
                        bytes: Bytes::copy_from_slice(&buf[..n]),
                        at: Instant::now(),
                    };
                    if !ctx.deliver(ev).await? {
                        return Ok(());
                    }
                }
            }
            Ok(Err(e)) => {
                // ICMP errors surfacing on an unconnected socket are not fatal.
                tracing::debug!("udp {bind}: {e}");
            }
        }
    }
}
