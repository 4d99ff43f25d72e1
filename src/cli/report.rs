//! `report`: one self-contained HTML page from the JSON lines allanscope wrote; the page is
//! [`crate::sink::report`]'s.

use anyhow::Result;

use super::{read_json_lines, usage, ReportArgs};
use allanscope::sink::page_file::write_page;
use allanscope::sink::report::render_html;
use allanscope::sink::results::{ReadRecord, ResultFile};

pub fn run(a: &ReportArgs) -> Result<()> {
    allanscope::sink::page_file::check_target(&a.out, "-o")?;
    let inputs = a
        .inputs
        .iter()
        .map(|p| {
            Ok(ResultFile {
                name: p
                    .file_name()
                    .map(|f| f.to_string_lossy().to_string())
                    .unwrap_or_default(),
                records: read_json_lines(p)?,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    // A file with no record to show (empty, or JSON of something else) is a mistake, not an
    // empty page.
    for (f, p) in inputs.iter().zip(&a.inputs) {
        let any = f
            .records
            .iter()
            .any(|v| ReadRecord::from_value(v.clone()).is_some());
        if !any {
            return Err(usage(format!(
                "{}: no allanscope record in it (curve, fit, diagnosis, health, aggregate, \
                 summary); give the JSON lines of `analyze`, `listen`, `run` or `diagnose`",
                p.display()
            )));
        }
    }
    let html = render_html(&inputs, &a.title, &utc_now());
    write_page(&a.out, html.as_bytes(), a.force)?;
    tracing::info!("{}: report written", a.out.display());
    Ok(())
}

/// The current UTC date and time, `YYYY-MM-DD HH:MM UTC` (days to civil date by Howard
/// Hinnant's `civil_from_days`).
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() as i64);
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z - era * 146_097;
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let d = doy - (153 * mp + 2) / 5 + 1;
    let m = if mp < 10 { mp + 3 } else { mp - 9 };
    let y = yoe + era * 400 + i64::from(m <= 2);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        rem / 3600,
        (rem % 3600) / 60
    )
}
