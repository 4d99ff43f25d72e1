//! Units, in one place: the constants (standard gravity, arcsec per radian, the foot), what a
//! channel's increment unit measures ([`SensorKind`], [`IncrementUnit`]), the unit expressions
//! of limits ([`Unit`], [`parse_unit`]), and the five coefficients in datasheet units beside the
//! native ones (docs/theory.md section 2), with the quantization check `Q / (LSB / sqrt(12))`.
//!
//! A channel's unit `u` is always the unit of its *increment* (an angle or a velocity change over
//! one sample), whether the input held increments, rates or phase. Datasheet units depend only
//! on the kind: a gyro is quoted in arcsec, deg/sqrt(h), deg/h, deg/h/sqrt(h), deg/h^2 and an
//! accelerometer in m/s, m/s/sqrt(h), micro-g, micro-g/sqrt(h), micro-g/h, whatever `u` is.
//! g-based units use standard gravity, [`G0_M_S2`] = 9.80665 m/s^2 (CGPM 1901; ISO 80000-3).

use serde::{Deserialize, Serialize};

/// Standard gravity (m/s^2), for g, mg and micro-g.
pub const G0_M_S2: f64 = 9.80665;
/// Arcseconds per degree.
pub const ARCSEC_PER_DEG: f64 = 3600.0;
/// Arcseconds per radian.
pub const ARCSEC_PER_RAD: f64 = 180.0 * ARCSEC_PER_DEG / std::f64::consts::PI;
/// Metres per international foot (exact).
pub const M_PER_FT: f64 = 0.3048;
/// Seconds per hour.
pub const S_PER_H: f64 = 3600.0;

/// What a channel's increment measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SensorKind {
    /// Angle increments (a gyro).
    Gyro,
    /// Velocity increments (an accelerometer).
    Accel,
}

/// A known increment unit: its kind and its size in SI (rad for an angle, m/s for a velocity).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IncrementUnit {
    pub kind: SensorKind,
    /// rad (gyro) or m/s (accelerometer) per unit.
    pub si_per_unit: f64,
}

impl IncrementUnit {
    /// Parses an increment unit: `rad`, `mrad`, `urad` (or `µrad`), `deg`, `arcsec` (angle);
    /// `m/s`, `mm/s`, `ft/s`, `g`, `mg`, `ug` (velocity; `g` as an increment is g*s, also
    /// written `g*s`, `g.s` or `g s`, likewise `mg*s`, `ug*s`; `µg` is `ug`). `None` for anything else (e.g. the default `u`).
    pub fn parse(unit: &str) -> Option<IncrementUnit> {
        let (kind, si) = match normalized(unit).as_str() {
            "rad" => (SensorKind::Gyro, 1.0),
            "mrad" => (SensorKind::Gyro, 1e-3),
            "urad" => (SensorKind::Gyro, 1e-6),
            "deg" => (SensorKind::Gyro, 1.0 / 180.0 * std::f64::consts::PI),
            "arcsec" => (SensorKind::Gyro, 1.0 / ARCSEC_PER_RAD),
            "m/s" => (SensorKind::Accel, 1.0),
            "mm/s" => (SensorKind::Accel, 1e-3),
            "ft/s" => (SensorKind::Accel, M_PER_FT),
            "g" | "g*s" => (SensorKind::Accel, G0_M_S2),
            "mg" | "mg*s" => (SensorKind::Accel, G0_M_S2 * 1e-3),
            "ug" | "ug*s" => (SensorKind::Accel, G0_M_S2 * 1e-6),
            _ => return None,
        };
        Some(IncrementUnit {
            kind,
            si_per_unit: si,
        })
    }

    /// The unit as a dimensioned [`Unit`] (angle in arcsec, length in m, time in s), for limits.
    pub fn as_unit(&self) -> Unit {
        match self.kind {
            SensorKind::Gyro => Unit {
                factor: self.si_per_unit * ARCSEC_PER_RAD,
                angle: 1.0,
                length: 0.0,
                time: 0.0,
            },
            SensorKind::Accel => Unit {
                factor: self.si_per_unit,
                angle: 0.0,
                length: 1.0,
                time: -1.0,
            },
        }
    }
}

/// The increment unit a `--unit` names. `--unit` is the unit of the increment whatever the
/// columns hold; with `--rate` the rate's own unit is accepted as meaning the same: `deg/s` (or
/// `deg/sec`) is `deg`, `m/s/s` and `m/s^2` are `m/s`, and a FOG's `deg/h` (`deg/hr`, `dph`)
/// is `arcsec` (1 deg/h turns 1 arcsec in 1 s). Anything else is returned as given.
pub fn increment_unit_label(unit: &str, rate: bool) -> String {
    let t = unit.trim();
    if !rate || IncrementUnit::parse(t).is_some() {
        return t.to_string();
    }
    if matches!(
        t.to_ascii_lowercase().as_str(),
        "deg/h" | "deg/hr" | "dph" | "\u{b0}/h" | "\u{b0}/hr"
    ) {
        return "arcsec".to_string();
    }
    if let Some(v) = t.strip_suffix("^2").filter(|v| v.ends_with("/s")) {
        if IncrementUnit::parse(v).is_some() {
            return v.to_string();
        }
    }
    for suffix in ["/s", "/sec"] {
        if let Some(v) = t.strip_suffix(suffix) {
            if IncrementUnit::parse(v).is_some() {
                return v.to_string();
            }
        }
    }
    t.to_string()
}

/// Index of each coefficient in the arrays below: Q, N, B, K, R.
pub const COEF_NAMES: [&str; 5] = ["Q", "N", "B", "K", "R"];

/// Native unit of each coefficient for a channel in `u` (docs/theory.md section 2 table).
///
/// An accelerometer counted in g (`g`, `mg`, `ug`, alone or as `g*s`) has increments of g*s,
/// so its labels are written out in the g unit itself: Q g*s, N g*sqrt(s) (= g/sqrt(Hz)), B g,
/// K g/sqrt(s), R g/s; `g/sqrt(s)` for N would be off by a second.
pub fn native_units(u: &str) -> [String; 5] {
    if let Some(g) = g_seconds_base(u) {
        return [
            format!("{g}*s"),
            format!("{g}*sqrt(s)"),
            g.to_string(),
            format!("{g}/sqrt(s)"),
            format!("{g}/s"),
        ];
    }
    [
        u.to_string(),
        format!("{u}/sqrt(s)"),
        format!("{u}/s"),
        format!("{u}/s/sqrt(s)"),
        format!("{u}/s^2"),
    ]
}

/// An increment unit as [`IncrementUnit::parse`] matches it: trimmed, `µ` as `u`, and `·`, `.`
/// or a space between factors as `*`.
fn normalized(unit: &str) -> String {
    unit.trim().replace('µ', "u").replace(['·', '.', ' '], "*")
}

/// The g unit (`g`, `mg`, `ug`) of an increment unit that is that unit times a second, as
/// [`IncrementUnit::parse`] reads `g`, `g*s`, `mg`, ...; `None` for any other unit.
pub fn g_seconds_base(u: &str) -> Option<&'static str> {
    match normalized(u).as_str() {
        "g" | "g*s" => Some("g"),
        "mg" | "mg*s" => Some("mg"),
        "ug" | "ug*s" => Some("ug"),
        _ => None,
    }
}

/// Datasheet unit labels of each kind, Q..R.
pub fn datasheet_units(kind: SensorKind) -> [&'static str; 5] {
    match kind {
        SensorKind::Gyro => ["arcsec", "deg/sqrt(h)", "deg/h", "deg/h/sqrt(h)", "deg/h^2"],
        SensorKind::Accel => [
            "m/s",
            "m/s/sqrt(h)",
            "micro-g",
            "micro-g/sqrt(h)",
            "micro-g/h",
        ],
    }
}

/// Factors that turn native coefficients `(Q, N, B, K, R)` (u, u/sqrt(s), u/s, u/s/sqrt(s),
/// u/s^2) into datasheet units ([`datasheet_units`]).
///
/// With `d` the unit in deg (gyro) or in m/s (accelerometer), `sqrt(s) = sqrt(h)/60`,
/// `s = h/3600`, and `ug = 9.80665e-6 m/s^2`:
/// gyro Q: `3600 d` arcsec; N: `60 d` deg/sqrt(h); B: `3600 d` deg/h; K: `3600 * 60 d`
/// deg/h/sqrt(h); R: `3600^2 d` deg/h^2. Accelerometer Q: `d` m/s; N: `60 d` m/s/sqrt(h);
/// B: `d / ug` micro-g; K: `60 d / ug` micro-g/sqrt(h); R: `3600 d / ug` micro-g/h.
/// (For a gyro in arcsec, `d = 1/3600`: N/60 is deg/sqrt(h) and B in arcsec/s is deg/h, the
/// checks of docs/theory.md section 2.)
pub fn datasheet_factors(unit: &IncrementUnit) -> [f64; 5] {
    match unit.kind {
        SensorKind::Gyro => {
            let d = unit.si_per_unit.to_degrees();
            [
                ARCSEC_PER_DEG * d,
                60.0 * d,
                S_PER_H * d,
                S_PER_H * 60.0 * d,
                S_PER_H * S_PER_H * d,
            ]
        }
        SensorKind::Accel => {
            let d = unit.si_per_unit;
            let ug = G0_M_S2 * 1e-6;
            [d, 60.0 * d, d / ug, 60.0 * d / ug, S_PER_H * d / ug]
        }
    }
}

/// Q, N, B, K, R in datasheet units, with their unit labels.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Datasheet {
    pub values: [f64; 5],
    pub units: [&'static str; 5],
}

/// Convert native coefficients `(Q, N, B, K, R)` into datasheet units ([`datasheet_factors`]).
pub fn datasheet(native: [f64; 5], unit: &IncrementUnit) -> Datasheet {
    let f = datasheet_factors(unit);
    Datasheet {
        values: std::array::from_fn(|i| native[i] * f[i]),
        units: datasheet_units(unit.kind),
    }
}

/// docs/theory.md section 2: uniform rounding of the phase with step `lsb` gives `Q = lsb / sqrt(12)`;
/// the ratio above 1 is excess white-phase noise.
pub fn quantization_ratio(q: f64, lsb: f64) -> f64 {
    q / (lsb / 12f64.sqrt())
}

// ---------------------------------------------------------------------------------------------
// Unit expressions (for limits)

/// A unit as a factor to (arcsec, m, s) and the exponents of angle, length and time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unit {
    pub factor: f64,
    pub angle: f64,
    pub length: f64,
    pub time: f64,
}

impl Unit {
    pub const ONE: Unit = Unit {
        factor: 1.0,
        angle: 0.0,
        length: 0.0,
        time: 0.0,
    };

    pub fn pow(self, e: f64) -> Unit {
        Unit {
            factor: self.factor.powf(e),
            angle: self.angle * e,
            length: self.length * e,
            time: self.time * e,
        }
    }

    pub fn times(self, o: Unit) -> Unit {
        Unit {
            factor: self.factor * o.factor,
            angle: self.angle + o.angle,
            length: self.length + o.length,
            time: self.time + o.time,
        }
    }

    pub fn same_dimension(&self, o: &Unit) -> bool {
        let eq = |a: f64, b: f64| (a - b).abs() < 1e-9;
        eq(self.angle, o.angle) && eq(self.length, o.length) && eq(self.time, o.time)
    }
}

/// One named unit of a unit expression. `g`, `mg`, `ug` are accelerations here (a limit on B in
/// micro-g); as a channel's increment unit `g` is g*s ([`IncrementUnit::parse`]).
pub fn atom(name: &str) -> Option<Unit> {
    let u = |factor, angle, length, time| Unit {
        factor,
        angle,
        length,
        time,
    };
    Some(match name {
        "1" => Unit::ONE,
        "arcsec" => u(1.0, 1.0, 0.0, 0.0),
        "deg" => u(ARCSEC_PER_DEG, 1.0, 0.0, 0.0),
        "rad" => u(ARCSEC_PER_RAD, 1.0, 0.0, 0.0),
        "mrad" => u(ARCSEC_PER_RAD * 1e-3, 1.0, 0.0, 0.0),
        "urad" => u(ARCSEC_PER_RAD * 1e-6, 1.0, 0.0, 0.0),
        "m" => u(1.0, 0.0, 1.0, 0.0),
        "mm" => u(1e-3, 0.0, 1.0, 0.0),
        "ft" => u(M_PER_FT, 0.0, 1.0, 0.0),
        "s" => u(1.0, 0.0, 0.0, 1.0),
        "min" => u(60.0, 0.0, 0.0, 1.0),
        "h" | "hr" => u(S_PER_H, 0.0, 0.0, 1.0),
        "g" => u(G0_M_S2, 0.0, 1.0, -2.0),
        "mg" => u(G0_M_S2 * 1e-3, 0.0, 1.0, -2.0),
        "ug" => u(G0_M_S2 * 1e-6, 0.0, 1.0, -2.0),
        _ => return None,
    })
}

/// Parses a unit expression: products and quotients of [`atom`]s with `^n` powers and
/// `sqrt(...)`, e.g. `deg/h/sqrt(h)`, `m/s/sqrt(h)`, `micro-g`. `None` when it is not one.
pub fn parse_unit(text: &str) -> Option<Unit> {
    let t = text
        .trim()
        .to_lowercase()
        .replace("micro-", "u")
        .replace('µ', "u")
        .replace(' ', "");
    if t.is_empty() {
        return None;
    }
    let mut out = Unit::ONE;
    for (i, tok) in t.split('/').enumerate() {
        let (inner, mut e) = match tok.strip_prefix("sqrt(").and_then(|r| r.strip_suffix(')')) {
            Some(x) => (x, 0.5),
            None => (tok, 1.0),
        };
        let (base, pow) = match inner.split_once('^') {
            Some((b, p)) => (b, p.parse::<f64>().ok().filter(|p| p.is_finite())?),
            None => (inner, 1.0),
        };
        e *= pow;
        if i > 0 {
            e = -e;
        }
        out = out.times(atom(base)?.pow(e));
    }
    Some(out)
}

/// A channel's unit as a dimensioned [`Unit`]: an increment unit when it is one (so `g` is g*s),
/// else a unit expression.
pub fn channel_unit(unit: &str) -> Option<Unit> {
    IncrementUnit::parse(unit)
        .map(|u| u.as_unit())
        .or_else(|| parse_unit(unit))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_units_name_the_increment() {
        assert_eq!(increment_unit_label("deg/s", true), "deg");
        assert_eq!(increment_unit_label("deg", true), "deg");
        assert_eq!(increment_unit_label("m/s", true), "m/s");
        assert_eq!(increment_unit_label("m/s^2", true), "m/s");
        assert_eq!(increment_unit_label("m/s/s", true), "m/s");
        assert_eq!(increment_unit_label("deg/s", false), "deg/s");
        assert_eq!(increment_unit_label("u", true), "u");
        // A FOG's deg/h is arcsec/s: 1 deg/h * 1 s = 1/3600 deg = 1 arcsec.
        for u in ["deg/h", "deg/hr", "dph", "\u{b0}/h"] {
            assert_eq!(increment_unit_label(u, true), "arcsec", "{u}");
        }
        assert_eq!(increment_unit_label("deg/h", false), "deg/h");
        let per_h = IncrementUnit::parse("deg").unwrap().si_per_unit / S_PER_H;
        let arcsec = IncrementUnit::parse("arcsec").unwrap().si_per_unit;
        assert!((per_h / arcsec - 1.0).abs() < 1e-12);
        let ug = IncrementUnit::parse("\u{b5}g").unwrap();
        assert_eq!(
            (ug.kind, ug.si_per_unit),
            (SensorKind::Accel, G0_M_S2 * 1e-6)
        );
    }

    #[test]
    fn g_increment_is_g_seconds() {
        let g = IncrementUnit::parse("g").unwrap();
        assert_eq!(g.kind, SensorKind::Accel);
        assert_eq!(g.si_per_unit, 9.80665);
        assert_eq!(IncrementUnit::parse("g*s"), Some(g));
        assert_eq!(IncrementUnit::parse("u"), None);
        // As a channel unit g is a velocity (m/s), not an acceleration.
        let u = channel_unit("g").unwrap();
        assert_eq!((u.length, u.time), (1.0, -1.0));
        // N of an increment in g*s is g*sqrt(s) (g/sqrt(Hz)), B is g; other units keep u/...
        assert_eq!(
            native_units("mg"),
            ["mg*s", "mg*sqrt(s)", "mg", "mg/sqrt(s)", "mg/s"].map(String::from)
        );
        assert_eq!(native_units("g*s")[1], "g*sqrt(s)");
        assert_eq!(native_units("deg")[1], "deg/sqrt(s)");
        assert_eq!(native_units("m/s")[2], "m/s/s");
    }
}
