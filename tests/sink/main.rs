//! Where results go (src/sink/): the metrics exporter scraped by Prometheus and the Grafana
//! dashboard that reads it; the figures and pages (plot.rs, dynamic.rs, report.rs), the SVG and
//! HTML parsed back and their numbers checked against the records they were drawn from.
//! One test binary per stage; each topic is a module of it.

#[path = "../common/mod.rs"]
mod common;

mod grafana;
mod plot;
mod prometheus;
mod report;
mod table;
