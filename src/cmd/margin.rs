//! `anholonomy margin FILE|DIR... [--dimension NAME]...`.

use anholonomy::engine::perturb::Dimension;
use anholonomy::error::Error;
use anholonomy::margin::{output, Nominal, Settings, DEFAULT_BATCH};
use anholonomy::runner::{RunOptions, DEFAULT_POSE_RATE};
use anholonomy::validate::{not_applicable, prepare_all, Call, Prepared};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `anholonomy margin`.
#[derive(clap::Args, Debug)]
pub struct MarginArgs {
    /// Scenario files, or directories whose *.toml files are all searched (sorted).
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
    /// A dimension to search (repeat for several): command_latency,
    /// actuator_tau, torque_scale, state_noise, state_latency,
    /// wheel_radius_scale, friction_scale, mass_scale. Default: every
    /// dimension that applies to the scenario.
    #[arg(long = "dimension", value_name = "NAME")]
    pub dimensions: Vec<String>,
    /// Directory for the nominal run's logs and margins.json (LOGS/<scenario>/).
    #[arg(long, default_value = "logs")]
    pub logs: PathBuf,
    /// Write no logs and no margins.json.
    #[arg(long)]
    pub no_logs: bool,
    /// Also write the HTML report (with the pass/fail plots against each perturbation).
    #[arg(long)]
    pub report: bool,
    /// Print the table as Markdown.
    #[arg(long, conflicts_with = "json")]
    pub markdown: bool,
    /// Print the margins as JSON (an array: one margins.json per scenario) instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Relative resolution: bisect until the edge lies within margin·(1 + R)
    /// [default: the scenario's `margins.resolution`, else 0.05].
    #[arg(long, value_name = "R", allow_negative_numbers = true)]
    pub resolution: Option<f64>,
    /// Seeds per level of a random dimension (state_noise)
    /// [default: `margins.seeds`, else 8].
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub seeds: Option<i64>,
    /// Fraction of a random level's seeds that must pass
    /// [default: `margins.success_rate`, else 0.875].
    #[arg(long, value_name = "F", allow_negative_numbers = true)]
    pub success_rate: Option<f64>,
    /// Levels run in parallel per round. It decides which levels are
    /// probed, so the margins depend on it (within the resolution), never on
    /// the number of threads.
    #[arg(long, value_name = "B", default_value_t = DEFAULT_BATCH as i64, allow_negative_numbers = true)]
    pub batch: i64,
    /// At most N runs per dimension: the search stops before a round that
    /// would exceed it and reports the bracket reached (a coarser edge,
    /// noted as such) [default: no limit].
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    pub max_runs: Option<i64>,
    /// Print nothing on stderr while searching.
    #[arg(long)]
    pub quiet: bool,
    /// Step budget per run (as for `run`).
    #[arg(long, value_name = "N", default_value_t = anholonomy::validate::DEFAULT_MAX_STEPS)]
    pub max_steps: u64,
}

/// The dimensions named on the command line; an unknown name is bad input.
fn parse_dimensions(names: &[String]) -> Result<Vec<Dimension>, Vec<Error>> {
    let mut out = Vec::new();
    let mut errors = Vec::new();
    for n in names {
        match Dimension::parse(n) {
            Some(d) if !out.contains(&d) => out.push(d),
            Some(_) => {}
            None => {
                let known: Vec<&str> = Dimension::all().map(|d| d.name()).collect();
                let hint = known
                    .iter()
                    .map(|k| (strsim::jaro_winkler(n, k), k))
                    .max_by(|a, b| a.0.total_cmp(&b.0))
                    .filter(|(s, _)| *s >= 0.8)
                    .map(|(_, k)| format!(" (did you mean `{k}`?)"))
                    .unwrap_or_default();
                errors.push(Error::input(
                    "--dimension",
                    format!(
                        "unknown dimension {}{hint}; known: {}",
                        anholonomy::echo::code(n),
                        known.join(", ")
                    ),
                ));
            }
        }
    }
    if errors.is_empty() {
        Ok(out)
    } else {
        Err(errors)
    }
}

/// The search settings: command line, else the scenario's `[margins]`, else defaults.
fn settings(a: &MarginArgs, prep: &Prepared) -> Settings {
    let cfg = &prep.scenario.margins;
    Settings {
        resolution: a.resolution.unwrap_or(cfg.resolution()),
        // Ranges checked by `check_options`.
        seeds: a.seeds.map_or(cfg.seeds(), |n| n as usize),
        success_rate: a.success_rate.unwrap_or(cfg.success_rate()),
        batch: a.batch as usize,
        max_runs: a.max_runs.map(|n| n as usize),
    }
}

fn check_options(a: &MarginArgs) -> Result<(), Vec<Error>> {
    use anholonomy::numfmt::shortest;
    let bad = |opt: &str, m: String| Err(vec![Error::input(opt, m)]);
    if let Some(r) = a.resolution {
        if !(r > 0.0 && r <= 1.0) {
            return bad(
                "--resolution",
                format!("{}: must be in (0, 1]", shortest(r)),
            );
        }
    }
    if let Some(n) = a.seeds {
        if !(1..=1000).contains(&n) {
            return bad("--seeds", format!("{n}: must be in 1..=1000"));
        }
    }
    if let Some(f) = a.success_rate {
        if !(f > 0.0 && f <= 1.0) {
            return bad(
                "--success-rate",
                format!("{}: must be in (0, 1]", shortest(f)),
            );
        }
    }
    if let Some(n) = a.max_runs {
        if !(1..=100_000).contains(&n) {
            return bad("--max-runs", format!("{n}: must be in 1..=100000"));
        }
    }
    if !(1..=64).contains(&a.batch) {
        return bad("--batch", format!("{}: must be in 1..=64", a.batch));
    }
    if a.report && a.no_logs {
        return bad(
            "--report",
            "the report is written into the logs: drop --no-logs".into(),
        );
    }
    Ok(())
}

/// Why `d` does not apply to the scenario, in a few words (the table's
/// note; the error for a dimension asked of no scenario says it at length).
fn why_not(d: Dimension, sc: &anholonomy::scenario::Scenario) -> String {
    match d {
        d if d.observes() => format!("open-loop plan (`{}` reads no state)", sc.planner.kind()),
        Dimension::WheelRadiusScale => "no wheels".into(),
        Dimension::FrictionScale => "no contacts (nothing touches anything)".into(),
        _ => format!("model `{}` does not take it", sc.model.kind()),
    }
}

/// What `margin` does with one scenario.
enum Todo {
    /// Nothing: no margin, with why (a sweep, a scenario expected to fail).
    Skip(String),
    /// Search `search`; the dimensions of `na` do not apply (with why).
    Search {
        search: Vec<Dimension>,
        na: Vec<(Dimension, String)>,
    },
}

impl Todo {
    fn searches(&self, d: Dimension) -> bool {
        matches!(self, Todo::Search { search, .. } if search.contains(&d))
    }
}

/// What to do with each scenario: the dimensions asked (every one when
/// none is named) that apply are searched, the others shown as n/a. A
/// dimension asked for that applies to no scenario of the call is bad input.
fn plan_dimensions(preps: &[Prepared], asked: &[Dimension]) -> Result<Vec<Todo>, Vec<Error>> {
    let all: Vec<Dimension> = Dimension::all().collect();
    let wanted: &[Dimension] = if asked.is_empty() { &all } else { asked };
    let mut out = Vec::new();
    for p in preps {
        let sc = &p.scenario;
        if sc.sweep.is_some() {
            out.push(Todo::Skip(
                "sweep: its verdict is a success rate over variants; margins are searched on single runs".into(),
            ));
            continue;
        }
        if sc.expect_fails.is_some() {
            // Its nominal run is meant to break a gate: no level passes.
            out.push(Todo::Skip(
                "expected to fail (`expect = \"fails\"`): no margin".into(),
            ));
            continue;
        }
        let applies = p.system.perturbable(&p.planned);
        let (search, na): (Vec<Dimension>, Vec<Dimension>) =
            wanted.iter().partition(|d| applies.contains(d));
        let na = na.into_iter().map(|d| (d, why_not(d, sc))).collect();
        out.push(Todo::Search { search, na });
    }
    let mut errors = Vec::new();
    for d in asked {
        if !out.iter().any(|t| t.searches(*d)) {
            // Name the first scenario it could have applied to.
            let single = preps
                .iter()
                .find(|p| p.scenario.sweep.is_none() && p.scenario.expect_fails.is_none());
            match single {
                Some(p) => errors.push(Error::input(
                    &p.scenario.path,
                    format!(
                        "option `--dimension {d}`: {}",
                        not_applicable(*d, &p.scenario, &p.system.perturbable(&p.planned))
                    ),
                )),
                None => errors.push(Error::input(
                    "--dimension",
                    "every scenario of the call is a sweep or expected to fail: no margin to search",
                )),
            }
        }
    }
    if errors.is_empty() {
        Ok(out)
    } else {
        Err(errors)
    }
}

/// What one scenario adds to the output.
struct Scenario {
    rows: Vec<output::Row>,
    json: Option<serde_json::Value>,
    /// Its name, when logs (and margins.json) were written.
    logged: Option<String>,
}

/// The nominal run (with its logs) and the margins of one scenario.
fn one(
    a: &MarginArgs,
    prep: &Prepared,
    todo: &Todo,
    opts: &RunOptions,
    bar: &ProgressBar,
) -> Result<Scenario, Error> {
    let name = &prep.scenario.name;
    let (dims, na) = match todo {
        Todo::Search { search, na } if !search.is_empty() => (search, na),
        Todo::Search { na, .. } => {
            // Nothing applies: nothing to run.
            return Ok(Scenario {
                rows: na
                    .iter()
                    .map(|(d, why)| output::na(name, *d, why))
                    .collect(),
                json: None,
                logged: None,
            });
        }
        Todo::Skip(why) => {
            return Ok(Scenario {
                rows: vec![output::skipped(name, why)],
                json: None,
                logged: None,
            })
        }
    };
    let t0 = Instant::now();
    // The nominal run, with its logs: level 0 of every dimension.
    let o = anholonomy::runner::run(prep, opts)?;
    let s = settings(a, prep);
    let progress = |r: &anholonomy::margin::DimensionResult| {
        bar.inc(1);
        if !a.quiet {
            let row = output::row(name, r);
            let line = format!(
                "{name}: {} margin {} ({} runs, {:.1} s CPU)",
                row.dimension, row.margin, row.runs, r.cpu_s
            );
            if bar.is_hidden() {
                eprintln!("{line}");
            } else {
                bar.println(line);
            }
        }
    };
    let rep = anholonomy::margin::margins(prep, Nominal::of(prep, &o), dims, &s, &progress);
    let wall = t0.elapsed().as_secs_f64();
    let logged = match &o.log_dir {
        Some(dir) => {
            rep.write(dir, wall).map_err(|e| Error::Log {
                path: dir.join("margins.json"),
                message: e.to_string(),
            })?;
            Some(name.clone())
        }
        None => None,
    };
    // Every dimension asked for, in `Dimension::ALL` order, n/a ones included.
    let mut rows: Vec<(Dimension, output::Row)> = rep
        .dimensions
        .iter()
        .map(|r| (r.dimension, output::row(name, r)))
        .chain(na.iter().map(|(d, why)| (*d, output::na(name, *d, why))))
        .collect();
    rows.sort_by_key(|(d, _)| Dimension::all().position(|x| x == *d));
    Ok(Scenario {
        rows: rows.into_iter().map(|(_, r)| r).collect(),
        json: Some(rep.to_json(wall)),
        logged,
    })
}

/// Dimensions searched so far, on stderr when it is a terminal.
fn progress_bar(total: u64, quiet: bool) -> ProgressBar {
    let target = if quiet {
        ProgressDrawTarget::hidden()
    } else {
        ProgressDrawTarget::stderr()
    };
    let bar = ProgressBar::with_draw_target(Some(total), target);
    if let Ok(style) =
        ProgressStyle::with_template("margins [{bar:40}] {pos}/{len} dimensions {elapsed}")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar
}

/// `anholonomy margin`: exit 0, 2 (bad input, nothing run) or 3 (a run or
/// the logs failed).
pub fn margin_cmd(a: &MarginArgs) -> Result<u8, Vec<Error>> {
    let asked = parse_dimensions(&a.dimensions)?;
    check_options(a)?;
    let log_root = (!a.no_logs).then(|| a.logs.clone());
    let call = Call {
        log_root: log_root.as_deref(),
        sharded: false,
        max_steps: Some(a.max_steps),
    };
    let preps = prepare_all(&a.paths, &call)?;
    let plan = plan_dimensions(&preps, &asked)?;
    let opts = RunOptions {
        log_root,
        progress: Default::default(),
        pose_rate: DEFAULT_POSE_RATE,
        keep: anholonomy::log::Keep::default(),
        cancel: Default::default(),
        batch: true,
    };
    let total: usize = plan
        .iter()
        .map(|t| match t {
            Todo::Search { search, .. } => search.len(),
            Todo::Skip(_) => 0,
        })
        .sum();
    let bar = progress_bar(total as u64, a.quiet);
    // Scenarios in parallel (each with its dimensions and levels in
    // parallel): results in input order, whatever the thread count.
    let done: Vec<Result<Scenario, Error>> = preps
        .par_iter()
        .zip(plan.par_iter())
        .with_max_len(1)
        .map(|(prep, todo)| one(a, prep, todo, &opts, &bar))
        .collect();
    bar.finish_and_clear();
    let mut rows = Vec::new();
    let mut reports = Vec::new();
    let mut names = Vec::new();
    let mut errors = Vec::new();
    for d in done {
        match d {
            Ok(s) => {
                rows.extend(s.rows);
                reports.extend(s.json);
                names.extend(s.logged);
            }
            Err(e) => errors.push(e),
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    if a.json {
        say!(
            "{}",
            serde_json::to_string_pretty(&reports).unwrap_or_default()
        );
    } else if a.markdown {
        crate::emit(&output::markdown(&rows));
    } else {
        crate::emit(&output::text(&rows));
    }
    if a.report && !names.is_empty() {
        let w = anholonomy::report::write_report(&a.logs, Some(&names)).map_err(|e| vec![e])?;
        for e in &w.skipped {
            eprintln!("warning: left out of the report: {e}");
        }
        say!(
            "report: {} ({} scenarios)",
            anholonomy::echo::path(&a.logs.join("index.html")),
            w.scenarios
        );
    }
    Ok(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_dimensions_are_named_with_a_hint() {
        let e = parse_dimensions(&["latency".into(), "command_latency".into()]).unwrap_err();
        assert_eq!(e.len(), 1);
        let m = e[0].to_string();
        assert!(
            m.starts_with("--dimension: unknown dimension `latency`"),
            "{m}"
        );
        assert!(m.contains("known: command_latency"), "{m}");
        let e = parse_dimensions(&["state_nosie".into()]).unwrap_err();
        assert!(e[0].to_string().contains("did you mean `state_noise`"));
        assert_eq!(
            parse_dimensions(&["mass_scale".into(), "mass_scale".into()]).unwrap(),
            vec![Dimension::MassScale]
        );
    }
}
