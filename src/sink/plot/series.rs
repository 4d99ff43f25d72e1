//! The curves a figure draws from result files, chosen once for `plot` and the report: each
//! final curve of one statistic with its run's label (when several runs are overlaid), fit and
//! diagnosis; and, for a channel whose final diagnosis carries an ensemble band but which has
//! no curve of its own (`diagnose --ensemble N` writes diagnosis records only), the measured
//! Allan deviation the band was judged against, as that channel's curve (no intervals).

use std::borrow::Cow;

use super::Series;
use crate::allan::Stat;
use crate::gap::DiagnosisRecord;
use crate::sink::band_words::ensemble_of;
use crate::sink::records::CurveRecord;
use crate::sink::results::{Labelled, Results};

/// The final curves of statistic `stat` whose channel `wanted` accepts, in the order written.
pub fn final_curves<'a>(
    res: &'a Results,
    stat: &str,
    wanted: &dyn Fn(&str) -> bool,
) -> Vec<&'a Labelled<CurveRecord>> {
    res.curves
        .iter()
        .filter(|c| c.rec.r#final && c.rec.stat.name() == stat && wanted(&c.rec.channel))
        .collect()
}

/// The series of `finals` (from [`final_curves`]): each with its run's label when the records
/// span several runs, and its fit and diagnosis unless `with_model` is false; then, for AVAR,
/// the measured curve of every wanted channel's final diagnosis with an ensemble band whose run
/// has no final AVAR curve of that channel.
pub fn figure_series<'a>(
    res: &'a Results,
    finals: &[&'a Labelled<CurveRecord>],
    stat: &str,
    wanted: &dyn Fn(&str) -> bool,
    with_model: bool,
) -> Vec<Series<'a>> {
    let several = res.several_runs();
    let label = |l: &str| {
        if several {
            l.to_string()
        } else {
            String::new()
        }
    };
    let mut out: Vec<Series> = finals
        .iter()
        .map(|c| Series {
            curve: Cow::Borrowed(&c.rec),
            run_label: label(&c.label),
            fit: if with_model { res.fit_of(c) } else { None },
            diagnosis: if with_model {
                res.diagnosis_of(c)
            } else {
                None
            },
        })
        .collect();
    if stat != Stat::Avar.name() {
        return out;
    }
    let mut seen: Vec<(usize, Option<usize>, &str)> = Vec::new();
    for d in &res.diagnoses {
        let key = (d.file, d.run, d.rec.channel.as_str());
        if seen.contains(&key) || !wanted(key.2) {
            continue;
        }
        seen.push(key);
        let has_curve = res.curves.iter().any(|c| {
            (c.file, c.run, c.rec.channel.as_str()) == key
                && c.rec.r#final
                && c.rec.stat == Stat::Avar
        });
        let Some(last) = res.diagnosis_in((d.file, d.run), key.2) else {
            continue;
        };
        if has_curve || ensemble_of(last).is_none() {
            continue;
        }
        out.push(Series {
            curve: Cow::Owned(measured_curve(last)),
            run_label: label(&d.label),
            fit: None,
            diagnosis: with_model.then_some(last),
        });
    }
    out
}

/// The measured ADEV an ensemble band was judged against, as a final AVAR curve record of the
/// diagnosis's channel: at its `model_tau`, without intervals, edf or counts.
pub fn measured_curve(d: &DiagnosisRecord) -> CurveRecord {
    let n = d.model_tau.len();
    let sigma = d
        .ensemble
        .as_ref()
        .map(|e| e.measured.clone())
        .unwrap_or_default();
    CurveRecord {
        channel: d.channel.clone(),
        unit: d.unit.clone().unwrap_or_else(|| "u".into()),
        stat: Stat::Avar,
        t_data: d.t_data,
        r#final: true,
        tau: d.model_tau.clone(),
        sigma,
        lo: vec![None; n],
        hi: vec![None; n],
        edf: vec![None; n],
        count: Vec::new(),
        m: Vec::new(),
        alpha: Vec::new(),
        run: d.run,
    }
}
