//! The bottom line of a terminal kept for a live run's status (sink::table::status_line) while
//! log lines scroll above it: a log line clears the status line, is written, and the status line
//! is drawn again under it, so the two never share a line. Pure bookkeeping over any `Write`
//! (the binary gives it standard error), so the bytes it writes can be checked in a test.
//!
//! A status line is cut to the terminal's width less one column (a full-width line would make
//! the terminal wrap, and the next redraw would then scroll instead of overwrite).

use std::io::{self, Write};

/// Return to the start of the line and erase it (ANSI CSI 2K).
pub const CLEAR: &str = "\r\x1b[2K";

/// What is on the terminal's last line.
#[derive(Debug, Default)]
pub struct StatusArea {
    /// The status line drawn now, if any.
    line: Option<String>,
    /// Set once the run's results are printed: no status line is drawn again.
    suspended: bool,
}

impl StatusArea {
    /// Nothing drawn.
    pub const fn new() -> StatusArea {
        StatusArea {
            line: None,
            suspended: false,
        }
    }

    /// Whether [`StatusArea::suspend`] was called.
    pub fn is_suspended(&self) -> bool {
        self.suspended
    }

    /// Draws `line` in place of the one shown, cut to `width - 1` characters.
    pub fn draw<W: Write>(&mut self, out: &mut W, line: &str, width: usize) -> io::Result<()> {
        if self.suspended {
            return Ok(());
        }
        let cut: String = line.chars().take(width.saturating_sub(1).max(1)).collect();
        write!(out, "{CLEAR}{cut}")?;
        out.flush()?;
        self.line = Some(cut);
        Ok(())
    }

    /// Erases the status line (if drawn).
    pub fn clear<W: Write>(&mut self, out: &mut W) -> io::Result<()> {
        if self.line.take().is_some() {
            out.write_all(CLEAR.as_bytes())?;
            out.flush()?;
        }
        Ok(())
    }

    /// Erases the status line for good (before a table is printed on the same terminal).
    pub fn suspend<W: Write>(&mut self, out: &mut W) -> io::Result<()> {
        self.suspended = true;
        self.clear(out)
    }

    /// Writes a log message above the status line: the line is erased, the message written,
    /// and the line drawn again below it when the message ended its own line.
    pub fn log<W: Write>(&mut self, out: &mut W, message: &[u8]) -> io::Result<()> {
        let Some(line) = self.line.take() else {
            out.write_all(message)?;
            return out.flush();
        };
        out.write_all(CLEAR.as_bytes())?;
        out.write_all(message)?;
        if message.ends_with(b"\n") {
            out.write_all(line.as_bytes())?;
            self.line = Some(line);
        }
        out.flush()
    }
}
