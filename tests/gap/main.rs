//! The sim-to-real gap diagnosis (src/gap/): simulated hidden effects, mixture statistics,
//! oracle bounds, a real recording, and the temperature effect.
//! One test binary per stage; each topic is a module of it.

mod alternatives;
mod band_noise;
mod diagnosis;
mod families;
mod filter_shape;
mod filter_tail;
mod filters;
mod gm_or_filter;
mod holdout_carry;
mod jump_null;
mod limit_cycle;
mod line_behind_filter;
mod mixture;
mod oracle;
mod outliers;
mod quantization;
mod real_slice;
mod reference;
mod rounding;
mod second_order_polish;
mod sinusoid_behind_filter;
mod sinusoid_interval;
mod temperature;
mod term_intervals;
mod warmup_null;
mod warmup_profile;
