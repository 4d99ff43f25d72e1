//! The inner loops: the lagged slices of a stream and the sums of squared differences over
//! them, in partial sums the compiler vectorizes.

#[allow(unused_imports)]
use super::*;

/// The differences of span `(K - 1) mp` not yet taken from `buf`, starting at stream index
/// `next`: `K` equal-length slices of the buffer at offsets `0, mp, 2 mp, ...`.
#[inline(always)]
pub(super) fn lagged<T: Copy, const K: usize>(
    buf: &Buf<T>,
    next: u64,
    mp: u64,
) -> Option<[&[T]; K]> {
    lagged_in(&buf.data, buf.base, next, mp)
}

/// [`lagged`] on a slice whose first element is stream index `base`.
#[inline(always)]
pub(super) fn lagged_in<T, const K: usize>(
    data: &[T],
    base: u64,
    next: u64,
    mp: u64,
) -> Option<[&[T]; K]> {
    let span = (K as u64 - 1) * mp;
    let end = base + data.len() as u64;
    (end > next + span).then(|| lagged_at(data, base, next, mp, (end - span - next) as usize))
}

/// Sum of `f(a_i, b_i, c_i)^2` over equal-length slices, in [`LANES`] partial sums over
/// `chunks_exact` so the loop has no bounds checks and runs on vector lanes.
#[inline(always)]
pub(super) fn sum_sq3<T: Copy>(a: &[T], b: &[T], c: &[T], f: impl Fn(T, T, T) -> f64) -> f64 {
    let mut acc = [0.0f64; LANES];
    let (ca, cb, cc) = (
        a.chunks_exact(LANES),
        b.chunks_exact(LANES),
        c.chunks_exact(LANES),
    );
    let mut rest = 0.0;
    for ((x, y), z) in ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .zip(cc.remainder())
    {
        let v = f(*x, *y, *z);
        rest += v * v;
    }
    for ((x, y), z) in ca.zip(cb).zip(cc) {
        for l in 0..LANES {
            let v = f(x[l], y[l], z[l]);
            acc[l] += v * v;
        }
    }
    fold_lanes(acc) + rest
}

/// The same with four slices.
#[inline(always)]
pub(super) fn sum_sq4<T: Copy>(
    a: &[T],
    b: &[T],
    c: &[T],
    d: &[T],
    f: impl Fn(T, T, T, T) -> f64,
) -> f64 {
    let mut acc = [0.0f64; LANES];
    let (ca, cb, cc, cd) = (
        a.chunks_exact(LANES),
        b.chunks_exact(LANES),
        c.chunks_exact(LANES),
        d.chunks_exact(LANES),
    );
    let mut rest = 0.0;
    let rem = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .zip(cc.remainder())
        .zip(cd.remainder());
    for (((w, x), y), z) in rem {
        let v = f(*w, *x, *y, *z);
        rest += v * v;
    }
    for (((w, x), y), z) in ca.zip(cb).zip(cc).zip(cd) {
        for l in 0..LANES {
            let v = f(w[l], x[l], y[l], z[l]);
            acc[l] += v * v;
        }
    }
    fold_lanes(acc) + rest
}

/// `K` slices of `data` (whose first element is stream index `base`), `n` long each, starting
/// at stream indices `from, from + mp, from + 2 mp, ...`.
#[inline(always)]
pub(super) fn lagged_at<T, const K: usize>(
    data: &[T],
    base: u64,
    from: u64,
    mp: u64,
    n: usize,
) -> [&[T]; K] {
    let o = (from - base) as usize;
    let m = mp as usize;
    std::array::from_fn(|j| &data[o + j * m..o + j * m + n])
}

/// Second differences `x2 - 2 x1 + x0` of integer phase as exact doubles (docs/theory.md section 1),
/// into `out`; the caller proves `|result| < 2^51`, so their differences are exact too.
/// (Summing their squares in the same loop was measured slower: the stores and the add chains
/// together defeat the vectorizer.)
#[inline(never)]
pub(super) fn second_differences(x0: &[i64], x1: &[i64], x2: &[i64], out: &mut Vec<f64>) {
    out.clear();
    out.extend(
        x0.iter()
            .zip(x1)
            .zip(x2)
            .map(|((&a, &b), &c)| IntRepr::d2_narrow(c, b, a)),
    );
}

/// Sum of squares, in [`LANES`] partial sums (independent add chains, so the loop is bound by
/// throughput rather than by the latency of one chain).
#[inline(never)]
pub(super) fn sum_sq(v: &[f64]) -> f64 {
    let mut acc = [0.0f64; LANES];
    let c = v.chunks_exact(LANES);
    let rest: f64 = c.remainder().iter().map(|x| x * x).sum();
    for x in c {
        for l in 0..LANES {
            acc[l] += x[l] * x[l];
        }
    }
    fold_lanes(acc) + rest
}

/// Sum of `(b_i - a_i)^2`, in [`LANES`] partial sums.
#[inline(never)]
pub(super) fn sum_sq_diff(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; LANES];
    let (ca, cb) = (a.chunks_exact(LANES), b.chunks_exact(LANES));
    let rest: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| (y - x) * (y - x))
        .sum();
    for (x, y) in ca.zip(cb) {
        for l in 0..LANES {
            let d = y[l] - x[l];
            acc[l] += d * d;
        }
    }
    fold_lanes(acc) + rest
}

/// Partial sums per kernel: 8 doubles are 4 independent two-lane SSE2 add chains, enough to
/// cover the add latency (4 and 16 were measured slower on kernel_probe, BENCHMARKS.md).
pub(super) const LANES: usize = 8;

/// The partial sums added pairwise.
#[inline(always)]
pub(super) fn fold_lanes(mut acc: [f64; LANES]) -> f64 {
    let mut w = LANES;
    while w > 1 {
        w /= 2;
        for l in 0..w {
            acc[l] += acc[l + w];
        }
    }
    acc[0]
}
