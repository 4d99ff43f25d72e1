//! PX4's CSV export (`ulog2csv LOG.ulg`, one file per uORB message: `LOG_sensor_combined_0.csv`).
//!
//! Every uORB message starts with `timestamp`, microseconds since the autopilot booted, written
//! as a whole number with no unit in its name; arrays are flattened to `name[0]`, `name[1]`, ...
//! Beside the measurements a message carries fields that describe each sample rather than measure
//! anything: its integration interval (`gyro_integral_dt`, `delta_angle_dt`, in us), a stamp
//! relative to `timestamp` (`accelerometer_timestamp_relative`), the sensor's id, clipping flags
//! and counters, calibration counts (PX4's `msg/SensorCombined.msg`, `msg/VehicleImu.msg`,
//! `msg/SensorGyro.msg`). Read as channels they are constants or counters, and a curve of them
//! means nothing; and a `timestamp` read as seconds makes tau0 5000 s at 200 Hz.
//!
//! So a header that is PX4's ([`is_export`]) gets its `timestamp` read in us ([`TIMESTAMP_UNIT_S`])
//! and its bookkeeping fields ([`bookkeeping`]) left out of the channels unless `--channels`
//! names them. The fields whose unit the message fixes are [`field_unit`]'s.

use super::header_unit::{array_element, HeaderUnit};

/// Seconds per unit of a uORB `timestamp`: microseconds since boot.
pub const TIMESTAMP_UNIT_S: f64 = 1e-6;

/// Whether a header (`names`, in input order) is that of a PX4 CSV export: its first column is
/// `timestamp`, and another is a field only uORB messages carry: an array whose unit the
/// message fixes (`gyro_rad[0]`, [`field_unit`]), `timestamp_sample`, `device_id`,
/// `..._timestamp_relative`, `..._integral_dt` (a logger's `gyro[0]` is not enough).
pub fn is_export(names: &[String]) -> bool {
    let Some((first, rest)) = names.split_first() else {
        return false;
    };
    first == "timestamp"
        && rest.iter().any(|n| {
            array_element(n).is_some_and(|b| field_unit(b).is_some())
                || n == "timestamp_sample"
                || n == "device_id"
                || n.ends_with("_timestamp_relative")
                || n.ends_with("_integral_dt")
        })
}

/// Whether the time column `column` of a PX4 export holds uORB stamps (us since boot):
/// `timestamp` or `timestamp_sample`, whole numbers (`stamps`) not the size of a clock since
/// 1970 (a file that only looks like PX4's, stamped in seconds or epoch ms, keeps its unit).
pub fn boot_stamps(column: &str, stamps: &[f64]) -> bool {
    let finite = || stamps.iter().filter(|t| t.is_finite());
    matches!(column, "timestamp" | "timestamp_sample")
        && finite().next().is_some()
        && finite().all(|t| t.fract() == 0.0 && *t >= 0.0 && *t < 1e12)
}

/// Whether the field `name` of a PX4 export describes its samples rather than measures: an
/// interval (`..._dt`), a relative stamp, a device id, clipping flags and counters, error and
/// calibration counts, a FIFO message's sample count and scale.
pub fn bookkeeping(name: &str) -> bool {
    let base = array_element(name).unwrap_or(name);
    let words: Vec<&str> = base.split('_').collect();
    let last = words.last().copied().unwrap_or("");
    let has = |w: &str| words.contains(&w);
    last == "dt"
        || (has("timestamp") && has("relative"))
        || (has("device") && last == "id")
        || has("clipping")
        || base == "clip_counter"
        || (last == "count" && (has("error") || has("calibration")))
        || base == "samples"
        || base == "scale"
}

/// A uORB field whose unit its message fixes, by its name without the array index:
/// `sensor_combined`'s `gyro_rad` (rad/s) and `accelerometer_m_s2` (m/s^2), `vehicle_imu`'s
/// `delta_angle` (rad) and `delta_velocity` (m/s) increments.
pub fn field_unit(base: &str) -> Option<HeaderUnit> {
    let (unit, rate, text) = match base {
        "gyro_rad" => ("rad", true, "rad/s, by PX4's sensor_combined"),
        "accelerometer_m_s2" => ("m/s", true, "m/s^2, by PX4's sensor_combined"),
        "delta_angle" => ("rad", false, "rad, by PX4's vehicle_imu"),
        "delta_velocity" => ("m/s", false, "m/s, by PX4's vehicle_imu"),
        _ => return None,
    };
    Some(HeaderUnit {
        unit: unit.into(),
        rate,
        text: text.into(),
    })
}

/// The unit of a `sensor_gyro` or `sensor_accel` export's `x`, `y`, `z` (rad/s, m/s^2 by their
/// message), which their names do not carry: the message is read off the file's name, as
/// `ulog2csv` writes it (`LOG_sensor_gyro_0.csv`; not `sensor_gyro_fifo`, whose `x[k]` are
/// scaled counts, nor `sensor_gyro_status`). `None` for any other file or column.
pub fn message_unit(file: &std::path::Path, column: &str) -> Option<HeaderUnit> {
    if !matches!(column, "x" | "y" | "z") {
        return None;
    }
    let stem = file.file_stem()?.to_str()?;
    // `..._sensor_gyro_<instance>`: the message name, then the instance number.
    let (head, instance) = stem.rsplit_once('_')?;
    if instance.is_empty() || !instance.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let (unit, text) = if head.ends_with("sensor_gyro") {
        ("rad", "rad/s, by its PX4 message sensor_gyro")
    } else if head.ends_with("sensor_accel") {
        ("m/s", "m/s^2, by its PX4 message sensor_accel")
    } else {
        return None;
    };
    Some(HeaderUnit {
        unit: unit.into(),
        rate: true,
        text: text.into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(h: &str) -> Vec<String> {
        h.split(',').map(str::to_string).collect()
    }

    /// The headers `ulog2csv` writes for sensor_combined, vehicle_imu and sensor_gyro are PX4's;
    /// a logger's `timestamp,gx,gy` and a header with `timestamp` elsewhere are not.
    #[test]
    fn export_headers() {
        for h in [
            "timestamp,gyro_rad[0],gyro_rad[1],gyro_rad[2],gyro_integral_dt,accelerometer_timestamp_relative,accelerometer_m_s2[0]",
            "timestamp,timestamp_sample,accel_device_id,gyro_device_id,delta_angle[0],delta_angle[1]",
            "timestamp,timestamp_sample,device_id,x,y,z,temperature,error_count",
        ] {
            assert!(is_export(&names(h)), "{h}");
        }
        for h in [
            "timestamp,gx,gy,gz",
            "timestamp,gyro[0],gyro[1],gyro[2]",
            "gx,timestamp,gyro_rad[0]",
            "timestamp",
            "time,timestamp_sample,x",
        ] {
            assert!(!is_export(&names(h)), "{h}");
        }
    }

    /// The fields of sensor_combined, vehicle_imu and sensor_gyro that describe samples; the
    /// measurements and the temperature are not among them.
    #[test]
    fn bookkeeping_fields() {
        for n in [
            "gyro_integral_dt",
            "accelerometer_timestamp_relative",
            "accelerometer_integral_dt",
            "accelerometer_clipping",
            "gyro_clipping",
            "accel_calibration_count",
            "gyro_calibration_count",
            "accel_device_id",
            "device_id",
            "delta_angle_dt",
            "delta_velocity_clipping",
            "error_count",
            "clip_counter[2]",
            "samples",
        ] {
            assert!(bookkeeping(n), "{n}");
        }
        for n in [
            "gyro_rad[0]",
            "accelerometer_m_s2[2]",
            "delta_angle[1]",
            "x",
            "temperature",
            "timestamp_sample",
            "dt_gyro_x",
        ] {
            assert!(!bookkeeping(n), "{n}");
        }
    }

    /// `x`, `y`, `z` of sensor_gyro and sensor_accel exports by the file's name; not of their
    /// FIFO or status messages, nor another column.
    #[test]
    fn units_by_the_message() {
        use std::path::Path;
        let u = |f: &str, c: &str| message_unit(Path::new(f), c).map(|u| (u.unit, u.rate));
        assert_eq!(
            u("log_12_sensor_gyro_0.csv", "x"),
            Some(("rad".into(), true))
        );
        assert_eq!(
            u("/tmp/flight/log_sensor_accel_1.csv", "z"),
            Some(("m/s".into(), true))
        );
        assert_eq!(u("log_sensor_gyro_0.csv", "temperature"), None);
        assert_eq!(u("log_sensor_gyro_fifo_0.csv", "x"), None);
        assert_eq!(u("log_sensor_gyro_status_0.csv", "x"), None);
        assert_eq!(u("sensor_gyro.csv", "x"), None);
        assert_eq!(u("log_vehicle_imu_0.csv", "x"), None);
    }

    /// Stamps since boot in us: whole, below 1e12 (11.6 days); not seconds, not epoch ms.
    #[test]
    fn boot_stamps_are_whole_and_small() {
        assert!(boot_stamps("timestamp", &[20_313_000.0, 20_317_000.0]));
        assert!(boot_stamps("timestamp_sample", &[f64::NAN, 20_313_000.0]));
        assert!(!boot_stamps("timestamp", &[0.0, 0.01, 0.02]));
        assert!(!boot_stamps("timestamp", &[1.7e12, 1.7e12 + 10.0]));
        assert!(!boot_stamps("time", &[20_313_000.0]));
        assert!(!boot_stamps("timestamp", &[]));
    }
}
