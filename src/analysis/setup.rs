//! What a run's analysis is given: the kind of values a text column holds ([`InputKind`], with
//! the one rule that turns a value into an increment), each channel's setup ([`ChannelSetup`]:
//! name, unit, column, LSB) and the run's options ([`AnalysisOptions`]).

use crate::allan::accum::AccumConfig;
use crate::model::fit::FitOptions;

/// What the values of a text column are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum InputKind {
    /// Increments over each step, in u (the default; docs/theory.md section 1).
    #[default]
    Increments,
    /// Rate samples in u/s: the increment is `y * tau0`.
    Rate,
    /// Phase, the running sum of increments, in u.
    Phase,
}

impl InputKind {
    /// The increment (u) one text value `v` stands for: the rule every reader of text columns
    /// shares (the analysis's gap evidence and `diagnose`). `None`: the value gives no step (the
    /// first phase value, or the first after a missing one: there is no previous phase to
    /// difference); a non-finite result is a missing step (a gap). `last_phase` carries the
    /// previous finite phase value of the channel.
    #[inline]
    pub fn step(self, v: f64, tau0_s: f64, last_phase: &mut Option<f64>) -> Option<f64> {
        match self {
            InputKind::Phase => {
                let d = last_phase.map(|p| v - p);
                *last_phase = v.is_finite().then_some(v);
                d
            }
            InputKind::Increments => Some(v),
            InputKind::Rate => Some(v * tau0_s),
        }
    }
}

/// The simulator's temperature column (degC), which `diagnose` reads as the unit's
/// temperature. Any temperature column is left out of the channels
/// ([`crate::input::temperature_column`]: `temp [degC]`, `imu_temp`, ...).
pub const AUXILIARY_COLUMNS: [&str; 1] = ["temperature_c"];

/// One channel as the input describes it.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChannelSetup {
    pub name: String,
    pub unit: String,
    /// Position of the channel's value in each row of the input.
    pub column: usize,
    /// `Some(lsb)` when values arrive as integer counts of `lsb` u (frame fields): they are
    /// accumulated exactly and scaled at read-out.
    pub counts_lsb: Option<f64>,
}

impl ChannelSetup {
    /// The channels of a frame format, in the order its frames carry them; integer increment
    /// fields are counts of their LSB.
    pub fn for_frames(desc: &crate::frame::FrameDescriptor) -> Vec<ChannelSetup> {
        desc.channels()
            .into_iter()
            .enumerate()
            .map(|(i, c)| ChannelSetup {
                name: c.name,
                unit: c.unit,
                column: i,
                counts_lsb: c.scale,
            })
            .collect()
    }

    /// The channels of text columns with header `names` (temperature columns left out:
    /// [`crate::input::temperature_column`]), each in `unit`.
    pub fn for_text(names: &[String], unit: &str) -> Vec<ChannelSetup> {
        let temperature: Vec<bool> = names
            .iter()
            .map(|n| crate::input::temperature_column::temperature_column(n).is_some())
            .collect();
        Self::for_text_columns(names, &temperature, unit)
    }

    /// [`ChannelSetup::for_text`] with the temperature columns given (`temperature[i]`: the
    /// column `names[i]` holds a temperature, as [`crate::input::text::TextReader::temperatures`]
    /// tells from the input's names and the run's).
    pub fn for_text_columns(
        names: &[String],
        temperature: &[bool],
        unit: &str,
    ) -> Vec<ChannelSetup> {
        names
            .iter()
            .enumerate()
            .filter(|(i, _)| !temperature.get(*i).copied().unwrap_or(false))
            .map(|(i, n)| ChannelSetup {
                name: n.clone(),
                unit: unit.to_string(),
                column: i,
                counts_lsb: None,
            })
            .collect()
    }
}

/// Settings of one run's analysis.
#[derive(Debug, Clone)]
pub struct AnalysisOptions {
    pub accum: AccumConfig,
    pub kind: InputKind,
    /// Data-seconds between interim records; `None`: final records only.
    pub every_s: Option<f64>,
    /// The five-term fit, or `None` for curves only.
    pub fit: Option<FitOptions>,
    /// Run index when several inputs are analyzed.
    pub run: Option<usize>,
    /// Datasheet limits judged on each run's final fits (per-run scope), in `summary`.
    pub limits: Vec<crate::model::limits::LimitSpec>,
    /// Also gather the sim-to-real evidence and write `diagnosis` records with the fits.
    pub diagnose: bool,
}
