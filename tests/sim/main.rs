//! The simulator (src/sim/): closed forms and the capture round trip.
//! One test binary per stage; each topic is a module of it.

mod closed_form;
mod roundtrip;
