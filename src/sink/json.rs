//! Writes records as JSON lines, one object per line, to standard output or a file.

use std::io::Write;

use serde::Serialize;

/// A buffered JSON-lines writer. Each record is flushed at the end of a batch so a monitor
/// reading the stream sees whole lines promptly.
pub struct JsonLines {
    out: Box<dyn Write + Send>,
}

impl JsonLines {
    pub fn new(out: Box<dyn Write + Send>) -> Self {
        JsonLines { out }
    }

    pub fn stdout() -> Self {
        JsonLines::new(Box::new(std::io::BufWriter::new(std::io::stdout())))
    }

    pub fn write<T: Serialize>(&mut self, record: &T) -> std::io::Result<()> {
        serde_json::to_writer(&mut self.out, record)?;
        self.out.write_all(b"\n")
    }

    pub fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }
}
