//! The text column that holds the unit's temperature, as loggers name it: the simulator's
//! `temperature_c`, a logger's `temp [degC]`, `Temp (°C)`, `imu_temp`, `temperature`,
//! `board_temp (K)`. Such a column is not a channel: `analyze` leaves it out and `diagnose`
//! reads it (in degC) as the temperature its `temperature` effect is fitted against
//! (docs/gap.md, "Temperature").
//!
//! A column is a temperature when its header's unit in brackets is one (`degC`, `°C`, `℃`,
//! `celsius`, `kelvin`, `degF`, `°F`, `fahrenheit`; a bare `C`, `K` or `F` only beside a
//! temperature's name), or when its name has `temp` or `temperature` as a word (split at `_`,
//! `-`, `.`, `/` and spaces; `temperature_c`, `imu_temp`, `Temp`, `gyro temperature`), with no
//! unit or one of these: without a unit it is read as degC, and the log says so. Before
//! (session 29), only `temperature_c` was one: `temp [degC]` and `Temp (°C)` stopped the run
//! with exit 2 (a unit not known), and `temperature` was analysed as a channel.

/// How a temperature column's values become degC: `c = value * scale + offset`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TemperatureScale {
    pub scale: f64,
    pub offset: f64,
    /// The unit read (`degC`, `K`, `degF`), and whether the header named it.
    pub unit: &'static str,
    pub named: bool,
}

impl TemperatureScale {
    /// The value `v` of the column in degC.
    pub fn to_c(&self, v: f64) -> f64 {
        v * self.scale + self.offset
    }
}

/// degC, named so.
pub const CELSIUS: TemperatureScale = TemperatureScale {
    scale: 1.0,
    offset: 0.0,
    unit: "degC",
    named: true,
};
const KELVIN: TemperatureScale = TemperatureScale {
    scale: 1.0,
    offset: -273.15,
    unit: "K",
    named: true,
};
const FAHRENHEIT: TemperatureScale = TemperatureScale {
    scale: 5.0 / 9.0,
    offset: -32.0 * 5.0 / 9.0,
    unit: "degF",
    named: true,
};

/// Whether `name` (without its unit) names a temperature: `temp` or `temperature` as a word.
fn temperature_name(name: &str) -> bool {
    name.to_lowercase()
        .split(['_', '-', '.', '/', ' '])
        .any(|w| w == "temp" || w == "temperature")
}

/// The temperature unit a header's brackets hold, if they hold one; a bare letter only where
/// the name is a temperature's.
fn temperature_unit(inner: &str, temp_name: bool) -> Option<TemperatureScale> {
    let u: String = inner
        .chars()
        .filter(|c| !c.is_whitespace() && *c != '_')
        .collect::<String>()
        .to_lowercase();
    match u.as_str() {
        "degc" | "\u{b0}c" | "\u{2103}" | "celsius" | "degreesc" | "degreec" => Some(CELSIUS),
        "kelvin" => Some(KELVIN),
        "degf" | "\u{b0}f" | "\u{2109}" | "fahrenheit" => Some(FAHRENHEIT),
        "c" if temp_name => Some(CELSIUS),
        "k" if temp_name => Some(KELVIN),
        "f" if temp_name => Some(FAHRENHEIT),
        _ => None,
    }
}

/// Whether the text column `name` holds the unit's temperature, and how its values become
/// degC (module doc); `None` for any other column.
pub fn temperature_column(name: &str) -> Option<TemperatureScale> {
    let n = name.trim();
    match super::header_unit::bracketed(n) {
        Some((base, inner)) => temperature_unit(inner, temperature_name(base)),
        None => temperature_name(n).then_some(TemperatureScale {
            named: false,
            ..CELSIUS
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The names loggers write are temperatures, in their units; others are not.
    #[test]
    fn temperature_columns_as_loggers_name_them() {
        for (name, unit, named) in [
            ("temperature_c", "degC", false),
            ("temp [degC]", "degC", true),
            ("Temp (\u{b0}C)", "degC", true),
            ("T_imu [\u{2103}]", "degC", true),
            ("imu_temp", "degC", false),
            ("Temperature", "degC", false),
            ("gyro temperature (C)", "degC", true),
            ("board_temp (K)", "K", true),
            ("temp [degF]", "degF", true),
        ] {
            let t = temperature_column(name).unwrap_or_else(|| panic!("{name}"));
            assert_eq!((t.unit, t.named), (unit, named), "{name}");
        }
        for name in [
            "gx",
            "w_RS_S_x [rad s^-1]",
            "tempchan",
            "contemporary",
            "c (C)",
            "attempt",
            "time",
            "acc_x [g]",
        ] {
            assert!(temperature_column(name).is_none(), "{name}");
        }
        // 300 K and 212 degF in degC.
        let k = temperature_column("board_temp (K)").unwrap();
        assert!((k.to_c(300.0) - 26.85).abs() < 1e-12);
        let f = temperature_column("temp [degF]").unwrap();
        assert!((f.to_c(212.0) - 100.0).abs() < 1e-12);
    }
}
