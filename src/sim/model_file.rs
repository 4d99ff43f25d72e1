//! Noise-model files (TOML, `config/models/`): parsed into a checked [`SimModel`] before anything
//! is simulated. Every problem is reported with the file and the key (all of them, the first as
//! the error's key); unknown keys are rejected.
//!
//! ```toml
//! rate_hz = 250.0                 # or tau0_s = 0.004 (exactly one of them)
//! description = "free text"       # optional
//!
//! [stand]                         # optional: Earth rate and gravity on each sensor axis
//! latitude_deg = 56.8
//! gravity_m_s2 = 9.8166           # optional; default WGS-84 normal gravity at the latitude
//!
//! [temperature]                   # optional: the unit's temperature, also output per step
//! start_c = 20.0                  # T(t) = final + (start - final) e^{-t/time_constant}
//! final_c = 32.0                  #        + sine_amplitude sin(2 pi t / sine_period)
//! time_constant_s = 900.0
//! sine_amplitude_c = 0.5          # optional, default 0
//! sine_period_s = 3600.0          # required when sine_amplitude_c is not 0
//! reference_c = 32.0              # optional, default final_c: zero temperature-driven bias
//!
//! [[channel]]
//! name = "g4"                     # CSV column name
//! unit = "arcsec"                 # u; an axis needs an angle or velocity unit (model::units)
//! lsb = 0.004                     # optional: quantization step of the integrated signal (u)
//! axis = "down"                   # optional: up|down|north|south|east|west or [east, north, up]
//! bias = 0.0                      # u/s, default 0
//! Q = 0.0                         # u            white phase
//! N = 0.254                       # u/sqrt(s)    white rate
//! B = 0.225                       # u/s          flicker rate
//! K = 1.826e-2                    # u/s/sqrt(s)  rate random walk
//! R = 0.891e-4                    # u/s^2        rate ramp
//! flicker_band_s = [0.004, 1.0e4] # optional: tau range where B is flat; default [tau0, 1e6 tau0]
//! temperature_coefficient = 0.01  # optional: u/s per degC of T(t) - reference_c
//! gauss_markov = [{ sigma = 0.1, tau_c = 2.0 }]                     # u/s, s (table or list)
//! sinusoid = [{ amplitude = 0.05, frequency = 1.3, phase = 0.0 }]   # u/s, Hz, rad (table or list)
//! output_filter = { time_constant = 0.01 }                          # s
//! moving_average = { taps = 16, stages = 2 }     # or, in place of output_filter (one filter):
//! second_order_filter = { natural_frequency = 20.0, damping = 0.7 }  # Hz, 1
//! zero_phase_filter = { time_constant = 0.01 }   # s, forward-backward first order
//! warmup = { amplitude = 0.5, time_constant = 600.0 }               # u/s, s
//! bias_jumps = { mean_interval = 1800.0, rms_size = 0.01 }          # s, u/s
//! rate_lsb = 0.01                 # optional: each rate sample rounded to this step (u/s), no carry
//! outliers = { rate = 1.0e-3, size = 5.0 }                          # 1/s, u/s
//! ```

use std::path::Path;

use crate::toml_check::{Collector, ConfigErrors};

use super::effects::TemperatureProfile;
use super::noise::FlickerBank;
use crate::model::lowpass::LowPass;

/// Earth rotation rate (WGS-84), rad/s.
pub const EARTH_RATE_RAD_S: f64 = 7.292_115e-5;
/// Arcseconds per radian.
pub use crate::model::units::ARCSEC_PER_RAD;
use crate::model::units::{IncrementUnit, SensorKind};
/// Default upper end of the flicker band in units of tau0 (six decades).
pub const FLICKER_BAND_DECADES_DEFAULT: f64 = 6.0;

/// A checked noise model: the sampling step, the stand, the temperature, the channels.
#[derive(Debug, Clone, PartialEq)]
pub struct SimModel {
    /// Sampling step in seconds.
    pub tau0_s: f64,
    pub stand: Option<Stand>,
    pub temperature: Option<TemperatureProfile>,
    pub channels: Vec<ChannelModel>,
}

/// The test stand: where it is, so Earth rate and gravity can be projected on each axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stand {
    pub latitude_deg: f64,
    /// Local gravity in m/s^2.
    pub gravity_m_s2: f64,
}

/// One channel's noise model.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelModel {
    pub name: String,
    pub unit: String,
    /// Quantization step of the integrated signal (u); counts are whole LSBs with the remainder
    /// carried.
    pub lsb: Option<f64>,
    /// Constant bias in u/s (the stand's projection is added on top).
    pub bias: f64,
    /// White phase, u.
    pub q: f64,
    /// White rate, u/sqrt(s).
    pub n: f64,
    /// Flicker rate, u/s.
    pub b: f64,
    /// Rate random walk, u/s/sqrt(s).
    pub k: f64,
    /// Rate ramp, u/s^2.
    pub r: f64,
    /// The tau range (s) where the flicker bank is flat.
    pub flicker_band_s: (f64, f64),
    /// The bank realising `b` (None when `b == 0`).
    pub flicker: Option<FlickerBank>,
    /// Sensor axis in the local level frame (east, north, up), unit length.
    pub axis_enu: Option<[f64; 3]>,
    /// What the unit measures (`None`: neither an angle nor a velocity; cannot take an `axis`).
    pub kind: Option<IncrementUnit>,
    /// u/s per degC.
    pub temperature_coefficient: f64,
    pub gauss_markov: Vec<GaussMarkov>,
    pub sinusoids: Vec<Sinusoid>,
    pub output_filter: Option<OutputFilterSpec>,
    /// A low-pass beyond first order (moving average, second order, zero phase), in place of
    /// `output_filter` ([`crate::model::lowpass`]; docs/gap.md, "Low-pass filters beyond first
    /// order").
    pub lowpass: Option<LowPass>,
    pub warmup: Option<Warmup>,
    pub bias_jumps: Option<BiasJumps>,
    /// Each rate sample rounded to this step (u/s), no remainder carried (MEMS parts): a white
    /// rate noise of `rate_lsb^2 tau0 / 12` (docs/gap.md, "Rate-sample quantization").
    pub rate_lsb: Option<f64>,
    /// Isolated spikes on single rate samples.
    pub outliers: Option<Outliers>,
}

/// Isolated outliers: on each step, with probability `rate_per_s * tau0`, the rate sample gets
/// a spike of random sign and magnitude `size (1 + E)`, `E` exponential of mean 1 (at least
/// `size`, rms `sqrt(5) size`): u/s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Outliers {
    pub rate_per_s: f64,
    pub size: f64,
}

/// First-order Gauss-Markov rate noise: stationary sd `sigma` (u/s), correlation time `tau_c_s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussMarkov {
    pub sigma: f64,
    pub tau_c_s: f64,
}

/// Sinusoidal rate `amplitude sin(2 pi frequency t + phase)`: u/s, Hz, rad.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinusoid {
    pub amplitude: f64,
    pub frequency_hz: f64,
    pub phase_rad: f64,
}

/// The unit's first-order low-pass of its own output.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OutputFilterSpec {
    pub time_constant_s: f64,
}

/// Bias `amplitude e^{-t/time_constant}` after power-on: u/s, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Warmup {
    pub amplitude: f64,
    pub time_constant_s: f64,
}

/// Bias steps at Poisson times: mean interval (s), rms size (u/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiasJumps {
    pub mean_interval_s: f64,
    pub rms_size: f64,
}

impl SimModel {
    /// Read and check a model file.
    pub fn load(path: &Path) -> anyhow::Result<SimModel> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Collector::unreadable(path, &e).into_errors(WHAT))?;
        Ok(Self::from_toml_str(&text, path)?)
    }

    /// Parse and check a model given as TOML text; `file` names it in errors, every problem
    /// once with its line and key (`crate::toml_check`).
    pub fn from_toml_str(text: &str, file: &Path) -> Result<SimModel, ConfigErrors> {
        let mut c = Collector::new(file, text);
        let Some(table) = c.parse(text) else {
            return Err(c.into_errors(WHAT));
        };
        let model = parse_model(&table, &mut c);
        match (c.is_empty(), model) {
            (true, Some(m)) => Ok(m),
            _ => {
                if c.is_empty() {
                    c.bad("(model)", "invalid model");
                }
                Err(c.into_errors(WHAT))
            }
        }
    }

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

// ---------------------------------------------------------------------------------------------
// Parsing: a small key walker that records every problem with its key path in the file's one
// collector (`crate::toml_check`), which adds the file and the line.

/// What a model file's errors are called.
const WHAT: &str = "model file";

/// One table being read: remembers which keys were taken, so the rest can be rejected.
struct Keys<'a> {
    table: &'a toml::Table,
    prefix: String,
    taken: Vec<&'static str>,
}

impl<'a> Keys<'a> {
    fn new(table: &'a toml::Table, prefix: &str) -> Self {
        Self {
            table,
            prefix: prefix.to_string(),
            taken: Vec::new(),
        }
    }

    fn path(&self, key: &str) -> String {
        if self.prefix.is_empty() {
            key.to_string()
        } else {
            format!("{}.{key}", self.prefix)
        }
    }

    fn get(&mut self, key: &'static str) -> Option<&'a toml::Value> {
        self.taken.push(key);
        self.table.get(key)
    }

    /// A finite number (integer or float), if present.
    fn num(&mut self, key: &'static str, errs: &mut Collector) -> Option<f64> {
        let v = self.get(key)?;
        let x = match v {
            toml::Value::Float(f) => *f,
            toml::Value::Integer(i) => *i as f64,
            other => {
                errs.bad(
                    self.path(key),
                    format!("expected a number, found {}", other.type_str()),
                );
                return None;
            }
        };
        if !x.is_finite() {
            errs.bad(self.path(key), "must be finite");
            return None;
        }
        Some(x)
    }

    /// A number that must be > 0 (`strict`) or >= 0.
    fn num_pos(&mut self, key: &'static str, strict: bool, errs: &mut Collector) -> Option<f64> {
        let x = self.num(key, errs)?;
        if (strict && x <= 0.0) || x < 0.0 {
            let what = if strict { "> 0" } else { ">= 0" };
            errs.bad(self.path(key), format!("must be {what}, got {x}"));
            return None;
        }
        Some(x)
    }

    fn required(&mut self, key: &'static str, x: Option<f64>, errs: &mut Collector) -> f64 {
        if x.is_none() && !self.table.contains_key(key) {
            errs.bad(self.path(key), "missing");
        }
        x.unwrap_or(f64::NAN)
    }

    fn string(&mut self, key: &'static str, errs: &mut Collector) -> Option<&'a str> {
        let v = self.get(key)?;
        match v.as_str() {
            Some(s) => Some(s),
            None => {
                errs.bad(
                    self.path(key),
                    format!("expected a string, found {}", v.type_str()),
                );
                None
            }
        }
    }

    /// A table, or a list of tables; each with its key path.
    fn tables(
        &mut self,
        key: &'static str,
        errs: &mut Collector,
    ) -> Vec<(String, &'a toml::Table)> {
        let path = self.path(key);
        match self.get(key) {
            None => Vec::new(),
            Some(toml::Value::Table(t)) => vec![(path, t)],
            Some(toml::Value::Array(a)) => {
                let mut out = Vec::new();
                for (i, v) in a.iter().enumerate() {
                    match v.as_table() {
                        Some(t) => out.push((format!("{path}[{i}]"), t)),
                        None => errs.bad(
                            format!("{path}[{i}]"),
                            format!("expected a table, found {}", v.type_str()),
                        ),
                    }
                }
                out
            }
            Some(other) => {
                errs.bad(
                    &path,
                    format!(
                        "expected a table or a list of tables, found {}",
                        other.type_str()
                    ),
                );
                Vec::new()
            }
        }
    }

    /// At most one table.
    fn table(
        &mut self,
        key: &'static str,
        errs: &mut Collector,
    ) -> Option<(String, &'a toml::Table)> {
        let v = self.tables(key, errs);
        if v.len() > 1 {
            errs.bad(self.path(key), "expected one table, found a list");
        }
        v.into_iter().next()
    }

    /// Reject every key not taken, listing the allowed ones.
    fn finish(self, errs: &mut Collector) {
        for k in self.table.keys() {
            if !self.taken.contains(&k.as_str()) {
                errs.bad(
                    self.path(k),
                    format!("unknown key (allowed: {})", self.taken.join(", ")),
                );
            }
        }
    }
}

fn parse_model(table: &toml::Table, errs: &mut Collector) -> Option<SimModel> {
    let mut top = Keys::new(table, "");
    let _ = top.string("description", errs);
    let rate = top.num_pos("rate_hz", true, errs);
    let tau0 = top.num_pos("tau0_s", true, errs);
    let tau0_s = match (rate, tau0) {
        (Some(r), None) => 1.0 / r,
        (None, Some(t)) => t,
        (Some(_), Some(_)) => {
            errs.bad("tau0_s", "give either rate_hz or tau0_s, not both");
            f64::NAN
        }
        (None, None) => {
            if !table.contains_key("rate_hz") && !table.contains_key("tau0_s") {
                errs.bad("rate_hz", "missing (or give tau0_s)");
            }
            f64::NAN
        }
    };
    let stand = top
        .table("stand", errs)
        .map(|(p, t)| parse_stand(t, &p, errs));
    let temperature = top
        .table("temperature", errs)
        .map(|(p, t)| parse_temperature(t, &p, errs));
    let channel_tables = top.tables("channel", errs);
    top.finish(errs);
    if channel_tables.is_empty() && !table.contains_key("channel") {
        errs.bad("channel", "at least one [[channel]] is needed");
    }
    let mut channels = Vec::new();
    for (path, t) in channel_tables {
        if let Some(c) = parse_channel(
            t,
            &path,
            tau0_s,
            temperature.is_some(),
            stand.is_some(),
            errs,
        ) {
            if channels.iter().any(|o: &ChannelModel| o.name == c.name) {
                errs.bad(
                    format!("{path}.name"),
                    format!("duplicate channel name `{}`", c.name),
                );
            }
            channels.push(c);
        }
    }
    errs.is_empty().then_some(SimModel {
        tau0_s,
        stand,
        temperature,
        channels,
    })
}

fn parse_stand(t: &toml::Table, path: &str, errs: &mut Collector) -> Stand {
    let mut k = Keys::new(t, path);
    let lat = k.num("latitude_deg", errs);
    let latitude_deg = k.required("latitude_deg", lat, errs);
    if latitude_deg.abs() > 90.0 {
        errs.bad(
            k.path("latitude_deg"),
            format!("must be within [-90, 90], got {latitude_deg}"),
        );
    }
    let gravity_m_s2 = k
        .num_pos("gravity_m_s2", true, errs)
        .unwrap_or_else(|| normal_gravity_m_s2(latitude_deg));
    k.finish(errs);
    Stand {
        latitude_deg,
        gravity_m_s2,
    }
}

fn parse_temperature(t: &toml::Table, path: &str, errs: &mut Collector) -> TemperatureProfile {
    let mut k = Keys::new(t, path);
    let s = k.num("start_c", errs);
    let start_c = k.required("start_c", s, errs);
    let f = k.num("final_c", errs);
    let final_c = k.required("final_c", f, errs);
    let tc = k.num_pos("time_constant_s", true, errs);
    let time_constant_s = k.required("time_constant_s", tc, errs);
    let sine_amplitude_c = k.num("sine_amplitude_c", errs).unwrap_or(0.0);
    let period = k.num_pos("sine_period_s", true, errs);
    let sine_period_s = if sine_amplitude_c != 0.0 {
        k.required("sine_period_s", period, errs)
    } else {
        period.unwrap_or(1.0)
    };
    let reference_c = k.num("reference_c", errs).unwrap_or(final_c);
    k.finish(errs);
    TemperatureProfile {
        start_c,
        final_c,
        time_constant_s,
        sine_amplitude_c,
        sine_period_s,
        reference_c,
    }
}

fn parse_axis(v: &toml::Value, path: &str, errs: &mut Collector) -> Option<[f64; 3]> {
    let raw = match v {
        toml::Value::String(s) => match s.as_str() {
            "east" => [1.0, 0.0, 0.0],
            "west" => [-1.0, 0.0, 0.0],
            "north" => [0.0, 1.0, 0.0],
            "south" => [0.0, -1.0, 0.0],
            "up" => [0.0, 0.0, 1.0],
            "down" => [0.0, 0.0, -1.0],
            other => {
                errs.bad(
                    path,
                    format!("unknown direction `{other}` (allowed: up, down, north, south, east, west, or [east, north, up])"),
                );
                return None;
            }
        },
        toml::Value::Array(a) => {
            let nums: Vec<f64> = a
                .iter()
                .filter_map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)))
                .collect();
            if a.len() != 3 || nums.len() != 3 || nums.iter().any(|x| !x.is_finite()) {
                errs.bad(path, "expected three numbers [east, north, up]");
                return None;
            }
            [nums[0], nums[1], nums[2]]
        }
        other => {
            errs.bad(
                path,
                format!(
                    "expected a direction name or [east, north, up], found {}",
                    other.type_str()
                ),
            );
            return None;
        }
    };
    let norm = (raw[0] * raw[0] + raw[1] * raw[1] + raw[2] * raw[2]).sqrt();
    if norm == 0.0 {
        errs.bad(path, "must not be the zero vector");
        return None;
    }
    Some([raw[0] / norm, raw[1] / norm, raw[2] / norm])
}

fn parse_channel(
    t: &toml::Table,
    path: &str,
    tau0_s: f64,
    has_temperature: bool,
    has_stand: bool,
    errs: &mut Collector,
) -> Option<ChannelModel> {
    let n_before = errs.problems().len();
    let mut k = Keys::new(t, path);
    let name = k.string("name", errs).unwrap_or("").to_string();
    if !t.contains_key("name") {
        errs.bad(k.path("name"), "missing");
    } else if name.is_empty() || name.contains([',', '"', '\n', '\r']) {
        errs.bad(
            k.path("name"),
            "must be non-empty, without commas, quotes or line breaks",
        );
    }
    let unit = k.string("unit", errs).unwrap_or("").to_string();
    if !t.contains_key("unit") {
        errs.bad(k.path("unit"), "missing");
    }
    let kind = IncrementUnit::parse(&unit);
    let lsb = k.num_pos("lsb", true, errs);
    let bias = k.num("bias", errs).unwrap_or(0.0);
    let q = k.num_pos("Q", false, errs).unwrap_or(0.0);
    let n = k.num_pos("N", false, errs).unwrap_or(0.0);
    let b = k.num_pos("B", false, errs).unwrap_or(0.0);
    let kk = k.num_pos("K", false, errs).unwrap_or(0.0);
    let r = k.num("R", errs).unwrap_or(0.0);
    let band_path = k.path("flicker_band_s");
    let flicker_band_s = match k.get("flicker_band_s") {
        None => (tau0_s, tau0_s * 10f64.powf(FLICKER_BAND_DECADES_DEFAULT)),
        Some(v) => {
            let nums: Vec<f64> = v
                .as_array()
                .map(|a| {
                    a.iter()
                        .filter_map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)))
                        .collect()
                })
                .unwrap_or_default();
            if nums.len() != 2 || !(nums[0] > 0.0 && nums[1] > nums[0] && nums[1].is_finite()) {
                errs.bad(
                    &band_path,
                    "expected [tau_lo_s, tau_hi_s] with 0 < tau_lo_s < tau_hi_s",
                );
                (tau0_s, tau0_s * 10f64.powf(FLICKER_BAND_DECADES_DEFAULT))
            } else {
                (nums[0], nums[1])
            }
        }
    };
    let axis_path = k.path("axis");
    let axis_enu = k.get("axis").and_then(|v| parse_axis(v, &axis_path, errs));
    if axis_enu.is_some() && kind.is_none() {
        errs.bad(
            &axis_path,
            format!(
                "an axis needs a unit of angle (arcsec, deg, rad, mrad) or velocity (m/s, ft/s, g, mg), not `{unit}`"
            ),
        );
    }
    if axis_enu.is_some() && !has_stand {
        errs.bad(
            &axis_path,
            "an axis needs a [stand] table (latitude) to project on",
        );
    }
    let temperature_coefficient = k.num("temperature_coefficient", errs).unwrap_or(0.0);
    if temperature_coefficient != 0.0 && !has_temperature {
        errs.bad(
            k.path("temperature_coefficient"),
            "needs a top-level [temperature] profile",
        );
    }
    let mut gauss_markov = Vec::new();
    for (p, tt) in k.tables("gauss_markov", errs) {
        let mut e = Keys::new(tt, &p);
        let s = e.num_pos("sigma", false, errs);
        let sigma = e.required("sigma", s, errs);
        let tc = e.num_pos("tau_c", true, errs);
        let tau_c_s = e.required("tau_c", tc, errs);
        e.finish(errs);
        gauss_markov.push(GaussMarkov { sigma, tau_c_s });
    }
    let mut sinusoids = Vec::new();
    for (p, tt) in k.tables("sinusoid", errs) {
        let mut e = Keys::new(tt, &p);
        let a = e.num("amplitude", errs);
        let amplitude = e.required("amplitude", a, errs);
        let f = e.num_pos("frequency", true, errs);
        let frequency_hz = e.required("frequency", f, errs);
        let phase_rad = e.num("phase", errs).unwrap_or(0.0);
        e.finish(errs);
        sinusoids.push(Sinusoid {
            amplitude,
            frequency_hz,
            phase_rad,
        });
    }
    let output_filter = k.table("output_filter", errs).map(|(p, tt)| {
        let mut e = Keys::new(tt, &p);
        let tc = e.num_pos("time_constant", true, errs);
        let time_constant_s = e.required("time_constant", tc, errs);
        e.finish(errs);
        OutputFilterSpec { time_constant_s }
    });
    let lowpass = parse_lowpass(&mut k, tau0_s, output_filter.is_some(), errs);
    let warmup = k.table("warmup", errs).map(|(p, tt)| {
        let mut e = Keys::new(tt, &p);
        let a = e.num("amplitude", errs);
        let amplitude = e.required("amplitude", a, errs);
        let tc = e.num_pos("time_constant", true, errs);
        let time_constant_s = e.required("time_constant", tc, errs);
        e.finish(errs);
        Warmup {
            amplitude,
            time_constant_s,
        }
    });
    let bias_jumps = k.table("bias_jumps", errs).map(|(p, tt)| {
        let mut e = Keys::new(tt, &p);
        let mi = e.num_pos("mean_interval", true, errs);
        let mean_interval_s = e.required("mean_interval", mi, errs);
        let rs = e.num_pos("rms_size", false, errs);
        let rms_size = e.required("rms_size", rs, errs);
        e.finish(errs);
        BiasJumps {
            mean_interval_s,
            rms_size,
        }
    });
    let rate_lsb = k.num_pos("rate_lsb", true, errs);
    let outliers = k.table("outliers", errs).map(|(p, tt)| {
        let mut e = Keys::new(tt, &p);
        let r = e.num_pos("rate", false, errs);
        let rate_per_s = e.required("rate", r, errs);
        if rate_per_s * tau0_s > 0.5 {
            errs.bad(
                e.path("rate"),
                format!("{rate_per_s} per second is more than one outlier every two samples"),
            );
        }
        let sz = e.num_pos("size", true, errs);
        let size = e.required("size", sz, errs);
        e.finish(errs);
        Outliers { rate_per_s, size }
    });
    k.finish(errs);
    if errs.problems().len() > n_before {
        return None;
    }
    let flicker = (b > 0.0).then(|| FlickerBank::design(b, flicker_band_s.0, flicker_band_s.1));
    Some(ChannelModel {
        name,
        unit,
        lsb,
        bias,
        q,
        n,
        b,
        k: kk,
        r,
        flicker_band_s,
        flicker,
        axis_enu,
        kind,
        temperature_coefficient,
        gauss_markov,
        sinusoids,
        output_filter,
        lowpass,
        warmup,
        bias_jumps,
        rate_lsb,
        outliers,
    })
}

/// The keys `moving_average = {taps, stages}`, `second_order_filter = {natural_frequency,
/// damping}` and `zero_phase_filter = {time_constant}`: at most one filter per channel
/// (`output_filter` included).
fn parse_lowpass(
    k: &mut Keys<'_>,
    tau0_s: f64,
    has_output_filter: bool,
    errs: &mut Collector,
) -> Option<LowPass> {
    let mut found: Vec<(String, LowPass)> = Vec::new();
    if let Some((p, tt)) = k.table("moving_average", errs) {
        let mut e = Keys::new(tt, &p);
        let t = e.num_pos("taps", true, errs);
        let taps = e.required("taps", t, errs);
        let stages = e.num_pos("stages", true, errs).unwrap_or(1.0);
        e.finish(errs);
        for (key, v) in [("taps", taps), ("stages", stages)] {
            if v.is_finite() && v.fract() != 0.0 {
                errs.bad(
                    format!("{p}.{key}"),
                    format!("must be a whole number, got {v}"),
                );
            }
        }
        found.push((
            p,
            LowPass::MovingAverage {
                taps: taps.clamp(0.0, u32::MAX as f64) as u32,
                stages: stages.clamp(0.0, u32::MAX as f64) as u32,
            },
        ));
    }
    if let Some((p, tt)) = k.table("second_order_filter", errs) {
        let mut e = Keys::new(tt, &p);
        let f = e.num_pos("natural_frequency", true, errs);
        let natural_frequency_hz = e.required("natural_frequency", f, errs);
        let z = e.num_pos("damping", true, errs);
        let damping = e.required("damping", z, errs);
        e.finish(errs);
        found.push((
            p,
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
            },
        ));
    }
    if let Some((p, tt)) = k.table("zero_phase_filter", errs) {
        let mut e = Keys::new(tt, &p);
        let tc = e.num_pos("time_constant", true, errs);
        let time_constant_s = e.required("time_constant", tc, errs);
        e.finish(errs);
        found.push((p, LowPass::ZeroPhase { time_constant_s }));
    }
    let mut out = None;
    for (i, (p, lp)) in found.into_iter().enumerate() {
        if i > 0 || has_output_filter {
            errs.bad(
                p,
                "one filter per channel: output_filter, moving_average, second_order_filter \
                 and zero_phase_filter exclude each other",
            );
            continue;
        }
        // Parameters already reported missing or not positive are not judged again.
        let judged = match lp {
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
            } => natural_frequency_hz.is_finite() && damping.is_finite(),
            LowPass::ZeroPhase { time_constant_s } => time_constant_s.is_finite(),
            _ => true,
        };
        if judged {
            if let Some(problem) = lp.check(tau0_s) {
                errs.bad(p, problem);
                continue;
            }
        }
        out = Some(lp);
    }
    out
}
