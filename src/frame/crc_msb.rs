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
//! 1 to 3 bytes left, a 16-bit one with 1) go byte by byte. The tail's length is a constant of
//! the compiled step (one match over the sixteen possible tails), and [`MsbCrc::checksums4`]
//! computes four messages of one length side by side, four independent chains of lookups: for
//! 38-byte siu8 frames the CRC's share of the decode thread fell by about 40% (BENCHMARKS.md,
//! issue 15 session 10).

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
        let [r] = self.checksums_w::<W, 1>([data]);
        r
    }

    /// The checksums of four messages of the **same length**, computed side by side: four
    /// independent chains of table lookups instead of one, so the lookups of one message fill
    /// the waits of the others (the decoder's run of clean frames, `Decoder::run_locked`).
    /// Messages of different lengths are each computed alone.
    #[inline]
    pub(crate) fn checksums4(&self, data: [&[u8]; 4]) -> [u32; 4] {
        let n = data[0].len();
        if data.iter().any(|d| d.len() != n) {
            return [
                self.checksum(data[0]),
                self.checksum(data[1]),
                self.checksum(data[2]),
                self.checksum(data[3]),
            ];
        }
        if self.width == 16 {
            self.checksums_w::<16, 4>(data)
        } else {
            self.checksums_w::<32, 4>(data)
        }
    }

    /// The checksums of `K` messages of one length, side by side: every full 16-byte step,
    /// then the tail in one step whose length is a constant of the compiled code (a match
    /// over the 16 possible tails), so no step runs a loop of unknown length.
    #[inline(always)]
    fn checksums_w<const W: u32, const K: usize>(&self, data: [&[u8]; K]) -> [u32; K] {
        let n = data[0].len();
        let full = n / 16;
        let mut r = [self.init; K];
        for s in 0..full {
            for k in 0..K {
                let c: &[u8; 16] = data[k][16 * s..16 * s + 16].try_into().unwrap_or(&[0; 16]);
                r[k] = self.step::<W, 16>(r[k], c);
            }
        }
        let at = 16 * full;
        macro_rules! tail {
            ($($n:literal)*) => {
                match n - at {
                    $($n => {
                        for k in 0..K {
                            let c: &[u8; $n] = data[k][at..].try_into().unwrap_or(&[0; $n]);
                            r[k] = self.tail::<W, $n>(r[k], c);
                        }
                    })*
                    _ => {}
                }
            };
        }
        tail!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15);
        for x in &mut r {
            *x ^= self.xorout;
        }
        r
    }

    /// The register after a tail of `N` bytes (1 to 15): one step when the tail is at least
    /// the register's width, byte by byte otherwise.
    #[inline(always)]
    fn tail<const W: u32, const N: usize>(&self, r: u32, run: &[u8; N]) -> u32 {
        if N >= (W / 8) as usize {
            return self.step::<W, N>(r, run);
        }
        let mut r = r;
        for &b in run {
            let i = ((r >> (W - 8)) as u8 ^ b) as usize;
            r = (r << 8) ^ self.tables[0][i];
            if W < 32 {
                r &= (1 << W) - 1;
            }
        }
        r
    }

    /// The register after a run of `N` bytes (1 to 16), at least the register's width long.
    #[inline(always)]
    fn step<const W: u32, const N: usize>(&self, r: u32, run: &[u8; N]) -> u32 {
        let mut acc = 0;
        for (i, &b) in run.iter().enumerate() {
            let x = if i < (W / 8) as usize {
                b ^ (r >> (W - 8 - 8 * i as u32)) as u8
            } else {
                b
            };
            acc ^= self.tables[N - 1 - i][x as usize];
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

    /// Four messages side by side give each message's own CRC: every length 0 to 100 (each
    /// tail of each width), four different messages; and messages of unequal lengths.
    #[test]
    fn four_side_by_side_agree_with_one_at_a_time() {
        let data: Vec<u8> = (0..520u32)
            .map(|i| (i.wrapping_mul(2_246_822_519) >> 11) as u8)
            .collect();
        for crc in [&CRC16_IBM_3740, &CRC16_XMODEM, &CRC32_MPEG2] {
            for len in 0..=100 {
                let m: [&[u8]; 4] = std::array::from_fn(|k| &data[k * 127 + 3..k * 127 + 3 + len]);
                assert_eq!(crc.checksums4(m), m.map(|d| crc.checksum(d)), "{len}");
            }
            let m: [&[u8]; 4] = [&data[..38], &data[50..87], &data[90..128], &data[200..201]];
            assert_eq!(crc.checksums4(m), m.map(|d| crc.checksum(d)));
        }
    }
}
