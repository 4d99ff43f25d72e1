//! Blind benchmark of the sim-to-real diagnosis over the space of units (docs/gap.md,
//! "Families of units"), where examples/blind_gap.rs draws VOG4-like gyros only.
//!
//! Each draw picks a family, then its base five-term model with each term over a wide
//! (log-uniform) range, its sampling step, run length and the quantization that kind of unit
//! really does, simulates a capture with `allanscope::sim` and runs the diagnosis, which never
//! sees the draw. With `--effect gm`, a Gauss-Markov term of peak size `rho` (its ADEV over the
//! base model's at its peak, log-uniform in [0.3, 1.5]) and correlation time within the
//! curve's taus is added; without it, runs are clean and every verdict other than `consistent`
//! is a false alarm.
//!
//! Families (units: increments in the unit's angle or velocity; rates per second):
//! - `navfog`: navigation-grade FOG, ARW 0.001-0.005 deg/sqrt(h), flicker 0.001-0.01 deg/h
//!   dominating the floor, tiny K, a fine angle LSB (0.1-1 of the per-sample noise
//!   `N sqrt(tau0)`), 200-1000 Hz;
//! - `tacfog`: tactical FOG, ARW 0.01-0.1 deg/sqrt(h), flicker 0.05-0.5 deg/h, the same
//!   LSB rule, 200-1000 Hz;
//! - `vog4`: the seed paper's VOG4 (config/models/vog4.toml's N, B, K each scaled 0.5-2,
//!   LSB 0.004 arcsec), 250 Hz;
//! - `memsgyro`: MEMS gyro, ARW 0.1-1 deg/sqrt(h), flicker 2-20 deg/h, K 1-10 deg/h/sqrt(h),
//!   each *rate sample* rounded to an LSB of 0.1-1 of the sample's noise, 100-400 Hz;
//! - `ma4`: the seed paper's pendulous MA4 (config/models/ma4.toml's Q, N, B, K, R each scaled
//!   0.5-2; quantization of the count with carry, LSB 2.104e-4 m/s), 250 Hz: white phase noise
//!   dominates up to tens of seconds;
//! - `memsacc`: MEMS accelerometer, VRW 0.02-0.2 m/s/sqrt(h), flicker 20-200 ug, K 1e-5-1e-4
//!   m/s^2/sqrt(s), rate samples rounded as the MEMS gyro's, 100-1000 Hz.
//!
//! Run lengths are 1-3 h (log-uniform), one draw in ten 6-24 h at a sampling step raised so
//! that a run has at most 8 M samples (the benchmark's compute stays affordable).
//!
//! ```text
//! cargo run --release --example family_gap -- [--draws 60] [--seed 1] [--threads 2]
//!     [--families navfog,tacfog,vog4,memsgyro,ma4,memsacc] [--effect none|gm] [--csv FILE]
//! ```
//!
//! `--draws` is per family. Prints, per family, the verdicts and (clean runs) the false-alarm
//! share with the effects named, or (`--effect gm`) the detection share and the errors of the
//! named term's `tau_c` and `sigma`; `--csv` writes one row per draw.

use allanscope::gap::{
    diagnose, DiagnoseOptions, EffectKind, EffectParams, GapConfig, GapEvidence, Verdict,
};
use allanscope::model::terms;
use allanscope::sim::{SimModel, Simulator};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::path::Path;
use std::time::Instant;

const FAMILIES: [&str; 6] = ["navfog", "tacfog", "vog4", "memsgyro", "ma4", "memsacc"];
/// Most samples in one run (long runs get a coarser sampling step).
const MAX_SAMPLES: f64 = 8.0e6;

/// One drawn unit: the five terms `(Q, N, B, K, R)`, its LSBs and its timing.
#[derive(Debug, Clone, Copy)]
struct Unit {
    family: &'static str,
    c: [f64; 5],
    /// Quantization of the integrated signal, with carry (u); 0: none.
    lsb: f64,
    /// Rounding of each rate sample (u/s); 0: none.
    rate_lsb: f64,
    tau0: f64,
    t_run: f64,
}

impl Unit {
    /// The base model's ADEV (u/s) at `tau` (s), quantization included.
    fn adev(&self, tau: f64) -> f64 {
        let q2 = self.c[0] * self.c[0] + terms::quantization_q(self.lsb).powi(2);
        let nq2 = self.rate_lsb * self.rate_lsb * self.tau0 / 12.0;
        let n2 = self.c[1] * self.c[1] + nq2;
        terms::avar([q2.sqrt(), n2.sqrt(), self.c[2], self.c[3], self.c[4]], tau).sqrt()
    }
}

fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.random::<f64>() * (hi.ln() - lo.ln())).exp()
}

/// ARW in deg/sqrt(h) to N in deg/sqrt(s); flicker in deg/h to B in deg/s; RRW in
/// deg/h/sqrt(h) to K in deg/s/sqrt(s).
const ARW: f64 = 1.0 / 60.0;
const DEG_H: f64 = 1.0 / 3600.0;
const RRW: f64 = 1.0 / (3600.0 * 60.0);

fn draw_unit(rng: &mut Xoshiro256PlusPlus, family: &'static str) -> Unit {
    let long = rng.random::<f64>() < 0.1;
    let t_run = if long {
        log_uniform(rng, 6.0, 24.0) * 3600.0
    } else {
        log_uniform(rng, 1.0, 3.0) * 3600.0
    };
    let rate = |rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64| {
        let hz = log_uniform(rng, lo, hi).round();
        // At most MAX_SAMPLES samples.
        (1.0 / hz).max(t_run / MAX_SAMPLES)
    };
    let mut u = Unit {
        family,
        c: [0.0; 5],
        lsb: 0.0,
        rate_lsb: 0.0,
        tau0: 0.004,
        t_run,
    };
    match family {
        "navfog" | "tacfog" => {
            let (arw, flk, rrw) = if family == "navfog" {
                ((0.001, 0.005), (0.001, 0.01), (1e-4, 1e-3))
            } else {
                ((0.01, 0.1), (0.05, 0.5), (0.01, 0.1))
            };
            u.c[1] = log_uniform(rng, arw.0, arw.1) * ARW;
            u.c[2] = log_uniform(rng, flk.0, flk.1) * DEG_H;
            u.c[3] = log_uniform(rng, rrw.0, rrw.1) * RRW;
            u.tau0 = rate(rng, 200.0, 1000.0);
            // A fine LSB: 0.1-1 of the per-sample noise `N sqrt(tau0)` (an LSB far above it
            // makes the quantization error a slow, non-white wander; docs/gap.md).
            u.lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] * u.tau0.sqrt();
        }
        "vog4" => {
            u.c[1] = 0.254 * log_uniform(rng, 0.5, 2.0);
            u.c[2] = 0.225 * log_uniform(rng, 0.5, 2.0);
            u.c[3] = 1.826e-2 * log_uniform(rng, 0.5, 2.0);
            u.lsb = 0.004;
            u.tau0 = (0.004f64).max(t_run / MAX_SAMPLES);
        }
        "memsgyro" => {
            u.c[1] = log_uniform(rng, 0.1, 1.0) * ARW;
            u.c[2] = log_uniform(rng, 2.0, 20.0) * DEG_H;
            u.c[3] = log_uniform(rng, 1.0, 10.0) * RRW;
            u.tau0 = rate(rng, 100.0, 400.0);
            u.rate_lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] / u.tau0.sqrt();
        }
        "ma4" => {
            let f = |rng: &mut Xoshiro256PlusPlus| log_uniform(rng, 0.5, 2.0);
            u.c = [
                6.840e-4 * f(rng),
                2.811e-4 * f(rng),
                0.403e-4 * f(rng),
                2.228e-6 * f(rng),
                6.020e-8 * f(rng),
            ];
            u.lsb = 2.104e-4;
            u.tau0 = (0.004f64).max(t_run / MAX_SAMPLES);
        }
        "memsacc" => {
            u.c[1] = log_uniform(rng, 0.02, 0.2) / 60.0;
            u.c[2] = log_uniform(rng, 20.0, 200.0) * 9.81e-6;
            u.c[3] = log_uniform(rng, 1e-5, 1e-4);
            u.tau0 = rate(rng, 100.0, 1000.0);
            u.rate_lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] / u.tau0.sqrt();
        }
        _ => unreachable!("family list"),
    }
    u
}

/// A Gauss-Markov term of peak size `rho` (its ADEV at its peak `~1.89 tau_c` over the base
/// model's there), `tau_c` log-uniform between 20 tau0 and a thirtieth of the run.
fn draw_gm(rng: &mut Xoshiro256PlusPlus, u: &Unit) -> (EffectParams, f64) {
    let rho = log_uniform(rng, 0.3, 1.5);
    let tau_c = log_uniform(rng, 20.0 * u.tau0, u.t_run / 30.0);
    let tau_peak = 1.89 * tau_c;
    let unit_peak = terms::gauss_markov_avar(1.0, tau_c, tau_peak).sqrt();
    let sigma = rho * u.adev(tau_peak) / unit_peak;
    (
        EffectParams::GaussMarkov {
            sigma,
            tau_c_s: tau_c,
        },
        rho,
    )
}

fn model_toml(u: &Unit, gm: Option<EffectParams>) -> String {
    let mut s = format!(
        "tau0_s = {}\n[[channel]]\nname = \"x\"\nunit = \"u\"\nQ = {:e}\nN = {:e}\nB = {:e}\nK = {:e}\nR = {:e}\nflicker_band_s = [{}, {:e}]\n",
        u.tau0,
        u.c[0],
        u.c[1],
        u.c[2],
        u.c[3],
        u.c[4],
        u.tau0,
        10.0 * u.t_run
    );
    if u.lsb > 0.0 {
        s += &format!("lsb = {:e}\n", u.lsb);
    }
    if let Some(EffectParams::GaussMarkov { sigma, tau_c_s }) = gm {
        s += &format!("gauss_markov = {{ sigma = {sigma:e}, tau_c = {tau_c_s:e} }}\n");
    }
    s
}

struct Outcome {
    unit: Unit,
    truth: Option<(EffectParams, f64)>,
    verdict: Verdict,
    gap_before: f64,
    gap_after: f64,
    named: Vec<EffectParams>,
    secs: f64,
}

fn run_one(family: &'static str, i: u64, seed: u64, effect: bool) -> Outcome {
    let fam_ix = FAMILIES.iter().position(|f| *f == family).unwrap_or(0) as u64;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed * 1_000_003 + fam_ix * 100_003 + i);
    let unit = draw_unit(&mut rng, family);
    let truth = effect.then(|| draw_gm(&mut rng, &unit));
    let text = model_toml(&unit, truth.map(|t| t.0));
    let m = SimModel::from_toml_str(&text, Path::new("<family_gap>")).expect("model");
    let t = Instant::now();
    let mut sim = Simulator::new(&m, rng.random::<u64>());
    let n = (unit.t_run / unit.tau0) as usize;
    let mut inc = vec![0.0; n];
    sim.fill_channel(0, &mut inc);
    if unit.rate_lsb > 0.0 {
        // Each rate sample rounded to the rate LSB (what MEMS parts report).
        let step = unit.rate_lsb * unit.tau0;
        for v in inc.iter_mut() {
            *v = (*v / step).round() * step;
        }
    }
    let mut ev = GapEvidence::from_increments(GapConfig::new(unit.tau0), &inc);
    let d = diagnose(&ev.snapshot(), &DiagnoseOptions::default());
    let secs = t.elapsed().as_secs_f64();
    match d {
        Ok(d) => Outcome {
            unit,
            truth,
            verdict: d.verdict,
            gap_before: d.gap_before,
            gap_after: d.gap_after,
            named: d.effects.iter().map(|e| e.params).collect(),
            secs,
        },
        Err(e) => {
            eprintln!("{family} draw {i}: {e}");
            Outcome {
                unit,
                truth,
                verdict: Verdict::Unexplained,
                gap_before: f64::NAN,
                gap_after: f64::NAN,
                named: Vec::new(),
                secs,
            }
        }
    }
}

fn par_map<T: Send>(
    items: &[(&'static str, u64)],
    threads: usize,
    f: impl Fn(&'static str, u64) -> T + Sync,
) -> Vec<T> {
    let f = &f;
    let threads = threads.max(1);
    let mut out: Vec<(usize, T)> = std::thread::scope(|s| {
        let hs: Vec<_> = (0..threads)
            .map(|t| {
                s.spawn(move || {
                    items
                        .iter()
                        .enumerate()
                        .filter(|(k, _)| k % threads == t)
                        .map(|(k, &(fam, i))| (k, f(fam, i)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        hs.into_iter()
            .flat_map(|h| h.join().expect("thread"))
            .collect()
    });
    out.sort_by_key(|r| r.0);
    out.into_iter().map(|r| r.1).collect()
}

fn quantile(v: &[f64], p: f64) -> f64 {
    let mut v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let get = |k: &str, d: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1).cloned())
            .unwrap_or_else(|| d.to_string())
    };
    let draws: u64 = get("--draws", "60").parse().expect("--draws");
    let seed: u64 = get("--seed", "1").parse().expect("--seed");
    let threads: usize = get("--threads", "2").parse().expect("--threads");
    let effect = match get("--effect", "none").as_str() {
        "none" => false,
        "gm" => true,
        e => panic!("--effect {e}: none or gm"),
    };
    let fams_arg = get("--families", &FAMILIES.join(","));
    let fams: Vec<&'static str> = fams_arg
        .split(',')
        .map(|f| {
            *FAMILIES
                .iter()
                .find(|x| **x == f)
                .unwrap_or_else(|| panic!("--families: unknown {f}"))
        })
        .collect();
    let csv = get("--csv", "");
    let items: Vec<(&'static str, u64)> = fams
        .iter()
        .flat_map(|&f| (0..draws).map(move |i| (f, i)))
        .collect();
    let t = Instant::now();
    let res = par_map(&items, threads, |f, i| run_one(f, i, seed, effect));
    println!(
        "{} draws per family, seed {seed}, effect {}, {:.0} s wall",
        draws,
        if effect { "gm" } else { "none" },
        t.elapsed().as_secs_f64()
    );
    println!("family    runs  consistent  explained  unexplained  flagged%  G0 q50  G0 q95  named (count)  s/run q50  s/run max");
    for &f in &fams {
        let r: Vec<&Outcome> = res.iter().filter(|o| o.unit.family == f).collect();
        let count = |v: Verdict| r.iter().filter(|o| o.verdict == v).count();
        let flagged = r.len() - count(Verdict::Consistent);
        let g0: Vec<f64> = r.iter().map(|o| o.gap_before).collect();
        let mut named: Vec<(String, usize)> = Vec::new();
        for o in &r {
            for p in &o.named {
                let k = p.kind().name().to_string();
                match named.iter_mut().find(|x| x.0 == k) {
                    Some(x) => x.1 += 1,
                    None => named.push((k, 1)),
                }
            }
        }
        let secs: Vec<f64> = r.iter().map(|o| o.secs).collect();
        println!(
            "{f:<9} {:>4}  {:>10}  {:>9}  {:>11}  {:>7.1}%  {:>6.2}  {:>6.2}  {}  {:>9.2}  {:>9.2}",
            r.len(),
            count(Verdict::Consistent),
            count(Verdict::Explained),
            count(Verdict::Unexplained),
            100.0 * flagged as f64 / r.len().max(1) as f64,
            quantile(&g0, 0.5),
            quantile(&g0, 0.95),
            named
                .iter()
                .map(|(k, c)| format!("{k} {c}"))
                .collect::<Vec<_>>()
                .join(", "),
            quantile(&secs, 0.5),
            quantile(&secs, 1.0),
        );
        if effect {
            // Detection: a Gauss-Markov term named; its errors.
            let mut found = 0;
            let mut tau_err = Vec::new();
            let mut sig_err = Vec::new();
            for o in &r {
                let Some((EffectParams::GaussMarkov { sigma, tau_c_s }, _)) = o.truth else {
                    continue;
                };
                if let Some(EffectParams::GaussMarkov {
                    sigma: s2,
                    tau_c_s: t2,
                }) = o
                    .named
                    .iter()
                    .find(|p| p.kind() == EffectKind::GaussMarkov)
                    .copied()
                {
                    found += 1;
                    tau_err.push((t2 / tau_c_s).ln().abs());
                    sig_err.push((s2 / sigma).ln().abs());
                }
            }
            println!(
                "          gauss_markov named in {found}/{} ({:.1}%); |ln tau_c error| q50 {:.2} q90 {:.2}; |ln sigma error| q50 {:.2} q90 {:.2}",
                r.len(),
                100.0 * found as f64 / r.len().max(1) as f64,
                quantile(&tau_err, 0.5),
                quantile(&tau_err, 0.9),
                quantile(&sig_err, 0.5),
                quantile(&sig_err, 0.9)
            );
        }
    }
    if !csv.is_empty() {
        let mut text = String::from("family,draw,tau0,t_run,q,n,b,k,r,lsb,rate_lsb,rho,verdict,gap_before,gap_after,named,secs\n");
        for (o, (_, i)) in res.iter().zip(&items) {
            let u = &o.unit;
            text += &format!(
                "{},{},{},{:.0},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:.3},{:?},{:.4},{:.4},{},{:.3}\n",
                u.family,
                i,
                u.tau0,
                u.t_run,
                u.c[0],
                u.c[1],
                u.c[2],
                u.c[3],
                u.c[4],
                u.lsb,
                u.rate_lsb,
                o.truth.map_or(0.0, |t| t.1),
                o.verdict,
                o.gap_before,
                o.gap_after,
                o.named
                    .iter()
                    .map(|p| p.kind().name())
                    .collect::<Vec<_>>()
                    .join("+"),
                o.secs
            );
        }
        std::fs::write(&csv, text).expect("csv");
    }
}
