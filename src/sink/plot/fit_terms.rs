//! The terms of a fit record as a figure shows them: the fitted coefficients `(Q, N, B, K, R)`
//! and each determined term's value, 95% interval and datasheet value in its native unit.

use crate::model::terms::TERM_NAMES;
use crate::sink::records::FitRecord;

/// The fitted model's coefficients `(Q, N, B, K, R)`: every fitted term (from `model_c`),
/// or the determined ones where an older record lacks it.
pub(super) fn fit_coefs(f: &FitRecord) -> [f64; 5] {
    if f.model_c.len() == 5 {
        std::array::from_fn(|i| f.model_c[i].max(0.0).sqrt())
    } else {
        std::array::from_fn(|i| f.coef.by_index(i).value.unwrap_or(0.0))
    }
}

/// One determined coefficient of a fit: value and 95% interval in the native unit, and the
/// datasheet value and unit when the record has them.
pub struct TermValue {
    pub index: usize,
    pub value: f64,
    pub lo: Option<f64>,
    pub hi: Option<f64>,
    pub datasheet: Option<(f64, String)>,
}

/// The determined terms of a fit.
pub fn determined_terms(f: &FitRecord) -> Vec<TermValue> {
    TERM_NAMES
        .iter()
        .enumerate()
        .filter_map(|(i, k)| {
            let c = f.coef.get(k)?;
            let v = c.value?;
            if !c.determined {
                return None;
            }
            let ds = f.datasheet.as_ref().and_then(|d| {
                let e = d.get(k)?;
                Some((e.value?, e.unit.clone()))
            });
            Some(TermValue {
                index: i,
                value: v,
                lo: c.lo,
                hi: c.hi,
                datasheet: ds,
            })
        })
        .collect()
}
