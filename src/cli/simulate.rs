//! `simulate`: writes a capture (text columns or frames of a descriptor) from a noise model.

use std::io::Write;

use anyhow::{Context, Result};

use super::{parse_duration_s, SimulateArgs};
use allanscope::frame::FrameDescriptor;

pub fn run(s: &SimulateArgs) -> Result<()> {
    let duration = parse_duration_s(&s.duration)?;
    let model = allanscope::sim::SimModel::load(&s.model)?;
    let f = std::fs::File::create(&s.out)
        .with_context(|| format!("cannot create {}", s.out.display()))?;
    let mut w = std::io::BufWriter::with_capacity(1 << 16, f);
    let steps = if s.format == "csv" {
        allanscope::sim::simulate_to_writer(
            &model,
            duration,
            s.seed,
            allanscope::sim::OutputFormat::Csv,
            &mut w,
        )?
    } else {
        let desc = FrameDescriptor::load(&s.format).map_err(anyhow::Error::new)?;
        allanscope::sim::capture::simulate_to_frames(&model, &desc, duration, s.seed, &mut w)?
    };
    w.flush()?;
    tracing::info!("{}: {steps} steps written", s.out.display());
    Ok(())
}
