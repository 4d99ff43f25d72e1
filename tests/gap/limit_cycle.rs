//! The counter's limit cycle (docs/gap.md, "The counter's limit cycle"): a ring-laser-gyro-like
//! unit (held2's `rlg` family: angle counted with carry at 1.22 arcsec, white angle noise of
//! 0.2 count beyond the counter, N 0.083 arcsec/sqrt(s), a constant input of 5.83 arcsec/s) at
//! 250 Hz for an hour. Its quantization error is a sawtooth at 5.83 / 1.22 = 4.78 Hz, which the
//! diagnosis names a sinusoid: the record must say that the line is the counter's (its `cause`)
//! and the verdict must not count it as an effect of the unit. A real vibration of the same
//! unit at another frequency is not attributed.

use allanscope::gap::{
    diagnose, DiagnoseOptions, Diagnosis, DiagnosisRecord, EffectKind, EffectParams, GapConfig,
    GapEvidence, Verdict,
};

const TAU0: f64 = 0.004;
const LSB: f64 = 1.22;
const RATE: f64 = 5.83;

fn run(extra: &str, seed: u64) -> Diagnosis {
    let text = format!(
        "tau0_s = {TAU0}\n[[channel]]\nname = \"r\"\nunit = \"arcsec\"\nlsb = {LSB}\n\
         bias = {RATE}\nQ = 0.255\nN = 0.083\nB = 0.002\nK = 5e-7\n{extra}\n"
    );
    let out = super::diagnosis::simulate_text(&text, TAU0, 3600.0, seed);
    let snap = GapEvidence::from_increments(GapConfig::new(TAU0), &out).snapshot();
    diagnose(&snap, &DiagnoseOptions::default()).expect("diagnosis")
}

fn sinusoids(d: &Diagnosis) -> Vec<(usize, f64)> {
    d.effects
        .iter()
        .enumerate()
        .filter_map(|(i, e)| match e.params {
            EffectParams::Sinusoid { frequency_hz, .. } => Some((i, frequency_hz)),
            _ => None,
        })
        .collect()
}

/// Seed 2: the line is named (G 579 -> 1.66) at the counter's 4.78 Hz, within 0.5%, and is
/// the only effect: the record gives its cause (`quantization_limit_cycle`, harmonic 1, the
/// expected frequency from the run's mean rate within 0.1% of 5.83 / 1.22), and the verdict is
/// `consistent` (it was `explained`, as if the unit vibrated).
#[test]
fn the_counters_tone_is_named_and_attributed_to_the_counter() {
    let d = run("", 2);
    let s = sinusoids(&d);
    assert_eq!(s.len(), 1, "{:?}", d.effects);
    let f_lc = RATE / LSB;
    assert!((s[0].1 / f_lc - 1.0).abs() < 0.005, "{s:?}");
    assert_eq!(d.limit_cycles.len(), 1, "{:?}", d.limit_cycles);
    let c = d.limit_cycles[0];
    assert_eq!((c.effect, c.harmonic), (s[0].0, 1));
    assert!((c.expected_hz / f_lc - 1.0).abs() < 1e-3, "{c:?}");
    assert_eq!(d.verdict, Verdict::Consistent, "{:?}", d.effects);
    assert_eq!(allanscope::gap::limit_cycle::unit_effects(&d).count(), 0);
    let v: serde_json::Value =
        serde_json::from_str(&DiagnosisRecord::new("r", &d, None, true).to_json_line())
            .expect("json");
    let e = &v["effects"][s[0].0];
    assert_eq!(e["kind"], "sinusoid");
    assert_eq!(e["cause"]["kind"], "quantization_limit_cycle");
    assert_eq!(e["cause"]["harmonic"], 1);
    assert_eq!(v["verdict"], "consistent");
}

/// The same unit shaken at 2.1 Hz (10 arcsec/s): that line is named and not attributed (it is
/// far from 4.78 Hz and its harmonics), so the verdict counts it.
#[test]
fn a_real_vibration_of_a_counter_unit_is_not_attributed() {
    let d = run(
        "sinusoid = { amplitude = 10.0, frequency = 2.1, phase = 0.0 }",
        2,
    );
    let s = sinusoids(&d);
    let real = s
        .iter()
        .find(|(_, f)| (f / 2.1 - 1.0).abs() < 0.01)
        .unwrap_or_else(|| panic!("2.1 Hz not named: {:?}", d.effects));
    assert!(
        !d.limit_cycles.iter().any(|c| c.effect == real.0),
        "{:?}",
        d.limit_cycles
    );
    assert!(allanscope::gap::limit_cycle::unit_effects(&d)
        .any(|e| e.params.kind() == EffectKind::Sinusoid));
    assert_ne!(d.verdict, Verdict::Consistent);
}

/// A line the angle's random walk widened is still the counter's (docs/gap.md, "Every family on
/// one commit, and the base `G`'s tail (session 22)"). The unit is family_gap's rlg, seed 221
/// draw 2 (its `--models` file and simulator seed): counted with carry at 0.722 arcsec at 237 Hz,
/// a constant input of 3.143 arcsec/s (the counter's tone at 4.353 Hz), white angle noise of 0.3
/// count, N 0.108 arcsec/sqrt(s). The angle's random walk spreads the tone into a Lorentzian of
/// half-width `pi N^2 / LSB^2` = 0.070 Hz, and the sinusoid fitted to it sat 0.072 Hz (1.7%)
/// off the expected frequency, outside the 1% window: the run was `explained` by a vibration.
/// Asserted: the one line named within 3% of 4.353 Hz, attributed to the counter (harmonic 1),
/// the half-width at the fitted `N` within 20% of the truth's, the verdict `consistent`.
#[test]
fn a_line_the_random_walk_widened_is_still_the_counters() {
    let (lsb, rate, n_arw) = (
        7.219788328363145e-1,
        3.142572633311266,
        1.0842341581741755e-1,
    );
    let d = family_gap_rlg(
        0.004219409282700422,
        4044.022614565478,
        [
            2.1461220438304413e-1,
            n_arw,
            1.4349865980341286e-3,
            1.0373250818259063e-6,
        ],
        rate,
        lsb,
        8287166162592586687,
    );
    let s = sinusoids(&d);
    let f_lc = rate / lsb;
    assert!(
        s.len() == 1 && (s[0].1 / f_lc - 1.0).abs() < 0.03,
        "{:?}",
        d.effects
    );
    let hw = allanscope::gap::limit_cycle::line_half_width(1, d.final_coef[1], lsb);
    let hw_true = std::f64::consts::PI * (n_arw / lsb).powi(2);
    assert!((hw / hw_true - 1.0).abs() < 0.2, "{hw} vs {hw_true}");
    assert!(
        d.limit_cycles.len() == 1 && d.limit_cycles[0].harmonic == 1,
        "{:?} {s:?}",
        d.limit_cycles
    );
    assert_eq!(d.verdict, Verdict::Consistent, "{:?}", d.effects);
}

/// family_gap's rlg unit (`tau0` s, `t_run` s, `[Q, N, B, K]`, input `rate`, counter `lsb`),
/// simulated from its `--models` file's numbers and simulator seed, and diagnosed.
fn family_gap_rlg(
    tau0: f64,
    t_run: f64,
    [q, n, b, k]: [f64; 4],
    rate: f64,
    lsb: f64,
    sim_seed: u64,
) -> Diagnosis {
    let text = format!(
        "tau0_s = {tau0}\n[[channel]]\nname = \"x\"\nunit = \"u\"\nQ = {q:e}\nN = {n:e}\n\
         B = {b:e}\nK = {k:e}\nflicker_band_s = [{tau0}, {:e}]\nbias = {rate:e}\nlsb = {lsb:e}\n",
        10.0 * t_run
    );
    let out = super::diagnosis::simulate_text(&text, tau0, t_run, sim_seed);
    let snap = GapEvidence::from_increments(GapConfig::new(tau0), &out).snapshot();
    diagnose(&snap, &DiagnoseOptions::default()).expect("diagnosis")
}

/// The line's sharpness is judged by the rate's slow wander, not by the block means' white
/// noise (which the line's half-width already carries). family_gap's rlg, seed 181 draw 12: a
/// counter at 1.067 arcsec, 299 Hz, input 2.086 arcsec/s (tone at 1.955 Hz), B 1.3e-3 and K
/// 2.4e-7 (a still rate). The 1.951 Hz line is 0.4% from the expected 1.959 Hz, but the block
/// means' whole spread (0.040 Hz of line, mostly their white noise) was beyond the 0.031 Hz
/// window and the run stayed `explained` by a vibration. Asserted: the line within 1% of
/// `rate / lsb`, attributed (harmonic 1), `consistent`.
#[test]
fn the_block_means_white_noise_does_not_make_the_line_unsharp() {
    let (lsb, rate) = (1.066873705625251, 2.085685932090091);
    let d = family_gap_rlg(
        0.0033444816053511705,
        3701.9424539584776,
        [
            2.4772626515803406e-1,
            6.315817717247031e-2,
            1.3331088429786196e-3,
            2.3590188114864121e-7,
        ],
        rate,
        lsb,
        820368892804944060,
    );
    let s = sinusoids(&d);
    assert!(
        s.len() == 1 && (s[0].1 / (rate / lsb) - 1.0).abs() < 0.01,
        "{:?}",
        d.effects
    );
    assert!(
        d.limit_cycles.len() == 1 && d.limit_cycles[0].harmonic == 1,
        "{:?} {s:?}",
        d.limit_cycles
    );
    assert_eq!(d.verdict, Verdict::Consistent, "{:?}", d.effects);
}
