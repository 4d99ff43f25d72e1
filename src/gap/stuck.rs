//! Stuck stretches: runs of one value repeated far longer than the channel's noise allows (an
//! axis that froze, a saturated input, a driver that re-sent its last sample), taken out of the
//! diagnosis's evidence as gaps, counted and reported (docs/gap.md, "Stuck stretches").
//!
//! A frozen stretch adds nothing to the Allan variance of its own differences and a step at
//! each end, so left in it lowers the curve where it covers most of a cluster and can pose as
//! bias jumps; the stretch was not measured, so it is a gap.
//!
//! # Rule
//!
//! Runs of bit-identical increments are held (their value and length only: O(1) memory) until
//! a different value, a gap or a snapshot ends them. With `p` the share of equal consecutive
//! increments in what the filter has passed on (`(equal + 1) / (pairs + 2)`; since session 52
//! the larger of that and the same over about the last [`RECENT_PAIRS`] pairs), a run of `L`
//! equal values holds `L - 1` equal pairs, which under independent samples has probability
//! `p^(L-1)` at a given start. The run is stuck when it is at least [`MIN_STUCK`] long and
//! `n p^(L-1) <` [`STUCK_P`] with `n` the pairs seen (a Bonferroni bound over the starts), and
//! only on a channel where equal neighbours are rare, `p <` [`MAX_EQUAL_SHARE`]: a counter whose
//! step is near its noise repeats values by nature, in runs whose lengths its carry pattern and
//! the wander of its rate set, not a geometric law, so such a channel is never judged (a
//! counter's neighbours are equal with probability about `0.4 / sigma_e` for a difference of
//! `sigma_e` steps rms, so 5% takes at least 8 steps of noise, where the values are near
//! continuous). Nor is a
//! run before [`MIN_PAIRS`] pairs have been passed on, when `p` is not known yet, with one
//! exception: the channel's first run (a recording that begins before the unit sends data, its
//! rows 0 until then). When it is [`MIN_STUCK`] or longer it is held, with what follows it
//! (at most [`MIN_PAIRS`] + 1 runs, bounded memory), until the pairs after it give `p`, and
//! judged by the same rule; a gap or a snapshot before that judges it with what there is. A
//! channel constant throughout is said by [`super::lsb::LsbEstimator::constant`].

/// Shortest run judged (samples).
pub const MIN_STUCK: u64 = 16;
/// Bound on the chance of any run this long among the run's pairs under independent samples.
pub const STUCK_P: f64 = 1e-9;
/// Share of equal neighbours at or above which a channel's runs are not judged.
pub const MAX_EQUAL_SHARE: f64 = 0.05;
/// Pairs passed on before any run is judged.
pub const MIN_PAIRS: u64 = 1000;
/// The pairs over which the recent share of equal neighbours is read (exponential forgetting).
/// A rev15 review's accelerometer switched range 40% into its run (its LSB from 5.98e-4 to
/// 1.2e-2 m/s^2, the noise 0.59 of the new step): with the share of the whole run so far, a run
/// of 16 equal samples after the switch, which that step gives by chance, was taken out as
/// stuck. The recent share follows a switch within a few hundred pairs; a run right after it
/// can still be taken.
pub const RECENT_PAIRS: f64 = 4096.0;

/// What was found (durations in samples).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct StuckCount {
    /// Stuck stretches taken out as gaps.
    pub stretches: u64,
    /// Samples in them.
    pub samples: u64,
    /// The longest, in samples.
    pub longest: u64,
    /// Where the first one began, in samples from the start (gaps included).
    pub first_at: u64,
}

impl StuckCount {
    /// The same in seconds, `None` when there is no stretch.
    pub fn span(&self, tau0_s: f64) -> Option<StuckSpan> {
        (self.stretches > 0).then_some(StuckSpan {
            stretches: self.stretches,
            seconds: self.samples as f64 * tau0_s,
            longest_s: self.longest as f64 * tau0_s,
            first_at_s: self.first_at as f64 * tau0_s,
        })
    }
}

/// The diagnosis record's `stuck` object: how many stretches, their total and longest duration
/// (s), and where the first began (s from the start of the run, gaps included).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct StuckSpan {
    pub stretches: u64,
    pub seconds: f64,
    pub longest_s: f64,
    pub first_at_s: f64,
}

/// What the filter passes on.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Release {
    /// `n` increments of this value.
    Values(f64, u64),
    /// `n` increments taken out as a stuck stretch.
    Stuck(u64),
}

impl Release {
    /// Its increments.
    pub fn samples(&self) -> u64 {
        match *self {
            Release::Values(_, n) | Release::Stuck(n) => n,
        }
    }
}

/// The streaming stuck-stretch filter of one channel (module doc).
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct StuckFilter {
    /// The run being held: its value and length.
    value: Option<f64>,
    len: u64,
    /// The held run continues one already judged stuck (its start was taken out at a
    /// snapshot): it is stuck whatever its length.
    continues_stuck: bool,
    /// Consecutive pairs passed on, and how many were equal.
    pairs: u64,
    equal: u64,
    /// The same over about the last [`RECENT_PAIRS`] pairs (exponentially forgotten).
    #[serde(default)]
    recent_pairs: f64,
    #[serde(default)]
    recent_equal: f64,
    /// Samples of the held run's value already passed on, and taken out, at earlier
    /// snapshots (the run is judged on its whole length).
    passed: u64,
    taken: u64,
    /// The last run was passed on, with no gap since.
    last_passed: bool,
    /// Samples accounted for (passed on, taken out, or lost in gaps), for `first_at`.
    position: u64,
    /// The channel's first run, held until the pairs after it can judge it (module doc).
    #[serde(default)]
    lead: Option<Lead>,
    /// Releases waiting to be taken, in order ([`StuckFilter::queued`]): what followed the
    /// first run, once it is judged.
    #[serde(default)]
    queue: std::collections::VecDeque<Release>,
    pub found: StuckCount,
}

/// A first run held for judgement: its value and length, and what the filter released after
/// it, in order.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
struct Lead {
    value: f64,
    len: u64,
    after: Vec<Release>,
}

impl StuckFilter {
    pub fn new() -> Self {
        Self::default()
    }

    /// One increment `d` (u); returns what the run it ends releases. Whenever this, [`Self::gap`]
    /// or [`Self::flush`] returns something, more may wait in [`Self::queued`], to be taken
    /// after it and before anything else.
    #[inline]
    pub fn push(&mut self, d: f64) -> Option<Release> {
        let mut out = None;
        match self.value {
            Some(v) if v.to_bits() == d.to_bits() => {
                // The equal pair joining a run passed on at a snapshot to its continuation.
                if self.len == 0 && self.last_passed {
                    self.count(1, 1);
                }
                self.len += 1;
            }
            Some(_) => {
                out = self.end_run();
                // The pair joining the new run to the one passed on before it (unequal).
                if self.last_passed {
                    self.count(1, 0);
                }
                self.value = Some(d);
                self.len = 1;
            }
            None => {
                self.value = Some(d);
                self.len = 1;
            }
        }
        out
    }

    /// A gap of `missing` increments: the held run ends (it is judged), and the pairs start
    /// again after the gap.
    pub fn gap(&mut self, missing: u64) -> Option<Release> {
        let out = self.end_run();
        let out = self.settle_lead(out);
        self.value = None;
        self.last_passed = false;
        self.position += missing;
        out
    }

    /// The next release waiting after one [`Self::push`], [`Self::gap`] or [`Self::flush`]
    /// returned.
    #[inline]
    pub fn queued(&mut self) -> Option<Release> {
        self.queue.pop_front()
    }

    /// Judges a first run still held (before a gap or a snapshot) with the pairs there are.
    fn settle_lead(&mut self, out: Option<Release>) -> Option<Release> {
        match (out, self.lead.is_some()) {
            (None, true) => self.judge_lead(),
            (out, _) => out,
        }
    }

    /// Judges the held first run by the rule of [`Self::is_stuck`] with `p` from the pairs after
    /// it; returns its release and queues what followed it.
    fn judge_lead(&mut self) -> Option<Release> {
        let lead = self.lead.take()?;
        let len = lead.len;
        let p = self.equal_share();
        let n = (self.pairs + len) as f64;
        let stuck = self.pairs >= MIN_PAIRS
            && p < MAX_EQUAL_SHARE
            && n.ln() + (len - 1) as f64 * p.ln() < STUCK_P.ln();
        let out = if stuck {
            self.found.first_at = 0;
            self.found.stretches += 1;
            self.found.samples += len;
            self.found.longest = self.found.longest.max(len);
            Release::Stuck(len)
        } else {
            // Its pairs, and the unequal one joining it to what followed, if anything did.
            self.count(len - 1 + u64::from(!lead.after.is_empty()), len - 1);
            Release::Values(lead.value, len)
        };
        self.queue.extend(lead.after);
        Some(out)
    }

    /// Releases the held run at a snapshot: judged as it stands; a stuck one stays stuck as it
    /// goes on (its value is kept, so the pairs' count sees no break).
    pub fn flush(&mut self) -> Option<Release> {
        if self.len == 0 {
            return self.settle_lead(None);
        }
        let stuck = self.is_stuck();
        let out = self.release(stuck);
        self.continues_stuck = stuck;
        self.settle_lead(out)
    }

    /// Checks a filter read back from a checkpoint: the held run at most 2^32 samples (50 days
    /// at 1 kHz; it is released sample by sample) and no more equal pairs than pairs.
    pub fn check_restored(&self) -> Result<(), String> {
        let held = self.lead.as_ref().map_or(0, |l| l.after.len()) + self.queue.len();
        if held > 2 * MIN_PAIRS as usize + 2 {
            return Err(format!("stuck-stretch filter holds {held} runs"));
        }
        // Every run held is 1 to 2^32 samples long (a 0 would underflow, a huge one stall).
        let lens = self
            .lead
            .iter()
            .flat_map(|l| std::iter::once(l.len).chain(l.after.iter().map(Release::samples)));
        if let Some(n) = lens
            .chain(self.queue.iter().map(Release::samples))
            .find(|&n| n == 0 || n > 1 << 32)
        {
            return Err(format!("stuck-stretch filter holds a run of {n} samples"));
        }
        if self.len + self.passed > 1 << 32 || self.equal > self.pairs {
            return Err(format!(
                "stuck-stretch filter out of range (a run of {} held, {} of {} pairs equal)",
                self.len + self.passed,
                self.equal,
                self.pairs
            ));
        }
        Ok(())
    }

    /// `pairs` more pairs passed on, `equal` of them equal.
    fn count(&mut self, pairs: u64, equal: u64) {
        self.pairs += pairs;
        self.equal += equal;
        let keep = (1.0 - 1.0 / RECENT_PAIRS).powf(pairs as f64);
        self.recent_pairs = self.recent_pairs * keep + pairs as f64;
        self.recent_equal = self.recent_equal * keep + equal as f64;
    }

    /// The share of equal neighbours, `(equal + 1) / (pairs + 2)`: the larger of the share so
    /// far and the share over about the last [`RECENT_PAIRS`] pairs, so that a channel whose
    /// step grew coarse (a range switch) is judged by its ties there, not by those of its finer
    /// start.
    pub fn equal_share(&self) -> f64 {
        let all = (self.equal + 1) as f64 / (self.pairs + 2) as f64;
        let recent = (self.recent_equal + 1.0) / (self.recent_pairs + 2.0);
        all.max(recent)
    }

    fn is_stuck(&self) -> bool {
        if self.continues_stuck {
            return true;
        }
        let p = self.equal_share();
        let len = self.len + self.passed;
        if len < MIN_STUCK || self.pairs < MIN_PAIRS || p >= MAX_EQUAL_SHARE {
            return false;
        }
        let n = (self.pairs + len) as f64;
        // n p^(L-1) < STUCK_P, in logarithms.
        n.ln() + (len - 1) as f64 * p.ln() < STUCK_P.ln()
    }

    fn end_run(&mut self) -> Option<Release> {
        let mut out = None;
        if self.len > 0 {
            let stuck = self.is_stuck();
            if !stuck && self.position == 0 && self.passed == 0 && self.len >= MIN_STUCK {
                // The channel's first run, too early to judge: held (module doc).
                self.lead = self.value.map(|value| Lead {
                    value,
                    len: self.len,
                    after: Vec::new(),
                });
                self.position += self.len;
                self.len = 0;
                self.last_passed = false;
            } else {
                out = self.release(stuck);
            }
        }
        self.continues_stuck = false;
        self.passed = 0;
        self.taken = 0;
        out
    }

    fn release(&mut self, stuck: bool) -> Option<Release> {
        let n = self.len;
        let mut out = None;
        if stuck {
            if !self.continues_stuck {
                if self.found.stretches == 0 {
                    self.found.first_at = self.position;
                }
                self.found.stretches += 1;
            }
            self.found.samples += n;
            self.taken += n;
            self.found.longest = self.found.longest.max(self.taken);
            out = Some(Release::Stuck(n));
        } else if let Some(v) = self.value {
            self.count(n - 1, n - 1);
            self.passed += n;
            out = Some(Release::Values(v, n));
        }
        self.last_passed = !stuck;
        self.position += n;
        self.len = 0;
        match (&mut self.lead, out) {
            (Some(lead), Some(r)) => {
                // After a held first run: kept in order until the run is judged.
                lead.after.push(r);
                if self.pairs >= MIN_PAIRS {
                    self.judge_lead()
                } else {
                    None
                }
            }
            (_, out) => out,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    fn run(x: &[f64], snapshot_every: Option<usize>) -> (Vec<Option<f64>>, StuckCount) {
        let mut f = StuckFilter::new();
        let mut out = Vec::new();
        let mut sink = |r: Release| match r {
            Release::Values(v, n) => out.extend(std::iter::repeat_n(Some(v), n as usize)),
            Release::Stuck(n) => out.extend(std::iter::repeat_n(None, n as usize)),
        };
        let mut take = |f: &mut StuckFilter, r: Option<Release>| {
            if let Some(r) = r {
                sink(r);
                while let Some(q) = f.queued() {
                    sink(q);
                }
            }
        };
        for (i, &v) in x.iter().enumerate() {
            let r = f.push(v);
            take(&mut f, r);
            if snapshot_every.is_some_and(|k| i % k == k - 1) {
                let r = f.flush();
                take(&mut f, r);
            }
        }
        let r = f.flush();
        take(&mut f, r);
        (out, f.found)
    }

    /// `n` samples of white noise (sd 1) written to six decimals, as a logger would.
    fn six_decimals(seed: u64, n: usize) -> Vec<f64> {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        (0..n)
            .map(|_| {
                let z: f64 = StandardNormal.sample(&mut rng);
                (z * 1e6).round() / 1e6
            })
            .collect()
    }

    /// A channel whose step grows coarse 40% into its run (a range switch: white noise at six
    /// decimals, then the same noise on a step 3 times its sd, where runs of 16 equal samples
    /// come by chance): nothing after the switch is taken out, where the share of ties over the
    /// whole run so far took six such runs for stuck; 40 samples frozen before the switch still
    /// are. (The recent share takes a few hundred pairs to follow the switch: on a step 2.5 times
    /// the sd one run of 16 right after it is still taken, against 23.)
    #[test]
    fn a_step_grown_coarse_is_judged_by_its_own_ties() {
        let n = 400_000;
        let mut x = six_decimals(21, n);
        let switch = 160_000;
        for v in &mut x[switch..] {
            *v = ((*v + 8.0) / 3.0).round() * 3.0;
        }
        for v in &mut x[50_000..50_040] {
            *v = 0.0;
        }
        let longest_tie = x[switch..]
            .chunk_by(|a, b| a == b)
            .map(|c| c.len())
            .max()
            .unwrap();
        assert!(longest_tie >= 16, "ties by chance: {longest_tie}");
        let (out, found) = run(&x, None);
        assert_eq!((found.stretches, found.samples), (1, 40), "{found:?}");
        assert!(out[switch..].iter().all(Option::is_some));
    }

    /// White noise at six decimals with 3000 samples frozen at 0.37 from sample 10000 and 40
    /// at 0 from 30000: both taken out, every other sample passed on unchanged, with or without
    /// snapshots every 777 samples; the same noise without them loses nothing.
    #[test]
    fn frozen_stretches_are_taken_out_and_nothing_else() {
        let clean = six_decimals(5, 40_000);
        let mut x = clean.clone();
        x[10_000..13_000].iter_mut().for_each(|v| *v = 0.37);
        x[30_000..30_040].iter_mut().for_each(|v| *v = 0.0);
        for snap in [None, Some(777)] {
            let (out, found) = run(&x, snap);
            assert_eq!(out.len(), x.len());
            assert_eq!(found.stretches, 2, "{found:?}");
            assert_eq!(found.samples, 3040);
            assert_eq!(found.longest, 3000);
            assert_eq!(found.first_at, 10_000);
            for (i, o) in out.iter().enumerate() {
                let frozen = (10_000..13_000).contains(&i) || (30_000..30_040).contains(&i);
                assert_eq!(o.is_none(), frozen, "sample {i}");
                if let Some(v) = o {
                    assert_eq!(*v, x[i]);
                }
            }
        }
        let (out, found) = run(&clean, Some(777));
        assert_eq!(found, StuckCount::default());
        assert_eq!(out.iter().flatten().count(), clean.len());
    }

    /// A recording that begins before the unit sends data: 300 samples of 0, then white noise.
    /// The first run is held until the pairs after it judge it, and taken out (`first_at` 0);
    /// everything after it is passed on unchanged and in order, with snapshots every 5000
    /// samples or none. A counter's first run of 300 is kept, and so is a first run followed by
    /// fewer than MIN_PAIRS pairs before the end.
    #[test]
    fn a_first_run_is_judged_by_what_follows_it() {
        let mut x = six_decimals(8, 20_000);
        x[..300].iter_mut().for_each(|v| *v = 0.0);
        for snap in [None, Some(5000)] {
            let (out, found) = run(&x, snap);
            assert_eq!(out.len(), x.len());
            assert_eq!(
                (found.stretches, found.samples, found.first_at),
                (1, 300, 0),
                "{found:?}"
            );
            assert!(out[..300].iter().all(Option::is_none));
            assert!(out[300..]
                .iter()
                .zip(&x[300..])
                .all(|(o, v)| *o == Some(*v)));
        }
        let (out, found) = run(&x[..800], None);
        assert_eq!(found.stretches, 0);
        assert_eq!(out.iter().flatten().count(), 800);
        let mut counter: Vec<f64> = (0..20_000)
            .map(|i| if i % 7 == 0 { 3.0 } else { 2.0 })
            .collect();
        counter[..300].iter_mut().for_each(|v| *v = 2.0);
        let (out, found) = run(&counter, None);
        assert_eq!(found.stretches, 0, "{found:?}");
        assert_eq!(out.iter().flatten().count(), counter.len());
    }

    /// A counter whose values are mostly one count (equal neighbours the rule) keeps its runs,
    /// even one of 5000.
    #[test]
    fn a_counter_keeps_its_runs() {
        let mut x: Vec<f64> = (0..50_000)
            .map(|i| if i % 7 == 0 { 3.0 } else { 2.0 })
            .collect();
        x[20_000..25_000].iter_mut().for_each(|v| *v = 2.0);
        let (out, found) = run(&x, None);
        assert_eq!(found.stretches, 0, "{found:?}");
        assert_eq!(out.iter().flatten().count(), x.len());
    }
}
