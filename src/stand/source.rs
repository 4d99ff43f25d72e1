//! One `[source]` table of a stand config (at the top, or a unit's own): the kind of source and
//! its keys (path, baud, address, pace), and the frame format, whose descriptor is loaded at once
//! so a bad one is refused with the rest of the config's problems.

use std::path::PathBuf;

use super::check::{join, show, Check};
use super::DEFAULT_BAUD;
use crate::error::UsageError;
use crate::source::{Pace, SourceSpec};

impl Check {
    /// The capture a file source replays, at `key`: refused when there is no such file. A
    /// relative path is taken from the working directory, as every path of the config
    /// (src/stand/mod.rs). Only a file source: a serial port may be plugged in after the check
    /// (it is reopened with backoff), a UDP address is no file.
    pub(super) fn capture_exists(&mut self, path: &std::path::Path, key: &str) {
        if let Err(e) = std::fs::metadata(path) {
            if e.kind() == std::io::ErrorKind::NotFound {
                let relative = if path.is_relative() {
                    " (a relative path is taken from the working directory)"
                } else {
                    ""
                };
                self.bad(key, format!("no such file `{}`{relative}", path.display()));
            }
        }
    }

    /// A `[source]` table (at `prefix`: `source`, or `unit[i].source`): the source and its
    /// frame format, every problem recorded at its key.
    pub(super) fn source(
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
