//! `plot`: an Allan-deviation SVG from the JSON lines `analyze` (or `listen`) wrote.

use anyhow::{Context, Result};

use super::{read_json_lines, usage, PlotArgs};
use allanscope::sink::plot::{render_svg, Series};
use allanscope::sink::records::{CurveRecord, FitRecord};

pub fn run(a: &PlotArgs) -> Result<()> {
    let mut curves: Vec<(String, CurveRecord)> = Vec::new();
    let mut fits: Vec<(String, FitRecord)> = Vec::new();
    for path in &a.inputs {
        for v in read_json_lines(path)? {
            let tag = path.display().to_string();
            match v.get("type").and_then(|t| t.as_str()) {
                Some("curve") => {
                    let c: CurveRecord = serde_json::from_value(v)
                        .with_context(|| format!("{tag}: a curve record"))?;
                    if c.r#final && c.stat.name() == a.stat {
                        curves.push((tag, c));
                    }
                }
                Some("fit") => {
                    let f: FitRecord = serde_json::from_value(v)
                        .with_context(|| format!("{tag}: a fit record"))?;
                    if f.r#final {
                        fits.push((tag, f));
                    }
                }
                _ => {}
            }
        }
    }
    if let Some(ch) = &a.channels {
        curves.retain(|(_, c)| ch.contains(&c.channel));
    }
    if curves.is_empty() {
        return Err(usage(format!(
            "plot: no final `{}` curve records in the input{}",
            a.stat,
            if a.channels.is_some() {
                " for those channels"
            } else {
                ""
            }
        )));
    }
    let several_files = a.inputs.len() > 1;
    let mut labelled: Vec<CurveRecord> = Vec::new();
    let mut their_fits: Vec<Option<&FitRecord>> = Vec::new();
    for (tag, c) in &curves {
        let fit = fits
            .iter()
            .find(|(t, f)| t == tag && f.channel == c.channel && f.run == c.run)
            .map(|(_, f)| f);
        let mut c = c.clone();
        if several_files || c.run.is_some() {
            let run = c.run.map(|r| format!(" run {r}")).unwrap_or_default();
            let file = std::path::Path::new(tag)
                .file_name()
                .map(|f| f.to_string_lossy().to_string())
                .unwrap_or_default();
            c.channel = format!("{} ({}{run})", c.channel, file);
        }
        labelled.push(c);
        their_fits.push(if a.no_model { None } else { fit });
    }
    let series: Vec<Series> = labelled
        .iter()
        .zip(their_fits)
        .map(|(curve, fit)| Series { curve, fit })
        .collect();
    let title = a.title.clone().unwrap_or_else(|| "allanscope".into());
    let svg = render_svg(&series, &title);
    std::fs::write(&a.out, svg).with_context(|| format!("cannot write {}", a.out.display()))?;
    tracing::info!("{}: {} curves", a.out.display(), series.len());
    Ok(())
}
