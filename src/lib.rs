//! allanscope: live, exact Allan-family statistics for inertial sensors on a test stand.
//!
//! # Layout
//!
//! The modules follow the flow of data, one stage each, and name the type that crosses
//! each boundary:
//!
//! ```text
//! source (file, stdin, serial, udp)                       bytes            (tokio tasks)
//!   -> frame (descriptor, decoder) | input (text columns)  bytes -> Chunk  (decode thread)
//!   -> analysis: one run, per channel       Chunk -> ChannelReport -> records (worker threads)
//!        allan (accumulators, batch reference, edf, noise id)   samples -> Curve
//!        model (terms, covariance, fit, aggregate, limits)      Curve -> FitResult
//!        gap (evidence, effects, diagnosis)                     increments -> Diagnosis
//!   -> sink (typed JSON-lines records, plot, report, table, metrics, export)  records -> bytes
//! pipeline: the threads and bounded channels between those stages, back-pressure, and
//!   checkpointing (checkpointing.rs: the schedule and the collector threads; checkpoint.rs: the
//!   file: header, atomic write, fingerprint, resume checks); run_frames_async /
//!   run_text_async in the caller's tokio runtime, stopped by its token
//! sim (model files, generators, capture writer)           model file -> capture
//! stand (the stand config of `run`: one unit, or several) TOML -> StandConfig
//! plan: the checked plan of a run (RunPlan of UnitPlans: input, channels, analysis options,
//!   checkpoint setup), from a stand config or the command line; option values (`FromStr`)
//! stats: the chi-squared quantile behind every interval
//! smallest_step: the smallest step between consecutive values (an LSB's candidate)
//! toml_check: the one error collector of every TOML file read (file, line, key, problem)
//! ranges: the bounds every user-given number is checked against where it is parsed, and the
//!   largest sample accepted
//! error: the errors that reach the user and their exit statuses
//! ```
//!
//! ## Files
//!
//! Every file of src/ and every folder, one line each, in the order data flows through them;
//! a folder's line stands for its `mod.rs` (the `layout_check` test fails when this list and
//! the tree disagree):
//!
//! ```text
//! lib.rs                   the library's map (this list, the dependency order) and its modules
//! main.rs                  the binary: logging to standard error, the command line, exit statuses
//! cli/                     the binary's commands (clap), one file each; not part of the library
//!   analyze.rs             `analyze`: a capture or text columns through the pipeline
//!   listen.rs              `listen`: a serial port, UDP socket or standard input, live
//!   run.rs                 `run --config`: a stand config's units through the pipeline
//!   diagnose.rs            `diagnose`: the sim-to-real gap of each channel of a run
//!   simulate.rs            `simulate`: a capture from a noise model
//!   aggregate.rs           `aggregate`: run-to-run statistics of fitted coefficients
//!   export.rs              `export`: the fitted model in another tool's format
//!   plot.rs                `plot`: SVG figures from the JSON lines
//!   report.rs              `report`: one HTML page from the JSON lines
//!   metrics.rs             `--metrics`: serves the metrics registry over HTTP
//!   process.rs             signals, `--duration`, the crash test hook
//!   status.rs              the status line of a live run on a terminal
//!   terminal.rs            what standard output is: a table for a terminal, JSON lines for a pipe
//! source/                  where bytes come from, one tokio task per source          -> bytes
//!   file.rs                a file or standard input, read in blocks, paced or not
//!   serial.rs              a serial port, reopened with backoff
//!   udp.rs                 a UDP socket, datagrams passed on whole
//! input/                   text columns                                         bytes -> Chunk
//!   text.rs                the column reader: separators, header, rates or increments
//!   time_column.rs         the time column: gaps found from the sampling step
//!   sampling_step.rs       the sampling step read off the time column (no --tau0)
//!   stamp_grid.rs          the sampling grid under a jittered clock's stamps
//!   header_unit.rs         a data column's unit in its header (`[rad s^-1]`), without --unit
//!   format_units.rs        units a file's format fixes (Kalibr, Xsens, UZH-FPV, ArduPilot)
//!   temperature_column.rs  the unit's temperature column (`temp [degC]`): not a channel
//!   px4_export.rs          PX4's CSV export: us stamps, fields that describe samples
//!   row_ties.rs            rows repeating the one before in every column: a logger's
//!   phase_hint.rs          a column that looks like accumulated angle or velocity
//!   lvm.rs                 LabVIEW Measurement files: tagged headers, Delta_X, units
//! frame/                   frames (pure: no I/O)                          bytes -> FrameEvent
//!   descriptor/            the descriptor language (TOML) and its checked types
//!     parse.rs             the top level, sync, checks across message kinds, interleave
//!     message.rs           one message kind: length, checksum, counter, status, channels
//!     walker.rs            typed reads of one TOML table, problems by key path
//!     layout.rs            each field inside the message, no two sharing a byte
//!   field.rs               the wire types and byte orders of one value
//!   checksum.rs            the named CRCs and plain sums
//!   crc_msb.rs             CRCs most significant bit first, sixteen bytes a step
//!   plan.rs                a message compiled into a read plan of loads and scales
//!   decoder.rs             the streaming decoder: sync, checksum, health
//!   seq_tracker.rs         the frame counter unwrapped: lost and repeated messages
//!   block.rs               a flat batch of decoded frames for the analysis
//!   encoder.rs             valid messages of a descriptor (the decoder's inverse)
//! analysis.rs              one run: chunks -> curves, fits, diagnoses -> ChannelReports -> records
//! analysis/                the run's parts
//!   setup.rs               what the analysis is given: input kind, channels, options
//!   block.rs               a frame block handed to each channel at once
//!   channel_fit.rs         a channel's curves and fit, noise types read off first
//!   channel_report.rs      ChannelReport: one channel's curves, fit, read-outs, diagnosis
//!   state.rs               the run's saved state for a checkpoint
//! allan/                   the Allan family                                   samples -> Curve
//!   accum/                 streaming accumulators of AVAR, HVAR, MVAR
//!     config.rs            which statistics, which cluster sizes, exact or bounded overlap
//!     repr.rs              integer counts or double-double phase
//!     kernels.rs           the inner loops: sums of squared differences
//!     engine.rs            one channel's phase streams and levels
//!     channel.rs           the facade a channel uses
//!   curve.rs               accumulator readings -> curves with noise type, edf, intervals
//!   edf.rs                 equivalent degrees of freedom and chi-squared intervals
//!   noise_id.rs            power-law noise identification by lag-1 autocorrelation
//!   batch.rs               the textbook batch formulas, the tests' reference
//! model/                   the five-term noise model                       Curve -> FitResult
//!   terms.rs               closed forms of each term's Allan variance
//!   term_values.rs         five values keyed Q..R; a coefficient with its interval
//!   avar_cov/              covariance of AVAR estimates between cluster sizes
//!     pair.rs              the lag sums of one pair of cluster sizes
//!     lag_covariance.rs    each random term's covariance of two second differences at a lag
//!     far_field.rs         the far-field series of the flicker covariance
//!     quadrature.rs        sums of a smooth lag function over long ranges
//!     shared.rs            the process-wide cache of pairs computed from scratch
//!   nnls.rs                non-negative least squares for small dense problems
//!   fit/                   the fit of the five terms with 95% intervals
//!     estimators.rs        the tau selection and the weighted estimators
//!     intervals.rs         intervals of the coefficients by test inversion
//!   lowpass.rs             output low-pass filters and their AVAR on white rate
//!   readout.rs             IEEE 952 annex C read-outs of a curve
//!   limits.rs              datasheet limits judged with the fit's uncertainty
//!   aggregate.rs           run-to-run statistics of fitted coefficients
//!   units.rs               unit constants, what a unit measures, increment units
//! gap/                     the sim-to-real gap                          increments -> Diagnosis
//!   evidence.rs            what one streaming pass over a channel gathers
//!   effects.rs             candidate effects and their AVAR columns
//!   block_cov.rs           covariance of block-mean differences under the model
//!   column_memo.rs         a problem's filter columns and rounding floors, kept once computed
//!   filter_cov.rs          covariance of filtered white rate, exact
//!   problem.rs             the GLS problem on one measured curve
//!   filter_scan.rs         shape scans of the filter candidates
//!   filter_shape.rs        the curve judged beyond the unit's filter's own stretch
//!   temperature.rs         a bias that follows the unit's temperature
//!   temperature_check.rs   the temperature's coefficient bounded when none is named
//!   k_profile.rs           the random walk's K^2 read off the block means
//!   warmup.rs              a warm-up found in time
//!   warmup_profile.rs      the warm-up test with the random walk profiled on the block means
//!   first_block.rs         a first block far off, shorter than a warm-up can be named
//!   steps.rs               bias jumps found in time
//!   step_null.rs           the jump rule's level on its own run (bootstrap)
//!   jump_mixture.rs        spike-and-slab statistics of bias jumps
//!   outliers.rs            isolated samples far outside the noise
//!   stuck.rs               stretches where the channel did not move, taken out as gaps
//!   lsb.rs                 the quantization step read off the values
//!   quantization.rs        which quantization the values show
//!   quant_limit.rs         when quantization limits what can be told
//!   rounding.rs            rate samples rounded after a filter, as AVAR
//!   discrepancy.rs         the rounding model's known error, carried in the covariance
//!   limit_cycle.rs         a named line that is the counter's limit cycle
//!   sawtooth.rs            the counter's whole sawtooth, in the base model
//!   segments.rs            homogeneity of the curve across the run's segments
//!   simplex.rs             a Nelder-Mead search in N parameters (the second-order filter's polish)
//!   thresholds.rs          the decision thresholds, calibrated by simulation
//!   diagnose.rs            the diagnosis: effects chosen, verdict
//!   band_noise.rs          the narrow-band noise candidate and its scan
//!   alternatives.rs        another explanation that fits about as well
//!   intervals.rs           95% intervals of the accepted effects' parameters
//!   holdout.rs             the gap on a held-out run
//!   ensemble.rs            the gap as a band of simulated runs
//!   oracle.rs              oracle bounds: statistics told the truth
//!   unit_model.rs          the fitted unit as a simulator model (`--model-out`)
//!   record.rs              the `diagnosis` record
//! sim/                     the simulator                                   model file -> capture
//!   model_file/            noise-model files (TOML) and their checked types
//!     parse.rs             the top level, stand and temperature
//!     channel.rs           one `[[channel]]`: terms, axis, effects, filters
//!     keys.rs              the key walker, problems by key path
//!   model_write.rs         a model written back as a model file
//!   model_avar.rs          the closed-form AVAR of a model's channel
//!   stand_rate.rs          Earth rate and gravity on a channel's axis
//!   noise.rs               streaming generators of the five terms
//!   effects.rs             streaming generators of the effects beyond them
//!   lowpass.rs             the output filters as streaming generators
//!   band_noise.rs          narrow-band (resonant) noise: generator, exact AVAR
//!   writer.rs              a simulated run as text columns
//!   capture.rs             a simulated run as frames of a descriptor
//! sink/                    where results go                                   records -> bytes
//!   records.rs             every JSON-lines record, typed, tagged by `type`
//!   unit_record.rs         the `unit` tag of a run of several units
//!   json.rs                records as JSON lines
//!   output.rs              result files never overwritten unless asked
//!   table/                 the readable table for a terminal
//!     layout.rs            style, number formats, padded columns
//!     channel.rs           one run: heading, per-channel rows, limits cells
//!     diagnosis.rs         a channel's diagnosis in one line
//!     runs.rs              the run-to-run table of several runs
//!     writer.rs            TableWriter, in place of standard output on a terminal
//!     status.rs            the one-line status of a live run
//!   status_area.rs         the terminal line kept for a live run's status
//!   effect_text.rs         an effect of a diagnosis as a person reads it
//!   alternative_words.rs   the other explanations about as good as the choice, in words
//!   band_words.rs          how far a measured curve leaves the ensemble bands, in words
//!   taken_out.rs           what a diagnosis set aside (outliers, stuck stretches), in words
//!   filter_shape_words.rs  a diagnosis judged beyond its filter's stretch, in words
//!   first_block_words.rs   a first block far off the rest of the run, in words
//!   jump_words.rs          the bias jumps a diagnosis named, when and how large, in words
//!   step_change_words.rs   a step of the values that changed during the run, in words
//!   results.rs             the records `plot` and `report` read, labelled
//!   plot/                  Allan-deviation figures (SVG)
//!     panel.rs             one panel per unit: curves, heading, legend
//!     curves.rs            one curve: points, intervals, model, asymptotes, misses
//!     band.rs              a diagnosis's ensemble band behind the curve
//!     axes.rs              log-log scale, grid, ticks, slope key
//!     legend.rs            the legend's lines
//!     fit_terms.rs         the determined terms of a fit record
//!     series.rs            the curves a figure draws (plot and report)
//!     text.rs              the words and numbers of labels
//!   dynamic.rs             the dynamic Allan view (time x tau)
//!   report/                the HTML test report: the page skeleton
//!     banner.rs            the PASS/FAIL banner of the datasheet limits
//!     runs.rs              the runs and limits tables
//!     figures.rs           the embedded SVG figures and dynamic views
//!     noise_model.rs       the noise-model section (table 2 layout)
//!     diagnosis.rs         each channel's diagnosis in words
//!     health.rs            the decoder-health table
//!     css.rs               the stylesheet, screen and print
//!   page_file.rs           a finished figure or page written safely
//!   export.rs              the fitted model in other tools' files
//!   metrics.rs             the metrics registry (Prometheus text)
//! pipeline/                the threads and bounded channels of a run
//!   decode.rs              source events -> frame blocks (the decode thread)
//!   reorder.rs             UDP datagrams in counter order
//!   writer.rs              the record writer thread behind a bounded queue
//!   checkpointing.rs       the checkpoint schedule and collector threads
//!   checkpoint.rs          the checkpoint file: header, atomic write, resume checks
//!   units.rs               several units in one process
//! plan/                    the checked plan of a run
//!   options.rs             option values shared with clap (`FromStr`)
//!   settings.rs            a unit's data and analysis settings
//!   channels.rs            which channels a run analyses
//!   checkpoint_setup.rs    a unit's checkpointing, checked
//!   unit.rs                one unit's plan
//!   run.rs                 the plan of a whole run
//! stand/                   the stand config of `run` (TOML, checked)
//!   parse.rs               the top level: run, statistics, channels, output, limits, units
//!   source.rs              one `[source]` table
//!   units.rs               `[[unit]]` tables and what two units may not share
//!   check.rs               typed reads and the collector
//! stats.rs                 the chi-squared quantile behind every interval
//! smallest_step.rs         the smallest step between consecutive values, printing passed over
//! toml_check.rs            the one error collector of every TOML file read
//! ranges.rs                the bounds every user-given number is checked against
//! error.rs                 errors that reach the user and their exit statuses
//! layout_check.rs          test only: this map and the dependency order hold
//! ```
//!
//! Dependencies point one way. A module uses (names `crate::X` of) only modules listed below it
//! here; the `layout_check` test reads the sources and fails on a use against this order, on an
//! import cycle, and on a module missing from the list:
//!
//! ```text
//! Dependencies (users first):
//! plan: builds the run's pipeline inputs and its checkpoint setup
//! pipeline: runs analysis, source, sink; owns the checkpoint file format
//! analysis: drives allan, model, gap; yields typed ChannelReports and sink's records
//! stand: reads the stand config (frame descriptors, sources)
//! source: bytes in (writes a capture through sink)
//! sink: the typed records and what is made of them
//! gap: the diagnosis (simulates with sim)
//! sim: model files and generators
//! input: text columns into chunks (of frame events too)
//! frame: descriptors and decoder
//! model: the five-term model, its fit, units and limits
//! allan: the accumulators and curves
//! stats: the chi-squared quantile
//! smallest_step: a column's smallest step
//! toml_check: the TOML error collector
//! error: user-facing errors
//! ranges: bounds of numbers
//! ```
//!
//! The command line is not part of the library: `src/cli/` (one file per subcommand, clap) is a
//! module of the `allanscope` binary (`src/main.rs`), which also owns the process: signals and
//! `--duration` (`cli/process.rs`), the progress bar, the crash test hook, the descriptor search
//! path and the exit statuses. Cargo features `cli`, `serial` and `plot` (default on) pull in
//! clap, indicatif, tokio-serial and plotters; the library builds without them
//! (`--no-default-features`), and `examples/embed.rs` runs the pipeline in a program's own
//! runtime.
//!
//! Numerical stages (`allan`, `model`, `gap`, `sim`) are plain synchronous code: they never know
//! where samples came from and never await. I/O lives at the edges (`source`, `input`, `sink`,
//! and the binary's `cli`); `pipeline` connects them with bounded crossbeam channels.
#![forbid(unsafe_code)]

pub mod allan;
pub mod analysis;
pub mod error;
pub mod frame;
pub mod gap;
pub mod input;
pub mod model;
pub mod pipeline;
pub mod plan;
pub mod ranges;
pub mod sim;
pub mod sink;
pub mod smallest_step;
pub mod source;
pub mod stand;
pub mod stats;
pub mod toml_check;

#[cfg(test)]
mod layout_check;
