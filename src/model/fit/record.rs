//! The shape of the fit in the `fit` record: the `coef` object (keys Q, N, B, K, R, each
//! `{value, lo, hi, determined}`) and the fields this module owns.

#[allow(unused_imports)]
use super::*;

/// One coefficient as docs/records.md's `fit` record prints it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoefValue {
    pub value: Option<f64>,
    pub lo: f64,
    pub hi: f64,
    pub determined: bool,
}

/// The `coef` object of docs/records.md's `fit` record: keys Q, N, B, K, R.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct CoefRecord {
    pub Q: CoefValue,
    pub N: CoefValue,
    pub B: CoefValue,
    pub K: CoefValue,
    pub R: CoefValue,
}

impl FitResult {
    /// The `coef` object of docs/records.md's `fit` record.
    pub fn coef_record(&self) -> CoefRecord {
        let v = |i: usize| {
            let e = &self.coef[i];
            CoefValue {
                value: e.determined.then_some(e.value),
                lo: e.lo,
                hi: e.hi,
                determined: e.determined,
            }
        };
        CoefRecord {
            Q: v(0),
            N: v(1),
            B: v(2),
            K: v(3),
            R: v(4),
        }
    }

    /// `coef` as JSON (keys Q..R).
    pub fn coef_json(&self) -> serde_json::Value {
        serde_json::to_value(self.coef_record()).unwrap_or(serde_json::Value::Null)
    }

    /// The fields this module owns in the `fit` record: `{"coef": {...}, "gof": ...}` (gof null
    /// when not finite, e.g. as many parameters as points).
    pub fn record_fields(&self) -> serde_json::Value {
        serde_json::json!({
            "coef": self.coef_json(),
            "gof": if self.gof.is_finite() { Some(self.gof) } else { None },
        })
    }
}
