//! Metrics for monitoring: the latest fit, limit verdicts and decoder health of every unit and
//! channel, kept in a Prometheus registry (`prometheus-client`) and encoded in the text
//! exposition format (OpenMetrics 1.0 text, which Prometheus reads).
//!
//! The library keeps the registry; serving it over HTTP is the binary's business
//! (`--metrics ADDR:PORT`). The pipeline feeds it through a [`MetricsTap`]: every `fit` record
//! (interim and final) the analysis writes, and the decoder's health a few times a second.
//!
//! Metric families (label `unit` is the unit's name in a multi-unit stand config, else the
//! run's input; `channel` the channel; `coef` one of `Q N B K R`):
//!
//! | name | type | labels | value |
//! |---|---|---|---|
//! | `allanscope_coef` | gauge | unit, channel, coef | fitted value, native units of docs/theory.md section 2 (absent while not determined) |
//! | `allanscope_coef_lo`, `allanscope_coef_hi` | gauge | unit, channel, coef | ends of its 95% interval |
//! | `allanscope_coef_determined` | gauge | unit, channel, coef | 1 determined, 0 not |
//! | `allanscope_coef_datasheet` | gauge | unit, channel, coef, datasheet_unit | the value in datasheet units (absent while not determined) |
//! | `allanscope_coef_datasheet_lo`, `_hi` | gauge | unit, channel, coef, datasheet_unit | its 95% interval ends in datasheet units |
//! | `allanscope_fit_gof` | gauge | unit, channel | goodness of fit |
//! | `allanscope_fit_t_data_seconds` | gauge | unit, channel | data-seconds behind the fit |
//! | `allanscope_fit_timestamp_seconds` | gauge | unit, channel | Unix time the fit was made |
//! | `allanscope_limit_verdict` | gauge | unit, channel, coef, bound | 1 pass, 0 undecided, -1 fail (`src/model/limits.rs`), -2 cannot be judged |
//! | `allanscope_frames_total` | counter | unit | good frames |
//! | `allanscope_missing_frames_total` | counter | unit | frames lost by the counter |
//! | `allanscope_crc_errors_total` | counter | unit | checksum failures |
//! | `allanscope_resyncs_total` | counter | unit | times the decoder regained lock |
//! | `allanscope_duplicates_total` | counter | unit | repeated frames dropped |
//! | `allanscope_health_timestamp_seconds` | gauge | unit | Unix time of the last health update |

use std::sync::atomic::AtomicU64;
use std::sync::{Arc, Mutex};

use prometheus_client::encoding::text::encode;
use prometheus_client::metrics::counter::Counter;
use prometheus_client::metrics::family::Family;
use prometheus_client::metrics::gauge::Gauge;
use prometheus_client::registry::Registry;

use crate::frame::Health;
use crate::model::limits::{channel_matches, conversion, decide, LimitSpec, Scope, Verdict};
use crate::model::terms::TERM_NAMES;
use crate::model::units::native_units;
use crate::sink::records::{FitRecord, Record};

/// Label pairs of one series.
type Labels = Vec<(String, String)>;
type GaugeFamily = Family<Labels, Gauge<f64, AtomicU64>>;
type CounterFamily = Family<Labels, Counter<u64>>;

/// The content type of [`Metrics::encode`]'s text.
pub const CONTENT_TYPE: &str = "application/openmetrics-text; version=1.0.0; charset=utf-8";

/// The registry and the handles of its families (module doc).
pub struct Metrics {
    registry: Registry,
    coef: GaugeFamily,
    coef_lo: GaugeFamily,
    coef_hi: GaugeFamily,
    coef_determined: GaugeFamily,
    coef_datasheet: GaugeFamily,
    coef_datasheet_lo: GaugeFamily,
    coef_datasheet_hi: GaugeFamily,
    gof: GaugeFamily,
    t_data: GaugeFamily,
    fit_time: GaugeFamily,
    verdict: GaugeFamily,
    frames: CounterFamily,
    missing: CounterFamily,
    crc_errors: CounterFamily,
    resyncs: CounterFamily,
    duplicates: CounterFamily,
    health_time: GaugeFamily,
    /// Each unit's latest decoder health and its time, written by its decode thread as often as
    /// it likes and read into the counters at each [`Metrics::encode`].
    health_slots: Mutex<Vec<(String, HealthSlot)>>,
    /// The newest figures read back for a person watching (the binary's status line).
    latest: Mutex<Latest>,
}

/// The newest figures of every unit, for a status line: lost frames and the latest white-noise
/// coefficient N of each channel.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Latest {
    /// Frames lost by the counter, per unit (the newest health totals).
    pub missing: Vec<(String, u64)>,
    /// `(channel, N, unit)` of the newest fit of each channel where N is determined: in
    /// datasheet units where the channel's unit is known, else native.
    pub n: Vec<(String, f64, String)>,
}

/// One unit's latest decoder health (totals) and the Unix time it was taken.
type HealthSlot = Arc<Mutex<Option<(Health, f64)>>>;

impl std::fmt::Debug for Metrics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Metrics")
    }
}

impl Default for Metrics {
    fn default() -> Self {
        Self::new()
    }
}

/// A label value as the text format can carry it unescaped: quotes, backslashes and line
/// breaks become `_`.
fn label(v: &str) -> String {
    v.chars()
        .map(|c| {
            if matches!(c, '"' | '\\' | '\n' | '\r') {
                '_'
            } else {
                c
            }
        })
        .collect()
}

fn labels(pairs: &[(&str, &str)]) -> Labels {
    pairs
        .iter()
        .map(|(k, v)| ((*k).to_string(), label(v)))
        .collect()
}

/// Seconds since the Unix epoch.
fn unix_now_s() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// The gauge value of a verdict (module doc).
pub fn verdict_value(v: Verdict) -> f64 {
    match v {
        Verdict::Pass => 1.0,
        Verdict::Undecided => 0.0,
        Verdict::Fail => -1.0,
        Verdict::Invalid => -2.0,
    }
}

impl Metrics {
    /// An empty registry with every family registered (a family appears in the exposition
    /// with its first series).
    pub fn new() -> Metrics {
        let mut registry = Registry::with_prefix("allanscope");
        let mut gauge = |name: &str, help: &str| {
            let f = GaugeFamily::default();
            registry.register(name, help, f.clone());
            f
        };
        let coef = gauge(
            "coef",
            "Latest fitted noise coefficient, native units (docs/theory.md section 2); absent while not determined",
        );
        let coef_lo = gauge(
            "coef_lo",
            "Lower end of the coefficient's 95% interval, native units",
        );
        let coef_hi = gauge(
            "coef_hi",
            "Upper end of the coefficient's 95% interval, native units",
        );
        let coef_determined = gauge(
            "coef_determined",
            "1 when the coefficient is determined, else 0",
        );
        let coef_datasheet = gauge(
            "coef_datasheet",
            "Latest fitted coefficient in datasheet units (label datasheet_unit); absent while not determined",
        );
        let coef_datasheet_lo = gauge(
            "coef_datasheet_lo",
            "Lower end of the 95% interval in datasheet units",
        );
        let coef_datasheet_hi = gauge(
            "coef_datasheet_hi",
            "Upper end of the 95% interval in datasheet units",
        );
        let gof = gauge(
            "fit_gof",
            "Goodness of the latest fit (near 1 when the model explains the curve)",
        );
        let t_data = gauge(
            "fit_t_data_seconds",
            "Seconds of data behind the latest fit",
        );
        let fit_time = gauge("fit_timestamp_seconds", "Unix time of the latest fit");
        let verdict = gauge(
            "limit_verdict",
            "Datasheet limit on the latest fit: 1 pass, 0 undecided, -1 fail, -2 cannot be judged",
        );
        let health_time = gauge(
            "health_timestamp_seconds",
            "Unix time of the latest decoder health update",
        );
        let mut counter = |name: &str, help: &str| {
            let f = CounterFamily::default();
            registry.register(name, help, f.clone());
            f
        };
        let frames = counter("frames", "Good frames decoded");
        let missing = counter("missing_frames", "Frames lost, by the frame counter");
        let crc_errors = counter("crc_errors", "Messages whose checksum failed");
        let resyncs = counter(
            "resyncs",
            "Times the decoder regained lock after skipped bytes",
        );
        let duplicates = counter(
            "duplicates",
            "Frames dropped because they repeated a counter",
        );
        Metrics {
            registry,
            coef,
            coef_lo,
            coef_hi,
            coef_determined,
            coef_datasheet,
            coef_datasheet_lo,
            coef_datasheet_hi,
            gof,
            t_data,
            fit_time,
            verdict,
            frames,
            missing,
            crc_errors,
            resyncs,
            duplicates,
            health_time,
            health_slots: Mutex::new(Vec::new()),
            latest: Mutex::new(Latest::default()),
        }
    }

    /// A tap for `unit` with its per-run `limits`: what one unit's run feeds in.
    pub fn tap(self: &Arc<Self>, unit: &str, limits: &[LimitSpec]) -> MetricsTap {
        let slot = HealthSlot::default();
        lock(&self.health_slots).push((unit.to_string(), slot.clone()));
        MetricsTap {
            metrics: self.clone(),
            unit: unit.into(),
            limits: limits.to_vec(),
            health: slot,
        }
    }

    /// The registry in the text exposition format ([`CONTENT_TYPE`]), ending with `# EOF`.
    pub fn encode(&self) -> String {
        for (unit, slot) in lock(&self.health_slots).iter() {
            if let Some((h, t)) = lock(slot).take() {
                self.set_health(unit, &h, t);
            }
        }
        let mut s = String::new();
        // Writing to a String cannot fail.
        let _ = encode(&mut s, &self.registry);
        s
    }

    /// The newest figures for a status line.
    pub fn latest(&self) -> Latest {
        lock(&self.latest).clone()
    }

    fn note_fit(&self, f: &FitRecord) {
        let ds = f.datasheet.as_ref().map(|d| &d.N);
        let determined = f.coef.N.determined;
        let value = match ds {
            Some(d) => d.value.map(|v| (v, d.unit.clone())),
            None => f
                .coef
                .N
                .value
                .map(|v| (v, native_units(&f.unit)[1].clone())),
        }
        .filter(|_| determined);
        let mut l = lock(&self.latest);
        l.n.retain(|(c, _, _)| *c != f.channel);
        if let Some((v, u)) = value {
            l.n.push((f.channel.clone(), v, u));
        }
    }

    fn note_health(&self, unit: &str, h: &Health) {
        let mut l = lock(&self.latest);
        match l.missing.iter_mut().find(|(u, _)| u == unit) {
            Some(x) => x.1 = h.missing,
            None => l.missing.push((unit.to_string(), h.missing)),
        }
    }

    /// Takes a `fit` record of `unit` (other records are ignored): its coefficients, intervals,
    /// datasheet values and the per-run `limits` judged on its intervals, stamped `now_s`.
    pub fn observe_fit(&self, unit: &str, limits: &[LimitSpec], f: &FitRecord, now_s: f64) {
        let ch = f.channel.as_str();
        for (i, name) in TERM_NAMES.into_iter().enumerate() {
            let l = labels(&[("unit", unit), ("channel", ch), ("coef", name)]);
            let c = f.coef.by_index(i);
            match c.value {
                Some(v) => {
                    self.coef.get_or_create(&l).set(v);
                }
                None => {
                    self.coef.remove(&l);
                }
            }
            if let Some(v) = c.lo {
                self.coef_lo.get_or_create(&l).set(v);
            }
            if let Some(v) = c.hi {
                self.coef_hi.get_or_create(&l).set(v);
            }
            let det = c.determined;
            self.coef_determined
                .get_or_create(&l)
                .set(if det { 1.0 } else { 0.0 });
            if let Some(d) = f.datasheet.as_ref().map(|d| d.by_index(i)) {
                let du = d.unit.as_str();
                let dl = labels(&[
                    ("unit", unit),
                    ("channel", ch),
                    ("coef", name),
                    ("datasheet_unit", du),
                ]);
                if let Some(v) = d.lo {
                    self.coef_datasheet_lo.get_or_create(&dl).set(v);
                }
                if let Some(v) = d.hi {
                    self.coef_datasheet_hi.get_or_create(&dl).set(v);
                }
                match d.value {
                    Some(v) => {
                        self.coef_datasheet.get_or_create(&dl).set(v);
                    }
                    None => {
                        self.coef_datasheet.remove(&dl);
                    }
                }
            }
        }
        let l = labels(&[("unit", unit), ("channel", ch)]);
        match f.gof {
            Some(g) => {
                self.gof.get_or_create(&l).set(g);
            }
            None => {
                self.gof.remove(&l);
            }
        }
        self.t_data.get_or_create(&l).set(f.t_data);
        self.fit_time.get_or_create(&l).set(now_s);
        for spec in limits.iter().filter(|s| s.over == Scope::Run) {
            if !channel_matches(&spec.channel, ch) {
                continue;
            }
            let coef = TERM_NAMES[spec.coef.index()];
            let c = f.coef.by_index(spec.coef.index());
            let ends = (c.lo, c.hi);
            for (bound, limit) in spec.bounds() {
                // The same decision as the summary's (model::limits::judge), on this fit.
                let v = match (conversion(&f.unit, spec.coef, spec.unit.as_deref()), ends) {
                    (Ok(k), (Some(lo), Some(hi))) => decide(bound, limit, lo * k, hi * k),
                    (Ok(_), _) => Verdict::Undecided,
                    (Err(_), _) => Verdict::Invalid,
                };
                let vl = labels(&[
                    ("unit", unit),
                    ("channel", ch),
                    ("coef", coef),
                    ("bound", bound),
                ]);
                self.verdict.get_or_create(&vl).set(verdict_value(v));
            }
        }
    }

    /// Sets the decoder health counters of `unit` to the totals in `h`, stamped `now_s`.
    pub fn set_health(&self, unit: &str, h: &Health, now_s: f64) {
        let l = labels(&[("unit", unit)]);
        let set = |f: &CounterFamily, total: u64| {
            let c = f.get_or_create(&l);
            // Totals only grow; a counter only goes up.
            c.inc_by(total.saturating_sub(c.get()));
        };
        set(&self.frames, h.frames);
        set(&self.missing, h.missing);
        set(&self.crc_errors, h.crc_errors);
        set(&self.resyncs, h.resyncs);
        set(&self.duplicates, h.duplicates);
        self.health_time.get_or_create(&l).set(now_s);
    }
}

/// A lock whose holder panicked still holds usable numbers.
fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

/// One unit's view of shared [`Metrics`] ([`Metrics::tap`]): its name, per-run limits and
/// health slot. Cheap to clone.
#[derive(Debug, Clone)]
pub struct MetricsTap {
    metrics: Arc<Metrics>,
    unit: String,
    limits: Vec<LimitSpec>,
    health: HealthSlot,
}

impl MetricsTap {
    /// Takes one record the analysis wrote (only `fit` records carry metrics).
    pub fn observe(&self, r: &Record) {
        if let Record::Fit(f) = r {
            self.metrics
                .observe_fit(&self.unit, &self.limits, f, unix_now_s());
            self.metrics.note_fit(f);
        }
    }

    /// The decoder's health totals as of now (cheap: stored for the next scrape).
    pub fn health(&self, h: &Health) {
        *lock(&self.health) = Some((h.clone(), unix_now_s()));
        self.metrics.note_health(&self.unit, h);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fit() -> FitRecord {
        let coef = serde_json::json!({
            "Q": {"value": null, "lo": 0.0, "hi": 0.5, "determined": false},
            "N": {"value": 0.25, "lo": 0.2, "hi": 0.3125, "determined": true},
            "B": {"value": 0.125, "lo": 0.0625, "hi": 0.5, "determined": true},
            "K": {"value": null, "lo": 0.0, "hi": 1.0, "determined": false},
            "R": {"value": null, "lo": 0.0, "hi": 2.0, "determined": false},
        });
        let datasheet = serde_json::json!({
            "Q": {"value": null, "unit": "arcsec"},
            "N": {"value": 0.25 / 60.0, "lo": 0.2 / 60.0, "hi": 0.3125 / 60.0, "unit": "deg/sqrt(h)"},
            "B": {"value": 0.125, "lo": 0.0625, "hi": 0.5, "unit": "deg/h"},
            "K": {"value": null, "unit": "deg/h/sqrt(h)"},
            "R": {"value": null, "unit": "deg/h^2"},
        });
        FitRecord {
            channel: "g4".into(),
            unit: "arcsec".into(),
            r#final: true,
            t_data: 300.0,
            coef: serde_json::from_value(coef).unwrap(),
            gof: Some(1.5),
            method: "model".into(),
            model_c: vec![],
            datasheet: Some(serde_json::from_value(datasheet).unwrap()),
            readouts: None,
            q_over_lsb: None,
            run: None,
        }
    }

    fn spec(coef: crate::model::limits::Coef, max: f64) -> LimitSpec {
        LimitSpec {
            channel: "g*".into(),
            coef,
            max: Some(max),
            min: None,
            unit: None,
            over: Scope::Run,
            origin: None,
        }
    }

    #[test]
    fn a_known_fit_gives_these_exact_lines() {
        use crate::model::limits::Coef;
        let m = Metrics::new();
        // N's interval [0.2, 0.3125] lies below 0.35 (pass) and straddles 0.25 (undecided);
        // B's [0.0625, 0.5] lies above 0.05 (fail).
        let limits = vec![spec(Coef::N, 0.35), spec(Coef::B, 0.05)];
        m.observe_fit("dut1", &limits, &fit(), 1.7e9);
        let mut h = Health {
            frames: 75_000,
            crc_errors: 3,
            resyncs: 2,
            missing: 7,
            ..Health::default()
        };
        m.set_health("dut1", &h, 1.7e9 + 1.0);
        // Totals are set, not added: a later, larger total replaces the count.
        h.frames = 75_010;
        m.set_health("dut1", &h, 1.7e9 + 2.0);
        let text = m.encode();
        let l = |s: &str| {
            assert!(
                text.lines().any(|x| x == s),
                "missing line {s:?} in\n{text}"
            )
        };
        l("# TYPE allanscope_coef gauge");
        l(r#"allanscope_coef{unit="dut1",channel="g4",coef="N"} 0.25"#);
        l(r#"allanscope_coef{unit="dut1",channel="g4",coef="B"} 0.125"#);
        l(r#"allanscope_coef_lo{unit="dut1",channel="g4",coef="N"} 0.2"#);
        l(r#"allanscope_coef_hi{unit="dut1",channel="g4",coef="N"} 0.3125"#);
        l(r#"allanscope_coef_hi{unit="dut1",channel="g4",coef="Q"} 0.5"#);
        l(r#"allanscope_coef_determined{unit="dut1",channel="g4",coef="Q"} 0.0"#);
        l(r#"allanscope_coef_determined{unit="dut1",channel="g4",coef="N"} 1.0"#);
        l(
            r#"allanscope_coef_datasheet{unit="dut1",channel="g4",coef="B",datasheet_unit="deg/h"} 0.125"#,
        );
        l(
            r#"allanscope_coef_datasheet_hi{unit="dut1",channel="g4",coef="B",datasheet_unit="deg/h"} 0.5"#,
        );
        l(r#"allanscope_fit_gof{unit="dut1",channel="g4"} 1.5"#);
        l(r#"allanscope_fit_t_data_seconds{unit="dut1",channel="g4"} 300.0"#);
        l(r#"allanscope_fit_timestamp_seconds{unit="dut1",channel="g4"} 1700000000.0"#);
        l(r#"allanscope_limit_verdict{unit="dut1",channel="g4",coef="N",bound="max"} 1.0"#);
        l(r#"allanscope_limit_verdict{unit="dut1",channel="g4",coef="B",bound="max"} -1.0"#);
        l("# TYPE allanscope_frames counter");
        l(r#"allanscope_frames_total{unit="dut1"} 75010"#);
        l(r#"allanscope_missing_frames_total{unit="dut1"} 7"#);
        l(r#"allanscope_crc_errors_total{unit="dut1"} 3"#);
        l(r#"allanscope_resyncs_total{unit="dut1"} 2"#);
        l(r#"allanscope_health_timestamp_seconds{unit="dut1"} 1700000002.0"#);
        assert_eq!(text.lines().last(), Some("# EOF"));
        // Not determined: no value series (the interval ends are there).
        assert!(!text.contains(r#"allanscope_coef{unit="dut1",channel="g4",coef="Q"}"#));
        assert!(!text.contains(r#"coef="Q",datasheet_unit"#));
    }

    #[test]
    fn an_undecided_limit_and_label_values_with_quotes() {
        use crate::model::limits::Coef;
        let m = Metrics::new();
        let mut f = fit();
        f.channel = "g\"1".into();
        m.observe_fit("a\\b", &[spec(Coef::N, 0.25)], &f, 0.0);
        let text = m.encode();
        assert!(
            text.contains(
                r#"allanscope_limit_verdict{unit="a_b",channel="g_1",coef="N",bound="max"} 0.0"#
            ),
            "{text}"
        );
    }
}
