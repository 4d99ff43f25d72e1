//! The rounding of rate samples after a unit's filter (docs/gap.md, "Rounding after a
//! filter"): `gap::rounding::rounding_avar` against the white floor where the step is fine and
//! against a simulation where it is not.

use allanscope::gap::rounding::{filtered_sigma, rounding_avar};
use allanscope::model::lowpass::LowPass;

/// Overlapping AVAR of rate samples `r` at cluster size `m` (rate units squared).
fn avar(r: &[f64], m: usize) -> f64 {
    let mut c = vec![0.0; r.len() + 1];
    for (i, v) in r.iter().enumerate() {
        c[i + 1] = c[i] + v;
    }
    let yb: Vec<f64> = (0..=r.len() - m)
        .map(|i| (c[i + m] - c[i]) / m as f64)
        .collect();
    let d: Vec<f64> = (0..yb.len() - m).map(|i| yb[i + m] - yb[i]).collect();
    0.5 * d.iter().map(|x| x * x).sum::<f64>() / d.len() as f64
}

/// An 8-tap moving average of white rate, 400 000 samples, rounded to a step of 2 filtered
/// sigmas (the mean at a quarter step): the rounding error's AVAR is the model's within 6% at
/// m = 1, 4, 64 (its own sampling spread is about 1-3%), where the white floor `L^2 / 12 / m`
/// is off by 18% at m = 1 and 45% at m = 64. A step of half a sigma is the white floor.
#[test]
fn the_rounding_after_a_moving_average_has_the_modelled_curve() {
    use rand::{RngExt, SeedableRng};
    use rand_distr::StandardNormal;
    let tau0 = 0.001;
    let n2 = 1e-4;
    let lp = LowPass::MovingAverage {
        taps: 8,
        stages: 1,
        decimation: 1,
    };
    let sigma = filtered_sigma(&lp, tau0, n2);
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
    let sd_x = (n2 / tau0).sqrt();
    let x: Vec<f64> = (0..400_007)
        .map(|_| sd_x * rng.sample::<f64, _>(StandardNormal))
        .collect();
    let s: Vec<f64> = x.windows(8).map(|w| w.iter().sum::<f64>() / 8.0).collect();
    let ms = [1u64, 4, 64];
    for (k, tol) in [(2.0, 0.06), (0.5, 0.03)] {
        let step = k * sigma;
        let e: Vec<f64> = s
            .iter()
            .map(|v| step * ((v + 0.25 * step) / step).round() - 0.25 * step - v)
            .collect();
        let model = rounding_avar(&lp, tau0, step, n2, &ms);
        for (mo, &m) in model.iter().zip(&ms) {
            let sim = avar(&e, m as usize);
            assert!(
                (sim / mo - 1.0).abs() < tol,
                "step {k} sigma, m {m}: {sim} vs {mo}"
            );
            if k == 2.0 && m != 4 {
                let white = step * step / 12.0 / m as f64;
                assert!(
                    (sim / white - 1.0).abs() > 0.15,
                    "m {m}: {sim} vs white {white}"
                );
            }
        }
    }
}

/// family_gap's `accfilt` clean draw 18 of seed 107 (session 10): a MEMS accelerometer at 209
/// Hz behind a first-order filter of 18.6 samples, each rate sample then rounded to a step of
/// 1.5 filtered sigmas (the mean on a step).
const ACCF18: &str = "tau0_s = 0.004784688995215311\n[[channel]]\nname = \"ax\"\nunit = \"m/s\"\n\
                      N = 1.5612420768984568e-3\nB = 2.0515424098150337e-4\n\
                      K = 3.110799335426825e-5\nrate_lsb = 5.710259440617705e-3\n\
                      output_filter = { time_constant = 8.9078e-2 }\n";
const ACCF18_TAU0: f64 = 0.004784688995215311;
const ACCF18_T: f64 = 8.9078e-2;

/// `duration_s` seconds of the one-channel `model` at `tau0_s` (simulator seed `seed`), as the
/// streaming evidence holds them.
fn snapshot_of(
    model: &str,
    tau0_s: f64,
    seed: u64,
    duration_s: f64,
) -> allanscope::gap::EvidenceSnapshot {
    use allanscope::gap::{GapConfig, GapEvidence};
    use allanscope::sim::{SimModel, Simulator};
    let m = SimModel::from_toml_str(model, std::path::Path::new("<test>")).expect("model");
    let mut sim = Simulator::new(&m, seed);
    let mut inc = vec![0.0; (duration_s / tau0_s) as usize];
    sim.fill_channel(0, &mut inc);
    GapEvidence::from_increments(GapConfig::new(tau0_s), &inc).snapshot()
}

/// The problem as the diagnosis's last pass sets it for a unit behind a first order of
/// `time_constant_s`: the covariance's five terms fitted beyond ten memories of the filter,
/// with the filter's correction (and the rounding's discrepancy where it applies).
fn last_pass_problem(
    snap: &allanscope::gap::EvidenceSnapshot,
    time_constant_s: f64,
) -> allanscope::gap::problem::GapProblem {
    use allanscope::gap::problem::GapProblem;
    use allanscope::gap::DiagnoseOptions;
    let beyond = DiagnoseOptions {
        min_m: (10.0 * time_constant_s / snap.tau0_s).ceil() as u64,
        ..DiagnoseOptions::default()
    };
    let cov = DiagnoseOptions {
        cov_coef: Some(GapProblem::new(snap, &beyond).expect("beyond").c_init),
        cov_filter: Some(LowPass::FirstOrder { time_constant_s }),
        ..DiagnoseOptions::default()
    };
    GapProblem::new(snap, &cov).expect("problem")
}

/// The rounding's correlation depends on the filtered noise against the step, so the model
/// with the unit's own filter fits only when that noise is the fit's own N (session 11): with
/// the N fixed when the floor was chosen (from a fit that began with no rounding at all) the
/// true first order fitted this curve with `G` 38-56 on the family's run and a sinusoid was
/// invented beside it. Now the true filter closes the curve, and the diagnosis names the first
/// order alone within 25% of its time constant.
#[test]
fn the_rounding_follows_the_fitted_white_rate() {
    use allanscope::gap::problem::ModelSpec;
    use allanscope::gap::{diagnose, DiagnoseOptions, EffectParams, Verdict};
    let snap = snapshot_of(ACCF18, ACCF18_TAU0, 18, 2400.0);
    let opts = DiagnoseOptions::default();
    // The covariance as the diagnosis's last pass takes it.
    let lp = LowPass::FirstOrder {
        time_constant_s: ACCF18_T,
    };
    let mut prob = last_pass_problem(&snap, ACCF18_T);
    prob.set_filter_floor(snap.lsb.expect("the values show their step"));
    assert!(
        prob.filter_floor.is_some(),
        "the rounding is after the filter"
    );
    let spec = ModelSpec {
        filter: Some(lp),
        ..ModelSpec::default()
    };
    let fit = prob.gls(&spec).expect("fit");
    // N is the simulated unit's within 5% (the rounding is beside it, not in it)
    let n = fit.coef[1].sqrt();
    assert!((n / 1.5612420768984568e-3 - 1.0).abs() < 0.05, "N {n}");
    let g = fit.gap();
    let d = diagnose(&snap, &opts).expect("diagnosis");
    crate::diagnosis::assert_bookkeeping(&d);
    assert!(g < 2.0, "true filter G {g}; diagnosis {:?}", d.effects);
    assert_eq!(d.verdict, Verdict::Explained, "{:?}", d.effects);
    assert_eq!(d.effects.len(), 1, "{:?}", d.effects);
    match d.effects[0].params {
        EffectParams::OutputFilter { time_constant_s } => {
            assert!(
                (time_constant_s / ACCF18_T - 1.0).abs() < 0.25,
                "T {time_constant_s}"
            )
        }
        p => panic!("named {p:?}"),
    }
}

/// A first-order filter of 10 samples, 2 000 000 samples, each rounded to a step of 1 / 0.35
/// filtered sigmas: the output's AVAR is the filtered rate's plus
/// `rounding_avar_on_grid` within 3% at m = 1, 8, 64 (the simulation's own spread is about
/// 0.5-1.5%) with the mean on a step, at a quarter step and at a half step, the grid read from
/// block means as the evidence keeps them (measured: within 0.3% at m = 1 and 8, 1.3% at 64).
/// With the mean on a step the model averaged over the mean's position is 19-31% too high
/// there (the dead band), at a half step 18-34% too low (the output flips between two steps),
/// and the signal's own AVAR with session 10's floor is not the output's either.
#[test]
fn the_rounding_in_the_dead_band_follows_the_mean_on_the_grid() {
    use allanscope::gap::rounding::{rounding_avar_on_grid, GridPosition};
    use allanscope::model::lowpass::avar_from_autocovariance;
    use rand::{RngExt, SeedableRng};
    use rand_distr::StandardNormal;
    let tau0 = 0.004;
    let t_f = 10.0 * tau0;
    let n2 = 1e-4;
    let lp = LowPass::FirstOrder {
        time_constant_s: t_f,
    };
    let sigma = filtered_sigma(&lp, tau0, n2);
    let step = sigma / 0.35;
    let a = (-tau0 / t_f).exp();
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(12);
    let sd_x = (n2 / tau0).sqrt();
    let n = 2_000_000;
    let mut s = Vec::with_capacity(n);
    let mut y = sigma * rng.sample::<f64, _>(StandardNormal);
    for _ in 0..n {
        y = a * y + (1.0 - a) * sd_x * rng.sample::<f64, _>(StandardNormal);
        s.push(y);
    }
    let ms = [1u64, 8, 64];
    let rho: Vec<f64> = lp
        .autocorrelation(tau0)
        .iter()
        .map(|v| v * n2 / tau0)
        .collect();
    let signal = avar_from_autocovariance(&rho, 1.0, &ms);
    let block = 8192;
    // (mean in steps, the averaged model's error: below 0.85 of the simulation with the mean on
    // a step, above 1.15 at a half step, where the output flips between two steps)
    for (mean_steps, averaged_off) in [(0.0, Some(false)), (0.25, None), (0.5, Some(true))] {
        let mu = mean_steps * step;
        let out: Vec<f64> = s.iter().map(|v| step * ((v + mu) / step).round()).collect();
        let grid = GridPosition {
            block_means: out
                .chunks(block)
                .map(|c| c.iter().sum::<f64>() / c.len() as f64)
                .collect(),
            block_s: block as f64 * tau0,
            flicker_b2: 0.0,
        };
        let on_grid = rounding_avar_on_grid(&lp, tau0, step, n2, Some(&grid), &ms);
        let averaged = rounding_avar(&lp, tau0, step, n2, &ms);
        for (i, &m) in ms.iter().enumerate() {
            let sim = avar(&out, m as usize);
            let model = signal[i] + on_grid[i];
            assert!(
                (sim / model - 1.0).abs() < 0.03,
                "mean {mean_steps} step, m {m}: simulated {sim} vs model {model}"
            );
            let old = signal[i] + averaged[i];
            match averaged_off {
                Some(false) => assert!(
                    sim / old < 0.85,
                    "mean on a step, m {m}: simulated {sim} vs averaged {old}"
                ),
                Some(true) => assert!(
                    sim / old > 1.15,
                    "mean at a half step, m {m}: simulated {sim} vs averaged {old}"
                ),
                None => {}
            }
        }
    }
}

/// 1800 s of the one-channel `model` at `tau0_s` (simulator seed `seed`) diagnosed with the
/// defaults: the bookkeeping holds, the verdict is `explained` and one effect is named.
fn explained_by_one_effect(model: &str, tau0_s: f64, seed: u64) -> allanscope::gap::Diagnosis {
    use allanscope::gap::{diagnose, DiagnoseOptions, Verdict};
    let snap = snapshot_of(model, tau0_s, seed, 1800.0);
    let d = diagnose(&snap, &DiagnoseOptions::default()).expect("diagnosis");
    crate::diagnosis::assert_bookkeeping(&d);
    assert_eq!(
        d.verdict,
        Verdict::Explained,
        "seed {seed}: {:?}",
        d.effects
    );
    assert_eq!(d.effects.len(), 1, "seed {seed}: {:?}", d.effects);
    d
}

/// `family_gap --families kalgyro --seed 121` draw 19 (session 12's blind family: a consumer
/// IMU gyro at 200 Hz behind its second-order digital low-pass, each rate sample rounded to a
/// step of 1 / 0.56 filtered sigmas). The rounding floor was decided by scanning the first order
/// and the moving average only; neither fits a second-order unit, so the floor was dropped and
/// the second order, fitted without its rounding, came out 10% high in frequency with a
/// band invented at 12 Hz beside it (seeds 1-3 through the CLI on main 5c42e80). The filter the
/// earlier pass found is now scanned with and without the floor too.
const KALG19: &str = "tau0_s = 0.005\n[[channel]]\nname = \"x\"\nunit = \"u\"\n\
                      N = 6.151372034169291e-3\nB = 1.208370899623152e-3\n\
                      K = 1.3762697694221681e-5\n\
                      flicker_band_s = [0.005, 2.3323595478756688e5]\n\
                      bias = 3.526245040773406e-1\n\
                      second_order_filter = { natural_frequency = 2.3707836501265064e1, \
                      damping = 6.765986489939894e-1 }\n\
                      rate_lsb = 8.475270101003542e-2\n";

/// 1800 s, simulator seeds 1 and 2: the second order alone, `explained`, within 2% in natural
/// frequency and 3% in damping; the values' step is read as rate rounding; `N` without the
/// rounding is the unit's within 5%.
#[test]
fn a_second_order_unit_keeps_its_rounding_floor() {
    use allanscope::gap::quantization::QuantKind;
    use allanscope::gap::EffectParams;
    for seed in [1, 2] {
        let d = explained_by_one_effect(KALG19, 0.005, seed);
        let EffectParams::SecondOrderFilter {
            natural_frequency_hz,
            damping,
            ..
        } = d.effects[0].params
        else {
            panic!("seed {seed}: named {:?}", d.effects);
        };
        let ef = natural_frequency_hz / 2.3707836501265064e1 - 1.0;
        let ez = damping / 6.765986489939894e-1 - 1.0;
        assert!(ef.abs() < 0.02, "seed {seed}: f0 {natural_frequency_hz}");
        assert!(ez.abs() < 0.03, "seed {seed}: damping {damping}");
        let q = d.quantization.expect("the values show their step");
        assert_eq!(q.kind, QuantKind::Rate, "seed {seed}: {q:?}");
        assert!(
            (q.n_unit / 6.151372034169291e-3 - 1.0).abs() < 0.05,
            "seed {seed}: N {}",
            q.n_unit
        );
    }
}

/// `family_gap --families accfilt --hours 1,2 --seed 107` draw 29: a MEMS accelerometer at 361
/// Hz behind a first-order filter of 15 samples, each rate sample then rounded to a step of
/// 1 / 0.384 filtered sigmas with the mean on a step (the dead band, where the rounding model
/// averaged over the mean's position is 19-31% off at the short taus).
const ACCF29: &str = "tau0_s = 0.002770083102493075\n[[channel]]\nname = \"x\"\nunit = \"u\"\n\
                      N = 1.6073054280352312e-3\nB = 2.6048171847428513e-4\n\
                      K = 8.350094600544586e-5\n\
                      flicker_band_s = [0.002770083102493075, 3.9011756822523996e4]\n\
                      output_filter = { time_constant = 4.1453357056591464e-2 }\n\
                      rate_lsb = 1.4535586033795069e-2\n";
const ACCF29_TAU0: f64 = 0.002770083102493075;
const ACCF29_T: f64 = 4.1453357056591464e-2;
const ACCF29_N: f64 = 1.6073054280352312e-3;

/// The filtered rate sample's sigma (u/s) of a unit of white rate `n` (u/sqrt(s)) at `tau0_s`
/// behind a first order of `time_constant_s`: `N sqrt(rho_0 / tau0)` with the first order's
/// `rho_0 = (1 - a) / (1 + a)` per sample, `a = exp(-tau0 / T)`.
fn first_order_sigma(n: f64, time_constant_s: f64, tau0_s: f64) -> f64 {
    let a = (-tau0_s / time_constant_s).exp();
    n * ((1.0 - a) / (1.0 + a) / tau0_s).sqrt()
}

/// The filtered rate sample's sigma (u/s) of `ACCF29`'s unit ([`first_order_sigma`]).
fn accf29_sigma() -> f64 {
    first_order_sigma(ACCF29_N, ACCF29_T, ACCF29_TAU0)
}

/// 1800 s of `model` (a unit at `tau0_s` behind a first order of `time_constant_s`) diagnosed
/// with simulator seed `seed`: the first order alone, `explained`, its time constant within
/// `rel_tol`.
fn first_order_alone(
    model: &str,
    tau0_s: f64,
    time_constant_s: f64,
    seed: u64,
    rel_tol: f64,
) -> allanscope::gap::Diagnosis {
    use allanscope::gap::EffectParams;
    let d = explained_by_one_effect(model, tau0_s, seed);
    let EffectParams::OutputFilter {
        time_constant_s: named,
    } = d.effects[0].params
    else {
        panic!("seed {seed}: named {:?}", d.effects);
    };
    assert!(
        (named / time_constant_s - 1.0).abs() < rel_tol,
        "seed {seed}: T {named}"
    );
    d
}

/// [`first_order_alone`] for a unit at `ACCF29_TAU0` behind `ACCF29_T`'s first order, and the
/// channel said to be quantization-limited.
fn dead_band_first_order(
    model: &str,
    seed: u64,
    rel_tol: f64,
) -> allanscope::gap::quant_limit::QuantizationLimit {
    first_order_alone(model, ACCF29_TAU0, ACCF29_T, seed, rel_tol)
        .quantization_limited
        .unwrap_or_else(|| panic!("seed {seed}: the dead band is not said"))
}

/// The rounding model's known error enters the covariance as a model discrepancy
/// (`gap::discrepancy`) instead of being read as effects. On main 5c42e80 the CLI's diagnosis of
/// this unit (1800 s, seeds 1-3) was `unexplained` every time, with a Gauss-Markov term at the
/// filter's own scale (tau_c 0.033-0.038 s) beside a second, short filter, and warm-ups,
/// sinusoids or bands after them; sessions 13-14 named the first order alone, 27-34% short
/// (the averaged model in the dead band with the mean on a step). With the grid model
/// (`gap::rounding::rounding_avar_on_grid`, docs/gap.md "The grid model wired (session 15)")
/// seeds 1-3 name it within 2.5% (0.0425, 0.0418, 0.0423 s against 0.0415); held to 6%. The
/// record says the channel is quantization-limited with the filtered noise over the step
/// from the final fit: 0.3855, 0.3849, 0.3833 on seeds 1-3 against the simulated 0.3840 (the
/// covariance's N, fitted beyond ten memories of the filter where the rounding's correlated
/// error still lowers the curve, gave 0.340, 0.335, 0.348 until session 17); held to 2%.
#[test]
fn the_dead_band_is_a_discrepancy_not_an_effect() {
    let ratio = accf29_sigma() / 1.4535586033795069e-2;
    assert!((ratio - 0.384).abs() < 0.001, "{ratio}");
    for seed in [1, 2] {
        let q = dead_band_first_order(ACCF29, seed, 0.06);
        assert!(
            (q.ratio / ratio - 1.0).abs() < 0.02,
            "seed {seed}: ratio {} against {ratio}",
            q.ratio
        );
    }
}

/// The step (u/s) of [`grid_discrepancy`]'s unit: 1 / 0.35 filtered sigmas (the dead band).
fn grid_step() -> f64 {
    accf29_sigma() / 0.35
}

/// A first order of 15 samples at 361 Hz, white rate only, each rate sample rounded to a step
/// of 1 / 0.35 filtered sigmas ([`grid_step`]), with the constant input `bias_steps` steps off
/// the grid and a rate random walk `k` (u/s/sqrt(s)): the discrepancy the diagnosis's last
/// pass carries.
fn grid_discrepancy(
    bias_steps: f64,
    k: f64,
) -> Option<allanscope::gap::discrepancy::RoundingDiscrepancy> {
    let (tau0, t, n, step) = (ACCF29_TAU0, ACCF29_T, ACCF29_N, grid_step());
    let model = format!(
        "tau0_s = {tau0}\n[[channel]]\nname = \"x\"\nunit = \"u\"\nN = {n}\nK = {k}\n\
         bias = {}\noutput_filter = {{ time_constant = {t} }}\nrate_lsb = {step}\n",
        bias_steps * step
    );
    let snap = snapshot_of(&model, tau0, 5, 1800.0);
    last_pass_problem(&snap, t).discrepancy
}

/// The rounding model's error depends on the run's averages `A_p` of `cos(2 pi p mu / L)`
/// (docs/gap.md "Rounding after a filter (session 12)"), which the block means measure and the
/// grid model then holds, so that only the residual of that estimate,
/// `4 GRID_FLOOR exp(-x / 2)`, is carried (`gap::discrepancy::grid_residual_bound`; 0.036 at
/// the simulated 0.35 filtered sigmas per step; the covariance's N sets sigma, 0.29 steps on
/// a step, held to 20%): with the
/// mean on a step `|A_1|` is read above 0.95, a quarter step off the grid below 0.05, and with
/// the mean wandering over several steps in the run (a random walk of 3 steps' rms over ten
/// minutes) below 0.1; the bound is the residual in all three, a tenth of the worst case's
/// (`relative_bound`, 0.356), which a channel without the block means keeps.
#[test]
fn the_discrepancy_follows_where_the_mean_falls_on_the_grid() {
    use allanscope::gap::discrepancy::{grid_residual_bound, relative_bound};
    let check = |d: Option<allanscope::gap::discrepancy::RoundingDiscrepancy>,
                 what: &str,
                 a1: &dyn Fn(f64) -> bool| {
        let d = d.unwrap_or_else(|| panic!("{what}: no discrepancy"));
        assert!((d.sigma_steps / 0.35 - 1.0).abs() < 0.2, "{what}: {d:?}");
        assert!(
            (d.bound / grid_residual_bound(d.sigma_steps) - 1.0).abs() < 1e-9,
            "{what}: {d:?}"
        );
        assert!(
            d.bound < 0.11 * relative_bound(d.sigma_steps),
            "{what}: {d:?}"
        );
        assert!(d.grid_first_harmonic.is_some_and(a1), "{what}: {d:?}");
    };
    check(grid_discrepancy(3.0, 0.0), "on a step", &|a| a > 0.95);
    check(grid_discrepancy(3.25, 0.0), "a quarter step off", &|a| {
        a < 0.05
    });
    // K sqrt(600 s) = 3 steps.
    let k = 3.0 * grid_step() / 600f64.sqrt();
    check(grid_discrepancy(3.0, k), "a wandering mean", &|a| a < 0.1);
}

/// [`ACCF29`]'s unit rounded at 0.3 filtered sigmas per step (the dead band, below
/// `MIN_SIGMA_STEPS`) with a constant input of 7.25 steps: the mean a quarter step off the grid,
/// where the rounding model averaged over the mean's position drops almost nothing (within 3.5%
/// of simulation at 0.3 steps: docs/gap.md, "The floor on the grid (session 14)").
const ACC03Q: &str = "tau0_s = 0.002770083102493075\n[[channel]]\nname = \"x\"\nunit = \"u\"\n\
                      N = 1.6073054280352312e-3\nB = 2.6048171847428513e-4\n\
                      K = 8.350094600544586e-5\n\
                      flicker_band_s = [0.002770083102493075, 3.9011756822523996e4]\n\
                      output_filter = { time_constant = 4.1453357056591464e-2 }\n\
                      rate_lsb = 1.8603793963662248e-2\nbias = 1.348775062365513e-1\n";

/// The floor is kept below `MIN_SIGMA_STEPS` where the block means place the mean on the grid
/// (`gap::discrepancy::floor_harmonics`): on main 9ebb8a8 the CLI's diagnosis of this unit
/// (1800 s, seeds 1-3) named the first order 35-38% short (0.0258-0.0269 s against 0.0415),
/// the floor dropped; session 14 (the averaged model kept where the grid said it held) named it
/// within 1% on seeds 2 and 3 and 38% short on seed 1, whose random walk leaves the run's
/// `|A_1|` at 0.33; with the grid model seeds 1-3 are within 3.4% (0.0429, 0.0418, 0.0412 s).
/// Held here to 6%, seeds 1 and 2, with the dead band said and its noise over the step read
/// from the final fit (0.3022, 0.2993, 0.3016 on seeds 1-3 against 0.3; from the covariance's N
/// until session 17, 0.281, 0.307, 0.329), held to 2%.
#[test]
fn the_floor_holds_in_the_dead_band_with_the_mean_off_the_grid() {
    for seed in [1, 2] {
        let q = dead_band_first_order(ACC03Q, seed, 0.06);
        assert!((q.ratio - 0.3).abs() < 0.006, "seed {seed}: {q:?}");
    }
}

/// `family_gap --families accgrav --hours 1,2 --seed 141` clean draw 17 (docs/repro/session15/
/// accgrav17.toml): an accelerometer at 412 Hz behind a first order of 6.1 samples, gravity's
/// projection (25.8 steps) on its axis, each rate sample rounded to a step of 1 / 0.34
/// filtered sigmas: the dead band with the mean near a step, where the rounded output is a
/// nonlinear function of the filtered rate and the averaged rounding model fails.
const ACCG17: &str = "tau0_s = 0.0024271844660194173\n[[channel]]\nname = \"x\"\nunit = \"u\"\n\
                      N = 2.078826765958311e-3\nB = 1.3593783711651829e-3\n\
                      K = 9.025333742085801e-5\n\
                      flicker_band_s = [0.0024271844660194173, 3.8443870572405525e4]\n\
                      bias = 9.153514833500154e-1\n\
                      output_filter = { time_constant = 1.491873109264487e-2 }\n\
                      rate_lsb = 3.547743191483923e-2\n";

/// On main 3e1d921 the family's run of this unit (3844 s) ended `unexplained`, the unit's own
/// first order named as a Gauss-Markov term at its time constant beside a second order (G
/// 6.4), and so did the CLI's diagnosis at 1800 s with simulator seed 3 (G 3.92); with the
/// grid model (docs/gap.md, "The grid model wired (session 15)") seeds 1-3 at 1800 s name the
/// first order within 0.6% (0.01485, 0.01508, 0.01499 s against 0.01492; seed 1 adds a
/// warm-up, on main too). Seeds 2 and 3, held to 3%.
#[test]
fn the_dead_band_near_a_step_names_the_first_order_not_a_gauss_markov_term() {
    for seed in [2, 3] {
        first_order_alone(
            ACCG17,
            0.0024271844660194173,
            1.491873109264487e-2,
            seed,
            0.03,
        );
    }
}

/// `family_gap --families accgrav --hours 1,2 --seed 141` clean draw 4: an accelerometer at
/// 242 Hz behind a first order of 21 samples, gravity's projection on its axis 0.3 steps off
/// the grid, each rate sample rounded to a step of 1 / 0.275 filtered sigmas, and a flicker
/// rate `B` of 0.2 steps: the mean wanders within each block of the run by about 0.15-0.2
/// steps (`gap::rounding::within_block_wander`), which spreads the samples' positions on the
/// grid and damps the mean-dependent part of the rounding's error.
const ACCG4: &str = "tau0_s = 0.004132231404958678\n[[channel]]\nname = \"x\"\nunit = \"u\"\n\
                     N = 9.785249792282284e-4\nB = 1.7458333327705986e-3\n\
                     K = 2.2364686588445553e-5\n\
                     flicker_band_s = [0.004132231404958678, 7.101077050016733e4]\n\
                     bias = -6.358156708859486e0\n\
                     output_filter = { time_constant = 8.636734412459114e-2 }\n\
                     rate_lsb = 8.560865116489994e-3\n";
const ACCG4_TAU0: f64 = 0.004132231404958678;
const ACCG4_T: f64 = 8.636734412459114e-2;
const ACCG4_N: f64 = 9.785249792282284e-4;
const ACCG4_STEP: f64 = 8.560865116489994e-3;

/// Without the wander the grid model takes the block means' positions for every sample's and
/// the fit's N comes out low (at 3600 s, simulator seed 1: the filtered noise at 0.217 steps
/// against 0.275, so the floor was dropped as below the grid model's range and a Gauss-Markov
/// term at the filter's time constant was named with a 66-Hz sinusoid, G 3.21). At 1800 s,
/// main c291ad8 named the first order on seeds 1-2 (87.8, 96.3 ms against 86.4) and on seed 3
/// a Gauss-Markov term at 84.9 ms with a band at 8.6 Hz, `unexplained` (G 5.41); the family's
/// run (7101 s) and the CLI's at 7200 s (seeds 1-2) likewise. With the wander seeds 1-5 name
/// the first order alone (89.1, 95.5, 84.2, 97.3, 81.7 ms), the dead band said with the
/// filtered noise at 0.273, 0.287, 0.265, 0.280, 0.256 steps against 0.275. Seeds 1 and 3, the
/// time constant held to 6% and the noise over the step to 10%.
#[test]
fn the_mean_wandering_within_a_block_keeps_the_floor_and_names_the_first_order() {
    let ratio = first_order_sigma(ACCG4_N, ACCG4_T, ACCG4_TAU0) / ACCG4_STEP;
    assert!((ratio - 0.275).abs() < 0.002, "{ratio}");
    for seed in [1, 3] {
        let q = first_order_alone(ACCG4, ACCG4_TAU0, ACCG4_T, seed, 0.06)
            .quantization_limited
            .unwrap_or_else(|| panic!("seed {seed}: the dead band is not said"));
        assert!(
            (q.ratio / ratio - 1.0).abs() < 0.1,
            "seed {seed}: ratio {} against {ratio}",
            q.ratio
        );
    }
}
