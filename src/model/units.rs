//! Datasheet units beside the native ones (THEORY.md section 2): a gyro channel in arcsec and an
//! accelerometer channel in m/s, and the quantization check `Q / (LSB / sqrt(12))`.

use serde::{Deserialize, Serialize};

/// Standard gravity (m/s^2), for micro-g.
pub const G0_M_S2: f64 = 9.80665;

/// What the channel's native unit `u` is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SensorKind {
    /// Angle increments in arcsec.
    GyroArcsec,
    /// Velocity increments in m/s.
    AccelMps,
}

/// Q, N, B, K, R in datasheet units, with their unit labels.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Datasheet {
    pub values: [f64; 5],
    pub units: [&'static str; 5],
}

/// Convert native coefficients `(Q, N, B, K, R)` (u, u/sqrt(s), u/s, u/s/sqrt(s), u/s^2).
///
/// Gyro (u = arcsec): Q arcsec; N/60 deg/sqrt(h); B arcsec/s = deg/h; K * 60 deg/h/sqrt(h)
/// (1 arcsec/s/sqrt(s) = (1/3600 deg)/(1/3600 h)/(sqrt(h)/60)); R * 3600 deg/h^2.
/// Accelerometer (u = m/s): Q m/s; N * 60 m/s/sqrt(h); B / 9.80665e-6 micro-g;
/// K * 60 / 9.80665e-6 micro-g/sqrt(h); R * 3600 / 9.80665e-6 micro-g/h.
pub fn datasheet(native: [f64; 5], kind: SensorKind) -> Datasheet {
    let [q, n, b, k, r] = native;
    match kind {
        SensorKind::GyroArcsec => Datasheet {
            values: [q, n / 60.0, b, k * 60.0, r * 3600.0],
            units: ["arcsec", "deg/sqrt(h)", "deg/h", "deg/h/sqrt(h)", "deg/h^2"],
        },
        SensorKind::AccelMps => {
            let ug = G0_M_S2 * 1e-6;
            Datasheet {
                values: [q, n * 60.0, b / ug, k * 60.0 / ug, r * 3600.0 / ug],
                units: [
                    "m/s",
                    "m/s/sqrt(h)",
                    "micro-g",
                    "micro-g/sqrt(h)",
                    "micro-g/h",
                ],
            }
        }
    }
}

/// THEORY.md section 2: uniform rounding of the phase with step `lsb` gives `Q = lsb / sqrt(12)`;
/// the ratio above 1 is excess white-phase noise.
pub fn quantization_ratio(q: f64, lsb: f64) -> f64 {
    q / (lsb / 12f64.sqrt())
}
