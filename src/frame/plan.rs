//! The frame message compiled once into a read plan: every field's load (width, byte order,
//! signedness) picked when the decoder is made, the status bits turned into masks, each
//! channel's kind, scale and factor resolved, so decoding a frame is a straight run of
//! fixed-width loads into the block's columns with no per-field lookups in the descriptor.
//!
//! The plan reads exactly what the descriptor's generic field reads give
//! ([`crate::frame::field::read`]): the same values, the same validity rules (status bit,
//! finite and within `ranges::MAX_ABS_VALUE` for real values), the same arithmetic order for
//! real increments (`raw x scale x kind factor`), so records stay bit for bit as before
//! (profiled: the generic reads with their type and byte-order dispatch were 590 instructions
//! of the decode thread's 1470 per siu8 frame; BENCHMARKS.md "Decoding at the speed of the
//! statistics").

use super::block::{BlockEvent, ColumnKind, FrameBlock};
use super::descriptor::{BitMeaning, FrameDescriptor};
use super::field::{ByteOrder, FieldType};

/// One field's load: width, byte order and how the bits widen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Load {
    U8,
    I8,
    U16Le,
    U16Be,
    I16Le,
    I16Be,
    U32Le,
    U32Be,
    I32Le,
    I32Be,
    F32Le,
    F32Be,
    F64Le,
    F64Be,
}

/// A loaded value: an integer exactly, a float widened to f64.
#[derive(Debug, Clone, Copy)]
enum Loaded {
    Int(i64),
    Float(f64),
}

impl Loaded {
    fn as_f64(self) -> f64 {
        match self {
            Loaded::Int(n) => n as f64,
            Loaded::Float(x) => x,
        }
    }
}

impl Load {
    fn new(ty: FieldType, order: ByteOrder) -> Load {
        let le = order == ByteOrder::Little;
        match ty {
            FieldType::U8 => Load::U8,
            FieldType::I8 => Load::I8,
            FieldType::U16 if le => Load::U16Le,
            FieldType::U16 => Load::U16Be,
            FieldType::I16 if le => Load::I16Le,
            FieldType::I16 => Load::I16Be,
            FieldType::U32 if le => Load::U32Le,
            FieldType::U32 => Load::U32Be,
            FieldType::I32 if le => Load::I32Le,
            FieldType::I32 => Load::I32Be,
            FieldType::F32 if le => Load::F32Le,
            FieldType::F32 => Load::F32Be,
            FieldType::F64 if le => Load::F64Le,
            FieldType::F64 => Load::F64Be,
        }
    }

    /// The field at `at`, or None when it runs past `msg` (never for a checked descriptor).
    #[inline(always)]
    fn read(self, msg: &[u8], at: usize) -> Option<Loaded> {
        fn b<const N: usize>(msg: &[u8], at: usize) -> Option<[u8; N]> {
            msg.get(at..at.checked_add(N)?)?.try_into().ok()
        }
        Some(match self {
            Load::U8 => Loaded::Int(i64::from(*msg.get(at)?)),
            Load::I8 => Loaded::Int(i64::from(*msg.get(at)? as i8)),
            Load::U16Le => Loaded::Int(i64::from(u16::from_le_bytes(b(msg, at)?))),
            Load::U16Be => Loaded::Int(i64::from(u16::from_be_bytes(b(msg, at)?))),
            Load::I16Le => Loaded::Int(i64::from(i16::from_le_bytes(b(msg, at)?))),
            Load::I16Be => Loaded::Int(i64::from(i16::from_be_bytes(b(msg, at)?))),
            Load::U32Le => Loaded::Int(i64::from(u32::from_le_bytes(b(msg, at)?))),
            Load::U32Be => Loaded::Int(i64::from(u32::from_be_bytes(b(msg, at)?))),
            Load::I32Le => Loaded::Int(i64::from(i32::from_le_bytes(b(msg, at)?))),
            Load::I32Be => Loaded::Int(i64::from(i32::from_be_bytes(b(msg, at)?))),
            Load::F32Le => Loaded::Float(f64::from(f32::from_le_bytes(b(msg, at)?))),
            Load::F32Be => Loaded::Float(f64::from(f32::from_be_bytes(b(msg, at)?))),
            Load::F64Le => Loaded::Float(f64::from_le_bytes(b(msg, at)?)),
            Load::F64Be => Loaded::Float(f64::from_be_bytes(b(msg, at)?)),
        })
    }

    /// Every value of the load fits an `i32` (a [`ColumnKind::Count32`] column holds it).
    fn fits_i32(self) -> bool {
        matches!(
            self,
            Load::U8
                | Load::I8
                | Load::U16Le
                | Load::U16Be
                | Load::I16Le
                | Load::I16Be
                | Load::I32Le
                | Load::I32Be
        )
    }

    /// The field's bits, unsigned (as [`crate::frame::field::read_bits`] gives them).
    #[inline(always)]
    fn bits(self, msg: &[u8], at: usize) -> Option<u64> {
        fn b<const N: usize>(msg: &[u8], at: usize) -> Option<[u8; N]> {
            msg.get(at..at.checked_add(N)?)?.try_into().ok()
        }
        Some(match self {
            Load::U8 | Load::I8 => u64::from(*msg.get(at)?),
            Load::U16Le | Load::I16Le => u64::from(u16::from_le_bytes(b(msg, at)?)),
            Load::U16Be | Load::I16Be => u64::from(u16::from_be_bytes(b(msg, at)?)),
            Load::U32Le | Load::I32Le | Load::F32Le => u64::from(u32::from_le_bytes(b(msg, at)?)),
            Load::U32Be | Load::I32Be | Load::F32Be => u64::from(u32::from_be_bytes(b(msg, at)?)),
            Load::F64Le => u64::from_le_bytes(b(msg, at)?),
            Load::F64Be => u64::from_be_bytes(b(msg, at)?),
        })
    }
}

/// One channel's read.
#[derive(Debug, Clone)]
struct ChannelRead {
    at: usize,
    load: Load,
    /// The status bit that marks the value invalid, as a mask (0: none).
    status_mask: u64,
    /// An integer increment: delivered as an exact count.
    count: bool,
    /// Channel unit per LSB and the kind's factor, applied in this order.
    scale: f64,
    factor: f64,
}

/// The frame message's reads (see the module documentation).
#[derive(Debug, Clone)]
pub(crate) struct FramePlan {
    channels: Vec<ChannelRead>,
    /// Status field: where, and whether its set bits mean valid (flipped to "set = invalid").
    status: Option<(usize, Load, bool)>,
    /// Temperature: where, its scale, its status mask.
    temperature: Option<(usize, Load, f64, u64)>,
    /// Frame counter: where, its shift, its modulus.
    counter: Option<(usize, Load, u32, u64)>,
    /// The kind of each channel's column: counts of fields that fit an `i32` narrow
    /// ([`ColumnKind::Count32`]), other counts wide, real values as f64 bits.
    pub kinds: Vec<ColumnKind>,
    /// Every channel an integer count of this one load, every field inside `min_len` bytes:
    /// a frame whose status marks none invalid is read in one tight loop.
    uniform: Option<Load>,
    /// Channel offsets, in channel order.
    offsets: Vec<usize>,
    /// Every channel's status mask together.
    all_masks: u64,
    /// Bytes a message needs for every channel field.
    min_len: usize,
}

/// The kind of each channel's column in the blocks a [`crate::frame::Decoder`] for `desc`
/// fills (a block made with these kinds takes the decoder's frames column by column).
pub fn column_kinds(desc: &FrameDescriptor) -> Vec<ColumnKind> {
    FramePlan::new(desc).kinds
}

/// A status bit as the mask [`FramePlan`] tests (`bits >> b & 1` as a mask).
fn mask(bit: Option<u32>) -> u64 {
    bit.map_or(0, |b| 1u64.wrapping_shl(b))
}

impl FramePlan {
    pub(crate) fn new(desc: &FrameDescriptor) -> FramePlan {
        let spec = desc.frame();
        let channels: Vec<ChannelRead> = spec
            .channels
            .iter()
            .map(|c| ChannelRead {
                at: c.offset,
                load: Load::new(c.ty, c.order),
                status_mask: mask(c.status_bit),
                count: c.is_count(),
                scale: c.scale,
                factor: desc.kind_factor(c.kind),
            })
            .collect();
        let uniform = channels
            .first()
            .map(|c| c.load)
            .filter(|l| !matches!(l, Load::F32Le | Load::F32Be | Load::F64Le | Load::F64Be))
            .filter(|l| channels.iter().all(|c| c.count && c.load == *l));
        FramePlan {
            uniform,
            offsets: channels.iter().map(|c| c.at).collect(),
            all_masks: channels.iter().fold(0, |m, c| m | c.status_mask),
            min_len: spec
                .channels
                .iter()
                .map(|c| c.offset + c.ty.size())
                .max()
                .unwrap_or(0),
            kinds: channels
                .iter()
                .map(|c| match (c.count, c.load.fits_i32()) {
                    (true, true) => ColumnKind::Count32,
                    (true, false) => ColumnKind::Count,
                    (false, _) => ColumnKind::Real,
                })
                .collect(),
            channels,
            status: spec.status.as_ref().map(|s| {
                (
                    s.offset,
                    Load::new(s.ty, s.order),
                    s.bit_set_means == BitMeaning::Valid,
                )
            }),
            temperature: spec.temperature.as_ref().map(|t| {
                (
                    t.offset,
                    Load::new(t.ty, t.order),
                    t.scale,
                    mask(t.status_bit),
                )
            }),
            counter: spec
                .counter
                .as_ref()
                .map(|c| (c.offset, Load::new(c.ty, c.order), c.shift, c.modulus)),
        }
    }

    /// The frame's counter modulo its modulus (0 without a counter).
    #[inline(always)]
    pub(crate) fn counter(&self, msg: &[u8]) -> u64 {
        let Some((at, load, shift, m)) = self.counter else {
            return 0;
        };
        let raw = load.bits(msg, at).unwrap_or(0) >> shift;
        if m.is_power_of_two() {
            raw & (m - 1)
        } else {
            raw % m
        }
    }

    /// Reads a good frame's channels, validity and temperature into `out` as frame `seq`;
    /// values marked invalid or not usable are counted in `invalid`.
    #[inline]
    pub(crate) fn decode(&self, msg: &[u8], seq: u64, invalid: &mut u64, out: &mut FrameBlock) {
        let bad = self.begin(msg, seq, out);
        if self.deferrable(msg, bad, out) {
            // A batch of one frame, starting at 0.
            self.fill_columns(msg, &[0], out);
        } else {
            self.read_channels(msg, bad, invalid, out);
        }
    }

    /// Starts frame `seq` in `out` (its event: counter, temperature, status) and returns the
    /// status bits that mark a value invalid; the channels follow, from
    /// [`FramePlan::read_channels`] or, for a [`FramePlan::deferrable`] frame, later from
    /// [`FramePlan::fill_columns`].
    #[inline]
    pub(crate) fn begin(&self, msg: &[u8], seq: u64, out: &mut FrameBlock) -> u64 {
        let status = self.status.and_then(|(at, load, _)| load.bits(msg, at));
        // The status bits that mark a value invalid: set bits of a fault status, clear bits of
        // a valid status.
        let bad = match (status, self.status) {
            (Some(st), Some((_, _, true))) => !st,
            (Some(st), _) => st,
            _ => 0,
        };
        let temperature_c = self.temperature.and_then(|(at, load, scale, m)| {
            if bad & m != 0 {
                return None;
            }
            load.read(msg, at).map(|r| r.as_f64() * scale)
        });
        out.begin_frame(BlockEvent::Frame {
            seq,
            temperature_c,
            status,
        });
        bad
    }

    /// Every channel field inside `msg` and none marked invalid by `bad`.
    #[inline]
    fn clean(&self, msg: &[u8], bad: u64) -> bool {
        bad & self.all_masks == 0 && msg.len() >= self.min_len
    }

    /// The channels of a frame begun with `bad` may be left to [`FramePlan::fill_columns`]:
    /// all counts of one integer load, every field inside, none marked invalid, and the
    /// block's columns all counts. What [`FramePlan::decode`] would then push is exactly the
    /// loads in channel order, so filling them column by column later gives the same block.
    #[inline]
    pub(crate) fn deferrable(&self, msg: &[u8], bad: u64, out: &FrameBlock) -> bool {
        self.uniform.is_some()
            && out.all_counts() == self.kinds.first().copied()
            && self.clean(msg, bad)
    }

    /// Reads the channels of the frame begun last, one by one (any kinds, holes, status).
    pub(crate) fn read_channels(
        &self,
        msg: &[u8],
        bad: u64,
        invalid: &mut u64,
        out: &mut FrameBlock,
    ) {
        for (ch, c) in self.channels.iter().enumerate() {
            if bad & c.status_mask != 0 {
                *invalid += 1;
                out.push_missing(ch);
                continue;
            }
            match c.load.read(msg, c.at) {
                Some(Loaded::Int(n)) if c.count => out.push_count(ch, n),
                Some(r) => {
                    // NaN, infinite or absurd values (a float field's NaN, a damaged exponent)
                    // are invalid: a gap, counted, never summed into the channel.
                    let v = r.as_f64() * c.scale * c.factor;
                    if !v.is_finite() || crate::ranges::plausible(v).is_none() {
                        *invalid += 1;
                        out.push_missing(ch);
                    } else {
                        out.push_real(ch, v);
                    }
                }
                None => out.push_missing(ch),
            }
        }
    }

    /// Fills the columns of the deferred frames whose messages start at `starts` in `data`
    /// (each checked [`FramePlan::deferrable`] when begun, in this order): channel by channel,
    /// one pass over the starts per column, instead of eight pushes per frame (the per-value
    /// push was most of the field reads' cost; BENCHMARKS.md "session 7").
    pub(crate) fn fill_columns(&self, data: &[u8], starts: &[usize], out: &mut FrameBlock) {
        /// One column's values, read at `at` from every start.
        fn column<const N: usize, T>(
            data: &[u8],
            starts: &[usize],
            at: usize,
            col: &mut Vec<T>,
            conv: impl Fn([u8; N]) -> T,
        ) {
            col.extend(starts.iter().map(|&s| {
                let mut b = [0u8; N];
                b.copy_from_slice(&data[s + at..s + at + N]);
                conv(b)
            }));
        }
        /// Narrow columns (`i32`), for loads that fit one.
        fn narrow<const N: usize>(
            o: &[usize],
            d: &[u8],
            st: &[usize],
            out: &mut FrameBlock,
            conv: impl Fn([u8; N]) -> i32 + Copy,
        ) {
            out.extend_count32_columns(|ch, col| column(d, st, o[ch], col, conv));
        }
        /// Wide columns (`i64`).
        fn wide<const N: usize>(
            o: &[usize],
            d: &[u8],
            st: &[usize],
            out: &mut FrameBlock,
            conv: impl Fn([u8; N]) -> i64 + Copy,
        ) {
            out.extend_count_columns(|ch, col| column(d, st, o[ch], col, conv));
        }
        let Some(load) = self.uniform else {
            return;
        };
        let (o, d, st) = (&self.offsets, data, starts);
        match load {
            Load::U8 => narrow::<1>(o, d, st, out, |b| i32::from(b[0])),
            Load::I8 => narrow::<1>(o, d, st, out, |b| i32::from(b[0] as i8)),
            Load::U16Le => narrow::<2>(o, d, st, out, |b| i32::from(u16::from_le_bytes(b))),
            Load::U16Be => narrow::<2>(o, d, st, out, |b| i32::from(u16::from_be_bytes(b))),
            Load::I16Le => narrow::<2>(o, d, st, out, |b| i32::from(i16::from_le_bytes(b))),
            Load::I16Be => narrow::<2>(o, d, st, out, |b| i32::from(i16::from_be_bytes(b))),
            Load::I32Le => narrow::<4>(o, d, st, out, i32::from_le_bytes),
            Load::I32Be => narrow::<4>(o, d, st, out, i32::from_be_bytes),
            Load::U32Le => wide::<4>(o, d, st, out, |b| i64::from(u32::from_le_bytes(b))),
            Load::U32Be => wide::<4>(o, d, st, out, |b| i64::from(u32::from_be_bytes(b))),
            // Floats are never counts (no uniform plan).
            Load::F32Le | Load::F32Be | Load::F64Le | Load::F64Be => {}
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::frame::field::{read, read_bits, RawValue};

    /// Every load gives what the generic field reads give, on bytes that make signs, NaNs and
    /// byte order matter; a field past the end is None either way.
    #[test]
    fn loads_agree_with_field_reads() {
        let msg: Vec<u8> = (0..16u8)
            .map(|i| i.wrapping_mul(37).wrapping_add(0x81))
            .collect();
        let types = [
            FieldType::U8,
            FieldType::I8,
            FieldType::U16,
            FieldType::I16,
            FieldType::U32,
            FieldType::I32,
            FieldType::F32,
            FieldType::F64,
        ];
        for ty in types {
            for order in [ByteOrder::Little, ByteOrder::Big] {
                let load = Load::new(ty, order);
                for at in 0..=msg.len() {
                    let want = read(&msg, at, ty, order);
                    let got = load.read(&msg, at);
                    match (want, got) {
                        (None, None) => {}
                        (Some(RawValue::Int(a)), Some(Loaded::Int(b))) => assert_eq!(a, b),
                        (Some(RawValue::Float(a)), Some(Loaded::Float(b))) => {
                            assert_eq!(a.to_bits(), b.to_bits())
                        }
                        other => panic!("{ty:?} {order:?} at {at}: {other:?}"),
                    }
                    assert_eq!(read_bits(&msg, at, ty, order), load.bits(&msg, at));
                }
            }
        }
    }
}

/// The two column widths: counts of fields that fit an `i32` in narrow columns, `u32` counts
/// wide, each read back exactly at the ends of its range, by the column-by-column fill of a
/// uniform frame and by the per-channel reads of a mixed one.
#[cfg(test)]
mod width_tests {
    use super::*;
    use crate::frame::{encode_frame, ChannelValue, Decoder, FrameEvent, FrameInput};

    /// A 4-byte-sync frame with counter, fault status and one channel per type of `types`.
    fn descriptor(types: &[&str]) -> FrameDescriptor {
        let mut text = String::from("name = \"w\"\nrate_hz = 100.0\nbyte_order = \"little\"\n");
        let mut at = 8;
        let mut channels = String::new();
        for (i, ty) in types.iter().enumerate() {
            let size = FieldType::parse(ty).expect("type").size();
            channels += &format!(
                "[[channels]]\nname = \"c{i}\"\noffset = {at}\ntype = \"{ty}\"\nscale = 1.0\n\
                 unit = \"u\"\nkind = \"increment\"\nstatus_bit = {i}\n"
            );
            at += size;
        }
        text += &format!(
            "length = {}\n[sync]\nbytes = [0xAA, 0x55]\noffset = 0\n\
             [checksum]\nalgorithm = \"CRC-16/IBM-3740\"\nrange = [2, {}]\nat = {}\n\
             [counter]\noffset = 2\ntype = \"u16\"\nmodulus = 65536\n\
             [status]\noffset = 4\ntype = \"u32\"\nbit_set_means = \"fault\"\n{channels}",
            at + 2,
            at - 1,
            at
        );
        FrameDescriptor::from_toml_str(&text, std::path::Path::new("w.toml")).expect("descriptor")
    }

    /// Frames of `values` (one row per frame) decoded whole: the values come back exactly.
    fn round_trip(desc: &FrameDescriptor, rows: &[Vec<i64>]) {
        let mut bytes = Vec::new();
        for (seq, row) in rows.iter().enumerate() {
            let values: Vec<ChannelValue> = row.iter().map(|&c| ChannelValue::Count(c)).collect();
            let input = FrameInput {
                seq: seq as u64,
                values: &values,
                status: 0,
                temperature_c: None,
            };
            bytes.extend(encode_frame(desc, &input).expect("encode"));
        }
        let mut dec = Decoder::new(desc.clone());
        dec.push(&bytes);
        dec.finish();
        let got: Vec<Vec<Option<ChannelValue>>> = dec
            .drain()
            .map(|e| match e {
                FrameEvent::Frame(f) => f.values,
                other => panic!("unexpected {other:?}"),
            })
            .collect();
        let want: Vec<Vec<Option<ChannelValue>>> = rows
            .iter()
            .map(|r| r.iter().map(|&c| Some(ChannelValue::Count(c))).collect())
            .collect();
        assert_eq!(got, want);
    }

    #[test]
    fn narrow_and_wide_columns() {
        use ColumnKind::{Count, Count32};
        let cases: [(&[&str], &[ColumnKind]); 4] = [
            (&["i32", "i32", "i32"], &[Count32; 3]),
            (&["i16", "i16"], &[Count32; 2]),
            (&["u32", "u32"], &[Count; 2]),
            // Mixed loads: no column fill, each value pushed to its own column's width.
            (
                &["u8", "i16", "u16", "i32", "u32"],
                &[Count32, Count32, Count32, Count32, Count],
            ),
        ];
        for (types, kinds) in cases {
            let desc = descriptor(types);
            let plan = FramePlan::new(&desc);
            assert_eq!(plan.kinds, kinds, "{types:?}");
            assert_eq!(column_kinds(&desc), kinds);
            let range = |ty: &str| match ty {
                "u8" => (0, 255),
                "i16" => (-32768, 32767),
                "u16" => (0, 65535),
                "i32" => (i64::from(i32::MIN), i64::from(i32::MAX)),
                _ => (0, i64::from(u32::MAX)),
            };
            let mut rows = Vec::new();
            for k in 0..600i64 {
                rows.push(
                    types
                        .iter()
                        .map(|ty| {
                            let (lo, hi) = range(ty);
                            match k % 3 {
                                0 => lo,
                                1 => hi,
                                _ => lo + (k * 7919) % (hi - lo),
                            }
                        })
                        .collect(),
                );
            }
            round_trip(&desc, &rows);
        }
    }
}
