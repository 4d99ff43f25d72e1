//! The ranges a user's numbers must lie in: durations, intervals, sampling steps, descriptor
//! rates and scales, sizes, and the samples themselves ([`MAX_ABS_VALUE`], for frames and text
//! alike). Each is checked where the number is parsed (the command-line option
//! parsers, the stand config, the descriptor checker, a restored checkpoint), so that every
//! loop, buffer and timer a number drives is bounded and a bad value is a usage error naming
//! the option or key, never a panic or a hang.
//!
//! The bounds are wide enough for any real stand and narrow enough that arithmetic on them
//! stays exact and finite: a run of [`MAX_SECONDS`] at [`MAX_RATE_HZ`] still counts its steps
//! in a u64 with room to spare, and a timer of [`MAX_SECONDS`] fits a `std::time::Duration`
//! added to `Instant::now()`.

/// Largest magnitude accepted for a sample (an increment, rate or phase, in the channel's
/// unit); anything larger, and any infinite value, is invalid: counted (`invalid_values`) and
/// taken as a gap, like a NaN. It is far above any sensor's output (a phase of 1e15 counts is
/// 30 years of a 1 MHz counter) and keeps every sum the accumulators form finite: a square is
/// at most 1e30, a run of 1e12 of them 1e42, against f64's 1.8e308. One `inf` or `1e308` would
/// otherwise turn every sigma of its channel into NaN and drop its fit.
pub const MAX_ABS_VALUE: f64 = 1e15;

/// Smallest non-zero magnitude accepted for a sample; anything smaller (but not zero) is
/// invalid, counted and taken as a gap like a value beyond [`MAX_ABS_VALUE`]. The variances sum
/// squares of differences of samples: below about 1e-154 those squares leave f64's normal
/// range (2.2e-308) and a channel of such values reported a deviation of exactly 0. 1e-100
/// keeps every square above 1e-220 even after `--rate` multiplies by the shortest sampling
/// step ([`MIN_TAU0_S`]), far below any sensor's resolution in any unit (a count of 1e-100
/// rad is not a measurement).
pub const MIN_ABS_VALUE: f64 = 1e-100;

/// `v` when it is a usable sample; `None` when it is infinite, beyond [`MAX_ABS_VALUE`], or
/// non-zero below [`MIN_ABS_VALUE`] in magnitude (NaN, a marked gap, is passed through).
#[inline]
pub fn plausible(v: f64) -> Option<f64> {
    let a = v.abs();
    ((a <= MAX_ABS_VALUE && (a >= MIN_ABS_VALUE || a == 0.0)) || v.is_nan()).then_some(v)
}

/// The longest duration or interval accepted anywhere, in seconds (about 31.7 years).
pub const MAX_SECONDS: f64 = 1.0e9;

/// The shortest interval between interim records or checkpoints, in seconds: 1 ms. Shorter ones
/// would make every sample an output.
pub const MIN_INTERVAL_S: f64 = 1.0e-3;

/// The shortest sampling step, in seconds (1 GHz).
pub const MIN_TAU0_S: f64 = 1.0e-9;

/// The longest sampling step, in seconds (about 11.6 days between samples).
pub const MAX_TAU0_S: f64 = 1.0e6;

/// The highest frame rate of a descriptor, in Hz (tau0 = [`MIN_TAU0_S`]).
pub const MAX_RATE_HZ: f64 = 1.0e9;

/// The lowest frame rate of a descriptor, in Hz (tau0 = [`MAX_TAU0_S`]).
pub const MIN_RATE_HZ: f64 = 1.0e-6;

/// The largest magnitude of a descriptor's `scale` (units per LSB): a 64-bit raw value times it
/// stays far below the largest double, and so do the squares the variances sum.
pub const MAX_SCALE: f64 = 1.0e20;

/// The smallest non-zero magnitude of a `scale`.
pub const MIN_SCALE: f64 = 1.0e-20;

/// The most channels one run analyses (descriptor channels, or text columns): each costs a few
/// hundred KB to a few MB of accumulator, evidence and fit state, so 256 stay well inside a
/// stand computer's memory (10 000 took 7 GB).
pub const MAX_CHANNELS: usize = 256;

/// The longest message a descriptor may declare, in bytes: the decoder buffers up to a message
/// to find its frame, so the length bounds its memory.
pub const MAX_MESSAGE_BYTES: u64 = 65_536;

/// The most bytes `simulate` writes in one file (64 GiB): a longer capture is a mistyped
/// duration far more often than a wish; split it into several runs.
pub const MAX_SIMULATED_BYTES: u64 = 1 << 36;

/// Checks that `v` is a number of seconds in `[min, max]`; the error says what was given and
/// what is allowed, for the caller to prefix with the option or key.
pub fn check_seconds(v: f64, min: f64, max: f64) -> Result<f64, String> {
    if v.is_finite() && v >= min && v <= max && v > 0.0 {
        Ok(v)
    } else {
        Err(format!(
            "{}: must be a number of seconds from {} to {}",
            show(v),
            show(min),
            show(max)
        ))
    }
}

/// Parses a duration: seconds, or a number with `s`, `min`, `h` or `d`, checked to lie in
/// `(0, max]` seconds (and at least `min`).
pub fn parse_seconds(text: &str, min: f64, max: f64) -> Result<f64, String> {
    let t = text.trim();
    let (num, mult) = if let Some(v) = t.strip_suffix("min") {
        (v, 60.0)
    } else if let Some(v) = t.strip_suffix('h') {
        (v, 3600.0)
    } else if let Some(v) = t.strip_suffix('d') {
        (v, 86400.0)
    } else if let Some(v) = t.strip_suffix('s') {
        (v, 1.0)
    } else {
        (t, 1.0)
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => {
            let s = v * mult;
            if s.is_finite() && s >= min && s <= max {
                Ok(s)
            } else {
                Err(format!(
                    "`{text}` is {s:.3e} s: must be from {} to {} s",
                    show(min),
                    show(max)
                ))
            }
        }
        _ => Err(format!(
            "`{text}`: expected a positive number of seconds, or one with s, min, h or d"
        )),
    }
}

/// A duration of a run (`--duration`, `run.duration`, `simulate --duration`).
pub fn parse_duration(text: &str) -> Result<f64, String> {
    parse_seconds(text, 0.0, MAX_SECONDS)
}

/// An interval between interim records or checkpoints, in seconds.
pub fn check_interval(v: f64) -> Result<f64, String> {
    check_seconds(v, MIN_INTERVAL_S, MAX_SECONDS)
}

/// A sampling step, in seconds.
pub fn check_tau0(v: f64) -> Result<f64, String> {
    check_seconds(v, MIN_TAU0_S, MAX_TAU0_S)
}

/// A number as a person writes it: plain in `[1e-3, 1e6)`, else in exponent form (`1e9`,
/// `1e-306`), never hundreds of digits.
pub fn show(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_in_and_out_of_range() {
        assert_eq!(parse_duration("3h"), Ok(10_800.0));
        assert_eq!(parse_duration("1.5min"), Ok(90.0));
        assert_eq!(parse_duration("2d"), Ok(172_800.0));
        assert_eq!(parse_duration("1e9"), Ok(1e9));
        assert!(parse_duration("1e20")
            .unwrap_err()
            .contains("from 0 to 1e9 s"));
        assert!(parse_duration("1e300d").is_err());
        assert!(parse_duration("-1").is_err());
        assert!(parse_duration("inf").is_err());
        assert!(parse_duration("nan").is_err());
        assert!(parse_duration("3x").is_err());
    }

    #[test]
    fn intervals_and_steps() {
        assert_eq!(check_interval(0.05), Ok(0.05));
        assert!(check_interval(1e-300).is_err());
        assert!(check_interval(1e20).is_err());
        assert!(check_interval(f64::NAN).is_err());
        assert_eq!(check_tau0(0.004), Ok(0.004));
        assert!(check_tau0(1e308).is_err());
        assert!(check_tau0(0.0).is_err());
        assert_eq!(
            check_tau0(1e308).unwrap_err(),
            "1e308: must be a number of seconds from 1e-9 to 1e6"
        );
    }
}
