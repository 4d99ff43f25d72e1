//! The temperature effect over many seeds (docs/gap.md, "Temperature"): a VOG4-like gyro whose
//! temperature settles from 20 to 40 degC (time constant `--tc`) while a chamber cycles it
//! (`--sine-amp` degC every `--sine-period` s, default 5 degC every 1200 s),
//! a known coefficient; each run is simulated, diagnosed with its temperature, and the named
//! coefficient, its interval and `z` are written one row per run. With `--coef 0` the same runs
//! are clean (no temperature-driven bias): the false alarms of the temperature test.
//!
//!     cargo run --release --example temperature_study -- --seeds 50 --coef 0.05 --hours 2
//!     cargo run --release --example temperature_study -- --seeds 200 --coef 0 --hours 2
//!
//! Options: `--seeds N` (runs, seeds 1..=N), `--first S` (first seed), `--coef C` (arcsec/s per
//! degC), `--hours H`, `--tc S` (temperature time constant), `--sine-amp C`, `--sine-period S`,
//! `--threads T`, `--csv FILE`.

use std::io::Write;

use allanscope::gap::diagnose::diagnose_with_temperature;
use allanscope::gap::problem::{GapProblem, ModelSpec};
use allanscope::gap::temperature::{enter_temperature, fit_temperature};
use allanscope::gap::{DiagnoseOptions, EffectParams, GapConfig, GapEvidence, Verdict};
use allanscope::sim::{SimModel, Simulator};

struct Row {
    seed: u64,
    named: bool,
    coefficient: f64,
    lo: f64,
    hi: f64,
    verdict: Verdict,
    kinds: String,
    z: f64,
    /// `z` once the coefficient is refitted with its AVAR in the curve's model, as the
    /// diagnosis judges it (`enter_temperature` with no threshold).
    z_settled: f64,
}

fn arg(args: &[String], key: &str, default: &str) -> String {
    args.iter()
        .position(|a| a == key)
        .and_then(|i| args.get(i + 1).cloned())
        .unwrap_or_else(|| default.to_string())
}

fn model(coef: f64, tc: f64, amp: f64, period: f64) -> SimModel {
    let text = format!(
        "tau0_s = 0.004\n[temperature]\nstart_c = 20.0\nfinal_c = 40.0\ntime_constant_s = {tc}\n\
         sine_amplitude_c = {amp}\nsine_period_s = {period}\n[[channel]]\nname = \"g\"\n\
         unit = \"arcsec\"\nlsb = 0.004\nbias = 15.0\nN = 0.254\nB = 0.225\nK = 1.826e-2\n\
         flicker_band_s = [0.004, 1.0e4]\ntemperature_coefficient = {coef}\n"
    );
    // A zero coefficient needs no profile check; the profile is still simulated and recorded.
    SimModel::from_toml_str(&text, std::path::Path::new("study.toml")).expect("study model")
}

fn run(m: &SimModel, seed: u64, steps: u64) -> Row {
    let cfg = GapConfig::new(m.tau0_s);
    let mut ch = GapEvidence::new(cfg.clone());
    let mut te = GapEvidence::new(cfg);
    let mut sim = Simulator::new(m, seed);
    for _ in 0..steps {
        let s = sim.next_step();
        ch.push_increment(s.increments[0]);
        // As the CSV writer prints it: three decimals.
        let t = (s.temperature_c.unwrap_or(f64::NAN) * 1000.0).round() / 1000.0;
        te.push_increment(t * m.tau0_s);
    }
    let (a, b) = (ch.snapshot(), te.snapshot());
    let d =
        diagnose_with_temperature(&a, Some(&b), &DiagnoseOptions::default()).expect("diagnosis");
    let t = d.effects.iter().find_map(|e| match e.params {
        EffectParams::Temperature {
            coefficient,
            lo,
            hi,
            ..
        } => Some((coefficient, lo, hi)),
        _ => None,
    });
    let (coefficient, lo, hi) = t.unwrap_or((f64::NAN, f64::NAN, f64::NAN));
    let kinds: Vec<&str> = d.effects.iter().map(|e| e.params.kind().name()).collect();
    Row {
        seed,
        named: t.is_some(),
        coefficient,
        lo,
        hi,
        verdict: d.verdict,
        kinds: kinds.join("+"),
        // The first-pass statistic on the base model's noise (what the threshold acts on).
        z: fit_temperature(
            &a.block_means,
            &b.block_means,
            a.block_len as f64 * m.tau0_s,
            &d.base_coef.map(|c| c * c),
            &[],
            &[],
        )
        .map_or(f64::NAN, |f| f.z),
        z_settled: settled_z(&a, &b),
    }
}

/// The temperature's `z` as the diagnosis judges it: refitted with its AVAR in the curve's
/// model until it settles, on the base model of the channel's own curve.
fn settled_z(
    a: &allanscope::gap::evidence::EvidenceSnapshot,
    b: &allanscope::gap::evidence::EvidenceSnapshot,
) -> f64 {
    let Ok(prob) = GapProblem::new(a, &DiagnoseOptions::default()) else {
        return f64::NAN;
    };
    prob.gls(&ModelSpec::default())
        .and_then(|base| enter_temperature(&prob, a, b, &base, 0.0))
        .map_or(f64::NAN, |(t, _)| t.finding.z)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let seeds: u64 = arg(&args, "--seeds", "50").parse().unwrap();
    let first: u64 = arg(&args, "--first", "1").parse().unwrap();
    let coef: f64 = arg(&args, "--coef", "0.05").parse().unwrap();
    let hours: f64 = arg(&args, "--hours", "2").parse().unwrap();
    let tc: f64 = arg(&args, "--tc", "1800").parse().unwrap();
    let threads: u64 = arg(&args, "--threads", "2").parse().unwrap();
    let csv = arg(&args, "--csv", "");
    let amp: f64 = arg(&args, "--sine-amp", "5").parse().unwrap();
    let period: f64 = arg(&args, "--sine-period", "1200").parse().unwrap();
    let m = model(coef, tc, amp, period);
    let steps = (hours * 3600.0 / m.tau0_s) as u64;
    let next = std::sync::atomic::AtomicU64::new(first);
    let rows = std::sync::Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..threads.max(1) {
            s.spawn(|| loop {
                let seed = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                if seed >= first + seeds {
                    break;
                }
                let r = run(&m, seed, steps);
                rows.lock().unwrap().push(r);
            });
        }
    });
    let mut rows = rows.into_inner().unwrap();
    rows.sort_by_key(|r| r.seed);
    if !csv.is_empty() {
        let mut f = std::fs::File::create(&csv).expect("csv");
        writeln!(
            f,
            "seed,named,coefficient,lo,hi,z,z_settled,verdict,effects"
        )
        .unwrap();
        for r in &rows {
            writeln!(
                f,
                "{},{},{},{},{},{},{},{:?},{}",
                r.seed, r.named, r.coefficient, r.lo, r.hi, r.z, r.z_settled, r.verdict, r.kinds
            )
            .unwrap();
        }
    }
    let n = rows.len();
    let named = rows.iter().filter(|r| r.named).count();
    let flagged = rows
        .iter()
        .filter(|r| r.verdict != Verdict::Consistent)
        .count();
    println!(
        "runs {n}, {hours} h, coefficient {coef}, temperature 20 -> 40 degC with time constant \
         {tc} s, sine {amp} degC every {period} s"
    );
    println!("temperature named: {named}/{n}; verdict not consistent: {flagged}/{n}");
    if coef != 0.0 {
        let mut errs: Vec<f64> = rows
            .iter()
            .filter(|r| r.named)
            .map(|r| (r.coefficient / coef - 1.0).abs())
            .collect();
        errs.sort_by(f64::total_cmp);
        let q = |p: f64| errs[((errs.len() as f64 - 1.0) * p).round() as usize];
        let within10 = errs.iter().filter(|e| **e <= 0.10).count();
        let covered = rows
            .iter()
            .filter(|r| r.named && r.lo <= coef && coef <= r.hi)
            .count();
        if !errs.is_empty() {
            println!(
                "relative error: median {:.4}, q90 {:.4}, max {:.4}; within 10%: {within10}/{named}",
                q(0.5),
                q(0.9),
                q(1.0)
            );
        }
        println!("95% interval covers the truth: {covered}/{n}");
    }
    let mut others: Vec<&str> = rows.iter().map(|r| r.kinds.as_str()).collect();
    others.sort();
    others.dedup();
    println!("effect lists seen: {others:?}");
    for (what, z) in [
        (
            "the first pass",
            rows.iter().map(|r| r.z).collect::<Vec<f64>>(),
        ),
        ("settled", rows.iter().map(|r| r.z_settled).collect()),
    ] {
        let mut az: Vec<f64> = z
            .iter()
            .map(|z| z.abs())
            .filter(|z| z.is_finite())
            .collect();
        az.sort_by(f64::total_cmp);
        if !az.is_empty() {
            let q = |p: f64| az[((az.len() as f64 - 1.0) * p).round() as usize];
            println!(
                "|z| of {what}: median {:.2}, q95 {:.2}, q99 {:.2}, max {:.2}",
                q(0.5),
                q(0.95),
                q(0.99),
                q(1.0)
            );
        }
    }
}
