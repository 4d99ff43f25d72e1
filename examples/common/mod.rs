//! Helpers shared by the diagnosis studies (`examples/blind_gap.rs`, `examples/family_gap.rs`):
//! parallel map over draws, empirical quantiles, Wilson intervals, log-uniform draws, the
//! simulator model lines of a drawn effect and the simulation of a drawn channel with the bias
//! jumps the benchmarks add themselves (so that the truth is the realised jumps).
//!
//! Each example that uses it declares `mod common;`; not every example uses every helper.
#![allow(dead_code)]

use allanscope::gap::{EffectKind, EffectParams};
use allanscope::model::terms;
use allanscope::sim::{SimModel, Simulator};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::path::Path;

/// `f(item)` for each of `items` on `threads` threads (item `k` on thread `k % threads`), in
/// the order of `items`.
pub fn par_map<I: Copy + Sync, T: Send>(
    items: &[I],
    threads: usize,
    f: impl Fn(I) -> T + Sync,
) -> Vec<T> {
    let threads = threads.max(1);
    let f = &f;
    let mut out: Vec<(usize, T)> = std::thread::scope(|s| {
        let hs: Vec<_> = (0..threads)
            .map(|t| {
                s.spawn(move || {
                    items
                        .iter()
                        .enumerate()
                        .filter(|(k, _)| k % threads == t)
                        .map(|(k, &i)| (k, f(i)))
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

/// Empirical quantile `p` of the finite values: the value of rank `round((n - 1) p)` (0-based)
/// in sorted order; NaN when there are none.
pub fn quantile(v: &[f64], p: f64) -> f64 {
    let mut v: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[((v.len() as f64 - 1.0) * p).round() as usize]
}

/// Standard normal distribution function.
pub fn std_normal_cdf(x: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::new(0.0, 1.0).map_or(f64::NAN, |n| n.cdf(x))
}

/// Standard normal quantile (`Phi^-1(p)`).
pub fn std_normal_quantile(p: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::new(0.0, 1.0).map_or(f64::NAN, |n| n.inverse_cdf(p))
}

/// Wilson score interval (95%) of a share `k / n` (Wilson 1927; Brown, Cai and DasGupta 2001):
/// `(p + z^2/2n -+ z sqrt(p(1-p)/n + z^2/4n^2)) / (1 + z^2/n)`, `z = 1.96`. `(0, 1)` when
/// `n = 0`.
pub fn wilson(k: usize, n: usize) -> (f64, f64) {
    if n == 0 {
        return (0.0, 1.0);
    }
    let z = 1.959_963_985;
    let (nf, p) = (n as f64, k as f64 / n as f64);
    let c = p + z * z / (2.0 * nf);
    let h = z * (p * (1.0 - p) / nf + z * z / (4.0 * nf * nf)).sqrt();
    let d = 1.0 + z * z / nf;
    (((c - h) / d).max(0.0), ((c + h) / d).min(1.0))
}

/// `k/n (p%, 95% Wilson lo-hi%)`.
pub fn share(k: usize, n: usize) -> String {
    let (lo, hi) = wilson(k, n);
    format!(
        "{k}/{n} ({:.0}%, {:.0}-{:.0}%)",
        100.0 * k as f64 / n.max(1) as f64,
        100.0 * lo,
        100.0 * hi
    )
}

/// A draw log-uniform in `[lo, hi]`.
pub fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.random::<f64>() * (hi.ln() - lo.ln())).exp()
}

/// `count` jumps `(time s, size u/s)` at uniform times in `[0, t_run)`, Gaussian sizes of rms
/// `rms_size`, sorted by time.
pub fn draw_jumps(count: u64, rms_size: f64, t_run: f64, seed: u64) -> Vec<(f64, f64)> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut jumps: Vec<(f64, f64)> = (0..count)
        .map(|_| {
            let t = rng.random::<f64>() * t_run;
            // Box-Muller normal.
            let (u1, u2) = (rng.random::<f64>().max(1e-300), rng.random::<f64>());
            let z = (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos();
            (t, rms_size * z)
        })
        .collect();
    jumps.sort_by(|a, b| a.0.total_cmp(&b.0));
    jumps
}

/// Adds the rate steps `jumps` (time s, size u/s, sorted by time) to increments of `tau0` s:
/// each increment gains the level reached times its length, split exactly inside the increment
/// where a step falls.
pub fn add_jumps(inc: &mut [f64], tau0: f64, jumps: &[(f64, f64)]) {
    let mut level = 0.0;
    let mut next = 0;
    for (k, o) in inc.iter_mut().enumerate() {
        let (t0, t1) = (k as f64 * tau0, (k + 1) as f64 * tau0);
        let mut add = level * tau0;
        while next < jumps.len() && jumps[next].0 < t1 {
            let (tj, s) = jumps[next];
            add += s * (t1 - tj.max(t0));
            level += s;
            next += 1;
        }
        *o += add;
    }
}

/// The rms of the sizes of `jumps`.
pub fn jumps_rms(jumps: &[(f64, f64)]) -> f64 {
    (jumps.iter().map(|j| j.1 * j.1).sum::<f64>() / jumps.len().max(1) as f64).sqrt()
}

/// The simulator's model lines (config/models format) of `effect`: none for bias jumps, which
/// [`simulate_channel`] adds itself, nor for a temperature coefficient (these runs carry no
/// temperature column).
pub fn effect_toml(effect: Option<EffectParams>) -> String {
    match effect {
        Some(EffectParams::GaussMarkov { sigma, tau_c_s }) => {
            format!("gauss_markov = {{ sigma = {sigma:e}, tau_c = {tau_c_s:e} }}\n")
        }
        Some(EffectParams::Sinusoid {
            amplitude,
            frequency_hz,
        }) => format!(
            "sinusoid = {{ amplitude = {amplitude:e}, frequency = {frequency_hz:e}, phase = 0.3 }}\n"
        ),
        Some(EffectParams::OutputFilter { time_constant_s }) => {
            format!("output_filter = {{ time_constant = {time_constant_s:e} }}\n")
        }
        Some(EffectParams::Warmup {
            amplitude,
            time_constant_s,
        }) => format!("warmup = {{ amplitude = {amplitude:e}, time_constant = {time_constant_s:e} }}\n"),
        Some(EffectParams::MovingAverage {
            taps,
            stages,
            decimation,
        }) => {
            format!("moving_average = {{ taps = {taps}, stages = {stages}, decimation = {decimation} }}\n")
        }
        Some(EffectParams::SecondOrderFilter {
            natural_frequency_hz,
            damping,
            ..
        }) => format!(
            "second_order_filter = {{ natural_frequency = {natural_frequency_hz:e}, damping = {damping:e} }}\n"
        ),
        Some(EffectParams::ZeroPhaseFilter { time_constant_s }) => {
            format!("zero_phase_filter = {{ time_constant = {time_constant_s:e} }}\n")
        }
        Some(EffectParams::FirFilter {
            cutoff_hz,
            decimation,
            taps,
        }) => format!(
            "fir_filter = {{ taps = {taps}, cutoff = {cutoff_hz:e}, decimation = {decimation} }}\n"
        ),
        Some(EffectParams::ButterworthFilter {
            cutoff_hz,
            decimation,
            order,
        }) => format!(
            "butterworth_filter = {{ order = {order}, cutoff = {cutoff_hz:e}, decimation = {decimation} }}\n"
        ),
        Some(EffectParams::BandNoise {
            frequency_hz,
            sigma,
            width_hz,
        }) => format!(
            "band_noise = {{ sigma = {sigma:e}, frequency = {frequency_hz:e}, width = {width_hz:e} }}\n"
        ),
        Some(EffectParams::BiasJumps { .. }) | Some(EffectParams::Temperature { .. }) | None => {
            String::new()
        }
    }
}

/// Simulates channel 0 of the model `toml` (its base terms and `effect_toml(effect)`) for
/// `t_run` s of `tau0` increments. Bias jumps are added here rather than by the simulator, so
/// that the truth is the realised jumps: `count` jumps at uniform times (a Poisson process
/// given its count), Gaussian sizes of rms `rms_size`. Returns the increments, the realised
/// effect (jumps: the count and the rms of the drawn sizes) and the realised jumps `(time s,
/// size u/s)`. `origin` names the generated model in an error.
pub fn simulate_channel(
    toml: &str,
    origin: &str,
    tau0: f64,
    t_run: f64,
    effect: Option<EffectParams>,
    seed: u64,
) -> (Vec<f64>, Option<EffectParams>, Vec<(f64, f64)>) {
    // Jumps change the bias the unit's counter sees, so they go in before its quantization
    // with carry: the model's `lsb` is taken out of the simulation and applied after them (before
    // session 9 they were added to the quantized increments, which then were no longer whole
    // multiples of the LSB).
    let jumpy = matches!(effect, Some(EffectParams::BiasJumps { .. }));
    let (toml, lsb) = if jumpy {
        take_lsb(toml)
    } else {
        (toml.to_string(), None)
    };
    let model = SimModel::from_toml_str(&toml, Path::new(origin)).expect("generated model");
    let mut sim = Simulator::new(&model, seed);
    let mut inc = vec![0.0; (t_run / tau0) as usize];
    sim.fill_channel(0, &mut inc);
    let mut truth = effect;
    let mut jumps = Vec::new();
    if let Some(EffectParams::BiasJumps { count, rms_size }) = effect {
        jumps = draw_jumps(count, rms_size, t_run, seed ^ 0x0005_eed1);
        add_jumps(&mut inc, tau0, &jumps);
        truth = Some(EffectParams::BiasJumps {
            count,
            rms_size: jumps_rms(&jumps),
        });
    }
    if let Some(l) = lsb {
        quantize_with_carry(&mut inc, l);
    }
    (inc, truth, jumps)
}

/// The model text without its `lsb = ...` line, and that LSB (u); one channel.
fn take_lsb(toml: &str) -> (String, Option<f64>) {
    let mut lsb = None;
    let mut out = String::with_capacity(toml.len());
    for line in toml.lines() {
        match line.trim().strip_prefix("lsb") {
            Some(rest) if rest.trim_start().starts_with('=') => {
                let v = rest.trim_start()[1..].trim();
                lsb = Some(v.parse::<f64>().expect("generated model: lsb"));
            }
            _ => {
                out += line;
                out.push('\n');
            }
        }
    }
    (out, lsb)
}

/// Quantization with carry (a counter that keeps its remainder): each increment becomes the
/// difference of the running sum rounded to whole `lsb` (u).
pub fn quantize_with_carry(inc: &mut [f64], lsb: f64) {
    let (mut sum, mut prev) = (0.0f64, 0.0f64);
    for v in inc.iter_mut() {
        sum += *v;
        let q = (sum / lsb).round();
        *v = (q - prev) * lsb;
        prev = q;
    }
}

/// The Gauss-Markov prior: `tau_c` log-uniform in `[.0 tau0, T_run / .1]`.
pub const GM_TAU_C_PRIOR: (f64, f64) = (20.0, 50.0);
/// The sinusoid prior: the frequency log-uniform in `[.0 / T_run, .1 / tau0]` Hz.
pub const SIN_FREQ_PRIOR: (f64, f64) = (30.0, 0.1);
/// The output filter prior: the time constant log-uniform in `[tau0, this tau0]`.
pub const FILTER_TAU_PRIOR: f64 = 10.0;
/// The warm-up prior: `T` log-uniform in `[.0 s, T_run / .1]`.
pub const WARMUP_T_PRIOR: (f64, f64) = (60.0, 5.0);

/// The Gauss-Markov `sigma` whose peak ADEV is `rho` times the base's there: peak ADEV 0.6174
/// sigma at tau = 1.893 tau_c (docs/theory.md section 3).
pub fn gm_sigma(rho: f64, tau_c: f64, base_adev: &dyn Fn(f64) -> f64) -> f64 {
    rho * base_adev(1.893 * tau_c) / 0.6174
}

/// The sinusoid's amplitude whose first ADEV maximum is `rho` times the base's there: the
/// first maximum of `sin^2(x) / x` at `x = pi 0.371`, 0.725 A.
pub fn sinusoid_amplitude(rho: f64, f_hz: f64, base_adev: &dyn Fn(f64) -> f64) -> f64 {
    rho * base_adev(0.371 / f_hz) / 0.725
}

/// The warm-up amplitude whose ADEV is at most `rho` times the base's over the dense taus of
/// a record of `t_run` s (`warmup_avar` is exact for the estimator on this record).
pub fn warmup_amplitude(
    rho: f64,
    t_s: f64,
    tau0: f64,
    t_run: f64,
    base_adev: &dyn Fn(f64) -> f64,
) -> f64 {
    let n_inc = (t_run / tau0) as u64;
    let peak = allanscope::gap::evidence::dense_ms(4, n_inc / 10)
        .iter()
        .map(|&m| {
            let tau = m as f64 * tau0;
            terms::warmup_avar(1.0, t_s, tau0, m, n_inc).sqrt() / base_adev(tau)
        })
        .fold(0.0, f64::max);
    rho / peak
}

/// The parameters of an effect of `kind` whose peak ADEV is `rho` times the base model's
/// (`base_adev`, u/s at tau s) on a run of `t_run` s at `tau0`, drawn from the benchmarks'
/// priors (examples/family_gap.rs's module doc; docs/gap.md, "Blind benchmark"): the
/// Gauss-Markov `tau_c` log-uniform in [20 tau0, T_run / 50], the sinusoid's frequency in
/// [30 / T_run, 0.1 / tau0], the filters' memory in [1, 10] tau0 (moving average: 2 to
/// `ma_taps_hi` taps, 1-2 stages), the warm-up's `T` in [60 s, T_run / 5] with its exact AVAR
/// on the record peaking at `rho`, and 2-8 jumps whose rate-random-walk ADEV at T_run / 10 is
/// `rho` times the base. `rho` is not used by the filters. Temperature is not drawn (these runs
/// carry no temperature column; examples/temperature_study.rs has its own study): a zero
/// coefficient.
pub fn draw_effect_params(
    rng: &mut Xoshiro256PlusPlus,
    kind: EffectKind,
    rho: f64,
    tau0: f64,
    t_run: f64,
    base_adev: &dyn Fn(f64) -> f64,
    ma_taps_hi: f64,
) -> EffectParams {
    match kind {
        EffectKind::GaussMarkov => {
            let tau_c = log_uniform(rng, GM_TAU_C_PRIOR.0 * tau0, t_run / GM_TAU_C_PRIOR.1);
            EffectParams::GaussMarkov {
                sigma: gm_sigma(rho, tau_c, base_adev),
                tau_c_s: tau_c,
            }
        }
        EffectKind::Sinusoid => {
            let f = log_uniform(rng, SIN_FREQ_PRIOR.0 / t_run, SIN_FREQ_PRIOR.1 / tau0);
            EffectParams::Sinusoid {
                amplitude: sinusoid_amplitude(rho, f, base_adev),
                frequency_hz: f,
            }
        }
        EffectKind::OutputFilter => EffectParams::OutputFilter {
            time_constant_s: log_uniform(rng, tau0, FILTER_TAU_PRIOR * tau0),
        },
        EffectKind::Warmup => {
            let tc = log_uniform(rng, WARMUP_T_PRIOR.0, t_run / WARMUP_T_PRIOR.1);
            EffectParams::Warmup {
                amplitude: warmup_amplitude(rho, tc, tau0, t_run, base_adev),
                time_constant_s: tc,
            }
        }
        EffectKind::BiasJumps => {
            let count = rng.random_range(2..=8u64);
            let tau = t_run / 10.0;
            let s = rho * base_adev(tau) / (tau / (3.0 * t_run / count as f64)).sqrt();
            EffectParams::BiasJumps { count, rms_size: s }
        }
        EffectKind::MovingAverage => EffectParams::MovingAverage {
            taps: log_uniform(rng, 2.0, ma_taps_hi).round() as u32,
            stages: rng.random_range(1..=2u32),
            decimation: 1,
        },
        EffectKind::SecondOrderFilter => EffectParams::SecondOrderFilter {
            natural_frequency_hz: 1.0
                / (2.0 * std::f64::consts::PI * log_uniform(rng, tau0, 10.0 * tau0)),
            damping: log_uniform(rng, 0.2, 2.0),
            bilinear: false,
            zero: None,
        },
        EffectKind::ZeroPhaseFilter => EffectParams::ZeroPhaseFilter {
            time_constant_s: log_uniform(rng, tau0, FILTER_TAU_PRIOR * tau0),
        },
        // 15-95 taps, the cut-off log-uniform from 0.02 to 0.4 of the output rate
        EffectKind::FirFilter => EffectParams::FirFilter {
            taps: rng.random_range(15..=95u32),
            cutoff_hz: log_uniform(rng, 0.02 / tau0, 0.4 / tau0),
            decimation: 1,
        },
        // orders 3-6, the cut-off log-uniform from 0.02 to 0.3 of the output rate
        EffectKind::ButterworthFilter => EffectParams::ButterworthFilter {
            decimation: 1,
            order: rng.random_range(3..=6u32),
            cutoff_hz: log_uniform(rng, 0.02 / tau0, 0.3 / tau0),
        },
        EffectKind::Temperature => EffectParams::Temperature {
            coefficient: 0.0,
            lo: 0.0,
            hi: 0.0,
            quadratic: None,
            lag: None,
        },
        // Centre log-uniform from 30 periods per run to 0.4 of the sample rate, width 5-50% of
        // it, the rms for the drawn peak ratio of its exact AVAR over the base's ADEV at the
        // dense taus.
        EffectKind::BandNoise => {
            let f0 = log_uniform(rng, 30.0 / t_run, 0.4 / tau0);
            let w = f0 * log_uniform(rng, 0.05, 0.5);
            let n_inc = (t_run / tau0) as u64;
            let peak = allanscope::gap::evidence::dense_ms(4, n_inc / 10)
                .iter()
                .map(|&m| {
                    let tau = m as f64 * tau0;
                    allanscope::sim::band_noise::band_noise_avar(1.0, f0, w, tau0, m).sqrt()
                        / base_adev(tau)
                })
                .fold(0.0, f64::max);
            EffectParams::BandNoise {
                frequency_hz: f0,
                sigma: rho / peak,
                width_hz: w,
            }
        }
    }
}
