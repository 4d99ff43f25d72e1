//! The frame decoder and encoder (src/frame/): golden frames and damaged streams.
//! One test binary per stage; each topic is a module of it.

#[path = "../common/mod.rs"]
mod common;

mod arbitrary;
mod corruption;
mod golden;
mod hg4930;
mod integrity;
