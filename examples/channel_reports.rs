//! A program embedding the analysis reads its results as structs, not JSON lines: ten minutes of
//! a simulated VOG4-like gyro (config/models/vog4.toml's N, B, K at 250 Hz, with a 0.8 Hz
//! sinusoid) go through [`RunAnalysis`], and the program takes each channel's
//! [`ChannelReport`]: the AVAR curve, the fitted N and B with their 95% intervals, the ARW
//! read-out, and what the diagnosis names. The same reports are what the record writer turns
//! into the JSON lines (`ChannelReport::records`).
//!
//! ```text
//! cargo run --release --example channel_reports
//! ```

use std::path::Path;

use allanscope::allan::accum::AccumConfig;
use allanscope::allan::Stat;
use allanscope::analysis::{AnalysisOptions, ChannelReport, ChannelSetup, InputKind, RunAnalysis};
use allanscope::input::Chunk;
use allanscope::model::fit::FitOptions;
use allanscope::sim::{SimModel, Simulator};

const TAU0_S: f64 = 0.004;

fn main() {
    let model = "tau0_s = 0.004\n[[channel]]\nname = \"g4\"\nunit = \"arcsec\"\nlsb = 0.0005\n\
                 N = 0.254\nB = 0.225\nK = 1.826e-2\nflicker_band_s = [0.004, 1.0e5]\n\
                 sinusoid = { amplitude = 0.3, frequency = 0.8, phase = 0.0 }\n";
    let m = SimModel::from_toml_str(model, Path::new("<example>")).expect("model");
    let mut inc = vec![0.0; (600.0 / TAU0_S) as usize];
    Simulator::new(&m, 7).fill_channel(0, &mut inc);

    let opts = AnalysisOptions {
        accum: AccumConfig::new(TAU0_S),
        kind: InputKind::Increments,
        every_s: None,
        fit: Some(FitOptions::default()),
        run: None,
        limits: Vec::new(),
        diagnose: true,
    };
    let setups = ChannelSetup::for_text(&["g4".to_string()], "arcsec");
    let mut run = RunAnalysis::new("simulated", setups, opts);
    // Interim records (none here: no `every_s`) would land in `interim`.
    let mut interim = Vec::new();
    run.push_chunk(
        &Chunk::Rows {
            values: inc,
            width: 1,
        },
        &mut interim,
    );
    for report in run.reports(true) {
        show(&report);
    }
}

fn show(r: &ChannelReport) {
    println!("{} [{}], {:.0} s of data", r.channel, r.unit, r.t_data_s);
    if let Some(avar) = r.curve(Stat::Avar) {
        let p = &avar.points;
        println!(
            "  AVAR: {} taus, sigma({:.3} s) = {:.4} {u}/s",
            p.len(),
            p[0].tau_s,
            p[0].sigma(),
            u = r.unit
        );
    }
    if let Some(f) = &r.fit {
        for (i, name) in [(1, "N"), (2, "B")] {
            let c = &f.coef[i];
            println!(
                "  {name} = {:.4} [{:.4}, {:.4}]{}",
                c.value,
                c.lo,
                c.hi,
                if c.determined {
                    ""
                } else {
                    " (not determined)"
                }
            );
        }
    }
    if let Some(arw) = r.readouts.as_ref().and_then(|x| x.arw) {
        println!("  ARW read-out at 1 s: {:.4}", arw.value);
    }
    if let Some(d) = &r.diagnosis {
        let kinds: Vec<&str> = d.effects.iter().map(|e| e.params.kind().name()).collect();
        println!(
            "  diagnosis: {:?}, gap {:.2} -> {:.2}, effects {kinds:?}",
            d.verdict, d.gap_before, d.gap_after
        );
    }
    println!("  as JSON lines: {} records", r.records().len());
}
