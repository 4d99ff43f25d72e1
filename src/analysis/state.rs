//! A run's saved state (a checkpoint, `crate::pipeline::checkpoint`): [`AnalysisState`], what
//! [`RunAnalysis::snapshot`] saves and [`RunAnalysis::restore`] continues from after checking
//! that the options and channels are the same.

use super::*;

/// One channel's saved state (a checkpoint): its setup, accumulator and evidence as they were.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ChannelSnapshot {
    pub setup: ChannelSetup,
    pub acc: ChannelAccumulator,
    pub gap: Option<GapEvidence>,
    pub last_phase: Option<f64>,
}

/// A run's saved state (a checkpoint, `crate::pipeline::checkpoint`): everything the final records
/// depend on. The fits are not saved: the final fit starts from a fresh covariance cache
/// anyway (see [`RunAnalysis::records`]), and interim fits are recomputed from the curves.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct AnalysisState {
    pub input: String,
    pub channels: Vec<ChannelSnapshot>,
    /// Data-second of the next interim record (infinite: none).
    pub next_emit_s: f64,
    pub bad_rows: u64,
    /// Wall-seconds the run had taken when saved.
    pub elapsed_s: f64,
}

impl RunAnalysis {
    /// The run's state as of now (pending points are not processed, so continuing from the
    /// saved state gives the same numbers as not stopping).
    pub fn snapshot(&self) -> AnalysisState {
        AnalysisState {
            input: self.input.clone(),
            channels: self
                .channels
                .iter()
                .map(|c| ChannelSnapshot {
                    setup: c.setup.clone(),
                    acc: c.acc.clone(),
                    gap: c.gap.clone(),
                    last_phase: c.last_phase,
                })
                .collect(),
            next_emit_s: self.next_emit_s,
            bad_rows: self.bad_rows,
            elapsed_s: self.started.elapsed().as_secs_f64(),
        }
    }

    /// Continues a run from its saved state with `opts`, which must accumulate the same way
    /// (same tau0, cluster sizes, overlap and statistics; the diagnosis on or off as before).
    /// `setups` are the channels the input has now: the saved ones must be the same.
    pub fn restore(
        state: AnalysisState,
        setups: &[ChannelSetup],
        opts: AnalysisOptions,
    ) -> Result<RunAnalysis, String> {
        let saved: Vec<&ChannelSetup> = state.channels.iter().map(|c| &c.setup).collect();
        if saved.len() != setups.len() || saved.iter().zip(setups).any(|(a, b)| *a != b) {
            return Err(format!(
                "saved for the channels [{}], the input now has [{}]",
                saved
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                setups
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        // The next interim record is due at a data-second ahead of zero, or never.
        if state.next_emit_s.is_nan() || state.next_emit_s < 0.0 {
            return Err(format!(
                "the next interim record is due at {} data-seconds",
                state.next_emit_s
            ));
        }
        for c in &state.channels {
            if c.acc.config() != &opts.accum {
                return Err(format!(
                    "channel {} was accumulated with other settings than asked now (saved vs \
                     now: {}); resume with the options of the saved run",
                    c.setup.name,
                    c.acc.config().differences(&opts.accum).join("; ")
                ));
            }
            if c.gap.is_some() != opts.diagnose {
                return Err(format!(
                    "the saved run was made {} the diagnosis; give --diagnose {}",
                    if opts.diagnose { "without" } else { "with" },
                    if opts.diagnose {
                        "only if it was given"
                    } else {
                        "again"
                    }
                ));
            }
        }
        for c in &state.channels {
            c.acc
                .check_restored()
                .map_err(|e| format!("channel {}: {e}", c.setup.name))?;
            if let Some(g) = &c.gap {
                g.check_restored(opts.accum.tau0_s)
                    .map_err(|e| format!("channel {}: {e}", c.setup.name))?;
            }
            if c.last_phase.is_some_and(|x| !x.is_finite()) {
                return Err(format!("channel {}: last phase not finite", c.setup.name));
            }
        }
        let started = Instant::now()
            .checked_sub(std::time::Duration::from_secs_f64(
                if state.elapsed_s.is_finite() {
                    state.elapsed_s.clamp(0.0, 1.0e9)
                } else {
                    0.0
                },
            ))
            .unwrap_or_else(Instant::now);
        Ok(RunAnalysis {
            input: state.input,
            opts,
            channels: state
                .channels
                .into_iter()
                .map(|c| ChannelState {
                    setup: c.setup,
                    acc: c.acc,
                    gap: c.gap,
                    last_phase: c.last_phase,
                    fitter: Fitter::new(),
                    last_fit: None,
                })
                .collect(),
            next_emit_s: state.next_emit_s,
            bad_rows: state.bad_rows,
            invalid_values: 0,
            flagged_cells: 0,
            time_column: None,
            started,
            stopping: Arc::default(),
        })
    }
}
