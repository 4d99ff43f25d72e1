//! `analyze`: replays text columns or captures of frames through the live pipeline
//! (`allanscope::pipeline`), one run per input: the same source, decode, analysis and writer stages
//! as `listen`, with a file or standard input as the source.

use std::io::{BufReader, IsTerminal, Write};
use std::path::PathBuf;

use anyhow::{Context, Result};

use std::io::Seek;
use std::sync::Arc;

use super::process::SignalWatch;
use super::{
    analysis_options, finish_records, format_and_tau0, interrupted, open_input, records_output,
    usage, AnalyzeArgs, DataArgs,
};
use allanscope::analysis::{AnalysisOptions, ChannelSetup};
use allanscope::frame::FrameDescriptor;
use allanscope::input::text::TextReader;
use allanscope::model::aggregate::{aggregate_channels, RunCoefs};
use allanscope::pipeline::checkpoint::Position;
use allanscope::pipeline::{RecordQueue, RecordWriter, RunControl, RunOutcome};
use allanscope::plan::unit::{InputPlan, UnitPlan};
use allanscope::sink::output::OutputMode;
use allanscope::sink::records::{AggregateRecord, Record};
use allanscope::source::{Pace, SourceSpec};

pub fn run(a: &AnalyzeArgs) -> Result<()> {
    let d = &a.data;
    // Every option is checked before the output is opened.
    parse_pace(&a.pace)?;
    let (_, tau0) = format_and_tau0(d)?;
    analysis_options(d, tau0)?;
    let (out, dest) = records_output(
        d.out.as_deref(),
        OutputMode::new(d.force, d.resume),
        "--out",
        d.json,
    )?;
    // A replay has no deadline: back-pressure, never coalesced interim records.
    let writer = RecordWriter::spawn(out);
    let ctl = RunControl::default();
    // SIGINT/SIGTERM end the current run and skip the rest.
    let signals = SignalWatch::start(
        ctl.shutdown.clone(),
        writer.queue().clone(),
        ctl.progress.clone(),
        None,
    );
    signals.release_fifos(&a.inputs);
    let result = analyze_all(a, writer.queue(), &ctl);
    let written = finish_records(writer, &dest, &signals);
    let unfinished = result?;
    written?;
    match unfinished {
        Some(input) => Err(interrupted(&input, &ctl.progress)),
        None => Ok(()),
    }
}

/// Where the JSON lines of a one-pass command go (`diagnose`): `--out FILE` (see
/// [`records_output`]) or standard output.
pub(crate) fn output_writer(d: &DataArgs) -> Result<Box<dyn Write + Send>> {
    Ok(records_output(
        d.out.as_deref(),
        OutputMode::new(d.force, d.resume),
        "--out",
        d.json,
    )?
    .0)
}

/// A run that crashed may have left its last JSON line half written (the writer's buffer is
/// flushed in blocks, not lines). Before a resumed run appends, the file is cut back to its last
/// complete line, so every line stays a whole record; returns the bytes dropped.
pub(crate) fn drop_torn_last_line(path: &std::path::Path) -> std::io::Result<u64> {
    use std::io::{Read, SeekFrom};
    let mut f = std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .open(path)?;
    let len = f.metadata()?.len();
    // Look back in blocks for the last newline.
    let mut end = len;
    let mut buf = vec![0u8; 64 * 1024];
    let keep = loop {
        if end == 0 {
            break 0;
        }
        let start = end.saturating_sub(buf.len() as u64);
        let chunk = &mut buf[..(end - start) as usize];
        f.seek(SeekFrom::Start(start))?;
        f.read_exact(chunk)?;
        if let Some(i) = chunk.iter().rposition(|&b| b == b'\n') {
            break start + i as u64 + 1;
        }
        end = start;
    };
    if keep < len {
        f.set_len(keep)?;
        tracing::warn!(
            "{}: dropped a torn last line of {} bytes before resuming",
            path.display(),
            len - keep
        );
    }
    Ok(len - keep)
}

/// Parses `--pace`.
pub(crate) fn parse_pace(s: &str) -> Result<bool> {
    match s {
        "max" => Ok(false),
        "realtime" => Ok(true),
        other => Err(usage(format!("--pace `{other}`: expected max or realtime"))),
    }
}

/// Runs every input; returns the first input not read to its end (a stopped replay).
fn analyze_all(a: &AnalyzeArgs, queue: &RecordQueue, ctl: &RunControl) -> Result<Option<String>> {
    let d = &a.data;
    let realtime = parse_pace(&a.pace)?;
    let (descriptor, tau0) = format_and_tau0(d)?;
    let base = analysis_options(d, tau0)?;
    let several = a.inputs.len() > 1;
    // Standard input, or a pipe, is read to its end by the first run that names it.
    if let Some(twice) = a
        .inputs
        .iter()
        .enumerate()
        .find_map(|(i, x)| (super::read_once(x) && a.inputs[..i].contains(x)).then_some(x))
    {
        return Err(usage(format!(
            "{} is given twice, but it can be read only once (each input is one run)",
            if twice == "-" {
                "standard input `-`"
            } else {
                twice.as_str()
            }
        )));
    }
    if several && (d.checkpoint_every.is_some() || d.resume) {
        return Err(usage(
            "--checkpoint-every and --resume take one input (one run per output file)",
        ));
    }
    let server = super::metrics::start_option(d.metrics.as_deref())?;
    let mut ctl = ctl.clone();
    ctl.crash_hook = super::process::abort_hook(d.abort_after_frames);
    let mut fits = Vec::new();
    let mut unfinished = None;
    for (run, input) in a.inputs.iter().enumerate() {
        if ctl.shutdown.is_cancelled() {
            unfinished.get_or_insert_with(|| input.clone());
            break;
        }
        let mut opts = base.clone();
        opts.run = several.then_some(run);
        ctl.metrics = server.as_ref().map(|s| s.tap(input, &opts.limits));
        let outcome = match &descriptor {
            None => analyze_text(input, d, opts, realtime, queue, &ctl),
            Some(desc) => analyze_frames(input, desc, d, opts, realtime, queue, &ctl),
        };
        // A pipe the first signal let through (super::process::release_fifos) ends empty: its
        // "no data rows" or "empty capture" is the stop, not a fault of the input.
        let outcome = match outcome {
            Err(_) if ctl.shutdown.is_cancelled() && super::read_once(input) && input != "-" => {
                return Err(anyhow::anyhow!(
                    "{input}: stopped by {} before the pipe delivered any data; nothing was \
                     analysed",
                    ctl.progress.stopped_by().unwrap_or("a signal")
                ));
            }
            r => r?,
        };
        if !outcome.read_to_end {
            unfinished.get_or_insert_with(|| input.clone());
        }
        fits.push(outcome.analysis.last_fits());
    }
    if several {
        // Each run's own records are written; runs in different units are not averaged.
        let aggregates = aggregate_channels(&run_coefs(&fits))
            .map_err(|e| super::aggregate::unit_mismatch(&e, &a.inputs))?;
        for a in &aggregates {
            queue.push_final(Record::Aggregate(AggregateRecord::new(a)));
        }
        // Run-to-run datasheet limits (e.g. the sd of B over runs) in a closing summary.
        let j = allanscope::model::limits::judge_runs(&base.limits, &aggregates);
        if !j.results.is_empty() {
            queue.push_final(Record::Summary(allanscope::sink::records::SummaryRecord {
                input: a.inputs.join(" "),
                run: None,
                channels: Vec::new(),
                tau0,
                t_data: 0.0,
                samples: Vec::new(),
                segments: Vec::new(),
                bad_rows: 0,
                invalid_values: 0,
                flagged_cells: 0,
                time_column: None,
                overlap: d.overlap.clone(),
                elapsed_s: 0.0,
                limits: j.results.clone(),
                pass: j.pass,
                read_to_end: unfinished.is_none(),
                stopped_by: None,
                capture_error: None,
            }));
        }
    }
    Ok(unfinished)
}

/// Text columns: a reader thread feeds the analysis.
fn analyze_text(
    input: &str,
    d: &DataArgs,
    opts: AnalysisOptions,
    realtime: bool,
    queue: &RecordQueue,
    ctl: &RunControl,
) -> Result<RunOutcome> {
    let path = PathBuf::from(input);
    let tau0 = opts.accum.tau0_s;
    sniff(input, None)?;
    let reader = TextReader::with_options(
        BufReader::with_capacity(1 << 16, open_input(input)?),
        &path,
        &d.text_options(),
    )
    .map_err(anyhow::Error::new)?;
    let (setups, kind) = d.text_channels(input, &reader, &d.settings()?)?;
    let mut opts = opts;
    opts.kind = kind;
    let plan = UnitPlan::with_options(
        InputPlan::Text {
            input: input.into(),
            options: d.text_options(),
        },
        "csv",
        setups,
        &d.channels,
        opts,
        &d.unit_request(false),
    )?;
    let replay = input != "-";
    let mut analysis = plan.start_analysis()?;
    let saved = plan.checkpoint.as_ref().and_then(|c| c.1.as_ref());
    let ck_path = plan.checkpoint_path().map(PathBuf::from);
    let reader = match saved.map(|c| &c.position) {
        Some(Position::Text(pos)) if replay => {
            // Continue the file where the saved run stood.
            let mut f =
                std::fs::File::open(input).with_context(|| format!("cannot open {input}"))?;
            f.seek(std::io::SeekFrom::Start(pos.offset))
                .with_context(|| format!("cannot seek in {input}"))?;
            let f: Box<dyn std::io::Read + Send> = Box::new(f);
            reader.resume(BufReader::with_capacity(1 << 16, f), pos)
        }
        Some(Position::Text(pos)) => {
            // Standard input cannot be rewound: what follows is a new stretch.
            analysis.break_segments();
            analysis.add_bad_rows(pos.bad_rows);
            analysis.add_invalid_values(pos.invalid_values);
            analysis.add_flagged_cells(pos.words);
            reader
        }
        Some(Position::Frames { .. }) => {
            return Err(usage(format!(
                "{}: the checkpoint is of frames, not text columns",
                ck_path.unwrap_or_default().display()
            )))
        }
        None => reader,
    };
    let mut ctl = ctl.clone();
    ctl.checkpoint = plan.checkpoint.map(|c| Arc::new(c.0));
    let rows_per_s = realtime.then_some(1.0 / tau0);
    allanscope::pipeline::run_text(reader, path, rows_per_s, analysis, queue, &ctl)
}

/// A capture of frames (a file, or `-`): the file source, the decode stage, the analysis.
fn analyze_frames(
    input: &str,
    desc: &FrameDescriptor,
    d: &DataArgs,
    opts: AnalysisOptions,
    realtime: bool,
    queue: &RecordQueue,
    ctl: &RunControl,
) -> Result<RunOutcome> {
    sniff(input, Some(desc))?;
    let pace = if realtime {
        Pace::Realtime {
            bytes_per_s: desc.frame_len() as f64 * desc.rate_hz,
        }
    } else {
        Pace::Max
    };
    let spec = if input == "-" {
        SourceSpec::Stdin { pace }
    } else {
        SourceSpec::File {
            path: input.into(),
            pace,
        }
    };
    let plan = UnitPlan::with_options(
        InputPlan::Frames {
            spec: spec.clone(),
            desc: Box::new(desc.clone()),
        },
        &d.format,
        ChannelSetup::for_frames(desc),
        &d.channels,
        opts,
        &d.unit_request(false),
    )?;
    let analysis = plan.start_analysis()?;
    let mut ctl = ctl.clone();
    ctl.checkpoint = plan.checkpoint.map(|c| Arc::new(c.0));
    let _bar = (input != "-" && std::io::stderr().is_terminal())
        .then(|| super::process::ProgressBar::start(ctl.progress.clone()));
    let ctl = &ctl;
    let outcome = allanscope::pipeline::run_frames(spec, desc, analysis, queue, ctl)?;
    if let Some(h) = &outcome.health {
        if h.frames == 0 && !d.resume {
            if h.bytes_in == 0 {
                return Err(usage(format!(
                    "{input}: empty (0 bytes): no {} frame to analyse",
                    desc.name
                )));
            }
            return Err(no_frame_error(input, desc, h.bytes_in));
        }
    }
    Ok(outcome)
}

/// Bytes looked at to tell text from binary data before a run starts.
const SNIFF_BYTES: usize = 4096;

/// Refuses an input whose first bytes show it is the other kind than the format says: binary
/// data read as text columns, or text read as frames; a compressed file or UTF-16 text, which
/// must be converted first; a directory; an empty capture. Only regular files are looked at:
/// standard input, a FIFO or a process substitution (`<(zcat run.csv.gz)`) cannot be read twice,
/// so their first bytes are left to the run.
pub(crate) fn sniff(input: &str, frames: Option<&FrameDescriptor>) -> Result<()> {
    use std::io::Read;
    if input == "-" {
        return Ok(());
    }
    let Ok(meta) = std::fs::metadata(input) else {
        return Ok(()); // open_input reports it
    };
    if meta.is_dir() {
        return Err(usage(format!("{input}: is a directory, not an input file")));
    }
    if !meta.is_file() {
        return Ok(());
    }
    let mut head = Vec::with_capacity(SNIFF_BYTES);
    let Ok(f) = std::fs::File::open(input) else {
        return Ok(()); // open_input reports it
    };
    if f.take(SNIFF_BYTES as u64).read_to_end(&mut head).is_err() {
        return Ok(());
    }
    sniff_head(input, &head, frames)
}

/// [`sniff`]'s checks on the first bytes `head` of `input` (an empty `head`: an empty file).
pub(crate) fn sniff_head(input: &str, head: &[u8], frames: Option<&FrameDescriptor>) -> Result<()> {
    if head.is_empty() {
        return match frames {
            // Text columns say "no data rows" with the line.
            None => Ok(()),
            Some(desc) => Err(usage(format!(
                "{input}: empty (0 bytes): no {} frame to analyse",
                desc.name
            ))),
        };
    }
    // A capture that holds frames is a capture, whatever its first bytes are.
    let frames_found = frames.is_some_and(|d| no_frame_in_head(input, d).is_ok());
    if let Some(kind) = compressed(head).filter(|_| !frames_found) {
        return Err(usage(format!(
            "{input}: {kind}-compressed; decompress it first, or read it through a pipe: \
             `{} {} | allanscope ... -` (standard input)",
            match kind {
                "gzip" => "zcat",
                "xz" => "xzcat",
                "bzip2" => "bzcat",
                _ => "zstdcat",
            },
            if input == "-" { "FILE" } else { input }
        )));
    }
    if let Some((what, how)) = container(head).filter(|_| !frames_found) {
        return Err(usage(format!(
            "{input}: {what}, not text columns or a capture of frames; {how}"
        )));
    }
    if head.starts_with(&[0xff, 0xfe]) || head.starts_with(&[0xfe, 0xff]) {
        return Err(usage(format!(
            "{input}: UTF-16 text (as Windows tools write it); convert it to UTF-8 first, e.g. \
             `iconv -f UTF-16 -t UTF-8 {input} > OUT.csv`"
        )));
    }
    let text_like = |b: &u8| matches!(b, b'\t' | b'\n' | b'\r' | 0x20..=0x7e);
    match frames {
        None => {
            // Text may be in any 8-bit code page (a Latin-1 header); binary data has NUL bytes or
            // many control bytes.
            let control = head
                .iter()
                .filter(|&&b| b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0c))
                .count();
            if head.contains(&0) || control * 20 > head.len() {
                let names: Vec<&str> = allanscope::frame::descriptor::BUILTIN
                    .iter()
                    .map(|(n, _)| *n)
                    .collect();
                return Err(usage(format!(
                    "{input}: binary data, not text columns; for a capture of frames give \
                     --format NAME ({})",
                    names.join(", ")
                )));
            }
        }
        Some(_) if frames_found => {}
        Some(desc) => {
            if head.iter().all(text_like) {
                return Err(usage(format!(
                    "{input}: text, not {} frames; for text columns give --format csv with \
                     --tau0",
                    desc.name
                )));
            }
            no_frame_in_head(input, desc)?;
        }
    }
    Ok(())
}

/// The kind of file whose magic bytes start `head` when it is a container a user may hand over
/// in place of text columns (a spreadsheet, a MATLAB or NumPy file, a ROS or PX4 log), and how
/// to get text columns out of it; `None` for anything else.
fn container(head: &[u8]) -> Option<(&'static str, &'static str)> {
    const KINDS: [(&[u8], &str, &str); 12] = [
        (
            b"PK\x03\x04",
            "a ZIP archive (an Excel .xlsx or LibreOffice .ods workbook is one)",
            "save the sheet as CSV (File > Save As > CSV) and analyse that",
        ),
        (
            &[0xd0, 0xcf, 0x11, 0xe0, 0xa1, 0xb1, 0x1a, 0xe1],
            "an old Excel workbook (.xls)",
            "save the sheet as CSV (File > Save As > CSV) and analyse that",
        ),
        (
            b"MATLAB 5.0 MAT-file",
            "a MATLAB MAT-file",
            "write the columns as CSV in MATLAB, e.g. `writematrix(data, 'run.csv')`",
        ),
        (
            b"\x89HDF\r\n\x1a\n",
            "an HDF5 file (MATLAB v7.3 .mat, pandas .h5)",
            "write the columns as CSV first (pandas: `pd.read_hdf(F).to_csv('run.csv')`)",
        ),
        (
            b"PAR1",
            "a Parquet file",
            "write it as CSV first (pandas: `pd.read_parquet(F).to_csv('run.csv', index=False)`)",
        ),
        (
            b"\x93NUMPY",
            "a NumPy .npy array",
            "write it as CSV first (`np.savetxt('run.csv', a, delimiter=',')`)",
        ),
        (
            b"#ROSBAG V2.0",
            "a ROS 1 bag",
            "export the IMU topic first: `rostopic echo -b F -p /imu > imu.csv` (README, ROS 1)",
        ),
        (
            b"\x89MCAP0\r\n",
            "an MCAP file (a ROS 2 bag)",
            "export the IMU topic as CSV first (`ros2 topic echo --csv /imu > imu.csv` while \
             playing it, or PlotJuggler's CSV export)",
        ),
        (
            b"SQLite format 3\0",
            "an SQLite database (a ROS 2 bag's .db3?)",
            "export the IMU topic as CSV first (`ros2 topic echo --csv /imu > imu.csv` while \
             playing the bag)",
        ),
        (
            &[0xa3, 0x95, 0x80],
            "an ArduPilot DataFlash log (.bin)",
            allanscope::input::format_units::MAVLOGDUMP,
        ),
        (
            b"FMT, ",
            allanscope::input::format_units::DATAFLASH_TEXT,
            allanscope::input::format_units::MAVLOGDUMP,
        ),
        (
            b"ULog\x01\x12\x35",
            "a PX4 ULog",
            "convert it with pyulog's `ulog2csv F` and analyse the sensor_combined CSV with \
             --tau0 (README, PX4)",
        ),
    ];
    KINDS
        .iter()
        .find(|(magic, _, _)| head.starts_with(magic))
        .map(|(_, what, how)| (*what, *how))
}

/// The compression whose magic bytes start `head`, if any.
fn compressed(head: &[u8]) -> Option<&'static str> {
    const MAGIC: [(&[u8], &str); 3] = [
        (&[0x1f, 0x8b, 0x08], "gzip"),
        (&[0xfd, b'7', b'z', b'X', b'Z', 0], "xz"),
        (&[0x28, 0xb5, 0x2f, 0xfd], "zstd"),
    ];
    let bzip2 = head.len() >= 4 && head.starts_with(b"BZh") && (b'1'..=b'9').contains(&head[3]);
    MAGIC
        .iter()
        .find(|(m, _)| head.starts_with(m))
        .map(|(_, k)| *k)
        .or(bzip2.then_some("bzip2"))
}

/// Bytes decoded before a run starts to find one frame of the format given: many frames of any
/// descriptor, and little to read (a few ms).
const FRAME_SNIFF_BYTES: u64 = 1 << 20;

/// Refuses a capture in whose first [`FRAME_SNIFF_BYTES`] the format's decoder finds no frame
/// (binary data of another kind, another unit's frames), before the output is touched: a run
/// that would end with no data must not replace an earlier result.
fn no_frame_in_head(input: &str, desc: &FrameDescriptor) -> Result<()> {
    use std::io::Read;
    let mut head = Vec::new();
    let read =
        std::fs::File::open(input).and_then(|f| f.take(FRAME_SNIFF_BYTES).read_to_end(&mut head));
    if read.is_err() || head.is_empty() {
        return Ok(()); // open_input reports it
    }
    let mut dec = allanscope::frame::decoder::Decoder::new(desc.clone());
    dec.push(&head);
    if head.len() < FRAME_SNIFF_BYTES as usize {
        dec.finish();
    }
    if dec.health().frames == 0 {
        return Err(no_frame_error(input, desc, head.len() as u64));
    }
    Ok(())
}

/// The usage error of a capture with no frame of `desc` in its first `bytes`.
fn no_frame_error(input: &str, desc: &FrameDescriptor, bytes: u64) -> anyhow::Error {
    usage(format!(
        "{input}: no {} frame found in {bytes} bytes: is it a {} capture? (another unit's \
         frames need their --format; text columns need --format csv)",
        desc.name, desc.name
    ))
}

/// Each run's determined coefficients, for the run-to-run statistics.
fn run_coefs(
    runs: &[Vec<(String, String, Option<allanscope::model::fit::FitResult>)>],
) -> Vec<Vec<RunCoefs>> {
    runs.iter()
        .map(|run| {
            run.iter()
                .filter_map(|(name, unit, fit)| Some(RunCoefs::from_fit(name, unit, fit.as_ref()?)))
                .collect()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::drop_torn_last_line;

    #[test]
    fn a_torn_last_line_is_dropped_and_whole_lines_are_kept() {
        let dir = std::env::temp_dir().join(format!("allanscope-torn-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("out.jsonl");
        let whole = "{\"type\":\"curve\",\"n\":1}\n{\"type\":\"curve\",\"n\":2}\n";
        std::fs::write(&p, format!("{whole}{{\"type\":\"cur")).unwrap();
        assert_eq!(drop_torn_last_line(&p).unwrap(), 12);
        assert_eq!(std::fs::read_to_string(&p).unwrap(), whole);
        // Nothing to drop when the file ends with a newline, or is empty.
        assert_eq!(drop_torn_last_line(&p).unwrap(), 0);
        std::fs::write(&p, "").unwrap();
        assert_eq!(drop_torn_last_line(&p).unwrap(), 0);
        // A single torn line, no newline at all: the file is emptied.
        std::fs::write(&p, "{\"type\"").unwrap();
        assert_eq!(drop_torn_last_line(&p).unwrap(), 7);
        assert_eq!(std::fs::metadata(&p).unwrap().len(), 0);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
