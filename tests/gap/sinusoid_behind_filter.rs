//! A sinusoid behind the unit's own filter through the model file (docs/gap.md, "Sinusoids
//! behind a filter in the model file"): the diagnosis names the amplitude seen at the output, the
//! simulator writes its sinusoids before the filter, so the twin's file must carry
//! `A / |H(f)|`. The loop truth -> run -> diagnosis -> model file -> twin run -> diagnosis must
//! give back the named amplitude within the first diagnosis's 95% interval.

use allanscope::gap::unit_model::{fitted_channel, fitted_unit, ChannelFacts};
use allanscope::gap::{diagnose, DiagnoseOptions, Diagnosis, EffectKind, GapConfig, GapEvidence};
use allanscope::sim::{SimModel, Simulator};

const TAU0: f64 = 0.01;

/// One hour of `model`'s channel 0 (increments).
fn run(model: &SimModel, seed: u64) -> Vec<f64> {
    let mut sim = Simulator::new(model, seed);
    let mut out = vec![0.0; (3600.0 / model.tau0_s) as usize];
    sim.fill_channel(0, &mut out);
    out
}

fn diagnosed(inc: &[f64]) -> Diagnosis {
    let mut ev = GapEvidence::from_increments(GapConfig::new(TAU0), inc);
    diagnose(&ev.snapshot(), &DiagnoseOptions::default()).expect("diagnosis")
}

/// The named sinusoid's (amplitude, frequency, amplitude interval).
fn sinusoid(d: &Diagnosis) -> (f64, f64, [f64; 2]) {
    let i = d
        .effects
        .iter()
        .position(|e| e.params.kind() == EffectKind::Sinusoid)
        .unwrap_or_else(|| panic!("no sinusoid named: {:?}", d.effects));
    let iv = d.effect_intervals[i]
        .iter()
        .find(|(k, _)| *k == "amplitude")
        .map(|(_, v)| *v)
        .expect("amplitude interval");
    (
        d.effects[i].params.amplitude(),
        d.effects[i].params.shape(),
        iv,
    )
}

/// Runs the loop on a unit (N 0.1 deg/sqrt(s) per sample at 100 Hz, flicker 0.007, a 0.3 deg/s
/// line at `f_hz`) behind `filter`; checks that `filter_kind` and the sinusoid are named on the
/// run, that the model file's amplitude is the named one over `|H(f)|` (`gain`, the filter's
/// closed-form amplitude gain), and that the twin's run names the amplitude within the first
/// diagnosis's interval.
fn round_trip(filter: &str, filter_kind: EffectKind, f_hz: f64, gain: f64, seed: u64) {
    let text = format!(
        "tau0_s = {TAU0}\n[[channel]]\nname = \"g\"\nunit = \"deg\"\nN = 0.1\nB = 0.007\n\
         sinusoid = {{ amplitude = 0.3, frequency = {f_hz}, phase = 0.3 }}\n{filter}\n"
    );
    let truth = SimModel::from_toml_str(&text, std::path::Path::new("<test>")).expect("model");
    let d1 = diagnosed(&run(&truth, seed));
    assert!(
        d1.effects.iter().any(|e| e.params.kind() == filter_kind),
        "{filter}: {:?}",
        d1.effects
    );
    let (a1, f1, iv1) = sinusoid(&d1);
    // The run names what the output shows: 0.3 |H(f)|.
    assert!(
        iv1[0] <= 0.3 * gain && 0.3 * gain <= iv1[1],
        "{filter}: named {a1} [{}, {}], output amplitude {}",
        iv1[0],
        iv1[1],
        0.3 * gain
    );
    let facts = ChannelFacts {
        name: "g".into(),
        unit: "deg".into(),
        lsb: None,
        bias: 0.0,
        temperature_coefficient: 0.0,
        temperature_quadratic: 0.0,
    };
    let ch = fitted_channel(&facts, &d1, TAU0);
    let written = ch.sinusoids[0].amplitude;
    // The gain is the named filter's at the named frequency (the first order's T is named
    // within its interval, about 10%, which moves |H| at 3 Hz by a few %).
    assert!(
        (written * gain / a1 - 1.0).abs() < 0.08,
        "{filter}: written {written}, named {a1} at {f1} Hz, gain {gain}"
    );
    let twin = fitted_unit(TAU0, vec![ch], None);
    let d2 = diagnosed(&run(&twin, seed + 100));
    let (a2, _, iv2) = sinusoid(&d2);
    assert!(
        iv1[0] <= a2 && a2 <= iv1[1],
        "{filter}: twin names {a2} [{}, {}], the run {a1} [{}, {}]",
        iv2[0],
        iv2[1],
        iv1[0],
        iv1[1]
    );
}

/// The ADIS16405's 2-tap average at 100 Hz and a 20 Hz line: `|H| = cos(pi f tau0) = 0.809`.
/// Before the fix the twin named 0.198 for a run's 0.244 (the gain applied twice).
#[test]
fn a_line_behind_a_moving_average_keeps_its_amplitude_on_the_twin() {
    let gain = (std::f64::consts::PI * 20.0 * TAU0).cos();
    round_trip(
        "moving_average = { taps = 2, stages = 1 }",
        EffectKind::MovingAverage,
        20.0,
        gain,
        10105,
    );
}

/// A first-order output filter of 30 ms (3 tau0) and a 3 Hz line: `|H|^2 = (1 - a)^2 /
/// ((1 - a)^2 + 4 a sin^2(pi f tau0))`, `a = e^{-tau0/T}`: `|H| = 0.872`.
#[test]
fn a_line_behind_a_first_order_filter_keeps_its_amplitude_on_the_twin() {
    let a = (-TAU0 / 0.03f64).exp();
    let s = (std::f64::consts::PI * 3.0 * TAU0).sin();
    let gain = ((1.0 - a) * (1.0 - a) / ((1.0 - a) * (1.0 - a) + 4.0 * a * s * s)).sqrt();
    round_trip(
        "output_filter = { time_constant = 0.03 }",
        EffectKind::OutputFilter,
        3.0,
        gain,
        10106,
    );
}
