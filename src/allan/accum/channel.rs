//! The facade a channel uses ([`ChannelAccumulator`]): one engine for integer counts or
//! floating input, whichever the channel delivers.

#[allow(unused_imports)]
use super::*;

/// What a channel's accumulator needs of its engine, whatever the number representation.
pub(super) trait ChannelEngine {
    fn gap(&mut self, missing: u64);
    fn break_seg(&mut self);
    fn points(&self) -> u64;
    fn seconds(&self) -> f64;
    fn step_count(&self) -> u64;
    fn segment_count(&self) -> u64;
    fn cfg(&self) -> &AccumConfig;
    fn bytes(&self) -> usize;
}

impl<R: Repr> ChannelEngine for Engine<R> {
    fn gap(&mut self, missing: u64) {
        self.push_gap(missing)
    }
    fn break_seg(&mut self) {
        self.break_segment()
    }
    fn points(&self) -> u64 {
        self.phase_points()
    }
    fn seconds(&self) -> f64 {
        self.t_data_s()
    }
    fn step_count(&self) -> u64 {
        self.steps()
    }
    fn segment_count(&self) -> u64 {
        self.segments()
    }
    fn cfg(&self) -> &AccumConfig {
        self.config()
    }
    fn bytes(&self) -> usize {
        self.stream_bytes()
    }
}

/// A channel's accumulator for whichever kind of input it receives.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub enum ChannelAccumulator {
    /// Integer counts (frame fields); the reading is scaled by `scale` (u per count).
    Counts { engine: Engine<IntRepr>, scale: f64 },
    /// Floating increments or phase in u.
    Real(Engine<FloatRepr>),
}

impl ChannelAccumulator {
    pub fn counts(cfg: AccumConfig, scale: f64) -> Self {
        ChannelAccumulator::Counts {
            engine: Engine::new(cfg),
            scale,
        }
    }

    pub fn real(cfg: AccumConfig) -> Self {
        ChannelAccumulator::Real(Engine::new(cfg))
    }

    /// The engine behind the channel, whichever its representation.
    fn engine(&self) -> &dyn ChannelEngine {
        match self {
            ChannelAccumulator::Counts { engine, .. } => engine,
            ChannelAccumulator::Real(e) => e,
        }
    }

    fn engine_mut(&mut self) -> &mut dyn ChannelEngine {
        match self {
            ChannelAccumulator::Counts { engine, .. } => engine,
            ChannelAccumulator::Real(e) => e,
        }
    }

    pub fn push_gap(&mut self, missing: u64) {
        self.engine_mut().gap(missing)
    }

    /// Ends the current phase segment without accounting for time: the data after it are not
    /// contiguous with the data before (a resumed live run), so no difference spans the break.
    pub fn break_segment(&mut self) {
        self.engine_mut().break_seg()
    }

    pub fn phase_points(&self) -> u64 {
        self.engine().points()
    }

    pub fn t_data_s(&self) -> f64 {
        self.engine().seconds()
    }

    /// Steps of data accounted for, gaps included (`t_data_s` is this times tau0).
    pub fn steps(&self) -> u64 {
        self.engine().step_count()
    }

    pub fn segments(&self) -> u64 {
        self.engine().segment_count()
    }

    pub fn config(&self) -> &AccumConfig {
        self.engine().cfg()
    }

    pub fn stream_bytes(&self) -> usize {
        self.engine().bytes()
    }

    /// [`Engine::check_restored`] for whichever engine this is; a count scale must be a
    /// finite non-zero number.
    pub fn check_restored(&self) -> Result<(), String> {
        match self {
            ChannelAccumulator::Counts { engine, scale } => {
                if !(scale.is_finite() && *scale != 0.0) {
                    return Err(format!("count scale {scale}"));
                }
                engine.check_restored()
            }
            ChannelAccumulator::Real(e) => e.check_restored(),
        }
    }

    /// The increment (u) every increment so far has been, when all are the same
    /// ([`Engine::constant_increment`]).
    pub fn constant_increment(&self) -> Option<f64> {
        match self {
            ChannelAccumulator::Counts { engine, scale } => {
                engine.constant_increment().map(|d| d as f64 * scale)
            }
            ChannelAccumulator::Real(e) => e.constant_increment(),
        }
    }

    /// Readings in u^2/s^2 (counts scaled).
    pub fn read(&mut self) -> Vec<LevelReading> {
        match self {
            ChannelAccumulator::Counts { engine, scale } => {
                let s2 = *scale * *scale;
                let sc = |v: Option<(f64, u64)>| v.map(|(var, n)| (var * s2, n));
                engine
                    .read()
                    .into_iter()
                    .map(|r| LevelReading {
                        avar: sc(r.avar),
                        hvar: sc(r.hvar),
                        mvar: sc(r.mvar),
                        ..r
                    })
                    .collect()
            }
            ChannelAccumulator::Real(e) => e.read(),
        }
    }
}
