//! A test report as one self-contained HTML page a lead can sign: a PASS/FAIL banner from the
//! datasheet limits, the runs and whether each input was read to its end, the limits with their
//! units, the Allan-deviation figures (one panel per channel unit, runs labelled by file), the
//! noise model (the seed paper's table 2 layout per channel when there are several runs: runs
//! as rows, the five coefficients as columns, then mean, 95% interval of the mean and sd) and
//! the IEEE 952 read-outs beside it, the final diagnosis in words with each effect's parameters
//! named and in units (interim diagnoses in a small time table), the dynamic Allan view where
//! interim curves exist, the decoder's health, and a signature block. Print CSS keeps tables and
//! figures whole on A4.
//!
//! Files: one per section (banner.rs, runs.rs with the limits, figures.rs with the SVG
//! embedding, noise_model.rs, diagnosis.rs, health.rs) and css.rs; here, the page's skeleton
//! ([`render_html`]).

use crate::gap::record::RecordedEffect;
use crate::gap::DiagnosisRecord;
use crate::model::aggregate::{aggregate_channels, RunCoefs};
use crate::model::limits::LimitResult;
use crate::model::terms::TERM_NAMES;
use crate::sink::dynamic::render_dynamic_svg;
use crate::sink::plot::{
    band_sentence, chance_share, coef_units, effect_name, effect_names, escape as esc,
    figure_series, final_curves, percent, ratio_text, render_svg, tick, Series,
};
use crate::sink::records::{
    AggregateRecord, FitRecord, HealthRecord, ReadoutRecord, TimeColumnRecord,
};
use crate::sink::results::{Labelled, ResultFile, Results};
use std::fmt::Write;

mod banner;
mod css;
mod diagnosis;
mod figures;
mod health;
mod noise_model;
mod runs;

use banner::*;
use css::*;
use diagnosis::*;
use figures::*;
use health::*;
use noise_model::*;
use runs::*;

pub use banner::{banner_of, Banner};
pub use diagnosis::effect_words;

fn opt(v: Option<f64>) -> String {
    v.map_or("&ndash;".into(), tick)
}

/// A run: its file and its `run` index inside the file.
type RunKey = (usize, Option<usize>);

/// Renders the page. `generated` is the date and time written under the title.
pub fn render_html(files: &[ResultFile], title: &str, generated: &str) -> String {
    let res = Results::from_files(files);
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>{CSS}</style></head><body>\n<h1>{t}</h1>\n<p class=\"meta\">Files: {f}. Written {g} by allanscope {v}.</p>\n",
        t = esc(title),
        f = esc(&files.iter().map(|f| f.name.as_str()).collect::<Vec<_>>().join(", ")),
        g = esc(generated),
        v = env!("CARGO_PKG_VERSION")
    );
    banner(&mut h, &res);
    runs_table(&mut h, &res);
    limits_table(&mut h, &res);
    figures(&mut h, &res);
    noise_model(&mut h, &res);
    diagnosis(&mut h, &res);
    dynamic_view(&mut h, &res);
    health(&mut h, &res);
    h.push_str(
        "<h2>Sign-off</h2>\n<div class=\"sign\"><table><tr><th class=\"l\">role</th><th class=\"l\">name</th><th class=\"l\">signature</th><th class=\"l\">date</th></tr>\n\
         <tr><td>Tested by</td><td></td><td></td><td></td></tr>\n<tr><td>Checked by</td><td></td><td></td><td></td></tr>\n<tr><td>Approved by</td><td></td><td></td><td></td></tr></table></div>\n\
         <p class=\"small\">Written by allanscope from its JSON-lines records; coefficients in the units of docs/theory.md section 2 in allanscope's repository (u = the channel's unit), 95% intervals in brackets.</p>\n</body></html>\n",
    );
    h
}
