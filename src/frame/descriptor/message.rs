//! One message kind of a descriptor: its length, checksum, counter, status and temperature
//! fields and its channels, read from one TOML table (the top level, or one `[[messages]]`
//! entry) into a [`MessageSpec`], with every problem recorded under the message's key path.
//! Checks across message kinds are `parse`'s.

use toml::Value;

use super::layout::check_span;
use super::walker::{show, Ctx, Tbl};
use super::*;
use crate::frame::checksum::{ChecksumAlgorithm, ALGORITHM_NAMES};
use crate::frame::field::ByteOrder;

pub(super) const MESSAGE_KEYS: &[&str] = &[
    "name",
    "id",
    "length",
    "checksum",
    "counter",
    "status",
    "temperature",
    "channels",
];
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

pub(super) fn parse_message(
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
