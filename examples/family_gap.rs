//! Blind benchmark of the sim-to-real diagnosis over the space of units (docs/gap.md,
//! "Families of units"), where examples/blind_gap.rs draws VOG4-like gyros only.
//!
//! Each draw picks a family, then its base five-term model with each term over a wide
//! (log-uniform) range, its sampling step, run length and the quantization that kind of unit
//! really does, then a hidden effect (or none), simulates a capture with `allanscope::sim` and
//! runs the diagnosis, which never sees the draw. The effects cycle through `--effects`; each
//! has a peak size `rho` (its ADEV over the base model's ADEV at that tau) log-uniform in
//! [0.3, 3], so every effect draw counts for the issue's detection target (rho >= 0.3):
//! - `gauss_markov`: `tau_c` log-uniform in [20 tau0, T_run / 50], `sigma` from `rho` at the
//!   peak `1.893 tau_c`;
//! - `sinusoid`: frequency log-uniform in [30 / T_run, 0.1 / tau0], amplitude from `rho` at
//!   `tau = 0.371 / f`;
//! - `output_filter`: first-order, time constant log-uniform in [1, 10] tau0 (`rho` unused);
//! - `warmup`: `T` log-uniform in [60 s, T_run / 5], amplitude so that its exact AVAR on the
//!   record peaks at `rho` times the base;
//! - `bias_jumps`: 2-8 jumps at uniform times, Gaussian sizes whose rate-random-walk ADEV at
//!   `T_run / 10` is `rho` times the base; the truth is the realised count and rms.
//!
//! Beside the diagnosis, each effect draw gets its *oracle*: the most powerful test of that
//! exact effect (shape and amplitude told) on the same evidence, `z = u' r_w / |u|`
//! (`gap::oracle`: `curve_known_z` on the curve for the stationary effects, the block-mean GLS
//! for the warm-up and the jumps; docs/gap.md, "Oracle bounds"), and its expected power
//! `Phi(|u| - z_{1-alpha})` at a false-alarm share `alpha`. Each clean draw gets the oracle
//! statistic of one effect of each kind drawn from the same priors on its base (a stream of its
//! own): their share above the nominal threshold checks that `z` is N(0, 1) on clean runs in
//! that family.
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
//!   m/s^2/sqrt(s), rate samples rounded as the MEMS gyro's, 100-1000 Hz;
//! - `coarse` (not in the default list): a tactical FOG whose angle LSB is 3-30 times the
//!   per-sample noise, so that the quantization error is a slow wander rather than white phase
//!   noise (docs/gap.md, "Quantization-limited units").
//!
//! Held-out families (`--families heldout`; defined before issue 13's last calibration round
//! and run only for its final tables, so no threshold was tuned on them):
//! - `consmems`: consumer MEMS gyro at 100 Hz, ARW 0.3-3 deg/sqrt(h), flicker 10-100 deg/h,
//!   K 5-50 deg/h/sqrt(h), each rate sample rounded to a very coarse LSB of 0.7-3 times the
//!   sample's noise (a +-2000 deg/s full scale on 16 bits);
//! - `fog2k`: a FOG sampled at 2 kHz (the step raised for runs above 8 M samples), ARW
//!   0.005-0.05 deg/sqrt(h), flicker 0.02-0.2 deg/h, a fine angle LSB;
//! - `accr`: an accelerometer at 200 Hz whose rate ramp `R` dominates the long taus (its ADEV
//!   meets the flicker floor at T_run / 100 to T_run / 20), VRW 0.01-0.05 m/s/sqrt(h), flicker
//!   10-50 ug, rate samples rounded.
//!
//! Held-out families of session 7 (defined at 14:27 UTC on 2026-11-24, before any run of them;
//! run only for the final per-family tables):
//! - `kmems`: a MEMS gyro at 1 kHz whose rate random walk dominates the long taus: ARW
//!   0.05-0.3 deg/sqrt(h), flicker 0.5-3 deg/h, `K` such that its ADEV meets the flicker floor
//!   at `tau_k` log-uniform in [T_run / 1000, T_run / 100], each rate sample rounded to 0.1-1 of
//!   the sample's noise;
//! - `rfog`: a FOG at 100 Hz (tau0 = 10 ms) with a rate ramp: ARW 0.01-0.05 deg/sqrt(h),
//!   flicker 0.02-0.2 deg/h, K 0.005-0.05 deg/h/sqrt(h), `R` such that its ADEV meets the
//!   flicker floor at `tau_x` log-uniform in [T_run / 50, T_run / 10], a fine angle LSB.
//!
//! Held-out families of session 9 (defined at 20:27 UTC on 2026-11-24 in the helpers' log,
//! before any run of them; `--families unseen`; nothing tuned on
//! them):
//! - `hrmems`: a high-rate MEMS IMU gyro at 2 kHz (tau0 0.5 ms), ARW 0.15-0.6 deg/sqrt(h), bias
//!   flicker 3-30 deg/h, K 0.5-5 deg/h/sqrt(h), each rate sample rounded to 0.1-1 of the
//!   sample's noise; runs 20-60 min (log-uniform; `--hours` overrides). Its detection draws also
//!   take the Bartlett / moving-average filter such parts run (`--effects moving_average`):
//!   2-32 taps, 1-2 stages (two stages of a moving average are a Bartlett window);
//! - `qtzgyro`: a quartz tuning-fork gyro at 200 Hz with large `K` and `R`: ARW 0.5-3
//!   deg/sqrt(h), flicker 10-100 deg/h, `K sqrt(tau / 3)` meets the flicker floor `0.664 B` at
//!   `tau_k` log-uniform in [T_run / 300, T_run / 30], `R tau / sqrt(2)` meets the `K` slope at
//!   `tau_k` times a log-uniform factor in [3, 30]; rate samples rounded to 0.1-1 of the
//!   sample's noise (its ADC);
//! - `servoacc`: a servo (pendulous) accelerometer at 100 Hz with coarse pulse counting: VRW
//!   0.005-0.03 m/s/sqrt(h), flicker 5-50 ug, K 1e-6-1e-5 m/s^2/sqrt(s), no `R` nor `Q`, the
//!   velocity counted with carry at an LSB of 1-10 times the per-sample noise `N sqrt(tau0)`;
//! - `short`: a MEMS gyro drawn as `memsgyro` over a very short run of 10-20 min
//!   (log-uniform; `--hours` is ignored);
//! - `long`: a tactical FOG drawn as `tacfog`, at 100 Hz, over 8-24 h (log-uniform, up to
//!   8.64 M samples; `--hours` is ignored).
//!
//! Held-out families of session 10 (defined at 22:41 UTC on 2026-11-24 in the helpers' log,
//! docs/repro/session10/helpers-log.md, before any run of them; `--families unseen10`; nothing tuned
//! on them; their tables ran with `--hours 1,2`, `lowrate` with `--hours 1,3`). Three carry an
//! *intrinsic* filter, part of the unit as sold, so that their right answer on a clean run is
//! that filter named and nothing else (`adistemp`: also a slow drift, below):
//! - `adis`: an ADIS16405-like gyro channel at 100 Hz as the part is: N 1.5-4 deg/sqrt(h),
//!   flicker 10-50 deg/h, K 2-20 deg/h/sqrt(h), a constant turn-on bias uniform in
//!   [-0.5, 0.5] deg/s, a decimating (Bartlett) average acting on everything (`moving_average`,
//!   `2^M` taps with `M` uniform in {1, 2, 3}, 1 or 2 stages), then each rate sample rounded to
//!   the part's fixed LSB of 0.05 deg/s;
//! - `adistemp`: `adis` with a slow temperature-driven bias, the temperature never shown to the
//!   diagnosis: it settles by 3-10 degC (time constant 600-3600 s) under a cycle of 0.2-1 degC
//!   (period 600-3600 s), 2e-4-2e-3 deg/s per degC (all log-uniform). Allowed beside the moving
//!   average: a warm-up, a sinusoid within a factor 2 of the cycle's frequency, or nothing;
//! - `rlg`: a ring-laser gyro (arcsec) at 200-500 Hz, the angle counted with carry at 0.5-2
//!   arcsec per count, the dither-stripping residual as white angle noise `Q` of 0.1-0.5 count,
//!   the lock-in random walk N 0.001-0.005 deg/sqrt(h), flicker 0.0005-0.005 deg/h, K
//!   1e-5-1e-4 deg/h/sqrt(h), a constant input (Earth's rate on the axis) uniform in [0, 15]
//!   arcsec/s;
//! - `lowrate`: a MEMS gyro drawn as `memsgyro` at 10-50 Hz (tau0 20-100 ms);
//! - `accfilt`: a MEMS accelerometer drawn as `memsacc` at 200-1000 Hz behind a strong
//!   first-order output filter (time constant 5-30 tau0), then each rate sample rounded to 0.3-3
//!   of the filtered sample noise `N / sqrt(2 T_f)`;
//! - `navacc`: a navigation-grade (quartz-flexure) accelerometer whose I/F converter is counted
//!   with carry: VRW 5-30 ug/sqrt(Hz), flicker 1-10 ug, K 1e-7-1e-6 m/s^2/sqrt(s), `R` meeting the
//!   flicker floor at T_run / 30 to T_run / 3, 100-400 Hz, the LSB 0.3-3 of the per-sample noise,
//!   a constant input (gravity's projection) uniform in [-9.81, 9.81] m/s^2.
//!
//! Held-out families of session 11 (defined at 01:28 UTC on 2026-11-25 in the helpers' log,
//! docs/repro/session11/helpers-log.md, before any run of them; `--families unseen11`; nothing tuned
//! on them):
//! - `mimu`: a consumer MEMS IMU gyro at an ODR of 1-2 kHz, ARW 0.15-1 deg/sqrt(h), flicker 3-30
//!   deg/h, K 1-10 deg/h/sqrt(h), behind its digital low-pass (a `second_order_filter`, natural
//!   frequency ODR/20-ODR/4, damping 0.5-1), then each rate sample rounded (16-bit LSB) at
//!   0.3-1 of the filtered sample noise `N sqrt(rho_0 / tau0)`; runs 20-60 min;
//! - `cicgyro`: a MEMS gyro (memsgyro's terms) at 200-1000 Hz behind a sinc^3 decimation filter
//!   (`moving_average`, 2-8 taps, 3 stages), rate samples rounded at 0.1-1 of the filtered
//!   sample noise;
//! - `hrg`: a hemispherical resonator gyro at 100-500 Hz, ARW 0.0001-0.0005 deg/sqrt(h),
//!   flicker 0.0005-0.005 deg/h, K 1e-5-1e-4 deg/h/sqrt(h), the angle counted with carry at
//!   0.05-0.5 of the per-sample noise;
//! - `thermfog`: a tactical FOG (tacfog's terms and LSB) at 100 Hz over 12-24 h (`--hours`
//!   ignored) with a thermal bias drift never shown to the diagnosis: the temperature settles by
//!   1-5 degC (time constant 1-4 h) under a cycle of 0.5-2 degC (period 4-24 h), 0.005-0.05
//!   deg/h per degC; allowed on a clean run as `adistemp`'s drift: a warm-up, a sinusoid within
//!   a factor 2 of the cycle's frequency, or nothing;
//! - `fog5k`: a tactical FOG (tacfog's terms and LSB) at 5 kHz over 10-20 min (`--hours`
//!   ignored).
//!
//! Held-out families of session 12 (defined at 04:40 UTC on 2026-11-25 in the helpers' log,
//! docs/repro/session12/helpers-log.md, before any run of them; `--families unseen12`; nothing
//! tuned on them). Each carries a filter that is part of the unit as sold or as exported:
//! - `kalgyro`: a consumer IMU gyro (BMI088 / ICM-42688 class) recorded static for a Kalibr
//!   calibration: ODR 200 Hz over 3-11 h (`--hours` ignored; at most 7.92 M samples), ARW
//!   0.15-1 deg/sqrt(h), flicker 2-20 deg/h, K 1-10 deg/h/sqrt(h), a turn-on bias uniform in
//!   [-0.5, 0.5] deg/s, its digital low-pass (`second_order_filter`, natural frequency
//!   ODR/10-ODR/4, damping 0.5-1), then each rate sample rounded at 0.2-2 of the filtered sample
//!   noise `N sqrt(rho_0 / tau0)` (a 16-bit LSB over ranges of +-125 to +-2000 deg/s);
//! - `kalacc`: the same IMU's accelerometer on that stand: VRW 0.03-0.15 m/s/sqrt(h), flicker
//!   20-200 ug, K 1e-5-1e-4 m/s^2/sqrt(s), gravity's projection on the axis uniform in
//!   [-9.81, 9.81] m/s^2 (the rounding grid sits anywhere), the same low-pass, rate samples
//!   rounded at 0.1-1 of the filtered sample noise;
//! - `cicacc`: a low-noise sigma-delta MEMS accelerometer (ADXL355 class) at 125-1000 Hz behind
//!   its sinc^3 decimator (`moving_average`, 2-8 taps, 3 stages): VRW 20-80 ug/sqrt(Hz), flicker
//!   2-20 ug, K 1e-6-1e-5 m/s^2/sqrt(s), gravity on the axis as `kalacc`, rate samples rounded
//!   to the 20-bit LSB of its range (3.9, 7.8 or 15.6 ug), far below the noise;
//! - `zpexp`: a post-processed export of a MEMS gyro (`memsgyro`'s terms, 100-1000 Hz),
//!   zero-phase filtered (`zero_phase_filter`: first order forward and backward, time constant
//!   1-10 tau0) and written as floats (no rounding after the filter);
//! - `bartfog`: a tactical FOG (`tacfog`'s terms) at 200-1000 Hz whose DSP outputs a Bartlett
//!   average (`moving_average`, 2-16 taps, 2 stages), the angle counted with carry at 0.1-1 of
//!   the filtered per-sample angle noise `N sqrt(rho_0 tau0)`.
//!
//! A development family of session 25 (tuned on: "The counter behind a filter (session 25)"):
//! - `cntfog`: a tactical FOG (`tacfog`'s terms) at 200-1000 Hz behind a first order of 3-20
//!   tau0 or a Bartlett average of 4-16 taps, its angle counted with carry at 2-6 times the
//!   filtered per-sample angle motion `N sqrt(rho_0 tau0)`, an input rate of 0-15 deg/h; its
//!   clean runs follow the session-12 families' rule (one low-pass of any kind).
//!
//! A development family of session 14 (tuned on: "The floor on the grid (session 14)"):
//! - `accgrav`: `accfilt`'s accelerometer with gravity's projection on its axis uniform in
//!   [-9.81, 9.81] m/s^2, each rate sample rounded at 1-4 filtered sample sigmas (the dead band
//!   and just above it, the mean anywhere on the grid).
//!
//! On `mimu`, `cicgyro` and the session-12 families a clean run's false alarm is any named
//! effect that is not a low-pass, or two or more low-passes (a second-order low-pass near
//! critical damping and a zero-phase filter have the same `|H|^2`); the kind and its
//! parameters are reported beside (a zero-phase filter's time constant within 25%, as a first
//! order's).
//!
//! On the families with an intrinsic filter an `output_filter` (or other filter) draw replaces
//! that filter (the simulator holds one); their detection cells are the other four effects on
//! top of it.
//!
//! Run lengths are 1-3 h (log-uniform), one draw in ten 6-24 h at a sampling step raised so
//! that a run has at most 8 M samples (the benchmark's compute stays affordable); `--hours A,B`
//! draws them log-uniform in [A, B] h instead (no long draws).
//!
//! ```text
//! cargo run --release --example family_gap -- [--draws 20] [--seed 1] [--threads 2]
//!     [--families navfog,tacfog,vog4,memsgyro,ma4,memsacc]
//!     [--effects none,gauss_markov,sinusoid,output_filter,warmup,bias_jumps] [--hours 1,3]
//!     [--csv FILE] [--resid FILE] [--no-oracle] [--from 0] [--shares 1,1,1,0.5,1]
//!     [--models DIR]
//! ```
//!
//! `--draws` is per family and effect; `--from N` starts at draw `N` (a split run gives the
//! same draws as one run). Jump draws (and clean draws, for the level) also get the
//! fair jump ceiling: the most powerful test told the count and rms but not the times
//! (`oracle::JumpCeiling`), its p-value from 199 draws of the Gaussian null. `--resid FILE`
//! writes the base fit's standardized residuals per tau of the clean draws, from the first tau
//! the diagnosis reads (a quantization-limited unit's `tau_white`; so do the `--csv` columns
//! computed from the base fit). Prints, per family: the false alarms (clean runs whose
//! verdict is not `consistent`), the confusion matrix (truth against the first effect named),
//! detection (the true effect named anywhere) against the oracle at 5% and at the share each
//! test of the diagnosis spends (`--shares`, in percent, per effect in the order
//! gauss_markov, sinusoid, output_filter, warmup, bias_jumps; without it the family's measured
//! false-alarm share, floored at 1%): its expected power and, in brackets, the draws its own `z`
//! passes, the parameter errors, and the count of runs whose final gap is
//! above the base gap (the bookkeeping rule says none). Shares carry 95% Wilson intervals.
//! `--csv` writes one row per draw, with the statistics each test of the diagnosis decides on
//! (the base `G`, each stationary candidate's first-scan score `lr_*` and the gap with it in
//! `galt_*`, the warm-up's `B` and its block-mean scale, the step z scores, the base `G`'s
//! effective degrees of freedom `nu` and the number of taus `n_taus`), so that the null
//! distribution of each test can be read off clean runs; `cceil_p` is the fair shape ceiling
//! (`oracle::ShapeCeiling`: told the kind and `rho`, not the shape) of a Gauss-Markov,
//! sinusoid, output-filter or warm-up draw, and on clean draws its level at the null stream's
//! Gauss-Markov draw (`wceil_p`: its warm-up draw); `alt_kinds` the effect kinds the record
//! lists among its alternatives. `--no-oracle` leaves out the clean
//! draws' oracle statistics and jump ceiling (a null study of the diagnosis alone). `--models
//! DIR` writes each draw's model file, which `allanscope simulate --model` reads, for
//! reproducing a run through the command line (another noise stream, the same unit).

mod common;

use allanscope::gap::effects::effect_column;
use allanscope::gap::oracle::{self, BlockGls, JumpCeiling};
use allanscope::gap::problem::{GapProblem, ModelSpec};
use allanscope::gap::step_null;
use allanscope::gap::steps::forward_steps;
use allanscope::gap::thresholds::Thresholds;
use allanscope::gap::warmup::{fit_warmup, WARMUP_K_DELTA};
use allanscope::gap::warmup_profile::fit_warmup_profiled;
use allanscope::gap::{
    diagnose, DiagnoseOptions, EffectKind, EffectParams, EvidenceSnapshot, GapConfig, GapEvidence,
    Verdict,
};
use allanscope::model::terms;
use common::{
    draw_effect_params, draw_jumps, effect_toml, gm_sigma, jumps_rms, log_uniform, par_map,
    quantile, share, simulate_channel, sinusoid_amplitude, std_normal_cdf, std_normal_quantile,
    warmup_amplitude, FILTER_TAU_PRIOR, GM_TAU_C_PRIOR, SIN_FREQ_PRIOR, WARMUP_T_PRIOR,
};
use rand::{RngExt, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::sync::OnceLock;
use std::time::Instant;

/// `--models DIR`: each draw's model file (`FAMILY_EFFECT_DRAW.toml`, the rate rounding as the
/// model's `rate_lsb`), for `allanscope simulate --model` (reproductions through the CLI).
static MODELS_DIR: OnceLock<String> = OnceLock::new();

/// The families; the first six are the default list, `coarse` is drawn on request. New
/// families go at the end: a draw's stream depends on the family's index.
const FAMILIES: [&str; 35] = [
    "navfog", "tacfog", "vog4", "memsgyro", "ma4", "memsacc", "coarse", "consmems", "fog2k",
    "accr", "kmems", "rfog", "hrmems", "qtzgyro", "servoacc", "short", "long", "adis", "adistemp",
    "rlg", "lowrate", "accfilt", "navacc", "mimu", "cicgyro", "hrg", "thermfog", "fog5k",
    "kalgyro", "kalacc", "cicacc", "zpexp", "bartfog", "accgrav", "cntfog",
];
/// The held-out families (`--families heldout`): defined before the calibration of issue 13's
/// last round and run only for its final tables, so nothing was tuned on them.
const HELDOUT: [&str; 5] = ["consmems", "fog2k", "accr", "kmems", "rfog"];
/// The held-out families of session 9 (`--families unseen`), defined before any run of them.
const UNSEEN: [&str; 5] = ["hrmems", "qtzgyro", "servoacc", "short", "long"];
/// The held-out families of session 10 (`--families unseen10`), defined before any run of them.
const UNSEEN10: [&str; 6] = ["adis", "adistemp", "rlg", "lowrate", "accfilt", "navacc"];
/// The held-out families of session 11 (`--families unseen11`), defined before any run of them.
const UNSEEN11: [&str; 5] = ["mimu", "cicgyro", "hrg", "thermfog", "fog5k"];
/// The held-out families of session 12 (`--families unseen12`), defined before any run of them.
const UNSEEN12: [&str; 5] = ["kalgyro", "kalacc", "cicacc", "zpexp", "bartfog"];
/// Importance samples and null draws of the fair jump ceiling (`oracle::JumpCeiling`).
const JUMP_CEIL_SAMPLES: usize = 1000;
const JUMP_CEIL_NULLS: usize = 199;
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
    /// Constant input rate (u/s): the turn-on bias, Earth's rate or gravity on the axis.
    bias: f64,
    /// A filter that is part of the unit (`adis`, `adistemp`, `accfilt`): on a clean run the
    /// right answer is this filter named and nothing else.
    intrinsic: Option<EffectParams>,
    /// A temperature-driven bias the diagnosis is never shown (`adistemp`): (step degC, settling
    /// time constant s, cycle amplitude degC, cycle period s, coefficient u/s per degC).
    temp: Option<[f64; 5]>,
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

/// ARW in deg/sqrt(h) to N in deg/sqrt(s); flicker in deg/h to B in deg/s; RRW in
/// deg/h/sqrt(h) to K in deg/s/sqrt(s).
const ARW: f64 = 1.0 / 60.0;
const DEG_H: f64 = 1.0 / 3600.0;
const RRW: f64 = 1.0 / (3600.0 * 60.0);

fn draw_unit(
    rng: &mut Xoshiro256PlusPlus,
    family: &'static str,
    hours: Option<(f64, f64)>,
) -> Unit {
    let long = rng.random::<f64>() < 0.1;
    let t_run = if family == "short" {
        log_uniform(rng, 10.0, 20.0) * 60.0
    } else if family == "long" {
        log_uniform(rng, 8.0, 24.0) * 3600.0
    } else if family == "thermfog" {
        log_uniform(rng, 12.0, 24.0) * 3600.0
    } else if family == "fog5k" {
        log_uniform(rng, 10.0, 20.0) * 60.0
    } else if family == "kalgyro" || family == "kalacc" {
        log_uniform(rng, 3.0, 11.0) * 3600.0
    } else if let Some((a, b)) = hours {
        log_uniform(rng, a, b) * 3600.0
    } else if family == "hrmems" || family == "mimu" {
        log_uniform(rng, 20.0, 60.0) * 60.0
    } else if long {
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
        bias: 0.0,
        intrinsic: None,
        temp: None,
    };
    match family {
        "navfog" | "tacfog" | "coarse" | "long" => {
            let (arw, flk, rrw) = if family == "navfog" {
                ((0.001, 0.005), (0.001, 0.01), (1e-4, 1e-3))
            } else {
                ((0.01, 0.1), (0.05, 0.5), (0.01, 0.1))
            };
            u.c[1] = log_uniform(rng, arw.0, arw.1) * ARW;
            u.c[2] = log_uniform(rng, flk.0, flk.1) * DEG_H;
            u.c[3] = log_uniform(rng, rrw.0, rrw.1) * RRW;
            u.tau0 = if family == "long" {
                0.01
            } else {
                rate(rng, 200.0, 1000.0)
            };
            // A fine LSB: 0.1-1 of the per-sample noise `N sqrt(tau0)` (an LSB far above it
            // makes the quantization error a slow, non-white wander; docs/gap.md).
            // `coarse`: 3-30 times it, the quantization-limited case.
            let (lo, hi) = if family == "coarse" {
                (3.0, 30.0)
            } else {
                (0.1, 1.0)
            };
            u.lsb = log_uniform(rng, lo, hi) * u.c[1] * u.tau0.sqrt();
        }
        "vog4" => {
            u.c[1] = 0.254 * log_uniform(rng, 0.5, 2.0);
            u.c[2] = 0.225 * log_uniform(rng, 0.5, 2.0);
            u.c[3] = 1.826e-2 * log_uniform(rng, 0.5, 2.0);
            u.lsb = 0.004;
            u.tau0 = (0.004f64).max(t_run / MAX_SAMPLES);
        }
        "memsgyro" | "short" => {
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
        "consmems" => {
            // Consumer MEMS gyro at 100 Hz: large noise and a very coarse rate LSB (a full
            // scale of +-2000 deg/s on 16 bits), 0.7-3 times the per-sample noise.
            u.c[1] = log_uniform(rng, 0.3, 3.0) * ARW;
            u.c[2] = log_uniform(rng, 10.0, 100.0) * DEG_H;
            u.c[3] = log_uniform(rng, 5.0, 50.0) * RRW;
            u.tau0 = (0.01f64).max(t_run / MAX_SAMPLES);
            u.rate_lsb = log_uniform(rng, 0.7, 3.0) * u.c[1] / u.tau0.sqrt();
        }
        "fog2k" => {
            // A FOG sampled at 2 kHz (the step raised for the longest runs to keep at most
            // MAX_SAMPLES), tactical noise, a fine angle LSB.
            u.c[1] = log_uniform(rng, 0.005, 0.05) * ARW;
            u.c[2] = log_uniform(rng, 0.02, 0.2) * DEG_H;
            u.c[3] = log_uniform(rng, 0.005, 0.05) * RRW;
            u.tau0 = (0.0005f64).max(t_run / MAX_SAMPLES);
            u.lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] * u.tau0.sqrt();
        }
        "accr" => {
            // An accelerometer whose rate ramp R dominates the long taus: its ADEV meets the
            // flicker floor at `tau_x` in [T_run / 100, T_run / 20].
            u.c[1] = log_uniform(rng, 0.01, 0.05) / 60.0;
            u.c[2] = log_uniform(rng, 10.0, 50.0) * 9.81e-6;
            u.c[3] = log_uniform(rng, 1e-6, 1e-5);
            let tau_x = log_uniform(rng, t_run / 100.0, t_run / 20.0);
            u.c[4] = 0.664 * u.c[2] * 2f64.sqrt() / tau_x;
            u.tau0 = rate(rng, 200.0, 200.0);
            u.rate_lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] / u.tau0.sqrt();
        }
        "kmems" => {
            // A MEMS gyro at 1 kHz, K dominant: ADEV_K = K sqrt(tau / 3) meets the flicker
            // floor 0.664 B at tau_k.
            u.c[1] = log_uniform(rng, 0.05, 0.3) * ARW;
            u.c[2] = log_uniform(rng, 0.5, 3.0) * DEG_H;
            let tau_k = log_uniform(rng, t_run / 1000.0, t_run / 100.0);
            u.c[3] = 0.664 * u.c[2] * (3.0 / tau_k).sqrt();
            u.tau0 = (0.001f64).max(t_run / MAX_SAMPLES);
            u.rate_lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] / u.tau0.sqrt();
        }
        "rfog" => {
            // A FOG at 100 Hz with a rate ramp: ADEV_R = R tau / sqrt(2) meets the flicker
            // floor at tau_x.
            u.c[1] = log_uniform(rng, 0.01, 0.05) * ARW;
            u.c[2] = log_uniform(rng, 0.02, 0.2) * DEG_H;
            u.c[3] = log_uniform(rng, 0.005, 0.05) * RRW;
            let tau_x = log_uniform(rng, t_run / 50.0, t_run / 10.0);
            u.c[4] = 0.664 * u.c[2] * 2f64.sqrt() / tau_x;
            u.tau0 = (0.01f64).max(t_run / MAX_SAMPLES);
            u.lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] * u.tau0.sqrt();
        }
        "hrmems" => {
            u.c[1] = log_uniform(rng, 0.15, 0.6) * ARW;
            u.c[2] = log_uniform(rng, 3.0, 30.0) * DEG_H;
            u.c[3] = log_uniform(rng, 0.5, 5.0) * RRW;
            u.tau0 = (0.0005f64).max(t_run / MAX_SAMPLES);
            u.rate_lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] / u.tau0.sqrt();
        }
        "qtzgyro" => {
            // Large K and R: K sqrt(tau / 3) meets 0.664 B at tau_k, R tau / sqrt(2) meets
            // K sqrt(tau / 3) at tau_r = tau_k * [3, 30].
            u.c[1] = log_uniform(rng, 0.5, 3.0) * ARW;
            u.c[2] = log_uniform(rng, 10.0, 100.0) * DEG_H;
            let tau_k = log_uniform(rng, t_run / 300.0, t_run / 30.0);
            u.c[3] = 0.664 * u.c[2] * (3.0 / tau_k).sqrt();
            let tau_r = tau_k * log_uniform(rng, 3.0, 30.0);
            u.c[4] = u.c[3] * (tau_r / 3.0).sqrt() * 2f64.sqrt() / tau_r;
            u.tau0 = rate(rng, 200.0, 200.0);
            u.rate_lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] / u.tau0.sqrt();
        }
        "servoacc" => {
            // Velocity pulses counted with carry, the LSB 1-10 times the per-sample noise.
            u.c[1] = log_uniform(rng, 0.005, 0.03) / 60.0;
            u.c[2] = log_uniform(rng, 5.0, 50.0) * 9.81e-6;
            u.c[3] = log_uniform(rng, 1e-6, 1e-5);
            u.tau0 = rate(rng, 100.0, 100.0);
            u.lsb = log_uniform(rng, 1.0, 10.0) * u.c[1] * u.tau0.sqrt();
        }
        "adis" | "adistemp" => {
            // ADIS16405-like: Bartlett / decimating average, then the 0.05 deg/s rate LSB.
            u.c[1] = log_uniform(rng, 1.5, 4.0) * ARW;
            u.c[2] = log_uniform(rng, 10.0, 50.0) * DEG_H;
            u.c[3] = log_uniform(rng, 2.0, 20.0) * RRW;
            u.tau0 = (0.01f64).max(t_run / MAX_SAMPLES);
            u.bias = rng.random_range(-0.5..0.5);
            u.intrinsic = Some(EffectParams::MovingAverage {
                taps: 1 << rng.random_range(1..=3u32),
                stages: rng.random_range(1..=2u32),
                decimation: 1,
            });
            u.rate_lsb = 0.05;
            if family == "adistemp" {
                u.temp = Some([
                    log_uniform(rng, 3.0, 10.0),
                    log_uniform(rng, 600.0, 3600.0),
                    log_uniform(rng, 0.2, 1.0),
                    log_uniform(rng, 600.0, 3600.0),
                    log_uniform(rng, 2e-4, 2e-3),
                ]);
            }
        }
        "rlg" => {
            // Arcsec units: 1 deg/h = 1 arcsec/s; N in arcsec/sqrt(s) = 60 x deg/sqrt(h).
            u.c[1] = log_uniform(rng, 0.001, 0.005) * 60.0;
            u.c[2] = log_uniform(rng, 0.0005, 0.005);
            u.c[3] = log_uniform(rng, 1e-5, 1e-4) / 60.0;
            u.tau0 = rate(rng, 200.0, 500.0);
            u.lsb = log_uniform(rng, 0.5, 2.0);
            u.c[0] = log_uniform(rng, 0.1, 0.5) * u.lsb;
            u.bias = rng.random_range(0.0..15.0);
        }
        "lowrate" => {
            u.c[1] = log_uniform(rng, 0.1, 1.0) * ARW;
            u.c[2] = log_uniform(rng, 2.0, 20.0) * DEG_H;
            u.c[3] = log_uniform(rng, 1.0, 10.0) * RRW;
            u.tau0 = rate(rng, 10.0, 50.0);
            u.rate_lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] / u.tau0.sqrt();
        }
        "accfilt" | "accgrav" => {
            u.c[1] = log_uniform(rng, 0.02, 0.2) / 60.0;
            u.c[2] = log_uniform(rng, 20.0, 200.0) * 9.81e-6;
            u.c[3] = log_uniform(rng, 1e-5, 1e-4);
            u.tau0 = rate(rng, 200.0, 1000.0);
            let tf = log_uniform(rng, 5.0, 30.0) * u.tau0;
            u.intrinsic = Some(EffectParams::OutputFilter {
                time_constant_s: tf,
            });
            if family == "accfilt" {
                u.rate_lsb = log_uniform(rng, 0.3, 3.0) * u.c[1] / (2.0 * tf).sqrt();
            } else {
                // `accgrav`: gravity's projection on the axis, so the mean falls anywhere on
                // the rounding grid, rounded in or near the dead band: the step 1-4 filtered
                // sample sigmas (a first order's rho_0 = (1 - a) / (1 + a)).
                let a = (-u.tau0 / tf).exp();
                let sigma = u.c[1] * ((1.0 - a) / (1.0 + a) / u.tau0).sqrt();
                u.rate_lsb = log_uniform(rng, 1.0, 4.0) * sigma;
                u.bias = rng.random_range(-9.81..9.81);
            }
        }
        "navacc" => {
            // ug/sqrt(Hz) to m/s/sqrt(s); ug to m/s^2.
            u.c[1] = log_uniform(rng, 5.0, 30.0) * 9.81e-6;
            u.c[2] = log_uniform(rng, 1.0, 10.0) * 9.81e-6;
            u.c[3] = log_uniform(rng, 1e-7, 1e-6);
            let tau_x = log_uniform(rng, t_run / 30.0, t_run / 3.0);
            u.c[4] = 0.664 * u.c[2] * 2f64.sqrt() / tau_x;
            u.tau0 = rate(rng, 100.0, 400.0);
            u.lsb = log_uniform(rng, 0.3, 3.0) * u.c[1] * u.tau0.sqrt();
            u.bias = rng.random_range(-9.81..9.81);
        }
        "mimu" | "cicgyro" => {
            // A low-pass the part runs before it rounds each rate sample: `mimu` a
            // second-order digital low-pass (natural frequency ODR/20-ODR/4), `cicgyro` a sinc^3
            // decimation filter (three cascaded moving averages of 2-8 output samples); the
            // step is a share of the *filtered* sample noise `N sqrt(rho_0 / tau0)`.
            let (arw, flk, rrw, hz, lsb) = if family == "mimu" {
                (
                    (0.15, 1.0),
                    (3.0, 30.0),
                    (1.0, 10.0),
                    (1000.0, 2000.0),
                    (0.3, 1.0),
                )
            } else {
                (
                    (0.1, 1.0),
                    (2.0, 20.0),
                    (1.0, 10.0),
                    (200.0, 1000.0),
                    (0.1, 1.0),
                )
            };
            u.c[1] = log_uniform(rng, arw.0, arw.1) * ARW;
            u.c[2] = log_uniform(rng, flk.0, flk.1) * DEG_H;
            u.c[3] = log_uniform(rng, rrw.0, rrw.1) * RRW;
            u.tau0 = rate(rng, hz.0, hz.1);
            let filter = if family == "mimu" {
                let odr = 1.0 / u.tau0;
                EffectParams::SecondOrderFilter {
                    natural_frequency_hz: log_uniform(rng, odr / 20.0, odr / 4.0),
                    damping: log_uniform(rng, 0.5, 1.0),
                    bilinear: false,
                    zero: None,
                }
            } else {
                EffectParams::MovingAverage {
                    taps: rng.random_range(2..=8u32),
                    stages: 3,
                    decimation: 1,
                }
            };
            u.intrinsic = Some(filter);
            let rho0 = rho0_of(filter, u.tau0);
            u.rate_lsb = log_uniform(rng, lsb.0, lsb.1) * u.c[1] * (rho0 / u.tau0).sqrt();
        }
        "hrg" => {
            // Hemispherical resonator gyro: tiny N, flicker-dominated, a finely counted angle.
            u.c[1] = log_uniform(rng, 0.0001, 0.0005) * ARW;
            u.c[2] = log_uniform(rng, 0.0005, 0.005) * DEG_H;
            u.c[3] = log_uniform(rng, 1e-5, 1e-4) * RRW;
            u.tau0 = rate(rng, 100.0, 500.0);
            u.lsb = log_uniform(rng, 0.05, 0.5) * u.c[1] * u.tau0.sqrt();
        }
        "thermfog" | "fog5k" => {
            // Tactical FOGs: `thermfog` over 12-24 h at 100 Hz with a thermal bias drift the
            // diagnosis is never shown, `fog5k` over 10-20 min at 5 kHz.
            u.c[1] = log_uniform(rng, 0.01, 0.1) * ARW;
            u.c[2] = log_uniform(rng, 0.05, 0.5) * DEG_H;
            u.c[3] = log_uniform(rng, 0.01, 0.1) * RRW;
            u.tau0 = if family == "fog5k" {
                (0.0002f64).max(t_run / MAX_SAMPLES)
            } else {
                (0.01f64).max(t_run / MAX_SAMPLES)
            };
            u.lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] * u.tau0.sqrt();
            if family == "thermfog" {
                u.temp = Some([
                    log_uniform(rng, 1.0, 5.0),
                    log_uniform(rng, 3600.0, 14400.0),
                    log_uniform(rng, 0.5, 2.0),
                    log_uniform(rng, 4.0 * 3600.0, 24.0 * 3600.0),
                    log_uniform(rng, 0.005, 0.05) * DEG_H,
                ]);
            }
        }
        "kalgyro" | "kalacc" => {
            // A consumer IMU (BMI088 / ICM-42688 class) recorded static for hours at an ODR of
            // 200 Hz, as for a Kalibr calibration: its digital low-pass (second order, natural
            // frequency ODR/10-ODR/4), then each rate sample rounded to the 16-bit LSB of the
            // range set, a share of the *filtered* sample noise `N sqrt(rho_0 / tau0)`. The gyro
            // carries a turn-on bias, the accelerometer gravity's projection on its axis, so the
            // rounding grid sits anywhere against the signal.
            let lsb = if family == "kalgyro" {
                u.c[1] = log_uniform(rng, 0.15, 1.0) * ARW;
                u.c[2] = log_uniform(rng, 2.0, 20.0) * DEG_H;
                u.c[3] = log_uniform(rng, 1.0, 10.0) * RRW;
                u.bias = rng.random_range(-0.5..0.5);
                (0.2, 2.0)
            } else {
                // m/s/sqrt(h) to m/s/sqrt(s); ug to m/s^2.
                u.c[1] = log_uniform(rng, 0.03, 0.15) / 60.0;
                u.c[2] = log_uniform(rng, 20.0, 200.0) * 9.81e-6;
                u.c[3] = log_uniform(rng, 1e-5, 1e-4);
                u.bias = rng.random_range(-9.81..9.81);
                (0.1, 1.0)
            };
            u.tau0 = rate(rng, 200.0, 200.0);
            let odr = 1.0 / u.tau0;
            let filter = EffectParams::SecondOrderFilter {
                natural_frequency_hz: log_uniform(rng, odr / 10.0, odr / 4.0),
                damping: log_uniform(rng, 0.5, 1.0),
                bilinear: false,
                zero: None,
            };
            u.intrinsic = Some(filter);
            let rho0 = rho0_of(filter, u.tau0);
            u.rate_lsb = log_uniform(rng, lsb.0, lsb.1) * u.c[1] * (rho0 / u.tau0).sqrt();
        }
        "cicacc" => {
            // A low-noise sigma-delta MEMS accelerometer (ADXL355 class) behind its sinc^3
            // decimator (three cascaded moving averages of 2-8 output samples), gravity's
            // projection on its axis, each rate sample rounded to the 20-bit LSB of its range
            // (3.9, 7.8 or 15.6 ug), far below the noise. ug/sqrt(Hz) to m/s/sqrt(s).
            u.c[1] = log_uniform(rng, 20.0, 80.0) * 9.81e-6;
            u.c[2] = log_uniform(rng, 2.0, 20.0) * 9.81e-6;
            u.c[3] = log_uniform(rng, 1e-6, 1e-5);
            u.tau0 = rate(rng, 125.0, 1000.0);
            u.intrinsic = Some(EffectParams::MovingAverage {
                taps: rng.random_range(2..=8u32),
                stages: 3,
                decimation: 1,
            });
            u.bias = rng.random_range(-9.81..9.81);
            u.rate_lsb = 3.9e-6 * 9.80665 * f64::from(1u32 << rng.random_range(0..=2u32));
        }
        "zpexp" => {
            // A post-processed export: a MEMS gyro (memsgyro's terms) zero-phase filtered
            // (first order forward and backward, time constant 1-10 tau0) and written as floats.
            // The part's own fine rounding, before that filter, is white rate noise inside `N`
            // (the simulator rounds after its filter, so it is left out).
            u.c[1] = log_uniform(rng, 0.1, 1.0) * ARW;
            u.c[2] = log_uniform(rng, 2.0, 20.0) * DEG_H;
            u.c[3] = log_uniform(rng, 1.0, 10.0) * RRW;
            u.tau0 = rate(rng, 100.0, 1000.0);
            u.intrinsic = Some(EffectParams::ZeroPhaseFilter {
                time_constant_s: log_uniform(rng, 1.0, 10.0) * u.tau0,
            });
        }
        "bartfog" => {
            // A tactical FOG whose DSP outputs a Bartlett average (two stages of a moving
            // average of 2-16 samples), the angle counted with carry at 0.1-1 of the filtered
            // per-sample angle noise `N sqrt(rho_0 tau0)`.
            u.c[1] = log_uniform(rng, 0.01, 0.1) * ARW;
            u.c[2] = log_uniform(rng, 0.05, 0.5) * DEG_H;
            u.c[3] = log_uniform(rng, 0.01, 0.1) * RRW;
            u.tau0 = rate(rng, 200.0, 1000.0);
            let filter = EffectParams::MovingAverage {
                taps: rng.random_range(2..=16u32),
                stages: 2,
                decimation: 1,
            };
            u.intrinsic = Some(filter);
            let rho0 = rho0_of(filter, u.tau0);
            u.lsb = log_uniform(rng, 0.1, 1.0) * u.c[1] * (rho0 * u.tau0).sqrt();
        }
        "cntfog" => {
            // A tactical FOG (tacfog's terms) at 200-1000 Hz that filters its rate (a first
            // order of 3-20 tau0 or a Bartlett average of 4-16 taps) and counts the filtered
            // angle with carry at 2-6 times its per-sample motion `N sqrt(rho_0 tau0)` (an LSB
            // about the unfiltered per-sample noise): the counter's error is correlated over
            // the filter's memory (docs/gap.md, "The counter behind a filter (session 25)"). An
            // input rate of 0-15 deg/h (the Earth's on the axis) sets the counter's line.
            u.c[1] = log_uniform(rng, 0.01, 0.1) * ARW;
            u.c[2] = log_uniform(rng, 0.05, 0.5) * DEG_H;
            u.c[3] = log_uniform(rng, 0.01, 0.1) * RRW;
            u.tau0 = rate(rng, 200.0, 1000.0);
            let filter = if rng.random::<f64>() < 0.5 {
                EffectParams::OutputFilter {
                    time_constant_s: log_uniform(rng, 3.0, 20.0) * u.tau0,
                }
            } else {
                EffectParams::MovingAverage {
                    taps: rng.random_range(4..=16u32),
                    stages: 2,
                    decimation: 1,
                }
            };
            u.intrinsic = Some(filter);
            let rho0 = rho0_of(filter, u.tau0);
            u.lsb = log_uniform(rng, 2.0, 6.0) * u.c[1] * (rho0 * u.tau0).sqrt();
            u.bias = rng.random_range(0.0..15.0) * DEG_H;
        }
        _ => unreachable!("family list"),
    }
    u
}

/// `rho_0` of a unit's intrinsic filter at `tau0` (1 without one): the filtered white rate's
/// per-sample variance against the unfiltered (`LowPass::autocorrelation`).
fn rho0_of(filter: EffectParams, tau0: f64) -> f64 {
    filter
        .lowpass()
        .map_or(1.0, |lp| lp.autocorrelation(tau0)[0])
}

/// The kinds a benchmark draws (`None`: a clean run), by name.
const KINDS: [(&str, Option<EffectKind>); 6] = [
    ("none", None),
    ("gauss_markov", Some(EffectKind::GaussMarkov)),
    ("sinusoid", Some(EffectKind::Sinusoid)),
    ("output_filter", Some(EffectKind::OutputFilter)),
    ("warmup", Some(EffectKind::Warmup)),
    ("bias_jumps", Some(EffectKind::BiasJumps)),
];

/// Kinds drawn only when asked (`--effects moving_average,...`): the filters beyond first order
/// (docs/gap.md, "Low-pass filters beyond first order"), memory 1-10 tau0 as the first order's.
const EXTRA_KINDS: [(&str, Option<EffectKind>); 4] = [
    ("moving_average", Some(EffectKind::MovingAverage)),
    ("second_order_filter", Some(EffectKind::SecondOrderFilter)),
    ("zero_phase_filter", Some(EffectKind::ZeroPhaseFilter)),
    // Session 11 (bandgm): narrow-band noise, drawn by common::draw_effect_params.
    ("band_noise", Some(EffectKind::BandNoise)),
];

fn kind_name(k: Option<EffectKind>) -> &'static str {
    k.map_or("none", |k| k.name())
}

/// An effect of `kind` on `u` with its drawn size `rho` (module doc).
fn draw_effect(rng: &mut Xoshiro256PlusPlus, u: &Unit, kind: EffectKind) -> (EffectParams, f64) {
    let rho = log_uniform(rng, 0.3, 3.0);
    let adev = |tau: f64| u.adev(tau);
    // hrmems: the strong Bartlett / moving-average filters of high-rate MEMS IMUs.
    let taps_hi = if u.family == "hrmems" { 32.0 } else { 10.0 };
    let p = draw_effect_params(rng, kind, rho, u.tau0, u.t_run, &adev, taps_hi);
    (p, rho)
}

fn model_toml(u: &Unit, effect: Option<EffectParams>) -> String {
    let mut s = format!("tau0_s = {}\n", u.tau0);
    if let Some([step, tc, amp, period, _]) = u.temp {
        s += &format!(
            "[temperature]\nstart_c = 20.0\nfinal_c = {:e}\ntime_constant_s = {tc:e}\nsine_amplitude_c = {amp:e}\nsine_period_s = {period:e}\n",
            20.0 + step
        );
    }
    s += &format!(
        "[[channel]]\nname = \"x\"\nunit = \"u\"\nQ = {:e}\nN = {:e}\nB = {:e}\nK = {:e}\nR = {:e}\nflicker_band_s = [{}, {:e}]\nbias = {:e}\n",
        u.c[0],
        u.c[1],
        u.c[2],
        u.c[3],
        u.c[4],
        u.tau0,
        10.0 * u.t_run,
        u.bias
    );
    if u.lsb > 0.0 {
        s += &format!("lsb = {:e}\n", u.lsb);
    }
    if let Some(t) = u.temp {
        s += &format!("temperature_coefficient = {:e}\n", t[4]);
    }
    // The unit's own filter, unless the drawn effect is a filter (the simulator holds one).
    if effect.and_then(|e| e.lowpass()).is_none() {
        s += &effect_toml(u.intrinsic);
    }
    s + &effect_toml(effect)
}

/// Simulates `u` with `effect`: the increments, the realised effect (jumps: the count and the
/// rms of the drawn sizes) and the realised jumps. Rate samples are rounded last, as a MEMS
/// part rounds what it reports.
fn simulate(
    u: &Unit,
    effect: Option<EffectParams>,
    seed: u64,
) -> (Vec<f64>, Option<EffectParams>, Vec<(f64, f64)>) {
    let (mut inc, truth, jumps) = simulate_channel(
        &model_toml(u, effect),
        "<family_gap>",
        u.tau0,
        u.t_run,
        effect,
        seed,
    );
    if u.rate_lsb > 0.0 {
        let step = u.rate_lsb * u.tau0;
        for v in inc.iter_mut() {
            *v = (*v / step).round() * step;
        }
    }
    (inc, truth, jumps)
}

/// The true five terms as `avar_cov` coefficients `[Q^2, N^2, B^2, K^2, R^2]`, quantization
/// included (the oracle's "true covariance" is not used here; the oracle uses the fitted base,
/// as the diagnosis does).
fn oracle_z(
    truth: EffectParams,
    jumps: &[(f64, f64)],
    u: &Unit,
    snap: &EvidenceSnapshot,
) -> Option<(f64, f64)> {
    let prob = GapProblem::new(snap, &DiagnoseOptions::default()).ok()?;
    let base = prob.gls(&ModelSpec::default())?;
    let c_fit: [f64; 5] = std::array::from_fn(|i| base.coef[i]);
    let block_s = snap.block_len as f64 * u.tau0;
    let col = |kind, shape| effect_column(kind, shape, &prob.ms, prob.tau0_s, prob.n_inc);
    match truth {
        EffectParams::GaussMarkov { sigma, tau_c_s } => {
            let s2 = sigma * sigma;
            let sig: Vec<f64> = col(EffectKind::GaussMarkov, tau_c_s)
                .iter()
                .map(|g| s2 * g)
                .collect();
            oracle::curve_known_z(&prob, &sig)
        }
        EffectParams::Sinusoid {
            amplitude,
            frequency_hz,
        } => {
            let a2 = amplitude * amplitude;
            let sig: Vec<f64> = col(EffectKind::Sinusoid, frequency_hz)
                .iter()
                .map(|g| a2 * g)
                .collect();
            oracle::curve_known_z(&prob, &sig)
        }
        EffectParams::OutputFilter { time_constant_s } => {
            // The filter acts on the simulated white rate (N), not on rate-sample rounding.
            let n2 = u.c[1] * u.c[1];
            let sig: Vec<f64> = col(EffectKind::OutputFilter, time_constant_s)
                .iter()
                .zip(&prob.tau)
                .map(|(g, t)| n2 * (g - 1.0 / t))
                .collect();
            oracle::curve_known_z(&prob, &sig)
        }
        EffectParams::MovingAverage { .. }
        | EffectParams::SecondOrderFilter { .. }
        | EffectParams::ZeroPhaseFilter { .. } => {
            let n2 = u.c[1] * u.c[1];
            let lp = truth.lowpass()?;
            let sig: Vec<f64> = lp
                .white_rate_avar(u.tau0, &prob.ms)
                .iter()
                .zip(&prob.tau)
                .map(|(g, t)| n2 * (g - 1.0 / t))
                .collect();
            oracle::curve_known_z(&prob, &sig)
        }
        EffectParams::BandNoise { sigma, .. } => {
            let s2 = sigma * sigma;
            let sig: Vec<f64> =
                allanscope::gap::effects::params_column(&truth, &prob.ms, prob.tau0_s, prob.n_inc)
                    .iter()
                    .map(|g| s2 * g)
                    .collect();
            oracle::curve_known_z(&prob, &sig)
        }
        EffectParams::Warmup {
            amplitude,
            time_constant_s,
        } => {
            let g = BlockGls::new(&snap.block_means, block_s, &c_fit)?;
            let (_, z, delta) = oracle::warmup_oracle(&g, amplitude, time_constant_s);
            Some((z, delta))
        }
        EffectParams::BiasJumps { .. } => {
            let g = BlockGls::new(&snap.block_means, block_s, &c_fit)?;
            let (_, z, delta) = oracle::jumps_oracle(&g, jumps);
            Some((z, delta))
        }
        _ => None,
    }
}

/// Grid points per decade of the shape prior in [`shape_ceiling_p`].
const SHAPE_CEIL_PER_DECADE: f64 = 16.0;
/// The sinusoid's grid is finer: its signature oscillates in the frequency.
const SIN_CEIL_PER_DECADE: f64 = 100.0;
/// Null draws of the shape ceiling's p-value.
const SHAPE_CEIL_NULLS: usize = 1999;

/// A log-spaced grid over `[lo, hi]`, `per_decade` points per decade, both ends included.
fn log_grid(lo: f64, hi: f64, per_decade: f64) -> Vec<f64> {
    let n = ((hi / lo).log10() * per_decade).ceil().max(1.0) as usize;
    (0..=n)
        .map(|k| lo * (hi / lo).powf(k as f64 / n as f64))
        .collect()
}

/// The fair ceiling of a stationary effect or a warm-up (`oracle::ShapeCeiling`): told the kind
/// and the peak ratio `rho` the draw was made with, not the shape (`tau_c`, the frequency, the
/// filter's time constant, the warm-up's `T`), which is spread over the generator's own prior
/// (`draw_effect_params`) on a log grid. Returns its p-value in the Gaussian model of the
/// evidence (the curve linearised at the base fit; the block means with the base fit's five
/// terms, as the warm-up oracle); NaN for other kinds.
fn shape_ceiling_p(
    kind: EffectKind,
    rho: f64,
    u: &Unit,
    snap: &EvidenceSnapshot,
    seed: u64,
) -> f64 {
    let Ok(prob) = GapProblem::new(snap, &DiagnoseOptions::default()) else {
        return f64::NAN;
    };
    let col = |kind, shape| effect_column(kind, shape, &prob.ms, prob.tau0_s, prob.n_inc);
    let adev = |tau: f64| u.adev(tau);
    let curve = |signals: Vec<Vec<f64>>| oracle::ShapeCeiling::on_curve(&prob, &signals);
    // An effect whose AVAR is its amplitude squared times its column: the column at each
    // shape of the grid, scaled by the amplitude `rho` gives there.
    let scaled = |grid: Vec<f64>, amplitude: &dyn Fn(f64) -> f64| {
        curve(
            grid.into_iter()
                .map(|x| {
                    let a2 = amplitude(x).powi(2);
                    col(kind, x).iter().map(|g| a2 * g).collect()
                })
                .collect(),
        )
    };
    let ceiling = match kind {
        EffectKind::GaussMarkov => scaled(
            log_grid(
                GM_TAU_C_PRIOR.0 * u.tau0,
                u.t_run / GM_TAU_C_PRIOR.1,
                SHAPE_CEIL_PER_DECADE,
            ),
            &|tc| gm_sigma(rho, tc, &adev),
        ),
        EffectKind::Sinusoid => scaled(
            log_grid(
                SIN_FREQ_PRIOR.0 / u.t_run,
                SIN_FREQ_PRIOR.1 / u.tau0,
                SIN_CEIL_PER_DECADE,
            ),
            &|f| sinusoid_amplitude(rho, f, &adev),
        ),
        EffectKind::OutputFilter => {
            // The filter acts on the simulated white rate (N), as in `oracle_z`.
            let n2 = u.c[1] * u.c[1];
            curve(
                log_grid(u.tau0, FILTER_TAU_PRIOR * u.tau0, SHAPE_CEIL_PER_DECADE)
                    .into_iter()
                    .map(|tc| {
                        col(EffectKind::OutputFilter, tc)
                            .iter()
                            .zip(&prob.tau)
                            .map(|(g, t)| n2 * (g - 1.0 / t))
                            .collect()
                    })
                    .collect(),
            )
        }
        EffectKind::Warmup => {
            let Some(base) = prob.gls(&ModelSpec::default()) else {
                return f64::NAN;
            };
            let c_fit: [f64; 5] = std::array::from_fn(|i| base.coef[i]);
            let block_s = snap.block_len as f64 * u.tau0;
            BlockGls::new(&snap.block_means, block_s, &c_fit).and_then(|g| {
                let profiles: Vec<Vec<f64>> = log_grid(
                    WARMUP_T_PRIOR.0,
                    u.t_run / WARMUP_T_PRIOR.1,
                    SHAPE_CEIL_PER_DECADE,
                )
                .into_iter()
                .map(|t| {
                    let a = warmup_amplitude(rho, t, u.tau0, u.t_run, &adev);
                    g.warmup_profile(t).iter().map(|v| a * v).collect()
                })
                .collect();
                oracle::ShapeCeiling::on_block_means(&g, &profiles)
            })
        }
        _ => None,
    };
    ceiling.map_or(f64::NAN, |c| c.p_value(SHAPE_CEIL_NULLS, seed).0)
}

struct Outcome {
    family: &'static str,
    truth_kind: Option<EffectKind>,
    truth: Option<EffectParams>,
    rho: f64,
    verdict: Verdict,
    gap_before: f64,
    gap_after: f64,
    named: Vec<EffectParams>,
    /// The oracle's `(z, delta)` for the true effect (effect draws).
    oracle: Option<(f64, f64)>,
    /// Clean draws: the oracle `z` of one effect of each kind of `KINDS[1..]` drawn on this
    /// base (their null distribution).
    null_z: [f64; 5],
    secs: f64,
    unit: Unit,
    /// The diagnosis said the unit is quantization-limited (`Diagnosis::quantization_limited`).
    qlim: bool,
    /// The warm-up test's `B` on the base five-term fit (`gap::warmup::fit_warmup`): above
    /// `warmup_bf` the test finds a warm-up, which the bookkeeping keeps only if its exact AVAR
    /// lowers the curve's gap.
    warm_b: f64,
    /// The three largest z scores of the first pass of the step search on the base five-term
    /// fit (`gap::steps::forward_steps` down to z = 3): the statistics the jump rule acts on.
    jump_z: [f64; 3],
    /// Clean draws: per tau of the curve, `(tau / T_run, r_j / sqrt(S_jj), S_jj, share of R in the
    /// covariance's fit)` of the base
    /// five-term fit (`--resid`: where on the tau axis a too-tight covariance shows).
    resid: Vec<(f64, f64, f64, f64)>,
    /// The fair jump ceiling (`oracle::JumpCeiling`: count and rms told, times unknown): its
    /// p-value in the Gaussian model of the block means. Jump draws: at the truth; clean
    /// draws: at the count and rms of the null stream's jump draw (its share below `alpha`
    /// checks the level on clean runs).
    jceil_p: f64,
    /// The fair ceiling of a stationary curve effect (`shape_ceiling_p`: the kind and `rho` told,
    /// the shape not): effect draws at the truth; clean draws at the null stream's Gauss-Markov
    /// draw (its share below `alpha` checks the level). NaN for other kinds.
    cceil_p: f64,
    /// Clean draws: the warm-up's fair ceiling at the null stream's warm-up draw (its level).
    wceil_p: f64,
    /// The effect kinds among the record's `alternatives`.
    alt_kinds: Vec<&'static str>,
    /// The diagnosis's jump procedure at the base fit's terms (`gap::step_null::JumpNull`): the
    /// rule's excess over `jump_z` at its own `K^2`, and the shift that sets the rule at
    /// `jump_alpha` on the run's Gaussian null; the procedure finds jumps when the excess reaches the shift.
    jump_excess: f64,
    jump_shift: f64,
    /// The first stationary scan's drop of `r' S^-1 r` per parameter of each candidate against
    /// the base model (`Diagnosis::first_scores`), in the order of `LR_KINDS` (NaN: not scanned).
    lr: [f64; 6],
    /// The gap `G` of the model with each of `LR_KINDS` in (its residual scale).
    galt: [f64; 6],
    /// The warm-up test's drift-alone whitened residual sum of squares per degree of freedom
    /// (`WarmupFinding::null_scale`).
    warm_scale: f64,
    /// The warm-up's `B` in units of that scale (`WarmupFinding::log_bf_scaled`).
    warm_b_scaled: f64,
    /// The p-value of the warm-up's `B` under the run's own Gaussian null
    /// (`WarmupFinding::p_value`).
    warm_p: f64,
    /// The same on the base fit with `K^2` at the curve's upper bound (session 8's null), the
    /// p-value with `K^2` profiled on the block means (`gap::warmup_profile`, session 12), the
    /// bound `K^2` and the profiled null's `K^2` (u^2/s^3).
    warm_p_up: f64,
    warm_p_prof: f64,
    warm_k_up: f64,
    warm_k_null: f64,
    /// The base model's effective degrees of freedom and the number of taus diagnosed.
    nu: f64,
    n_taus: usize,
}

/// The stationary candidates whose first-scan scores `--csv` writes (`lr_*` columns).
const LR_KINDS: [EffectKind; 6] = [
    EffectKind::GaussMarkov,
    EffectKind::Sinusoid,
    EffectKind::OutputFilter,
    EffectKind::MovingAverage,
    EffectKind::SecondOrderFilter,
    EffectKind::ZeroPhaseFilter,
];

fn run_one(
    family: &'static str,
    kind: Option<EffectKind>,
    i: u64,
    seed: u64,
    hours: Option<(f64, f64)>,
    no_oracle: bool,
) -> Outcome {
    let fam_ix = FAMILIES.iter().position(|f| *f == family).unwrap_or(0) as u64;
    let kind_ix = KINDS
        .iter()
        .chain(EXTRA_KINDS.iter())
        .position(|k| k.1 == kind)
        .unwrap_or(0) as u64;
    let stream = seed
        .wrapping_mul(1_000_003)
        .wrapping_add(fam_ix * 100_003 + kind_ix * 10_007 + i);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(stream);
    let unit = draw_unit(&mut rng, family, hours);
    let drawn = kind.map(|k| draw_effect(&mut rng, &unit, k));
    let sim_seed = rng.random::<u64>();
    if let Some(dir) = MODELS_DIR.get() {
        let mut toml = model_toml(&unit, drawn.map(|d| d.0));
        if unit.rate_lsb > 0.0 {
            toml += &format!("rate_lsb = {:e}\n", unit.rate_lsb);
        }
        let name = format!("{dir}/{family}_{}_{i}.toml", kind_name(kind));
        // the simulator's seed too, so that a test can run this very draw (Simulator::new)
        std::fs::write(
            &name,
            format!("# family_gap --seed {seed}: {name}, simulator seed {sim_seed}\n{toml}"),
        )
        .expect("--models");
    }
    let t = Instant::now();
    let (inc, truth, jumps) = simulate(&unit, drawn.map(|d| d.0), sim_seed);
    let mut ev = GapEvidence::from_increments(GapConfig::new(unit.tau0), &inc);
    let snap = ev.snapshot();
    let d = diagnose(&snap, &DiagnoseOptions::default());
    let secs = t.elapsed().as_secs_f64();
    let mut rho = drawn.map_or(f64::NAN, |d| d.1);
    if let (
        Some((EffectParams::BiasJumps { rms_size: nom, .. }, _)),
        Some(EffectParams::BiasJumps { rms_size: real, .. }),
    ) = (drawn, truth)
    {
        rho *= real / nom;
    }
    let oracle = truth.and_then(|t| oracle_z(t, &jumps, &unit, &snap));
    let block_s = snap.block_len as f64 * unit.tau0;
    let ceiling = |count: u64, rms: f64, c5: &[f64; 5], seed: u64| {
        BlockGls::new(&snap.block_means, block_s, c5)
            .and_then(|g| {
                JumpCeiling::new(&g).p_value(
                    count as usize,
                    rms,
                    JUMP_CEIL_SAMPLES,
                    JUMP_CEIL_NULLS,
                    seed,
                )
            })
            .map_or(f64::NAN, |p| p.0)
    };
    // The base problem the diagnosis read: with the counter's sawtooth when it carried one
    // (then over the whole curve, also for a quantization-limited unit: session 24), else from
    // `tau_white` for a quantization-limited unit.
    let sawtooth = d.as_ref().is_ok_and(|d| d.sawtooth.is_some());
    let min_m = d
        .as_ref()
        .ok()
        .filter(|_| !sawtooth)
        .and_then(|d| d.quantization_limited.map(|q| q.m_white))
        .unwrap_or(DiagnoseOptions::default().min_m);
    let base_opts = DiagnoseOptions {
        min_m,
        ..DiagnoseOptions::default()
    };
    let base_prob = GapProblem::new(&snap, &base_opts).ok().and_then(|p| {
        if sawtooth {
            p.with_sawtooth(&snap, &base_opts, false).ok()
        } else {
            Some(p)
        }
    });
    let base_fit = base_prob
        .as_ref()
        .and_then(|p| p.gls(&ModelSpec::default()));
    let base_c5: Option<[f64; 5]> = base_fit
        .as_ref()
        .map(|b| std::array::from_fn(|i| b.coef[i]));
    let (nu, n_taus) = match (base_prob.as_ref(), base_fit.as_ref()) {
        (Some(p), Some(b)) => (p.effective_dof(&ModelSpec::default(), b), p.len()),
        _ => (f64::NAN, 0),
    };
    let mut resid = Vec::new();
    if let (None, Some(p), Some(b)) = (kind, base_prob.as_ref(), base_fit.as_ref()) {
        let t_run = snap.n_increments as f64 * unit.tau0;
        for j in 0..p.len() {
            let r = p.ln_avar()[j] - b.model[j].ln();
            let r_share = p.c_init[4] * p.tau[j] * p.tau[j] / 2.0 / b.model[j];
            resid.push((
                p.tau[j] / t_run,
                r / p.s_diag[j].sqrt(),
                p.s_diag[j],
                r_share,
            ));
        }
    }
    let warm = base_c5.and_then(|c5| {
        fit_warmup(
            &snap.block_means,
            block_s,
            snap.n_increments as f64 * unit.tau0,
            &c5,
            &[],
        )
    });
    let warm_b = warm.map_or(f64::NAN, |w| w.log_bf);
    let warm_scale = warm.map_or(f64::NAN, |w| w.null_scale);
    let warm_b_scaled = warm.map_or(f64::NAN, |w| w.log_bf_scaled);
    let warm_p = warm.map_or(f64::NAN, |w| w.p_value);
    let warm_k_up = match (base_prob.as_ref(), base_fit.as_ref()) {
        (Some(p), Some(b)) => p
            .upper_bound(&ModelSpec::default(), b, 3, WARMUP_K_DELTA)
            .map_or(f64::NAN, |k| k.max(b.coef[3])),
        _ => f64::NAN,
    };
    let t_run_s = snap.n_increments as f64 * unit.tau0;
    let warm_p_up = base_c5
        .and_then(|mut c5| {
            c5[3] = warm_k_up;
            fit_warmup(&snap.block_means, block_s, t_run_s, &c5, &[])
        })
        .map_or(f64::NAN, |w| w.p_value);
    let prof = base_c5.and_then(|c5| {
        fit_warmup_profiled(&snap.block_means, block_s, t_run_s, &c5, warm_k_up, &[])
    });
    let warm_p_prof = prof.map_or(f64::NAN, |w| w.0.p_value);
    let warm_k_null = prof.map_or(f64::NAN, |w| w.1);
    let mut jump_z = [0.0; 3];
    if let Some(f) = base_c5.and_then(|c5| forward_steps(&snap.block_means, block_s, &c5, &[], 3.0))
    {
        let mut zs = f.z_scores.clone();
        zs.sort_by(|a, b| b.total_cmp(a));
        for (o, z) in jump_z.iter_mut().zip(zs) {
            *o = z;
        }
    }
    // The jump procedure of the diagnosis (`gap::step_null`) at the base fit's terms: its
    // excess and its shift at the diagnosis's `jump_alpha` (found in time when the excess
    // reaches the shift).
    let (jump_excess, jump_shift) = base_c5
        .and_then(|c5| {
            let th = Thresholds::default();
            let mut null = step_null::JumpNull::new(
                snap.block_means.len(),
                block_s,
                &c5,
                &[],
                &th.jump_z,
                warm_k_up,
            )?;
            let st = null.statistic(&null.rotate(&snap.block_means)?);
            Some((st.excess, null.shift(st.k0, th.jump_alpha)?))
        })
        .unwrap_or((f64::NAN, f64::NAN));
    let mut jceil_p = f64::NAN;
    if let (Some(EffectParams::BiasJumps { count, rms_size }), Some(c5)) = (truth, base_c5) {
        jceil_p = ceiling(count, rms_size, &c5, stream);
    }
    let ceil_seed = stream ^ 0x0c_e11;
    let mut cceil_p = match (kind, drawn) {
        (Some(k), Some((_, r))) if !no_oracle => shape_ceiling_p(k, r, &unit, &snap, ceil_seed),
        _ => f64::NAN,
    };
    let mut wceil_p = f64::NAN;
    let mut null_z = [f64::NAN; 5];
    if kind.is_none() && !no_oracle {
        let mut nrng = Xoshiro256PlusPlus::seed_from_u64(stream ^ 0x6a_c1e5);
        for (k, (_, kk)) in KINDS[1..].iter().enumerate() {
            let (p, r) = draw_effect(&mut nrng, &unit, kk.expect("effect kind"));
            match p.kind() {
                EffectKind::GaussMarkov => {
                    cceil_p = shape_ceiling_p(p.kind(), r, &unit, &snap, ceil_seed)
                }
                EffectKind::Warmup => {
                    wceil_p = shape_ceiling_p(p.kind(), r, &unit, &snap, ceil_seed)
                }
                _ => {}
            }
            let js = match p {
                EffectParams::BiasJumps { count, rms_size } => {
                    draw_jumps(count, rms_size, unit.t_run, nrng.random::<u64>())
                }
                _ => Vec::new(),
            };
            null_z[k] = oracle_z(p, &js, &unit, &snap).map_or(f64::NAN, |o| o.0);
            if let (EffectParams::BiasJumps { count, .. }, Some(c5)) = (p, base_c5) {
                jceil_p = ceiling(count, jumps_rms(&js), &c5, stream);
            }
        }
    }
    let mut lr = [f64::NAN; 6];
    let mut galt = [f64::NAN; 6];
    if let Ok(d) = &d {
        for sc in &d.first_scores {
            if let Some(ix) = LR_KINDS.iter().position(|k| *k == sc.kind) {
                lr[ix] = sc.score;
                galt[ix] = sc.gap_alt;
            }
        }
    }
    // The kinds the record lists among its alternatives (a tie said out loud).
    let alt_kinds: Vec<&'static str> = d.as_ref().map_or(Vec::new(), |d| {
        let mut k: Vec<&'static str> = d
            .alternatives
            .iter()
            .flat_map(|a| a.effects.iter().map(|e| e.kind().name()))
            .collect();
        k.sort_unstable();
        k.dedup();
        k
    });
    let (verdict, gap_before, gap_after, named, qlim) = match d {
        Ok(d) => (
            d.verdict,
            d.gap_before,
            d.gap_after,
            d.effects.iter().map(|e| e.params).collect(),
            d.quantization_limited.is_some(),
        ),
        Err(e) => {
            eprintln!("{family} {} draw {i}: {e}", kind_name(kind));
            (Verdict::Unexplained, f64::NAN, f64::NAN, Vec::new(), false)
        }
    };
    Outcome {
        family,
        truth_kind: kind,
        truth,
        rho,
        verdict,
        gap_before,
        gap_after,
        named,
        oracle,
        null_z,
        secs,
        unit,
        qlim,
        warm_b,
        jump_z,
        resid,
        jceil_p,
        cceil_p,
        wceil_p,
        alt_kinds,
        jump_excess,
        jump_shift,
        lr,
        galt,
        warm_scale,
        warm_b_scaled,
        warm_p,
        warm_p_up,
        warm_p_prof,
        warm_k_up,
        warm_k_null,
        nu,
        n_taus,
    }
}

/// `|found / truth - 1|` of the shape and the amplitude (jumps: the count and the rms size).
fn param_errors(truth: &EffectParams, found: &EffectParams) -> (f64, f64) {
    let rel = |a: f64, b: f64| ((a - b) / b).abs();
    match (truth, found) {
        (
            EffectParams::BiasJumps { count, rms_size },
            EffectParams::BiasJumps {
                count: c2,
                rms_size: r2,
            },
        ) => (rel(*c2 as f64, *count as f64), rel(*r2, *rms_size)),
        _ => (
            rel(found.shape(), truth.shape()),
            rel(found.amplitude(), truth.amplitude()),
        ),
    }
}

fn fmt_q(v: &[f64]) -> String {
    if v.is_empty() {
        return "-".into();
    }
    format!("{:.3} / {:.3}", quantile(v, 0.5), quantile(v, 0.9))
}

/// Whether the effect `p` named on a clean draw of `u` is part of the unit: its intrinsic
/// filter's kind, or (`adistemp`) a warm-up or a sinusoid within a factor 2 of the temperature
/// cycle's frequency, which describe the hidden temperature-driven drift.
fn part_of_unit(u: &Unit, p: &EffectParams) -> bool {
    if u.intrinsic.map(|i| i.kind()) == Some(p.kind()) {
        return true;
    }
    match (u.temp, p) {
        (Some(_), EffectParams::Warmup { .. }) => true,
        (Some(t), EffectParams::Sinusoid { frequency_hz, .. }) => {
            let r = frequency_hz * t[3];
            (0.5..=2.0).contains(&r)
        }
        _ => false,
    }
}

/// The families of sessions 11 and 12 whose intrinsic filter may be named as any one low-pass
/// kind on a clean run (their rule, fixed before any run: a second-order low-pass with damping
/// near 1 and a zero-phase filter have the same `|H|^2`, hence the same AVAR); the kind named
/// and its parameters are reported beside (`intrinsic_exact`).
fn any_filter_family(family: &str) -> bool {
    matches!(
        family,
        "mimu" | "cicgyro" | "kalgyro" | "kalacc" | "cicacc" | "zpexp" | "bartfog" | "cntfog"
    )
}

/// A clean draw's false alarm (`any_filter_family`: any named effect that is not a low-pass, or
/// two or more low-passes): `consistent` is the right answer for a unit without an intrinsic
/// filter or drift, and anything else a false alarm; for one with them, a false alarm is an
/// effect named that is not part of the unit (`part_of_unit`).
fn false_alarm(o: &Outcome) -> bool {
    if any_filter_family(o.unit.family) {
        let filters = o.named.iter().filter(|p| p.lowpass().is_some()).count();
        return filters >= 2 || o.named.iter().any(|p| p.lowpass().is_none());
    }
    if o.unit.intrinsic.is_none() && o.unit.temp.is_none() {
        o.verdict != Verdict::Consistent
    } else {
        o.named.iter().any(|p| !part_of_unit(&o.unit, p))
    }
}

/// The intrinsic filter named with the right parameters: a moving average's taps and stages
/// exactly, a first-order or zero-phase filter's time constant within 25%, a second-order
/// filter's natural frequency within 25%.
fn intrinsic_exact(o: &Outcome) -> bool {
    let Some(i) = o.unit.intrinsic else {
        return false;
    };
    o.named.iter().any(|p| match (i, p) {
        (
            EffectParams::MovingAverage {
                taps,
                stages,
                decimation,
            },
            EffectParams::MovingAverage {
                taps: t2,
                stages: s2,
                decimation: d2,
            },
        ) => taps == *t2 && stages == *s2 && decimation == *d2,
        (
            EffectParams::OutputFilter { time_constant_s },
            EffectParams::OutputFilter {
                time_constant_s: t2,
            },
        ) => ((t2 - time_constant_s) / time_constant_s).abs() <= 0.25,
        (
            EffectParams::SecondOrderFilter {
                natural_frequency_hz: f,
                ..
            },
            EffectParams::SecondOrderFilter {
                natural_frequency_hz: f2,
                ..
            },
        ) => ((f2 - f) / f).abs() <= 0.25,
        (
            EffectParams::ZeroPhaseFilter { time_constant_s },
            EffectParams::ZeroPhaseFilter {
                time_constant_s: t2,
            },
        ) => ((t2 - time_constant_s) / time_constant_s).abs() <= 0.25,
        _ => false,
    })
}

/// `shares`: the false-alarm share each test of the diagnosis spends, per effect in the order of
/// `KINDS[1..]` (`--shares`), at which the oracle is read beside the whole 5%.
fn report(fam: &str, res: &[&Outcome], kinds: &[Option<EffectKind>], shares: Option<[f64; 5]>) {
    let clean: Vec<&&Outcome> = res.iter().filter(|o| o.truth_kind.is_none()).collect();
    let fa = clean.iter().filter(|o| false_alarm(o)).count();
    let alpha = if clean.is_empty() {
        0.05
    } else {
        fa as f64 / clean.len() as f64
    };
    let g0: Vec<f64> = clean.iter().map(|o| o.gap_before).collect();
    let worse = res
        .iter()
        .filter(|o| o.gap_after > o.gap_before * (1.0 + 1e-12))
        .count();
    let secs: Vec<f64> = res.iter().map(|o| o.secs).collect();
    println!("\n## {fam}");
    if !clean.is_empty() {
        let mut what: Vec<String> = Vec::new();
        for o in clean.iter().filter(|o| false_alarm(o)) {
            let n: Vec<&str> = o.named.iter().map(|p| p.kind().name()).collect();
            what.push(if n.is_empty() {
                format!("{:?} G {:.2}", o.verdict, o.gap_before)
            } else {
                n.join("+")
            });
        }
        println!(
            "false alarms: {} [{}]; G0 median {:.2} q95 {:.2}",
            share(fa, clean.len()),
            what.join(", "),
            quantile(&g0, 0.5),
            quantile(&g0, 0.95)
        );
        let z95 = std_normal_quantile(0.95);
        let nz: Vec<String> = KINDS[1..]
            .iter()
            .enumerate()
            .map(|(k, (n, _))| {
                let zs: Vec<f64> = clean
                    .iter()
                    .map(|o| o.null_z[k])
                    .filter(|z| z.is_finite())
                    .collect();
                let above = zs.iter().filter(|&&z| z > z95).count();
                format!("{n} {above}/{}", zs.len())
            })
            .collect();
        println!(
            "oracle z on clean runs above the nominal 5% point 1.645: {}",
            nz.join(", ")
        );
        // Units with an intrinsic filter or drift: is the filter named, with its parameters,
        // and how do the verdicts fall.
        let own: Vec<&&&Outcome> = clean
            .iter()
            .filter(|o| o.unit.intrinsic.is_some() || o.unit.temp.is_some())
            .collect();
        if !own.is_empty() {
            let kind_named = own
                .iter()
                .filter(|o| {
                    o.unit
                        .intrinsic
                        .is_some_and(|i| o.named.iter().any(|p| p.kind() == i.kind()))
                })
                .count();
            let exact = own.iter().filter(|o| intrinsic_exact(o)).count();
            let by = |v: Verdict| own.iter().filter(|o| o.verdict == v).count();
            let mut wrong: Vec<String> = Vec::new();
            for o in own.iter().filter(|o| {
                o.unit
                    .intrinsic
                    .is_some_and(|i| !o.named.iter().any(|p| p.kind() == i.kind()))
            }) {
                let n: Vec<&str> = o.named.iter().map(|p| p.kind().name()).collect();
                wrong.push(format!("{:?} [{}]", o.verdict, n.join("+")));
            }
            println!(
                "the unit's own filter: kind named {}, with its parameters {}; verdicts consistent {} explained {} unexplained {}; filter not named: {}",
                share(kind_named, own.len()),
                share(exact, own.len()),
                by(Verdict::Consistent),
                by(Verdict::Explained),
                by(Verdict::Unexplained),
                wrong.join(", ")
            );
        }
    }
    println!(
        "said quantization-limited: {}/{}; runs whose final gap is above the base gap: {worse}/{}; seconds per run median {:.1} max {:.1}",
        res.iter().filter(|o| o.qlim).count(),
        res.len(),
        res.len(),
        quantile(&secs, 0.5),
        quantile(&secs, 1.0)
    );
    // Confusion matrix: truth against the first effect named.
    let mut cols: Vec<&'static str> = vec!["none"];
    for o in res.iter() {
        if let Some(p) = o.named.first() {
            let n = p.kind().name();
            if !cols.contains(&n) {
                cols.push(n);
            }
        }
    }
    println!("\n| truth \\ first named | n | {} |", cols.join(" | "));
    println!("|---|---|{}", "---|".repeat(cols.len()));
    for &k in kinds {
        let r: Vec<&&Outcome> = res.iter().filter(|o| o.truth_kind == k).collect();
        if r.is_empty() {
            continue;
        }
        let cells: Vec<String> = cols
            .iter()
            .map(|c| {
                r.iter()
                    .filter(|o| o.named.first().map_or("none", |p| p.kind().name()) == *c)
                    .count()
                    .to_string()
            })
            .collect();
        println!("| {} | {} | {} |", kind_name(k), r.len(), cells.join(" | "));
    }
    println!(
        "\n| effect | n | right first | named anywhere | oracle at 5%: expected [z passes] | oracle at the test's share: expected [z passes] | named - oracle at that share | shape err q50 / q90 | amplitude err q50 / q90 |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    // Without `--shares`, the diagnosis's measured share in this family, floored at 1% (0 of a
    // few tens of runs does not say the share is 0).
    // The filters beyond first order share the output filter's test (`lr_crit_filters`).
    let share_of = |k: EffectKind| {
        let k = match k {
            EffectKind::MovingAverage
            | EffectKind::SecondOrderFilter
            | EffectKind::ZeroPhaseFilter => EffectKind::OutputFilter,
            k => k,
        };
        KINDS[1..]
            .iter()
            .position(|x| x.1 == Some(k))
            .and_then(|i| shares.map(|s| s[i]))
            .unwrap_or(alpha.max(0.01))
    };
    let z5 = std_normal_quantile(0.95);
    for &k in kinds.iter().filter(|k| k.is_some()) {
        let r: Vec<&&Outcome> = res.iter().filter(|o| o.truth_kind == k).collect();
        if r.is_empty() {
            continue;
        }
        let first = r
            .iter()
            .filter(|o| o.named.first().map(|p| p.kind()) == k)
            .count();
        let mut anywhere = 0;
        let (mut es, mut ea) = (Vec::new(), Vec::new());
        for o in &r {
            if let (Some(t), Some(f)) = (
                o.truth,
                o.named.iter().find(|p| Some(p.kind()) == k).copied(),
            ) {
                anywhere += 1;
                let (s, a) = param_errors(&t, &f);
                es.push(s);
                ea.push(a);
            }
        }
        if k == Some(EffectKind::Warmup) {
            let dropped = r
                .iter()
                .filter(|o| {
                    o.warm_b > DiagnoseOptions::default().thresholds.warmup_bf
                        && !o.named.iter().any(|p| p.kind() == EffectKind::Warmup)
                })
                .count();
            eprintln!(
                "{fam}: warm-ups found in time (B > warmup_bf) but not kept: {dropped}/{}",
                r.len()
            );
        }
        let a = k.map_or(0.05, share_of);
        let za = std_normal_quantile(1.0 - a);
        let deltas: Vec<f64> = r.iter().filter_map(|o| o.oracle.map(|x| x.1)).collect();
        let zs: Vec<f64> = r.iter().filter_map(|o| o.oracle.map(|x| x.0)).collect();
        // The oracle's expected power `mean Phi(delta - z_(1-a))` and the draws its own `z`
        // passes at that share.
        let pow = |zc: f64| {
            deltas.iter().map(|d| std_normal_cdf(d - zc)).sum::<f64>() / deltas.len().max(1) as f64
        };
        let passes = |zc: f64| zs.iter().filter(|&&z| z > zc).count();
        let (p5, pa) = (pow(z5), pow(za));
        let named = anywhere as f64 / r.len() as f64;
        println!(
            "| {} | {} | {} | {} | {:.0}% [{}] | {:.1}%: {:.0}% [{}] | {:+.0} | {} | {} |",
            kind_name(k),
            r.len(),
            share(first, r.len()),
            share(anywhere, r.len()),
            100.0 * p5,
            passes(z5),
            100.0 * a,
            100.0 * pa,
            passes(za),
            100.0 * (named - pa),
            fmt_q(&es),
            fmt_q(&ea)
        );
    }
    report_ceiling(res, share_of(EffectKind::BiasJumps));
}

/// The fair jump ceiling's line of the report: jump draws whose ceiling p-value is at most 5%
/// and at most `alpha` (the jump test's share), and the clean runs' share at 5%.
fn report_ceiling(res: &[&Outcome], alpha: f64) {
    let jp: Vec<f64> = res
        .iter()
        .filter(|o| o.truth_kind == Some(EffectKind::BiasJumps))
        .map(|o| o.jceil_p)
        .filter(|p| p.is_finite())
        .collect();
    let np: Vec<f64> = res
        .iter()
        .filter(|o| o.truth_kind.is_none())
        .map(|o| o.jceil_p)
        .filter(|p| p.is_finite())
        .collect();
    if jp.is_empty() && np.is_empty() {
        return;
    }
    let below = |v: &[f64], a: f64| v.iter().filter(|&&p| p <= a + 1e-12).count();
    let a = alpha;
    println!(
        "jump ceiling (count and rms told, times unknown): {} at 5%, {} at {:.1}%; clean runs at 5%: {}",
        share(below(&jp, 0.05), jp.len()),
        share(below(&jp, a), jp.len()),
        100.0 * a,
        share(below(&np, 0.05), np.len())
    );
}

fn main() {
    // The diagnosis's debug lines (`ALLANSCOPE_LOG=allanscope::gap=debug`, one run at a time
    // with `--threads 1`) on standard error, as the binary writes them.
    #[cfg(feature = "cli")]
    if let Ok(f) = tracing_subscriber::EnvFilter::try_from_env("ALLANSCOPE_LOG") {
        tracing_subscriber::fmt()
            .with_writer(std::io::stderr)
            .with_env_filter(f)
            .init();
    }
    let args: Vec<String> = std::env::args().collect();
    let get = |k: &str, d: &str| {
        args.iter()
            .position(|a| a == k)
            .and_then(|i| args.get(i + 1).cloned())
            .unwrap_or_else(|| d.to_string())
    };
    let draws: u64 = get("--draws", "20").parse().expect("--draws");
    // The first draw's index: `--from 10 --draws 10` runs draws 10-19 (the same draws a
    // `--draws 20` run would give them), so that a long run can be split.
    let from: u64 = get("--from", "0").parse().expect("--from");
    // Clean draws without their oracle statistics and jump ceiling (null studies of the
    // diagnosis's own statistics, about twice as fast).
    let no_oracle = args.iter().any(|a| a == "--no-oracle");
    let seed: u64 = get("--seed", "1").parse().expect("--seed");
    let threads: usize = get("--threads", "2").parse().expect("--threads");
    let default_kinds: Vec<&str> = KINDS.iter().map(|k| k.0).collect();
    let kinds: Vec<Option<EffectKind>> = get("--effects", &default_kinds.join(","))
        .split(',')
        .map(|e| {
            KINDS
                .iter()
                .chain(EXTRA_KINDS.iter())
                .find(|k| k.0 == e)
                .unwrap_or_else(|| panic!("--effects: unknown {e} (one of {default_kinds:?})"))
                .1
        })
        .collect();
    let hours = match get("--hours", "").as_str() {
        "" => None,
        h => {
            let v: Vec<f64> = h
                .split(',')
                .map(|x| x.parse().expect("--hours A,B"))
                .collect();
            assert!(v.len() == 2 && v[0] > 0.0 && v[1] >= v[0], "--hours A,B");
            Some((v[0], v[1]))
        }
    };
    let fams_arg = get("--families", &FAMILIES[..6].join(","));
    let fams_arg = fams_arg
        .replace("heldout", &HELDOUT.join(","))
        .replace("unseen10", &UNSEEN10.join(","))
        .replace("unseen11", &UNSEEN11.join(","))
        .replace("unseen12", &UNSEEN12.join(","))
        .replace("unseen", &UNSEEN.join(","));
    let fams: Vec<&'static str> = fams_arg
        .split(',')
        .map(|f| {
            *FAMILIES
                .iter()
                .find(|x| **x == f)
                .unwrap_or_else(|| panic!("--families: unknown {f} (one of {FAMILIES:?})"))
        })
        .collect();
    let csv = get("--csv", "");
    let models = get("--models", "");
    if !models.is_empty() {
        std::fs::create_dir_all(&models).expect("--models DIR");
        MODELS_DIR.set(models).expect("--models once");
    }
    // The share each test of the diagnosis spends, in percent, per effect of `KINDS[1..]`
    // (docs/gap.md, "Detection against the oracle"); the oracle is also read at it.
    let shares: Option<[f64; 5]> = match get("--shares", "").as_str() {
        "" => None,
        v => {
            let p: Vec<f64> = v
                .split(',')
                .map(|x| x.parse::<f64>().expect("--shares: five percentages") / 100.0)
                .collect();
            assert!(
                p.len() == 5 && p.iter().all(|x| *x > 0.0 && *x < 1.0),
                "--shares: five percentages in (0, 100), gauss_markov,sinusoid,output_filter,warmup,bias_jumps"
            );
            Some([p[0], p[1], p[2], p[3], p[4]])
        }
    };
    let mut items: Vec<(&'static str, Option<EffectKind>, u64)> = Vec::new();
    for &f in &fams {
        for i in from..from + draws {
            for &k in &kinds {
                items.push((f, k, i));
            }
        }
    }
    let t = Instant::now();
    let res = par_map(&items, threads, |(f, k, i)| {
        run_one(f, k, i, seed, hours, no_oracle)
    });
    println!(
        "# family_gap: {draws} draws per family and effect, seed {seed}, {:.0} s wall",
        t.elapsed().as_secs_f64()
    );
    for &f in &fams {
        let r: Vec<&Outcome> = res.iter().filter(|o| o.family == f).collect();
        report(f, &r, &kinds, shares);
    }
    if !csv.is_empty() {
        let mut text = String::from(
            "family,effect,draw,tau0,t_run,q,n,b,k,r,lsb,rate_lsb,rho,verdict,gap_before,gap_after,named,shape_true,amp_true,oracle_z,oracle_delta,null_z_gm,null_z_sin,null_z_filter,null_z_warmup,null_z_jumps,secs,qlim,warm_b,jump_z1,jump_z2,jump_z3,jceil_p,lr_gm,lr_sin,lr_filter,lr_ma,lr_second,lr_zero,galt_gm,galt_sin,galt_filter,galt_ma,galt_second,galt_zero,warm_scale,warm_b_scaled,warm_p,bias,intrinsic,false_alarm,intrinsic_exact,named_params,warm_p_up,warm_p_prof,warm_k_up,warm_k_null,nu,n_taus,cceil_p,wceil_p,alt_kinds,jump_excess,jump_shift\n",
        );
        for (o, (_, _, i)) in res.iter().zip(&items) {
            let u = &o.unit;
            let (st, at) = o.truth.map_or((f64::NAN, f64::NAN), |t| match t {
                EffectParams::BiasJumps { count, rms_size } => (count as f64, rms_size),
                _ => (t.shape(), t.amplitude()),
            });
            let nz: Vec<String> = o.null_z.iter().map(|z| format!("{z:.4}")).collect();
            text += &format!(
                "{},{},{},{},{:.0},{:e},{:e},{:e},{:e},{:e},{:e},{:e},{:.3},{:?},{:.4},{:.4},{},{:e},{:e},{:.4},{:.4},{},{:.3},{},{:.3},{:.3},{:.3},{:.3},{:.4},{},{},{:.4},{:.3},{:.4},{:e},{},{},{},{},{:.4},{:.4},{:e},{:e},{:.2},{},{:.4},{:.4},{},{:.3},{:.3}\n",
                u.family,
                kind_name(o.truth_kind),
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
                o.rho,
                o.verdict,
                o.gap_before,
                o.gap_after,
                o.named
                    .iter()
                    .map(|p| p.kind().name())
                    .collect::<Vec<_>>()
                    .join("+"),
                st,
                at,
                o.oracle.map_or(f64::NAN, |x| x.0),
                o.oracle.map_or(f64::NAN, |x| x.1),
                nz.join(","),
                o.secs,
                o.qlim,
                o.warm_b,
                o.jump_z[0],
                o.jump_z[1],
                o.jump_z[2],
                o.jceil_p,
                o.lr.iter()
                    .map(|v| format!("{v:.3}"))
                    .collect::<Vec<_>>()
                    .join(","),
                o.galt
                    .iter()
                    .map(|v| format!("{v:.4}"))
                    .collect::<Vec<_>>()
                    .join(","),
                o.warm_scale,
                o.warm_b_scaled,
                o.warm_p,
                u.bias,
                u.intrinsic
                    .map_or(String::new(), |p| format!("{}:{:.4e}", p.kind().name(), p.shape())),
                o.truth_kind.is_none() && false_alarm(o),
                intrinsic_exact(o),
                o.named
                    .iter()
                    .map(|p| format!("{}:{:.4e}:{:.4e}", p.kind().name(), p.shape(), p.amplitude()))
                    .collect::<Vec<_>>()
                    .join("+"),
                o.warm_p_up,
                o.warm_p_prof,
                o.warm_k_up,
                o.warm_k_null,
                o.nu,
                o.n_taus,
                o.cceil_p,
                o.wceil_p,
                o.alt_kinds.join("+"),
                o.jump_excess,
                o.jump_shift
            );
        }
        std::fs::write(&csv, text).expect("csv");
    }
    let resid_csv = get("--resid", "");
    if !resid_csv.is_empty() {
        let mut text = String::from("family,draw,t_run,tau_frac,z,s_jj,r_share\n");
        for (o, (_, _, i)) in res.iter().zip(&items) {
            for (f, z, sjj, rs) in &o.resid {
                text += &format!(
                    "{},{},{:.0},{:.5e},{:.4},{:.4e},{:.4}\n",
                    o.family, i, o.unit.t_run, f, z, sjj, rs
                );
            }
        }
        std::fs::write(&resid_csv, text).expect("resid csv");
    }
}
