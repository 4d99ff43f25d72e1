//! Writes a [`SimModel`] back as a model file (the format of [`super::model_file`]), so that a
//! model built in code (the fitted unit of `diagnose --model-out`) is a file `simulate --model`
//! reads unchanged. Every number is written in Rust's shortest round-trip form, so reading the
//! file back gives the same model bit for bit.

use std::fmt::Write as _;

use super::model_file::{ChannelModel, SimModel};
use crate::model::lowpass::{LowPass, SecondOrderForm};

/// A number as TOML reads it back to the same `f64` (`{:?}` is the shortest round-trip form and
/// always has a `.` or an exponent). Non-finite values have no TOML form a model file accepts;
/// callers only pass checked models, whose numbers are finite, and 0 is written instead.
fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x:?}")
    } else {
        "0.0".into()
    }
}

/// A TOML basic string (quotes and backslashes escaped; names never hold line breaks).
fn text(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for ch in s.chars() {
        match ch {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// The model file of `model`: `header` lines become `#` comments at the top, `description`
/// the file's `description` key.
pub fn model_toml(model: &SimModel, description: &str, header: &[String]) -> String {
    let mut s = String::new();
    for h in header {
        for line in h.lines() {
            let _ = writeln!(s, "# {line}");
        }
    }
    let _ = writeln!(s, "description = {}", text(description));
    let _ = writeln!(s, "tau0_s = {}", num(model.tau0_s));
    if let Some(st) = model.stand {
        let _ = writeln!(s, "\n[stand]");
        let _ = writeln!(s, "latitude_deg = {}", num(st.latitude_deg));
        let _ = writeln!(s, "gravity_m_s2 = {}", num(st.gravity_m_s2));
    }
    if let Some(t) = &model.temperature {
        let _ = writeln!(s, "\n[temperature]");
        let _ = writeln!(s, "start_c = {}", num(t.start_c));
        let _ = writeln!(s, "final_c = {}", num(t.final_c));
        let _ = writeln!(s, "time_constant_s = {}", num(t.time_constant_s));
        if t.sine_amplitude_c != 0.0 {
            let _ = writeln!(s, "sine_amplitude_c = {}", num(t.sine_amplitude_c));
            let _ = writeln!(s, "sine_period_s = {}", num(t.sine_period_s));
        }
        let _ = writeln!(s, "reference_c = {}", num(t.reference_c));
    }
    for c in &model.channels {
        channel_toml(&mut s, c);
    }
    s
}

fn channel_toml(s: &mut String, c: &ChannelModel) {
    let _ = writeln!(s, "\n[[channel]]");
    let _ = writeln!(s, "name = {}", text(&c.name));
    let _ = writeln!(s, "unit = {}", text(&c.unit));
    if let Some(l) = c.lsb {
        let _ = writeln!(s, "lsb = {}", num(l));
    }
    if let Some(a) = c.axis_enu {
        let _ = writeln!(s, "axis = [{}, {}, {}]", num(a[0]), num(a[1]), num(a[2]));
    }
    let _ = writeln!(s, "bias = {}", num(c.bias));
    let _ = writeln!(s, "Q = {}", num(c.q));
    let _ = writeln!(s, "N = {}", num(c.n));
    let _ = writeln!(s, "B = {}", num(c.b));
    let _ = writeln!(s, "K = {}", num(c.k));
    let _ = writeln!(s, "R = {}", num(c.r));
    let _ = writeln!(
        s,
        "flicker_band_s = [{}, {}]",
        num(c.flicker_band_s.0),
        num(c.flicker_band_s.1)
    );
    if c.temperature_coefficient != 0.0 {
        let _ = writeln!(
            s,
            "temperature_coefficient = {}",
            num(c.temperature_coefficient)
        );
    }
    if c.temperature_quadratic != 0.0 {
        let _ = writeln!(
            s,
            "temperature_quadratic = {}",
            num(c.temperature_quadratic)
        );
    }
    if let Some(l) = c.rate_lsb {
        let _ = writeln!(s, "rate_lsb = {}", num(l));
    }
    for g in &c.gauss_markov {
        let _ = writeln!(
            s,
            "[[channel.gauss_markov]]\nsigma = {}\ntau_c = {}",
            num(g.sigma),
            num(g.tau_c_s)
        );
    }
    for x in &c.sinusoids {
        let _ = writeln!(
            s,
            "[[channel.sinusoid]]\namplitude = {}\nfrequency = {}\nphase = {}",
            num(x.amplitude),
            num(x.frequency_hz),
            num(x.phase_rad)
        );
    }
    for x in &c.band_noise {
        let _ = writeln!(
            s,
            "[[channel.band_noise]]\nsigma = {}\nfrequency = {}\nwidth = {}",
            num(x.sigma),
            num(x.frequency_hz),
            num(x.width_hz)
        );
    }
    if let Some(f) = c.output_filter {
        let _ = writeln!(
            s,
            "[channel.output_filter]\ntime_constant = {}",
            num(f.time_constant_s)
        );
    }
    // a cascade as its two parts' tables (the model file reads them back as one)
    let parts = match c.lowpass {
        Some(lp @ LowPass::Cascade { .. }) => lp.parts().map(|(a, b)| vec![a, b]),
        lp => lp.map(|lp| vec![lp]),
    };
    for lp in parts.unwrap_or_default() {
        write_lowpass(s, lp);
    }
    if let Some(w) = c.warmup {
        let _ = writeln!(
            s,
            "[channel.warmup]\namplitude = {}\ntime_constant = {}",
            num(w.amplitude),
            num(w.time_constant_s)
        );
    }
    if let Some(j) = c.bias_jumps {
        let _ = writeln!(
            s,
            "[channel.bias_jumps]\nmean_interval = {}\nrms_size = {}",
            num(j.mean_interval_s),
            num(j.rms_size)
        );
    }
    if let Some(o) = c.outliers {
        let _ = writeln!(
            s,
            "[channel.outliers]\nrate = {}\nsize = {}",
            num(o.rate_per_s),
            num(o.size)
        );
    }
}

/// The model file's table of one filter (`[channel.moving_average]`, ...).
fn write_lowpass(s: &mut String, lp: LowPass) {
    match lp {
        LowPass::MovingAverage {
            taps,
            stages,
            decimation,
        } => {
            let _ = writeln!(
                s,
                "[channel.moving_average]\ntaps = {taps}\nstages = {stages}{}",
                if decimation > 1 {
                    format!("\ndecimation = {decimation}")
                } else {
                    String::new()
                }
            );
        }
        LowPass::SecondOrder {
            natural_frequency_hz,
            damping,
            form,
        } => {
            let _ = writeln!(
                s,
                "[channel.second_order_filter]\nnatural_frequency = {}\ndamping = {}{}",
                num(natural_frequency_hz),
                num(damping),
                match form {
                    SecondOrderForm::PoleMapped => String::new(),
                    SecondOrderForm::Bilinear => "\nbilinear = true".to_string(),
                    SecondOrderForm::Sampled { zero } => format!("\nzero = {}", num(zero)),
                }
            );
        }
        LowPass::ZeroPhase { time_constant_s } => {
            let _ = writeln!(
                s,
                "[channel.zero_phase_filter]\ntime_constant = {}",
                num(time_constant_s)
            );
        }
        LowPass::FirstOrder { time_constant_s } => {
            let _ = writeln!(
                s,
                "[channel.output_filter]\ntime_constant = {}",
                num(time_constant_s)
            );
        }
        // (written as its parts above)
        LowPass::Cascade { .. } => {}
        LowPass::Butterworth {
            order,
            cutoff_hz,
            decimation,
        } => {
            let _ = writeln!(
                s,
                "[channel.butterworth_filter]\norder = {order}\ncutoff = {}{}",
                num(cutoff_hz),
                if decimation > 1 {
                    format!("\ndecimation = {decimation}")
                } else {
                    String::new()
                }
            );
        }
        LowPass::Fir {
            taps,
            cutoff_hz,
            decimation,
        } => {
            let _ = writeln!(
                s,
                "[channel.fir_filter]\ntaps = {taps}\ncutoff = {}{}",
                num(cutoff_hz),
                if decimation > 1 {
                    format!("\ndecimation = {decimation}")
                } else {
                    String::new()
                }
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn read(text: &str) -> SimModel {
        SimModel::from_toml_str(text, Path::new("t.toml")).expect("model parses")
    }

    /// Every shipped model, written and read back, is the same model (every field, bit for bit;
    /// the flicker bank is designed again from the same numbers).
    #[test]
    fn shipped_models_round_trip() {
        for text in [
            include_str!("../../config/models/vog4_effects.toml"),
            include_str!("../../config/models/ma4.toml"),
            include_str!("../../config/models/vog4.toml"),
            include_str!("../../config/models/siu8_stand.toml"),
        ] {
            let m = read(text);
            let written = model_toml(&m, "round trip", &["a header".into()]);
            let back = read(&written);
            assert_eq!(m, back, "{written}");
        }
    }

    /// Effects a shipped file lacks (several Gauss-Markov terms, a filter, jumps) and awkward
    /// names and numbers survive the round trip too.
    #[test]
    fn all_effects_and_odd_numbers_round_trip() {
        let text = r#"
tau0_s = 0.0025
[[channel]]
name = "g x\\y"
unit = "deg"
lsb = 1.0e-7
bias = -3.0e-3
N = 1.0e-300
K = 2.5e-5
R = -1.0e-9
gauss_markov = [{ sigma = 0.1, tau_c = 2.0 }, { sigma = 0.01, tau_c = 300.0 }]
sinusoid = [{ amplitude = 0.05, frequency = 1.3, phase = 0.25 }]
band_noise = [{ sigma = 0.3, frequency = 20.7, width = 2.0 }, { sigma = 0.01, frequency = 49.0, width = 0.5 }]
output_filter = { time_constant = 0.01 }
warmup = { amplitude = -0.5, time_constant = 600.0 }
bias_jumps = { mean_interval = 1800.0, rms_size = 0.01 }
rate_lsb = 0.02
outliers = { rate = 0.001, size = 3.5 }
"#;
        let m = read(text);
        assert_eq!(m.channels[0].gauss_markov.len(), 2);
        let back = read(&model_toml(&m, "quote \" inside", &[]));
        assert_eq!(m, back);
        assert_eq!(back.channels[0].name, "g x\\y");
    }

    /// A temperature dependence with its second order is written and read back as it was
    /// (`temperature_quadratic`, session 51), and the simulator's bias follows it: a unit held
    /// at `reference_c + 10` degC has the mean rate `c 10 + q 100` over its run.
    #[test]
    fn a_bent_temperature_dependence_round_trips_and_is_simulated() {
        let text = r#"
tau0_s = 0.01
[temperature]
start_c = 40.0
final_c = 40.0
time_constant_s = 100.0
reference_c = 30.0
[[channel]]
name = "gx"
unit = "deg"
N = 1.0e-12
temperature_coefficient = 0.002
temperature_quadratic = 3.0e-5
"#;
        let m = read(text);
        assert_eq!(m.channels[0].temperature_quadratic, 3.0e-5);
        let back = read(&model_toml(&m, "bent", &[]));
        assert_eq!(m, back);
        let mut sim = crate::sim::Simulator::new(&back, 7);
        let steps = 1000;
        let sum: f64 = (0..steps).map(|_| sim.next_step().increments[0]).sum();
        let rate = sum / (steps as f64 * 0.01);
        let truth = 0.002 * 10.0 + 3.0e-5 * 100.0;
        assert!((rate / truth - 1.0).abs() < 1e-6, "{rate} against {truth}");
    }

    /// The second order's bilinear and sampled forms are written (`bilinear = true`,
    /// `zero = 0.25`) and read back as such; the pole-mapped form is written without either
    /// key, as before.
    #[test]
    fn the_second_order_forms_round_trip() {
        for (extra, form) in [
            (", bilinear = true", SecondOrderForm::Bilinear),
            (", zero = 0.25", SecondOrderForm::Sampled { zero: 0.25 }),
            ("", SecondOrderForm::PoleMapped),
        ] {
            let m = read(&format!(
                "tau0_s = 0.005\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = 0.01\n\
                 second_order_filter = {{ natural_frequency = 20.0, damping = 0.7{extra} }}\n"
            ));
            let text = model_toml(&m, "t", &[]);
            assert_eq!(
                text.contains("bilinear = true"),
                form == SecondOrderForm::Bilinear,
                "{text}"
            );
            assert_eq!(
                text.contains("zero = 0.25"),
                form != SecondOrderForm::Bilinear && form != SecondOrderForm::PoleMapped,
                "{text}"
            );
            let back = read(&text);
            assert_eq!(m, back);
            let Some(LowPass::SecondOrder { form: got, .. }) = back.channels[0].lowpass else {
                panic!("{text}");
            };
            assert_eq!(got, form);
        }
    }

    /// `decimation = 5` in a model file is the sampled form with the zero of the pole-mapped
    /// filter run 5 times faster (0.2497 for a Butterworth at 20 Hz read at 200 Hz, the value
    /// docs/gap.md's table gives); a decimation out of range, a zero beside a decimation and
    /// either beside `bilinear = true` are refused at their key.
    #[test]
    fn a_decimation_gives_the_sampled_zero_and_conflicts_are_refused() {
        let head = "tau0_s = 0.005\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = 0.01\n";
        let m = read(&format!(
            "{head}second_order_filter = {{ natural_frequency = 20.0, damping = 0.7071, decimation = 5 }}\n"
        ));
        let Some(LowPass::SecondOrder {
            form: SecondOrderForm::Sampled { zero },
            ..
        }) = m.channels[0].lowpass
        else {
            panic!("{:?}", m.channels[0].lowpass);
        };
        assert!((zero - 0.2497).abs() < 5e-4, "zero {zero}");
        for (extra, key) in [
            ("decimation = 0.5", "decimation"),
            ("decimation = 5, zero = 0.2", "decimation"),
            ("bilinear = true, zero = 0.2", "zero"),
            ("bilinear = true, decimation = 4", "decimation"),
            ("zero = 0.95", "second_order_filter"),
        ] {
            let text = format!(
                "{head}second_order_filter = {{ natural_frequency = 20.0, damping = 0.7, {extra} }}\n"
            );
            let err = SimModel::from_toml_str(&text, Path::new("t.toml"))
                .expect_err(extra)
                .to_string();
            assert!(
                err.contains(key) && err.contains("t.toml"),
                "{extra}: {err}"
            );
        }
    }

    /// A moving average run faster than the output (`decimation = 8`: a sinc^3 CIC decimator)
    /// is written with its decimation and read back the same; an output-rate one without the
    /// key, as before; a decimation of 0, 2.5 or beyond 1024 is refused at its key.
    #[test]
    fn the_decimated_average_round_trips_and_bad_decimations_are_refused() {
        let head = "tau0_s = 0.004\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = 0.01\n";
        for (extra, decimation) in [(", decimation = 8", 8u32), ("", 1)] {
            let m = read(&format!(
                "{head}moving_average = {{ taps = 8, stages = 3{extra} }}\n"
            ));
            let text = model_toml(&m, "t", &[]);
            assert_eq!(text.contains("decimation = 8"), decimation == 8, "{text}");
            assert!(!text.contains("decimation = 1"), "{text}");
            let back = read(&text);
            assert_eq!(m, back);
            assert_eq!(
                back.channels[0].lowpass,
                Some(LowPass::MovingAverage {
                    taps: 8,
                    stages: 3,
                    decimation
                })
            );
        }
        for bad in ["0", "2.5", "2000"] {
            let text = format!("{head}moving_average = {{ taps = 8, decimation = {bad} }}\n");
            let err = SimModel::from_toml_str(&text, Path::new("t.toml"))
                .expect_err(bad)
                .to_string();
            assert!(
                err.contains("decimation") && err.contains("t.toml"),
                "{bad}: {err}"
            );
        }
    }

    /// A moving average with a low-pass behind it (a consumer part's chain) is one filter, a
    /// [`LowPass::Cascade`]: with a second order or with an `output_filter`, written as its two
    /// tables and read back the same; any other pair of filters is refused at the second's key.
    #[test]
    fn a_decimator_with_a_low_pass_behind_round_trips_and_other_pairs_are_refused() {
        use crate::model::lowpass::{Average, Behind};
        let head = "tau0_s = 0.01\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = 0.01\n";
        let cic = Average {
            taps: 8,
            stages: 3,
            decimation: 8,
        };
        let ma = "moving_average = { taps = 8, stages = 3, decimation = 8 }\n";
        for (behind, back) in [
            (
                "second_order_filter = { natural_frequency = 40.0, damping = 0.7, bilinear = true }",
                Behind::SecondOrder {
                    natural_frequency_hz: 40.0,
                    damping: 0.7,
                    form: SecondOrderForm::Bilinear,
                },
            ),
            (
                "output_filter = { time_constant = 0.008 }",
                Behind::FirstOrder {
                    time_constant_s: 0.008,
                },
            ),
            (
                "butterworth_filter = { order = 3, cutoff = 25.0 }",
                Behind::Butterworth {
                    order: 3,
                    cutoff_hz: 25.0,
                },
            ),
        ] {
            let m = read(&format!("{head}{ma}{behind}\n"));
            let want = LowPass::Cascade { front: cic, back };
            assert_eq!(m.channels[0].lowpass, Some(want), "{behind}");
            assert_eq!(m.channels[0].output_filter, None, "{behind}");
            let text = model_toml(&m, "t", &[]);
            assert!(text.contains("[channel.moving_average]"), "{text}");
            let back = read(&text);
            assert_eq!(m, back, "{text}");
        }
        for (pair, key) in [
            (
                "output_filter = { time_constant = 0.008 }\nsecond_order_filter = { natural_frequency = 4.0, damping = 0.7 }",
                "second_order_filter",
            ),
            (
                "moving_average = { taps = 4 }\nzero_phase_filter = { time_constant = 0.01 }",
                "zero_phase_filter",
            ),
            (
                "zero_phase_filter = { time_constant = 0.01 }\noutput_filter = { time_constant = 0.008 }",
                "zero_phase_filter",
            ),
        ] {
            let text = format!("{head}{pair}\n");
            let err = SimModel::from_toml_str(&text, Path::new("t.toml"))
                .expect_err(pair)
                .to_string();
            assert!(
                err.contains(key) && err.contains("one filter per channel"),
                "{pair}: {err}"
            );
        }
    }

    /// A Butterworth, at the output rate and run 16 times faster, is written as
    /// `[channel.butterworth_filter]` and read back the same; a bad order, cut-off or decimation
    /// is refused naming its key.
    #[test]
    fn the_butterworth_round_trips_and_bad_ones_are_refused() {
        let head = "tau0_s = 0.01\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = 0.01\n";
        for (extra, want) in [
            (
                "order = 4, cutoff = 20.0",
                LowPass::Butterworth {
                    order: 4,
                    cutoff_hz: 20.0,
                    decimation: 1,
                },
            ),
            (
                "order = 3, cutoff = 10.0, decimation = 16",
                LowPass::Butterworth {
                    order: 3,
                    cutoff_hz: 10.0,
                    decimation: 16,
                },
            ),
        ] {
            let m = read(&format!("{head}butterworth_filter = {{ {extra} }}\n"));
            assert_eq!(m.channels[0].lowpass, Some(want), "{extra}");
            let text = model_toml(&m, "t", &[]);
            assert!(text.contains("[channel.butterworth_filter]"), "{text}");
            assert_eq!(read(&text), m, "{text}");
        }
        for (extra, key) in [
            ("order = 9, cutoff = 20.0", "butterworth_filter"),
            ("order = 4, cutoff = 60.0", "butterworth_filter"),
            ("order = 2.5, cutoff = 20.0", "order"),
            ("order = 4, cutoff = 20.0, decimation = 0", "decimation"),
            ("cutoff = 20.0", "order"),
        ] {
            let text = format!("{head}butterworth_filter = {{ {extra} }}\n");
            let err = SimModel::from_toml_str(&text, Path::new("t.toml"))
                .expect_err(extra)
                .to_string();
            assert!(err.contains(key), "{extra}: {err}");
        }
    }

    /// A linear-phase FIR is written as `[channel.fir_filter]` and read back the same; a
    /// cut-off at or beyond Nyquist and taps that are not whole are refused at their key.
    #[test]
    fn the_fir_round_trips_and_bad_ones_are_refused() {
        let head = "tau0_s = 0.001\n[[channel]]\nname = \"gx\"\nunit = \"deg\"\nN = 0.01\n";
        let m = read(&format!(
            "{head}fir_filter = {{ taps = 47, cutoff = 131.0 }}\n"
        ));
        assert_eq!(
            m.channels[0].lowpass,
            Some(LowPass::Fir {
                taps: 47,
                cutoff_hz: 131.0,
                decimation: 1
            })
        );
        let text = model_toml(&m, "t", &[]);
        assert!(text.contains("[channel.fir_filter]"), "{text}");
        assert!(!text.contains("decimation"), "{text}");
        assert_eq!(read(&text), m);
        // run at twice the output rate: the cut-off may reach the internal rate's Nyquist
        let m = read(&format!(
            "{head}fir_filter = {{ taps = 31, cutoff = 500.0, decimation = 2 }}\n"
        ));
        assert_eq!(
            m.channels[0].lowpass,
            Some(LowPass::Fir {
                taps: 31,
                cutoff_hz: 500.0,
                decimation: 2
            })
        );
        let text = model_toml(&m, "t", &[]);
        assert!(text.contains("decimation = 2"), "{text}");
        assert_eq!(read(&text), m);
        for (extra, key) in [
            ("taps = 47, cutoff = 500.0", "fir_filter"),
            ("taps = 31, cutoff = 1000.0, decimation = 2", "fir_filter"),
            ("taps = 31, cutoff = 100.0, decimation = 1.5", "decimation"),
            ("taps = 31, cutoff = 100.0, decimation = 0", "decimation"),
            ("taps = 4.5, cutoff = 100.0", "taps"),
            ("cutoff = 100.0", "taps"),
        ] {
            let text = format!("{head}fir_filter = {{ {extra} }}\n");
            let err = SimModel::from_toml_str(&text, Path::new("t.toml"))
                .expect_err(extra)
                .to_string();
            assert!(err.contains(key), "{extra}: {err}");
        }
    }
}
