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
pub(crate) fn metrics_of(expr: &str) -> Vec<(String, Vec<String>)> {
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
pub(crate) fn expressions(
    v: &serde_json::Value,
    at: &str,
    out: &mut Vec<(String, String, Option<String>)>,
) {
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

/// The shipped dashboard, parsed.
pub(crate) fn dashboard() -> serde_json::Value {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("config/grafana/allanscope.json");
    serde_json::from_str(&std::fs::read_to_string(&path).expect("dashboard")).expect("JSON")
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

    let dash = dashboard();
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
    // The dashboard shows the issue's quantities: ARW (N) and bias instability (B) per channel,
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

/// The dashboard against Grafana's (classic) dashboard JSON model, as far as an import needs
/// it: the top-level fields (`uid` at most 40 characters, `schemaVersion`, `time`,
/// `templating.list`, `annotations.list`), every panel with a unique integer `id`, a `type`
/// that `__requires` lists, a `title`, a `gridPos` inside the 24-column grid overlapping no
/// other panel, a Prometheus `datasource` naming the `__inputs` entry an import asks for, and
/// `targets` each with a unique `refId` and a PromQL `expr`; every template variable likewise
/// with its data source.
#[test]
fn dashboard_has_the_fields_of_grafanas_model() {
    let d = dashboard();
    let uid = d["uid"].as_str().expect("uid");
    assert!(!uid.is_empty() && uid.len() <= 40, "uid {uid:?}");
    assert!(d["title"].as_str().is_some_and(|t| !t.is_empty()));
    // Grafana 8 (timeseries panels, schema 30) to Grafana 11 (schema 39-41).
    let schema = d["schemaVersion"].as_u64().expect("schemaVersion");
    assert!((30..=41).contains(&schema), "schemaVersion {schema}");
    assert!(d["version"].is_u64());
    assert!(d["time"]["from"].is_string() && d["time"]["to"].is_string());
    assert!(d["annotations"]["list"].is_array());
    // The data source an import asks for.
    let inputs = d["__inputs"].as_array().expect("__inputs");
    let ds_inputs: Vec<String> = inputs
        .iter()
        .filter(|i| i["type"] == "datasource" && i["pluginId"] == "prometheus")
        .map(|i| format!("${{{}}}", i["name"].as_str().expect("input name")))
        .collect();
    assert_eq!(ds_inputs.len(), 1, "{inputs:?}");
    let requires = d["__requires"].as_array().expect("__requires");
    let required =
        |kind: &str, id: &str| requires.iter().any(|r| r["type"] == kind && r["id"] == id);
    assert!(required("grafana", "grafana") && required("datasource", "prometheus"));
    let check_ds = |ds: &serde_json::Value, at: &str| {
        assert_eq!(ds["type"], "prometheus", "{at}: datasource");
        assert_eq!(ds["uid"].as_str(), Some(ds_inputs[0].as_str()), "{at}");
    };
    let panels = d["panels"].as_array().expect("panels");
    assert!(panels.len() >= 6);
    let mut ids = BTreeSet::new();
    let mut cells: BTreeMap<(u64, u64), u64> = BTreeMap::new();
    for p in panels {
        let id = p["id"].as_u64().expect("panel id");
        assert!(ids.insert(id), "panel id {id} twice");
        let at = format!("panel {id}");
        let ty = p["type"].as_str().expect("panel type");
        assert!(required("panel", ty), "{at}: type {ty} not in __requires");
        assert!(p["title"].as_str().is_some_and(|t| !t.is_empty()), "{at}");
        let g = &p["gridPos"];
        let [x, y, w, h] = ["x", "y", "w", "h"]
            .map(|k| g[k].as_u64().unwrap_or_else(|| panic!("{at}: gridPos.{k}")));
        assert!(w >= 1 && h >= 1 && x + w <= 24, "{at}: gridPos {g}");
        for cx in x..x + w {
            for cy in y..y + h {
                if let Some(other) = cells.insert((cx, cy), id) {
                    panic!("{at} overlaps panel {other} at ({cx}, {cy})");
                }
            }
        }
        check_ds(&p["datasource"], &at);
        let targets = p["targets"].as_array().expect("targets");
        assert!(!targets.is_empty(), "{at}: no targets");
        let mut refs = BTreeSet::new();
        for t in targets {
            let r = t["refId"].as_str().expect("refId");
            assert!(refs.insert(r.to_string()), "{at}: refId {r} twice");
            assert!(
                t["expr"].as_str().is_some_and(|e| !e.is_empty()),
                "{at}: target {r} has no expr"
            );
        }
    }
    for v in d["templating"]["list"].as_array().expect("templating.list") {
        let at = format!("variable {}", v["name"]);
        assert!(v["name"].as_str().is_some_and(|n| !n.is_empty()), "{at}");
        assert_eq!(v["type"], "query", "{at}");
        check_ds(&v["datasource"], &at);
        assert!(v["query"]["query"].as_str().is_some(), "{at}");
    }
}

/// What one query of the dashboard gave through Prometheus: where it is, the PromQL sent, the
/// legend, and each series' labels and value.
#[derive(Debug)]
pub(crate) struct Answer {
    pub at: String,
    pub expr: String,
    pub legend: Option<String>,
    pub series: Vec<(serde_json::Value, f64)>,
}

/// A value of a template variable as Grafana puts it into a regex matcher (`=~`) of a PromQL
/// string: regex metacharacters escaped, and the backslash doubled for the string literal.
fn regex_value(v: &str) -> String {
    let mut out = String::new();
    for c in v.chars() {
        if r"\.+*?()|[]{}^$".contains(c) {
            out.push_str(r"\\");
        }
        out.push(c);
    }
    out
}

/// Every panel target of the dashboard, evaluated by `query` (Prometheus's instant query API)
/// twice: with each template variable at "All" (its `allValue`, as the dashboard opens) and
/// with each at one value of `picked`, as a user who picks a unit and a channel sees it.
/// Template variables (`label_values(SELECTOR, LABEL)`) go to `label_values` as Grafana's
/// Prometheus data source sends them (`/api/v1/label/LABEL/values?match[]=SELECTOR`).
pub(crate) fn evaluate(
    query: &dyn Fn(&str) -> Vec<(serde_json::Value, f64)>,
    label_values: &dyn Fn(&str, &str) -> Vec<String>,
    picked: &[(&str, &str)],
) -> (Vec<Answer>, Vec<Answer>, BTreeMap<String, Vec<String>>) {
    let d = dashboard();
    let vars = d["templating"]["list"].as_array().expect("templating");
    let fill = |e: &str, all: bool| {
        let mut e = e.to_string();
        for v in vars {
            let name = v["name"].as_str().expect("name");
            let value = if all {
                v["allValue"].as_str().expect("allValue").to_string()
            } else {
                let p = picked.iter().find(|p| p.0 == name).expect("a picked value");
                regex_value(p.1)
            };
            e = e.replace(&format!("${name}"), &value);
        }
        e
    };
    let mut variables = BTreeMap::new();
    for v in vars {
        let q = v["query"]["query"].as_str().expect("query");
        let inner = q
            .strip_prefix("label_values(")
            .and_then(|r| r.strip_suffix(')'))
            .unwrap_or_else(|| {
                panic!("variable query {q}: expected label_values(SELECTOR, LABEL)")
            });
        let (selector, label) = inner.rsplit_once(',').expect("SELECTOR, LABEL");
        let name = v["name"].as_str().expect("name").to_string();
        variables.insert(
            name,
            label_values(label.trim(), &fill(selector.trim(), true)),
        );
    }
    let mut runs = [Vec::new(), Vec::new()];
    for (k, all) in [true, false].into_iter().enumerate() {
        for p in d["panels"].as_array().expect("panels") {
            for t in p["targets"].as_array().expect("targets") {
                let expr = fill(t["expr"].as_str().expect("expr"), all);
                runs[k].push(Answer {
                    at: format!("panel {} ({}) {}", p["id"], p["title"], t["refId"]),
                    series: query(&expr),
                    legend: t["legendFormat"].as_str().map(String::from),
                    expr,
                });
            }
        }
    }
    let [all, one] = runs;
    (all, one, variables)
}
