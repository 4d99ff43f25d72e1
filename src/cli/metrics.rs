//! `--metrics ADDR:PORT`: serves the library's metrics registry (`sink::metrics`) at
//! `GET /metrics` over HTTP (`tiny_http`) on a thread of its own, for Prometheus to scrape.
//! A bare port binds 127.0.0.1 (loopback unless told otherwise).

use std::net::SocketAddr;
use std::sync::Arc;
use std::thread::JoinHandle;

use anyhow::Result;

use super::usage;
use allanscope::model::limits::LimitSpec;
use allanscope::sink::metrics::{Metrics, MetricsTap, CONTENT_TYPE};

/// A running metrics endpoint; stops when dropped.
pub struct MetricsServer {
    server: Arc<tiny_http::Server>,
    thread: Option<JoinHandle<()>>,
    pub metrics: Arc<Metrics>,
}

/// Parses `--metrics` (or the stand config's `run.metrics`): `ADDR:PORT`, or `PORT` for
/// 127.0.0.1.
pub fn parse_addr(s: &str) -> Result<SocketAddr, String> {
    allanscope::source::udp::parse_bind(s)
}

/// The server `--metrics` asks for, if any (a bad address is a usage error naming the option).
pub fn start_option(opt: Option<&str>) -> Result<Option<MetricsServer>> {
    let Some(text) = opt else { return Ok(None) };
    let addr = parse_addr(text).map_err(|e| usage(format!("--metrics {e}")))?;
    MetricsServer::start(addr).map(Some)
}

impl MetricsServer {
    /// What one unit's run feeds into the registry.
    pub fn tap(&self, unit: &str, limits: &[LimitSpec]) -> MetricsTap {
        self.metrics.tap(unit, limits)
    }

    /// Binds `addr` and starts answering: `/metrics` gives the registry, anything else 404.
    pub fn start(addr: SocketAddr) -> Result<MetricsServer> {
        let server = tiny_http::Server::http(addr)
            .map_err(|e| usage(format!("--metrics {addr}: cannot listen there: {e}")))?;
        let addr = server
            .server_addr()
            .to_ip()
            .ok_or_else(|| usage(format!("--metrics {addr}: not an IP address")))?;
        let server = Arc::new(server);
        let metrics = Arc::new(Metrics::new());
        let thread = {
            let (server, metrics) = (server.clone(), metrics.clone());
            std::thread::Builder::new()
                .name("allanscope-metrics".into())
                .spawn(move || serve(&server, &metrics))?
        };
        tracing::info!("metrics at http://{addr}/metrics");
        Ok(MetricsServer {
            server,
            thread: Some(thread),
            metrics,
        })
    }
}

impl Drop for MetricsServer {
    fn drop(&mut self) {
        self.server.unblock();
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn serve(server: &tiny_http::Server, metrics: &Metrics) {
    for req in server.incoming_requests() {
        let path = req.url().split('?').next().unwrap_or("");
        let response = if path == "/metrics" && *req.method() == tiny_http::Method::Get {
            let header = tiny_http::Header::from_bytes(&b"Content-Type"[..], CONTENT_TYPE)
                .expect("a valid header");
            tiny_http::Response::from_string(metrics.encode()).with_header(header)
        } else {
            tiny_http::Response::from_string("allanscope serves GET /metrics\n")
                .with_status_code(404)
        };
        if let Err(e) = req.respond(response) {
            tracing::debug!("metrics response: {e}");
        }
    }
}
