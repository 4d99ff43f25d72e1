//! The unit's low-pass filters beyond first order as streaming generators on the output
//! increments ([`LowPassGen`]): cascaded moving averages, a second-order recursive low-pass and
//! a zero-phase (forward-backward) first-order filter. Their AVAR on white rate is
//! [`LowPass::white_rate_avar`] (docs/gap.md, "Low-pass filters beyond first order").
//!
//! Each filter starts in the stationary state of the first input's level plus white noise
//! ([`LowPassGen::start_stationary`]), so a large constant such as gravity causes no transient
//! and the record's first samples are as noisy as the later ones. The zero-phase filter needs the future: it is run as its
//! symmetric impulse response `(1 - a)/(1 + a) a^|k|` truncated at `a^L < 1e-14` (weights
//! renormalised to sum 1), so the output is the zero-phase filtered stream delayed by `L`
//! steps, as a unit filtering in blocks delivers it.

use std::collections::VecDeque;

use crate::model::lowpass::{Behind, LowPass};

/// A running low-pass filter (DC gain 1).
#[derive(Debug, Clone)]
pub enum LowPassGen {
    /// One ring buffer of the last `taps` inputs per stage, with its exact sum recomputed every
    /// `taps` steps (the running sum's rounding never accumulates).
    ///
    /// With `decimation` above 1 the filter runs at the internal rate: the simulator feeds it
    /// that many internal samples per output step ([`LowPassGen::decimation`]) and keeps the
    /// last output.
    MovingAverage {
        taps: usize,
        stages: Vec<(VecDeque<f64>, f64)>,
        since_exact: usize,
        started: bool,
        decimation: usize,
        /// [`LowPass::internal_white_scale`].
        white_scale: f64,
    },
    /// `y_k = a1 y_{k-1} + a2 y_{k-2} + g (b0 d_k + b1 d_{k-1} + b2 d_{k-2})` with the
    /// numerator `b` of [`LowPass::numerator`] (`(1, 0, 0)` pole-mapped, `(1, 2, 1) / 4`
    /// bilinear, `(1, c, 0) / (1 + c)` sampled; [`LowPass::SecondOrder`]).
    SecondOrder {
        a1: f64,
        a2: f64,
        g: f64,
        y1: f64,
        y2: f64,
        b: [f64; 3],
        x1: f64,
        x2: f64,
        started: bool,
    },
    /// Symmetric weights `w[|k|]`, `k = -L..=L`, over a window of `2L + 1` inputs.
    ZeroPhase {
        weights: Vec<f64>,
        window: VecDeque<f64>,
        started: bool,
    },
    /// A FIR's taps `h` over a window of its last `h.len()` inputs, newest last
    /// ([`LowPass::Fir`]). With `decimation` above 1 it runs at the internal rate, as the
    /// decimated moving average does.
    Fir {
        h: Vec<f64>,
        window: VecDeque<f64>,
        started: bool,
        decimation: usize,
        /// [`LowPass::internal_white_scale`].
        white_scale: f64,
    },
    /// A moving average with a recursive low-pass behind it at the output rate
    /// ([`LowPass::Cascade`]): every input goes through the front, and every `decimation`-th
    /// front output (the output sample the front delivers) through the back; the output is the
    /// back's last. A first order behind is the recursion with `a2 = 0`.
    Cascade {
        front: Box<LowPassGen>,
        back: Box<LowPassGen>,
        /// Inputs since the back's last step.
        phase: usize,
        /// The back's last output.
        last: f64,
    },
    /// Second-order sections one after the other at the output rate, each a
    /// [`LowPassGen::SecondOrder`] ([`LowPass::Butterworth`]'s
    /// [`butterworth_sections`](crate::model::lowpass::butterworth_sections)). With
    /// `decimation` above 1 they run at the internal rate, as the decimated FIR does.
    Sections {
        parts: Vec<LowPassGen>,
        decimation: usize,
        /// [`LowPass::internal_white_scale`].
        white_scale: f64,
    },
}

impl LowPassGen {
    /// The generator of `lp` at step `tau0_s`. A first-order filter is the simulator's
    /// [`super::effects::OutputFilter`] and has no generator here (None).
    pub fn new(lp: &LowPass, tau0_s: f64) -> Option<Self> {
        match *lp {
            LowPass::FirstOrder { .. } => None,
            LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation,
            } => {
                let d = decimation.max(1);
                let step = tau0_s / f64::from(d);
                Some(LowPassGen::Sections {
                    parts: crate::model::lowpass::butterworth_sections(order, cutoff_hz, step)
                        .into_iter()
                        .map(|q| LowPassGen::SecondOrder {
                            a1: q.a1,
                            a2: q.a2,
                            g: 1.0 - q.a1 - q.a2,
                            y1: 0.0,
                            y2: 0.0,
                            b: q.b,
                            x1: 0.0,
                            x2: 0.0,
                            started: false,
                        })
                        .collect(),
                    decimation: d as usize,
                    white_scale: lp.internal_white_scale(tau0_s),
                })
            }
            LowPass::Fir { .. } => {
                let (h, d) = lp.internal_response(tau0_s)?;
                Some(LowPassGen::Fir {
                    window: VecDeque::with_capacity(h.len()),
                    h,
                    started: false,
                    decimation: d,
                    white_scale: lp.internal_white_scale(tau0_s),
                })
            }
            LowPass::Cascade { front, back } => {
                let back = match back {
                    Behind::FirstOrder { time_constant_s } => {
                        let a = (-tau0_s / time_constant_s).exp();
                        LowPassGen::SecondOrder {
                            a1: a,
                            a2: 0.0,
                            g: 1.0 - a,
                            y1: 0.0,
                            y2: 0.0,
                            b: [1.0, 0.0, 0.0],
                            x1: 0.0,
                            x2: 0.0,
                            started: false,
                        }
                    }
                    Behind::SecondOrder { .. } | Behind::Butterworth { .. } => {
                        LowPassGen::new(&back.lowpass(), tau0_s)?
                    }
                };
                Some(LowPassGen::Cascade {
                    front: Box::new(LowPassGen::new(&front.lowpass(), tau0_s)?),
                    back: Box::new(back),
                    phase: 0,
                    last: 0.0,
                })
            }
            LowPass::MovingAverage {
                taps,
                stages,
                decimation,
            } => Some(LowPassGen::MovingAverage {
                taps: taps.max(1) as usize,
                stages: (0..stages.max(1)).map(|_| (VecDeque::new(), 0.0)).collect(),
                since_exact: 0,
                started: false,
                decimation: decimation.max(1) as usize,
                white_scale: lp.internal_white_scale(tau0_s),
            }),
            LowPass::SecondOrder { .. } => {
                // The same poles and zeros as the AVAR's (model::lowpass): its
                // autocorrelation is of this recursion.
                let (a1, a2) = lp.ar2(tau0_s)?;
                Some(LowPassGen::SecondOrder {
                    a1,
                    a2,
                    g: 1.0 - a1 - a2,
                    y1: 0.0,
                    y2: 0.0,
                    b: lp.numerator()?,
                    x1: 0.0,
                    x2: 0.0,
                    started: false,
                })
            }
            LowPass::ZeroPhase { time_constant_s } => {
                let a = (-tau0_s / time_constant_s).exp();
                let l = ((1e-14f64.ln() / a.ln()).ceil() as usize).clamp(1, 1 << 20);
                let mut w: Vec<f64> = (0..=l).map(|k| a.powi(k as i32)).collect();
                let total = crate::model::lowpass::two_sided_sum(&w);
                w.iter_mut().for_each(|x| *x /= total);
                Some(LowPassGen::ZeroPhase {
                    weights: w,
                    window: VecDeque::with_capacity(2 * l + 1),
                    started: false,
                })
            }
        }
    }

    /// Internal samples per output sample: [`Self::step`] takes internal samples, and the
    /// output is every this-many-th one (1 for all but a decimated moving average).
    pub fn decimation(&self) -> usize {
        match self {
            LowPassGen::MovingAverage { decimation, .. }
            | LowPassGen::Fir { decimation, .. }
            | LowPassGen::Sections { decimation, .. } => *decimation,
            LowPassGen::Cascade { front, .. } => front.decimation(),
            _ => 1,
        }
    }

    /// The factor on the output step's white-rate standard deviation for the internal samples
    /// ([`LowPass::internal_white_scale`]; 1 but for a decimated moving average).
    pub fn white_scale(&self) -> f64 {
        match self {
            LowPassGen::MovingAverage { white_scale, .. }
            | LowPassGen::Fir { white_scale, .. }
            | LowPassGen::Sections { white_scale, .. } => *white_scale,
            LowPassGen::Cascade { front, .. } => front.white_scale(),
            _ => 1.0,
        }
    }

    /// Whether the filter has had its first input (or [`Self::start_at`]).
    pub fn is_started(&self) -> bool {
        match self {
            LowPassGen::MovingAverage { started, .. }
            | LowPassGen::SecondOrder { started, .. }
            | LowPassGen::ZeroPhase { started, .. }
            | LowPassGen::Fir { started, .. } => *started,
            LowPassGen::Cascade { front, .. } => front.is_started(),
            LowPassGen::Sections { parts, .. } => parts.iter().all(LowPassGen::is_started),
        }
    }

    /// Steps after which the filter's output no longer depends on its state before them: the
    /// moving average's `taps * stages`, the zero-phase window's `2L + 1`, and for the
    /// second-order recursion the steps its slower pole takes to fall below 1e-12.
    pub fn memory_steps(&self) -> usize {
        match self {
            LowPassGen::MovingAverage { taps, stages, .. } => taps * stages.len(),
            LowPassGen::ZeroPhase { weights, .. } => 2 * (weights.len() - 1) + 1,
            LowPassGen::Fir { h, .. } => h.len(),
            // whole output samples (the phase stays with the output's), the front's and then
            // the back's
            LowPassGen::Cascade { front, back, .. } => {
                let d = front.decimation();
                (front.memory_steps().div_ceil(d) + back.memory_steps()) * d
            }
            LowPassGen::Sections { parts, .. } => parts.iter().map(LowPassGen::memory_steps).sum(),
            LowPassGen::SecondOrder { a1, a2, .. } => {
                // poles: roots of z^2 - a1 z - a2
                let r = crate::model::lowpass::slow_pole(*a1, *a2);
                if r <= 0.0 {
                    2
                } else if r >= 1.0 {
                    1 << 22
                } else {
                    ((1e-12f64.ln() / r.ln()).ceil() as usize).clamp(2, 1 << 22)
                }
            }
        }
    }

    /// Starts the filter in the stationary state of its input `level + white_sd * e_k` (`e_k`
    /// standard normal from `normal`; u per step), as a unit whose filter ran before the record
    /// began: `start_at(level)` and then [`Self::memory_steps`] such inputs, their outputs
    /// dropped. No-op when the filter has started already.
    ///
    /// The simulator passes the first input without its white rate noise as `level` and the
    /// white rate's per-step standard deviation as `white_sd`. Before session 20 the first input
    /// itself was copied into the filter's past: a white sample is independent of every earlier
    /// one, so that put one sample's noise, weighted by the filter's whole memory (for the
    /// zero-phase filter 2L + 1 copies, about 32 time constants), into the start of the record,
    /// a transient no running unit shows (a zpexp unit, 300 seeds: the first difference of
    /// 22.6-s block means had 1.37 times the standard deviation of the next one; 1.08 with the
    /// level alone, which leaves the first L outputs without noise). The slower processes
    /// (flicker, random walk, Gauss-Markov) keep their first value over the filter's memory,
    /// which is near what they had.
    pub fn start_stationary(&mut self, level: f64, white_sd: f64, mut normal: impl FnMut() -> f64) {
        if self.is_started() {
            return;
        }
        self.start_at(level);
        // at the internal rate a white sample's standard deviation is about sqrt(D) times the
        // output step's ([`Self::white_scale`])
        let white_sd = white_sd * self.white_scale();
        if white_sd != 0.0 {
            for _ in 0..self.memory_steps() {
                self.step(level + white_sd * normal());
            }
        }
    }

    /// Starts the filter as if its input had always been `level` (u per step), unless it has
    /// started already. Without this call the first input is that level.
    pub fn start_at(&mut self, level: f64) {
        match self {
            LowPassGen::MovingAverage {
                taps,
                stages,
                started,
                ..
            } => {
                if !*started {
                    *started = true;
                    for (buf, sum) in stages.iter_mut() {
                        buf.extend(std::iter::repeat_n(level, *taps));
                        *sum = level * *taps as f64;
                    }
                }
            }
            LowPassGen::SecondOrder {
                y1,
                y2,
                x1,
                x2,
                started,
                ..
            } => {
                if !*started {
                    *started = true;
                    *y1 = level;
                    *y2 = level;
                    *x1 = level;
                    *x2 = level;
                }
            }
            LowPassGen::ZeroPhase {
                weights,
                window,
                started,
            } => {
                if !*started {
                    *started = true;
                    // the newest slot is taken by the first input's push
                    window.extend(std::iter::repeat_n(level, 2 * (weights.len() - 1) + 1));
                }
            }
            LowPassGen::Fir {
                h, window, started, ..
            } => {
                if !*started {
                    *started = true;
                    // the newest slot is taken by the first input's push
                    window.extend(std::iter::repeat_n(level, h.len()));
                }
            }
            LowPassGen::Cascade {
                front, back, last, ..
            } => {
                if !front.is_started() {
                    front.start_at(level);
                    back.start_at(level);
                    *last = level;
                }
            }
            // DC gain 1: every section's input is the level
            LowPassGen::Sections { parts, .. } => parts.iter_mut().for_each(|q| q.start_at(level)),
        }
    }

    /// The filtered increment for input `d`.
    #[inline]
    pub fn step(&mut self, d: f64) -> f64 {
        self.start_at(d);
        match self {
            LowPassGen::MovingAverage {
                taps,
                stages,
                since_exact,
                ..
            } => {
                let m = *taps;
                *since_exact += 1;
                let exact = *since_exact >= m;
                if exact {
                    *since_exact = 0;
                }
                let mut x = d;
                for (buf, sum) in stages.iter_mut() {
                    let old = buf.pop_front().unwrap_or(x);
                    buf.push_back(x);
                    *sum += x - old;
                    if exact {
                        *sum = buf.iter().sum();
                    }
                    x = *sum / m as f64;
                }
                x
            }
            LowPassGen::SecondOrder {
                a1,
                a2,
                g,
                y1,
                y2,
                b,
                x1,
                x2,
                ..
            } => {
                let input = b[0] * d + b[1] * *x1 + b[2] * *x2;
                *x2 = *x1;
                *x1 = d;
                let y = *a1 * *y1 + *a2 * *y2 + *g * input;
                *y2 = *y1;
                *y1 = y;
                y
            }
            LowPassGen::ZeroPhase {
                weights, window, ..
            } => {
                let l = weights.len() - 1;
                window.pop_front();
                window.push_back(d);
                let (a, b) = window.as_slices();
                // centre at index l; weight w[|i - l|]
                let mut acc = 0.0;
                for (i, x) in a.iter().chain(b.iter()).enumerate() {
                    acc += weights[i.abs_diff(l)] * x;
                }
                acc
            }
            // `y_n = sum_j h_j x_{n - j}`: the newest input meets h_0
            LowPassGen::Fir { h, window, .. } => {
                window.pop_front();
                window.push_back(d);
                window.iter().rev().zip(h.iter()).map(|(x, w)| x * w).sum()
            }
            LowPassGen::Cascade {
                front,
                back,
                phase,
                last,
            } => {
                let y = front.step(d);
                *phase += 1;
                if *phase >= front.decimation() {
                    *phase = 0;
                    *last = back.step(y);
                }
                *last
            }
            LowPassGen::Sections { parts, .. } => parts.iter_mut().fold(d, |x, q| q.step(x)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::lowpass::SecondOrderForm;

    /// Each filter passes a constant unchanged and has the impulse response its autocorrelation
    /// was computed from (checked on lag-0 energy of the response to a unit impulse).
    #[test]
    fn dc_gain_and_impulse_energy() {
        let tau0 = 0.004;
        for lp in [
            LowPass::MovingAverage {
                taps: 6,
                stages: 2,
                decimation: 1,
            },
            LowPass::SecondOrder {
                natural_frequency_hz: 8.0,
                damping: 0.4,
                form: SecondOrderForm::PoleMapped,
            },
            LowPass::SecondOrder {
                natural_frequency_hz: 30.0,
                damping: 0.7,
                form: SecondOrderForm::Sampled { zero: 0.3 },
            },
            LowPass::ZeroPhase {
                time_constant_s: 0.012,
            },
        ] {
            let mut g = LowPassGen::new(&lp, tau0).unwrap();
            for _ in 0..5000 {
                assert!((g.step(3.5) - 3.5).abs() < 1e-9, "{lp:?}");
            }
            // impulse on a zero background: the output's energy is rho_0
            let mut g = LowPassGen::new(&lp, tau0).unwrap();
            g.step(0.0);
            let mut e = g.step(1.0).powi(2);
            for _ in 0..20_000 {
                e += g.step(0.0).powi(2);
            }
            let r0 = lp.autocorrelation(tau0)[0];
            assert!((e / r0 - 1.0).abs() < 1e-6, "{lp:?}: {e} vs {r0}");
        }
    }
}
