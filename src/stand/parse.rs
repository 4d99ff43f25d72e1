//! The top level of a stand config: the tables `[source]`, `[run]`, `[statistics]`,
//! `[channels]`, `[output]`, `[[limits]]` and `[[unit]]` read into a [`StandConfig`], every
//! problem collected before the config is accepted or refused.

use std::path::{Path, PathBuf};

use super::check::{show, Check};
use super::{StandConfig, StandConfigErrors, UnitConfig, WHAT};
use crate::allan::accum::{Overlap, StatSet, TauSpec, DEFAULT_L};
use crate::model::fit::FitMethod;

impl StandConfig {
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
            Some(s) => {
                (source, format) = ck.source(s, "source", descriptor_dirs);
                // One unit: a capture to replay that is not there is refused with the config,
                // at its key. A unit of a `[[unit]]` config whose capture cannot be opened is
                // recorded as failed (an `outage`) while the others go on (README, docs/
                // records.md), so it is not checked here.
                if let Some(crate::source::SourceSpec::File { path, .. }) = &source {
                    ck.capture_exists(path, "source.path");
                }
            }
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
                        "a config with [[unit]] tables gives each unit its own source (`source = { kind = ..., format = ... }` in the unit): remove [source]",
                    );
                }
                if capture.is_some() {
                    ck.bad(
                        "run.capture",
                        "a config with [[unit]] tables gives each unit its own capture (`capture = \"FILE\"` in the unit)",
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
}
