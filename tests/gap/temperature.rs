//! The temperature effect (issue 13): a VOG4-like gyro in a chamber whose temperature settles
//! from 20 to 40 degC while it cycles 5 degC every 600 s, with a known coefficient of
//! 0.2 arcsec/s per degC. The diagnosis, given the temperature, names `temperature` with the
//! coefficient within 10% and an interval that covers it; without a temperature-driven bias the
//! same runs name none. The study over 50 seeds (examples/temperature_study.rs, docs/gap.md)
//! measures the coverage; these are three seeds of it.

use allanscope::gap::diagnose::diagnose_with_temperature;
use allanscope::gap::temperature::fit_temperature;
use allanscope::gap::temperature_check::TemperatureOutcome;
use allanscope::gap::{
    holdout_gap_with_temperature, DiagnoseOptions, Diagnosis, EffectKind, EffectParams,
    EvidenceSnapshot, GapConfig, GapEvidence,
};
use allanscope::sim::{SimModel, Simulator};
use rand::SeedableRng;
use rand_distr::Distribution;
use std::path::Path;

const TAU0: f64 = 0.004;
const TRUTH: f64 = 0.2;

/// The chamber: settling from 20 to 40 degC with time constant `tc_s` while it cycles
/// `amp_c` degC every `period_s` s.
struct Chamber {
    tc_s: f64,
    amp_c: f64,
    period_s: f64,
}

/// The chamber of the study (examples/temperature_study.rs's defaults but a 600-s cycle).
const STUDY: Chamber = Chamber {
    tc_s: 1800.0,
    amp_c: 5.0,
    period_s: 600.0,
};

fn model(coef: f64, ch: &Chamber) -> SimModel {
    let Chamber {
        tc_s,
        amp_c,
        period_s,
    } = ch;
    let text = format!(
        "tau0_s = {TAU0}\n[temperature]\nstart_c = 20.0\nfinal_c = 40.0\ntime_constant_s = {tc_s}\n\
         sine_amplitude_c = {amp_c}\nsine_period_s = {period_s}\n[[channel]]\nname = \"g\"\n\
         unit = \"arcsec\"\nlsb = 0.004\nbias = 15.0\nN = 0.254\nB = 0.225\nK = 1.826e-2\n\
         flicker_band_s = [0.004, 1.0e4]\ntemperature_coefficient = {coef}\n"
    );
    SimModel::from_toml_str(&text, Path::new("<test>")).expect("model")
}

/// Two hours, the temperature printed with three decimals as the CSV writer does.
fn run(coef: f64, seed: u64) -> Diagnosis {
    run_in(coef, &STUDY, 7200.0, seed).0
}

/// `seconds` of the unit in `chamber`: the diagnosis, and the temperature's `z` on the base
/// model's noise alone (the first pass of `enter_temperature`).
fn run_in(coef: f64, chamber: &Chamber, seconds: f64, seed: u64) -> (Diagnosis, f64) {
    let (a, b) = evidence_of(&model(coef, chamber), seconds, seed);
    let d =
        diagnose_with_temperature(&a, Some(&b), &DiagnoseOptions::default()).expect("diagnosis");
    let first = fit_temperature(
        &a.block_means,
        &b.block_means,
        a.block_len as f64 * TAU0,
        &d.base_coef.map(|c| c * c),
        &[],
        &[],
    )
    .expect("first pass")
    .z;
    (d, first)
}

/// `seconds` of `m` simulated at `seed` through the library: the first channel's evidence and
/// the temperature's (fed `T tau0` per step, printed with three decimals as the CSV writer does).
fn evidence_of(m: &SimModel, seconds: f64, seed: u64) -> (EvidenceSnapshot, EvidenceSnapshot) {
    evidence_through(m, seconds, seed, |increment, t| {
        (increment, (t * 1000.0).round() / 1000.0)
    })
}

/// [`evidence_of`] with each step's first increment and the unit's temperature (degC) turned
/// into the increment and the temperature recorded by `record`.
fn evidence_through(
    m: &SimModel,
    seconds: f64,
    seed: u64,
    mut record: impl FnMut(f64, f64) -> (f64, f64),
) -> (EvidenceSnapshot, EvidenceSnapshot) {
    let tau0 = m.tau0_s;
    let cfg = GapConfig::new(tau0);
    let (mut ch, mut te) = (GapEvidence::new(cfg.clone()), GapEvidence::new(cfg));
    let mut sim = Simulator::new(m, seed);
    for _ in 0..(seconds / tau0) as u64 {
        let s = sim.next_step();
        let (increment, t) = record(s.increments[0], s.temperature_c.expect("profile"));
        ch.push_increment(increment);
        te.push_increment(t * tau0);
    }
    (ch.snapshot(), te.snapshot())
}

fn temperature_of(d: &Diagnosis) -> Option<(f64, f64, f64)> {
    temperature_in(d.effects.iter().map(|e| &e.params))
}

/// The temperature among `effects`: its coefficient and interval.
fn temperature_in<'a>(
    mut effects: impl Iterator<Item = &'a EffectParams>,
) -> Option<(f64, f64, f64)> {
    effects.find_map(|p| match *p {
        EffectParams::Temperature {
            coefficient,
            lo,
            hi,
            ..
        } => Some((coefficient, lo, hi)),
        _ => None,
    })
}

#[test]
fn a_temperature_coefficient_is_named_within_ten_percent_and_covered() {
    for seed in [1, 2, 3] {
        let d = run(TRUTH, seed);
        let (c, lo, hi) = temperature_of(&d).unwrap_or_else(|| panic!("seed {seed}: {d:?}"));
        assert!(
            (c / TRUTH - 1.0).abs() < 0.10,
            "seed {seed}: coefficient {c}"
        );
        assert!(lo <= TRUTH && TRUTH <= hi, "seed {seed}: [{lo}, {hi}]");
        // The interval is a real one: about +-10% here (the study's median half-width 9%).
        assert!(hi - lo < 0.3 * TRUTH, "seed {seed}: [{lo}, {hi}]");
        // It comes first, and its gap_after is the gap with it in (below the base model's).
        assert_eq!(d.effects[0].params.kind(), EffectKind::Temperature);
        assert!(d.effects[0].gap_after < d.gap_before, "{d:?}");
        // A straight dependence is given no second order (its `z` is about N(0, 1) here).
        assert_eq!(quadratic_of(&d), None, "seed {seed}");
    }
}

/// A noisy temperature column does not lower `N` (docs/gap.md, "A temperature that bends
/// (session 51)"): a quiet unit (N 0.01 arcsec/sqrt(s) at 10 Hz, 0.5 arcsec/s per degC) in the
/// study's chamber for 4 hours, its column carrying 0.05 degC of white noise rounded at 0.01
/// degC, as a die sensor does. The column's noise times `c^2` is 62% of `N^2`: taken out of the
/// curve with the temperature's AVAR, it read `N` at 0.61 of its truth, with bias jumps named
/// beside (through the CLI, the same run). `N` is within 5% of the
/// truth with the noisy column, and the coefficient within 10%.
#[test]
fn a_noisy_temperature_column_leaves_the_white_rate_alone() {
    let text = "tau0_s = 0.1\n[temperature]\nstart_c = 20.0\nfinal_c = 40.0\ntime_constant_s = 1800.0\n\
         sine_amplitude_c = 5.0\nsine_period_s = 600.0\n[[channel]]\nname = \"g\"\nunit = \"arcsec\"\n\
         N = 0.01\ntemperature_coefficient = 0.5\n";
    let m = SimModel::from_toml_str(text, Path::new("<test>")).expect("model");
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(9);
    let (a, b) = evidence_through(&m, 4.0 * 3600.0, 5, |increment, t| {
        let e: f64 = rand_distr::StandardNormal.sample(&mut rng);
        (increment, ((t + 0.05 * e) * 100.0).round() / 100.0)
    });
    let d =
        diagnose_with_temperature(&a, Some(&b), &DiagnoseOptions::default()).expect("diagnosis");
    let (c, _, _) = temperature_of(&d).unwrap_or_else(|| panic!("{d:?}"));
    assert!((c / 0.5 - 1.0).abs() < 0.1, "coefficient {c}");
    let n = d.final_coef[1];
    assert!((n / 0.01 - 1.0).abs() < 0.05, "N {n}");
}

/// A unit whose temperature lags the recorded one (docs/gap.md, "A temperature that lags
/// (session 51)"): the study's gyro, 0.5 arcsec/s per degC of a die temperature that follows
/// the recorded chamber air through a first order of 600 s, the air cycling 15 degC every
/// hour, 4 hours. Read on the air, the coefficient comes out about 0.69 of its truth (the
/// lag's gain at the cycle) with an interval that excludes it. The diagnosis names the
/// temperature with its lag: the lag's interval covers 600 s, the coefficient is within 10% and
/// covered.
#[test]
fn a_unit_lagging_the_recorded_temperature_is_named_with_its_lag() {
    let text = format!(
        "tau0_s = {TAU0}\n[temperature]\nstart_c = 20.0\nfinal_c = 20.0\ntime_constant_s = 100.0\n\
         sine_amplitude_c = 15.0\nsine_period_s = 3600.0\n[[channel]]\nname = \"g\"\n\
         unit = \"arcsec\"\nlsb = 0.004\nbias = 15.0\nN = 0.254\nB = 0.225\nK = 1.826e-2\n\
         flicker_band_s = [0.004, 1.0e4]\n"
    );
    let m = SimModel::from_toml_str(&text, Path::new("<test>")).expect("model");
    let (coef, lag_s) = (0.5, 600.0);
    let a = -(-TAU0 / lag_s).exp_m1();
    for seed in [1, 2] {
        let mut die = f64::NAN;
        let (ch, te) = evidence_through(&m, 4.0 * 3600.0, seed, |increment, air| {
            die = if die.is_nan() {
                air
            } else {
                die + a * (air - die)
            };
            (
                increment + coef * die * TAU0,
                (air * 1000.0).round() / 1000.0,
            )
        });
        let d = diagnose_with_temperature(&ch, Some(&te), &DiagnoseOptions::default())
            .expect("diagnosis");
        let lag = d
            .effects
            .iter()
            .find_map(|e| match e.params {
                EffectParams::Temperature { lag, .. } => lag,
                _ => None,
            })
            .unwrap_or_else(|| panic!("seed {seed}: {:?}", d.effects));
        assert!(lag.lo <= lag_s && lag_s <= lag.hi, "seed {seed}: {lag:?}");
        let (c, lo, hi) = temperature_of(&d).expect("temperature");
        assert!(
            (c / coef - 1.0).abs() < 0.1 && lo <= coef && coef <= hi,
            "seed {seed}: {c} [{lo}, {hi}], {lag:?}"
        );
    }
}

/// The second order of the temperature effect among `d`'s effects.
fn quadratic_of(d: &Diagnosis) -> Option<allanscope::gap::effects::TemperatureQuadratic> {
    d.effects.iter().find_map(|e| match e.params {
        EffectParams::Temperature { quadratic, .. } => quadratic,
        _ => None,
    })
}

/// A bias that bends with the temperature (docs/gap.md, "A temperature that bends (session
/// 51)"): the study's gyro with `q (T - 30)^2`, q = 0.01 arcsec/s per degC^2, and no slope at
/// 30 degC, in a chamber settling from 20 to 40 degC while it cycles 15 degC every 1800 s (two
/// hours). A blind review's MEMS gyro bent so over -40..85 degC and was given a sinusoid, a
/// warm-up and 16 bias jumps. The diagnosis names the temperature with its second order: `q`
/// within 10% and covered by its interval, and the slope at the reported reference,
/// `2 q (T_ref - 30)`, within three standard errors of its own (seed 3's is 2.0 off, its 95%
/// interval missing the truth by 0.2%); nothing else is named. (Seed 1, whose noise lifts
/// the curve 6-8% above the signal's AVAR from 30 to 260 s, is also given a sinusoid at the
/// cycle's second harmonic: left, in docs/gap.md.)
#[test]
fn a_bias_that_bends_with_the_temperature_is_named_with_its_second_order() {
    let q_true = 0.01;
    let text = format!(
        "tau0_s = {TAU0}\n[temperature]\nstart_c = 20.0\nfinal_c = 40.0\ntime_constant_s = 1800.0\n\
         sine_amplitude_c = 15.0\nsine_period_s = 1800.0\nreference_c = 30.0\n[[channel]]\n\
         name = \"g\"\nunit = \"arcsec\"\nlsb = 0.004\nbias = 15.0\nN = 0.254\nB = 0.225\n\
         K = 1.826e-2\nflicker_band_s = [0.004, 1.0e4]\ntemperature_quadratic = {q_true}\n"
    );
    let m = SimModel::from_toml_str(&text, Path::new("<test>")).expect("model");
    for seed in [2, 3, 4] {
        let (a, b) = evidence_of(&m, 7200.0, seed);
        let d = diagnose_with_temperature(&a, Some(&b), &DiagnoseOptions::default())
            .expect("diagnosis");
        let q = quadratic_of(&d).unwrap_or_else(|| panic!("seed {seed}: {d:?}"));
        assert!(
            (q.coefficient / q_true - 1.0).abs() < 0.10,
            "seed {seed}: {q:?}"
        );
        assert!(q.lo <= q_true && q_true <= q.hi, "seed {seed}: {q:?}");
        let slope_true = 2.0 * q_true * (q.reference_c - 30.0);
        let (c, lo, hi) = temperature_of(&d).expect("temperature");
        let se = (hi - lo) / (2.0 * 1.959_964);
        assert!(
            (c - slope_true).abs() < 3.0 * se,
            "seed {seed}: {c} [{lo}, {hi}] against {slope_true}"
        );
        assert_eq!(d.effects.len(), 1, "seed {seed}: {:?}", d.effects);
        assert!(d.gap_after < 1.5, "seed {seed}: {d:?}");
    }
}

/// A chamber cycling 7 degC every 1500 s (no settling) over 1.4 h, 0.1 arcsec/s per degC: the
/// temperature-driven wander raises the curve from minutes on, and the base fit takes it as
/// rate random walk, whose noise widens the coefficient's first interval (`|z|` 3.59 on seed 8,
/// 3.93 on seed 7, under the threshold 4). Refitted with the temperature's AVAR in the model
/// until it settles, `z` is 6.0 and 4.8: named, the interval covering the truth (found by a
/// blind check whose generator's chamber cycled so: docs/gap.md, "Temperature").
#[test]
fn a_temperature_cycle_the_base_fit_takes_as_random_walk_is_named_once_refitted() {
    let chamber = Chamber {
        tc_s: 1.0,
        amp_c: 7.0,
        period_s: 1500.0,
    };
    for seed in [7, 8] {
        let (d, first) = run_in(0.1, &chamber, 1.4 * 3600.0, seed);
        assert!(first.abs() < 4.0, "seed {seed}: first-pass z {first}");
        let (c, lo, hi) = temperature_of(&d).unwrap_or_else(|| panic!("seed {seed}: {d:?}"));
        assert!(lo <= 0.1 && 0.1 <= hi, "seed {seed}: {c} [{lo}, {hi}]");
        assert!(hi - lo < 0.8 * 0.1, "seed {seed}: [{lo}, {hi}]");
    }
}

/// Without a coefficient none is named, and the record's check says so with an interval that
/// rules out a coefficient of half the study's (the chamber's cycles let the block means bound
/// it), covering 0 at least when `|z|` is under 1.96.
#[test]
fn without_a_temperature_driven_bias_none_is_named() {
    for seed in [1, 2, 3] {
        let d = run(0.0, seed);
        assert!(temperature_of(&d).is_none(), "seed {seed}: {:?}", d.effects);
        let t = d.temperature_check.expect("a check");
        assert_eq!(
            t.outcome,
            TemperatureOutcome::NotShown,
            "seed {seed}: {t:?}"
        );
        let [lo, hi] = t.interval.expect("an interval");
        assert!(lo > -TRUTH / 2.0 && hi < TRUTH / 2.0, "seed {seed}: {t:?}");
        // The interval is the coefficient's alone joined with its interval beside the block
        // means' best warm-up: it covers 0 at least when the first does.
        assert!(
            t.z.unwrap().abs() > 1.96 || (lo <= 0.0 && 0.0 <= hi),
            "{t:?}"
        );
    }
}

/// A chamber that settles with a time constant ten times the run (20 to 40 degC over 72 000 s;
/// 1.9 degC in the two hours, bent from a straight line by 0.4% of that): the bias it drives is a
/// rate ramp, which the test's drift takes as well. The check says `straight`, its interval
/// covers the truth (0.2 arcsec/s per degC) and is too wide to name it (the curve gives the ramp
/// to `R` or `K`).
/// A chamber held at 25 degC: `constant`, no coefficient. A named temperature's check is the
/// effect's own interval.
#[test]
fn the_temperature_check_says_why_no_temperature_is_named() {
    let ramp = Chamber {
        tc_s: 72_000.0,
        amp_c: 0.0,
        period_s: 600.0,
    };
    for seed in [1, 2] {
        let (d, _) = run_in(TRUTH, &ramp, 7200.0, seed);
        assert!(temperature_of(&d).is_none(), "seed {seed}: {:?}", d.effects);
        let t = d.temperature_check.expect("a check");
        assert_eq!(
            t.outcome,
            TemperatureOutcome::Straight,
            "seed {seed}: {t:?}"
        );
        assert!((t.change_c - 1.90).abs() < 0.05, "seed {seed}: {t:?}");
        assert!(t.bend.unwrap() < 0.01, "seed {seed}: {t:?}");
        let [lo, hi] = t.interval.unwrap();
        assert!(lo <= TRUTH && TRUTH <= hi, "seed {seed}: {t:?}");
    }
    let text = |coef: f64| {
        format!(
            "tau0_s = {TAU0}\n[temperature]\nstart_c = 25.0\nfinal_c = 25.0\n\
             time_constant_s = 100.0\nsine_amplitude_c = 0.0\nsine_period_s = 600.0\n\
             [[channel]]\nname = \"g\"\nunit = \"arcsec\"\nlsb = 0.004\nbias = 15.0\n\
             N = 0.254\nB = 0.225\nK = 1.826e-2\nflicker_band_s = [0.004, 1.0e4]\n\
             temperature_coefficient = {coef}\n"
        )
    };
    let m = SimModel::from_toml_str(&text(TRUTH), Path::new("<test>")).expect("model");
    let (a, b) = evidence_of(&m, 1800.0, 4);
    let d = diagnose_with_temperature(&a, Some(&b), &DiagnoseOptions::default()).expect("d");
    let t = d.temperature_check.expect("a check");
    assert_eq!(
        (t.outcome, t.change_c, t.coefficient),
        (TemperatureOutcome::Constant, 0.0, None),
        "{t:?}"
    );
    let d = run(TRUTH, 1);
    let t = d.temperature_check.expect("a check");
    let (c, lo, hi) = temperature_of(&d).expect("named");
    assert_eq!(t.outcome, TemperatureOutcome::Named);
    assert_eq!((t.coefficient, t.interval), (Some(c), Some([lo, hi])));
}

/// A unit with a warm-up of its own (5e-4 rad/s over 300 s) and no temperature coefficient, in
/// a chamber that settles (22 -> 30 degC over 1500 s): the settling gives the temperature a
/// warm-up's shape, and the coefficient fitted alone takes the unit's warm-up (about -2.5e-4
/// rad/s per degC, `|z|` up to 6; a review's 20 runs had the check's interval exclude 0 in 17).
/// The check's interval joins the coefficient's interval beside the block means' best warm-up:
/// it covers 0 (19 of those 20 runs through the CLI). And the warm-up is named, as without the
/// column: the temperature entered first at `|z|` 4-6 took the warm-up out of the block means
/// and then was not kept, leaving nothing named in 17 of the 20 (session 39: the pass again
/// without it, named in 17 of 20 as without the column; amplitudes 4.1-6.4e-4 rad/s, time
/// constants 260-420 s on seeds 1-4).
#[test]
fn a_unit_s_own_warm_up_in_a_settling_chamber_is_no_temperature_coefficient() {
    let text = "tau0_s = 0.04\n[temperature]\nstart_c = 22.0\nfinal_c = 30.0\n\
                time_constant_s = 1500.0\nsine_amplitude_c = 0.0\nsine_period_s = 1043.0\n\
                [[channel]]\nname = \"g\"\nunit = \"rad\"\nN = 1.22e-4\nB = 2.9e-5\n\
                K = 1.0e-6\nflicker_band_s = [0.04, 1.0e5]\ntemperature_coefficient = 0.0\n\
                [channel.warmup]\namplitude = 5e-4\ntime_constant = 300.0\n";
    let m = SimModel::from_toml_str(text, Path::new("<test>")).expect("model");
    for seed in [1, 2] {
        let (a, b) = evidence_of(&m, 2026.0, seed);
        let d = diagnose_with_temperature(&a, Some(&b), &DiagnoseOptions::default()).expect("d");
        assert!(temperature_of(&d).is_none(), "seed {seed}: {:?}", d.effects);
        let warm = d.effects.iter().find_map(|e| match e.params {
            EffectParams::Warmup {
                amplitude,
                time_constant_s,
            } => Some((amplitude, time_constant_s)),
            _ => None,
        });
        let (amp, tc) = warm.unwrap_or_else(|| panic!("seed {seed}: {:?}", d.effects));
        assert!((2.5e-4..1e-3).contains(&amp), "seed {seed}: {amp}");
        assert!((150.0..600.0).contains(&tc), "seed {seed}: {tc}");
        let t = d.temperature_check.expect("a check");
        let [lo, hi] = t.interval.expect("an interval");
        assert!(lo <= 0.0 && 0.0 <= hi, "seed {seed}: {t:?}");
    }
}

/// Issue 13: a day of a unit whose bias follows its temperature (a daily cycle of 6 degC over
/// a settling from 15 to 25 degC, 0.005 u/s per degC), diagnosed WITHOUT the temperature (the
/// input has no temperature column), on three seeds. The diagnosis cannot name the cause, but
/// it must not make the model worse: the final gap is at most the base model's, each effect
/// kept lowers it (or, found in time, leaves it as it was), and the verdict says the five
/// terms alone do not describe the day (not `consistent`). 10 Hz keeps the day at 864 000
/// samples.
#[test]
fn a_day_of_temperature_driven_bias_without_the_temperature_never_ends_above_the_base_gap() {
    let tau0 = 0.1;
    let text = "tau0_s = 0.1\n[temperature]\nstart_c = 15.0\nfinal_c = 25.0\n\
                time_constant_s = 10800.0\nsine_amplitude_c = 6.0\nsine_period_s = 86400.0\n\
                [[channel]]\nname = \"g\"\nunit = \"deg\"\nbias = 1.0\nN = 0.01\nB = 0.002\n\
                K = 2.0e-5\nflicker_band_s = [0.1, 1.0e6]\ntemperature_coefficient = 0.005\n";
    let m = SimModel::from_toml_str(text, Path::new("<test>")).expect("model");
    for seed in [1, 2, 3] {
        let mut ev = GapEvidence::new(GapConfig::new(tau0));
        let mut sim = Simulator::new(&m, seed);
        for _ in 0..(86_400.0 / tau0) as u64 {
            ev.push_increment(sim.next_step().increments[0]);
        }
        let d = allanscope::gap::diagnose(&ev.snapshot(), &DiagnoseOptions::default())
            .expect("diagnosis");
        super::diagnosis::assert_bookkeeping(&d);
        assert!(
            d.gap_after <= d.gap_before,
            "seed {seed}: {} -> {}",
            d.gap_before,
            d.gap_after
        );
        assert_ne!(
            d.verdict,
            allanscope::gap::Verdict::Consistent,
            "seed {seed}: a day of temperature-driven bias passed as the five terms alone: {d:?}"
        );
        assert!(
            temperature_of(&d).is_none(),
            "seed {seed}: no temperature was given"
        );
    }
}

/// A 200 Hz MEMS-like gyro (unit arcsec: N 18 arcsec/sqrt(s), B 10 arcsec/s, K 0.05, rate
/// samples rounded to 3.6 arcsec/s) whose chamber settles from 20 to 45 degC over 1800 s,
/// `coef` arcsec/s per degC, two hours, simulated through the library: the channel's and the
/// temperature's evidence.
fn mems_evidence(coef: f64, seed: u64) -> (EvidenceSnapshot, EvidenceSnapshot) {
    mems_evidence_from(20.0, coef, seed)
}

/// [`mems_evidence`] with the chamber starting at `start_c` degC (45: held constant).
fn mems_evidence_from(start_c: f64, coef: f64, seed: u64) -> (EvidenceSnapshot, EvidenceSnapshot) {
    let text = format!(
        "tau0_s = 0.005\n[temperature]\nstart_c = {start_c}\nfinal_c = 45.0\n\
         time_constant_s = 1800.0\nsine_amplitude_c = 0.0\nsine_period_s = 1800.0\n\
         [[channel]]\nname = \"gz\"\nunit = \"arcsec\"\nbias = 15.0\nrate_lsb = 3.6\n\
         N = 18.0\nB = 10.0\nK = 0.05\nflicker_band_s = [0.005, 1.0e4]\n\
         temperature_coefficient = {coef}\n"
    );
    let m = SimModel::from_toml_str(&text, Path::new("<test>")).expect("model");
    evidence_of(&m, 7200.0, seed)
}

/// [`mems_evidence`] at `coef` arcsec/s per degC diagnosed: the diagnosis and the temperature's
/// coefficient, interval and settled `|z|` (coefficient over the standard error of its interval).
fn mems_run(coef: f64, seed: u64) -> (Diagnosis, Option<(f64, f64, f64, f64)>) {
    let (a, b) = mems_evidence(coef, seed);
    let d =
        diagnose_with_temperature(&a, Some(&b), &DiagnoseOptions::default()).expect("diagnosis");
    let t = temperature_of(&d).map(|(c, lo, hi)| {
        let se = (hi - lo) / (2.0 * allanscope::gap::temperature::Z95);
        (c, lo, hi, c / se)
    });
    (d, t)
}

/// The held-out run judges a temperature too (session 36; before, its offset was never added
/// there and every held-out record said it did not carry). The MEMS gyro at 10 arcsec/s per
/// degC, its temperature named on seed 10 (`|z|` 9.7), held fixed on seed 17 of the same unit:
/// the held-out curve's gap does not fall with it in, but `c T` taken out of the held-out block
/// means lowers their whitened residuals by more than `TEMPERATURE_Z_ALONE^2` (64, the evidence
/// the fitting run asks of a temperature kept in time), so it carries, its `gap_after` the
/// held-out gap before it. On seed 4 of the same unit with no temperature coefficient it does
/// not carry (the residuals rise).
#[test]
fn a_temperature_kept_in_time_is_judged_in_time_on_the_held_out_run() {
    let opts = DiagnoseOptions::default();
    let (d, t) = mems_run(10.0, 10);
    assert!(t.is_some(), "{:?}", d.effects);
    for (coef, seed, carries) in [(10.0, 17, true), (0.0, 4, false)] {
        let (a, b) = mems_evidence(coef, seed);
        let h = holdout_gap_with_temperature(&d, &a, Some(&b), &opts).expect("held out");
        let e = h
            .effect(EffectKind::Temperature)
            .unwrap_or_else(|| panic!("seed {seed}: {h:?}"));
        assert_eq!(e.carried, carries, "seed {seed}: {h:?}");
        assert!(h.gap_after <= h.gap_before, "seed {seed}: {h:?}");
        if carries {
            assert_eq!(
                e.gap_after, h.gap_before,
                "seed {seed}: kept in time: {h:?}"
            );
        }
        // Without the held-out temperature it cannot be judged, and is left out.
        let none = allanscope::gap::holdout_gap(&d, &a, &opts).expect("held out");
        assert!(none
            .effects
            .iter()
            .all(|e| e.kind != EffectKind::Temperature));
        assert_eq!(none.not_judged, vec![EffectKind::Temperature], "{none:?}");
        assert!(h.not_judged.is_empty(), "seed {seed}: {h:?}");
    }
    // Nor with a temperature held constant on the held-out run (session 37: before, it read
    // `carried: false`, as if the run had disowned a coefficient it could not show): the same
    // unit at 10 arcsec/s per degC in a chamber held at 45 degC.
    let (a, b) = mems_evidence_from(45.0, 10.0, 17);
    let h = holdout_gap_with_temperature(&d, &a, Some(&b), &opts).expect("held out");
    assert!(
        h.effects.iter().all(|e| e.kind != EffectKind::Temperature),
        "{h:?}"
    );
    assert_eq!(h.not_judged, vec![EffectKind::Temperature], "{h:?}");
    // A chamber settling from 27 degC (18 degC, not 25, in the two hours): with the coefficient
    // the held-out block means drop by 24-56 when `c T` is taken out (expected 20-53), short of
    // the fitting run's 64 and far above the drops of a run without it (-10 to -27); before
    // session 39 both read `carried: false`. Now the run that has it leaves it unjudged (it
    // could not have shown it reliably, `delta^2` below 96) and the run without it disowns it.
    for seed in [17, 18] {
        for (coef, judged) in [(10.0, false), (0.0, true)] {
            let (a, b) = mems_evidence_from(27.0, coef, seed);
            let h = holdout_gap_with_temperature(&d, &a, Some(&b), &opts).expect("held out");
            let t = h.effect(EffectKind::Temperature);
            assert_eq!(t.is_some(), judged, "seed {seed}, {coef}: {h:?}");
            assert_eq!(
                h.not_judged.contains(&EffectKind::Temperature),
                !judged,
                "seed {seed}, {coef}: {h:?}"
            );
            assert!(t.is_none_or(|e| !e.carried), "seed {seed}, {coef}: {h:?}");
        }
    }
}

/// The random walk the curve's fit sets to 0 once the temperature's AVAR is in (session 36): a
/// pendulous accelerometer of MA4's white phase noise, white noise and random walk (no flicker),
/// 3e-5 m/s^2 per degC in a chamber settling from 20 to 40 degC over 1800 s and cycling 1 degC
/// every 1200 s, two hours. The temperature took the long-tau rise, the curve's `K` went to 0,
/// the random walk left the coefficient's covariance and its interval was far too narrow: seed
/// 101 was named at 1.7 times the truth, 12.7 standard errors off; seed 116 2.6 off (over seeds
/// 101-120 the 12 named intervals' errors had sd 3.8 standard errors, 9 covering). With the
/// block means' own random walk kept in the covariance ([`TemperatureInModel::refit`]) seed 101
/// is not named, seed 116 is named and covered (over 101-120: 11 named, all covering, sd 0.9).
#[test]
fn a_random_walk_the_curve_gives_to_the_temperature_stays_in_its_interval() {
    let truth = 3.0e-5;
    let text = "tau0_s = 0.004\n[temperature]\nstart_c = 20.0\nfinal_c = 40.0\n\
                time_constant_s = 1800.0\nsine_amplitude_c = 1.0\nsine_period_s = 1200.0\n\
                [[channel]]\nname = \"a\"\nunit = \"m/s\"\nbias = 9.8\nlsb = 2.104e-4\n\
                Q = 6.840e-4\nN = 2.811e-4\nK = 2.228e-6\ntemperature_coefficient = 3.0e-5\n";
    let m = SimModel::from_toml_str(text, Path::new("<test>")).expect("model");
    for (seed, named) in [(101, false), (116, true)] {
        let (a, b) = evidence_of(&m, 7200.0, seed);
        let d = diagnose_with_temperature(&a, Some(&b), &DiagnoseOptions::default())
            .expect("diagnosis");
        let found = temperature_of(&d);
        assert_eq!(found.is_some(), named, "seed {seed}: {:?}", d.effects);
        if let Some((c, lo, hi)) = found {
            assert!(lo <= truth && truth <= hi, "seed {seed}: {c} [{lo}, {hi}]");
        }
    }
}

/// A temperature the time domain suggests but the diagnosis did not keep is listed as an
/// alternative, not dropped without a word (session 37; docs/gap.md, "Alternatives"). The
/// MEMS gyro at 6 arcsec/s per degC, seed 17: the block means give the temperature `|z|` 6.4,
/// below the bar for keeping it on that evidence alone (8) and the curve does not show it, so
/// nothing is named; the alternative with the temperature added is listed, its interval
/// covering the truth, its gap below the critical one. The same unit with no coefficient, seed
/// 10: a short warm-up is named (its own signal, 150 s) and no temperature is listed beside it.
#[test]
fn a_temperature_below_the_bar_is_listed_as_an_alternative() {
    let (d, t) = mems_run(6.0, 17);
    assert!(t.is_none(), "{:?}", d.effects);
    let listed: Vec<(f64, f64, f64)> = d
        .alternatives
        .iter()
        .filter_map(|a| temperature_in(a.effects.iter()))
        .collect();
    assert_eq!(listed.len(), 1, "{:?}", d.alternatives);
    let (c, lo, hi) = listed[0];
    assert!(lo < 6.0 && 6.0 < hi, "{c} [{lo}, {hi}]");
    assert!(d.alternatives.iter().all(|a| a.gap <= 1.9));

    let (d, t) = mems_run(0.0, 10);
    assert!(t.is_none());
    assert!(d.names(EffectKind::Warmup), "{:?}", d.effects);
    assert!(
        d.alternatives.iter().all(|a| a
            .effects
            .iter()
            .all(|p| p.kind() != EffectKind::Temperature)),
        "{:?}",
        d.alternatives
    );
}

/// A MEMS accelerometer behind a sinc^3 CIC of 4 read every 4th (200 Hz), its rate samples
/// rounded to 0.000598 m/s^2 (a 16-bit part at 2 g), in a chamber settling from 25 to 28 degC
/// while it cycles 1 degC every 1800 s, with a coefficient of 0.0072 m/s^2 per degC, 2 h
/// (a blind review's consumer accelerometer, session 45). The coefficient is named within 10%
/// and its interval covers it, beside the unit's average. Before, the temperature's first fit
/// took the block means' noise from five terms fitted without the unit's filter (B twelve
/// times too large on the review's file), put the temperature at `z` 1.6, and a sinusoid at
/// the chamber's cycle was named in its place on all three seeds (docs/gap.md, "The
/// temperature behind a filter (session 45)").
#[test]
fn a_temperature_behind_a_units_filter_is_named() {
    let truth = 0.0072;
    let text = format!(
        "tau0_s = 0.005\n[temperature]\nstart_c = 25.0\nfinal_c = 28.0\ntime_constant_s = 3000.0\n\
         sine_amplitude_c = 1.0\nsine_period_s = 1800.0\n[[channel]]\nname = \"ax\"\n\
         unit = \"m/s\"\nN = 0.00265\nB = 0.00136\nrate_lsb = 0.000598\n\
         temperature_coefficient = {truth}\n\
         moving_average = {{ taps = 4, stages = 3, decimation = 4 }}\n"
    );
    let m = SimModel::from_toml_str(&text, Path::new("<test>")).expect("model");
    for seed in [1, 2, 3] {
        let (a, b) = evidence_of(&m, 7200.0, seed);
        let d = diagnose_with_temperature(&a, Some(&b), &DiagnoseOptions::default())
            .expect("diagnosis");
        let (c, lo, hi) = temperature_of(&d).unwrap_or_else(|| panic!("seed {seed}: {d:?}"));
        assert!(
            (c / truth - 1.0).abs() < 0.10,
            "seed {seed}: coefficient {c}"
        );
        assert!(lo <= truth && truth <= hi, "seed {seed}: [{lo}, {hi}]");
        assert!(
            d.effects
                .iter()
                .all(|e| !matches!(e.params.kind(), EffectKind::Sinusoid)),
            "seed {seed}: {:?}",
            d.effects
        );
    }
}
