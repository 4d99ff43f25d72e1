//! Frame descriptors: the TOML language that tells the decoder how a unit frames its data, and
//! its checked form [`FrameDescriptor`]. Loading collects every problem it finds (file, key,
//! what is wrong, what is allowed) and rejects unknown keys; nothing here reads a byte stream.
//!
//! This file holds the types; the checker that builds them from TOML is `parse` (the top level
//! and the checks across message kinds), `message` (one message kind), `walker` (typed reads of
//! one TOML table) and `layout` (fields inside the message, no shared bytes).
//!
//! # The language
//!
//! ```toml
//! name = "siu8"                 # optional; defaults to the file stem
//! description = "..."           # optional
//! rate_hz = 250.0               # nominal frame rate; tau0 = 1 / rate_hz
//! byte_order = "little"         # default for every field ("little" | "big")
//!
//! [sync]                        # bytes every message starts with, at `offset` in the message
//! bytes = [0xAA, 0x55]
//! offset = 0                    # optional, default 0
//! id_offset = 2                 # where a message's `id` bytes sit (only with [[messages]])
//!
//! # One message kind: its keys at the top level, as below. Several kinds: one [[messages]]
//! # table each, with `name` and `id = [bytes]`; exactly one kind carries `channels`.
//! length = 42
//! [checksum]
//! algorithm = "CRC-16/IBM-3740" # or CRC-16/XMODEM, CRC-32/MPEG-2, CRC-32/ISO-HDLC, sum16, sum8
//! range = [2, 39]               # covered bytes, inclusive
//! at = 40                       # where the checksum is stored
//! byte_order = "little"         # optional
//! [counter]
//! offset = 2
//! type = "u16"
//! modulus = 65536               # the counter is (raw >> shift) % modulus
//! shift = 0                     # optional
//! [status]
//! offset = 38
//! type = "u16"
//! bit_set_means = "fault"       # or "valid": what a 1 in a channel's status_bit says
//! [temperature]                 # optional
//! offset = 36
//! type = "i16"
//! scale = 0.01                  # degC per LSB
//! status_bit = 8                # optional: the reading is missing when this bit says so
//! [[channels]]
//! name = "g1"
//! offset = 4
//! type = "i32"
//! scale = 0.004                 # channel unit per LSB
//! unit = "arcsec"               # unit of the delivered increment
//! kind = "increment"            # "increment" | "rate" (x tau0) | "accel_g" (x g0 x tau0)
//! status_bit = 0                # optional
//!
//! [interleave]                  # optional: another kind shares the frame's counter, `count`
//! message = "control"           # of them between two frames (the hg4930 schedule)
//! count = 5
//! ```

use std::path::{Path, PathBuf};

mod layout;
mod message;
mod parse;
mod walker;

use super::checksum::ChecksumAlgorithm;
use super::field::{ByteOrder, FieldType};
use super::ChannelInfo;
use crate::error::UsageError;
use crate::toml_check::Collector;

/// Standard gravity, m/s^2 (CGPM 1901), for `accel_g` fields (one constant, in model::units).
pub use crate::model::units::G0_M_S2;

/// The descriptors that ship with the program, embedded so the binary works from any directory.
pub const BUILTIN: &[(&str, &str)] = &[
    ("siu8", include_str!("../../../config/frames/siu8.toml")),
    (
        "kvh1750",
        include_str!("../../../config/frames/kvh1750.toml"),
    ),
    (
        "kvh1750b",
        include_str!("../../../config/frames/kvh1750b.toml"),
    ),
    ("hg4930", include_str!("../../../config/frames/hg4930.toml")),
];

/// What a channel's number is, and so how it becomes an increment over one step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChannelKind {
    /// Already the increment over one step.
    Increment,
    /// A rate: increment = value x scale x tau0.
    Rate,
    /// An acceleration in g: delta-velocity = value x scale x g0 x tau0, in m/s.
    AccelG,
}

/// What a set status bit says about the value it guards.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BitMeaning {
    Fault,
    Valid,
}

/// The bytes all messages start with.
#[derive(Debug, Clone, PartialEq)]
pub struct SyncSpec {
    pub bytes: Vec<u8>,
    /// Offset of the sync bytes in a message.
    pub offset: usize,
    /// Offset of the message id bytes in a message.
    pub id_offset: usize,
}

/// One increment channel.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelSpec {
    pub name: String,
    pub offset: usize,
    pub ty: FieldType,
    pub order: ByteOrder,
    /// Channel unit per LSB (before the kind's factor).
    pub scale: f64,
    pub unit: String,
    pub kind: ChannelKind,
    pub status_bit: Option<u32>,
}

impl ChannelSpec {
    /// True when the decoder delivers exact integer counts (an integer `increment` field).
    pub fn is_count(&self) -> bool {
        self.ty.is_integer() && self.kind == ChannelKind::Increment
    }
}

/// The frame counter.
#[derive(Debug, Clone, PartialEq)]
pub struct CounterSpec {
    pub offset: usize,
    pub ty: FieldType,
    pub order: ByteOrder,
    pub modulus: u64,
    pub shift: u32,
}

/// The checksum of a message.
#[derive(Debug, Clone, PartialEq)]
pub struct ChecksumSpec {
    pub algorithm: ChecksumAlgorithm,
    /// First covered byte.
    pub start: usize,
    /// Last covered byte (inclusive).
    pub end: usize,
    /// Where the checksum is stored.
    pub at: usize,
    pub order: ByteOrder,
}

/// The status field whose bits mark channels valid or faulty.
#[derive(Debug, Clone, PartialEq)]
pub struct StatusSpec {
    pub offset: usize,
    pub ty: FieldType,
    pub order: ByteOrder,
    pub bit_set_means: BitMeaning,
}

/// An optional temperature reading.
#[derive(Debug, Clone, PartialEq)]
pub struct TemperatureSpec {
    pub offset: usize,
    pub ty: FieldType,
    pub order: ByteOrder,
    /// degC per LSB.
    pub scale: f64,
    pub status_bit: Option<u32>,
}

/// One kind of message in the stream.
#[derive(Debug, Clone, PartialEq)]
pub struct MessageSpec {
    pub name: String,
    /// Id bytes at `sync.id_offset` (empty for a single-kind format).
    pub id: Vec<u8>,
    /// Total length in bytes.
    pub length: usize,
    pub checksum: ChecksumSpec,
    pub counter: Option<CounterSpec>,
    pub status: Option<StatusSpec>,
    pub temperature: Option<TemperatureSpec>,
    /// Empty for messages that carry no increments (skipped by the decoder).
    pub channels: Vec<ChannelSpec>,
}

/// Another message kind that shares the frame counter: `count` of them between two frames.
#[derive(Debug, Clone, PartialEq)]
pub struct InterleaveSpec {
    /// Index into [`FrameDescriptor::messages`].
    pub message: usize,
    pub count: u64,
}

/// A checked frame descriptor.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameDescriptor {
    pub name: String,
    pub description: String,
    /// The file it was read from (`<builtin>/NAME.toml` for an embedded one).
    pub source: PathBuf,
    pub rate_hz: f64,
    pub sync: SyncSpec,
    pub messages: Vec<MessageSpec>,
    /// Index of the message kind that carries the channels.
    pub frame_kind: usize,
    pub interleave: Option<InterleaveSpec>,
}

/// All problems found in one descriptor (or why it could not be found): the one TOML error
/// type (`crate::toml_check`), exit status 2.
pub type DescriptorErrors = crate::toml_check::ConfigErrors;

/// What a descriptor's errors are called.
const WHAT: &str = "frame descriptor";

impl FrameDescriptor {
    /// The message kind that carries the channels.
    pub fn frame(&self) -> &MessageSpec {
        &self.messages[self.frame_kind]
    }

    /// Sampling step in seconds (1 / rate_hz).
    pub fn tau0_s(&self) -> f64 {
        1.0 / self.rate_hz
    }

    /// Length in bytes of the frame message.
    pub fn frame_len(&self) -> usize {
        self.frame().length
    }

    /// Names, units and (for integer counts) LSBs of the channels, in decoder order.
    pub fn channels(&self) -> Vec<ChannelInfo> {
        self.frame()
            .channels
            .iter()
            .map(|c| ChannelInfo {
                name: c.name.clone(),
                unit: c.unit.clone(),
                scale: c.is_count().then_some(c.scale),
            })
            .collect()
    }

    /// The factor from `raw x scale` to the increment over one step for a channel kind.
    pub fn kind_factor(&self, kind: ChannelKind) -> f64 {
        match kind {
            ChannelKind::Increment => 1.0,
            ChannelKind::Rate => self.tau0_s(),
            ChannelKind::AccelG => G0_M_S2 * self.tau0_s(),
        }
    }

    /// The status value that marks every channel and the temperature valid (0 without status).
    pub fn status_all_valid(&self) -> u64 {
        let f = self.frame();
        match &f.status {
            Some(s) if s.bit_set_means == BitMeaning::Valid => f
                .channels
                .iter()
                .filter_map(|c| c.status_bit)
                .chain(f.temperature.as_ref().and_then(|t| t.status_bit))
                .fold(0, |acc, b| acc | (1u64 << b)),
            _ => 0,
        }
    }

    /// Loads a descriptor by path (anything with a path separator or ending in `.toml`) or by
    /// the name of an embedded copy in [`BUILTIN`]. [`Self::load_in`] also searches folders.
    pub fn load(name_or_path: &str) -> Result<Self, DescriptorErrors> {
        Self::load_in(name_or_path, &[])
    }

    /// Loads a descriptor by name (`siu8`: `NAME.toml` searched in `dirs` in order, then the
    /// embedded copies in [`BUILTIN`]) or by path. The binary passes its search path
    /// (`./config/frames`, beside the executable, the crate's own).
    pub fn load_in(name_or_path: &str, dirs: &[PathBuf]) -> Result<Self, DescriptorErrors> {
        let looks_like_path = name_or_path.contains('/')
            || name_or_path.contains(std::path::MAIN_SEPARATOR)
            || name_or_path.ends_with(".toml");
        if looks_like_path {
            return Self::from_path(Path::new(name_or_path));
        }
        for d in dirs {
            let p = d.join(format!("{name_or_path}.toml"));
            if p.is_file() {
                return Self::from_path(&p);
            }
        }
        if let Some(d) = Self::builtin(name_or_path) {
            return d;
        }
        let known: Vec<&str> = BUILTIN.iter().map(|(n, _)| *n).collect();
        let searched: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
        let looked = if searched.is_empty() {
            String::new()
        } else {
            format!("no {name_or_path}.toml in {} and ", searched.join(", "))
        };
        Err(DescriptorErrors {
            what: WHAT,
            problems: vec![UsageError::Option(format!(
                "unknown frame format `{name_or_path}`: {looked}no built-in of that name \
                 (built-in: {})",
                known.join(", ")
            ))],
        })
    }

    /// The embedded copy of a shipped descriptor.
    pub fn builtin(name: &str) -> Option<Result<Self, DescriptorErrors>> {
        BUILTIN.iter().find(|(n, _)| *n == name).map(|(n, text)| {
            Self::from_toml_str(text, &PathBuf::from(format!("<builtin>/{n}.toml")))
        })
    }

    /// Reads and checks a descriptor file.
    pub fn from_path(path: &Path) -> Result<Self, DescriptorErrors> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Collector::unreadable(path, &e).into_errors(WHAT))?;
        Self::from_toml_str(&text, path)
    }

    /// Parses and checks descriptor text; `source` names it in errors.
    pub fn from_toml_str(text: &str, source: &Path) -> Result<Self, DescriptorErrors> {
        let mut ctx = Collector::new(source, text);
        let Some(table) = ctx.parse(text) else {
            return Err(ctx.into_errors(WHAT));
        };
        let out = parse::parse_descriptor(&mut ctx, &table, source);
        match out {
            Some(d) if ctx.is_empty() => Ok(d),
            _ => {
                if ctx.is_empty() {
                    ctx.bad("(descriptor)", "invalid descriptor");
                }
                Err(ctx.into_errors(WHAT))
            }
        }
    }
}
