//! What standard output is: a terminal gets the readable table of `allanscope::sink::table`
//! unless `--json` asks for JSON lines; a pipe or a file always gets JSON lines, byte for byte
//! as the record writer makes them (docs/records.md).

use std::io::{IsTerminal, Write};

use allanscope::sink::results::ResultFile;
use allanscope::sink::table::{TableStyle, TableWriter};

/// Whether standard output gets the table: a terminal, and no `--json`.
pub(crate) fn table_on_stdout(json: bool) -> bool {
    !json && std::io::stdout().is_terminal()
}

/// Colours unless the terminal says it has none (`TERM=dumb`) or the user asked for none
/// (`NO_COLOR`, no-color.org).
fn style() -> TableStyle {
    let dumb = std::env::var("TERM").is_ok_and(|t| t == "dumb");
    TableStyle {
        color: !dumb && std::env::var_os("NO_COLOR").is_none_or(|v| v.is_empty()),
    }
}

/// Standard output for a command's records: the table on a terminal (module doc), else JSON
/// lines through a buffer.
pub(crate) fn stdout_records(json: bool) -> Box<dyn Write + Send> {
    stdout_records_with_runs(json, Vec::new)
}

/// As [`stdout_records`], the table's run-to-run rows taken from `runs()` (read only when a
/// table is printed): the `aggregate` command's input files.
pub(crate) fn stdout_records_with_runs(
    json: bool,
    runs: impl FnOnce() -> Vec<ResultFile>,
) -> Box<dyn Write + Send> {
    if table_on_stdout(json) {
        Box::new(
            TableWriter::new(
                std::io::stdout(),
                style(),
                Some("(a table because standard output is a terminal: --json, --out FILE or a pipe give the JSON lines)".into()),
            )
            .before_print(Box::new(super::status::suspend))
            .with_runs(runs()),
        )
    } else {
        Box::new(std::io::BufWriter::new(std::io::stdout()))
    }
}
