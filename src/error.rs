//! Errors that reach the user, and the exit status each maps to (docs/records.md: 2 for usage or
//! configuration errors, 1 for anything else).

use std::fmt;
use std::path::PathBuf;

/// An error in what the user asked for or gave us: a bad option, a bad config or descriptor key,
/// an unreadable input row. Exit status 2.
#[derive(Debug, thiserror::Error)]
pub enum UsageError {
    #[error("{0}")]
    Option(String),
    /// A problem with an input file, at `line` (1-based; 0: the file as a whole, e.g. it cannot
    /// be opened, printed without a line).
    #[error("{}{}: {problem}", file.display(), line_part(*line))]
    Input {
        file: PathBuf,
        line: u64,
        problem: String,
    },
    /// A problem in a TOML file (descriptor, stand config, model, limits), at `line` when the
    /// key is written in the file (collected by `toml_check`).
    #[error("{}{}: key `{key}`: {problem}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Config {
        file: PathBuf,
        line: Option<usize>,
        key: String,
        problem: String,
    },
    /// A checkpoint that cannot be used: missing, damaged, or saved with other options.
    #[error("checkpoint {file}: {problem}")]
    Checkpoint { file: PathBuf, problem: String },
}

/// Every problem found in one file (or why it could not be read). Each is a
/// [`UsageError::Config`]; the program exits with status 2. Printed as a count and one line
/// per problem; it has no `source`, so an error chain never prints a problem twice.
#[derive(Debug)]
pub struct ConfigErrors {
    /// What the file is: "frame descriptor", "stand config", "model file", "limits file".
    pub what: &'static str,
    pub problems: Vec<UsageError>,
}

impl fmt::Display for ConfigErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.problems.len();
        write!(
            f,
            "{}: {n} problem{}",
            self.what,
            if n == 1 { "" } else { "s" }
        )?;
        for p in &self.problems {
            write!(f, "\n  {p}")?;
        }
        Ok(())
    }
}

impl std::error::Error for ConfigErrors {}

/// `: line N` for an input's line, nothing for the file as a whole (line 0).
fn line_part(line: u64) -> String {
    if line == 0 {
        String::new()
    } else {
        format!(": line {line}")
    }
}

/// The exit status for an error chain: 2 when a [`UsageError`] is anywhere in it, else 1.
pub fn exit_status(err: &anyhow::Error) -> i32 {
    if err.chain().any(|e| {
        e.downcast_ref::<UsageError>().is_some() || e.downcast_ref::<ConfigErrors>().is_some()
    }) {
        2
    } else {
        1
    }
}
