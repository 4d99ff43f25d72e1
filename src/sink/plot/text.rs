//! The words and numbers of a figure's labels: numbers to 4 significant digits and axis ticks,
//! decade labels, coefficient and sigma units, what a unit measures, effect names and verdicts
//! as a person reads them, and XML escaping.

use crate::gap::DiagnosisRecord;
use crate::model::units::{g_seconds_base, native_units};

pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A number for a label: 4 significant digits, plain between 1e-3 and 1e4.
pub fn sig4(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if (1e-3..1e4).contains(&x.abs()) {
        let d = (3 - x.abs().log10().floor() as i32).max(0) as usize;
        format!("{x:.d$}")
    } else {
        format!("{x:.3e}")
    }
}

/// A number for an axis tick: at most 4 significant digits, trailing zeros dropped.
pub fn tick(x: f64) -> String {
    let t = sig4(x);
    let (m, e) = match t.split_once('e') {
        Some((m, e)) => (m.to_string(), format!("e{e}")),
        None => (t.clone(), String::new()),
    };
    if m.contains('.') {
        format!("{}{e}", m.trim_end_matches('0').trim_end_matches('.'))
    } else {
        t
    }
}

/// A decade label: `10^k` written plainly for |k| <= 3, else as `1e{k}`.
pub(super) fn decade_label(k: i32) -> String {
    match k {
        -3..=-1 => format!("{}", 10f64.powi(k)),
        0..=3 => format!("{}", 10f64.powi(k) as i64),
        _ => format!("1e{k}"),
    }
}

/// The native unit of each coefficient `(Q, N, B, K, R)` for a channel in `u`
/// (docs/theory.md section 2; g-counted accelerometers as [`native_units`] writes them).
pub fn coef_units(u: &str) -> [String; 5] {
    native_units(u)
}

/// What a channel unit measures, for a panel's heading.
pub fn unit_kind(u: &str) -> &'static str {
    let base = u.split('/').next().unwrap_or(u);
    match base {
        "deg" | "rad" | "mrad" | "urad" | "arcsec" | "arcmin" => "gyros (angle increments)",
        "m" if u.starts_with("m/s") => "accelerometers (velocity increments)",
        "ft" | "g" | "mg" | "ug" | "micro-g" => "accelerometers (velocity increments)",
        _ => "channels",
    }
}
/// The kept effects of a diagnosis, in the order added, as a person names them.
pub fn effect_names(d: &DiagnosisRecord) -> Vec<&str> {
    d.effects
        .iter()
        .map(|e| effect_name(e.effect.kind_name()))
        .collect()
}

/// An effect kind of the diagnosis record, as a person names it.
pub fn effect_name(kind: &str) -> &str {
    match kind {
        "gauss_markov" => "Gauss-Markov",
        "output_filter" => "output filter",
        "warmup" => "warm-up",
        "bias_jumps" => "bias jumps",
        "temperature" => "temperature",
        k => k,
    }
}

/// A ratio of deviations: two decimals, three when it is within 1% of 1.
pub fn ratio_text(r: f64) -> String {
    if (r - 1.0).abs() < 0.01 {
        format!("{r:.3}")
    } else {
        format!("{r:.2}")
    }
}

/// The unit of sigma for a channel in `u`: `u/s` (`(m/s)/s` for a compound unit; `g` for
/// increments in g*s).
pub fn sigma_unit(u: &str) -> String {
    if let Some(g) = g_seconds_base(u) {
        g.to_string()
    } else if u.contains('/') {
        format!("({u})/s")
    } else {
        format!("{u}/s")
    }
}

pub(super) fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    match c.next() {
        Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
        None => String::new(),
    }
}

pub(super) fn verdict_word(d: &DiagnosisRecord) -> String {
    d.verdict.name().to_string()
}
