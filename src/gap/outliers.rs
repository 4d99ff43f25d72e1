//! Outliers: isolated samples far outside the channel's noise (a glitch on one rate sample),
//! found and replaced in the stream before the diagnosis's evidence sees them, so that they
//! pose neither as bias jumps (a spike moves one block mean: up then down in the block-mean
//! differences) nor as white rate noise (each spike adds its square to the short-tau AVAR, and
//! their heavy tail widens the scatter the curve's covariance assumes). docs/gap.md, "Outliers".
//!
//! # Test
//!
//! The increments are judged in chunks of [`CHUNK`]. With `e_k = d_k - d_{k-1}` the first
//! differences, a spike of size `a` on `d_k` gives `e_k = +a` and `e_{k+1} = -a`: two large
//! differences of *opposite* sign on each side of one sample. A bias step gives one large
//! difference only, so it is never taken for a spike. Sample `k` is an outlier when
//! `e_k` and `-e_{k+1}` have the same sign and both exceed [`OUTLIER_Z`] times the chunk's
//! robust scale of `e`: the rms of the differences within 8 median-based deviations
//! (`median|e| / 0.6745`, the median absolute difference of a normal sample over its quantile),
//! never below the smallest non-zero `|e|`. The trimmed rms, not the median itself: a counter's
//! median difference is a whole number of counts, as low as half the standard deviation when the
//! step is near the noise (measured: two clean runs of 120 flagged with the median). The floor
//! keeps a counter whose differences are mostly zero from calling every one-count step an
//! outlier. Under Gaussian
//! noise `e_k` and `-e_{k+1}` have correlation 1/2, and both beyond 6 sigma has probability
//! about 1e-13 per sample (bivariate normal tail): none in a year at 1 kHz.
//!
//! A flagged increment is replaced by the mean of its neighbours (the left one already
//! cleaned); its size is `(d_k - replacement) / tau0` in u/s. Work per sample: two
//! differences and a comparison, plus one selection (O(n)) per chunk.
//!
//! The samples whose two differences lie beyond [`SHOULDER_Z`] = 4 deviations (opposite signs,
//! not both beyond 6) are counted too, and kept: the tail's shoulder, which tells isolated
//! glitches (few there) from a white noise whose own law is heavy-tailed (many there:
//! [`OutlierCount::heavy_tail`]; docs/gap.md, "A heavy tail (session 49)").

/// Increments per chunk (the scale is the chunk's own).
pub const CHUNK: usize = 4096;
/// Both differences beside a spike beyond this many robust standard deviations.
pub const OUTLIER_Z: f64 = 6.0;
/// The rms scale counts the differences within this many median-based deviations.
const TRIM: f64 = 8.0;
/// The median non-zero difference, in steps (the smallest non-zero difference), above which
/// zero differences are not a counter's but a stuck stretch's, and the scale leaves them out.
const FINE_STEPS: f64 = 8.0;
/// `Phi^-1(3/4)`: the median of `|e|` over the standard deviation of a normal `e`.
const MAD_NORMAL: f64 = 0.674_489_750_196_081_7;

/// The shoulder of the tail: both differences beside a sample beyond this many robust standard
/// deviations (and not both beyond [`OUTLIER_Z`]). Counted, never replaced.
pub const SHOULDER_Z: f64 = 4.0;
/// Probability per sample of a shoulder pair under Gaussian white noise: `2 P(X > 4, Y > 4)`,
/// `(X, Y)` standard bivariate normal with correlation 1/2 (the correlation of `e_k` and
/// `-e_{k+1}`), less the same beyond 6 (7.8e-13). Computed with scipy's
/// `multivariate_normal.cdf([-4, -4], cov=[[1, .5], [.5, 1]])` (4.8705e-7, times two).
pub const SHOULDER_P_NORMAL: f64 = 9.741e-7;

/// What was found (sizes in u/s).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct OutlierCount {
    pub count: u64,
    /// Sum of the squared sizes (u^2/s^2).
    pub sum_sq_size: f64,
    /// Largest absolute size (u/s).
    pub max_size: f64,
    /// Samples judged (both neighbours and a scale known).
    #[serde(default)]
    pub judged: u64,
    /// Samples in the tail's shoulder ([`SHOULDER_Z`]): both differences beside them beyond 4
    /// robust standard deviations with opposite signs, not both beyond [`OUTLIER_Z`].
    #[serde(default)]
    pub shoulder: u64,
}

impl OutlierCount {
    /// The shoulder count a Gaussian white noise gives over the samples judged.
    pub fn shoulder_normal(&self) -> f64 {
        SHOULDER_P_NORMAL * self.judged as f64
    }

    /// Whether the samples beyond [`OUTLIER_Z`] are the far end of the noise's own heavy tail
    /// rather than isolated glitches (docs/gap.md, "Outliers", "A heavy tail (session 49)").
    /// Glitches stand apart from the noise: few samples between 4 and 6 robust deviations
    /// (a Gaussian noise puts [`SHOULDER_P_NORMAL`] of them there, spikes of 8 or more only
    /// the odd one). A heavy-tailed law (Student's t) fills that shoulder several times over
    /// what it puts beyond 6 (t with 4 degrees of freedom: 3.4-4 times, measured). So: some
    /// samples beyond 6, at least twice as many in the shoulder as beyond, and a shoulder a
    /// normal law would reach with probability well below 1e-4 (more than its mean + 4
    /// sqrt(mean) + 4). Twice, not half (the first form, session 49): spikes whose sizes reach
    /// down to the shoulder, on a scale a strong line widens (a tenth review's 22 spikes of
    /// 15-40 deviations beside a 36 Hz line: 7 beyond, 8 in the shoulder), were called a tail.
    pub fn heavy_tail(&self) -> bool {
        let mu = self.shoulder_normal();
        self.count > 0
            && self.shoulder >= 2 * self.count
            && self.shoulder as f64 > mu + 4.0 * mu.sqrt() + 4.0
    }

    /// The rms of the sizes (u/s), 0 when there is none.
    pub fn rms_size(&self) -> f64 {
        if self.count == 0 {
            0.0
        } else {
            (self.sum_sq_size / self.count as f64).sqrt()
        }
    }
}

/// The streaming outlier filter of one channel: increments in, cleaned increments out (in
/// chunks; [`Despiker::flush`] releases the rest).
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Despiker {
    /// Increments waiting to be judged (u).
    buf: Vec<f64>,
    /// The last cleaned increment released and the one before it, the left context of the
    /// next chunk (None after a gap or at the start).
    left: Option<f64>,
    /// Scale of the previous chunk (used for a short chunk at a flush).
    last_scale: Option<f64>,
    pub found: OutlierCount,
    tau0_s: f64,
}

impl Despiker {
    pub fn new(tau0_s: f64) -> Self {
        Self {
            tau0_s,
            ..Self::default()
        }
    }

    /// Increments held (at most [`CHUNK`]).
    pub fn pending(&self) -> usize {
        self.buf.len()
    }

    /// Adds one increment; when a chunk is full, judges all but its last increment (the right
    /// neighbour of the last is not known yet) and passes the cleaned ones to `out`.
    #[inline]
    pub fn push(&mut self, d: f64, out: &mut impl FnMut(f64)) {
        if self.push_ready(d) {
            self.judge_chunk(out);
        }
    }

    /// Adds one increment; true when a chunk is full and [`Despiker::judge_chunk`] is due.
    #[inline]
    pub fn push_ready(&mut self, d: f64) -> bool {
        self.buf.push(d);
        self.buf.len() >= CHUNK
    }

    /// Judges a full chunk but its last increment and passes the cleaned ones to `out`.
    pub fn judge_chunk(&mut self, out: &mut impl FnMut(f64)) {
        self.judge(false, out);
    }

    /// Judges and releases everything held (before a gap, or at a snapshot): the last
    /// increment has no right neighbour and is released as it is. After a flush the left
    /// context is cleared (`gap`) or kept.
    pub fn flush(&mut self, gap: bool, out: &mut impl FnMut(f64)) {
        if !self.buf.is_empty() {
            self.judge(true, out);
        }
        if gap {
            self.left = None;
        }
    }

    /// The robust scale of the first differences of `x` (see the module doc).
    fn scale(x: &[f64], left: Option<f64>) -> Option<f64> {
        let mut e: Vec<f64> = Vec::with_capacity(x.len());
        if let Some(l) = left {
            e.push((x[0] - l).abs());
        }
        e.extend(x.windows(2).map(|w| (w[1] - w[0]).abs()));
        if e.len() < 16 {
            return None;
        }
        let floor = e
            .iter()
            .copied()
            .filter(|v| *v > 0.0)
            .fold(f64::INFINITY, f64::min);
        let floor = if floor.is_finite() { floor } else { 0.0 };
        // Zero differences are a counter's own when its step is near the noise. Where the
        // non-zero ones are many steps wide, a run of zeros is a stretch where the channel did
        // not move (stuck, saturated): the noise's scale is read without them, else a chunk
        // half stuck got the scale of its zeros and had its ordinary samples taken for spikes.
        let nz = e.iter().filter(|v| **v > 0.0).count();
        if nz >= 16 && nz < e.len() {
            let mut nonzero: Vec<f64> = e.iter().copied().filter(|v| *v > 0.0).collect();
            let m = nonzero.len() / 2;
            let med_nz = *nonzero.select_nth_unstable_by(m, |a, b| a.total_cmp(b)).1;
            if med_nz > FINE_STEPS * floor {
                e = nonzero;
            }
        }
        let mid = e.len() / 2;
        let med = *e.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1;
        // The median of a counter's differences is a whole number of counts, which can be half
        // the standard deviation: the scale is the rms of the differences within TRIM robust
        // deviations (the outliers are beyond), never below one count.
        let cut = TRIM * (med / MAD_NORMAL).max(floor);
        let (mut sum, mut n) = (0.0, 0usize);
        for &v in e.iter().filter(|v| **v <= cut) {
            sum += v * v;
            n += 1;
        }
        let s = if n > 0 { (sum / n as f64).sqrt() } else { 0.0 }.max(floor);
        (s > 0.0 && s.is_finite()).then_some(s)
    }

    fn judge(&mut self, all: bool, out: &mut impl FnMut(f64)) {
        let n = self.buf.len();
        let scale = Self::scale(&self.buf, self.left).or(self.last_scale);
        if let Some(s) = Self::scale(&self.buf, self.left) {
            self.last_scale = Some(s);
        }
        let keep_last = !all && n >= 2;
        let release = if keep_last { n - 1 } else { n };
        let thr = scale.map(|s| OUTLIER_Z * s);
        let shoulder = scale.map(|s| SHOULDER_Z * s);
        for k in 0..release {
            let d = self.buf[k];
            let mut v = d;
            if let (Some(t), Some(sh), Some(l), Some(&r)) =
                (thr, shoulder, self.left, self.buf.get(k + 1))
            {
                let e_in = d - l;
                let e_out = r - d;
                self.found.judged += 1;
                let apart = e_in.signum() != e_out.signum();
                let beyond = e_in.abs() > t && e_out.abs() > t;
                if apart && !beyond && e_in.abs() > sh && e_out.abs() > sh {
                    self.found.shoulder += 1;
                }
                if apart && beyond {
                    // The right neighbour may be a spike too (two in a row): then use the left.
                    let r_ok = self
                        .buf
                        .get(k + 2)
                        .is_none_or(|&rr| (rr - r).abs() <= t || (r - l).abs() <= t);
                    let rep = if r_ok { 0.5 * (l + r) } else { l };
                    let size = (d - rep) / self.tau0_s;
                    self.found.count += 1;
                    self.found.sum_sq_size += size * size;
                    self.found.max_size = self.found.max_size.max(size.abs());
                    v = rep;
                }
            }
            out(v);
            self.left = Some(v);
        }
        self.buf.drain(..release);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    fn run(x: &[f64]) -> (Vec<f64>, OutlierCount) {
        let mut d = Despiker::new(1.0);
        let mut out = Vec::new();
        for &v in x {
            d.push(v, &mut |c| out.push(c));
        }
        d.flush(false, &mut |c| out.push(c));
        (out, d.found)
    }

    /// White noise with 20 spikes of 30 sigma and 5 steps of 50 sigma: the 20 spikes are
    /// found, replaced by the mean of their neighbours, and the steps pass untouched.
    #[test]
    fn spikes_found_steps_kept() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let n = 200_000;
        let mut x: Vec<f64> = (0..n)
            .map(|_| {
                let z: f64 = StandardNormal.sample(&mut rng);
                z
            })
            .collect();
        let mut level = 0.0;
        for (i, v) in x.iter_mut().enumerate() {
            if i % 40_000 == 20_000 {
                level += 50.0;
            }
            *v += level;
        }
        let clean = x.clone();
        for k in 0..20 {
            x[5000 + k * 9973] += if k % 2 == 0 { 30.0 } else { -30.0 };
        }
        let (out, found) = run(&x);
        assert_eq!(out.len(), n);
        assert_eq!(found.count, 20, "{found:?}");
        assert!((found.rms_size() - 30.0).abs() < 3.0, "{found:?}");
        let moved = out
            .iter()
            .zip(&clean)
            .filter(|(a, b)| (*a - *b).abs() > 5.0)
            .count();
        assert_eq!(moved, 0, "every spike replaced by a value within the noise");
    }

    /// White noise (sd 1, six decimals) with a stretch of 3000 samples stuck at one value
    /// across a chunk boundary: no outlier (the chunks half stuck had the scale of their zeros,
    /// and 1288 of their ordinary samples were replaced as spikes), and 10 spikes of 30 sd
    /// placed in the noisy half of those chunks are still found.
    #[test]
    fn a_stuck_stretch_is_not_a_run_of_spikes() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(11);
        let mut x: Vec<f64> = (0..40_000)
            .map(|i| {
                let z: f64 = StandardNormal.sample(&mut rng);
                if (10_000..13_000).contains(&i) {
                    0.37
                } else {
                    (z * 1e6).round() / 1e6
                }
            })
            .collect();
        assert_eq!(run(&x).1.count, 0);
        for k in 0..10 {
            x[13_100 + 150 * k] += if k % 2 == 0 { 30.0 } else { -30.0 };
        }
        let found = run(&x).1;
        assert_eq!(found.count, 10, "{found:?}");
    }

    /// The heavy-tail rule on the counts the reviews measured: Student's t noise (rev9 E01: 412
    /// beyond, 1664 in the shoulder over 1.86 M samples; E07, t8: 2 and 57 over 336 k) is a
    /// tail; spikes beside a strong line (rev10 M35/ax: 7 and 8 over 248 k) and spikes on a
    /// normal noise (rev9 E13: 101 and 5) are not; nothing beyond 6 is no tail whatever the
    /// shoulder.
    #[test]
    fn a_heavy_tail_by_its_shoulder() {
        let c = |count, shoulder, judged| OutlierCount {
            count,
            shoulder,
            judged,
            ..OutlierCount::default()
        };
        assert!(c(412, 1664, 1_860_000).heavy_tail());
        assert!(c(2, 57, 336_000).heavy_tail());
        assert!(!c(7, 8, 248_000).heavy_tail());
        assert!(!c(101, 5, 648_000).heavy_tail());
        assert!(!c(0, 500, 1_000_000).heavy_tail());
        // Over 1.86 M samples a normal law's shoulder is 1.8, its bound 1.8 + 4 sqrt(1.8) + 4 =
        // 11.2: 12 is past it, 11 is not.
        assert!(c(2, 12, 1_860_000).heavy_tail());
        assert!(!c(2, 11, 1_860_000).heavy_tail());
    }

    /// A counter whose increments are mostly one value (differences mostly zero) has no
    /// outlier: the scale's floor is one count.
    #[test]
    fn a_quiet_counter_has_none() {
        let x: Vec<f64> = (0..50_000)
            .map(|i| if i % 97 == 0 { 3.0 } else { 2.0 })
            .collect();
        assert_eq!(run(&x).1.count, 0);
    }
}
