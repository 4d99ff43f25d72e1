//! The sampling grid under a jittered clock's stamps.
//!
//! A host that stamps each sample as it receives it (a ROS driver, a logger on a USB port) puts
//! the stamp of sample `i` at `t_i = t_0 + i tau0 + e_i`, the jitter `e_i` fresh each time. The
//! step between two rows is then `tau0 + e_i - e_{i-1}`: jitter of +-30% of `tau0` gives steps of
//! 0.4 to 1.6 `tau0`, and a step read alone calls each one past 1.5 a missing sample. A blind
//! review's 100 Hz file with +-28.5% jitter had 5641 missing samples counted for its 34 real
//! ones, and every gap statistic of the run was deflated (docs/robustness.md).
//!
//! Measured against the grid the stamps lie on, a row is `k tau0 + e_i` on from the last sample,
//! the jitter counted once: a missing sample is told while the jitter stays under half a step.
//! The grid is followed by an alpha-beta tracker (the steady state of a Kalman filter for a
//! position and a constant rate; e.g. Brookner, Tracking and Kalman Filtering Made Easy, ch. 1):
//! each row placed `k` steps on moves the grid to the predicted place plus [`FOLLOW`] of the
//! stamp's offset from it, and the step by [`RATE`] of that offset over `k`, so a clock whose step
//! is not quite the nominal one (a given `--tau0` a few parts in a thousand off, a crystal's
//! drift) is followed without a standing offset. The tracker is trusted only once it is
//! locked: [`LOCK_ROWS`] rows followed with the root mean square of the offsets under
//! [`LOCK_RMS`] steps; until then, and on a clock that steps by other than its nominal step
//! by more than the tracker follows, a reader measures each step alone as before.

/// The share of a stamp's offset from the grid that moves the grid (alpha).
pub const FOLLOW: f64 = 1.0 / 16.0;

/// The share of a stamp's offset, per step, that moves the grid's step (beta): `alpha^2 / 4`,
/// the critically damped alpha-beta tracker.
pub const RATE: f64 = FOLLOW * FOLLOW / 4.0;

/// Rows after which the growing memory of the place has become the fading one (`1 / (n + 1)`
/// is [`FOLLOW`] from `n = 15`).
const FADING_ROWS: u64 = 16;

/// The share of each row in the mean square of the offsets (a longer memory than the place's:
/// the spread of +-30% jitter over 16 rows scatters by a third, over 256 by 4%).
const SPREAD_MEMORY: f64 = 1.0 / 256.0;

/// Stamps whose phases on the step set a grid from a look at the start ([`sample_numbers`]).
const CIRCLE_ROWS: usize = 64;

/// How far the grid's step follows the clock from the nominal step (a share of it): a crystal's
/// drift and a step given a few parts in a thousand off, not a clock that changed its rate (a
/// file whose rows come twice as often from its middle on is read off the grid there, its rows
/// counted as not a whole number of steps, as before the grid).
pub const STEP_FOLLOWED: f64 = 0.01;

/// Rows followed before the grid is trusted.
pub const LOCK_ROWS: u64 = FADING_ROWS;

/// The root mean square of the stamps' offsets from the grid (steps) under which it is trusted:
/// uniform jitter of +-30% of a step has 0.17, of +-40% 0.23; stamps on no grid of the step
/// (offsets spread over the whole step) have 0.29.
pub const LOCK_RMS: f64 = 0.23;

/// The grid of a clock's samples, in the clock's own units.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct StampGrid {
    /// The grid's step (clock units).
    step: f64,
    /// The nominal step it started from (clock units): the step follows the clock within
    /// [`STEP_FOLLOWED`] of it.
    nominal: f64,
    /// Where the grid puts the last sample placed (clock units).
    at: Option<f64>,
    /// The mean square of the stamps' offsets from the grid (steps^2), over [`SPREAD_MEMORY`].
    offset2: f64,
    /// Rows placed since the grid was set.
    rows: u64,
}

impl StampGrid {
    /// A grid of nominal step `step` (clock units), not yet set to a stamp.
    pub fn new(step: f64) -> StampGrid {
        StampGrid {
            step,
            nominal: step,
            ..StampGrid::default()
        }
    }

    /// Sets the grid at a stamp `t` (the first row, a clock that restarted or went back): it
    /// follows again from there, not trusted until locked anew.
    pub fn set(&mut self, t: f64) {
        self.at = Some(t);
        self.offset2 = 0.0;
        self.rows = 0;
    }

    /// Whether the grid is trusted (see the module doc).
    pub fn locked(&self) -> bool {
        self.at.is_some() && self.rows >= LOCK_ROWS && self.spread() < LOCK_RMS
    }

    /// The steps from the last sample placed to a stamp `t`, measured on the grid: `None`
    /// while the grid is not trusted.
    pub fn steps_to(&self, t: f64) -> Option<f64> {
        let at = self.at?;
        (self.locked() && self.step > 0.0).then(|| (t - at) / self.step)
    }

    /// The row stamped `t` is the next sample: the grid places it on the nearest of its
    /// points past the last one placed (at least one step on) and follows it; the steps it
    /// moved on (a gap is more than one). The offset the grid follows is then never more than
    /// half a step, whatever a reader decided for the row. The first row sets the grid.
    pub fn place(&mut self, t: f64) -> u64 {
        let Some(at) = self.at else {
            self.set(t);
            return 0;
        };
        if !t.is_finite() || self.step.is_nan() || self.step <= 0.0 {
            return 0;
        }
        let k = ((t - at) / self.step).round().max(1.0);
        let predicted = at + k * self.step;
        let offset = t - predicted;
        // A growing memory of the place at the start (the mean of the offsets so far: a grid
        // set at one jittered stamp is off by that stamp's jitter), the nominal step kept;
        // from `FADING_ROWS` on, the fading memory of `FOLLOW` for the place and `RATE` for
        // the step.
        let growing = 1.0 / (self.rows as f64 + 2.0);
        let follow = growing.max(FOLLOW);
        self.at = Some(predicted + follow * offset);
        if self.rows >= FADING_ROWS {
            self.step = (self.step + RATE * offset / k).clamp(
                self.nominal * (1.0 - STEP_FOLLOWED),
                self.nominal * (1.0 + STEP_FOLLOWED),
            );
        }
        let steps = offset / self.step;
        self.offset2 += growing.max(SPREAD_MEMORY) * (steps * steps - self.offset2);
        self.rows += 1;
        k as u64
    }

    /// A sample with no stamp was taken `k` steps on: the grid moves on by them, unfollowed.
    pub fn skip(&mut self, k: u64) {
        if let Some(at) = self.at.as_mut() {
            *at += k as f64 * self.step;
        }
    }

    /// The root mean square of the stamps' offsets from the grid (steps), over
    /// [`SPREAD_MEMORY`]: the clock's jitter about its grid.
    pub fn spread(&self) -> f64 {
        self.offset2.sqrt()
    }

    /// The grid's step (clock units) as followed so far.
    pub fn step(&self) -> f64 {
        self.step
    }
}

/// Each stamp's sample number from the first (0), placed on a grid of nominal step `step` that
/// follows them ([`StampGrid`]); every row is at least one step on from the row before. `None`
/// where a stamp is not finite, or there is none.
pub fn sample_numbers(stamps: &[f64], step: f64) -> Option<Vec<u64>> {
    if stamps.iter().any(|t| !t.is_finite()) || step.is_nan() || step <= 0.0 {
        return None;
    }
    let &first = stamps.first()?;
    // The grid's place from the first stamps together, not the first alone: the circular mean
    // of their phases on the step (jitter under half a step averages out there, where the
    // offsets from one jittered stamp would wrap).
    let (s, c) = stamps
        .iter()
        .take(CIRCLE_ROWS)
        .map(|x| (2.0 * std::f64::consts::PI * (x - first) / step).sin_cos())
        .fold((0.0, 0.0), |(a, b), (x, y)| (a + x, b + y));
    let phase = s.atan2(c) / (2.0 * std::f64::consts::PI);
    let mut grid = StampGrid::new(step);
    grid.set(first + phase * step);
    // Place and step both known: the fading memory from the start.
    grid.rows = FADING_ROWS;
    let mut out = Vec::with_capacity(stamps.len());
    out.push(0);
    let mut n = 0u64;
    for &t in &stamps[1..] {
        n += grid.place(t);
        out.push(n);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic jitter in [-1/2, 1/2) (a Weyl sequence), no generator needed.
    fn weyl(i: u64) -> f64 {
        ((i as f64 * 0.618_033_988_75) % 1.0) - 0.5
    }

    /// Stamps at 100 Hz jittered by +-`j` steps, samples `drop` left out.
    fn stamps(n: u64, j: f64, drop: &[u64]) -> Vec<f64> {
        (0..n)
            .filter(|i| !drop.contains(i))
            .map(|i| 0.01 * (i as f64 + 2.0 * j * weyl(i)))
            .collect()
    }

    #[test]
    fn jitter_under_half_a_step_leaves_every_sample_number_right() {
        // +-45% of a step: neighbouring stamps differ by up to 0.9 step, so a step read alone
        // would call a missing sample where two neighbours part by more than 1.5 steps.
        let drop = [500, 1200, 1201, 3000];
        let t = stamps(4000, 0.45, &drop);
        let alone = t.windows(2).filter(|w| (w[1] - w[0]) / 0.01 > 1.5).count();
        assert!(alone > 100, "steps read alone: {alone} gaps");
        let got = sample_numbers(&t, 0.01).expect("finite");
        let want: Vec<u64> = (0..4000).filter(|i| !drop.contains(i)).collect();
        assert_eq!(got, want);
    }

    #[test]
    fn a_clock_off_its_nominal_step_is_followed() {
        // The nominal step 0.3% short of the clock's (a given --tau0 of 0.00997 s for a 100 Hz
        // clock), jitter +-30%: after 4000 rows (12 steps of drift read alone) every number is
        // right and the grid's step is the clock's to 1e-4.
        let t = stamps(4000, 0.3, &[]);
        let got = sample_numbers(&t, 0.00997).expect("finite");
        assert_eq!(got, (0..4000).collect::<Vec<u64>>());
        let mut g = StampGrid::new(0.00997);
        for (i, &s) in t.iter().enumerate() {
            if i == 0 {
                g.set(s);
            } else {
                g.place(s);
            }
        }
        assert!((g.step() / 0.01 - 1.0).abs() < 1e-4, "{}", g.step());
        assert!(g.locked());
    }

    /// A clock whose rate doubles halfway is not followed: the grid loses its lock there and
    /// stays off it (its step held within 1% of the nominal one).
    #[test]
    fn a_clock_that_changes_its_rate_is_not_followed() {
        let mut g = StampGrid::new(0.01);
        g.set(0.0);
        for i in 1..1000u64 {
            g.place(0.01 * i as f64);
        }
        assert!(g.locked());
        for i in 1..1000u64 {
            g.place(9.99 + 0.005 * i as f64);
        }
        assert!(!g.locked(), "step {}", g.step());
        assert!((g.step() / 0.01 - 1.0).abs() <= STEP_FOLLOWED + 1e-12);
    }

    #[test]
    fn the_grid_is_trusted_only_once_locked() {
        let mut g = StampGrid::new(0.01);
        g.set(0.0);
        assert_eq!(g.steps_to(0.01), None);
        for i in 1..LOCK_ROWS {
            g.place(0.01 * i as f64);
        }
        assert_eq!(g.steps_to(1.0), None, "{} rows", LOCK_ROWS - 1);
        g.place(0.01 * LOCK_ROWS as f64);
        let s = g.steps_to(0.01 * (LOCK_ROWS + 3) as f64).expect("locked");
        assert!((s - 3.0).abs() < 1e-9, "{s}");
        // Stamps on no grid of the step (their offsets spread over it) are never trusted.
        let mut w = StampGrid::new(0.01);
        w.set(0.0);
        for i in 1..500u64 {
            w.place(0.01 * (i as f64 + 0.37 * i as f64 * i as f64 % 1.0));
        }
        assert!(!w.locked());
    }
}
