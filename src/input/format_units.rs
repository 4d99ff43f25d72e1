//! Units that a file's format fixes for data columns whose names carry none. Each format is
//! told by its whole header (and the Sensor Logger app's by its file's name too), never by one
//! column's name, since `omega_x` or `x` alone may be in any unit:
//!
//! - Kalibr's `imu0.csv`: `timestamp,omega_x,omega_y,omega_z,alpha_x,alpha_y,alpha_z`, the
//!   rates in rad/s and m/s^2 (Kalibr's wiki, "Bag format");
//! - an Xsens export (MT Manager, an Xsens DOT's app), told by its `PacketCounter` or
//!   `SampleTimeFine` column: `Gyr_X` in rad/s, `Acc_X` and `FreeAcc_X` in m/s^2, the velocity
//!   increments `dv[1]` in m/s (the MTi and MTw manuals' output tables);
//! - UZH-FPV's `imu.txt`: `ang_vel_x` ... in rad/s, `lin_acc_x` ... in m/s^2;
//! - the Sensor Logger phone app's per-sensor files: `time,seconds_elapsed,z,y,x` in
//!   `Gyroscope.csv` (rad/s) or `Accelerometer.csv`, `TotalAcceleration.csv`, `Gravity.csv`
//!   (m/s^2), the units of the phone's sensor interface;
//! - ArduPilot's `IMU` (and batch `GYR`, `ACC`) messages as pymavlink's `mavlogdump.py --format
//!   csv` writes them, told by `TimeUS` or `TimeMS` beside `GyrX` or `AccX`: `GyrX` in rad/s,
//!   `AccX` in m/s^2, `T` the IMU's temperature in degC.
//!
//! A format also names its columns that are no channels ([`FileFormat::other_column`]: Xsens's
//! orientation increments, its velocity increments beside rates; ArduPilot's instance number,
//! error counts, health flags and rates) and its temperature ([`FileFormat::temperature`]). A
//! unit in a column's own name rules over its format's (`super::header_unit::units_from_headers`).

use super::header_unit::HeaderUnit;
use super::temperature_column::{TemperatureScale, CELSIUS};
use std::path::Path;

/// A file format that fixes the units of its data columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileFormat {
    /// Kalibr's `imu0.csv`.
    Kalibr,
    /// An Xsens MT Manager or DOT export; `rates`: it holds rates of turn or accelerations
    /// (`Gyr_X`, `Acc_X`, `FreeAcc_X`), beside which its velocity increments are no channels.
    Xsens { rates: bool },
    /// UZH-FPV's `imu.txt`.
    UzhFpv,
    /// A Sensor Logger file of a gyroscope (`true`) or an accelerometer (`false`).
    SensorLogger { gyro: bool },
    /// ArduPilot's `IMU` messages as `mavlogdump.py --format csv` writes them.
    ArduPilot,
    /// A ROS 1 `rostopic echo -p` export of `sensor_msgs/Imu` (`field.header.stamp`,
    /// `field.angular_velocity.x`, ...): its units are the message's (`super::header_unit`).
    RosImu,
}

/// What to do with an ArduPilot DataFlash log, binary or text: the reader takes the CSV that
/// pymavlink writes of its `IMU` messages.
pub const MAVLOGDUMP: &str = "export its IMU messages as CSV first with pymavlink: \
                              `mavlogdump.py --types IMU --format csv F > imu.csv` (README, \
                              ArduPilot)";

/// What a DataFlash log in text is called where it is refused (the file's start, or the header
/// its first line makes).
pub const DATAFLASH_TEXT: &str =
    "an ArduPilot DataFlash log as text (.log: messages of many kinds)";

/// The header of Kalibr's `imu0.csv`.
pub const KALIBR_HEADER: [&str; 7] = [
    "timestamp",
    "omega_x",
    "omega_y",
    "omega_z",
    "alpha_x",
    "alpha_y",
    "alpha_z",
];

/// The data columns of UZH-FPV's `imu.txt` (beside `id` and `timestamp`).
const UZH_FPV_COLUMNS: [&str; 6] = [
    "ang_vel_x",
    "ang_vel_y",
    "ang_vel_z",
    "lin_acc_x",
    "lin_acc_y",
    "lin_acc_z",
];

/// The header of a Sensor Logger per-sensor file.
const SENSOR_LOGGER_HEADER: [&str; 5] = ["time", "seconds_elapsed", "z", "y", "x"];

/// The format whose header `names` is (`file`: the input's path, whose name tells a Sensor
/// Logger file's sensor), if any.
pub fn file_format<S: AsRef<str>>(names: &[S], file: &Path) -> Option<FileFormat> {
    let has = |k: &str| {
        names
            .iter()
            .any(|n| n.as_ref().trim().trim_start_matches(['#', '%']).trim() == k)
    };
    if KALIBR_HEADER.iter().all(|k| has(k)) {
        return Some(FileFormat::Kalibr);
    }
    if has("PacketCounter") || has("SampleTimeFine") {
        let rates = ["Gyr_", "Acc_", "FreeAcc_"]
            .iter()
            .any(|p| ["X", "Y", "Z"].iter().any(|a| has(&format!("{p}{a}"))));
        return Some(FileFormat::Xsens { rates });
    }
    if (has("TimeUS") || has("TimeMS")) && (has("GyrX") || has("AccX")) {
        return Some(FileFormat::ArduPilot);
    }
    if UZH_FPV_COLUMNS.iter().all(|k| has(k)) {
        return Some(FileFormat::UzhFpv);
    }
    if has("field.header.stamp")
        && (has("field.angular_velocity.x") || has("field.linear_acceleration.x"))
    {
        return Some(FileFormat::RosImu);
    }
    let exact = names.len() == SENSOR_LOGGER_HEADER.len()
        && names
            .iter()
            .zip(SENSOR_LOGGER_HEADER)
            .all(|(n, k)| n.as_ref().trim() == k);
    if exact {
        let stem = file.file_stem()?.to_str()?;
        return match stem {
            "Gyroscope" | "GyroscopeUncalibrated" => Some(FileFormat::SensorLogger { gyro: true }),
            "Accelerometer" | "AccelerometerUncalibrated" | "TotalAcceleration" | "Gravity" => {
                Some(FileFormat::SensorLogger { gyro: false })
            }
            _ => None,
        };
    }
    None
}

impl FileFormat {
    /// The unit this format fixes for the column `name`; `None` for a column it says nothing of.
    pub fn column_unit(self, name: &str) -> Option<HeaderUnit> {
        let n = name.trim();
        let (unit, rate, text) = match self {
            FileFormat::Kalibr => match n.split_once('_')? {
                ("omega", "x" | "y" | "z") => ("rad", true, "rad/s, by Kalibr's imu0.csv"),
                ("alpha", "x" | "y" | "z") => ("m/s", true, "m/s^2, by Kalibr's imu0.csv"),
                _ => return None,
            },
            FileFormat::Xsens { .. } => match n {
                "Gyr_X" | "Gyr_Y" | "Gyr_Z" => ("rad", true, "rad/s, by its Xsens export"),
                "Acc_X" | "Acc_Y" | "Acc_Z" | "FreeAcc_X" | "FreeAcc_Y" | "FreeAcc_Z" => {
                    ("m/s", true, "m/s^2, by its Xsens export")
                }
                "dv[1]" | "dv[2]" | "dv[3]" | "VelInc_X" | "VelInc_Y" | "VelInc_Z" => {
                    ("m/s", false, "m/s, by its Xsens export")
                }
                _ => return None,
            },
            FileFormat::UzhFpv => match n.rsplit_once('_')? {
                ("ang_vel", "x" | "y" | "z") => ("rad", true, "rad/s, by UZH-FPV's imu.txt"),
                ("lin_acc", "x" | "y" | "z") => ("m/s", true, "m/s^2, by UZH-FPV's imu.txt"),
                _ => return None,
            },
            FileFormat::ArduPilot => match n {
                "GyrX" | "GyrY" | "GyrZ" => ("rad", true, "rad/s, by ArduPilot's IMU message"),
                "AccX" | "AccY" | "AccZ" => ("m/s", true, "m/s^2, by ArduPilot's IMU message"),
                _ => return None,
            },
            FileFormat::SensorLogger { gyro } => match (n, gyro) {
                ("x" | "y" | "z", true) => ("rad", true, "rad/s, by Sensor Logger's Gyroscope.csv"),
                ("x" | "y" | "z", false) => ("m/s", true, "m/s^2, by Sensor Logger's file"),
                _ => return None,
            },
            // The message's units are read off its field names (`super::header_unit`).
            FileFormat::RosImu => return None,
        };
        Some(HeaderUnit {
            unit: unit.into(),
            rate,
            text: text.into(),
        })
    }

    /// The format, as the log names it where it says what a column holds.
    pub fn source(self) -> &'static str {
        match self {
            FileFormat::Kalibr => "Kalibr's imu0.csv",
            FileFormat::Xsens { .. } => "its Xsens export",
            FileFormat::UzhFpv => "UZH-FPV's imu.txt",
            FileFormat::SensorLogger { .. } => "Sensor Logger's file",
            FileFormat::ArduPilot => "ArduPilot's IMU message",
            FileFormat::RosImu => "its sensor_msgs/Imu export",
        }
    }

    /// The scale of the column `name` when this format fixes it as the unit's temperature
    /// (ArduPilot's `T`, degC): `diagnose` fits the bias against it, `analyze` leaves it out,
    /// as a `temp [degC]` column (`super::temperature_column`).
    pub fn temperature(self, name: &str) -> Option<TemperatureScale> {
        (self == FileFormat::ArduPilot && name.trim() == "T").then_some(CELSIUS)
    }

    /// What a column this format fixes as no channel holds (ArduPilot's `IMU` message: the
    /// IMU's number `I`, the error counts `EG`, `EA`, the health flags `GH`, `AH`, the sensors'
    /// rates `GHz`, `AHz`; an Xsens export's orientation increments `dq_*`, and its velocity
    /// increments `dv[*]` beside rates, since one run reads rates or increments, not both);
    /// `None` for the others.
    pub fn other_column(self, name: &str) -> Option<&'static str> {
        match (self, name.trim()) {
            (FileFormat::ArduPilot, "I") => Some("the number of the IMU its rows are of"),
            // A driver's orientation estimate and the covariances the message carries (often
            // constant, -1 for "not given"): read as channels, a run on a ROS export diagnosed
            // them in `u` beside the six rates, with a warning for each that never moved.
            (FileFormat::RosImu, n) if n.contains("_covariance") => {
                Some("a covariance the message carries, no sample")
            }
            (FileFormat::RosImu, n) if n.starts_with("field.orientation.") => {
                Some("an orientation the driver computes")
            }
            // Half the angle increment about each axis (and the real part): no angle as it
            // stands, and read as a rate beside `Gyr_X` it would be off by 1/tau0.
            (FileFormat::Xsens { .. }, "dq_W" | "dq_X" | "dq_Y" | "dq_Z") => {
                Some("an orientation increment as a quaternion (half angles)")
            }
            (FileFormat::Xsens { rates: true }, "dv[1]" | "dv[2]" | "dv[3]") => Some(
                "velocity increments beside the rates (analyse them alone: --columns \
                 dv[1],dv[2],dv[3])",
            ),
            (FileFormat::Xsens { rates: true }, "VelInc_X" | "VelInc_Y" | "VelInc_Z") => Some(
                "velocity increments beside the rates (analyse them alone: --columns \
                 VelInc_X,VelInc_Y,VelInc_Z)",
            ),
            // What the unit's filter and receiver compute from its sensors: no sensor output.
            (FileFormat::Xsens { .. }, n)
                if n.starts_with("Quat_")
                    || n.starts_with("OriInc_")
                    || n.starts_with("Euler_")
                    || n.starts_with("Mat[")
                    || matches!(n, "Roll" | "Pitch" | "Yaw") =>
            {
                Some("an orientation the unit's filter computes")
            }
            (FileFormat::Xsens { .. }, n)
                if n.starts_with("Vel_")
                    || n.starts_with("UTC_")
                    || matches!(n, "Latitude" | "Longitude" | "Altitude" | "Pressure") =>
            {
                Some("a navigation, time or air-data output, no inertial sensor's")
            }
            (FileFormat::ArduPilot, "EG" | "EA") => Some("an error count"),
            (FileFormat::ArduPilot, "GH" | "AH") => Some("a health flag"),
            (FileFormat::ArduPilot, "GHz" | "AHz") => Some("a sensor's sampling rate"),
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::header_unit::units_from_headers;
    use super::*;

    fn units(format: FileFormat, names: &[&str]) -> Vec<Option<(String, bool)>> {
        names
            .iter()
            .map(|n| format.column_unit(n).map(|u| (u.unit, u.rate)))
            .collect()
    }

    fn some(unit: &str, rate: bool) -> Option<(String, bool)> {
        Some((unit.to_string(), rate))
    }

    /// Kalibr's imu0.csv: its header is told only whole; its columns are rates in rad/s and
    /// m/s^2, taken where a name carries no unit of its own.
    #[test]
    fn kalibr_imu_csv() {
        let h = KALIBR_HEADER;
        let p = Path::new("imu0.csv");
        assert_eq!(file_format(&h, p), Some(FileFormat::Kalibr));
        assert_eq!(file_format(&h[..6], p), None);
        assert_eq!(file_format(&["t", "omega_x", "alpha_x"], p), None);
        let cols: Vec<(usize, &str)> = h
            .iter()
            .enumerate()
            .skip(1)
            .map(|(i, n)| (i + 1, *n))
            .collect();
        let fixed: Vec<Option<HeaderUnit>> = cols
            .iter()
            .map(|(_, n)| FileFormat::Kalibr.column_unit(n))
            .collect();
        let u = units_from_headers(&cols, &fixed, false, false)
            .unwrap()
            .unwrap();
        assert_eq!(u.units, ["rad", "rad", "rad", "m/s", "m/s", "m/s"]);
        assert!(u.rate);
        assert!(
            u.account
                .contains("`omega_x` rates in rad/s, by Kalibr's imu0.csv (unit rad)"),
            "{}",
            u.account
        );
        assert_eq!(FileFormat::Kalibr.column_unit("omega_w"), None);
        assert_eq!(FileFormat::Kalibr.column_unit("theta_x"), None);
        // A unit in a column's own name rules over the format's.
        let own = units_from_headers(&[(2, "omega_x [deg/s]")], &fixed[..1], false, false);
        assert_eq!(own.unwrap().unwrap().units, ["deg"]);
    }

    /// An Xsens export: rates of turn in rad/s, accelerations in m/s^2, velocity increments in
    /// m/s; the magnetometer and the orientation increments carry no unit from it.
    #[test]
    fn xsens_export() {
        let mt = [
            "PacketCounter",
            "SampleTimeFine",
            "Acc_X",
            "Gyr_Z",
            "FreeAcc_Y",
        ];
        let f = file_format(&mt, Path::new("MT_0123_000.txt")).unwrap();
        assert_eq!(f, FileFormat::Xsens { rates: true });
        assert_eq!(
            units(f, &mt[2..]),
            [some("m/s", true), some("rad", true), some("m/s", true)]
        );
        let dot = ["PacketCounter", "dq_X", "dv[1]", "dv[3]", "Mag_X", "Gyr_W"];
        let d = file_format(&dot, Path::new("x.csv")).unwrap();
        assert_eq!(d, FileFormat::Xsens { rates: false });
        assert_eq!(
            units(d, &dot[1..]),
            [None, some("m/s", false), some("m/s", false), None, None]
        );
        // The orientation increments are no channel; the velocity increments only beside rates.
        assert!(d.other_column("dq_X").is_some() && d.other_column("dv[1]").is_none());
        // An MTi-G's filter and receiver outputs are no channels either; an MTw's VelInc_X are
        // velocity increments.
        for n in [
            "Quat_q0",
            "Roll",
            "Euler_X",
            "Mat[1][1]",
            "Vel_E",
            "Latitude",
            "UTC_Nano",
        ] {
            assert!(f.other_column(n).is_some(), "{n}");
        }
        assert_eq!(
            units(d, &["VelInc_Y", "Gyr_X"]),
            [some("m/s", false), some("rad", true)]
        );
        assert!(f.other_column("VelInc_Y").is_some() && f.other_column("Gyr_X").is_none());
        assert!(f
            .other_column("dv[1]")
            .unwrap()
            .contains("--columns dv[1],dv[2],dv[3]"));
        // Without a counter or Xsens's clock, `Acc_X` alone fixes nothing.
        assert_eq!(
            file_format(&["time", "Acc_X", "Gyr_X"], Path::new("a")),
            None
        );
    }

    /// UZH-FPV's imu.txt (`# id timestamp ang_vel_x ...`): rad/s and m/s^2, all six names
    /// needed.
    #[test]
    fn uzh_fpv_imu_txt() {
        let h: Vec<&str> = ["# id", "timestamp"]
            .into_iter()
            .chain(UZH_FPV_COLUMNS)
            .collect();
        let f = file_format(&h, Path::new("imu.txt")).unwrap();
        assert_eq!(f, FileFormat::UzhFpv);
        assert_eq!(
            units(f, &["ang_vel_y", "lin_acc_z", "ang_vel_w", "id"]),
            [some("rad", true), some("m/s", true), None, None]
        );
        assert_eq!(file_format(&h[..7], Path::new("imu.txt")), None);
    }

    /// Sensor Logger: the header is the same in every sensor's file, so the file's name tells
    /// the unit; a file renamed, or another sensor's (the magnetometer's), fixes none.
    #[test]
    fn sensor_logger_files() {
        let h = SENSOR_LOGGER_HEADER;
        let at = |p: &str| file_format(&h, Path::new(p));
        let g = at("run/Gyroscope.csv").unwrap();
        assert_eq!(g, FileFormat::SensorLogger { gyro: true });
        assert_eq!(
            units(g, &["z", "x", "seconds_elapsed"]),
            [some("rad", true), some("rad", true), None]
        );
        for a in ["Accelerometer.csv", "TotalAcceleration.csv", "Gravity.csv"] {
            let f = at(a).unwrap();
            assert_eq!(units(f, &["y"]), [some("m/s", true)], "{a}");
        }
        assert_eq!(at("Magnetometer.csv"), None);
        assert_eq!(at("phone.csv"), None);
        assert_eq!(at("-"), None);
        // More columns than the app writes: not its file.
        let more = ["time", "seconds_elapsed", "z", "y", "x", "accuracy"];
        assert_eq!(file_format(&more, Path::new("Gyroscope.csv")), None);
    }
}
