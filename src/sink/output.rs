//! Result files (`--out`, `--capture`, a stand config's outputs) opened so that an earlier result
//! is never lost by accident.
//!
//! - **Refused when not empty.** An existing non-empty regular file is refused (a usage error,
//!   exit status 2, naming the file and `--force`) unless the run overwrites on purpose
//!   (`--force`) or continues it (`--resume`, which appends).
//! - **Emptied only once the run produces something.** The file is opened when the run is
//!   planned (so a path that cannot be written fails before any data is read), but it is not
//!   truncated then: its old content is cut away at the first byte written, which happens only
//!   once the input is open and every option was accepted. A start that fails (a missing input,
//!   an absent serial port, a bad option found late) leaves an earlier result as it was, and a
//!   file that did not exist before is removed again.
//!
//! - **One writer.** A regular file is locked (advisory, `flock`) while the run has it open; a
//!   second run given the same file is refused (exit status 2) instead of interleaving its
//!   records with the first run's.
//!
//! - **Never over the data.** An output that is one of the files the run reads (the input
//!   itself, by a hard or symbolic link or another path to it, or standard input redirected
//!   from it) is refused before anything is opened, `--force` or not ([`refuse_outputs_over_inputs`]):
//!   `--force` replaces an earlier result, never the recording it would be computed from, which
//!   the first record would cut short while it is being read.
//!
//! Special files (`/dev/null`, a FIFO, a terminal) are never truncated or refused.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::UsageError;

/// A file a command reads, as its messages name it: `the input run.csv`, `--holdout h.csv`,
/// `standard input` (whose path is then `/dev/stdin`, the file it is redirected from).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ReadFile {
    pub named: String,
    pub path: PathBuf,
}

/// A file a command writes: the option that names it (`--out`, `--capture`, `-o`) and its path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WrittenFile {
    pub option: String,
    pub path: PathBuf,
}

/// Refuses (a usage error, exit status 2) an output that is one of the files the command reads,
/// checked before any output is opened: a run with `--out run.csv --force` over its own input
/// `run.csv` used to truncate the recording at its first record while still reading it, and end
/// with exit status 0 over part of it. The first output found is named, with the input.
pub fn refuse_outputs_over_inputs(
    outputs: &[WrittenFile],
    inputs: &[ReadFile],
) -> Result<(), UsageError> {
    for out in outputs {
        if let Some(input) = inputs.iter().find(|i| same_file(&out.path, &i.path)) {
            return Err(UsageError::Option(format!(
                "{} {}: is the same file as {}: --force replaces an earlier result, never the \
                 data it is computed from; write the result to another file",
                out.option,
                out.path.display(),
                input.named
            )));
        }
    }
    Ok(())
}

/// Whether `a` and `b` are one regular file: the same (device, inode) where both exist (a hard
/// link, a symbolic link, `dir/../name`); elsewhere than Unix, the same canonical path. A path
/// that does not exist is no file a run reads; special files (`/dev/null`, a FIFO) are not
/// compared.
pub fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    if !(ma.is_file() && mb.is_file()) {
        return false;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ma.dev() == mb.dev() && ma.ino() == mb.ino()
    }
    #[cfg(not(unix))]
    {
        matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
    }
}

/// How a result file is opened.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputMode {
    /// A new result: refused if the file holds one, unless `force`.
    Fresh { force: bool },
    /// A resumed run: appended to.
    Append,
}

impl OutputMode {
    /// The mode of a command's `--force` and `--resume`.
    pub fn new(force: bool, resume: bool) -> OutputMode {
        if resume {
            OutputMode::Append
        } else {
            OutputMode::Fresh { force }
        }
    }
}

/// A result file opened for a run, emptied at its first write (see the module documentation).
#[derive(Debug)]
pub struct OutputFile {
    path: PathBuf,
    file: File,
    /// Cut the old content away at the first write (a regular file, not appended to).
    truncate_on_write: bool,
    /// The file did not exist before: removed again if nothing was written.
    created: bool,
    written: bool,
}

impl OutputFile {
    /// Opens `path` for a run without changing it; `what` names the option in messages
    /// (`--out`, `--capture`, `[output] path`).
    pub fn open(path: &Path, mode: OutputMode, what: &str) -> Result<OutputFile, UsageError> {
        let meta = std::fs::metadata(path).ok();
        let regular = meta.as_ref().is_some_and(|m| m.is_file());
        if meta.as_ref().is_some_and(|m| m.is_dir()) {
            return Err(UsageError::Option(format!(
                "{what} {}: is a directory, not a file",
                path.display()
            )));
        }
        if let (OutputMode::Fresh { force: false }, Some(m)) = (mode, &meta) {
            if m.is_file() && m.len() > 0 {
                return Err(UsageError::Option(format!(
                    "{what} {}: exists and holds {} bytes (an earlier result?); pass --force to \
                     overwrite it{}",
                    path.display(),
                    m.len(),
                    if what.contains("capture") || what.contains("aggregate") {
                        ""
                    } else {
                        ", or --resume to continue its run"
                    }
                )));
            }
        }
        let mut opts = OpenOptions::new();
        opts.write(true).create(true);
        if mode == OutputMode::Append {
            opts.append(true);
        }
        let file = opts.open(path).map_err(|e| {
            UsageError::Option(format!("{what} {}: cannot open: {e}", path.display()))
        })?;
        // One writer at a time: a second run given the same file (or --out and --capture naming
        // one file) would interleave its bytes with the first's. The lock is advisory and lasts
        // as long as the file is open; where locks are not supported the file is used as is.
        if regular || meta.is_none() {
            if let Err(std::fs::TryLockError::WouldBlock) = file.try_lock() {
                return Err(UsageError::Option(format!(
                    "{what} {}: another writer has it open (an allanscope run still going, or \
                     two options naming the same file); wait for it to end or choose another file",
                    path.display()
                )));
            }
        }
        Ok(OutputFile {
            path: path.to_path_buf(),
            file,
            truncate_on_write: regular && matches!(mode, OutputMode::Fresh { .. }),
            created: meta.is_none(),
            written: false,
        })
    }

    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The file, emptied first if this is the first write; for writers that need a `File`
    /// (the capture's async writer).
    pub fn into_started(mut self) -> std::io::Result<File> {
        self.start()?;
        let f = self.file.try_clone()?;
        // The clone is the file from now on; `self` must not remove it.
        self.created = false;
        Ok(f)
    }

    fn start(&mut self) -> std::io::Result<()> {
        if !self.written {
            if self.truncate_on_write {
                self.file.set_len(0)?;
            }
            self.written = true;
        }
        Ok(())
    }
}

impl Write for OutputFile {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        if buf.is_empty() {
            return Ok(0);
        }
        self.start()?;
        self.file.write(buf)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.file.flush()
    }
}

impl Drop for OutputFile {
    fn drop(&mut self) {
        // A file this run created and never wrote to is not a result: leave no empty file behind.
        if self.created && !self.written {
            let empty = std::fs::metadata(&self.path).is_ok_and(|m| m.is_file() && m.len() == 0);
            if empty {
                let _ = std::fs::remove_file(&self.path);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(tag: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("allanscope-output-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn an_earlier_result_is_refused_then_kept_until_the_first_write() {
        let d = dir("refuse");
        let p = d.join("out.jsonl");
        std::fs::write(&p, "earlier\n").unwrap();
        let e = OutputFile::open(&p, OutputMode::Fresh { force: false }, "--out").unwrap_err();
        assert!(e.to_string().contains("--force"), "{e}");
        assert!(e.to_string().contains("holds 8 bytes"), "{e}");
        // Forced, but nothing written: the earlier result is intact.
        drop(OutputFile::open(&p, OutputMode::Fresh { force: true }, "--out").unwrap());
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "earlier\n");
        // Forced and written: replaced, not appended to.
        let mut f = OutputFile::open(&p, OutputMode::Fresh { force: true }, "--out").unwrap();
        f.write_all(b"new\n").unwrap();
        drop(f);
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new\n");
        // Appended.
        let mut f = OutputFile::open(&p, OutputMode::Append, "--out").unwrap();
        f.write_all(b"more\n").unwrap();
        drop(f);
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new\nmore\n");
        let _ = std::fs::remove_dir_all(&d);
    }

    #[test]
    fn a_new_file_never_written_is_removed_and_an_empty_one_is_not_refused() {
        let d = dir("new");
        let p = d.join("new.jsonl");
        drop(OutputFile::open(&p, OutputMode::Fresh { force: false }, "--out").unwrap());
        assert!(!p.exists());
        std::fs::write(&p, "").unwrap();
        let mut f = OutputFile::open(&p, OutputMode::Fresh { force: false }, "--out").unwrap();
        f.write_all(b"x").unwrap();
        drop(f);
        assert_eq!(std::fs::read(&p).unwrap(), b"x");
        assert!(
            OutputFile::open(&d, OutputMode::Fresh { force: true }, "--out")
                .unwrap_err()
                .to_string()
                .contains("is a directory")
        );
        let _ = std::fs::remove_dir_all(&d);
    }
}
