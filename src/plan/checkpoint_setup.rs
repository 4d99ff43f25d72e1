//! A unit's checkpointing, checked before the run starts: the header of the options its state
//! depends on, where the checkpoint lives (beside the output), and, when resuming, the saved
//! checkpoint checked against the header. The file format itself is [`crate::pipeline::checkpoint`]; the
//! threads that write it are [`crate::pipeline::checkpointing`].

use std::path::Path;

use anyhow::Result;

use crate::analysis::{AnalysisOptions, ChannelSetup, InputKind};
use crate::error::UsageError;
use crate::pipeline::checkpoint::{
    check_fresh_start, check_resume, fingerprint, path_for, Checkpoint, CheckpointPlan, Header,
};

/// What was asked of a unit's checkpoints (`--checkpoint-every`, `--resume`, the hidden
/// `--abort-after-frames`, or `[run] checkpoint_every` and `run --resume`).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CheckpointRequest {
    /// Seconds between checkpoints: data-seconds for a replay, wall-seconds live.
    pub every_s: Option<f64>,
    /// Continue from the checkpoint beside the output.
    pub resume: bool,
    /// Test hook: the crash point after this many frames (rows).
    pub abort_after_frames: Option<u64>,
}

impl CheckpointRequest {
    /// Nothing asked.
    pub fn is_none(&self) -> bool {
        self.every_s.is_none() && !self.resume
    }
}

/// The checkpoint plan for the pipeline and, when resuming, the saved checkpoint.
pub type CheckpointSetup = (CheckpointPlan, Option<Checkpoint>);

/// The checkpoint header of a run: the options its accumulated state depends on.
pub fn header(
    input: &str,
    format: &str,
    opts: &AnalysisOptions,
    channels: &[ChannelSetup],
) -> Header {
    use crate::allan::accum::Overlap;
    let s = opts.accum.stats;
    let stats = [("avar", s.avar), ("hvar", s.hvar), ("mvar", s.mvar)]
        .iter()
        .filter(|x| x.1)
        .map(|x| x.0.to_string())
        .collect();
    let file = Path::new(input);
    Header {
        input: input.into(),
        input_fingerprint: (input != "-" && file.is_file())
            .then(|| fingerprint(file))
            .flatten(),
        format: format.into(),
        kind: match opts.kind {
            InputKind::Increments => "increments",
            InputKind::Rate => "rate",
            InputKind::Phase => "phase",
        }
        .into(),
        tau0_s: opts.accum.tau0_s,
        taus: opts.accum.taus.cluster_sizes(),
        overlap: match opts.accum.overlap {
            Overlap::Full => "full".into(),
            Overlap::Bounded(l) => l.to_string(),
        },
        stats,
        channels: channels.iter().map(|c| c.name.clone()).collect(),
        diagnose: opts.diagnose,
    }
}

/// A run's checkpointing from what was asked and the output path: the plan for the pipeline
/// and, when resuming, the saved checkpoint (checked against `header`). `data_seconds`: the
/// interval is in data-seconds (a replay) rather than wall-seconds; `replay`: the input can be
/// read again from an offset (a file).
pub fn setup(
    req: &CheckpointRequest,
    out: Option<&Path>,
    header: Header,
    data_seconds: bool,
    replay: bool,
) -> Result<Option<CheckpointSetup>> {
    let usage = |m: &str| anyhow::Error::new(UsageError::Option(m.into()));
    if req.is_none() {
        if req.abort_after_frames.is_some() {
            return Err(usage("--abort-after-frames needs --checkpoint-every"));
        }
        return Ok(None);
    }
    let Some(out) = out else {
        return Err(usage(concat!(
            "--checkpoint-every and --resume need an output file (--out FILE, or [output] path ",
            "in a stand config): the checkpoint is kept beside it, as FILE.ckpt"
        )));
    };
    if let Some(e) = req.every_s {
        crate::ranges::check_interval(e).map_err(|p| usage(&format!("--checkpoint-every {p}")))?;
    }
    let path = path_for(out);
    let mut plan = CheckpointPlan {
        path: path.clone(),
        every_s: req.every_s.unwrap_or(0.0),
        data_seconds,
        header,
        resume: None,
        abort_after_frames: req.abort_after_frames,
    };
    if !req.resume {
        check_fresh_start(&path)?;
        return Ok(Some((plan, None)));
    }
    let ck = Checkpoint::load(&path)?;
    check_resume(&path, &ck, &plan.header, replay)?;
    if req.every_s.is_none() {
        plan.every_s = ck.every_s;
    }
    plan.resume = Some((ck.position.clone(), ck.sequence));
    tracing::info!(
        "resuming from {} (checkpoint {}, {:.1} s of data, {} bytes of input)",
        path.display(),
        ck.sequence,
        ck.analysis
            .channels
            .iter()
            .map(|c| c.acc.t_data_s())
            .fold(0.0, f64::max),
        ck.position.offset()
    );
    Ok(Some((plan, Some(ck))))
}
