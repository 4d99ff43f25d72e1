//! The TOML walker of the descriptor checker: one table at a time, with its key path, the keys
//! it may hold and typed getters that record a missing or mistyped value (with its key path) in
//! the one collector (`crate::toml_check`) instead of failing. What the values mean is left to
//! `parse` and `message`.

use std::collections::BTreeSet;

use toml::{Table, Value};

use crate::frame::field::{ByteOrder, FieldType, FIELD_TYPE_NAMES};
use crate::toml_check::Collector;

pub(super) type Ctx = Collector;

/// One TOML table being read: its key path, the keys it may have, the keys read so far.
pub(super) struct Tbl<'t> {
    t: &'t Table,
    path: String,
    allowed: &'static [&'static str],
    used: BTreeSet<String>,
}

impl<'t> Tbl<'t> {
    pub(super) fn new(t: &'t Table, path: String, allowed: &'static [&'static str]) -> Self {
        Tbl {
            t,
            path,
            allowed,
            used: BTreeSet::new(),
        }
    }

    pub(super) fn key(&self, k: &str) -> String {
        if self.path.is_empty() {
            k.to_string()
        } else {
            format!("{}.{k}", self.path)
        }
    }

    pub(super) fn get(&mut self, k: &str) -> Option<&'t Value> {
        self.used.insert(k.to_string());
        self.t.get(k)
    }

    pub(super) fn has(&self, k: &str) -> bool {
        self.t.contains_key(k)
    }

    /// Reports keys that are not allowed here.
    pub(super) fn finish(self, ctx: &mut Ctx) {
        for k in self.t.keys() {
            if !self.allowed.contains(&k.as_str()) {
                ctx.bad(
                    self.key(k),
                    format!("unknown key (allowed here: {})", self.allowed.join(", ")),
                );
            }
        }
    }

    pub(super) fn uint(&mut self, ctx: &mut Ctx, k: &str, required: bool) -> Option<u64> {
        match self.get(k) {
            None => {
                if required {
                    ctx.bad(self.key(k), "missing (a non-negative integer)");
                }
                None
            }
            Some(Value::Integer(i)) if *i >= 0 => Some(*i as u64),
            Some(v) => {
                ctx.bad(
                    self.key(k),
                    format!("expected a non-negative integer, found {}", show(v)),
                );
                None
            }
        }
    }

    pub(super) fn float(&mut self, ctx: &mut Ctx, k: &str, required: bool) -> Option<f64> {
        match self.get(k) {
            None => {
                if required {
                    ctx.bad(self.key(k), "missing (a number)");
                }
                None
            }
            Some(Value::Integer(i)) => Some(*i as f64),
            Some(Value::Float(f)) if f.is_finite() => Some(*f),
            Some(v) => {
                ctx.bad(
                    self.key(k),
                    format!("expected a finite number, found {}", show(v)),
                );
                None
            }
        }
    }

    pub(super) fn string(&mut self, ctx: &mut Ctx, k: &str, required: bool) -> Option<&'t str> {
        match self.get(k) {
            None => {
                if required {
                    ctx.bad(self.key(k), "missing (a string)");
                }
                None
            }
            Some(Value::String(s)) => Some(s.as_str()),
            Some(v) => {
                ctx.bad(self.key(k), format!("expected a string, found {}", show(v)));
                None
            }
        }
    }

    pub(super) fn bytes(&mut self, ctx: &mut Ctx, k: &str, required: bool) -> Option<Vec<u8>> {
        match self.get(k) {
            None => {
                if required {
                    ctx.bad(
                        self.key(k),
                        "missing (an array of bytes, e.g. [0xAA, 0x55])",
                    );
                }
                None
            }
            Some(Value::Array(a)) => {
                let mut out = Vec::with_capacity(a.len());
                for (i, v) in a.iter().enumerate() {
                    match v {
                        Value::Integer(b) if (0..=255).contains(b) => out.push(*b as u8),
                        _ => {
                            ctx.bad(
                                format!("{}[{i}]", self.key(k)),
                                format!("expected a byte 0..=255, found {}", show(v)),
                            );
                            return None;
                        }
                    }
                }
                if out.is_empty() {
                    ctx.bad(self.key(k), "must not be empty");
                    return None;
                }
                Some(out)
            }
            Some(v) => {
                ctx.bad(
                    self.key(k),
                    format!("expected an array of bytes, found {}", show(v)),
                );
                None
            }
        }
    }

    pub(super) fn table(&mut self, ctx: &mut Ctx, k: &str) -> Option<&'t Table> {
        match self.get(k) {
            None => None,
            Some(Value::Table(t)) => Some(t),
            Some(v) => {
                ctx.bad(self.key(k), format!("expected a table, found {}", show(v)));
                None
            }
        }
    }

    pub(super) fn tables(&mut self, ctx: &mut Ctx, k: &str) -> Option<Vec<&'t Table>> {
        match self.get(k) {
            None => None,
            Some(Value::Array(a)) => {
                let mut out = Vec::new();
                for (i, v) in a.iter().enumerate() {
                    match v {
                        Value::Table(t) => out.push(t),
                        _ => ctx.bad(
                            format!("{}[{i}]", self.key(k)),
                            format!("expected a table, found {}", show(v)),
                        ),
                    }
                }
                Some(out)
            }
            Some(v) => {
                ctx.bad(
                    self.key(k),
                    format!("expected an array of tables, found {}", show(v)),
                );
                None
            }
        }
    }

    pub(super) fn field_type(&mut self, ctx: &mut Ctx, k: &str) -> Option<FieldType> {
        let s = self.string(ctx, k, true)?;
        let t = FieldType::parse(s);
        if t.is_none() {
            ctx.bad(
                self.key(k),
                format!("unknown type `{s}` (allowed: {FIELD_TYPE_NAMES})"),
            );
        }
        t
    }

    pub(super) fn byte_order(&mut self, ctx: &mut Ctx, default: ByteOrder) -> ByteOrder {
        match self.string(ctx, "byte_order", false) {
            None => default,
            Some(s) => ByteOrder::parse(s).unwrap_or_else(|| {
                ctx.bad(
                    self.key("byte_order"),
                    format!("unknown byte order `{s}` (allowed: little, big)"),
                );
                default
            }),
        }
    }

    pub(super) fn offset(&mut self, ctx: &mut Ctx, k: &str) -> Option<usize> {
        self.uint(ctx, k, true).map(|v| v as usize)
    }
}

pub(super) fn show(v: &Value) -> String {
    let s = match v {
        Value::String(s) => format!("string {s:?}"),
        Value::Integer(i) => format!("integer {i}"),
        Value::Float(f) => format!("float {f}"),
        Value::Boolean(b) => format!("boolean {b}"),
        Value::Datetime(d) => format!("datetime {d}"),
        Value::Array(_) => "an array".to_string(),
        Value::Table(_) => "a table".to_string(),
    };
    s.chars().take(60).collect()
}
