//! [`TableWriter`]: the adapter the binary puts in place of standard output on a terminal. It
//! takes the JSON lines the record writer produces, parses each once into its typed record
//! ([`ReadRecord`]), keeps the final records and prints a run's table when its `summary` arrives
//! (the rest when it is dropped).
//!
//! What it holds is bounded by the run's channels, not its length: curves are not kept (a table
//! does not show them), and an interim fit or diagnosis replaces the one of the same channel
//! before it, so only final records accumulate until their run's `summary` prints them.

use super::*;
use crate::sink::results::{ReadFile, ReadRecord};

/// Whether a [`TableWriter`] keeps a record: everything but the curves, which a table does not
/// show.
fn kept(r: &ReadRecord) -> bool {
    !matches!(r.record, Record::Curve(_))
}

/// What an interim record replaces: the interim record of the same type, channel, run and unit
/// written before it. `None` for a record that is kept whatever follows (a final one, health,
/// a summary).
fn interim_key(r: &ReadRecord) -> Option<(&'static str, &str, Option<usize>, Option<&str>)> {
    let channel = match &r.record {
        Record::Fit(f) if !f.r#final => f.channel.as_str(),
        Record::Diagnosis(d) if !d.is_final => d.channel.as_str(),
        _ => return None,
    };
    Some((r.record.type_name(), channel, r.run(), r.unit.as_deref()))
}

/// A `Write` that takes JSON lines and prints tables ([`render`]) to `out`: a run's table when its
/// `summary` arrives, and whatever is left (run-to-run statistics, the `diagnose` command's
/// diagnoses) when it is dropped or [`TableWriter::finish`]ed.
pub struct TableWriter<W: Write> {
    out: W,
    style: TableStyle,
    line: Vec<u8>,
    /// The records of the run whose table is not printed yet.
    pending: Vec<ReadRecord>,
    /// A hint under the first table: where the JSON lines are.
    hint: Option<String>,
    printed: bool,
    /// Called before a table is printed (the binary clears and stops its status line there).
    before_print: Option<Box<dyn FnMut() + Send>>,
    /// The final fits and summaries of the runs printed so far, for the rows of the run-to-run
    /// table when the `aggregate` records come.
    seen: Vec<ReadRecord>,
    /// The runs given by [`TableWriter::with_runs`] (the `aggregate` command's inputs): the
    /// rows of the run-to-run table instead of `seen`.
    run_files: Option<Results>,
}

impl<W: Write> TableWriter<W> {
    /// `hint` is printed once, dimmed, after the first table.
    pub fn new(out: W, style: TableStyle, hint: Option<String>) -> TableWriter<W> {
        TableWriter {
            out,
            style,
            line: Vec::new(),
            pending: Vec::new(),
            hint,
            printed: false,
            before_print: None,
            seen: Vec::new(),
            run_files: None,
        }
    }

    /// The runs whose final fits fill the rows of the run-to-run table (one file each, named
    /// by its file name), when the records written are `aggregate` records only.
    pub fn with_runs(mut self, files: Vec<ResultFile>) -> Self {
        if !files.is_empty() {
            self.run_files = Some(Results::from_files(&files));
        }
        self
    }

    /// Calls `f` before each table is printed.
    pub fn before_print(mut self, f: Box<dyn FnMut() + Send>) -> Self {
        self.before_print = Some(f);
        self
    }

    fn take_line(&mut self, line: &[u8]) -> std::io::Result<()> {
        let Ok(read) = ReadRecord::from_line(line) else {
            // Not JSON: shown as it came.
            self.out.write_all(line)?;
            return self.out.write_all(b"\n");
        };
        // JSON but no record this version reads: nothing a table shows.
        let Some(r) = read else {
            return Ok(());
        };
        // A summary ends its run (its unit's, in a run of several units): its table is printed.
        let summary = matches!(r.record, Record::Summary(_)).then(|| r.unit.clone());
        if kept(&r) {
            // Only the newest interim fit or diagnosis of a channel is kept.
            if let Some(key) = interim_key(&r) {
                self.pending.retain(|w| interim_key(w) != Some(key));
            }
            self.pending.push(r);
        }
        if let Some(unit) = summary {
            // The other units' records wait for their own summaries.
            self.print_unit(&unit)?;
        }
        Ok(())
    }

    /// Prints the pending records of `unit` (`None`: a one-unit run), leaving the others.
    fn print_unit(&mut self, unit: &Option<String>) -> std::io::Result<()> {
        let (mine, others) = std::mem::take(&mut self.pending)
            .into_iter()
            .partition(|w| w.unit == *unit);
        self.pending = others;
        self.print(mine)
    }

    /// Prints every pending record, each unit's under its name.
    fn print_pending(&mut self) -> std::io::Result<()> {
        while let Some(first) = self.pending.first() {
            let unit = first.unit.clone();
            self.print_unit(&unit)?;
        }
        Ok(())
    }

    /// Prints the table of `records` (one run, or one unit's run).
    fn print(&mut self, records: Vec<ReadRecord>) -> std::io::Result<()> {
        if records.is_empty() {
            return Ok(());
        }
        // A run of several units prints each unit's table as its summary comes, under its name.
        let unit = records.iter().find_map(|r| r.unit.clone());
        // Final fits and summaries are kept for a run-to-run table printed later.
        let keep = |r: &&ReadRecord| match &r.record {
            Record::Summary(_) => true,
            Record::Fit(f) => f.r#final,
            _ => false,
        };
        let now_seen: Vec<ReadRecord> = records.iter().filter(keep).cloned().collect();
        let has_aggregates = records
            .iter()
            .any(|r| matches!(r.record, Record::Aggregate(_)));
        let runs = has_aggregates.then(|| {
            self.run_files.clone().unwrap_or_else(|| {
                let mut all = self.seen.clone();
                all.extend(records.iter().cloned());
                Results::from_read(vec![ReadFile {
                    name: String::new(),
                    records: all,
                }])
            })
        });
        let res = Results::from_read(vec![ReadFile {
            name: String::new(),
            records,
        }]);
        let text = match &runs {
            None => render(&res, &self.style),
            Some(runs) => render_with_runs(&res, runs, &self.style),
        };
        self.seen.extend(now_seen);
        if text.trim().is_empty() {
            return Ok(());
        }
        if let Some(f) = &mut self.before_print {
            f();
        }
        if self.printed {
            self.out.write_all(b"\n")?;
        }
        if let Some(u) = unit {
            writeln!(self.out, "unit {u}")?;
        }
        self.out.write_all(text.as_bytes())?;
        if !self.printed {
            if let Some(hint) = &self.hint {
                let t = self.style.dim(hint);
                writeln!(self.out, "{t}")?;
            }
        }
        self.printed = true;
        self.out.flush()
    }

    /// Prints what is left and flushes.
    pub fn finish(&mut self) -> std::io::Result<()> {
        if !self.line.is_empty() {
            let line = std::mem::take(&mut self.line);
            self.take_line(&line)?;
        }
        self.print_pending()?;
        self.out.flush()
    }
}

impl<W: Write> Write for TableWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let mut rest = buf;
        while let Some(i) = rest.iter().position(|&b| b == b'\n') {
            self.line.extend_from_slice(&rest[..i]);
            let line = std::mem::take(&mut self.line);
            if !line.iter().all(u8::is_ascii_whitespace) {
                self.take_line(&line)?;
            }
            rest = &rest[i + 1..];
        }
        self.line.extend_from_slice(rest);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}

impl<W: Write> Drop for TableWriter<W> {
    fn drop(&mut self) {
        // The end of the records: a terminal has nowhere to report a failure to but itself.
        let _ = self.finish();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sink::unit_record::UnitRecord;
    use serde_json::{json, Value};

    /// An interim (`final: false`) or final fit of `channel` whose N is `n` (arcsec/sqrt(s)).
    fn fit(channel: &str, n: f64, is_final: bool) -> Value {
        let c =
            |v: Option<f64>| json!({"determined": v.is_some(), "value": v, "lo": 0.0, "hi": 1.0});
        json!({"type": "fit", "channel": channel, "unit": "arcsec", "final": is_final,
            "t_data": 60.0, "coef": {"Q": c(None), "N": c(Some(n)), "B": c(None), "K": c(None),
            "R": c(None)}, "gof": 1.0, "method": "model"})
    }

    fn diagnosis(channel: &str, gap: f64, is_final: bool) -> Value {
        json!({"type": "diagnosis", "channel": channel, "gap_before": gap, "gap_after": gap,
            "verdict": "consistent", "regions": [], "effects": [], "final": is_final})
    }

    fn summary(channels: &[&str]) -> Value {
        json!({"type": "summary", "input": "a.csv", "channels": channels, "tau0": 0.01,
            "t_data": 60.0, "samples": [6000], "segments": [1], "bad_rows": 0, "overlap": "16",
            "elapsed_s": 0.1, "read_to_end": true})
    }

    /// The first line of `text` that starts (after its indent) with `start`.
    fn row<'a>(text: &'a str, start: &str) -> &'a str {
        text.lines()
            .find(|l| l.trim_start().starts_with(start))
            .unwrap_or_else(|| panic!("no line starting with `{start}` in\n{text}"))
    }

    fn write(w: &mut TableWriter<Vec<u8>>, v: &Value) {
        w.write_all(format!("{v}\n").as_bytes()).unwrap();
    }

    /// A long run with interim records: the writer holds one interim fit and diagnosis per
    /// channel however many come, and the table shows the final ones.
    #[test]
    fn interim_records_are_replaced_so_the_queue_stays_bounded() {
        let mut w = TableWriter::new(Vec::new(), TableStyle { color: false }, None);
        for i in 0..5000 {
            for ch in ["g1", "g2"] {
                write(&mut w, &fit(ch, 100.0 + i as f64, false));
                write(&mut w, &diagnosis(ch, 9.0, false));
            }
            // Curves are never kept.
            write(&mut w, &json!({"type": "curve", "channel": "g1"}));
        }
        assert_eq!(w.pending.len(), 4);
        write(&mut w, &fit("g1", 0.6, true));
        write(&mut w, &fit("g2", 1.2, true));
        write(&mut w, &diagnosis("g1", 0.9, true));
        assert_eq!(w.pending.len(), 7);
        write(&mut w, &summary(&["g1", "g2"]));
        assert!(w.pending.is_empty());
        let text = String::from_utf8(w.out.clone()).unwrap();
        // The final fits (no datasheet: native units), not the last interim ones (5099).
        let g2 = text.split_once("\ng2 ").expect("g2's block").1;
        assert!(row(&text, "N ").contains(" 0.600 "), "{text}");
        assert!(row(g2, "N ").contains(" 1.20 "), "{text}");
        assert!(!text.contains("5.10e3"), "{text}");
        assert!(text.contains("(gap 0.900)"), "{text}");
    }

    /// Records of several units: each unit's interim records replace only that unit's, and each
    /// unit's table is headed by its name.
    #[test]
    fn units_are_kept_apart() {
        let mut w = TableWriter::new(Vec::new(), TableStyle { color: false }, None);
        let tagged = |unit: &str, v: &Value| {
            serde_json::from_str::<Value>(
                &serde_json::to_string(&UnitRecord { unit, record: v }).unwrap(),
            )
            .unwrap()
        };
        write(&mut w, &tagged("imu01", &fit("g1", 3.0, false)));
        write(&mut w, &tagged("imu02", &fit("g1", 4.0, false)));
        write(&mut w, &tagged("imu01", &fit("g1", 5.0, false)));
        assert_eq!(w.pending.len(), 2);
        write(&mut w, &tagged("imu01", &fit("g1", 0.6, true)));
        write(&mut w, &tagged("imu01", &summary(&["g1"])));
        // imu02's interim fit waits for its own summary (or the end).
        assert_eq!(w.pending.len(), 1);
        let text = String::from_utf8(w.out.clone()).unwrap();
        assert!(text.starts_with("unit imu01\n"), "{text}");
        assert!(row(&text, "N ").contains(" 0.600 "), "{text}");
        assert!(!text.contains("imu02"), "{text}");
        w.finish().unwrap();
        let text = String::from_utf8(w.out.clone()).unwrap();
        let (_, second) = text.split_once("\nunit imu02\n").expect("imu02's table");
        assert!(row(second, "N ").contains(" 4.00 "), "{text}");
    }
}
