//! Writes a simulated capture as text columns (CSV): a header row of channel names (plus
//! `temperature_c` when the model has a temperature profile), then one row per step.
//!
//! Values are increments in each channel's unit u, which is what `analyze --format csv` reads.
//! A quantized channel's value is its integer count times its LSB, printed as an exact decimal
//! built from the integer count and the LSB's shortest decimal form (e.g. count 3, lsb 0.004 ->
//! `0.012`), so its bytes depend on the integer count only. An unquantized channel's value is
//! printed in the shortest form that reads back to the same f64 (`{:e}`), the temperature with
//! three decimals (degC).

use std::fmt::Write as _;
use std::io::Write;

use crate::error::UsageError;
use crate::input::header_unit::bracketed;
use crate::model::units::{g_seconds_base, IncrementUnit};

use super::{SimModel, Simulator};

/// Output format of [`simulate_to_writer`]. Frame formats are the frame layer's business.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OutputFormat {
    /// Text columns, comma-separated, header row of channel names.
    Csv,
}

/// Simulate `model` for `duration_s` (rounded to whole steps) from seed `seed` and write it to
/// `out` in `format`. Returns the number of steps written.
pub fn simulate_to_writer(
    model: &SimModel,
    duration_s: f64,
    seed: u64,
    format: OutputFormat,
    out: impl Write,
) -> anyhow::Result<u64> {
    if !(duration_s.is_finite() && duration_s > 0.0) {
        return Err(UsageError::Option(format!(
            "--duration must be a positive number of seconds, got {duration_s}"
        ))
        .into());
    }
    let steps = (duration_s / model.tau0_s).round() as u64;
    match format {
        OutputFormat::Csv => write_csv(model, steps, seed, out)?,
    }
    Ok(steps)
}

fn write_csv(model: &SimModel, steps: u64, seed: u64, out: impl Write) -> anyhow::Result<()> {
    let mut out = std::io::BufWriter::with_capacity(1 << 16, out);
    let lsbs: Vec<Option<DecimalLsb>> = model
        .channels
        .iter()
        .map(|c| c.lsb.map(DecimalLsb::new))
        .collect();
    let mut line = String::with_capacity(256);
    let names: Vec<String> = model
        .channels
        .iter()
        .map(|c| column_header(&c.name, &c.unit))
        .collect();
    line.push_str(&names.join(","));
    if model.temperature.is_some() {
        line.push_str(",temperature_c");
    }
    line.push('\n');
    out.write_all(line.as_bytes())?;
    let mut sim = Simulator::new(model, seed);
    for _ in 0..steps {
        line.clear();
        let step = sim.next_step();
        for (i, (v, c)) in step.increments.iter().zip(step.counts).enumerate() {
            if i > 0 {
                line.push(',');
            }
            match (c, &lsbs[i]) {
                (Some(count), Some(lsb)) => lsb.write_multiple(*count, &mut line),
                _ => write!(line, "{v:e}")?,
            }
        }
        if let Some(t) = step.temperature_c {
            write!(line, ",{t:.3}")?;
        }
        line.push('\n');
        out.write_all(line.as_bytes())?;
    }
    out.flush()?;
    Ok(())
}

/// The header of a channel's column. A name without a unit in brackets is written as it is.
/// A name with one (a twin from `diagnose --model-out` of `ax [m/s^2]`, whose values were rates)
/// would tell a reader its increments are rates: the brackets then hold the channel's increment
/// unit (`ax [m/s]`, `ax [g*s]`), or nothing when that unit is not one a header names.
fn column_header(name: &str, unit: &str) -> String {
    let Some((base, _)) = bracketed(name) else {
        return name.to_string();
    };
    let written = if let Some(g) = g_seconds_base(unit) {
        format!("{base} [{g}*s]")
    } else if IncrementUnit::parse(unit).is_some() {
        format!("{base} [{}]", unit.trim())
    } else {
        base.to_string()
    };
    if written != name {
        tracing::info!(
            "channel `{name}`: its column is headed `{written}`, the unit of its increments"
        );
    }
    written
}

/// An LSB as `digits * 10^exp10`, from its shortest decimal form.
#[derive(Debug, Clone, Copy, PartialEq)]
struct DecimalLsb {
    digits: i128,
    exp10: i32,
}

impl DecimalLsb {
    fn new(lsb: f64) -> Self {
        // `{:e}` gives the shortest round-trip form, e.g. "2.104e-4" or "4e-3".
        let s = format!("{lsb:e}");
        let (mant, exp) = s.split_once('e').unwrap_or((s.as_str(), "0"));
        let exp: i32 = exp.parse().unwrap_or(0);
        let (int, frac) = mant.split_once('.').unwrap_or((mant, ""));
        let digits: i128 = format!("{int}{frac}").parse().unwrap_or(0);
        Self {
            digits,
            exp10: exp - frac.len() as i32,
        }
    }

    /// Append `count * lsb` as an exact decimal, trailing zeros trimmed.
    fn write_multiple(&self, count: i64, out: &mut String) {
        let v = count as i128 * self.digits;
        if v < 0 {
            out.push('-');
        }
        let abs = v.unsigned_abs().to_string();
        if self.exp10 >= 0 {
            out.push_str(&abs);
            if v != 0 {
                out.extend(std::iter::repeat_n('0', self.exp10 as usize));
            }
            return;
        }
        let point = self.exp10.unsigned_abs() as usize;
        let (int, frac) = if abs.len() > point {
            let (a, b) = abs.split_at(abs.len() - point);
            (a.to_string(), b.to_string())
        } else {
            (
                "0".to_string(),
                format!("{}{abs}", "0".repeat(point - abs.len())),
            )
        };
        out.push_str(&int);
        let frac = frac.trim_end_matches('0');
        if !frac.is_empty() {
            out.push('.');
            out.push_str(frac);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{column_header, DecimalLsb};
    use crate::input::header_unit::header_unit;

    /// A twin's channel named after rates (`ax [m/s^2]`) is headed by the unit of the increments
    /// it writes, and reading that header back gives the increment unit, not a rate.
    #[test]
    fn a_unit_in_a_name_becomes_the_increment_s() {
        for (name, unit, want, inc) in [
            ("ax [m/s^2]", "m/s", "ax [m/s]", Some("m/s")),
            ("gx (deg/s)", "deg", "gx [deg]", Some("deg")),
            ("acc_x[g]", "g", "acc_x [g*s]", Some("g")),
            ("gz [rad s^-1]", "u", "gz", None),
            ("g1", "arcsec", "g1", None),
        ] {
            let h = column_header(name, unit);
            assert_eq!(h, want);
            let read = header_unit(&h).map(|r| r.unwrap());
            assert_eq!(read.as_ref().map(|r| r.rate), inc.map(|_| false), "{h}");
            assert_eq!(read.as_ref().map(|r| r.unit.as_str()), inc, "{h}");
        }
    }

    /// Exact decimals of count * lsb, checked by hand.
    #[test]
    fn decimal_multiples() {
        let cases = [
            (0.004, 3, "0.012"),
            (0.004, -250, "-1"),
            (2.104e-4, 186, "0.0391344"),
            (2.104e-4, 0, "0"),
            (0.5, 7, "3.5"),
            (10.0, 3, "30"),
        ];
        for (lsb, count, want) in cases {
            let mut s = String::new();
            DecimalLsb::new(lsb).write_multiple(count, &mut s);
            assert_eq!(s, want, "lsb {lsb} count {count}");
        }
    }
}
