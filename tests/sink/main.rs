//! Figures and pages (src/sink/plot.rs, dynamic.rs, report.rs): the SVG and HTML parsed back
//! and their numbers checked against the records they were drawn from.
//! One test binary per stage; each topic is a module of it.

mod plot;
mod report;
