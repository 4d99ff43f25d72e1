//! The unit a text column's header gives in brackets (EuRoC's `w_RS_S_x [rad s^-1]` and
//! `a_RS_S_x [m s^-2]`, a logger's `gyro_x (deg/s)` or `acc_x[g]`), read when no `--unit` is
//! given: which increment unit the column is in and whether it holds rates or increments
//! ([`header_unit`]), and for a whole input the channels' units and the one kind they share
//! ([`units_from_headers`]). The time column's unit (`timestamp [ns]`) is
//! [`super::text::time_column_unit`]'s; this module reads the data columns'.
//!
//! A ROS `sensor_msgs/Imu` field without brackets (`field.angular_velocity.x`,
//! `linear_acceleration.z`) is in the unit its message fixes: rad/s, m/s^2 (`ros_imu_field`).
//!
//! A header unit is read as a product of atoms with powers, `/` dividing (`rad/s`, `rad s^-1`,
//! `m/s^2`, `m.s-2`, `deg/sec`, `°/s`, `dps`), and classed by its one physical atom and its power
//! of time: an angle (rad, mrad, urad, deg, arcsec) is an increment, per second a rate; a
//! velocity (m/s, mm/s, ft/s) an increment, per second again a rate; an acceleration in g or mg a
//! rate, times s an increment. The increment unit is the one `--unit` would name
//! (`crate::model::units::IncrementUnit`). Anything else (a magnetometer's `[G]` or `[uT]`, a
//! temperature's `[degC]`) is not known, and the caller refuses it, naming column and header.

/// What a column's header says of its values.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct HeaderUnit {
    /// The increment's unit, as `--unit` names it (`rad`, `deg`, `m/s`, `g`).
    pub unit: String,
    /// The values are rates (the increment's unit per second), not increments.
    pub rate: bool,
    /// The unit as the header writes it (inside the brackets).
    pub text: String,
}

/// The unit in brackets at the end of a column's name: `Some(Ok)` when it is a unit this module
/// knows, `Some(Err(text))` when it is not (`text` is what the brackets hold), `None` when the
/// name carries no unit in brackets.
pub fn header_unit(name: &str) -> Option<Result<HeaderUnit, String>> {
    let n = name.trim();
    // `gyro_rad[0]`: an array's index in brackets (PX4's CSV export), not a unit.
    if let Some(base) = array_element(n) {
        return super::px4_export::field_unit(base).map(Ok);
    }
    match bracketed(n) {
        Some((_, inner)) => Some(parse(inner).ok_or_else(|| inner.to_string())),
        // A name that ends in a bracket it does not open, or is nothing but brackets, is a
        // name, not a unit.
        None if n.ends_with([']', ')']) => None,
        None => ros_imu_field(n).map(Ok),
    }
}

/// The increment unit of a `--unit` that is unambiguously a rate, read as a header's unit is
/// (`deg/s`, `rad s^-1`, `dps`, `m/s^2`, `m/s2`, `deg/h`: `deg`, `rad`, `deg`, `m/s`, `m/s`,
/// `arcsec`), or one that `--rate` takes as the rate's own (`deg/sec`, `g/s`:
/// [`crate::model::units::increment_unit_label`]). `None` for an increment unit (`deg`, `m/s`,
/// and `g`, `mg`, `ug`, which as an option are g*s: `IncrementUnit::parse`) and for a unit not
/// known. Before (session 42) a rate unit without `--rate` was read as increments, N 1 / tau0
/// times too large, while a header `gx [deg/s]` was read as rates.
pub fn option_rate_unit(unit: &str) -> Option<String> {
    use crate::model::units::{increment_unit_label, IncrementUnit};
    let t = unit.trim();
    if IncrementUnit::parse(t).is_some() {
        return None;
    }
    if let Some(u) = parse(t).filter(|u| u.rate) {
        return Some(u.unit);
    }
    let label = increment_unit_label(t, true);
    (label != t && IncrementUnit::parse(&label).is_some()).then_some(label)
}

/// Whether `wanted` (a name `--channels` or a stand config's `channels.include` gives) names
/// the channel `name`: the whole name, or the name without the unit in brackets that ends it
/// (`gx` names `gx [deg/s]`, as a person types it; before session 53 only the whole name did,
/// and a review's `--channels dvx` on a header `dvx [m/s]` was refused).
pub fn names_channel(wanted: &str, name: &str) -> bool {
    let wanted = wanted.trim();
    wanted == name.trim()
        || bracketed(name).is_some_and(|(bare, _)| !bare.is_empty() && bare == wanted)
}

/// A column's name split at the brackets that end it: the name before them and what they hold,
/// both trimmed (`gyro_x (deg/s)` -> `gyro_x`, `deg/s`); `None` when the name does not end in a
/// bracket, or holds nothing before it. The one reading of a unit in brackets: the header's
/// unit here, the temperature's (`super::temperature_column`), the name without its unit
/// (`super::text`).
pub fn bracketed(name: &str) -> Option<(&str, &str)> {
    let n = name.trim();
    let open = match n.chars().last()? {
        ']' => '[',
        ')' => '(',
        _ => return None,
    };
    let start = n.rfind(open)?;
    let base = n[..start].trim();
    (!base.is_empty()).then(|| (base, n[start + 1..n.len() - 1].trim()))
}

/// A ROS `sensor_msgs/Imu` field, whose unit the message fixes (REP 103): `angular_velocity.x`
/// in rad/s, `linear_acceleration.x` in m/s^2, as exports name them (`rostopic echo -p`'s
/// `field.angular_velocity.x`, a rosbag2 export's `angular_velocity.x`, PlotJuggler's
/// `/imu/angular_velocity/x`).
fn ros_imu_field(name: &str) -> Option<HeaderUnit> {
    let mut parts = name.rsplit(['.', '/']);
    let axis = parts.next()?;
    let field = parts.next()?;
    fixed_rate(
        field,
        axis,
        &[
            ("angular_velocity", "rad", "rad/s, by sensor_msgs/Imu"),
            ("linear_acceleration", "m/s", "m/s^2, by sensor_msgs/Imu"),
        ],
    )
}

/// The rate a format fixes for a vector's `field` (`table`: the field, its increment unit and
/// the unit as said) when `axis` is `x`, `y` or `z`.
fn fixed_rate(field: &str, axis: &str, table: &[(&str, &str, &str)]) -> Option<HeaderUnit> {
    if !matches!(axis, "x" | "y" | "z") {
        return None;
    }
    let &(_, unit, text) = table.iter().find(|(f, _, _)| *f == field)?;
    Some(HeaderUnit {
        unit: unit.into(),
        rate: true,
        text: text.into(),
    })
}

/// The name of the array a column is an element of (`gyro_rad` for `gyro_rad[0]`), when its
/// brackets hold only an index.
pub fn array_element(name: &str) -> Option<&str> {
    let inner = name.strip_suffix(']')?;
    let open = inner.rfind('[')?;
    let index = &inner[open + 1..];
    (!index.is_empty() && index.bytes().all(|b| b.is_ascii_digit())).then(|| inner[..open].trim())
}

/// What a column holds when its unit in brackets is that of a quantity no inertial sensor
/// measures (a magnetometer's `uT`, a barometer's `hPa`, a supply's `V`): such a column is no
/// channel unless the run names it. `G` and `mG` are not among these (a gauss as often as a g);
/// nor are temperatures (`super::temperature_column` reads them).
pub fn other_quantity(name: &str) -> Option<&'static str> {
    let (_, inner) = bracketed(name)?;
    let u = inner.replace(['\u{b5}', '\u{3bc}'], "u");
    let what = match u.as_str() {
        "uT" | "nT" | "mT" | "T" | "gauss" | "Gauss" | "Gs" | "mGauss" | "mgauss" => {
            "a magnetic field"
        }
        "Pa" | "hPa" | "kPa" | "mbar" | "bar" | "psi" | "mmHg" | "inHg" | "atm" => "a pressure",
        "V" | "mV" | "uV" | "Volts" | "volts" | "Volt" | "volt" => "a voltage",
        "A" | "mA" | "uA" => "a current",
        "%" | "%RH" => "a percentage",
        "lx" | "lux" => "an illuminance",
        "Hz" | "kHz" => "a frequency",
        "dB" | "dBm" => "a level in dB",
        _ => return None,
    };
    Some(what)
}

/// The physical atoms a header unit may hold: the name, the increment unit it gives, the power
/// of time it carries itself (`dps` is deg/s) and the power of time of its increment (`m/s` for
/// a length, `g*s` for an acceleration); one power below the increment's is a rate.
const ATOMS: [(&str, &str, i32, i32); 13] = [
    ("rad", "rad", 0, 0),
    ("mrad", "mrad", 0, 0),
    ("urad", "urad", 0, 0),
    ("deg", "deg", 0, 0),
    ("\u{b0}", "deg", 0, 0),
    ("arcsec", "arcsec", 0, 0),
    ("dps", "deg", -1, 0),
    ("m", "m/s", 0, -1),
    ("mm", "mm/s", 0, -1),
    ("ft", "ft/s", 0, -1),
    ("g", "g", 0, 1),
    ("mg", "mg", 0, 1),
    ("ug", "ug", 0, 1),
];

/// Names of the hour as a factor of a unit (`deg/h`, `°/hr`).
const HOURS: [&str; 4] = ["h", "hr", "hrs", "hour"];

fn parse(text: &str) -> Option<HeaderUnit> {
    let t = text
        .replace(['\u{b5}', '\u{3bc}'], "u")
        .replace('\u{b7}', "*")
        .replace('\u{b2}', "^2")
        .replace("\u{207b}\u{b9}", "^-1")
        .replace("\u{207b}\u{b2}", "^-2");
    // `G` is a gauss (magnetometers) as often as a g, and `mG`, `uG` (`µG`) a milli- or
    // microgauss as often as a milli- or micro-g: not taken.
    if t.split(|c: char| !c.is_alphanumeric())
        .any(|w| matches!(w, "G" | "mG" | "uG" | "UG" | "nG" | "kG"))
    {
        return None;
    }
    let t = t.to_lowercase();
    // A FOG's rate in deg/h: 1 deg/h over 1 s turns 1 arcsec, so it is a rate in arcsec/s.
    if t == "dph" {
        return Some(HeaderUnit {
            unit: "arcsec".into(),
            rate: true,
            text: text.to_string(),
        });
    }
    let mut atom: Option<(&str, i32)> = None;
    // The power of time of the whole unit, and of the hour in it.
    let mut time = 0i32;
    let mut hours = 0i32;
    for (i, part) in t.split('/').enumerate() {
        let sign: i32 = if i == 0 { 1 } else { -1 };
        let factors = part
            .split(|c: char| c.is_whitespace() || c == '*' || c == '.')
            .filter(|f| !f.is_empty());
        let mut any = false;
        for f in factors {
            any = true;
            let (base, power) = split_power(f)?;
            let power = sign.checked_mul(power)?;
            if base == "s" || base == "sec" {
                time = time.checked_add(power)?;
                continue;
            }
            if HOURS.contains(&base) {
                hours = hours.checked_add(power)?;
                continue;
            }
            let &(_, unit, own, incr) = ATOMS.iter().find(|(a, _, _, _)| *a == base)?;
            if atom.is_some() || power != 1 {
                return None;
            }
            time = time.checked_add(own)?;
            atom = Some((unit, incr));
        }
        if !any {
            return None;
        }
    }
    let (mut unit, incr) = atom?;
    // Per hour: only deg/h (arcsec/s, above); other units per hour have no increment unit.
    if hours != 0 {
        if (unit, hours, time, incr) != ("deg", -1, 0, 0) {
            return None;
        }
        unit = "arcsec";
        time = -1;
    }
    let rate = match time.checked_sub(incr)? {
        0 => false,
        -1 => true,
        _ => return None,
    };
    Some(HeaderUnit {
        unit: unit.to_string(),
        rate,
        text: text.to_string(),
    })
}

/// `s^-2`, `s-2`, `s2` -> (`s`, -2); a factor without a power has power 1.
fn split_power(f: &str) -> Option<(&str, i32)> {
    let at = f
        .find(|c: char| c == '^' || c == '-' || c == '+' || c.is_ascii_digit())
        .unwrap_or(f.len());
    let (base, rest) = f.split_at(at);
    if base.is_empty() {
        return None;
    }
    let rest = rest.strip_prefix('^').unwrap_or(rest);
    let power = if rest.is_empty() {
        1
    } else {
        rest.parse::<i32>().ok()?
    };
    Some((base, power))
}

/// The channels' units of a text input whose headers carry them, and the kind they share.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColumnUnits {
    /// Per channel, in the reader's order: the increment unit (`u` for a column whose header
    /// gives none).
    pub units: Vec<String>,
    /// The columns hold rates (every header with a unit says so).
    pub rate: bool,
    /// What was read, for the log: `` `w_RS_S_x [rad s^-1]`: rad/s `` per column, then the
    /// columns without a unit.
    pub account: String,
}

/// The units of `columns` (each channel's 1-based input column and header name) read from the
/// headers, when no `--unit` is given; `fixed` holds, per column (or none at all), the unit the
/// file's format fixes for a name that carries none (a PX4 message's `x`, Kalibr's `omega_x`),
/// taken when the name itself gives none. `rate`/`phase` are the options given. `Ok(None)`: no
/// header carries a unit (the columns are in `u`, as before). Errors (a usage error to the
/// caller, naming column and header): a unit not known; rates and increments mixed; `--rate`
/// on increments, or `--phase` on rates, by their headers.
pub fn units_from_headers(
    columns: &[(usize, &str)],
    fixed: &[Option<HeaderUnit>],
    rate: bool,
    phase: bool,
) -> Result<Option<ColumnUnits>, String> {
    let mut read: Vec<Option<HeaderUnit>> = Vec::new();
    for (i, &(col, name)) in columns.iter().enumerate() {
        match header_unit(name) {
            None => read.push(fixed.get(i).cloned().flatten()),
            Some(Ok(u)) => read.push(Some(u)),
            Some(Err(text)) => {
                return Err(format!(
                    "column {col} `{name}`: unit `{text}` in its header is not one allanscope \
                     knows (angles rad, mrad, urad, deg, arcsec; velocities m/s, mm/s, ft/s; \
                     accelerations g, mg, ug; each per s for a rate, as `rad/s`, `rad s^-1`, \
                     `m/s^2`, and deg/h); give --unit U for the columns' unit, or --columns to \
                     leave this one out"
                ))
            }
        }
    }
    let with: Vec<(usize, &HeaderUnit)> = read
        .iter()
        .enumerate()
        .filter_map(|(i, u)| u.as_ref().map(|u| (i, u)))
        .collect();
    let Some(&(first, u0)) = with.first() else {
        return Ok(None);
    };
    let name = |i: usize| format!("column {} `{}`", columns[i].0, columns[i].1);
    if let Some(&(other, _)) = with.iter().find(|(_, u)| u.rate != u0.rate) {
        let (r, inc) = if u0.rate {
            (first, other)
        } else {
            (other, first)
        };
        return Err(format!(
            "{} holds rates and {} increments by their headers (or their file's format): \
             analyse them in separate runs (--columns), or give --unit and --rate or not to read \
             them all one way",
            name(r),
            name(inc)
        ));
    }
    if rate && !u0.rate {
        return Err(format!(
            "--rate, but {} holds increments by its header unit `{}`: leave out --rate, or give \
             --unit to override the headers",
            name(first),
            u0.text
        ));
    }
    if phase && u0.rate {
        return Err(format!(
            "--phase, but {} holds rates by its header unit `{}`: leave out --phase, or give \
             --unit to override the headers",
            name(first),
            u0.text
        ));
    }
    let mut account: Vec<String> = with
        .iter()
        .map(|(i, u)| format!("`{}` {}", columns[*i].1, shown(u)))
        .collect();
    let bare: Vec<String> = read
        .iter()
        .enumerate()
        .filter(|(_, u)| u.is_none())
        .map(|(i, _)| format!("`{}`", columns[i].1))
        .collect();
    if !bare.is_empty() {
        account.push(format!("no unit (u) for {}", bare.join(", ")));
    }
    Ok(Some(ColumnUnits {
        units: read
            .iter()
            .map(|u| u.as_ref().map_or("u".to_string(), |u| u.unit.clone()))
            .collect(),
        rate: u0.rate,
        account: account.join(", "),
    }))
}

/// `rates in deg/s (unit deg)` or `increments in m/s (unit m/s)`: a header unit as the log
/// shows it, as written and as the records name it.
fn shown(u: &HeaderUnit) -> String {
    let what = if u.rate { "rates" } else { "increments" };
    format!("{what} in {} (unit {})", u.text, u.unit)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::units::IncrementUnit;

    fn unit(name: &str) -> (String, bool) {
        let u = header_unit(name)
            .unwrap_or_else(|| panic!("{name}: no unit"))
            .unwrap_or_else(|t| panic!("{name}: `{t}` not known"));
        // Every unit read is one `--unit` accepts, with datasheet units.
        assert!(
            IncrementUnit::parse(&u.unit).is_some(),
            "{name}: {}",
            u.unit
        );
        (u.unit, u.rate)
    }

    /// ROS `sensor_msgs/Imu` fields carry their units by the message: rad/s and m/s^2 rates.
    #[test]
    fn ros_imu_fields_are_rates_in_the_message_units() {
        for name in [
            "field.angular_velocity.x",
            "angular_velocity.z",
            "/imu/data/angular_velocity/y",
        ] {
            assert_eq!(unit(name), ("rad".to_string(), true), "{name}");
        }
        assert_eq!(
            unit("field.linear_acceleration.y"),
            ("m/s".to_string(), true)
        );
        for name in [
            "field.angular_velocity_covariance0",
            "field.orientation.x",
            "field.magnetic_field.x",
            "angular_velocity",
        ] {
            assert!(header_unit(name).is_none(), "{name}");
        }
    }

    /// `--unit` as a rate (its increment unit) or not: `g` stays the increment g*s it is
    /// documented as, `m/s` a velocity increment, `G` (a gauss) and `u` no unit of either.
    #[test]
    fn option_units_that_are_rates() {
        let rate = |u: &str| option_rate_unit(u);
        for (u, inc) in [
            ("deg/s", "deg"),
            ("deg/sec", "deg"),
            ("rad/s", "rad"),
            ("rad s^-1", "rad"),
            ("dps", "deg"),
            ("deg/h", "arcsec"),
            ("m/s^2", "m/s"),
            ("m/s2", "m/s"),
            ("m/s/s", "m/s"),
            ("g/s", "g"),
        ] {
            assert_eq!(rate(u).as_deref(), Some(inc), "{u}");
        }
        for u in [
            "deg", "rad", "m/s", "ft/s", "g", "mg", "ug", "g*s", "u", "G", "uT",
        ] {
            assert_eq!(rate(u), None, "{u}");
        }
    }

    #[test]
    fn the_units_datasets_write() {
        let r = |u: &str| (u.to_string(), true);
        let i = |u: &str| (u.to_string(), false);
        // EuRoC, TUM-VI.
        assert_eq!(unit("w_RS_S_x [rad s^-1]"), r("rad"));
        assert_eq!(unit("a_RS_S_x [m s^-2]"), r("m/s"));
        // Loggers and ROS exports.
        assert_eq!(unit("gyro_x (deg/s)"), r("deg"));
        assert_eq!(unit("acc_x[g]"), r("g"));
        assert_eq!(unit("acc_z [mg]"), r("mg"));
        assert_eq!(unit("gx [dps]"), r("deg"));
        assert_eq!(unit("gx [\u{b0}/s]"), r("deg"));
        assert_eq!(unit("wx [rad/sec]"), r("rad"));
        assert_eq!(unit("ax [m/s^2]"), r("m/s"));
        assert_eq!(unit("ax [m/s\u{b2}]"), r("m/s"));
        assert_eq!(unit("ax [m.s-2]"), r("m/s"));
        assert_eq!(unit("ax [m/s/s]"), r("m/s"));
        assert_eq!(unit("ax [ft/s^2]"), r("ft/s"));
        assert_eq!(unit("wx [mrad/s]"), r("mrad"));
        assert_eq!(unit("wx [\u{b5}rad/s]"), r("urad"));
        // A FOG's rate in deg/h is one in arcsec/s (1 deg/h turns 1 arcsec in 1 s); a
        // navigation accelerometer's in micro-g.
        for n in [
            "wx [deg/h]",
            "wx [deg/hr]",
            "wx (\u{b0}/h)",
            "wx [dph]",
            "wx [deg h^-1]",
        ] {
            assert_eq!(unit(n), r("arcsec"), "{n}");
        }
        assert_eq!(unit("az [\u{b5}g]"), r("ug"));
        assert_eq!(unit("az [ug]"), r("ug"));
        // Increments.
        assert_eq!(unit("dtheta_x [rad]"), i("rad"));
        assert_eq!(unit("dtheta_x [arcsec]"), i("arcsec"));
        assert_eq!(unit("dv_x [m/s]"), i("m/s"));
        assert_eq!(unit("dv_x [m s^-1]"), i("m/s"));
        assert_eq!(unit("dv_x [g*s]"), i("g"));
    }

    #[test]
    fn names_without_a_unit_and_units_not_known() {
        for n in ["gx", "w_RS_S_x", "(x)", "[a]", "gyro x"] {
            assert_eq!(header_unit(n), None, "{n}");
        }
        for (n, t) in [
            ("mag_x [G]", "G"),
            ("ax [mG]", "mG"),
            ("ax [\u{b5}G]", "\u{b5}G"),
            ("ax [uG]", "uG"),
            ("mag_x [uT]", "uT"),
            ("temp [degC]", "degC"),
            ("gx [rad/h]", "rad/h"),
            ("gx [deg/h^2]", "deg/h^2"),
            ("dtheta [deg*h]", "deg*h"),
            ("gx [rad/s^2]", "rad/s^2"),
            ("ax [m]", "m"),
            ("gx [rad rad/s]", "rad rad/s"),
            ("gx []", ""),
            ("acc (x)", "x"),
            (
                "gx [deg h^2147483647 h^2147483647 h^2]",
                "deg h^2147483647 h^2147483647 h^2",
            ),
            ("gx [deg s^2147483647 s^2]", "deg s^2147483647 s^2"),
        ] {
            assert_eq!(header_unit(n), Some(Err(t.to_string())), "{n}");
        }
    }

    /// A magnetometer's, a barometer's, a supply's column is another quantity; inertial units,
    /// temperatures and the ambiguous `G` are not.
    #[test]
    fn other_quantities() {
        for (n, w) in [
            ("mag_x [uT]", "a magnetic field"),
            ("mx (\u{b5}T)", "a magnetic field"),
            ("baro [hPa]", "a pressure"),
            ("vbat [V]", "a voltage"),
            ("rssi [dBm]", "a level in dB"),
        ] {
            assert_eq!(other_quantity(n), Some(w), "{n}");
        }
        for n in [
            "mag_x [G]",
            "acc [mG]",
            "gx [deg/s]",
            "temp [degC]",
            "mag_x",
            "x [a.u.]",
        ] {
            assert_eq!(other_quantity(n), None, "{n}");
        }
    }

    #[test]
    fn an_input_reads_one_kind_or_is_refused() {
        let euroc = [
            (2, "w_RS_S_x [rad s^-1]"),
            (5, "a_RS_S_x [m s^-2]"),
            (8, "status"),
        ];
        let u = units_from_headers(&euroc, &[], false, false)
            .unwrap()
            .unwrap();
        assert_eq!(u.units, ["rad", "m/s", "u"]);
        assert!(u.rate);
        assert!(
            u.account
                .contains("`w_RS_S_x [rad s^-1]` rates in rad s^-1 (unit rad)"),
            "{}",
            u.account
        );
        assert!(
            u.account.contains("no unit (u) for `status`"),
            "{}",
            u.account
        );
        // `--rate` agrees with the headers; `--phase` does not.
        assert!(units_from_headers(&euroc, &[], true, false)
            .unwrap()
            .is_some());
        let e = units_from_headers(&euroc, &[], false, true).unwrap_err();
        assert!(
            e.contains("--phase, but column 2 `w_RS_S_x [rad s^-1]`"),
            "{e}"
        );
        // Increments by their headers: `--rate` refused, `--phase` taken.
        let inc = [(1, "dth [deg]"), (2, "dv [m/s]")];
        let e = units_from_headers(&inc, &[], true, false).unwrap_err();
        assert!(e.contains("--rate, but column 1 `dth [deg]`"), "{e}");
        let u = units_from_headers(&inc, &[], false, true).unwrap().unwrap();
        assert_eq!((u.units, u.rate), (vec!["deg".into(), "m/s".into()], false));
        // Mixed kinds, a unit not known, no units at all.
        let e =
            units_from_headers(&[(1, "g [deg/s]"), (3, "d [deg]")], &[], false, false).unwrap_err();
        assert!(
            e.starts_with("column 1 `g [deg/s]` holds rates and column 3 `d [deg]` increments"),
            "{e}"
        );
        let e = units_from_headers(&[(4, "gyro_x (furlong/s)")], &[], false, false).unwrap_err();
        assert!(
            e.starts_with("column 4 `gyro_x (furlong/s)`: unit `furlong/s`"),
            "{e}"
        );
        assert_eq!(
            units_from_headers(&[(1, "gx")], &[], false, false),
            Ok(None)
        );
    }

    /// PX4's CSV export: an index in brackets is no unit; the fields whose unit the message
    /// fixes are read in it; other arrays carry none.
    #[test]
    fn px4_arrays() {
        let g = header_unit("gyro_rad[0]").unwrap().unwrap();
        assert_eq!((g.unit.as_str(), g.rate), ("rad", true));
        let a = header_unit("accelerometer_m_s2[2]").unwrap().unwrap();
        assert_eq!((a.unit.as_str(), a.rate), ("m/s", true));
        let d = header_unit("delta_velocity[1]").unwrap().unwrap();
        assert_eq!((d.unit.as_str(), d.rate), ("m/s", false));
        assert!(header_unit("magnetometer_ga[0]").is_none());
        assert!(header_unit("acc_x[g]").unwrap().is_ok());
    }
}
