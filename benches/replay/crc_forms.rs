// Micro-benchmark of CRC-16/IBM-3740 forms on 38-byte messages (issue 15, session 10; the table in
// BENCHMARKS.md). Not part of the build (cargo does not look in benches/replay/); it holds the
// carry-less-multiply forms E and F, which need `unsafe`. Run: rustc --edition 2021 -O -C target-cpu=native
// benches/replay/crc_forms.rs -o /tmp/crc_forms && /tmp/crc_forms /tmp/lab_siu8_3h.siu8 [hot|stream]
use std::arch::x86_64::*;
use std::hint::black_box;

const POLY: u32 = 0x1021;
struct Tables([[u16; 256]; 16]);
fn tables() -> Tables {
    let mut t = [[0u16; 256]; 16];
    for b in 0..256 {
        let mut r = (b as u32) << 8;
        for _ in 0..8 { r = if r & 0x8000 != 0 { (r << 1) ^ POLY } else { r << 1 }; }
        t[0][b] = r as u16;
    }
    for j in 1..16 { for b in 0..256 { let p = t[j-1][b] as u32; t[j][b] = (((p << 8) & 0xFFFF) ^ t[0][(p >> 8) as usize] as u32) as u16; } }
    Tables(t)
}
// u32 tables like the crate (16 KiB)
struct T32([[u32; 256]; 16]);
fn t32(t: &Tables) -> T32 { let mut o = [[0u32;256];16]; for j in 0..16 { for b in 0..256 { o[j][b] = t.0[j][b] as u32; } } T32(o) }

fn bitwise(d: &[u8]) -> u16 {
    let mut r: u32 = 0xFFFF;
    for &b in d { r ^= (b as u32) << 8; for _ in 0..8 { r = if r & 0x8000 != 0 { (r << 1) ^ POLY } else { r << 1 }; } r &= 0xFFFF; }
    r as u16
}

// A: the repository's generic form (chunks_exact(16) + runtime-length tail step)
#[inline(always)]
fn step_dyn(t: &T32, r: u32, run: &[u8]) -> u32 {
    let n = run.len(); let mut acc = 0;
    for (i, &b) in run.iter().enumerate() {
        let x = if i < 2 { b ^ (r >> (8 - 8 * i as u32)) as u8 } else { b };
        acc ^= t.0[n - 1 - i][x as usize];
    }
    acc
}
#[inline(never)]
fn crc_a(t: &T32, d: &[u8]) -> u16 {
    let mut r = 0xFFFF;
    let mut ch = d.chunks_exact(16);
    for c in &mut ch { r = step_dyn(t, r, c); }
    let tail = ch.remainder();
    if tail.len() >= 2 { r = step_dyn(t, r, tail); } else { for &b in tail { r = ((r << 8) ^ t.0[0][((r >> 8) as u8 ^ b) as usize]) & 0xFFFF; } }
    r as u16
}
// B: fixed length, every step's length known when compiled
#[inline(always)]
fn step_n<const N: usize>(t: &T32, r: u32, run: &[u8; N]) -> u32 {
    let mut acc = 0;
    let mut i = 0;
    while i < N {
        let x = if i == 0 { run[0] ^ (r >> 8) as u8 } else if i == 1 { run[1] ^ r as u8 } else { run[i] };
        acc ^= t.0[N - 1 - i][x as usize];
        i += 1;
    }
    acc
}
#[inline(always)]
fn crc_b_inl(t: &T32, d: &[u8; 38]) -> u16 {
    let r = step_n::<16>(t, 0xFFFF, d[0..16].try_into().unwrap());
    let r = step_n::<16>(t, r, d[16..32].try_into().unwrap());
    step_n::<6>(t, r, d[32..38].try_into().unwrap()) as u16
}
#[inline(never)]
fn crc_b(t: &T32, d: &[u8; 38]) -> u16 { crc_b_inl(t, d) }
// C: four frames interleaved (B inlined, independent chains)
#[inline(never)]
fn crc_c4(t: &T32, d: [&[u8; 38]; 4]) -> [u16; 4] {
    let mut r = [0xFFFFu32; 4];
    for k in 0..4 { r[k] = step_n::<16>(t, r[k], d[k][0..16].try_into().unwrap()); }
    for k in 0..4 { r[k] = step_n::<16>(t, r[k], d[k][16..32].try_into().unwrap()); }
    for k in 0..4 { r[k] = step_n::<6>(t, r[k], d[k][32..38].try_into().unwrap()); }
    [r[0] as u16, r[1] as u16, r[2] as u16, r[3] as u16]
}
// D: u64 loads, bytes by shifts, u16 tables
#[inline(never)]
fn crc_d(t: &Tables, d: &[u8; 38]) -> u16 {
    let w = |i: usize| u64::from_be_bytes(d[i..i + 8].try_into().unwrap());
    let mut r: u64 = 0xFFFF;
    let mut acc;
    for base in [0usize, 16] {
        let a = w(base) ^ (r << 48); let b = w(base + 8);
        acc = 0u16;
        for i in 0..8 { acc ^= t.0[15 - i][((a >> (56 - 8 * i)) & 0xFF) as usize]; }
        for i in 0..8 { acc ^= t.0[7 - i][((b >> (56 - 8 * i)) & 0xFF) as usize]; }
        r = acc as u64;
    }
    let a = (u64::from(u32::from_be_bytes(d[32..36].try_into().unwrap())) << 16 | u64::from(u16::from_be_bytes(d[36..38].try_into().unwrap()))) ^ (r << 32);
    acc = 0;
    for i in 0..6 { acc ^= t.0[5 - i][((a >> (40 - 8 * i)) & 0xFF) as usize]; }
    acc
}

// E: carry-less multiply (pclmulqdq): unsafe at the call, as forbid(unsafe_code) would not allow
fn pmod(mut a: u128, deg_a_max: u32) -> u16 { // a mod P, a < 2^(deg_a_max+1)
    let p: u128 = 0x1_1021;
    for i in (16..=deg_a_max).rev() { if a >> i & 1 == 1 { a ^= p << (i - 16); } }
    a as u16
}
fn xpow_mod(e: u32) -> u64 { // x^e mod P
    let mut r: u32 = 1;
    for _ in 0..e { r <<= 1; if r & 0x1_0000 != 0 { r ^= 0x1_1021; } }
    r as u64
}
fn pdiv(num_deg: u32) -> u64 { // floor(x^num_deg / P), 64-bit
    let mut rem: u128 = 1u128 << num_deg; let mut q: u128 = 0; let p: u128 = 0x1_1021;
    for i in (16..=num_deg).rev() { if rem >> i & 1 == 1 { rem ^= p << (i - 16); q |= 1u128 << (i - 16); } }
    q as u64
}
#[derive(Clone, Copy)]
struct K { k: [u64; 5], k64: u64, mu: u64 }
fn consts() -> K { K { k: [xpow_mod(256 + 16), xpow_mod(192 + 16), xpow_mod(128 + 16), xpow_mod(64 + 16), xpow_mod(16)], k64: xpow_mod(64), mu: pdiv(64) } }
#[inline(always)]
fn clmul(a: u64, b: u64) -> __m128i {
    unsafe { _mm_clmulepi64_si128(_mm_cvtsi64_si128(a as i64), _mm_cvtsi64_si128(b as i64), 0) }
}
#[inline(always)]
fn lo(x: __m128i) -> u64 { unsafe { _mm_cvtsi128_si64(x) as u64 } }
#[inline(always)]
fn hi(x: __m128i) -> u64 { unsafe { _mm_extract_epi64(x, 1) as u64 } }
#[target_feature(enable = "pclmulqdq,sse4.1")]
fn crc_e_tf(k: &K, d: &[u8; 38]) -> u16 {
    let w = |i: usize| u64::from_be_bytes(d[i..i + 8].try_into().unwrap());
    let l0 = (u64::from(u32::from_be_bytes(d[0..4].try_into().unwrap())) << 16 | u64::from(u16::from_be_bytes(d[4..6].try_into().unwrap()))) ^ 0xFFFF_0000_0000;
    let v = _mm_xor_si128(
        _mm_xor_si128(clmul(l0, k.k[0]), clmul(w(6), k.k[1])),
        _mm_xor_si128(_mm_xor_si128(clmul(w(14), k.k[2]), clmul(w(22), k.k[3])), clmul(w(30), k.k[4])),
    );
    let t = lo(v) ^ lo(clmul(hi(v), k.k64));
    let q = hi(clmul(t >> 16, k.mu)) << 16 | lo(clmul(t >> 16, k.mu)) >> 48;
    (t ^ lo(clmul(q, 0x1_1021))) as u16
}
#[inline(never)]
fn crc_e(k: &K, d: &[u8; 38]) -> u16 { unsafe { crc_e_tf(k, d) } }
#[target_feature(enable = "pclmulqdq,sse4.1")]
fn crc_f_tf(k: &K, d: [&[u8; 38]; 4]) -> [u16; 4] { [crc_e_tf(k, d[0]), crc_e_tf(k, d[1]), crc_e_tf(k, d[2]), crc_e_tf(k, d[3])] }
#[inline(never)]
fn crc_f4(k: &K, d: [&[u8; 38]; 4]) -> [u16; 4] { unsafe { crc_f_tf(k, d) } }

fn cpu() -> f64 { let s = std::fs::read_to_string("/proc/thread-self/schedstat").unwrap(); s.split_whitespace().next().unwrap().parse::<f64>().unwrap() * 1e-9 }

fn main() {
    let path = std::env::args().nth(1).unwrap();
    let mode = std::env::args().nth(2).unwrap_or("hot".into());
    let all = std::fs::read(&path).unwrap();
    let t = tables(); let t3 = t32(&t); let k = consts();
    let _ = pmod(0, 0);
    // correctness
    for f in all[..42 * 2000].chunks_exact(42) {
        let d: &[u8; 38] = f[2..40].try_into().unwrap();
        let want = bitwise(d);
        let stored = u16::from_le_bytes([f[40], f[41]]);
        assert_eq!(want, stored);
        assert_eq!(crc_a(&t3, d), want); assert_eq!(crc_b(&t3, d), want); assert_eq!(crc_d(&t, d), want);
        assert_eq!(crc_e(&k, d), want, "clmul");
    }
    // frames to check per pass
    let frames: usize = all.len() / 42;
    let window = if mode == "hot" { 1560 } else { frames }; // hot: 64 KiB of frames, L1/L2
    let total = 2_700_000usize;
    let mut buf = vec![0u8; 256 * 1024];
    for name in ["A generic", "B fixed", "C fixed x4", "D u64+shifts", "E clmul", "F clmul x4"] {
        let mut s = 0u64;
        let c0 = cpu();
        let mut done = 0;
        let mut off = 0;
        while done < total {
            // the frames of one 256 KiB read (stream mode: copied into a recycled buffer first, as the reader does)
            let n = (6241).min(total - done);
            let src_frames = if mode == "hot" { let o = (done % window) ; (o, n.min(window - o)) } else { (off, n.min(frames - off)) };
            let (fo, n) = src_frames;
            let bytes: &[u8] = if mode == "hot" { &all[fo * 42..(fo + n) * 42] } else { buf[..n * 42].copy_from_slice(&all[fo * 42..(fo + n) * 42]); &buf[..n * 42] };
            let fr = |i: usize| -> &[u8; 38] { bytes[i * 42 + 2..i * 42 + 40].try_into().unwrap() };
            match name {
                "A generic" => for i in 0..n { s += crc_a(&t3, black_box(&bytes[i * 42 + 2..i * 42 + 40])) as u64 },
                "B fixed" => for i in 0..n { s += crc_b(&t3, black_box(fr(i))) as u64 },
                "D u64+shifts" => for i in 0..n { s += crc_d(&t, black_box(fr(i))) as u64 },
                "E clmul" => for i in 0..n { s += crc_e(&k, black_box(fr(i))) as u64 },
                "C fixed x4" | "F clmul x4" => { let mut i = 0; while i + 4 <= n { let r = if name == "C fixed x4" { crc_c4(&t3, black_box([fr(i), fr(i+1), fr(i+2), fr(i+3)])) } else { crc_f4(&k, black_box([fr(i), fr(i+1), fr(i+2), fr(i+3)])) }; s += r.iter().map(|&x| x as u64).sum::<u64>(); i += 4; } while i < n { s += crc_b(&t3, fr(i)) as u64; i += 1; } }
                _ => unreachable!(),
            }
            done += n; off = (off + n) % frames;
        }
        let c = cpu() - c0;
        println!("{mode} {name:14} {:6.2} ns/frame  ({s})", c / total as f64 * 1e9);
    }
}
