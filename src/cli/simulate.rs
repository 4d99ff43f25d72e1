//! `simulate`: writes a capture (text columns or frames of a descriptor) from a noise model.
//!
//! The capture is written to `OUT.partial` beside the output and renamed over it when
//! complete: a failed or interrupted run leaves no file (nor a 0-byte one), and an existing
//! output is replaced only with `--force`. The size is estimated before anything is written
//! and refused above [`allanscope::ranges::MAX_SIMULATED_BYTES`]. A pipe or device given with
//! `--force` (`-o /dev/stdout`) is written directly.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use allanscope::frame::FrameDescriptor;

use super::{parse_duration_s, usage, SimulateArgs};

/// Bytes a text row takes per channel, at most: a separator and a `{:.9e}`-style number.
const CSV_BYTES_PER_VALUE: u64 = 24;

pub fn run(s: &SimulateArgs) -> Result<()> {
    let duration = parse_duration_s(&s.duration)?;
    allanscope::sink::page_file::check_target(&s.out, "-o")?;
    let stdout = s.out == Path::new("-");
    if !s.force && !stdout && s.out.exists() {
        return Err(usage(format!(
            "{}: exists; give --force to replace it, or another -o",
            s.out.display()
        )));
    }
    let model = allanscope::sim::SimModel::load(&s.model)?;
    let desc = if s.format == "csv" {
        None
    } else {
        Some(super::load_descriptor(&s.format).map_err(anyhow::Error::new)?)
    };
    let steps = (duration / model.tau0_s).ceil();
    let per_step = match &desc {
        None => CSV_BYTES_PER_VALUE * model.channels.len().max(1) as u64,
        Some(d) => {
            let extra = d
                .interleave
                .as_ref()
                .map_or(0, |i| i.count * d.messages[i.message].length as u64);
            d.frame_len() as u64 + extra
        }
    };
    let bytes = steps * per_step as f64;
    if bytes > allanscope::ranges::MAX_SIMULATED_BYTES as f64 {
        return Err(usage(format!(
            "--duration {}: {steps:.3e} steps of {per_step} bytes would write about {:.3e} bytes, \
             more than the {} GiB one simulated file may hold; simulate a shorter run",
            s.duration,
            bytes,
            allanscope::ranges::MAX_SIMULATED_BYTES >> 30
        )));
    }
    if stdout {
        // `-o -`: standard output, written as it goes (`simulate ... -o - | allanscope analyze -`).
        let steps = write_capture_to(s, &model, desc.as_ref(), duration, std::io::stdout().lock())
            .context("writing to standard output")?;
        tracing::info!("standard output: {steps} steps written");
        return Ok(());
    }
    if std::fs::metadata(&s.out).is_ok_and(|m| !m.is_file()) {
        // A pipe or a device (`-o /dev/stdout --force`): written as it goes, nothing to rename.
        let steps = write_capture(s, &model, desc.as_ref(), duration, &s.out)?;
        tracing::info!("{}: {steps} steps written", s.out.display());
        return Ok(());
    }
    let partial = partial_path(&s.out);
    let written = write_capture(s, &model, desc.as_ref(), duration, &partial);
    match written {
        Ok(steps) => {
            std::fs::rename(&partial, &s.out).with_context(|| {
                format!("cannot rename {} to {}", partial.display(), s.out.display())
            })?;
            match desc {
                // Text columns carry no time: say the step they must be read at.
                None => tracing::info!(
                    "{}: {steps} steps written, {} s apart (read it with --tau0 {})",
                    s.out.display(),
                    model.tau0_s,
                    model.tau0_s
                ),
                Some(_) => tracing::info!("{}: {steps} steps written", s.out.display()),
            }
            Ok(())
        }
        Err(e) => {
            let _ = std::fs::remove_file(&partial);
            Err(e)
        }
    }
}

/// `OUT.partial`, beside the output.
fn partial_path(out: &Path) -> PathBuf {
    let mut p = out.as_os_str().to_owned();
    p.push(".partial");
    PathBuf::from(p)
}

fn write_capture(
    s: &SimulateArgs,
    model: &allanscope::sim::SimModel,
    desc: Option<&FrameDescriptor>,
    duration: f64,
    path: &Path,
) -> Result<u64> {
    let f = std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(true)
        .open(path)
        .with_context(|| format!("cannot create {}", path.display()))?;
    write_capture_to(s, model, desc, duration, f)
        .with_context(|| format!("cannot write {}", path.display()))
}

fn write_capture_to(
    s: &SimulateArgs,
    model: &allanscope::sim::SimModel,
    desc: Option<&FrameDescriptor>,
    duration: f64,
    out: impl Write,
) -> Result<u64> {
    let mut w = std::io::BufWriter::with_capacity(1 << 16, out);
    let steps = match desc {
        None => allanscope::sim::simulate_to_writer(
            model,
            duration,
            s.seed,
            allanscope::sim::OutputFormat::Csv,
            &mut w,
        )?,
        Some(desc) => {
            allanscope::sim::capture::simulate_to_frames(model, desc, duration, s.seed, &mut w)?
        }
    };
    w.flush()?;
    Ok(steps)
}
