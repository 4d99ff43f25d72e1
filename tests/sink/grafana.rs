//! The Grafana dashboard in config/grafana/ reads only what the exporter emits.
//!
//! The 5-minute siu8 fixture goes through the library pipeline with a metrics tap (and one
//! datasheet limit, so verdicts are emitted); the exposition it leaves gives the emitted series
//! and their label names. Every PromQL expression of the dashboard (panels and template
//! variables) must name at least one `allanscope_` metric, every such metric must be emitted,
//! every label its selectors match on must be a label of that metric, and every `{{label}}` of a
//! legend a label of the expression's metrics (or Prometheus's own `job`, `instance`).

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Arc;

use crate::common::fixtures;
use crate::common::pipeline::*;
use allanscope::model::limits::{Coef, LimitSpec, Scope};
use allanscope::pipeline::RunControl;
use allanscope::sink::metrics::Metrics;
use allanscope::source::{Pace, SourceSpec};

/// Metric name -> label names, from an exposition.
fn emitted(text: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mut out: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for line in text.lines().filter(|l| !l.starts_with('#')) {
        let name_end = line.find(['{', ' ']).expect("a sample line");
        let labels = out.entry(line[..name_end].to_string()).or_default();
        if let Some(body) = line[name_end..]
            .strip_prefix('{')
            .and_then(|r| r.split_once('}'))
        {
            for pair in body.0.split("\",") {
                labels.insert(pair.split('=').next().expect("key").to_string());
            }
        }
    }
    out
}

/// The `allanscope_` metrics of a PromQL expression, each with the label names its selector
/// matches on.
fn metrics_of(expr: &str) -> Vec<(String, Vec<String>)> {
    let mut out = Vec::new();
    let mut rest = expr;
    while let Some(i) = rest.find("allanscope_") {
        let tail = &rest[i..];
        let end = tail
            .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
            .unwrap_or(tail.len());
        let name = tail[..end].to_string();
        let mut keys = Vec::new();
        if let Some(sel) = tail[end..].strip_prefix('{') {
            let body = sel.split('}').next().expect("closed selector");
            for m in body.split(',').filter(|m| !m.trim().is_empty()) {
                let key = m.split(['=', '!']).next().expect("key").trim();
                keys.push(key.to_string());
            }
        }
        out.push((name, keys));
        rest = &tail[end..];
    }
    out
}

/// Every string under a key named `expr` or a template query, with where it is.
fn expressions(v: &serde_json::Value, at: &str, out: &mut Vec<(String, String, Option<String>)>) {
    match v {
        serde_json::Value::Object(m) => {
            if let Some(e) = m.get("expr").and_then(|e| e.as_str()) {
                let legend = m.get("legendFormat").and_then(|l| l.as_str());
                out.push((at.into(), e.into(), legend.map(String::from)));
            }
            if m.get("type").and_then(|t| t.as_str()) == Some("query") {
                if let Some(q) = m
                    .get("query")
                    .and_then(|q| q.get("query"))
                    .and_then(|q| q.as_str())
                {
                    out.push((at.into(), q.into(), None));
                }
            }
            for (k, x) in m {
                expressions(x, &format!("{at}.{k}"), out);
            }
        }
        serde_json::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                expressions(x, &format!("{at}[{i}]"), out);
            }
        }
        _ => {}
    }
}

#[test]
fn every_dashboard_query_names_metrics_the_exporter_emits() {
    let metrics = Arc::new(Metrics::new());
    let limits = vec![LimitSpec {
        channel: "g*".into(),
        coef: Coef::N,
        max: Some(0.3),
        min: None,
        unit: None,
        over: Scope::Run,
        origin: None,
    }];
    let ctl = RunControl {
        metrics: Some(metrics.tap("dut1", &limits)),
        ..RunControl::default()
    };
    let spec = SourceSpec::File {
        path: fixtures().join("captures/siu8_stand_5min_seed1.siu8"),
        pace: Pace::Max,
    };
    let (recs, _) = run_to_records(spec, &siu8(), &ctl);
    let exposition = metrics.encode();
    let have = emitted(&exposition);
    // The run itself is what the metrics say: 75,000 frames.
    assert_eq!(last_of(&recs, "health")["frames"], 75_000);
    assert!(
        exposition.contains("allanscope_frames_total{unit=\"dut1\"} 75000"),
        "{exposition}"
    );

    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("config/grafana/allanscope.json");
    let dash: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("dashboard")).expect("JSON");
    assert!(dash["title"].is_string() && dash["panels"].is_array());
    let mut exprs = Vec::new();
    expressions(&dash, "", &mut exprs);
    assert!(exprs.len() >= 10, "{exprs:?}");
    let mut used = BTreeSet::new();
    for (at, expr, legend) in &exprs {
        let named = metrics_of(expr);
        assert!(
            !named.is_empty(),
            "{at}: `{expr}` names no allanscope metric"
        );
        let mut labels: BTreeSet<String> = ["job", "instance"].map(String::from).into();
        for (name, keys) in &named {
            let l = have.get(name).unwrap_or_else(|| {
                panic!("{at}: `{name}` is not emitted; emitted: {:?}", have.keys())
            });
            for k in keys {
                assert!(
                    l.contains(k),
                    "{at}: `{name}` has no label `{k}` (it has {l:?})"
                );
            }
            labels.extend(l.iter().cloned());
            used.insert(name.clone());
        }
        if let Some(legend) = legend {
            for part in legend.split("{{").skip(1) {
                let key = part.split("}}").next().expect("closed").trim();
                assert!(
                    labels.contains(key),
                    "{at}: legend label `{key}` not on {named:?}"
                );
            }
        }
    }
    // The dashboard shows the quantities: ARW (N) and bias instability (B) per channel,
    // and lost frames.
    let all: String = exprs
        .iter()
        .map(|e| e.1.clone())
        .collect::<Vec<_>>()
        .join("\n");
    assert!(all.contains("allanscope_coef_datasheet{") && all.contains("coef=\"N\""));
    assert!(all.contains("coef=\"B\""));
    assert!(used.contains("allanscope_missing_frames_total"));
}
