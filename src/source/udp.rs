//! UDP source: one socket, each datagram one or more whole frames, passed on whole. Reordering
//! and duplicate datagrams are the decode stage's business (`pipeline::reorder`); this task
//! only receives, so the socket's buffer drains as fast as the kernel fills it.
//! The socket asks for a receive buffer of [`RECV_BUFFER`] bytes, so a receiver that misses the
//! CPU for a while (a loaded host, many units in one process) finds its datagrams waiting
//! instead of dropped.

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

/// The receive buffer asked for (`SO_RCVBUF`), in bytes. Linux's default (`rmem_default`, often
/// 208 KiB) holds a few hundred small datagrams: at 200 datagrams/s per unit, about a second of
/// a receiver that does not get the CPU, and a loaded 2-core host with 100 units lost 1.4% of
/// its frames there (BENCHMARKS.md, "Several units live"). 4 MiB holds several seconds; the
/// kernel caps the request at `net.core.rmem_max` (the size granted is logged), and the memory
/// is used only while datagrams wait.
pub const RECV_BUFFER: usize = 4 << 20;

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

/// A non-blocking UDP socket bound to `bind`, with a receive buffer of `recv_buffer` bytes
/// asked for (the kernel may grant less, or, as Linux does, twice the request for its own
/// bookkeeping); returns the socket and the size granted.
pub fn bind_socket(bind: SocketAddr, recv_buffer: usize) -> Result<(std::net::UdpSocket, usize)> {
    use socket2::{Domain, Protocol, Socket, Type};
    let sock = Socket::new(Domain::for_address(bind), Type::DGRAM, Some(Protocol::UDP))
        .context("cannot create a UDP socket")?;
    // A smaller buffer than asked is not an error: the kernel's limit is the administrator's.
    if let Err(e) = sock.set_recv_buffer_size(recv_buffer) {
        tracing::debug!("udp {bind}: SO_RCVBUF {recv_buffer}: {e}");
    }
    sock.set_nonblocking(true)
        .context("cannot make the UDP socket non-blocking")?;
    sock.bind(&bind.into())
        .with_context(|| format!("cannot bind UDP socket {bind}"))?;
    let granted = sock.recv_buffer_size().unwrap_or(0);
    Ok((sock.into(), granted))
}

/// Receives datagrams until shutdown.
pub async fn run(bind: SocketAddr, ctx: &mut SourceContext) -> Result<()> {
    let (std_sock, granted) = bind_socket(bind, RECV_BUFFER)?;
    let sock = UdpSocket::from_std(std_sock)
        .with_context(|| format!("cannot register UDP socket {bind}"))?;
    tracing::info!(
        "listening on udp {} (receive buffer {} KiB)",
        sock.local_addr()?,
        granted / 1024
    );
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The receive buffer granted is the one asked for, up to the kernel's limit: Linux grants
    /// twice the request (its own bookkeeping), the request capped at `net.core.rmem_max`.
    #[test]
    fn the_socket_gets_the_receive_buffer_asked_for() {
        let any = SocketAddr::from(([127, 0, 0, 1], 0));
        let (_, small) = bind_socket(any, 4096).expect("bind");
        let (sock, granted) = bind_socket(any, RECV_BUFFER).expect("bind");
        assert_ne!(sock.local_addr().expect("addr").port(), 0);
        assert!(granted >= small, "{granted} < {small}");
        #[cfg(target_os = "linux")]
        {
            let max: usize = std::fs::read_to_string("/proc/sys/net/core/rmem_max")
                .ok()
                .and_then(|t| t.trim().parse().ok())
                .unwrap_or(0);
            assert_eq!(granted, 2 * RECV_BUFFER.min(max), "rmem_max {max}");
        }
    }
}
