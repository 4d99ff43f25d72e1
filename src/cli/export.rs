//! `export`: the fitted noise model of a results file in another tool's format (Kalibr,
//! OpenVINS, VINS, KF-GINS), or its curves as CSV or a Stable32-style table (sink::export).

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;

use super::usage;
use allanscope::model::units::{IncrementUnit, SensorKind};
use allanscope::sink::export::{self, ExportFormat, ImuNoise};
use allanscope::sink::records::{CurveRecord, FitRecord};

#[derive(Debug, Args)]
pub struct ExportArgs {
    /// A JSON-lines file written by `analyze`, `listen` or `run` (its final records are used).
    pub input: PathBuf,
    /// kalibr | openvins | vins | kf-gins | csv | stable32.
    #[arg(long)]
    pub to: String,
    /// The file to write (never overwritten without --force).
    #[arg(short = 'o', long = "out")]
    pub out: PathBuf,
    /// Gyro channels (comma-separated; default: every channel in an angle unit).
    #[arg(long, value_delimiter = ',')]
    pub gyro: Option<Vec<String>>,
    /// Accelerometer channels (default: every channel in a velocity unit).
    #[arg(long, value_delimiter = ',')]
    pub accel: Option<Vec<String>>,
    /// The unit to export from the results of a stand config with several units (`[[unit]]`
    /// tables; records carrying `"unit": NAME`). Needed when the file holds more than one.
    #[arg(long, value_name = "NAME")]
    pub stand_unit: Option<String>,
    /// Replace an existing output file.
    #[arg(long)]
    pub force: bool,
}

fn kind_of(f: &FitRecord) -> Option<SensorKind> {
    IncrementUnit::parse(&f.unit).map(|u| u.kind)
}

/// `label` of each fit, each label once, in the order the fits come.
fn distinct(fits: &[&FitRecord], label: impl Fn(&FitRecord) -> String) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for f in fits {
        let l = label(f);
        if !out.contains(&l) {
            out.push(l);
        }
    }
    out
}

/// The fits of one kind: the named channels, or every channel of that kind.
fn chosen<'a>(
    fits: &[&'a FitRecord],
    names: &Option<Vec<String>>,
    kind: SensorKind,
    flag: &str,
) -> Result<Vec<&'a FitRecord>> {
    match names {
        // Every fit of each named channel: a file of several runs gives one per run, and the
        // largest over them is exported, as without names.
        Some(names) => {
            let mut out = Vec::new();
            for n in names {
                let mine: Vec<&FitRecord> =
                    fits.iter().copied().filter(|f| &f.channel == n).collect();
                if mine.is_empty() {
                    let have = distinct(fits, |f| f.channel.clone());
                    return Err(usage(format!(
                        "--{flag} {n}: no final fit of that channel in the input (it has: {})",
                        have.join(", ")
                    )));
                }
                out.extend(mine);
            }
            Ok(out)
        }
        None => Ok(fits
            .iter()
            .copied()
            .filter(|f| kind_of(f) == Some(kind))
            .collect()),
    }
}

pub fn run(a: &ExportArgs) -> Result<()> {
    let format: ExportFormat = a.to.parse().map_err(usage)?;
    allanscope::sink::page_file::check_target(&a.out, "-o")?;
    let stdout = a.out == Path::new("-");
    if !a.force && !stdout && a.out.exists() {
        return Err(usage(format!(
            "{} exists: give --force to replace it",
            a.out.display()
        )));
    }
    let mut fits: Vec<FitRecord> = Vec::new();
    let mut curves: Vec<CurveRecord> = Vec::new();
    let mut diagnoses = 0usize;
    let mut tau0: Option<f64> = None;
    let tag = a.input.display().to_string();
    // A run of several units: one unit is exported (--stand-unit), by its name.
    let mut units: Vec<String> = Vec::new();
    // A record of a known type that does not read (another version's file): its line named.
    let bad = |line: u64, what: &str, e: serde_json::Error| {
        anyhow::Error::new(allanscope::error::UsageError::Input {
            file: a.input.clone(),
            line,
            problem: format!(
                "a {what} record that does not read ({e}): a file written by another version of \
                 allanscope? rerun the analysis"
            ),
        })
    };
    for (line, mut v) in super::numbered_json_lines(&a.input)? {
        if let Some(u) = allanscope::sink::unit_record::untag(&mut v) {
            if !units.contains(&u) {
                units.push(u.clone());
            }
            if a.stand_unit.as_deref().is_some_and(|w| w != u) {
                continue;
            }
        }
        match v.get("type").and_then(|t| t.as_str()) {
            Some("fit") if v["final"] == true => {
                let f: FitRecord = serde_json::from_value(v).map_err(|e| bad(line, "fit", e))?;
                // A later final fit of the same channel and run replaces an earlier one.
                fits.retain(|g| !(g.channel == f.channel && g.run == f.run));
                fits.push(f);
            }
            Some("curve") if v["final"] == true => {
                let c: CurveRecord =
                    serde_json::from_value(v).map_err(|e| bad(line, "curve", e))?;
                curves.retain(|g| !(g.channel == c.channel && g.run == c.run && g.stat == c.stat));
                curves.push(c);
            }
            Some("summary") => tau0 = v.get("tau0").and_then(|t| t.as_f64()).or(tau0),
            Some("diagnosis") => diagnoses += 1,
            _ => {}
        }
    }
    // `diagnose` writes diagnoses alone: say what to run for the records export reads.
    let hint = if diagnoses > 0 {
        format!(
            " (it holds {diagnoses} diagnosis record{}, as `diagnose` writes: export reads the \
             fit and curve records of `analyze`, `listen` or `run`; `allanscope analyze INPUT \
             --out FILE` writes them, with `--diagnose` the diagnoses beside them)",
            if diagnoses == 1 { "" } else { "s" }
        )
    } else {
        String::new()
    };
    match (&a.stand_unit, units.len()) {
        (None, n) if n > 1 => {
            return Err(usage(format!(
                "{tag} holds {n} units ({}): choose one with --stand-unit NAME",
                units.join(", ")
            )))
        }
        (Some(w), _) if !units.contains(w) => {
            return Err(usage(format!(
                "--stand-unit {w}: {tag} has no unit of that name ({})",
                if units.is_empty() {
                    "it holds the records of one unnamed unit".to_string()
                } else {
                    format!("it has: {}", units.join(", "))
                }
            )))
        }
        _ => {}
    }
    let text = match format {
        ExportFormat::Csv | ExportFormat::Stable32 => {
            if curves.is_empty() {
                return Err(usage(format!(
                    "{tag}: no final curve records to export{hint}"
                )));
            }
            let refs: Vec<&CurveRecord> = curves.iter().collect();
            if format == ExportFormat::Csv {
                export::curves_csv(&refs)
            } else {
                export::stable32(&refs)
            }
        }
        _ => {
            if fits.is_empty() {
                return Err(usage(format!(
                    "{tag}: no final fit records to export{hint}"
                )));
            }
            let runs: std::collections::BTreeSet<Option<usize>> =
                fits.iter().map(|f| f.run).collect();
            if runs.len() > 1 {
                tracing::warn!(
                    "{tag} holds {} runs; exporting the largest figure over all of them",
                    runs.len()
                );
            }
            let refs: Vec<&FitRecord> = fits.iter().collect();
            let gyro = chosen(&refs, &a.gyro, SensorKind::Gyro, "gyro")?;
            let accel = chosen(&refs, &a.accel, SensorKind::Accel, "accel")?;
            let noise = |v: &[&FitRecord], k| {
                if v.is_empty() {
                    Ok(None)
                } else {
                    export::kind_noise(v, k).map(Some).map_err(usage)
                }
            };
            let tau0 = tau0.ok_or_else(|| {
                usage(format!(
                    "{tag}: no summary record gives the sampling step tau0"
                ))
            })?;
            let imu = ImuNoise {
                gyro: noise(&gyro, SensorKind::Gyro)?,
                accel: noise(&accel, SensorKind::Accel)?,
                update_rate_hz: 1.0 / tau0,
            };
            // Warned about: only the terms this format writes (Kalibr, OpenVINS and VINS take N
            // and K; KF-GINS N and B of each axis), and a kind without three axes for KF-GINS.
            let per_axis = format == ExportFormat::KfGins;
            for k in [&imu.gyro, &imu.accel].into_iter().flatten() {
                if per_axis {
                    for (c, (n, b)) in k.channels.iter().zip(&k.per_axis) {
                        for (name, t) in [("N", n), ("B", b)] {
                            if t.bound {
                                tracing::warn!(
                                    "{c}: {name} is not determined; its upper 95% bound is \
                                     exported"
                                );
                            }
                        }
                    }
                    if k.per_axis.len() != 3 {
                        tracing::warn!(
                            "{}: {} channel(s) where KF-GINS takes three axes: the largest is \
                             written for every axis",
                            k.channels.join(","),
                            k.per_axis.len()
                        );
                    }
                } else {
                    for (name, t) in [("N", k.white), ("K", k.random_walk)] {
                        if t.bound {
                            tracing::warn!(
                                "{}: {name} is not determined; its upper 95% bound is exported",
                                k.channels.join(",")
                            );
                        }
                    }
                }
            }
            match format {
                ExportFormat::Kalibr => export::kalibr(&imu),
                ExportFormat::OpenVins => export::openvins(&imu),
                ExportFormat::Vins => export::vins(&imu),
                _ => export::kf_gins(&imu),
            }
            .map_err(|e| {
                let have = distinct(&refs, |f| format!("{} [{}]", f.channel, f.unit));
                usage(format!("{tag}: {e} (its fits: {})", have.join(", ")))
            })?
        }
    };
    if stdout {
        let mut out = std::io::stdout().lock();
        out.write_all(text.as_bytes())
            .and_then(|()| out.flush())
            .context("cannot write to standard output")?;
        return Ok(());
    }
    let mut f = if a.force {
        std::fs::File::create(&a.out)
    } else {
        std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&a.out)
    }
    .with_context(|| format!("cannot write {}", a.out.display()))?;
    f.write_all(text.as_bytes())
        .with_context(|| format!("cannot write {}", a.out.display()))?;
    tracing::info!("{}: written ({})", a.out.display(), a.to);
    if format == ExportFormat::KfGins {
        tracing::warn!(
            "{}: gsstd and asstd (scale-factor instability, ppm) are written as 0: an Allan \
             analysis does not measure them; set them from the unit's datasheet",
            a.out.display()
        );
    }
    Ok(())
}
