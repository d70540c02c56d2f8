//! `run`, `check` and `baseline`: prepare every scenario, run them, then
//! settle baselines, JUnit and the report, in that order.

use crate::cmd::cli::RunArgs;
use crate::cmd::progress::Bars;
use crate::cmd::table::print_table;
use anholonomy::baseline::{self, Baseline, Delta};
use anholonomy::error::Error;
use anholonomy::junit::{self, CaseResult};
use anholonomy::progress::Progress;
use anholonomy::runner::{Prepared, RunOptions, RunOutcome};
use anholonomy::validate::{prepare_all, Call};
use anholonomy::verdict::Verdict;
use std::path::PathBuf;
use std::time::Instant;

/// What `run_cmd` does with the baselines.
#[derive(Clone, Copy, PartialEq)]
pub enum Mode {
    Run,
    Check,
    WriteBaselines,
}

/// Options that only make sense together are checked before anything runs.
fn check_options(args: &RunArgs, mode: Mode, sharded: bool) -> Result<Option<PathBuf>, Vec<Error>> {
    let bad = |opt: &str, m: &str| vec![Error::input(opt, m)];
    let updating = args.update_baseline || mode == Mode::WriteBaselines;
    let dir = args
        .baseline
        .clone()
        .or_else(|| updating.then(|| PathBuf::from("baselines")));
    if sharded && dir.is_some() {
        return Err(bad(
            "--shard",
            "baselines need the whole sweep: do not combine --shard with --baseline/--update-baseline",
        ));
    }
    if args.report && args.no_logs {
        return Err(bad(
            "--report",
            "the report is written into the logs: drop --no-logs",
        ));
    }
    if args.report && args.keep == anholonomy::log::Keep::Summary {
        return Err(bad(
            "--report",
            "the report reads series.json, which --keep summary drops: use --keep report",
        ));
    }
    if let Some(d) = &dir {
        if d.exists() && !d.is_dir() {
            return Err(vec![Error::input(
                d,
                "option `--baseline`: not a directory",
            )]);
        }
    }
    if let Some(j) = &args.junit {
        let logs = (!args.no_logs).then_some(args.logs.as_path());
        junit::check_writable(j, logs).map_err(|e| vec![e])?;
    }
    Ok(dir)
}

/// `--variant I`: variant I of the one sweep scenario of the call, as a
/// single scenario named `<scenario>-variant-I`.
fn one_variant(preps: Vec<Prepared>, i: usize, gated: bool) -> Result<Prepared, Vec<Error>> {
    let bad = |m: String| vec![Error::input("--variant", m)];
    let [prep] = <[Prepared; 1]>::try_from(preps)
        .map_err(|p| bad(format!("needs exactly one scenario, got {}", p.len())))?;
    let Some(cfg) = &prep.scenario.sweep else {
        return Err(vec![Error::input(
            &prep.scenario.path,
            "--variant: this scenario has no [sweep] table",
        )]);
    };
    if gated {
        return Err(bad(
            "re-runs one variant for its logs: do not combine it with --shard or baselines".into(),
        ));
    }
    if i >= cfg.count {
        return Err(vec![prep.scenario.error_at(
            "sweep.count",
            format!(
                "--variant {i} is not a variant of this sweep (0..{})",
                cfg.count
            ),
        )]);
    }
    let v = cfg.variant(i);
    let mut one = prep.variant(&v).map_err(|e| vec![e])?;
    one.scenario.name = format!("{}-variant-{i}", prep.scenario.name);
    let mut what: Vec<String> = v.params.iter().map(|(k, x)| format!("{k} = {x}")).collect();
    if v.mass_scale != 1.0 {
        what.push(format!("mass scale {}", v.mass_scale));
    }
    if let Some(r) = v.sigma_rate {
        what.push(format!("telegraph σ at {r}/s, seed {}", v.seed));
    }
    say!(
        "variant {i} of {}: {}",
        prep.scenario.name,
        if what.is_empty() {
            "the scenario as written".to_string()
        } else {
            what.join(", ")
        }
    );
    Ok(one)
}

/// `regression.json` next to the run's logs (read by the report); removed when no
/// comparison was made so a stale one is never shown.
fn record_regression(o: &RunOutcome, deltas: Option<&[Delta]>) -> Result<(), Error> {
    let Some(dir) = &o.log_dir else {
        return Ok(());
    };
    let path = dir.join("regression.json");
    let log_err = |message: String| Error::Log {
        path: path.clone(),
        message,
    };
    match deltas {
        Some(d) => anholonomy::log::atomic::write_file(&path, |w| {
            serde_json::to_writer_pretty(w, d).map_err(std::io::Error::other)
        })
        .map_err(|e| log_err(e.to_string())),
        None => match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(log_err(e.to_string())),
            _ => Ok(()),
        },
    }
}

/// A scenario's outcome, or its error and wall time (s) for JUnit.
type Outcome = Result<RunOutcome, (Error, f64)>;

pub fn run_cmd(args: &RunArgs, mode: Mode) -> Result<u8, Vec<Error>> {
    let t_all = Instant::now();
    let shard = shard_of(args)?;
    check_flags(args)?;
    let log_root = (!args.no_logs).then(|| args.logs.clone());
    let call = Call {
        log_root: log_root.as_deref(),
        sharded: shard.is_some(),
        max_steps: Some(args.max_steps),
    };
    let mut preps = prepare_all(&args.paths, &call)?;
    let base_dir = check_options(args, mode, shard.is_some())?;
    if let Some(i) = args.variant {
        preps = vec![one_variant(
            preps,
            i,
            shard.is_some() || base_dir.is_some(),
        )?];
    }
    let updating = args.update_baseline || mode == Mode::WriteBaselines;
    // Every baseline and every records file is read (and checked) before
    // anything runs.
    let baselines = match (&base_dir, updating) {
        (Some(dir), false) => load_baselines(&preps, dir)?,
        _ => preps.iter().map(|_| None).collect(),
    };
    let resumed = match (args.resume, &log_root) {
        (true, Some(root)) => resume_states(&preps, root, shard)?,
        _ => Vec::new(),
    };
    let opts = RunOptions {
        log_root,
        progress: if args.quiet {
            Progress::silent()
        } else {
            Progress(std::sync::Arc::new(Bars::default()))
        },
        pose_rate: args.pose_rate,
        cancel: Default::default(),
        keep: args.keep,
        batch: !args.no_batch,
    };
    // Independent scenarios run in parallel; results come back in input order.
    let results: Vec<(usize, Outcome)> = anholonomy::suite::run_all(&preps, &opts, shard, &resumed)
        .into_iter()
        .enumerate()
        .map(|(i, ran)| {
            // A sweep's table, in input order.
            crate::emit(&ran.table);
            (i, ran.result.map_err(|e| (e, ran.wall)))
        })
        .collect();
    let rows: Vec<RunOutcome> = results
        .iter()
        .filter_map(|(_, r)| r.as_ref().ok().cloned())
        .collect();
    print_table(&rows);
    // What the physics filled in or left out of a URDF, once per scenario.
    for p in &preps {
        for w in &p.reading.warnings {
            eprintln!("warning: {}: {w}", p.scenario.name);
        }
    }
    let (deltas, mut errors) =
        settle_baselines(&preps, &results, &baselines, base_dir.as_deref(), updating);
    let regressed = match (&base_dir, updating) {
        (Some(dir), false) => print_comparison(dir, &results, &deltas),
        (Some(dir), true) => {
            let n = results.iter().filter(|(_, r)| r.is_ok()).count();
            say!("wrote {n} baseline(s) to {}", anholonomy::echo::path(dir));
            0
        }
        (None, _) => 0,
    };
    if let Some(path) = &args.junit {
        errors.extend(write_junit(path, &preps, &results, &deltas, t_all));
    }
    if args.report {
        errors.extend(write_report(args, &rows));
    }
    errors.extend(
        results
            .into_iter()
            .filter_map(|(_, r)| r.err().map(|(e, _)| e)),
    );
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok(exit_status(mode, &rows, regressed))
}

/// `--shard`, or the shard a Slurm array or Kubernetes indexed job gives.
fn shard_of(args: &RunArgs) -> Result<Option<anholonomy::sweep::Shard>, Vec<Error>> {
    match &args.shard {
        Some(s) => anholonomy::sweep::Shard::parse(s)
            .map(Some)
            .map_err(|e| vec![Error::input("--shard", e.to_string())]),
        None => match anholonomy::sweep::Shard::from_env(|k| std::env::var(k).ok(), args.shards) {
            Ok(Some((s, from))) => {
                eprintln!("{from}");
                Ok(Some(s))
            }
            Ok(None) => Ok(None),
            Err(e) => Err(vec![Error::input("--shard", e.to_string())]),
        },
    }
}

/// Flags checked before any scenario is read.
fn check_flags(args: &RunArgs) -> Result<(), Vec<Error>> {
    if args.resume && args.no_logs {
        return Err(vec![Error::input(
            "--resume",
            "continues the sweep's variants.jsonl in the logs: drop --no-logs",
        )]);
    }
    if !(args.pose_rate.is_finite() && args.pose_rate >= 0.0) {
        return Err(vec![Error::input(
            "--pose-rate",
            format!(
                "{} is not a rate: give link poses per second of simulated time (0 = every sample)",
                args.pose_rate
            ),
        )]);
    }
    Ok(())
}

/// Every scenario's baseline in `dir`, or every problem with them.
fn load_baselines(
    preps: &[Prepared],
    dir: &std::path::Path,
) -> Result<Vec<Option<Baseline>>, Vec<Error>> {
    let mut out = Vec::new();
    let mut errs = Vec::new();
    for p in preps {
        let path = baseline::path_for(dir, &p.scenario.name);
        match Baseline::load(&path, &p.scenario.name, p.scenario.planner.kind()) {
            Ok(b) => out.push(Some(b)),
            Err(e) => errs.push(e),
        }
    }
    if errs.is_empty() {
        Ok(out)
    } else {
        Err(errs)
    }
}

/// `--resume`: what each sweep's records file already holds.
fn resume_states(
    preps: &[Prepared],
    root: &std::path::Path,
    shard: Option<anholonomy::sweep::Shard>,
) -> Result<Vec<Option<anholonomy::sweep::records::Scan>>, Vec<Error>> {
    let mut out = Vec::new();
    let mut errs = Vec::new();
    for p in preps {
        match anholonomy::sweep::resumable(p, root, shard) {
            Ok(s) => out.push(s),
            Err(e) => {
                errs.push(e);
                out.push(None);
            }
        }
    }
    if errs.is_empty() {
        Ok(out)
    } else {
        Err(errs)
    }
}

/// Baselines written (`baseline`, `--update-baseline`) or compared, and
/// each run's `regression.json`: the deltas per result, and write errors.
fn settle_baselines(
    preps: &[Prepared],
    results: &[(usize, Outcome)],
    baselines: &[Option<Baseline>],
    base_dir: Option<&std::path::Path>,
    updating: bool,
) -> (Vec<Option<Vec<Delta>>>, Vec<Error>) {
    let mut deltas: Vec<Option<Vec<Delta>>> = results.iter().map(|_| None).collect();
    let mut errors = Vec::new();
    for (k, (i, res)) in results.iter().enumerate() {
        let Ok(o) = res else { continue };
        let p = &preps[*i];
        if let (Some(dir), true) = (base_dir, updating) {
            let path = baseline::path_for(dir, &o.name);
            if let Err(m) = Baseline::from_outcome(o).write(&path) {
                errors.push(Error::Log {
                    path,
                    message: m.to_string(),
                });
            }
        } else if let Some(b) = &baselines[*i] {
            let spec = anholonomy::compare::metric_spec(p.system.model());
            let d = baseline::compare(b, o, &p.scenario.regression, baseline::direction, |m| {
                baseline::floor_of(&p.scenario, &spec, m)
            });
            deltas[k] = Some(d);
        }
        if let Err(e) = record_regression(o, deltas[k].as_deref()) {
            errors.push(e);
        }
    }
    (deltas, errors)
}

/// The baseline comparison table; returns how many scenarios regressed.
fn print_comparison(
    dir: &std::path::Path,
    results: &[(usize, Outcome)],
    deltas: &[Option<Vec<Delta>>],
) -> usize {
    let table: Vec<(String, Vec<Delta>)> = results
        .iter()
        .zip(deltas)
        .filter_map(|((_, r), d)| Some((r.as_ref().ok()?.name.clone(), d.clone()?)))
        .collect();
    say!("\nbaseline comparison ({}):", anholonomy::echo::path(dir));
    say!("{}", baseline::format_table(&table).trim_end());
    table
        .iter()
        .filter(|(_, d)| d.iter().any(|d| d.status.fails()))
        .count()
}

/// `--junit PATH`: one test case per scenario, failures and errors included.
fn write_junit(
    path: &std::path::Path,
    preps: &[Prepared],
    results: &[(usize, Outcome)],
    deltas: &[Option<Vec<Delta>>],
    t_all: Instant,
) -> Option<Error> {
    let cases: Vec<CaseResult<'_>> = results
        .iter()
        .zip(deltas)
        .map(|((i, r), d)| match r {
            Ok(o) => CaseResult::Ran {
                outcome: o,
                deltas: d.as_deref(),
                sweep: preps[*i].scenario.sweep.is_some(),
            },
            Err((e, wall)) => CaseResult::Failed {
                name: &preps[*i].scenario.name,
                planner: preps[*i].scenario.planner.kind(),
                error: e,
                wall_s: *wall,
            },
        })
        .collect();
    let rep = junit::report(&cases, t_all.elapsed().as_secs_f64());
    junit::write(path, &rep).err().map(|e| Error::Log {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// `--report`: the HTML report of this call's scenarios.
fn write_report(args: &RunArgs, rows: &[RunOutcome]) -> Option<Error> {
    let names: Vec<String> = rows.iter().map(|o| o.name.clone()).collect();
    match anholonomy::report::write_report(&args.logs, Some(&names)) {
        Ok(w) => {
            for e in &w.skipped {
                eprintln!("warning: left out of the report: {e}");
            }
            say!(
                "report: {} ({} scenarios)",
                anholonomy::echo::path(&args.logs.join("index.html")),
                w.scenarios
            );
            None
        }
        Err(e) => Some(e),
    }
}

/// 1 when `check` finds a broken threshold, an XPASS or a regression
/// (each counted on stderr), else 0.
fn exit_status(mode: Mode, rows: &[RunOutcome], regressed: usize) -> u8 {
    let failed = rows.iter().filter(|o| !o.verdict.ok()).count();
    if mode != Mode::Check || (failed == 0 && regressed == 0) {
        return 0;
    }
    let count = |v: Verdict| rows.iter().filter(|o| o.verdict == v).count();
    if count(Verdict::Fail) > 0 {
        eprintln!(
            "{} of {} scenarios broke a threshold",
            count(Verdict::Fail),
            rows.len()
        );
    }
    if count(Verdict::Xpass) > 0 {
        eprintln!(
            "{} of {} scenarios met every threshold although they are expected to fail (XPASS): check them and drop `expect = \"fails\"`, or restore what they show",
            count(Verdict::Xpass),
            rows.len()
        );
    }
    if regressed > 0 {
        eprintln!(
            "{regressed} of {} scenarios regressed against their baseline",
            rows.len()
        );
    }
    1
}
