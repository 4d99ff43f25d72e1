//! [`TableWriter`]: the adapter the binary puts in place of standard output on a terminal. It
//! takes the JSON lines the record writer produces, keeps the final records and prints a run's
//! table when its `summary` arrives (the rest when it is dropped).

use super::*;

/// Whether a [`TableWriter`] keeps a record: everything typed but the curves, which a table
/// does not show.
pub(super) fn kept(v: &Value) -> bool {
    v.get("type")
        .and_then(Value::as_str)
        .is_some_and(|t| t != "curve")
}

/// A `Write` that takes JSON lines and prints tables ([`render`]) to `out`: a run's table when its
/// `summary` arrives, and whatever is left (run-to-run statistics, the `diagnose` command's
/// diagnoses) when it is dropped or [`TableWriter::finish`]ed.
pub struct TableWriter<W: Write> {
    out: W,
    style: TableStyle,
    line: Vec<u8>,
    pending: Vec<Value>,
    /// A hint under the first table: where the JSON lines are.
    hint: Option<String>,
    printed: bool,
    /// Called before a table is printed (the binary clears and stops its status line there).
    before_print: Option<Box<dyn FnMut() + Send>>,
    /// The final fits and summaries of the runs printed so far, for the rows of the run-to-run
    /// table when the `aggregate` records come.
    seen: Vec<Value>,
    /// Result files given by [`TableWriter::with_runs`] (the `aggregate` command's inputs): the
    /// rows of the run-to-run table instead of `seen`.
    run_files: Vec<ResultFile>,
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
            run_files: Vec::new(),
        }
    }

    /// The runs whose final fits fill the rows of the run-to-run table (one file each, named
    /// by its file name), when the records written are `aggregate` records only.
    pub fn with_runs(mut self, files: Vec<ResultFile>) -> Self {
        self.run_files = files;
        self
    }

    /// Calls `f` before each table is printed.
    pub fn before_print(mut self, f: Box<dyn FnMut() + Send>) -> Self {
        self.before_print = Some(f);
        self
    }

    fn take_line(&mut self, line: &[u8]) -> std::io::Result<()> {
        let Ok(v) = serde_json::from_slice::<Value>(line) else {
            // Not a record: shown as it came.
            self.out.write_all(line)?;
            return self.out.write_all(b"\n");
        };
        let summary = v.get("type").and_then(Value::as_str) == Some("summary");
        if kept(&v) {
            // Only the newest interim fit or diagnosis of a channel is kept.
            if v.get("final").and_then(Value::as_bool) == Some(false) {
                let same = |w: &Value| {
                    w.get("type") == v.get("type")
                        && w.get("channel") == v.get("channel")
                        && w.get("run") == v.get("run")
                        && w.get("unit") == v.get("unit")
                        && w.get("final").and_then(Value::as_bool) == Some(false)
                };
                self.pending.retain(|w| !same(w));
            }
            self.pending.push(v);
        }
        if summary {
            self.print_pending()?;
        }
        Ok(())
    }

    fn print_pending(&mut self) -> std::io::Result<()> {
        if self.pending.is_empty() {
            return Ok(());
        }
        let records = std::mem::take(&mut self.pending);
        // A run of several units prints each unit's table as its summary comes, under its name.
        let unit = records
            .iter()
            .find_map(|r| crate::sink::unit_record::untag(&mut r.clone()));
        let res = Results::from_files(&[ResultFile {
            name: String::new(),
            records: records.clone(),
        }]);
        let is = |v: &Value, t: &str| v.get("type").and_then(Value::as_str) == Some(t);
        let text = if res.aggregates.is_empty() {
            render(&res, &self.style)
        } else {
            let runs = if self.run_files.is_empty() {
                let mut all = self.seen.clone();
                all.extend(records.iter().cloned());
                Results::from_files(&[ResultFile {
                    name: String::new(),
                    records: all,
                }])
            } else {
                Results::from_files(&self.run_files)
            };
            render_with_runs(&res, &runs, &self.style)
        };
        // Final fits and summaries are kept for a run-to-run table printed later.
        self.seen.extend(records.into_iter().filter(|v| {
            is(v, "summary")
                || (is(v, "fit") && v.get("final").and_then(Value::as_bool) == Some(true))
        }));
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
