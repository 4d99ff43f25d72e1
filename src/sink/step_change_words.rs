//! A step of the values that changed during the run ([`crate::gap::lsb::StepChange`]: a range
//! switched, or the unit changed its output format), in the words of the warning that both
//! `diagnose` and `analyze --diagnose` give (docs/gap.md, "A sixteenth blind review").

use crate::gap::lsb::StepChange;

/// `the values' step changed during the run (2.99e-6 -> 6.00e-5 after about 2867 s): a range
/// switched or a new output format? The run is diagnosed as one unit; its quantization is
/// judged with one step, 2.99e-6`, or `None` when the step never changed.
///
/// `changes` and `more` as [`crate::gap::lsb::LsbEstimator::step_changes`] gives them, `held`
/// the run's one step (`None`: the values show no single step), all as increments (u);
/// `per` turns an increment's step into the step of the values read (`1 / tau0` for rate
/// samples, 1 for increments); `tau0_s` the sampling step; `number` formats a value.
pub fn step_change_words(
    changes: &[StepChange],
    more: u64,
    held: Option<f64>,
    per: f64,
    tau0_s: f64,
    number: &dyn Fn(f64) -> String,
) -> Option<String> {
    if changes.is_empty() {
        return None;
    }
    let each: Vec<String> = changes
        .iter()
        .map(|c| {
            format!(
                "{} -> {} after about {:.0} s",
                number(c.from * per),
                number(c.to * per),
                c.at_value as f64 * tau0_s
            )
        })
        .collect();
    Some(format!(
        "the values' step changed during the run ({}{}): a range switched or a new output \
         format? The run is diagnosed as one unit; its quantization is judged with {}",
        each.join(", "),
        if more > 0 {
            format!(", and {more} more")
        } else {
            String::new()
        },
        held.map_or("no single step".to_string(), |q| format!(
            "one step, {}",
            number(q * per)
        ))
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sci(x: f64) -> String {
        format!("{x:.2e}")
    }

    #[test]
    fn a_step_that_changed_is_said_in_the_values_own_unit() {
        let changes = [StepChange {
            at_value: 286_720,
            from: 2.99e-8,
            to: 6.0e-7,
        }];
        // rate samples at 100 Hz: the increments' steps are a hundredth of the values'
        let w = step_change_words(&changes, 0, Some(2.99e-8), 100.0, 0.01, &sci).unwrap();
        assert_eq!(
            w,
            "the values' step changed during the run (2.99e-6 -> 6.00e-5 after about 2867 s): a \
             range switched or a new output format? The run is diagnosed as one unit; its \
             quantization is judged with one step, 2.99e-6"
        );
        let w = step_change_words(&changes, 3, None, 1.0, 0.01, &sci).unwrap();
        assert!(
            w.contains("(2.99e-8 -> 6.00e-7 after about 2867 s, and 3 more)"),
            "{w}"
        );
        assert!(w.ends_with("judged with no single step"), "{w}");
        assert_eq!(step_change_words(&[], 0, Some(1.0), 1.0, 0.01, &sci), None);
    }
}
