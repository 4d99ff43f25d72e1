//! Five values keyed by the term names (Q, N, B, K, R), and one coefficient with its 95%
//! interval: the shapes of the `fit` record's `coef` and `datasheet` objects and of the
//! `diagnosis` record's `final_terms` (docs/records.md).

use crate::model::terms::TERM_NAMES;
use serde::{Deserialize, Serialize};

// The fields of the `fit` record's `coef` and `datasheet` and of their entries are declared in alphabetical order:
// versions before the typed records wrote these two objects through a sorted JSON map, and
// declaring them so keeps every file byte-identical to theirs (JSON readers ignore the order).

/// One coefficient of the `fit` record's `coef` (native unit, docs/theory.md section 2 table):
/// `value` is `null` when the term is not determined; `lo`, `hi` its 95% interval (`null` where
/// undefined).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CoefValue {
    pub determined: bool,
    pub hi: Option<f64>,
    pub lo: Option<f64>,
    pub value: Option<f64>,
}

/// Five values keyed by the term names, as the `fit` record's `coef` and `datasheet` objects hold
/// them ([`Terms::by_index`] in the order Q, N, B, K, R of `crate::model::terms::TERM_NAMES`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[allow(non_snake_case)]
pub struct Terms<T> {
    pub B: T,
    pub K: T,
    pub N: T,
    pub Q: T,
    pub R: T,
}

impl<T> Terms<T> {
    /// The five values from `v(i)`, `i` the index in Q, N, B, K, R order.
    pub fn from_fn(v: impl Fn(usize) -> T) -> Terms<T> {
        Terms {
            Q: v(0),
            N: v(1),
            B: v(2),
            K: v(3),
            R: v(4),
        }
    }

    /// Q..R in order (`crate::model::terms::TERM_NAMES`).
    pub fn by_index(&self, i: usize) -> &T {
        [&self.Q, &self.N, &self.B, &self.K, &self.R][i]
    }

    /// The value of the term named `Q`, `N`, `B`, `K` or `R`.
    pub fn get(&self, name: &str) -> Option<&T> {
        TERM_NAMES
            .iter()
            .position(|k| *k == name)
            .map(|i| self.by_index(i))
    }
}
