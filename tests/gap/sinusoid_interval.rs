//! The sinusoid's amplitude interval (docs/gap.md, "Parameter intervals", session 39): a fixed
//! signal's AVAR estimate errs by its cross term with the noise, which the curve's covariance
//! of the noise lacks; each tau's standard deviation is widened by `sqrt(1 + 2 A_s / A_n)`.

use allanscope::gap::{diagnose, DiagnoseOptions, EffectParams, GapConfig, GapEvidence};
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

/// A MEMS gyro at 200 Hz (N 8.7e-5 rad/sqrt(s), rate samples rounded to 1.2e-3 rad/s) with a
/// sinusoid of 5e-5 rad/s at 0.05 Hz, about the noise's ADEV at its hump, two hours. Over
/// seeds 1-30 through the CLI the named amplitudes spread by 4.7% (sd; mean 4.99e-5), so a 95%
/// interval is about +-9.2%: the intervals were +-6.0% (median) and missed the truth on 7 of
/// 30, among them seeds 8 and 11; now +-9.5% and 30 of 30. Here, seeds 8 and 11: the truth
/// covered, the half-width between 7% and 13%.
#[test]
fn a_sinusoid_s_amplitude_interval_holds_its_cross_term_with_the_noise() {
    let text = "tau0_s = 0.005\n[[channel]]\nname = \"gx\"\nunit = \"rad\"\nrate_lsb = 1.2e-3\n\
                N = 8.7e-5\nB = 2.4e-5\nK = 2.0e-6\nflicker_band_s = [0.005, 1.0e4]\n\
                sinusoid = { amplitude = 5.0e-5, frequency = 0.05, phase = 0.3 }\n";
    let m = SimModel::from_toml_str(text, Path::new("<test>")).expect("model");
    for seed in [8, 11] {
        let mut sim = Simulator::new(&m, seed);
        let mut x = vec![0.0; (7200.0 / m.tau0_s) as usize];
        sim.fill_channel(0, &mut x);
        for v in x.iter_mut() {
            *v = format!("{v}").parse().expect("number");
        }
        let snap = GapEvidence::from_increments(GapConfig::new(m.tau0_s), &x).snapshot();
        let d = diagnose(&snap, &DiagnoseOptions::default()).expect("diagnosis");
        let (i, a) = d
            .effects
            .iter()
            .enumerate()
            .find_map(|(i, e)| match e.params {
                EffectParams::Sinusoid { amplitude, .. } => Some((i, amplitude)),
                _ => None,
            })
            .unwrap_or_else(|| panic!("seed {seed}: {:?}", d.effects));
        let [lo, hi] = d.effect_intervals[i]
            .iter()
            .find(|(name, _)| *name == "amplitude")
            .map(|(_, iv)| *iv)
            .expect("an amplitude interval");
        assert!(
            lo <= 5.0e-5 && 5.0e-5 <= hi,
            "seed {seed}: {a} [{lo}, {hi}]"
        );
        let half = (hi - lo) / (2.0 * a);
        assert!(
            (0.07..0.13).contains(&half),
            "seed {seed}: half-width {half}"
        );
    }
}
