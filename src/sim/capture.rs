//! Writes a simulated run as a capture of frames of any descriptor, through the same encoder
//! the decoder's tests use, so `analyze CAPTURE --format NAME` reads it like a recording.
//!
//! Channels are matched by name. An integer increment field gets the unit's own counting: the
//! increment is quantized to the field's LSB with the remainder carried to the next step
//! (docs/theory.md section 2, `Q = LSB/sqrt(12)`), or the simulator's own counts are used when the
//! model's LSB is the field's.

use std::io::Write;

use anyhow::{bail, Result};

use super::{SimModel, Simulator};
use crate::error::UsageError;
use crate::frame::{encode_frame, ChannelValue, FrameDescriptor, FrameInput};

enum Source {
    /// The simulator's own counts (same LSB).
    Counts(usize),
    /// Quantize the increment to `lsb`, carrying the remainder (u).
    Quantize { ch: usize, lsb: f64, carry: f64 },
    /// A floating field: the increment itself.
    Real(usize),
}

/// Simulates `duration_s` seconds and writes frames of `desc` to `out`; returns the frame count.
pub fn simulate_to_frames(
    model: &SimModel,
    desc: &FrameDescriptor,
    duration_s: f64,
    seed: u64,
    mut out: impl Write,
) -> Result<u64> {
    let tau0 = model.tau0_s;
    if (desc.tau0_s() - tau0).abs() > 1e-12 * tau0 {
        bail!(UsageError::Option(format!(
            "the model's step {tau0} s differs from the {} descriptor's {} s",
            desc.name,
            desc.tau0_s()
        )));
    }
    let mut sources = Vec::new();
    for info in desc.channels() {
        let Some(ch) = model.channels.iter().position(|c| c.name == info.name) else {
            bail!(UsageError::Option(format!(
                "the model has no channel `{}` that the {} frame carries (model channels: {})",
                info.name,
                desc.name,
                model
                    .channels
                    .iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        };
        let m = &model.channels[ch];
        if m.unit != info.unit {
            bail!(UsageError::Option(format!(
                "channel `{}`: the model's unit `{}` is not the frame's `{}`",
                info.name, m.unit, info.unit
            )));
        }
        sources.push(match info.scale {
            Some(lsb) if m.lsb == Some(lsb) => Source::Counts(ch),
            Some(lsb) => Source::Quantize {
                ch,
                lsb,
                carry: 0.0,
            },
            None => Source::Real(ch),
        });
    }
    let n_steps = (duration_s / tau0).round() as u64;
    let status = desc.status_all_valid();
    let mut sim = Simulator::new(model, seed);
    let mut values = vec![ChannelValue::Real(0.0); sources.len()];
    for k in 0..n_steps {
        let step = sim.next_step();
        for (v, src) in values.iter_mut().zip(sources.iter_mut()) {
            *v = match src {
                Source::Counts(ch) => ChannelValue::Count(step.counts[*ch].unwrap_or(0)),
                Source::Quantize { ch, lsb, carry } => {
                    let total = step.increments[*ch] + *carry;
                    let c = (total / *lsb).round();
                    *carry = total - c * *lsb;
                    ChannelValue::Count(c as i64)
                }
                Source::Real(ch) => ChannelValue::Real(step.increments[*ch]),
            };
        }
        let bytes = encode_frame(
            desc,
            &FrameInput {
                seq: k,
                values: &values,
                status,
                temperature_c: step.temperature_c,
            },
        )?;
        out.write_all(&bytes)?;
    }
    Ok(n_steps)
}
