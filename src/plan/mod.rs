//! What a run is asked to do, checked before anything starts: the option values shared by the
//! command line and the stand config ([`options`]).

pub mod options;
