//! The frame encoder: builds valid messages of a descriptor, the exact inverse of the decoder
//! for integer fields. Used by the simulator to write captures and by tests. Bytes the
//! descriptor does not describe are written as zero.

use super::decoder::width_type;
use super::descriptor::{FrameDescriptor, MessageSpec};
use super::field::{to_bits, write_bits, FieldType, RawValue};
use super::ChannelValue;

/// Why a frame could not be encoded.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EncodeError {
    #[error("{expected} channel values expected, {got} given")]
    WrongValueCount { expected: usize, got: usize },
    #[error("channel `{channel}`: raw value {raw} does not fit its {ty} field")]
    OutOfRange {
        channel: String,
        raw: f64,
        ty: &'static str,
    },
    #[error("channel `{channel}`: value is not finite")]
    NotFinite { channel: String },
}

/// Everything that goes into one frame.
#[derive(Debug, Clone, Copy)]
pub struct FrameInput<'a> {
    /// Frame number; the counter field gets `seq mod modulus` (the slot `seq x (count + 1)`
    /// with `[interleave]`).
    pub seq: u64,
    /// One per channel: [`ChannelValue::Count`] is the raw field value (for a float field, the
    /// raw number), [`ChannelValue::Real`] the physical increment (converted back through
    /// scale, tau0 and g0, rounded for integer fields).
    pub values: &'a [ChannelValue],
    /// The raw status field (see [`FrameDescriptor::status_all_valid`]).
    pub status: u64,
    pub temperature_c: Option<f64>,
}

/// One frame (with `[interleave]`: the frame followed by its `count` interleaved messages, so
/// that consecutive `seq` give a well-formed stream). No temperature.
pub fn encode(
    desc: &FrameDescriptor,
    seq: u64,
    values: &[ChannelValue],
    status: u64,
) -> Result<Vec<u8>, EncodeError> {
    encode_frame(
        desc,
        &FrameInput {
            seq,
            values,
            status,
            temperature_c: None,
        },
    )
}

/// As [`encode`], with all inputs.
pub fn encode_frame(
    desc: &FrameDescriptor,
    input: &FrameInput<'_>,
) -> Result<Vec<u8>, EncodeError> {
    let n = desc.frame().channels.len();
    if input.values.len() != n {
        return Err(EncodeError::WrongValueCount {
            expected: n,
            got: input.values.len(),
        });
    }
    match &desc.interleave {
        None => encode_message(
            desc,
            desc.frame_kind,
            input.seq,
            input.values,
            input.status,
            input.temperature_c,
        ),
        Some(il) => {
            let cycle = il.count + 1;
            let slot = input.seq.wrapping_mul(cycle);
            let mut out = encode_message(
                desc,
                desc.frame_kind,
                slot,
                input.values,
                input.status,
                input.temperature_c,
            )?;
            for k in 1..cycle {
                out.extend(encode_message(
                    desc,
                    il.message,
                    slot.wrapping_add(k),
                    &[],
                    input.status,
                    input.temperature_c,
                )?);
            }
            Ok(out)
        }
    }
}

/// One message of kind `kind` (index into `desc.messages`) with counter value
/// `counter mod modulus`; `values` must match the kind's channels (empty for kinds without).
pub fn encode_message(
    desc: &FrameDescriptor,
    kind: usize,
    counter: u64,
    values: &[ChannelValue],
    status: u64,
    temperature_c: Option<f64>,
) -> Result<Vec<u8>, EncodeError> {
    let spec: &MessageSpec = &desc.messages[kind.min(desc.messages.len() - 1)];
    if values.len() != spec.channels.len() {
        return Err(EncodeError::WrongValueCount {
            expected: spec.channels.len(),
            got: values.len(),
        });
    }
    let mut buf = vec![0u8; spec.length];
    let so = desc.sync.offset;
    buf[so..so + desc.sync.bytes.len()].copy_from_slice(&desc.sync.bytes);
    if !spec.id.is_empty() {
        let io = desc.sync.id_offset;
        buf[io..io + spec.id.len()].copy_from_slice(&spec.id);
    }
    if let Some(s) = &spec.status {
        write_bits(&mut buf, s.offset, s.ty, s.order, status);
    }
    if let Some(c) = &spec.counter {
        let value = counter % c.modulus;
        let old = super::field::read_bits(&buf, c.offset, c.ty, c.order).unwrap_or(0);
        let new = if c.modulus.is_power_of_two() {
            let mask = (c.modulus - 1) << c.shift;
            (old & !mask) | (value << c.shift)
        } else {
            value << c.shift
        };
        write_bits(&mut buf, c.offset, c.ty, c.order, new);
    }
    for (c, v) in spec.channels.iter().zip(values) {
        let raw = match *v {
            ChannelValue::Count(n) => RawValue::Int(n),
            ChannelValue::Real(x) => {
                let r = x / (c.scale * desc.kind_factor(c.kind));
                if !r.is_finite() {
                    return Err(EncodeError::NotFinite {
                        channel: c.name.clone(),
                    });
                }
                if c.ty.is_integer() {
                    RawValue::Float(r.round())
                } else {
                    RawValue::Float(r)
                }
            }
        };
        check_range(&c.name, c.ty, raw)?;
        write_bits(&mut buf, c.offset, c.ty, c.order, to_bits(c.ty, raw));
    }
    if let (Some(t), Some(tc)) = (&spec.temperature, temperature_c) {
        let r = tc / t.scale;
        let raw = if t.ty.is_integer() {
            RawValue::Float(r.round())
        } else {
            RawValue::Float(r)
        };
        check_range("temperature", t.ty, raw)?;
        write_bits(&mut buf, t.offset, t.ty, t.order, to_bits(t.ty, raw));
    }
    let ck = &spec.checksum;
    let sum = ck.algorithm.compute(&buf[ck.start..=ck.end], ck.order);
    write_bits(
        &mut buf,
        ck.at,
        width_type(ck.algorithm.width()),
        ck.order,
        sum,
    );
    Ok(buf)
}

fn check_range(name: &str, ty: FieldType, raw: RawValue) -> Result<(), EncodeError> {
    let v = raw.as_f64();
    if !v.is_finite() {
        return Err(EncodeError::NotFinite {
            channel: name.to_string(),
        });
    }
    let (lo, hi) = ty.int_range();
    let fits = match (ty, raw) {
        (FieldType::F32, _) => v.abs() <= f64::from(f32::MAX),
        (FieldType::F64, _) => true,
        (_, RawValue::Int(i)) => (lo..=hi).contains(&i),
        (_, RawValue::Float(f)) => f >= lo as f64 && f <= hi as f64,
    };
    if fits {
        Ok(())
    } else {
        Err(EncodeError::OutOfRange {
            channel: name.to_string(),
            raw: v,
            ty: ty.name(),
        })
    }
}
