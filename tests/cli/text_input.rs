//! Text columns as they come (issue 14): a byte-order mark, `;` separators, a time column,
//! `--columns` to pick and rename, and the errors (exit 2) for duplicate names, unknown columns,
//! a text column, and an input without one sample. Each file is written here and read through
//! the binary; the curves are compared with those of the same numbers written plainly.

use crate::common::exe;
use std::path::{Path, PathBuf};
use std::process::Output;

use allanscope::sink::records::{CurveRecord, Record, SummaryRecord};

fn tmp(name: &str) -> PathBuf {
    crate::common::tmp_in("cli_text", name)
}

/// 400 rows (401 phase points, the summary's `samples`) of two deterministic, unequal columns (no generator needed: the test compares two
/// readings of the same numbers, so any values that are not constant do).
fn columns() -> (Vec<f64>, Vec<f64>) {
    let a = (0..400)
        .map(|i| ((i * 37 % 101) as f64 - 50.0) * 1e-3)
        .collect();
    let b = (0..400)
        .map(|i| ((i * 53 % 89) as f64 - 44.0) * 2e-3)
        .collect();
    (a, b)
}

fn write(name: &str, text: &[u8]) -> PathBuf {
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn rows(sep: &str, with_time: bool) -> String {
    let (a, b) = columns();
    let mut s = String::new();
    for i in 0..a.len() {
        if with_time {
            s += &format!("{:.3}{sep}", i as f64 * 0.01);
        }
        s += &format!("{:e}{sep}{:e}\n", a[i], b[i]);
    }
    s
}

fn analyze(path: &Path, extra: &[&str]) -> Output {
    exe()
        .args([
            "analyze",
            path.to_str().unwrap(),
            "--tau0",
            "0.01",
            "--fit",
            "none",
        ])
        .args(["--stats", "avar"])
        .args(extra)
        .output()
        .unwrap()
}

fn parsed(out: &Output) -> (Vec<CurveRecord>, SummaryRecord) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let recs: Vec<Record> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let curves = recs
        .iter()
        .filter_map(|r| match r {
            Record::Curve(c) if c.r#final => Some(c.clone()),
            _ => None,
        })
        .collect();
    let Some(Record::Summary(s)) = recs.last() else {
        panic!("summary last")
    };
    (curves, s.clone())
}

fn plain() -> (Vec<CurveRecord>, SummaryRecord) {
    let p = write(
        "plain.csv",
        format!("gx,gy\n{}", rows(",", false)).as_bytes(),
    );
    parsed(&analyze(&p, &[]))
}

fn usage_error(out: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in: {err}");
    }
}

#[test]
fn bom_semicolons_and_a_time_column_read_as_the_plain_file() {
    let (pc, ps) = plain();
    assert_eq!(ps.channels, ["gx", "gy"]);
    assert_eq!(ps.samples, [401, 401]);
    let mut text = b"\xef\xbb\xbf".to_vec();
    text.extend_from_slice(format!("Time;gx;gy\n{}", rows(";", true)).as_bytes());
    let p = write("bom_semicolon_time.csv", &text);
    let (c, s) = parsed(&analyze(&p, &[]));
    assert_eq!(s.channels, ["gx", "gy"]);
    assert_eq!(s.samples, [401, 401]);
    assert_eq!(c.len(), pc.len());
    for (a, b) in c.iter().zip(&pc) {
        assert_eq!(a.channel, b.channel);
        assert_eq!(a.sigma, b.sigma);
    }
    // A BOM before the first name of a file without a time column.
    let mut text = b"\xef\xbb\xbf".to_vec();
    text.extend_from_slice(format!("gx\tgy\n{}", rows("\t", false)).as_bytes());
    let (c, s) = parsed(&analyze(&write("bom_tab.csv", &text), &[]));
    assert_eq!(s.channels, ["gx", "gy"]);
    assert_eq!(c[0].sigma, pc[0].sigma);
}

#[test]
fn a_named_time_column_and_columns_picked_and_renamed() {
    let (pc, _) = plain();
    let p = write(
        "stamp.csv",
        format!("stamp,gx,gy\n{}", rows(",", true)).as_bytes(),
    );
    let (c, s) = parsed(&analyze(&p, &["--time-column", "stamp"]));
    assert_eq!(s.channels, ["gx", "gy"]);
    assert_eq!(c[1].sigma, pc[1].sigma);
    // Without --time-column, `stamp` is a time column by its name too; `counter` is a
    // counter, no channel either unless --channels names it; `level` is a channel.
    let (_, s) = parsed(&analyze(&p, &[]));
    assert_eq!(s.channels, ["gx", "gy"]);
    for (name, channels) in [
        ("counter", vec!["gx", "gy"]),
        ("level", vec!["level", "gx", "gy"]),
    ] {
        let q = write(
            &format!("{name}.csv"),
            format!("{name},gx,gy\n{}", rows(",", true)).as_bytes(),
        );
        let (_, s) = parsed(&analyze(&q, &[]));
        assert_eq!(s.channels, channels);
    }
    let q = tmp("counter.csv");
    let (_, s) = parsed(&analyze(&q, &["--channels", "counter,gx"]));
    assert_eq!(s.channels, ["counter", "gx"]);
    // Picked in another order, one renamed.
    let (c, s) = parsed(&analyze(&p, &["--columns", "gy,gx=g1"]));
    assert_eq!(s.channels, ["gy", "g1"]);
    assert_eq!(s.samples, [401, 401]);
    assert_eq!(c[0].channel, "gy");
    assert_eq!(c[0].sigma, pc[1].sigma);
    assert_eq!(c[1].channel, "g1");
    assert_eq!(c[1].sigma, pc[0].sigma);
}

#[test]
fn bad_headers_and_columns_are_usage_errors_naming_them() {
    let p = write(
        "dup.csv",
        format!("gx,gy,gx\n{}", rows(",", true)).as_bytes(),
    );
    usage_error(
        &analyze(&p, &[]),
        &[
            "dup.csv",
            "line 1",
            "duplicate column name `gx`: columns 1 and 3",
        ],
    );
    let p = write(
        "cols.csv",
        format!("gx,gy\n{}", rows(",", false)).as_bytes(),
    );
    usage_error(
        &analyze(&p, &["--columns", "gx,gz=g3"]),
        &["--columns: no column named `gz`", "gx, gy"],
    );
    usage_error(
        &analyze(&p, &["--time-column", "clock"]),
        &["--time-column `clock`: no such column"],
    );
}

/// A column of text (a status word, a ROS export's `frame_id`) is a label, not a channel: left
/// out with a warning, the other columns read as the file without it. Named (`--columns`,
/// `--channels`), or a cell that is not a number and not text (`1.2.3`), it is an error; so is
/// an input without one sample.
#[test]
fn a_text_column_is_left_out_unless_named_and_an_input_without_samples_is_an_error() {
    let p = write(
        "status.csv",
        b"# log\ngx,state,gy\n0.1,OK,0.2\n0.3,OK,0.4\n0.5,FAIL,0.25\n",
    );
    let out = analyze(&p, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("line 3: column 2 `state` holds text (`OK`), not numbers: left out"),
        "{err}"
    );
    let (c, s) = parsed(&out);
    assert_eq!(
        (s.channels.clone(), s.samples.clone(), s.bad_rows),
        (vec!["gx".to_string(), "gy".into()], vec![4, 4], 0)
    );
    let (c2, _) = parsed(&analyze(&p, &["--columns", "gx,gy"]));
    assert_eq!(c.len(), c2.len());
    for (x, y) in c.iter().zip(&c2) {
        assert_eq!((&x.channel, &x.sigma), (&y.channel, &y.sigma));
    }
    for named in [["--columns", "gx,state"], ["--channels", "state"]] {
        usage_error(
            &analyze(&p, &named),
            &[
                "status.csv",
                "line 3",
                "column 2 `state`: `OK` is not a number",
            ],
        );
    }
    // A column of cells that are neither numbers nor words (version strings, addresses).
    let p = write("dotted.csv", b"gx,gy\n0.1,1.2.3\n0.3,1.2.4\n");
    usage_error(
        &analyze(&p, &[]),
        &[
            "dotted.csv",
            "line 2",
            "column 2 `gy`: `1.2.3` is not a number",
        ],
    );
    // One damaged first cell of a column of numbers: a bad row, as any later one.
    let p = write("dotted_first.csv", b"gx,gy\n0.1,1.2.3\n0.3,0.4\n0.5,0.6\n");
    let (_, s) = parsed(&analyze(&p, &[]));
    assert_eq!((s.bad_rows, s.samples.clone()), (1, vec![3, 3]));
    let p = write("empty_values.csv", b"gx,gy\nnan,nan\n,\nnan,\n");
    usage_error(&analyze(&p, &[]), &["empty_values.csv", "no samples"]);
    let p = write("header_only.csv", b"gx,gy\n");
    usage_error(&analyze(&p, &[]), &["header_only.csv", "no data rows"]);
}

/// A ROS 1 `rostopic echo -p` export as robotics users make it: `%time` in ns since 1970, a
/// `frame_id` label column, orientation and covariance columns that never change, a cell that
/// is not a number in a column the run does not analyse. With `--rate --channels`, no `--tau0`:
/// the step is read off `field.header.stamp`, nothing is lost, and the curves are those of the
/// same rates in a plain file, to the last bit; without `--channels` too (the orientation is
/// no channel); without `--rate` too, in rad by the message's units.
#[test]
fn a_rostopic_export_reads_as_the_plain_file() {
    let (a, b) = columns();
    let mut text = String::from(
        "%time,field.header.seq,field.header.stamp,field.header.frame_id,field.orientation.w,\
         field.angular_velocity.x,field.angular_velocity.y\n",
    );
    let mut plain = String::from("wx,wy\n");
    for i in 0..a.len() {
        let ns = 1_700_000_000_000_000_000u64 + i as u64 * 10_000_000;
        let w = if i == 123 { "n/a" } else { "1" };
        text += &format!("{},{i},{ns},imu_link,{w},{:e},{:e}\n", ns + 137, a[i], b[i]);
        plain += &format!("{:e},{:e}\n", a[i], b[i]);
    }
    let p = write("rostopic.csv", text.as_bytes());
    let q = write("rostopic_plain.csv", plain.as_bytes());
    let out = analyze_no_tau0(
        &p,
        &[
            "--rate",
            "--channels",
            "field.angular_velocity.x,field.angular_velocity.y",
        ],
    );
    let (c, s) = parsed(&out);
    let (pc, ps) = parsed(&analyze(&q, &["--rate"]));
    assert_eq!((s.tau0, s.bad_rows, s.invalid_values), (0.01, 0, 0));
    assert_eq!(s.samples, ps.samples);
    assert_eq!(c.len(), pc.len());
    for (x, y) in c.iter().zip(&pc) {
        assert_eq!(x.sigma, y.sigma);
    }
    // Without --channels: the driver's orientation is no channel (by the message), and the
    // rates are the only channels, their curves the same.
    let (c, _) = parsed(&analyze_no_tau0(&p, &["--rate"]));
    let mut channels: Vec<&str> = c.iter().map(|x| x.channel.as_str()).collect();
    channels.dedup();
    assert_eq!(
        channels,
        ["field.angular_velocity.x", "field.angular_velocity.y"]
    );
    for (x, y) in c.iter().zip(&pc) {
        assert_eq!(x.sigma, y.sigma);
    }
    // Without --rate or --unit: sensor_msgs/Imu's angular velocity is a rate in rad/s by the
    // message, so the records are in rad, the same numbers.
    let out = analyze_no_tau0(
        &p,
        &[
            "--channels",
            "field.angular_velocity.x,field.angular_velocity.y",
        ],
    );
    let (c, _) = parsed(&out);
    assert_eq!(c.len(), pc.len());
    for (x, y) in c.iter().zip(&pc) {
        assert_eq!((x.unit.as_str(), &x.sigma), ("rad", &y.sigma));
    }
    // A column renamed with a unit (`--columns "wx=wx [deg/s]"`) is in that unit.
    let out = analyze(&q, &["--columns", "wx=wx [deg/s],wy=wy [deg/s]"]);
    let (c, _) = parsed(&out);
    for (x, y) in c.iter().zip(&pc) {
        assert_eq!((x.unit.as_str(), &x.sigma), ("deg", &y.sigma));
    }
}

/// PX4's `ulog2csv` exports as they come, no `--tau0`, no `--unit`: sensor_combined's
/// `timestamp` in us since boot (jittered by a few us) gives tau0, its fields that describe
/// samples are no channels, `gyro_rad[0]` is in rad; sensor_gyro's `x`, `y` are in rad by the
/// message its file is named after. The curves are those of the same rates in a plain file.
#[test]
fn px4_exports_read_as_they_come() {
    let (a, b) = columns();
    let mut combined = String::from(
        "timestamp,gyro_rad[0],gyro_rad[1],gyro_integral_dt,accelerometer_timestamp_relative,\
         gyro_clipping,gyro_calibration_count\n",
    );
    let mut gyro = String::from("timestamp,timestamp_sample,device_id,x,y,temperature,samples\n");
    let mut plain = String::from("wx,wy\n");
    for i in 0..a.len() {
        let us = 20_313_000 + 4000 * i as u64 + (i as u64 * 7) % 5;
        combined += &format!("{us},{:e},{:e},4000,0,0,1\n", a[i], b[i]);
        gyro += &format!("{us},{},2490378,{:e},{:e},41.5,1\n", us - 150, a[i], b[i]);
        plain += &format!("{:e},{:e}\n", a[i], b[i]);
    }
    let q = write("px4_plain.csv", plain.as_bytes());
    let (pc, ps) = parsed(&analyze_no_tau0(&q, &["--rate", "--tau0", "0.004"]));
    for (name, text) in [
        ("log_1_sensor_combined_0.csv", &combined),
        ("log_1_sensor_gyro_0.csv", &gyro),
    ] {
        let p = write(name, text.as_bytes());
        let out = analyze_no_tau0(&p, &[]);
        let (c, s) = parsed(&out);
        assert_eq!((s.tau0, s.channels.len()), (0.004, 2), "{name}");
        assert_eq!(s.samples, ps.samples, "{name}");
        assert_eq!(c.len(), pc.len(), "{name}");
        for (x, y) in c.iter().zip(&pc) {
            assert_eq!((x.unit.as_str(), &x.sigma), ("rad", &y.sigma), "{name}");
        }
    }
}

/// An Arduino sketch's serial output saved to a file: greetings, then labelled values with a
/// `millis()` stamp. No `--tau0`: the step is read off `millis` (ms), the labels are the names,
/// and the curves are those of the same values in a plain file.
#[test]
fn an_arduino_serial_log_reads_as_the_plain_file() {
    let (a, b) = columns();
    let mut text = String::from("Initializing I2C devices...\nMPU6050 connection successful\n");
    let mut plain = String::from("ax,gz\n");
    for i in 0..a.len() {
        text += &format!("millis:{},ax:{:e},gz:{:e}\n", 2000 + 10 * i, a[i], b[i]);
        plain += &format!("{:e},{:e}\n", a[i], b[i]);
    }
    let p = write("arduino.txt", text.as_bytes());
    let q = write("arduino_plain.csv", plain.as_bytes());
    let (c, s) = parsed(&analyze_no_tau0(&p, &[]));
    let (pc, ps) = parsed(&analyze(&q, &[]));
    assert_eq!((s.tau0, s.channels.clone()), (0.01, ps.channels.clone()));
    assert_eq!((s.samples.clone(), s.bad_rows), (ps.samples.clone(), 0));
    assert_eq!(c.len(), pc.len());
    for (x, y) in c.iter().zip(&pc) {
        assert_eq!(x.sigma, y.sigma);
    }
}

/// A temperature column (`temp [degC]`) is the unit's temperature, not a channel, and the log
/// says so; named in --channels it is analysed as one too (with --unit, its header's unit being
/// no inertial one). Before, its unit stopped every run with exit 2.
#[test]
fn a_temperature_column_is_not_a_channel_unless_named() {
    let (a, _) = columns();
    let mut text = String::from("gx,temp [degC]\n");
    for (i, x) in a.iter().enumerate() {
        text += &format!("{x:e},{}\n", 20.0 + i as f64 * 0.01);
    }
    let p = write("with_temp.csv", text.as_bytes());
    let out = analyze(&p, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("column `temp [degC]` holds the unit's temperature")
            && err.contains("not a channel"),
        "{err}"
    );
    let (_, s) = parsed(&out);
    assert_eq!(s.channels, ["gx"]);
    let (c, s) = parsed(&analyze(&p, &["--channels", "temp [degC]", "--unit", "C"]));
    assert_eq!(
        (s.channels.clone(), s.samples.clone()),
        (vec!["temp [degC]".to_string()], vec![401])
    );
    // Increments 20 + 0.01 i every 10 ms: a rate ramp of 100 u/s^2, whose Allan deviation is
    // 100 tau / sqrt(2) (THEORY.md section 2, the R term).
    assert!(!c[0].sigma.is_empty());
    for (t, s) in c[0].tau.iter().zip(&c[0].sigma) {
        assert!(
            (s / (100.0 * t / 2f64.sqrt()) - 1.0).abs() < 1e-9,
            "{:?}",
            c[0].sigma
        );
    }
}

/// `--channels gy` names the column `gy [deg]` (the name without its unit, as a person types
/// it): the curve is that column's, bit for bit the plain file's `gy`, under its whole name; a
/// bare name two columns share is refused, naming both (session 53; before, `gy` was refused).
#[test]
fn a_channel_is_picked_by_its_name_without_the_unit() {
    let (_, plain_summary) = plain();
    let (plain_curves, _) = plain();
    let p = write(
        "units.csv",
        format!("gx [deg],gy [deg]\n{}", rows(",", false)).as_bytes(),
    );
    let (c, s) = parsed(&analyze(&p, &["--channels", "gy"]));
    assert_eq!(s.channels, ["gy [deg]"]);
    assert_eq!(s.samples, vec![plain_summary.samples[1]]);
    assert_eq!(c.len(), 1);
    assert_eq!(c[0].sigma, plain_curves[1].sigma);
    let twice = write(
        "units_twice.csv",
        format!("gy [deg],gy [rad]\n{}", rows(",", false)).as_bytes(),
    );
    usage_error(
        &analyze(&twice, &["--channels", "gy"]),
        &["`gy` names 2 channels", "gy [deg], gy [rad]"],
    );
}

/// A channel that never moves (a rate of 1.25 throughout, an orientation's `w` of 1): its
/// curves are exactly 0, nothing is fitted, and a warning says so with the rate. Before, the
/// rounding of the running sums (about 1e-19 u/s) was fitted as a "determined" noise term.
#[test]
fn a_constant_channel_has_curves_of_zero_and_no_fit() {
    let (a, _) = columns();
    let mut text = String::from("g,stuck\n");
    for x in &a {
        text += &format!("{x:e},1.25\n");
    }
    let p = write("constant.csv", text.as_bytes());
    let out = exe()
        .args([
            "analyze",
            p.to_str().unwrap(),
            "--tau0",
            "0.01",
            "--rate",
            "--json",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("stuck: every sample is the same, a rate of 1.25 u/s throughout"),
        "{err}"
    );
    assert!(!err.contains("g: every sample"), "{err}");
    let (c, _) = parsed(&out);
    let stuck: Vec<&CurveRecord> = c.iter().filter(|c| c.channel == "stuck").collect();
    assert_eq!(stuck.len(), 3);
    for c in &stuck {
        assert!(
            !c.sigma.is_empty() && c.sigma.iter().all(|&s| s == 0.0),
            "{:?}",
            c.sigma
        );
    }
    assert!(c
        .iter()
        .any(|c| c.channel == "g" && c.sigma.iter().all(|&s| s > 1e-4)));
    let fits: Vec<String> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .filter(|r| r["type"] == "fit")
        .map(|r| r["channel"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(fits, ["g"]);
}

/// The two columns with a time column (`scale` units per second), rows `skip` left out.
fn stamped(header: &str, scale: f64, skip: std::ops::Range<usize>) -> String {
    let (a, b) = columns();
    let mut s = format!("{header},gx,gy\n");
    for i in (0..a.len()).filter(|i| !skip.contains(i)) {
        s += &format!("{},{:e},{:e}\n", i as f64 * 0.01 * scale, a[i], b[i]);
    }
    s
}

#[test]
fn a_jump_of_the_time_column_is_a_gap_of_the_missing_samples() {
    // The same 400 rows with rows 200..210 marked missing (NaN) and no time column...
    let (a, b) = columns();
    let mut marked = String::from("gx,gy\n");
    for i in 0..a.len() {
        marked += &if (200..210).contains(&i) {
            "nan,nan\n".to_string()
        } else {
            format!("{:e},{:e}\n", a[i], b[i])
        };
    }
    let (mc, ms) = parsed(&analyze(&write("marked.csv", marked.as_bytes()), &[]));
    // ... and with those rows left out, the time column jumping from 1.99 s to 2.10 s: a jump
    // of 11 steps, 10 missing samples.
    for (name, header, scale) in [
        ("jump_s.csv", "time", 1.0),
        ("jump_ms.csv", "timestamp", 1e3),
    ] {
        let p = write(name, stamped(header, scale, 200..210).as_bytes());
        let (c, s) = parsed(&analyze(&p, &["--stats", "avar"]));
        // 400 steps of 0.01 s: the 10 missing samples are counted in the data's span.
        assert_eq!(s.t_data, 4.0, "{name}");
        assert_eq!(s.t_data, ms.t_data);
        assert_eq!(s.segments, [2, 2], "one gap in each channel: {name}");
        assert_eq!(s.samples, ms.samples);
        // The summary says so: one jump taken as a gap, 10 samples missing, in the column's unit.
        let t = s.time_column.as_ref().expect("summary.time_column");
        assert_eq!(
            (t.name.as_str(), t.used, t.unit.as_deref()),
            (header, true, Some(if scale == 1.0 { "s" } else { "ms" })),
            "{name}"
        );
        assert_eq!((t.gaps, t.missing_samples), (1, 10), "{name}");
        assert_eq!((t.backwards, t.irregular, t.discontinuities), (0, 0, 0));
        assert!(ms.time_column.is_none(), "no time column, no account");
        assert_eq!(c.len(), mc.len());
        for (x, y) in c.iter().zip(&mc) {
            assert_eq!((&x.channel, &x.tau), (&y.channel, &y.tau));
            assert_eq!(
                x.count, y.count,
                "differences across the gap left out: {name}"
            );
            assert_eq!(x.sigma, y.sigma, "{name}");
        }
    }
    // Without the jump the same file is uniform and has no gap.
    let (_, s) = parsed(&analyze(
        &write("nojump.csv", stamped("time", 1.0, 0..0).as_bytes()),
        &[],
    ));
    assert_eq!(s.segments, [1, 1]);
}

#[test]
fn a_time_column_that_goes_backwards_or_is_not_uniform_is_reported() {
    let mut text = stamped("time", 1.0, 0..0);
    // Row 100 stamped 0.5 s (backwards from 0.99 s), row 300 at 3.004 s (0.4 step off).
    text = text
        .replacen("\n1,", "\n0.5,", 1)
        .replacen("\n3,", "\n3.004,", 1);
    let p = write("backwards.csv", text.as_bytes());
    let out = analyze(&p, &[]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    let (_, s) = parsed(&out);
    assert!(
        err.contains("the time column `time` goes backwards (0.99 -> 0.5)"),
        "{err}"
    );
    assert!(err.contains("not a whole number of steps"), "{err}");
    assert!(err.contains("1 steps backwards or repeated"), "{err}");
    // Nothing inserted: 400 rows, 4 s.
    assert_eq!(s.t_data, 4.0);
    // Row 300 at 3.004 s is 0.4 step off its place on the grid the stamps lie on (the rows
    // before and after it are on it: src/input/stamp_grid.rs): one stamp off, counted once.
    // Read step by step (before session 50) it was two steps off, 1.4 after 2.99 s and 0.6
    // before 3.01 s.
    let t = s.time_column.as_ref().expect("summary.time_column");
    assert_eq!(
        (t.gaps, t.missing_samples, t.backwards, t.irregular),
        (0, 0, 1, 1)
    );
    // A time column that is not in steps of tau0 (here --tau0 is 0.01, the column steps 0.02)
    // is refused in a file (a_tau0_the_time_column_contradicts_is_refused_and_none_reads_the_
    // rows_at_it); on standard input, which is not looked at before the run, it is reported and
    // only skipped.
    let mut child = exe()
        .args([
            "analyze", "-", "--tau0", "0.01", "--fit", "none", "--stats", "avar",
        ])
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    {
        use std::io::Write;
        let mut stdin = child.stdin.take().unwrap();
        stdin
            .write_all(stamped("time", 2.0, 0..0).as_bytes())
            .unwrap();
    }
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    let (_, s) = parsed(&out);
    assert!(
        err.contains("steps by 0.02 where --tau0 is 0.01 s"),
        "{err}"
    );
    assert_eq!(s.segments, [1, 1]);
    let t = s.time_column.as_ref().expect("summary.time_column");
    assert_eq!((t.used, t.unit.as_deref(), t.gaps), (false, None, 0));
}

/// A row in the middle that repeats the stamp before it with other values (an extra row), and
/// a stray row stamped 500 ms among 1200, 1210 ms, each count one step backwards; the
/// rows after them are on their clock, and the gap of rows 200..210 keeps its 10 samples.
/// Before, the repeat put the clock a step ahead of every later row (each counted backwards)
/// and the stray row then read as a clock restart: 71 backwards, 80 samples missing.
#[test]
fn one_repeated_or_backward_stamp_mid_file_counts_once() {
    let (a, b) = columns();
    let mut text = String::from("time_ms,gx,gy\n");
    for i in (0..a.len()).filter(|i| !(200..210).contains(i)) {
        text += &format!("{},{:e},{:e}\n", i * 10, a[i], b[i]);
        // Row 50 again with other values; a stray row stamped 500 ms after row 120.
        if i == 50 {
            text += "500,1e-3,-2e-3\n";
        }
        if i == 120 {
            text += "500,3e-3,4e-3\n";
        }
    }
    let out = analyze(&write("repeated_stamp.csv", text.as_bytes()), &[]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    let (_, s) = parsed(&out);
    let t = s.time_column.as_ref().expect("summary.time_column");
    assert_eq!(
        (
            t.backwards,
            t.irregular,
            t.gaps,
            t.missing_samples,
            t.duplicates
        ),
        (2, 0, 1, 10, 0),
        "{err}"
    );
    assert!(err.contains("2 steps backwards or repeated"), "{err}");
    // The two extra rows stay samples: 392 rows and the 10 missing, 4.02 s.
    assert!((s.t_data - 4.02).abs() < 1e-9, "{}", s.t_data);
}

/// A recording whose last line was cut while written (no line end): a field short, or its last
/// number cut (`0.00` where the rows write six decimals), is a bad row, counted in the summary's
/// `bad_rows` and named with its file and line; the same line complete is read, line end or
/// not. Before, the cut number was read as a sample (`bad_rows` 0).
#[test]
fn a_last_line_cut_while_written_is_counted_and_skipped() {
    let (a, b) = columns();
    let mut whole = String::from("time,gx,gy\n");
    for i in 0..a.len() {
        whole += &format!("{:.3},{:.6},{:.6}\n", i as f64 * 0.01, a[i], b[i]);
    }
    let last = format!("4.000,{:.6},0.012345", a[7]);
    for (name, tail, bad, samples) in [
        ("complete.csv", last.clone(), 0, 402),
        ("complete_ended.csv", format!("{last}\n"), 0, 402),
        ("cut_number.csv", last[..last.len() - 4].to_string(), 1, 401),
        ("cut_field.csv", last[..last.len() - 9].to_string(), 1, 401),
    ] {
        let p = write(name, format!("{whole}{tail}").as_bytes());
        let out = analyze(&p, &[]);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        let (_, s) = parsed(&out);
        assert_eq!((s.bad_rows, s.samples[1]), (bad, samples), "{name}: {err}");
        let said = format!("{name}: line 402: ");
        assert_eq!(
            err.contains(&said) && err.contains("the last line, without its line end"),
            bad == 1,
            "{name}: {err}"
        );
    }
}

/// Rows written twice (stamp and values repeated, as a logger or driver repeats a record) are
/// dropped and counted, and a later jump of the time column is still the gap it stands for:
/// the file with rows 50, 120, 121 and 150 doubled and rows 200..210 missing reads as the same
/// file without the doubles (the same curves to the last bit, 10 missing samples). Before, each
/// double put the clock a step ahead: 153 later rows counted "backwards" and the gap came out
/// 4 samples short (6 for 10).
#[test]
fn rows_written_twice_are_dropped_and_later_gaps_keep_their_size() {
    let single = stamped("time", 1.0, 200..210);
    let mut doubled = String::new();
    for (i, line) in single.lines().enumerate() {
        doubled += line;
        doubled += "\n";
        // Line 0 is the header: line i + 1 holds row i.
        if [51, 121, 122, 151].contains(&i) {
            doubled += line;
            doubled += "\n";
        }
    }
    let (c1, s1) = parsed(&analyze(&write("single.csv", single.as_bytes()), &[]));
    let out = analyze(&write("doubled.csv", doubled.as_bytes()), &[]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    let (c2, s2) = parsed(&out);
    assert!(err.contains("4 rows written twice dropped"), "{err}");
    let t = s2.time_column.as_ref().expect("summary.time_column");
    assert_eq!(
        (
            t.duplicates,
            t.gaps,
            t.missing_samples,
            t.backwards,
            t.irregular
        ),
        (4, 1, 10, 0, 0)
    );
    assert_eq!((s2.t_data, &s2.samples), (s1.t_data, &s1.samples));
    assert_eq!(c1.len(), c2.len());
    for (x, y) in c1.iter().zip(&c2) {
        assert_eq!(
            (&x.channel, &x.tau, &x.count),
            (&y.channel, &y.tau, &y.count)
        );
        assert_eq!(x.sigma, y.sigma);
    }
}

/// `analyze` with the given arguments and no `--tau0`.
fn analyze_no_tau0(path: &Path, extra: &[&str]) -> Output {
    exe()
        .args(["analyze", path.to_str().unwrap(), "--fit", "none"])
        .args(["--stats", "avar"])
        .args(extra)
        .output()
        .unwrap()
}

/// A dataset as EuRoC writes it: a commented header with units in brackets, nanosecond stamps
/// since 1970 (resolved to 256 ns as f64), rows 200..210 absent. Without `--tau0` the step is
/// read off the time column (0.01 s, said on standard error), and the records are those of the
/// same file given `--tau0 0.01`: the same curves, the gap found.
#[test]
fn a_euroc_file_needs_no_tau0() {
    let (a, b) = columns();
    let mut text = String::from("#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1]\n");
    for i in (0..a.len()).filter(|i| !(200..210).contains(i)) {
        let ns = 1_403_636_579_758_555_392u64 + i as u64 * 10_000_000;
        text += &format!("{ns},{:e},{:e}\n", a[i], b[i]);
    }
    let p = write("euroc_imu0.csv", text.as_bytes());
    let told = analyze(&p, &["--stats", "avar"]);
    let (tc, ts) = parsed(&told);
    let out = analyze_no_tau0(&p, &[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("tau0 0.01 s from the time column `timestamp [ns]`"),
        "{err}"
    );
    let (c, s) = parsed(&out);
    assert_eq!(s.tau0, 0.01);
    assert_eq!(s.channels, ["w_RS_S_x [rad s^-1]", "w_RS_S_y [rad s^-1]"]);
    assert_eq!(s.t_data, 4.0);
    assert_eq!(s.segments, [2, 2]);
    let t = s.time_column.as_ref().expect("time column");
    assert_eq!((t.unit.as_deref(), t.missing_samples), (Some("ns"), 10));
    assert_eq!(
        (s.samples.clone(), s.segments.clone()),
        (ts.samples, ts.segments)
    );
    assert_eq!(c.len(), tc.len());
    for (x, y) in c.iter().zip(&tc) {
        assert_eq!((&x.channel, &x.sigma), (&y.channel, &y.sigma));
    }
    // Piped in (`zcat imu0.csv.gz | allanscope analyze -`): the step read off the stream's
    // start, which the run then reads: the same records (refused before without --tau0).
    let piped = analyze_stdin(&["--fit", "none", "--stats", "avar"], text.into_bytes());
    let (pc, ps) = parsed(&piped);
    assert_eq!(
        (ps.tau0, ps.samples.clone(), ps.segments.clone()),
        (0.01, s.samples.clone(), s.segments.clone())
    );
    assert_eq!(pc.len(), c.len());
    for (x, y) in pc.iter().zip(&c) {
        assert_eq!((&x.channel, &x.sigma), (&y.channel, &y.sigma));
    }
}

/// A LabVIEW Measurement file (file header, segment header with `Y_Unit_Label`, `X_Value`
/// first, an empty `Comment` column, tabs and CRLF), no `--tau0`: the step read off `X_Value`,
/// the units off the header, and the records of the plain CSV with the same units in its names.
/// Without an x column, the step is the header's `Delta_X`.
#[test]
fn a_labview_measurement_file_needs_no_options() {
    let (a, b) = columns();
    let head = "LabVIEW Measurement\t\r\nWriter_Version\t2\r\nSeparator\tTab\r\n\
                Decimal_Separator\t.\r\nX_Columns\tOne\r\n***End_of_Header***\t\r\n\t\r\n\
                Channels\t2\t\t\r\nY_Unit_Label\tdeg/s\tdeg/s\t\r\nX_Dimension\tTime\tTime\t\r\n\
                Delta_X\t1.000000E-2\t1.000000E-2\t\r\n***End_of_Header***\t\t\t\r\n";
    let mut lvm = format!("{head}X_Value\tgx\tgy\tComment\r\n");
    let mut no_x = format!(
        "{}gx\tgy\tComment\r\n",
        head.replace("X_Columns\tOne", "X_Columns\tNo")
    );
    let mut plain = String::from("time,gx [deg/s],gy [deg/s]\n");
    for i in 0..a.len() {
        lvm += &format!("{:.6}\t{:e}\t{:e}\t\r\n", i as f64 * 0.01, a[i], b[i]);
        no_x += &format!("{:e}\t{:e}\t\r\n", a[i], b[i]);
        plain += &format!("{:.6},{:e},{:e}\n", i as f64 * 0.01, a[i], b[i]);
    }
    let want = parsed(&analyze_no_tau0(
        &write("plain_units.csv", plain.as_bytes()),
        &[],
    ));
    for (name, text, from) in [
        (
            "stand.lvm",
            lvm,
            "tau0 0.01 s from the time column `X_Value`",
        ),
        (
            "no_x.lvm",
            no_x,
            "tau0 0.01 s from the LabVIEW header's Delta_X",
        ),
    ] {
        let out = analyze_no_tau0(&write(name, text.as_bytes()), &[]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(from), "{err}");
        let (c, s) = parsed(&out);
        assert_eq!(s.channels, ["gx", "gy"]);
        assert_eq!((s.tau0, &s.samples, s.bad_rows), (0.01, &want.1.samples, 0));
        assert_eq!(c.len(), want.0.len());
        for (x, y) in c.iter().zip(&want.0) {
            assert_eq!((&x.unit, &x.sigma), (&y.unit, &y.sigma), "{name}");
        }
    }
}

/// Without `--tau0` and without a usable time column: exit 2 saying why, once.
#[test]
fn no_tau0_without_a_usable_time_column_is_a_usage_error() {
    let p = write(
        "no_time.csv",
        format!("gx,gy\n{}", rows(",", false)).as_bytes(),
    );
    usage_error(
        &analyze_no_tau0(&p, &[]),
        &["no_time.csv", "no time column"],
    );
    let mut irregular = String::from("time,gx\n");
    for i in 0..50u64 {
        irregular += &format!("{},{}\n", i * i, i % 7);
    }
    let p = write("irregular_time.csv", irregular.as_bytes());
    usage_error(
        &analyze_no_tau0(&p, &[]),
        &["irregular_time.csv", "irregular"],
    );
    // Standard input is looked at as a file is: no time column, no --tau0.
    let rows_only = format!("gx,gy\n{}", rows(",", false));
    usage_error(
        &analyze_stdin(&["--fit", "none"], rows_only.into_bytes()),
        &["-: ", "no time column"],
    );
    // Compressed bytes on standard input are told as such (its first bytes checked as a
    // file's are), not read as text without a time column.
    let mut gz = vec![0x1f, 0x8b, 0x08, 0x00];
    gz.extend((0..4000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8));
    usage_error(
        &analyze_stdin(&["--fit", "none"], gz),
        &["-: gzip-compressed", "zcat FILE | allanscope ... -"],
    );
}

/// `allanscope analyze - ARGS` with `bytes` on its standard input, written from a thread (the
/// run may stop reading before the end: the write's error is ignored).
fn analyze_stdin(args: &[&str], bytes: Vec<u8>) -> Output {
    let mut child = exe()
        .args(["analyze", "-"])
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    let feeder = std::thread::spawn(move || {
        use std::io::Write;
        let _ = stdin.write_all(&bytes);
    });
    let out = child.wait_with_output().unwrap();
    feeder.join().unwrap();
    out
}

/// A merged multi-rate file (`ax` logged at half the rate of `gx`, empty cells between): read
/// with `gx`, `ax` has no curve and the log says why and what to do; read alone
/// (`--channels ax`, no `--tau0`), its rows are its samples, 0.01 s apart, and its curve is
/// that of the same numbers written alone; a row of units and a word in a cell on the way.
#[test]
fn a_slower_stream_merged_into_the_rows_is_read_at_its_own_rate() {
    let (a, b) = columns();
    let mut merged = String::from("Zeit;gx;ax\ns;deg/s;g\n");
    let mut alone = String::from("gx\n");
    for i in 0..800 {
        let ax = if i % 2 == 0 {
            format!("{}", b[i / 2]).replace('.', ",")
        } else {
            String::new()
        };
        let gx = if i == 7 {
            "OVF".to_string()
        } else {
            format!("{}", a[i % 400]).replace('.', ",")
        };
        merged.push_str(&format!(
            "{};{gx};{ax}\n",
            format!("{:.3}", i as f64 * 0.005).replace('.', ",")
        ));
    }
    for x in &b {
        alone.push_str(&format!("{x}\n"));
    }
    let p = write("merged.csv", merged.as_bytes());
    let run = |args: &[&str]| {
        exe()
            .args([
                "analyze",
                p.to_str().unwrap(),
                "--fit",
                "none",
                "--stats",
                "avar",
            ])
            .args(args)
            .output()
            .unwrap()
    };
    let out = run(&[]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("channel `ax` holds a value on every 2nd row only"),
        "{err}"
    );
    assert!(
        err.contains("column 2 `gx [deg/s]` holds `OVF`, not a number"),
        "{err}"
    );
    let (c, s) = parsed(&out);
    assert_eq!(s.channels, ["gx", "ax"]);
    assert_eq!(s.tau0, 0.005);
    assert!(c.iter().any(|c| c.channel == "gx" && !c.sigma.is_empty()));
    assert!(c.iter().any(|c| c.channel == "ax" && c.sigma.is_empty()));
    assert_eq!(s.flagged_cells, 1);
    let (c, s) = parsed(&run(&["--channels", "ax"]));
    assert_eq!((s.tau0, s.samples.clone()), (0.01, vec![401]));
    // Given the file's row step as --tau0, it is said what the stream's own step is.
    let out = run(&["--channels", "ax", "--tau0", "0.005"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("give --tau0 0.01 (or leave it out)"), "{err}");
    let reference = exe()
        .args(["analyze"])
        .arg(write("ax_alone.csv", alone.as_bytes()))
        .args([
            "--tau0", "0.01", "--rate", "--unit", "g", "--fit", "none", "--stats", "avar",
        ])
        .output()
        .unwrap();
    let (r, _) = parsed(&reference);
    assert_eq!(c[0].tau, r[0].tau);
    assert_eq!(c[0].unit, "g");
    for (x, y) in c[0].sigma.iter().zip(&r[0].sigma) {
        assert!((x - y).abs() <= 1e-12 * y, "{x} vs {y}");
    }
}

#[test]
fn a_tau0_the_time_column_contradicts_is_refused_and_none_reads_the_rows_at_it() {
    // The time column steps by 0.01 s; --tau0 0.02 says otherwise. Before (session 42) the run
    // went on at 0.02 s with a warning and every coefficient scaled (N by sqrt 2).
    let p = write(
        "time_against_tau0.csv",
        format!("time,gx,gy\n{}", rows(",", true)).as_bytes(),
    );
    let out = exe()
        .args(["analyze", p.to_str().unwrap(), "--tau0", "0.02"])
        .args(["--fit", "none", "--stats", "avar"])
        .output()
        .unwrap();
    usage_error(
        &out,
        &[
            "--tau0 is 0.02 s",
            "tau0 0.01 s from the time column `time`",
            "0.5 times that",
            "--time-column none",
        ],
    );
    assert!(out.stdout.is_empty(), "no records before the refusal");
    assert_eq!(
        String::from_utf8_lossy(&out.stderr)
            .matches("--tau0 is")
            .count(),
        1,
        "said once"
    );
    // `--time-column none`: the time column is still no channel, the rows are samples at
    // 0.02 s. Increments read at twice the step give the same curve at twice the taus, its
    // deviations halved (sigma = rms second difference of the phase / (sqrt 2 tau)).
    let (pc, _) = plain();
    let out = exe()
        .args(["analyze", p.to_str().unwrap(), "--tau0", "0.02"])
        .args(["--time-column", "none", "--fit", "none", "--stats", "avar"])
        .output()
        .unwrap();
    let (c, s) = parsed(&out);
    assert_eq!(s.channels, ["gx", "gy"]);
    assert_eq!(s.tau0, 0.02);
    assert_eq!(c.len(), pc.len());
    for (a, b) in c.iter().zip(&pc) {
        for (x, y) in a.sigma.iter().zip(&b.sigma) {
            assert!((x / y - 0.5).abs() < 1e-12, "{x} vs {y}");
        }
    }
    // A clock in ms without a unit in its name (0, 10, 20, ...) agrees with --tau0 0.01.
    let mut text = String::from("time,gx,gy\n");
    for (i, line) in rows(",", false).lines().enumerate() {
        text += &format!("{},{line}\n", i * 10);
    }
    let (c, _) = parsed(&analyze(&write("time_in_ms.csv", text.as_bytes()), &[]));
    assert_eq!(c[0].sigma, pc[0].sigma);
    // A `time` that counts samples (0, 1, 2, ...) is no clock in another unit: read at
    // --tau0, the column not used to find gaps (as before session 42), not refused.
    let mut text = String::from("time,gx,gy\n");
    for (i, line) in rows(",", false).lines().enumerate() {
        text += &format!("{i},{line}\n");
    }
    let out = analyze(&write("time_in_samples.csv", text.as_bytes()), &[]);
    let (c, s) = parsed(&out);
    assert_eq!(c[0].sigma, pc[0].sigma);
    let t = s.time_column.as_ref().expect("summary.time_column");
    assert!(!t.used, "{t:?}");
    // Without --tau0, `none` has no step to read the rows at.
    let out = exe()
        .args(["analyze", p.to_str().unwrap(), "--time-column", "none"])
        .output()
        .unwrap();
    usage_error(&out, &["--time-column none", "--tau0"]);
}

/// A gyro's pulse counts in a column named `gz_cnt` (running, 0-3 pulses a row) beside `gx`: a
/// channel, not the file's sample counter. Before (session 42) its name made it the counter:
/// every step other than one was read as missing samples or a step back, `gx` broken into
/// stretches and the run's time stretched.
#[test]
fn an_axis_count_column_is_a_channel_not_the_sample_counter() {
    let (a, _) = columns();
    let mut text = String::from("gx,gz_cnt\n");
    let mut count = 0u64;
    for (i, x) in a.iter().enumerate() {
        count += [1u64, 3, 0, 2][i % 4];
        text += &format!("{x:e},{count}\n");
    }
    let (c, s) = parsed(&analyze(&write("axis_count.csv", text.as_bytes()), &[]));
    assert_eq!(s.channels, ["gx", "gz_cnt"]);
    assert_eq!(s.samples, [401, 401]);
    assert_eq!(s.segments, [1, 1]);
    assert_eq!(s.t_data, 4.0);
    assert!(s.time_column.is_none(), "{:?}", s.time_column);
    // gx reads as in the plain file.
    let (pc, _) = plain();
    assert_eq!(c[0].sigma, pc[0].sigma);
}

/// Fields in double quotes that hold the separator are one field each, by CSV's rule: a quoted
/// label with a comma (`"ok, nominal"`, and `""` for a quote inside) is a label column, quoted
/// decimal commas (`"0,01","1,5e-2"`, as spreadsheets export them) and quoted thousands
/// (`"2,001.523"`) are the numbers they write. Each reads as the same numbers written plainly,
/// to the last bit of every `sigma`. Before (session 42), every row was split at the commas in
/// the quotes, skipped as a row of too many fields, and the run stopped with exit 2.
#[test]
fn quoted_fields_holding_the_separator_read_as_the_plain_file() {
    let (pc, ps) = plain();
    let (a, b) = columns();
    let (mut label, mut comma) = (
        String::from("time,gx,status,gy\n"),
        String::from("\"time\",\"gx\",\"gy\"\n"),
    );
    for i in 0..a.len() {
        let t = format!("{:.2}", i as f64 * 0.01);
        let status = if i % 7 == 0 {
            "\"say \"\"hi\"\", ok\""
        } else {
            "\"ok, nominal\""
        };
        label += &format!("{t},{:e},{status},{:e}\n", a[i], b[i]);
        let dc = |x: String| format!("\"{}\"", x.replace('.', ","));
        comma += &format!(
            "{},{},{}\n",
            dc(t),
            dc(format!("{:e}", a[i])),
            dc(format!("{:e}", b[i]))
        );
    }
    for (name, text) in [("quoted_label.csv", label), ("quoted_comma.csv", comma)] {
        let (c, s) = parsed(&analyze(&write(name, text.as_bytes()), &[]));
        assert_eq!(s.channels, ["gx", "gy"], "{name}");
        assert_eq!(
            (s.samples.as_slice(), s.bad_rows),
            (ps.samples.as_slice(), 0)
        );
        let t = s.time_column.as_ref().expect("summary.time_column");
        assert_eq!((t.used, t.gaps, t.irregular), (true, 0, 0), "{name}");
        assert_eq!(c.len(), pc.len());
        for (x, y) in c.iter().zip(&pc) {
            assert_eq!((&x.channel, &x.sigma), (&y.channel, &y.sigma), "{name}");
        }
    }
    // Thousands: 1950.000 .. 2050.000 written `"2,001.523"` against `2001.523`.
    let big = |x: f64| format!("{:.3}", 2000.0 + 1e3 * x);
    let grouped = |s: String| format!("\"{},{}\"", &s[..1], &s[1..]);
    let (mut plain_big, mut quoted_big) = (String::from("gx,gy\n"), String::from("gx,gy\n"));
    for i in 0..a.len() {
        plain_big += &format!("{},{}\n", big(a[i]), big(b[i]));
        quoted_big += &format!("{},{}\n", grouped(big(a[i])), grouped(big(b[i])));
    }
    assert!(quoted_big.contains("\n\"2,001.000\","), "{quoted_big:.80}");
    let (want, _) = parsed(&analyze(&write("big.csv", plain_big.as_bytes()), &[]));
    let (c, s) = parsed(&analyze(
        &write("big_quoted.csv", quoted_big.as_bytes()),
        &[],
    ));
    assert_eq!(s.channels, ["gx", "gy"]);
    assert_eq!(s.bad_rows, 0);
    assert_eq!(c.len(), want.len());
    for (x, y) in c.iter().zip(&want) {
        assert_eq!((&x.channel, &x.sigma), (&y.channel, &y.sigma));
    }
}

/// Trailing separators, several of them (`gx;gy;;;` and rows ending `;;;`, with CRLF and
/// decimal commas, as a spreadsheet exports a sheet wider than its data), are no channels: the
/// channels are exactly `gx`, `gy`, with the plain file's curves. A column after the last name
/// that holds numbers is still a channel, named by its number (`c4`). Before (session 42), only
/// the last empty column was left out: `c3`, `c4` came out as channels with empty curves.
#[test]
fn trailing_empty_columns_are_no_channels() {
    let (pc, ps) = plain();
    let comma = |x: f64| format!("{x:e}").replace('.', ",");
    let (a, b) = columns();
    let (mut semi, mut fourth) = (String::from("gx;gy;;;\r\n"), String::from("gx,gy,,\n"));
    for i in 0..a.len() {
        semi += &format!("{};{};;;\r\n", comma(a[i]), comma(b[i]));
        fourth += &format!("{:e},{:e},,{:e}\n", a[i], b[i], b[i]);
    }
    let (c, s) = parsed(&analyze(&write("trailing3.csv", semi.as_bytes()), &[]));
    assert_eq!(s.channels, ["gx", "gy"]);
    assert_eq!(
        (s.samples.as_slice(), s.bad_rows),
        (ps.samples.as_slice(), 0)
    );
    assert_eq!(c.len(), pc.len());
    for (x, y) in c.iter().zip(&pc) {
        assert_eq!((&x.channel, &x.sigma), (&y.channel, &y.sigma));
    }
    let (c, s) = parsed(&analyze(&write("unnamed4.csv", fourth.as_bytes()), &[]));
    assert_eq!(s.channels, ["gx", "gy", "c4"]);
    let gy: Vec<_> = pc.iter().filter(|x| x.channel == "gy").collect();
    let c4: Vec<_> = c.iter().filter(|x| x.channel == "c4").collect();
    assert_eq!(c4.len(), gy.len());
    for (x, y) in c4.iter().zip(&gy) {
        assert_eq!(x.sigma, y.sigma);
    }
}

/// A time column whose first step is not tau0 still finds the gaps: the 400 rows with row 1
/// left out (the first step 0.02 s, one sample missing) and rows 200..210 left out read as the
/// file with those 11 rows empty (the same curves to the last bit, t_data 4 s, 2 gaps of 1 and
/// 10 samples); with the first stamp written twice (another value), the column is used too:
/// one repeated stamp, the gap of 10, 401 samples (4.01 s). Before (session 42), the first step
/// alone ruled the column out (`used: false`, no gap, t_data 3.89 s, the later gap joined).
#[test]
fn a_first_step_that_is_not_tau0_does_not_rule_the_time_column_out() {
    let (a, b) = columns();
    let missing = |i: usize| i == 1 || (200..210).contains(&i);
    let (mut marked, mut skipped) = (String::from("gx,gy\n"), String::from("time,gx,gy\n"));
    for i in 0..a.len() {
        if missing(i) {
            marked += "nan,nan\n";
        } else {
            marked += &format!("{:e},{:e}\n", a[i], b[i]);
            skipped += &format!("{:.2},{:e},{:e}\n", i as f64 * 0.01, a[i], b[i]);
        }
    }
    let (mc, ms) = parsed(&analyze(&write("first_marked.csv", marked.as_bytes()), &[]));
    let (c, s) = parsed(&analyze(&write("first_gap.csv", skipped.as_bytes()), &[]));
    assert_eq!((s.t_data, ms.t_data), (4.0, 4.0));
    assert_eq!(s.samples, ms.samples);
    let t = s.time_column.as_ref().expect("summary.time_column");
    assert_eq!(
        (t.used, t.unit.as_deref(), t.gaps, t.missing_samples),
        (true, Some("s"), 2, 11)
    );
    assert_eq!((t.backwards, t.irregular, t.discontinuities), (0, 0, 0));
    assert_eq!(c.len(), mc.len());
    for (x, y) in c.iter().zip(&mc) {
        assert_eq!(
            (&x.channel, &x.count, &x.sigma),
            (&y.channel, &y.count, &y.sigma)
        );
    }
    // The first stamp twice, the second time with another value; rows 200..210 left out: 391
    // rows, 401 steps with the gap's 10, and 393 phase points (391 rows in 2 segments).
    let mut dup = String::from("time,gx,gy\n0.00,0.0123,-0.0456\n");
    for i in (0..a.len()).filter(|i| !(200..210).contains(i)) {
        dup += &format!("{:.2},{:e},{:e}\n", i as f64 * 0.01, a[i], b[i]);
    }
    let out = analyze(&write("first_dup.csv", dup.as_bytes()), &[]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    let (_, s) = parsed(&out);
    assert!(
        err.contains(
            "line 3: the time column `time` goes nowhere (a repeated stamp) at its first step"
        ),
        "{err}"
    );
    let t = s.time_column.as_ref().expect("summary.time_column");
    assert_eq!(
        (t.used, t.gaps, t.missing_samples, t.backwards, t.irregular),
        (true, 1, 10, 1, 0)
    );
    assert_eq!(
        (s.t_data, s.samples.as_slice()),
        (4.01, [393, 393].as_slice())
    );
}

/// Rows that repeat the row before them in every column, the stamp moved on (a logger's stale
/// sample: 2% of 20 000 rows of two near-continuous channels). Those after the first 2000
/// pairs, once the repeats are judged the logger's (`input::row_ties`), are dropped without a
/// gap: the curves are, to the last bit, those of the same file with those rows left out and
/// the stamps closed up. The ones before stay (not judged by then), and a file without repeats
/// is read as it is.
#[test]
fn a_loggers_stale_rows_are_dropped_without_a_gap() {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(52);
    let n = 20_000;
    let mut fresh = Vec::with_capacity(n);
    for _ in 0..n {
        let a: f64 = rng.random::<f64>() - 0.5;
        let b: f64 = rng.random::<f64>() - 0.5;
        fresh.push((a, b));
    }
    // No two in a row: a run of equal rows is the stuck filter's.
    let mut stale = vec![false; n];
    for i in 1..n {
        stale[i] = !stale[i - 1] && rng.random::<f64>() < 0.02;
    }
    let mut rows = Vec::with_capacity(n);
    for i in 0..n {
        let v = if stale[i] { rows[i - 1] } else { fresh[i] };
        rows.push(v);
    }
    let text = |keep: &dyn Fn(usize) -> bool| {
        let mut s = String::from("time,gx,gy\n");
        for (k, i) in (0..n).filter(|&i| keep(i)).enumerate() {
            s += &format!(
                "{:.2},{:.9e},{:.9e}\n",
                k as f64 * 0.01,
                rows[i].0,
                rows[i].1
            );
        }
        s
    };
    // Row i makes pair i; the verdict is made at pair 2000.
    let late = |i: usize| stale[i] && i > 2000;
    let dropped = (0..n).filter(|&i| late(i)).count();
    let out = analyze(&write("stale.csv", text(&|_| true).as_bytes()), &[]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    let (c1, s1) = parsed(&out);
    let (c2, s2) = parsed(&analyze(
        &write("stale_closed.csv", text(&|i| !late(i)).as_bytes()),
        &[],
    ));
    assert!(dropped > 300, "{dropped}");
    assert!(
        err.contains(&format!("{dropped} rows repeat the row before them")),
        "{err}"
    );
    let t = s1.time_column.as_ref().expect("summary.time_column");
    assert_eq!((t.gaps, t.missing_samples, t.backwards), (0, 0, 0));
    assert_eq!((s1.t_data, &s1.samples), (s2.t_data, &s2.samples));
    assert_eq!(c1.len(), c2.len());
    for (x, y) in c1.iter().zip(&c2) {
        assert_eq!((&x.channel, &x.tau), (&y.channel, &y.tau));
        assert_eq!(x.sigma, y.sigma);
    }
    // Without the repeats nothing is said or dropped.
    let clean = analyze(&write("fresh.csv", text(&|i| !stale[i]).as_bytes()), &[]);
    let err = String::from_utf8_lossy(&clean.stderr);
    assert!(!err.contains("rows repeat"), "{err}");
}

/// Empty and `NaN` cells of an analysed channel are gaps, counted and said once at the end of
/// the input (a review found them counted nowhere); a column left out of the analysis is not
/// counted.
#[test]
fn empty_and_nan_cells_are_counted_and_said() {
    let (a, b) = columns();
    let mut s = String::from("gx,gy\n");
    for i in 0..a.len() {
        let x = match i {
            50 | 120 | 300 => "NaN".to_string(),
            77 | 201 => String::new(),
            _ => format!("{:e}", a[i]),
        };
        let y = if i == 90 {
            String::new()
        } else {
            format!("{:e}", b[i])
        };
        s += &format!("{x},{y}\n");
    }
    let path = write("cells.csv", s.as_bytes());
    let out = analyze(&path, &[]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("6 cells of the analysed channels were empty or not a number"),
        "{err}"
    );
    let out = analyze(&path, &["--channels", "gy"]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        err.contains("1 cell of the analysed channels was empty or not a number"),
        "{err}"
    );
}

/// Stamps 0.2% slower than `--tau0` over 2000 rows (a sample clock a little off its nominal
/// rate): read at `--tau0` as asked, and said with the stamps' mean step; stamps at `--tau0`
/// are not.
#[test]
fn stamps_off_the_stated_tau0_are_said() {
    let text = |step: f64| {
        let mut s = String::from("time,gx\n");
        for i in 0..2000 {
            s += &format!(
                "{:.6},{:e}\n",
                i as f64 * step,
                ((i * 37 % 101) as f64 - 50.0) * 1e-3
            );
        }
        s
    };
    let out = analyze(&write("slow_clock.csv", text(0.01002).as_bytes()), &[]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(out.status.success(), "{err}");
    assert!(
        err.contains("its stamps step 0.01002 s on average, +0.20% off --tau0 0.01 s"),
        "{err}"
    );
    let out = analyze(&write("right_clock.csv", text(0.01).as_bytes()), &[]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!err.contains("off --tau0"), "{err}");
}
