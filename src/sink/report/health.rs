//! The decoder-health table: the last health record of each run.

use super::*;

pub(super) fn health(h: &mut String, res: &Results) {
    if res.health.is_empty() {
        return;
    }
    h.push_str("<h2>Decoder health</h2>\n<table><tr><th class=\"l\">run</th><th>frames</th><th>checksum errors</th><th>resynchronisations</th><th>missing</th><th>duplicated</th><th>bytes skipped</th></tr>\n");
    // The last health record of each run.
    let mut last: Vec<&Labelled<HealthRecord>> = Vec::new();
    for hl in &res.health {
        match last
            .iter_mut()
            .find(|x| x.file == hl.file && x.run == hl.run)
        {
            Some(x) => *x = hl,
            None => last.push(hl),
        }
    }
    for hl in last {
        let v = &hl.rec;
        let bad = v.crc_errors > 0 || v.missing > 0 || v.duplicates > 0;
        let _ = writeln!(
            h,
            "<tr><td class=\"l\">{}</td><td>{}</td><td{c}>{}</td><td>{}</td><td{c}>{}</td><td{c}>{}</td><td>{}</td></tr>",
            esc(&hl.label),
            v.frames,
            v.crc_errors,
            v.resyncs,
            v.missing,
            v.duplicates,
            v.bytes_skipped,
            c = if bad { " class=\"warn\"" } else { "" }
        );
    }
    h.push_str("</table>\n");
}
