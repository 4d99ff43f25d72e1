//! The claim behind `DEFAULT_L` (its doc comment and BENCHMARKS.md, "Choosing L"), checked with
//! Greenhall's edf: bounded mode at the default L keeps >= 99% of full overlap's degrees of
//! freedom for rate noises (alpha <= 0) on every statistic, and for every noise on MVAR.

use allanscope::allan::accum::DEFAULT_L;
use allanscope::allan::edf::edf;
use allanscope::allan::Stat;

#[test]
fn default_l_keeps_the_degrees_of_freedom_of_rate_noise() {
    let n: u64 = 2_700_001; // a 3-hour 250 Hz run
    for j in 5..=19 {
        let m = 1u64 << j;
        let stride = (m / DEFAULT_L).max(1);
        for stat in Stat::ALL {
            for alpha in [2, 1, 0, -1, -2] {
                if stat != Stat::Mvar && alpha > 0 {
                    continue;
                }
                let b = edf(stat, alpha, m, stride, n).unwrap();
                let f = edf(stat, alpha, m, 1, n).unwrap();
                assert!(b / f >= 0.99, "{stat:?} alpha={alpha} m={m}: {:.4}", b / f);
                // Decimation cannot add degrees of freedom, but at full overlap Greenhall's
                // algorithm falls back on tabulated asymptotic sums while the strided case is
                // summed exactly, so the decimated figure may sit slightly above it (seen: up to
                // 1.011 at m = 2^19, where N/m is 5 blocks).
                assert!(b <= f * 1.02, "{stat:?} alpha={alpha} m={m}: {:.6}", b / f);
            }
        }
    }
}

#[test]
fn white_phase_noise_on_avar_loses_edf_in_proportion_to_the_stride() {
    // Neighbouring second differences of white phase are nearly independent: the decimated
    // estimator keeps about 1/stride of them (within 20%).
    let n: u64 = 2_700_001;
    for j in 8..=14 {
        let m = 1u64 << j;
        let stride = m / DEFAULT_L;
        let ratio =
            edf(Stat::Avar, 2, m, stride, n).unwrap() / edf(Stat::Avar, 2, m, 1, n).unwrap();
        let expected = 1.0 / stride as f64;
        assert!(
            (ratio / expected - 1.0).abs() < 0.2,
            "m={m}: {ratio:.4e} vs {expected:.4e}"
        );
    }
}
