//! The accumulators' configuration: which statistics, which cluster sizes, exact or bounded
//! overlap ([`AccumConfig`]).

#[allow(unused_imports)]
use super::*;

/// Which statistics to accumulate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct StatSet {
    pub avar: bool,
    pub hvar: bool,
    pub mvar: bool,
}

impl StatSet {
    pub const ALL: StatSet = StatSet {
        avar: true,
        hvar: true,
        mvar: true,
    };

    pub fn contains(self, stat: Stat) -> bool {
        match stat {
            Stat::Avar => self.avar,
            Stat::Hvar => self.hvar,
            Stat::Mvar => self.mvar,
        }
    }

    pub fn only(stat: Stat) -> StatSet {
        StatSet {
            avar: stat == Stat::Avar,
            hvar: stat == Stat::Hvar,
            mvar: stat == Stat::Mvar,
        }
    }
}

/// Overlap of the estimates.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Overlap {
    /// The exact overlapping estimate: every difference, memory grows with the run.
    Full,
    /// Bounded memory: differences at stride `max(1, m/L)` (`L >= 1`).
    Bounded(u64),
}

/// The default `L` of bounded mode.
///
/// Chosen from Greenhall's edf of the decimated estimator against full overlap
/// (`cargo run --release --example choose_l`, table in BENCHMARKS.md, "Choosing L"): for a
/// 3-hour 250 Hz run, at `L = 16` AVAR and HVAR keep at least 99.4% of the full overlap's degrees
/// of freedom at every m for white, flicker and random-walk rate noise (the N, B and K terms, which
/// dominate beyond the shortest taus), and MVAR keeps 99.4% for every noise type. White and
/// flicker phase noise on AVAR and HVAR lose edf in proportion to L/m once m > L (their
/// neighbouring differences are nearly independent, so skipping them costs); quantization
/// dominates only at the shortest taus, where the stride is 1. L = 8 keeps 98%, L = 32 99.9%
/// at twice the memory. Memory per channel stays a few hundred KB.
pub const DEFAULT_L: u64 = 16;

/// Which cluster sizes `m` to compute.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum TauSpec {
    /// `m = 1, 2, 4, 8, ...`
    Octave,
    /// `m = 1, 2, 4, 10, 20, 40, 100, ...` (Stable32's decade spacing)
    Decade,
    /// An explicit list of cluster sizes.
    List(Vec<u64>),
}

/// Largest cluster size considered by the open-ended tau specs: 2^40 samples is 35 years at 1 kHz.
pub(super) const MAX_M: u64 = 1 << 40;

impl TauSpec {
    /// The cluster sizes, ascending and without duplicates.
    pub fn cluster_sizes(&self) -> Vec<u64> {
        let mut ms: Vec<u64> = match self {
            TauSpec::Octave => (0..=40).map(|j| 1u64 << j).collect(),
            TauSpec::Decade => {
                let mut v = Vec::new();
                let mut decade = 1u64;
                while decade <= MAX_M {
                    for f in [1, 2, 4] {
                        v.push(f * decade);
                    }
                    decade *= 10;
                }
                v
            }
            TauSpec::List(list) => list.iter().copied().filter(|&m| m >= 1).collect(),
        };
        ms.sort_unstable();
        ms.dedup();
        ms
    }
}

/// Settings of one channel's accumulator.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct AccumConfig {
    /// Sampling step in seconds.
    pub tau0_s: f64,
    pub stats: StatSet,
    pub overlap: Overlap,
    pub taus: TauSpec,
    /// Also accumulate the lag-1 autocorrelations used to identify the noise type per tau.
    pub noise_id: bool,
}

impl AccumConfig {
    /// Each setting that differs from `other`'s, as `name: this vs other` (empty when equal),
    /// in the words of the command line.
    pub fn differences(&self, other: &AccumConfig) -> Vec<String> {
        let mut out = Vec::new();
        if self.tau0_s.to_bits() != other.tau0_s.to_bits() {
            out.push(format!("tau0: {:?} s vs {:?} s", self.tau0_s, other.tau0_s));
        }
        if self.stats != other.stats {
            let names = |s: StatSet| {
                [("avar", s.avar), ("hvar", s.hvar), ("mvar", s.mvar)]
                    .iter()
                    .filter(|x| x.1)
                    .map(|x| x.0)
                    .collect::<Vec<_>>()
                    .join(",")
            };
            out.push(format!(
                "--stats: {} vs {}",
                names(self.stats),
                names(other.stats)
            ));
        }
        if self.overlap != other.overlap {
            let show = |o: Overlap| match o {
                Overlap::Full => "full".to_string(),
                Overlap::Bounded(l) => l.to_string(),
            };
            out.push(format!(
                "--overlap: {} vs {}",
                show(self.overlap),
                show(other.overlap)
            ));
        }
        if self.taus != other.taus {
            let show = |t: &TauSpec| match t {
                TauSpec::Octave => "octave".to_string(),
                TauSpec::Decade => "decade".to_string(),
                TauSpec::List(v) => v.iter().map(u64::to_string).collect::<Vec<_>>().join(","),
            };
            out.push(format!(
                "--taus: {} vs {}",
                show(&self.taus),
                show(&other.taus)
            ));
        }
        if self.noise_id != other.noise_id {
            out.push(format!(
                "noise identification: {} vs {}",
                self.noise_id, other.noise_id
            ));
        }
        out
    }

    pub fn new(tau0_s: f64) -> AccumConfig {
        AccumConfig {
            tau0_s,
            stats: StatSet::ALL,
            overlap: Overlap::Bounded(DEFAULT_L),
            taus: TauSpec::Octave,
            noise_id: true,
        }
    }
}
