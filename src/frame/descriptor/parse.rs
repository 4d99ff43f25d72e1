//! The descriptor checker: a walk over the TOML tables of a descriptor that builds the
//! [`FrameDescriptor`] types and records every problem with its key path in the one collector
//! (`crate::toml_check`): unknown keys, missing or mistyped values, fields past the message's
//! end or overlapping each other, and numbers outside `crate::ranges` (rate, scale, length,
//! channel count). This file reads the top level (name, rate, sync, interleave) and checks
//! message kinds against each other; `walker` reads tables, `message` one message kind,
//! `layout` where fields sit.

use std::path::Path;

use toml::Table;

use super::layout::{check_overlaps, check_span};
use super::message::{parse_message, MESSAGE_KEYS};
use super::walker::{Ctx, Tbl};
use super::*;
use crate::frame::field::ByteOrder;

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
const SYNC_KEYS: &[&str] = &["bytes", "offset", "id_offset"];
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
