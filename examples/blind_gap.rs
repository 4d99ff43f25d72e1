//! Blind benchmark of the sim-to-real diagnosis (docs/gap.md).
//!
//! A generator draws a base five-term model (VOG4-like, each coefficient scaled by a
//! log-uniform factor) and a hidden effect (or none) with parameters from wide ranges, simulates
//! a capture with `allanscope::sim`, and runs the diagnosis, which never sees the draw.
//!
//! ```text
//! cargo run --release --example blind_gap -- [--draws 240] [--seed 1] [--duration 3600]
//!     [--tau0 0.004] [--threads 2] [--mode bench|calibrate|speed|one|oracle] [--csv FILE]
//!     [--scores] [--null-draws 400] [--null-seed 2]
//! ```
//!
//! `--mode calibrate` draws clean runs only and prints the null quantiles of the statistics the
//! thresholds are set from (and with `--csv`, each run's statistics); `--mode speed` times one
//! 3-hour 250 Hz channel. `--scores` adds the base model's per-candidate statistics to the
//! benchmark's CSV. `--mode oracle` runs the benchmark's Gauss-Markov, warm-up and jump draws
//! (the same draws as `bench`) and `--null-draws` clean runs of `--mode calibrate` with seed
//! `--null-seed`, and prints the oracle bounds of docs/gap.md ("Oracle bounds"): the power of
//! tests told the true effect, and Cramér-Rao bounds on its parameters (`allanscope::gap::oracle`).

mod common;

use allanscope::gap::jump_mixture::{
    jump_forward_mixture_log_bf, jump_forward_mixture_stat, jump_mixture_log_bf, jump_mixture_stat,
    JUMP_FWD_Z_MIN,
};
use allanscope::gap::oracle::{self, BlockGls};
use allanscope::gap::problem::{GapProblem, ModelSpec};
use allanscope::gap::steps::{forward_steps, step_scan, StepScan};
use allanscope::gap::warmup::fit_warmup;
use allanscope::gap::{
    diagnose, DiagnoseOptions, EffectKind, EffectParams, EvidenceSnapshot, GapConfig, GapEvidence,
};
use allanscope::model::terms;
use common::{
    draw_effect_params, draw_jumps, effect_toml, jumps_rms, log_uniform, par_map, quantile,
    simulate_channel, std_normal_cdf,
};
use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;
use std::time::Instant;

#[derive(Debug, Clone, Copy)]
struct Base {
    n: f64,
    b: f64,
    k: f64,
    lsb: f64,
}

impl Base {
    fn adev(&self, tau: f64) -> f64 {
        let q = terms::quantization_q(self.lsb);
        terms::avar([q, self.n, self.b, self.k, 0.0], tau).sqrt()
    }
}

#[derive(Debug, Clone, Copy)]
struct Draw {
    base: Base,
    effect: Option<EffectParams>,
    /// Peak effect ADEV over base ADEV at that tau, as drawn.
    rho: f64,
}

fn draw(rng: &mut Xoshiro256PlusPlus, kind: Option<EffectKind>, t_run: f64, tau0: f64) -> Draw {
    let base = Base {
        n: 0.254 * log_uniform(rng, 0.5, 2.0),
        b: 0.225 * log_uniform(rng, 0.5, 2.0),
        k: 1.826e-2 * log_uniform(rng, 0.5, 2.0),
        lsb: 0.004,
    };
    draw_effect(rng, base, kind, t_run, tau0)
}

/// The effect part of [`draw`] on a given base: `rho`, then the effect's parameters.
fn draw_effect(
    rng: &mut Xoshiro256PlusPlus,
    base: Base,
    kind: Option<EffectKind>,
    t_run: f64,
    tau0: f64,
) -> Draw {
    let rho = log_uniform(rng, 0.15, 3.0);
    let adev = |tau: f64| base.adev(tau);
    let effect = kind.map(|k| draw_effect_params(rng, k, rho, tau0, t_run, &adev, 32.0));
    Draw { base, effect, rho }
}

fn model_toml(d: &Draw, tau0: f64) -> String {
    let s = format!(
        "tau0_s = {tau0}\n[[channel]]\nname = \"g\"\nunit = \"arcsec\"\nlsb = {}\nN = {}\nB = {}\nK = {}\nflicker_band_s = [{}, 1.0e5]\n",
        d.base.lsb, d.base.n, d.base.b, d.base.k, tau0
    );
    s + &effect_toml(d.effect)
}

/// Simulates a draw (the jumps added by `common::simulate_channel`, the truth the realised
/// ones).
fn simulate(
    d: &Draw,
    tau0: f64,
    t_run: f64,
    seed: u64,
) -> (Vec<f64>, Option<EffectParams>, Vec<(f64, f64)>) {
    simulate_channel(&model_toml(d, tau0), "<blind>", tau0, t_run, d.effect, seed)
}

struct Outcome {
    truth: Option<EffectKind>,
    rho: f64,
    named: Option<EffectKind>,
    /// Every effect named, in order.
    all_named: Vec<EffectKind>,
    verdict: String,
    gap_before: f64,
    gap_after: f64,
    shape_err: f64,
    amp_err: f64,
    truth_params: Option<EffectParams>,
    found_params: Option<EffectParams>,
    /// With `--scores`: the base model's best drop of chi2 per parameter for each stationary
    /// candidate, the warm-up statistic and the three largest step z scores, then the mixture
    /// statistics (`MixScores`: warm-up `B`, jump mixture integrated / max / boundaries only,
    /// and the jump ceiling at the true count and rms) (NaN otherwise).
    scores: [f64; 15],
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b) / b
}

/// One benchmark draw, simulated: its effect kind, the draw (its effect the realised one), the
/// increments and the realised jumps.
struct Prepared {
    kind: Option<EffectKind>,
    d: Draw,
    inc: Vec<f64>,
    /// The realised jumps `(time s, size u/s)` of a jump draw.
    jumps: Vec<(f64, f64)>,
}

fn prepare(i: u64, seed: u64, tau0: f64, t_run: f64, kinds: &[Option<EffectKind>]) -> Prepared {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed.wrapping_mul(1_000_003).wrapping_add(i));
    let kind = kinds[(i as usize) % kinds.len()];
    let mut d = draw(&mut rng, kind, t_run, tau0);
    let (inc, truth, jumps) = simulate(&d, tau0, t_run, seed.wrapping_add(7919 * i));
    // Jumps: the size is that of the realised jumps (their rms over the nominal one).
    if let (
        Some(EffectParams::BiasJumps {
            rms_size: nominal, ..
        }),
        Some(EffectParams::BiasJumps { rms_size: real, .. }),
    ) = (d.effect, truth)
    {
        d.rho *= real / nominal;
    }
    d.effect = truth;
    Prepared {
        kind,
        d,
        inc,
        jumps,
    }
}

fn run_one(
    i: u64,
    seed: u64,
    tau0: f64,
    t_run: f64,
    kinds: &[Option<EffectKind>],
    with_scores: bool,
) -> Outcome {
    let p = prepare(i, seed, tau0, t_run, kinds);
    let mut ev = GapEvidence::from_increments(GapConfig::new(tau0), &p.inc);
    let snap = ev.snapshot();
    outcome(p.kind, &p.d, &snap, tau0, t_run, with_scores)
}

/// The diagnosis of one draw's evidence against its truth.
fn outcome(
    kind: Option<EffectKind>,
    d: &Draw,
    snap: &EvidenceSnapshot,
    tau0: f64,
    t_run: f64,
    with_scores: bool,
) -> Outcome {
    let diag = diagnose(snap, &DiagnoseOptions::default()).expect("diagnosis");
    let mut scores = [f64::NAN; 15];
    if with_scores {
        let b = base_scores(snap, tau0, t_run);
        scores[..3].copy_from_slice(&b.per_kind);
        scores[3] = b.w;
        for k in 0..3 {
            scores[4 + k] = b.jumps.get(k).copied().unwrap_or(0.0);
        }
        let truth = match d.effect {
            Some(EffectParams::BiasJumps { count, rms_size }) => Some((count as f64, rms_size)),
            _ => None,
        };
        scores[7..].copy_from_slice(&b.mix.row(truth));
    }
    let first = diag.effects.first().map(|e| e.params);
    let (mut shape_err, mut amp_err) = (f64::NAN, f64::NAN);
    if let (Some(t), Some(f)) = (
        d.effect,
        diag.effects.iter().find(|e| Some(e.params.kind()) == kind),
    ) {
        let f = f.params;
        match (t, f) {
            (
                EffectParams::BiasJumps { count, rms_size },
                EffectParams::BiasJumps {
                    count: c2,
                    rms_size: r2,
                },
            ) => {
                shape_err = rel(c2 as f64, count as f64);
                amp_err = rel(r2, rms_size);
            }
            _ => {
                shape_err = rel(f.shape(), t.shape());
                amp_err = rel(f.amplitude(), t.amplitude());
            }
        }
    }
    Outcome {
        truth: kind,
        rho: d.rho,
        named: first.map(|p| p.kind()),
        all_named: diag.effects.iter().map(|e| e.params.kind()).collect(),
        verdict: format!("{:?}", diag.verdict).to_lowercase(),
        gap_before: diag.gap_before,
        gap_after: diag.gap_after,
        shape_err,
        amp_err,
        truth_params: d.effect,
        found_params: first,
        scores,
    }
}

fn name(k: Option<EffectKind>) -> &'static str {
    k.map_or("none", |k| k.name())
}

/// One clean run's null statistics.
struct Null {
    g: f64,
    zmax: f64,
    /// Best drop of chi2 per parameter over all candidates, then per candidate
    /// (Gauss-Markov, sinusoid, output filter).
    best: f64,
    per_kind: Vec<f64>,
    /// z scores of the steps forward selection finds down to `JUMP_ZS[0]`, largest first.
    jumps: Vec<f64>,
    w: f64,
    flagged: bool,
    verdict_effects: String,
    /// [`MixScores::row`], the ceiling at a prior draw of the jumps.
    mix: [f64; 8],
}

/// Statistics of the base five-term model that the thresholds are set on: `G`, the largest
/// `|z|` over taus, each stationary candidate's drop of chi2 per parameter, the warm-up `W`, and
/// the z scores of the steps forward selection finds down to `JUMP_ZS[0]`, largest first.
struct BaseScores {
    g: f64,
    zmax: f64,
    per_kind: [f64; 3],
    w: f64,
    jumps: Vec<f64>,
    mix: MixScores,
}

/// The mixture statistics of the base model (docs/gap.md, "Mixture statistics").
struct MixScores {
    /// Warm-up: `ln mean_T exp(W(T) / 2)` over the scan.
    w_bf: f64,
    /// The first pass's single-step scan, for the jump mixtures.
    scan: Option<StepScan>,
    /// z scores of the forward search down to `JUMP_FWD_Z_MIN`.
    fwd: Vec<f64>,
    /// The block GLS of the base model, for the marginal-likelihood jump ceiling.
    gls: Option<BlockGls>,
}

/// Importance samples of the marginal-likelihood jump ceiling (`oracle::jumps_marginal_oracle`).
const JUMP_CEIL_SAMPLES: usize = 4000;

impl MixScores {
    /// `[w_bf, jump mixture (integrated), jump mixture (max over the grid), jump mixture
    /// (boundaries only, integrated), jump ceiling]`; the ceiling is the mixture at the given
    /// `(count, rms)` (NaN without one).
    fn row(&self, truth: Option<(f64, f64)>) -> [f64; 8] {
        let Some(scan) = &self.scan else {
            let mut out = [f64::NAN; 8];
            out[0] = self.w_bf;
            return out;
        };
        let mut se = scan.se.clone();
        se.sort_by(|a, b| a.total_cmp(b));
        let med = se[se.len() / 2];
        let npos = scan.z.len();
        [
            self.w_bf,
            jump_mixture_stat(scan, false, false),
            jump_mixture_stat(scan, false, true),
            jump_mixture_stat(scan, true, false),
            truth.map_or(f64::NAN, |(c, s)| jump_mixture_log_bf(scan, s, c, false)),
            jump_forward_mixture_stat(&self.fwd, npos),
            truth.map_or(f64::NAN, |(c, s)| {
                jump_forward_mixture_log_bf(&self.fwd, npos, s / med, c)
            }),
            match (truth, &self.gls) {
                (Some((c, s)), Some(g)) => {
                    oracle::jumps_marginal_oracle(g, c as usize, s, JUMP_CEIL_SAMPLES, 17)
                        .unwrap_or(f64::NAN)
                }
                _ => f64::NAN,
            },
        ]
    }
}

fn base_scores(snap: &EvidenceSnapshot, tau0: f64, t_run: f64) -> BaseScores {
    let opts = DiagnoseOptions::default();
    let prob = GapProblem::new(snap, &opts).expect("problem");
    let base = prob.gls(&ModelSpec::default()).expect("gls");
    let zmax = prob
        .z(&base.model)
        .iter()
        .fold(0.0f64, |a, z| a.max(z.abs()));
    let per_kind = [
        EffectKind::GaussMarkov,
        EffectKind::Sinusoid,
        EffectKind::OutputFilter,
    ]
    .map(|k| {
        prob.scan(&ModelSpec::default(), k)
            .map_or(0.0, |(_, f)| (base.chi2 - f.chi2) / k.n_params() as f64)
    });
    let c5: [f64; 5] = std::array::from_fn(|i| base.coef[i]);
    let block_s = snap.block_len as f64 * tau0;
    let wf = fit_warmup(&snap.block_means, block_s, t_run, &c5, &[]);
    let w = wf.map_or(0.0, |w| w.w_stat);
    let mix = MixScores {
        w_bf: wf.map_or(0.0, |w| w.log_bf),
        scan: step_scan(&snap.block_means, block_s, &c5, &[]),
        fwd: forward_steps(&snap.block_means, block_s, &c5, &[], JUMP_FWD_Z_MIN)
            .map_or(Vec::new(), |f| f.z_scores),
        gls: BlockGls::new(&snap.block_means, block_s, &c5),
    };
    let mut jumps = forward_steps(&snap.block_means, block_s, &c5, &[], JUMP_ZS[0])
        .map_or(Vec::new(), |f| f.z_scores);
    jumps.sort_by(|a, b| b.total_cmp(a));
    BaseScores {
        g: base.gap(),
        zmax,
        per_kind,
        w,
        jumps,
        mix,
    }
}

fn calibrate(i: u64, seed: u64, tau0: f64, t_run: f64) -> Null {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed.wrapping_mul(1_000_003).wrapping_add(i));
    let d = draw(&mut rng, None, t_run, tau0);
    let (inc, _, _) = simulate(&d, tau0, t_run, seed.wrapping_add(7919 * i));
    let mut ev = GapEvidence::from_increments(GapConfig::new(tau0), &inc);
    let snap = ev.snapshot();
    let opts = DiagnoseOptions::default();
    let BaseScores {
        g,
        zmax,
        per_kind,
        w,
        jumps,
        mix,
    } = base_scores(&snap, tau0, t_run);
    // The jump ceiling's null: a count and realised rms drawn from the benchmark's prior on
    // this base, from a stream of their own (the clean run is unchanged).
    let mut jrng =
        Xoshiro256PlusPlus::seed_from_u64(seed.wrapping_mul(1_000_003).wrapping_add(i) ^ 0x6a_c1e5);
    let dj = draw_effect(&mut jrng, d.base, Some(EffectKind::BiasJumps), t_run, tau0);
    let truth = match dj.effect {
        Some(EffectParams::BiasJumps { count, rms_size }) => {
            let js = draw_jumps(
                count,
                rms_size,
                t_run,
                seed.wrapping_add(7919 * i) ^ 0x6a_c1e5,
            );
            let rms = jumps_rms(&js);
            Some((count as f64, rms))
        }
        _ => None,
    };
    let mix = mix.row(truth);
    let best = per_kind.iter().fold(0.0f64, |a, &b| a.max(b));
    let diag = diagnose(&snap, &opts).expect("diag");
    let flagged = diag.verdict != allanscope::gap::Verdict::Consistent;
    let verdict_effects = diag
        .effects
        .iter()
        .map(|e| e.params.kind().name())
        .collect::<Vec<_>>()
        .join("+");
    Null {
        g,
        zmax,
        best,
        per_kind: per_kind.to_vec(),
        jumps,
        w,
        flagged,
        verdict_effects,
        mix,
    }
}

/// Step-detector thresholds whose null rates `--mode calibrate` prints (the first is also the
/// lowest z the selection goes down to).
const JUMP_ZS: [f64; 6] = [3.25, 3.5, 3.75, 4.0, 4.25, 4.5];

fn quantiles(mut v: Vec<f64>) -> String {
    v.sort_by(|a, b| a.total_cmp(b));
    let q = |p: f64| v[((v.len() as f64 - 1.0) * p).round() as usize];
    format!(
        "median {:.3} q90 {:.3} q95 {:.3} q99 {:.3} max {:.3}",
        q(0.5),
        q(0.9),
        q(0.95),
        q(0.99),
        q(1.0)
    )
}

/// Oracle statistics of one run for one effect, told the effect's true parameters (docs/gap.md,
/// "Oracle bounds"; `allanscope::gap::oracle`).
#[derive(Debug, Clone, Copy)]
struct OracleStat {
    /// Shape known, amplitude(s) fitted: the Gauss-Markov drop of chi2 at the true `tau_c`, the
    /// warm-up `W` at the true `T`, the jumps' chi2 with steps at the true times.
    fitted: f64,
    /// Its nominal degrees of freedom (1, 1, the jump count).
    dof: f64,
    /// Everything known: `z` and its noncentrality `delta` (model covariance, as the diagnosis).
    z: f64,
    delta: f64,
    /// Gauss-Markov: the drop with the amplitude fixed at the truth. Block effects: `fitted`
    /// with the covariance of the true five terms.
    alt: f64,
    /// Block effects: `z`, `delta` with the true five terms' covariance (NaN for Gauss-Markov).
    z_true: f64,
    delta_true: f64,
    /// Cramér-Rao sd of the log shape (`ln tau_c`, `ln T`; NaN for jumps) and log amplitude
    /// (`ln sigma`, `ln A`): Gauss-Markov with R known (0), warm-up with the true covariance.
    crb_shape: f64,
    crb_amp: f64,
    /// The same shape bound in the other setting: Gauss-Markov with R free, warm-up with the
    /// fitted covariance.
    crb_shape_alt: f64,
}

impl OracleStat {
    fn nan() -> Self {
        Self {
            fitted: f64::NAN,
            dof: f64::NAN,
            z: f64::NAN,
            delta: f64::NAN,
            alt: f64::NAN,
            z_true: f64::NAN,
            delta_true: f64::NAN,
            crb_shape: f64::NAN,
            crb_amp: f64::NAN,
            crb_shape_alt: f64::NAN,
        }
    }

    /// Upper-tail probability of `fitted` under its nominal chi-squared law (a monotone map
    /// per dof, so that runs with different jump counts share one threshold).
    fn p_fitted(&self) -> f64 {
        use statrs::distribution::{ChiSquared, ContinuousCDF};
        if self.dof.is_nan() || self.dof <= 0.0 || !self.fitted.is_finite() {
            return f64::NAN;
        }
        ChiSquared::new(self.dof).map_or(f64::NAN, |c| 1.0 - c.cdf(self.fitted.max(0.0)))
    }
}

/// The oracle statistics of `snap` for the effect `truth` (with the realised `jumps`), on a run
/// whose true base is `base`.
fn oracle_stats(
    truth: EffectParams,
    jumps: &[(f64, f64)],
    base: &Base,
    snap: &EvidenceSnapshot,
    tau0: f64,
) -> OracleStat {
    let mut o = OracleStat::nan();
    let opts = DiagnoseOptions::default();
    let Ok(prob) = GapProblem::new(snap, &opts) else {
        return o;
    };
    let Some(base_fit) = prob.gls(&ModelSpec::default()) else {
        return o;
    };
    let c_fit: [f64; 5] = std::array::from_fn(|i| base_fit.coef[i]);
    let q = terms::quantization_q(base.lsb);
    let c_true = [
        q * q,
        base.n * base.n,
        base.b * base.b,
        base.k * base.k,
        0.0,
    ];
    let block_s = snap.block_len as f64 * tau0;
    let gls_fit = BlockGls::new(&snap.block_means, block_s, &c_fit);
    let gls_true = BlockGls::new(&snap.block_means, block_s, &c_true);
    match truth {
        EffectParams::GaussMarkov { sigma, tau_c_s } => {
            if let Some(g) = oracle::gm_oracle(&prob, sigma, tau_c_s) {
                o.fitted = g.drop_fitted;
                o.dof = 1.0;
                o.z = g.z_known;
                o.delta = g.delta;
                o.alt = g.drop_fixed;
            }
            let r_known = [true, true, true, true, false];
            if let Some(c) = oracle::gm_curve_crb(&prob, &c_true, sigma, tau_c_s, r_known) {
                o.crb_shape = c.sd_ln_tau_c;
                o.crb_amp = c.sd_ln_sigma;
            }
            if let Some(c) = oracle::gm_curve_crb(&prob, &c_true, sigma, tau_c_s, [true; 5]) {
                o.crb_shape_alt = c.sd_ln_tau_c;
            }
        }
        EffectParams::Warmup {
            amplitude,
            time_constant_s,
        } => {
            if let Some(g) = &gls_fit {
                let (w, z, delta) = oracle::warmup_oracle(g, amplitude, time_constant_s);
                (o.fitted, o.dof, o.z, o.delta) = (w, 1.0, z, delta);
                if let Some(c) = oracle::warmup_crb(g, amplitude, time_constant_s) {
                    o.crb_shape_alt = c.sd_ln_t;
                }
            }
            if let Some(g) = &gls_true {
                let (w, z, delta) = oracle::warmup_oracle(g, amplitude, time_constant_s);
                (o.alt, o.z_true, o.delta_true) = (w, z, delta);
                if let Some(c) = oracle::warmup_crb(g, amplitude, time_constant_s) {
                    o.crb_shape = c.sd_ln_t;
                    o.crb_amp = c.sd_ln_a;
                }
            }
        }
        EffectParams::BiasJumps { .. } => {
            if let Some(g) = &gls_fit {
                let (chi2, z, delta) = oracle::jumps_oracle(g, jumps);
                (o.fitted, o.dof, o.z, o.delta) = (chi2, jumps.len() as f64, z, delta);
            }
            if let Some(g) = &gls_true {
                let (chi2, z, delta) = oracle::jumps_oracle(g, jumps);
                (o.alt, o.z_true, o.delta_true) = (chi2, z, delta);
            }
        }
        _ => {}
    }
    o
}

/// One effect draw of the benchmark (the same generator and seeds as `--mode bench`): the
/// diagnosis's outcome and the oracle statistics at the truth.
fn oracle_effect(
    i: u64,
    seed: u64,
    tau0: f64,
    t_run: f64,
    kinds: &[Option<EffectKind>],
) -> (Outcome, OracleStat) {
    let p = prepare(i, seed, tau0, t_run, kinds);
    let mut ev = GapEvidence::from_increments(GapConfig::new(tau0), &p.inc);
    let snap = ev.snapshot();
    let out = outcome(p.kind, &p.d, &snap, tau0, t_run, true);
    let o = match p.d.effect {
        Some(t) => oracle_stats(t, &p.jumps, &p.d.base, &snap, tau0),
        None => OracleStat::nan(),
    };
    (out, o)
}

/// One clean run of `--mode calibrate` (same base and simulation seed) with the oracle
/// statistics of a Gauss-Markov term, a warm-up and jumps whose parameters are drawn from the
/// benchmark's priors on that base (the jumps' times and sizes from their own stream): the null
/// distributions of the oracle statistics, and the diagnosis's own base statistics (Gauss-Markov
/// drop per parameter, scanned `W`, largest step z: [`base_scores`]).
fn oracle_null(i: u64, seed: u64, tau0: f64, t_run: f64) -> ([OracleStat; 3], [f64; 3]) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed.wrapping_mul(1_000_003).wrapping_add(i));
    let d_gm = draw(&mut rng, Some(EffectKind::GaussMarkov), t_run, tau0);
    let d_w = draw_effect(&mut rng, d_gm.base, Some(EffectKind::Warmup), t_run, tau0);
    let d_j = draw_effect(
        &mut rng,
        d_gm.base,
        Some(EffectKind::BiasJumps),
        t_run,
        tau0,
    );
    let clean = Draw {
        base: d_gm.base,
        effect: None,
        rho: 0.0,
    };
    let sim_seed = seed.wrapping_add(7919 * i);
    let (inc, _, _) = simulate(&clean, tau0, t_run, sim_seed);
    let mut ev = GapEvidence::from_increments(GapConfig::new(tau0), &inc);
    let snap = ev.snapshot();
    let jumps = match d_j.effect {
        Some(EffectParams::BiasJumps { count, rms_size }) => {
            draw_jumps(count, rms_size, t_run, sim_seed ^ 0x00ac_1e5e_u64)
        }
        _ => Vec::new(),
    };
    let b = base_scores(&snap, tau0, t_run);
    let own = [b.per_kind[0], b.w, b.jumps.first().copied().unwrap_or(0.0)];
    let stats = [d_gm, d_w, d_j].map(|d| match d.effect {
        Some(t) => oracle_stats(t, &jumps, &clean.base, &snap, tau0),
        None => OracleStat::nan(),
    });
    (stats, own)
}

/// `--mode oracle`: oracle power and Cramér-Rao bounds (docs/gap.md, "Oracle bounds").
/// What `--mode oracle` runs: the benchmark's draws (`draws`, `seed`) and the clean runs
/// (`null_draws`, `null_seed`).
struct OracleArgs<'a> {
    draws: u64,
    seed: u64,
    null_draws: u64,
    null_seed: u64,
    tau0: f64,
    t_run: f64,
    threads: u64,
    csv: &'a str,
}

fn oracle_mode(a: &OracleArgs) {
    let OracleArgs {
        draws,
        seed,
        null_draws,
        null_seed,
        tau0,
        t_run,
        threads,
        csv,
    } = *a;
    let kinds: Vec<Option<EffectKind>> = vec![
        None,
        Some(EffectKind::GaussMarkov),
        Some(EffectKind::Sinusoid),
        Some(EffectKind::OutputFilter),
        Some(EffectKind::Warmup),
        Some(EffectKind::BiasJumps),
    ];
    let targets = [
        EffectKind::GaussMarkov,
        EffectKind::Warmup,
        EffectKind::BiasJumps,
    ];
    let t0 = Instant::now();
    let null_idx: Vec<u64> = (0..null_draws).collect();
    let nulls = par_map(&null_idx, threads as usize, |i| {
        oracle_null(i, null_seed, tau0, t_run)
    });
    let eff_idx: Vec<u64> = (0..draws)
        .filter(|&i| kinds[(i as usize) % kinds.len()].is_some_and(|k| targets.contains(&k)))
        .collect();
    let effs = par_map(&eff_idx, threads as usize, |i| {
        oracle_effect(i, seed, tau0, t_run, &kinds)
    });
    println!(
        "oracle: {} effect draws (seed {seed}), {} clean runs (seed {null_seed}), duration {t_run} s, {:.0} s wall",
        effs.len(),
        nulls.len(),
        t0.elapsed().as_secs_f64()
    );
    if !csv.is_empty() {
        let head =
            "fitted,dof,p_fitted,z,delta,alt,z_true,delta_true,crb_shape,crb_amp,crb_shape_alt";
        let row = |o: &OracleStat| {
            format!(
                "{:.4},{},{:.3e},{:.4},{:.4},{:.4},{:.4},{:.4},{:.5},{:.5},{:.5}",
                o.fitted,
                o.dof,
                o.p_fitted(),
                o.z,
                o.delta,
                o.alt,
                o.z_true,
                o.delta_true,
                o.crb_shape,
                o.crb_amp,
                o.crb_shape_alt
            )
        };
        let mut text = format!("draw,truth,rho,named,all_named,shape_err,amp_err,gm,w,jump_z1,jump_z2,jump_z3,{head}\n");
        for (i, (out, o)) in eff_idx.iter().zip(&effs) {
            text += &format!(
                "{i},{},{:.3},{},{},{:.4},{:.4},{:.3},{:.3},{:.3},{:.3},{:.3},{}\n",
                name(out.truth),
                out.rho,
                name(out.named),
                out.all_named
                    .iter()
                    .map(|k| k.name())
                    .collect::<Vec<_>>()
                    .join("+"),
                out.shape_err,
                out.amp_err,
                out.scores[0],
                out.scores[3],
                out.scores[4],
                out.scores[5],
                out.scores[6],
                row(o)
            );
        }
        std::fs::write(csv, text).expect("csv");
        let mut text = format!("run,pseudo_effect,{head},own\n");
        for (i, (r, own)) in nulls.iter().enumerate() {
            for ((k, o), v) in targets.iter().zip(r).zip(own) {
                text += &format!("{i},{},{},{v:.4}\n", k.name(), row(o));
            }
        }
        let null_csv = format!("{}.null.csv", csv.trim_end_matches(".csv"));
        std::fs::write(&null_csv, text).expect("null csv");
    }

    println!();
    println!(
        "Null (clean runs, pseudo-effects from the priors): quantiles of the oracle statistics"
    );
    println!("| effect | p-value of `fitted` q05 / q01 (nominal 0.05 / 0.01) | `z` q95 / q99 (nominal 1.645 / 2.326) | `z` true cov. q95 | own statistic q95 |");
    println!("|---|---|---|---|---|");
    let mut thr = Vec::new();
    for (k, kind) in targets.iter().enumerate() {
        let pf: Vec<f64> = nulls.iter().map(|r| r.0[k].p_fitted()).collect();
        let z: Vec<f64> = nulls.iter().map(|r| r.0[k].z).collect();
        let zt: Vec<f64> = nulls.iter().map(|r| r.0[k].z_true).collect();
        let own: Vec<f64> = nulls.iter().map(|r| r.1[k]).collect();
        let t = (
            quantile(&pf, 0.05),
            quantile(&pf, 0.01),
            quantile(&z, 0.95),
            quantile(&z, 0.99),
            quantile(&zt, 0.95),
            quantile(&own, 0.95),
        );
        println!(
            "| {} | {:.4} / {:.4} | {:.3} / {:.3} | {:.3} | {:.3} |",
            kind.name(),
            t.0,
            t.1,
            t.2,
            t.3,
            t.4,
            t.5
        );
        thr.push(t);
    }

    for (big, label) in [(0.3, "rho >= 0.3"), (0.0, "all draws")] {
        println!();
        println!("Detection, {label}: the diagnosis (right effect named first) against the oracles at the clean runs' 5% (1%) quantiles");
        println!("| effect | n | diagnosis | own statistic alone at its 5% | shape known, amplitude fitted: 5% (1%) | all known `z`: 5% (1%) | all known, expected `Phi(delta - z95)` | all known, true cov.: expected |");
        println!("|---|---|---|---|---|---|---|---|");
        for (k, kind) in targets.iter().enumerate() {
            let rows: Vec<&(Outcome, OracleStat)> = effs
                .iter()
                .filter(|(o, _)| o.truth == Some(*kind) && o.rho >= big)
                .collect();
            let n = rows.len().max(1) as f64;
            let t = thr[k];
            let ours = rows.iter().filter(|(o, _)| o.named == Some(*kind)).count();
            let own_col = match kind {
                EffectKind::GaussMarkov => 0,
                EffectKind::Warmup => 3,
                _ => 4,
            };
            let own5 = rows.iter().filter(|(o, _)| o.scores[own_col] > t.5).count();
            let f5 = rows.iter().filter(|(_, s)| s.p_fitted() <= t.0).count();
            let f1 = rows.iter().filter(|(_, s)| s.p_fitted() <= t.1).count();
            let z5 = rows.iter().filter(|(_, s)| s.z >= t.2).count();
            let z1 = rows.iter().filter(|(_, s)| s.z >= t.3).count();
            let ez: f64 = rows
                .iter()
                .map(|(_, s)| std_normal_cdf(s.delta - t.2))
                .sum::<f64>()
                / n;
            let ezt: f64 = rows
                .iter()
                .map(|(_, s)| std_normal_cdf(s.delta_true - 1.645))
                .sum::<f64>()
                / n;
            let pc = |c: usize| 100.0 * c as f64 / n;
            println!(
                "| {} | {} | {ours} ({:.0}%) | {own5} ({:.0}%) | {f5} ({:.0}%) ({f1}, {:.0}%) | {z5} ({:.0}%) ({z1}, {:.0}%) | {:.0}% | {} |",
                kind.name(),
                rows.len(),
                pc(ours),
                pc(own5),
                pc(f5),
                pc(f1),
                pc(z5),
                pc(z1),
                100.0 * ez,
                if kind == &EffectKind::GaussMarkov {
                    "-".to_string()
                } else {
                    format!("{:.0}%", 100.0 * ezt)
                }
            );
        }
    }

    println!();
    println!("Draws at rho >= 0.3 the diagnosis misses (oracle p-value of `fitted`, `z`, `delta`; the diagnosis's own base statistic: GM drop per parameter, W, largest step z)");
    println!("| draw | effect | rho | named | p(fitted) | fitted | z | delta | own statistic |");
    println!("|---|---|---|---|---|---|---|---|---|");
    for (i, (out, o)) in eff_idx.iter().zip(&effs) {
        let Some(kind) = out.truth else { continue };
        if out.rho < 0.3 || out.named == Some(kind) {
            continue;
        }
        let own = match kind {
            EffectKind::GaussMarkov => out.scores[0],
            EffectKind::Warmup => out.scores[3],
            _ => out.scores[4],
        };
        println!(
            "| {i} | {} | {:.2} | {} | {:.2e} | {:.2} | {:.2} | {:.2} | {:.2} |",
            kind.name(),
            out.rho,
            name(out.named),
            o.p_fitted(),
            o.fitted,
            o.z,
            o.delta,
            own
        );
    }

    println!();
    println!("Cramér-Rao bounds (sd of the log parameter for any unbiased estimator) and the measured errors");
    println!("| effect, parameter | draw set | n | CRB sd median | CRB sd q90 | share with CRB sd > 10%/1.645 (25%/1.645 for amplitudes) | CRB-implied q90 of abs rel. error | measured q90 | measured median | share with abs ln error > 1.645 CRB sd |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for kind in [EffectKind::GaussMarkov, EffectKind::Warmup] {
        for (param, is_shape) in [("shape", true), ("amplitude", false)] {
            for (set, named_only, big) in [
                ("named", true, 0.0),
                ("named, rho >= 0.3", true, 0.3),
                ("all, rho >= 0.3", false, 0.3),
            ] {
                let rows: Vec<&(Outcome, OracleStat)> = effs
                    .iter()
                    .filter(|(o, _)| {
                        o.truth == Some(kind)
                            && o.rho >= big
                            && (!named_only || o.shape_err.is_finite())
                    })
                    .collect();
                let sd: Vec<f64> = rows
                    .iter()
                    .map(|(_, s)| if is_shape { s.crb_shape } else { s.crb_amp })
                    .collect();
                let err: Vec<f64> = rows
                    .iter()
                    .map(|(o, _)| if is_shape { o.shape_err } else { o.amp_err })
                    .collect();
                let lim = if is_shape { 0.10 } else { 0.25 } / 1.645;
                let over = sd.iter().filter(|&&v| v > lim).count();
                let abs_err: Vec<f64> = err.iter().map(|e| e.abs()).collect();
                let eff_out = rows
                    .iter()
                    .zip(&sd)
                    .filter(|((o, _), &s)| {
                        let e = if is_shape { o.shape_err } else { o.amp_err };
                        e.is_finite() && (1.0 + e).ln().abs() > 1.645 * s
                    })
                    .count();
                let n_err = abs_err.iter().filter(|v| v.is_finite()).count();
                println!(
                    "| {} {param} | {set} | {} | {:.3} | {:.3} | {over}/{} | {:.3} | {} | {} | {} |",
                    kind.name(),
                    rows.len(),
                    quantile(&sd, 0.5),
                    quantile(&sd, 0.9),
                    rows.len(),
                    oracle::mixture_rel_error_quantile(&sd, 0.9),
                    if n_err > 0 { format!("{:.3}", quantile(&abs_err, 0.9)) } else { "-".into() },
                    if n_err > 0 { format!("{:.3}", quantile(&abs_err, 0.5)) } else { "-".into() },
                    if n_err > 0 { format!("{eff_out}/{n_err}") } else { "-".into() },
                );
            }
        }
    }
    // The other setting of the shape bound.
    for kind in [EffectKind::GaussMarkov, EffectKind::Warmup] {
        let sd: Vec<f64> = effs
            .iter()
            .filter(|(o, _)| o.truth == Some(kind) && o.shape_err.is_finite())
            .map(|(_, s)| s.crb_shape_alt)
            .collect();
        println!(
            "{} shape CRB, other setting ({}), named draws: median {:.3}, q90 {:.3}, implied q90 rel. error {:.3}, share > 10%/1.645: {}/{}",
            kind.name(),
            if kind == EffectKind::GaussMarkov { "R free" } else { "fitted covariance" },
            quantile(&sd, 0.5),
            quantile(&sd, 0.9),
            oracle::mixture_rel_error_quantile(&sd, 0.9),
            sd.iter().filter(|&&v| v > 0.1 / 1.645).count(),
            sd.len()
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let get = |k: &str, d: &str| -> String {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1).cloned())
            .unwrap_or_else(|| d.to_string())
    };
    let draws: u64 = get("--draws", "240").parse().expect("--draws");
    let seed: u64 = get("--seed", "1").parse().expect("--seed");
    let t_run: f64 = get("--duration", "3600").parse().expect("--duration");
    let tau0: f64 = get("--tau0", "0.004").parse().expect("--tau0");
    let threads: u64 = get("--threads", "2").parse().expect("--threads");
    let mode = get("--mode", "bench");
    let csv = get("--csv", "");
    let with_scores = args.iter().any(|a| a == "--scores");

    if mode == "speed" {
        let tau0 = 0.004;
        let n = (3.0 * 3600.0 / tau0) as usize;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let d = draw(
            &mut rng,
            Some(EffectKind::GaussMarkov),
            n as f64 * tau0,
            tau0,
        );
        let (inc, _, _) = simulate(&d, tau0, n as f64 * tau0, seed);
        let t = Instant::now();
        let mut ev = GapEvidence::from_increments(GapConfig::new(tau0), &inc);
        let snap = ev.snapshot();
        let t1 = t.elapsed();
        let diag = diagnose(&snap, &DiagnoseOptions::default()).expect("diagnosis");
        let t2 = t.elapsed();
        println!(
            "{n} samples: evidence {:.2} s, diagnosis {:.2} s, total {:.2} s; verdict {:?}, effects {:?}",
            t1.as_secs_f64(),
            (t2 - t1).as_secs_f64(),
            t2.as_secs_f64(),
            diag.verdict,
            diag.effects.iter().map(|e| e.params).collect::<Vec<_>>()
        );
        return;
    }

    if mode == "one" {
        let i: u64 = get("--draw", "0").parse().expect("--draw");
        let kinds: Vec<Option<EffectKind>> = vec![
            None,
            Some(EffectKind::GaussMarkov),
            Some(EffectKind::Sinusoid),
            Some(EffectKind::OutputFilter),
            Some(EffectKind::Warmup),
            Some(EffectKind::BiasJumps),
        ];
        let mut rng =
            Xoshiro256PlusPlus::seed_from_u64(seed.wrapping_mul(1_000_003).wrapping_add(i));
        // `--clean`: the clean run of `--mode calibrate` with this seed and index.
        let kind = if args.iter().any(|a| a == "--clean") {
            None
        } else {
            kinds[(i as usize) % kinds.len()]
        };
        let d = draw(&mut rng, kind, t_run, tau0);
        println!("{d:?}");
        let (inc, _, _) = simulate(&d, tau0, t_run, seed.wrapping_add(7919 * i));
        let mut ev = GapEvidence::from_increments(GapConfig::new(tau0), &inc);
        let snap = ev.snapshot();
        let opts = DiagnoseOptions::default();
        let prob = GapProblem::new(&snap, &opts).expect("problem");
        let base = prob.gls(&ModelSpec::default()).expect("gls");
        println!(
            "base chi2 {:.2} exp {:.2} G {:.3} coef {:?}",
            base.chi2,
            base.expected,
            base.gap(),
            base.coef
        );
        for k in [
            EffectKind::GaussMarkov,
            EffectKind::Sinusoid,
            EffectKind::OutputFilter,
            EffectKind::Warmup,
        ] {
            if let Some((sh, f)) = prob.scan(&ModelSpec::default(), k) {
                println!(
                    "{:?}: shape {sh:.4} chi2 {:.2} exp {:.2} G {:.3} coef {:?}",
                    k,
                    f.chi2,
                    f.expected,
                    f.gap(),
                    f.coef
                );
            }
        }
        let c5: [f64; 5] = std::array::from_fn(|i| base.coef[i]);
        let block_s = snap.block_len as f64 * tau0;
        println!(
            "warm-up: {:?}",
            fit_warmup(&snap.block_means, block_s, t_run, &c5, &[])
        );
        if let Some(se) =
            allanscope::gap::steps::step_standard_errors(snap.block_means.len(), block_s, &c5, &[])
        {
            let tb = 10.0 * t_run / 10.0;
            let true_se = allanscope::gap::steps::step_standard_errors(
                snap.block_means.len(),
                block_s,
                &[
                    terms::quantization_q(d.base.lsb).powi(2),
                    d.base.n * d.base.n,
                    d.base.b * d.base.b,
                    d.base.k * d.base.k,
                    0.0,
                ],
                &[],
            )
            .unwrap_or_default();
            println!(
                "step s.e. (u/s) with the fitted terms: first {:.4} middle {:.4}; true base: middle {:.4}; base ADEV(T_run/10) {:.4} (T_run {tb} s)",
                se[0],
                se[se.len() / 2],
                true_se.get(true_se.len() / 2).copied().unwrap_or(f64::NAN),
                d.base.adev(t_run / 10.0)
            );
        }
        if let Some(scan) = step_scan(&snap.block_means, block_s, &c5, &[]) {
            let mut idx: Vec<usize> = (0..scan.z.len()).collect();
            idx.sort_by(|&a, &b| scan.z[b].abs().total_cmp(&scan.z[a].abs()));
            let mut se = scan.se.clone();
            se.sort_by(|a, b| a.total_cmp(b));
            let med = se[se.len() / 2];
            println!(
                "step scan: {} candidates, median s.e. {med:.4}; mixture {:.3} (max {:.3}, boundaries {:.3})",
                scan.z.len(),
                jump_mixture_stat(&scan, false, false),
                jump_mixture_stat(&scan, false, true),
                jump_mixture_stat(&scan, true, false)
            );
            for &j in idx.iter().take(10) {
                println!(
                    "  candidate {j}: z {:.3} s.e. {:.4} boundary {}",
                    scan.z[j], scan.se[j], scan.boundary[j]
                );
            }
        }
        let diag = diagnose(&snap, &opts).expect("diag");
        println!("{diag:#?}");
        println!(
            "blocks: {:?}",
            snap.block_means.iter().take(20).collect::<Vec<_>>()
        );
        return;
    }

    if mode == "oracle" {
        let null_draws: u64 = get("--null-draws", "400").parse().expect("--null-draws");
        let null_seed: u64 = get("--null-seed", "2").parse().expect("--null-seed");
        oracle_mode(&OracleArgs {
            draws,
            seed,
            null_draws,
            null_seed,
            tau0,
            t_run,
            threads,
            csv: &csv,
        });
        return;
    }

    if mode == "calibrate" {
        let idx: Vec<u64> = (0..draws).collect();
        let res: Vec<Null> = par_map(&idx, threads as usize, |i| calibrate(i, seed, tau0, t_run));
        if !csv.is_empty() {
            let mut text = String::from(
                "g,zmax,best,gm,sin,filter,w,flagged,effects,jump_z1,jump_z2,jump_z3,w_bf,jmix,jmix_max,jmix_b,jceil,jfwd,jfwd_ceil,jmarg\n",
            );
            for r in &res {
                text += &format!(
                    "{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{},{}",
                    r.g,
                    r.zmax,
                    r.best,
                    r.per_kind[0],
                    r.per_kind[1],
                    r.per_kind[2],
                    r.w,
                    u8::from(r.flagged),
                    r.verdict_effects
                );
                for k in 0..3 {
                    text += &format!(",{:.4}", r.jumps.get(k).copied().unwrap_or(0.0));
                }
                for v in r.mix {
                    text += &format!(",{v:.4}");
                }
                text += "\n";
            }
            std::fs::write(&csv, text).expect("csv");
        }
        println!("clean draws: {}", res.len());
        println!("G0:       {}", quantiles(res.iter().map(|r| r.g).collect()));
        println!(
            "max|z|:   {}",
            quantiles(res.iter().map(|r| r.zmax).collect())
        );
        println!(
            "best dchi2/param: {}",
            quantiles(res.iter().map(|r| r.best).collect())
        );
        for (k, nm) in ["gauss_markov", "sinusoid", "output_filter"]
            .iter()
            .enumerate()
        {
            println!(
                "  {nm} dchi2/param: {}",
                quantiles(res.iter().map(|r| r.per_kind[k]).collect())
            );
        }
        println!(
            "warm-up W: {}",
            quantiles(res.iter().map(|r| r.w).collect())
        );
        println!(
            "flagged (not consistent): {:.3}",
            res.iter().filter(|r| r.flagged).count() as f64 / res.len() as f64
        );
        for z in JUMP_ZS {
            let frac = |k: usize| {
                res.iter()
                    .filter(|r| r.jumps.get(k).is_some_and(|&v| v >= z))
                    .count() as f64
                    / res.len() as f64
            };
            println!(
                "steps at z >= {z}: at least one {:.3}, two {:.3}, three {:.3}",
                frac(0),
                frac(1),
                frac(2)
            );
        }
        return;
    }

    let kinds: Vec<Option<EffectKind>> = vec![
        None,
        Some(EffectKind::GaussMarkov),
        Some(EffectKind::Sinusoid),
        Some(EffectKind::OutputFilter),
        Some(EffectKind::Warmup),
        Some(EffectKind::BiasJumps),
    ];
    let t0 = Instant::now();
    let idx: Vec<u64> = (0..draws).collect();
    let res: Vec<(u64, Outcome)> = par_map(&idx, threads as usize, |i| {
        (i, run_one(i, seed, tau0, t_run, &kinds, with_scores))
    });
    let elapsed = t0.elapsed().as_secs_f64();
    if !csv.is_empty() {
        let mut text = String::from("draw,truth,rho,named,verdict,gap_before,gap_after,shape_err,amp_err,gm,sin,filter,w,jump_z1,jump_z2,jump_z3,w_bf,jmix,jmix_max,jmix_b,jceil,jfwd,jfwd_ceil,jmarg,all_named,truth_params,found_params\n");
        for (i, o) in &res {
            text += &format!(
                "{i},{},{:.3},{},{},{:.3},{:.3},{:.4},{:.4},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.3},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{:.4},{},\"{:?}\",\"{:?}\"\n",
                name(o.truth),
                o.rho,
                name(o.named),
                o.verdict,
                o.gap_before,
                o.gap_after,
                o.shape_err,
                o.amp_err,
                o.scores[0],
                o.scores[1],
                o.scores[2],
                o.scores[3],
                o.scores[4],
                o.scores[5],
                o.scores[6],
                o.scores[7],
                o.scores[8],
                o.scores[9],
                o.scores[10],
                o.scores[11],
                o.scores[12],
                o.scores[13],
                o.scores[14],
                o.all_named
                    .iter()
                    .map(|k| k.name())
                    .collect::<Vec<_>>()
                    .join("+"),
                o.truth_params,
                o.found_params
            );
        }
        std::fs::write(&csv, text).expect("csv");
    }
    println!(
        "{} draws, duration {t_run} s, tau0 {tau0} s, {elapsed:.0} s wall",
        res.len()
    );
    // Confusion matrix: truth rows, first named effect columns.
    print!("| truth \\ named | n |");
    for k in &kinds {
        print!(" {} |", name(*k));
    }
    println!(" right (all) | right (rho >= 0.3) | named anywhere (rho >= 0.3) |");
    print!("|---|---|");
    for _ in &kinds {
        print!("---|");
    }
    println!("---|---|---|");
    for t in &kinds {
        let rows: Vec<&Outcome> = res.iter().map(|r| &r.1).filter(|o| o.truth == *t).collect();
        print!("| {} | {} |", name(*t), rows.len());
        for k in &kinds {
            print!(" {} |", rows.iter().filter(|o| o.named == *k).count());
        }
        let right = rows.iter().filter(|o| o.named == *t).count();
        let big: Vec<_> = rows
            .iter()
            .filter(|o| o.rho >= 0.3 || t.is_none())
            .collect();
        let right_big = big.iter().filter(|o| o.named == *t).count();
        let anywhere = big
            .iter()
            .filter(|o| match t {
                Some(k) => o.all_named.contains(k),
                None => o.all_named.is_empty(),
            })
            .count();
        println!(
            " {right}/{} ({:.0}%) | {right_big}/{} ({:.0}%) | {anywhere}/{} ({:.0}%) |",
            rows.len(),
            100.0 * right as f64 / rows.len().max(1) as f64,
            big.len(),
            100.0 * right_big as f64 / big.len().max(1) as f64,
            big.len(),
            100.0 * anywhere as f64 / big.len().max(1) as f64
        );
    }
    println!();
    println!("| effect | n named right | shape err median abs | shape err q90 abs | amp err median abs | amp err q90 abs |");
    println!("|---|---|---|---|---|---|");
    for t in kinds.iter().flatten() {
        let mut se: Vec<f64> = res
            .iter()
            .map(|r| &r.1)
            .filter(|o| o.truth == Some(*t) && o.shape_err.is_finite())
            .map(|o| o.shape_err.abs())
            .collect();
        let mut ae: Vec<f64> = res
            .iter()
            .map(|r| &r.1)
            .filter(|o| o.truth == Some(*t) && o.amp_err.is_finite())
            .map(|o| o.amp_err.abs())
            .collect();
        se.sort_by(|a, b| a.total_cmp(b));
        ae.sort_by(|a, b| a.total_cmp(b));
        let q = |v: &Vec<f64>, p: f64| {
            if v.is_empty() {
                f64::NAN
            } else {
                v[((v.len() as f64 - 1.0) * p).round() as usize]
            }
        };
        println!(
            "| {} | {} | {:.3} | {:.3} | {:.3} | {:.3} |",
            t.name(),
            se.len(),
            q(&se, 0.5),
            q(&se, 0.9),
            q(&ae, 0.5),
            q(&ae, 0.9)
        );
    }
}
