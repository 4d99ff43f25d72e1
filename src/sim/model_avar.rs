//! The closed-form Allan variance of a simulated channel ([`SimModel::avar_closed_form`]): the
//! sum of the exact discrete AVAR of every term and effect of a model file (docs/theory.md sections 2
//! and 3, via [`crate::model::terms`]), which the simulator's tests and the diagnosis's round
//! trip check against.

use crate::model::terms;

use super::model_file::SimModel;

impl SimModel {
    /// The model's Allan variance (u^2/s^2) of channel `ch` at cluster `m`, for a record of
    /// `n_increments` starting at power-on, from the exact discrete closed forms of
    /// [`crate::model::terms`]: Q (with `lsb / sqrt(12)` added in quadrature), N (through the
    /// output filter when there is one), the flicker bank, K, R, Gauss-Markov, sinusoids (times
    /// the output filter's gain), warm-up, bias jumps (as K) and the temperature-driven bias
    /// (its settling as a warm-up, two with a second order, its sine as a sinusoid).
    ///
    /// Not included: the output filter's effect on terms other than N and the sinusoids (small
    /// where those terms matter, at tau >> the filter's time constant), and the cross terms
    /// between the deterministic parts (ramp, warm-up, sinusoids, temperature) on a finite
    /// record, which average out over many periods.
    pub fn avar_closed_form(&self, ch: usize, m: u64, n_increments: u64) -> f64 {
        let Some(c) = self.channels.get(ch) else {
            return f64::NAN;
        };
        let tau0 = self.tau0_s;
        let tau = m as f64 * tau0;
        let q2 = c.q * c.q + c.lsb.map_or(0.0, |l| terms::quantization_q(l).powi(2));
        let mut v = terms::white_phase_avar(q2.sqrt(), tau);
        let filter = c.output_filter.map(|f| f.time_constant_s);
        v += match (filter, &c.lowpass) {
            (Some(t), _) if c.n > 0.0 => terms::filtered_white_rate_avar(c.n, t, tau0, m),
            (None, Some(lp)) if c.n > 0.0 => c.n * c.n * lp.white_rate_avar(tau0, &[m])[0],
            _ => terms::white_rate_avar(c.n, tau),
        };
        if let Some(bank) = &c.flicker {
            v += bank.avar(tau);
        }
        v += terms::rate_random_walk_avar(c.k, tau);
        v += terms::rate_ramp_avar(c.r, tau);
        for g in &c.gauss_markov {
            v += terms::gauss_markov_avar(g.sigma, g.tau_c_s, tau);
        }
        let gain = |f_hz: f64| match (filter, &c.lowpass) {
            (Some(t), _) => terms::output_filter_power_gain(t, tau0, f_hz),
            (None, Some(lp)) => lp.power_gain(tau0, f_hz),
            _ => 1.0,
        };
        for s in &c.sinusoids {
            v += gain(s.frequency_hz) * terms::sinusoid_avar(s.amplitude, s.frequency_hz, tau);
        }
        // A band behind a filter: its gain at the centre (exact for a band narrow against the
        // filter's response).
        for b in &c.band_noise {
            v += gain(b.frequency_hz)
                * super::band_noise::band_noise_avar(b.sigma, b.frequency_hz, b.width_hz, tau0, m);
        }
        if let Some(w) = c.warmup {
            v += terms::warmup_avar(w.amplitude, w.time_constant_s, tau0, m, n_increments);
        }
        if let Some(j) = c.bias_jumps {
            v += terms::bias_jumps_avar(j.mean_interval_s, j.rms_size, tau);
        }
        let bends = c.temperature_quadratic != 0.0;
        if let (Some(t), true) = (&self.temperature, c.temperature_coefficient != 0.0 || bends) {
            // With `T - r = (final - r) + d e^{-t/T} + sine`, the settling's part of
            // `c (T - r) + q (T - r)^2` is `(c + 2 q (final - r)) d e^{-t/T} + q d^2 e^{-2t/T}`:
            // two warm-ups (the second order's harmonic of the sine left out with the other
            // cross terms).
            let q = c.temperature_quadratic;
            let slope = c.temperature_coefficient + 2.0 * q * (t.final_c - t.reference_c);
            let d = t.start_c - t.final_c;
            let a = slope * d;
            if a != 0.0 {
                v += terms::warmup_avar(a, t.time_constant_s, tau0, m, n_increments);
            }
            if bends && d != 0.0 {
                v += terms::warmup_avar(q * d * d, t.time_constant_s / 2.0, tau0, m, n_increments);
            }
            if t.sine_amplitude_c != 0.0 {
                let f = 1.0 / t.sine_period_s;
                let amp = slope * t.sine_amplitude_c;
                v += gain(f) * terms::sinusoid_avar(amp, f, tau);
            }
        }
        v
    }
}
