//! The frame layer: bytes from a unit -> decoded frames of increments. Pure: no I/O, no async.
//!
//! - [`descriptor`]: the TOML descriptor language and its checked form [`FrameDescriptor`].
//! - [`decoder`]: [`Decoder`], fed arbitrary chunks of a byte stream; finds sync, checks length
//!   and checksum, resynchronises after garbage, follows the frame counter (gaps, duplicates)
//!   and keeps the [`Health`] counters of docs/records.md.
//! - [`encoder`]: builds valid frames of a descriptor (for the simulator and tests).
//! - [`block`]: [`FrameBlock`], decoded frames flat, a column per channel (no allocation per
//!   frame), as the decoder hands them on.
//! - [`checksum`], [`field`]: the checksum algorithms and wire types they share (`crc_msb`: the
//!   MSB-first CRCs, sixteen bytes per step).
//! - `plan`: the frame message compiled once into a read plan (what [`Decoder`] reads a good
//!   frame with).
//!
//! Sources (serial, UDP, files) own the bytes and hand them to a [`Decoder`]; the accumulators
//! downstream receive [`DecodedFrame`]s and [`FrameEvent::Gap`]s and never see bytes.

pub mod block;
pub mod checksum;
mod crc_msb;
pub mod decoder;
pub mod descriptor;
pub mod encoder;
pub mod field;
pub(crate) mod plan;
mod seq_tracker;

pub use block::{BlockEvent, ColumnKind, ColumnValues, FrameBlock, FrameSink, GapAt, Hole};
pub use decoder::{Decoder, DecoderState, Health};
pub use descriptor::{DescriptorErrors, FrameDescriptor};
pub use encoder::{encode, encode_frame, EncodeError, FrameInput};
pub use plan::column_kinds;

/// One channel's value in one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ChannelValue {
    /// An integer increment field: the physical increment is `count x scale` (the channel's
    /// [`ChannelInfo::scale`]). Kept exact so the accumulators can sum in integers.
    Count(i64),
    /// Already the physical increment over one step, in the channel's unit (rate and accel_g
    /// fields converted with tau0 and g0).
    Real(f64),
}

impl ChannelValue {
    /// The physical increment, given the channel's LSB for counts.
    pub fn physical(self, scale: Option<f64>) -> f64 {
        match self {
            Self::Count(n) => n as f64 * scale.unwrap_or(1.0),
            Self::Real(x) => x,
        }
    }
}

/// Name, unit and LSB of a channel as the decoder delivers it.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelInfo {
    pub name: String,
    /// Unit of the increment (e.g. `arcsec`, `rad`, `m/s`).
    pub unit: String,
    /// LSB in `unit` for channels delivered as [`ChannelValue::Count`]; None for `Real`.
    pub scale: Option<f64>,
}

/// One good frame.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedFrame {
    /// The frame counter unwrapped across its modulus: starts at the first counter value seen
    /// (at 0 for formats with `[interleave]`); a running index when the format has no counter.
    pub seq: u64,
    /// One entry per channel, in [`FrameDescriptor::channels`] order; None where the status
    /// field marks the channel invalid.
    pub values: Vec<Option<ChannelValue>>,
    /// Temperature in degC, when the format has one and it is marked valid.
    pub temperature_c: Option<f64>,
    /// The raw status field, when the format has one.
    pub status: Option<u64>,
}

/// What the decoder emits, in stream order.
#[derive(Debug, Clone, PartialEq)]
pub enum FrameEvent {
    Frame(DecodedFrame),
    /// `missing` frames were lost (by the counter) before the next frame.
    Gap {
        missing: u64,
    },
}
