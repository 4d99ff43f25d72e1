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
use crate::stand::{StandConfig, UnitConfig};

/// A whole run, checked before anything starts: its units (one per `[[unit]]` table of a
/// stand config, else one) and what the run as a whole does.
#[derive(Debug)]
pub struct RunPlan {
    pub units: Vec<UnitPlan>,
    /// The units are named (`[[unit]]` tables): every record carries `unit`.
    pub named: bool,
    /// Stop after this many wall-seconds (the binary's timer).
    pub duration_s: Option<f64>,
    /// Wall-seconds between interim records of live units (replays use data-seconds, in each
    /// unit's analysis options).
    pub every_wall_s: Option<f64>,
    /// Wall-seconds of silence after which a live unit of several is recorded as out.
    pub quiet_after_s: f64,
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
        let named = cfg.named_units();
        let mut units = Vec::new();
        let mut live = false;
        for u in &cfg.units {
            let plan = unit_plan(cfg, u, dirs, flags)?;
            live |= plan.is_live();
            units.push(plan);
        }
        Ok(RunPlan {
            units,
            named,
            duration_s: cfg.duration_s,
            every_wall_s: if live { cfg.every_s } else { None },
            quiet_after_s: cfg
                .quiet_after_s
                .unwrap_or(crate::stand::DEFAULT_QUIET_AFTER_S),
            output: cfg.output.clone(),
            metrics: cfg.metrics,
        })
    }
}

/// The plan of one unit of a stand config.
fn unit_plan(
    cfg: &StandConfig,
    u: &UnitConfig,
    dirs: &[PathBuf],
    flags: &RunFlags,
) -> Result<UnitPlan> {
    // Checked with the config (StandConfig::load_in): a descriptor that fails now changed
    // since, and names its own file.
    let desc = FrameDescriptor::load_in(&u.format, dirs)?;
    let mut spec = u.source.clone();
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
        limits: u.limits.clone(),
        diagnose: cfg.diagnose,
        channels: u.channels.clone(),
        text: TextOptions::default(),
    };
    let all = ChannelSetup::for_frames(&desc);
    let tau0 = desc.tau0_s();
    // A named unit keeps its checkpoint beside the output as OUTPUT.NAME.ckpt.
    let out = match (&cfg.output, &u.name) {
        (Some(o), Some(n)) => {
            let mut p = o.clone().into_os_string();
            p.push(format!(".{n}"));
            Some(PathBuf::from(p))
        }
        (o, _) => o.clone(),
    };
    let req = UnitRequest {
        checkpoint: CheckpointRequest {
            every_s: cfg.checkpoint_every_s,
            resume: flags.resume,
            abort_after_frames: flags.abort_after_frames,
        },
        out,
        config: Some(cfg.file.clone()),
        wall_clock: false,
    };
    let input = InputPlan::Frames {
        spec,
        desc: Box::new(desc),
    };
    let mut plan = UnitPlan::new(input, &u.format, all, &settings, tau0, &req)?;
    plan.unit_name = u.name.clone();
    plan.capture = u.capture.clone();
    Ok(plan)
}
