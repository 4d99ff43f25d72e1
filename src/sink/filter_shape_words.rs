//! A diagnosis judged beyond the unit's filter's own stretch (docs/gap.md, "The filter's own
//! stretch of the curve (session 48)"), in words: the filter the whole curve named, from which
//! tau the curve was judged, the whole curve's verdict and gap, and what was set aside there.
//! The record holds it (`filter_shape`: docs/records.md); the terminal table (sink::table) and
//! the report (sink::report) say it through [`filter_shape_words`].

use crate::gap::record::DiagnosisRecord;
use crate::sink::effect_text::effect_bracketed;

/// `the unit's filter, as the whole curve named it: ... (its shape none of the kinds exactly:
/// the curve judged from tau 0.096 s on; the whole curve unexplained, gap 12.7; set aside there:
/// ...)`, or `None` when the whole curve was judged. `unit` is the channel's unit; `number`
/// formats a value; `eq` joins a parameter's name and value (" " or " = ").
pub fn filter_shape_words(
    d: &DiagnosisRecord,
    unit: &str,
    number: &dyn Fn(f64) -> String,
    eq: &str,
) -> Option<String> {
    let f = d.filter_shape.as_ref()?;
    let filter: Vec<String> = f
        .filter
        .iter()
        .map(|e| effect_bracketed(&e.effect, unit, number, eq))
        .collect();
    let verdict = f.verdict_whole.name();
    let mut s = format!(
        "the unit's filter, as the whole curve named it: {} (its shape none of the kinds \
         exactly: the curve judged from tau {} s on; the whole curve {verdict}, gap {}",
        filter.join(" + "),
        number(f.from_tau),
        number(f.gap_whole)
    );
    if !f.set_aside.is_empty() {
        let aside: Vec<String> = f
            .set_aside
            .iter()
            .map(|e| effect_bracketed(&e.effect, unit, number, eq))
            .collect();
        s.push_str("; set aside there: ");
        s.push_str(&aside.join(" + "));
    }
    s.push(')');
    Some(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The words carry the record's numbers: the tau, the whole curve's verdict and gap, the
    /// filter and what was set aside; nothing when the whole curve was judged.
    #[test]
    fn the_words_say_the_tau_the_whole_curve_and_what_was_set_aside() {
        let base = r#"{"type":"diagnosis","channel":"gx","gap_before":1.2,"gap_after":1.2,
            "verdict":"explained","regions":[],"effects":[]"#;
        let whole: DiagnosisRecord = serde_json::from_str(&format!("{base}}}")).expect("record");
        let number = |v: f64| format!("{v}");
        assert_eq!(filter_shape_words(&whole, "deg", &number, " "), None);
        let beyond: DiagnosisRecord = serde_json::from_str(&format!(
            r#"{base},"filter_shape":{{"from_tau":0.096,"gap_whole":12.5,
            "verdict_whole":"unexplained",
            "filter":[{{"kind":"output_filter","params":{{"time_constant":0.02}},"gap_after":40.0}}],
            "set_aside":[{{"kind":"gauss_markov","params":{{"sigma":0.01,"tau_c":0.006}},
            "gap_after":12.5}}]}}}}"#
        ))
        .expect("record with filter_shape");
        let w = filter_shape_words(&beyond, "deg", &number, " ").expect("words");
        assert!(w.contains("from tau 0.096 s on"), "{w}");
        assert!(w.contains("the whole curve unexplained, gap 12.5"), "{w}");
        assert!(w.contains("time constant 0.02"), "{w}");
        assert!(
            w.contains("set aside there: ") && w.contains("correlation time 0.006"),
            "{w}"
        );
    }
}
