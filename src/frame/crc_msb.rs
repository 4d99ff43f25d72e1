//! CRCs computed most significant bit first (no reflection) sixteen bytes per step, with the
//! bytes left over after the last full step taken in **one** more step instead of one at a
//! time: CRC-16/IBM-3740, CRC-16/XMODEM and CRC-32/MPEG-2 of the descriptor catalogue.
//!
//! Why: the `crc` crate's slice-by-16 takes the tail of a message byte by byte, one dependent
//! table lookup after the other; for a 38-byte siu8 frame that tail and the crate's checks of
//! the algorithm's reflection on every call made the CRC 12% of a replay's CPU time, the largest
//! cost after the statistics (`perf record`, BENCHMARKS.md "Decoding at the speed of the
//! statistics"). The results are the catalogue's (checked against the crate on every length
//! and against the catalogue's check values in `checksum`).
//!
//! The method (Kounavis and Berry's "slicing-by-N", MSB-first form): `T[0][b]` is the CRC
//! register after shifting in byte `b` alone, `T[j][b]` the same followed by `j` zero bytes.
//! A run of `n` bytes with `n` at least the register's width in bytes is absorbed in one step:
//! the register is XORed into the run's first bytes (its top byte with the first), and the new
//! register is the XOR of `T[n - 1 - i][byte i]` over the run. Shorter tails (a 32-bit CRC with
//! 1 to 3 bytes left, a 16-bit one with 1) go byte by byte.

/// One MSB-first CRC of width 16 or 32 bits, its tables built at compile time (16 KiB).
pub(crate) struct MsbCrc {
    width: u32,
    init: u32,
    xorout: u32,
    tables: [[u32; 256]; 16],
}

impl MsbCrc {
    /// The CRC of `width` bits (16 or 32) with polynomial `poly` (top bit implicit), initial
    /// register `init` and final XOR `xorout`, no reflection.
    pub(crate) const fn new(width: u32, poly: u32, init: u32, xorout: u32) -> MsbCrc {
        let mask = if width == 32 {
            u32::MAX
        } else {
            (1u32 << width) - 1
        };
        let top = 1u32 << (width - 1);
        let mut tables = [[0u32; 256]; 16];
        let mut b = 0;
        while b < 256 {
            let mut r = (b as u32) << (width - 8);
            let mut k = 0;
            while k < 8 {
                r = if r & top != 0 {
                    (r << 1) ^ poly
                } else {
                    r << 1
                };
                k += 1;
            }
            tables[0][b] = r & mask;
            b += 1;
        }
        let mut j = 1;
        while j < 16 {
            let mut b = 0;
            while b < 256 {
                let p = tables[j - 1][b];
                tables[j][b] = ((p << 8) & mask) ^ tables[0][(p >> (width - 8)) as usize];
                b += 1;
            }
            j += 1;
        }
        MsbCrc {
            width,
            init,
            xorout,
            tables,
        }
    }

    /// The checksum of `data`.
    #[inline]
    pub(crate) fn checksum(&self, data: &[u8]) -> u32 {
        if self.width == 16 {
            self.checksum_w::<16>(data)
        } else {
            self.checksum_w::<32>(data)
        }
    }

    /// [`MsbCrc::checksum`] for a register of `W` bits (the shifts known when compiled).
    #[inline(always)]
    fn checksum_w<const W: u32>(&self, data: &[u8]) -> u32 {
        let mut r = self.init;
        let mut chunks = data.chunks_exact(16);
        for c in &mut chunks {
            let c: &[u8; 16] = c.try_into().unwrap_or(&[0; 16]);
            r = self.step::<W>(r, c);
        }
        let tail = chunks.remainder();
        if tail.len() >= (W / 8) as usize {
            r = self.step::<W>(r, tail);
        } else {
            for &b in tail {
                let i = ((r >> (W - 8)) as u8 ^ b) as usize;
                r = (r << 8) ^ self.tables[0][i];
                if W < 32 {
                    r &= (1 << W) - 1;
                }
            }
        }
        r ^ self.xorout
    }

    /// The register after a run of 1 to 16 bytes, at least the register's width long.
    #[inline(always)]
    fn step<const W: u32>(&self, r: u32, run: &[u8]) -> u32 {
        let n = run.len();
        let mut acc = 0;
        for (i, &b) in run.iter().enumerate() {
            let x = if i < (W / 8) as usize {
                b ^ (r >> (W - 8 - 8 * i as u32)) as u8
            } else {
                b
            };
            acc ^= self.tables[n - 1 - i][x as usize];
        }
        acc
    }
}

/// CRC-16/IBM-3740: poly 0x1021, init 0xFFFF, no reflection, xorout 0.
pub(crate) static CRC16_IBM_3740: MsbCrc = MsbCrc::new(16, 0x1021, 0xFFFF, 0);
/// CRC-16/XMODEM: poly 0x1021, init 0, no reflection, xorout 0.
pub(crate) static CRC16_XMODEM: MsbCrc = MsbCrc::new(16, 0x1021, 0, 0);
/// CRC-32/MPEG-2: poly 0x04C11DB7, init 0xFFFFFFFF, no reflection, xorout 0.
pub(crate) static CRC32_MPEG2: MsbCrc = MsbCrc::new(32, 0x04C1_1DB7, 0xFFFF_FFFF, 0);

#[cfg(test)]
mod tests {
    use super::*;
    use crc::{Crc, CRC_16_IBM_3740, CRC_16_XMODEM, CRC_32_MPEG_2};

    /// The catalogue's check values (CRC of the ASCII bytes "123456789").
    #[test]
    fn check_values() {
        let d = b"123456789";
        assert_eq!(CRC16_IBM_3740.checksum(d), 0x29B1);
        assert_eq!(CRC16_XMODEM.checksum(d), 0x31C3);
        assert_eq!(CRC32_MPEG2.checksum(d), 0x0376_E6E7);
    }

    /// Every length from 0 to 100 bytes (full steps, every tail, the byte-wise tails) and every
    /// start: the same CRC as the `crc` crate's byte-wise table.
    #[test]
    fn agrees_with_the_crc_crate_on_every_length() {
        let a = Crc::<u16>::new(&CRC_16_IBM_3740);
        let x = Crc::<u16>::new(&CRC_16_XMODEM);
        let m = Crc::<u32>::new(&CRC_32_MPEG_2);
        let data: Vec<u8> = (0..120u32)
            .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
            .collect();
        for start in 0..8 {
            for len in 0..=100 {
                let d = &data[start..start + len];
                assert_eq!(
                    CRC16_IBM_3740.checksum(d),
                    u32::from(a.checksum(d)),
                    "{len}"
                );
                assert_eq!(CRC16_XMODEM.checksum(d), u32::from(x.checksum(d)), "{len}");
                assert_eq!(CRC32_MPEG2.checksum(d), m.checksum(d), "{len}");
            }
        }
    }
}
