//! The decision thresholds of the gap diagnosis ([`super::diagnose`](mod@super::diagnose)), calibrated by simulation
//! of correct models (docs/gap.md, "Calibration").

use super::effects::EffectKind;

/// Decision thresholds, calibrated by simulation of correct models (docs/gap.md, "Calibration").
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// `G` above this flags the model (about the null 97% quantile, leaving room for the
    /// time-domain tests within a 5% overall false-alarm rate).
    pub gap_crit: f64,
    /// Simultaneous band on `|z_j| = |r_j| / sqrt(S_jj)`: the whole correct curve stays inside
    /// it in 95% of runs.
    pub band_z: f64,
    /// Drop in `r' S^-1 r` per added parameter needed to add an effect once the model is
    /// flagged.
    pub add_chi2: f64,
    /// Drop in `r' S^-1 r` per added parameter by a stationary candidate that flags the model
    /// on its own, even when `G <= gap_crit` (a likelihood-ratio test against the named
    /// alternatives, more sensitive to them than the omnibus `G`), one threshold per candidate
    /// because their scans are searches of very different sizes (12 shapes per decade for the
    /// Gauss-Markov term, 60 for the sinusoid): Gauss-Markov, sinusoid, output filter. Set so
    /// that their union stays within the false-alarm budget (docs/gap.md, "Calibration").
    pub lr_crit: [f64; 3],
    /// `lr_crit` of the filters beyond first order: moving average, second order, zero phase
    /// (docs/gap.md, "Low-pass filters beyond first order").
    pub lr_crit_filters: [f64; 3],
    /// z scores (square roots of the drops of the whitened residual sum of squares at forward
    /// selection) that steps in the block means need to count as bias jumps: at least `k`
    /// steps at `z >= jump_z[k - 1]` ([`detect_steps`](super::steps::detect_steps)).
    pub jump_z: [f64; 3],
    /// Drop of the block-mean residual sum of squares (in robust block variances) that a
    /// warm-up must bring at its best `T` ([`fit_warmup`](super::warmup::fit_warmup)'s `w_stat`); infinite: not used.
    pub warmup_w: f64,
    /// The warm-up's evidence integrated over the scanned `T` ([`WarmupFinding::log_bf`](super::warmup::WarmupFinding::log_bf)) that
    /// a warm-up must bring. A warm-up is found when either statistic passes its threshold.
    pub warmup_bf: f64,
}

impl Thresholds {
    /// The likelihood-ratio threshold of a stationary candidate (`lr_crit`); infinite for the
    /// effects found in time.
    pub fn lr_crit_of(&self, kind: EffectKind) -> f64 {
        match kind {
            EffectKind::GaussMarkov => self.lr_crit[0],
            EffectKind::Sinusoid => self.lr_crit[1],
            EffectKind::OutputFilter => self.lr_crit[2],
            EffectKind::MovingAverage => self.lr_crit_filters[0],
            EffectKind::SecondOrderFilter => self.lr_crit_filters[1],
            EffectKind::ZeroPhaseFilter => self.lr_crit_filters[2],
            EffectKind::Warmup | EffectKind::BiasJumps | EffectKind::Temperature => f64::INFINITY,
        }
    }
}

impl Default for Thresholds {
    fn default() -> Self {
        Self {
            gap_crit: 1.9,
            band_z: 2.5,
            add_chi2: 3.0,
            lr_crit: [5.5, 7.0, 7.0],
            lr_crit_filters: [7.0, 7.0, 7.0],
            jump_z: [4.5, 4.0, 3.4],
            // The integrated statistic replaces the maximum (docs/gap.md, "Mixture
            // statistics"): at the same share of clean runs its tail is steadier across seeds.
            warmup_w: f64::INFINITY,
            warmup_bf: 3.39,
        }
    }
}
