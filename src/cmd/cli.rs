//! The command line: subcommands and their arguments (clap derive), with
//! the help text users read.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

/// Does the plan survive physics? Plans nonholonomic motions, integrates them
/// on the ideal kinematic model, replays the same commands on a rigid-body
/// model in Rapier (loaded from URDF, with contact and friction), compares
/// the two and logs everything to MCAP (Foxglove) and Rerun (.rrd).
///
/// Every scenario of a call is validated (files, TOML, URDF, names, plan,
/// physics at the start pose, baselines) before anything runs or is written.
/// Paths are relative to the working directory; paths inside a scenario file
/// are relative to that file.
///
/// Exit status: 0 success, 1 a threshold was broken or a metric regressed
/// against its baseline (`check`), 2 bad input (scenario, URDF, baseline
/// file, a goal the planner cannot reach, an unwritable `--junit` path, a log
/// directory `report` cannot read: one line per error, `error: FILE:LINE:
/// key ...`, nothing written), 3 runtime failure (physics diverged, a
/// planner that did not converge).
#[derive(Parser)]
#[command(name = "anholonomy", version, about, long_about)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) cmd: Cmd,
}

#[derive(Subcommand)]
pub(crate) enum Cmd {
    /// Run scenarios end to end and print a results table.
    ///
    /// For each scenario: plan, ideal run, physics replay, comparison, and
    /// logs in LOGS/<scenario>/ (run.mcap, run.rrd, summary.json), which
    /// replace the previous run's files as one unit. A scenario with a
    /// [sweep] table runs its Monte Carlo variants instead (LOGS/<scenario>/
    /// sweep.json). Broken thresholds are reported in the table but do not
    /// change the exit status (use `check` for that).
    Run(RunArgs),
    /// Run scenarios like `run` and exit with status 1 when any breaks a threshold or, with
    /// `--baseline DIR`, when any metric regressed against its baseline (for CI).
    ///
    /// Every metric named in a scenario's [thresholds] table must stay at or
    /// below its value and every one in [minimums] at or above it (a NaN
    /// metric breaks it); a sweep must reach its `min_success_rate`. Broken
    /// thresholds are listed in the table's result column and counted on
    /// stderr; regressions are printed as a table scenario / metric /
    /// baseline / now / change.
    ///
    /// Exit status: 0 all thresholds met and nothing regressed, 1 otherwise,
    /// 2 bad input (nothing ran), 3 runtime failure. Typical CI use:
    /// `anholonomy check scenarios/ --baseline baselines/ --junit report.xml --report --quiet`.
    Check(RunArgs),
    /// Run scenarios and write their baselines (one JSON per scenario) into `--baseline DIR`
    /// (default `baselines/`); same as `check --update-baseline` without the gate.
    Baseline(RunArgs),
    /// Write the HTML report of a log directory: LOGDIR/index.html and
    /// LOGDIR/<scenario>/report.html (self-contained: inline SVG figures).
    Report {
        /// Log directory written by `run`/`check` (default `logs`).
        #[arg(default_value = "logs")]
        logdir: PathBuf,
    },
    /// Plan one scenario without physics and print the plan.
    ///
    /// The scenario is validated as for `run` (URDF, physics at the start
    /// pose, [sweep] table included). Prints the segments with their timing,
    /// the planner's derived numbers (`details`) and the ideal final state
    /// reached by integrating the plan with RK4 at `sim.dt`. Nothing is
    /// written. With --json the same as one JSON object (state and input
    /// names, duration_s, labels, segments, details, ideal_final_state in SI
    /// units, angles in radians); it is identical across runs.
    Plan {
        /// Scenario file.
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// Step budget: refuse (exit 2, before anything runs) a scenario whose plan
        /// plus `sim.settle`, or whose planner's own recorded run, takes more than N
        /// steps of `sim.dt` (memory and time grow with the step count).
        #[arg(long, value_name = "N", default_value_t = anholonomy::validate::DEFAULT_MAX_STEPS)]
        max_steps: u64,
    },
    /// List scenarios with model, planner and description.
    ///
    /// Scenarios go through the same validation as `run` (so `list` also
    /// tells whether they would run). Valid scenarios are listed on stdout;
    /// each invalid one is reported on stderr (`error: FILE:LINE: ...`) and
    /// the exit status is then 2.
    List {
        /// Scenario files or directories (*.toml, not recursive) [default: scenarios/].
        paths: Vec<PathBuf>,
        /// Step budget: refuse (exit 2, before anything runs) a scenario whose plan
        /// plus `sim.settle`, or whose planner's own recorded run, takes more than N
        /// steps of `sim.dt` (memory and time grow with the step count).
        #[arg(long, value_name = "N", default_value_t = anholonomy::validate::DEFAULT_MAX_STEPS)]
        max_steps: u64,
    },
    /// Robustness margins: for each perturbation dimension (the others
    /// nominal), the largest perturbation at which every gate of the
    /// scenario still holds.
    ///
    /// Dimensions are the keys of [sim.perturb]: command_latency,
    /// actuator_tau, torque_scale, state_noise, state_latency,
    /// wheel_radius_scale, friction_scale, mass_scale (only those that apply
    /// to the scenario's system and plan). Each search brackets the edge on a
    /// doubling ladder and bisects it to the resolution, checking on the way
    /// that pass/fail is monotone (a non-monotone pattern is reported);
    /// levels of a round run in parallel. Prints a table (dimension, margin,
    /// the gate that broke first beyond it, runs used) and writes the nominal
    /// run's logs plus LOGS/<scenario>/margins.json (every level, plotted
    /// by `report`). Exit 0, 2 bad input (nothing run), 3 runtime failure.
    Margin(super::margin::MarginArgs),
    /// Fit the twin (`model.*` keys) or the physics (`sim.*` keys) to a
    /// reference: the scenario's own physics run, or a recording.
    ///
    /// The plan's commands are replayed for each trial: the ideal run with
    /// the trial's `model.*` values, the physics run with its `sim.*`
    /// values. Against `sim` (the default), the ideal run is compared with
    /// the physics run; against a recording (`--against BAG:TOPIC`, a tf
    /// frame `BAG:/tf:FRAME`, or a CSV `t,x,y,theta`), the ideal run when
    /// every key is a `model.*` key, the physics run when every key is a
    /// `sim.*` key. The residual is the RMS over the reference's samples of
    /// the pose error, a heading error counted as its arc at `--length`:
    /// sqrt(mean(|dp|^2 + (L dtheta)^2)). A parallel scan of the ranges, then
    /// Nelder-Mead (argmin), then three evaluations per parameter around the
    /// fit give its sensitivity and interval. Prints the values, the
    /// residual before and after, and the TOML to paste (or `--json`). The
    /// same answer on any number of threads.
    ///
    /// Exit status: 0, 2 bad input (an unknown or unvariable key, an empty or
    /// inverted range, a missing topic, a recording that does not overlap the
    /// plan, a CSV without `t`: nothing fitted), 3 runtime failure.
    Fit(super::fit::FitArgs),
    /// Write a starter repository into DIR that works with this binary
    /// alone: a `diff_drive` scenario on a plan file and one driven by a
    /// Python feedback law (standard library only), the URDF, baselines made
    /// on the spot, a GitHub Actions workflow and a GitLab CI job pinned to
    /// this version (both install it with ci/install-anholonomy.sh: the
    /// release binary, or a build from source where there is none), and a
    /// .gitignore.
    ///
    /// Then `cd DIR && anholonomy check scenarios/ --baseline baselines/`
    /// passes. Exit 2 when DIR exists and is not empty (nothing written).
    Init(InitArgs),
    /// List the shipped models (URDFs embedded in the binary); `models
    /// export DIR [NAME...]` writes them.
    Models(ModelsArgs),
    /// Print every key of a model's or planner's table, or of the scenario file's own
    /// tables, with its default, type and range, and description.
    ///
    /// The same definitions are what every scenario is checked against, so a
    /// value outside a printed range is refused. Without NAME, lists the kinds.
    /// `--markdown --out DIR` writes every page (the reference under
    /// docs/src/reference/ is made that way).
    Keys {
        /// A model kind, a planner kind, or `scenario` (top-level keys, [limits], [sim], [sweep], ...).
        name: Option<String>,
        /// Markdown instead of plain text.
        #[arg(long)]
        markdown: bool,
        /// Write every page as Markdown into DIR (DIR/keys.md, DIR/scenario-keys.md, DIR/models/KIND.md, DIR/planners/KIND.md).
        #[arg(long, value_name = "DIR", conflicts_with = "name")]
        out: Option<PathBuf>,
    },
    /// Merge the shards of one sweep into the sweep.json an unsharded run writes.
    ///
    /// Reads the variants-shard-I-of-N.jsonl files written by `run --shard I/N`
    /// (a directory stands for all of them in it), checks that every shard
    /// 0..N-1 is there exactly once, complete, and of the same sweep (scenario
    /// text, seed, count), and writes sweep.json beside the first shard (or
    /// --out FILE). Statistics and per-variant records are identical to an
    /// unsharded run's. Missing, duplicate, incomplete or mismatched shards
    /// are bad input (exit 2, nothing written).
    Merge {
        /// Shard files, or directories holding them (e.g. logs/rover_sweep).
        #[arg(required = true)]
        paths: Vec<PathBuf>,
        /// Where to write the merged sweep.json.
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
}

#[derive(Args)]
pub(crate) struct RunArgs {
    /// Scenario files, or directories whose *.toml files (not hidden ones) are all run (sorted).
    #[arg(required = true)]
    pub(crate) paths: Vec<PathBuf>,
    /// Directory for run logs (created if needed; LOGS/<scenario>/ per scenario).
    #[arg(long, default_value = "logs")]
    pub(crate) logs: PathBuf,
    /// Do not write any log files.
    #[arg(long)]
    pub(crate) no_logs: bool,
    /// Never show progress bars.
    #[arg(long)]
    pub(crate) quiet: bool,
    /// Sweep scenarios only: run the variants with index % N == I and write
    /// LOGS/<scenario>/variants-shard-I-of-N.jsonl and sweep-shard-I-of-N.json
    /// (combine them with `merge`). Every scenario of the call must have a
    /// [sweep] table (others are an error, exit 2). Without --shard the shard
    /// comes from the scheduler's environment when set: SLURM_ARRAY_TASK_ID
    /// with SLURM_ARRAY_TASK_COUNT (or SLURM_ARRAY_TASK_MIN/MAX), or
    /// JOB_COMPLETION_INDEX (Kubernetes Indexed Job) with --shards N or
    /// ANHOLONOMY_SHARDS.
    #[arg(long, value_name = "I/N")]
    pub(crate) shard: Option<String>,
    /// Sweeps: run only variant I of the one sweep scenario given, as a single
    /// run with full logs (LOGS/<scenario>-variant-I/: run.mcap, run.rrd,
    /// summary.json), to look at one variant a sweep reported.
    #[arg(long, value_name = "I")]
    pub(crate) variant: Option<usize>,
    /// Number of shards for JOB_COMPLETION_INDEX (default: $ANHOLONOMY_SHARDS).
    #[arg(long, value_name = "N")]
    pub(crate) shards: Option<usize>,
    /// Sweeps: continue LOGS/<scenario>/variants.jsonl (or the shard's file)
    /// instead of starting over; variants already recorded are not run again.
    /// The file must be of the same scenario text, seed, count and shard
    /// (else exit 2, nothing written); a partial last line is dropped; no file
    /// yet means a fresh start.
    #[arg(long)]
    pub(crate) resume: bool,
    /// Compare every metric with the baselines in DIR (DIR/<scenario>.json); `check` exits 1
    /// on a regression. All baselines are read before anything runs.
    #[arg(long, value_name = "DIR")]
    pub(crate) baseline: Option<PathBuf>,
    /// Write the baselines from this run (into --baseline DIR, default baselines/) instead of
    /// comparing.
    #[arg(long)]
    pub(crate) update_baseline: bool,
    /// Write a JUnit XML report to FILE (one testcase per scenario).
    #[arg(long, value_name = "FILE")]
    pub(crate) junit: Option<PathBuf>,
    /// Also write the HTML report of this run into the log directory.
    #[arg(long)]
    pub(crate) report: bool,
    /// Step budget: refuse (exit 2, before anything runs) a scenario whose plan
    /// plus `sim.settle`, or whose planner's own recorded run, takes more than N
    /// steps of `sim.dt` (memory and time grow with the step count).
    #[arg(long, value_name = "N", default_value_t = anholonomy::validate::DEFAULT_MAX_STEPS)]
    pub(crate) max_steps: u64,
    /// Link poses per second of simulated time in the logs (`/tf` in run.mcap,
    /// the `robot/<link>` transforms in run.rrd): every k-th physics sample
    /// with k = floor(1 / (HZ * sim.dt)), so at least HZ, plus the last
    /// sample. 0 logs every sample. Every other topic, the metrics and
    /// series.json use every sample whatever the rate; link poses are most
    /// of the log's size and writing time.
    #[arg(long, value_name = "HZ", default_value_t = anholonomy::runner::DEFAULT_POSE_RATE)]
    pub(crate) pose_rate: f64,
    /// Which files each scenario's log directory keeps: `all` (run.mcap and
    /// run.rrd for Foxglove and Rerun, series.json, summary.json), `report`
    /// (no 3D logs: what the HTML report needs, a fraction of the bytes), or
    /// `summary` (summary.json only; no report). Sweeps keep their records
    /// whatever the level.
    #[arg(long, value_name = "LEVEL", default_value_t = anholonomy::log::Keep::All)]
    pub(crate) keep: anholonomy::log::Keep,
    /// Sweeps: run every variant in an engine world of its own instead of
    /// stepping groups of variants together in one shared world (the
    /// default; the same results, bit for bit, and more variants per
    /// CPU-second).
    #[arg(long)]
    pub(crate) no_batch: bool,
}

/// Arguments of `anholonomy init`.
#[derive(clap::Args, Debug)]
pub struct InitArgs {
    /// The new repository's directory (created; it must not exist or be empty).
    pub dir: PathBuf,
    /// The repository CI installs this version from instead of the
    /// project's: its release binary (URL/releases/download/vVERSION/...,
    /// checksum verified), else `cargo install --git URL --tag vVERSION`.
    #[arg(long, value_name = "URL", alias = "git")]
    pub from: Option<String>,
}

/// Arguments of `anholonomy models`.
#[derive(clap::Args, Debug)]
pub struct ModelsArgs {
    #[command(subcommand)]
    pub cmd: Option<ModelsCmd>,
}

/// `anholonomy models export`.
#[derive(clap::Subcommand, Debug)]
pub enum ModelsCmd {
    /// Write shipped URDFs into DIR as NAME.urdf (all of them without NAME).
    ///
    /// An existing file is left alone and reported (exit 2, nothing
    /// written) unless --force.
    Export {
        /// Directory to write into (created if needed).
        dir: PathBuf,
        /// Models to write (see `anholonomy models`); default: every one.
        names: Vec<String>,
        /// Overwrite existing files.
        #[arg(long)]
        force: bool,
    },
}
