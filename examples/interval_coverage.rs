//! Coverage of the diagnosis's 95% parameter intervals (docs/gap.md, "Parameter intervals"):
//! seeds of a VOG4-like unit (N, B, K of config/models/vog4.toml, LSB 0.0005 arcsec, 250 Hz)
//! with one known effect; for each parameter, the share of runs whose interval holds the truth
//! (runs where the effect is not named first count as misses).
//!
//! ```text
//! cargo run --release --example interval_coverage -- [--seeds 50] [--minutes 30] [--cases KIND,...]
//! ```

use allanscope::gap::{diagnose, DiagnoseOptions, DiagnosisRecord, GapConfig, GapEvidence};
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

/// A case: the effect's record kind, its model-file line, and its true parameters by name.
type Case = (&'static str, &'static str, &'static [(&'static str, f64)]);

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let get = |k: &str, d: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1).cloned())
            .unwrap_or_else(|| d.to_string())
    };
    let seeds: u64 = get("--seeds", "50").parse().expect("--seeds");
    let minutes: f64 = get("--minutes", "30").parse().expect("--minutes");
    let tau0 = 0.004;
    let only = get("--cases", "");
    let cases: [Case; 6] = [
        (
            "gauss_markov",
            "gauss_markov = { sigma = 0.6, tau_c = 1.5 }",
            &[("sigma", 0.6), ("tau_c", 1.5)],
        ),
        (
            "sinusoid",
            "sinusoid = { amplitude = 0.3, frequency = 0.8 }",
            &[("amplitude", 0.3), ("frequency", 0.8)],
        ),
        (
            "zero_phase_filter",
            "zero_phase_filter = { time_constant = 0.02 }",
            &[("time_constant", 0.02)],
        ),
        (
            "second_order_filter",
            "second_order_filter = { natural_frequency = 8.0, damping = 0.3 }",
            &[("natural_frequency", 8.0), ("damping", 0.3)],
        ),
        (
            "output_filter",
            "output_filter = { time_constant = 0.025 }",
            &[("time_constant", 0.025)],
        ),
        (
            "moving_average",
            "moving_average = { taps = 16, stages = 2 }",
            &[("taps", 16.0)],
        ),
    ];
    for (kind, extra, truth) in cases {
        if !only.is_empty() && !only.split(',').any(|c| c == kind) {
            continue;
        }
        let mut named = 0;
        let mut covered = vec![0u64; truth.len()];
        let mut widths: Vec<Vec<f64>> = vec![Vec::new(); truth.len()];
        for seed in 1..=seeds {
            let text = format!(
                "tau0_s = {tau0}\n[[channel]]\nname = \"g\"\nunit = \"arcsec\"\nlsb = 0.0005\nN = 0.254\nB = 0.225\nK = 1.826e-2\nflicker_band_s = [0.004, 1.0e5]\n{extra}\n"
            );
            let m = SimModel::from_toml_str(&text, Path::new("<case>")).expect("model");
            let mut sim = Simulator::new(&m, 1000 + seed);
            let mut inc = vec![0.0; (minutes * 60.0 / tau0) as usize];
            sim.fill_channel(0, &mut inc);
            let mut ev = GapEvidence::from_increments(GapConfig::new(tau0), &inc);
            let Ok(d) = diagnose(&ev.snapshot(), &DiagnoseOptions::default()) else {
                continue;
            };
            let rec = DiagnosisRecord::new("g", &d, None, true);
            let Some(e) = rec.effects.iter().find(|e| e.effect.kind_name() == kind) else {
                continue;
            };
            named += 1;
            for (i, (name, t)) in truth.iter().enumerate() {
                if let Some([lo, hi]) = e.intervals.get(*name) {
                    if lo <= t && t <= hi {
                        covered[i] += 1;
                    }
                    widths[i].push((hi / lo).ln() / 2.0);
                }
            }
        }
        let parts: Vec<String> = truth
            .iter()
            .enumerate()
            .map(|(i, (name, _))| {
                let mut w = widths[i].clone();
                w.sort_by(f64::total_cmp);
                let med = w.get(w.len() / 2).copied().unwrap_or(f64::NAN);
                format!(
                    "{name}: covered {}/{seeds} ({:.0}%), median half-width {:.1}%",
                    covered[i],
                    100.0 * covered[i] as f64 / seeds as f64,
                    100.0 * (med.exp() - 1.0)
                )
            })
            .collect();
        println!("{kind}: named {named}/{seeds}; {}", parts.join("; "));
    }
}
