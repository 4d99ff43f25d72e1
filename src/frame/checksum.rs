//! Frame checksums: the named CRCs (through the `crc` crate's catalogue) and the two plain sums
//! some units use. Pure functions of the covered bytes; where they sit in a frame is the
//! descriptor's business.

use super::crc_msb;
use super::field::ByteOrder;
use crc::{Crc, Table, CRC_32_ISO_HDLC};

/// The MSB-first CRCs (both CRC-16s, CRC-32/MPEG-2) are computed by `crc_msb` (sixteen bytes
/// per step, the tail in one step); the reflected CRC-32/ISO-HDLC by the crate, slice-by-16
/// (sixteen 256-entry tables) rather than its default byte-at-a-time table: the CRC of every
/// candidate frame was 7% of a replay's instructions at one table lookup per byte
/// (BENCHMARKS.md, "Decoding at the speed of the statistics"). Tables are built at compile time.
type Slice16 = Table<16>;

static CRC32_ISO_HDLC: Crc<u32, Slice16> = Crc::<u32, Slice16>::new(&CRC_32_ISO_HDLC);

/// A checksum algorithm a descriptor can name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChecksumAlgorithm {
    /// CRC-16/IBM-3740 (also called CRC-16/CCITT-FALSE): poly 0x1021, init 0xFFFF, no reflection.
    Crc16Ibm3740,
    /// CRC-16/XMODEM: poly 0x1021, init 0, no reflection.
    Crc16Xmodem,
    /// CRC-32/MPEG-2: poly 0x04C11DB7, init 0xFFFFFFFF, no reflection, xorout 0.
    Crc32Mpeg2,
    /// CRC-32/ISO-HDLC (the zlib/Ethernet CRC-32).
    Crc32IsoHdlc,
    /// Sum of the covered bytes taken as 16-bit words (in the checksum's byte order), modulo 2^16.
    Sum16,
    /// Sum of the covered bytes modulo 256.
    Sum8,
}

/// The names a descriptor may use (case-insensitive), for error messages.
pub const ALGORITHM_NAMES: &str = "CRC-16/IBM-3740 (alias CRC-16/CCITT-FALSE), CRC-16/XMODEM, \
     CRC-32/MPEG-2, CRC-32/ISO-HDLC, sum16, sum8";

impl ChecksumAlgorithm {
    /// Parses a catalogue name (case-insensitive; `_` and `-` interchangeable).
    pub fn parse(name: &str) -> Option<Self> {
        let n = name.to_ascii_uppercase().replace('_', "-");
        Some(match n.as_str() {
            "CRC-16/IBM-3740" | "CRC-16/CCITT-FALSE" | "CRC-16/AUTOSAR" => Self::Crc16Ibm3740,
            "CRC-16/XMODEM" => Self::Crc16Xmodem,
            "CRC-32/MPEG-2" => Self::Crc32Mpeg2,
            "CRC-32/ISO-HDLC" | "CRC-32" => Self::Crc32IsoHdlc,
            "SUM16" => Self::Sum16,
            "SUM8" => Self::Sum8,
            _ => return None,
        })
    }

    /// Bytes the checksum occupies in the frame.
    pub fn width(self) -> usize {
        match self {
            Self::Sum8 => 1,
            Self::Crc16Ibm3740 | Self::Crc16Xmodem | Self::Sum16 => 2,
            Self::Crc32Mpeg2 | Self::Crc32IsoHdlc => 4,
        }
    }

    /// The checksum of `data`; `order` is the word order for [`Self::Sum16`] (ignored otherwise).
    /// An odd trailing byte of a 16-bit sum counts as a word with a zero second byte.
    pub fn compute(self, data: &[u8], order: ByteOrder) -> u64 {
        match self {
            Self::Crc16Ibm3740 => u64::from(crc_msb::CRC16_IBM_3740.checksum(data)),
            Self::Crc16Xmodem => u64::from(crc_msb::CRC16_XMODEM.checksum(data)),
            Self::Crc32Mpeg2 => u64::from(crc_msb::CRC32_MPEG2.checksum(data)),
            Self::Crc32IsoHdlc => u64::from(CRC32_ISO_HDLC.checksum(data)),
            Self::Sum16 => {
                let sum = data.chunks(2).fold(0u16, |acc, w| {
                    let (a, b) = (w[0], w.get(1).copied().unwrap_or(0));
                    let word = match order {
                        ByteOrder::Little => u16::from_le_bytes([a, b]),
                        ByteOrder::Big => u16::from_be_bytes([a, b]),
                    };
                    acc.wrapping_add(word)
                });
                u64::from(sum)
            }
            Self::Sum8 => u64::from(data.iter().fold(0u8, |acc, b| acc.wrapping_add(*b))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The catalogue's check value: each CRC of the ASCII bytes "123456789" (Williams/reveng
    /// catalogue, as listed in the `crc-catalog` crate).
    #[test]
    fn catalogue_check_values() {
        let d = b"123456789";
        let o = ByteOrder::Big;
        assert_eq!(ChecksumAlgorithm::Crc16Ibm3740.compute(d, o), 0x29B1);
        assert_eq!(ChecksumAlgorithm::Crc16Xmodem.compute(d, o), 0x31C3);
        assert_eq!(ChecksumAlgorithm::Crc32Mpeg2.compute(d, o), 0x0376E6E7);
        assert_eq!(ChecksumAlgorithm::Crc32IsoHdlc.compute(d, o), 0xCBF43926);
    }

    /// Sums worked by hand: 0x0201 + 0x0403 = 0x0604 little-endian; bytes 1+2+3+4 = 10.
    #[test]
    fn plain_sums() {
        let d = [1u8, 2, 3, 4];
        assert_eq!(
            ChecksumAlgorithm::Sum16.compute(&d, ByteOrder::Little),
            0x0604
        );
        assert_eq!(ChecksumAlgorithm::Sum16.compute(&d, ByteOrder::Big), 0x0406);
        assert_eq!(ChecksumAlgorithm::Sum8.compute(&d, ByteOrder::Big), 10);
        assert_eq!(
            ChecksumAlgorithm::Sum8.compute(&[0xFF, 0x02], ByteOrder::Big),
            1
        );
    }
}
