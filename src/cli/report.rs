//! `report`: one self-contained HTML page from the JSON lines allanscope wrote.

use anyhow::{Context, Result};

use super::{read_json_lines, ReportArgs};
use allanscope::sink::report::{render_html, ReportInput};

pub fn run(a: &ReportArgs) -> Result<()> {
    let inputs = a
        .inputs
        .iter()
        .map(|p| {
            Ok(ReportInput {
                name: p
                    .file_name()
                    .map(|f| f.to_string_lossy().to_string())
                    .unwrap_or_default(),
                records: read_json_lines(p)?,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let html = render_html(&inputs, &a.title);
    std::fs::write(&a.out, html).with_context(|| format!("cannot write {}", a.out.display()))?;
    tracing::info!("{}: report written", a.out.display());
    Ok(())
}
