//! The descriptor checker: a walk over the TOML tables of a descriptor that builds the
//! [`FrameDescriptor`] types and records every problem with its key path in the one collector
//! (`crate::toml_check`): unknown keys, missing or mistyped values, fields past the message's
//! end or overlapping each other, and numbers outside `crate::ranges` (rate, scale, length,
//! channel count).

use std::collections::BTreeSet;
use std::path::Path;

use toml::{Table, Value};

use super::*;
use crate::frame::checksum::{ChecksumAlgorithm, ALGORITHM_NAMES};
use crate::frame::field::{ByteOrder, FieldType, FIELD_TYPE_NAMES};
use crate::toml_check::Collector;

type Ctx = Collector;

/// One TOML table being read: its key path, the keys it may have, the keys read so far.
struct Tbl<'t> {
    t: &'t Table,
    path: String,
    allowed: &'static [&'static str],
    used: BTreeSet<String>,
}

impl<'t> Tbl<'t> {
    fn new(t: &'t Table, path: String, allowed: &'static [&'static str]) -> Self {
        Tbl {
            t,
            path,
            allowed,
            used: BTreeSet::new(),
        }
    }

    fn key(&self, k: &str) -> String {
        if self.path.is_empty() {
            k.to_string()
        } else {
            format!("{}.{k}", self.path)
        }
    }

    fn get(&mut self, k: &str) -> Option<&'t Value> {
        self.used.insert(k.to_string());
        self.t.get(k)
    }

    fn has(&self, k: &str) -> bool {
        self.t.contains_key(k)
    }

    /// Reports keys that are not allowed here.
    fn finish(self, ctx: &mut Ctx) {
        for k in self.t.keys() {
            if !self.allowed.contains(&k.as_str()) {
                ctx.bad(
                    self.key(k),
                    format!("unknown key (allowed here: {})", self.allowed.join(", ")),
                );
            }
        }
    }

    fn uint(&mut self, ctx: &mut Ctx, k: &str, required: bool) -> Option<u64> {
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

    fn float(&mut self, ctx: &mut Ctx, k: &str, required: bool) -> Option<f64> {
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

    fn string(&mut self, ctx: &mut Ctx, k: &str, required: bool) -> Option<&'t str> {
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

    fn bytes(&mut self, ctx: &mut Ctx, k: &str, required: bool) -> Option<Vec<u8>> {
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

    fn table(&mut self, ctx: &mut Ctx, k: &str) -> Option<&'t Table> {
        match self.get(k) {
            None => None,
            Some(Value::Table(t)) => Some(t),
            Some(v) => {
                ctx.bad(self.key(k), format!("expected a table, found {}", show(v)));
                None
            }
        }
    }

    fn tables(&mut self, ctx: &mut Ctx, k: &str) -> Option<Vec<&'t Table>> {
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

    fn field_type(&mut self, ctx: &mut Ctx, k: &str) -> Option<FieldType> {
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

    fn byte_order(&mut self, ctx: &mut Ctx, default: ByteOrder) -> ByteOrder {
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

    fn offset(&mut self, ctx: &mut Ctx, k: &str) -> Option<usize> {
        self.uint(ctx, k, true).map(|v| v as usize)
    }
}

fn show(v: &Value) -> String {
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

/// Records a problem when a scale is 0 or outside the magnitudes `crate::ranges` allows.
fn check_scale(ctx: &mut Ctx, key: String, scale: f64) {
    use crate::ranges::{MAX_SCALE, MIN_SCALE};
    if !(MIN_SCALE..=MAX_SCALE).contains(&scale.abs()) {
        ctx.bad(
            key,
            format!(
                "{}: the magnitude must be from {MIN_SCALE:e} to {MAX_SCALE:e} units per LSB",
                crate::ranges::show(scale)
            ),
        );
    }
}

/// Records a problem for each pair of a message's fields that share a byte: sync, id, stored
/// checksum, counter, status, temperature and channels each own their bytes.
fn check_overlaps(ctx: &mut Ctx, prefix: &str, sync: &SyncSpec, multi: bool, m: &MessageSpec) {
    let mut fields: Vec<(String, usize, usize)> =
        vec![("sync.bytes".into(), sync.offset, sync.bytes.len())];
    if multi {
        fields.push((format!("{prefix}id"), sync.id_offset, m.id.len()));
    }
    fields.push((
        format!("{prefix}checksum.at"),
        m.checksum.at,
        m.checksum.algorithm.width(),
    ));
    if let Some(c) = &m.counter {
        fields.push((format!("{prefix}counter"), c.offset, c.ty.size()));
    }
    if let Some(s) = &m.status {
        fields.push((format!("{prefix}status"), s.offset, s.ty.size()));
    }
    if let Some(t) = &m.temperature {
        fields.push((format!("{prefix}temperature"), t.offset, t.ty.size()));
    }
    for (i, c) in m.channels.iter().enumerate() {
        fields.push((format!("{prefix}channels[{i}]"), c.offset, c.ty.size()));
    }
    for (j, (key, off, len)) in fields.iter().enumerate() {
        if let Some((other, o2, l2)) = fields[..j]
            .iter()
            .find(|(_, o2, l2)| off < &(o2 + l2) && o2 < &(off + len))
        {
            ctx.bad(
                key.clone(),
                format!(
                    "bytes {off}..{} overlap {other} (bytes {o2}..{})",
                    off + len - 1,
                    o2 + l2 - 1
                ),
            );
        }
    }
}

/// Records a problem when `offset + size` runs past `length`.
fn check_span(ctx: &mut Ctx, key: String, offset: usize, size: usize, length: usize) {
    if offset.saturating_add(size) > length {
        ctx.bad(
            key,
            format!(
                "offset {offset} + {size} byte(s) runs past the message length {length} \
                 (the last byte is {})",
                length.saturating_sub(1)
            ),
        );
    }
}

const TOP_KEYS: &[&str] = &[
    "name",
    "description",
    "rate_hz",
    "byte_order",
    "sync",
    "messages",
    "interleave",
];
const TOP_SINGLE_KEYS: &[&str] = &[
    "name",
    "description",
    "rate_hz",
    "byte_order",
    "sync",
    "length",
    "checksum",
    "counter",
    "status",
    "temperature",
    "channels",
];
const MESSAGE_KEYS: &[&str] = &[
    "name",
    "id",
    "length",
    "checksum",
    "counter",
    "status",
    "temperature",
    "channels",
];
const SYNC_KEYS: &[&str] = &["bytes", "offset", "id_offset"];
const CHECKSUM_KEYS: &[&str] = &["algorithm", "range", "at", "byte_order"];
const COUNTER_KEYS: &[&str] = &["offset", "type", "modulus", "shift", "byte_order"];
const STATUS_KEYS: &[&str] = &["offset", "type", "bit_set_means", "byte_order"];
const TEMPERATURE_KEYS: &[&str] = &["offset", "type", "scale", "status_bit", "byte_order"];
const CHANNEL_KEYS: &[&str] = &[
    "name",
    "offset",
    "type",
    "scale",
    "unit",
    "kind",
    "status_bit",
    "byte_order",
];
const INTERLEAVE_KEYS: &[&str] = &["message", "count"];

pub(super) fn parse_descriptor(
    ctx: &mut Ctx,
    table: &Table,
    source: &Path,
) -> Option<FrameDescriptor> {
    let multi = table.contains_key("messages");
    let mut top = Tbl::new(
        table,
        String::new(),
        if multi { TOP_KEYS } else { TOP_SINGLE_KEYS },
    );
    let stem = source
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let name = top
        .string(ctx, "name", false)
        .map(str::to_string)
        .unwrap_or(stem);
    let description = top
        .string(ctx, "description", false)
        .unwrap_or("")
        .to_string();
    let rate_hz = top.float(ctx, "rate_hz", true);
    if let Some(r) = rate_hz {
        use crate::ranges::{MAX_RATE_HZ, MIN_RATE_HZ};
        if !(MIN_RATE_HZ..=MAX_RATE_HZ).contains(&r) {
            ctx.bad(
                "rate_hz",
                format!(
                    "must be from {MIN_RATE_HZ:e} to {MAX_RATE_HZ:e} Hz, found {}",
                    crate::ranges::show(r)
                ),
            );
        }
    }
    let order = top.byte_order(ctx, ByteOrder::Little);

    let sync = match top.table(ctx, "sync") {
        Some(t) => {
            let mut s = Tbl::new(t, "sync".into(), SYNC_KEYS);
            let bytes = s.bytes(ctx, "bytes", true);
            let offset = s.uint(ctx, "offset", false).unwrap_or(0) as usize;
            let id_offset = s.uint(ctx, "id_offset", false);
            if multi && id_offset.is_none() {
                ctx.bad(
                    "sync.id_offset",
                    "missing: several message kinds need the offset of their `id` bytes",
                );
            }
            s.finish(ctx);
            bytes.map(|bytes| SyncSpec {
                bytes,
                offset,
                id_offset: id_offset.unwrap_or(0) as usize,
            })
        }
        None => {
            ctx.bad("sync", "missing (a table with `bytes` and `offset`)");
            None
        }
    };

    let mut messages = Vec::new();
    if multi {
        let tables = top.tables(ctx, "messages").unwrap_or_default();
        if tables.is_empty() {
            ctx.bad("messages", "must list at least one message kind");
        }
        for (i, t) in tables.into_iter().enumerate() {
            let mut m = Tbl::new(t, format!("messages[{i}]"), MESSAGE_KEYS);
            let msg = parse_message(ctx, &mut m, order, true);
            m.finish(ctx);
            messages.push(msg);
        }
    } else {
        let msg = parse_message(ctx, &mut top, order, false);
        messages.push(msg);
    }

    let interleave_table = if multi {
        top.table(ctx, "interleave")
    } else {
        None
    };
    top.finish(ctx);

    let sync = sync?;
    let messages: Vec<MessageSpec> = messages.into_iter().collect::<Option<Vec<_>>>()?;
    let rate_hz = rate_hz?;

    // Cross-message checks.
    let prefix = |i: usize| {
        if multi {
            format!("messages[{i}].")
        } else {
            String::new()
        }
    };
    for (i, m) in messages.iter().enumerate() {
        check_span(
            ctx,
            "sync.bytes".into(),
            sync.offset,
            sync.bytes.len(),
            m.length,
        );
        if multi {
            check_span(
                ctx,
                format!("{}id", prefix(i)),
                sync.id_offset,
                m.id.len(),
                m.length,
            );
            if m.id.len() != messages[0].id.len() {
                ctx.bad(
                    format!("{}id", prefix(i)),
                    format!(
                        "has {} byte(s); every message id must have the same length as \
                         messages[0].id ({})",
                        m.id.len(),
                        messages[0].id.len()
                    ),
                );
            }
            if let Some(j) = messages[..i].iter().position(|o| o.id == m.id) {
                ctx.bad(
                    format!("{}id", prefix(i)),
                    format!("same id as messages[{j}]"),
                );
            }
            if let Some(j) = messages[..i].iter().position(|o| o.name == m.name) {
                ctx.bad(
                    format!("{}name", prefix(i)),
                    format!("same name as messages[{j}]"),
                );
            }
        }
    }
    for (i, m) in messages.iter().enumerate() {
        check_overlaps(ctx, &prefix(i), &sync, multi, m);
        if m.channels.len() > crate::ranges::MAX_CHANNELS {
            ctx.bad(
                format!("{}channels", prefix(i)),
                format!(
                    "{} channels: at most {} are analysed in one run",
                    m.channels.len(),
                    crate::ranges::MAX_CHANNELS
                ),
            );
        }
    }
    let with_channels: Vec<usize> = (0..messages.len())
        .filter(|&i| !messages[i].channels.is_empty())
        .collect();
    let frame_kind = match with_channels.as_slice() {
        [k] => *k,
        [] => {
            ctx.bad(
                format!(
                    "{}channels",
                    if multi {
                        "messages[].".into()
                    } else {
                        String::new()
                    }
                ),
                "no message kind carries channels",
            );
            return None;
        }
        [_, rest @ ..] => {
            for &k in rest {
                ctx.bad(
                    format!("{}channels", prefix(k)),
                    "only one message kind may carry channels",
                );
            }
            return None;
        }
    };

    let mut interleave = None;
    if let Some(t) = interleave_table {
        let mut it = Tbl::new(t, "interleave".into(), INTERLEAVE_KEYS);
        let mname = it.string(ctx, "message", true);
        let count = it.uint(ctx, "count", true);
        it.finish(ctx);
        if let (Some(mname), Some(count)) = (mname, count) {
            match messages.iter().position(|m| m.name == mname) {
                None => ctx.bad(
                    "interleave.message",
                    format!(
                        "no message kind named `{mname}` (have: {})",
                        messages
                            .iter()
                            .map(|m| m.name.as_str())
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ),
                Some(k) if k == frame_kind => ctx.bad(
                    "interleave.message",
                    "must name a message kind other than the one with channels",
                ),
                Some(k) => {
                    if count == 0 {
                        ctx.bad("interleave.count", "must be >= 1");
                    }
                    let fc = messages[frame_kind].counter.as_ref();
                    let ic = messages[k].counter.as_ref();
                    match (fc, ic) {
                        (Some(a), Some(b)) if a.modulus == b.modulus => {}
                        (Some(_), Some(_)) => ctx.bad(
                            format!("{}counter.modulus", prefix(k)),
                            "interleaved messages must share the frame's counter modulus",
                        ),
                        _ => ctx.bad(
                            "interleave",
                            "both the frame message and the interleaved message need a counter",
                        ),
                    }
                    interleave = Some(InterleaveSpec { message: k, count });
                }
            }
        }
    }
    for (i, m) in messages.iter().enumerate() {
        let shares = i == frame_kind || interleave.as_ref().is_some_and(|s| s.message == i);
        if m.counter.is_some() && !shares {
            ctx.bad(
                format!("{}counter", prefix(i)),
                "a counter on a message without channels needs [interleave] naming it",
            );
        }
    }

    Some(FrameDescriptor {
        name,
        description,
        source: source.to_path_buf(),
        rate_hz,
        sync,
        messages,
        frame_kind,
        interleave,
    })
}

fn parse_message(
    ctx: &mut Ctx,
    m: &mut Tbl<'_>,
    order: ByteOrder,
    multi: bool,
) -> Option<MessageSpec> {
    let name = if multi {
        m.string(ctx, "name", true).unwrap_or("").to_string()
    } else {
        "frame".to_string()
    };
    let id = if multi {
        m.bytes(ctx, "id", true).unwrap_or_default()
    } else {
        Vec::new()
    };
    let mut length = m.uint(ctx, "length", true);
    match length {
        Some(0) => ctx.bad(m.key("length"), "must be > 0"),
        Some(l) if l > crate::ranges::MAX_MESSAGE_BYTES => {
            ctx.bad(
                m.key("length"),
                format!(
                    "{l} bytes: a message may have at most {} bytes",
                    crate::ranges::MAX_MESSAGE_BYTES
                ),
            );
            length = None;
        }
        _ => {}
    }
    let length = length.map(|v| v as usize);
    let len = length.unwrap_or(usize::MAX);

    let checksum = match m.table(ctx, "checksum") {
        None => {
            ctx.bad(
                m.key("checksum"),
                "missing (a table with `algorithm`, `range`, `at`)",
            );
            None
        }
        Some(t) => parse_checksum(
            ctx,
            Tbl::new(t, m.key("checksum"), CHECKSUM_KEYS),
            order,
            len,
        ),
    };
    let counter = m.table(ctx, "counter").and_then(|t| {
        let mut c = Tbl::new(t, m.key("counter"), COUNTER_KEYS);
        let offset = c.offset(ctx, "offset");
        let ty = c.field_type(ctx, "type");
        let modulus = c.uint(ctx, "modulus", true);
        let shift = c.uint(ctx, "shift", false).unwrap_or(0);
        let o = c.byte_order(ctx, order);
        let key = c.key("offset");
        if let (Some(off), Some(ty)) = (offset, ty) {
            check_span(ctx, key, off, ty.size(), len);
            if !ty.is_integer() {
                ctx.bad(c.key("type"), "a counter must be an integer type");
            }
        }
        if let (Some(ty), Some(md)) = (ty, modulus) {
            let room = ty.bits().saturating_sub(shift as u32);
            if md < 2 || (room < 64 && md > (1u64 << room)) {
                ctx.bad(
                    c.key("modulus"),
                    format!(
                        "{md} does not fit: must be 2..=2^{room} for a {} field shifted by {shift}",
                        ty.name()
                    ),
                );
            }
        }
        if shift >= 32 {
            ctx.bad(c.key("shift"), "must be < 32");
        }
        c.finish(ctx);
        Some(CounterSpec {
            offset: offset?,
            ty: ty?,
            order: o,
            modulus: modulus?,
            shift: shift as u32,
        })
    });
    let status = m.table(ctx, "status").and_then(|t| {
        let mut s = Tbl::new(t, m.key("status"), STATUS_KEYS);
        let offset = s.offset(ctx, "offset");
        let ty = s.field_type(ctx, "type");
        let meaning = match s.string(ctx, "bit_set_means", true) {
            Some("fault") => Some(BitMeaning::Fault),
            Some("valid") => Some(BitMeaning::Valid),
            Some(other) => {
                ctx.bad(
                    s.key("bit_set_means"),
                    format!("unknown value `{other}` (allowed: fault, valid)"),
                );
                None
            }
            None => None,
        };
        let o = s.byte_order(ctx, order);
        if let (Some(off), Some(ty)) = (offset, ty) {
            check_span(ctx, s.key("offset"), off, ty.size(), len);
            if !ty.is_integer() {
                ctx.bad(s.key("type"), "a status field must be an integer type");
            }
        }
        s.finish(ctx);
        Some(StatusSpec {
            offset: offset?,
            ty: ty?,
            order: o,
            bit_set_means: meaning?,
        })
    });
    let status_bits = status.as_ref().map(|s| s.ty.bits());
    let has_status_table = m.has("status");

    let check_bit = |ctx: &mut Ctx, key: String, bit: Option<u64>| -> Option<u32> {
        let b = bit?;
        match status_bits {
            Some(n) if b < u64::from(n) => Some(b as u32),
            Some(n) => {
                ctx.bad(key, format!("bit {b} is outside the {n}-bit status field"));
                None
            }
            None => {
                if !has_status_table {
                    ctx.bad(key, "needs a [status] field in the same message");
                }
                None
            }
        }
    };

    let temperature = m.table(ctx, "temperature").and_then(|t| {
        let mut s = Tbl::new(t, m.key("temperature"), TEMPERATURE_KEYS);
        let offset = s.offset(ctx, "offset");
        let ty = s.field_type(ctx, "type");
        let scale = s.float(ctx, "scale", false).unwrap_or(1.0);
        let bit = s.uint(ctx, "status_bit", false);
        let bit_key = s.key("status_bit");
        let o = s.byte_order(ctx, order);
        if let (Some(off), Some(ty)) = (offset, ty) {
            check_span(ctx, s.key("offset"), off, ty.size(), len);
        }
        check_scale(ctx, s.key("scale"), scale);
        let bit = check_bit(ctx, bit_key, bit);
        s.finish(ctx);
        Some(TemperatureSpec {
            offset: offset?,
            ty: ty?,
            order: o,
            scale,
            status_bit: bit,
        })
    });

    let mut channels = Vec::new();
    let mut ok = true;
    for (ci, t) in m
        .tables(ctx, "channels")
        .unwrap_or_default()
        .into_iter()
        .enumerate()
    {
        let mut c = Tbl::new(t, m.key(&format!("channels[{ci}]")), CHANNEL_KEYS);
        let cname = c.string(ctx, "name", true);
        let offset = c.offset(ctx, "offset");
        let ty = c.field_type(ctx, "type");
        let scale = c.float(ctx, "scale", true);
        let unit = c.string(ctx, "unit", true);
        let kind = match c.string(ctx, "kind", true) {
            Some("increment") => Some(ChannelKind::Increment),
            Some("rate") => Some(ChannelKind::Rate),
            Some("accel_g") => Some(ChannelKind::AccelG),
            Some(other) => {
                ctx.bad(
                    c.key("kind"),
                    format!("unknown kind `{other}` (allowed: increment, rate, accel_g)"),
                );
                None
            }
            None => None,
        };
        let bit = c.uint(ctx, "status_bit", false);
        let bit = check_bit(ctx, c.key("status_bit"), bit);
        let o = c.byte_order(ctx, order);
        if let (Some(off), Some(ty)) = (offset, ty) {
            check_span(ctx, c.key("offset"), off, ty.size(), len);
        }
        if let Some(sc) = scale {
            check_scale(ctx, c.key("scale"), sc);
        }
        if let Some(n) = cname {
            if n.is_empty() {
                ctx.bad(c.key("name"), "must not be empty");
            } else if channels.iter().any(|x: &ChannelSpec| x.name == n) {
                ctx.bad(c.key("name"), format!("duplicate channel name `{n}`"));
            }
        }
        c.finish(ctx);
        match (cname, offset, ty, scale, unit, kind) {
            (Some(n), Some(off), Some(ty), Some(sc), Some(u), Some(k)) => {
                channels.push(ChannelSpec {
                    name: n.to_string(),
                    offset: off,
                    ty,
                    order: o,
                    scale: sc,
                    unit: u.to_string(),
                    kind: k,
                    status_bit: bit,
                })
            }
            _ => ok = false,
        }
    }
    if !ok {
        return None;
    }
    Some(MessageSpec {
        name,
        id,
        length: length?,
        checksum: checksum?,
        counter,
        status,
        temperature,
        channels,
    })
}

fn parse_checksum(
    ctx: &mut Ctx,
    mut c: Tbl<'_>,
    order: ByteOrder,
    len: usize,
) -> Option<ChecksumSpec> {
    let algorithm = c.string(ctx, "algorithm", true).and_then(|s| {
        let a = ChecksumAlgorithm::parse(s);
        if a.is_none() {
            ctx.bad(
                c.key("algorithm"),
                format!("unknown checksum `{s}` (allowed: {ALGORITHM_NAMES})"),
            );
        }
        a
    });
    let range = match c.get("range") {
        Some(Value::Array(a))
            if a.len() == 2 && a.iter().all(|v| matches!(v, Value::Integer(i) if *i >= 0)) =>
        {
            let s = a[0].as_integer().unwrap_or(0) as usize;
            let e = a[1].as_integer().unwrap_or(0) as usize;
            if s > e {
                ctx.bad(c.key("range"), format!("start {s} is after end {e}"));
                None
            } else if e >= len {
                ctx.bad(
                    c.key("range"),
                    format!(
                        "end {e} runs past the message length {len} (the last byte is {})",
                        len.saturating_sub(1)
                    ),
                );
                None
            } else {
                Some((s, e))
            }
        }
        None => {
            ctx.bad(
                c.key("range"),
                "missing ([first, last] covered byte, inclusive)",
            );
            None
        }
        Some(v) => {
            ctx.bad(
                c.key("range"),
                format!(
                    "expected [first, last] (two non-negative integers), found {}",
                    show(v)
                ),
            );
            None
        }
    };
    let at = c.uint(ctx, "at", true).map(|v| v as usize);
    let o = c.byte_order(ctx, order);
    if let (Some(a), Some(at)) = (algorithm, at) {
        check_span(ctx, c.key("at"), at, a.width(), len);
        if let Some((s, e)) = range {
            if at <= e && s < at + a.width() {
                ctx.bad(
                    c.key("range"),
                    format!(
                        "covers the checksum itself (bytes {at}..{})",
                        at + a.width() - 1
                    ),
                );
            }
            if a == ChecksumAlgorithm::Sum16 && (e - s + 1) % 2 != 0 {
                ctx.bad(
                    c.key("range"),
                    "a sum16 checksum needs an even number of covered bytes",
                );
            }
        }
    }
    c.finish(ctx);
    let (start, end) = range?;
    Some(ChecksumSpec {
        algorithm: algorithm?,
        start,
        end,
        at: at?,
        order: o,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every shipped descriptor loads, from disk and embedded, and the two agree.
    #[test]
    fn shipped_descriptors_load() {
        for (name, _) in BUILTIN {
            let embedded = FrameDescriptor::builtin(name)
                .expect("listed")
                .unwrap_or_else(|e| panic!("{e}"));
            let disk = FrameDescriptor::from_path(
                &Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("config/frames/{name}.toml")),
            )
            .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(embedded.messages, disk.messages);
            assert_eq!(embedded.name, *name);
        }
    }

    fn problems(text: &str) -> Vec<(String, String, String)> {
        let e =
            FrameDescriptor::from_toml_str(text, Path::new("bad.toml")).expect_err("should fail");
        e.problems
            .iter()
            .map(|p| match p {
                UsageError::Config {
                    file, key, problem, ..
                } => (file.display().to_string(), key.clone(), problem.clone()),
                other => panic!("not a config error: {other}"),
            })
            .collect()
    }

    /// Four independent mistakes are all reported, each with the file and its key, in the
    /// order of their lines.
    #[test]
    fn several_problems_reported_together() {
        let text = r#"
rate_hz = 250.0
length = 42
colour = "red"
[sync]
bytes = [0xAA, 0x55]
[checksum]
algorithm = "CRC-16/FOO"
range = [2, 39]
at = 40
[[channels]]
name = "g1"
offset = 4
type = "i33"
scale = 0.004
unit = "arcsec"
kind = "increment"
[[channels]]
name = "g2"
offset = 40
type = "i32"
scale = 0.004
unit = "arcsec"
kind = "increment"
"#;
        let p = problems(text);
        let keys: Vec<&str> = p.iter().map(|(_, k, _)| k.as_str()).collect();
        assert_eq!(
            keys,
            vec![
                "colour",
                "checksum.algorithm",
                "channels[0].type",
                "channels[1].offset"
            ],
            "{p:?}"
        );
        assert!(p.iter().all(|(f, _, _)| f == "bad.toml"));
        assert!(p[0].2.contains("unknown key"));
        assert!(p[1].2.contains("unknown checksum `CRC-16/FOO`"));
        assert!(p[2].2.contains("unknown type `i33`"));
        assert!(p[3].2.contains("runs past the message length 42"));
    }

    /// Key paths inside [[messages]]; a bad [interleave] name; the error maps to exit status 2.
    #[test]
    fn message_key_paths_and_exit_status() {
        let text = r#"
rate_hz = 100.0
[sync]
bytes = [0x0E]
id_offset = 1
[interleave]
message = "nope"
count = 5
[[messages]]
name = "inertial"
id = [0x02]
lenght = 44
[messages.checksum]
algorithm = "sum16"
range = [0, 40]
at = 42
[[messages.channels]]
name = "gx"
offset = 18
type = "i32"
scale = 1.0
unit = "rad"
kind = "velocity"
"#;
        let p = problems(text);
        let keys: Vec<&str> = p.iter().map(|(_, k, _)| k.as_str()).collect();
        assert!(keys.contains(&"messages[0].length"), "{p:?}");
        assert!(keys.contains(&"messages[0].lenght"), "{p:?}");
        assert!(keys.contains(&"messages[0].channels[0].kind"), "{p:?}");
        let e = FrameDescriptor::from_toml_str(text, Path::new("bad.toml")).expect_err("fails");
        let msg = e.to_string();
        assert!(
            msg.contains("bad.toml:12: key `messages[0].lenght`: unknown key"),
            "{msg}"
        );
        assert_eq!(crate::error::exit_status(&anyhow::Error::from(e)), 2);

        // With the length fixed: the odd sum16 coverage and the unknown interleave name remain.
        let fixed = text
            .replace("lenght", "length")
            .replace("velocity", "increment");
        let p = problems(&fixed);
        let keys: Vec<&str> = p.iter().map(|(_, k, _)| k.as_str()).collect();
        assert_eq!(
            keys,
            vec!["interleave.message", "messages[0].checksum.range"],
            "{p:?}"
        );
    }

    /// TOML syntax errors are reported with the file.
    #[test]
    fn syntax_error() {
        let p = problems("rate_hz = = 3");
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].1, "(syntax)");
    }

    /// Names resolve (search path or embedded copy); paths load; unknown names and missing files
    /// are usage errors.
    #[test]
    fn load_by_name_and_path() {
        let d = FrameDescriptor::load("siu8").unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(d.frame_len(), 42);
        assert_eq!(d.rate_hz, 250.0);
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/frames/kvh1750.toml");
        let d =
            FrameDescriptor::load(path.to_str().expect("utf8")).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(d.frame_len(), 36);
        assert_eq!(d.source, path);
        let e = FrameDescriptor::load("no_such_format").expect_err("unknown");
        assert!(e
            .to_string()
            .contains("unknown frame format `no_such_format`"));
        let e = FrameDescriptor::load("missing/dir/x.toml").expect_err("missing");
        assert!(e
            .to_string()
            .contains("missing/dir/x.toml: key `(file)`: cannot read"));
    }
}
