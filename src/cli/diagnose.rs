//! `diagnose`: the sim-to-real gap of each channel of a run (text columns or a capture):
//! where the measured curve leaves the five-term model, which effect closes it, and how far;
//! with `--holdout`, the effects fitted on INPUT judged on a second run of the same unit.

use std::io::{BufReader, Read};
use std::path::Path;

use anyhow::{Context, Result};

use super::{format_and_tau0, open_input, usage, DiagnoseArgs};
use allanscope::analysis::ChannelSetup;
use allanscope::frame::{FrameDescriptor, FrameEvent};
use allanscope::gap::diagnose::diagnose_with_temperature;
use allanscope::gap::temperature::settling_profile;
use allanscope::gap::unit_model::{fitted_channel, fitted_unit, ChannelFacts};
use allanscope::gap::EffectParams;
use allanscope::gap::{
    holdout_gap_with_temperature, DiagnoseOptions, DiagnosisRecord, GapConfig, GapEvidence,
};
use allanscope::input::text::{TextReader, BATCH_ROWS};
use allanscope::pipeline::decode::DecodeStage;
use allanscope::plan::unit::{InputPlan, UnitPlan, UnitRequest};
use allanscope::sim::model_write::model_toml;
use allanscope::sink::first_block_words::first_block_words;
use allanscope::sink::records::Record;
use allanscope::sink::step_change_words::step_change_words;
use allanscope::sink::table::sig3;
use allanscope::source::{Pace, SourceEvent, SourceSpec};

/// One channel's evidence, gathered from a whole input.
struct Gathered {
    names: Vec<String>,
    /// Each channel's unit (the descriptor's, or `--unit` for text columns).
    units: Vec<String>,
    evidence: Vec<GapEvidence>,
    /// The values were rate samples (`--rate`, a rate `--unit` or the headers' units), whose
    /// step is no LSB of the increments.
    rate: bool,
    /// The sum of each channel's increments (u), for the model file's bias.
    sums: Vec<f64>,
    /// The unit's temperature (degC) when the input has one, as evidence fed `T tau0` per step
    /// (the channels' block layout: gap::temperature), and its sum (degC) and sum of squares
    /// (degC^2) over the steps.
    temperature: Option<GapEvidence>,
    temperature_sum: f64,
    temperature_sum2: f64,
    temperature_n: u64,
    /// The last known temperature (degC), held over steps without one (a temperature logged
    /// more slowly than the rates, or a missing value), and how many steps were held.
    temperature_last: Option<f64>,
    temperature_held: u64,
    /// Steps before the first known temperature: given that first value when it comes.
    temperature_pending: u64,
}

impl Gathered {
    /// One increment (u) of channel `k`.
    fn push(&mut self, k: usize, d: f64) {
        self.evidence[k].push_increment(d);
        self.sums[k] += d;
    }

    /// A missing increment of channel `k`.
    fn gap(&mut self, k: usize, missing: u64) {
        self.evidence[k].push_gap(missing);
    }

    /// The temperature of one step (NaN or None: not known for this step). A step without one
    /// gets the last known temperature (zero-order hold: a temperature logged at 1 Hz beside
    /// 100 Hz rates, or a missing value), the steps before the first known one that first
    /// value, so that the temperature's evidence sees every step the channels see (the
    /// temperature test needs both on the same steps: gap::temperature).
    fn push_temperature(&mut self, t: Option<f64>, tau0: f64) {
        let Some(ev) = self.temperature.as_mut() else {
            return;
        };
        match (t.filter(|t| t.is_finite()), self.temperature_last) {
            (Some(t), _) => {
                for _ in 0..std::mem::take(&mut self.temperature_pending) {
                    ev.push_increment(t * tau0);
                    self.temperature_held += 1;
                }
                ev.push_increment(t * tau0);
                self.temperature_sum += t;
                self.temperature_sum2 += t * t;
                self.temperature_n += 1;
                self.temperature_last = Some(t);
            }
            (None, Some(l)) => {
                ev.push_increment(l * tau0);
                self.temperature_held += 1;
            }
            (None, None) => self.temperature_pending += 1,
        }
    }

    /// `missing` lost steps of the temperature (a gap of the frames).
    fn temperature_gap(&mut self, missing: u64) {
        if let Some(ev) = self.temperature.as_mut() {
            // Steps waiting for a first temperature stay unknown when a gap comes first.
            ev.push_gap(std::mem::take(&mut self.temperature_pending) + missing);
        }
    }

    /// At the end of the input: a temperature column without a single value is not used;
    /// held steps are said once.
    fn finish_temperature(&mut self, input: &str) {
        if self.temperature.is_none() {
            return;
        }
        if self.temperature_n == 0 {
            tracing::warn!("{input}: the temperature has no value; it is not used");
            self.temperature = None;
            return;
        }
        if self.temperature_held > 0 {
            tracing::warn!(
                "{input}: the temperature is missing at {} of {} steps; each such step takes \
                 the last known value (the steps before the first known value take that value)",
                self.temperature_held,
                self.temperature_held + self.temperature_n
            );
        }
    }

    fn add_channel(&mut self, name: &str, unit: &str, cfg: &GapConfig) {
        self.names.push(name.to_string());
        self.units.push(unit.to_string());
        self.evidence.push(GapEvidence::new(cfg.clone()));
        self.sums.push(0.0);
    }
}

/// Reads a run and feeds every selected channel's increments to its evidence. The input is
/// planned as `analyze` plans it ([`UnitPlan`]: the same format, channels, and channel choice,
/// `--channel` or `--channels`), read by the same readers (the text reader, the replay's decode
/// stage), and its values become increments by the same rule ([`InputKind::step`]).
fn gather(
    input: &str,
    a: &DiagnoseArgs,
    desc: Option<&FrameDescriptor>,
    tau0: f64,
) -> Result<Gathered> {
    let cfg = GapConfig::new(tau0);
    let mut g = Gathered {
        names: Vec::new(),
        units: Vec::new(),
        rate: a.data.rate,
        evidence: Vec::new(),
        sums: Vec::new(),
        temperature: None,
        temperature_sum: 0.0,
        temperature_sum2: 0.0,
        temperature_n: 0,
        temperature_last: None,
        temperature_held: 0,
        temperature_pending: 0,
    };
    let mut settings = a.data.settings()?;
    if a.channel.is_some() {
        settings.channels = a.channel.clone();
        settings.text.channels = a.channel.clone();
    }
    // Diagnose reads the input once: no checkpoints (refused in `run`).
    let req = UnitRequest::default();
    // Binary data given as text columns, text or another unit's bytes given as frames: refused
    // as `analyze` refuses them.
    super::analyze::sniff(input, desc)?;
    match desc {
        None => {
            let path = Path::new(input);
            let mut reader = TextReader::with_options(
                BufReader::with_capacity(1 << 16, open_input(input)?),
                path,
                &settings.text,
            )
            .map_err(anyhow::Error::new)?;
            let (setups, kind) = a.data.text_channels(input, &reader, &settings)?;
            settings.kind = kind;
            g.rate = kind == allanscope::analysis::InputKind::Rate;
            let plan = UnitPlan::new(
                InputPlan::Text {
                    input: input.into(),
                    options: settings.text.clone(),
                },
                "csv",
                setups,
                &settings,
                tau0,
                &req,
            )?;
            for c in &plan.channels {
                g.add_channel(&c.name, &c.unit, &cfg);
            }
            let columns: Vec<usize> = plan.channels.iter().map(|c| c.column).collect();
            // The temperature column (docs/records.md's `temperature_c`, or one a logger
            // names: `temp [degC]`), read here only, in degC; the first if there are several.
            let temp = reader
                .temperatures()
                .into_iter()
                .enumerate()
                .find_map(|(i, t)| t.map(|t| (i, t)));
            let temp_col = temp.map(|(i, _)| i);
            let temp_scale = temp.map(|(_, t)| t);
            if temp_col.is_some() {
                g.temperature = Some(GapEvidence::new(cfg.clone()).without_outlier_filter());
            }
            let width = reader.names().len();
            let mut last_phase: Vec<Option<f64>> = vec![None; columns.len()];
            let mut rows = Vec::with_capacity(BATCH_ROWS * width);
            loop {
                rows.clear();
                if reader
                    .read_rows(&mut rows, BATCH_ROWS)
                    .with_context(|| format!("reading {input}"))?
                    == 0
                {
                    break;
                }
                for row in rows.chunks_exact(width) {
                    let mut stepped = false;
                    for (k, &col) in columns.iter().enumerate() {
                        match kind.step(row[col], tau0, &mut last_phase[k]) {
                            Some(d) if d.is_finite() => g.push(k, d),
                            Some(_) => g.gap(k, 1),
                            None => continue,
                        }
                        stepped = true;
                    }
                    // The temperature follows the steps of the channels (a first phase row
                    // gives none), so both evidences see the same steps.
                    if stepped || columns.is_empty() {
                        g.push_temperature(
                            temp_col.zip(temp_scale).map(|(c, t)| t.to_c(row[c])),
                            tau0,
                        );
                    }
                }
            }
            let invalid = reader.position().invalid_values;
            if invalid > 0 {
                tracing::warn!(
                    "{input}: {invalid} values infinite, above {:e} or non-zero below {:e} in \
                     magnitude: each taken as a gap of its channel",
                    allanscope::ranges::MAX_ABS_VALUE,
                    allanscope::ranges::MIN_ABS_VALUE
                );
            }
            if reader.samples() == 0 {
                return Err(anyhow::Error::new(allanscope::error::UsageError::Input {
                    file: path.into(),
                    line: reader.position().line_no,
                    problem: allanscope::input::text::no_samples_problem(
                        reader.position().invalid_values,
                    ),
                }));
            }
        }
        Some(desc) => {
            let spec = if input == "-" {
                SourceSpec::Stdin { pace: Pace::Max }
            } else {
                SourceSpec::File {
                    path: input.into(),
                    pace: Pace::Max,
                }
            };
            let plan = UnitPlan::new(
                InputPlan::Frames {
                    spec,
                    desc: Box::new(desc.clone()),
                },
                &a.data.format,
                ChannelSetup::for_frames(desc),
                &settings,
                tau0,
                &req,
            )?;
            if desc.frame().temperature.is_some() {
                g.temperature = Some(GapEvidence::new(cfg.clone()).without_outlier_filter());
            }
            for c in &plan.channels {
                g.add_channel(&c.name, &c.unit, &cfg);
            }
            let columns: Vec<(usize, Option<f64>)> = plan
                .channels
                .iter()
                .map(|c| (c.column, c.counts_lsb))
                .collect();
            let mut src = open_input(input)?;
            // The decode stage of a replay, as `analyze` runs it.
            let mut stage = DecodeStage::new(desc.clone(), false);
            let mut events = Vec::new();
            let mut buf = vec![0u8; 1 << 16];
            loop {
                let n = src
                    .read(&mut buf)
                    .with_context(|| format!("reading {input}"))?;
                if n == 0 {
                    stage.finish(&mut events);
                } else {
                    let ev = SourceEvent::Data {
                        bytes: bytes::Bytes::copy_from_slice(&buf[..n]),
                        at: std::time::Instant::now(),
                    };
                    stage.push(ev, &mut events);
                }
                for ev in events.drain(..) {
                    match ev {
                        FrameEvent::Frame(f) => {
                            g.push_temperature(f.temperature_c, tau0);
                            for (k, &(col, lsb)) in columns.iter().enumerate() {
                                match f.values.get(col).copied().flatten() {
                                    Some(v) => g.push(k, v.physical(lsb)),
                                    None => g.gap(k, 1),
                                }
                            }
                        }
                        FrameEvent::Gap { missing } => {
                            (0..columns.len()).for_each(|k| g.gap(k, missing));
                            g.temperature_gap(missing);
                        }
                    }
                }
                if n == 0 {
                    break;
                }
            }
            let h = stage.health();
            if h.crc_errors + h.missing + h.invalid_values + h.bytes_skipped > 0 {
                tracing::warn!(
                    "{input}: {} frames decoded; {} failed their check, {} missing (gaps), {} \
                     values out of range (gaps), {} bytes skipped",
                    h.frames,
                    h.crc_errors,
                    h.missing,
                    h.invalid_values,
                    h.bytes_skipped
                );
            }
        }
    }
    g.finish_temperature(input);
    Ok(g)
}

pub fn run(a: &DiagnoseArgs) -> Result<()> {
    let d = &a.data;
    if d.checkpoint_every.is_some() || d.resume {
        return Err(usage(
            "diagnose reads its input in one pass and keeps no checkpoints: --checkpoint-every \
             and --resume are for analyze, listen and run",
        ));
    }
    if let Some(p) = &a.model_out {
        check_model_out(p)?;
    }
    let mut sink = allanscope::sink::json::JsonLines::new(super::analyze::output_writer(d)?);
    let (desc, tau0) = format_and_tau0(d)?;
    let opts = DiagnoseOptions::default();
    let mut main = gather(&a.input, a, desc.as_ref(), tau0)?;
    let mut held = match &a.holdout {
        Some(h) => Some(gather(h, a, desc.as_ref(), tau0)?),
        None => None,
    };
    // The held-out run is matched to the input by channel name: one with none of the input's
    // channels would judge nothing, and say nothing of it.
    if let (Some(h), Some(path)) = (&held, &a.holdout) {
        let missing: Vec<&String> = main.names.iter().filter(|n| !h.names.contains(n)).collect();
        if missing.len() == main.names.len() {
            return Err(usage(format!(
                "--holdout {path}: none of the channels of {} ({}) is in it (it has {}); the \
                 held-out run is matched by channel name",
                a.input,
                main.names.join(", "),
                h.names.join(", ")
            )));
        }
        for n in missing {
            tracing::warn!(
                "--holdout {path}: no channel {n}; that channel is diagnosed without a held-out \
                 run"
            );
        }
    }
    let mut fitted = Vec::new();
    // The twin's terms the run did not determine, said at the model file's top.
    let mut notes: Vec<String> = Vec::new();
    let temp_snap = main.temperature.as_mut().map(|t| t.snapshot());
    let held_temp = held
        .as_mut()
        .and_then(|h| h.temperature.as_mut().map(|t| t.snapshot()));
    // The recorded temperature as the simulator's settling profile (for --model-out).
    let profile = temp_snap
        .as_ref()
        .and_then(|t| settling_profile(&t.block_means, t.block_len as f64 * tau0));
    let mut written = 0usize;
    for (i, name) in main.names.iter().enumerate() {
        let snap = main.evidence[i].snapshot();
        let diag = match diagnose_with_temperature(&snap, temp_snap.as_ref(), &opts) {
            Ok(x) => x,
            Err(e) => {
                tracing::warn!("{}: channel {name}: {e}", a.input);
                continue;
            }
        };
        if let Some(st) = diag.stuck {
            tracing::warn!(
                "{}: channel {name}: {} stretch(es) where every sample was the same, far longer \
                 than its noise allows (stuck, saturated or a repeated sample?): {:.3} s in all, \
                 the longest {:.3} s, the first at {:.3} s; taken out as gaps",
                a.input,
                st.stretches,
                st.seconds,
                st.longest_s,
                st.first_at_s
            );
        }
        // The values' step changed during the run (gap::lsb::StepChange): a range switched or
        // a new output format; the quantization is judged with one step for the whole run.
        // Rate samples' steps as rates (the values read), increments' as increments.
        let per = if main.rate { 1.0 / tau0 } else { 1.0 };
        if let Some(w) = step_change_words(
            &snap.step_changes,
            snap.step_changes_more,
            snap.lsb,
            per,
            tau0,
            &sig3,
        ) {
            tracing::warn!("{}: channel {name}: {w}", a.input);
        }
        let holdout = held.as_mut().and_then(|h| {
            let j = h.names.iter().position(|n| n == name)?;
            let snap2 = h.evidence[j].snapshot();
            // What the held-out judgement says (an effect it could not judge) names the channel.
            let _channel = tracing::info_span!("holdout", channel = %name).entered();
            holdout_gap_with_temperature(&diag, &snap2, held_temp.as_ref(), &opts)
                .map_err(|e| tracing::warn!("{}: holdout channel {name}: {e}", a.input))
                .ok()
        });
        let mut rec = DiagnosisRecord::new(name, &diag, holdout.as_ref(), true);
        rec.unit = Some(main.units[i].clone());
        // A first block far off, in the table's words (sink::first_block_words).
        if let Some(w) = first_block_words(&rec, &main.units[i], &sig3) {
            tracing::warn!("{}: channel {name}: {w}", a.input);
        }
        // The twin is the unit: an effect the held-out run judged and disowned (it did not
        // carry there) was this run's, not the unit's, and is left out of it (a filter, the
        // unit's own shaping, is kept). Before (session 53), a rev16 review's accelerometer had
        // a 0.04 Hz sinusoid beside its Gauss-Markov term that the held-out run rejected and
        // the twin still drew.
        let disowned: Vec<_> = holdout
            .iter()
            .flat_map(|h| &h.effects)
            .filter(|e| !e.carried && !e.kind.is_filter())
            .map(|e| e.kind)
            .collect();
        let twin_diag = (!disowned.is_empty()).then(|| {
            let mut d = diag.clone();
            d.effects.retain(|e| !disowned.contains(&e.params.kind()));
            d
        });
        let twin_diag = twin_diag.as_ref().unwrap_or(&diag);
        let twin = (a.model_out.is_some() || a.ensemble.is_some()).then(|| {
            let t_run = snap.n_increments as f64 * tau0;
            let mut facts = ChannelFacts {
                name: name.clone(),
                unit: main.units[i].clone(),
                // The step of rate samples is not a phase LSB (it is the rate-sample
                // quantization of a MEMS part), so only increments and phase give one.
                lsb: if main.rate { None } else { snap.lsb },
                bias: if t_run > 0.0 {
                    main.sums[i] / t_run
                } else {
                    0.0
                },
                temperature_coefficient: 0.0,
                temperature_quadratic: 0.0,
            };
            // A temperature effect: its coefficient, the bias at the profile's reference.
            let coef = twin_diag.effects.iter().find_map(|e| match e.params {
                EffectParams::Temperature {
                    coefficient,
                    quadratic,
                    ..
                } => Some((coefficient, quadratic)),
                _ => None,
            });
            if let (Some((c, quadratic)), Some(p), true) = (coef, &profile, main.temperature_n > 0)
            {
                let n = main.temperature_n as f64;
                let mean_t = main.temperature_sum / n;
                let mean_t2 = main.temperature_sum2 / n;
                let r = p.reference_c;
                // `c (T - T_q) + q (T - T_q)^2` about the model's reference `r`:
                // `(c + 2 q (r - T_q)) (T - r) + q (T - r)^2` and a constant the bias takes.
                let (slope, q) = match quadratic {
                    Some(q) => (c + 2.0 * q.coefficient * (r - q.reference_c), q.coefficient),
                    None => (c, 0.0),
                };
                facts.temperature_coefficient = slope;
                facts.temperature_quadratic = q;
                facts.bias -= slope * (mean_t - r) + q * (mean_t2 - 2.0 * r * mean_t + r * r);
            }
            fitted_channel(&facts, twin_diag, tau0)
        });
        if let (Some(runs), Some(ch)) = (a.ensemble, twin.as_ref()) {
            rec.ensemble = Some(ensemble_record(
                ch,
                &snap,
                &rec.model_tau,
                tau0,
                runs as usize,
            ));
        }
        sink.write(&Record::from(rec))?;
        written += 1;
        if a.model_out.is_some() && twin.is_some() {
            if let Some(n) = undetermined_note(name, &main.units[i], &diag) {
                notes.push(n);
            }
            if !disowned.is_empty() {
                let kinds: Vec<&str> = disowned.iter().map(|k| k.name()).collect();
                notes.push(format!(
                    "{name}: left out, found on this run but not carried to the held-out run {}: \
                     {}",
                    a.holdout.as_deref().unwrap_or("?"),
                    kinds.join(", ")
                ));
            }
            fitted.extend(twin);
        }
    }
    sink.flush()?;
    if written == 0 {
        // Each channel's reason was logged above; a run that diagnosed nothing is an error,
        // not an empty success.
        return Err(usage(format!(
            "{}: no channel could be diagnosed (see the warnings above)",
            a.input
        )));
    }
    if let Some(p) = &a.model_out {
        let model = fitted_unit(tau0, fitted, profile);
        let mut header = vec![
            format!("The unit fitted by `allanscope diagnose {}`.", a.input),
            "Five terms with the accepted effects in; a sinusoid's phase is not estimated (0)."
                .to_string(),
        ];
        header.extend(notes);
        let text = model_toml(&model, &format!("fitted from {}", a.input), &header);
        write_new(p, &text)?;
    }
    Ok(())
}

/// `--ensemble N`: the measured ADEV at the record's taus against the bands of `runs` simulated
/// runs of the fitted channel, base and twin (gap::ensemble), on the machine's threads.
fn ensemble_record(
    ch: &allanscope::sim::model_file::ChannelModel,
    snap: &allanscope::gap::EvidenceSnapshot,
    taus: &[f64],
    tau0: f64,
    runs: usize,
) -> allanscope::gap::record::EnsembleRecord {
    use allanscope::gap::ensemble::{band, base_of};
    let ms: Vec<u64> = taus.iter().map(|t| (t / tau0).round() as u64).collect();
    let measured: Vec<f64> = ms
        .iter()
        .map(|m| {
            snap.curve
                .iter()
                .find(|p| p.m == *m)
                .map_or(f64::NAN, |p| p.avar.max(0.0).sqrt())
        })
        .collect();
    let n_inc = snap.n_increments as usize;
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let base = band(&base_of(ch), tau0, n_inc, &ms, runs, threads, 1);
    let twin = band(ch, tau0, n_inc, &ms, runs, threads, 1);
    allanscope::gap::record::EnsembleRecord {
        runs,
        outside_base: base.outside_share(&measured),
        outside_twin: twin.outside_share(&measured),
        measured,
        base_lo: base.lo,
        base_hi: base.hi,
        twin_lo: twin.lo,
        twin_hi: twin.hi,
    }
}

/// `--model-out` never replaces a file, and must be one that can be created: an existing file,
/// a directory or a folder that does not exist is refused before any input is read (exit 2),
/// not found once the whole diagnosis has run.
fn check_model_out(p: &Path) -> Result<()> {
    allanscope::sink::page_file::check_target(p, "--model-out")?;
    if p.exists() {
        return Err(usage(format!(
            "--model-out {}: the file exists; remove it or choose another name",
            p.display()
        )));
    }
    Ok(())
}

/// Writes `text` to a new file (never over an existing one).
fn write_new(p: &Path, text: &str) -> Result<()> {
    use std::io::Write as _;
    let mut f = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(p)
        .with_context(|| format!("--model-out {}: cannot create", p.display()))?;
    f.write_all(text.as_bytes())
        .and_then(|_| f.sync_all())
        .with_context(|| format!("--model-out {}: cannot write", p.display()))
}

/// A line for the model file's top naming the channel's terms that the run did not determine
/// (the record's `final_terms`: an interval reaching zero or below a third of the value), each
/// written at the fit's value, with its 95% interval in the record's units (docs/theory.md
/// section 2); `None` when every term written is determined. A twin's undetermined R or K,
/// simulated at its point value, draws a ramp or a walk the run did not show; the file says so
/// rather than hiding it (session 42).
fn undetermined_note(name: &str, unit: &str, diag: &allanscope::gap::Diagnosis) -> Option<String> {
    let terms: Vec<String> = diag
        .final_terms
        .iter()
        .enumerate()
        .filter_map(|(i, t)| {
            let t = t.filter(|t| !t.determined && t.value > 0.0)?;
            Some(format!(
                "{} {:.3e} (95% interval [{:.3e}, {:.3e}], {})",
                allanscope::model::terms::TERM_NAMES[i],
                t.value,
                t.lo,
                t.hi,
                allanscope::model::units::native_units(unit)[i]
            ))
        })
        .collect();
    (!terms.is_empty()).then(|| {
        format!(
            "{name}: not determined by the run, written at the fit's value: {}",
            terms.join("; ")
        )
    })
}
