//! The gap as a band (docs/gap.md, "The ensemble band"): the measured curve against the spread
//! of an ensemble of simulated runs of the fitted unit, its five terms alone (`base`) and with
//! the accepted effects (`twin`), each run as long as the input and at its `tau0`. Per tau, the
//! 2.5% and 97.5% points of the simulated ADEV (empirical quantiles over the runs), and the
//! share of measured taus outside each band. Runs are spread over threads; run `k` uses seed
//! `seed + k`.

use crate::sim::model_file::{ChannelModel, SimModel};
use crate::sim::Simulator;

use super::evidence::{GapConfig, GapEvidence};

/// One band: per tau, the 2.5% and 97.5% points of the ensemble's ADEV (u/s).
#[derive(Debug, Clone, PartialEq)]
pub struct Band {
    pub lo: Vec<f64>,
    pub hi: Vec<f64>,
}

impl Band {
    /// The share of `measured` (ADEV at the same taus) outside the band.
    pub fn outside_share(&self, measured: &[f64]) -> f64 {
        let n = measured.len().min(self.lo.len());
        if n == 0 {
            return f64::NAN;
        }
        let out = (0..n)
            .filter(|&i| measured[i] < self.lo[i] || measured[i] > self.hi[i])
            .count();
        out as f64 / n as f64
    }
}

/// The channel with its five terms, LSB and bias only (the effects taken out).
pub fn base_of(ch: &ChannelModel) -> ChannelModel {
    ChannelModel {
        gauss_markov: Vec::new(),
        sinusoids: Vec::new(),
        band_noise: Vec::new(),
        output_filter: None,
        lowpass: None,
        warmup: None,
        bias_jumps: None,
        outliers: None,
        temperature_coefficient: 0.0,
        temperature_quadratic: 0.0,
        ..ch.clone()
    }
}

/// The band of `runs` simulated runs of `ch` (one channel, no temperature profile) of
/// `n_inc` increments at `tau0_s`, at the cluster sizes `ms`, on `threads` threads.
pub fn band(
    ch: &ChannelModel,
    tau0_s: f64,
    n_inc: usize,
    ms: &[u64],
    runs: usize,
    threads: usize,
    seed: u64,
) -> Band {
    let model = SimModel {
        tau0_s,
        stand: None,
        temperature: None,
        channels: vec![ChannelModel {
            temperature_coefficient: 0.0,
            temperature_quadratic: 0.0,
            axis_enu: None,
            ..ch.clone()
        }],
    };
    let one = |k: usize| -> Vec<f64> {
        let mut sim = Simulator::new(&model, seed.wrapping_add(k as u64));
        let mut inc = vec![0.0; n_inc];
        sim.fill_channel(0, &mut inc);
        let mut ev = GapEvidence::from_increments(GapConfig::new(tau0_s), &inc);
        let snap = ev.snapshot();
        ms.iter()
            .map(|m| {
                snap.curve
                    .iter()
                    .find(|p| p.m == *m)
                    .map_or(f64::NAN, |p| p.avar.max(0.0).sqrt())
            })
            .collect()
    };
    let threads = threads.clamp(1, runs.max(1));
    let mut curves: Vec<Vec<f64>> = Vec::with_capacity(runs);
    std::thread::scope(|s| {
        let handles: Vec<_> = (0..threads)
            .map(|t| {
                let one = &one;
                s.spawn(move || (t..runs).step_by(threads).map(one).collect::<Vec<_>>())
            })
            .collect();
        for h in handles {
            curves.extend(h.join().unwrap_or_default());
        }
    });
    let q = |v: &mut Vec<f64>, p: f64| {
        v.sort_by(f64::total_cmp);
        let x = p * (v.len().saturating_sub(1)) as f64;
        let (i, f) = (x.floor() as usize, x.fract());
        match (v.get(i), v.get(i + 1)) {
            (Some(a), Some(b)) => a + f * (b - a),
            (Some(a), None) => *a,
            _ => f64::NAN,
        }
    };
    let mut lo = Vec::with_capacity(ms.len());
    let mut hi = Vec::with_capacity(ms.len());
    for j in 0..ms.len() {
        let mut col: Vec<f64> = curves
            .iter()
            .filter_map(|c| c.get(j).copied())
            .filter(|v| v.is_finite())
            .collect();
        lo.push(q(&mut col, 0.025));
        hi.push(q(&mut col, 0.975));
    }
    Band { lo, hi }
}
