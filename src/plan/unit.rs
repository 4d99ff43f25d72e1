//! One unit's part of a run, checked ([`UnitPlan`]): where its samples come from, the channels
//! analysed, the analysis options and the checkpointing. [`super::run::RunPlan`] holds the units.

use std::path::{Path, PathBuf};

use anyhow::Result;

use super::channels::select_channels;
use super::checkpoint_setup::{self as checkpoint, CheckpointRequest, CheckpointSetup};
use super::settings::DataSettings;
use crate::analysis::{AnalysisOptions, ChannelSetup, RunAnalysis};
use crate::error::UsageError;
use crate::frame::FrameDescriptor;
use crate::input::text::TextOptions;
use crate::source::SourceSpec;

/// Where a unit's samples come from.
#[derive(Debug, Clone)]
pub enum InputPlan {
    /// Frames of a descriptor from a source (a file, standard input, a serial port, UDP).
    Frames {
        spec: SourceSpec,
        desc: Box<FrameDescriptor>,
    },
    /// Text columns from a file, or `-` for standard input.
    Text { input: String, options: TextOptions },
}

/// One unit's part of a run, checked: every option parsed and in range, the channels chosen,
/// the checkpoint found and matched when resuming. Nothing has been read or written yet.
#[derive(Debug)]
pub struct UnitPlan {
    /// The input's name in records and messages: a path, `-`, `udp:ADDR`, `serial:PATH`.
    pub name: String,
    pub input: InputPlan,
    /// The format as given (`csv`, a descriptor's name or path), for the checkpoint header.
    pub format: String,
    /// The channels analysed, in input order.
    pub channels: Vec<ChannelSetup>,
    pub analysis: AnalysisOptions,
    /// The checkpoint plan and, when resuming, the saved checkpoint.
    pub checkpoint: Option<CheckpointSetup>,
    /// The unit's name in a stand config of several (`[[unit]]`): its records carry it.
    pub unit_name: Option<String>,
    /// Every received byte of a live source also written here.
    pub capture: Option<PathBuf>,
}

/// What the units are checked against while they are planned.
#[derive(Debug, Clone, Default)]
pub struct UnitRequest {
    /// The checkpoints asked for.
    pub checkpoint: CheckpointRequest,
    /// The output the checkpoint is kept beside.
    pub out: Option<PathBuf>,
    /// The stand config the settings came from: errors then name its file and key instead of
    /// an option.
    pub config: Option<PathBuf>,
    /// The command keeps wall time (`listen`, even on standard input): checkpoints every
    /// wall-second and interim records by the pipeline's clock, as for a live source.
    pub wall_clock: bool,
}

impl UnitPlan {
    /// Plans a unit whose input has `all` channels (the descriptor's, or the text header's):
    /// the settings' channel choice applied, the analysis options for `tau0_s`, the checkpoint
    /// set up. `data_seconds`: checkpoints and interim records count data time (a replay).
    pub fn new(
        input: InputPlan,
        format: &str,
        all: Vec<ChannelSetup>,
        settings: &DataSettings,
        tau0_s: f64,
        req: &UnitRequest,
    ) -> Result<UnitPlan> {
        let analysis = settings.analysis_options(tau0_s);
        Self::with_options(input, format, all, &settings.channels, analysis, req)
    }

    /// [`Self::new`] with the analysis options already made (several runs of one command share
    /// them, each with its run index) and `wanted` the channel choice.
    pub fn with_options(
        input: InputPlan,
        format: &str,
        all: Vec<ChannelSetup>,
        wanted: &Option<Vec<String>>,
        mut analysis: AnalysisOptions,
        req: &UnitRequest,
    ) -> Result<UnitPlan> {
        let name = match &input {
            InputPlan::Frames { spec, .. } => spec.name(),
            InputPlan::Text { input, .. } => input.clone(),
        };
        let (data_seconds, replay) = match &input {
            InputPlan::Frames { spec, .. } => (
                !(req.wall_clock || spec.is_live()),
                matches!(spec, SourceSpec::File { .. }),
            ),
            InputPlan::Text { input, .. } => (!req.wall_clock, input != "-"),
        };
        let channels = select_channels(all, wanted, &name).map_err(|e| match &req.config {
            // In a stand config the choice is its `channels.include`: said at its line, not as
            // the option `--channels` (session 42's review found neither).
            Some(file) => {
                let key = "channels.include";
                let line = crate::toml_check::Collector::line_in_file(file, key);
                let problem = e.to_string();
                UsageError::Config {
                    file: file.clone(),
                    line,
                    key: key.into(),
                    problem: problem
                        .strip_prefix("--channels: ")
                        .unwrap_or(&problem)
                        .to_string(),
                }
            }
            None => e,
        })?;
        if !data_seconds {
            // Live: interim records on wall time (the pipeline), not data time.
            analysis.every_s = None;
        }
        let header = checkpoint::header(&name, format, &analysis, &channels);
        let checkpoint = checkpoint::setup(
            &req.checkpoint,
            req.out.as_deref(),
            header,
            data_seconds,
            replay,
        )
        .map_err(|e| match &req.config {
            Some(file) => e.context(format!("stand config {}", file.display())),
            None => e,
        })?;
        Ok(UnitPlan {
            name,
            input,
            format: format.into(),
            channels,
            analysis,
            checkpoint,
            unit_name: None,
            capture: None,
        })
    }

    /// The frame descriptor (`None` for text columns).
    pub fn descriptor(&self) -> Option<&FrameDescriptor> {
        match &self.input {
            InputPlan::Frames { desc, .. } => Some(desc),
            InputPlan::Text { .. } => None,
        }
    }

    /// True for a serial or UDP source (no end; silences are wall time).
    pub fn is_live(&self) -> bool {
        matches!(&self.input, InputPlan::Frames { spec, .. } if spec.is_live())
    }

    /// The name the unit is known by in messages and metrics: its stand-config name, else its
    /// input.
    pub fn label(&self) -> &str {
        self.unit_name.as_deref().unwrap_or(&self.name)
    }

    /// The checkpoint's file, when the unit has one.
    pub fn checkpoint_path(&self) -> Option<&Path> {
        self.checkpoint.as_ref().map(|c| c.0.path.as_path())
    }

    /// The unit's analysis: fresh, or continued from the saved checkpoint's state. A datasheet
    /// limit on a channel the unit does not have is refused (it would never be judged).
    pub fn start_analysis(&self) -> Result<RunAnalysis> {
        start_analysis(
            &self.name,
            self.channels.clone(),
            self.analysis.clone(),
            self.checkpoint.as_ref().and_then(|c| c.1.as_ref()),
            self.checkpoint_path(),
        )
    }
}

/// The analysis of a run: fresh, or continued from a checkpoint's state (`path` names it).
pub fn start_analysis(
    input: &str,
    setups: Vec<ChannelSetup>,
    opts: AnalysisOptions,
    resume: Option<&crate::pipeline::checkpoint::Checkpoint>,
    path: Option<&Path>,
) -> Result<RunAnalysis> {
    // A limit that no channel matches would never be judged: a misspelt name, refused here,
    // at the file and line it was written on.
    let names: Vec<(&str, &str)> = setups
        .iter()
        .map(|c| (c.name.as_str(), c.unit.as_str()))
        .collect();
    crate::model::limits::check_channels(&opts.limits, input, &names)?;
    match resume {
        None => Ok(RunAnalysis::new(input, setups, opts)),
        Some(ck) => RunAnalysis::restore(ck.analysis.clone(), &setups, opts).map_err(|p| {
            anyhow::Error::new(UsageError::Checkpoint {
                file: path.map(Path::to_path_buf).unwrap_or_default(),
                problem: p,
            })
        }),
    }
}
