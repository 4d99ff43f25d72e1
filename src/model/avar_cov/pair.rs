//! The lag sums of one pair of cluster sizes ([`PairSums`]): the cross-covariances summed over
//! the whole overlap range by quadrature ([`PairCtx::sum_range`]), their state for live
//! updates ([`PairState`]), the white-phase point masses, and the exact lag-by-lag reference.

use super::far_field::{flicker_series, FAR_FACTOR, NSER, SERIES_TOL};
use super::lag_covariance::{g_cont, pair_count, A};
use super::quadrature::{add, sum_graded, Vals, NV};

/// Index of the random terms in [`PairSums`]: Q, N, B, K.
pub(super) const NQ: usize = 0;
pub(super) const NRAND: usize = 4;

/// Lag sums of one pair of cluster sizes, per unit coefficient and lag unit `tau0 = 1`:
/// `quad[t][u] = sum_h n(h) g_t(h) g_u(h)` and `lin[t] = sum_h n(h) g_t(h)`, where `g_t` is the
/// cross-covariance of the two second differences for term `t` (Q, N, B, K).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PairSums {
    pub quad: [[f64; NRAND]; NRAND],
    pub lin: [f64; NRAND],
}

pub(super) fn products(g: &[f64; 3]) -> [f64; NV] {
    [
        g[0] * g[0],
        g[0] * g[1],
        g[0] * g[2],
        g[1] * g[1],
        g[1] * g[2],
        g[2] * g[2],
        g[0],
        g[1],
        g[2],
    ]
}

/// One pair of cluster sizes at given counts: what the lag function needs.
pub(super) struct PairCtx {
    m1: f64,
    m2: f64,
    big_m1: f64,
    big_m2: f64,
    /// `max(m1, m2)`.
    scale: f64,
    /// `|h|` from which the series is used (infinite: never).
    far: f64,
    /// `g_B(h) = scale^2 sum_k series[k] (scale / h)^(k + 2)`.
    series: [f64; NSER],
    /// `tail[k] = sum_{j >= k} |series[j]| (1/16)^(j - k)`: with `|x| = scale/|h| <= 1/16`, the
    /// terms from order `k` on add at most `|x|^k tail[k]` ([`PairCtx::terms_for`]).
    tail: [f64; NSER],
}

impl PairCtx {
    /// `series`: the pair's [`flicker_series`], or `None` to evaluate `g` directly everywhere.
    fn new(m1: u64, m2: u64, big_m1: u64, big_m2: u64, series: Option<&[f64; NSER]>) -> PairCtx {
        let (fm1, fm2) = (m1 as f64, m2 as f64);
        let scale = fm1.max(fm2);
        PairCtx {
            m1: fm1,
            m2: fm2,
            big_m1: big_m1 as f64,
            big_m2: big_m2 as f64,
            scale,
            far: if series.is_some() {
                FAR_FACTOR * scale
            } else {
                f64::INFINITY
            },
            series: series.copied().unwrap_or([0.0; NSER]),
            tail: series.map_or([0.0; NSER], |c| {
                let mut t = [0.0; NSER];
                let mut acc = 0.0;
                for k in (0..NSER).rev() {
                    acc = c[k].abs() + acc / FAR_FACTOR;
                    t[k] = acc;
                }
                t
            }),
        }
    }

    /// Number of far-field terms that represent `g_B` to [`SERIES_TOL`] of the leading one
    /// wherever `|scale / h| <= x_max` (`x_max <= 1/16`).
    fn terms_for(&self, x_max: f64) -> usize {
        let tol = SERIES_TOL * self.series[0].abs();
        let mut pw = x_max;
        for k in 1..NSER {
            if pw * self.tail[k] <= tol {
                return k;
            }
            pw *= x_max;
        }
        NSER
    }

    /// `(g_N, g_B, g_K)` at lag `h`: the series (its first `terms` terms) far out, the direct
    /// sums nearer.
    #[inline]
    fn g(&self, h: f64, terms: usize) -> [f64; 3] {
        if h.abs() >= self.far {
            let x = self.scale / h;
            let mut acc = 0.0;
            for c in self.series[..terms.min(NSER)].iter().rev() {
                acc = acc * x + c;
            }
            [0.0, self.scale * self.scale * acc * x * x, 0.0]
        } else {
            g_cont(h, self.m1, self.m2)
        }
    }

    #[inline]
    fn vals(&self, h: f64, terms: usize) -> Vals {
        let n = pair_count(h, self.big_m1, self.big_m2);
        let p = products(&self.g(h, terms));
        let mut v = [0.0; 2 * NV];
        for k in 0..NV {
            v[k] = n * p[k];
            v[NV + k] = p[k];
        }
        v
    }

    /// Lags where `g` is not smooth: `j m2 - i m1` (a lag of `G` crosses 0), sorted, and how many
    /// are distinct (no allocation: the live refit calls this for every pair).
    fn kinks(&self) -> ([i64; 9], usize) {
        let (m1, m2) = (self.m1 as i64, self.m2 as i64);
        let mut k = [0i64; 9];
        for i in 0..3i64 {
            for j in 0..3i64 {
                k[(3 * i + j) as usize] = j * m2 - i * m1;
            }
        }
        k.sort_unstable();
        let n = dedup_sorted(&mut k);
        (k, n)
    }

    /// Adds `sum_{h=lo}^{hi}` of the lag values to `acc`. The range is cut where the integrand
    /// changes form (kinks of `g`, of `n(h)` at 0 and `M1 - M2`, and at `+- far` where the
    /// series takes over); each piece is summed by [`sum_graded`] with its distances to the
    /// nearest kinks of `g`, towards which the quadrature panels are graded.
    fn sum_range(&self, lo: i64, hi: i64, acc: &mut Vals) {
        if hi < lo {
            return;
        }
        let (kink_buf, nk) = self.kinks();
        let kinks = &kink_buf[..nk];
        let mut buf = [0i64; 15];
        let mut nb = 0;
        let mut push = |b: i64| {
            if b >= lo && b <= hi + 1 {
                buf[nb] = b;
                nb += 1;
            }
        };
        push(lo);
        push(hi + 1);
        push(0);
        push(self.big_m1 as i64 - self.big_m2 as i64);
        for &k in kinks {
            push(k);
        }
        if self.far.is_finite() {
            let f = self.far.ceil() as i64;
            push(f);
            push(-f + 1);
        }
        let bps = &mut buf[..nb];
        bps.sort_unstable();
        let nb = dedup_sorted(bps);
        let bps = &buf[..nb];
        for w in bps.windows(2) {
            let (p, q) = (w[0], w[1] - 1);
            // A window of the far field (one sign; the quadrature reads it at most one lag
            // beyond its ends) needs only the series terms its nearest lag does.
            let near = (p.abs().min(q.abs()) - 1) as f64;
            let terms = if self.far.is_finite() && p.signum() == q.signum() && near >= self.far {
                self.terms_for(self.scale / near)
            } else {
                NSER
            };
            let f = |h: f64| self.vals(h, terms);
            let s_lo = kinks
                .iter()
                .rev()
                .find(|&&k| k <= p)
                .map_or(f64::INFINITY, |&k| (p - k) as f64);
            let s_hi = kinks
                .iter()
                .find(|&&k| k > q)
                .map_or(f64::INFINITY, |&k| (k - q) as f64);
            sum_graded(p, q, s_lo, s_hi, &f, acc);
        }
    }
}

/// A pair's lag sums at its current counts, and what a larger count needs to update them.
#[derive(Debug, Clone)]
pub(super) struct PairState {
    m1: u64,
    m2: u64,
    pub(super) counts: (u64, u64),
    /// `sum_h n(h) p(h)` and `sum_h p(h)` over the overlap range, for the continuous terms.
    acc: Vals,
    /// White-phase point masses: lag `h`, `g_Q(h)`, and `(g_N, g_B, g_K)` at `h`.
    masses: Vec<(i64, f64, [f64; 3])>,
    /// The pair's far-field flicker series (count-independent).
    series: [f64; NSER],
}

impl PairState {
    /// Sums over the whole overlap range `-(M2-1) ..= M1-1` (see the module doc).
    pub(super) fn fresh(m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairState {
        let series = flicker_series(m1 as f64, m2 as f64);
        let ctx = PairCtx::new(m1, m2, big_m1, big_m2, Some(&series));
        let mut acc = [0.0; 2 * NV];
        ctx.sum_range(-(big_m2 as i64 - 1), big_m1 as i64 - 1, &mut acc);
        PairState {
            m1,
            m2,
            counts: (big_m1, big_m2),
            acc,
            masses: masses(m1, m2),
            series,
        }
    }

    /// Moves the sums to counts `(M1 + d, M2 + d)`, `d >= 0`. The pair count is
    /// `n(h) = min(M2, M1 - h) - max(-h, 0)`, so on the old range every `n(h)` grows by exactly
    /// `d` (adding `d` times the unweighted sums), and the range gains `d` lags at each end.
    /// Returns `false` (nothing changed) when the counts do not move that way.
    pub(super) fn advance(&mut self, big_m1: u64, big_m2: u64) -> bool {
        let (o1, o2) = self.counts;
        if big_m1 < o1 || big_m2 < o2 || big_m1 - o1 != big_m2 - o2 {
            return false;
        }
        let d = (big_m1 - o1) as f64;
        if d == 0.0 {
            return true;
        }
        for k in 0..NV {
            self.acc[k] += d * self.acc[NV + k];
        }
        let ctx = PairCtx::new(self.m1, self.m2, big_m1, big_m2, Some(&self.series));
        ctx.sum_range(-(big_m2 as i64 - 1), -(o2 as i64), &mut self.acc);
        ctx.sum_range(o1 as i64, big_m1 as i64 - 1, &mut self.acc);
        self.counts = (big_m1, big_m2);
        true
    }

    pub(super) fn sums(&self) -> PairSums {
        assemble(&self.acc, &self.masses, self.counts.0, self.counts.1)
    }
}

/// Lag sums by quadrature (see the module doc). `m1, m2 >= 1`, `M1, M2 >= 1`.
pub fn pair_sums(m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairSums {
    PairState::fresh(m1, m2, big_m1, big_m2).sums()
}

/// Lag sums at counts `(M1, M2)` reached from `(M1 - d, M2 - d)` by the incremental update the
/// live cache uses (exposed for tests: it must agree with [`pair_sums`]).
pub fn pair_sums_advanced(m1: u64, m2: u64, steps: &[(u64, u64)]) -> Option<PairSums> {
    let (first, rest) = steps.split_first()?;
    let mut st = PairState::fresh(m1, m2, first.0, first.1);
    for &(c1, c2) in rest {
        if !st.advance(c1, c2) {
            return None;
        }
    }
    Some(st.sums())
}

/// Lag sums summed lag by lag over the whole range (the slow reference for [`pair_sums`]).
pub fn pair_sums_exact(m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairSums {
    let ctx = PairCtx::new(m1, m2, big_m1, big_m2, None);
    let mut acc = [0.0; 2 * NV];
    for h in -(big_m2 as i64 - 1)..=(big_m1 as i64 - 1) {
        add(&mut acc, &ctx.vals(h as f64, NSER), 1.0);
    }
    assemble(&acc, &masses(m1, m2), big_m1, big_m2)
}

/// The white-phase point masses of a pair: `g_Q(h) = sum_{i,j: h = j m2 - i m1} a_i a_j`, with the
/// continuous terms' values at those lags.
fn masses(m1: u64, m2: u64) -> Vec<(i64, f64, [f64; 3])> {
    let mut out: Vec<(i64, f64, [f64; 3])> = Vec::with_capacity(9);
    for (i, ai) in A.iter().enumerate() {
        for (j, aj) in A.iter().enumerate() {
            let h = j as i64 * m2 as i64 - i as i64 * m1 as i64;
            match out.iter_mut().find(|e| e.0 == h) {
                Some(e) => e.1 += ai * aj,
                None => out.push((h, ai * aj, [0.0; 3])),
            }
        }
    }
    out.retain(|e| e.1 != 0.0);
    for e in &mut out {
        e.2 = g_cont(e.0 as f64, m1 as f64, m2 as f64);
    }
    out
}

/// Unpack the continuous-term sums and add the white-phase point masses (nonzero only where a
/// lag `h + i m1 - j m2` is exactly 0).
fn assemble(acc: &Vals, masses: &[(i64, f64, [f64; 3])], big_m1: u64, big_m2: u64) -> PairSums {
    let mut s = PairSums::default();
    let idx = [
        (1, 1, 0),
        (1, 2, 1),
        (1, 3, 2),
        (2, 2, 3),
        (2, 3, 4),
        (3, 3, 5),
    ];
    for (t, u, k) in idx {
        s.quad[t][u] = acc[k];
        s.quad[u][t] = acc[k];
    }
    s.lin[1] = acc[6];
    s.lin[2] = acc[7];
    s.lin[3] = acc[8];
    let (fbm1, fbm2) = (big_m1 as f64, big_m2 as f64);
    for &(h, gq, g) in masses {
        let n = pair_count(h as f64, fbm1, fbm2);
        if n <= 0.0 {
            continue;
        }
        s.quad[NQ][NQ] += n * gq * gq;
        for (t, gt) in g.iter().enumerate() {
            s.quad[NQ][t + 1] += n * gq * gt;
            s.quad[t + 1][NQ] += n * gq * gt;
        }
        s.lin[NQ] += n * gq;
    }
    s
}

/// Removes repeats from a sorted slice in place; returns the number of distinct values (now at
/// its front).
pub(super) fn dedup_sorted(v: &mut [i64]) -> usize {
    let mut n = 0;
    for i in 0..v.len() {
        if n == 0 || v[i] != v[n - 1] {
            v[n] = v[i];
            n += 1;
        }
    }
    n
}

/// The far-field series of the flicker cross-covariance at lag `h` (for tests; valid for
/// `|h| > 2 max(m1, m2)`), per unit coefficient with `tau0 = 1`.
pub fn flicker_far_field(h: f64, m1: u64, m2: u64) -> f64 {
    let series = flicker_series(m1 as f64, m2 as f64);
    let mut ctx = PairCtx::new(m1, m2, 1, 1, Some(&series));
    ctx.far = 0.0;
    ctx.g(h, NSER)[1]
}
