//! Rate-sample quantization (docs/gap.md, "Rate-sample quantization"): a MEMS gyro that rounds
//! each rate sample has a white-rate contribution `N_q = rate_lsb sqrt(tau0 / 12)` the
//! diagnosis names as such (kind `rate`, the step read off the values), with the unit's own N
//! left once it is taken out, and no false effect; a counter with carry (the seed's MA4) is
//! told apart (kind `angle`).

use allanscope::gap::quantization::QuantKind;
use allanscope::gap::unit_model::{fitted_channel, ChannelFacts};
use allanscope::gap::{diagnose, DiagnoseOptions, Diagnosis, GapConfig, GapEvidence, Verdict};
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

fn run(text: &str, seconds: f64, seed: u64) -> Diagnosis {
    let m = SimModel::from_toml_str(text, Path::new("<test>")).expect("model");
    let mut sim = Simulator::new(&m, seed);
    let mut inc = vec![0.0; (seconds / m.tau0_s) as usize];
    sim.fill_channel(0, &mut inc);
    // the values as the CSV writer prints them and a reader reads them back
    for v in inc.iter_mut() {
        *v = format!("{v}").parse().expect("number");
    }
    let mut ev = GapEvidence::from_increments(GapConfig::new(m.tau0_s), &inc);
    diagnose(&ev.snapshot(), &DiagnoseOptions::default()).expect("diagnosis")
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

/// A MEMS gyro at 200 Hz: N 0.005 deg/sqrt(s) (rate-sample noise 0.0707 deg/s), rate samples
/// rounded to 0.05 deg/s (0.71 of the noise; `N_q` = 0.00177, a 12.5% share of `N^2`), one
/// hour. Named `rate` with the step exact, the unit's own N within 3% of 0.005, the fitted N
/// within 3% of `sqrt(N^2 + N_q^2)` (so no N excess is left unexplained) and no effect.
#[test]
fn mems_rate_rounding_is_named() {
    let text = "tau0_s = 0.005\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = 0.005\nB = 2.0e-4\nK = 1.0e-5\nrate_lsb = 0.05\n";
    for seed in [1, 2] {
        let d = run(text, 3600.0, seed);
        let q = d.quantization.expect("values on a grid");
        assert_eq!(q.kind, QuantKind::Rate, "seed {seed}: {q:?}");
        assert!(rel(q.rate_lsb, 0.05) < 1e-9, "{q:?}");
        let n_q = 0.05 * (0.005f64 / 12.0).sqrt();
        assert!(rel(q.n_q, n_q) < 1e-9);
        assert!(rel(q.n_unit, 0.005) < 0.03, "n_unit {}", q.n_unit);
        let n_all = (0.005f64.powi(2) + n_q * n_q).sqrt();
        assert!(rel(d.final_coef[1], n_all) < 0.03, "N {:?}", d.final_coef);
        assert!(q.delta_chi2_angle > 100.0, "{q:?}");
        assert!(q.delta_chi2_rate < 9.0, "{q:?}");
        assert_eq!(d.verdict, Verdict::Consistent, "{d:?}");
        // The twin rounds its rate samples too, with the unit's own N.
        let facts = ChannelFacts {
            name: "gx".into(),
            unit: "deg".into(),
            lsb: Some(q.lsb),
            bias: 0.0,
            temperature_coefficient: 0.0,
            temperature_quadratic: 0.0,
        };
        let ch = fitted_channel(&facts, &d, 0.005);
        assert_eq!(ch.lsb, None);
        assert!(rel(ch.rate_lsb.expect("rate_lsb"), 0.05) < 1e-9);
        assert!(rel(ch.n, 0.005) < 0.03, "twin N {}", ch.n);
    }
}

/// The seed's MA4 (config/models/ma4.toml: a counter with carry, Q-dominated), 30 minutes:
/// named `angle`; the rate hypothesis would need an N about 20 times the fitted one.
#[test]
fn a_counter_with_carry_is_angle_quantization() {
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("config/models/ma4.toml"),
    )
    .expect("ma4.toml");
    let d = run(&text, 1800.0, 3);
    let q = d.quantization.expect("values on a grid");
    assert_eq!(q.kind, QuantKind::Angle, "{q:?}");
    assert!(rel(q.lsb, 2.104e-4) < 1e-9);
    assert!(q.delta_chi2_rate > 100.0, "{q:?}");
}

/// An accelerometer that counts its velocity with carry at 2.7 times the per-sample noise
/// (80 Hz, N 3.33e-4 m/s/sqrt(s), LSB 9.985e-5 m/s; a review's blind family, session 39), four
/// hours: the base model carries the counter's sawtooth, and the kind is not `rate` (before, the
/// white floor forced on top of the sawtooth was rejected and `rate` read by elimination in 9
/// of 40 such runs, the twin then rounding rate samples with N 37% low). The twin counts with
/// carry at the step and keeps the fitted N (within 5% of the truth).
#[test]
fn a_coarse_counter_whose_sawtooth_the_model_carries_is_not_rate_rounding() {
    let text = "tau0_s = 0.0125\n[[channel]]\nname = \"c1\"\nunit = \"m/s\"\nlsb = 9.985226e-05\n\
                N = 3.331393e-04\nB = 2.177971e-05\nK = 1.100166e-06\n\
                flicker_band_s = [0.0125, 1.0e4]\n";
    for seed in [4, 7] {
        let d = run(text, 14_400.0, seed);
        let q = d.quantization.expect("values on a grid");
        assert_ne!(q.kind, QuantKind::Rate, "seed {seed}: {q:?}");
        assert!(rel(q.lsb, 9.985226e-05) < 1e-9, "{q:?}");
        let facts = ChannelFacts {
            name: "c1".into(),
            unit: "m/s".into(),
            lsb: Some(q.lsb),
            bias: 0.0,
            temperature_coefficient: 0.0,
            temperature_quadratic: 0.0,
        };
        let ch = fitted_channel(&facts, &d, 0.0125);
        assert_eq!(ch.rate_lsb, None, "seed {seed}");
        assert!(rel(ch.lsb.expect("a counter"), 9.985226e-05) < 1e-9);
        assert!(
            rel(ch.n, 3.331393e-04) < 0.05,
            "seed {seed}: twin N {}",
            ch.n
        );
    }
}

/// Rate samples rounded to a step four times their noise (two or three values in all, N 0.005
/// deg/sqrt(s) at 200 Hz on a 0.3 deg/s step): the rounding error is no uniform one of variance
/// `lsb^2 / 12`, and the fitted white rate lies below that formula's `N_q`. The share of the
/// white rate that is rounding is then all of it, 1, not above (a review read 1.39), and the
/// unit's own white rate left beside it is not determined (since session 53; it read 0).
#[test]
fn a_step_coarse_against_the_noise_is_at_most_all_of_the_white_rate() {
    let text = "tau0_s = 0.005\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = 0.005\nB = 2.0e-4\nK = 1.0e-5\nrate_lsb = 0.3\n";
    let d = run(text, 1800.0, 3);
    let q = d.quantization.expect("values on a grid");
    let n_q = 0.3 * (0.005f64 / 12.0).sqrt();
    assert!(rel(q.n_q, n_q) < 1e-9);
    assert!(
        d.final_coef[1] < n_q,
        "N {} below N_q {n_q}",
        d.final_coef[1]
    );
    assert_eq!(q.share_of_n2, 1.0, "{q:?}");
    assert!(q.n_unit.is_nan(), "{q:?}");
}

/// Rate samples of 0.3 step's noise on a mean half a step off the grid (N 0.00212
/// deg/sqrt(s) at 200 Hz, rate samples of 0.03 deg/s on a 0.1 deg/s step, bias 0.05 deg/s):
/// two values, about equally often, whose deviation is half a step whatever the unit's. The
/// unit's own white rate is not determined (the uniform rounding model read 1.37 times the
/// truth). The same unit with 0.6 step's noise is within 4% of its N.
#[test]
fn two_value_rate_samples_leave_the_units_noise_undetermined() {
    let model = |n: f64| {
        format!(
            "tau0_s = 0.005\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = {n}\nB = 1.0e-4\n\
             bias = 0.05\nrate_lsb = 0.1\n"
        )
    };
    let per_sample = |r: f64| r * 0.1 * 0.005f64.sqrt();
    for seed in [4, 5] {
        let coarse = run(&model(per_sample(0.3)), 1800.0, seed);
        let q = coarse.quantization.expect("values on a grid");
        assert!(rel(q.rate_lsb, 0.1) < 1e-9, "{q:?}");
        let naive = (coarse.final_coef[1].powi(2) - q.n_q * q.n_q)
            .max(0.0)
            .sqrt();
        assert!(
            naive > 1.25 * per_sample(0.3),
            "seed {seed}: the uniform model's reading {naive} is off"
        );
        assert!(q.n_unit.is_nan(), "seed {seed}: {q:?}");
        let fine = run(&model(per_sample(0.6)), 1800.0, seed);
        let q = fine.quantization.expect("values on a grid");
        assert!(
            rel(q.n_unit, per_sample(0.6)) < 0.04,
            "seed {seed}: n_unit {} against {}",
            q.n_unit,
            per_sample(0.6)
        );
    }
}
