//! Files whose format fixes their columns' units and roles (src/input/format_units.rs): an
//! Xsens MT Manager or DOT export, UZH-FPV's `imu.txt`, the Sensor Logger app's
//! `Gyroscope.csv`, ArduPilot's IMU messages as pymavlink exports them. Each reads as the same
//! columns told by hand (`--columns C --rate --unit U`); the same header elsewhere (another
//! file name, a header not whole) fixes nothing. Columns that are no channel by their name
//! (a status word, a magnetometer, a magnitude, an instance number) are left out, said; rows of
//! several sensors interleaved, and DataFlash logs themselves, are usage errors saying what to
//! do.

use crate::common::tmp_in;
use std::path::PathBuf;
use std::process::Output;

use allanscope::sink::records::CurveRecord;

/// A deterministic value in [-0.5, 0.5) for row `i`, column `k`.
fn noise(i: u64, k: u64) -> f64 {
    let x = (i * 2_654_435_761 + k * 40_503 + 12_345) % 1_000_003;
    x as f64 / 1_000_003.0 - 0.5
}

fn write(name: &str, text: &str) -> PathBuf {
    let p = tmp_in("cli_format_units", name);
    std::fs::write(&p, text).unwrap();
    p
}

use crate::common::analyze_avar as analyze;

/// The final curves of a run that must succeed.
fn curves(out: &Output) -> Vec<CurveRecord> {
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    crate::common::final_curve_records(out)
}

fn curve<'a>(cs: &'a [CurveRecord], channel: &str) -> &'a CurveRecord {
    cs.iter()
        .find(|c| c.channel == channel)
        .unwrap_or_else(|| panic!("no curve of {channel}"))
}

fn channels(cs: &[CurveRecord]) -> Vec<&str> {
    cs.iter().map(|c| c.channel.as_str()).collect()
}

fn tau0(c: &CurveRecord) -> f64 {
    c.tau[0] / c.m[0] as f64
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn usage_error(out: &Output, needles: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
    assert!(out.stdout.is_empty(), "records written before the error");
}

/// An Xsens MT Manager export (notes, tabs, `SampleTimeFine` in 100 us at 100 Hz): `Gyr_X` in
/// rad/s, `Acc_Z` in m/s^2, as told by hand; the magnetometer and the status word no channels;
/// tau0 0.01 s.
#[test]
fn xsens_mt_manager_export() {
    let mut s = String::from(
        "// Start Time: Unknown\n// Update Rate: 100.0Hz\n// Filter Profile: human (46.1)\n\
         PacketCounter\tSampleTimeFine\tAcc_X\tAcc_Y\tAcc_Z\tGyr_X\tGyr_Y\tGyr_Z\tMag_X\tStatus\n",
    );
    for i in 0..600u64 {
        s += &format!(
            "{}\t{}\t{:.6}\t{:.6}\t{:.6}\t{:.6}\t{:.6}\t{:.6}\t{:.4}\t3\n",
            i,
            51_000 + i * 100,
            0.02 * noise(i, 1),
            0.02 * noise(i, 2),
            9.81 + 0.02 * noise(i, 3),
            0.01 * noise(i, 4),
            0.01 * noise(i, 5),
            0.01 * noise(i, 6),
            0.4 + 0.01 * noise(i, 7),
        );
    }
    let p = write("MT_01234567_000.txt", &s);
    let out = analyze(&p, &[]);
    let err = stderr(&out);
    let read = curves(&out);
    assert_eq!(
        channels(&read),
        ["Acc_X", "Acc_Y", "Acc_Z", "Gyr_X", "Gyr_Y", "Gyr_Z"]
    );
    assert!(
        err.contains("`Gyr_X` rates in rad/s, by its Xsens export (unit rad)"),
        "{err}"
    );
    assert!(
        err.contains("column 9 `Mag_X` holds a magnetic field, by its name"),
        "{err}"
    );
    assert!(
        err.contains("column 10 `Status` holds a status word, by its name"),
        "{err}"
    );
    assert!((tau0(&read[0]) - 0.01).abs() < 1e-12);
    for (c, unit) in [("Gyr_X", "rad"), ("Acc_Z", "m/s")] {
        let told = curves(&analyze(&p, &["--columns", c, "--rate", "--unit", unit]));
        assert_eq!(curve(&read, c), &told[0], "{c}");
        assert_eq!(told[0].unit, unit);
    }
}

/// An Xsens DOT's export: its `SampleTimeFine` counts us (60 Hz: steps of 16666 and 16667),
/// not an MTi's 100 us (which at 1 Hz steps by 10000); `dv[1]` are velocity increments in m/s;
/// the orientation increments `dq_*` (half angles) are no channels.
#[test]
fn xsens_dot_export() {
    let mut s = String::from("PacketCounter,SampleTimeFine,dq_W,dq_X,dv[1],dv[2]\n");
    for i in 0..600u64 {
        s += &format!(
            "{},{},{:.9},{:.9},{:.9},{:.9}\n",
            i,
            7_000_000 + (i as f64 * 1e6 / 60.0).round() as u64,
            1.0 - 1e-9 * noise(i, 1).abs(),
            1e-4 * noise(i, 2),
            1e-4 * noise(i, 3),
            1e-4 * noise(i, 4),
        );
    }
    let p = write("dot_export.csv", &s);
    let out = analyze(&p, &[]);
    let err = stderr(&out);
    let read = curves(&out);
    assert!(
        (tau0(&read[0]) - 1.0 / 60.0).abs() < 1e-6,
        "{}",
        tau0(&read[0])
    );
    assert!(err.contains("an Xsens DOT's clock counts us"), "{err}");
    assert_eq!(curve(&read, "dv[1]").unit, "m/s");
    assert_eq!(channels(&read), ["dv[1]", "dv[2]"]);
    assert!(
        err.contains("`dq_X` holds an orientation increment as a quaternion (half angles)"),
        "{err}"
    );
    let told = curves(&analyze(&p, &["--columns", "dv[2]", "--unit", "m/s"]));
    assert_eq!(curve(&read, "dv[2]"), &told[0]);
    // No gaps in a 60 Hz clock of 16666 and 16667 us steps.
    assert!(!err.contains("missing"), "{err}");
    // An MTi at 1 Hz: 10000 steps of 100 us, tau0 1 s.
    let mut s = String::from("PacketCounter,SampleTimeFine,Gyr_X\n");
    for i in 0..600u64 {
        s += &format!("{i},{},{:.6}\n", 1000 + i * 10_000, 0.01 * noise(i, 1));
    }
    let p = write("mti_1hz.csv", &s);
    assert_eq!(tau0(&curves(&analyze(&p, &[]))[0]), 1.0);
}

/// An MTi export of rates and velocity increments: one run reads rates or increments, so the
/// increments beside the rates are left out, said with the option that reads them alone.
#[test]
fn xsens_rates_beside_increments() {
    let mut s = String::from("PacketCounter\tSampleTimeFine\tAcc_X\tGyr_X\tdv[1]\tdv[2]\n");
    for i in 0..600u64 {
        s += &format!(
            "{i}\t{}\t{:.6}\t{:.6}\t{:.9}\t{:.9}\n",
            1000 + i * 25,
            0.02 * noise(i, 1),
            0.01 * noise(i, 2),
            1e-4 * noise(i, 3),
            1e-4 * noise(i, 4),
        );
    }
    let p = write("MT_both_000.txt", &s);
    let out = analyze(&p, &[]);
    let err = stderr(&out);
    assert_eq!(channels(&curves(&out)), ["Acc_X", "Gyr_X"]);
    assert!(
        err.contains("`dv[1]` holds velocity increments beside the rates (analyse them alone: --columns dv[1],dv[2],dv[3])"),
        "{err}"
    );
    let inc = curves(&analyze(&p, &["--columns", "dv[1],dv[2]"]));
    assert_eq!(channels(&inc), ["dv[1]", "dv[2]"]);
    assert_eq!(inc[0].unit, "m/s");
    let told = curves(&analyze(&p, &["--columns", "dv[2]", "--unit", "m/s"]));
    assert_eq!(curve(&inc, "dv[2]"), &told[0]);
}

/// UZH-FPV's `imu.txt` (a `#` header, spaces, `id`, seconds since 1970) and the Sensor Logger
/// app's `Gyroscope.csv` (ns since 1970, `seconds_elapsed`): rates in rad/s; the Sensor Logger
/// header in a file of another name fixes nothing.
#[test]
fn uzh_fpv_and_sensor_logger() {
    let mut s = String::from(
        "# id timestamp ang_vel_x ang_vel_y ang_vel_z lin_acc_x lin_acc_y lin_acc_z\n",
    );
    for i in 0..600u64 {
        s += &format!(
            "{i} {:.6} {:.9} {:.9} {:.9} {:.9} {:.9} {:.9}\n",
            1_540_820_000.0 + i as f64 * 0.002,
            0.01 * noise(i, 1),
            0.01 * noise(i, 2),
            0.01 * noise(i, 3),
            0.1 * noise(i, 4),
            0.1 * noise(i, 5),
            9.81 + 0.1 * noise(i, 6),
        );
    }
    let p = write("imu.txt", &s);
    let read = curves(&analyze(&p, &[]));
    assert_eq!(read.len(), 6, "{:?}", channels(&read));
    assert!((tau0(&read[0]) - 0.002).abs() < 1e-12);
    let told = curves(&analyze(
        &p,
        &["--columns", "lin_acc_y", "--rate", "--unit", "m/s"],
    ));
    assert_eq!(curve(&read, "lin_acc_y"), &told[0]);
    assert_eq!(curve(&read, "ang_vel_z").unit, "rad");

    let mut s = String::from("time,seconds_elapsed,z,y,x\n");
    for i in 0..600u64 {
        s += &format!(
            "{},{:.6},{:.6},{:.6},{:.6}\n",
            1_698_765_432_123_456_789u64 + i * 5_000_000,
            i as f64 * 0.005,
            0.01 * noise(i, 1),
            0.01 * noise(i, 2),
            0.01 * noise(i, 3),
        );
    }
    let g = write("Gyroscope.csv", &s);
    let out = analyze(&g, &[]);
    let read = curves(&out);
    assert_eq!(channels(&read), ["z", "y", "x"]);
    assert!(stderr(&out).contains("rates in rad/s, by Sensor Logger's Gyroscope.csv"));
    let told = curves(&analyze(&g, &["--columns", "x", "--rate", "--unit", "rad"]));
    assert_eq!(curve(&read, "x"), &told[0]);
    let other = write("phone.csv", &s);
    assert!(curves(&analyze(&other, &[])).iter().all(|c| c.unit == "u"));
}

/// ArduPilot's IMU messages through `mavlogdump.py --format csv`: one IMU's rows read with
/// `GyrX` in rad/s, `TimeUS` a second clock, `T` the temperature (in degC), `I` and the
/// message's bookkeeping fields no channels; two IMUs' rows interleaved are refused with the `awk` line that keeps one; a
/// DataFlash log itself (text or binary) is refused with the `mavlogdump.py` line.
#[test]
fn ardupilot_imu_messages() {
    let header = "timestamp,TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz\n";
    let row = |i: u64, imu: u64| {
        let us = 2_000_000 + i * 2500 + imu * 10;
        format!(
            "{:.6},{us},{imu},{:.6},{:.6},{:.6},{:.5},{:.5},{:.5},0,0,45.5,1,1,400,400\n",
            1_650_000_000.0 + us as f64 * 1e-6,
            0.01 * noise(i, 1 + imu),
            0.01 * noise(i, 2 + imu),
            0.01 * noise(i, 3 + imu),
            0.1 * noise(i, 4 + imu),
            0.1 * noise(i, 5 + imu),
            -9.81 + 0.1 * noise(i, 6 + imu),
        )
    };
    let one: String = std::iter::once(header.to_string())
        .chain((0..600).map(|i| row(i, 0)))
        .collect();
    let p = write("imu0_mav.csv", &one);
    let out = analyze(&p, &[]);
    let err = stderr(&out);
    let read = curves(&out);
    assert_eq!(
        channels(&read),
        ["GyrX", "GyrY", "GyrZ", "AccX", "AccY", "AccZ"],
        "{err}"
    );
    assert!((tau0(&read[0]) - 0.0025).abs() < 1e-12);
    for (name, what) in [
        ("TimeUS", "is a second time column"),
        ("I", "holds the number of the IMU its rows are of"),
        ("EG", "holds an error count"),
        (
            "T",
            "holds the unit's temperature, which diagnose fits the bias against (in degC)",
        ),
        ("AHz", "holds a sensor's sampling rate"),
    ] {
        assert!(err.contains(&format!("`{name}` {what}")), "{name}: {err}");
    }
    let told = curves(&analyze(
        &p,
        &["--columns", "AccZ", "--rate", "--unit", "m/s"],
    ));
    assert_eq!(curve(&read, "AccZ"), &told[0]);

    let both: String = std::iter::once(header.to_string())
        .chain((0..600).flat_map(|i| [row(i, 0), row(i, 1)]))
        .collect();
    let q = write("imus_mav.csv", &both);
    for extra in [&[][..], &["--tau0", "0.0025"], &["--columns", "GyrX"]] {
        usage_error(
            &analyze(&q, extra),
            &[
                "column 3 `I` numbers 2 sensors (0, 1) whose rows share the file",
                "`awk -F, '!/^[-+0-9.]/ || $3 == 0' ",
            ],
        );
    }
    // The line the message gives keeps IMU 0's rows: the one-IMU file's records.
    let kept: String = both
        .lines()
        .filter(|l| {
            !l.starts_with(|c: char| c.is_ascii_digit()) || l.split(',').nth(2) == Some("0")
        })
        .map(|l| format!("{l}\n"))
        .collect();
    let k = write("imu0_kept.csv", &kept);
    assert_eq!(curves(&analyze(&k, &[])), read);

    let text = write(
        "00000042.log",
        "FMT, 128, 89, FMT, BBnNZ, Type,Length,Name,Format,Columns\n\
         FMT, 130, 50, IMU, QBffffff, TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ\n\
         IMU, 2000000, 0, 0.001, 0.002, 0.003, 0.1, 0.2, -9.8\n",
    );
    let bin = tmp_in("cli_format_units", "00000042.BIN");
    std::fs::write(&bin, [0xa3, 0x95, 0x80, 0x80, 0x59, b'F', b'M', b'T', 0, 0]).unwrap();
    for (p, what) in [(&text, "as text (.log"), (&bin, "DataFlash log (.bin)")] {
        usage_error(
            &analyze(p, &[]),
            &[what, "mavlogdump.py --types IMU --format csv"],
        );
    }
    // With --tau0 no look at the start is needed, and standard input has none to look at: the
    // header the log's first line makes names `FMT` twice, and says what the file is.
    let needles = ["as text (.log", "mavlogdump.py --types IMU --format csv"];
    usage_error(&analyze(&text, &["--tau0", "0.0025"]), &needles);
    let mut child = crate::common::exe()
        .args(["analyze", "-", "--tau0", "0.0025", "--json"])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    use std::io::Write;
    let _ = child
        .stdin
        .take()
        .unwrap()
        .write_all(&std::fs::read(&text).unwrap());
    usage_error(&child.wait_with_output().unwrap(), &needles);
}

/// phyphox's `Absolute (rad/s)`, the norm of the three axes, is no channel though its unit is a
/// rate; `--channels` keeps it.
#[test]
fn a_magnitude_is_no_channel() {
    let mut s = String::from(
        "\"Time (s)\",\"Gyroscope x (rad/s)\",\"Gyroscope y (rad/s)\",\"Gyroscope z (rad/s)\",\"Absolute (rad/s)\"\n",
    );
    for i in 0..600u64 {
        let (x, y, z) = (noise(i, 1), noise(i, 2), noise(i, 3));
        s += &format!(
            "{:.9E},{x:.9E},{y:.9E},{z:.9E},{:.9E}\n",
            i as f64 * 0.005,
            (x * x + y * y + z * z).sqrt()
        );
    }
    let p = write("Gyroscope rate.csv", &s);
    let out = analyze(&p, &[]);
    assert!(stderr(&out).contains("`Absolute (rad/s)` holds a vector's magnitude, by its name"));
    assert_eq!(curves(&out).len(), 3);
    let kept = curves(&analyze(&p, &["--channels", "Absolute (rad/s)"]));
    assert_eq!(channels(&kept), ["Absolute (rad/s)"]);
    assert_eq!(kept[0].unit, "rad");
}
