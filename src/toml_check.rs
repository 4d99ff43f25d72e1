//! The one error collector behind every TOML file the program reads (frame descriptors, stand
//! configs, model files, limits files): each checker walks its tables and reports a problem by
//! its key path (`channels[1].offset`, `run.duration`); the [`Collector`] adds the file and the
//! line the key stands on (from the parser's spans), and [`ConfigErrors`] gives every problem
//! once, in the order of the file's lines, with exit status 2.

use std::path::{Path, PathBuf};

use toml::de::{DeTable, DeValue};
use toml::Spanned;

pub use crate::error::ConfigErrors;
use crate::error::UsageError;

/// Collects the problems of one file, each with its key and the key's line.
pub struct Collector {
    file: PathBuf,
    /// Every key path of the file with the line (1-based) it is written on.
    lines: Vec<(String, usize)>,
    problems: Vec<UsageError>,
}

impl Collector {
    /// A collector for `text`, read from `file`.
    pub fn new(file: &Path, text: &str) -> Collector {
        let mut lines = Vec::new();
        if let Ok(root) = DeTable::parse(text) {
            index_table(text, "", root.get_ref(), &mut lines);
        }
        Collector {
            file: file.into(),
            lines,
            problems: Vec::new(),
        }
    }

    /// A collector holding the one problem that the file cannot be read.
    pub fn unreadable(file: &Path, e: &std::io::Error) -> Collector {
        let mut c = Collector::new(file, "");
        let problem = if file.is_dir() {
            "is a directory, not a file".to_string()
        } else {
            format!("cannot read: {e}")
        };
        c.bad("(file)", problem);
        c
    }

    /// The file's name as given.
    pub fn file(&self) -> &Path {
        &self.file
    }

    /// The line of `key` (`a.b[2].c`), or of the nearest enclosing table or array written in
    /// the file (a missing key is placed at its table).
    pub fn line_of(&self, key: &str) -> Option<usize> {
        let mut k = key;
        loop {
            if let Some((_, l)) = self.lines.iter().find(|(p, _)| p == k) {
                return Some(*l);
            }
            let cut = k.rfind(['.', '['])?;
            k = &k[..cut];
        }
    }

    /// The line of `key` in the TOML file `file`, read again for it (an error found after the
    /// file was loaded, against the run's channels: [`Collector::line_of`]); `None` when the
    /// file cannot be read.
    pub fn line_in_file(file: &Path, key: &str) -> Option<usize> {
        let text = std::fs::read_to_string(file).ok()?;
        Collector::new(file, &text).line_of(key)
    }

    /// Records a problem with `key`.
    pub fn bad(&mut self, key: impl Into<String>, problem: impl Into<String>) {
        let key = key.into();
        self.problems.push(UsageError::Config {
            file: self.file.clone(),
            line: self.line_of(&key),
            key,
            problem: problem.into(),
        });
    }

    /// Records a TOML syntax error, at the line the parser names.
    pub fn syntax(&mut self, text: &str, e: &toml::de::Error) {
        let line = e.span().map(|s| line_at(text, s.start));
        self.problems.push(UsageError::Config {
            file: self.file.clone(),
            line,
            key: "(syntax)".into(),
            problem: format!("not valid TOML: {}", e.message().trim_end()),
        });
    }

    /// Parses `text` into a table, recording a syntax error if it is not TOML.
    pub fn parse(&mut self, text: &str) -> Option<toml::Table> {
        match text.parse::<toml::Table>() {
            Ok(t) => Some(t),
            Err(e) => {
                self.syntax(text, &e);
                None
            }
        }
    }

    pub fn is_empty(&self) -> bool {
        self.problems.is_empty()
    }

    /// The problems found so far.
    pub fn problems(&self) -> &[UsageError] {
        &self.problems
    }

    /// Adds problems found by another checker (already with file, key and line).
    pub fn extend(&mut self, more: impl IntoIterator<Item = UsageError>) {
        self.problems.extend(more);
    }

    /// The problems as one error, in the order of their lines in the file (the ones of the
    /// whole file first; problems on one line in the order found; those of another file that
    /// this one names, such as a stand config's descriptor, last).
    pub fn into_errors(self, what: &'static str) -> ConfigErrors {
        let own = self.file;
        let mut problems = self.problems;
        // Problems of another file (a descriptor a stand config names) after this file's.
        problems.sort_by_key(|p| match p {
            UsageError::Config { file, line, .. } => (*file != own, *line),
            _ => (false, None),
        });
        ConfigErrors { what, problems }
    }
}

/// The 1-based line of byte `at` in `text`.
fn line_at(text: &str, at: usize) -> usize {
    let at = at.min(text.len());
    text.as_bytes()[..at]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.into()
    } else {
        format!("{prefix}.{key}")
    }
}

fn index_table(text: &str, prefix: &str, t: &DeTable<'_>, out: &mut Vec<(String, usize)>) {
    for (k, v) in t {
        let path = join(prefix, k.get_ref());
        out.push((path.clone(), line_at(text, k.span().start)));
        index_value(text, &path, v, out);
    }
}

fn index_value(text: &str, path: &str, v: &Spanned<DeValue<'_>>, out: &mut Vec<(String, usize)>) {
    match v.get_ref() {
        DeValue::Table(t) => index_table(text, path, t, out),
        DeValue::Array(a) => {
            for (i, item) in a.iter().enumerate() {
                let p = format!("{path}[{i}]");
                out.push((p.clone(), line_at(text, item.span().start)));
                index_value(text, &p, item, out);
            }
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_placed_on_their_lines() {
        let text = "a = 1\n[b]\nc = 2\n\n[[d]]\ne = 3\n[[d]]\ne = 4\nf = [1,\n  2]\n";
        let c = Collector::new(Path::new("x.toml"), text);
        assert_eq!(c.line_of("a"), Some(1));
        assert_eq!(c.line_of("b.c"), Some(3));
        assert_eq!(c.line_of("b.missing"), Some(2));
        assert_eq!(c.line_of("d[1].e"), Some(8));
        assert_eq!(c.line_of("d[1].f[1]"), Some(10));
        assert_eq!(c.line_of("(syntax)"), None);
    }

    #[test]
    fn each_problem_printed_once() {
        let text = "a = 1\nb = 2\n";
        let mut c = Collector::new(Path::new("x.toml"), text);
        c.bad("a", "first problem");
        c.bad("b", "second problem");
        let e = anyhow::Error::new(c.into_errors("stand config"));
        assert_eq!(
            format!("{e:#}"),
            "stand config: 2 problems\n  x.toml:1: key `a`: first problem\n  x.toml:2: key `b`: \
             second problem"
        );
        assert_eq!(crate::error::exit_status(&e), 2);
    }
}
