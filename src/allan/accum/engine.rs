//! The engine of one channel ([`Engine`]): phase streams at each stride, the levels (cluster
//! sizes) that read them, and the per-block update of their sums.

#[allow(unused_imports)]
use super::*;

/// Points of one stream since the start of the segment, of which the first `base` were dropped.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(super) struct Buf<T> {
    pub(super) data: Vec<T>,
    /// Segment-relative stream index of `data[0]`.
    pub(super) base: u64,
    /// Index into `data` where this block's new points begin (for decimating children).
    pub(super) new_from: usize,
}

impl<T: Copy> Buf<T> {
    fn new() -> Self {
        Buf {
            data: Vec::new(),
            base: 0,
            new_from: 0,
        }
    }
    fn end(&self) -> u64 {
        self.base + self.data.len() as u64
    }
    fn clear(&mut self) {
        self.data.clear();
        self.base = 0;
        self.new_from = 0;
    }
    /// Drops points before segment index `keep_from`.
    fn trim(&mut self, keep_from: u64) {
        if keep_from > self.base {
            let n = ((keep_from - self.base) as usize).min(self.data.len());
            self.data.drain(..n);
            self.base += n as u64;
        }
        self.new_from = self.data.len();
    }
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
pub(super) struct Stream<R: Repr> {
    pub(super) stride: u64,
    /// Index of the stream this one decimates (itself for stride 1).
    pub(super) parent: usize,
    /// `stride / parent.stride`.
    pub(super) factor: u64,
    pub(super) x: Buf<R::X>,
    pub(super) c: Buf<R::C>,
    /// Whether any level reads the `C` points.
    pub(super) needs_c: bool,
}

/// Sum of squared differences of one statistic at one level.
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
pub(super) struct SqSum {
    pub(super) sum: CompensatedSum,
    pub(super) count: u64,
    /// Segment-relative stream index of the next difference to take.
    pub(super) next: u64,
}

impl SqSum {
    /// Adds the sum of `n` squared differences just taken.
    fn add(&mut self, n: usize, sum_sq: f64) {
        self.sum.add(sum_sq);
        self.count += n as u64;
        self.next += n as u64;
    }
}

/// Moments for the lag-1 autocorrelation of one differenced series (noise identification).
#[derive(Debug, Clone, Copy, Default, serde::Serialize, serde::Deserialize)]
pub(super) struct LagMoments {
    /// The first value seen, subtracted from every value so the moments do not cancel.
    pub(super) shift: Option<f64>,
    pub(super) n: u64,
    pub(super) sum: f64,
    pub(super) sum_sq: f64,
    pub(super) sum_lag: f64,
}

impl LagMoments {
    #[inline(always)]
    fn add(&mut self, a: f64, b: f64) {
        let s = *self.shift.get_or_insert(a);
        let (a, b) = (a - s, b - s);
        self.n += 1;
        self.sum += a + b;
        self.sum_sq += a * a + b * b;
        self.sum_lag += a * b;
    }

    /// Lag-1 autocorrelation of the series, its mean removed.
    fn r1(&self) -> Option<f64> {
        if self.n < 2 {
            return None;
        }
        let n = self.n as f64;
        let mean = self.sum / (2.0 * n);
        let var = self.sum_sq / (2.0 * n) - mean * mean;
        let cov = self.sum_lag / n - mean * mean;
        (var > 0.0).then(|| (cov / var).clamp(-1.0, 1.0))
    }
}

#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(super) struct Level {
    pub(super) m: u64,
    pub(super) stream: usize,
    /// Cluster size in stream points: `m / stride`.
    pub(super) mp: u64,
    pub(super) avar: SqSum,
    pub(super) hvar: SqSum,
    pub(super) mvar: SqSum,
    /// Next term of the noise-identification moments (a multiple of `mp`; span `4 mp`).
    pub(super) nid_next: u64,
    pub(super) lag: [LagMoments; 3],
}

/// What a level holds at the moment it is read.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelReading {
    /// Cluster size.
    pub m: u64,
    /// Samples between successive differences (1 = full overlap).
    pub stride: u64,
    /// Averaging time in seconds.
    pub tau_s: f64,
    /// `(variance in u^2/s^2, number of differences)` per statistic, `None` when no difference
    /// has been taken yet or the statistic is off.
    pub avar: Option<(f64, u64)>,
    pub hvar: Option<(f64, u64)>,
    pub mvar: Option<(f64, u64)>,
    /// Lag-1 autocorrelations (lag `m`) of the `m`-averaged rate and of its first and second
    /// differences, for noise identification.
    pub lag1: [Option<f64>; 3],
}

impl LevelReading {
    pub fn get(&self, stat: Stat) -> Option<(f64, u64)> {
        match stat {
            Stat::Avar => self.avar,
            Stat::Hvar => self.hvar,
            Stat::Mvar => self.mvar,
        }
    }
}

/// Smallest step between the starts of noise-identification block pairs: at m = 1 a 3-hour
/// 250 Hz run still gives 42 000 pairs (standard error of the lag-1 autocorrelation about 0.005,
/// against decision steps of 0.25 in Riley and Greenhall's delta), and a 5-minute run 1 200.
/// 64 rather than 16 took 11% off the stand benchmark (BENCHMARKS.md, "Allan engine").
pub(super) const NID_MIN_STEP: u64 = 64;

/// Points of stream 1 gathered before the levels are updated: large enough that the inner loops
/// run over long slices, small enough to stay in L1 cache with its history.
pub(super) const BLOCK: usize = 2048;

/// The streaming accumulator of one channel, generic over the number representation.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
pub struct Engine<R: Repr> {
    pub(super) cfg: AccumConfig,
    pub(super) streams: Vec<Stream<R>>,
    pub(super) levels: Vec<Level>,
    /// Is a phase segment open (false at the start and after a gap)?
    pub(super) open: bool,
    pub(super) x_cur: R::X,
    pub(super) c_cur: R::C,
    /// Phase points received in all segments.
    pub(super) n_points: u64,
    /// Increments accounted for, gaps included (for `t_data`).
    pub(super) n_steps: u64,
    /// Number of segments started.
    pub(super) segments: u64,
    /// The first increment, and the OR of [`Repr::deviation`] over the increments since, so that
    /// `spread + 1 >= |d - first|` for each of them: MVAR's inner sum at
    /// cluster m is at most `2 m^2 (spread + 1)` in magnitude (each of its m second differences is a
    /// difference of two sums of m increments, and a constant offset cancels), which decides
    /// when its third difference of the running sum fits in 64 bits. `spread` is 0 exactly when
    /// every increment so far equals the first ([`Engine::constant_increment`]).
    pub(super) first_inc: Option<R::Inc>,
    pub(super) spread: u64,
    /// `spread` is 0 only while every increment equals the first (false for a state saved
    /// before session 30, whose `spread` did not say that: such a run never reads constant).
    #[serde(default)]
    pub(super) spread_exact: bool,
    /// Scratch for the moving sums of phase at m = 2, 4, 8, ... (integer input); rebuilt at
    /// every block, so a saved state leaves it out.
    #[serde(skip)]
    pub(super) pyramid: Vec<Vec<i64>>,
    /// Scratch for one level's second differences (integer input).
    #[serde(skip)]
    pub(super) scratch: Vec<f64>,
}

impl<R: Repr> Engine<R> {
    pub fn new(cfg: AccumConfig) -> Engine<R> {
        let ms = cfg.taus.cluster_sizes();
        let mut strides: Vec<u64> = vec![1];
        let mut level_strides = Vec::with_capacity(ms.len());
        for &m in &ms {
            let s = match cfg.overlap {
                Overlap::Full => 1,
                Overlap::Bounded(l) => largest_divisor_at_most(m, (m / l.max(1)).max(1)),
            };
            level_strides.push(s);
            if !strides.contains(&s) {
                strides.push(s);
            }
        }
        strides.sort_unstable();
        let mut streams: Vec<Stream<R>> = Vec::with_capacity(strides.len());
        for (i, &s) in strides.iter().enumerate() {
            // Parent: the largest smaller stride that divides this one.
            let parent = (0..i).rev().find(|&j| s % strides[j] == 0).unwrap_or(0);
            streams.push(Stream {
                stride: s,
                parent,
                factor: if i == 0 { 1 } else { s / strides[parent] },
                x: Buf::new(),
                c: Buf::new(),
                needs_c: false,
            });
        }
        let levels: Vec<Level> = ms
            .iter()
            .zip(&level_strides)
            .map(|(&m, &s)| {
                let stream = strides.iter().position(|&t| t == s).unwrap_or(0);
                Level {
                    m,
                    stream,
                    mp: m / s,
                    avar: SqSum::default(),
                    hvar: SqSum::default(),
                    mvar: SqSum::default(),
                    nid_next: 0,
                    lag: [LagMoments::default(); 3],
                }
            })
            .collect();
        if cfg.stats.mvar {
            // A stream carries C points if it, or any stream decimated from it, feeds an MVAR level.
            for lv in &levels {
                let mut s = lv.stream;
                loop {
                    streams[s].needs_c = true;
                    if s == 0 {
                        break;
                    }
                    s = streams[s].parent;
                }
            }
        }
        Engine {
            cfg,
            streams,
            levels,
            open: false,
            x_cur: R::zero_x(),
            c_cur: R::C::default(),
            n_points: 0,
            n_steps: 0,
            segments: 0,
            first_inc: None,
            spread: 0,
            spread_exact: true,
            pyramid: Vec::new(),
            scratch: Vec::new(),
        }
    }

    pub fn config(&self) -> &AccumConfig {
        &self.cfg
    }

    /// Phase points received so far, all segments together.
    pub fn phase_points(&self) -> u64 {
        self.n_points
    }

    /// Steps of data accounted for (increments and lost ones), gaps included.
    pub fn steps(&self) -> u64 {
        self.n_steps
    }

    /// Seconds of data accounted for, gaps included.
    pub fn t_data_s(&self) -> f64 {
        self.n_steps as f64 * self.cfg.tau0_s
    }

    /// Number of contiguous segments so far.
    pub fn segments(&self) -> u64 {
        self.segments
    }

    /// The increment every increment so far has been, when they are all the same (a channel
    /// that does not move: stuck, saturated, or a constant such as an unused field); `None`
    /// before the first or once one differs. Phase points fed directly are not looked at.
    pub fn constant_increment(&self) -> Option<R::Inc> {
        self.first_inc
            .filter(|_| self.spread == 0 && self.spread_exact)
    }

    /// Feeds one increment `d_k` (docs/theory.md section 1).
    #[inline]
    pub fn push_increment(&mut self, d: R::Inc) {
        if !self.open {
            self.start_segment(R::zero_x());
        }
        match self.first_inc {
            Some(r) => self.spread |= R::deviation(d, r),
            None => self.first_inc = Some(d),
        }
        let x = R::step(self.x_cur, d);
        self.append_point(x);
        self.n_steps += 1;
    }

    /// Feeds a run of increments, as [`Engine::push_increment`] on each in turn (the same
    /// result), with the per-sample bookkeeping done a block at a time.
    pub fn push_increments(&mut self, ds: &[R::Inc]) {
        self.push_increments_from(ds);
    }

    /// [`Engine::push_increments`] from a narrower type each increment widens from exactly
    /// (e.g. `i32` counts of a narrow block column into the `i64` counts engine), widened as
    /// they are summed: the same result as widening them first.
    pub fn push_increments_from<T: Copy + Into<R::Inc>>(&mut self, ds: &[T]) {
        let mut rest = ds;
        while let Some((&d0, tail)) = rest.split_first() {
            if !self.open || self.first_inc.is_none() {
                self.push_increment(d0.into());
                rest = tail;
                continue;
            }
            let s0 = &mut self.streams[0];
            let room = BLOCK.saturating_sub(s0.x.data.len() - s0.x.new_from).max(1);
            let (chunk, tail) = rest.split_at(room.min(rest.len()));
            if let Some(r) = self.first_inc {
                self.spread |= chunk
                    .iter()
                    .fold(0, |acc, &d| acc | R::deviation(d.into(), r));
            }
            let from = s0.x.data.len();
            let mut x = self.x_cur;
            s0.x.data.extend(chunk.iter().map(|&d| {
                x = R::step(x, d.into());
                x
            }));
            self.x_cur = x;
            if s0.needs_c {
                let mut c = self.c_cur;
                s0.c.data.extend(s0.x.data[from..].iter().map(|&x| {
                    c = R::accumulate(c, x);
                    c
                }));
                self.c_cur = c;
            }
            self.n_points += chunk.len() as u64;
            self.n_steps += chunk.len() as u64;
            if s0.x.data.len() - s0.x.new_from >= BLOCK {
                self.process();
            }
            rest = tail;
        }
    }

    /// Feeds `missing` lost increments: the segment ends here.
    pub fn push_gap(&mut self, missing: u64) {
        if missing == 0 {
            return;
        }
        self.close_segment();
        self.n_steps += missing;
    }

    /// Ends the current phase segment without accounting for time (a phase point was missing).
    pub fn break_segment(&mut self) {
        self.close_segment();
    }

    /// Feeds one phase point directly (phase input).
    pub fn push_phase(&mut self, x: R::X) {
        if !self.open {
            self.start_segment(x);
        } else {
            self.append_point(x);
            self.n_steps += 1;
        }
    }

    fn start_segment(&mut self, x0: R::X) {
        for s in &mut self.streams {
            s.x.clear();
            s.c.clear();
        }
        for lv in &mut self.levels {
            lv.avar.next = 0;
            lv.hvar.next = 0;
            lv.mvar.next = 0;
            lv.nid_next = 0;
        }
        self.open = true;
        self.segments += 1;
        self.x_cur = x0;
        self.c_cur = R::C::default();
        // C_0 = 0 and C_1 = x_0: the running sum is one point ahead of the phase, so that with
        // P phase points the C stream holds C_0..C_P and MVAR has P - 3m + 1 terms.
        let s0 = &mut self.streams[0];
        s0.x.data.push(x0);
        if s0.needs_c {
            s0.c.data.push(self.c_cur);
            self.c_cur = R::accumulate(self.c_cur, x0);
            s0.c.data.push(self.c_cur);
        }
        self.n_points += 1;
    }

    #[inline(always)]
    fn append_point(&mut self, x: R::X) {
        let s0 = &mut self.streams[0];
        if s0.needs_c {
            self.c_cur = R::accumulate(self.c_cur, x);
            s0.c.data.push(self.c_cur);
        }
        s0.x.data.push(x);
        self.x_cur = x;
        self.n_points += 1;
        if s0.x.data.len() - s0.x.new_from >= BLOCK {
            self.process();
        }
    }

    fn close_segment(&mut self) {
        if self.open {
            self.process();
            self.open = false;
        }
    }

    /// Decimates the new points down the streams, updates every level, trims the streams.
    fn process(&mut self) {
        // Decimation, parents before children (streams are sorted by stride).
        for i in 1..self.streams.len() {
            let (head, tail) = self.streams.split_at_mut(i);
            let child = &mut tail[0];
            let parent = &head[child.parent];
            decimate(&parent.x, &mut child.x, child.factor);
            if child.needs_c {
                decimate(&parent.c, &mut child.c, child.factor);
            }
        }
        let stats = self.cfg.stats;
        let nid = self.cfg.noise_id;
        let spread = self.spread;
        // Bounds from the spread (see `spread`), with s = spread + 1: |second difference| <= 2 m s,
        // |third difference| <= 4 m s, |MVAR inner sum| <= 2 m^2 s.
        let bounds: Vec<Narrow> = self
            .levels
            .iter()
            .map(|lv| {
                let m = lv.m as u128;
                let s = spread as u128 + 1;
                Narrow {
                    d2: (2 * m).saturating_mul(s) < (1 << 51),
                    d3: (4 * m).saturating_mul(s) < (1 << 51),
                    c3: m.saturating_mul(m).saturating_mul(2 * s) < (1 << 51),
                }
            })
            .collect();
        // MVAR of stream 0's levels at m = 2^k (integer phase, narrow bound) from the moving
        // sums of phase, built by doubling: A_2m(j) = A_m(j) + A_m(j + m), A_1 = x.
        let uses_sums =
            |lv: &Level, b: &Narrow| stats.mvar && lv.stream == 0 && lv.m.is_power_of_two() && b.c3;
        let mut pyramid = std::mem::take(&mut self.pyramid);
        let s0 = &self.streams[0].x;
        let mut lo = s0.end();
        let mut top = 0;
        if let Some(xi) = R::as_i64(&s0.data) {
            for (lv, b) in self.levels.iter().zip(&bounds) {
                if uses_sums(lv, b) {
                    lo = lo.min(lv.mvar.next);
                    top = top.max(lv.m.trailing_zeros() as usize);
                }
            }
            pyramid.resize_with(top, Vec::new);
            for k in 0..top {
                let (done, rest) = pyramid.split_at_mut(k);
                let prev: &[i64] = if k == 0 {
                    &xi[(lo - s0.base) as usize..]
                } else {
                    &done[k - 1]
                };
                let half = 1usize << k;
                let next = &mut rest[0];
                next.clear();
                if prev.len() > half {
                    let len = prev.len() - half;
                    next.extend(
                        prev[..len]
                            .iter()
                            .zip(&prev[half..])
                            .map(|(a, b)| a.wrapping_add(*b)),
                    );
                }
            }
        }
        for (lv, b) in self.levels.iter_mut().zip(&bounds) {
            let st = &self.streams[lv.stream];
            let sums = if uses_sums(lv, b) {
                match (lv.m.trailing_zeros() as usize, R::as_i64(&st.x.data)) {
                    (0, Some(xi)) => Some((xi, st.x.base)),
                    (k, Some(_)) => Some((&pyramid[k - 1][..], lo)),
                    _ => None,
                }
            } else {
                None
            };
            update_level::<R>(lv, st, stats, nid, *b, sums, &mut self.scratch);
        }
        self.pyramid = pyramid;
        // Trim: each stream keeps what its levels still need.
        let mut keep: Vec<u64> = self.streams.iter().map(|s| s.x.end()).collect();
        let mut keep_c: Vec<u64> = self.streams.iter().map(|s| s.c.end()).collect();
        for lv in &self.levels {
            let k = &mut keep[lv.stream];
            if stats.avar {
                *k = (*k).min(lv.avar.next);
            }
            if stats.hvar {
                *k = (*k).min(lv.hvar.next);
            }
            if nid {
                *k = (*k).min(lv.nid_next);
            }
            if stats.mvar {
                keep_c[lv.stream] = keep_c[lv.stream].min(lv.mvar.next);
                if lv.stream == 0 {
                    // The moving sums read phase from MVAR's next term on.
                    *k = (*k).min(lv.mvar.next);
                }
            }
        }
        for (i, s) in self.streams.iter_mut().enumerate() {
            // A child decimates only new points, so nothing is kept for children.
            s.x.trim(keep[i]);
            s.c.trim(keep_c[i]);
        }
    }

    /// Processes pending points and reads every level.
    pub fn read(&mut self) -> Vec<LevelReading> {
        if self.open {
            self.process();
        }
        let tau0 = self.cfg.tau0_s;
        let stats = self.cfg.stats;
        // Equal increments make a straight line of phase, whose second and third differences
        // are 0: the variances are exactly 0, not the rounding of the running sums (about 1e-38
        // of the squared rate in double-double, which a fit would read as a noise term).
        let exact_zero = self.constant_increment().is_some();
        self.levels
            .iter()
            .map(|lv| {
                let tau = lv.m as f64 * tau0;
                let stride = self.streams[lv.stream].stride;
                let fin = |q: &SqSum, on: bool, denom: f64| {
                    let mean = |q: &SqSum| match exact_zero {
                        true => 0.0,
                        false => q.sum.value() / (denom * q.count as f64),
                    };
                    (on && q.count > 0).then(|| (mean(q), q.count))
                };
                let mf = lv.m as f64;
                LevelReading {
                    m: lv.m,
                    stride,
                    tau_s: tau,
                    // docs/theory.md section 1: AVAR divides by 2 tau^2, HVAR by 6 tau^2, MVAR by 2 m^2 tau^2.
                    avar: fin(&lv.avar, stats.avar, 2.0 * tau * tau),
                    hvar: fin(&lv.hvar, stats.hvar, 6.0 * tau * tau),
                    mvar: fin(&lv.mvar, stats.mvar, 2.0 * mf * mf * tau * tau),
                    lag1: [lv.lag[0].r1(), lv.lag[1].r1(), lv.lag[2].r1()],
                }
            })
            .filter(|r| r.avar.is_some() || r.hvar.is_some() || r.mvar.is_some())
            .collect()
    }

    /// Checks a state read back from a checkpoint: the streams and levels must be the ones its
    /// configuration builds, and every index must point into what the streams hold, so that a
    /// damaged or forged state is refused rather than read out of bounds. The numbers in the
    /// sums are not checked (any value is a possible sum).
    pub fn check_restored(&self) -> Result<(), String> {
        let fresh = Engine::<R>::new(self.cfg.clone());
        if self.streams.len() != fresh.streams.len() || self.levels.len() != fresh.levels.len() {
            return Err(format!(
                "{} streams and {} levels, where its settings give {} and {}",
                self.streams.len(),
                self.levels.len(),
                fresh.streams.len(),
                fresh.levels.len()
            ));
        }
        // Indices stay far below u64::MAX, so the sums of index and span cannot overflow.
        const MAX_INDEX: u64 = 1 << 62;
        for (i, (s, f)) in self.streams.iter().zip(&fresh.streams).enumerate() {
            if (s.stride, s.parent, s.factor, s.needs_c)
                != (f.stride, f.parent, f.factor, f.needs_c)
            {
                return Err(format!("stream {i} is not the one its settings build"));
            }
            for (name, base, len, new_from) in [
                ("x", s.x.base, s.x.data.len(), s.x.new_from),
                ("c", s.c.base, s.c.data.len(), s.c.new_from),
            ] {
                if new_from > len || base > MAX_INDEX || len as u64 > MAX_INDEX {
                    return Err(format!(
                        "stream {i} ({name}): new points from {new_from} of {len} held, base {base}"
                    ));
                }
            }
            if !s.needs_c && !s.c.data.is_empty() {
                return Err(format!("stream {i} holds running sums it does not use"));
            }
        }
        for (lv, f) in self.levels.iter().zip(&fresh.levels) {
            if (lv.m, lv.stream, lv.mp) != (f.m, f.stream, f.mp) {
                return Err(format!(
                    "the level of m = {} is not the one its settings build",
                    lv.m
                ));
            }
            let st = &self.streams[lv.stream];
            let within = |next: u64, b: &Buf<R::X>| next >= b.base && next <= b.end() + 4 * lv.mp;
            let within_c = |next: u64, b: &Buf<R::C>| next >= b.base && next <= b.end() + 4 * lv.mp;
            let stats = self.cfg.stats;
            let bad = (stats.avar && !within(lv.avar.next, &st.x))
                || (stats.hvar && !within(lv.hvar.next, &st.x))
                || (self.cfg.noise_id && !within(lv.nid_next, &st.x))
                || (stats.mvar && !within_c(lv.mvar.next, &st.c))
                || (stats.mvar && lv.stream == 0 && !within(lv.mvar.next, &st.x));
            if bad {
                return Err(format!(
                    "the level of m = {} points outside the data it holds",
                    lv.m
                ));
            }
        }
        if self.n_points > self.n_steps.saturating_add(self.segments) || self.n_steps > MAX_INDEX {
            return Err(format!(
                "{} points in {} steps and {} segments",
                self.n_points, self.n_steps, self.segments
            ));
        }
        Ok(())
    }

    /// Bytes held by the streams (the part of memory that could grow with the run).
    pub fn stream_bytes(&self) -> usize {
        self.streams
            .iter()
            .map(|s| {
                s.x.data.capacity() * std::mem::size_of::<R::X>()
                    + s.c.data.capacity() * std::mem::size_of::<R::C>()
            })
            .sum()
    }
}

impl Engine<FloatRepr> {
    /// Feeds one phase value in u (phase input); a non-finite value ends the segment.
    pub fn push_phase_f64(&mut self, x: f64) {
        if x.is_finite() {
            self.push_phase(Dd { hi: x, lo: 0.0 });
        } else {
            self.break_segment();
        }
    }
}

/// The largest divisor of `m` not above `cap` (`cap >= 1`): the stride of a level in bounded mode.
pub(super) fn largest_divisor_at_most(m: u64, cap: u64) -> u64 {
    if cap >= m {
        return m;
    }
    // m / d is a divisor <= cap for every divisor d >= m / cap; the smallest such d gives the
    // largest one. Divisors come in pairs around sqrt(m), so search each side up to sqrt(m).
    let mut d = m.div_ceil(cap);
    while d.saturating_mul(d) <= m {
        if m.is_multiple_of(d) {
            return m / d;
        }
        d += 1;
    }
    let mut e = cap.min(m.isqrt());
    while e > 1 {
        if m.is_multiple_of(e) {
            return e;
        }
        e -= 1;
    }
    1
}

/// Appends to `child` every `factor`-th point of `parent`'s new points (segment-relative index
/// divisible by `factor`).
pub(super) fn decimate<T: Copy>(parent: &Buf<T>, child: &mut Buf<T>, factor: u64) {
    let first_new = parent.base + parent.new_from as u64;
    // First index >= first_new that is a multiple of factor.
    let k = first_new.div_ceil(factor) * factor;
    if let Some(from) = parent.data.get((k - parent.base) as usize..) {
        if factor == 2 {
            // The usual case (octave strides); pairs vectorize where `step_by` does not.
            let pairs = from.chunks_exact(2);
            let last = pairs.remainder().first().copied();
            child.data.extend(pairs.map(|p| p[0]));
            child.data.extend(last);
        } else {
            child
                .data
                .extend(from.iter().step_by(factor as usize).copied());
        }
    }
}

/// Which differences of a level are proved below 2^51 in magnitude (integer input), so they
/// can take the narrow, vectorizable conversions.
#[derive(Debug, Clone, Copy)]
pub(super) struct Narrow {
    pub(super) d2: bool,
    pub(super) d3: bool,
    pub(super) c3: bool,
}

pub(super) fn update_level<R: Repr>(
    lv: &mut Level,
    st: &Stream<R>,
    stats: StatSet,
    nid: bool,
    narrow: Narrow,
    moving_sums: Option<(&[i64], u64)>,
    scratch: &mut Vec<f64>,
) {
    let mp = lv.mp;
    let x = &st.x;
    // Integer phase with both bounds proved: AVAR and HVAR from one set of second differences.
    // AVAR first catches up to HVAR's next + mp (the start of a segment), so that AVAR's
    // difference at k + mp is the one HVAR subtracts its difference at k from.
    let mut fused = false;
    // The AVAR terms this update took in one piece: (first index, count, sum of squares).
    let mut avar_piece: Option<(u64, usize, f64)> = None;
    if let (true, true, true, Some(xi)) = (stats.avar, stats.hvar, narrow.d3, R::as_i64(&x.data)) {
        let target = lv.hvar.next + mp;
        if lv.avar.next <= target {
            fused = true;
            let upto = target.min(x.end().saturating_sub(2 * mp));
            if upto > lv.avar.next {
                let n = (upto - lv.avar.next) as usize;
                let [a, b, c] = lagged_at(xi, x.base, lv.avar.next, mp, n);
                lv.avar
                    .add(n, sum_sq3(a, b, c, |a, b, c| IntRepr::d2_narrow(c, b, a)));
            }
            if lv.avar.next == target && x.end() > lv.hvar.next + 3 * mp {
                // Second differences at k in [hvar.next, end - 2 mp): AVAR takes them from
                // k = hvar.next + mp on, HVAR their differences at lag mp (docs/theory.md section 1).
                let n = (x.end() - 3 * mp - lv.hvar.next) as usize;
                let m = mp as usize;
                let [a, b, c] = lagged_at(xi, x.base, lv.hvar.next, mp, n + m);
                second_differences(a, b, c, scratch);
                let sq = sum_sq(&scratch[m..]);
                avar_piece = Some((target, n, sq));
                lv.avar.add(n, sq);
                lv.hvar.add(n, sum_sq_diff(&scratch[..n], &scratch[m..]));
            }
        }
    }
    // AVAR: x_{k+2m} - 2 x_{k+m} + x_k (docs/theory.md section 1).
    if stats.avar && !fused {
        if let Some([a, b, c]) = lagged(x, lv.avar.next, mp) {
            lv.avar.add(
                a.len(),
                if narrow.d2 {
                    sum_sq3(a, b, c, |a, b, c| R::d2_narrow(c, b, a))
                } else {
                    sum_sq3(a, b, c, |a, b, c| R::d2(c, b, a))
                },
            );
        }
    }
    // HVAR: x_{k+3m} - 3 x_{k+2m} + 3 x_{k+m} - x_k (docs/theory.md section 1).
    if stats.hvar && !fused {
        if let Some([a, b, c, d]) = lagged(x, lv.hvar.next, mp) {
            lv.hvar.add(
                a.len(),
                if narrow.d3 {
                    sum_sq4(a, b, c, d, |a, b, c, d| R::d3_narrow(d, c, b, a))
                } else {
                    sum_sq4(a, b, c, d, |a, b, c, d| R::d3(d, c, b, a))
                },
            );
        }
    }
    // MVAR: the inner sum of m second differences is C_{j+3m} - 3C_{j+2m} + 3C_{j+m} - C_j
    // (docs/theory.md section 1 with C the running sum of phase); with stride s the stream holds
    // C at every s-th index, and mp = m/s.
    if let (true, Some((sums, base))) = (stats.mvar, moving_sums) {
        // The same inner sum as the second difference at lag m of the moving sums
        // A_m(j) = C_{j+m} - C_j of phase, which the caller holds from `base` up to P - m + 1
        // (P phase points), in wrapping i64, with |result| < 2^51 proved.
        if let Some([a, b, c]) = lagged_in(sums, base, lv.mvar.next, mp) {
            match avar_piece {
                // At m = 1 MVAR's inner sum is AVAR's second difference: the same terms in the
                // same order give the same sum, so it is not taken twice.
                Some((from, n, sq)) if lv.m == 1 && from == lv.mvar.next && n == a.len() => {
                    lv.mvar.add(n, sq)
                }
                _ => {
                    second_differences(a, b, c, scratch);
                    lv.mvar.add(a.len(), sum_sq(scratch));
                }
            }
        }
    } else if stats.mvar {
        if let Some([a, b, c, d]) = lagged(&st.c, lv.mvar.next, mp) {
            lv.mvar.add(
                a.len(),
                if narrow.c3 {
                    sum_sq4(a, b, c, d, |a, b, c, d| R::c3_narrow(d, c, b, a))
                } else {
                    sum_sq4(a, b, c, d, |a, b, c, d| R::c3(d, c, b, a))
                },
            );
        }
    }
    // Noise identification (Riley and Greenhall 2004): lag-1 products of the non-overlapping
    // m-averaged rate (first phase differences at cluster m, taken every m samples) and of its
    // first and second differences (second and third phase differences).
    // At short clusters every block would give far more pairs than the identification needs,
    // so pairs start every NID_MIN_STEP points at least (lag-1 is still between adjacent blocks).
    if nid {
        let m = mp as usize;
        let step = mp.max(NID_MIN_STEP);
        while x.end() > lv.nid_next + 4 * mp {
            let o = (lv.nid_next - x.base) as usize;
            let p = |j: usize| x.data[o + j * m];
            let (x0, x1, x2, x3, x4) = (p(0), p(1), p(2), p(3), p(4));
            lv.lag[0].add(R::d1(x1, x0), R::d1(x2, x1));
            lv.lag[1].add(R::d2(x2, x1, x0), R::d2(x3, x2, x1));
            lv.lag[2].add(R::d3(x3, x2, x1, x0), R::d3(x4, x3, x2, x1));
            lv.nid_next += step;
        }
    }
}
