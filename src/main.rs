//! `anholonomy` command-line interface.

use anholonomy::error::Error;
use anholonomy::integrate::simulate;
use anholonomy::runner::{run, RunOptions, RunOutcome};
use anholonomy::say;
use anholonomy::validate::{prepare_all, prepare_each, Call};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// Does the plan survive physics? Plans nonholonomic motions, integrates them
/// on the ideal kinematic model, replays the same commands on a rigid-body
/// model in Rapier (loaded from URDF, with contact and friction), compares
/// the two and logs everything to MCAP (Foxglove) and Rerun (.rrd).
///
/// Every scenario of a call is validated (files, TOML, URDF, names, plan,
/// physics at the start pose) before anything runs or is written. Paths are
/// relative to the working directory; paths inside a scenario file are
/// relative to that file.
///
/// Exit status: 0 success, 1 a threshold was broken (`check`), 2 bad input
/// (scenario, URDF, or a goal the planner cannot reach: one line per error,
/// `error: FILE:LINE: key ...`, nothing written), 3 runtime failure.
#[derive(Parser)]
#[command(name = "anholonomy", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Run scenarios end to end and print a results table.
    ///
    /// For each scenario: plan, ideal run, physics replay, comparison, and
    /// logs in LOGS/<scenario>/ (run.mcap, run.rrd, summary.json), which
    /// replace the previous run's files as one unit. A scenario with a
    /// [sweep] table runs its Monte Carlo variants instead (LOGS/<scenario>/
    /// sweep.json). Broken thresholds are reported in the table but do not
    /// change the exit status (use `check` for that).
    Run(RunArgs),
    /// Run scenarios like `run` and exit with status 1 when any breaks a threshold (for CI).
    ///
    /// Every metric named in a scenario's [thresholds] table must stay at or
    /// below its value (a NaN metric breaks it); a sweep must reach its
    /// `min_success_rate`. Broken thresholds are listed in the table's result
    /// column and counted on stderr.
    ///
    /// Exit status: 0 all thresholds met, 1 at least one broken, 2 bad input
    /// (nothing ran), 3 runtime failure. Typical CI use:
    /// `anholonomy check scenarios/ --quiet --logs ci-logs`.
    Check(RunArgs),
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
    },
}

#[derive(Args)]
struct RunArgs {
    /// Scenario files, or directories whose *.toml files (not hidden ones) are all run (sorted).
    #[arg(required = true)]
    paths: Vec<PathBuf>,
    /// Directory for run logs (created if needed; LOGS/<scenario>/ per scenario).
    #[arg(long, default_value = "logs")]
    logs: PathBuf,
    /// Do not write any log files.
    #[arg(long)]
    no_logs: bool,
    /// Never show progress bars.
    #[arg(long)]
    quiet: bool,
    /// Sweep scenarios only: run the variants with index % N == I and write
    /// LOGS/<scenario>/sweep-shard-I-of-N.json. Every scenario of the call
    /// must have a [sweep] table (others are an error, exit 2).
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
}

fn fmt_metric(o: &RunOutcome, name: &str) -> String {
    o.metric(name)
        .map(|v| format!("{v:.4}"))
        .unwrap_or_else(|| "-".into())
}

/// The coordinate the table reports: the planar position when the model has
/// one, else its first coordinate (the first `ideal_goal_*` metric).
fn primary(o: &RunOutcome) -> Option<&str> {
    o.metrics
        .iter()
        .find_map(|(n, _)| n.strip_prefix("ideal_goal_"))
}

fn print_table(rows: &[RunOutcome]) {
    say!(
        "{:<30} {:<17} {:>7} {:>9} {:>7} {:>14} {:>10} {:>10} {:>10} {:>10}  result",
        "scenario",
        "planner",
        "steps",
        "steps/s",
        "wall s",
        "coordinate",
        "ideal goal",
        "sim goal",
        "track rms",
        "track max"
    );
    for o in rows {
        let c = primary(o).unwrap_or("-");
        say!(
            "{:<30} {:<17} {:>7} {:>9.0} {:>7.3} {:>14} {:>10} {:>10} {:>10} {:>10}  {}",
            o.name,
            o.planner,
            o.steps,
            o.steps as f64 / o.timings.physics.max(1e-9),
            o.timings.total,
            c,
            fmt_metric(o, &format!("ideal_goal_{c}")),
            fmt_metric(o, &format!("sim_goal_{c}")),
            fmt_metric(o, &format!("tracking_{c}_rms")),
            fmt_metric(o, &format!("tracking_{c}_max")),
            if o.passed {
                "PASS".to_string()
            } else {
                format!("FAIL: {}", o.failures.join("; "))
            }
        );
    }
}

fn run_cmd(args: &RunArgs, gate: bool) -> Result<u8, Vec<Error>> {
    let shard = match &args.shard {
        Some(s) => {
            Some(anholonomy::sweep::Shard::parse(s).map_err(|m| vec![Error::input("--shard", m)])?)
        }
        None => None,
    };
    let log_root = (!args.no_logs).then(|| args.logs.clone());
    let call = Call {
        log_root: log_root.as_deref(),
        sharded: shard.is_some(),
    };
    let preps = prepare_all(&args.paths, &call)?;
    let opts = RunOptions {
        log_root,
        progress: !args.quiet,
    };
    let mut rows = Vec::new();
    let mut errors = Vec::new();
    for p in &preps {
        let res = if p.scenario.sweep.is_some() {
            anholonomy::sweep::run_sweep(p, &opts, shard)
        } else {
            run(p, &opts)
        };
        match res {
            Ok(o) => rows.push(o),
            Err(e) => errors.push(e),
        }
    }
    print_table(&rows);
    if !errors.is_empty() {
        return Err(errors);
    }
    let failed = rows.iter().filter(|o| !o.passed).count();
    if gate && failed > 0 {
        eprintln!("{failed} of {} scenarios broke a threshold", rows.len());
        return Ok(1);
    }
    Ok(0)
}

fn plan_cmd(file: &std::path::Path, as_json: bool) -> Result<u8, Vec<Error>> {
    if file.is_dir() {
        return Err(vec![Error::input(
            file,
            "`plan` takes one scenario file, not a directory",
        )]);
    }
    let preps = prepare_all(&[file.to_path_buf()], &Call::default())?;
    let prep = &preps[0];
    let plan = &prep.planned;
    let (start, _goal) = prep.start_goal();
    let ideal = simulate(prep.model(), plan, &start, prep.scenario.sim.dt);
    let fin: Vec<f64> = ideal.last().iter().copied().collect();
    if as_json {
        let v = serde_json::json!({
            "scenario": prep.scenario.name,
            "planner": prep.scenario.planner,
            "state_names": prep.model().state_names(),
            "input_names": prep.model().input_names(),
            "duration_s": plan.duration,
            "labels": plan.labels,
            "segments": plan.segments,
            "details": plan.details,
            "ideal_final_state": fin,
        });
        say!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
    } else {
        say!(
            "{} ({}), duration {:.3} s",
            prep.scenario.name,
            prep.scenario.planner.kind(),
            plan.duration
        );
        for s in &plan.segments {
            say!(
                "  {:>8.3} – {:>8.3} s  {}",
                s.start,
                s.end,
                plan.label_name(s.label)
            );
        }
        say!("  details: {}", plan.details);
        say!("  ideal final state: {fin:?}");
    }
    Ok(0)
}

fn list_cmd(paths: &[PathBuf]) -> Result<u8, Vec<Error>> {
    let paths = if paths.is_empty() {
        vec![PathBuf::from("scenarios")]
    } else {
        paths.to_vec()
    };
    let (preps, errors) = prepare_each(&paths, &Call::default());
    if !preps.is_empty() {
        say!(
            "{:<30} {:<14} {:<17} description",
            "scenario",
            "model",
            "planner"
        );
    }
    for p in &preps {
        let s = &p.scenario;
        say!(
            "{:<30} {:<14} {:<17} {}",
            s.name,
            s.model.kind(),
            s.planner.kind(),
            s.description
        );
    }
    if errors.is_empty() {
        Ok(0)
    } else {
        Err(errors)
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let res = match &cli.cmd {
        Cmd::Run(a) => run_cmd(a, false),
        Cmd::Check(a) => run_cmd(a, true),
        Cmd::Plan { file, json } => plan_cmd(file, *json),
        Cmd::List { paths } => list_cmd(paths),
    };
    match res {
        Ok(code) => ExitCode::from(code),
        Err(errors) => {
            for e in &errors {
                eprintln!("error: {e}");
            }
            ExitCode::from(errors.iter().map(|e| e.exit_code()).max().unwrap_or(2) as u8)
        }
    }
}
