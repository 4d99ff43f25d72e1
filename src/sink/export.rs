//! Exports: the fitted noise model in the files other tools read (Kalibr `imu.yaml`, OpenVINS
//! `kalibr_imu_chain.yaml`, VINS-Mono/Fusion noise keys, KF-GINS `imunoise`), and the curves as a
//! CSV or a Stable32-style table. Input: the JSON-lines records allanscope wrote; output: text.
//! Every conversion is written out in docs/export.md with its source.
//!
//! Continuous-time densities (docs/export.md): for a channel whose increment unit is `u` with
//! `s` SI units (rad or m/s) per `u`,
//! - white-noise density = N * s: N in u/sqrt(s) is `u/s/sqrt(Hz)`, since the two-sided PSD of a
//!   white rate of density `sigma_c` gives AVAR `sigma_c^2 / tau` (IEEE 952 annex C.1), so
//!   `sigma_c = N`: rad/s/sqrt(Hz) (gyro) or m/s^2/sqrt(Hz) (accelerometer);
//! - bias random-walk density = K * s: the rate random walk `K^2 tau / 3` (annex C.3) is the
//!   integral of white noise of density K: rad/s^2/sqrt(Hz) or m/s^3/sqrt(Hz).
//!
//! Where a coefficient is not determined, its upper 95% bound is exported instead (a filter
//! tuned on it is conservative) and the file says so in a comment.

use std::fmt::Write as _;

use crate::model::units::{native_units, IncrementUnit, SensorKind};
use crate::sink::records::{CurveRecord, FitRecord};

/// The export targets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExportFormat {
    Kalibr,
    OpenVins,
    Vins,
    KfGins,
    Csv,
    Stable32,
}

impl std::str::FromStr for ExportFormat {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s {
            "kalibr" => ExportFormat::Kalibr,
            "openvins" => ExportFormat::OpenVins,
            "vins" => ExportFormat::Vins,
            "kf-gins" => ExportFormat::KfGins,
            "csv" => ExportFormat::Csv,
            "stable32" => ExportFormat::Stable32,
            _ => {
                return Err(format!(
                    "--to `{s}`: expected kalibr, openvins, vins, kf-gins, csv or stable32"
                ))
            }
        })
    }
}

/// One coefficient taken for export: the value in SI, and whether it is the fit's estimate or
/// its upper bound (not determined).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Taken {
    pub si: f64,
    pub bound: bool,
}

/// The noise of one sensor kind over the chosen channels (the largest of them: one figure for a
/// triad, conservative), in SI continuous time.
#[derive(Debug, Clone, PartialEq)]
pub struct KindNoise {
    pub channels: Vec<String>,
    /// White noise density: rad/s/sqrt(Hz) or m/s^2/sqrt(Hz) (= N in rad/sqrt(s), m/s/sqrt(s)).
    pub white: Taken,
    /// Bias random-walk density: rad/s^2/sqrt(Hz) or m/s^3/sqrt(Hz) (= K).
    pub random_walk: Taken,
    /// Bias instability B: rad/s or m/s^2.
    pub bias_instability: Taken,
    /// Per channel (in the order of `channels`) N, B in SI, for tools that take one per axis.
    pub per_axis: Vec<(Taken, Taken)>,
    /// The tau (s) of the minimum of the Allan deviation, largest over the channels (KF-GINS
    /// correlation time), when the read-outs give it.
    pub tau_min_s: Option<f64>,
}

/// The coefficient `i` (0..5 = Q..R) of a fit, in SI, estimate or upper bound.
fn take(fit: &FitRecord, name: &str, si_per_unit: f64) -> Option<Taken> {
    let c = fit.coef.get(name)?;
    let hi = c.hi;
    match c.value {
        Some(v) => Some(Taken {
            si: v * si_per_unit,
            bound: false,
        }),
        None => hi.map(|h| Taken {
            si: h * si_per_unit,
            bound: true,
        }),
    }
}

fn largest(v: impl Iterator<Item = Taken>) -> Option<Taken> {
    v.fold(None, |a: Option<Taken>, t| match a {
        Some(a) if a.si >= t.si => Some(a),
        _ => Some(t),
    })
}

/// The noise of the chosen fits (all of one kind); `Err` names what is missing.
pub fn kind_noise(fits: &[&FitRecord], kind: SensorKind) -> Result<KindNoise, String> {
    let mut white = Vec::new();
    let mut rw = Vec::new();
    let mut bi = Vec::new();
    let mut tau_min: Option<f64> = None;
    for f in fits {
        let u = IncrementUnit::parse(&f.unit)
            .filter(|u| u.kind == kind)
            .ok_or_else(|| {
                format!(
                    "channel `{}` is in `{}`, not a unit of {} (deg, rad, mrad, arcsec{})",
                    f.channel,
                    f.unit,
                    match kind {
                        SensorKind::Gyro => "angle",
                        SensorKind::Accel => "velocity",
                    },
                    match kind {
                        SensorKind::Gyro => "",
                        SensorKind::Accel => "; m/s, ft/s, g, mg",
                    }
                )
            })?;
        let s = u.si_per_unit;
        let missing = |c: &str| format!("channel `{}`: the fit has no coefficient {c}", f.channel);
        white.push(take(f, "N", s).ok_or_else(|| missing("N"))?);
        rw.push(take(f, "K", s).ok_or_else(|| missing("K"))?);
        bi.push(take(f, "B", s).ok_or_else(|| missing("B"))?);
        if let Some(t) = f
            .readouts
            .as_ref()
            .and_then(|r| r.bias_instability.as_ref())
            .map(|b| b.tau)
        {
            tau_min = Some(tau_min.map_or(t, |m: f64| m.max(t)));
        }
    }
    let per_axis = white.iter().copied().zip(bi.iter().copied()).collect();
    Ok(KindNoise {
        // Each channel once (a file of several runs has a fit of each per run).
        channels: fits.iter().fold(Vec::new(), |mut v: Vec<String>, f| {
            if !v.contains(&f.channel) {
                v.push(f.channel.clone());
            }
            v
        }),
        white: largest(white.into_iter()).ok_or("no channel")?,
        random_walk: largest(rw.into_iter()).ok_or("no channel")?,
        bias_instability: largest(bi.into_iter()).ok_or("no channel")?,
        per_axis,
        tau_min_s: tau_min,
    })
}

/// The noise model of an IMU: gyro and accelerometer (either may be absent), and the rate.
#[derive(Debug, Clone, PartialEq)]
pub struct ImuNoise {
    pub gyro: Option<KindNoise>,
    pub accel: Option<KindNoise>,
    /// Samples per second (1 / tau0).
    pub update_rate_hz: f64,
}

fn note(t: &Taken) -> &'static str {
    if t.bound {
        "; not determined: its upper 95% bound"
    } else {
        ""
    }
}

fn need<'a>(n: &'a Option<KindNoise>, what: &str) -> Result<&'a KindNoise, String> {
    n.as_ref().ok_or_else(|| {
        format!("this format needs {what} channels: name them with --{what} or analyze them in a unit the tool knows")
    })
}

fn source_comment(out: &mut String, imu: &ImuNoise) {
    let names = |k: &Option<KindNoise>| k.as_ref().map_or("-".into(), |k| k.channels.join(","));
    let _ = writeln!(
        out,
        "# allanscope export: gyro {}, accelerometer {}; the largest over the channels; \
         continuous-time densities (docs/export.md)",
        names(&imu.gyro),
        names(&imu.accel)
    );
}

/// Kalibr's `imu.yaml` (Kalibr wiki, "IMU Noise Model" and "YAML formats").
pub fn kalibr(imu: &ImuNoise) -> Result<String, String> {
    let (g, a) = (need(&imu.gyro, "gyro")?, need(&imu.accel, "accel")?);
    let mut o = String::new();
    source_comment(&mut o, imu);
    let _ = writeln!(o, "rostopic: /imu0");
    let _ = writeln!(o, "update_rate: {:?}  # Hz", imu.update_rate_hz);
    let _ = writeln!(
        o,
        "accelerometer_noise_density: {:e}  # m/s^2/sqrt(Hz){}",
        a.white.si,
        note(&a.white)
    );
    let _ = writeln!(
        o,
        "accelerometer_random_walk: {:e}  # m/s^3/sqrt(Hz){}",
        a.random_walk.si,
        note(&a.random_walk)
    );
    let _ = writeln!(
        o,
        "gyroscope_noise_density: {:e}  # rad/s/sqrt(Hz){}",
        g.white.si,
        note(&g.white)
    );
    let _ = writeln!(
        o,
        "gyroscope_random_walk: {:e}  # rad/s^2/sqrt(Hz){}",
        g.random_walk.si,
        note(&g.random_walk)
    );
    Ok(o)
}

/// OpenVINS's `kalibr_imu_chain.yaml` (OpenCV `%YAML:1.0` file; the same four densities as
/// Kalibr, continuous time, under `imu0`, and the IMU intrinsics its parser requires, as an ideal
/// IMU; the layout of its configs' `kalibr_imu_chain.yaml`, docs/export.md).
pub fn openvins(imu: &ImuNoise) -> Result<String, String> {
    let (g, a) = (need(&imu.gyro, "gyro")?, need(&imu.accel, "accel")?);
    let mut o = String::from("%YAML:1.0\n");
    source_comment(&mut o, imu);
    let _ = writeln!(o, "imu0:");
    let _ = writeln!(o, "  T_i_b:");
    for row in [
        "[1.0, 0.0, 0.0, 0.0]",
        "[0.0, 1.0, 0.0, 0.0]",
        "[0.0, 0.0, 1.0, 0.0]",
        "[0.0, 0.0, 0.0, 1.0]",
    ] {
        let _ = writeln!(o, "    - {row}");
    }
    for (k, t, u) in [
        ("accelerometer_noise_density", a.white, "m/s^2/sqrt(Hz)"),
        ("accelerometer_random_walk", a.random_walk, "m/s^3/sqrt(Hz)"),
        ("gyroscope_noise_density", g.white, "rad/s/sqrt(Hz)"),
        ("gyroscope_random_walk", g.random_walk, "rad/s^2/sqrt(Hz)"),
    ] {
        let _ = writeln!(o, "  {k}: {:e}  # {u}{}", t.si, note(&t));
    }
    let _ = writeln!(o, "  rostopic: /imu0");
    let _ = writeln!(o, "  time_offset: 0.0");
    let _ = writeln!(o, "  update_rate: {:?}", imu.update_rate_hz);
    let _ = writeln!(o, "  model: \"kalibr\"");
    // The IMU intrinsics OpenVINS requires under imu0 (its parser reads them as required keys):
    // an ideal IMU, since an Allan analysis measures none of them (docs/export.md).
    let _ = writeln!(
        o,
        "  # IMU intrinsics: not measured by an Allan analysis; an ideal IMU (identities, no g-sensitivity)"
    );
    let identity = ["[1.0, 0.0, 0.0]", "[0.0, 1.0, 0.0]", "[0.0, 0.0, 1.0]"];
    for (k, rows) in [
        ("Tw", identity),
        ("R_IMUtoGYRO", identity),
        ("Ta", identity),
        ("R_IMUtoACC", identity),
        ("Tg", ["[0.0, 0.0, 0.0]"; 3]),
    ] {
        let _ = writeln!(o, "  {k}:");
        for r in rows {
            let _ = writeln!(o, "    - {r}");
        }
    }
    Ok(o)
}

/// VINS-Mono / VINS-Fusion's noise keys `acc_n`, `gyr_n`, `acc_w`, `gyr_w` (continuous time, the
/// same densities as Kalibr's), to paste into its config.
pub fn vins(imu: &ImuNoise) -> Result<String, String> {
    let (g, a) = (need(&imu.gyro, "gyro")?, need(&imu.accel, "accel")?);
    let mut o = String::from("%YAML:1.0\n");
    source_comment(&mut o, imu);
    for (k, t, u) in [
        ("acc_n", a.white, "m/s^2/sqrt(Hz)"),
        ("gyr_n", g.white, "rad/s/sqrt(Hz)"),
        ("acc_w", a.random_walk, "m/s^3/sqrt(Hz)"),
        ("gyr_w", g.random_walk, "rad/s^2/sqrt(Hz)"),
    ] {
        let _ = writeln!(o, "{k}: {:e}  # {u}{}", t.si, note(&t));
    }
    Ok(o)
}

/// What a KF-GINS line's comment adds for its three values `v` of `k`'s channels: which axes
/// are upper bounds (a term not determined), and that one figure stands for every axis when
/// the unit does not have exactly three channels of that kind (a dead axis left out, say).
fn triad_note(k: &KindNoise, v: &[Taken; 3]) -> String {
    let mut out = String::new();
    if k.per_axis.len() != 3 {
        let _ = write!(
            out,
            "; the largest over {} on every axis",
            k.channels.join(", ")
        );
        if v[0].bound {
            out.push_str(note(&v[0]));
        }
    } else {
        let bounds: Vec<String> = v
            .iter()
            .zip(&k.channels)
            .filter(|(t, _)| t.bound)
            .map(|(_, c)| c.clone())
            .collect();
        if !bounds.is_empty() {
            let _ = write!(
                out,
                "; not determined on {}: its upper 95% bound",
                bounds.join(", ")
            );
        }
    }
    out
}

/// Three values per axis: the channels' own when there are exactly three, else the largest
/// three times.
fn triad(k: &KindNoise, pick: impl Fn(&(Taken, Taken)) -> Taken, all: Taken) -> [Taken; 3] {
    if k.per_axis.len() == 3 {
        std::array::from_fn(|i| pick(&k.per_axis[i]))
    } else {
        [all; 3]
    }
}

/// KF-GINS's `imunoise` block (its `kf-gins.yaml`): `arw` deg/sqrt(h), `vrw` m/s/sqrt(h), `gbstd`
/// deg/h, `abstd` mGal, `corrtime` h. KF-GINS models the biases as first-order Gauss-Markov
/// processes of standard deviation `gbstd`/`abstd` and correlation time `corrtime`: the bias
/// instability B is taken as that standard deviation and the tau of the Allan minimum as the
/// correlation time (1 h when no read-out gives it); scale-factor terms (`gsstd`, `asstd`) are
/// not measured here and are written as zeros, commented, since KF-GINS requires the keys.
pub fn kf_gins(imu: &ImuNoise) -> Result<String, String> {
    let (g, a) = (need(&imu.gyro, "gyro")?, need(&imu.accel, "accel")?);
    let conv = |f: fn(f64) -> f64| move |t: Taken| Taken { si: f(t.si), ..t };
    let arw = triad(g, |p| p.0, g.white).map(conv(|x| x.to_degrees() * 60.0));
    let vrw = triad(a, |p| p.0, a.white).map(conv(|x| x * 60.0));
    let gb = triad(g, |p| p.1, g.bias_instability).map(conv(|x| x.to_degrees() * 3600.0));
    // 1 mGal = 1e-5 m/s^2.
    let ab = triad(a, |p| p.1, a.bias_instability).map(conv(|x| x / 1e-5));
    let corr_h = g
        .tau_min_s
        .into_iter()
        .chain(a.tau_min_s)
        .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.max(t))))
        .map_or(1.0, |s| s / 3600.0);
    let v3 = |v: [Taken; 3]| format!("[{:e}, {:e}, {:e}]", v[0].si, v[1].si, v[2].si);
    let mut o = String::new();
    source_comment(&mut o, imu);
    let _ = writeln!(o, "imunoise:");
    let _ = writeln!(
        o,
        "  arw: {}  # deg/sqrt(hr){}",
        v3(arw),
        triad_note(g, &arw)
    );
    let _ = writeln!(
        o,
        "  vrw: {}  # m/s/sqrt(hr){}",
        v3(vrw),
        triad_note(a, &vrw)
    );
    let _ = writeln!(o, "  gbstd: {}  # deg/hr{}", v3(gb), triad_note(g, &gb));
    let _ = writeln!(o, "  abstd: {}  # mGal{}", v3(ab), triad_note(a, &ab));
    // KF-GINS reads the scale-factor keys with the others and refuses the block without them;
    // an Allan analysis does not measure them (docs/export.md): zeros, said so here and by the
    // command's warning.
    for k in ["gsstd", "asstd"] {
        let _ = writeln!(
            o,
            "  {k}: [0.0, 0.0, 0.0]  # ppm; NOT MEASURED (an Allan analysis cannot): set your unit's scale-factor instability"
        );
    }
    let _ = writeln!(o, "  corrtime: {corr_h:e}  # hr");
    Ok(o)
}

/// The final curves as CSV: `channel,unit,stat,tau_s,sigma,lo,hi,edf,count,alpha` (sigma in
/// the channel's unit per second; empty cells where an interval or edf is undefined).
pub fn curves_csv(curves: &[&CurveRecord]) -> String {
    let mut o = String::from("channel,unit,stat,tau_s,sigma,lo,hi,edf,count,alpha\n");
    let opt = |v: Option<f64>| v.map(|x| format!("{x:e}")).unwrap_or_default();
    for c in curves {
        for i in 0..c.tau.len() {
            let _ = writeln!(
                o,
                "{},{},{},{:e},{:e},{},{},{},{},{}",
                csv_field(&c.channel),
                csv_field(&c.unit),
                c.stat.name(),
                c.tau[i],
                c.sigma[i],
                opt(c.lo[i]),
                opt(c.hi[i]),
                opt(c.edf[i]),
                c.count[i],
                c.alpha[i]
            );
        }
    }
    o
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The final curves in Stable32's table layout, one table per channel and statistic: `#`
/// header lines, then the columns `AF Tau # Alpha MinSigma Sigma MaxSigma` (averaging factor m,
/// tau in s, number of differences, noise exponent of S_y, the interval and the deviation).
/// The confidence factor is 0.95 (Stable32 prints 0.683 by default).
pub fn stable32(curves: &[&CurveRecord]) -> String {
    let mut o = String::new();
    for c in curves {
        let kind = match c.stat.name() {
            "avar" => "Overlapping Allan",
            "hvar" => "Overlapping Hadamard",
            "mvar" => "Modified Allan",
            other => other,
        };
        let _ = writeln!(o, "# allanscope (Stable32 column layout)");
        let _ = writeln!(o, "# Channel: {} ({})", c.channel, native_units(&c.unit)[2]);
        let _ = writeln!(o, "# Sigma Type: {kind}");
        let _ = writeln!(o, "# Confidence Factor = 0.95");
        let _ = writeln!(o, "#");
        let _ = writeln!(
            o,
            "#  AF        Tau        #    Alpha  Min Sigma      Sigma         Max Sigma"
        );
        let e = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.4e}"));
        for i in 0..c.tau.len() {
            let _ = writeln!(
                o,
                "{:>5}   {:.4e} {:>8}   {:>3}   {:<13} {:.4e}    {}",
                c.m.get(i).copied().unwrap_or(0),
                c.tau[i],
                c.count[i],
                c.alpha[i],
                e(c.lo[i]),
                c.sigma[i],
                e(c.hi[i])
            );
        }
        o.push('\n');
    }
    o
}
