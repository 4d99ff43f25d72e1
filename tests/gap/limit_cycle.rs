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
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

const TAU0: f64 = 0.004;
const LSB: f64 = 1.22;
const RATE: f64 = 5.83;

fn run(extra: &str, seed: u64) -> Diagnosis {
    let text = format!(
        "tau0_s = {TAU0}\n[[channel]]\nname = \"r\"\nunit = \"arcsec\"\nlsb = {LSB}\n\
         bias = {RATE}\nQ = 0.255\nN = 0.083\nB = 0.002\nK = 5e-7\n{extra}\n"
    );
    let m = SimModel::from_toml_str(&text, Path::new("<test>")).expect("model");
    let mut sim = Simulator::new(&m, seed);
    let mut out = vec![0.0; (3600.0 / TAU0) as usize];
    sim.fill_channel(0, &mut out);
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
