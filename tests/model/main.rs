//! The noise-model fit and what is built on it (src/model/): exact and noisy curves, NNLS,
//! covariance between taus, quantiles, run statistics, datasheet limits.
//! One test binary per stage; each topic is a module of it.

#[path = "../common/mod.rs"]
mod common;

mod adis;
mod aggregate_table2;
mod chi2_quantile;
mod covariance;
mod exact;
mod limits;
mod nnls;
mod noisy;
mod sim_study;
mod units;
