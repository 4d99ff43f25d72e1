//! The diagnosis on units other than the VOG4-like gyro it was first tuned on, and its
//! bookkeeping: the seed paper's pendulous MA4 accelerometer, simulated clean from the shipped
//! config/models/ma4.toml (white phase noise, quantization with carry, dominating up to tau ~ 18
//! s; R present) is `consistent`, and on every run each effect's `gap_after` is the gap after it
//! is added, each lower than the one before, the last the final gap, never above `gap_before`.
//!
//! The MA4 rate over 100 seeds (the target: >= 95 consistent) is a study in docs/gap.md
//! ("Families of units"); here five seeds, all of which must be consistent: with the study's
//! 98/100, five of five happen by chance in about 90% of seed sets, and these five are fixed.

use super::diagnosis::assert_bookkeeping;
use allanscope::gap::{diagnose, DiagnoseOptions, Diagnosis, GapConfig, GapEvidence, Verdict};
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

/// Two hours, the run.
const DURATION_S: f64 = 7200.0;

fn ma4_run(seed: u64) -> Diagnosis {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/models/ma4.toml");
    let text = std::fs::read_to_string(&path).expect("config/models/ma4.toml");
    let m = SimModel::from_toml_str(&text, &path).expect("model");
    let tau0 = m.tau0_s;
    let mut sim = Simulator::new(&m, seed);
    let mut inc = vec![0.0; (DURATION_S / tau0) as usize];
    sim.fill_channel(0, &mut inc);
    let mut ev = GapEvidence::from_increments(GapConfig::new(tau0), &inc);
    diagnose(&ev.snapshot(), &DiagnoseOptions::default()).expect("diagnosis")
}

#[test]
fn ma4_clean_runs_are_consistent() {
    for seed in [901, 902, 903, 904, 905] {
        let d = ma4_run(seed);
        assert_bookkeeping(&d);
        assert_eq!(
            d.verdict,
            Verdict::Consistent,
            "seed {seed}: G {} -> {}, {:?}",
            d.gap_before,
            d.gap_after,
            d.effects
        );
        // The base model's gap is near 1 (its null median is 1.0; docs/gap.md), not the
        // 9.5-25 the full-overlap covariance gave on these runs.
        assert!(d.gap_before < 1.6, "seed {seed}: G {}", d.gap_before);
        // The segments' homogeneity at the evidence's strides: before session 40 their
        // variance took full overlap and some tau of every clean MA4 run had p = 0. 13 taus by
        // 5 seeds at 1e-4: a false failure in about 0.7% of seed sets.
        assert!(
            d.segment_tests.len() >= 10,
            "seed {seed}: {:?}",
            d.segment_tests
        );
        for t in &d.segment_tests {
            assert!(t.p_value > 1e-4, "seed {seed}: {t:?}");
        }
    }
}

/// The segments' test still sees a unit whose white noise doubles halfway through a two-hour
/// run (N 1e-3 then 2e-3 m/s/sqrt(s), 250 Hz): at the shortest tau each segment's AVAR is 1 or
/// 4 times the other half's, with some 1e5 differences in each.
#[test]
fn the_segments_see_a_white_noise_that_doubles_halfway() {
    let half = |n: f64, seed: u64| {
        let text = format!("tau0_s = 0.004\n[[channel]]\nname = \"a\"\nunit = \"m/s\"\nN = {n}\n");
        let m = SimModel::from_toml_str(&text, Path::new("<test>")).expect("model");
        let mut sim = Simulator::new(&m, seed);
        let mut inc = vec![0.0; (3600.0 / m.tau0_s) as usize];
        sim.fill_channel(0, &mut inc);
        inc
    };
    let mut inc = half(1e-3, 5);
    inc.extend(half(2e-3, 6));
    let mut ev = GapEvidence::from_increments(GapConfig::new(0.004), &inc);
    let d = diagnose(&ev.snapshot(), &DiagnoseOptions::default()).expect("diagnosis");
    let first = d.segment_tests.first().expect("segment tests");
    assert!(first.p_value < 1e-9, "{first:?}");
    // The worst segment's ADEV is sqrt(2) or 1/sqrt(2) times the segments' geometric mean
    // (N and 2N in equal shares).
    assert!(
        (first.worst_ratio - 2f64.sqrt()).abs() < 0.1
            || (first.worst_ratio - 1.0 / 2f64.sqrt()).abs() < 0.1,
        "{first:?}"
    );
}

/// One unit of each family of examples/family_gap.rs at the middle of its ranges (docs/gap.md,
/// "Families of units"): `(name, [Q, N, B, K, R], angle LSB (u, with carry; 0: none), rate
/// LSB as a fraction of the rate sample's noise `N / sqrt(tau0)` (0: none))`, at 250 Hz.
const TAU0: f64 = 0.004;
fn family_units() -> Vec<(&'static str, [f64; 5], f64, f64)> {
    let arw = 1.0 / 60.0;
    let deg_h = 1.0 / 3600.0;
    let rrw = 1.0 / (3600.0 * 60.0);
    let fine = |n: f64| 0.5 * n * TAU0.sqrt();
    vec![
        (
            "navfog",
            [0.0, 0.002 * arw, 0.003 * deg_h, 3e-4 * rrw, 0.0],
            fine(0.002 * arw),
            0.0,
        ),
        (
            "tacfog",
            [0.0, 0.03 * arw, 0.15 * deg_h, 0.03 * rrw, 0.0],
            fine(0.03 * arw),
            0.0,
        ),
        ("vog4", [0.0, 0.254, 0.225, 1.826e-2, 0.0], 0.004, 0.0),
        (
            "memsgyro",
            [0.0, 0.3 * arw, 6.0 * deg_h, 3.0 * rrw, 0.0],
            0.0,
            0.5,
        ),
        (
            "ma4",
            [6.84e-4, 2.811e-4, 0.403e-4, 2.228e-6, 6.02e-8],
            2.104e-4,
            0.0,
        ),
        (
            "memsacc",
            [0.0, 0.06 / 60.0, 60.0 * 9.81e-6, 3e-5, 0.0],
            0.0,
            0.5,
        ),
    ]
}

/// A clean one-hour run of a unit (`lsb`: angle quantization with carry; `rate_frac`: each
/// rate sample rounded to that fraction of its noise).
fn unit_run(c: [f64; 5], lsb: f64, rate_frac: f64, seed: u64) -> Diagnosis {
    let mut text = format!(
        "tau0_s = {TAU0}\n[[channel]]\nname = \"x\"\nunit = \"u\"\nQ = {:e}\nN = {:e}\nB = {:e}\nK = {:e}\nR = {:e}\nflicker_band_s = [{TAU0}, 36000.0]\n",
        c[0], c[1], c[2], c[3], c[4]
    );
    if lsb > 0.0 {
        text += &format!("lsb = {lsb:e}\n");
    }
    let m = SimModel::from_toml_str(&text, Path::new("<families>")).expect("model");
    let mut sim = Simulator::new(&m, seed);
    let mut inc = vec![0.0; (3600.0 / TAU0) as usize];
    sim.fill_channel(0, &mut inc);
    if rate_frac > 0.0 {
        let step = rate_frac * c[1] / TAU0.sqrt() * TAU0;
        for v in inc.iter_mut() {
            *v = (*v / step).round() * step;
        }
    }
    let mut ev = GapEvidence::from_increments(GapConfig::new(TAU0), &inc);
    diagnose(&ev.snapshot(), &DiagnoseOptions::default()).expect("diagnosis")
}

/// Clean runs of every family: 12 runs (two seeds per family), at most one not `consistent`.
/// The tolerance: at the 5% false-alarm rate per family, two or more alarms in 12
/// runs happen with probability 12%, and these seeds are fixed; before the strided covariance
/// MA4 alone was flagged in 10 of 10, and the coarse-LSB FOG (below) in about 70%. No run is
/// quantization-limited (their LSBs are fine), and the bookkeeping holds on each.
#[test]
fn clean_runs_of_every_family_raise_at_most_one_alarm() {
    let mut alarms = Vec::new();
    for (name, c, lsb, rate) in family_units() {
        for seed in [71, 72] {
            let d = unit_run(c, lsb, rate, seed);
            assert_bookkeeping(&d);
            assert_eq!(d.quantization_limited, None, "{name} seed {seed}");
            if d.verdict != Verdict::Consistent {
                alarms.push(format!(
                    "{name} seed {seed}: {:?} G {:.2} -> {:.2} {:?}",
                    d.verdict, d.gap_before, d.gap_after, d.effects
                ));
            }
        }
    }
    assert!(alarms.len() <= 1, "{alarms:#?}");
}

/// A tactical FOG whose angle LSB is ten times the per-sample noise `N sqrt(tau0)`: the
/// quantization error wanders instead of being white phase noise (docs/gap.md,
/// "Quantization-limited units"; the five-term model on the whole curve gave G ~200 on such
/// units). The diagnosis says so, with the ratio `N sqrt(tau0) / LSB` = 0.1 within 15% (its N
/// is fitted) and `tau_white = 0.405 / r^2 tau0` (about 0.16 s); until session 24 the curve
/// was read from there on, and since then the counter's sawtooth in the base model describes
/// the taus below it: the curve is read whole, the sawtooth's width `N` within 10% of the
/// unit's, and the model is consistent (docs/gap.md, "The whole curve of a quantization-limited
/// counter (session 24)").
#[test]
fn a_coarse_lsb_unit_is_said_quantization_limited_and_consistent_beyond() {
    let n = 0.03 / 60.0;
    let lsb = 10.0 * n * TAU0.sqrt();
    for seed in [81, 82] {
        let d = unit_run([0.0, n, 0.15 / 3600.0, 0.0, 0.0], lsb, 0.0, seed);
        let q = d.quantization_limited.expect("quantization-limited");
        assert!((q.lsb - lsb).abs() < 1e-6 * lsb, "lsb {} vs {lsb}", q.lsb);
        assert!((q.ratio - 0.1).abs() < 0.015, "ratio {}", q.ratio);
        assert!(
            q.tau_white_s > 0.1 && q.tau_white_s < 0.25,
            "tau_white {}",
            q.tau_white_s
        );
        let st = d.sawtooth.expect("the sawtooth in the base model");
        assert!(
            (d.tau_span_s.0 / TAU0 - 1.0).abs() < 1e-9,
            "{:?}",
            d.tau_span_s
        );
        assert!((st.n_arw / n - 1.0).abs() < 0.1, "{st:?}");
        assert_bookkeeping(&d);
        assert_eq!(d.verdict, Verdict::Consistent, "seed {seed}: {d:?}");
    }
}

/// A pendulous accelerometer counted with carry, its velocity LSB 160 times the sample's white
/// noise (N 3.25e-5 m/s/sqrt(s) at 4 ms against 3.3e-4 m/s: the class of a tenth blind review's
/// pendulous units, whose quantization error stays a slow sawtooth for tens of seconds), one
/// hour, axis up. Where the white tau it estimates leaves too few points before the run ends
/// (seed 3: 186 s), the curve is judged from the nearest cut below it, not whole: `consistent`
/// with nothing named, read from 20 s or later (before, seed 3 was `unexplained`, G 373 -> 31
/// with a line and a band named on the quantization error). Seed 1 (white tau 41 s) is judged
/// from its white tau as before.
#[test]
fn a_pendulous_counter_judged_near_its_white_tau_when_the_run_is_short() {
    let text = "tau0_s = 0.004\n[stand]\nlatitude_deg = 56.8\n[[channel]]\nname = \"a\"\n\
                unit = \"m/s\"\naxis = \"up\"\nlsb = 3.3e-4\nN = 3.25e-5\nB = 7.2e-6\n\
                K = 2.0e-7\nR = 3.3e-9\nflicker_band_s = [0.004, 1.0e4]\n";
    let m = SimModel::from_toml_str(text, Path::new("<pendulous>")).expect("model");
    for seed in [1, 3] {
        let mut sim = Simulator::new(&m, seed);
        let mut inc = vec![0.0; (3600.0 / TAU0) as usize];
        sim.fill_channel(0, &mut inc);
        let mut ev = GapEvidence::from_increments(GapConfig::new(TAU0), &inc);
        let d = diagnose(&ev.snapshot(), &DiagnoseOptions::default()).expect("diagnosis");
        let q = d.quantization_limited.expect("quantization-limited");
        assert!((q.lsb - 3.3e-4).abs() < 1e-9, "lsb {}", q.lsb);
        assert!(d.tau_span_s.0 >= 20.0, "seed {seed}: {:?}", d.tau_span_s);
        assert_bookkeeping(&d);
        assert!(d.effects.is_empty(), "seed {seed}: {:?}", d.effects);
        assert_eq!(
            d.verdict,
            Verdict::Consistent,
            "seed {seed}: G {}",
            d.gap_before
        );
    }
}
