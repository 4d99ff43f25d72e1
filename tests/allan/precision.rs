//! Precision of the accumulators where naive arithmetic fails (docs/theory.md section 1,
//! "Precision"): integer counts summed exactly, MVAR's running sum of phase in 128 bits when a
//! 64-bit third difference could overflow, and floating input over 1e9 samples of a 1 g
//! accelerometer checked against the exact integer computation.

use allanscope::allan::accum::{
    AccumConfig, Engine, FloatRepr, IntRepr, Overlap, StatSet, TauSpec,
};
use allanscope::allan::Stat;

struct XorShift(u64);
impl XorShift {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// MVAR from integer increments, computed independently: exact i128 running sums of phase and
/// exact third differences, squares summed in f64.
fn exact_mvar(d: &[i64], m: usize) -> (f64, u64) {
    let mut x = vec![0i128];
    for &v in d {
        x.push(x.last().unwrap() + v as i128);
    }
    let mut c = vec![0i128];
    for &v in &x {
        c.push(c.last().unwrap() + v);
    }
    let mut sum = 0.0f64;
    let mut comp = 0.0f64;
    let mut n = 0u64;
    for j in 0..=(c.len() - 1 - 3 * m) {
        let v = (c[j + 3 * m] - 3 * c[j + 2 * m] + 3 * c[j + m] - c[j]) as f64;
        // Kahan: the reference's own sum must not be the weak side.
        let y = v * v - comp;
        let t = sum + y;
        comp = (t - sum) - y;
        sum = t;
        n += 1;
    }
    let tau = m as f64;
    (sum / (2.0 * tau * tau * (m * m) as f64 * n as f64), n)
}

#[test]
fn integer_mvar_takes_the_128_bit_path_when_64_bits_could_overflow() {
    // A square wave over the whole i32 range with half-period 1.5 * 2^16, plus noise: at
    // m = 2^16 MVAR's inner sum reaches 1.5 * 2^63 (computed separately), beyond i64, so a
    // 64-bit third difference would wrap; 2 m^2 |d - d0| passes 2^62 from m ~ 2^15, where the
    // engine must switch to 128 bits.
    let mut r = XorShift(7);
    let d: Vec<i64> = (0..220_000u64)
        .map(|k| {
            let noise = (r.next() % 1000) as i64;
            if (k / (3 << 15)) % 2 == 0 {
                i32::MAX as i64 - noise
            } else {
                i32::MIN as i64 + noise
            }
        })
        .collect();
    let mut cfg = AccumConfig::new(1.0);
    cfg.stats = StatSet::only(Stat::Mvar);
    cfg.overlap = Overlap::Full;
    cfg.taus = TauSpec::List(vec![1 << 10, 1 << 14, 1 << 15, 1 << 16]);
    cfg.noise_id = false;
    let mut e: Engine<IntRepr> = Engine::new(cfg);
    d.iter().for_each(|&v| e.push_increment(v));
    let readings = e.read();
    for r in &readings {
        let (var, n) = r.mvar.unwrap();
        let (ev, en) = exact_mvar(&d, r.m as usize);
        assert_eq!(n, en, "m={}", r.m);
        assert!(
            (var - ev).abs() <= 1e-12 * ev,
            "m={}: {var:e} vs exact {ev:e}",
            r.m
        );
    }
    assert_eq!(readings.len(), 4);
}

/// A 1 g accelerometer at 4 ms (186.4 counts of 2.104e-4 m/s per step, the seed paper's LSB)
/// with white noise and a wandering bias, as counts.
fn accel_counts(seed: u64) -> impl FnMut() -> i64 {
    let mut r = XorShift(seed);
    let mut walk: i64 = 0;
    let mut k = 0u64;
    move || {
        k += 1;
        if k.is_multiple_of(4096) {
            walk += (r.next() % 3) as i64 - 1;
        }
        186 + walk / 8 + (r.next() % 15) as i64 - 7
    }
}

#[test]
fn float_input_keeps_full_precision_over_1e9_samples() {
    // The float path gets count * LSB (not exactly representable); the exact reference is the
    // integer path on the counts, times LSB^2. Naive f64 phase would be ~4e7 m/s after 1e9
    // steps, with rounding steps of 7e-9 m/s against second differences of a few 1e-3 m/s at
    // m = 1, and MVAR's running sum of phase (~2e16) would keep no significant digit at all.
    const N: u64 = 1_000_000_000;
    const LSB: f64 = 2.104e-4;
    let mut cfg = AccumConfig::new(0.004);
    cfg.stats = StatSet::ALL;
    cfg.overlap = Overlap::Bounded(16);
    cfg.taus = TauSpec::Octave;
    cfg.noise_id = false;
    let c1 = cfg.clone();
    let exact = std::thread::spawn(move || {
        let mut e: Engine<IntRepr> = Engine::new(c1);
        let mut g = accel_counts(42);
        for _ in 0..N {
            e.push_increment(g());
        }
        e.read()
    });
    let mut f: Engine<FloatRepr> = Engine::new(cfg);
    let mut g = accel_counts(42);
    for _ in 0..N {
        f.push_increment(g() as f64 * LSB);
    }
    let fl = f.read();
    let ex = exact.join().unwrap();
    assert_eq!(fl.len(), ex.len());
    let mut worst: f64 = 0.0;
    for (a, b) in fl.iter().zip(&ex) {
        for stat in Stat::ALL {
            let ((va, na), (vb, nb)) = (a.get(stat).unwrap(), b.get(stat).unwrap());
            assert_eq!(na, nb);
            let vb = vb * LSB * LSB;
            let rel = (va - vb).abs() / vb;
            worst = worst.max(rel);
            assert!(
                rel < 1e-10,
                "{stat:?} m={}: float {va:e}, exact {vb:e}",
                a.m
            );
        }
    }
    eprintln!("1e9 samples: worst relative difference float vs exact {worst:.2e}");
}
