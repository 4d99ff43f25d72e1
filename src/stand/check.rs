//! The typed reads of a stand config: a collector with the file attached, and getters for a
//! table, a string, a number of seconds, a `channels` table and `[[limits]]` tables that record
//! a mistyped or out-of-range value at its key path instead of failing; unknown keys rejected.

use super::WHAT;

/// Collects problems with the file name attached.
pub(super) struct Check {
    pub(super) c: crate::toml_check::Collector,
}

impl Check {
    pub(super) fn bad(&mut self, key: &str, problem: impl Into<String>) {
        self.c.bad(key, problem);
    }

    /// A table's keys must all be in `allowed`.
    pub(super) fn known_keys(&mut self, prefix: &str, t: &toml::Table, allowed: &[&str]) {
        for k in t.keys() {
            if !allowed.contains(&k.as_str()) {
                self.bad(
                    &join(prefix, k),
                    format!("unknown key (allowed here: {})", allowed.join(", ")),
                );
            }
        }
    }

    pub(super) fn table<'t>(
        &mut self,
        root: &'t toml::Table,
        key: &str,
    ) -> Option<&'t toml::Table> {
        match root.get(key) {
            None => None,
            Some(toml::Value::Table(t)) => Some(t),
            Some(v) => {
                self.bad(key, format!("must be a table, not {}", v.type_str()));
                None
            }
        }
    }

    /// A table under `key` of `t`, itself at `prefix`.
    pub(super) fn sub_table<'t>(
        &mut self,
        t: &'t toml::Table,
        prefix: &str,
        key: &str,
    ) -> Option<&'t toml::Table> {
        match t.get(key) {
            None => None,
            Some(toml::Value::Table(t)) => Some(t),
            Some(v) => {
                self.bad(
                    &join(prefix, key),
                    format!("must be a table, not {}", v.type_str()),
                );
                None
            }
        }
    }

    pub(super) fn string(&mut self, t: &toml::Table, prefix: &str, key: &str) -> Option<String> {
        match t.get(key) {
            None => None,
            Some(toml::Value::String(s)) if !s.trim().is_empty() => Some(s.clone()),
            Some(v) => {
                self.bad(
                    &join(prefix, key),
                    format!("must be a non-empty string, not {}", show(v)),
                );
                None
            }
        }
    }

    /// A number of seconds in `[min, max]` (`crate::ranges`).
    pub(super) fn seconds(
        &mut self,
        t: &toml::Table,
        prefix: &str,
        key: &str,
        min: f64,
        max: f64,
    ) -> Option<f64> {
        let v = t.get(key)?;
        let x = match v {
            toml::Value::Float(f) => *f,
            toml::Value::Integer(i) => *i as f64,
            _ => {
                self.bad(
                    &join(prefix, key),
                    format!("must be a number of seconds, not {}", show(v)),
                );
                return None;
            }
        };
        match crate::ranges::check_seconds(x, min, max) {
            Ok(x) => Some(x),
            Err(e) => {
                self.bad(&join(prefix, key), e);
                None
            }
        }
    }
    /// A `channels` table (`include = [...]`) at `prefix`.
    pub(super) fn channels(&mut self, c: &toml::Table, prefix: &str) -> Option<Vec<String>> {
        self.known_keys(prefix, c, &["include"]);
        let v = c.get("include")?;
        let list: Option<Vec<String>> = v.as_array().and_then(|a| {
            a.iter()
                .map(|x| x.as_str().map(String::from))
                .collect::<Option<Vec<_>>>()
        });
        match list {
            Some(l) if !l.is_empty() => Some(l),
            _ => {
                self.bad(
                    &join(prefix, "include"),
                    format!(
                        "must be a non-empty array of channel names, not {}",
                        show(v)
                    ),
                );
                None
            }
        }
    }

    /// The `[[limits]]` tables under `key` of `t` (`limits`, `unit[i].limits`).
    pub(super) fn limits(
        &mut self,
        t: &toml::Table,
        key: &str,
    ) -> Vec<crate::model::limits::LimitSpec> {
        let at = key.rsplit('.').next().unwrap_or(key);
        match t.get(at) {
            None => Vec::new(),
            Some(toml::Value::Array(a)) => {
                crate::model::limits::from_tables(a, key, &mut self.c, WHAT)
            }
            Some(v) => {
                self.bad(
                    key,
                    format!("must be an array of tables ([[{key}]]), not {}", show(v)),
                );
                Vec::new()
            }
        }
    }
}

pub(super) fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.into()
    } else {
        format!("{prefix}.{key}")
    }
}

pub(super) fn show(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("\"{s}\""),
        toml::Value::Table(_) => "a table".into(),
        toml::Value::Array(_) => "an array".into(),
        other => other.to_string(),
    }
}
