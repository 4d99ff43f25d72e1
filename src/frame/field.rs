//! Primitive field access: the eight wire types, byte order, and reading or writing one value
//! at a byte offset. Knows nothing about what a field means; `descriptor` and `decoder` do.

/// Byte order of a multi-byte field on the wire.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ByteOrder {
    Little,
    Big,
}

impl ByteOrder {
    /// Parses `little`/`le` or `big`/`be`.
    pub fn parse(s: &str) -> Option<Self> {
        match s.to_ascii_lowercase().as_str() {
            "little" | "le" | "little_endian" => Some(Self::Little),
            "big" | "be" | "big_endian" => Some(Self::Big),
            _ => None,
        }
    }
}

/// The wire type of a field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FieldType {
    U8,
    I8,
    U16,
    I16,
    U32,
    I32,
    F32,
    F64,
}

/// The names accepted for [`FieldType`] in a descriptor.
pub const FIELD_TYPE_NAMES: &str = "u8, i8, u16, i16, u32, i32, f32, f64";

impl FieldType {
    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "u8" => Self::U8,
            "i8" => Self::I8,
            "u16" => Self::U16,
            "i16" => Self::I16,
            "u32" => Self::U32,
            "i32" => Self::I32,
            "f32" => Self::F32,
            "f64" => Self::F64,
            _ => return None,
        })
    }

    /// The descriptor name of the type.
    pub fn name(self) -> &'static str {
        match self {
            Self::U8 => "u8",
            Self::I8 => "i8",
            Self::U16 => "u16",
            Self::I16 => "i16",
            Self::U32 => "u32",
            Self::I32 => "i32",
            Self::F32 => "f32",
            Self::F64 => "f64",
        }
    }

    /// Size on the wire in bytes.
    pub fn size(self) -> usize {
        match self {
            Self::U8 | Self::I8 => 1,
            Self::U16 | Self::I16 => 2,
            Self::U32 | Self::I32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    pub fn bits(self) -> u32 {
        8 * self.size() as u32
    }

    pub fn is_integer(self) -> bool {
        !matches!(self, Self::F32 | Self::F64)
    }

    pub fn is_signed(self) -> bool {
        matches!(self, Self::I8 | Self::I16 | Self::I32)
    }

    /// Smallest and largest integer the type holds (integer types only; floats give the i64 range).
    pub fn int_range(self) -> (i64, i64) {
        match self {
            Self::U8 => (0, u8::MAX as i64),
            Self::I8 => (i8::MIN as i64, i8::MAX as i64),
            Self::U16 => (0, u16::MAX as i64),
            Self::I16 => (i16::MIN as i64, i16::MAX as i64),
            Self::U32 => (0, u32::MAX as i64),
            Self::I32 => (i32::MIN as i64, i32::MAX as i64),
            Self::F32 | Self::F64 => (i64::MIN, i64::MAX),
        }
    }
}

/// A value read from the wire: integers exactly, floats widened to f64.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RawValue {
    Int(i64),
    Float(f64),
}

impl RawValue {
    pub fn as_f64(self) -> f64 {
        match self {
            Self::Int(v) => v as f64,
            Self::Float(v) => v,
        }
    }
}

/// The field's bytes as an unsigned bit pattern, or None when the field runs past `bytes`.
#[inline]
pub fn read_bits(bytes: &[u8], offset: usize, ty: FieldType, order: ByteOrder) -> Option<u64> {
    let s = bytes.get(offset..offset.checked_add(ty.size())?)?;
    // One fixed-width load per size (a byte-by-byte fold was a fifth of the decode thread).
    Some(match (s.len(), order) {
        (1, _) => u64::from(s[0]),
        (2, ByteOrder::Little) => u64::from(u16::from_le_bytes([s[0], s[1]])),
        (2, ByteOrder::Big) => u64::from(u16::from_be_bytes([s[0], s[1]])),
        (4, ByteOrder::Little) => u64::from(u32::from_le_bytes([s[0], s[1], s[2], s[3]])),
        (4, ByteOrder::Big) => u64::from(u32::from_be_bytes([s[0], s[1], s[2], s[3]])),
        (_, order) => {
            let mut b = [0u8; 8];
            b.copy_from_slice(s);
            match order {
                ByteOrder::Little => u64::from_le_bytes(b),
                ByteOrder::Big => u64::from_be_bytes(b),
            }
        }
    })
}

/// Reads one typed value, or None when the field runs past `bytes`.
#[inline]
pub fn read(bytes: &[u8], offset: usize, ty: FieldType, order: ByteOrder) -> Option<RawValue> {
    let v = read_bits(bytes, offset, ty, order)?;
    Some(match ty {
        FieldType::U8 | FieldType::U16 | FieldType::U32 => RawValue::Int(v as i64),
        FieldType::I8 => RawValue::Int(i64::from(v as u8 as i8)),
        FieldType::I16 => RawValue::Int(i64::from(v as u16 as i16)),
        FieldType::I32 => RawValue::Int(i64::from(v as u32 as i32)),
        FieldType::F32 => RawValue::Float(f64::from(f32::from_bits(v as u32))),
        FieldType::F64 => RawValue::Float(f64::from_bits(v)),
    })
}

/// Writes a bit pattern (its low `ty.size()` bytes); false when the field runs past `buf`.
pub fn write_bits(buf: &mut [u8], offset: usize, ty: FieldType, order: ByteOrder, v: u64) -> bool {
    let n = ty.size();
    let Some(s) = offset
        .checked_add(n)
        .and_then(|end| buf.get_mut(offset..end))
    else {
        return false;
    };
    for (i, b) in s.iter_mut().enumerate() {
        let shift = match order {
            ByteOrder::Little => 8 * i,
            ByteOrder::Big => 8 * (n - 1 - i),
        };
        *b = (v >> shift) as u8;
    }
    true
}

/// The bit pattern of a value in the given type: integers two's complement (the caller checks
/// the range), floats IEEE-754.
pub fn to_bits(ty: FieldType, value: RawValue) -> u64 {
    match (ty, value) {
        (FieldType::F32, v) => u64::from((v.as_f64() as f32).to_bits()),
        (FieldType::F64, v) => v.as_f64().to_bits(),
        (_, RawValue::Int(i)) => i as u64,
        (_, RawValue::Float(f)) => f.round() as i64 as u64,
    }
}
