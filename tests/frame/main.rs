//! The frame decoder and encoder (src/frame/): golden frames and damaged streams.
//! One test binary per stage; each topic is a module of it.

mod arbitrary;
mod corruption;
mod golden;
