//! The stand config of `allanscope run --config FILE`: source, channels, statistics, outputs
//! and datasheet limits in one TOML file, checked into a [`StandConfig`] before anything starts.
//!
//! Every problem is collected and reported together, each with the file, the key and what is
//! wrong ([`StandConfigErrors`], exit status 2); unknown keys are rejected. Relative paths are
//! taken from the working directory, as on the command line. `config/stand.toml` is the
//! commented example.
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

use std::path::{Path, PathBuf};

use crate::allan::accum::{Overlap, StatSet, TauSpec, DEFAULT_L};
use crate::error::UsageError;
use crate::model::fit::FitMethod;
use crate::source::{Pace, SourceSpec};

/// Default baud of a serial source (the siu8's RS-422 link, SPEC-frames.md).
pub const DEFAULT_BAUD: u32 = 230_400;

/// A checked stand config.
#[derive(Debug, Clone, PartialEq)]
pub struct StandConfig {
    /// The file it came from.
    pub file: PathBuf,
    pub source: SourceSpec,
    /// Frame descriptor name or path (`source.format`).
    pub format: String,
    /// Stop after this many seconds (`run.duration`).
    pub duration_s: Option<f64>,
    /// Seconds between checkpoints beside the output (`run.checkpoint_every`): wall-seconds
    /// live, data-seconds for a file.
    pub checkpoint_every_s: Option<f64>,
    /// Seconds between interim records (`run.every_s`).
    pub every_s: Option<f64>,
    /// Write `diagnosis` records (the sim-to-real gap) with the fits (`run.diagnose`).
    pub diagnose: bool,
    /// `run.capture`.
    pub capture: Option<PathBuf>,
    /// Serve `/metrics` here (`run.metrics`, ADDR:PORT or a port on 127.0.0.1).
    pub metrics: Option<std::net::SocketAddr>,
    pub stats: StatSet,
    pub taus: TauSpec,
    pub overlap: Overlap,
    /// `None`: no fit.
    pub fit: Option<FitMethod>,
    /// Only these channels (`channels.include`).
    pub channels: Option<Vec<String>>,
    /// `output.path`; `None`: standard output.
    pub output: Option<PathBuf>,
    /// The `[[limits]]` tables, checked (each knows its line, for [`crate::model::limits::check_channels`]).
    pub limits: Vec<crate::model::limits::LimitSpec>,
}

/// All problems found in one stand config, each a [`UsageError::Config`] with its line and key
/// (exit status 2): the one TOML error type, `crate::toml_check::ConfigErrors`.
pub type StandConfigErrors = crate::toml_check::ConfigErrors;

/// What a stand config's errors are called.
const WHAT: &str = "stand config";

/// Collects problems with the file name attached.
struct Check {
    c: crate::toml_check::Collector,
}

impl Check {
    fn bad(&mut self, key: &str, problem: impl Into<String>) {
        self.c.bad(key, problem);
    }

    /// A table's keys must all be in `allowed`.
    fn known_keys(&mut self, prefix: &str, t: &toml::Table, allowed: &[&str]) {
        for k in t.keys() {
            if !allowed.contains(&k.as_str()) {
                self.bad(
                    &join(prefix, k),
                    format!("unknown key (allowed here: {})", allowed.join(", ")),
                );
            }
        }
    }

    fn table<'t>(&mut self, root: &'t toml::Table, key: &str) -> Option<&'t toml::Table> {
        match root.get(key) {
            None => None,
            Some(toml::Value::Table(t)) => Some(t),
            Some(v) => {
                self.bad(key, format!("must be a table, not {}", v.type_str()));
                None
            }
        }
    }

    fn string(&mut self, t: &toml::Table, prefix: &str, key: &str) -> Option<String> {
        match t.get(key) {
            None => None,
            Some(toml::Value::String(s)) if !s.trim().is_empty() => Some(s.clone()),
            Some(v) => {
                self.bad(
                    &join(prefix, key),
                    format!("must be a non-empty string, not {}", show(v)),
                );
                None
            }
        }
    }

    /// A number of seconds in `[min, max]` (`crate::ranges`).
    fn seconds(
        &mut self,
        t: &toml::Table,
        prefix: &str,
        key: &str,
        min: f64,
        max: f64,
    ) -> Option<f64> {
        let v = t.get(key)?;
        let x = match v {
            toml::Value::Float(f) => *f,
            toml::Value::Integer(i) => *i as f64,
            _ => {
                self.bad(
                    &join(prefix, key),
                    format!("must be a number of seconds, not {}", show(v)),
                );
                return None;
            }
        };
        match crate::ranges::check_seconds(x, min, max) {
            Ok(x) => Some(x),
            Err(e) => {
                self.bad(&join(prefix, key), e);
                None
            }
        }
    }
}

fn join(prefix: &str, key: &str) -> String {
    if prefix.is_empty() {
        key.into()
    } else {
        format!("{prefix}.{key}")
    }
}

fn show(v: &toml::Value) -> String {
    match v {
        toml::Value::String(s) => format!("\"{s}\""),
        toml::Value::Table(_) => "a table".into(),
        toml::Value::Array(_) => "an array".into(),
        other => other.to_string(),
    }
}

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

    /// [`StandConfig::from_toml_str`], the descriptor also searched for in `descriptor_dirs`.
    pub fn from_toml_str_in(
        text: &str,
        file: &Path,
        descriptor_dirs: &[PathBuf],
    ) -> Result<StandConfig, StandConfigErrors> {
        let mut ck = Check {
            c: crate::toml_check::Collector::new(file, text),
        };
        let Some(root) = ck.c.parse(text) else {
            return Err(ck.c.into_errors(WHAT));
        };
        ck.known_keys(
            "",
            &root,
            &[
                "source",
                "run",
                "statistics",
                "channels",
                "output",
                "limits",
            ],
        );

        // [source]
        let mut format = String::new();
        let mut source = None;
        match ck.table(&root, "source") {
            None if !root.contains_key("source") => ck.bad("source", "missing: the [source] table"),
            None => {}
            Some(s) => {
                ck.known_keys(
                    "source",
                    s,
                    &["kind", "path", "baud", "address", "format", "pace"],
                );
                match ck.string(s, "source", "format") {
                    Some(f) if f == "csv" => ck.bad(
                        "source.format",
                        "\"csv\": run reads frames; give a frame descriptor (siu8, kvh1750, ...)",
                    ),
                    Some(f) => {
                        // The descriptor is read now, so a bad one is refused with the rest:
                        // an unknown name at this key, a bad file by its own lines.
                        if let Err(e) = crate::frame::FrameDescriptor::load_in(&f, descriptor_dirs)
                        {
                            for p in e.problems {
                                match p {
                                    UsageError::Option(m) => ck.bad("source.format", m),
                                    other => ck.c.extend([other]),
                                }
                            }
                        }
                        format = f;
                    }
                    None if !s.contains_key("format") => ck.bad(
                        "source.format",
                        "missing: a frame descriptor name (siu8, kvh1750, hg4930) or path",
                    ),
                    None => {}
                }
                let pace = match ck.string(s, "source", "pace").as_deref() {
                    None | Some("max") => Pace::Max,
                    // The byte rate is filled in once the descriptor is loaded.
                    Some("realtime") => Pace::Realtime { bytes_per_s: 0.0 },
                    Some(other) => {
                        ck.bad(
                            "source.pace",
                            format!("\"{other}\": expected \"max\" or \"realtime\""),
                        );
                        Pace::Max
                    }
                };
                let kind = ck.string(s, "source", "kind");
                let baud = match s.get("baud") {
                    None => Some(DEFAULT_BAUD),
                    Some(toml::Value::Integer(b)) if *b > 0 && *b <= 20_000_000 => Some(*b as u32),
                    Some(v) => {
                        ck.bad(
                            "source.baud",
                            format!("must be a positive integer baud rate, not {}", show(v)),
                        );
                        None
                    }
                };
                let path = ck.string(s, "source", "path");
                let needs = |ck: &mut Check, key: &str, what: &str| {
                    if !s.contains_key(key) {
                        ck.bad(&join("source", key), format!("missing: {what}"));
                    }
                };
                let only_for = |ck: &mut Check, key: &str, kinds: &str| {
                    if s.contains_key(key) {
                        ck.bad(&join("source", key), format!("only for kind = {kinds}"));
                    }
                };
                match kind.as_deref() {
                    Some("serial") => {
                        needs(&mut ck, "path", "the serial port, e.g. \"/dev/ttyUSB0\"");
                        only_for(&mut ck, "address", "\"udp\"");
                        only_for(&mut ck, "pace", "\"file\" or \"stdin\"");
                        if let (Some(p), Some(baud)) = (path, baud) {
                            source = Some(SourceSpec::Serial {
                                path: p.into(),
                                baud,
                            });
                        }
                    }
                    Some("udp") => {
                        needs(
                            &mut ck,
                            "address",
                            "ADDR:PORT to bind, e.g. \"127.0.0.1:5000\"",
                        );
                        only_for(&mut ck, "path", "\"serial\" or \"file\"");
                        only_for(&mut ck, "baud", "\"serial\"");
                        only_for(&mut ck, "pace", "\"file\" or \"stdin\"");
                        if let Some(a) = ck.string(s, "source", "address") {
                            match crate::source::udp::parse_bind(&a) {
                                Ok(bind) => source = Some(SourceSpec::Udp { bind }),
                                Err(e) => ck.bad("source.address", e),
                            }
                        }
                    }
                    Some("file") => {
                        needs(&mut ck, "path", "the capture file");
                        only_for(&mut ck, "address", "\"udp\"");
                        only_for(&mut ck, "baud", "\"serial\"");
                        if let Some(p) = path {
                            source = Some(SourceSpec::File {
                                path: p.into(),
                                pace,
                            });
                        }
                    }
                    Some("stdin") => {
                        only_for(&mut ck, "path", "\"serial\" or \"file\"");
                        only_for(&mut ck, "address", "\"udp\"");
                        only_for(&mut ck, "baud", "\"serial\"");
                        source = Some(SourceSpec::Stdin { pace });
                    }
                    Some(other) => ck.bad(
                        "source.kind",
                        format!("\"{other}\": expected serial, udp, file or stdin"),
                    ),
                    None if !s.contains_key("kind") => {
                        ck.bad("source.kind", "missing: serial, udp, file or stdin")
                    }
                    None => {}
                }
            }
        }

        // [run]
        let (mut duration_s, mut every_s, mut capture) = (None, None, None);
        let mut checkpoint_every_s = None;
        let mut diagnose = false;
        let mut metrics = None;
        if let Some(r) = ck.table(&root, "run") {
            ck.known_keys(
                "run",
                r,
                &[
                    "duration",
                    "every_s",
                    "capture",
                    "diagnose",
                    "checkpoint_every",
                    "metrics",
                ],
            );
            match r.get("metrics") {
                None => {}
                Some(toml::Value::Integer(p)) => match u16::try_from(*p) {
                    Ok(port) => metrics = Some(std::net::SocketAddr::from(([127, 0, 0, 1], port))),
                    Err(_) => ck.bad("run.metrics", format!("port {p} is not in 0..=65535")),
                },
                Some(toml::Value::String(a)) => match crate::source::udp::parse_bind(a) {
                    Ok(addr) => metrics = Some(addr),
                    Err(e) => ck.bad("run.metrics", e),
                },
                Some(v) => ck.bad(
                    "run.metrics",
                    format!("expected \"ADDR:PORT\" or a port, not {}", show(v)),
                ),
            }
            use crate::ranges::{MAX_SECONDS, MIN_INTERVAL_S};
            checkpoint_every_s =
                ck.seconds(r, "run", "checkpoint_every", MIN_INTERVAL_S, MAX_SECONDS);
            match r.get("diagnose") {
                None => {}
                Some(toml::Value::Boolean(b)) => diagnose = *b,
                Some(v) => ck.bad(
                    "run.diagnose",
                    format!("expected true or false, not {}", show(v)),
                ),
            }
            match r.get("duration") {
                None => {}
                Some(toml::Value::String(d)) => match crate::ranges::parse_duration(d) {
                    Ok(v) => duration_s = Some(v),
                    Err(e) => ck.bad("run.duration", e),
                },
                Some(_) => duration_s = ck.seconds(r, "run", "duration", 0.0, MAX_SECONDS),
            }
            every_s = ck.seconds(r, "run", "every_s", MIN_INTERVAL_S, MAX_SECONDS);
            capture = ck.string(r, "run", "capture").map(PathBuf::from);
        }

        // [statistics]
        let mut stats = StatSet::ALL;
        let mut taus = TauSpec::Octave;
        let mut overlap = Overlap::Bounded(DEFAULT_L);
        let mut fit = Some(FitMethod::default());
        if let Some(st) = ck.table(&root, "statistics") {
            ck.known_keys("statistics", st, &["stats", "taus", "overlap", "fit"]);
            if let Some(v) = st.get("stats") {
                let list: Option<Vec<&str>> = v
                    .as_array()
                    .and_then(|a| a.iter().map(|x| x.as_str()).collect());
                match list {
                    Some(l) if !l.is_empty() => {
                        stats = StatSet {
                            avar: false,
                            hvar: false,
                            mvar: false,
                        };
                        for s in l {
                            match s {
                                "avar" => stats.avar = true,
                                "hvar" => stats.hvar = true,
                                "mvar" => stats.mvar = true,
                                other => ck.bad(
                                    "statistics.stats",
                                    format!(
                                        "unknown statistic \"{other}\" (allowed: avar, hvar, mvar)"
                                    ),
                                ),
                            }
                        }
                    }
                    _ => ck.bad(
                        "statistics.stats",
                        format!(
                            "must be a non-empty array of \"avar\", \"hvar\", \"mvar\", not {}",
                            show(v)
                        ),
                    ),
                }
            }
            match st.get("taus") {
                None => {}
                Some(toml::Value::String(s)) if s == "octave" || s == "decade" => {
                    taus = if s == "octave" {
                        TauSpec::Octave
                    } else {
                        TauSpec::Decade
                    }
                }
                Some(toml::Value::Array(a)) => {
                    let ms: Option<Vec<u64>> = a
                        .iter()
                        .map(|x| x.as_integer().filter(|&m| m >= 1).map(|m| m as u64))
                        .collect();
                    match ms {
                        Some(v) if !v.is_empty() => taus = TauSpec::List(v),
                        _ => ck.bad(
                            "statistics.taus",
                            "a list must hold integer cluster sizes m >= 1",
                        ),
                    }
                }
                Some(v) => ck.bad(
                    "statistics.taus",
                    format!(
                        "{}: expected \"octave\", \"decade\" or an array of cluster sizes",
                        show(v)
                    ),
                ),
            }
            match st.get("overlap") {
                None => {}
                Some(toml::Value::String(s)) if s == "full" => overlap = Overlap::Full,
                Some(toml::Value::Integer(l)) if *l >= 1 => overlap = Overlap::Bounded(*l as u64),
                Some(v) => ck.bad(
                    "statistics.overlap",
                    format!("{}: expected \"full\" or an integer L >= 1", show(v)),
                ),
            }
            match ck.string(st, "statistics", "fit").as_deref() {
                None => {}
                Some("none") => fit = None,
                Some(m) => match m.parse::<FitMethod>() {
                    Ok(f) => fit = Some(f),
                    Err(e) => ck.bad("statistics.fit", format!("\"{m}\": {e}")),
                },
            }
        }

        // [channels]
        let mut channels = None;
        if let Some(c) = ck.table(&root, "channels") {
            ck.known_keys("channels", c, &["include"]);
            if let Some(v) = c.get("include") {
                let list: Option<Vec<String>> = v.as_array().and_then(|a| {
                    a.iter()
                        .map(|x| x.as_str().map(String::from))
                        .collect::<Option<Vec<_>>>()
                });
                match list {
                    Some(l) if !l.is_empty() => channels = Some(l),
                    _ => ck.bad(
                        "channels.include",
                        format!(
                            "must be a non-empty array of channel names, not {}",
                            show(v)
                        ),
                    ),
                }
            }
        }

        // [output]
        let mut output = None;
        if let Some(o) = ck.table(&root, "output") {
            ck.known_keys("output", o, &["path"]);
            output = ck.string(o, "output", "path").map(PathBuf::from);
        }

        // [[limits]]: checked here, so their problems come with the others, with lines.
        let limits = match root.get("limits") {
            None => Vec::new(),
            Some(toml::Value::Array(a)) => {
                crate::model::limits::from_tables(a, "limits", &mut ck.c, WHAT)
            }
            Some(v) => {
                ck.bad(
                    "limits",
                    format!("must be an array of tables ([[limits]]), not {}", show(v)),
                );
                Vec::new()
            }
        };

        match (ck.c.is_empty(), source) {
            (true, Some(source)) => Ok(StandConfig {
                file: file.into(),
                source,
                format,
                duration_s,
                checkpoint_every_s,
                every_s,
                capture,
                metrics,
                diagnose,
                stats,
                taus,
                overlap,
                fit,
                channels,
                output,
                limits,
            }),
            _ => Err(ck.c.into_errors(WHAT)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
