//! The sim-to-real gap diagnosis (src/gap/): simulated hidden effects, mixture statistics,
//! oracle bounds and a real recording.
//! One test binary per stage; each topic is a module of it.

mod diagnosis;
mod families;
mod mixture;
mod oracle;
mod reference;
