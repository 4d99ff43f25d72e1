//! The key walker of model files: one TOML table at a time, typed reads that record a missing,
//! mistyped or out-of-range value with its key path in the file's one collector
//! (`crate::toml_check`, which adds the file and the line), and the rejection of every key not
//! read.

use crate::toml_check::Collector;

/// One table being read: remembers which keys were taken, so the rest can be rejected.
pub(super) struct Keys<'a> {
    table: &'a toml::Table,
    prefix: String,
    taken: Vec<&'static str>,
}

impl<'a> Keys<'a> {
    pub(super) fn new(table: &'a toml::Table, prefix: &str) -> Self {
        Self {
            table,
            prefix: prefix.to_string(),
            taken: Vec::new(),
        }
    }

    pub(super) fn path(&self, key: &str) -> String {
        if self.prefix.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.prefix)
        }
    }

    pub(super) fn get(&mut self, key: &'static str) -> Option<&'a toml::Value> {
        self.taken.push(key);
        self.table.get(key)
    }

    /// A finite number (integer or float), if present.
    pub(super) fn num(&mut self, key: &'static str, errs: &mut Collector) -> Option<f64> {
        let v = self.get(key)?;
        let x = match v {
            toml::Value::Float(f) => *f,
            toml::Value::Integer(i) => *i as f64,
            other => {
                errs.bad(
                    self.path(key),
                    format!("expected a number, found {}", other.type_str()),
                );
                return None;
            }
        };
        if !x.is_finite() {
            errs.bad(self.path(key), "must be finite");
            return None;
        }
        Some(x)
    }

    /// A number that must be > 0 (`strict`) or >= 0.
    pub(super) fn num_pos(
        &mut self,
        key: &'static str,
        strict: bool,
        errs: &mut Collector,
    ) -> Option<f64> {
        let x = self.num(key, errs)?;
        if (strict && x <= 0.0) || x < 0.0 {
            let what = if strict { "> 0" } else { ">= 0" };
            errs.bad(self.path(key), format!("must be {what}, got {x}"));
            return None;
        }
        Some(x)
    }

    pub(super) fn required(
        &mut self,
        key: &'static str,
        x: Option<f64>,
        errs: &mut Collector,
    ) -> f64 {
        if x.is_none() && !self.table.contains_key(key) {
            errs.bad(self.path(key), "missing");
        }
        x.unwrap_or(f64::NAN)
    }

    /// A boolean, if present.
    pub(super) fn boolean(&mut self, key: &'static str, errs: &mut Collector) -> Option<bool> {
        let v = self.get(key)?;
        match v.as_bool() {
            Some(b) => Some(b),
            None => {
                errs.bad(
                    self.path(key),
                    format!("expected true or false, found {}", v.type_str()),
                );
                None
            }
        }
    }

    pub(super) fn string(&mut self, key: &'static str, errs: &mut Collector) -> Option<&'a str> {
        let v = self.get(key)?;
        match v.as_str() {
            Some(s) => Some(s),
            None => {
                errs.bad(
                    self.path(key),
                    format!("expected a string, found {}", v.type_str()),
                );
                None
            }
        }
    }

    /// A table, or a list of tables; each with its key path.
    pub(super) fn tables(
        &mut self,
        key: &'static str,
        errs: &mut Collector,
    ) -> Vec<(String, &'a toml::Table)> {
        let path = self.path(key);
        match self.get(key) {
            None => Vec::new(),
            Some(toml::Value::Table(t)) => vec![(path, t)],
            Some(toml::Value::Array(a)) => {
                let mut out = Vec::new();
                for (i, v) in a.iter().enumerate() {
                    match v.as_table() {
                        Some(t) => out.push((format!("{path}[{i}]"), t)),
                        None => errs.bad(
                            format!("{path}[{i}]"),
                            format!("expected a table, found {}", v.type_str()),
                        ),
                    }
                }
                out
            }
            Some(other) => {
                errs.bad(
                    &path,
                    format!(
                        "expected a table or a list of tables, found {}",
                        other.type_str()
                    ),
                );
                Vec::new()
            }
        }
    }

    /// At most one table.
    pub(super) fn table(
        &mut self,
        key: &'static str,
        errs: &mut Collector,
    ) -> Option<(String, &'a toml::Table)> {
        let v = self.tables(key, errs);
        if v.len() > 1 {
            errs.bad(self.path(key), "expected one table, found a list");
        }
        v.into_iter().next()
    }

    /// Reject every key not taken, listing the allowed ones.
    pub(super) fn finish(self, errs: &mut Collector) {
        for k in self.table.keys() {
            if !self.taken.contains(&k.as_str()) {
                errs.bad(
                    self.path(k),
                    format!("unknown key (allowed: {})", self.taken.join(", ")),
                );
            }
        }
    }
}
