//! Where results go (src/sink/): the metrics exporter scraped by Prometheus, and the Grafana
//! dashboard that reads it.
//! One test binary per stage; each topic is a module of it.

#[path = "../common/mod.rs"]
mod common;

mod grafana;
mod prometheus;
