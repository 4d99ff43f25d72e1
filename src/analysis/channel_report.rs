//! What the analysis yields for one channel at one moment (interim or final): its curves, its
//! five-term fit with the IEEE 952 read-outs, and its diagnosis, as the numerical stages' own
//! types, so a program embedding allanscope (a ROS node, a GUI, a lab service) reads numbers,
//! not JSON. [`ChannelReport::records`] turns a report into the JSON-lines records the writer
//! prints (docs/records.md): the curves, then the fit, then the diagnosis.

use crate::allan::{Curve, Stat};
use crate::gap::{diagnose, DiagnoseOptions, Diagnosis, DiagnosisRecord};
use crate::model::fit::{FitResult, Fitter};
use crate::model::readout::{readouts, Readouts};
use crate::model::units::{quantization_ratio, IncrementUnit};
use crate::sink::records::{
    CoefRecord, CurveRecord, DatasheetRecord, FitRecord, ReadoutsRecord, Record,
};

use crate::sink::step_change_words::step_change_words;
use crate::sink::table::sig3;

use super::{analyze_channel, AnalysisOptions, ChannelState, InputKind};

/// One channel's results as of `t_data_s` ([`super::RunAnalysis::reports`]).
#[derive(Debug, Clone)]
pub struct ChannelReport {
    pub channel: String,
    /// The channel's unit `u` of an increment (`arcsec`, `m/s`, ...).
    pub unit: String,
    /// True once the input has ended.
    pub is_final: bool,
    /// Run index when several inputs are analyzed.
    pub run: Option<usize>,
    /// Seconds of data consumed.
    pub t_data_s: f64,
    /// The LSB (u) of a channel delivered as counts, for Q against the quantization alone.
    pub counts_lsb: Option<f64>,
    /// One curve per statistic asked for (AVAR, HVAR, MVAR), deviations in u/s.
    pub curves: Vec<Curve>,
    /// The five-term fit of the AVAR curve (`None`: not asked for, or no fit could be made).
    pub fit: Option<FitResult>,
    /// The IEEE 952 read-outs of the AVAR curve (with a fit only).
    pub readouts: Option<Readouts>,
    /// The sim-to-real gap (with `diagnose` only, once the run is long enough for one).
    pub diagnosis: Option<Diagnosis>,
}

impl ChannelReport {
    /// The curve of one statistic, if computed.
    pub fn curve(&self, stat: Stat) -> Option<&Curve> {
        self.curves.iter().find(|c| c.stat == stat)
    }

    /// The `fit` record (coefficients, their datasheet units, read-outs), if there is a fit.
    pub fn fit_record(&self) -> Option<FitRecord> {
        let f = self.fit.as_ref()?;
        let coef = CoefRecord::new(f);
        let datasheet = IncrementUnit::parse(&self.unit).map(|u| DatasheetRecord::new(&coef, &u));
        let q = &f.coef[0];
        Some(FitRecord {
            channel: self.channel.clone(),
            unit: self.unit.clone(),
            r#final: self.is_final,
            t_data: self.t_data_s,
            coef,
            gof: f.gof.is_finite().then_some(f.gof),
            method: f.method.name().into(),
            model_c: f.c.to_vec(),
            datasheet,
            readouts: self
                .readouts
                .as_ref()
                .map(|r| Box::new(ReadoutsRecord::new(r, &self.unit, Some(f.c)))),
            q_over_lsb: self
                .counts_lsb
                .filter(|_| q.determined)
                .map(|lsb| quantization_ratio(q.value, lsb)),
            run: self.run,
        })
    }

    /// The `diagnosis` record, if there is a diagnosis.
    pub fn diagnosis_record(&self) -> Option<DiagnosisRecord> {
        let d = self.diagnosis.as_ref()?;
        let mut rec = DiagnosisRecord::new(&self.channel, d, None, self.is_final);
        rec.run = self.run;
        rec.unit = Some(self.unit.clone());
        Some(rec)
    }

    /// The report's records, in the order the writer prints them: each curve, the fit, the
    /// diagnosis.
    pub fn records(&self) -> Vec<Record> {
        let mut out: Vec<Record> = self
            .curves
            .iter()
            .map(|c| {
                Record::Curve(CurveRecord::new(
                    &self.channel,
                    &self.unit,
                    c,
                    self.is_final,
                    self.run,
                ))
            })
            .collect();
        out.extend(self.fit_record().map(Record::from));
        out.extend(self.diagnosis_record().map(Record::from));
        out
    }
}

/// The reports of `channels` (see [`super::RunAnalysis::reports`]), in channel order.
pub(super) fn channel_reports(
    channels: &mut [ChannelState],
    opts: &AnalysisOptions,
    final_: bool,
) -> Vec<ChannelReport> {
    let mut out = Vec::with_capacity(channels.len());
    for ch in channels {
        if final_ {
            // The final fit starts from a fresh covariance cache, so it does not depend on
            // how many interim refits came before (the cache's incremental updates agree
            // with a fresh computation only to ~1e-11).
            ch.fitter = Fitter::new();
        }
        if let Some(d) = ch.acc.constant_increment().filter(|_| final_) {
            // docs/robustness.md: a channel that never moves has curves of exactly 0, so
            // nothing to fit; said once, at the end, with the rate it is stuck at.
            tracing::warn!(
                "{}: every sample is the same, a rate of {} {}/s throughout: its curves are \
                 exactly 0 and nothing is fitted (the channel does not move: stuck, saturated \
                 or not connected?)",
                ch.setup.name,
                d / opts.accum.tau0_s,
                ch.setup.unit
            );
        }
        let (curves, fit) = analyze_channel(ch, opts);
        let (points, stretches) = (ch.acc.phase_points(), ch.acc.segments());
        if final_
            && points > 16
            && 3 * stretches > points
            && curves.iter().all(|c| c.points.is_empty())
        {
            // A merged multi-rate file read with the faster channels: said, not left as an
            // empty curve.
            tracing::warn!(
                "{}: its {points} samples come in {stretches} stretches, one or two each (a value \
                 on every other row: a channel logged slower than the file's rows?), so it has \
                 no curve; analyse it alone (--channels {}: with a time column its rows are \
                 then its samples)",
                ch.setup.name,
                ch.setup.name
            );
        }
        let readouts = fit.as_ref().and_then(|_| {
            curves
                .iter()
                .find(|c| c.stat == Stat::Avar)
                .map(|c| readouts(&c.points))
        });
        if let Some(f) = &fit {
            ch.last_fit = Some(f.clone());
        }
        // The diagnosis refreshed with the fits (docs/theory.md section 5); a run still too
        // short for it gives none yet.
        let diagnosis = ch.gap.as_mut().and_then(|g| {
            let snap = g.snapshot();
            // A range switched during the run is said once, with the final records, as
            // `diagnose` says it (sink::step_change_words).
            let per = match opts.kind {
                InputKind::Rate => 1.0 / opts.accum.tau0_s,
                InputKind::Increments | InputKind::Phase => 1.0,
            };
            let words = final_.then(|| {
                step_change_words(
                    &snap.step_changes,
                    snap.step_changes_more,
                    snap.lsb,
                    per,
                    opts.accum.tau0_s,
                    &sig3,
                )
            });
            if let Some(w) = words.flatten() {
                tracing::warn!("channel {}: {w}", ch.setup.name);
            }
            diagnose(&snap, &DiagnoseOptions::default())
                .map_err(|e| tracing::debug!("{}: {e}", ch.setup.name))
                .ok()
        });
        out.push(ChannelReport {
            channel: ch.setup.name.clone(),
            unit: ch.setup.unit.clone(),
            is_final: final_,
            run: opts.run,
            t_data_s: ch.acc.t_data_s(),
            counts_lsb: ch.setup.counts_lsb,
            curves,
            fit,
            readouts,
            diagnosis,
        });
    }
    out
}
