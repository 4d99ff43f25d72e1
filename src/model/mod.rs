//! The noise model: the five-term Allan-variance model (docs/theory.md section 2), its fit, run-to-run
//! aggregation, datasheet units, IEEE 952 read-outs and limits. Works on curves only; never sees samples.

pub mod aggregate;
pub mod avar_cov;
pub mod fit;
pub mod limits;
pub mod lowpass;
pub mod nnls;
pub mod readout;
pub mod term_values;
pub mod terms;
pub mod units;
