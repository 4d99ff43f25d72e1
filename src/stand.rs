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
//!
//! Several units in one process: `[[unit]]` tables instead of `[source]`, each with a `name`,
//! a `source` table (the keys above), and optionally `capture`, `channels` and `[[unit.limits]]`
//! (`config/lab.toml`); `[run] capture` moves into the units, `[run] quiet_after` (seconds) says
//! when a silent live unit is recorded as out. Two units may not share a name, a UDP port, a
//! serial device, standard input or a capture file ([`UnitConfig`]).

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

/// A unit name: letters, digits, `_`, `-`, `.` (it is part of file names and metric labels).
fn valid_unit_name(n: &str) -> bool {
    n.len() <= MAX_UNIT_NAME
        && n.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
}

/// What a unit holds that no other unit may hold too.
#[derive(Debug, Clone, PartialEq)]
enum Holding {
    Name(String),
    Udp(std::net::SocketAddr),
    Serial(PathBuf),
    Stdin,
    Capture(PathBuf),
}

impl Holding {
    /// Two units cannot both hold these: the same name, port (a UDP port bound on every
    /// interface clashes with any address of that port), device, standard input or capture.
    fn clashes(&self, o: &Holding) -> bool {
        match (self, o) {
            (Holding::Udp(a), Holding::Udp(b)) => {
                a.port() == b.port()
                    && (a.ip() == b.ip() || a.ip().is_unspecified() || b.ip().is_unspecified())
            }
            (a, b) => a == b,
        }
    }

    fn clash_phrase(&self) -> String {
        match self {
            Holding::Name(n) => format!("unit name \"{n}\" given twice: the same name"),
            Holding::Udp(a) => format!("UDP {a}: the same port"),
            Holding::Serial(p) => format!("serial port {}: the same device", p.display()),
            Holding::Stdin => "standard input: read by one unit only, and already".into(),
            Holding::Capture(p) => format!("capture {}: the same file", p.display()),
        }
    }
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

    /// A table under `key` of `t`, itself at `prefix`.
    fn sub_table<'t>(
        &mut self,
        t: &'t toml::Table,
        prefix: &str,
        key: &str,
    ) -> Option<&'t toml::Table> {
        match t.get(key) {
            None => None,
            Some(toml::Value::Table(t)) => Some(t),
            Some(v) => {
                self.bad(
                    &join(prefix, key),
                    format!("must be a table, not {}", v.type_str()),
                );
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
    /// A `channels` table (`include = [...]`) at `prefix`.
    fn channels(&mut self, c: &toml::Table, prefix: &str) -> Option<Vec<String>> {
        self.known_keys(prefix, c, &["include"]);
        let v = c.get("include")?;
        let list: Option<Vec<String>> = v.as_array().and_then(|a| {
            a.iter()
                .map(|x| x.as_str().map(String::from))
                .collect::<Option<Vec<_>>>()
        });
        match list {
            Some(l) if !l.is_empty() => Some(l),
            _ => {
                self.bad(
                    &join(prefix, "include"),
                    format!(
                        "must be a non-empty array of channel names, not {}",
                        show(v)
                    ),
                );
                None
            }
        }
    }

    /// The `[[limits]]` tables under `key` of `t` (`limits`, `unit[i].limits`).
    fn limits(&mut self, t: &toml::Table, key: &str) -> Vec<crate::model::limits::LimitSpec> {
        let at = key.rsplit('.').next().unwrap_or(key);
        match t.get(at) {
            None => Vec::new(),
            Some(toml::Value::Array(a)) => {
                crate::model::limits::from_tables(a, key, &mut self.c, WHAT)
            }
            Some(v) => {
                self.bad(
                    key,
                    format!("must be an array of tables ([[{key}]]), not {}", show(v)),
                );
                Vec::new()
            }
        }
    }

    /// The `[[unit]]` tables: each unit's name, source, capture, channels and limits; the
    /// config's `[channels]` and `[[limits]]` are every unit's defaults (a unit's own
    /// `channels` replace them, its own `limits` are added). Two units may not share a name,
    /// a UDP port, a serial port, standard input or a capture file.
    fn units(
        &mut self,
        v: &toml::Value,
        descriptor_dirs: &[PathBuf],
        channels: &Option<Vec<String>>,
        limits: &[crate::model::limits::LimitSpec],
        output: Option<&Path>,
    ) -> Vec<UnitConfig> {
        let tables: Vec<Option<&toml::Table>> = match v {
            toml::Value::Array(a) if !a.is_empty() => a.iter().map(|x| x.as_table()).collect(),
            other => {
                self.bad(
                    "unit",
                    format!(
                        "must be one or more [[unit]] tables, not {}",
                        match other {
                            toml::Value::Array(_) => "an empty array".to_string(),
                            o => show(o),
                        }
                    ),
                );
                return Vec::new();
            }
        };
        let mut units = Vec::new();
        // What each unit holds, with the key it was given at, to name both of a pair.
        let mut held: Vec<(Holding, String)> = Vec::new();
        for (i, t) in tables.into_iter().enumerate() {
            let at = format!("unit[{i}]");
            let Some(t) = t else {
                self.bad(&at, "must be a table ([[unit]])");
                continue;
            };
            self.known_keys(&at, t, &["name", "source", "capture", "channels", "limits"]);
            let name = self.string(t, &at, "name");
            match &name {
                None if !t.contains_key("name") => self.bad(
                    &join(&at, "name"),
                    "missing: the unit's name (its records, metrics and files carry it)",
                ),
                Some(n) if !valid_unit_name(n) => self.bad(
                    &join(&at, "name"),
                    format!(
                        "\"{n}\": use letters, digits, `_`, `-` and `.` (at most {MAX_UNIT_NAME} \
                         characters): it names the unit's files and metrics"
                    ),
                ),
                _ => {}
            }
            let src_key = join(&at, "source");
            let (source, format) = match self.sub_table(t, &at, "source") {
                Some(s) => self.source(s, &src_key, descriptor_dirs),
                None => {
                    if !t.contains_key("source") {
                        self.bad(
                            &src_key,
                            "missing: the unit's source, e.g. source = { kind = \"udp\", \
                             address = \"127.0.0.1:5001\", format = \"siu8\" }",
                        );
                    }
                    (None, String::new())
                }
            };
            let capture = self.string(t, &at, "capture").map(PathBuf::from);
            let own_channels = match self.sub_table(t, &at, "channels") {
                Some(c) => self.channels(c, &join(&at, "channels")),
                None => None,
            };
            let mut unit_limits = limits.to_vec();
            unit_limits.extend(self.limits(t, &join(&at, "limits")));
            let mut holds = Vec::new();
            if let Some(n) = &name {
                holds.push((Holding::Name(n.clone()), join(&at, "name")));
            }
            match &source {
                Some(SourceSpec::Udp { bind }) => {
                    holds.push((Holding::Udp(*bind), join(&src_key, "address")))
                }
                Some(SourceSpec::Serial { path, .. }) => {
                    holds.push((Holding::Serial(path.clone()), join(&src_key, "path")))
                }
                Some(SourceSpec::Stdin { .. }) => {
                    holds.push((Holding::Stdin, join(&src_key, "kind")))
                }
                _ => {}
            }
            if let Some(c) = &capture {
                if output == Some(c.as_path()) {
                    self.bad(
                        &join(&at, "capture"),
                        format!("\"{}\" is also [output] path", c.display()),
                    );
                }
                holds.push((Holding::Capture(c.clone()), join(&at, "capture")));
            }
            for (h, key) in holds {
                if let Some((_, first)) = held.iter().find(|(o, _)| o.clashes(&h)) {
                    let line = self
                        .c
                        .line_of(first)
                        .map_or(String::new(), |l| format!(" (line {l})"));
                    self.bad(&key, format!("{} as `{first}`{line}", h.clash_phrase()));
                } else {
                    held.push((h, key));
                }
            }
            if let (Some(name), Some(source)) = (name, source) {
                units.push(UnitConfig {
                    name: Some(name),
                    source,
                    format,
                    capture,
                    channels: own_channels.or_else(|| channels.clone()),
                    limits: unit_limits,
                });
            }
        }
        units
    }

    /// A `[source]` table (at `prefix`: `source`, or `unit[i].source`): the source and its
    /// frame format, every problem recorded at its key.
    fn source(
        &mut self,
        s: &toml::Table,
        prefix: &str,
        descriptor_dirs: &[PathBuf],
    ) -> (Option<SourceSpec>, String) {
        let mut format = String::new();
        let mut source = None;
        self.known_keys(
            prefix,
            s,
            &["kind", "path", "baud", "address", "format", "pace"],
        );
        match self.string(s, prefix, "format") {
            Some(f) if f == "csv" => self.bad(
                &join(prefix, "format"),
                "\"csv\": run reads frames; give a frame descriptor (siu8, kvh1750, ...)",
            ),
            Some(f) => {
                // The descriptor is read now, so a bad one is refused with the rest:
                // an unknown name at this key, a bad file by its own lines.
                if let Err(e) = crate::frame::FrameDescriptor::load_in(&f, descriptor_dirs) {
                    for p in e.problems {
                        match p {
                            UsageError::Option(m) => self.bad(&join(prefix, "format"), m),
                            other => self.c.extend([other]),
                        }
                    }
                }
                format = f;
            }
            None if !s.contains_key("format") => self.bad(
                &join(prefix, "format"),
                "missing: a frame descriptor name (siu8, kvh1750, hg4930) or path",
            ),
            None => {}
        }
        let pace = match self.string(s, prefix, "pace").as_deref() {
            None | Some("max") => Pace::Max,
            // The byte rate is filled in once the descriptor is loaded.
            Some("realtime") => Pace::Realtime { bytes_per_s: 0.0 },
            Some(other) => {
                self.bad(
                    &join(prefix, "pace"),
                    format!("\"{other}\": expected \"max\" or \"realtime\""),
                );
                Pace::Max
            }
        };
        let kind = self.string(s, prefix, "kind");
        let baud = match s.get("baud") {
            None => Some(DEFAULT_BAUD),
            Some(toml::Value::Integer(b)) if *b > 0 && *b <= 20_000_000 => Some(*b as u32),
            Some(v) => {
                self.bad(
                    &join(prefix, "baud"),
                    format!("must be a positive integer baud rate, not {}", show(v)),
                );
                None
            }
        };
        let path = self.string(s, prefix, "path");
        let needs = |ck: &mut Check, key: &str, what: &str| {
            if !s.contains_key(key) {
                ck.bad(&join(prefix, key), format!("missing: {what}"));
            }
        };
        let only_for = |ck: &mut Check, key: &str, kinds: &str| {
            if s.contains_key(key) {
                ck.bad(&join(prefix, key), format!("only for kind = {kinds}"));
            }
        };
        match kind.as_deref() {
            Some("serial") => {
                needs(self, "path", "the serial port, e.g. \"/dev/ttyUSB0\"");
                only_for(self, "address", "\"udp\"");
                only_for(self, "pace", "\"file\" or \"stdin\"");
                if let (Some(p), Some(baud)) = (path, baud) {
                    source = Some(SourceSpec::Serial {
                        path: p.into(),
                        baud,
                    });
                }
            }
            Some("udp") => {
                needs(
                    self,
                    "address",
                    "ADDR:PORT to bind, e.g. \"127.0.0.1:5000\"",
                );
                only_for(self, "path", "\"serial\" or \"file\"");
                only_for(self, "baud", "\"serial\"");
                only_for(self, "pace", "\"file\" or \"stdin\"");
                if let Some(a) = self.string(s, prefix, "address") {
                    match crate::source::udp::parse_bind(&a) {
                        Ok(bind) => source = Some(SourceSpec::Udp { bind }),
                        Err(e) => self.bad(&join(prefix, "address"), e),
                    }
                }
            }
            Some("file") => {
                needs(self, "path", "the capture file");
                only_for(self, "address", "\"udp\"");
                only_for(self, "baud", "\"serial\"");
                if let Some(p) = path {
                    source = Some(SourceSpec::File {
                        path: p.into(),
                        pace,
                    });
                }
            }
            Some("stdin") => {
                only_for(self, "path", "\"serial\" or \"file\"");
                only_for(self, "address", "\"udp\"");
                only_for(self, "baud", "\"serial\"");
                source = Some(SourceSpec::Stdin { pace });
            }
            Some(other) => self.bad(
                &join(prefix, "kind"),
                format!("\"{other}\": expected serial, udp, file or stdin"),
            ),
            None if !s.contains_key("kind") => {
                self.bad(&join(prefix, "kind"), "missing: serial, udp, file or stdin")
            }
            None => {}
        }
        (source, format)
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
                "unit",
            ],
        );

        // [source]
        let mut format = String::new();
        let mut source = None;
        match ck.table(&root, "source") {
            None if !root.contains_key("source") && !root.contains_key("unit") => {
                ck.bad("source", "missing: the [source] table (or [[unit]] tables)")
            }
            None => {}
            Some(s) => (source, format) = ck.source(s, "source", descriptor_dirs),
        }

        // [run]
        let (mut duration_s, mut every_s, mut capture) = (None, None, None);
        let mut checkpoint_every_s = None;
        let mut diagnose = false;
        let mut metrics = None;
        let mut quiet_after_s = None;
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
                    "quiet_after",
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
            quiet_after_s = ck.seconds(r, "run", "quiet_after", MIN_INTERVAL_S, MAX_SECONDS);
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
        let channels = match ck.table(&root, "channels") {
            Some(c) => ck.channels(c, "channels"),
            None => None,
        };

        // [output]
        let mut output = None;
        if let Some(o) = ck.table(&root, "output") {
            ck.known_keys("output", o, &["path"]);
            output = ck.string(o, "output", "path").map(PathBuf::from);
        }

        // [[limits]]: checked here, so their problems come with the others, with lines.
        let limits = ck.limits(&root, "limits");

        // [[unit]]: several units in one process, each with its own source.
        let units = match root.get("unit") {
            None => match source {
                Some(source) => vec![UnitConfig {
                    name: None,
                    source,
                    format,
                    capture,
                    channels,
                    limits,
                }],
                None => Vec::new(),
            },
            Some(v) => {
                if root.contains_key("source") {
                    ck.bad(
                        "source",
                        "a config with [[unit]] tables gives each unit its own source                          (`source = { kind = ..., format = ... }` in the unit): remove [source]",
                    );
                }
                if capture.is_some() {
                    ck.bad(
                        "run.capture",
                        "a config with [[unit]] tables gives each unit its own capture                          (`capture = \"FILE\"` in the unit)",
                    );
                }
                ck.units(v, descriptor_dirs, &channels, &limits, output.as_deref())
            }
        };

        if ck.c.is_empty() && !units.is_empty() {
            Ok(StandConfig {
                file: file.into(),
                units,
                duration_s,
                checkpoint_every_s,
                every_s,
                quiet_after_s,
                metrics,
                diagnose,
                stats,
                taus,
                overlap,
                fit,
                output,
            })
        } else {
            Err(ck.c.into_errors(WHAT))
        }
    }

    /// True when the config lists its units in `[[unit]]` tables: records then carry `unit`.
    pub fn named_units(&self) -> bool {
        self.units.iter().any(|u| u.name.is_some())
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
