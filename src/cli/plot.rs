//! `plot`: Allan-deviation figures (SVG) from the JSON lines allanscope wrote; the drawing is
//! [`crate::sink::plot`]'s and [`crate::sink::dynamic`]'s.

use anyhow::Result;

use super::{read_json_lines, usage, PlotArgs};
use allanscope::sink::dynamic::{render_dynamic_svg, stack};
use allanscope::sink::page_file::write_page;
use allanscope::sink::plot::{default_title, figure_series, final_curves, render_svg};
use allanscope::sink::results::{ResultFile, Results};

pub fn run(a: &PlotArgs) -> Result<()> {
    allanscope::sink::page_file::check_target(&a.out, "-o")?;
    let files = a
        .inputs
        .iter()
        .map(|p| {
            Ok(ResultFile {
                name: file_name(p),
                records: read_json_lines(p)?,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let res = Results::from_files(&files);
    let wanted = |ch: &str| {
        a.channels
            .as_ref()
            .is_none_or(|c| c.iter().any(|x| x == ch))
    };
    let finals = final_curves(&res, &a.stat, &wanted);
    let series = figure_series(&res, &finals, &a.stat, &wanted, !a.no_model);
    if series.is_empty() {
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
    let names: Vec<String> = files.iter().map(|f| f.name.clone()).collect();
    let title = a
        .title
        .clone()
        .unwrap_or_else(|| default_title(&series, &names));
    let n = series.len();
    let mut svg = render_svg(series, &title);
    if a.dynamic {
        let mut parts = vec![svg];
        for c in &finals {
            let all = res.history_of(c);
            let label = res.curve_caption(c);
            parts.push(render_dynamic_svg(&all, &label));
        }
        svg = stack(&parts);
    }
    write_page(&a.out, svg.as_bytes(), a.force)?;
    tracing::info!("{}: {n} curves", a.out.display());
    Ok(())
}

fn file_name(p: &std::path::Path) -> String {
    p.file_name()
        .map(|f| f.to_string_lossy().to_string())
        .unwrap_or_else(|| p.display().to_string())
}
