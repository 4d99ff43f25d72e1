//! `--metrics` scraped by the real Prometheus server, read back through its HTTP API.
//!
//! `allanscope listen --udp ... --metrics ...` receives the first 60 s of the siu8 fixture
//! (15,000 frames, 10 per datagram) on loopback; a Prometheus server (Debian package
//! `prometheus`, which `.ci/run` installs) scrapes it every second. Once the fits cover all 60 s,
//! `/api/v1/query` must give every channel's coefficient interval ends (and the determined
//! values) equal to the final `fit` records the run writes after SIGTERM (the interim and final
//! fits differ only by the covariance cache, ~1e-11 relative), and the frame counters the
//! truth: all 15,000 frames accounted for, as received or as counted missing (loopback UDP may
//! drop a datagram on a starved machine; at most 2% tolerated). Everything on 127.0.0.1, every
//! wait bounded.
//!
//! The Grafana dashboard (config/grafana/allanscope.json) is checked against the same server:
//! every panel's PromQL, with the template variables at "All" and at the run's unit and one
//! channel, and every template variable's `label_values` through `/api/v1/label/.../values`,
//! must return the series the panel is for, with the labels its legend shows: the coefficients
//! each channel's final fit determined, the interval ends of all 8 channels, one series per unit
//! for the frame counters, the verdicts of the two datasheet limits given (`--limits`) as the
//! summary judges them. (No Grafana server is installable here: not in Debian, crates, PyPI or
//! npm; `dashboard_has_the_fields_of_grafanas_model` checks the JSON model instead.)
//!
//! Without a `prometheus` binary the test is skipped, except under CI (`CI=true`), where it
//! fails.

use std::io::{Read, Write};
use std::net::{TcpListener, TcpStream};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::pipeline::*;

const FRAMES: usize = 15_000;
const FRAME_LEN: usize = 42;
const PER_DATAGRAM: usize = 10;
/// Longest wait for any one step.
const STEP_TIMEOUT: Duration = Duration::from_secs(60);

/// Kills the child when dropped (a failing assertion must not leave a server behind).
struct Reaped(Child);

impl Drop for Reaped {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn free_tcp_port() -> u16 {
    let l = TcpListener::bind("127.0.0.1:0").expect("bind");
    l.local_addr().expect("addr").port()
}

/// A plain HTTP/1.0 GET on 127.0.0.1 (the test's client side): status and body.
fn http_get(port: u16, path: &str) -> Option<(u16, String)> {
    let mut s = TcpStream::connect(("127.0.0.1", port)).ok()?;
    s.set_read_timeout(Some(Duration::from_secs(5))).ok()?;
    write!(s, "GET {path} HTTP/1.0\r\nHost: 127.0.0.1\r\n\r\n").ok()?;
    let mut text = String::new();
    s.read_to_string(&mut text).ok()?;
    let (head, body) = text.split_once("\r\n\r\n")?;
    let status = head.split_whitespace().nth(1)?.parse().ok()?;
    Some((status, body.to_string()))
}

fn url_encode(q: &str) -> String {
    q.bytes()
        .map(|b| match b {
            b'a'..=b'z' | b'A'..=b'Z' | b'0'..=b'9' | b'_' | b'-' | b'.' => (b as char).to_string(),
            _ => format!("%{b:02X}"),
        })
        .collect()
}

/// Instant query through Prometheus's HTTP API: each series' labels and value.
fn query(prom_port: u16, q: &str) -> Vec<(serde_json::Value, f64)> {
    let Some((200, body)) = http_get(prom_port, &format!("/api/v1/query?query={}", url_encode(q)))
    else {
        return Vec::new();
    };
    let v: serde_json::Value = serde_json::from_str(&body).expect("API answer is JSON");
    assert_eq!(v["status"], "success", "{body}");
    v["data"]["result"]
        .as_array()
        .map(|a| {
            a.iter()
                .map(|s| {
                    let x: f64 = s["value"][1]
                        .as_str()
                        .and_then(|t| t.parse().ok())
                        .expect("a sample value");
                    (s["metric"].clone(), x)
                })
                .collect()
        })
        .unwrap_or_default()
}

/// Waits until `cond` gives `Some`, at most [`STEP_TIMEOUT`].
fn wait_for<T>(what: &str, mut cond: impl FnMut() -> Option<T>) -> T {
    let t0 = Instant::now();
    loop {
        if let Some(v) = cond() {
            return v;
        }
        assert!(t0.elapsed() < STEP_TIMEOUT, "timed out waiting for {what}");
        std::thread::sleep(Duration::from_millis(100));
    }
}

fn prometheus_available() -> bool {
    Command::new("prometheus")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

fn rel_eq(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-8 * a.abs().max(b.abs()) + 1e-300
}

#[test]
fn prometheus_scrapes_the_coefficients_and_counters() {
    if !prometheus_available() {
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "CI=true but no `prometheus` binary: .ci/run must install the Debian package"
        );
        eprintln!("skipped: no `prometheus` binary (apt-get install prometheus)");
        return;
    }
    let dir = std::env::temp_dir().join(format!("allanscope-prom-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("tmp dir");
    let (udp, metrics, prom) = (free_udp_port(), free_tcp_port(), free_tcp_port());
    let out = dir.join("out.jsonl");
    // One limit every channel passes (N of g1 below 1000 arcsec/sqrt(s)) and one it fails.
    std::fs::write(
        dir.join("limits.toml"),
        "[[limits]]\nchannel = \"g1\"\ncoef = \"N\"\nmax = 1000.0\n\n\
         [[limits]]\nchannel = \"g2\"\ncoef = \"N\"\nmax = 1e-9\n",
    )
    .expect("limits");
    let log = std::fs::File::create(dir.join("allanscope.log")).expect("log");
    let listen = Reaped(
        Command::new(env!("CARGO_BIN_EXE_allanscope"))
            .args([
                "listen",
                "--udp",
                &format!("127.0.0.1:{udp}"),
                "--format",
                "siu8",
            ])
            .args([
                "--metrics",
                &format!("127.0.0.1:{metrics}"),
                "--every",
                "0.5",
            ])
            .arg("--limits")
            .arg(dir.join("limits.toml"))
            .arg("--out")
            .arg(&out)
            .stdout(Stdio::null())
            .stderr(log)
            .spawn()
            .expect("start allanscope"),
    );
    std::fs::write(
        dir.join("prometheus.yml"),
        format!(
            "global:\n  scrape_interval: 1s\n  evaluation_interval: 1s\nscrape_configs:\n  \
             - job_name: allanscope\n    static_configs:\n      - targets: ['127.0.0.1:{metrics}']\n"
        ),
    )
    .expect("config");
    let prom_log = std::fs::File::create(dir.join("prometheus.log")).expect("log");
    let _prometheus = Reaped(
        Command::new("prometheus")
            .arg(format!(
                "--config.file={}",
                dir.join("prometheus.yml").display()
            ))
            .arg(format!(
                "--storage.tsdb.path={}",
                dir.join("tsdb").display()
            ))
            .arg(format!("--web.listen-address=127.0.0.1:{prom}"))
            .stdout(Stdio::null())
            .stderr(prom_log)
            .spawn()
            .expect("start prometheus"),
    );

    // The exporter answers before any data (an empty exposition).
    let first = wait_for("the /metrics endpoint", || http_get(metrics, "/metrics"));
    // The metrics server starts before the UDP socket is bound: a datagram sent before the bind
    // is dropped by the kernel and no later frame could reveal it (CI failed so once, 14,990).
    let log_path = dir.join("allanscope.log");
    wait_for("the UDP socket to be bound", || {
        std::fs::read_to_string(&log_path)
            .ok()
            .filter(|l| l.contains("listening on udp"))
    });
    assert_eq!(first.0, 200);
    assert!(first.1.ends_with("# EOF\n"), "{}", first.1);
    assert_eq!(http_get(metrics, "/nothing").map(|r| r.0), Some(404));

    // 60 s of frames at 20 times their rate: no pause near the half counter period that a live
    // stream's outage detection would take for a silence (src/pipeline/decode.rs).
    let bytes = siu8_capture()[..FRAMES * FRAME_LEN].to_vec();
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").expect("bind sender");
    let start = Instant::now();
    for (i, d) in bytes.chunks(PER_DATAGRAM * FRAME_LEN).enumerate() {
        let due = start + Duration::from_secs_f64((i * PER_DATAGRAM) as f64 / (20.0 * 250.0));
        std::thread::sleep(due.saturating_duration_since(Instant::now()));
        sock.send_to(d, ("127.0.0.1", udp)).expect("send");
    }
    let sent = FRAMES as u64;
    // Through Prometheus: every frame counted, as received or as missing. Loopback UDP may still
    // drop a datagram when the receiver is starved of CPU (a loaded CI machine); such a loss must
    // show as `missing`, so received + missing is the frames sent, unless the loss is at the very
    // end, where no later counter can reveal it.
    let metric_now = |name: &str| -> u64 {
        http_get(metrics, "/metrics")
            .and_then(|(_, b)| {
                b.lines()
                    .find(|l| l.starts_with(&format!("{name}{{")))
                    .and_then(|l| l.rsplit(' ').next()?.parse().ok())
            })
            .unwrap_or(0)
    };
    let q_frames = r#"allanscope_frames_total{job="allanscope"}"#;
    let q_missing = r#"allanscope_missing_frames_total{job="allanscope"}"#;
    let mut last = (0, Instant::now());
    let (seen, missing) = wait_for("Prometheus to see the frames", || {
        let n = query(prom, q_frames).first().map(|s| s.1)?;
        let m = query(prom, q_missing).first().map(|s| s.1)?;
        let direct = metric_now("allanscope_frames_total");
        let direct_missing = metric_now("allanscope_missing_frames_total");
        if direct != last.0 {
            last = (direct, Instant::now());
        }
        // Done when all are accounted for, or when the count has stood still for 3 s.
        let still = last.1.elapsed() > Duration::from_secs(3);
        let same = direct as f64 == n && direct_missing as f64 == m;
        (same && (direct + direct_missing == sent || still)).then_some((n, m))
    });
    let health: Vec<String> = http_get(metrics, "/metrics")
        .map(|(_, b)| {
            b.lines()
                .filter(|l| l.contains("_total{"))
                .map(String::from)
                .collect()
        })
        .unwrap_or_default();
    let accounted = seen + missing;
    assert!(
        accounted <= sent as f64 && accounted >= 0.98 * sent as f64,
        "frames {seen} + missing {missing} of {sent} sent; exporter: {health:?}"
    );
    assert!(
        seen >= 0.98 * sent as f64,
        "more than 2% of the datagrams lost on loopback: {seen} of {sent}; exporter: {health:?}"
    );
    if accounted < sent as f64 {
        eprintln!(
            "note: the last {} frames were lost in transit",
            sent as f64 - accounted
        );
    }
    assert_eq!(
        query(prom, "allanscope_crc_errors_total")
            .first()
            .map(|s| s.1),
        Some(0.0)
    );
    // The fits span every frame accounted for, at 250 Hz.
    let t_all = accounted / 250.0;
    wait_for("Prometheus to hold fits of all 60 s", || {
        let t = query(prom, "allanscope_fit_t_data_seconds");
        (t.len() == 8 && t.iter().all(|s| rel_eq(s.1, t_all))).then_some(())
    });
    let read = |name: &str| -> Vec<(String, String, f64)> {
        query(prom, name)
            .into_iter()
            .map(|(m, x)| {
                let s = |k: &str| m[k].as_str().unwrap_or("").to_string();
                assert_eq!(m["unit"], format!("udp:127.0.0.1:{udp}"), "{m}");
                (s("channel"), s("coef"), x)
            })
            .collect()
    };
    let (lo, hi, value) = (
        read("allanscope_coef_lo"),
        read("allanscope_coef_hi"),
        read("allanscope_coef"),
    );
    // The dashboard's queries, while the run still serves them (the Lost frames and Frame rate
    // panels look one minute back).
    // `rate` and `increase` need two samples of a counter in their window.
    wait_for("two scrapes of the counters", || {
        let n = query(prom, "count_over_time(allanscope_missing_frames_total[1m])");
        n.first().is_some_and(|s| s.1 >= 2.0).then_some(())
    });
    let unit = format!("udp:127.0.0.1:{udp}");
    let label_values = |label: &str, selector: &str| -> Vec<String> {
        let path = format!(
            "/api/v1/label/{label}/values?{}={}",
            url_encode("match[]"),
            url_encode(selector)
        );
        let (status, body) = http_get(prom, &path).expect("label values");
        assert_eq!(status, 200, "{path}: {body}");
        let v: serde_json::Value = serde_json::from_str(&body).expect("JSON");
        v["data"]
            .as_array()
            .map(|a| {
                a.iter()
                    .filter_map(|x| x.as_str().map(String::from))
                    .collect()
            })
            .unwrap_or_default()
    };
    let (dash_all, dash_one, variables) = crate::grafana::evaluate(
        &|q| query(prom, q),
        &label_values,
        &[("unit", &unit), ("channel", "g1")],
    );

    // The final fit records, written on SIGTERM.
    let pid = listen.0.id().to_string();
    let st = Command::new("kill").args(["-TERM", &pid]).status();
    assert!(st.is_ok_and(|s| s.success()));
    let mut listen = listen;
    let t0 = Instant::now();
    while listen.0.try_wait().expect("wait").is_none() {
        assert!(
            t0.elapsed() < STEP_TIMEOUT,
            "listen did not stop on SIGTERM"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    let recs = parse_lines(&std::fs::read(&out).expect("output"));
    let fits: Vec<&serde_json::Value> = recs
        .iter()
        .filter(|r| r["type"] == "fit" && r["final"] == true)
        .collect();
    assert_eq!(fits.len(), 8, "one final fit per channel");
    assert_eq!(lo.len(), 40, "5 coefficients x 8 channels: {lo:?}");
    assert_eq!(hi.len(), 40);
    let mut determined = 0;
    for f in fits {
        let ch = f["channel"].as_str().expect("channel");
        for coef in ["Q", "N", "B", "K", "R"] {
            let c = &f["coef"][coef];
            let find = |v: &[(String, String, f64)]| {
                v.iter().find(|s| s.0 == ch && s.1 == coef).map(|s| s.2)
            };
            let want = |k: &str| c[k].as_f64();
            for (k, got) in [("lo", find(&lo)), ("hi", find(&hi))] {
                let (g, w) = (got.expect("scraped"), want(k).expect("in the record"));
                assert!(rel_eq(g, w), "{ch} {coef} {k}: Prometheus {g}, record {w}");
            }
            match want("value") {
                Some(w) => {
                    let g = find(&value).unwrap_or_else(|| panic!("{ch} {coef} not scraped"));
                    assert!(rel_eq(g, w), "{ch} {coef}: Prometheus {g}, record {w}");
                    determined += 1;
                }
                None => assert_eq!(find(&value), None, "{ch} {coef} is not determined"),
            }
        }
    }
    // 60 s of the stand's unit determine at least N of every channel.
    assert!(determined >= 8, "only {determined} coefficients determined");
    let summary = last_of(&recs, "summary");
    check_dashboard(&dash_all, &dash_one, &variables, &recs, summary, &unit);
    let _ = std::fs::remove_dir_all(&dir);
}

/// The channels whose final fit determined `coef` (a value, not only an interval).
fn determined_channels(recs: &[serde_json::Value], coef: &str) -> Vec<String> {
    let mut v: Vec<String> = recs
        .iter()
        .filter(|r| r["type"] == "fit" && r["final"] == true)
        .filter(|r| r["coef"][coef]["value"].is_number())
        .map(|r| r["channel"].as_str().expect("channel").to_string())
        .collect();
    v.sort();
    v
}

/// The dashboard's answers through Prometheus against the run's own records (see the module
/// doc): `all` with the template variables at "All", `one` at the run's unit and channel g1.
fn check_dashboard(
    all: &[crate::grafana::Answer],
    one: &[crate::grafana::Answer],
    variables: &std::collections::BTreeMap<String, Vec<String>>,
    recs: &[serde_json::Value],
    summary: &serde_json::Value,
    unit: &str,
) {
    let mut sorted: Vec<String> = ["g1", "g2", "g3", "g4", "a1", "a2", "a3", "a4"]
        .map(String::from)
        .into();
    sorted.sort();
    assert_eq!(variables["unit"], [unit.to_string()], "the unit variable");
    assert_eq!(variables["channel"], sorted, "the channel variable");
    assert!(all.len() >= 12, "{} panel targets", all.len());
    for (answers, picked) in [(all, None), (one, Some("g1"))] {
        for a in answers {
            let at = format!("{}: `{}`", a.at, a.expr);
            let label = |s: &serde_json::Value, k: &str| s[k].as_str().map(String::from);
            // Every label the legend shows is on every series, and the unit is the run's.
            for (m, _) in &a.series {
                for part in a.legend.as_deref().unwrap_or("").split("{{").skip(1) {
                    let key = part.split("}}").next().expect("closed").trim();
                    assert!(m[key].is_string(), "{at}: series {m} lacks `{key}`");
                }
                assert_eq!(label(m, "unit").as_deref(), Some(unit), "{at}: {m}");
            }
            let mut got: Vec<String> = a
                .series
                .iter()
                .filter_map(|(m, _)| label(m, "channel"))
                .collect();
            got.sort();
            let restrict = |v: Vec<String>| -> Vec<String> {
                v.into_iter()
                    .filter(|c| picked.is_none_or(|p| p == c))
                    .collect()
            };
            let coef = ["N", "B"]
                .into_iter()
                .find(|c| a.expr.contains(&format!("coef=\"{c}\"")));
            let e = &a.expr;
            if e.contains("allanscope_coef_datasheet{") || e.starts_with("allanscope_coef{") {
                // The value: exactly the channels whose fit determined it.
                let want = restrict(determined_channels(recs, coef.expect("a coefficient")));
                assert_eq!(got, want, "{at}");
            } else if e.starts_with("allanscope_coef_lo{") || e.starts_with("allanscope_coef_hi{") {
                assert_eq!(got, restrict(sorted.clone()), "{at}");
            } else if e.contains("_total{") {
                // One series per unit, without a channel; a counter's increase is >= 0.
                assert_eq!(a.series.len(), 1, "{at}: {:?}", a.series);
                assert!(got.is_empty() && a.series[0].1 >= 0.0, "{at}");
            } else if e.starts_with("allanscope_limit_verdict{") {
                // The verdicts the summary gives for the two limits.
                let limits = summary["limits"].as_array().expect("summary limits");
                let mut want: Vec<(String, f64)> = limits
                    .iter()
                    .filter(|l| picked.is_none_or(|p| l["channel"] == p))
                    .map(|l| {
                        let v = match l["verdict"].as_str() {
                            Some("pass") => 1.0,
                            Some("undecided") => 0.0,
                            Some("fail") => -1.0,
                            _ => -2.0,
                        };
                        (l["channel"].as_str().expect("channel").to_string(), v)
                    })
                    .collect();
                let mut have: Vec<(String, f64)> = a
                    .series
                    .iter()
                    .map(|(m, v)| (label(m, "channel").expect("channel"), *v))
                    .collect();
                want.sort_by(|x, y| x.0.cmp(&y.0));
                have.sort_by(|x, y| x.0.cmp(&y.0));
                assert_eq!(have, want, "{at}");
                if picked.is_none() {
                    assert_eq!(have, [("g1".into(), 1.0), ("g2".into(), -1.0)], "{at}");
                }
            } else if e.contains("allanscope_fit_timestamp_seconds{") {
                assert_eq!(got, restrict(sorted.clone()), "{at}");
                assert!(a.series.iter().all(|s| (0.0..600.0).contains(&s.1)), "{at}");
            } else if e.contains("allanscope_health_timestamp_seconds{") {
                assert_eq!(a.series.len(), 1, "{at}");
                assert!((0.0..600.0).contains(&a.series[0].1), "{at}");
            } else {
                panic!("{at}: a query this test does not know what to expect of");
            }
            if a.expr.contains("_total{") || a.expr.contains("timestamp") {
                continue;
            }
            // Per-channel panels show something for every channel they select, except a
            // value not determined by 60 s of data.
            if coef != Some("B") || !determined_channels(recs, "B").is_empty() {
                assert!(!a.series.is_empty(), "{at}: no series");
            }
        }
    }
}
