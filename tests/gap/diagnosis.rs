//! The diagnosis on simulated captures with a known hidden effect (ground truth from the
//! simulator's model file): clean data is `consistent`, each effect is named with its parameters
//! within tolerance, the held-out gap shrinks as on the fitting run, the record parses back
//! field by field (docs/records.md), and live streaming gives the batch curve.
//!
//! Runs of one hour at tau0 = 4 ms (900 000 increments, the seed paper's step) of a VOG4-like
//! base (config/models/vog4.toml's N, B, K, LSB). The blind benchmark (examples/blind_gap.rs,
//! docs/gap.md) measures the rates; these cases are single draws well above the detection level.

use allanscope::gap::{
    diagnose, holdout_gap, DiagnoseOptions, Diagnosis, DiagnosisRecord, EffectKind, EffectParams,
    GapConfig, GapEvidence, Verdict,
};
use allanscope::sim::{SimModel, Simulator};
use std::path::Path;

/// Relative tolerance on frequencies and correlation times (the brief's target).
const TOL_SHAPE: f64 = 0.10;
/// Relative tolerance on amplitudes and sigmas (the brief's target).
const TOL_AMP: f64 = 0.25;
/// Gauss-Markov correlation time and filter time constant: the blind benchmark's 90% quantile
/// of the error is 10-45% (docs/gap.md), so the 10% target is not held here.
const TOL_TIME_LOOSE: f64 = 0.25;
/// Warm-up time constant against a free linear drift: 90% quantile of the error about 30-50%
/// (docs/gap.md).
const TOL_WARMUP_T: f64 = 0.5;

pub(crate) const TAU0: f64 = 0.004;
pub(crate) const DURATION_S: f64 = 3600.0;

/// The VOG4-like base model (config/models/vog4.toml's N, B, K and LSB) with `extra` effects:
/// shared by the gap tests that simulate one gyro channel.
pub(crate) fn model(extra: &str) -> String {
    format!(
        "tau0_s = {TAU0}\n[[channel]]\nname = \"g4\"\nunit = \"arcsec\"\nlsb = 0.004\nN = 0.254\nB = 0.225\nK = 1.826e-2\nflicker_band_s = [0.004, 1.0e5]\n{extra}\n"
    )
}

/// [`DURATION_S`] of increments of [`model`]`(extra)`.
pub(crate) fn simulate(extra: &str, seed: u64) -> Vec<f64> {
    simulate_text(&model(extra), TAU0, DURATION_S, seed)
}

/// `seconds` of increments at `tau0` of the first channel of the model file `text`, simulated
/// with `seed`.
pub(crate) fn simulate_text(text: &str, tau0: f64, seconds: f64, seed: u64) -> Vec<f64> {
    let m = SimModel::from_toml_str(text, Path::new("<test>")).expect("model");
    let mut sim = Simulator::new(&m, seed);
    let mut out = vec![0.0; (seconds / tau0) as usize];
    sim.fill_channel(0, &mut out);
    out
}

/// [`simulate`]`("", seed)` with one step of `size` (u/s) in the rate at `t_step` (s)
/// ([`add_step`]).
fn clean_with_step(seed: u64, t_step: f64, size: f64) -> Vec<f64> {
    let mut inc = simulate("", seed);
    add_step(&mut inc, t_step, size);
    inc
}

/// One step of `size` (u/s) in the rate at `t_step` (s) added to increments at [`TAU0`], exact
/// within the increment it falls in.
fn add_step(inc: &mut [f64], t_step: f64, size: f64) {
    for (k, d) in inc.iter_mut().enumerate() {
        let (t0, t1) = (k as f64 * TAU0, (k + 1) as f64 * TAU0);
        if t1 > t_step {
            *d += size * (t1 - t_step.max(t0));
        }
    }
}

/// `inc` diagnosed with the default options, the bookkeeping's rules checked on the result.
fn diagnosed(inc: &[f64]) -> Diagnosis {
    let mut ev = GapEvidence::from_increments(GapConfig::new(TAU0), inc);
    let d = diagnose(&ev.snapshot(), &DiagnoseOptions::default()).expect("diagnosis");
    assert_bookkeeping(&d);
    d
}

fn run(extra: &str, seed: u64) -> Diagnosis {
    diagnosed(&simulate(extra, seed))
}

/// The bookkeeping (docs/gap.md, "Bookkeeping"): each effect's `gap_after` is the gap once it
/// is added, below the one before, except a warm-up or jumps kept on their time-domain
/// evidence alone, which leave the gap as it was (and bring no drop of the curve's misfit); the
/// last is the final gap, never above the base's.
pub(crate) fn assert_bookkeeping(d: &Diagnosis) {
    let mut prev = d.gap_before;
    for e in &d.effects {
        let in_time = matches!(
            e.params.kind(),
            EffectKind::Warmup | EffectKind::BiasJumps | EffectKind::Temperature
        );
        assert!(
            e.gap_after < prev || (in_time && e.gap_after == prev && e.delta_chi2 == 0.0),
            "{e:?} did not lower the gap from {prev}"
        );
        prev = e.gap_after;
    }
    assert_eq!(d.gap_after, prev, "final gap vs the last effect's");
    assert!(d.gap_after <= d.gap_before);
}

fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}

fn first_of(d: &Diagnosis, kind: EffectKind) -> EffectParams {
    assert_eq!(
        d.effects.first().map(|e| e.params.kind()),
        Some(kind),
        "first effect: {:?}",
        d.effects
    );
    d.effects[0].params
}

#[test]
fn clean_runs_are_consistent() {
    // The five-term model is the truth: the gap statistic stays near 1 (null median 1.01,
    // 97% quantile about 1.7 over 600 simulated runs, docs/gap.md). Seeds 2 and 3: seed 1's
    // realization carries a warm-up-shaped wander that the warm-up test (at its 1% level, with
    // K profiled on the block means) names, p 0.006 under its null at any K^2 from 0 to 4 times
    // the null's (docs/gap.md, "The warm-up's null level (session 12)"); session 7's null gave
    // it 0.014.
    for seed in [2, 3] {
        let d = run("", seed);
        assert_eq!(d.verdict, Verdict::Consistent, "seed {seed}: {d:?}");
        assert!(d.effects.is_empty());
        assert!(d.gap_before < 1.7, "gap {}", d.gap_before);
        // N recovered within 5% (vog4.toml: 0.254 arcsec/sqrt(s)).
        assert!(rel(d.base_coef[1], 0.254) < 0.05, "N {}", d.base_coef[1]);
    }
}

#[test]
fn gauss_markov_is_named_with_its_parameters() {
    // vog4_effects.toml's Gauss-Markov term.
    let d = run("gauss_markov = { sigma = 0.5, tau_c = 2.0 }", 3);
    assert_eq!(d.verdict, Verdict::Explained, "{d:?}");
    assert!(d
        .regions
        .iter()
        .any(|r| r.sign > 0 && r.tau_lo_s < 4.0 && r.tau_hi_s > 2.0));
    match first_of(&d, EffectKind::GaussMarkov) {
        EffectParams::GaussMarkov { sigma, tau_c_s } => {
            assert!(rel(tau_c_s, 2.0) < TOL_TIME_LOOSE, "tau_c {tau_c_s}");
            assert!(rel(sigma, 0.5) < TOL_AMP, "sigma {sigma}");
        }
        p => panic!("{p:?}"),
    }
    assert!(d.gap_after < d.gap_before / 3.0);
}

#[test]
fn sinusoid_is_named_with_its_parameters() {
    let d = run(
        "sinusoid = { amplitude = 0.3, frequency = 0.8, phase = 0.0 }",
        4,
    );
    match first_of(&d, EffectKind::Sinusoid) {
        EffectParams::Sinusoid {
            amplitude,
            frequency_hz,
        } => {
            assert!(rel(frequency_hz, 0.8) < TOL_SHAPE, "f {frequency_hz}");
            assert!(rel(amplitude, 0.3) < TOL_AMP, "A {amplitude}");
        }
        p => panic!("{p:?}"),
    }
    assert_eq!(d.verdict, Verdict::Explained);
}

#[test]
fn output_filter_is_named_with_its_time_constant() {
    let d = run("output_filter = { time_constant = 0.02 }", 5);
    match first_of(&d, EffectKind::OutputFilter) {
        EffectParams::OutputFilter { time_constant_s } => {
            assert!(
                rel(time_constant_s, 0.02) < TOL_TIME_LOOSE,
                "T {time_constant_s}"
            );
        }
        p => panic!("{p:?}"),
    }
    // The data lie below the white-noise line at the shortest taus.
    assert!(d
        .regions
        .first()
        .is_some_and(|r| r.sign < 0 && r.tau_lo_s < 0.01));
}

#[test]
fn warmup_is_named_with_its_parameters() {
    // A = 5 u/s: with a free linear drift, the generalised least squares on the block means
    // sees a 2 u/s warm-up of 300 s at only about 2.9 sigma against this base (a noise-free
    // run through the same test gives W = 8.5), 5 u/s at about 7 sigma.
    let d = run("warmup = { amplitude = 5.0, time_constant = 300.0 }", 6);
    match first_of(&d, EffectKind::Warmup) {
        EffectParams::Warmup {
            amplitude,
            time_constant_s,
        } => {
            assert!(
                rel(time_constant_s, 300.0) < TOL_WARMUP_T,
                "T {time_constant_s}"
            );
            assert!(rel(amplitude, 5.0) < TOL_AMP, "A {amplitude}");
        }
        p => panic!("{p:?}"),
    }
}

/// The first block's mean raised alone (the first 8.2 s of a VOG4-like hour counted at
/// 0.0005 arcsec, by 1.2 arcsec/s: 13 times a block mean's noise, nothing after it). Its best
/// warm-up decays within that block, at the scan's shortest time constant (half a block), where
/// only one mean shows it and its amplitude and time constant are not told apart: not named.
/// Before session 43 it was, as a 2.4 arcsec/s warm-up of 4.1 s (and on a review's FOG, a
/// Gauss-Markov hump's excursion at the start as a 0.19 arcsec/s warm-up of 16 s).
#[test]
fn a_first_block_raised_alone_is_no_warmup() {
    let text = model("").replace("lsb = 0.004", "lsb = 0.0005");
    let mut inc = simulate_text(&text, TAU0, DURATION_S, 3);
    // as the command line reads a file, its length not known ahead: blocks of 8.192 s
    let mut ev = GapEvidence::new(GapConfig::new(TAU0));
    let block = (8.192 / TAU0) as usize;
    for d in inc.iter_mut().take(block) {
        *d += 1.2 * TAU0;
    }
    for &d in &inc {
        ev.push_increment(d);
    }
    let snap = ev.snapshot();
    assert_eq!(
        snap.block_len as usize, block,
        "the block this case was found at"
    );
    let d = diagnose(&snap, &DiagnoseOptions::default()).expect("diagnosis");
    assert_bookkeeping(&d);
    assert!(
        d.effects
            .iter()
            .all(|e| e.params.kind() != EffectKind::Warmup),
        "{:?}",
        d.effects
    );
    // Reported as what it is (session 45): the first block, from the start, 1.2 arcsec/s above
    // the four blocks after it within three standard deviations of that difference (a block
    // mean's sd, read from the later blocks' successive differences, is about 0.2 arcsec/s
    // with the unit's flicker; 0.83 measured), at a small p-value.
    let later = &snap.block_means[1..];
    let sd_block = (later.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>()
        / (2.0 * (later.len() - 1) as f64))
        .sqrt();
    let b = d.first_block.expect("the first block is reported");
    assert!(b.start_s.abs() < 1e-9, "start {}", b.start_s);
    assert!((b.seconds - 8.192).abs() < 1e-6, "length {}", b.seconds);
    assert!(
        (b.offset - 1.2).abs() < 3.0 * sd_block * 1.25f64.sqrt(),
        "offset {} (block sd {sd_block})",
        b.offset
    );
    assert!(b.p_value <= 0.01, "p {}", b.p_value);
    // The record carries it, and the table says it.
    let rec = allanscope::gap::record::DiagnosisRecord::new("x", &d, None, true);
    let json = serde_json::to_value(&rec).expect("json");
    assert_eq!(json["first_block"]["seconds"].as_f64(), Some(b.seconds));
    let words = allanscope::sink::first_block_words::first_block_words(&rec, "arcsec", &|v| {
        format!("{v:.2}")
    })
    .expect("words");
    assert!(
        words.starts_with("the block from 0.00 s to 8.19 s averages ") && words.contains("above"),
        "{words}"
    );
}

#[test]
fn bias_jumps_are_found_in_time() {
    // Jumps of rms 6 arcsec/s, about 24 times the block-difference noise (0.25 arcsec/s at
    // 14 s blocks).
    let d = run("bias_jumps = { mean_interval = 900.0, rms_size = 6.0 }", 7);
    let p = d
        .effects
        .iter()
        .find(|e| e.params.kind() == EffectKind::BiasJumps)
        .map(|e| e.params);
    match p {
        Some(EffectParams::BiasJumps { count, rms_size }) => {
            let found = d.jumps.as_ref().map_or(0, |j| j.sizes.len());
            assert_eq!(count as usize, found);
            assert!((1..=12).contains(&count), "count {count}");
            assert!(rms_size > 2.0 && rms_size < 18.0, "rms {rms_size}");
        }
        other => panic!("{other:?} in {:?}", d.effects),
    }
}

#[test]
fn injected_steps_are_located_and_sized() {
    // Three steps added to a clean run (the truth is exact): sizes 3, -2.5 and 2 arcsec/s,
    // 8-12 times the block-difference noise (about 0.25 arcsec/s at 14 s blocks).
    let truth = [(1000.3, 3.0), (2000.0, -2.5), (2900.7, 2.0)];
    let mut inc = simulate("", 12);
    let mut level = 0.0;
    let mut next = 0;
    for (k, d) in inc.iter_mut().enumerate() {
        let (t0, t1) = (k as f64 * TAU0, (k + 1) as f64 * TAU0);
        let mut add = level * TAU0;
        while next < truth.len() && truth[next].0 < t1 {
            add += truth[next].1 * (t1 - truth[next].0.max(t0));
            level += truth[next].1;
            next += 1;
        }
        *d += add;
    }
    let d = diagnosed(&inc);
    let j = d.jumps.as_ref().expect("jump search ran");
    assert_eq!(j.sizes.len(), truth.len(), "{j:?}");
    for ((t, s), (tt, ts)) in j.times_s.iter().zip(&j.sizes).zip(truth) {
        assert!((t - tt).abs() <= j.block_s, "time {t} vs {tt}");
        assert!(rel(*s, ts) < TOL_AMP, "size {s} vs {ts}");
    }
    match d
        .effects
        .iter()
        .find(|e| e.params.kind() == EffectKind::BiasJumps)
    {
        Some(e) => match e.params {
            EffectParams::BiasJumps { count, rms_size } => {
                assert_eq!(count, 3);
                // rms of the true sizes: sqrt((9 + 6.25 + 4) / 3) = 2.533.
                assert!(rel(rms_size, 2.533) < TOL_AMP, "rms {rms_size}");
            }
            p => panic!("{p:?}"),
        },
        None => panic!("no bias_jumps in {:?}", d.effects),
    }
}

#[test]
fn a_jump_the_curve_does_not_show_is_kept_on_its_time_domain_evidence() {
    // One step of 1.6 arcsec/s at 1800.3 s on a clean one-hour run (seed 12): the step search
    // scores it at z 9.3, far above the jump rule's one-step 4.5, while its AVAR is lost in the
    // five terms' curve (the gap with it in is not lower). The jump rule is calibrated on
    // clean runs as such (0.7% of seed 181's 600 clean runs, docs/gap.md, "Bookkeeping"), so
    // the step is named with its time and size although the curve's gap does not fall; until
    // session 18 the bookkeeping dropped it.
    let (t_step, size) = (1800.3, 1.6);
    let inc = clean_with_step(12, t_step, size);
    let d = diagnosed(&inc);
    let j = d.jumps.as_ref().expect("jump search ran");
    assert_eq!(j.sizes.len(), 1, "{j:?}");
    assert!(
        (j.times_s[0] - t_step).abs() <= j.block_s,
        "time {:?}",
        j.times_s
    );
    assert!(rel(j.sizes[0], size) < TOL_AMP, "size {:?}", j.sizes);
    let e = d
        .effects
        .iter()
        .find(|e| e.params.kind() == EffectKind::BiasJumps)
        .unwrap_or_else(|| panic!("no bias_jumps in {:?}", d.effects));
    match e.params {
        EffectParams::BiasJumps { count, rms_size } => {
            assert_eq!(count, 1);
            assert!(rel(rms_size, size) < TOL_AMP, "rms {rms_size}");
        }
        p => panic!("{p:?}"),
    }
    // Kept on the time-domain evidence: the model and the gap are those before it.
    assert_eq!((e.gap_after, e.delta_chi2), (d.gap_before, 0.0), "{e:?}");
    assert_eq!(d.gap_after, d.gap_before);
    assert_eq!(d.verdict, Verdict::Explained);
}

/// A warm-up of 3 arcsec/s over 300 s beside a jump of 2.5 arcsec/s at 2000.3 s (one hour of
/// the VOG4-like base). The jump, not yet taken out when the warm-up is tested, raised the
/// random walk of the warm-up's null (on the block means and on the curve), and on seeds 2 and 5
/// the warm-up passed for wander: session 54's build named the jump alone (these increments
/// written out and read by its `diagnose`; 5 of 8 seeds so). Since session 55 the warm-up is
/// tested again with the jumps out, and the jumps searched again with the warm-up out: 7 of the
/// 8 seeds name it (seed 4 does not).
#[test]
fn a_warmup_beside_a_jump_is_tested_with_the_jump_out() {
    let (t_step, size) = (2000.3, 2.5);
    for seed in [2, 5] {
        let mut inc = simulate("warmup = { amplitude = 3.0, time_constant = 300.0 }", seed);
        add_step(&mut inc, t_step, size);
        let d = diagnosed(&inc);
        let warm = d
            .effects
            .iter()
            .find(|e| e.params.kind() == EffectKind::Warmup)
            .unwrap_or_else(|| panic!("seed {seed}: no warm-up in {:?}", d.effects));
        match warm.params {
            EffectParams::Warmup {
                amplitude,
                time_constant_s,
            } => {
                assert!(rel(amplitude, 3.0) < TOL_AMP, "seed {seed}: A {amplitude}");
                assert!(
                    rel(time_constant_s, 300.0) < TOL_WARMUP_T,
                    "seed {seed}: T {time_constant_s}"
                );
            }
            p => panic!("{p:?}"),
        }
        let j = d.jumps.as_ref().expect("jump search ran");
        assert_eq!(j.sizes.len(), 1, "seed {seed}: {j:?}");
        assert!(
            (j.times_s[0] - t_step).abs() <= j.block_s,
            "seed {seed}: {j:?}"
        );
        assert!(rel(j.sizes[0], size) < TOL_AMP, "seed {seed}: {j:?}");
        assert_eq!(d.verdict, Verdict::Explained);
    }
}

#[test]
fn the_record_gives_each_jump_its_time_from_the_first_sample_and_its_size() {
    // The run of the test above behind a leading gap of 2.6 blocks (a logger that started
    // late): the block tests leave out the three short blocks at the start and count time from
    // the first block they keep; the record's `jumps` counts it from the record's first sample,
    // as the run's other times are. Before, the diagnosis knew the step's time and the record
    // did not carry it (count and rms size only).
    let (t_step, size) = (1800.3, 1.6);
    let inc = clean_with_step(12, t_step, size);
    let streamed = |lead: u64| {
        let mut ev = GapEvidence::new(GapConfig::new(TAU0));
        ev.push_gap(lead);
        for &x in &inc {
            ev.push_increment(x);
        }
        ev.snapshot()
    };
    let block_len = streamed(0).block_len;
    let lead = block_len * 26 / 10;
    let snap = streamed(lead);
    assert_eq!(
        (snap.block_len, snap.block_first),
        (block_len, 3),
        "the short blocks left out"
    );
    let d = diagnose(&snap, &DiagnoseOptions::default()).expect("diagnosis");
    assert_bookkeeping(&d);
    let rec = DiagnosisRecord::new("g", &d, None, true);
    let j = rec.jumps.as_ref().expect("the record's jumps");
    assert_eq!(j.steps.len(), 1, "{j:?}");
    let want_s = lead as f64 * TAU0 + t_step;
    assert!(
        (j.steps[0].time_s - want_s).abs() <= j.block_s,
        "time {} s vs {want_s} s (block {} s)",
        j.steps[0].time_s,
        j.block_s
    );
    assert!(rel(j.steps[0].size, size) < TOL_AMP, "size {:?}", j.steps);
    // The jump rule's one-step level is 4.5 (docs/gap.md); this step stands far above it.
    assert!(j.steps[0].z > 4.5, "z {}", j.steps[0].z);
    // The terminal and the report say it in words, with the channel's datasheet unit.
    let words = allanscope::sink::jump_words::jump_words(&rec, "arcsec", &|v| format!("{v:.0}"))
        .expect("words");
    assert!(
        words.starts_with(&format!(
            "jump (times to within {:.0} s): at {:.0} s, +",
            j.block_s, j.steps[0].time_s
        )) && words.contains("deg/h"),
        "{words}"
    );
    // Without a jump named, no `jumps` at all.
    let clean = DiagnosisRecord::new("g", &diagnosed(&simulate("", 12)), None, true);
    assert!(clean.jumps.is_none(), "{:?}", clean.jumps);
}

#[test]
fn held_out_gap_shrinks_as_on_the_fitting_run() {
    let extra = "gauss_markov = { sigma = 0.5, tau_c = 2.0 }";
    let d = run(extra, 8);
    let inc2 = simulate(extra, 9);
    let mut ev2 = GapEvidence::from_increments(GapConfig::new(TAU0), &inc2);
    let held = holdout_gap(&d, &ev2.snapshot(), &DiagnoseOptions::default()).expect("holdout");
    let (before, after) = (held.gap_before, held.gap_after);
    // The Gauss-Markov term is the same on both runs: it carries.
    assert!(held.carried(), "{held:?}");
    assert!(before > 3.0, "held-out gap before {before}");
    // As small as on the fitting run: below the critical gap (1.7, the null 97% quantile) and no more than 1.5
    // times the fitting run's.
    assert!(
        after < 1.7 && after < 1.5 * d.gap_after.max(1.0),
        "{after} vs {}",
        d.gap_after
    );
    let rec = DiagnosisRecord::new("g4", &d, Some(&held), true);
    let back: serde_json::Value = serde_json::from_str(&rec.to_json_line()).expect("json");
    assert_eq!(back["holdout"]["carried"], true);
    assert!(
        rel(
            back["holdout"]["gap_after"].as_f64().unwrap_or(f64::NAN),
            after
        ) < 1e-12
    );
}

#[test]
fn record_has_the_contract_fields() {
    let d = run(
        "sinusoid = { amplitude = 0.3, frequency = 0.8, phase = 0.0 }",
        10,
    );
    let line = DiagnosisRecord::new("g4", &d, None, true).to_json_line();
    let v: serde_json::Value = serde_json::from_str(&line).expect("json");
    assert_eq!(v["type"], "diagnosis");
    assert_eq!(v["channel"], "g4");
    assert_eq!(v["verdict"], "explained");
    // Parsed numbers agree to the last bits (serde_json's default float parser).
    assert!(rel(v["gap_before"].as_f64().unwrap_or(f64::NAN), d.gap_before) < 1e-12);
    assert!(rel(v["gap_after"].as_f64().unwrap_or(f64::NAN), d.gap_after) < 1e-12);
    assert!(v.get("holdout").is_none());
    let r0 = &v["regions"][0];
    for k in ["tau_lo", "tau_hi", "sign", "worst_ratio"] {
        assert!(r0.get(k).is_some(), "region field {k}");
    }
    let e0 = &v["effects"][0];
    assert_eq!(e0["kind"], "sinusoid");
    assert!(e0["params"]["amplitude"].is_f64() && e0["params"]["frequency"].is_f64());
    assert!(e0["gap_after"].is_f64());
    let back: DiagnosisRecord = serde_json::from_str(&line).expect("parse back");
    assert_eq!(back.effects.len(), d.effects.len());
}

#[test]
fn live_stream_gives_the_batch_curve() {
    // The dense curve does not depend on the segmentation (known length vs doubling), and a
    // gap splits the data without being counted as data.
    let inc = simulate("", 12);
    let n = 300_000;
    let mut batch = GapEvidence::from_increments(GapConfig::new(TAU0), &inc[..n]);
    let mut live = GapEvidence::new(GapConfig::new(TAU0));
    for &d in &inc[..n] {
        live.push_increment(d);
    }
    let (a, b) = (batch.snapshot(), live.snapshot());
    assert_eq!(a.curve, b.curve);
    assert_eq!(b.n_increments, n as u64);
    live.push_gap(10);
    assert_eq!(live.snapshot().n_received, n as u64);
    assert_eq!(live.snapshot().n_increments, n as u64 + 10);
}

#[test]
fn jumps_are_kept_by_the_one_strong_or_several_moderate_rule() {
    use allanscope::gap::steps::JumpFinding;
    let f = |z: &[f64]| JumpFinding {
        times_s: (0..z.len()).map(|i| 100.0 * (i + 1) as f64).collect(),
        sizes: vec![1.0; z.len()],
        z_scores: z.to_vec(),
        block_s: 10.0,
    };
    let rule = [4.5, 4.0, 3.6];
    // One strong step: kept alone, the weaker one is not.
    assert_eq!(f(&[3.0, 4.6]).accepted(&rule).times_s, vec![200.0]);
    // Two moderate steps, neither strong: both kept.
    assert_eq!(f(&[4.1, 4.2]).accepted(&rule).z_scores, vec![4.1, 4.2]);
    // Three at the lowest level: all three kept, a fourth below it is not.
    assert_eq!(f(&[3.7, 3.3, 3.8, 3.65]).accepted(&rule).sizes.len(), 3);
    // Two at the lowest level only: none.
    assert!(f(&[3.7, 3.8]).accepted(&rule).sizes.is_empty());
    // A single threshold is the plain rule.
    assert_eq!(f(&[4.4, 4.6, 4.7]).accepted(&[4.5]).sizes.len(), 2);
}

#[test]
fn steps_avar_matches_the_batch_estimator_on_a_step_signal() {
    // Rate steps (u/s) at known samples, through the batch overlapped AVAR of their phase
    // (docs/theory.md section 1), against the closed-form triangles of `terms::steps_avar`.
    use allanscope::allan::batch::{oavar, phase_from_increments};
    use allanscope::model::terms::steps_avar;
    let n = 20_000u64;
    let tau0 = 0.004;
    let positions = [3_000u64, 3_100, 12_000, 19_990];
    let sizes = [1.0, -0.5, 2.0, 0.7];
    let d: Vec<f64> = (0..n)
        .map(|i| {
            let y: f64 = positions
                .iter()
                .zip(&sizes)
                .filter(|(&p, _)| i >= p)
                .map(|(_, &s)| s)
                .sum();
            y * tau0
        })
        .collect();
    let x = phase_from_increments(&d);
    for m in [1u64, 7, 50, 64, 100, 640, 3_000, 9_000] {
        let batch = oavar(&[&x[..]], m as usize, tau0).unwrap().var;
        let closed = steps_avar(&positions, &sizes, m, n);
        // Exact while each triangle side has at most 64 points; midpoint sums beyond.
        let tol = if m <= 64 { 1e-9 } else { 1e-4 };
        assert!(
            ((closed - batch) / batch).abs() < tol,
            "m {m}: closed {closed:e} batch {batch:e}"
        );
    }
}

#[test]
fn a_large_step_is_named_as_a_jump_not_as_a_slow_oscillation() {
    // One step early in the run: on the curve it is not the smooth rate random walk that K
    // describes. Before the step's own AVAR was taken out of the curve, a slow sinusoid took it
    // first on this seed (and on seed 4; blind benchmark draws 281 and 383 likewise), with the
    // gap left at 1.03. The step is 16 times the block-difference noise.
    let (t_step, size) = (250.0, 4.0);
    let inc = clean_with_step(2, t_step, size);
    let d = diagnosed(&inc);
    match first_of(&d, EffectKind::BiasJumps) {
        EffectParams::BiasJumps { count, rms_size } => {
            assert!((1..=2).contains(&count), "count {count}");
            let j = d.jumps.as_ref().expect("jumps");
            let total: f64 = j.sizes.iter().sum();
            assert!(rel(total, size) < TOL_AMP, "sizes {:?}", j.sizes);
            assert!(rms_size > 0.0);
        }
        p => panic!("{p:?}"),
    }
    assert_eq!(d.effects.len(), 1, "{:?}", d.effects);
    // Taking the step's AVAR out of the curve closes the gap (2.07 before, 0.71 after).
    assert!(
        d.gap_after < 0.5 * d.gap_before,
        "gap {} -> {}",
        d.gap_before,
        d.gap_after
    );
}

#[test]
fn record_carries_the_base_model_and_the_model_with_effects() {
    // A sinusoid at 0.8 Hz lifts the curve near tau = 1/(2 f) over the five-term model; the
    // record's two model lines (for plots) must be the GLS fits the regions were judged on.
    let inc = simulate(
        "sinusoid = { amplitude = 0.3, frequency = 0.8, phase = 0.0 }",
        10,
    );
    let mut ev = GapEvidence::from_increments(GapConfig::new(TAU0), &inc);
    let snap = ev.snapshot();
    let d = diagnose(&snap, &DiagnoseOptions::default()).expect("diagnosis");
    let rec = DiagnosisRecord::new("g4", &d, None, true);
    let n = rec.model_tau.len();
    assert!(n >= 10, "{n} taus");
    assert_eq!(rec.model_base.len(), n);
    assert_eq!(rec.model_effects.len(), n);
    assert_eq!(rec.model_tau[0], d.tau_span_s.0);
    assert_eq!(rec.model_tau[n - 1], d.tau_span_s.1);
    // The measured deviation at each of the record's taus, from the same snapshot.
    let data: Vec<f64> = rec
        .model_tau
        .iter()
        .map(|t| {
            let p = snap
                .curve
                .iter()
                .find(|p| p.tau_s == *t)
                .expect("tau of the curve");
            p.avar.sqrt()
        })
        .collect();
    // Each region's worst ratio (at its largest |z|) is data / base model at one of its taus.
    for r in &rec.regions {
        let hit = (0..n)
            .filter(|&i| rec.model_tau[i] >= r.tau_lo && rec.model_tau[i] <= r.tau_hi)
            .any(|i| rel(data[i] / rec.model_base[i], r.worst_ratio) < 1e-9);
        assert!(hit, "no tau of {r:?} gives its worst ratio");
    }
    // With the sinusoid in, the model follows the data in the regions much more closely.
    let taus = &rec.model_tau;
    let in_region: Vec<usize> = (0..n)
        .filter(|&i| {
            rec.regions
                .iter()
                .any(|r| taus[i] >= r.tau_lo && taus[i] <= r.tau_hi)
        })
        .collect();
    let miss = |m: &[f64]| -> f64 {
        in_region
            .iter()
            .map(|&i| (data[i] / m[i]).ln().abs())
            .fold(0.0, f64::max)
    };
    assert!(!rec.regions.is_empty());
    assert!(
        miss(&rec.model_effects) < 0.5 * miss(&rec.model_base),
        "{} vs {}",
        miss(&rec.model_effects),
        miss(&rec.model_base)
    );
    let back: DiagnosisRecord = serde_json::from_str(&rec.to_json_line()).expect("parse back");
    assert_eq!(back.model_effects.len(), n);
}

/// A run cut into 17 stretches by 16 single missing samples (a review's channel with 16 empty
/// cells over an hour): at the longest taus few second differences fit in a stretch, and an
/// AVAR read off one or two of them is no Gaussian log the fit can weigh. Those taus are not
/// diagnosed (each point's differences must span 4 clusters, `MIN_SPAN_CLUSTERS`; a whole
/// run's span at least 7.5), and the sinusoid the unit has is named, nothing beside it. Before,
/// the rev15 review's channel got five bias jumps and `unexplained` (G 6.6) from its point at
/// 328 s, one difference whose ADEV was 0.03 of the truth.
#[test]
fn taus_starved_by_gaps_are_not_diagnosed() {
    use allanscope::gap::problem::MIN_SPAN_CLUSTERS;
    let inc = simulate(
        "sinusoid = { amplitude = 0.3, frequency = 0.8, phase = 0.0 }",
        3,
    );
    // The review's gaps, as fractions of the run.
    let at = [
        0.045, 0.119, 0.199, 0.283, 0.365, 0.423, 0.508, 0.571, 0.622, 0.708, 0.771, 0.818, 0.866,
        0.906, 0.951, 0.989,
    ];
    let gaps: Vec<usize> = at.iter().map(|f| (f * inc.len() as f64) as usize).collect();
    let mut ev = GapEvidence::new(GapConfig::new(TAU0));
    for (k, &x) in inc.iter().enumerate() {
        if gaps.contains(&k) {
            ev.push_gap(1);
        } else {
            ev.push_increment(x);
        }
    }
    let snap = ev.snapshot();
    let n = snap.n_increments;
    let starved: Vec<u64> = snap
        .curve
        .iter()
        .filter(|p| p.m * 10 <= n && p.count > 0)
        .filter(|p| p.count * p.stride.max(1) < MIN_SPAN_CLUSTERS * p.m)
        .map(|p| p.m)
        .collect();
    assert!(!starved.is_empty(), "the gaps starve the longest taus");
    let d = diagnose(&snap, &DiagnoseOptions::default()).expect("diagnosis");
    assert_bookkeeping(&d);
    let m_last = (d.tau_span_s.1 / TAU0).round() as u64;
    assert!(m_last < starved[0], "{m_last} vs {starved:?}");
    let kinds: Vec<EffectKind> = d.effects.iter().map(|e| e.params.kind()).collect();
    assert_eq!(kinds, vec![EffectKind::Sinusoid], "{:?}", d.effects);
    assert_eq!(d.verdict, Verdict::Explained);
}
