//! UDP source: one socket, each datagram one or more whole frames, passed on whole. Reordering
//! and duplicate datagrams are the decode stage's business (`pipeline::reorder`); this task
//! only receives: it reads the socket empty, then lets datagrams gather for [`GATHER_PAUSE`]
//! before it reads again (one wake-up for several datagrams, not one each).
//! The socket asks for a receive buffer of [`RECV_BUFFER`] bytes, so a receiver that misses the
//! CPU for a while (a loaded host, many units in one process) finds its datagrams waiting
//! instead of dropped.

use std::net::SocketAddr;
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use bytes::BytesMut;

use super::{SourceContext, SourceEvent};

/// Largest datagram accepted (the UDP maximum).
const MAX_DATAGRAM: usize = 65_536;

/// After this long without a datagram (beyond a [`GATHER_PAUSE`]) the source reports
/// [`SourceEvent::Idle`], so frames held for reordering are released: 20 ms is 5 siu8 frames,
/// far longer than loopback or LAN reordering spans.
pub const IDLE_AFTER: Duration = Duration::from_millis(20);

/// After the socket has been read empty, the source waits this long before it looks again, so
/// the datagrams of that while are taken in one go, from the socket's buffer, with one wake-up
/// and no timer each. Waking once per datagram (20,000 a second for 100 units at 2 kHz in
/// datagrams of 10 frames) was most of the receiving thread's time in the 100-unit live
/// benchmark (BENCHMARKS.md, "Several units live"). 10 ms is far inside what the receive
/// buffer holds ([`RECV_BUFFER`]) and than any silence the decode stage judges (half a counter
/// period: 64 ms for kvh1750's 7-bit counter at 1 kHz); a datagram's arrival time is its read
/// time, so up to this much late.
pub const GATHER_PAUSE: Duration = Duration::from_millis(10);

/// The end of the gather pause begun at `now`: the next whole multiple of [`GATHER_PAUSE`]
/// since one instant common to the process, at least half a pause away. Every UDP source of
/// the process (100 units in one) then wakes at the same instants, one wake-up of the runtime
/// thread for all, instead of one for each source at its own phase.
fn next_gather(now: tokio::time::Instant) -> std::time::Instant {
    static EPOCH: std::sync::OnceLock<Instant> = std::sync::OnceLock::new();
    let now = now.into_std();
    let epoch = *EPOCH.get_or_init(|| now);
    let p = GATHER_PAUSE.as_nanos();
    let since = now.saturating_duration_since(epoch).as_nanos() + p / 2;
    let k = since.div_ceil(p);
    epoch + Duration::from_nanos(u64::try_from(k * p).unwrap_or(u64::MAX))
}

/// Received datagrams are copied into shared blocks of this many bytes, each datagram a slice
/// of one ([`bytes::BytesMut::split`]), so most datagrams cost no allocation; a block is
/// reused once the decode stage has dropped every datagram in it.
const ARENA_BYTES: usize = 16 << 10;

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
///
/// The socket is not registered with the runtime's poller: the task reads it empty, then sleeps
/// until the next gather instant ([`next_gather`]) and reads it again. With readiness events
/// the runtime thread woke for every datagram (each arrival is an event, whether or not a task
/// waits), 20,000 times a second for 100 units; now it wakes 100 times a second for all of them.
pub async fn run(bind: SocketAddr, ctx: &mut SourceContext) -> Result<()> {
    let (sock, granted) = bind_socket(bind, RECV_BUFFER)?;
    tracing::info!(
        "listening on udp {} (receive buffer {} KiB)",
        sock.local_addr()?,
        granted / 1024
    );
    let mut buf = vec![0u8; MAX_DATAGRAM];
    let mut arena = BytesMut::with_capacity(ARENA_BYTES);
    let mut idle_sent = true;
    let mut last = tokio::time::Instant::now();
    loop {
        // Every datagram waiting is taken now, until the socket is empty (it is non-blocking).
        loop {
            let n = match sock.recv_from(&mut buf) {
                Ok((n, _from)) => n,
                Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => break,
                Err(e) => {
                    // ICMP errors surfacing on an unconnected socket are not fatal.
                    tracing::debug!("udp {bind}: {e}");
                    break;
                }
            };
            idle_sent = false;
            arena.extend_from_slice(&buf[..n]);
            let ev = SourceEvent::Datagram {
                bytes: arena.split().freeze(),
                at: Instant::now(),
            };
            if !ctx.deliver(ev).await? {
                return Ok(());
            }
            last = tokio::time::Instant::now();
        }
        let now = tokio::time::Instant::now();
        if !idle_sent && now.saturating_duration_since(last) >= IDLE_AFTER {
            idle_sent = true;
            if ctx.tx.send(SourceEvent::Idle).await.is_err() {
                return Ok(());
            }
        }
        tokio::select! {
            biased;
            _ = ctx.shutdown.cancelled() => return Ok(()),
            _ = tokio::time::sleep_until(next_gather(now).into()) => {}
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
