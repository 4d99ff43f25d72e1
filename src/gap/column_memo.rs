//! The model columns of one [`super::problem::GapProblem`] that depend only on a candidate
//! filter (and, for the rounding after it, on the white rate it is computed at), kept once
//! computed. The diagnosis fits the same filters over and over: every greedy step, every first
//! step it tries and every polish scans the same grids of time constants, natural frequencies
//! and dampings, and only the other columns of the model change. On a 3-hour rounded 250 Hz
//! channel (docs/repro/session11/accf3h.toml) about 14 000 filter columns were asked for, of
//! 1 100 distinct filters, and 86 000 rounding floors of 49 000 distinct `(filter, N^2)` pairs
//! (docs/gap.md, "Speed (session 17)"). The values are the functions' own, bit for bit: a memo,
//! not an approximation.
//!
//! Each table is bounded ([`MAX_COLUMNS`], [`MAX_FLOORS`]): when full it is emptied and starts
//! again, so a long search never holds more than a few megabytes. A clone of the problem starts
//! with empty tables (they are keyed by the filter only and hold the problem's cluster sizes).

use crate::model::lowpass::{LowPass, SecondOrderForm};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Filters whose columns are kept at most (each holds two columns of the curve's length, a few
/// hundred bytes).
pub const MAX_COLUMNS: usize = 4096;
/// Rounding floors kept at most (one column each).
pub const MAX_FLOORS: usize = 16384;
/// Filters whose autocorrelation is kept at most (the rounding floor's input, asked for at
/// every white rate the floor is computed at: a tenth of a filtered unit's diagnosis was
/// recomputing it; at most a few thousand lags each).
pub const MAX_AUTOCORRELATIONS: usize = 1024;

/// A filter's identity: its kind and the bits of its parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct FilterKey(u8, u64, u64, u64, u64);

impl FilterKey {
    pub fn of(lp: &LowPass) -> Self {
        match *lp {
            LowPass::FirstOrder { time_constant_s } => {
                FilterKey(0, time_constant_s.to_bits(), 0, 0, 0)
            }
            LowPass::MovingAverage {
                taps,
                stages,
                decimation,
            } => FilterKey(
                1,
                u64::from(taps),
                u64::from(stages),
                u64::from(decimation),
                0,
            ),
            // the back's key, its kind moved past the plain ones', and the front packed in the
            // last place (taps below 2^32, stages below 2^8, decimation below 2^24)
            LowPass::Cascade { front, back } => {
                let FilterKey(kind, a, b, c, _) = FilterKey::of(&back.lowpass());
                let packed = u64::from(front.taps)
                    | u64::from(front.stages.min(255)) << 32
                    | u64::from(front.decimation.min((1 << 24) - 1)) << 40;
                FilterKey(kind + 16, a, b, c, packed)
            }
            LowPass::SecondOrder {
                natural_frequency_hz,
                damping,
                form,
            } => {
                let (kind, extra) = match form {
                    SecondOrderForm::PoleMapped => (2, 0),
                    SecondOrderForm::Bilinear => (4, 0),
                    SecondOrderForm::Sampled { zero } => (5, zero.to_bits()),
                };
                FilterKey(
                    kind,
                    natural_frequency_hz.to_bits(),
                    damping.to_bits(),
                    extra,
                    0,
                )
            }
            LowPass::ZeroPhase { time_constant_s } => {
                FilterKey(3, time_constant_s.to_bits(), 0, 0, 0)
            }
            LowPass::Butterworth {
                order,
                cutoff_hz,
                decimation,
            } => FilterKey(
                7,
                u64::from(order),
                cutoff_hz.to_bits(),
                u64::from(decimation),
                0,
            ),
            LowPass::Fir {
                taps,
                cutoff_hz,
                decimation,
            } => FilterKey(
                6,
                u64::from(taps),
                cutoff_hz.to_bits(),
                u64::from(decimation),
                0,
            ),
        }
    }
}

/// A filter's two columns: its white rate's AVAR and its flicker rate's, per unit `N^2`, `B^2`.
pub type FilterColumns = Arc<(Vec<f64>, Vec<f64>)>;

/// A rounding floor's identity: the filter, and the bits of `N^2` (u^2/s) and of the step (u/s).
type FloorKey = (FilterKey, u64, u64);

/// The kept columns (see the module doc).
#[derive(Default)]
pub struct ColumnMemo {
    columns: Mutex<HashMap<FilterKey, FilterColumns>>,
    floors: Mutex<HashMap<FloorKey, Arc<Vec<f64>>>>,
    autocorrelations: Mutex<HashMap<FilterKey, Arc<Vec<f64>>>>,
}

impl ColumnMemo {
    /// The autocorrelation of `lp` ([`LowPass::autocorrelation`] at the problem's step),
    /// computed by `make` the first time.
    pub fn autocorrelation(&self, lp: &LowPass, make: impl FnOnce() -> Vec<f64>) -> Arc<Vec<f64>> {
        kept_or_made(
            &self.autocorrelations,
            FilterKey::of(lp),
            MAX_AUTOCORRELATIONS,
            make,
        )
    }

    /// The columns of `lp`, computed by `make` the first time.
    pub fn columns(
        &self,
        lp: &LowPass,
        make: impl FnOnce() -> (Vec<f64>, Vec<f64>),
    ) -> FilterColumns {
        kept_or_made(&self.columns, FilterKey::of(lp), MAX_COLUMNS, make)
    }

    /// The rounding floor after `lp` for the white rate `n2` (u^2/s) and the step `step` (u/s),
    /// computed by `make` the first time.
    pub fn floor(
        &self,
        lp: &LowPass,
        n2: f64,
        step: f64,
        make: impl FnOnce() -> Vec<f64>,
    ) -> Arc<Vec<f64>> {
        let key = (FilterKey::of(lp), n2.to_bits(), step.to_bits());
        kept_or_made(&self.floors, key, MAX_FLOORS, make)
    }
}

/// The value kept in `table` under `key`, or `make`'s, then kept (the table emptied first when
/// it holds `cap` values).
fn kept_or_made<K: std::hash::Hash + Eq, V>(
    table: &Mutex<HashMap<K, Arc<V>>>,
    key: K,
    cap: usize,
    make: impl FnOnce() -> V,
) -> Arc<V> {
    if let Some(v) = lock(table).get(&key) {
        return Arc::clone(v);
    }
    let v = Arc::new(make());
    let mut t = lock(table);
    if t.len() >= cap {
        t.clear();
    }
    t.insert(key, Arc::clone(&v));
    v
}

/// The table, whether or not another thread panicked while holding it (a table is only ever
/// read or added to whole, so it is never left half-written).
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Clone for ColumnMemo {
    fn clone(&self) -> Self {
        ColumnMemo::default()
    }
}

impl std::fmt::Debug for ColumnMemo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ColumnMemo")
            .field("columns", &lock(&self.columns).len())
            .field("floors", &lock(&self.floors).len())
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn a_filter_is_computed_once_and_a_different_one_again() {
        let memo = ColumnMemo::default();
        let calls = Cell::new(0);
        let make = |v: f64| {
            calls.set(calls.get() + 1);
            (vec![v], vec![2.0 * v])
        };
        let a = LowPass::FirstOrder {
            time_constant_s: 0.05,
        };
        let b = LowPass::ZeroPhase {
            time_constant_s: 0.05,
        };
        assert_eq!(memo.columns(&a, || make(1.0)).0, vec![1.0]);
        assert_eq!(memo.columns(&a, || make(3.0)).1, vec![2.0]);
        assert_eq!(calls.get(), 1);
        // the same time constant in a different kind of filter is a different filter
        assert_eq!(memo.columns(&b, || make(3.0)).0, vec![3.0]);
        assert_eq!(calls.get(), 2);
        // the floor is keyed by N^2 and the step too
        assert_eq!(*memo.floor(&a, 1e-4, 0.01, || vec![5.0]), vec![5.0]);
        assert_eq!(*memo.floor(&a, 1e-4, 0.01, || vec![6.0]), vec![5.0]);
        assert_eq!(*memo.floor(&a, 1.0001e-4, 0.01, || vec![7.0]), vec![7.0]);
        assert_eq!(*memo.floor(&a, 1e-4, 0.02, || vec![8.0]), vec![8.0]);
    }

    #[test]
    fn a_full_table_starts_again_and_a_clone_is_empty() {
        let memo = ColumnMemo::default();
        for i in 0..MAX_FLOORS + 10 {
            memo.floor(
                &LowPass::MovingAverage {
                    taps: 4,
                    stages: 1,
                    decimation: 1,
                },
                i as f64,
                1.0,
                || vec![i as f64],
            );
        }
        assert_eq!(lock(&memo.floors).len(), 10);
        assert_eq!(lock(&memo.clone().floors).len(), 0);
    }
}
