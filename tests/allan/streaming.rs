//! Streaming accumulators against the batch formulas (docs/theory.md section 1) on seeded random
//! data: random lengths, values and gap patterns; integer and floating paths; bounded mode.

use crate::common::STREAM_VS_BATCH_REL;
use allanscope::allan::accum::{
    AccumConfig, Engine, FloatRepr, IntRepr, LevelReading, Overlap, TauSpec,
};
use allanscope::allan::batch::{mvar, oavar, ohvar, phase_from_increments, BatchPoint};
use allanscope::allan::Stat;
use proptest::prelude::*;

fn cfg(tau0: f64, overlap: Overlap) -> AccumConfig {
    let mut c = AccumConfig::new(tau0);
    c.overlap = overlap;
    c.taus = TauSpec::Octave;
    c
}

/// Phase segments from increments with gaps (`None` = a missing increment).
fn segments(incs: &[Option<f64>]) -> Vec<Vec<f64>> {
    let mut segs = Vec::new();
    let mut cur: Vec<f64> = Vec::new();
    for d in incs {
        match d {
            Some(v) => cur.push(*v),
            None => {
                if !cur.is_empty() {
                    segs.push(phase_from_increments(&cur));
                    cur.clear();
                }
            }
        }
    }
    if !cur.is_empty() {
        segs.push(phase_from_increments(&cur));
    }
    segs
}

fn batch(stat: Stat, segs: &[Vec<f64>], m: usize, tau0: f64) -> Option<BatchPoint> {
    let s: Vec<&[f64]> = segs.iter().map(|v| v.as_slice()).collect();
    match stat {
        Stat::Avar => oavar(&s, m, tau0),
        Stat::Hvar => ohvar(&s, m, tau0),
        Stat::Mvar => mvar(&s, m, tau0),
    }
}

fn rel(a: f64, b: f64) -> f64 {
    if a == b {
        0.0
    } else {
        (a - b).abs() / a.abs().max(b.abs())
    }
}

/// Every level of `readings` equals the batch formula on `segs`; every batch point with a
/// difference is present.
fn assert_matches_batch(readings: &[LevelReading], segs: &[Vec<f64>], tau0: f64, tol: f64) {
    let longest = segs.iter().map(|s| s.len()).max().unwrap_or(0);
    for stat in Stat::ALL {
        let mut m = 1usize;
        while m <= longest {
            let b = batch(stat, segs, m, tau0);
            let r = readings
                .iter()
                .find(|r| r.m == m as u64)
                .and_then(|r| r.get(stat));
            match (b, r) {
                (None, None) => {}
                (Some(b), Some((var, n))) => {
                    assert_eq!(n, b.count, "{stat:?} m={m} count");
                    assert!(
                        rel(var, b.var) <= tol,
                        "{stat:?} m={m}: {var:e} vs {:e}",
                        b.var
                    );
                }
                (b, r) => panic!("{stat:?} m={m}: batch {b:?}, stream {r:?}"),
            }
            m *= 2;
        }
    }
}

fn incs_strategy() -> impl Strategy<Value = Vec<Option<f64>>> {
    // Values around a large mean (a 1 g accelerometer's increments), 2% of rows missing. They
    // are multiples of 2^-30, so the batch reference's phase is exact in f64 and the reference
    // itself is good to a few ulps (with arbitrary values its rounded phase, not the stream, would
    // be the less accurate side at 1e-12); arbitrary values are covered by tests/allan/precision.rs.
    prop::collection::vec(
        (0u32..100, -1.0f64..1.0).prop_map(|(g, v)| {
            let exact = ((0.0392 + 1e-3 * v) * 1073741824.0).round() / 1073741824.0;
            (g >= 2).then_some(exact)
        }),
        1..3000,
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, .. ProptestConfig::default() })]

    #[test]
    fn float_stream_equals_batch_with_gaps(incs in incs_strategy()) {
        let tau0 = 0.004;
        let mut e: Engine<FloatRepr> = Engine::new(cfg(tau0, Overlap::Full));
        for d in &incs {
            match d { Some(v) => e.push_increment(*v), None => e.push_gap(1) }
        }
        let segs = segments(&incs);
        assert_matches_batch(&e.read(), &segs, tau0, STREAM_VS_BATCH_REL);
        prop_assert_eq!(e.t_data_s(), incs.len() as f64 * tau0);
    }

    #[test]
    fn integer_stream_equals_batch_with_gaps(
        incs in prop::collection::vec(
            (0u32..100, -40i64..40).prop_map(|(g, v)| (g >= 2).then_some(186 + v)), 1..3000)
    ) {
        let tau0 = 0.004;
        let mut e: Engine<IntRepr> = Engine::new(cfg(tau0, Overlap::Full));
        for d in &incs {
            match d { Some(v) => e.push_increment(*v), None => e.push_gap(1) }
        }
        let f: Vec<Option<f64>> = incs.iter().map(|d| d.map(|v| v as f64)).collect();
        assert_matches_batch(&e.read(), &segments(&f), tau0, STREAM_VS_BATCH_REL);
    }

    /// Bounded mode uses exactly the full-overlap sums wherever its stride is 1.
    #[test]
    fn bounded_equals_full_where_stride_is_one(incs in incs_strategy(), l in 1u64..40) {
        let tau0 = 0.01;
        let mut full: Engine<FloatRepr> = Engine::new(cfg(tau0, Overlap::Full));
        let mut bounded: Engine<FloatRepr> = Engine::new(cfg(tau0, Overlap::Bounded(l)));
        for d in &incs {
            match d {
                Some(v) => { full.push_increment(*v); bounded.push_increment(*v) }
                None => { full.push_gap(1); bounded.push_gap(1) }
            }
        }
        let f = full.read();
        let b = bounded.read();
        let mut compared = 0;
        for rb in b.iter().filter(|r| r.stride == 1) {
            let rf = f.iter().find(|r| r.m == rb.m).expect("level in full mode");
            prop_assert_eq!(rb, rf);
            compared += 1;
        }
        // Levels with m <= L have stride 1.
        prop_assert!(compared >= b.iter().filter(|r| r.m <= l).count());
    }
}

/// Batch estimator with differences every `stride` samples (what bounded mode computes when
/// its stride exceeds 1), on one segment of phase.
fn strided_batch(stat: Stat, x: &[f64], m: usize, stride: usize, tau0: f64) -> (f64, u64) {
    let tau = m as f64 * tau0;
    let (span, denom) = match stat {
        Stat::Avar => (2 * m, 2.0 * tau * tau),
        Stat::Hvar => (3 * m, 6.0 * tau * tau),
        Stat::Mvar => (3 * m - 1, 2.0 * (m * m) as f64 * tau * tau),
    };
    let mut sum = 0.0;
    let mut n = 0u64;
    let mut k = 0;
    while k + span < x.len() {
        let v = match stat {
            Stat::Avar => x[k + 2 * m] - 2.0 * x[k + m] + x[k],
            Stat::Hvar => x[k + 3 * m] - 3.0 * x[k + 2 * m] + 3.0 * x[k + m] - x[k],
            Stat::Mvar => (k..k + m)
                .map(|i| x[i + 2 * m] - 2.0 * x[i + m] + x[i])
                .sum(),
        };
        sum += v * v;
        n += 1;
        k += stride;
    }
    (sum / (denom * n as f64), n)
}

#[test]
fn bounded_mode_equals_strided_batch() {
    // Seeded LCG data: white noise plus a random walk, 20000 samples, no gaps.
    let mut s: u64 = 12345;
    let mut rnd = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    };
    let mut rw = 0.0;
    let incs: Vec<f64> = (0..20000)
        .map(|_| {
            rw += 0.01 * rnd();
            1.0 + rnd() + rw
        })
        .collect();
    let x = phase_from_increments(&incs);
    for l in [4u64, 8, 16] {
        let mut e: Engine<FloatRepr> = Engine::new(cfg(1.0, Overlap::Bounded(l)));
        incs.iter().for_each(|&d| e.push_increment(d));
        let readings = e.read();
        let mut strided_levels = 0;
        for r in &readings {
            assert_eq!(r.stride, (r.m / l).max(1), "L={l} m={}", r.m);
            for stat in Stat::ALL {
                if let Some((var, n)) = r.get(stat) {
                    let (bv, bn) = strided_batch(stat, &x, r.m as usize, r.stride as usize, 1.0);
                    assert_eq!(n, bn, "L={l} {stat:?} m={}", r.m);
                    assert!(
                        rel(var, bv) < 1e-10,
                        "L={l} {stat:?} m={}: {var:e} {bv:e}",
                        r.m
                    );
                }
            }
            strided_levels += (r.stride > 1) as usize;
        }
        assert!(
            strided_levels >= 5,
            "L={l}: {strided_levels} strided levels"
        );
    }
}

#[test]
fn bounded_memory_does_not_grow_with_the_run() {
    // Stream memory after 1e5 and after 2e6 samples: bounded mode holds O(L log N) points.
    let mut e: Engine<IntRepr> = Engine::new(cfg(0.004, Overlap::Bounded(16)));
    let mut s: u64 = 1;
    let mut bytes_at = Vec::new();
    for k in 0..2_000_000u64 {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        e.push_increment(186 + (s % 7) as i64 - 3);
        if k == 100_000 || k == 1_999_999 {
            e.read();
            bytes_at.push(e.stream_bytes());
        }
    }
    // Stream 1's block (2048 points of i64 phase and i128 running sum) and about 4L points per
    // further level: a few hundred KB, against 48 MB for the 2e6 points of an exact run.
    // Between 1e5 and 2e6 samples only the rings of the few new octaves are added.
    assert!(bytes_at[1] < 300_000, "{bytes_at:?}");
    assert!(bytes_at[1] < bytes_at[0] + bytes_at[0] / 10, "{bytes_at:?}");
}

#[test]
fn gap_breaks_only_the_differences_spanning_it() {
    // 100 unit increments, then a gap of 3, then 100 more: at m = 1 AVAR has 99 + 99 differences.
    let mut e: Engine<IntRepr> = Engine::new(cfg(1.0, Overlap::Full));
    (0..100).for_each(|k| e.push_increment(k % 3));
    e.push_gap(3);
    (0..100).for_each(|k| e.push_increment(k % 5));
    let r = e.read();
    assert_eq!(r[0].avar.unwrap().1, 99 + 99);
    assert_eq!(e.segments(), 2);
    assert_eq!(e.t_data_s(), 203.0);
}

/// Integer counts in random chunks through `push_increments`, with gaps, in bounded mode:
/// the same readings, bit for bit, as pushing one sample at a time; and the fused integer
/// kernels (AVAR with HVAR in one pass, MVAR from moving sums of phase) agree with the
/// floating path's separate kernels. A rare large count makes the narrow bounds fail part
/// way through the run, so both the fused and the exact 128-bit paths run.
fn chunked_int_case(incs: &[Option<i64>], cuts: &[usize], l: u64) {
    let tau0 = 0.004;
    let mut c = cfg(tau0, Overlap::Bounded(l));
    c.stats = allanscope::allan::accum::StatSet::ALL;
    let mut one: Engine<IntRepr> = Engine::new(c.clone());
    let mut many: Engine<IntRepr> = Engine::new(c.clone());
    let mut float: Engine<FloatRepr> = Engine::new(c);
    for d in incs {
        match d {
            Some(v) => {
                one.push_increment(*v);
                float.push_increment(*v as f64);
            }
            None => {
                one.push_gap(1);
                float.push_gap(1);
            }
        }
    }
    // The same data in chunks cut at `cuts` and at the gaps.
    let mut i = 0;
    let mut cut = cuts.iter().copied().peekable();
    while i < incs.len() {
        if incs[i].is_none() {
            many.push_gap(1);
            i += 1;
            continue;
        }
        let mut j = i;
        while j < incs.len() && incs[j].is_some() && cut.peek().is_none_or(|&c| j < c.max(i + 1)) {
            j += 1;
        }
        while cut.peek().is_some_and(|&c| c <= j) {
            cut.next();
        }
        let chunk: Vec<i64> = incs[i..j].iter().map(|d| d.unwrap()).collect();
        many.push_increments(&chunk);
        i = j;
    }
    let (a, b, f) = (one.read(), many.read(), float.read());
    assert_eq!(a, b, "push_increments differs from push_increment");
    assert_eq!(a.len(), f.len());
    for (ri, rf) in a.iter().zip(&f) {
        assert_eq!((ri.m, ri.stride), (rf.m, rf.stride));
        for stat in [Stat::Avar, Stat::Hvar, Stat::Mvar] {
            match (ri.get(stat), rf.get(stat)) {
                (Some((vi, ni)), Some((vf, nf))) => {
                    assert_eq!(ni, nf, "{stat:?} m {} count", ri.m);
                    assert!(
                        rel(vi, vf) < STREAM_VS_BATCH_REL,
                        "{stat:?} m {}: int {vi} float {vf}",
                        ri.m
                    );
                }
                (None, None) => {}
                other => panic!("{stat:?} m {}: {other:?}", ri.m),
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]

    #[test]
    fn chunked_integer_pushes_equal_single_pushes_and_the_float_path(
        incs in prop::collection::vec(
            (0u32..1000, -40i64..40, 0u32..20000).prop_map(|(g, v, big)| {
                (g >= 3).then_some(if big == 0 { 1i64 << 40 } else { 186 + v })
            }),
            1..20000,
        ),
        cuts in prop::collection::vec(0usize..20000, 0..40),
        l in 1u64..40,
    ) {
        let mut cuts = cuts;
        cuts.sort_unstable();
        chunked_int_case(&incs, &cuts, l);
    }
}

#[test]
fn chunked_integer_pushes_long_run_with_a_late_large_count() {
    // 300 000 counts (many blocks, strided levels up to m = 2^16), one count of 2^40 at 70%
    // alone between two gaps, so it takes part in no difference: the levels whose narrow bound
    // fails after it switch to the exact 128-bit path, and the sums stay those of ordinary
    // counts (a mistake in either path shows).
    let mut s: u64 = 0x2545F4914F6CDD1D;
    let incs: Vec<Option<i64>> = (0..300_000)
        .map(|k| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            match k {
                209_999 | 210_001 => None,
                210_000 => Some(1i64 << 40),
                _ => Some(186 + (s % 81) as i64 - 40),
            }
        })
        .collect();
    let cuts: Vec<usize> = (1..60).map(|k| k * 4999 + (k * k) % 97).collect();
    chunked_int_case(&incs, &cuts, 16);
}

/// A channel whose every increment is the same is constant: its variances are exactly 0 (a
/// straight line of phase), counts or floats. A counts channel stepping between two
/// neighbouring counts, the larger first (3, 2, 3, 3, 2, ...: a quantized rate at rest), is
/// not: its AVAR at m = 1 equals the batch formula. Before session 30 the integer `deviation`
/// was 0 for a step of -1 too, and such a channel read as constant.
#[test]
fn constant_channels_read_zero_and_neighbouring_counts_do_not() {
    let c = cfg(0.01, Overlap::Full);
    let toggling: Vec<i64> = (0..4000).map(|i| if i % 3 == 1 { 2 } else { 3 }).collect();
    let mut e: Engine<IntRepr> = Engine::new(c.clone());
    e.push_increments(&toggling);
    assert_eq!(e.constant_increment(), None);
    let phase = phase_from_increments(&toggling.iter().map(|&v| v as f64).collect::<Vec<_>>());
    let want = oavar(&[&phase], 1, 0.01).unwrap().var;
    let got = e.read()[0].avar.unwrap().0;
    assert!(
        want > 0.0 && (got / want - 1.0).abs() < 1e-12,
        "{got} vs {want}"
    );
    let mut k: Engine<IntRepr> = Engine::new(c.clone());
    k.push_increments(&[5; 4000]);
    assert_eq!(k.constant_increment(), Some(5));
    assert!(k
        .read()
        .iter()
        .all(|r| r.avar == Some((0.0, r.avar.unwrap().1))));
    let mut f: Engine<FloatRepr> = Engine::new(c);
    f.push_increments(&[0.0125; 4000]);
    assert_eq!(f.constant_increment(), Some(0.0125));
    assert!(f
        .read()
        .iter()
        .all(|r| r.avar.unwrap().0 == 0.0 && r.mvar.unwrap().0 == 0.0));
    f.push_increments(&[0.0126]);
    assert_eq!(f.constant_increment(), None);
}
