//! The settings of a unit's data and analysis, as the command line (`analyze`, `listen`,
//! `diagnose`) and a stand config give them, already parsed ([`super::options`]'s `FromStr`
//! types): turned into the analysis options in one place.

use crate::allan::accum::{AccumConfig, Overlap, StatSet, TauSpec};
use crate::analysis::{AnalysisOptions, InputKind};
use crate::input::text::TextOptions;
use crate::model::fit::{FitMethod, FitOptions};
use crate::model::limits::LimitSpec;

/// What a unit's samples are and how they are analysed.
#[derive(Debug, Clone)]
pub struct DataSettings {
    /// What the values of text columns are (frames are always increments).
    pub kind: InputKind,
    /// Unit of the increment of text columns (`--unit`; frames take the descriptor's).
    pub unit: String,
    pub taus: TauSpec,
    pub overlap: Overlap,
    pub stats: StatSet,
    /// Data-seconds between interim records (a replay); live runs keep theirs on wall time.
    pub every_s: Option<f64>,
    /// `None`: no fit.
    pub fit: Option<FitMethod>,
    pub limits: Vec<LimitSpec>,
    /// `diagnosis` records with the fits.
    pub diagnose: bool,
    /// Only these channels (`None`: all).
    pub channels: Option<Vec<String>>,
    /// How text columns become channels.
    pub text: TextOptions,
}

impl DataSettings {
    /// The analysis options for samples `tau0_s` apart.
    pub fn analysis_options(&self, tau0_s: f64) -> AnalysisOptions {
        let mut accum = AccumConfig::new(tau0_s);
        accum.taus = self.taus.clone();
        accum.overlap = self.overlap;
        accum.stats = self.stats;
        AnalysisOptions {
            accum,
            kind: self.kind,
            every_s: self.every_s,
            fit: self.fit.map(|method| FitOptions {
                method,
                ..FitOptions::default()
            }),
            run: None,
            limits: self.limits.clone(),
            diagnose: self.diagnose,
        }
    }
}
