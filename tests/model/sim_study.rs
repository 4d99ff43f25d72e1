//! Proof by simulation (the noise-model issue): runs of the seed paper's MA4 and VOG4 means
//! (config/models/ma4.toml, vog4.toml; tau0 = 4 ms) through the real pipeline (the simulator, the
//! streaming accumulator in bounded mode at the default L, `build_curves` with the two-pass noise
//! type of src/analysis.rs), then the fit. The truth is the model file's coefficients, Q being
//! the total white phase: `sqrt(Q_file^2 + LSB^2 / 12)` (quantization with carry,
//! docs/theory.md section 2).
//!
//! - `sim_study_ci`: 40 seeds of 3-hour runs per model, asserting the bias of each determined
//!   coefficient, its 95% coverage and the gof mean, with tolerances set by the seed count.
//! - `sim_study_full` (ignored): 200 seeds per model, the four methods side by side; prints the
//!   tables of docs/fit.md. `cargo test --release --test model -- sim_study:: --ignored --nocapture`.
#![allow(clippy::needless_range_loop)]

use std::path::Path;

use allanscope::allan::accum::{AccumConfig, ChannelAccumulator, StatSet};
use allanscope::allan::curve::{build_curves, AlphaSource};
use allanscope::allan::{CurvePoint, Stat};
use allanscope::model::fit::{CoefEstimate, FitMethod, FitOptions, FitResult, Fitter};
use allanscope::model::terms::{basis, TERM_NAMES};
use allanscope::sim::{SimModel, Simulator};

/// Seed paper's run length: 3 hours (the seed paper, docs/theory.md section 6).
const DURATION_S: f64 = 3.0 * 3600.0;
/// Seeds of the CI test: coverage of a 95% interval over 40 seeds has a binomial sd of 3.4%, so
/// 85% is three sds below; the bias allowance is 5% plus three standard errors of the mean
/// (sample sd / sqrt(runs determined)).
const CI_SEEDS: u64 = 40;
/// Every term, determined or not: the test-inverted intervals cover 91.5-98% over 200 seeds
/// (docs/fit.md).
const CI_COVERAGE_MIN: f64 = 0.85;
/// ... and at most this often (a 95% interval that always covers is too wide to be honest): 40
/// of 40 is allowed, but an interval the width of the curve's own bound would show as 100% for
/// every term.
const CI_COVERAGE_ALL_MAX_TERMS: usize = 3;
/// Terms determined in fewer than half the seeds (MA4's K and R, VOG4's R, 0-14% of 200 seeds
/// with the quantitation condition): at most this fraction of the seeds.
const CI_WEAK_DETERMINED_MAX: f64 = 0.25;
const BIAS_TOL: f64 = 0.05;
/// gof's mean over 40 seeds: its sd per run is about sqrt(2 / (J - p)) ~ 0.35 (J ~ 20 taus), so
/// the mean is within 0.2 of 1 at more than three standard errors.
const CI_GOF_MEAN_TOL: f64 = 0.2;
/// The power-law exponent given to the edf for each dominant term (as src/analysis.rs does).
const TERM_ALPHA: [i32; 5] = [2, 0, -1, -2, -2];

struct Study {
    name: &'static str,
    model: SimModel,
    truth: [f64; 5],
}

fn study(file: &str, name: &'static str) -> Study {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("config/models")
        .join(file);
    let model = SimModel::load(&path).expect("model file");
    let c = &model.channels[0];
    let q_quant = c.lsb.map_or(0.0, |l| l / 12f64.sqrt());
    let truth = [(c.q * c.q + q_quant * q_quant).sqrt(), c.n, c.b, c.k, c.r];
    Study { name, model, truth }
}

/// One run through the pipeline: the AVAR curve with the noise type of the fitted model's
/// dominant term at each tau (src/analysis.rs' second pass), and the default fit.
fn simulate_curve(st: &Study, seed: u64, duration_s: f64) -> Vec<CurvePoint> {
    let tau0 = st.model.tau0_s;
    let mut cfg = AccumConfig::new(tau0);
    cfg.stats = StatSet::only(Stat::Avar);
    let mut acc = ChannelAccumulator::real(cfg);
    let mut sim = Simulator::new(&st.model, seed);
    let steps = (duration_s / tau0).round() as u64;
    if let ChannelAccumulator::Real(e) = &mut acc {
        for _ in 0..steps {
            e.push_increment(sim.next_step().increments[0]);
        }
    }
    let readings = acc.read();
    let (n, t) = (acc.phase_points(), acc.t_data_s());
    let stats = StatSet::only(Stat::Avar);
    let first_curve = build_curves(&readings, stats, tau0, n, t, AlphaSource::Lag1);
    let first = Fitter::new()
        .fit(&first_curve[0].points, &FitOptions::default())
        .expect("first fit");
    let alphas: Vec<i32> = readings
        .iter()
        .map(|r| {
            let b = basis(r.tau_s);
            let i = (0..5)
                .max_by(|&i, &j| (b[i] * first.c[i]).total_cmp(&(b[j] * first.c[j])))
                .unwrap_or(1);
            TERM_ALPHA[i]
        })
        .collect();
    build_curves(&readings, stats, tau0, n, t, AlphaSource::Given(&alphas))
        .remove(0)
        .points
}

/// The curve of one seed; with `SIM_STUDY_CACHE=DIR` set, curves are read from (or written to)
/// `DIR/NAME-SEED.txt`, so that changes to the fit can be studied without re-simulating.
fn cached_curve(st: &Study, seed: u64) -> Vec<CurvePoint> {
    let Some(dir) = std::env::var_os("SIM_STUDY_CACHE") else {
        return simulate_curve(st, seed, DURATION_S);
    };
    let path = Path::new(&dir).join(format!("{}-{seed}.txt", st.name));
    if let Ok(text) = std::fs::read_to_string(&path) {
        let pts: Option<Vec<CurvePoint>> = text
            .lines()
            .map(|l| {
                let f: Vec<&str> = l.split_whitespace().collect();
                (f.len() == 10).then_some(())?;
                Some(CurvePoint {
                    m: f[0].parse().ok()?,
                    tau_s: f[1].parse().ok()?,
                    var: f[2].parse().ok()?,
                    count: f[3].parse().ok()?,
                    edf: f[4].parse().ok()?,
                    alpha: f[5].parse().ok()?,
                    sigma_lo: f[6].parse().ok()?,
                    sigma_hi: f[7].parse().ok()?,
                    stride: f[8].parse().ok()?,
                    n_phase: f[9].parse().ok()?,
                })
            })
            .collect();
        if let Some(pts) = pts.filter(|p| !p.is_empty()) {
            return pts;
        }
    }
    let pts = simulate_curve(st, seed, DURATION_S);
    let text: String = pts
        .iter()
        .map(|p| {
            format!(
                "{} {} {} {} {} {} {} {} {} {}\n",
                p.m,
                p.tau_s,
                p.var,
                p.count,
                p.edf,
                p.alpha,
                p.sigma_lo,
                p.sigma_hi,
                p.stride,
                p.n_phase
            )
        })
        .collect();
    std::fs::create_dir_all(&dir).expect("cache dir");
    std::fs::write(&path, text).expect("cache write");
    pts
}

#[derive(Default, Clone)]
struct Tally {
    runs: usize,
    det: [usize; 5],
    /// Sums of value / truth over determined runs, and of its square.
    sum: [f64; 5],
    sum2: [f64; 5],
    /// Over all runs (determined or not): relative error squared, and the squared coefficient
    /// `c = value^2` over its truth (the quantity the fit is linear in).
    sq_all: [f64; 5],
    c_all: [f64; 5],
    covered: [usize; 5],
    /// Per rule of `determined` (see [`RULES`]): runs determined, and sums of value / truth and
    /// its square over them, and how often their interval covers the truth.
    rule_det: [[usize; 5]; RULES.len()],
    rule_sum: [[f64; 5]; RULES.len()],
    rule_sum2: [[f64; 5]; RULES.len()],
    rule_cov: [[usize; 5]; RULES.len()],
    gof: Vec<f64>,
    dof: Vec<f64>,
}

impl Tally {
    fn add(&mut self, f: &FitResult, truth: &[f64; 5]) {
        self.runs += 1;
        for i in 0..5 {
            let e = &f.coef[i];
            let r = e.value / truth[i];
            if e.determined {
                self.det[i] += 1;
                self.sum[i] += r;
                self.sum2[i] += r * r;
            }
            self.sq_all[i] += (r - 1.0) * (r - 1.0);
            self.c_all[i] += r * r;
            let covers = e.lo <= truth[i] && truth[i] <= e.hi;
            if covers {
                self.covered[i] += 1;
            }
            for (k, rule) in RULES.iter().enumerate() {
                if (rule.1)(e) {
                    self.rule_det[k][i] += 1;
                    self.rule_sum[k][i] += r;
                    self.rule_sum2[k][i] += r * r;
                    self.rule_cov[k][i] += usize::from(covers);
                }
            }
        }
        if f.gof.is_finite() {
            self.gof.push(f.gof);
            let p = f.c.iter().filter(|c| **c > 0.0).count();
            self.dof.push((f.n_points - p) as f64);
        }
    }

    fn bias(&self, i: usize) -> Option<f64> {
        (self.det[i] > 0).then(|| self.sum[i] / self.det[i] as f64 - 1.0)
    }

    /// Sample sd of value / truth over determined runs.
    fn sd(&self, i: usize) -> Option<f64> {
        let n = self.det[i] as f64;
        (self.det[i] > 1).then(|| {
            let m = self.sum[i] / n;
            ((self.sum2[i] - n * m * m) / (n - 1.0)).max(0.0).sqrt()
        })
    }

    fn coverage(&self, i: usize) -> f64 {
        self.covered[i] as f64 / self.runs as f64
    }

    /// Bias of the squared coefficient over all runs.
    fn c_bias(&self, i: usize) -> f64 {
        self.c_all[i] / self.runs as f64 - 1.0
    }

    fn rms_all(&self, i: usize) -> f64 {
        (self.sq_all[i] / self.runs as f64).sqrt()
    }

    fn gof_mean(&self) -> f64 {
        self.gof.iter().sum::<f64>() / self.gof.len().max(1) as f64
    }
}

type Rule = (&'static str, fn(&CoefEstimate) -> bool);

/// Readings of docs/theory.md section 2's `determined` compared in docs/fit.md ("Which terms are
/// determined"); the first is the fit's own.
const RULES: [Rule; 5] = [
    ("dominant, lower end >= value / 3 (the fit's rule)", |e| {
        e.determined
    }),
    ("dominant, interval excludes 0", |e| {
        e.dominant && e.lo > 0.0
    }),
    (
        "dominant, estimate > 1.96 sd at the fit (Wald; before)",
        |e| e.dominant && e.value * e.value > 1.959964 * e.sd_c,
    ),
    ("dominant at its lower end, interval excludes 0", |e| {
        e.dominant_at_lo && e.lo > 0.0
    }),
    ("dominant, lower end >= value / 2", |e| {
        e.dominant && e.lo > 0.0 && e.lo >= 0.5 * e.value
    }),
];

const METHODS: [FitMethod; 4] = [
    FitMethod::Model,
    FitMethod::Paper,
    FitMethod::Slopes,
    FitMethod::LogLog,
];

/// Runs `seeds` seeds (split over `threads`), every method on each curve.
fn run_study(st: &Study, seeds: std::ops::Range<u64>, threads: usize) -> Vec<Tally> {
    let seeds: Vec<u64> = seeds.collect();
    let chunks: Vec<Vec<u64>> = (0..threads)
        .map(|t| seeds.iter().copied().skip(t).step_by(threads).collect())
        .collect();
    let parts: Vec<Vec<Tally>> = std::thread::scope(|s| {
        let handles: Vec<_> = chunks
            .iter()
            .map(|chunk| {
                s.spawn(move || {
                    let mut tallies = vec![Tally::default(); METHODS.len()];
                    let mut fitter = Fitter::new();
                    for &seed in chunk {
                        let pts = cached_curve(st, seed);
                        for (k, m) in METHODS.iter().enumerate() {
                            let opts = FitOptions {
                                method: *m,
                                ..FitOptions::default()
                            };
                            let f = fitter.fit(&pts, &opts).expect("fit");
                            tallies[k].add(&f, &st.truth);
                        }
                    }
                    tallies
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("study thread"))
            .collect()
    });
    let mut out = vec![Tally::default(); METHODS.len()];
    for part in parts {
        for (o, p) in out.iter_mut().zip(part) {
            o.runs += p.runs;
            for i in 0..5 {
                o.det[i] += p.det[i];
                o.sum[i] += p.sum[i];
                o.sum2[i] += p.sum2[i];
                o.sq_all[i] += p.sq_all[i];
                o.c_all[i] += p.c_all[i];
                o.covered[i] += p.covered[i];
                for k in 0..RULES.len() {
                    o.rule_det[k][i] += p.rule_det[k][i];
                    o.rule_sum[k][i] += p.rule_sum[k][i];
                    o.rule_sum2[k][i] += p.rule_sum2[k][i];
                    o.rule_cov[k][i] += p.rule_cov[k][i];
                }
            }
            o.gof.extend(p.gof);
            o.dof.extend(p.dof);
        }
    }
    out
}

fn print_table(st: &Study, tallies: &[Tally]) {
    println!(
        "\n{} (truth Q..R = {:?}), {} seeds",
        st.name, st.truth, tallies[0].runs
    );
    println!(
        "| method | coef | determined | bias (determined) | sd (determined) | bias of c (all) \
         | rms error (all) | 95% coverage |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for (k, t) in tallies.iter().enumerate() {
        for i in 0..5 {
            let f = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{:+.1}%", 100.0 * v));
            println!(
                "| {} | {} | {}/{} | {} | {} | {:+.1}% | {:.1}% | {:.1}% |",
                METHODS[k].name(),
                TERM_NAMES[i],
                t.det[i],
                t.runs,
                f(t.bias(i)),
                t.sd(i).map_or("-".into(), |v| format!("{:.1}%", 100.0 * v)),
                100.0 * t.c_bias(i),
                100.0 * t.rms_all(i),
                100.0 * t.coverage(i)
            );
        }
    }
    let t = &tallies[0];
    let mut g = t.gof.clone();
    g.sort_by(f64::total_cmp);
    let q = |p: f64| g[((g.len() - 1) as f64 * p).round() as usize];
    let sd = (g.iter().map(|x| (x - t.gof_mean()).powi(2)).sum::<f64>()
        / (g.len().max(2) - 1) as f64)
        .sqrt();
    let dof = t.dof.iter().sum::<f64>() / t.dof.len().max(1) as f64;
    // Under the model gof ~ chi2(nu)/nu with nu = J - p: mean 1, sd sqrt(2/nu), and 5% above
    // the chi2 95% quantile.
    let nu = dof.round().max(1.0);
    let q95 = statrs::distribution::ChiSquared::new(nu)
        .map(|d| statrs::distribution::ContinuousCDF::inverse_cdf(&d, 0.95) / nu)
        .unwrap_or(f64::NAN);
    let above = g.iter().filter(|x| **x > q95).count() as f64 / g.len() as f64;
    println!(
        "gof (model): mean {:.3}, sd {:.3} (chi2/nu with nu = J - p = {:.1}: sd {:.3}), \
         quartiles {:.2} {:.2} {:.2}, 95th percentile {:.2} (chi2/nu: {:.2}), above it {:.1}%",
        t.gof_mean(),
        sd,
        dof,
        (2.0 / nu).sqrt(),
        q(0.25),
        q(0.5),
        q(0.75),
        q(0.95),
        q95,
        100.0 * above
    );
}

/// The rules of `determined` side by side (model method).
fn print_rules(t: &Tally) {
    println!("| rule | coef | determined | bias (det.) | sd (det.) | coverage (det.) |");
    println!("|---|---|---|---|---|---|");
    for (k, rule) in RULES.iter().enumerate() {
        for i in 0..5 {
            let n = t.rule_det[k][i];
            if n == 0 {
                println!(
                    "| {} | {} | 0/{} | - | - | - |",
                    rule.0, TERM_NAMES[i], t.runs
                );
                continue;
            }
            let m = t.rule_sum[k][i] / n as f64;
            let sd = if n > 1 {
                ((t.rule_sum2[k][i] - n as f64 * m * m) / (n as f64 - 1.0))
                    .max(0.0)
                    .sqrt()
            } else {
                f64::NAN
            };
            println!(
                "| {} | {} | {}/{} | {:+.1}% | {:.1}% | {:.1}% |",
                rule.0,
                TERM_NAMES[i],
                n,
                t.runs,
                100.0 * (m - 1.0),
                100.0 * sd,
                100.0 * t.rule_cov[k][i] as f64 / n as f64
            );
        }
    }
}

fn assert_model_method(st: &Study, t: &Tally) {
    let mut full = 0;
    for i in 0..5 {
        assert!(
            t.coverage(i) >= CI_COVERAGE_MIN,
            "{} {}: coverage {}",
            st.name,
            TERM_NAMES[i],
            t.coverage(i)
        );
        full += usize::from(t.covered[i] == t.runs);
        if t.det[i] < t.runs / 2 {
            // Rarely determined: the runs that determine it are the high draws (selection, not
            // the estimator: docs/fit.md), so no bias is asserted; the quantitation condition
            // must keep them rare.
            assert!(
                t.det[i] as f64 <= CI_WEAK_DETERMINED_MAX * t.runs as f64,
                "{} {}: determined in {} of {}",
                st.name,
                TERM_NAMES[i],
                t.det[i],
                t.runs
            );
            continue;
        }
        let bias = t.bias(i).unwrap_or(f64::NAN);
        let se = t.sd(i).unwrap_or(0.0) / (t.det[i] as f64).sqrt();
        assert!(
            bias.abs() <= BIAS_TOL + 3.0 * se,
            "{} {}: bias {bias} (se {se})",
            st.name,
            TERM_NAMES[i]
        );
    }
    assert!(
        full <= CI_COVERAGE_ALL_MAX_TERMS,
        "{}: {full} terms covered in every run",
        st.name
    );
    assert!(
        (t.gof_mean() - 1.0).abs() <= CI_GOF_MEAN_TOL,
        "{}: gof mean {}",
        st.name,
        t.gof_mean()
    );
}

#[test]
fn sim_study_ci() {
    for (file, name) in [("ma4.toml", "MA4"), ("vog4.toml", "VOG4")] {
        let st = study(file, name);
        let t = run_study(&st, 0..CI_SEEDS, 1);
        print_table(&st, &t[..1]);
        assert_model_method(&st, &t[0]);
    }
}

#[test]
#[ignore]
fn sim_study_full() {
    let seeds: u64 = std::env::var("SIM_STUDY_SEEDS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(200);
    for (file, name) in [("ma4.toml", "MA4"), ("vog4.toml", "VOG4")] {
        let st = study(file, name);
        let t0 = std::time::Instant::now();
        let t = run_study(&st, 1000..1000 + seeds, 2);
        println!(
            "{name}: {seeds} seeds in {:.1} s",
            t0.elapsed().as_secs_f64()
        );
        print_table(&st, &t);
        print_rules(&t[0]);
    }
}
