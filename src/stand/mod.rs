//! The stand config of `allanscope run --config FILE`: source, channels, statistics, outputs
//! and datasheet limits in one TOML file, checked into a [`StandConfig`] before anything starts.
//!
//! Every problem is collected and reported together, each with the file, the key and what is
//! wrong ([`StandConfigErrors`], exit status 2); unknown keys are rejected. Relative paths are
//! taken from the working directory, as on the command line, not from the config's folder. The
//! capture a one-unit config's file source replays (`source.path`) must exist when the config is
//! checked; in a `[[unit]]` config a capture that cannot be opened is that unit's failure, an
//! `outage` record, while the others go on. `config/stand.toml` is the commented example.
//!
//! ```toml
//! [source]
//! kind = "serial"             # serial | udp | file | stdin
//! path = "/dev/ttyUSB0"       # serial: the port; file: the capture
//! baud = 230400               # serial (default 230400)
//! address = "127.0.0.1:5000"  # udp: ADDR:PORT to bind (or a port: 127.0.0.1)
//! format = "siu8"             # a frame descriptor name or path
//! pace = "max"                # file: max | realtime
//!
//! [run]
//! duration = "3h"             # optional: stop after (s, min, h, d)
//! every_s = 60.0              # optional: interim records (wall-seconds live, data-seconds file)
//! capture = "stand.siu8"      # optional: every received byte (live sources)
//! diagnose = true              # optional: `diagnosis` records with the fits (default false)
//! checkpoint_every = 300.0    # optional: save the state beside output.path (run --resume)
//! metrics = "127.0.0.1:9464"  # optional: serve /metrics for Prometheus (a port: 127.0.0.1)
//!
//! [statistics]
//! stats = ["avar", "hvar", "mvar"]
//! taus = "octave"             # octave | decade | [1, 2, 4, ...]
//! overlap = 16                # an integer L, or "full"
//! fit = "model"               # model | paper | slopes | loglog | none
//!
//! [channels]
//! include = ["g1", "g4"]      # optional: only these channels
//!
//! [output]
//! path = "stand.jsonl"        # optional: JSON lines here instead of standard output
//!
//! [[limits]]                  # datasheet limits (crate::model::limits), checked here with
//! channel = "g4"              # the rest; a channel that the source lacks is refused at start
//! ```
//!
//! Several units in one process: `[[unit]]` tables instead of `[source]`, each with a `name`,
//! a `source` table (the keys above), and optionally `capture`, `channels` and `[[unit.limits]]`
//! (`config/lab.toml`); `[run] capture` moves into the units, `[run] quiet_after` (seconds) says
//! when a silent live unit is recorded as out. Two units may not share a name, a UDP port, a
//! serial device, standard input or a capture file ([`UnitConfig`]).
//!
//! This file holds the checked types and the entry points; `parse` reads the top level (`[run]`,
//! `[statistics]`, `[channels]`, `[output]`, `[[limits]]`), `source` one `[source]` table,
//! `units` the `[[unit]]` tables and what two units may not share, `check` the typed reads all
//! of them record their problems through.

use std::path::{Path, PathBuf};

use crate::allan::accum::{Overlap, StatSet, TauSpec};
use crate::model::fit::FitMethod;
use crate::source::SourceSpec;

mod check;
mod parse;
mod source;
mod units;

/// Default baud of a serial source (the siu8's RS-422 link, SPEC-frames.md).
pub const DEFAULT_BAUD: u32 = 230_400;

/// A checked stand config.
#[derive(Debug, Clone, PartialEq)]
pub struct StandConfig {
    /// The file it came from.
    pub file: PathBuf,
    /// The units: one for a config with `[source]` at the top (no name: its records are as
    /// they always were), or one per `[[unit]]` table (named: every record carries `unit`).
    pub units: Vec<UnitConfig>,
    /// Stop after this many seconds (`run.duration`).
    pub duration_s: Option<f64>,
    /// Seconds between checkpoints beside the output (`run.checkpoint_every`): wall-seconds
    /// live, data-seconds for a file.
    pub checkpoint_every_s: Option<f64>,
    /// Seconds between interim records (`run.every_s`).
    pub every_s: Option<f64>,
    /// Wall-seconds without a byte after which a live unit of a `[[unit]]` config is recorded
    /// as out (`run.quiet_after`, default [`DEFAULT_QUIET_AFTER_S`]).
    pub quiet_after_s: Option<f64>,
    /// Write `diagnosis` records (the sim-to-real gap) with the fits (`run.diagnose`).
    pub diagnose: bool,
    /// Serve `/metrics` here (`run.metrics`, ADDR:PORT or a port on 127.0.0.1).
    pub metrics: Option<std::net::SocketAddr>,
    pub stats: StatSet,
    pub taus: TauSpec,
    pub overlap: Overlap,
    /// `None`: no fit.
    pub fit: Option<FitMethod>,
    /// `output.path`; `None`: standard output.
    pub output: Option<PathBuf>,
}

/// One unit of a stand config: its source and what is analysed of it.
#[derive(Debug, Clone, PartialEq)]
pub struct UnitConfig {
    /// `unit[i].name`; `None` for the one-unit shape (`[source]` at the top).
    pub name: Option<String>,
    pub source: SourceSpec,
    /// Frame descriptor name or path (`source.format`).
    pub format: String,
    /// Every received byte of a live source written here (`run.capture`, `unit[i].capture`).
    pub capture: Option<PathBuf>,
    /// Only these channels (`channels.include`, or the unit's own).
    pub channels: Option<Vec<String>>,
    /// The `[[limits]]` tables that apply to this unit, checked (each knows its line, for
    /// [`crate::model::limits::check_channels`]).
    pub limits: Vec<crate::model::limits::LimitSpec>,
}

/// Default of `run.quiet_after`: a live unit silent for this many wall-seconds is recorded as
/// out (an `outage` record). Long enough that a scheduling hiccup or a datagram burst lost on
/// a busy host is not an outage, short enough that an operator sees an unplugged unit at once.
pub const DEFAULT_QUIET_AFTER_S: f64 = 5.0;

/// Longest unit name: it names the unit's checkpoint file and labels its metrics.
pub const MAX_UNIT_NAME: usize = 64;

/// All problems found in one stand config, each a [`crate::error::UsageError::Config`] with its
/// line and key (exit status 2): the one TOML error type, `crate::toml_check::ConfigErrors`.
pub type StandConfigErrors = crate::toml_check::ConfigErrors;

/// What a stand config's errors are called.
const WHAT: &str = "stand config";

impl StandConfig {
    /// Reads and checks a stand config file (its frame descriptor a built-in or a path).
    pub fn load(path: &Path) -> Result<StandConfig, StandConfigErrors> {
        Self::load_in(path, &[])
    }

    /// Reads and checks a stand config file; a descriptor named in `source.format` is also
    /// searched for in `descriptor_dirs` (`FrameDescriptor::load_in`).
    pub fn load_in(
        path: &Path,
        descriptor_dirs: &[PathBuf],
    ) -> Result<StandConfig, StandConfigErrors> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| crate::toml_check::Collector::unreadable(path, &e).into_errors(WHAT))?;
        Self::from_toml_str_in(&text, path, descriptor_dirs)
    }

    /// Parses and checks config text; `file` names it in errors.
    pub fn from_toml_str(text: &str, file: &Path) -> Result<StandConfig, StandConfigErrors> {
        Self::from_toml_str_in(text, file, &[])
    }

    /// True when the config lists its units in `[[unit]]` tables: records then carry `unit`.
    pub fn named_units(&self) -> bool {
        self.units.iter().any(|u| u.name.is_some())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::UsageError;

    /// Three problems in one file are reported together, each with its key, in line order.
    #[test]
    fn problems_collected() {
        let text = r#"
[source]
kind = "udp"
address = "localhost:99999"
format = "siu8"
[statistics]
stats = ["avar", "tdev"]
colour = "red"
"#;
        let e = StandConfig::from_toml_str(text, Path::new("s.toml")).unwrap_err();
        let keys: Vec<String> = e
            .problems
            .iter()
            .map(|p| match p {
                UsageError::Config { key, .. } => key.clone(),
                other => other.to_string(),
            })
            .collect();
        assert_eq!(
            keys,
            ["source.address", "statistics.stats", "statistics.colour"]
        );
    }
}
