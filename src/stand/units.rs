//! The `[[unit]]` tables of a stand config: each unit's name, source, capture, channels and
//! limits, and what two units may not share (a name, a UDP port, a serial device, standard input,
//! a capture file), each clash reported with the key and line of the first holder.

use std::path::{Path, PathBuf};

use super::check::{join, show, Check};
use super::{UnitConfig, MAX_UNIT_NAME};
use crate::source::SourceSpec;

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
impl Check {
    /// The `[[unit]]` tables: each unit's name, source, capture, channels and limits; the
    /// config's `[channels]` and `[[limits]]` are every unit's defaults (a unit's own
    /// `channels` replace them, its own `limits` are added). Two units may not share a name,
    /// a UDP port, a serial port, standard input or a capture file.
    pub(super) fn units(
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
}
