//! Datasheet limits on the fitted coefficients, judged with their uncertainty.
//!
//! A stand config lists limits as an array of tables, each deserializing into a [`LimitSpec`]:
//!
//! ```toml
//! [[limits]]
//! channel = "g*"             # a channel name, or a pattern with `*` and `?`
//! coef = "N"                 # Q, N, B, K or R
//! max = 0.3                  # an upper bound (`min` for a lower one; both may be given)
//! unit = "arcsec/sqrt(s)"    # the unit the bound is stated in; "native" (the default) is the
//!                            # coefficient's own unit (docs/theory.md section 2 table)
//!
//! [[limits]]
//! channel = "g4"
//! coef = "N"
//! max = 0.005
//! unit = "deg/sqrt(h)"       # the same kind of bound in datasheet units
//!
//! [[limits]]
//! channel = "a4"
//! coef = "B"
//! over = "runs_sd"           # run-to-run: the sd of B over the runs (the seed paper (docs/theory.md section 6): <= 5e-4 m/s^2)
//! max = 5e-4
//! unit = "m/s^2"
//! ```
//!
//! `over` is `"run"` (default: each run's fitted coefficient), `"runs_sd"` (the sample standard
//! deviation over runs) or `"runs_mean"` (the mean over runs). Units are products and quotients
//! of `arcsec`, `deg`, `rad`, `mrad`, `urad`, `m`, `mm`, `s`, `min`, `h`, `g`, `mg`, `ug` (also
//! written `micro-g`), with `^n` powers and `sqrt(...)`, e.g. `deg/h/sqrt(h)`, `m/s/sqrt(h)`,
//! `micro-g`. A bound in a unit whose dimension is not the coefficient's (given the channel's
//! unit) is refused before the run, at its file, line and key ([`check_channels`]; exit 2),
//! and reported `invalid` where it is judged without that check (a limit built in code).
//!
//! # The rule
//!
//! Each value comes with its 95% interval `[lo, hi]` (the fit's interval for a run; for
//! `runs_mean` the Student interval of the mean; for `runs_sd` the chi-squared interval of the
//! sd with `n - 1` degrees of freedom). For a `max` limit: **pass** when `hi <= max`, **fail**
//! when `lo > max`, **undecided** when the interval straddles the limit; mirrored for `min`. Each
//! decision is one-sided at 97.5% confidence. A coefficient the fit did not determine still has
//! an interval (from zero up to its upper bound), so a `max` limit can pass on it. Overall:
//! `pass = false` if any limit fails, `true` if all pass, `null` (not decided) otherwise.

use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF};

use crate::model::aggregate::CoefAggregate;
use crate::model::fit::FitResult;
use crate::model::terms::TERM_NAMES;

/// One coefficient of the five-term model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Coef {
    Q,
    N,
    B,
    K,
    R,
}

impl Coef {
    /// Index in Q, N, B, K, R order.
    pub fn index(self) -> usize {
        match self {
            Coef::Q => 0,
            Coef::N => 1,
            Coef::B => 2,
            Coef::K => 3,
            Coef::R => 4,
        }
    }

    /// Its name, `Q`..`R`, as the records write it.
    pub fn name(self) -> &'static str {
        TERM_NAMES[self.index()]
    }

    /// Power of time the coefficient carries beyond the channel's unit: Q u, N u/sqrt(s),
    /// B u/s, K u/s/sqrt(s), R u/s^2 (docs/theory.md section 2).
    fn time_exponent(self) -> f64 {
        -0.5 * self.index() as f64
    }
}

/// What a limit applies to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scope {
    /// Each run's fitted coefficient.
    #[default]
    Run,
    /// The sample standard deviation of the coefficient over runs.
    RunsSd,
    /// The mean of the coefficient over runs.
    RunsMean,
}

impl Scope {
    /// Its name as the records write it (`run`, `runs_sd`, `runs_mean`).
    pub fn name(self) -> &'static str {
        match self {
            Scope::Run => "run",
            Scope::RunsSd => "runs_sd",
            Scope::RunsMean => "runs_mean",
        }
    }
}

/// One `[[limits]]` table of a stand config (module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LimitSpec {
    /// Channel name or pattern (`*` any run of characters, `?` one character).
    pub channel: String,
    pub coef: Coef,
    #[serde(default)]
    pub max: Option<f64>,
    #[serde(default)]
    pub min: Option<f64>,
    /// The unit of `max`/`min`; `None` or "native": the coefficient's native unit.
    #[serde(default)]
    pub unit: Option<String>,
    #[serde(default)]
    pub over: Scope,
    /// Where the limit was written, for errors about it; `None` for a limit built in code.
    #[serde(skip)]
    pub origin: Option<LimitOrigin>,
}

/// The outcome of one bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    Pass,
    Fail,
    Undecided,
    /// The limit could not be judged (no such channel, no data, a unit of the wrong dimension).
    Invalid,
}

impl Verdict {
    /// Its name as the records write it (`pass`, `fail`, `undecided`, `invalid`).
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Pass => "pass",
            Verdict::Fail => "fail",
            Verdict::Undecided => "undecided",
            Verdict::Invalid => "invalid",
        }
    }
}

/// One judged bound, as the `summary` record's `limits` field lists it. `limit`, `value`, `lo`
/// and `hi` are in `unit`, the unit the bound was stated in. The fields are declared in
/// alphabetical order: the order the records have always written them in.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LimitResult {
    /// "max" or "min".
    pub bound: String,
    pub channel: String,
    pub coef: Coef,
    pub hi: Option<f64>,
    pub limit: f64,
    pub lo: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub note: Option<String>,
    /// `run` when a reader finds none (as earlier readers took it).
    #[serde(default)]
    pub over: Scope,
    pub unit: String,
    pub value: Option<f64>,
    pub verdict: Verdict,
}

/// All judged bounds and the overall outcome.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Judgement {
    pub results: Vec<LimitResult>,
    /// `Some(false)` if any bound fails, `Some(true)` if all pass, `None` otherwise (and when
    /// there is no bound).
    pub pass: Option<bool>,
}

impl Judgement {
    fn from_results(results: Vec<LimitResult>) -> Judgement {
        let pass = if results.is_empty() {
            None
        } else if results.iter().any(|r| r.verdict == Verdict::Fail) {
            Some(false)
        } else if results.iter().all(|r| r.verdict == Verdict::Pass) {
            Some(true)
        } else {
            None
        };
        Judgement { results, pass }
    }

    /// Both judgements together (e.g. per-run and run-to-run limits).
    pub fn merge(self, other: Judgement) -> Judgement {
        let mut r = self.results;
        r.extend(other.results);
        Judgement::from_results(r)
    }
}

/// `name` matches `pattern` (`*` any run, `?` one character, otherwise literal).
pub fn channel_matches(pattern: &str, name: &str) -> bool {
    fn rec(p: &[char], n: &[char]) -> bool {
        match p.split_first() {
            None => n.is_empty(),
            Some(('*', rest)) => (0..=n.len()).any(|k| rec(rest, &n[k..])),
            Some(('?', rest)) => !n.is_empty() && rec(rest, &n[1..]),
            Some((c, rest)) => n.first() == Some(c) && rec(rest, &n[1..]),
        }
    }
    let p: Vec<char> = pattern.chars().collect();
    let n: Vec<char> = name.chars().collect();
    rec(&p, &n)
}

// ---------------------------------------------------------------------------------------------
// Units

use crate::model::units::{atom, channel_unit as parse_channel_unit};
pub use crate::model::units::{parse_unit, Unit};

/// Factor `f` such that a coefficient in its native unit times `f` is in `limit_unit`, for a
/// channel in `channel_unit`; `Err` says why not.
pub fn conversion(channel_unit: &str, coef: Coef, limit_unit: Option<&str>) -> Result<f64, String> {
    let lu = match limit_unit {
        None => return Ok(1.0),
        Some(u) if u.trim() == "native" => return Ok(1.0),
        Some(u) => u,
    };
    let limit = parse_unit(lu).ok_or_else(|| format!("unknown unit `{lu}`"))?;
    let chan = parse_channel_unit(channel_unit).ok_or_else(|| {
        format!("channel unit `{channel_unit}` is not a known unit: state the limit as native")
    })?;
    let native = chan.times(atom("s").map_or(Unit::ONE, |s| s.pow(coef.time_exponent())));
    if !native.same_dimension(&limit) {
        return Err(format!(
            "`{lu}` is not a unit of {:?} for a channel in {channel_unit}",
            coef
        ));
    }
    Ok(native.factor / limit.factor)
}

impl LimitSpec {
    /// Problems a config loader should report (key and what is wrong), before any data.
    pub fn problems(&self) -> Vec<(&'static str, String)> {
        let mut p = Vec::new();
        if self.max.is_none() && self.min.is_none() {
            p.push(("max", "a limit needs `max` or `min`".to_string()));
        }
        for (key, v) in [("max", self.max), ("min", self.min)] {
            if let Some(v) = v {
                if !v.is_finite() {
                    p.push((key, format!("{v} is not a finite number")));
                }
            }
        }
        if let Some(u) = &self.unit {
            if u.trim() != "native" && parse_unit(u).is_none() {
                p.push(("unit", format!("unknown unit `{u}`")));
            }
        }
        if self.channel.is_empty() {
            p.push(("channel", "empty channel name".to_string()));
        }
        p
    }

    fn unit_label(&self) -> String {
        self.unit.clone().unwrap_or_else(|| "native".into())
    }

    /// The bounds this limit states: ("max", value) and/or ("min", value).
    pub fn bounds(&self) -> Vec<(&'static str, f64)> {
        let mut b = Vec::new();
        if let Some(v) = self.max {
            b.push(("max", v));
        }
        if let Some(v) = self.min {
            b.push(("min", v));
        }
        b
    }

    fn result(&self, channel: &str, bound: &str, limit: f64) -> LimitResult {
        LimitResult {
            channel: channel.into(),
            coef: self.coef,
            over: self.over,
            bound: bound.into(),
            limit,
            unit: self.unit_label(),
            value: None,
            lo: None,
            hi: None,
            verdict: Verdict::Invalid,
            note: None,
        }
    }
}

/// The rule of the module doc for one bound.
pub fn decide(bound: &str, limit: f64, lo: f64, hi: f64) -> Verdict {
    if !(lo.is_finite() && hi.is_finite()) {
        return Verdict::Undecided;
    }
    match bound {
        "max" if hi <= limit => Verdict::Pass,
        "max" if lo > limit => Verdict::Fail,
        "min" if lo >= limit => Verdict::Pass,
        "min" if hi < limit => Verdict::Fail,
        _ => Verdict::Undecided,
    }
}

/// One channel's fit as the judge needs it.
#[derive(Debug, Clone, Copy)]
pub struct ChannelFit<'a> {
    pub channel: &'a str,
    pub unit: &'a str,
    /// `None` when no fit could be made.
    pub fit: Option<&'a FitResult>,
}

/// Judges the per-run limits (`over = "run"`) on one run's fits; the others are left to
/// [`judge_runs`].
pub fn judge(specs: &[LimitSpec], fits: &[ChannelFit]) -> Judgement {
    let mut out = Vec::new();
    for spec in specs.iter().filter(|s| s.over == Scope::Run) {
        let matched: Vec<&ChannelFit> = fits
            .iter()
            .filter(|f| channel_matches(&spec.channel, f.channel))
            .collect();
        for (bound, limit) in spec.bounds() {
            if matched.is_empty() {
                let mut r = spec.result(&spec.channel, bound, limit);
                r.note = Some("no channel matches".into());
                out.push(r);
            }
            for f in &matched {
                let mut r = spec.result(f.channel, bound, limit);
                let factor = match conversion(f.unit, spec.coef, spec.unit.as_deref()) {
                    Ok(x) => x,
                    Err(e) => {
                        r.note = Some(e);
                        out.push(r);
                        continue;
                    }
                };
                let Some(fit) = f.fit else {
                    r.note = Some("no fit".into());
                    out.push(r);
                    continue;
                };
                let e = &fit.coef[spec.coef.index()];
                r.value = e.determined.then_some(e.value * factor);
                r.lo = Some(e.lo * factor);
                r.hi = Some(e.hi * factor);
                r.verdict = decide(bound, limit, e.lo * factor, e.hi * factor);
                if !e.determined {
                    r.note = Some("coefficient not determined; judged on its interval".into());
                }
                out.push(r);
            }
        }
    }
    Judgement::from_results(out)
}

/// 95% interval of a standard deviation `sd` from `n` samples: `sd sqrt((n-1) / chi2_{q}(n-1))`
/// at `q = 0.975, 0.025` (docs/theory.md section 4's form).
pub fn sd_interval(sd: f64, n: usize) -> Option<(f64, f64)> {
    if n < 2 {
        return None;
    }
    let k = (n - 1) as f64;
    let d = ChiSquared::new(k).ok()?;
    Some((
        sd * (k / d.inverse_cdf(0.975)).sqrt(),
        sd * (k / d.inverse_cdf(0.025)).sqrt(),
    ))
}

/// Judges the run-to-run limits (`over = "runs_sd"` or `"runs_mean"`) on the aggregate of
/// several runs.
pub fn judge_runs(specs: &[LimitSpec], aggregates: &[CoefAggregate]) -> Judgement {
    let mut out = Vec::new();
    for spec in specs.iter().filter(|s| s.over != Scope::Run) {
        let name = TERM_NAMES[spec.coef.index()];
        let matched: Vec<&CoefAggregate> = aggregates
            .iter()
            .filter(|a| a.coef == name && channel_matches(&spec.channel, &a.channel))
            .collect();
        for (bound, limit) in spec.bounds() {
            if matched.is_empty() {
                let mut r = spec.result(&spec.channel, bound, limit);
                r.note = Some("no channel matches".into());
                out.push(r);
            }
            for a in &matched {
                let mut r = spec.result(&a.channel, bound, limit);
                let factor = match conversion(&a.unit, spec.coef, spec.unit.as_deref()) {
                    Ok(x) => x,
                    Err(e) => {
                        r.note = Some(e);
                        out.push(r);
                        continue;
                    }
                };
                let Some(s) = &a.stats else {
                    r.note = Some("not determined in any run".into());
                    out.push(r);
                    continue;
                };
                let (value, interval) = match spec.over {
                    Scope::RunsSd => (s.sd, s.sd.and_then(|sd| sd_interval(sd, s.n))),
                    _ => (Some(s.mean), s.ci_t.map(|c| (c[0], c[1]))),
                };
                r.value = value.map(|v| v * factor);
                match interval {
                    Some((lo, hi)) => {
                        r.lo = Some(lo * factor);
                        r.hi = Some(hi * factor);
                        r.verdict = decide(bound, limit, lo * factor, hi * factor);
                    }
                    None => r.note = Some(format!("{} run(s): no interval", s.n)),
                }
                out.push(r);
            }
        }
    }
    Judgement::from_results(out)
}

/// The keys a `[[limits]]` table may have.
const LIMIT_KEYS: [&str; 6] = ["channel", "coef", "max", "min", "unit", "over"];

/// Reads `[[limits]]` tables (a stand config's, or a limits file's; `prefix` is their key,
/// `limits`) into specs: every unknown key, mistyped or unknown value and inconsistent limit is
/// recorded in the file's one collector, with its key (`limits[i].key`) and line. Each spec
/// read remembers where it was written ([`LimitOrigin`], `what` names the file's kind), so a
/// limit that no channel matches is reported there too ([`check_channels`]).
pub fn from_tables(
    tables: &[toml::Value],
    prefix: &str,
    c: &mut crate::toml_check::Collector,
    what: &'static str,
) -> Vec<LimitSpec> {
    let mut specs = Vec::new();
    for (i, v) in tables.iter().enumerate() {
        let at = format!("{prefix}[{i}]");
        let Some(t) = v.as_table() else {
            c.bad(
                at,
                format!("must be a table ([[{prefix}]]), not {}", v.type_str()),
            );
            continue;
        };
        let before = c.problems().len();
        for k in t.keys().filter(|k| !LIMIT_KEYS.contains(&k.as_str())) {
            c.bad(
                format!("{at}.{k}"),
                format!("unknown key (allowed here: {})", LIMIT_KEYS.join(", ")),
            );
        }
        let text = |c: &mut crate::toml_check::Collector, k: &str| match t.get(k) {
            None => None,
            Some(toml::Value::String(s)) => Some(s.clone()),
            Some(v) => {
                c.bad(
                    format!("{at}.{k}"),
                    format!("expected a string, found {}", v.type_str()),
                );
                None
            }
        };
        let number = |c: &mut crate::toml_check::Collector, k: &str| match t.get(k) {
            None => None,
            Some(toml::Value::Float(x)) => Some(*x),
            Some(toml::Value::Integer(n)) => Some(*n as f64),
            Some(v) => {
                c.bad(
                    format!("{at}.{k}"),
                    format!("expected a number, found {}", v.type_str()),
                );
                None
            }
        };
        let channel = text(c, "channel");
        if channel.is_none() && !t.contains_key("channel") {
            c.bad(
                format!("{at}.channel"),
                "missing: a channel name or pattern",
            );
        }
        let coef = match text(c, "coef").as_deref() {
            None => {
                if !t.contains_key("coef") {
                    c.bad(format!("{at}.coef"), "missing: Q, N, B, K or R");
                }
                None
            }
            Some("Q") => Some(Coef::Q),
            Some("N") => Some(Coef::N),
            Some("B") => Some(Coef::B),
            Some("K") => Some(Coef::K),
            Some("R") => Some(Coef::R),
            Some(other) => {
                c.bad(
                    format!("{at}.coef"),
                    format!("unknown coefficient `{other}` (allowed: Q, N, B, K, R)"),
                );
                None
            }
        };
        let over = match text(c, "over").as_deref() {
            None | Some("run") => Scope::Run,
            Some("runs_sd") => Scope::RunsSd,
            Some("runs_mean") => Scope::RunsMean,
            Some(other) => {
                c.bad(
                    format!("{at}.over"),
                    format!("unknown scope `{other}` (allowed: run, runs_sd, runs_mean)"),
                );
                Scope::Run
            }
        };
        let (max, min) = (number(c, "max"), number(c, "min"));
        let unit = text(c, "unit");
        let complete = channel.is_some() && coef.is_some();
        let spec = LimitSpec {
            origin: Some(LimitOrigin {
                what,
                file: c.file().to_path_buf(),
                line: c.line_of(&format!("{at}.channel")),
                key: format!("{at}.channel"),
            }),
            // Placeholders where a problem is already recorded (the spec is then not kept).
            channel: channel.unwrap_or_else(|| "?".into()),
            coef: coef.unwrap_or(Coef::N),
            max,
            min,
            unit,
            over,
        };
        // The consistency of the limit (a bound given, finite, a known unit), for the keys
        // not already refused above.
        let refused: Vec<String> = c.problems()[before..]
            .iter()
            .filter_map(|p| match p {
                crate::error::UsageError::Config { key, .. } => Some(key.clone()),
                _ => None,
            })
            .collect();
        for (key, problem) in spec.problems() {
            let key = format!("{at}.{key}");
            if !refused.contains(&key) {
                c.bad(key, problem);
            }
        }
        if complete {
            specs.push(spec);
        }
    }
    specs
}

/// Where a limit was written: the kind of file, the file, and the key and line of its
/// `channel`.
#[derive(Debug, Clone, PartialEq)]
pub struct LimitOrigin {
    /// "stand config" or "limits file".
    pub what: &'static str,
    pub file: std::path::PathBuf,
    pub key: String,
    pub line: Option<usize>,
}

/// Every limit must match at least one of `channels` (the run's, read from `input`): a
/// misspelt name would never be judged. The ones that match none are reported together, each at
/// the file and line it was written on (a limit built in code, without an origin, by its name).
pub fn check_channels(
    specs: &[LimitSpec],
    input: &str,
    channels: &[(&str, &str)],
) -> Result<(), crate::toml_check::ConfigErrors> {
    let mut what = "limits";
    let mut problems = Vec::new();
    for l in specs {
        let matched: Vec<&(&str, &str)> = channels
            .iter()
            .filter(|(c, _)| channel_matches(&l.channel, c))
            .collect();
        // A bound in a unit whose dimension is not the coefficient's for the channel's unit
        // (a gyro's N in m/s/sqrt(h)) could never be judged: every verdict would be `invalid`
        // for the whole run. Refused here, at its table's line, with the key `unit`. Before
        // (session 42) a stand ran for hours judging nothing, exit 0.
        let unit_problem = matched.iter().find_map(|(c, u)| {
            conversion(u, l.coef, l.unit.as_deref())
                .err()
                .map(|p| format!("limit on {} of `{c}` (in {u}): {p}", l.coef.name()))
        });
        let (problem, key_end) = match (matched.is_empty(), unit_problem) {
            (true, _) => (
                format!(
                    "`{}` matches no channel of {input} (it has: {})",
                    l.channel,
                    channels
                        .iter()
                        .map(|(c, _)| *c)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
                None,
            ),
            (false, Some(p)) => (p, Some("unit")),
            (false, None) => continue,
        };
        problems.push(match &l.origin {
            Some(o) => {
                what = o.what;
                let key = match key_end {
                    Some(k) => format!("{}.{k}", o.key.trim_end_matches(".channel")),
                    None => o.key.clone(),
                };
                // The line of that key, read again from its file (the origin keeps the
                // channel's).
                let line = key_end
                    .and_then(|_| crate::toml_check::Collector::line_in_file(&o.file, &key))
                    .or(o.line);
                crate::error::UsageError::Config {
                    file: o.file.clone(),
                    line,
                    key,
                    problem,
                }
            }
            None => crate::error::UsageError::Option(format!("datasheet limit: {problem}")),
        });
    }
    if problems.is_empty() {
        Ok(())
    } else {
        Err(crate::toml_check::ConfigErrors { what, problems })
    }
}

/// Reads a limits file: TOML with a `[[limits]]` array (the stand config's form). Every problem
/// is reported once, with its line and key (`crate::toml_check`).
pub fn load_file(path: &std::path::Path) -> anyhow::Result<Vec<LimitSpec>> {
    use crate::toml_check::Collector;
    const WHAT: &str = "limits file";
    let text = std::fs::read_to_string(path)
        .map_err(|e| Collector::unreadable(path, &e).into_errors(WHAT))?;
    let mut c = Collector::new(path, &text);
    let Some(root) = c.parse(&text) else {
        return Err(c.into_errors(WHAT).into());
    };
    for k in root.keys().filter(|k| *k != "limits") {
        c.bad(
            k.as_str(),
            "unknown key (a limits file holds [[limits]] tables)",
        );
    }
    let specs = match root.get("limits") {
        Some(toml::Value::Array(a)) => from_tables(a, "limits", &mut c, WHAT),
        _ => {
            c.bad("limits", "expected an array of tables ([[limits]])");
            Vec::new()
        }
    };
    if c.is_empty() {
        Ok(specs)
    } else {
        Err(c.into_errors(WHAT).into())
    }
}
