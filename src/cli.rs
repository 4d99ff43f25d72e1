//! The command line: argument parsing and one function per subcommand. `main.rs` only calls
//! [`main_with_args`] and maps errors to exit statuses (CONTRACT.md: 2 for usage and
//! configuration errors, 1 for anything else).

use std::io::{BufRead, BufReader, Read, Write};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use crate::allan::accum::{AccumConfig, Overlap, StatSet, TauSpec, DEFAULT_L};
use crate::analysis::{AnalysisOptions, ChannelSetup, InputKind, RunAnalysis};
use crate::error::UsageError;
use crate::frame::{Decoder, FrameDescriptor};
use crate::input::text::{TextReader, BATCH_ROWS};
use crate::input::Chunk;
use crate::model::aggregate::run_stats;
use crate::model::fit::{FitMethod, FitOptions};
use crate::model::terms::TERM_NAMES;
use crate::sink::json::JsonLines;
use crate::sink::records::{AggregateRecord, HealthRecord, Record};

#[derive(Debug, Parser)]
#[command(
    name = "allanscope",
    version,
    about = "Allan, Hadamard and modified Allan deviations of inertial sensors, live or replayed, \
             with the five-term noise model and its uncertainty"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Replay capture files or text columns through the analysis; each INPUT is one run.
    Analyze(AnalyzeArgs),
    /// Write a capture (frames of a descriptor, or text columns) from a noise model.
    Simulate(SimulateArgs),
}

/// Options shared by the commands that read data (CONTRACT.md).
#[derive(Debug, Args, Clone)]
pub struct DataArgs {
    /// A frame descriptor (a name from config/frames, or a path), or `csv` for text columns.
    #[arg(long, default_value = "csv")]
    pub format: String,
    /// Sampling step in seconds (required for csv; taken from the descriptor for frames).
    #[arg(long)]
    pub tau0: Option<f64>,
    /// Text columns hold rate samples (u/s) instead of increments (u).
    #[arg(long, conflicts_with = "phase")]
    pub rate: bool,
    /// Text columns hold phase (the running sum of increments, u).
    #[arg(long)]
    pub phase: bool,
    /// Unit label of text columns.
    #[arg(long, default_value = "u")]
    pub unit: String,
    /// Cluster sizes: `octave` (powers of two), `decade` (1, 2, 4 per decade) or a list of m.
    #[arg(long, default_value = "octave")]
    pub taus: String,
    /// Only these channels (comma-separated names).
    #[arg(long, value_delimiter = ',')]
    pub channels: Option<Vec<String>>,
    /// `full` (exact, memory grows with the run) or L (bounded memory, stride max(1, m/L)).
    #[arg(long, default_value_t = DEFAULT_L.to_string())]
    pub overlap: String,
    /// Statistics to compute (comma-separated: avar, hvar, mvar).
    #[arg(long, value_delimiter = ',', default_value = "avar,hvar,mvar")]
    pub stats: Vec<String>,
    /// Data-seconds between interim records (replay).
    #[arg(long)]
    pub every: Option<f64>,
    /// Fit method: model (default), paper, slopes, loglog, or none.
    #[arg(long, default_value = "model")]
    pub fit: String,
    /// JSON lines to this file instead of standard output.
    #[arg(long)]
    pub out: Option<PathBuf>,
}

#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// Input files (`-` for standard input); each is one run.
    #[arg(required = true)]
    pub inputs: Vec<String>,
    #[command(flatten)]
    pub data: DataArgs,
}

#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Noise model file (TOML, see config/models/).
    #[arg(long)]
    pub model: PathBuf,
    /// Duration in seconds (suffixes s, min, h accepted: `3h`).
    #[arg(long)]
    pub duration: String,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// `csv` for text columns, or a frame descriptor (`siu8`, `kvh1750`, a path).
    #[arg(long, default_value = "csv")]
    pub format: String,
    /// Output file.
    #[arg(short = 'o', long = "out")]
    pub out: PathBuf,
}

/// Parses `args` and runs the command.
pub fn main_with_args<I, T>(args: I) -> Result<()>
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let cli = Cli::try_parse_from(args).map_err(|e| {
        use clap::error::ErrorKind;
        if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
            let _ = e.print();
            std::process::exit(0);
        }
        anyhow::Error::new(UsageError::Option(e.to_string()))
    })?;
    match cli.command {
        Command::Analyze(a) => analyze(&a),
        Command::Simulate(s) => simulate(&s),
    }
}

fn usage(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(UsageError::Option(msg.into()))
}

/// Parses `--taus`.
pub fn parse_taus(s: &str) -> Result<TauSpec> {
    match s {
        "octave" => Ok(TauSpec::Octave),
        "decade" => Ok(TauSpec::Decade),
        list => {
            let ms: Result<Vec<u64>, _> =
                list.split(',').map(|t| t.trim().parse::<u64>()).collect();
            match ms {
                Ok(v) if !v.is_empty() && v.iter().all(|&m| m >= 1) => Ok(TauSpec::List(v)),
                _ => Err(usage(format!(
                    "--taus `{list}`: expected octave, decade or a comma list of cluster sizes m >= 1"
                ))),
            }
        }
    }
}

/// Parses `--overlap`.
pub fn parse_overlap(s: &str) -> Result<Overlap> {
    match s {
        "full" => Ok(Overlap::Full),
        l => match l.parse::<u64>() {
            Ok(l) if l >= 1 => Ok(Overlap::Bounded(l)),
            _ => Err(usage(format!(
                "--overlap `{l}`: expected `full` or an integer L >= 1"
            ))),
        },
    }
}

fn parse_stats(list: &[String]) -> Result<StatSet> {
    let mut set = StatSet {
        avar: false,
        hvar: false,
        mvar: false,
    };
    for s in list {
        match s.trim() {
            "avar" => set.avar = true,
            "hvar" => set.hvar = true,
            "mvar" => set.mvar = true,
            other => {
                return Err(usage(format!(
                    "--stats: unknown statistic `{other}` (allowed: avar, hvar, mvar)"
                )))
            }
        }
    }
    if !(set.avar || set.hvar || set.mvar) {
        return Err(usage("--stats: at least one statistic"));
    }
    Ok(set)
}

/// Parses a duration: seconds, or a number with `s`, `min`, `h` or `d`.
pub fn parse_duration_s(s: &str) -> Result<f64> {
    let t = s.trim();
    let (num, mult) = if let Some(v) = t.strip_suffix("min") {
        (v, 60.0)
    } else if let Some(v) = t.strip_suffix('h') {
        (v, 3600.0)
    } else if let Some(v) = t.strip_suffix('d') {
        (v, 86400.0)
    } else if let Some(v) = t.strip_suffix('s') {
        (v, 1.0)
    } else {
        (t, 1.0)
    };
    match num.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v * mult),
        _ => Err(usage(format!(
            "duration `{s}`: expected a positive number of seconds, or with s, min, h or d"
        ))),
    }
}

/// The analysis options common to every run of a command.
fn analysis_options(d: &DataArgs, tau0_s: f64) -> Result<AnalysisOptions> {
    if !(tau0_s.is_finite() && tau0_s > 0.0) {
        return Err(usage(format!(
            "--tau0 {tau0_s}: must be a positive number of seconds"
        )));
    }
    let mut accum = AccumConfig::new(tau0_s);
    accum.taus = parse_taus(&d.taus)?;
    accum.overlap = parse_overlap(&d.overlap)?;
    accum.stats = parse_stats(&d.stats)?;
    let fit = match d.fit.as_str() {
        "none" => None,
        m => Some(FitOptions {
            method: m.parse::<FitMethod>().map_err(usage)?,
            ..FitOptions::default()
        }),
    };
    if let Some(e) = d.every {
        if !(e.is_finite() && e > 0.0) {
            return Err(usage(format!(
                "--every {e}: must be a positive number of seconds"
            )));
        }
    }
    Ok(AnalysisOptions {
        accum,
        kind: if d.rate {
            InputKind::Rate
        } else if d.phase {
            InputKind::Phase
        } else {
            InputKind::Increments
        },
        every_s: d.every,
        fit,
        run: None,
    })
}

fn open_input(input: &str) -> Result<Box<dyn Read + Send>> {
    if input == "-" {
        Ok(Box::new(std::io::stdin()))
    } else {
        let f = std::fs::File::open(input).map_err(|e| {
            anyhow::Error::new(UsageError::Input {
                file: input.into(),
                line: 0,
                problem: format!("cannot open: {e}"),
            })
        })?;
        Ok(Box::new(f))
    }
}

fn output(d: &DataArgs) -> Result<JsonLines> {
    Ok(match &d.out {
        Some(p) => {
            let f = std::fs::File::create(p)
                .with_context(|| format!("cannot create output {}", p.display()))?;
            JsonLines::new(Box::new(std::io::BufWriter::new(f)))
        }
        None => JsonLines::stdout(),
    })
}

fn select_channels(
    all: Vec<ChannelSetup>,
    wanted: &Option<Vec<String>>,
    input: &str,
) -> Result<Vec<ChannelSetup>> {
    let Some(w) = wanted else {
        return Ok(all);
    };
    for name in w {
        if !all.iter().any(|c| &c.name == name) {
            return Err(usage(format!(
                "--channels: `{name}` is not a channel of {input} (it has: {})",
                all.iter()
                    .map(|c| c.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
    }
    Ok(all.into_iter().filter(|c| w.contains(&c.name)).collect())
}

/// Capacity of the channel between the reader thread and the analysis: a few chunks, so
/// reading runs ahead of the analysis by at most that much memory.
const CHUNK_QUEUE: usize = 4;

/// Text columns the analysis does not treat as channels (the simulator's temperature column).
const AUXILIARY_COLUMNS: [&str; 1] = ["temperature_c"];

fn analyze(a: &AnalyzeArgs) -> Result<()> {
    let d = &a.data;
    let mut sink = output(d)?;
    let descriptor = if d.format == "csv" {
        None
    } else {
        Some(FrameDescriptor::load(&d.format).map_err(anyhow::Error::new)?)
    };
    let tau0 = match (&descriptor, d.tau0) {
        (_, Some(t)) => t,
        (Some(desc), None) => desc.tau0_s(),
        (None, None) => return Err(usage("--tau0 is required for --format csv")),
    };
    let base = analysis_options(d, tau0)?;
    let several = a.inputs.len() > 1;
    let mut fits = Vec::new();
    for (run, input) in a.inputs.iter().enumerate() {
        let mut opts = base.clone();
        opts.run = several.then_some(run);
        let analysis = match &descriptor {
            None => analyze_text(input, d, opts, &mut sink)?,
            Some(desc) => analyze_frames(input, desc, d, opts, &mut sink)?,
        };
        fits.push(analysis.last_fits());
    }
    if several {
        for r in aggregate_records(&fits) {
            sink.write(&r)?;
        }
    }
    sink.flush()?;
    Ok(())
}

/// Reads a text input on a thread of its own and feeds the analysis on this one.
fn analyze_text(
    input: &str,
    d: &DataArgs,
    opts: AnalysisOptions,
    sink: &mut JsonLines,
) -> Result<RunAnalysis> {
    let path = PathBuf::from(input);
    let reader = TextReader::new(BufReader::with_capacity(1 << 16, open_input(input)?), &path)
        .map_err(anyhow::Error::new)?;
    let setups: Vec<ChannelSetup> = reader
        .names()
        .iter()
        .enumerate()
        .filter(|(_, n)| !AUXILIARY_COLUMNS.contains(&n.as_str()))
        .map(|(i, n)| ChannelSetup {
            name: n.clone(),
            unit: d.unit.clone(),
            column: i,
            counts_lsb: None,
        })
        .collect();
    let setups = select_channels(setups, &d.channels, input)?;
    let width = reader.names().len();
    let mut analysis = RunAnalysis::new(input, setups, opts);
    let (tx, rx) = crossbeam_channel::bounded::<Chunk>(CHUNK_QUEUE);
    let reader_thread = std::thread::spawn(move || -> Result<u64> {
        let mut reader = reader;
        loop {
            let mut values = Vec::with_capacity(BATCH_ROWS * width);
            let n = reader
                .read_rows(&mut values, BATCH_ROWS)
                .with_context(|| format!("reading {}", path.display()))?;
            if n == 0 {
                return Ok(reader.bad_rows());
            }
            if tx.send(Chunk::Rows { values, width }).is_err() {
                return Ok(reader.bad_rows());
            }
        }
    });
    run_chunks(&mut analysis, rx, sink)?;
    let bad = reader_thread
        .join()
        .map_err(|_| anyhow::anyhow!("the reader thread panicked"))??;
    analysis.add_bad_rows(bad);
    finish_run(&mut analysis, None, sink)?;
    Ok(analysis)
}

/// Replays a capture of frames: a reader thread decodes, the analysis runs here.
fn analyze_frames(
    input: &str,
    desc: &FrameDescriptor,
    d: &DataArgs,
    opts: AnalysisOptions,
    sink: &mut JsonLines,
) -> Result<RunAnalysis> {
    let setups: Vec<ChannelSetup> = desc
        .channels()
        .into_iter()
        .enumerate()
        .map(|(i, c)| ChannelSetup {
            name: c.name,
            unit: c.unit,
            column: i,
            counts_lsb: c.scale,
        })
        .collect();
    let setups = select_channels(setups, &d.channels, input)?;
    let mut analysis = RunAnalysis::new(input, setups, opts);
    let mut src = open_input(input)?;
    let mut decoder = Decoder::new(desc.clone());
    let (tx, rx) = crossbeam_channel::bounded::<Chunk>(CHUNK_QUEUE);
    let path = input.to_string();
    let reader_thread = std::thread::spawn(move || -> Result<Decoder> {
        let mut buf = vec![0u8; 1 << 16];
        loop {
            let n = src
                .read(&mut buf)
                .with_context(|| format!("reading {path}"))?;
            if n == 0 {
                decoder.finish();
            } else {
                decoder.push(&buf[..n]);
            }
            let events: Vec<_> = decoder.drain().collect();
            if !events.is_empty() && tx.send(Chunk::Frames(events)).is_err() {
                return Ok(decoder);
            }
            if n == 0 {
                return Ok(decoder);
            }
        }
    });
    run_chunks(&mut analysis, rx, sink)?;
    let decoder = reader_thread
        .join()
        .map_err(|_| anyhow::anyhow!("the reader thread panicked"))??;
    let h = decoder.health();
    let mut health = HealthRecord {
        kind: "health".into(),
        frames: h.frames,
        crc_errors: h.crc_errors,
        resyncs: h.resyncs,
        missing: h.missing,
        duplicates: h.duplicates,
        bytes_skipped: h.bytes_skipped,
        extra: serde_json::Map::new(),
        run: analysis.summary().run,
    };
    if let Ok(serde_json::Value::Object(all)) = serde_json::to_value(h) {
        for (k, v) in all {
            if !matches!(
                k.as_str(),
                "frames" | "crc_errors" | "resyncs" | "missing" | "duplicates" | "bytes_skipped"
            ) {
                health.extra.insert(k, v);
            }
        }
    }
    finish_run(&mut analysis, Some(health), sink)?;
    Ok(analysis)
}

fn run_chunks(
    analysis: &mut RunAnalysis,
    rx: crossbeam_channel::Receiver<Chunk>,
    sink: &mut JsonLines,
) -> Result<()> {
    let mut out = Vec::new();
    for chunk in rx {
        analysis.push_chunk(&chunk, &mut out);
        if !out.is_empty() {
            for r in out.drain(..) {
                sink.write(&r)?;
            }
            sink.flush()?;
        }
    }
    Ok(())
}

fn finish_run(
    analysis: &mut RunAnalysis,
    health: Option<HealthRecord>,
    sink: &mut JsonLines,
) -> Result<()> {
    for r in analysis.records(true) {
        sink.write(&r)?;
    }
    if let Some(h) = health {
        sink.write(&h)?;
    }
    sink.write(&analysis.summary())?;
    sink.flush()?;
    Ok(())
}

/// `aggregate` records (the seed paper's table 2) from the final fits of several runs.
pub fn aggregate_records(
    runs: &[Vec<(String, String, Option<crate::model::fit::FitResult>)>],
) -> Vec<Record> {
    let mut out = Vec::new();
    let Some(first) = runs.first() else {
        return out;
    };
    for (ci, (name, unit, _)) in first.iter().enumerate() {
        for (ti, term) in TERM_NAMES.iter().enumerate() {
            let values: Vec<Option<f64>> = runs
                .iter()
                .map(|r| {
                    r.get(ci)
                        .filter(|(n, _, _)| n == name)
                        .and_then(|(_, _, f)| f.as_ref())
                        .filter(|f| f.coef[ti].determined)
                        .map(|f| f.coef[ti].value)
                })
                .collect();
            let s = run_stats(&values);
            out.push(Record::Aggregate(AggregateRecord {
                kind: "aggregate".into(),
                channel: name.clone(),
                unit: unit.clone(),
                coef: (*term).into(),
                n: s.as_ref().map_or(0, |s| s.n),
                mean: s.as_ref().map(|s| s.mean),
                sd: s.as_ref().and_then(|s| s.sd),
                ci_t: s.as_ref().and_then(|s| s.ci_t),
                ci_z: s.as_ref().and_then(|s| s.ci_z),
            }));
        }
    }
    out
}

fn simulate(s: &SimulateArgs) -> Result<()> {
    let duration = parse_duration_s(&s.duration)?;
    let model = crate::sim::SimModel::load(&s.model)?;
    let f = std::fs::File::create(&s.out)
        .with_context(|| format!("cannot create {}", s.out.display()))?;
    let mut w = std::io::BufWriter::with_capacity(1 << 16, f);
    let steps = if s.format == "csv" {
        crate::sim::simulate_to_writer(
            &model,
            duration,
            s.seed,
            crate::sim::OutputFormat::Csv,
            &mut w,
        )?
    } else {
        let desc = FrameDescriptor::load(&s.format).map_err(anyhow::Error::new)?;
        crate::sim::capture::simulate_to_frames(&model, &desc, duration, s.seed, &mut w)?
    };
    w.flush()?;
    tracing::info!("{}: {steps} steps written", s.out.display());
    Ok(())
}

/// Reads a whole text file of JSON lines into values (for `aggregate`, `plot`, tests).
pub fn read_json_lines(path: &Path) -> Result<Vec<serde_json::Value>> {
    let f = std::fs::File::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let mut out = Vec::new();
    for (i, line) in BufReader::new(f).lines().enumerate() {
        let line = line?;
        if line.trim().is_empty() {
            continue;
        }
        out.push(serde_json::from_str(&line).map_err(|e| {
            anyhow::Error::new(UsageError::Input {
                file: path.into(),
                line: i as u64 + 1,
                problem: format!("not a JSON record: {e}"),
            })
        })?);
    }
    Ok(out)
}
