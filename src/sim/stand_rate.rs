//! What the test stand puts on a simulated channel: Earth rate on a gyro, the specific force of
//! gravity on an accelerometer, projected on the channel's axis in the local level frame; and
//! the normal gravity at a latitude that a model file's `[stand]` defaults to.

use super::model_file::SimModel;
use crate::model::units::{IncrementUnit, SensorKind};

/// Earth rotation rate (WGS-84), rad/s.
pub const EARTH_RATE_RAD_S: f64 = 7.292_115e-5;

impl SimModel {
    /// Rate (u/s) the stand puts on channel `ch`: Earth rate for a gyro, specific force (+g up)
    /// for an accelerometer, projected on the channel's axis; 0 without a stand or an axis.
    /// Earth rate in the local level frame is `Omega (0, cos lat, sin lat)`, the specific force
    /// at rest `(0, 0, g)`: a gyro along the vertical sees `Omega sin(lat)`.
    pub fn stand_rate(&self, ch: usize) -> f64 {
        let (Some(stand), Some(c)) = (self.stand, self.channels.get(ch)) else {
            return 0.0;
        };
        let Some(axis) = c.axis_enu else {
            return 0.0;
        };
        match c.kind {
            Some(IncrementUnit {
                kind: SensorKind::Gyro,
                si_per_unit,
            }) => {
                let lat = stand.latitude_deg.to_radians();
                EARTH_RATE_RAD_S / si_per_unit * (axis[1] * lat.cos() + axis[2] * lat.sin())
            }
            Some(IncrementUnit {
                kind: SensorKind::Accel,
                si_per_unit,
            }) => stand.gravity_m_s2 / si_per_unit * axis[2],
            None => 0.0,
        }
    }
}

/// WGS-84 normal gravity at a latitude (Somigliana's formula), m/s^2.
pub fn normal_gravity_m_s2(latitude_deg: f64) -> f64 {
    let s2 = latitude_deg.to_radians().sin().powi(2);
    9.780_325_335_9 * (1.0 + 0.001_931_852_652_41 * s2) / (1.0 - 0.006_694_379_990_13 * s2).sqrt()
}
