//! The process-wide cache of pair states computed from scratch (see [`SharedFresh`]).

use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock, PoisonError};

use super::pair::PairState;

/// Fresh pair states kept for the whole process, keyed by `(m1, m2, M1, M2)`: the lag sums are
/// per unit coefficient, so they depend on nothing else, and the channels of one run (same
/// cluster sizes, same counts) need the same ones. Eight channels' final fits computed each pair
/// eight times (BENCHMARKS.md, "session 7"). Each entry is a cell that the first caller fills
/// while later callers of the same key wait for it, so two threads fitting two channels at
/// once compute each pair once. Cleared when it reaches [`SHARED_CAPACITY`] keys.
pub(super) type SharedFresh = HashMap<(u64, u64, u64, u64), Arc<OnceLock<PairState>>>;

pub(super) static SHARED_FRESH: Mutex<Option<SharedFresh>> = Mutex::new(None);

/// Keys the process-wide cache holds before it is cleared (a pair state is about 0.5 kB).
pub(super) const SHARED_CAPACITY: usize = 1024;

/// [`PairState::fresh`] through the process-wide cache ([`SharedFresh`]): the same value,
/// computed once per key.
pub(super) fn shared_fresh(m1: u64, m2: u64, big_m1: u64, big_m2: u64) -> PairState {
    let key = (m1, m2, big_m1, big_m2);
    let cell = {
        let mut guard = SHARED_FRESH.lock().unwrap_or_else(PoisonError::into_inner);
        let map = guard.get_or_insert_with(HashMap::new);
        if map.len() >= SHARED_CAPACITY && !map.contains_key(&key) {
            map.clear();
        }
        Arc::clone(map.entry(key).or_default())
    };
    cell.get_or_init(|| PairState::fresh(m1, m2, big_m1, big_m2))
        .clone()
}

/// Empties the process-wide cache of fresh pair states, so the next covariance computes every
/// pair (benchmarks of a cold fit call this between iterations).
pub fn clear_shared_cache() {
    let mut guard = SHARED_FRESH.lock().unwrap_or_else(PoisonError::into_inner);
    *guard = None;
}
