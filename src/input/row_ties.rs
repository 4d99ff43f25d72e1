//! Rows that repeat the row before them in every column: a logger that read a sensor's output
//! register before the next sample was in it (a stale row, its time stamp moved on) or that
//! wrote one record twice without a time column. Either way the repeated row is not a sample of
//! the unit; left in, each one holds the signal for a sample, which shapes the shortest taus of
//! the Allan variance like a moving average (a rev15 review: 2% stale rows were named
//! `moving_average {taps 3, stages 4, decimation 6}` on every clean channel, G 12 -> 0.9, and a
//! Q the unit does not have).
//!
//! A tie of one column is common where values are counted in coarse steps and rare where they
//! are near continuous, so the rule compares the share of rows tied in every column with the
//! share chance gives: for a column whose consecutive differences have standard deviation
//! `sigma` and whose values are written in steps of `res` (the smallest difference seen, printing
//! noise passed over: [`SmallestStep`]), a Gaussian difference falls within half
//! a step of 0 with probability about `res / (sigma sqrt(2 pi))`, at most 1; the columns'
//! chances multiply (independent noise). Once [`MIN_PAIRS`] pairs have been seen, the repeats
//! are the logger's when there are at least [`MIN_TIES`] of them at [`EXCESS`] times that chance
//! or more; from then on each tied row is dropped (not a sample, no gap: the rows around it
//! are a sample apart in the unit's sequence) and counted. Only a row that repeats a row not
//! itself a repeat counts and is dropped: a longer run of equal rows (every channel frozen, or
//! rows of 0 before the unit sent data) is a stretch for the stuck filter
//! ([`crate::gap::stuck`]), which takes it out as a gap. A share above [`MAX_SHARE`] is no
//! logger's stray repeat but a unit whose output rate is below the logging rate (every other
//! row repeats at half the rate): then nothing is dropped and the run says so, since dropping
//! would change the step.

use serde::{Deserialize, Serialize};

use crate::smallest_step::SmallestStep;

/// Pairs of rows seen before the repeats are judged.
pub const MIN_PAIRS: u64 = 2000;
/// Fewest tied rows, by then, for the repeats to be the logger's.
pub const MIN_TIES: u64 = 10;
/// How many times the chance share the ties must be.
pub const EXCESS: f64 = 50.0;
/// Largest share of tied rows dropped as a logger's repeats.
pub const MAX_SHARE: f64 = 0.05;

/// One column's account: its smallest difference and the sum of squared differences.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
struct ColumnTies {
    /// Flattened: a checkpoint keeps the fields `min_step` and `scale` it had before the step
    /// was shared with [`crate::gap::lsb`].
    #[serde(flatten)]
    step: SmallestStep,
    sum_d2: f64,
    n_d: u64,
}

impl ColumnTies {
    /// The chance that two consecutive values are equal.
    fn chance(&self) -> f64 {
        let Some(res) = self.step.get().filter(|_| self.n_d > 0) else {
            return 1.0;
        };
        let sigma = (self.sum_d2 / self.n_d as f64).sqrt();
        if sigma <= 0.0 {
            return 1.0;
        }
        (res / (sigma * (2.0 * std::f64::consts::PI).sqrt())).min(1.0)
    }
}

/// What was decided about the repeats.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub enum TieVerdict {
    /// Not judged yet, or the ties are chance.
    #[default]
    Chance,
    /// The logger's repeats: dropped.
    Logger,
    /// Too many to be a logger's strays: kept, said once.
    HeldOutput,
}

/// The account of tied rows over the values handed out.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RowTies {
    columns: Vec<ColumnTies>,
    last: Vec<f64>,
    pairs: u64,
    ties: u64,
    /// The last pair was tied.
    prev_tied: bool,
    /// Tied rows dropped.
    pub dropped: u64,
    pub verdict: TieVerdict,
    /// The chance share when the verdict was made.
    pub chance_share: f64,
}

impl RowTies {
    /// Whether the row `v` (the reader's columns) is a repeat to drop. Rows with a gap in any
    /// column, or whose counted columns (`counted`) are all gaps, are passed over.
    pub fn observe(&mut self, v: &[f64], counted: &[bool]) -> bool {
        if self.columns.len() != v.len() {
            self.columns = vec![ColumnTies::default(); v.len()];
            self.last.clear();
        }
        let usable = v.iter().all(|x| x.is_finite())
            && v.iter().zip(counted).any(|(x, &c)| c && x.is_finite());
        if !usable {
            self.last.clear();
            return false;
        }
        if self.last.len() != v.len() {
            self.last = v.to_vec();
            return false;
        }
        let tied = v
            .iter()
            .zip(&self.last)
            .all(|(a, b)| a.to_bits() == b.to_bits());
        self.pairs += 1;
        let run = std::mem::replace(&mut self.prev_tied, tied);
        if tied && !run {
            self.ties += 1;
            if self.verdict == TieVerdict::Logger {
                self.dropped += 1;
                return true;
            }
        } else if !tied {
            for ((c, &x), &p) in self.columns.iter_mut().zip(v).zip(&self.last) {
                let d = c.step.push(p, x);
                c.sum_d2 += d * d;
                c.n_d += 1;
            }
            self.last.copy_from_slice(v);
        }
        if self.pairs == MIN_PAIRS {
            self.judge();
        }
        false
    }

    fn judge(&mut self) {
        let chance: f64 = self.columns.iter().map(ColumnTies::chance).product();
        let share = self.ties as f64 / self.pairs as f64;
        self.chance_share = chance;
        if self.ties >= MIN_TIES && share >= EXCESS * chance {
            self.verdict = if share <= MAX_SHARE {
                TieVerdict::Logger
            } else {
                TieVerdict::HeldOutput
            };
        }
    }

    /// The share of tied rows among the pairs seen.
    pub fn share(&self) -> f64 {
        if self.pairs == 0 {
            0.0
        } else {
            self.ties as f64 / self.pairs as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    /// Three near-continuous columns (printed with 7 decimals) with 2% of rows repeating the
    /// row before: the verdict is the logger's and about 2% of the rows after the first
    /// `MIN_PAIRS` are dropped, every one a repeat. The same values counted in steps of their
    /// own noise (ties by chance in each column, about a third of pairs, of all three columns about 1.4%) are left alone, as
    /// are the continuous columns without repeats.
    #[test]
    fn a_loggers_repeats_are_dropped_and_a_counters_ties_are_not() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let noise = Normal::new(0.0, 1e-3).unwrap();
        let n = 50_000;
        let counted = [true, true, true];
        let round = |x: f64, step: f64| (x / step).round() * step;
        let (mut stale, mut coarse, mut clean) =
            (RowTies::default(), RowTies::default(), RowTies::default());
        let (mut dropped_ok, mut repeats, mut row) = (0u64, 0u64, [0.0; 3]);
        for _ in 0..n {
            let fresh: [f64; 3] =
                std::array::from_fn(|c| 9.8 * (c as f64) + noise.sample(&mut rng));
            let repeat = rand::RngExt::random::<f64>(&mut rng) < 0.02;
            if !repeat {
                row = fresh.map(|x| round(x, 1e-7));
            } else {
                repeats += 1;
            }
            if stale.observe(&row, &counted) {
                dropped_ok += u64::from(repeat);
            }
            coarse.observe(&fresh.map(|x| round(x, 1e-3)), &counted);
            clean.observe(&fresh.map(|x| round(x, 1e-7)), &counted);
        }
        assert_eq!(stale.verdict, TieVerdict::Logger);
        assert_eq!(stale.dropped, dropped_ok, "only repeats are dropped");
        let after = repeats as f64 * (n - MIN_PAIRS) as f64 / n as f64;
        assert!(
            (stale.dropped as f64 - after).abs() < 4.0 * after.sqrt(),
            "{} of about {after}",
            stale.dropped
        );
        assert_eq!(coarse.verdict, TieVerdict::Chance, "{}", coarse.share());
        assert_eq!(coarse.dropped, 0);
        assert!(
            coarse.share() > 0.01,
            "the counter ties by chance: {}",
            coarse.share()
        );
        assert_eq!(clean.verdict, TieVerdict::Chance);
        assert_eq!(clean.dropped, 0);
    }

    /// A unit whose output holds each sample for two rows: half the rows tie; nothing is
    /// dropped and the verdict says so.
    #[test]
    fn a_held_output_is_said_not_dropped() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(4);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let mut t = RowTies::default();
        let mut x = 0.0;
        for i in 0..10_000 {
            if i % 2 == 0 {
                x = noise.sample(&mut rng);
            }
            assert!(!t.observe(&[x], &[true]));
        }
        assert_eq!(t.verdict, TieVerdict::HeldOutput);
        assert!((t.share() - 0.5).abs() < 0.01, "{}", t.share());
    }

    /// A checkpoint taken part way (CBOR, as the pipeline writes it) resumes to the same
    /// verdict and the same rows dropped as one reading, and keeps each column's fields under
    /// the names a checkpoint of session 52 wrote (`min_step`, `scale`).
    #[test]
    fn a_checkpoint_resumes_the_same_account() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        let noise = Normal::new(0.0, 1e-3).unwrap();
        let counted = [true, true];
        let mut row = [0.0; 2];
        let rows: Vec<[f64; 2]> = (0..6000)
            .map(|_| {
                if rand::RngExt::random::<f64>(&mut rng) >= 0.03 {
                    row = std::array::from_fn(|c| {
                        ((c as f64 + noise.sample(&mut rng)) * 1e7).round() / 1e7
                    });
                }
                row
            })
            .collect();
        let mut whole = RowTies::default();
        let mut part = RowTies::default();
        let mut dropped_whole = Vec::new();
        let mut dropped_resumed = Vec::new();
        for (i, r) in rows.iter().enumerate() {
            dropped_whole.push(whole.observe(r, &counted));
            if i == 1500 {
                let mut bytes = Vec::new();
                ciborium::into_writer(&part, &mut bytes).unwrap();
                let value: ciborium::Value = ciborium::from_reader(&bytes[..]).unwrap();
                let text = format!("{value:?}");
                assert!(
                    text.contains("min_step") && text.contains("scale"),
                    "{text}"
                );
                part = ciborium::from_reader(&bytes[..]).unwrap();
            }
            dropped_resumed.push(part.observe(r, &counted));
        }
        assert_eq!(whole.verdict, TieVerdict::Logger);
        assert!(whole.dropped > 100, "{}", whole.dropped);
        assert_eq!(dropped_whole, dropped_resumed);
        assert_eq!(whole, part);
    }
}
