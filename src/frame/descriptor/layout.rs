//! Where a message's fields sit: each field inside the message's length, and no two fields
//! sharing a byte. Problems go to the collector with the key of the field.

use super::walker::Ctx;
use super::{MessageSpec, SyncSpec};

/// Records a problem for each pair of a message's fields that share a byte: sync, id, stored
/// checksum, counter, status, temperature and channels each own their bytes.
pub(super) fn check_overlaps(
    ctx: &mut Ctx,
    prefix: &str,
    sync: &SyncSpec,
    multi: bool,
    m: &MessageSpec,
) {
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
pub(super) fn check_span(ctx: &mut Ctx, key: String, offset: usize, size: usize, length: usize) {
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
