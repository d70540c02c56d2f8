//! `anholonomy` command-line interface.

use anholonomy::error::Error;
use anholonomy::integrate::simulate;
use anholonomy::runner::{Prepared, RunOptions, RunOutcome};
use anholonomy::scenario::{collect, Scenario};
use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

/// Does the plan survive physics? Plans nonholonomic motions, integrates them
/// on the ideal kinematic model, replays the same commands on a rigid-body
/// model in Rapier (loaded from URDF, with contact and friction), compares
/// the two and logs everything to MCAP (Foxglove) and Rerun (.rrd).
///
/// Exit status: 0 success, 1 a threshold was broken (`check`), 2 bad input
/// (scenario, URDF, or a goal the planner cannot reach), 3 runtime failure.
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
    /// logs in LOGS/<scenario>/ (run.mcap, run.rrd, summary.json).
    /// Broken thresholds are reported in the table but do not change the
    /// exit status (use `check` for that).
    Run(RunArgs),
    /// Like `run`, but exit with status 1 when any scenario breaks a threshold (for CI).
    Check(RunArgs),
    /// Plan one scenario without physics and print the plan.
    ///
    /// Prints the segments, their timing and the planner's derived numbers,
    /// and the ideal final state reached by integrating the plan.
    Plan {
        /// Scenario file.
        file: PathBuf,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
    },
    /// List scenarios (default: the scenarios/ directory) with model and planner.
    List {
        /// Scenario files or directories.
        paths: Vec<PathBuf>,
    },
}

#[derive(Args)]
struct RunArgs {
    /// Scenario files, or directories whose *.toml files are all run (sorted).
    #[arg(required = true)]
    paths: Vec<PathBuf>,
    /// Directory for run logs.
    #[arg(long, default_value = "logs")]
    logs: PathBuf,
    /// Do not write any log files.
    #[arg(long)]
    no_logs: bool,
    /// Never show progress bars.
    #[arg(long)]
    quiet: bool,
    /// Sweep scenarios only: run the variants with index % N == I (writes sweep-shard-I-of-N.json).
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
}

fn load_all(paths: &[PathBuf]) -> Result<Vec<Prepared>, Vec<Error>> {
    let files = collect(paths).map_err(|e| vec![e])?;
    let mut ok = Vec::new();
    let mut errs = Vec::new();
    for f in files {
        match Scenario::load(&f).and_then(Prepared::new) {
            Ok(p) => ok.push(p),
            Err(e) => errs.push(e),
        }
    }
    if errs.is_empty() {
        Ok(ok)
    } else {
        Err(errs)
    }
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
    println!(
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
        println!(
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
    let preps = load_all(&args.paths)?;
    let opts = RunOptions {
        log_root: (!args.no_logs).then(|| args.logs.clone()),
        progress: !args.quiet,
    };
    let shard = match &args.shard {
        Some(s) => {
            Some(anholonomy::sweep::Shard::parse(s).map_err(|m| vec![Error::input("--shard", m)])?)
        }
        None => None,
    };
    let mut rows = Vec::new();
    let mut errors = Vec::new();
    for res in anholonomy::suite::run_all(&preps, &opts, shard) {
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
    let prep = Scenario::load(file)
        .and_then(Prepared::new)
        .map_err(|e| vec![e])?;
    let plan = prep.plan().map_err(|e| vec![e])?;
    let (start, _goal) = prep.start_goal();
    let ideal = simulate(prep.model(), &plan, &start, prep.scenario.sim.dt);
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
        println!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
    } else {
        println!(
            "{} ({}), duration {:.3} s",
            prep.scenario.name,
            prep.scenario.planner.kind(),
            plan.duration
        );
        for s in &plan.segments {
            println!(
                "  {:>8.3} – {:>8.3} s  {}",
                s.start,
                s.end,
                plan.label_name(s.label)
            );
        }
        println!("  details: {}", plan.details);
        println!("  ideal final state: {fin:?}");
    }
    Ok(0)
}

fn list_cmd(paths: &[PathBuf]) -> Result<u8, Vec<Error>> {
    let paths = if paths.is_empty() {
        vec![PathBuf::from("scenarios")]
    } else {
        paths.to_vec()
    };
    let files = collect(&paths).map_err(|e| vec![e])?;
    println!(
        "{:<26} {:<14} {:<14} description",
        "scenario", "model", "planner"
    );
    for f in files {
        match Scenario::load(&f) {
            Ok(s) => {
                let model = s.model.kind();
                println!(
                    "{:<26} {:<14} {:<14} {}",
                    s.name,
                    model,
                    s.planner.kind(),
                    s.description
                );
            }
            Err(e) => println!("{:<26} error: {e}", f.display()),
        }
    }
    Ok(0)
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
