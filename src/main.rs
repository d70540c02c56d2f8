//! `anholonomy` command-line interface.

use anholonomy::baseline::{self, Baseline, Delta};
use anholonomy::error::Error;
use anholonomy::integrate::simulate;
use anholonomy::junit::{self, CaseResult};
use anholonomy::runner::{Prepared, RunOptions, RunOutcome};
use anholonomy::say;
use anholonomy::validate::{prepare_all, prepare_each, Call};
use anholonomy::verdict::Verdict;
use clap::Parser;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

mod cli;
use cli::{Cli, Cmd, RunArgs};

/// What `run_cmd` does with the baselines.
#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Run,
    Check,
    WriteBaselines,
}

/// A metric for the table: 4 significant digits at any magnitude (a goal
/// error of 1e300 from a runaway plan is `1e300`, not 300 digits).
fn fmt_metric(o: &RunOutcome, name: &str) -> String {
    o.metric(name)
        .map(anholonomy::numfmt::readable)
        .unwrap_or_else(|| "-".into())
}

/// The coordinate the table reports: the planar position when the model has
/// one, else its first coordinate (the first `ideal_goal_*` metric).
fn primary(o: &RunOutcome) -> Option<&str> {
    o.metrics
        .iter()
        .find_map(|(n, _)| n.strip_prefix("ideal_goal_"))
}

/// A tracking column: the number, or `n/a` when tracking means nothing for the run.
fn fmt_tracking(o: &RunOutcome, name: &str) -> String {
    if o.tracking_meaningful {
        fmt_metric(o, name)
    } else {
        "n/a".into()
    }
}

/// The result column: the verdict, and the `[margins]` gates that held.
fn result(o: &RunOutcome) -> String {
    let v = o.verdict.describe(&o.failures, o.expect_reason.as_deref());
    if o.notes.is_empty() {
        v
    } else {
        format!("{v} ({})", o.notes.join("; "))
    }
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
            fmt_tracking(o, &format!("tracking_{c}_rms")),
            fmt_tracking(o, &format!("tracking_{c}_max")),
            result(o)
        );
    }
    if rows.iter().any(|o| !o.tracking_meaningful) {
        say!("n/a: tracking error means nothing for a feedback policy (each run closes the loop on its own state and reaches the goal at its own time); see sim goal.");
    }
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
        Some(d) => anholonomy::log::atomic::write_atomic(&path, |w| {
            serde_json::to_writer_pretty(w, d).map_err(std::io::Error::other)
        })
        .map_err(log_err),
        None => match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(log_err(e.to_string())),
            _ => Ok(()),
        },
    }
}

/// A scenario's outcome, or its error and wall time (s) for JUnit.
type Outcome = Result<RunOutcome, (Error, f64)>;

fn run_cmd(args: &RunArgs, mode: Mode) -> Result<u8, Vec<Error>> {
    let t_all = Instant::now();
    let shard = match &args.shard {
        Some(s) => {
            Some(anholonomy::sweep::Shard::parse(s).map_err(|m| vec![Error::input("--shard", m)])?)
        }
        None => match anholonomy::sweep::Shard::from_env(|k| std::env::var(k).ok(), args.shards) {
            Ok(Some((s, from))) => {
                eprintln!("{from}");
                Some(s)
            }
            Ok(None) => None,
            Err(m) => return Err(vec![Error::input("--shard", m)]),
        },
    };
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
    // Every baseline is read (and checked) before anything runs.
    let baselines: Vec<Option<Baseline>> = match (&base_dir, updating) {
        (Some(dir), false) => {
            let mut out = Vec::new();
            let mut errs = Vec::new();
            for p in &preps {
                let path = baseline::path_for(dir, &p.scenario.name);
                match Baseline::load(&path, &p.scenario.name, p.scenario.planner.kind()) {
                    Ok(b) => out.push(Some(b)),
                    Err(e) => errs.push(e),
                }
            }
            if !errs.is_empty() {
                return Err(errs);
            }
            out
        }
        _ => preps.iter().map(|_| None).collect(),
    };
    // --resume: every records file is read and checked before anything runs.
    let mut resumed = Vec::new();
    if let (true, Some(root)) = (args.resume, &log_root) {
        let mut errs = Vec::new();
        for p in &preps {
            match anholonomy::sweep::resumable(p, root, shard) {
                Ok(s) => resumed.push(s),
                Err(e) => {
                    errs.push(e);
                    resumed.push(None);
                }
            }
        }
        if !errs.is_empty() {
            return Err(errs);
        }
    }
    let opts = RunOptions {
        log_root,
        progress: !args.quiet,
        pose_rate: args.pose_rate,
        cancel: Default::default(),
        keep: args.keep,
        batch: !args.no_batch,
    };
    let mut rows = Vec::new();
    let mut results: Vec<(usize, Outcome)> = Vec::new();
    // Independent scenarios run in parallel; results come back in input order.
    let ran = anholonomy::suite::run_all(&preps, &opts, shard, &resumed);
    for (i, (res, wall)) in ran.into_iter().enumerate() {
        match res {
            Ok(o) => {
                rows.push(o.clone());
                results.push((i, Ok(o)));
            }
            Err(e) => results.push((i, Err((e, wall)))),
        }
    }
    print_table(&rows);
    // What the physics filled in or left out of a URDF, once per scenario.
    for p in &preps {
        for w in &p.reading.warnings {
            eprintln!("warning: {}: {w}", p.scenario.name);
        }
    }

    // Baselines: compare or write.
    let mut deltas: Vec<Option<Vec<Delta>>> = results.iter().map(|_| None).collect();
    let mut errors = Vec::new();
    for (k, (i, res)) in results.iter().enumerate() {
        let Ok(o) = res else { continue };
        let p = &preps[*i];
        if let (Some(dir), true) = (&base_dir, updating) {
            let path = baseline::path_for(dir, &o.name);
            if let Err(m) = Baseline::from_outcome(o).write(&path) {
                errors.push(Error::Log { path, message: m });
            }
        } else if let Some(b) = &baselines[*i] {
            let d = baseline::compare(b, o, &p.scenario.regression, |m| {
                baseline::direction(p.system.as_ref(), m)
            });
            deltas[k] = Some(d);
        }
        if let Err(e) = record_regression(o, deltas[k].as_deref()) {
            errors.push(e);
        }
    }
    let mut regressed = 0;
    if base_dir.is_some() && !updating {
        let table: Vec<(String, Vec<Delta>)> = results
            .iter()
            .zip(&deltas)
            .filter_map(|((_, r), d)| Some((r.as_ref().ok()?.name.clone(), d.clone()?)))
            .collect();
        regressed = table
            .iter()
            .filter(|(_, d)| d.iter().any(|d| d.status.fails()))
            .count();
        say!(
            "\nbaseline comparison ({}):",
            base_dir
                .as_ref()
                .map(|d| d.display().to_string())
                .unwrap_or_default()
        );
        say!("{}", baseline::format_table(&table).trim_end());
    } else if let (Some(dir), true) = (&base_dir, updating) {
        let n = results.iter().filter(|(_, r)| r.is_ok()).count();
        say!("wrote {n} baseline(s) to {}", dir.display());
    }

    if let Some(path) = &args.junit {
        let cases: Vec<CaseResult<'_>> = results
            .iter()
            .zip(&deltas)
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
        if let Err(m) = junit::write(path, &rep) {
            errors.push(Error::Log {
                path: path.clone(),
                message: m,
            });
        }
    }
    if args.report {
        let names: Vec<String> = rows.iter().map(|o| o.name.clone()).collect();
        match anholonomy::report::write_report(&args.logs, Some(&names)) {
            Ok(w) => {
                for e in &w.skipped {
                    eprintln!("warning: left out of the report: {e}");
                }
                say!(
                    "report: {} ({} scenarios)",
                    args.logs.join("index.html").display(),
                    w.scenarios
                )
            }
            Err(e) => errors.push(e),
        }
    }
    errors.extend(
        results
            .into_iter()
            .filter_map(|(_, r)| r.err().map(|(e, _)| e)),
    );
    if !errors.is_empty() {
        return Err(errors);
    }
    let failed = rows.iter().filter(|o| !o.verdict.ok()).count();
    if mode == Mode::Check && (failed > 0 || regressed > 0) {
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
        return Ok(1);
    }
    Ok(0)
}

fn report_cmd(logdir: &Path) -> Result<u8, Vec<Error>> {
    let t0 = Instant::now();
    let w = anholonomy::report::write_report(logdir, None).map_err(|e| vec![e])?;
    say!(
        "report: {} ({} scenarios, {:.2} s)",
        logdir.join("index.html").display(),
        w.scenarios,
        t0.elapsed().as_secs_f64()
    );
    Ok(0)
}

fn plan_cmd(file: &std::path::Path, as_json: bool, max_steps: u64) -> Result<u8, Vec<Error>> {
    if file.is_dir() {
        return Err(vec![Error::input(
            file,
            "`plan` takes one scenario file, not a directory",
        )]);
    }
    let call = Call {
        max_steps: Some(max_steps),
        ..Call::default()
    };
    let preps = prepare_all(&[file.to_path_buf()], &call)?;
    let prep = &preps[0];
    let plan = &prep.planned;
    let (start, _goal) = prep.start_goal();
    let ideal = simulate(prep.model(), plan, &start, prep.scenario.sim.dt);
    let fin: Vec<f64> = ideal.last().iter().copied().collect();
    let (_, goal) = prep.start_goal();
    let paper = prep.system.paper(&start, &goal, plan);
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
            "paper": paper,
            "read_from_urdf": prep.reading,
        });
        say!("{}", serde_json::to_string_pretty(&v).unwrap_or_default());
    } else {
        say!(
            "{} ({}), duration {} s",
            prep.scenario.name,
            prep.scenario.planner.kind(),
            anholonomy::numfmt::with_digits(plan.duration, 7)
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
        say!("  ideal final state: {}", display_state(prep.model(), &fin));
        say!("read from {}:", prep.scenario.urdf.display());
        for line in prep.reading.lines() {
            say!("{line}");
        }
        if !paper.is_empty() {
            say!("{}", anholonomy::paper::format_table(&paper).trim_end());
        }
    }
    Ok(0)
}

/// A state as the scenario files write it: angles in degrees, lengths in m.
fn display_state(model: &dyn anholonomy::model::KinematicModel, q: &[f64]) -> String {
    let angular = model.angular_states();
    let position = model.position_states();
    let fmt = |x: f64| anholonomy::numfmt::with_digits(x, 6);
    model
        .state_names()
        .iter()
        .zip(q)
        .enumerate()
        .map(|(i, (n, x))| {
            if angular.contains(&i) {
                format!("{n} = {} deg", fmt(x.to_degrees()))
            } else if position.is_some_and(|p| p.contains(&i)) {
                format!("{n} = {} m", fmt(*x))
            } else {
                format!("{n} = {}", fmt(*x))
            }
        })
        .collect::<Vec<_>>()
        .join(", ")
}

fn list_cmd(paths: &[PathBuf], max_steps: u64) -> Result<u8, Vec<Error>> {
    let paths = if paths.is_empty() {
        vec![PathBuf::from("scenarios")]
    } else {
        paths.to_vec()
    };
    let call = Call {
        max_steps: Some(max_steps),
        ..Call::default()
    };
    let (preps, errors) = prepare_each(&paths, &call);
    let rows: Vec<[&str; 4]> = preps
        .iter()
        .map(|p| {
            let s = &p.scenario;
            [
                s.name.as_str(),
                s.model.kind(),
                s.planner.kind(),
                s.description.as_str(),
            ]
        })
        .collect();
    let header = ["scenario", "model", "planner", "description"];
    let width = |c: usize| {
        rows.iter()
            .chain([&header])
            .map(|r| r[c].chars().count())
            .max()
            .unwrap_or(0)
    };
    let (w0, w1, w2) = (width(0), width(1), width(2));
    for r in [&header]
        .into_iter()
        .chain(&rows)
        .take(if rows.is_empty() { 0 } else { usize::MAX })
    {
        say!("{:<w0$}  {:<w1$}  {:<w2$}  {}", r[0], r[1], r[2], r[3]);
    }
    if errors.is_empty() {
        Ok(0)
    } else {
        Err(errors)
    }
}

fn keys_cmd(name: Option<&str>, markdown: bool, out: Option<&Path>) -> Result<u8, Vec<Error>> {
    use anholonomy::reference::Page;
    if let Some(dir) = out {
        if !markdown {
            return Err(vec![Error::input(
                "--out",
                "writes Markdown pages: add --markdown",
            )]);
        }
        let mut pages = Vec::new();
        for p in Page::all() {
            let text = p.markdown().map_err(|m| vec![Error::input("keys", m)])?;
            pages.push((dir.join(p.file()), text));
        }
        for (path, text) in &pages {
            let parent = path.parent().unwrap_or(Path::new("."));
            std::fs::create_dir_all(parent).map_err(|e| {
                vec![Error::Log {
                    path: parent.to_path_buf(),
                    message: e.to_string(),
                }]
            })?;
            anholonomy::log::atomic::write_atomic(path, |w| {
                std::io::Write::write_all(w, text.as_bytes())
            })
            .map_err(|message| {
                vec![Error::Log {
                    path: path.clone(),
                    message,
                }]
            })?;
        }
        say!("wrote {} pages to {}", pages.len(), dir.display());
        return Ok(0);
    }
    let Some(name) = name else {
        let models = anholonomy::scenario::ModelConfig::KINDS.join(", ");
        let planners = anholonomy::scenario::PlannerConfig::KINDS.join(", ");
        say!("anholonomy keys NAME prints the keys of:\n  scenario   the file's own tables (top level, [limits], [sim], [thresholds], [sweep], [regression])\n  models     {models}\n  planners   {planners}");
        return Ok(0);
    };
    let Some(page) = Page::find(name) else {
        let mut known = vec!["scenario"];
        known.extend(anholonomy::scenario::ModelConfig::KINDS);
        known.extend(anholonomy::scenario::PlannerConfig::KINDS);
        return Err(vec![Error::input(
            "keys",
            format!(
                "`{name}` is not a model or planner kind (known: {})",
                known.join(", ")
            ),
        )]);
    };
    let text = if markdown {
        page.markdown()
    } else {
        page.text()
    }
    .map_err(|m| vec![Error::input("keys", m)])?;
    anholonomy::emit(&text);
    Ok(0)
}

fn merge_cmd(paths: &[PathBuf], out: Option<&Path>) -> Result<u8, Vec<Error>> {
    let (sum, path) = anholonomy::sweep::merge::merge(paths, out)?;
    anholonomy::emit(&sum.table);
    say!("merged: {}", path.display());
    Ok(0)
}

/// A command-line error as one line (exit 2, like every bad input): clap's
/// own first line, with its tip (a similar argument, `--` before a value)
/// in parentheses, without the usage block. Help and version are printed
/// as clap prints them.
fn one_line(e: &clap::Error) -> String {
    let text = e.render().to_string();
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let first = lines.next().unwrap_or("error: bad arguments");
    let first = first.strip_prefix("error: ").unwrap_or(first);
    let tips: Vec<&str> = lines.filter_map(|l| l.strip_prefix("tip: ")).collect();
    if tips.is_empty() {
        first.to_string()
    } else {
        format!("{first} (tip: {})", tips.join("; "))
    }
}

fn main() -> ExitCode {
    // External laws run in process groups of their own: Ctrl-C reaches
    // them through the harness.
    #[cfg(unix)]
    anholonomy::planner::external::process::on_signal::install();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            eprintln!("error: {}", one_line(&e));
            return ExitCode::from(2);
        }
    };
    let res = match &cli.cmd {
        Cmd::Run(a) => run_cmd(a, Mode::Run),
        Cmd::Check(a) => run_cmd(a, Mode::Check),
        Cmd::Baseline(a) => run_cmd(a, Mode::WriteBaselines),
        Cmd::Report { logdir } => report_cmd(logdir),
        Cmd::Plan {
            file,
            json,
            max_steps,
        } => plan_cmd(file, *json, *max_steps),
        Cmd::List { paths, max_steps } => list_cmd(paths, *max_steps),
        Cmd::Keys {
            name,
            markdown,
            out,
        } => keys_cmd(name.as_deref(), *markdown, out.as_deref()),
        Cmd::Merge { paths, out } => merge_cmd(paths, out.as_deref()),
        Cmd::Margin(a) => anholonomy::margin::cli::margin_cmd(a),
        Cmd::Init(a) => anholonomy::init::init_cmd(a),
        Cmd::Models(a) => anholonomy::init::models_cmd(a),
    };
    match res {
        Ok(code) => ExitCode::from(code),
        Err(errors) => {
            for e in &errors {
                // A last guard for numbers a message writes in full (1e300 as
                // 301 digits): the messages format theirs readably already.
                eprintln!(
                    "error: {}",
                    anholonomy::numfmt::shorten_long_numbers(&e.to_string())
                );
            }
            ExitCode::from(errors.iter().map(|e| e.exit_code()).max().unwrap_or(2) as u8)
        }
    }
}
