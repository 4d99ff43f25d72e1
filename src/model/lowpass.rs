//! The unit's output low-pass filters on its increments, first order and beyond: moving averages
//! (FIR decimation filters, one stage or cascaded: two stages is the triangular Bartlett window of
//! the ADIS16405), a second-order low-pass (natural frequency, damping) and a zero-phase
//! (forward-backward) first-order filter. Each is described by the autocorrelation of its
//! impulse response, from which the exact discrete AVAR of white rate noise through it follows
//! (docs/gap.md, "Low-pass filters beyond first order"), and by its power gain `|H(f)|^2`, by
//! which a sinusoid's AVAR is multiplied.
//!
//! All filters have DC gain 1, so the AVAR they give tends to the white rate's `N^2 / tau` once
//! `tau` is long against their memory.

use std::f64::consts::PI;

/// A low-pass filter on the increments (times in s, frequencies in Hz).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LowPass {
    /// `y_k = a y_{k-1} + (1 - a) d_k`, `a = e^{-tau0/T}`.
    FirstOrder { time_constant_s: f64 },
    /// `stages` cascaded moving averages of `taps` increments each (1: boxcar; 2: triangular,
    /// the Bartlett window), run at `decimation` times the output rate and read every
    /// `decimation`-th sample: `taps` counts the internal samples. 1 is an average of the
    /// output samples; `taps = decimation` with 3 stages is the sinc^3 of a CIC decimator, which
    /// at the output rate spans three samples whatever its length (docs/gap.md, "Averages run
    /// faster than the output (session 44)").
    MovingAverage {
        taps: u32,
        stages: u32,
        decimation: u32,
    },
    /// `y_k = a1 y_{k-1} + a2 y_{k-2} + (1 - a1 - a2) d_k` with the poles of the continuous
    /// `w^2 / (s^2 + 2 zeta w s + w^2)`, `w = 2 pi f_n`, mapped by `z = e^{s tau0}`. With
    /// [`SecondOrderForm::Bilinear`], the digital biquad most units and tools build instead (scipy's `butter`,
    /// PX4's `LowPassFilter2p`, the audio cookbook's low-pass; Butterworth at `zeta = 1/sqrt 2`):
    /// the same prototype by the bilinear transform with `f_n` prewarped,
    /// `K = tan(pi f_n tau0)`, `D = 1 + 2 zeta K + K^2`,
    /// `H(z) = K^2 (1 + z^-1)^2 / (D + (2 K^2 - 2) z^-1 + (1 - 2 zeta K + K^2) z^-2)`: two zeros
    /// at Nyquist, which the pole-mapped form lacks (docs/gap.md, "The bilinear second order
    /// (session 42)"). With [`SecondOrderForm::Sampled`], the prototype run faster than the
    /// output and read every so many samples, as MEMS parts filter at their internal rate and
    /// deliver at the output rate: the pole-mapped poles and one zero.
    SecondOrder {
        natural_frequency_hz: f64,
        damping: f64,
        form: SecondOrderForm,
    },
    /// The first-order filter run forward then backward over the record: the symmetric impulse
    /// response `(1 - a)/(1 + a) a^|k|`, `|H|^2` the first order's squared, no phase.
    ZeroPhase { time_constant_s: f64 },
    /// A moving average (a CIC decimator, or an average of output samples) with a first- or
    /// second-order low-pass behind it at the output rate: the commonest consumer MEMS chain,
    /// sinc^3 decimation and then the digital low-pass a register sets. Both are linear and
    /// time-invariant at the output rate, so the output's autocorrelation is the two-sided
    /// convolution of the parts' and its power gain their product (docs/gap.md, "A low-pass
    /// behind a decimator (session 46)").
    Cascade { front: Average, back: Behind },
    /// A linear-phase FIR low-pass of `taps` taps: the Hamming-windowed sinc of cut-off
    /// `cutoff_hz` (the window method, scipy's `firwin` and the STIM300's filters), scaled to
    /// DC gain 1 ([`fir_window_sinc`]; docs/gap.md, "A linear-phase FIR low-pass (session
    /// 46)"). With `decimation` above 1 it runs at `decimation` times the output rate and is
    /// read every `decimation`-th sample (`taps` counts the internal samples): a half-band
    /// decimator by 2 (its cut-off at the output's Nyquist), a FIR filtering at 2 kHz read
    /// at a lower rate (docs/gap.md, "A FIR read every so many samples (session 47)").
    Fir {
        taps: u32,
        cutoff_hz: f64,
        decimation: u32,
    },
    /// The digital Butterworth low-pass of `order` and cut-off (half power) `cutoff_hz`: the
    /// analog prototype's poles `w_c e^{i pi (2k + n - 1) / (2n)}` taken by the bilinear
    /// transform with the cut-off prewarped, `K = tan(pi f_c tau0)`, so that
    /// `|H|^2 = 1 / (1 + (tan(pi f tau0) / K)^(2n))` (Oppenheim and Schafer, "Discrete-Time
    /// Signal Processing", section 7.1; scipy's `signal.butter(n, f_c, fs=1/tau0)`). It is run
    /// as [`butterworth_sections`]: a biquad per pole pair, damping `sin((2k - 1) pi / (2n))`,
    /// and for an odd order a first-order section. The selectable-order digital low-pass of
    /// consumer MEMS IMUs (the "UI filter" of orders 1 to 3 and beyond); order 2 is
    /// [`LowPass::SecondOrder`]'s bilinear form at damping `1/sqrt 2` (docs/gap.md, "An n-th
    /// order Butterworth (session 54)"). With `decimation` above 1 it runs at `decimation` times
    /// the output rate and is read every `decimation`-th sample, as parts that filter at their
    /// internal rate deliver ([`butterworth_internal_autocovariance`]).
    Butterworth {
        order: u32,
        cutoff_hz: f64,
        decimation: u32,
    },
}

/// One section of a recursive filter on the increments, DC gain 1:
/// `y_k = a1 y_{k-1} + a2 y_{k-2} + (1 - a1 - a2) (b0 d_k + b1 d_{k-1} + b2 d_{k-2})`,
/// `b0 + b1 + b2 = 1`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Biquad {
    pub a1: f64,
    pub a2: f64,
    pub b: [f64; 3],
}

/// The sections of [`LowPass::Butterworth`] at step `tau0_s`, pole pairs from the least damped:
/// the pair `k = 1..=n/2` is the bilinear second order of natural frequency `f_c` and damping
/// `zeta_k = sin((2k - 1) pi / (2n))` (`D = 1 + 2 zeta K + K^2`, `a1 = 2 (1 - K^2) / D`,
/// `a2 = -(1 - 2 zeta K + K^2) / D`, numerator `(1, 2, 1) / 4`), and an odd order's real pole
/// `w_c` is `p = (1 - K) / (1 + K)` with the numerator `(1, 1) / 2`; `K = tan(pi f_c tau0)`.
/// The product of the sections is the bilinear transform of the whole prototype, since the
/// transform maps each factor of `H(s)` on its own.
pub fn butterworth_sections(order: u32, cutoff_hz: f64, tau0_s: f64) -> Vec<Biquad> {
    let n = order.max(1);
    let k = (PI * cutoff_hz * tau0_s).tan();
    let mut out: Vec<Biquad> = (1..=n / 2)
        .map(|i| {
            let zeta = ((2 * i - 1) as f64 * PI / (2 * n) as f64).sin();
            let d = 1.0 + 2.0 * zeta * k + k * k;
            Biquad {
                a1: 2.0 * (1.0 - k * k) / d,
                a2: -(1.0 - 2.0 * zeta * k + k * k) / d,
                b: [0.25, 0.5, 0.25],
            }
        })
        .collect();
    if n % 2 == 1 {
        out.push(Biquad {
            a1: (1.0 - k) / (1.0 + k),
            a2: 0.0,
            b: [0.5, 0.5, 0.0],
        });
    }
    out
}

impl Biquad {
    /// The normalised autocorrelation of the section's output for white input (total over
    /// both sides 1), from lag 0 to where the slower pole's decay falls below [`TAIL`].
    /// Yule-Walker for the all-pole part: `rho_1 = a1 / (1 - a2)`,
    /// `rho_k = a1 rho_{k-1} + a2 rho_{k-2}`; `gamma_0` of `y_k = a1 y_{k-1} + a2 y_{k-2} + g e_k`
    /// (unit-variance `e`) is `g^2 (1 - a2) / ((1 + a2)((1 - a2)^2 - a1^2))` (Box, Jenkins and
    /// Reinsel, "Time Series Analysis", section 3.2.4); the numerator's own autocorrelation
    /// `q_j = sum_i b_i b_{i+j}` is then convolved with it.
    pub fn autocorrelation(&self) -> Vec<f64> {
        let (a1, a2) = (self.a1, self.a2);
        let g = 1.0 - a1 - a2;
        let g0 = g * g * (1.0 - a2) / ((1.0 + a2) * ((1.0 - a2).powi(2) - a1 * a1));
        // the slowest pole sets the decay
        let n = lags_for(slow_pole(a1, a2));
        let mut out = Vec::with_capacity(n + 2);
        let (mut r_prev, mut r) = (f64::NAN, 1.0);
        for k in 0..n + 2 {
            out.push(g0 * r);
            let next = if k == 0 {
                a1 / (1.0 - a2)
            } else {
                a1 * r + a2 * r_prev
            };
            r_prev = r;
            r = next;
        }
        let b = self.b;
        if b == [1.0, 0.0, 0.0] {
            out.truncate(n);
            return out;
        }
        // The numerator on the all-pole part: its autocorrelation `q_j = sum_i b_i b_{i+j}` at
        // lags 0, +-1, +-2 (bilinear (6, 4, 1) / 16) convolved with the all-pole part's (even
        // in the lag).
        let q = [
            b[0] * b[0] + b[1] * b[1] + b[2] * b[2],
            b[0] * b[1] + b[1] * b[2],
            b[0] * b[2],
        ];
        let at = |k: i64| out[k.unsigned_abs() as usize];
        (0..n as i64)
            .map(|k| q[0] * at(k) + q[1] * (at(k - 1) + at(k + 1)) + q[2] * (at(k - 2) + at(k + 2)))
            .collect()
    }

    /// The section run over `x` in place from rest (its impulse response when `x` is a unit
    /// impulse): `y_k = a1 y_{k-1} + a2 y_{k-2} + (1 - a1 - a2)(b0 x_k + b1 x_{k-1} + b2 x_{k-2})`.
    pub fn run(&self, x: &mut [f64]) {
        let g = 1.0 - self.a1 - self.a2;
        let b = self.b;
        let (mut x1, mut x2, mut y1, mut y2) = (0.0, 0.0, 0.0, 0.0);
        for v in x.iter_mut() {
            let y = self.a1 * y1 + self.a2 * y2 + g * (b[0] * *v + b[1] * x1 + b[2] * x2);
            (x2, x1, y2, y1) = (x1, *v, y1, y);
            *v = y;
        }
    }

    /// `|H(w)|^2` at `w` radians per sample:
    /// `g^2 |b0 + b1 e^{-iw} + b2 e^{-2iw}|^2 / |1 - a1 e^{-iw} - a2 e^{-2iw}|^2`.
    pub fn power_gain(&self, w: f64) -> f64 {
        let (a1, a2, b) = (self.a1, self.a2, self.b);
        let g = 1.0 - a1 - a2;
        let re = 1.0 - a1 * w.cos() - a2 * (2.0 * w).cos();
        let im = a1 * w.sin() + a2 * (2.0 * w).sin();
        let nre = b[0] + b[1] * w.cos() + b[2] * (2.0 * w).cos();
        let nim = b[1] * w.sin() + b[2] * (2.0 * w).sin();
        (nre * nre + nim * nim) * g * g / (re * re + im * im)
    }

    /// The slower pole's time constant in steps, `-1 / ln |z|` (one step for a modulus outside
    /// (0, 1)).
    pub fn memory_steps(&self) -> f64 {
        let slow = slow_pole(self.a1, self.a2);
        if slow > 0.0 && slow < 1.0 {
            -1.0 / slow.ln()
        } else {
            1.0
        }
    }
}

/// `sum_i h_i h_{i + D j}`, `j = 0, 1, ...`, of [`LowPass::Butterworth`] run at `D` times the
/// output rate (step `tau0_s / D`, DC gain 1): the autocovariance of its output read every
/// `D`-th sample for unit-variance white input at the internal rate. The impulse response is
/// run through the sections until every section's slower pole has decayed below [`TAIL`], and
/// its autocorrelation is taken by the FFT (`|H_k|^2` transformed back, the record zero-padded
/// to twice its length so that no lag wraps; Wiener-Khinchin), the internal lags being `D` times
/// the output's.
pub fn butterworth_internal_autocovariance(
    order: u32,
    cutoff_hz: f64,
    tau0_s: f64,
    decimation: u32,
) -> Vec<f64> {
    use rustfft::{num_complex::Complex64 as C, FftPlanner};
    let d = decimation.max(1) as usize;
    let sections = butterworth_sections(order, cutoff_hz, tau0_s / d as f64);
    let len = sections
        .iter()
        .map(|q| lags_for(slow_pole(q.a1, q.a2)))
        .sum::<usize>()
        .clamp(2, MAX_LAGS);
    let mut h = vec![0.0; len];
    h[0] = 1.0;
    sections.iter().for_each(|q| q.run(&mut h));
    let n = (2 * len).next_power_of_two();
    let mut buf: Vec<C> = h.iter().map(|&v| C::new(v, 0.0)).collect();
    buf.resize(n, C::new(0.0, 0.0));
    let mut planner = FftPlanner::new();
    planner.plan_fft_forward(n).process(&mut buf);
    buf.iter_mut().for_each(|c| *c = C::new(c.norm_sqr(), 0.0));
    planner.plan_fft_inverse(n).process(&mut buf);
    (0..len).step_by(d).map(|k| buf[k].re / n as f64).collect()
}

/// The problem with a filter's decimation (internal samples per output sample), if any.
fn decimation_problem(decimation: u32) -> Option<String> {
    (!(1..=MAX_DECIMATION).contains(&decimation))
        .then(|| format!("decimation {decimation} must be 1..={MAX_DECIMATION}"))
}

/// Highest order of [`LowPass::Butterworth`] accepted.
pub const MAX_BUTTERWORTH_ORDER: u32 = 8;

/// The impulse response of [`LowPass::Fir`]: `h_n = w_n sin(2 pi f_c t_n) / (pi t_n)` at
/// `t_n = (n - (taps - 1) / 2) tau0`, `w_n = 0.54 - 0.46 cos(2 pi n / (taps - 1))` (Hamming;
/// Oppenheim and Schafer, "Discrete-Time Signal Processing", section 7.5), then scaled so that
/// `sum h_n = 1`. One tap is the identity.
pub fn fir_window_sinc(taps: u32, cutoff_hz: f64, tau0_s: f64) -> Vec<f64> {
    let n = taps.max(1) as usize;
    if n == 1 {
        return vec![1.0];
    }
    let fc = cutoff_hz * tau0_s; // cycles per sample
    let mid = (n - 1) as f64 / 2.0;
    let mut h: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64 - mid;
            let sinc = if t == 0.0 {
                2.0 * fc
            } else {
                (2.0 * PI * fc * t).sin() / (PI * t)
            };
            let w = 0.54 - 0.46 * (2.0 * PI * i as f64 / (n - 1) as f64).cos();
            w * sinc
        })
        .collect();
    let total: f64 = h.iter().sum();
    h.iter_mut().for_each(|x| *x /= total);
    h
}

/// The moving average in front of a [`LowPass::Cascade`] ([`LowPass::MovingAverage`]'s fields).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Average {
    pub taps: u32,
    pub stages: u32,
    pub decimation: u32,
}

/// The recursive low-pass behind a [`LowPass::Cascade`]'s average, at the output rate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Behind {
    /// [`LowPass::FirstOrder`].
    FirstOrder { time_constant_s: f64 },
    /// [`LowPass::SecondOrder`].
    SecondOrder {
        natural_frequency_hz: f64,
        damping: f64,
        form: SecondOrderForm,
    },
    /// [`LowPass::Butterworth`].
    Butterworth { order: u32, cutoff_hz: f64 },
}

impl Average {
    /// The average alone.
    pub fn lowpass(self) -> LowPass {
        LowPass::MovingAverage {
            taps: self.taps,
            stages: self.stages,
            decimation: self.decimation,
        }
    }
}

impl Behind {
    /// The low-pass alone.
    pub fn lowpass(self) -> LowPass {
        match self {
            Behind::FirstOrder { time_constant_s } => LowPass::FirstOrder { time_constant_s },
            Behind::SecondOrder {
                natural_frequency_hz,
                damping,
                form,
            } => LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                form,
            },
            Behind::Butterworth { order, cutoff_hz } => LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation: 1,
            },
        }
    }
}

/// How the second order's continuous prototype becomes a filter on the samples
/// ([`LowPass::SecondOrder`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SecondOrderForm {
    /// The poles mapped by `z = e^{s tau0}`, no zeros: an AR(2) on the increments.
    PoleMapped,
    /// The bilinear transform with the frequency prewarped: two zeros at Nyquist.
    Bilinear,
    /// The prototype run at an internal rate above the output's and read every so many
    /// samples: at the output rate an ARMA(2,1), the pole-mapped form's poles and the numerator
    /// `(1 + zero z^-1) / (1 + zero)`. 0 is [`SecondOrderForm::PoleMapped`]; the pole-mapped
    /// filter run `D` times faster gives the zero of [`sampled_zero`], from 0 at `D = 1` up to
    /// the continuous filter sampled every `tau0` (0.268 for a Butterworth at 20 Hz read at
    /// 200 Hz), and a bilinear biquad run 5 times faster about 0.30 (docs/gap.md, "Filters run
    /// faster than the output (session 43)").
    Sampled { zero: f64 },
}

/// Largest zero of [`SecondOrderForm::Sampled`] accepted (a bilinear biquad run twice as fast
/// as the output gives 0.49).
pub const MAX_ZERO: f64 = 0.9;

/// The decimation at which [`sampled_zero`] stands for the continuous filter (its zero within
/// 0.5% of the limit for a Butterworth at a tenth of the output rate).
pub const CONTINUOUS_DECIMATION: f64 = 64.0;

/// Autocorrelation terms below this fraction of the first are dropped (IIR filters).
const TAIL: f64 = 1e-15;
/// Longest autocorrelation kept (lags), whatever the filter.
pub const MAX_LAGS: usize = 2_000_000;
/// Largest moving-average length and number of stages accepted.
pub const MAX_TAPS: u32 = 100_000;
pub const MAX_STAGES: u32 = 4;
/// Largest decimation of a moving average (internal samples per output sample).
pub const MAX_DECIMATION: u32 = 1024;
/// Most taps of a [`LowPass::Fir`].
pub const MAX_FIR_TAPS: u32 = 4096;

impl LowPass {
    /// The two parts of a [`LowPass::Cascade`], front then back (None for the others).
    pub fn parts(&self) -> Option<(LowPass, LowPass)> {
        match *self {
            LowPass::Cascade { front, back } => Some((front.lowpass(), back.lowpass())),
            _ => None,
        }
    }

    /// `next` added to the unit's filter `current`: a moving average goes in front of a first
    /// or second order already there (or takes the front's place in a cascade), a first or
    /// second order behind a moving average (or in the back's place); otherwise `next`
    /// replaces `current`. The diagnosis names a cascade as two effects, one per part.
    pub fn compose(current: Option<LowPass>, next: LowPass) -> LowPass {
        let (front, back) = match current {
            Some(LowPass::Cascade { front, back }) => (Some(front), Some(back)),
            Some(lp) => (lp.as_average(), lp.as_behind()),
            None => (None, None),
        };
        match (next.as_average(), next.as_behind()) {
            (Some(front), _) => back.map_or(next, |back| LowPass::Cascade { front, back }),
            (_, Some(back)) => front.map_or(next, |front| LowPass::Cascade { front, back }),
            _ => next,
        }
    }

    /// A moving average as a cascade's front (None for the others).
    fn as_average(&self) -> Option<Average> {
        match *self {
            LowPass::MovingAverage {
                taps,
                stages,
                decimation,
            } => Some(Average {
                taps,
                stages,
                decimation,
            }),
            _ => None,
        }
    }

    /// A first or second order as a cascade's back (None for the others).
    fn as_behind(&self) -> Option<Behind> {
        match *self {
            LowPass::FirstOrder { time_constant_s } => Some(Behind::FirstOrder { time_constant_s }),
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                form,
            } => Some(Behind::SecondOrder {
                natural_frequency_hz,
                damping,
                form,
            }),
            // (at the output rate only: the back of a cascade runs at the output rate)
            LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation: 1,
            } => Some(Behind::Butterworth { order, cutoff_hz }),
            _ => None,
        }
    }

    /// Whether this is the bilinear second order ([`LowPass::SecondOrder`]).
    pub fn is_bilinear(&self) -> bool {
        matches!(
            self,
            LowPass::SecondOrder {
                form: SecondOrderForm::Bilinear,
                ..
            }
        )
    }

    /// The numerator taps `(b0, b1, b2)` of the second order, scaled to sum 1 (the poles' gain
    /// `1 - a1 - a2` is apart): `(1, 0, 0)` pole-mapped, `(1, 2, 1) / 4` bilinear,
    /// `(1, c, 0) / (1 + c)` sampled with the zero `c`. None for the other filters.
    pub fn numerator(&self) -> Option<[f64; 3]> {
        match *self {
            LowPass::SecondOrder { form, .. } => Some(match form {
                SecondOrderForm::PoleMapped => [1.0, 0.0, 0.0],
                SecondOrderForm::Bilinear => [0.25, 0.5, 0.25],
                SecondOrderForm::Sampled { zero: c } => [1.0 / (1.0 + c), c / (1.0 + c), 0.0],
            }),
            _ => None,
        }
    }

    /// Shape parameters the diagnosis fits (the moving average's stage count is a discrete
    /// choice and not counted).
    pub fn n_shape(&self) -> usize {
        match self {
            LowPass::SecondOrder {
                form: SecondOrderForm::Sampled { .. },
                ..
            } => 3,
            // the Butterworth's order as the FIR's taps: a discrete choice counted as one
            LowPass::SecondOrder { .. } | LowPass::Fir { .. } | LowPass::Butterworth { .. } => 2,
            LowPass::Cascade { front, back } => {
                front.lowpass().n_shape() + back.lowpass().n_shape()
            }
            _ => 1,
        }
    }

    /// A problem with the parameters, for model files and options (None: fine).
    pub fn check(&self, tau0_s: f64) -> Option<String> {
        match *self {
            LowPass::Fir {
                taps,
                cutoff_hz,
                decimation,
            } => {
                let nyquist = 0.5 * f64::from(decimation) / tau0_s;
                if !(1..=MAX_FIR_TAPS).contains(&taps) {
                    Some(format!("taps {taps} must be 1..={MAX_FIR_TAPS}"))
                } else if let Some(problem) = decimation_problem(decimation) {
                    Some(problem)
                } else if !(cutoff_hz > 0.0 && cutoff_hz < nyquist) {
                    Some(format!(
                        "cutoff {cutoff_hz} Hz must be above 0 and below the Nyquist frequency \
                         of the rate it runs at ({nyquist} Hz)"
                    ))
                } else {
                    None
                }
            }
            LowPass::Cascade { front, back } => front
                .lowpass()
                .check(tau0_s)
                .or_else(|| back.lowpass().check(tau0_s)),
            LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation,
            } => {
                let nyquist = 0.49 * f64::from(decimation) / tau0_s;
                if !(1..=MAX_BUTTERWORTH_ORDER).contains(&order) {
                    Some(format!("order {order} must be 1..={MAX_BUTTERWORTH_ORDER}"))
                } else if let Some(problem) = decimation_problem(decimation) {
                    Some(problem)
                } else if !(cutoff_hz > 0.0 && cutoff_hz < nyquist) {
                    Some(format!(
                        "cutoff {cutoff_hz} Hz must be above 0 and below 0.49 of the rate it \
                         runs at ({nyquist} Hz)"
                    ))
                } else {
                    None
                }
            }
            LowPass::FirstOrder { time_constant_s } | LowPass::ZeroPhase { time_constant_s } => {
                (!(time_constant_s > 0.0 && time_constant_s.is_finite()))
                    .then(|| format!("time constant {time_constant_s} must be > 0"))
            }
            LowPass::MovingAverage {
                taps,
                stages,
                decimation,
            } => {
                if !(1..=MAX_TAPS).contains(&taps) {
                    Some(format!("taps {taps} must be 1..={MAX_TAPS}"))
                } else if !(1..=MAX_STAGES).contains(&stages) {
                    Some(format!("stages {stages} must be 1..={MAX_STAGES}"))
                } else {
                    decimation_problem(decimation)
                }
            }
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                form,
            } => {
                let bilinear = form == SecondOrderForm::Bilinear;
                if let SecondOrderForm::Sampled { zero } = form {
                    if !(0.0..=MAX_ZERO).contains(&zero) {
                        return Some(format!("zero {zero} must be in [0, {MAX_ZERO}]"));
                    }
                }
                if !(natural_frequency_hz > 0.0 && natural_frequency_hz.is_finite()) {
                    Some(format!(
                        "natural frequency {natural_frequency_hz} must be > 0"
                    ))
                } else if bilinear && natural_frequency_hz * tau0_s >= 0.49 {
                    Some(format!(
                        "natural frequency {natural_frequency_hz} Hz must be below Nyquist \
                         (f tau0 must be < 0.49)"
                    ))
                } else if !bilinear && 2.0 * PI * natural_frequency_hz * tau0_s > 2.5 {
                    Some(format!(
                        "natural frequency {natural_frequency_hz} Hz is too close to Nyquist \
                         (2 pi f tau0 must be <= 2.5)"
                    ))
                } else if !(damping > 0.0 && damping <= 100.0) {
                    Some(format!("damping {damping} must be in (0, 100]"))
                } else {
                    None
                }
            }
        }
    }

    /// The AR(2) coefficients `(a1, a2)` of the recursive filters (the zero-phase filter's
    /// autocorrelation is that of two first-order stages in cascade: its `|H|^2` is theirs).
    pub fn ar2(&self, tau0_s: f64) -> Option<(f64, f64)> {
        match *self {
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                form: SecondOrderForm::Bilinear,
            } => {
                let k = (PI * natural_frequency_hz * tau0_s).tan();
                let d = 1.0 + 2.0 * damping * k + k * k;
                Some((
                    2.0 * (1.0 - k * k) / d,
                    -(1.0 - 2.0 * damping * k + k * k) / d,
                ))
            }
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                ..
            } => Some(mapped_ar2(natural_frequency_hz, damping, tau0_s)),
            LowPass::ZeroPhase { time_constant_s } => {
                let a = (-tau0_s / time_constant_s).exp();
                Some((2.0 * a, -a * a))
            }
            _ => None,
        }
    }

    /// The impulse response of a moving average of `taps` taps and `stages` stages (its
    /// internal rate's, for one run faster than the output), DC gain 1.
    /// Each stage is a running sum over a window of `m` (one addition and one subtraction
    /// per output tap instead of `m` products: a 750-tap Bartlett was a fifth of a filtered
    /// unit's diagnosis).
    pub fn fir(taps: u32, stages: u32) -> Vec<f64> {
        let m = taps.max(1) as usize;
        let scale = 1.0 / m as f64;
        let mut h = vec![1.0];
        for _ in 0..stages.max(1) {
            let len = h.len() + m - 1;
            let mut out = Vec::with_capacity(len);
            let mut window = 0.0;
            for k in 0..len {
                if let Some(&x) = h.get(k) {
                    window += x;
                }
                if k >= m {
                    window -= h.get(k - m).copied().unwrap_or(0.0);
                }
                out.push(window * scale);
            }
            h = out;
        }
        h
    }

    /// The impulse response of a moving average or a FIR at its internal rate (step
    /// `tau0_s / D`, `tau0_s` the output step; DC gain 1) with its decimation `D`: the average's
    /// [`Self::fir`], the FIR's [`fir_window_sinc`]. None for the other kinds.
    pub fn internal_response(&self, tau0_s: f64) -> Option<(Vec<f64>, usize)> {
        match *self {
            LowPass::MovingAverage {
                taps,
                stages,
                decimation,
            } => Some((Self::fir(taps, stages), decimation.max(1) as usize)),
            LowPass::Fir {
                taps,
                cutoff_hz,
                decimation,
            } => {
                let d = decimation.max(1);
                let h = fir_window_sinc(taps, cutoff_hz, tau0_s / f64::from(d));
                Some((h, d as usize))
            }
            _ => None,
        }
    }

    /// `sum_i h_i h_{i + D j}`, `j = 0, 1, ...` of [`Self::internal_response`]: the
    /// autocovariance of the output read every `D`-th sample for unit-variance white input at
    /// the internal rate (empty for the other kinds).
    fn internal_autocovariance(&self, tau0_s: f64) -> Vec<f64> {
        self.internal_response(tau0_s)
            .map_or_else(Vec::new, |(h, d)| autocovariance_every(&h, d))
    }

    /// The factor on the output step's white-rate standard deviation that gives the internal
    /// samples' for a filter run faster than the output (1 for the others): the output's
    /// autocovariances then sum to the output step's white variance, so `N` is the output's
    /// low-frequency white level, aliasing included, as the diagnosis fits it. For a CIC
    /// (taps a multiple of `D`) it is `sqrt(D)`: the mean of `D` internal samples has the
    /// output step's variance. `tau0_s` is the output step (a FIR's taps depend on it).
    pub fn internal_white_scale(&self, tau0_s: f64) -> f64 {
        match *self {
            LowPass::MovingAverage { decimation, .. } | LowPass::Fir { decimation, .. }
                if decimation > 1 =>
            {
                let r = self.internal_autocovariance(tau0_s);
                1.0 / two_sided_sum(&r).sqrt()
            }
            LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation,
            } if decimation > 1 => {
                let r = butterworth_internal_autocovariance(order, cutoff_hz, tau0_s, decimation);
                1.0 / two_sided_sum(&r).sqrt()
            }
            LowPass::Cascade { front, .. } => front.lowpass().internal_white_scale(tau0_s),
            _ => 1.0,
        }
    }

    /// The normalised autocorrelation `rho(k)`, `k = 0, 1, ...` of the filter's impulse
    /// response: the filtered white increments have autocovariance `N^2 tau0 rho(|k|)`, and
    /// `rho(0) + 2 sum_{k>0} rho(k) = 1` (DC gain 1).
    pub fn autocorrelation(&self, tau0_s: f64) -> Vec<f64> {
        match *self {
            LowPass::Cascade { front, back } => convolve_even(
                &front.lowpass().autocorrelation(tau0_s),
                &back.lowpass().autocorrelation(tau0_s),
            ),
            LowPass::FirstOrder { time_constant_s } => {
                let a = (-tau0_s / time_constant_s).exp();
                let r0 = (1.0 - a) / (1.0 + a);
                let n = lags_for(a.abs());
                let mut out = Vec::with_capacity(n);
                let mut v = r0;
                for _ in 0..n {
                    out.push(v);
                    v *= a;
                }
                out
            }
            // `sum_i h_i h_{i+k}` at D = 1, where DC gain 1 makes the two-sided total
            // `(sum h)^2 = 1`
            LowPass::MovingAverage { decimation, .. } | LowPass::Fir { decimation, .. } => {
                // The impulse response at the internal rate, its autocorrelation read at every
                // `decimation`-th lag (the output samples are every D-th internal one), scaled
                // to a two-sided total of 1: the output's low-frequency white level is then the
                // fitted N, aliasing included. A CIC (taps a multiple of D) needs no scaling
                // beyond D: its zeros at the output rate's multiples leave nothing to alias.
                let r = self.internal_autocovariance(tau0_s);
                if decimation <= 1 {
                    return r;
                }
                let total = two_sided_sum(&r);
                r.iter().map(|v| v / total).collect()
            }
            LowPass::SecondOrder { .. } | LowPass::ZeroPhase { .. } => {
                let (a1, a2) = self.ar2(tau0_s).unwrap_or((0.0, 0.0));
                let b = self.numerator().unwrap_or([1.0, 0.0, 0.0]);
                Biquad { a1, a2, b }.autocorrelation()
            }
            // the sections' autocorrelations convolved (a cascade's); run faster than the output,
            // read every D-th lag and scaled to a two-sided total of 1, as the FIR's
            LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation,
            } => {
                if decimation <= 1 {
                    return butterworth_sections(order, cutoff_hz, tau0_s)
                        .iter()
                        .map(Biquad::autocorrelation)
                        .reduce(|acc, r| convolve_even(&acc, &r))
                        .unwrap_or_else(|| vec![1.0]);
                }
                let r = butterworth_internal_autocovariance(order, cutoff_hz, tau0_s, decimation);
                let total = two_sided_sum(&r);
                r.iter().map(|v| v / total).collect()
            }
        }
    }

    /// AVAR (u^2/s^2) of white rate noise of unit `N` (u/sqrt(s)) through the filter at each
    /// cluster size of `ms`: `(4 S(m) - S(2m)) / (2 m^2 tau0^2)` with
    /// `S(n) = tau0 (n rho_0 + 2 sum_{0<k<n} (n - k) rho_k)` the variance of a sum of `n`
    /// filtered increments (docs/gap.md, "Low-pass filters beyond first order").
    pub fn white_rate_avar(&self, tau0_s: f64, ms: &[u64]) -> Vec<f64> {
        avar_from_autocovariance(&self.autocorrelation(tau0_s), tau0_s, ms)
    }

    /// AVAR (u^2/s^2) of flicker rate noise of unit `B` through the filter at each cluster
    /// size of `ms`. The unit's filter smooths all of its rate noise, and where the filtered
    /// white rate is small (the shortest taus of a strong filter) the flicker floor's share is
    /// not. With the flicker's generalised phase covariance `G_B(t) = t^2 ln|t| / (2 pi)` (lags
    /// in samples; docs/theory.md section 4) and the filter's two-sided autocorrelation `r_q`,
    /// the filtered phase has `F(t) = sum_q r_q G_B(t - q)`, and the second difference's variance
    /// gives `AVAR(m) = (6 F(0) - 8 F(m) + 2 F(2m)) / (2 m^2)` (without the filter,
    /// `2 ln 2 / pi`). Beyond 200 memories the filter changes it by less than 1e-4 relative
    /// (`(sigma_r / m)^2`, `sigma_r^2 = sum q^2 r_q`), and the unfiltered value is returned.
    pub fn flicker_rate_avar(&self, tau0_s: f64, ms: &[u64]) -> Vec<f64> {
        let plain = 2.0 * std::f64::consts::LN_2 / PI;
        let rho = self.autocorrelation(tau0_s);
        // one side, cut at 1e-9 of rho_0, renormalised to a total of 1 over both sides
        let cut = rho
            .iter()
            .rposition(|v| v.abs() > 1e-9 * rho[0].abs())
            .map_or(1, |i| i + 1);
        let one: Vec<f64> = rho[..cut].to_vec();
        let total = two_sided_sum(&one);
        let m_exact = 200.0 * (self.memory_s(tau0_s) / tau0_s).max(cut as f64);
        // F(t) at whole lags t, with G_B read from the table where it reaches: F(0) needs
        // lags up to the cut even when every m is beyond m_exact (the table is per thread, and
        // a fresh one holds a single entry)
        let longest = ms
            .iter()
            .filter(|&&m| m as f64 <= m_exact)
            .max()
            .map_or(cut, |&m| 2 * m as usize + cut);
        flicker_phase_table(longest, |table| {
            let g = |t: usize| match table {
                Some(tab) => tab[t],
                None => flicker_phase(t as f64),
            };
            let f = |t: usize| -> f64 {
                let mut s = one[0] * g(t);
                for (q, r) in one.iter().enumerate().skip(1) {
                    s += r * (g(t.abs_diff(q)) + g(t + q));
                }
                s / total
            };
            let f0 = f(0);
            ms.iter()
                .map(|&m| {
                    let mf = m as f64;
                    if mf > m_exact {
                        plain
                    } else {
                        let m = m as usize;
                        ((6.0 * f0 - 8.0 * f(m) + 2.0 * f(2 * m)) / (2.0 * mf * mf)).max(0.0)
                    }
                })
                .collect()
        })
    }

    /// Power gain `|H(f)|^2` at `frequency_hz`.
    pub fn power_gain(&self, tau0_s: f64, frequency_hz: f64) -> f64 {
        let w = 2.0 * PI * frequency_hz * tau0_s;
        match *self {
            // `|sum_n h_n e^{-i x n}|^2` at the internal rate, folded as the average's below
            LowPass::Fir { .. } => {
                let (h, d) = self.internal_response(tau0_s).unwrap_or((vec![1.0], 1));
                folded_gain(d, w, |x| {
                    let (re, im) = h.iter().enumerate().fold((0.0, 0.0), |(re, im), (n, c)| {
                        let a = x * n as f64;
                        (re + c * a.cos(), im - c * a.sin())
                    });
                    re * re + im * im
                })
            }
            LowPass::Cascade { front, back } => {
                front.lowpass().power_gain(tau0_s, frequency_hz)
                    * back.lowpass().power_gain(tau0_s, frequency_hz)
            }
            LowPass::FirstOrder { time_constant_s } => first_order_gain(time_constant_s, tau0_s, w),
            LowPass::ZeroPhase { time_constant_s } => {
                first_order_gain(time_constant_s, tau0_s, w).powi(2)
            }
            LowPass::MovingAverage {
                taps,
                stages,
                decimation,
            } => {
                // at the internal rate `|sin(M x / 2) / (M sin(x / 2))|^(2 S)`; read every D-th
                // sample, the D images `x = (w + 2 pi a) / D` fold onto `w`, scaled as the
                // autocorrelation is (`sum_j R(D j) = sum_a |H(2 pi a / D)|^2 / D`, Poisson)
                let m = taps.max(1) as f64;
                folded_gain(decimation.max(1) as usize, w, |x| {
                    let den = m * (x / 2.0).sin();
                    let g = if den.abs() < 1e-300 {
                        1.0
                    } else {
                        (m * x / 2.0).sin() / den
                    };
                    (g * g).powi(stages.max(1) as i32)
                })
            }
            LowPass::SecondOrder { .. } => {
                // for the bilinear form the numerator's gain is cos^4(w / 2), its zeros at
                // Nyquist
                let (a1, a2) = self.ar2(tau0_s).unwrap_or((0.0, 0.0));
                let b = self.numerator().unwrap_or([1.0, 0.0, 0.0]);
                Biquad { a1, a2, b }.power_gain(w)
            }
            // the closed form of the bilinear Butterworth (its sections' product) at the rate it
            // runs at, its images folded as the average's
            LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation,
            } => {
                let d = decimation.max(1);
                let k = (PI * cutoff_hz * tau0_s / f64::from(d)).tan();
                folded_gain(d as usize, w, |x| {
                    let r = (x / 2.0).tan() / k;
                    if r.is_finite() {
                        1.0 / (1.0 + r.abs().powi(2 * order.max(1) as i32))
                    } else {
                        0.0
                    }
                })
            }
        }
    }

    /// Its memory in s: the delay beyond which the filtered white rate is white again (for
    /// grids, plots and the taus the diagnosis's covariance is fitted beyond): the time
    /// constant, the moving average's span; for the second order its slowest pole's time
    /// constant, `1 / (zeta w)` while underdamped (the envelope's decay) and
    /// `(zeta + sqrt(zeta^2 - 1)) / w` when overdamped (the slow real pole
    /// `w (zeta - sqrt(zeta^2 - 1))`; about `2 zeta / w` at large damping, the first order
    /// it tends to).
    pub fn memory_s(&self, tau0_s: f64) -> f64 {
        match *self {
            // its span
            LowPass::Fir {
                taps, decimation, ..
            } => f64::from(taps) * tau0_s / f64::from(decimation.max(1)),
            // the sections' slower poles' time constants, one after the other, at the rate it
            // runs at
            LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation,
            } => {
                let step = tau0_s / f64::from(decimation.max(1));
                step * butterworth_sections(order, cutoff_hz, step)
                    .iter()
                    .map(Biquad::memory_steps)
                    .sum::<f64>()
            }
            // the back's memory of the front's output
            LowPass::Cascade { front, back } => {
                front.lowpass().memory_s(tau0_s) + back.lowpass().memory_s(tau0_s)
            }
            LowPass::FirstOrder { time_constant_s } | LowPass::ZeroPhase { time_constant_s } => {
                time_constant_s
            }
            LowPass::MovingAverage {
                taps,
                stages,
                decimation,
            } => (taps * stages) as f64 * tau0_s / decimation.max(1) as f64,
            LowPass::SecondOrder {
                form: SecondOrderForm::Bilinear,
                ..
            } => {
                // the slower pole's time constant, from its modulus
                let (a1, a2) = self.ar2(tau0_s).unwrap_or((0.0, 0.0));
                let slow = slow_pole(a1, a2);
                if slow > 0.0 && slow < 1.0 {
                    -tau0_s / slow.ln()
                } else {
                    tau0_s
                }
            }
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                ..
            } => {
                let w = 2.0 * PI * natural_frequency_hz;
                if damping <= 1.0 {
                    1.0 / (damping.max(0.01) * w)
                } else {
                    (damping + (damping * damping - 1.0).sqrt()) / w
                }
            }
        }
    }
}

/// `sum_i h_i h_{i + step j}`, `j = 0, 1, ...`: the autocovariance of the impulse response `h`
/// for unit-variance white input, read every `step`-th lag.
fn autocovariance_every(h: &[f64], step: usize) -> Vec<f64> {
    if step == 0 {
        return Vec::new();
    }
    (0..h.len())
        .step_by(step)
        .map(|k| h.iter().zip(&h[k..]).map(|(a, b)| a * b).sum())
        .collect()
}

/// The power gain at `w` (radians per output sample) of a filter run at `d` times the output
/// rate with internal gain `internal(x)` (`x` radians per internal sample) and read every `d`-th
/// sample: the `d` images `x = (w + 2 pi a) / d` folded onto `w` and scaled as its
/// autocorrelation is, `sum_a |H((w + 2 pi a) / d)|^2 / sum_a |H(2 pi a / d)|^2`
/// (`sum_j R(d j) = sum_a |H(2 pi a / d)|^2 / d`, Poisson); the internal gain itself at `d = 1`.
fn folded_gain(d: usize, w: f64, internal: impl Fn(f64) -> f64) -> f64 {
    if d <= 1 {
        return internal(w);
    }
    let folded = |w: f64| {
        (0..d)
            .map(|a| internal((w + 2.0 * PI * a as f64) / d as f64))
            .sum::<f64>()
    };
    folded(w) / folded(0.0)
}

/// The autocorrelation of two filters in cascade from theirs, both given from lag 0 and even:
/// `c_k = sum_j a_|j| b_|k - j|` over every lag `j` of either sign, `k = 0, 1, ...` up to the
/// sum of their lengths (the autocorrelation of `h_a * h_b` is that of `h_a` convolved with that
/// of `h_b`). Two totals of 1 give a total of 1.
fn convolve_even(a: &[f64], b: &[f64]) -> Vec<f64> {
    // the shorter one on the outer loop
    let (a, b) = if a.len() <= b.len() { (a, b) } else { (b, a) };
    let n = a.len() + b.len() - 1;
    let at = |k: i64| b.get(k.unsigned_abs() as usize).copied().unwrap_or(0.0);
    (0..n as i64)
        .map(|k| {
            (-(a.len() as i64 - 1)..a.len() as i64)
                .map(|j| a[j.unsigned_abs() as usize] * at(k - j))
                .sum()
        })
        .collect()
}

/// `r_0 + 2 sum_{k>0} r_k`: the total over both sides of an even sequence given from lag 0 (an
/// autocorrelation, symmetric weights).
pub fn two_sided_sum(r: &[f64]) -> f64 {
    r[0] + 2.0 * r[1..].iter().sum::<f64>()
}

/// The flicker rate's generalised phase covariance `G_B(t) = t^2 ln|t| / (2 pi)` (0 at 0; lags
/// in samples, [`LowPass::flicker_rate_avar`]).
fn flicker_phase(t: f64) -> f64 {
    if t == 0.0 {
        0.0
    } else {
        t * t * t.abs().ln() / (2.0 * PI)
    }
}

/// Longest table of [`flicker_phase`] kept per thread (lags; 8 bytes each).
const FLICKER_TABLE_MAX: usize = 1 << 22;

thread_local! {
    /// [`flicker_phase`] at the lags `0, 1, 2, ...`: the flicker column sums it over every lag of
    /// a filter's autocorrelation at three points per cluster size, thousands of times in one
    /// diagnosis, and a logarithm per term was most of that diagnosis's time (docs/gap.md,
    /// "Speed (session 17)"). The same values as the function, bit for bit.
    static FLICKER_TABLE: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// Runs `body` with the thread's table of [`flicker_phase`] grown to hold lags `0..=longest`, or
/// with None when that is beyond [`FLICKER_TABLE_MAX`] (the function is then evaluated).
fn flicker_phase_table<T>(longest: usize, body: impl FnOnce(Option<&[f64]>) -> T) -> T {
    if longest >= FLICKER_TABLE_MAX {
        return body(None);
    }
    FLICKER_TABLE.with(|cell| {
        let mut table = cell.borrow_mut();
        for k in table.len()..=longest {
            table.push(flicker_phase(k as f64));
        }
        body(Some(&table[..]))
    })
}

/// The modulus of the slower pole of `y_k = a1 y_{k-1} + a2 y_{k-2} + ...`: the larger root of
/// `z^2 - a1 z - a2` (both of modulus `sqrt(-a2)` when complex), which sets how fast its
/// autocorrelation and its memory of a start decay.
pub fn slow_pole(a1: f64, a2: f64) -> f64 {
    let disc = a1 * a1 + 4.0 * a2;
    if disc < 0.0 {
        (-a2).sqrt()
    } else {
        (a1.abs() + disc.sqrt()) / 2.0
    }
}

/// The AR(2) coefficients `(a1, a2)` of the continuous prototype's poles
/// `s = w (-zeta +- sqrt(zeta^2 - 1))`, `w = 2 pi f_n`, mapped by `z = e^{s step}`:
/// `a1 = z1 + z2`, `a2 = -z1 z2`.
pub fn mapped_ar2(natural_frequency_hz: f64, damping: f64, step_s: f64) -> (f64, f64) {
    let w = 2.0 * PI * natural_frequency_hz;
    if damping < 1.0 {
        let r = (-damping * w * step_s).exp();
        let th = w * step_s * (1.0 - damping * damping).sqrt();
        (2.0 * r * th.cos(), -r * r)
    } else {
        let d = (damping * damping - 1.0).sqrt();
        let p1 = (w * (-damping + d) * step_s).exp();
        let p2 = (w * (-damping - d) * step_s).exp();
        (p1 + p2, -p1 * p2)
    }
}

/// The zero `c` of the second order run at the internal step `h = tau0 / decimation` and read
/// every `decimation`-th sample ([`SecondOrderForm::Sampled`]), as the MA(1) numerator
/// `(1 + c z^-1) / (1 + c)` beside the poles mapped at `tau0`.
///
/// The AR(2) at step `h` with poles `z_i = e^{s_i h}` has the autocorrelation
/// `rho(k) = (z1 (1 - z2^2) z1^k - z2 (1 - z1^2) z2^k) / ((z1 - z2)(1 + z1 z2))` (Box, Jenkins
/// and Reinsel, "Time Series Analysis", section 3.2.4), read at the lags `k = D j` as
/// `R(j) = sum_i w_i e^{s_i tau0 j}`: a sum of the powers of the poles mapped at `tau0` for all
/// `j >= 0`, which is the autocorrelation of an ARMA(2,1). Its MA part `u_k = y_k - a1 y_{k-1} -
/// a2 y_{k-2}` has the autocovariances `gamma_u(l) = sum_{p,q} phi_p phi_q R(l + p - q)`,
/// `phi = (1, -a1, -a2)`, zero beyond `l = 1`; with `r = gamma_u(1) / gamma_u(0)` the
/// invertible zero is `c = (1 - sqrt(1 - 4 r^2)) / (2 r)`. At `decimation = 1` it is 0; as the
/// decimation grows it tends to the continuous filter sampled every `tau0` (0.268 for a
/// Butterworth at 20 Hz read at 200 Hz).
pub fn sampled_zero(natural_frequency_hz: f64, damping: f64, tau0_s: f64, decimation: f64) -> f64 {
    use rustfft::num_complex::Complex64 as C;
    // critical damping's double pole: nudged apart (the weights' common factor 1 / (z1 - z2))
    let zeta = if (damping - 1.0).abs() < 1e-6 {
        1.0 + 1e-6
    } else {
        damping
    };
    let w = 2.0 * PI * natural_frequency_hz;
    let root = C::new(zeta * zeta - 1.0, 0.0).sqrt();
    let (s1, s2) = (w * (-zeta + root), w * (-zeta - root));
    let h = tau0_s / decimation.max(1.0);
    let (z1, z2) = ((s1 * h).exp(), (s2 * h).exp());
    let (w1, w2) = (z1 * (1.0 - z2 * z2), -z2 * (1.0 - z1 * z1));
    let (e1, e2) = ((s1 * tau0_s).exp(), (s2 * tau0_s).exp());
    let r = |j: i64| -> f64 {
        let j = j.unsigned_abs() as i32;
        ((w1 * e1.powi(j) + w2 * e2.powi(j)) / (z1 - z2)).re
    };
    let (a1, a2) = mapped_ar2(natural_frequency_hz, zeta, tau0_s);
    let phi = [1.0, -a1, -a2];
    let gamma = |l: i64| -> f64 {
        let mut g = 0.0;
        for (p, fp) in phi.iter().enumerate() {
            for (q, fq) in phi.iter().enumerate() {
                g += fp * fq * r(l + p as i64 - q as i64);
            }
        }
        g
    };
    let g0 = gamma(0);
    if g0.is_nan() || g0 <= 0.0 {
        return 0.0;
    }
    let ratio = (gamma(1) / g0).clamp(-0.5, 0.5);
    if ratio.abs() < 1e-12 {
        0.0
    } else {
        (1.0 - (1.0 - 4.0 * ratio * ratio).max(0.0).sqrt()) / (2.0 * ratio)
    }
}

/// Lags kept for a geometric decay of ratio `r`.
fn lags_for(r: f64) -> usize {
    if !(r > 0.0 && r < 1.0) {
        return 1;
    }
    ((TAIL.ln() / r.ln()).ceil() as usize + 2).min(MAX_LAGS)
}

fn first_order_gain(time_constant_s: f64, tau0_s: f64, w: f64) -> f64 {
    let a = (-tau0_s / time_constant_s).exp();
    let s = (w / 2.0).sin();
    (1.0 - a) * (1.0 - a) / ((1.0 - a) * (1.0 - a) + 4.0 * a * s * s)
}

/// AVAR at each cluster size of `ms` of a stationary sequence whose lag-`k` autocovariance is
/// `cov[k]` (zero beyond the slice; `cov` not empty): `(4 S(m) - S(2m)) / (2 m^2 tau0^2)` with
/// `S(n)` the variance of a sum of `n` of its samples scaled by `tau0_s` ([`SumVariance`]).
/// With `tau0_s = 1` it is the AVAR of averages of `m` samples, in the samples' units squared.
pub fn avar_from_autocovariance(cov: &[f64], tau0_s: f64, ms: &[u64]) -> Vec<f64> {
    let s = SumVariance::new(cov, tau0_s);
    ms.iter()
        .map(|&m| {
            let mf = m as f64;
            ((4.0 * s.at(m) - s.at(2 * m)) / (2.0 * mf * mf * tau0_s * tau0_s)).max(0.0)
        })
        .collect()
}

/// `S(n) = tau0 (n c_0 + 2 sum_{0<k<n} (n - k) c_k)`: the variance of a sum of `n` samples of a
/// stationary sequence whose lag-`k` autocovariance is `cov[k]` (zero beyond the slice; `cov`
/// not empty), scaled by `tau0_s`. Prefix sums of `c_k` and `k c_k` make each `S(n)` one
/// lookup.
pub struct SumVariance {
    tau0_s: f64,
    c0: f64,
    /// `sum_{0<k<=i} c_k` and `sum_{0<k<=i} k c_k` at index `i`.
    p0: Vec<f64>,
    p1: Vec<f64>,
}

impl SumVariance {
    pub fn new(cov: &[f64], tau0_s: f64) -> Self {
        let mut p0 = vec![0.0; cov.len()];
        let mut p1 = vec![0.0; cov.len()];
        for k in 1..cov.len() {
            p0[k] = p0[k - 1] + cov[k];
            p1[k] = p1[k - 1] + k as f64 * cov[k];
        }
        SumVariance {
            tau0_s,
            c0: cov[0],
            p0,
            p1,
        }
    }

    /// `S(n)`.
    pub fn at(&self, n: u64) -> f64 {
        let kk = (n.saturating_sub(1) as usize).min(self.p0.len() - 1);
        let nf = n as f64;
        self.tau0_s * (nf * self.c0 + 2.0 * (nf * self.p0[kk] - self.p1[kk]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::terms;

    /// `rho_0 + 2 sum_k rho_k cos(w k)`: the power spectrum of the even sequence `rho` at `w`
    /// radians per sample (Wiener-Khinchin).
    fn transform(rho: &[f64], w: f64) -> f64 {
        rho[0]
            + 2.0
                * rho[1..]
                    .iter()
                    .enumerate()
                    .map(|(k, r)| r * (w * (k + 1) as f64).cos())
                    .sum::<f64>()
    }

    /// Cluster sizes all beyond 200 memories, asked first on a fresh thread (whose flicker
    /// table is empty): the unfiltered flicker AVAR `2 ln 2 / pi`, not an index out of the
    /// table (it panicked there in session 22, family_gap's rlg on a quantization-limited cut).
    #[test]
    fn flicker_beyond_the_filter_memory_on_a_fresh_thread_is_the_plain_value() {
        let lp = LowPass::FirstOrder {
            time_constant_s: 0.02,
        };
        let got = std::thread::spawn(move || lp.flicker_rate_avar(0.004, &[50_000, 400_000]))
            .join()
            .expect("no panic");
        let plain = 2.0 * std::f64::consts::LN_2 / PI;
        assert!(
            got.iter().all(|v| (v / plain - 1.0).abs() < 1e-12),
            "{got:?}"
        );
    }

    /// The memory is the slowest pole's time constant: the autocorrelation's decay per lag far
    /// out is `exp(-tau0 / memory)`, overdamped (where `1 / (zeta w)` was 50 times too short at
    /// `zeta = 5`) and underdamped (the envelope) alike.
    #[test]
    fn second_order_memory_is_its_slowest_pole() {
        let tau0 = 0.002;
        for (f0, zeta) in [(35.0, 5.0), (20.0, 2.0), (10.0, 1.2), (8.0, 0.3)] {
            let lp = LowPass::SecondOrder {
                natural_frequency_hz: f0,
                damping: zeta,
                form: SecondOrderForm::PoleMapped,
            };
            let r = lp.autocorrelation(tau0);
            let mem = lp.memory_s(tau0);
            let k = (5.0 * mem / tau0).ceil() as usize;
            // one period of an underdamped ringing apart, the envelope's ratio
            let period = if zeta < 1.0 {
                (1.0 / (f0 * (1.0 - zeta * zeta).sqrt() * tau0)).round() as usize
            } else {
                1
            };
            let decay = (r[k + period] / r[k]).abs().ln() / period as f64;
            let want = -tau0 / mem;
            assert!(
                (decay / want - 1.0).abs() < 0.02,
                "{lp:?}: {decay} vs {want}"
            );
        }
        // a heavily damped second order is a first order of time constant ~ 2 zeta / w
        let lp = LowPass::SecondOrder {
            natural_frequency_hz: 35.0,
            damping: 5.0,
            form: SecondOrderForm::PoleMapped,
        };
        let t = 2.0 * 5.0 / (2.0 * PI * 35.0);
        assert!((lp.memory_s(tau0) / t - 1.0).abs() < 0.02);
    }

    /// The bilinear biquad against its own recursion run by hand: the autocorrelation of the
    /// impulse response of `y_k = a1 y_{k-1} + a2 y_{k-2} + K^2/D (x_k + 2 x_{k-1} + x_{k-2})`
    /// (scipy's `butter(2, f_c)` at `zeta = 1/sqrt 2`), DC gain 1, `|H(f_c)|^2 = 1/2` exactly
    /// for the prewarped Butterworth and zero gain at Nyquist (Parseval: `power_gain_parseval`).
    #[test]
    fn the_bilinear_second_order_is_the_biquad_it_names() {
        let tau0 = 0.005;
        for (fc, zeta) in [
            (20.0, std::f64::consts::FRAC_1_SQRT_2),
            (40.0, 0.4),
            (5.0, 2.0),
        ] {
            let lp = LowPass::SecondOrder {
                natural_frequency_hz: fc,
                damping: zeta,
                form: SecondOrderForm::Bilinear,
            };
            let k = (PI * fc * tau0).tan();
            let d = 1.0 + 2.0 * zeta * k + k * k;
            let (b, a1, a2) = (
                k * k / d,
                2.0 * (1.0 - k * k) / d,
                -(1.0 - 2.0 * zeta * k + k * k) / d,
            );
            let mut h = vec![0.0f64; 20_000];
            for i in 0..h.len() {
                let x = |j: usize| if j == 0 { 1.0 } else { 0.0 };
                let mut y = b * x(i);
                if i >= 1 {
                    y += a1 * h[i - 1] + 2.0 * b * x(i - 1);
                }
                if i >= 2 {
                    y += a2 * h[i - 2] + b * x(i - 2);
                }
                h[i] = y;
            }
            assert!((h.iter().sum::<f64>() - 1.0).abs() < 1e-9, "DC gain");
            let r = lp.autocorrelation(tau0);
            for lag in [0usize, 1, 2, 3, 7, 40] {
                let want: f64 = h.iter().zip(&h[lag..]).map(|(x, y)| x * y).sum();
                assert!(
                    (r[lag] - want).abs() <= 1e-9 * want.abs().max(1e-6 * r[0]),
                    "{lp:?} lag {lag}: {} vs {want}",
                    r[lag]
                );
            }
            let s = r[0] + 2.0 * r[1..].iter().sum::<f64>();
            assert!((s - 1.0).abs() < 1e-9, "{lp:?}: {s}");
            assert!(lp.power_gain(tau0, 0.5 / tau0) < 1e-20, "zero at Nyquist");
        }
        let butter = LowPass::SecondOrder {
            natural_frequency_hz: 20.0,
            damping: std::f64::consts::FRAC_1_SQRT_2,
            form: SecondOrderForm::Bilinear,
        };
        assert!((butter.power_gain(tau0, 20.0) - 0.5).abs() < 1e-12);
        // Its memory: the poles' modulus, |p|^2 = -a2, per lag.
        let k = (PI * 20.0 * tau0).tan();
        let a2 = -(1.0 - 2.0f64.sqrt() * k + k * k) / (1.0 + 2.0f64.sqrt() * k + k * k);
        let want = -tau0 / (-a2).sqrt().ln();
        assert!((butter.memory_s(tau0) / want - 1.0).abs() < 1e-12);
    }

    /// The sampled form with the zero of [`sampled_zero`] against the filter it names, run by
    /// hand: the pole-mapped recursion at
    /// the internal step `tau0 / D`, its impulse response's autocorrelation read at the lags
    /// `D k` and scaled to a total of 1. Under- and overdamped, D 2, 5 and 12, lags 0-60 within
    /// 1e-8 of the first; the zero 0 at D = 1; and at D = 64 the
    /// continuous filter sampled every `tau0` (its autocorrelation in closed form,
    /// `e^{-zeta w t} (cos w_d t + zeta / sqrt(1 - zeta^2) sin w_d t)`), within 1% at lag 1.
    #[test]
    fn the_sampled_second_order_is_the_filter_read_every_d_samples() {
        use std::f64::consts::FRAC_1_SQRT_2;
        let tau0 = 0.005;
        for (fc, zeta, d) in [
            (20.0, FRAC_1_SQRT_2, 5usize),
            (40.0, 0.3, 2),
            (8.0, 2.5, 12),
        ] {
            let lp = LowPass::SecondOrder {
                natural_frequency_hz: fc,
                damping: zeta,
                form: SecondOrderForm::Sampled {
                    zero: sampled_zero(fc, zeta, tau0, d as f64),
                },
            };
            let (a1, a2) = mapped_ar2(fc, zeta, tau0 / d as f64);
            let mut h = vec![0.0f64; 400_000];
            for i in 0..h.len() {
                let mut y = if i == 0 { 1.0 } else { 0.0 };
                if i >= 1 {
                    y += a1 * h[i - 1];
                }
                if i >= 2 {
                    y += a2 * h[i - 2];
                }
                h[i] = y;
            }
            let acf = |lag: usize| -> f64 { h.iter().zip(&h[lag..]).map(|(x, y)| x * y).sum() };
            let read: Vec<f64> = (0..400).map(|k| acf(k * d)).collect();
            let total = read[0] + 2.0 * read[1..].iter().sum::<f64>();
            let r = lp.autocorrelation(tau0);
            for lag in [0usize, 1, 2, 3, 10, 60] {
                let want = read[lag] / total;
                let got = r.get(lag).copied().unwrap_or(0.0);
                assert!(
                    (got - want).abs() <= 1e-8 * r[0],
                    "{lp:?} lag {lag}: {got} vs {want}"
                );
            }
        }
        assert!(sampled_zero(20.0, FRAC_1_SQRT_2, tau0, 1.0).abs() < 1e-9);
        let (zeta, w) = (FRAC_1_SQRT_2, 2.0 * PI * 20.0);
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let cont = |t: f64| {
            (-zeta * w * t).exp()
                * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin())
        };
        let lp = LowPass::SecondOrder {
            natural_frequency_hz: 20.0,
            damping: zeta,
            form: SecondOrderForm::Sampled {
                zero: sampled_zero(20.0, zeta, tau0, CONTINUOUS_DECIMATION),
            },
        };
        let r = lp.autocorrelation(tau0);
        let (got, want) = (r[1] / r[0], cont(tau0) / cont(0.0));
        assert!((got / want - 1.0).abs() < 0.01, "{got} vs {want}");
    }

    /// The generic form reproduces the first-order closed form of `terms`.
    #[test]
    fn first_order_matches_closed_form() {
        let tau0 = 0.004;
        let lp = LowPass::FirstOrder {
            time_constant_s: 0.02,
        };
        let ms = [1u64, 2, 3, 5, 8, 13, 40, 1000, 100_000];
        for (m, v) in ms.iter().zip(lp.white_rate_avar(tau0, &ms)) {
            let want = terms::filtered_white_rate_avar(1.0, 0.02, tau0, *m);
            assert!((v / want - 1.0).abs() < 1e-9, "m {m}: {v} vs {want}");
        }
    }

    /// Autocorrelations sum to 1 (DC gain 1), and the zero-phase filter's equals two
    /// first-order stages in cascade (computed by brute force from the impulse response).
    #[test]
    fn autocorrelations_sum_to_one() {
        let tau0 = 0.004;
        for lp in [
            LowPass::MovingAverage {
                taps: 7,
                stages: 1,
                decimation: 1,
            },
            LowPass::MovingAverage {
                taps: 16,
                stages: 2,
                decimation: 1,
            },
            LowPass::MovingAverage {
                taps: 7,
                stages: 3,
                decimation: 3,
            },
            LowPass::SecondOrder {
                natural_frequency_hz: 5.0,
                damping: 0.3,
                form: SecondOrderForm::PoleMapped,
            },
            LowPass::SecondOrder {
                natural_frequency_hz: 5.0,
                damping: 2.0,
                form: SecondOrderForm::PoleMapped,
            },
            LowPass::ZeroPhase {
                time_constant_s: 0.02,
            },
            LowPass::Cascade {
                front: Average {
                    taps: 8,
                    stages: 3,
                    decimation: 8,
                },
                back: Behind::SecondOrder {
                    natural_frequency_hz: 40.0,
                    damping: 0.7,
                    form: SecondOrderForm::Bilinear,
                },
            },
        ] {
            let r = lp.autocorrelation(tau0);
            let s = r[0] + 2.0 * r[1..].iter().sum::<f64>();
            assert!((s - 1.0).abs() < 1e-9, "{lp:?}: {s}");
        }
        // brute force: impulse response of two cascaded first-order stages
        let a: f64 = (-0.004f64 / 0.02).exp();
        let h: Vec<f64> = (0..600)
            .map(|k| (1.0 - a).powi(2) * (k as f64 + 1.0) * a.powi(k))
            .collect();
        let zp = LowPass::ZeroPhase {
            time_constant_s: 0.02,
        }
        .autocorrelation(tau0);
        for k in [0usize, 1, 5, 30] {
            let want: f64 = h.iter().zip(&h[k..]).map(|(x, y)| x * y).sum();
            assert!((zp[k] / want - 1.0).abs() < 1e-9, "lag {k}");
        }
    }

    /// A moving average of M taps on white rate: for m >= M the AVAR is exactly
    /// `N^2/tau - N^2 (M^2 - 1) / (2 M m^2 tau0)` (sum of k rho_k = (M^2 - 1) / (6 M)), and at
    /// m = 1 it is `(1 - rho_1) / tau0` with `rho_1 = (M - 1) / M^2`.
    #[test]
    fn moving_average_closed_forms() {
        let tau0 = 0.01;
        let mm = 9u32;
        let lp = LowPass::MovingAverage {
            taps: mm,
            stages: 1,
            decimation: 1,
        };
        let ms = [1u64, 9, 20, 500];
        let v = lp.white_rate_avar(tau0, &ms);
        let m2 = (mm * mm) as f64;
        let rho1 = (mm as f64 - 1.0) / m2;
        assert!((v[0] / ((1.0 / mm as f64 - rho1) / tau0) - 1.0).abs() < 1e-12);
        for (i, &m) in ms.iter().enumerate().skip(1) {
            let mf = m as f64;
            let want = 1.0 / (mf * tau0) - (m2 - 1.0) / (2.0 * mm as f64 * mf * mf * tau0);
            assert!((v[i] / want - 1.0).abs() < 1e-12, "m {m}");
        }
    }

    /// The flicker AVAR through each filter: the plain floor far beyond its memory, reduced
    /// within it.
    #[test]
    fn flicker_through_filters() {
        // Far beyond the memory the flicker floor is untouched; at one sample a long filter
        // takes most of it out; the two-tap average by hand: r = (1/4, 1/2, 1/4), m = 1:
        // F(0) = G(1)/2 = 0, F(1) = G(1)/2 + G(2)/4 = ln2/(2 pi), F(2) = (G(1) + 2 G(2) + G(3))/4.
        let plain = 2.0 * std::f64::consts::LN_2 / PI;
        let tau0 = 0.004;
        for lp in [
            LowPass::FirstOrder {
                time_constant_s: 0.03,
            },
            LowPass::MovingAverage {
                taps: 8,
                stages: 2,
                decimation: 1,
            },
            LowPass::SecondOrder {
                natural_frequency_hz: 8.0,
                damping: 0.3,
                form: SecondOrderForm::PoleMapped,
            },
        ] {
            let v = lp.flicker_rate_avar(tau0, &[1, 100_000]);
            assert!(v[0] < 0.5 * plain, "{lp:?}: {v:?}");
            assert!((v[1] / plain - 1.0).abs() < 1e-4, "{lp:?}: {v:?}");
        }
        let g = |t: f64| t * t * t.ln() / (2.0 * PI);
        let f1 = g(2.0) / 4.0;
        let f2 = (g(1.0) + 2.0 * g(2.0) + g(3.0)) / 4.0;
        let want = (-8.0 * f1 + 2.0 * f2) / 2.0;
        let got = LowPass::MovingAverage {
            taps: 2,
            stages: 1,
            decimation: 1,
        }
        .flicker_rate_avar(tau0, &[1])[0];
        assert!((got / want - 1.0).abs() < 1e-12, "{got} vs {want}");
    }

    /// A FIR read every `D`-th sample: its autocorrelation is the internal taps' polyphase sum
    /// `sum_i h_i h_{i + D k}` (by hand here) scaled to a two-sided total of 1, and its power
    /// gain is that autocorrelation's transform, `rho_0 + 2 sum_k rho_k cos(w k)` (Wiener-
    /// Khinchin; the folded images of [`LowPass::power_gain`] are its Poisson sum). A FIR at
    /// the output rate (`D = 1`) keeps session 46's taps and gains.
    #[test]
    fn a_fir_read_every_so_many_samples_is_its_polyphase_sum() {
        let tau0 = 0.002;
        for (taps, cutoff, d) in [
            (31u32, 250.0, 2u32),
            (64, 60.0, 8),
            (23, 180.0, 2),
            (47, 131.0, 1),
        ] {
            let lp = LowPass::Fir {
                taps,
                cutoff_hz: cutoff,
                decimation: d,
            };
            let h = fir_window_sinc(taps, cutoff, tau0 / f64::from(d));
            let d = d as usize;
            let raw: Vec<f64> = (0..h.len().div_ceil(d))
                .map(|k| {
                    (0..h.len())
                        .filter_map(|i| h.get(i + d * k).map(|b| h[i] * b))
                        .sum()
                })
                .collect();
            let total = raw[0] + 2.0 * raw[1..].iter().sum::<f64>();
            let rho = lp.autocorrelation(tau0);
            assert_eq!(rho.len(), raw.len(), "{lp:?}");
            for (k, (r, w)) in rho.iter().zip(&raw).enumerate() {
                assert!(
                    (r - w / total).abs() < 1e-13,
                    "{lp:?} lag {k}: {r} vs {}",
                    w / total
                );
            }
            for f in [0.0, 7.0, 60.0, 125.0, 200.0, 249.0] {
                let s = transform(&rho, 2.0 * PI * f * tau0);
                let g = lp.power_gain(tau0, f);
                assert!(
                    (g - s).abs() < 1e-9 * s.abs().max(1e-3),
                    "{lp:?} {f} Hz: {g} vs {s}"
                );
            }
            assert!(
                (lp.memory_s(tau0) - f64::from(taps) * tau0 / d as f64).abs() < 1e-15,
                "{lp:?}"
            );
        }
    }

    /// The running-sum impulse response against closed forms: one stage is `1/m` on `m` taps;
    /// two stages are the Bartlett triangle `(m - |k - (m - 1)|) / m^2` on `2m - 1` taps; three
    /// stages against the direct convolution of the two-stage one with the boxcar.
    #[test]
    fn the_averages_impulse_response_is_the_boxcars_convolved() {
        for m in [1u32, 2, 7, 47, 750] {
            let mf = f64::from(m);
            let one = LowPass::fir(m, 1);
            assert_eq!(one.len(), m as usize);
            assert!(one.iter().all(|&x| (x - 1.0 / mf).abs() < 1e-15));
            let two = LowPass::fir(m, 2);
            assert_eq!(two.len(), 2 * m as usize - 1);
            for (k, &x) in two.iter().enumerate() {
                let want = (mf - (k as f64 - (mf - 1.0)).abs()) / (mf * mf);
                assert!((x - want).abs() < 1e-13, "m {m} k {k}: {x} vs {want}");
            }
            let three = LowPass::fir(m, 3);
            for (k, &x) in three.iter().enumerate() {
                let want: f64 = (0..m as usize)
                    .filter_map(|j| k.checked_sub(j).and_then(|i| two.get(i)))
                    .sum::<f64>()
                    / mf;
                assert!((x - want).abs() < 1e-13, "m {m} k {k}: {x} vs {want}");
            }
            assert!((three.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        }
    }

    /// A moving average run `D` times faster than the output and read every `D`-th sample:
    /// its output is, for each phase `p` of the input within a sample, an average of that
    /// phase's inputs with the taps `h_{qD+p}`. The autocovariance at output lag `j` is then
    /// `sum_p sum_q h_{qD+p} h_{(q+j)D+p}` (the polyphase decomposition, by hand here), scaled
    /// to a two-sided total of 1; and a CIC's total before the scaling is exactly `1 / D`.
    #[test]
    fn the_decimated_average_is_its_polyphase_parts() {
        let tau0 = 0.004;
        for (taps, stages, d) in [(8u32, 3u32, 8u32), (5, 2, 3), (2, 3, 2), (12, 1, 5)] {
            let lp = LowPass::MovingAverage {
                taps,
                stages,
                decimation: d,
            };
            let got = lp.autocorrelation(tau0);
            let h = LowPass::fir(taps, stages);
            let d = d as usize;
            let at = |i: usize| h.get(i).copied().unwrap_or(0.0);
            let q_max = h.len() / d + 1;
            let cov = |j: usize| -> f64 {
                (0..d)
                    .map(|p| {
                        (0..q_max)
                            .map(|q| at(q * d + p) * at((q + j) * d + p))
                            .sum::<f64>()
                    })
                    .sum()
            };
            let total = cov(0) + 2.0 * (1..q_max).map(cov).sum::<f64>();
            if (taps as usize).is_multiple_of(d) {
                assert!((total * d as f64 - 1.0).abs() < 1e-12, "{lp:?}: {total}");
            }
            for (j, g) in got.iter().enumerate() {
                assert!((g - cov(j) / total).abs() < 1e-14, "{lp:?} lag {j}");
            }
            assert!(got.len() >= q_max - 1);
        }
    }

    /// A CIC of `D` taps and `S` stages read every `D`-th sample tends, as `D` grows, to a
    /// continuous boxcar of one output sample applied `S` times: its output autocorrelation is
    /// the centred B-spline of order `2 S` at whole lags (sinc^3: 66/120, 26/120, 1/120;
    /// sinc^2: 4/6, 1/6), and the boxcar alone (S = 1) leaves white noise white.
    #[test]
    fn a_long_cic_is_the_b_spline() {
        for (stages, want) in [
            (1u32, vec![1.0]),
            (2, vec![4.0 / 6.0, 1.0 / 6.0]),
            (3, vec![66.0 / 120.0, 26.0 / 120.0, 1.0 / 120.0]),
        ] {
            let d = 256;
            let rho = LowPass::MovingAverage {
                taps: d,
                stages,
                decimation: d,
            }
            .autocorrelation(0.001);
            for (j, w) in want.iter().enumerate() {
                // the discrete spline differs from the continuous one by O(1 / D^2)
                assert!((rho[j] - w).abs() < 1e-4, "S {stages} lag {j}: {}", rho[j]);
            }
            assert!(rho[want.len()..].iter().all(|v| v.abs() < 1e-9));
        }
    }

    /// The power gains integrate to the white-noise variance ratio `rho_0` (Parseval), the
    /// bilinear and sampled second orders' zeros included, and the DC gain is 1.
    #[test]
    fn power_gain_parseval() {
        let tau0 = 0.004;
        for lp in [
            LowPass::MovingAverage {
                taps: 5,
                stages: 2,
                decimation: 1,
            },
            LowPass::MovingAverage {
                taps: 5,
                stages: 2,
                decimation: 3,
            },
            LowPass::MovingAverage {
                taps: 8,
                stages: 3,
                decimation: 8,
            },
            LowPass::SecondOrder {
                natural_frequency_hz: 10.0,
                damping: 0.5,
                form: SecondOrderForm::PoleMapped,
            },
            LowPass::SecondOrder {
                natural_frequency_hz: 40.0,
                damping: 0.4,
                form: SecondOrderForm::Bilinear,
            },
            LowPass::SecondOrder {
                natural_frequency_hz: 20.0,
                damping: 0.7,
                form: SecondOrderForm::Sampled { zero: 0.27 },
            },
            LowPass::ZeroPhase {
                time_constant_s: 0.01,
            },
            LowPass::Cascade {
                front: Average {
                    taps: 4,
                    stages: 3,
                    decimation: 4,
                },
                back: Behind::FirstOrder {
                    time_constant_s: 0.008,
                },
            },
        ] {
            let n = 20_000;
            let fs = 1.0 / tau0;
            let mean: f64 = (0..n)
                .map(|i| lp.power_gain(tau0, (i as f64 + 0.5) / n as f64 * fs / 2.0))
                .sum::<f64>()
                / n as f64;
            let r0 = lp.autocorrelation(tau0)[0];
            assert!((mean / r0 - 1.0).abs() < 1e-6, "{lp:?}: {mean} vs {r0}");
            assert!((lp.power_gain(tau0, 0.0) - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn the_flicker_column_from_the_table_is_the_formula_term_by_term() {
        let tau0 = 0.004;
        let ms: Vec<u64> = (0..18).map(|k| 1u64 << k).collect();
        for lp in [
            LowPass::FirstOrder {
                time_constant_s: 0.05,
            },
            LowPass::SecondOrder {
                natural_frequency_hz: 3.0,
                damping: 0.4,
                form: SecondOrderForm::PoleMapped,
            },
            LowPass::MovingAverage {
                taps: 7,
                stages: 2,
                decimation: 1,
            },
        ] {
            let got = lp.flicker_rate_avar(tau0, &ms);
            // the sum written out with a logarithm per term, as docs/gap.md states it
            let rho = lp.autocorrelation(tau0);
            let cut = rho
                .iter()
                .rposition(|v| v.abs() > 1e-9 * rho[0].abs())
                .map_or(1, |i| i + 1);
            let total = rho[0] + 2.0 * rho[1..cut].iter().sum::<f64>();
            let f = |t: f64| {
                (-(cut as i64 - 1)..cut as i64)
                    .map(|q| rho[q.unsigned_abs() as usize] * flicker_phase(t - q as f64))
                    .sum::<f64>()
                    / total
            };
            let m_exact = 200.0 * (lp.memory_s(tau0) / tau0).max(cut as f64);
            for (&m, g) in ms.iter().zip(&got) {
                let mf = m as f64;
                let want = if mf > m_exact {
                    2.0 * std::f64::consts::LN_2 / PI
                } else {
                    (6.0 * f(0.0) - 8.0 * f(mf) + 2.0 * f(2.0 * mf)) / (2.0 * mf * mf)
                };
                assert!(
                    (g - want).abs() <= 1e-9 * want.abs(),
                    "{lp:?} m {m}: {g} against {want}"
                );
            }
        }
    }

    /// A cascade's autocorrelation against its impulse response by brute force: a boxcar of 5
    /// output samples convolved with a first order's `(1 - a) a^k`, then `sum_i h_i h_{i+k}`;
    /// and its power gain is the parts' product, its memory their sum.
    #[test]
    fn a_cascade_is_its_parts_convolved() {
        let tau0 = 0.004;
        let tc = 0.02;
        let lp = LowPass::Cascade {
            front: Average {
                taps: 5,
                stages: 1,
                decimation: 1,
            },
            back: Behind::FirstOrder {
                time_constant_s: tc,
            },
        };
        let a = (-tau0 / tc).exp();
        let h: Vec<f64> = (0..2000)
            .map(|k| {
                (0..5usize)
                    .filter(|&j| j <= k)
                    .map(|j| 0.2 * (1.0 - a) * a.powi((k - j) as i32))
                    .sum()
            })
            .collect();
        let r = lp.autocorrelation(tau0);
        for k in [0usize, 1, 2, 4, 5, 9, 40] {
            let want: f64 = h.iter().zip(&h[k..]).map(|(x, y)| x * y).sum();
            assert!(
                (r[k] / want - 1.0).abs() < 1e-9,
                "lag {k}: {} vs {want}",
                r[k]
            );
        }
        let (front, back) = lp.parts().expect("parts");
        for f in [0.0, 3.0, 41.0, 120.0] {
            let want = front.power_gain(tau0, f) * back.power_gain(tau0, f);
            assert!((lp.power_gain(tau0, f) - want).abs() < 1e-15, "{f} Hz");
        }
        assert!((lp.memory_s(tau0) - (5.0 * tau0 + tc)).abs() < 1e-15);
        assert_eq!(lp.n_shape(), 2);
    }

    /// `compose`: a moving average goes in front of a first or second order, either way round
    /// and in place of a cascade's own part; any other pair is a replacement.
    #[test]
    fn filters_compose_into_a_cascade_front_and_back() {
        let ma = LowPass::MovingAverage {
            taps: 4,
            stages: 3,
            decimation: 4,
        };
        let so = LowPass::SecondOrder {
            natural_frequency_hz: 20.0,
            damping: 0.7,
            form: SecondOrderForm::Bilinear,
        };
        let fo = LowPass::FirstOrder {
            time_constant_s: 0.01,
        };
        let zp = LowPass::ZeroPhase {
            time_constant_s: 0.01,
        };
        let both = LowPass::compose(Some(so), ma);
        assert_eq!(both.parts(), Some((ma, so)));
        assert_eq!(LowPass::compose(Some(ma), so), both);
        // the back replaced, then the front
        assert_eq!(LowPass::compose(Some(both), fo).parts(), Some((ma, fo)));
        let ma2 = LowPass::MovingAverage {
            taps: 2,
            stages: 1,
            decimation: 1,
        };
        assert_eq!(LowPass::compose(Some(both), ma2).parts(), Some((ma2, so)));
        // no cascade: replaced
        assert_eq!(LowPass::compose(Some(fo), so), so);
        assert_eq!(LowPass::compose(Some(zp), ma), ma);
        assert_eq!(LowPass::compose(Some(ma), zp), zp);
        assert_eq!(LowPass::compose(None, so), so);
    }

    /// The FIR's taps against scipy 1.17's `signal.firwin` (Hamming window, scaled to DC gain 1;
    /// the values printed by `firwin(31, 100.0, fs=1000.0)` and `firwin(8, 50.0, fs=400.0)`),
    /// its power gain against `freqz` of the first (0.2482 at the cut-off, 8.646e-5 at 150
    /// Hz), and its autocorrelation summing to 1.
    #[test]
    fn the_fir_is_scipys_firwin() {
        let h = fir_window_sinc(31, 100.0, 0.001);
        for (i, want) in [
            (1usize, 0.001_201_426_375_882_78),
            (3, 0.004_227_316_085_446_9),
            (7, -0.018_583_210_130_235_96),
            (12, 0.091_888_877_020_527_64),
            (15, 0.199_660_667_298_695_5),
        ] {
            assert!((h[i] - want).abs() < 1e-12, "tap {i}: {} vs {want}", h[i]);
        }
        let h = fir_window_sinc(8, 50.0, 1.0 / 400.0);
        for (i, want) in [
            (0usize, 0.003_560_172_702_628_89),
            (2, 0.161_031_852_333_115_3),
            (3, 0.297_324_252_168_556_5),
        ] {
            assert!((h[i] - want).abs() < 1e-12, "tap {i}: {} vs {want}", h[i]);
        }
        let lp = LowPass::Fir {
            taps: 31,
            cutoff_hz: 100.0,
            decimation: 1,
        };
        for (f, want) in [(0.0, 1.0), (100.0, 0.248_207_65), (150.0, 8.645_696_86e-5)] {
            let g = lp.power_gain(0.001, f);
            assert!((g / want - 1.0).abs() < 1e-6, "{f} Hz: {g} vs {want}");
        }
        assert!((two_sided_sum(&lp.autocorrelation(0.001)) - 1.0).abs() < 1e-12);
    }

    /// The Butterworth against scipy 1.17: `signal.butter(n, fc, fs=fs)` run by `lfilter` on a
    /// unit impulse gave the first six taps below, and `freqz` the power gains at 0, fc / 2, fc,
    /// 1.5 fc and 0.4 fs (fc's is the half-power 0.5). The sections, run one after the other,
    /// give the same impulse response; the power gain's closed form is `freqz`'s; the
    /// autocorrelation is `sum_i h_i h_{i+k}` of the impulse response (DC gain 1: total 1).
    #[test]
    fn the_butterworth_is_scipys_butter() {
        type Case = (u32, f64, f64, [f64; 6], [f64; 5]);
        let cases: [Case; 3] = [
            (
                4,
                20.0,
                200.0,
                [
                    0.004_824_343_357_716_228,
                    0.030_728_717_768_085_785,
                    0.090_594_681_954_882_88,
                    0.167_944_821_844_737_2,
                    0.224_641_271_344_028_14,
                    0.233_457_187_867_600_56,
                ],
                [
                    1.0,
                    0.996_822_324_381_951_5,
                    0.5,
                    0.026_617_352_843_484_39,
                    1.543_180_084_737_900_8e-8,
                ],
            ),
            (
                3,
                45.0,
                400.0,
                [
                    0.024_371_051_873_211_4,
                    0.112_326_860_915_706_96,
                    0.228_528_853_331_987_52,
                    0.281_100_611_992_742_44,
                    0.241_255_230_220_811_94,
                    0.149_828_317_392_187_13,
                ],
                [
                    1.0,
                    0.987_299_594_732_506_7,
                    0.5,
                    0.058_548_026_216_874_924,
                    2.966_500_660_753_5e-6,
                ],
            ),
            (
                5,
                130.0,
                1000.0,
                [
                    0.003_857_535_132_406_283,
                    0.028_447_460_099_693_35,
                    0.095_955_732_266_906_32,
                    0.197_477_819_615_139_8,
                    0.277_918_197_958_029_1,
                    0.279_752_808_201_990_8,
                ],
                [
                    1.0,
                    0.999_370_404_064_685_7,
                    0.5,
                    0.007_771_026_992_440_986_5,
                    3.020_071_084_298_559e-9,
                ],
            ),
        ];
        for (order, fc, fs, taps, gains) in cases {
            let tau0 = 1.0 / fs;
            let lp = LowPass::Butterworth {
                order,
                cutoff_hz: fc,
                decimation: 1,
            };
            assert_eq!(lp.check(tau0), None);
            // the impulse response through the sections
            let mut h: Vec<f64> = (0..6000).map(|i| if i == 0 { 1.0 } else { 0.0 }).collect();
            for q in butterworth_sections(order, fc, tau0) {
                q.run(&mut h);
            }
            for (i, want) in taps.iter().enumerate() {
                assert!(
                    (h[i] - want).abs() < 1e-13,
                    "order {order} tap {i}: {} vs {want}",
                    h[i]
                );
            }
            for (f, want) in [0.0, 0.5 * fc, fc, 1.5 * fc, 0.4 * fs]
                .into_iter()
                .zip(gains)
            {
                let g = lp.power_gain(tau0, f);
                assert!(
                    (g - want).abs() <= 1e-9 * want,
                    "order {order} at {f} Hz: {g} vs {want}"
                );
            }
            let rho = lp.autocorrelation(tau0);
            assert!((two_sided_sum(&rho) - 1.0).abs() < 1e-12, "order {order}");
            for k in [0usize, 1, 2, 5, 17, 60] {
                let want: f64 = h.iter().zip(&h[k..]).map(|(a, b)| a * b).sum();
                assert!(
                    (rho[k] - want).abs() < 1e-13,
                    "order {order} lag {k}: {} vs {want}",
                    rho[k]
                );
            }
            // Parseval: the mean power gain over the band is rho_0
            let n = 20_000;
            let mean = (0..n)
                .map(|i| lp.power_gain(tau0, (i as f64 + 0.5) / n as f64 * fs / 2.0))
                .sum::<f64>()
                / n as f64;
            assert!(
                (mean / rho[0] - 1.0).abs() < 1e-6,
                "order {order}: {mean} vs {}",
                rho[0]
            );
        }
        // order 2 is the bilinear second order at damping 1/sqrt 2
        let two = LowPass::Butterworth {
            order: 2,
            cutoff_hz: 20.0,
            decimation: 1,
        };
        let so = LowPass::SecondOrder {
            natural_frequency_hz: 20.0,
            damping: std::f64::consts::FRAC_1_SQRT_2,
            form: SecondOrderForm::Bilinear,
        };
        let (a, b) = (two.autocorrelation(0.005), so.autocorrelation(0.005));
        assert_eq!(a.len(), b.len());
        assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-15));
        assert!(LowPass::Butterworth {
            order: 9,
            cutoff_hz: 20.0,
            decimation: 1,
        }
        .check(0.005)
        .is_some());
        assert!(LowPass::Butterworth {
            order: 4,
            cutoff_hz: 100.0,
            decimation: 1,
        }
        .check(0.005)
        .is_some());
    }

    /// A Butterworth run `D` times faster than the output and read every `D`-th sample: its
    /// output autocorrelation is the internal impulse response's `sum_i h_i h_{i + D j}`, the
    /// impulse response here run sample by sample through the sections (not by the FFT of
    /// [`butterworth_internal_autocovariance`]), scaled to a two-sided total of 1; its power
    /// gain is that autocorrelation's transform (Wiener-Khinchin), and at `D = 1` it is the
    /// output-rate filter's.
    #[test]
    fn a_butterworth_read_every_so_many_samples_is_its_polyphase_sum() {
        let tau0 = 0.01;
        for (order, fc, d) in [(4u32, 20.0, 16u32), (3, 45.0, 4), (5, 8.0, 2)] {
            let lp = LowPass::Butterworth {
                order,
                cutoff_hz: fc,
                decimation: d,
            };
            assert_eq!(lp.check(tau0), None);
            let step = tau0 / f64::from(d);
            let mut h: Vec<f64> = (0..60_000)
                .map(|i| if i == 0 { 1.0 } else { 0.0 })
                .collect();
            for q in butterworth_sections(order, fc, step) {
                q.run(&mut h);
            }
            let d = d as usize;
            let rho = lp.autocorrelation(tau0);
            let raw: Vec<f64> = (0..rho.len().min(40))
                .map(|j| h.iter().zip(&h[d * j..]).map(|(a, b)| a * b).sum())
                .collect();
            let total = two_sided_sum(&rho);
            assert!((total - 1.0).abs() < 1e-12, "{lp:?}: total {total}");
            // the scale: the internal total read every D-th lag
            let full = two_sided_sum(&butterworth_internal_autocovariance(
                order, fc, tau0, d as u32,
            ));
            for (j, w) in raw.iter().enumerate() {
                assert!(
                    (rho[j] - w / full).abs() < 1e-12,
                    "{lp:?} lag {j}: {} vs {}",
                    rho[j],
                    w / full
                );
            }
            for f in [0.0, 3.0, 12.0, 30.0, 49.0] {
                let s = transform(&rho, 2.0 * PI * f * tau0);
                let g = lp.power_gain(tau0, f);
                assert!(
                    (g - s).abs() < 1e-9 * s.abs().max(1e-3),
                    "{lp:?} {f} Hz: {g} vs {s}"
                );
            }
            assert!((lp.internal_white_scale(tau0) - 1.0 / full.sqrt()).abs() < 1e-12);
        }
        // at D = 1 the FFT's autocovariance is the sections' convolved
        let one = LowPass::Butterworth {
            order: 4,
            cutoff_hz: 20.0,
            decimation: 1,
        };
        let fft = butterworth_internal_autocovariance(4, 20.0, 0.01, 1);
        let conv = one.autocorrelation(0.01);
        for k in 0..50 {
            assert!(
                (fft[k] - conv[k]).abs() < 1e-14,
                "lag {k}: {} vs {}",
                fft[k],
                conv[k]
            );
        }
    }
}
