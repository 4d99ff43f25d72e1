//! The command line (a module of the binary, not of the library): argument parsing here, one file
//! per subcommand beside it, each over `allanscope::...`. `main.rs` only calls
//! [`main_with_args`] and maps errors to exit statuses (docs/records.md: 2 for usage and
//! configuration errors, 1 for anything else).

mod aggregate;
mod analyze;
mod diagnose;
mod export;
mod listen;
mod metrics;
mod plot;
mod process;
mod report;
mod run;
mod simulate;
mod status;
pub use status::LogWriter;
mod terminal;

use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args, Parser, Subcommand};

use allanscope::allan::accum::{Overlap, StatSet, TauSpec, DEFAULT_L};
use allanscope::analysis::ChannelSetup;
use allanscope::analysis::{AnalysisOptions, InputKind};
use allanscope::error::UsageError;
use allanscope::frame::FrameDescriptor;
use allanscope::input::header_unit::{header_unit, units_from_headers, HeaderUnit};
use allanscope::input::px4_export;
use allanscope::input::text::{ColumnPick, TextOptions, TextReader};
use allanscope::model::fit::FitMethod;
use allanscope::plan::checkpoint_setup::CheckpointRequest;
use allanscope::plan::settings::DataSettings;
use allanscope::plan::unit::UnitRequest;
use allanscope::sink::output::{ReadFile, WrittenFile};

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
    /// Live from a serial port, a UDP socket or standard input, until SIGINT/SIGTERM or
    /// --duration; then the final records.
    Listen(listen::ListenArgs),
    /// The same, with sources, channels, statistics, outputs and limits from a stand config.
    Run(run::RunArgs),
    /// Write a capture (frames of a descriptor, or text columns) from a noise model.
    Simulate(SimulateArgs),
    /// The sim-to-real gap of each channel: where, which effect, how much it shrinks.
    Diagnose(DiagnoseArgs),
    /// Allan-deviation plot (SVG) from the JSON lines allanscope wrote.
    Plot(PlotArgs),
    /// One self-contained HTML page: plots, coefficient tables, diagnosis, pass/fail.
    Report(ReportArgs),
    /// Run-to-run statistics (the seed paper's table 2) from the final `fit` records of several
    /// runs, one JSON-lines file per run.
    Aggregate(AggregateArgs),
    /// The fitted noise model in another tool's format (Kalibr, OpenVINS, VINS, KF-GINS), or
    /// the curves as CSV or a Stable32-style table.
    Export(export::ExportArgs),
}

#[derive(Debug, Args)]
pub struct ReportArgs {
    /// JSON-lines files written by allanscope (one section each).
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// The HTML file to write.
    #[arg(short = 'o', long = "out")]
    pub out: PathBuf,
    /// Title of the page.
    #[arg(long, default_value = "allanscope test report")]
    pub title: String,
    /// Overwrite an existing non-empty -o file.
    #[arg(long)]
    pub force: bool,
}

#[derive(Debug, Args)]
pub struct DiagnoseArgs {
    /// The run to diagnose (text columns or a capture; `-` for standard input).
    pub input: String,
    /// Only these channels (comma-separated).
    #[arg(long, value_delimiter = ',')]
    pub channel: Option<Vec<String>>,
    /// A second run of the same unit, on which the effects fitted on INPUT are judged (its
    /// channels matched to INPUT's by name).
    #[arg(long)]
    pub holdout: Option<String>,
    /// Write the fitted unit (five terms, LSB, tau0, accepted effects) as a model file that
    /// `simulate --model` reads. An existing file is never overwritten.
    #[arg(long, value_name = "FILE")]
    pub model_out: Option<PathBuf>,
    /// Simulate the fitted unit N times (its five terms alone and with the effects, as long as
    /// the input) and record the measured curve against the 2.5-97.5% band of each (the
    /// record's `ensemble`).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(2..=10000))]
    pub ensemble: Option<u32>,
    #[command(flatten)]
    pub data: DataArgs,
}

#[derive(Debug, Args)]
pub struct PlotArgs {
    /// JSON-lines files written by `analyze` or `listen`.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// The SVG file to write.
    #[arg(short = 'o', long = "out")]
    pub out: PathBuf,
    /// Which statistic: avar, hvar or mvar.
    #[arg(long, default_value = "avar")]
    pub stat: String,
    /// Only these channels.
    #[arg(long, value_delimiter = ',')]
    pub channels: Option<Vec<String>>,
    /// Title on top of the plot.
    #[arg(long)]
    pub title: Option<String>,
    /// Leave out the fitted model lines.
    #[arg(long)]
    pub no_model: bool,
    /// Also draw the dynamic Allan view (time x tau) of each curve, from its interim records
    /// (written with --every): where in the run the noise changed.
    #[arg(long)]
    pub dynamic: bool,
    /// Overwrite an existing non-empty -o file.
    #[arg(long)]
    pub force: bool,
}

#[derive(Debug, Args)]
pub struct AggregateArgs {
    /// JSON-lines files written by `analyze`, one per run.
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// JSON lines to this file instead of standard output (an existing non-empty file is
    /// refused unless --force).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Overwrite a non-empty --out.
    #[arg(long)]
    pub force: bool,
    /// JSON lines even when standard output is a terminal (which otherwise gets a table).
    #[arg(long)]
    pub json: bool,
}

/// Options shared by the commands that read data (docs/records.md).
#[derive(Debug, Args, Clone)]
pub struct DataArgs {
    /// A frame descriptor (a name from config/frames, or a path), or `csv` for text columns.
    #[arg(long, default_value = "csv")]
    pub format: String,
    /// Sampling step in seconds (frames: taken from the descriptor; text columns: read off their
    /// time column when they have one, else required).
    #[arg(long, value_parser = tau0_arg, allow_hyphen_values = true)]
    pub tau0: Option<f64>,
    /// Text columns hold rate samples (u/s) instead of increments (u).
    #[arg(long, conflicts_with = "phase")]
    pub rate: bool,
    /// Text columns hold phase (the running sum of increments, u).
    #[arg(long)]
    pub phase: bool,
    /// Unit of the increment of text columns, also with --rate or --phase: deg, rad, mrad,
    /// arcsec, m/s, ft/s, g (g*s), mg, ug give datasheet units. A rate unit (`deg/s`, `dps`,
    /// `m/s^2`, `deg/h`) reads the columns as rate samples, --rate or not, in its increment unit
    /// (`deg/s` means `deg`). Without it, a unit in brackets in a column's header (`w_RS_S_x [rad s^-1]`, `acc_x[g]`)
    /// is read, rates or increments as it says; else `u`.
    #[arg(long, value_name = "U")]
    pub unit: Option<String>,
    /// Cluster sizes: `octave` (powers of two), `decade` (1, 2, 4 per decade) or a list of m.
    #[arg(long, default_value = "octave")]
    pub taus: String,
    /// Only these channels (comma-separated names).
    #[arg(long, value_delimiter = ',')]
    pub channels: Option<Vec<String>>,
    /// Text columns: the header name of the time column (by default a column named time, t,
    /// timestamp or time_s, in any case): not a channel; a jump of more than 1.5 tau0 in it is
    /// a gap of the missing samples (seconds, or ms, us, ns when its first step says so).
    /// `none`: such a column is skipped and not read, the rows taken as consecutive samples at
    /// --tau0 (a clock in a unit this cannot tell).
    #[arg(long, value_name = "NAME")]
    pub time_column: Option<String>,
    /// Text columns: only these, in this order, renamed with `=`: `gx=g1,gy` reads column
    /// `gx` as channel `g1` and `gy` as `gy`.
    #[arg(long, value_delimiter = ',', value_name = "NAME[=NEW],...")]
    pub columns: Option<Vec<ColumnPick>>,
    /// Found, not given: the channels analysed hold values on every k-th row only (a merged
    /// multi-rate file), so rows where they are all empty are no samples
    /// (`TextOptions::sparse_rows`).
    #[arg(skip)]
    pub sparse_rows: bool,
    /// `full` (exact, memory grows with the run) or L (bounded memory, stride max(1, m/L)).
    #[arg(long, default_value_t = DEFAULT_L.to_string())]
    pub overlap: String,
    /// Statistics to compute (comma-separated: avar, hvar, mvar).
    #[arg(long, value_delimiter = ',', default_value = "avar,hvar,mvar")]
    pub stats: Vec<String>,
    /// Seconds between interim records: data-seconds (analyze), wall-seconds (listen, run).
    #[arg(long, value_parser = interval_arg)]
    pub every: Option<f64>,
    /// Fit method: model (default), paper, slopes, loglog, or none.
    #[arg(long, default_value = "model")]
    pub fit: String,
    /// JSON lines to this file instead of standard output. An existing non-empty file is
    /// refused unless --force (or --resume, which appends); it is only replaced once the input
    /// is open and the first record is written.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Overwrite a non-empty --out (and --capture): without it an earlier result is never
    /// touched.
    #[arg(long)]
    pub force: bool,
    /// JSON lines even when standard output is a terminal (which otherwise gets a readable
    /// table); pipes and files always get JSON lines.
    #[arg(long)]
    pub json: bool,
    /// Datasheet limits (a TOML file with `[[limits]]` tables, as in a stand config), judged
    /// with the fits' intervals; verdicts in `summary`.
    #[arg(long)]
    pub limits: Option<PathBuf>,
    /// Also write `diagnosis` records (the sim-to-real gap) with the fits, interim and final.
    #[arg(long)]
    pub diagnose: bool,
    /// Save the analysis state every S seconds beside the output (`--out FILE` -> FILE.ckpt),
    /// and at the end: data-seconds when replaying a file, wall-seconds live. Written to a
    /// temporary file and renamed, so a crash never leaves a partial checkpoint.
    #[arg(long, value_name = "S", value_parser = interval_arg)]
    pub checkpoint_every: Option<f64>,
    /// Continue the run saved in FILE.ckpt (after a crash): a replayed file from the saved byte
    /// offset, giving the final records of an uninterrupted run; a live source from now on, the
    /// outage a gap. Records are appended to --out. Refused (exit 2) if the options differ.
    #[arg(long)]
    pub resume: bool,
    /// Test hook: abort (as a crash would) once this many frames are decoded (rows read, for
    /// text columns) and a checkpoint is on disk.
    #[arg(long, hide = true, value_name = "N")]
    pub abort_after_frames: Option<u64>,
    /// Serve the latest fits, limit verdicts and decoder health at http://ADDR:PORT/metrics
    /// (Prometheus text format); a bare PORT listens on 127.0.0.1 only.
    #[arg(long, value_name = "ADDR:PORT")]
    pub metrics: Option<String>,
}

#[derive(Debug, Args)]
pub struct AnalyzeArgs {
    /// Input files (`-` for standard input); each is one run.
    #[arg(required = true)]
    pub inputs: Vec<String>,
    /// Replay as fast as possible (`max`) or at the data's own rate (`realtime`).
    #[arg(long, default_value = "max")]
    pub pace: String,
    #[command(flatten)]
    pub data: DataArgs,
}

#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// Noise model file (TOML, see config/models/).
    #[arg(long)]
    pub model: PathBuf,
    /// Duration in seconds (suffixes s, min, h accepted: `3h`).
    #[arg(long, allow_hyphen_values = true)]
    pub duration: String,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// `csv` for text columns, or a frame descriptor (`siu8`, `kvh1750`, a path).
    #[arg(long, default_value = "csv")]
    pub format: String,
    /// Output file. Written beside it under a temporary name and renamed when complete, so a
    /// failed run leaves nothing; an existing file is refused unless --force.
    #[arg(short = 'o', long = "out")]
    pub out: PathBuf,
    /// Replace an existing output file.
    #[arg(long)]
    pub force: bool,
}

impl DataArgs {
    /// How text columns become channels (`--time-column`, `--columns`).
    pub fn text_options(&self) -> TextOptions {
        TextOptions {
            time_column: self.time_column.clone(),
            columns: self.columns.clone(),
            // Text columns need --tau0; with it, jumps of the time column are gaps.
            tau0_s: self.tau0,
            channels: self.channels.clone(),
            sparse_rows: self.sparse_rows,
            phase: self.phase,
        }
    }
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
    // Before anything is read or opened: no output may be one of the inputs.
    let (inputs, outputs) = cli.command.files();
    allanscope::sink::output::refuse_outputs_over_inputs(&outputs, &inputs)?;
    match cli.command {
        Command::Analyze(mut a) => {
            let inputs: Vec<&str> = a.inputs.iter().map(String::as_str).collect();
            text_tau0(&mut a.data, &inputs)?;
            analyze::run(&a)
        }
        Command::Listen(l) => listen::run(&l),
        Command::Run(r) => run::run(&r),
        Command::Simulate(s) => simulate::run(&s),
        Command::Diagnose(mut d) => {
            let mut inputs = vec![d.input.as_str()];
            inputs.extend(d.holdout.as_deref());
            text_tau0(&mut d.data, &inputs)?;
            diagnose::run(&d)
        }
        Command::Plot(p) => plot::run(&p),
        Command::Report(r) => report::run(&r),
        Command::Aggregate(a) => aggregate::run(&a),
        Command::Export(e) => export::run(&e),
    }
}

impl Command {
    /// The files the command reads and the files it writes, named as the options name them, for
    /// [`allanscope::sink::output::refuse_outputs_over_inputs`]. `run` reads its stand config
    /// for them (`run::run`, the same check).
    fn files(&self) -> (Vec<ReadFile>, Vec<WrittenFile>) {
        let mut inputs = Vec::new();
        let mut outputs = Vec::new();
        let written = |option: &str, path: &Path| WrittenFile {
            option: option.into(),
            path: path.to_path_buf(),
        };
        match self {
            Command::Analyze(a) => {
                inputs.extend(a.inputs.iter().map(|i| read_file("the input", i)));
                a.data.files(&mut inputs, &mut outputs);
            }
            Command::Listen(l) => {
                inputs.extend(l.input.as_deref().map(|i| read_file("the input", i)));
                outputs.extend(l.capture.as_deref().map(|p| written("--capture", p)));
                l.data.files(&mut inputs, &mut outputs);
            }
            Command::Run(_) => {}
            Command::Simulate(s) => {
                inputs.push(read_file("--model", &s.model.to_string_lossy()));
                inputs.push(read_file("--format", &s.format));
                outputs.push(written("-o", &s.out));
            }
            Command::Diagnose(d) => {
                inputs.push(read_file("the input", &d.input));
                inputs.extend(d.holdout.as_deref().map(|h| read_file("--holdout", h)));
                outputs.extend(d.model_out.as_deref().map(|p| written("--model-out", p)));
                d.data.files(&mut inputs, &mut outputs);
            }
            Command::Plot(p) => {
                inputs.extend(
                    p.inputs
                        .iter()
                        .map(|i| read_file("the input", &i.to_string_lossy())),
                );
                outputs.push(written("-o", &p.out));
            }
            Command::Report(r) => {
                inputs.extend(
                    r.inputs
                        .iter()
                        .map(|i| read_file("the input", &i.to_string_lossy())),
                );
                outputs.push(written("-o", &r.out));
            }
            Command::Aggregate(a) => {
                inputs.extend(
                    a.inputs
                        .iter()
                        .map(|i| read_file("the input", &i.to_string_lossy())),
                );
                outputs.extend(a.out.as_deref().map(|p| written("--out", p)));
            }
            Command::Export(e) => {
                inputs.push(read_file("the input", &e.input.to_string_lossy()));
                outputs.push(written("-o", &e.out));
            }
        }
        (inputs, outputs)
    }
}

/// An input as messages name it (`the input run.csv`, `--holdout h.csv`); `-` is standard
/// input, compared as the file it may be redirected from (`/dev/stdin`).
fn read_file(named: &str, input: &str) -> ReadFile {
    if input == "-" {
        return ReadFile {
            named: "standard input".into(),
            path: PathBuf::from("/dev/stdin"),
        };
    }
    ReadFile {
        named: format!("{named} {input}"),
        path: PathBuf::from(input),
    }
}

impl DataArgs {
    /// The files the data options read (`--limits`, a descriptor given as a path in
    /// `--format`) and write (`--out`, and its checkpoint with `--checkpoint-every`).
    fn files(&self, inputs: &mut Vec<ReadFile>, outputs: &mut Vec<WrittenFile>) {
        if let Some(l) = &self.limits {
            inputs.push(read_file("--limits", &l.to_string_lossy()));
        }
        if self.format != "csv" {
            inputs.push(read_file("--format", &self.format));
        }
        if let Some(out) = &self.out {
            outputs.push(WrittenFile {
                option: "--out".into(),
                path: out.clone(),
            });
            if self.checkpoint_every.is_some() {
                outputs.push(WrittenFile {
                    option: "the checkpoint".into(),
                    path: allanscope::pipeline::checkpoint::path_for(out),
                });
            }
        }
    }
}

/// Text columns given no `--tau0`: the sampling step read off each input's time column
/// ([`allanscope::input::sampling_step`]), logged; every input must show the same step.
fn text_tau0(d: &mut DataArgs, inputs: &[&str]) -> Result<()> {
    if d.format != "csv" {
        return Ok(());
    }
    let no_clock = d.time_column.as_deref() == Some(allanscope::input::text::NO_TIME_COLUMN);
    if let Some(tau0) = d.tau0 {
        // Given the step, the look at the start finds a merged multi-rate file's rows, and a
        // time column that contradicts the step.
        for &input in inputs {
            if input == "-" || read_once(input) {
                continue;
            }
            if let Ok(Ok(step)) = look_at_start(input, d) {
                if !no_clock {
                    clock_agrees(input, &step, tau0)?;
                }
                say_rows(input, &step, d);
            }
        }
        return Ok(());
    }
    if no_clock {
        return Err(usage(
            "--time-column none: the rows are read as consecutive samples, so their step must \
             be given with --tau0"
                .to_string(),
        ));
    }
    let mut found: Option<(&str, allanscope::input::sampling_step::InferredStep)> = None;
    for &input in inputs {
        let step = look_at_start(input, d)?.map_err(anyhow::Error::new)?;
        match &found {
            Some((first, s)) if (s.tau0_s - step.tau0_s).abs() > 1e-9 * s.tau0_s => {
                return Err(usage(format!(
                    "{input}: {step}; but {first}: {s}: the inputs differ, give --tau0"
                )))
            }
            Some(_) => {}
            None => {
                tracing::info!("{input}: {step}");
                say_rows(input, &step, d);
                found = Some((input, step));
            }
        }
    }
    d.tau0 = found.map(|(_, s)| s.tau0_s);
    Ok(())
}

/// A usage error when `--tau0` and the time column's step (the median of its first steps,
/// read in seconds, or in ms, us, ns or days as the reader would read it: `time_column.rs`,
/// `step_scale`) disagree by more than a quarter: a wrong tau0 scales every coefficient (N by
/// the square root of the ratio), and the reader would not find the gaps either. Before
/// (session 42) the run went on at `--tau0` with a warning, its N 41% off for a step twice the
/// time column's. A file whose channels hold a value on every k-th row is left to
/// [`say_rows`].
fn clock_agrees(
    input: &str,
    step: &allanscope::input::sampling_step::InferredStep,
    tau0: f64,
) -> Result<()> {
    if step.steps == 0 || step.every > 1 || !(step.tau0_s > 0.0 && step.unit_s > 0.0) {
        return Ok(());
    }
    let raw = step.tau0_s / step.unit_s;
    // A column that steps by one (a logger's `time` in samples or ticks) is a count, not a
    // clock in another unit: left to the reader, which says it is not used to find gaps.
    if raw == 1.0 && step.unit_s == 1.0 && tau0 < 0.5 {
        return Ok(());
    }
    if allanscope::input::time_column::step_scale(&step.column, raw, tau0).is_some()
        || allanscope::input::time_column::step_scale(&step.column, step.tau0_s, tau0).is_some()
    {
        return Ok(());
    }
    let show = allanscope::ranges::show;
    Err(usage(format!(
        "{input}: --tau0 is {} s, but {step}: {} times that, nor does the column's step read in \
         ms, us or ns give {} s. A wrong tau0 scales the coefficients (N by {:.3}); leave out \
         --tau0 to take the time column's step, or, if the column is a clock in another unit, \
         give --time-column none to read the rows as consecutive samples at --tau0",
        show(tau0),
        show((step.tau0_s / tau0 * 1e4).round() / 1e4),
        show(tau0),
        (step.tau0_s / tau0).sqrt()
    )))
}

/// The sampling step and rows found at the start of `input` by
/// [`allanscope::input::sampling_step::infer_tau0`], as the run will lay out its columns but
/// with no `--tau0`. The run reads the input again and logs what it finds (a column without a
/// name, a label column): this look says nothing, so nothing is said twice. An input that can
/// be read only once (standard input, a FIFO, `<(zcat run.csv.gz)`) keeps the bytes the look
/// took, and the run reads them first ([`open_input`]). The outer error: the input does not
/// open, or is no text (a compressed file, a workbook, binary data: refused as the run would
/// refuse it, not read as columns without a time column).
fn look_at_start(
    input: &str,
    d: &DataArgs,
) -> Result<Result<allanscope::input::sampling_step::InferredStep, UsageError>> {
    analyze::sniff(input, None)?;
    let opts = TextOptions {
        tau0_s: None,
        ..d.text_options()
    };
    let once = read_once(input);
    let mut src = std::io::BufReader::new(Recording {
        inner: open_input(input)?,
        seen: once.then(Vec::new),
    });
    if once {
        // Standard input and a pipe are checked on the bytes they send first (a file was
        // above): a compressed stream, a workbook or binary data is refused as such.
        let head = src.fill_buf().map_err(|e| usage(format!("{input}: {e}")))?;
        analyze::sniff_head(input, head, None)?;
    }
    let step =
        tracing::subscriber::with_default(tracing::subscriber::NoSubscriber::default(), || {
            allanscope::input::sampling_step::infer_tau0(&mut src, Path::new(input), &opts)
        });
    let Recording { inner, seen } = src.into_inner();
    if let Some(head) = seen {
        read_once_heads().push(ReadOnceHead {
            input: input.to_string(),
            head,
            rest: inner,
        });
    }
    Ok(step)
}

/// A reader that keeps every byte read through it (when `seen` is `Some`).
struct Recording {
    inner: Box<dyn Read + Send>,
    seen: Option<Vec<u8>>,
}

impl Read for Recording {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        if let Some(seen) = &mut self.seen {
            seen.extend_from_slice(&buf[..n]);
        }
        Ok(n)
    }
}

/// The start of a read-once input that [`look_at_start`] read, and the stream after it.
struct ReadOnceHead {
    input: String,
    head: Vec<u8>,
    rest: Box<dyn Read + Send>,
}

/// The read-once inputs' starts taken by [`look_at_start`], until [`open_input`] hands each
/// out (standard input and a pipe are the process's, so this is too).
fn read_once_heads() -> std::sync::MutexGuard<'static, Vec<ReadOnceHead>> {
    static HEADS: std::sync::Mutex<Vec<ReadOnceHead>> = std::sync::Mutex::new(Vec::new());
    HEADS
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// What the look at an input's start found of its rows: the channels analysed on every k-th
/// row only (their rows are the samples: `sparse_rows`), or some channels on every k-th row
/// beside others on every row (no curve for them in this run: said, with how to get one).
fn say_rows(input: &str, step: &allanscope::input::sampling_step::InferredStep, d: &mut DataArgs) {
    use allanscope::input::sampling_step::ordinal;
    if step.every > 1 {
        match d.tau0 {
            // --tau0 the file's row step: the channels' own step is k times that.
            Some(t) if (t - step.tau0_s).abs() > 1e-6 * step.tau0_s => tracing::warn!(
                "{input}: the channels analysed hold a value on every {} row only, {} s apart by \
                 the time column, but --tau0 is {t} s: give --tau0 {} (or leave it out) to read \
                 them at their own rate",
                ordinal(step.every),
                allanscope::ranges::show(step.tau0_s),
                allanscope::ranges::show(step.tau0_s)
            ),
            _ => d.sparse_rows = true,
        }
    }
    for (name, k) in &step.slow {
        tracing::warn!(
            "{input}: channel `{name}` holds a value on every {} row only (a stream logged at 1/{k} \
             of the rate of the others?): analysed with them its samples are one-sample \
             stretches and it has no curve; analyse it alone (--channels {name}): its rows are then \
             its samples, spaced by the time column",
            ordinal(*k)
        );
    }
}

/// Where a command's JSON lines go: `out` (a result file, opened as [`OutputFile`] explains: an
/// earlier result refused unless `mode` allows, replaced only at the first record) or standard
/// output (a table on a terminal unless `json`, [`terminal`]); and the destination's name for
/// messages.
pub(crate) fn records_output(
    out: Option<&Path>,
    mode: allanscope::sink::output::OutputMode,
    what: &str,
    json: bool,
) -> Result<(Box<dyn std::io::Write + Send>, String)> {
    use allanscope::sink::output::{OutputFile, OutputMode};
    Ok(match out {
        Some(p) => {
            if mode == OutputMode::Append && p.is_file() {
                // A resumed run adds whole lines after the last whole line written.
                analyze::drop_torn_last_line(p)
                    .with_context(|| format!("{what} {}", p.display()))?;
            }
            let f = OutputFile::open(p, mode, what).map_err(anyhow::Error::new)?;
            (
                Box::new(std::io::BufWriter::new(f)),
                p.display().to_string(),
            )
        }
        None => (terminal::stdout_records(json), "standard output".into()),
    })
}

/// The `--capture` file of a live run, opened as [`allanscope::sink::output::OutputFile`] explains.
pub(crate) fn capture_output(
    path: Option<&Path>,
    mode: allanscope::sink::output::OutputMode,
    what: &str,
) -> Result<Option<allanscope::source::CaptureSlot>> {
    let Some(p) = path else { return Ok(None) };
    let f =
        allanscope::sink::output::OutputFile::open(p, mode, what).map_err(anyhow::Error::new)?;
    Ok(Some(allanscope::source::CaptureSlot::new(f)))
}

/// Ends a command's record writer: every record written (within the grace the signals allow)
/// or an error naming the destination.
pub(crate) fn finish_records(
    writer: allanscope::pipeline::RecordWriter,
    dest: &str,
    signals: &process::SignalWatch,
) -> Result<()> {
    writer
        .finish_within(|| signals.grace())
        .with_context(|| format!("writing the JSON lines to {dest}"))?;
    Ok(())
}

/// The error of a replay that was stopped before its input ended (exit status 1; docs/records.md:
/// 0 only when the input was read to its end). The final records were written all the same.
pub(crate) fn interrupted(input: &str, progress: &allanscope::source::Progress) -> anyhow::Error {
    anyhow::anyhow!(
        "{input}: stopped by {} before the end of the input; the final records cover the data \
         read (the summary says `read_to_end: false`)",
        progress.stopped_by().unwrap_or("a signal")
    )
}

pub(crate) fn usage(msg: impl Into<String>) -> anyhow::Error {
    anyhow::Error::new(UsageError::Option(msg.into()))
}

/// Parses `--taus` ([`TauSpec`]'s `FromStr`, shared with the stand config).
pub fn parse_taus(s: &str) -> Result<TauSpec> {
    s.parse::<TauSpec>()
        .map_err(|e| usage(format!("--taus `{s}`: {e}")))
}

/// Parses `--overlap`.
pub fn parse_overlap(s: &str) -> Result<Overlap> {
    s.parse::<Overlap>()
        .map_err(|e| usage(format!("--overlap `{s}`: {e}")))
}

fn parse_stats(list: &[String]) -> Result<StatSet> {
    StatSet::from_names(list.iter().map(String::as_str)).map_err(|e| usage(format!("--stats: {e}")))
}

/// Parses a duration (`--duration`): seconds, or a number with `s`, `min`, `h` or `d`, within
/// [`allanscope::ranges::MAX_SECONDS`].
pub fn parse_duration_s(s: &str) -> Result<f64> {
    allanscope::ranges::parse_duration(s).map_err(|e| usage(format!("--duration {e}")))
}

/// Clap's parser of `--tau0`: a number of seconds within the sampling-step range.
fn tau0_arg(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    allanscope::ranges::check_tau0(v)
}

/// Clap's parser of `--every` and `--checkpoint-every`: seconds within the interval range.
fn interval_arg(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a number"))?;
    allanscope::ranges::check_interval(v)
}

/// The folders searched for a descriptor given by name, in order: `./config/frames`, the
/// executable's `../../config/frames`, and the crate's own `config/frames` as it was at compile
/// time (then the library's embedded copies).
pub(crate) fn descriptor_dirs() -> Vec<PathBuf> {
    let mut dirs = vec![PathBuf::from("config/frames")];
    if let Ok(exe) = std::env::current_exe() {
        if let Some(d) = exe.parent().and_then(Path::parent).and_then(Path::parent) {
            dirs.push(d.join("config/frames"));
        }
    }
    dirs.push(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/frames"));
    // A binary run from its build tree finds the crate's folder twice.
    dirs.dedup();
    dirs
}

/// A frame descriptor by name (searched in [`descriptor_dirs`]) or path.
pub(crate) fn load_descriptor(
    name_or_path: &str,
) -> Result<FrameDescriptor, allanscope::frame::descriptor::DescriptorErrors> {
    FrameDescriptor::load_in(name_or_path, &descriptor_dirs())
}

/// The frame descriptor (`None` for text columns) and the sampling step: `--tau0` when given,
/// else the descriptor's; required for text columns.
pub(crate) fn format_and_tau0(d: &DataArgs) -> Result<(Option<FrameDescriptor>, f64)> {
    let desc = if d.format == "csv" {
        None
    } else {
        Some(load_descriptor(&d.format).map_err(anyhow::Error::new)?)
    };
    let tau0 = match (&desc, d.tau0) {
        (_, Some(t)) => {
            allanscope::ranges::check_tau0(t).map_err(|e| usage(format!("--tau0 {e}")))?
        }
        (Some(desc), None) => desc.tau0_s(),
        (None, None) => return Err(usage("--tau0 is required for --format csv")),
    };
    Ok((desc, tau0))
}

/// The analysis options common to every run of a command.
pub(crate) fn analysis_options(d: &DataArgs, tau0_s: f64) -> Result<AnalysisOptions> {
    allanscope::ranges::check_tau0(tau0_s).map_err(|e| usage(format!("tau0 {e}")))?;
    Ok(d.settings()?.analysis_options(tau0_s))
}

impl DataArgs {
    /// The data and analysis settings of these options, each parsed and checked (the plan's
    /// [`DataSettings`], as a stand config also gives them).
    pub(crate) fn settings(&self) -> Result<DataSettings> {
        let taus = parse_taus(&self.taus)?;
        let overlap = parse_overlap(&self.overlap)?;
        let stats = parse_stats(&self.stats)?;
        let fit = match self.fit.as_str() {
            "none" => None,
            m => Some(m.parse::<FitMethod>().map_err(usage)?),
        };
        if let Some(e) = self.every {
            allanscope::ranges::check_interval(e).map_err(|p| usage(format!("--every {p}")))?;
        }
        // A rate unit (`deg/s`) reads the columns as rate samples, `--rate` or not, as a
        // header's `[deg/s]` does; phase is never in one.
        let rate_unit = self.rate_unit();
        if let (Some(_), true) = (&rate_unit, self.phase) {
            return Err(usage(format!(
                "--phase, but --unit {} is a rate: phase is the running sum of increments; give \
                 its increment unit (--unit {}), or --rate instead of --phase",
                self.unit_or_default(),
                rate_unit.as_deref().unwrap_or("u")
            )));
        }
        Ok(DataSettings {
            kind: if self.rate || rate_unit.is_some() {
                InputKind::Rate
            } else if self.phase {
                InputKind::Phase
            } else {
                InputKind::Increments
            },
            // `--unit` names the increment's unit; a rate's own unit (`deg/s`) means the same
            // (docs: README "--unit").
            unit: rate_unit.unwrap_or_else(|| {
                allanscope::model::units::increment_unit_label(self.unit_or_default(), self.rate)
            }),
            taus,
            overlap,
            stats,
            every_s: self.every,
            fit,
            limits: match &self.limits {
                Some(p) => allanscope::model::limits::load_file(p)?,
                None => Vec::new(),
            },
            diagnose: self.diagnose,
            channels: self.channels.clone(),
            text: self.text_options(),
        })
    }

    /// The increment unit of a `--unit` that names a rate (`deg/s`: `deg`), which reads the
    /// columns as rate samples (`allanscope::input::header_unit::option_rate_unit`).
    pub(crate) fn rate_unit(&self) -> Option<String> {
        self.unit
            .as_deref()
            .and_then(allanscope::input::header_unit::option_rate_unit)
    }

    /// `--unit`, or `u` when not given.
    pub(crate) fn unit_or_default(&self) -> &str {
        self.unit.as_deref().unwrap_or("u")
    }

    /// The channels of a text input in `reader` and what their values are: in `--unit` with the
    /// kind of `--rate`/`--phase` (`settings`) when `--unit` is given or no column header
    /// carries a unit; else in the units the headers give, rates or increments as they say
    /// (src/input/header_unit.rs), said in the log. A header unit not known, rates mixed with
    /// increments, or headers that contradict `--rate`/`--phase` are usage errors (exit 2)
    /// naming the input, column and header.
    pub(crate) fn text_channels<R: BufRead>(
        &self,
        input: &str,
        reader: &TextReader<R>,
        settings: &DataSettings,
    ) -> Result<(Vec<ChannelSetup>, InputKind)> {
        let temperatures = reader.temperatures();
        let is_temp: Vec<bool> = temperatures.iter().map(Option::is_some).collect();
        let mut setups = ChannelSetup::for_text_columns(reader.names(), &is_temp, &settings.unit);
        // Temperature columns are not channels, unless --channels names one (its Allan
        // deviation is wanted too); `diagnose` reads the first as the temperature either way.
        if let Some(wanted) = &settings.channels {
            for (i, n) in reader.names().iter().enumerate() {
                if wanted.contains(n) && is_temp[i] {
                    setups.push(ChannelSetup {
                        name: n.clone(),
                        unit: settings.unit.clone(),
                        column: i,
                        counts_lsb: None,
                    });
                }
            }
            setups.sort_by_key(|c| c.column);
        }
        let temps = reader
            .names()
            .iter()
            .zip(&temperatures)
            .filter_map(|(n, t)| t.as_ref().map(|t| (n, t)));
        for (k, (n, t)) in temps.enumerate() {
            let how = if t.named {
                format!("in {}", t.unit)
            } else {
                "read as degC: no unit in its name".to_string()
            };
            let role = if k == 0 {
                "the unit's temperature, which diagnose fits the bias against"
            } else {
                "another temperature, left out (diagnose reads the first)"
            };
            let named = settings.channels.as_ref().is_some_and(|w| {
                w.iter()
                    .any(|x| allanscope::input::header_unit::names_channel(x, n))
            });
            let channel = if named {
                "a channel too, as --channels names it"
            } else {
                "not a channel"
            };
            tracing::info!("{input}: column `{n}` holds {role} ({how}); {channel}");
        }
        let columns = reader.channel_columns();
        // A column renamed with a unit (`--columns "c17=wx [rad/s]"`) is in that unit when its
        // own header gives none.
        let ours: Vec<(usize, &str)> = setups
            .iter()
            .map(|c| match columns[c.column] {
                (i, src) if header_unit(src).is_none() && header_unit(&c.name).is_some() => {
                    (i, c.name.as_str())
                }
                col => col,
            })
            .collect();
        // A name that carries no unit may be in the unit its file's format fixes: a PX4
        // sensor_gyro's `x` (by its message), Kalibr's `omega_x`, an Xsens export's `Gyr_X`.
        let format = reader.file_format();
        let fixed: Vec<Option<HeaderUnit>> = ours
            .iter()
            .map(|&(_, name)| {
                let px4 = reader
                    .px4_export()
                    .then(|| px4_export::message_unit(Path::new(input), name));
                px4.flatten()
                    .or_else(|| format.and_then(|f| f.column_unit(name)))
            })
            .collect();
        if self.unit.is_some() {
            if let (Some(u), false) = (self.rate_unit(), self.rate) {
                tracing::info!(
                    "{input}: --unit {} is a rate: the columns are read as rate samples (u = \
                     {u}); give --unit {u} for increments",
                    self.unit_or_default()
                );
            }
            let carried: Vec<String> = ours
                .iter()
                .zip(&fixed)
                .filter(|((_, n), f)| header_unit(n).is_some() || f.is_some())
                .map(|((_, n), _)| format!("`{n}`"))
                .collect();
            if !carried.is_empty() {
                tracing::info!(
                    "{input}: --unit {} given: the units in the headers of {} are not read",
                    self.unit_or_default(),
                    carried.join(", ")
                );
            }
            // A header that says rates while the options read increments (or the reverse)
            // is most often a forgotten --rate: the results would be 1 / tau0 times too large
            // (or too small). --unit overrides the headers, so this is said, not refused.
            let by_header = ours.iter().zip(&fixed).find_map(|(&(_, n), f)| {
                match header_unit(n) {
                    Some(Ok(u)) => Some(u),
                    _ => f.clone(),
                }
                .map(|u| (n, u))
            });
            if let Some((n, u)) = by_header {
                let reads_rate = settings.kind == InputKind::Rate;
                if settings.kind != InputKind::Phase && u.rate != reads_rate {
                    let (says, reads, hint) = if u.rate {
                        (
                            "rate samples",
                            "increments (the change over each sample)",
                            "add --rate if they are rates",
                        )
                    } else {
                        (
                            "increments",
                            "rate samples",
                            "leave out --rate if they are increments",
                        )
                    };
                    tracing::warn!(
                        "{input}: column `{n}` holds {says} by its header unit `{}`, but the \
                         options read {reads} in {}: {hint}, or the results are off by a \
                         factor of the sampling rate",
                        u.text,
                        self.unit_or_default()
                    );
                }
            }
            return Ok((setups, settings.kind));
        }
        let read = units_from_headers(&ours, &fixed, self.rate, self.phase)
            .map_err(|e| usage(format!("{input}: {e}")))?;
        let Some(read) = read else {
            if settings.kind == InputKind::Increments && !setups.is_empty() {
                tracing::info!(
                    "{input}: no unit in the column headers and no --unit: the values are read as \
                     increments (each sample's angle or velocity change) in u; give --rate if they \
                     are rate samples, and --unit for their unit"
                );
            }
            return Ok((setups, settings.kind));
        };
        for (c, u) in setups.iter_mut().zip(&read.units) {
            c.unit.clone_from(u);
        }
        let kind = if read.rate {
            InputKind::Rate
        } else {
            settings.kind
        };
        let how = match kind {
            InputKind::Rate => "rate samples, as --rate",
            InputKind::Phase => "phase, as --phase",
            InputKind::Increments => "increments",
        };
        tracing::info!(
            "{input}: no --unit: units from the column headers: {}; read as {how} (--unit U \
             overrides the headers)",
            read.account
        );
        Ok((setups, kind))
    }

    /// What the unit's checkpoints are checked against: `--checkpoint-every`, `--resume`,
    /// `--abort-after-frames` and `--out`; `wall_clock` for `listen`.
    pub(crate) fn unit_request(&self, wall_clock: bool) -> UnitRequest {
        UnitRequest {
            checkpoint: CheckpointRequest {
                every_s: self.checkpoint_every,
                resume: self.resume,
                abort_after_frames: self.abort_after_frames,
            },
            out: self.out.clone(),
            config: None,
            wall_clock,
        }
    }
}

/// Whether `input` is a stream that can be read only once (a FIFO, a process substitution, a
/// character device), not a file that can be opened again: standard input `-` included.
pub(crate) fn read_once(input: &str) -> bool {
    input == "-" || std::fs::metadata(input).is_ok_and(|m| !m.is_file() && !m.is_dir())
}

pub(crate) fn open_input(input: &str) -> Result<Box<dyn Read + Send>> {
    let mut heads = read_once_heads();
    if let Some(at) = heads.iter().position(|h| h.input == input) {
        let h = heads.remove(at);
        return Ok(Box::new(std::io::Cursor::new(h.head).chain(h.rest)));
    }
    drop(heads);
    if input == "-" {
        Ok(Box::new(std::io::stdin()))
    } else {
        let path = Path::new(input);
        if path.is_dir() {
            return Err(usage(format!("{input}: is a directory, not an input file")));
        }
        let f =
            std::fs::File::open(path).map_err(|e| usage(format!("{input}: cannot open: {e}")))?;
        Ok(Box::new(f))
    }
}

/// Reads a whole text file of JSON lines into values (for `plot`, `report`, tests).
pub fn read_json_lines(path: &Path) -> Result<Vec<serde_json::Value>> {
    Ok(numbered_json_lines(path)?
        .into_iter()
        .map(|(_, v)| v)
        .collect())
}

/// The longest JSON line read back (bytes): a curve of thousands of taus takes a few hundred kB.
const MAX_JSON_LINE_BYTES: usize = 64 << 20;

/// The JSON lines of a file with their line numbers (1-based), blank lines skipped. A last line
/// that is cut short (no newline after it, and not a whole record: the file of a run killed
/// while writing, or still being written) is left out with a warning; any other line that is
/// not a record is an error naming its line.
pub(crate) fn numbered_json_lines(path: &Path) -> Result<Vec<(u64, serde_json::Value)>> {
    use std::io::BufRead;
    if path.is_dir() {
        return Err(usage(format!(
            "{}: is a directory, not a file of JSON lines",
            path.display()
        )));
    }
    let f = std::fs::File::open(path)
        .map_err(|e| usage(format!("{}: cannot open: {e}", path.display())))?;
    let mut src = BufReader::new(f);
    let mut out = Vec::new();
    let mut buf = Vec::new();
    let mut line_no = 0u64;
    let input_error = |line: u64, problem: String| {
        anyhow::Error::new(UsageError::Input {
            file: path.into(),
            line,
            problem,
        })
    };
    loop {
        buf.clear();
        let n = (&mut src)
            .take(MAX_JSON_LINE_BYTES as u64 + 1)
            .read_until(b'\n', &mut buf)
            .map_err(|e| input_error(line_no + 1, format!("cannot read: {e}")))?;
        if n == 0 {
            break;
        }
        line_no += 1;
        if buf.len() > MAX_JSON_LINE_BYTES {
            return Err(input_error(
                line_no,
                format!(
                    "longer than {} MiB: not a file of JSON lines written by allanscope",
                    MAX_JSON_LINE_BYTES >> 20
                ),
            ));
        }
        let torn = !buf.ends_with(b"\n");
        let Ok(line) = std::str::from_utf8(&buf) else {
            return Err(usage(format!(
                "{}: line {line_no}: not text (stream did not contain valid UTF-8); give a file \
                 of JSON lines written by allanscope",
                path.display()
            )));
        };
        if line.trim().is_empty() {
            continue;
        }
        match serde_json::from_str(line) {
            Ok(v) => out.push((line_no, v)),
            Err(e) if torn && e.is_eof() => {
                tracing::warn!(
                    "{}: line {line_no}: the last line is cut short ({} bytes, no newline: a run \
                     stopped while writing?); left out",
                    path.display(),
                    buf.len()
                );
            }
            Err(e) => return Err(input_error(line_no, format!("not a JSON record: {e}"))),
        }
    }
    Ok(out)
}
