//! The checked plan of a whole run ([`RunPlan`]): its units and what the run as a whole does
//! (duration, interim records on wall time, capture, outputs, metrics), built from a stand config
//! ([`RunPlan::from_stand`]) or, by the binary, from command-line options.

use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::Result;

use super::checkpoint_setup::CheckpointRequest;
use super::settings::DataSettings;
use super::unit::{InputPlan, UnitPlan, UnitRequest};
use crate::analysis::{ChannelSetup, InputKind};
use crate::frame::FrameDescriptor;
use crate::input::text::TextOptions;
use crate::source::{Pace, SourceSpec};
use crate::stand::StandConfig;

/// A whole run, checked before anything starts: its units (one today; a stand config may list
/// several) and what the run as a whole does.
#[derive(Debug)]
pub struct RunPlan {
    pub units: Vec<UnitPlan>,
    /// Stop after this many wall-seconds (the binary's timer).
    pub duration_s: Option<f64>,
    /// Wall-seconds between interim records of live units (replays use data-seconds, in each
    /// unit's analysis options).
    pub every_wall_s: Option<f64>,
    /// Every received byte of a live unit also written here.
    pub capture: Option<PathBuf>,
    /// The JSON lines (`None`: standard output).
    pub output: Option<PathBuf>,
    /// Serve `/metrics` here.
    pub metrics: Option<SocketAddr>,
}

/// The flags of `run` that a stand config does not hold.
#[derive(Debug, Clone, Default)]
pub struct RunFlags {
    pub resume: bool,
    pub abort_after_frames: Option<u64>,
}

impl RunPlan {
    /// The plan of a stand config (`run --config`); descriptors by name are searched in `dirs`
    /// (the binary's search path), then the built-in ones. Errors name the config's file and key.
    pub fn from_stand(cfg: &StandConfig, dirs: &[PathBuf], flags: &RunFlags) -> Result<RunPlan> {
        // Checked with the config (StandConfig::load_in): a descriptor that fails now changed
        // since, and names its own file.
        let desc = FrameDescriptor::load_in(&cfg.format, dirs)?;
        let limits = cfg.limits.clone();
        let mut spec = cfg.source.clone();
        let live = spec.is_live();
        if let SourceSpec::File { pace, .. } | SourceSpec::Stdin { pace } = &mut spec {
            if let Pace::Realtime { bytes_per_s } = pace {
                *bytes_per_s = desc.frame_len() as f64 * desc.rate_hz;
            }
        }
        let settings = DataSettings {
            kind: InputKind::Increments,
            unit: "u".into(),
            taus: cfg.taus.clone(),
            overlap: cfg.overlap,
            stats: cfg.stats,
            every_s: cfg.every_s,
            fit: cfg.fit,
            limits,
            diagnose: cfg.diagnose,
            channels: cfg.channels.clone(),
            text: TextOptions::default(),
        };
        let all = ChannelSetup::for_frames(&desc);
        let tau0 = desc.tau0_s();
        let req = UnitRequest {
            checkpoint: CheckpointRequest {
                every_s: cfg.checkpoint_every_s,
                resume: flags.resume,
                abort_after_frames: flags.abort_after_frames,
            },
            out: cfg.output.clone(),
            config: Some(cfg.file.clone()),
            wall_clock: false,
        };
        let input = InputPlan::Frames {
            spec,
            desc: Box::new(desc),
        };
        let unit = UnitPlan::new(input, &cfg.format, all, &settings, tau0, &req)?;
        Ok(RunPlan {
            units: vec![unit],
            duration_s: cfg.duration_s,
            every_wall_s: if live { cfg.every_s } else { None },
            capture: cfg.capture.clone(),
            output: cfg.output.clone(),
            metrics: cfg.metrics,
        })
    }
}
