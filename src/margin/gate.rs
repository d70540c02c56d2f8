//! `[margins]` gates in `run`, `check` and `baseline`: each gated dimension
//! is checked at its gate, one level (one run; a random dimension its
//! seeds), not searched. The search (`anholonomy margin`) assumes the gates
//! hold below an edge and break above it, and checks that on the way; under
//! the same assumption a pass at the gate means the margin is at least the
//! gate, which is all the gate asks. `check` on `rover_paper` thereby costs
//! the nominal run plus one level instead of a ten-level search.

use crate::engine::perturb::{Dimension, Perturbation};
use crate::margin::level::{self, Ctx, Run};
use crate::margin::search::Status;
use crate::margin::{
    most_frequent, nearest_gate, output, DimensionResult, Level, Nominal, Report, Settings, FORMAT,
};
use crate::runner::RunOutcome;
use crate::scenario::MarginsConfig;
use crate::validate::Prepared;
use rayon::prelude::*;
use std::time::Instant;

/// One gated dimension checked at its gate alone (`run`/`check`/`baseline`):
/// the level at the gate runs (a random dimension: its seeds), and passes
/// or fails like a level of the search. The search assumes the gates hold
/// below an edge and break above it (monotonicity, checked by `margin`), so
/// a pass at the gate means the margin is at least the gate: one run
/// answers what the gate asks, where the search took ten.
pub fn check_gate(
    ctx: &Ctx<'_>,
    d: Dimension,
    least: f64,
    nominal: &Nominal,
    s: &Settings,
) -> DimensionResult {
    let t0 = Instant::now();
    let seeds = if d.random() { s.seeds.max(1) } else { 1 };
    let nominal_level = Level {
        level: 0.0,
        value: d.value_at(0.0),
        passed: nominal.passed,
        round: 0,
        successes: usize::from(nominal.passed),
        runs: Vec::new(),
    };
    let mut levels = vec![nominal_level];
    let status = if !nominal.passed {
        Status::NominalFails
    } else if least <= 0.0 {
        // The gate is the nominal run itself.
        Status::Holds
    } else {
        let base = ctx.prep.scenario.sim.perturb;
        let runs: Vec<Run> = (0..seeds as u64)
            .collect::<Vec<u64>>()
            .par_iter()
            .with_max_len(1)
            .map(|&k| {
                let mut p: Perturbation = base;
                d.set(&mut p, d.value_at(least));
                if d.random() {
                    p.seed = k;
                }
                level::run(ctx, &p, d.random().then_some(k))
            })
            .collect();
        let successes = runs.iter().filter(|r| r.passed).count();
        let passed = if d.random() {
            successes as f64 >= s.success_rate * seeds as f64 - 1e-9
        } else {
            successes == 1
        };
        levels.push(Level {
            level: least,
            value: d.value_at(least),
            passed,
            round: 1,
            successes,
            runs,
        });
        if passed {
            Status::Holds
        } else {
            Status::Breaks
        }
    };
    let first_broken = match status {
        Status::NominalFails => nominal.broken.clone(),
        Status::Breaks => most_frequent(&levels[1].runs),
        _ => Vec::new(),
    };
    let breaking_metric = first_broken
        .first()
        .map(|b| b.metric.clone())
        .or_else(|| nearest_gate(ctx, levels.last()));
    let runs: Vec<&Run> = levels.iter().flat_map(|l| &l.runs).collect();
    let margin = if status == Status::Holds { least } else { 0.0 };
    DimensionResult {
        dimension: d,
        unit: d.unit(),
        status,
        margin,
        value_at_margin: d.value_at(margin),
        first_failing: (status == Status::Breaks).then_some(least),
        non_monotone: false,
        inversions: Vec::new(),
        first_broken,
        breaking_metric,
        jumps: Vec::new(),
        default_caps: super::caps::default_caps(ctx.prep, d),
        runs: runs.len(),
        rounds: usize::from(!runs.is_empty()),
        seeds: d.random().then_some(seeds),
        cpu_s: runs.iter().map(|r| r.cpu_s).sum(),
        levels,
        wall_s: t0.elapsed().as_secs_f64(),
    }
}

/// `[margins]` of a scenario in `run`/`check`/`baseline`: every gated
/// dimension is checked at its gate ([`check_gate`]: one run each, in
/// parallel) after the nominal run `o`. Each adds a metric
/// `margin_<dimension>`: the gate when it holds (a lower bound of the
/// margin, "holds at 0.02"), NaN when it breaks; a broken gate fails the
/// run. `margins.json` goes beside the logs. `anholonomy margin` gives the
/// margin itself.
pub fn gate(prep: &Prepared, o: &mut RunOutcome) -> Result<(), crate::error::Error> {
    let gates = prep.scenario.margins.gates();
    if gates.is_empty() {
        return Ok(());
    }
    let t0 = Instant::now();
    let s = Settings::of(&prep.scenario.margins);
    let nominal = Nominal::of(prep, o);
    let ctx = Ctx::new(prep);
    let dimensions: Vec<DimensionResult> = gates
        .par_iter()
        .with_max_len(1)
        .map(|&(d, least)| check_gate(&ctx, d, least, &nominal, &s))
        .collect();
    for ((d, least), r) in gates.iter().zip(&dimensions) {
        let name = MarginsConfig::metric(*d);
        let at = output::magnitude(*d, *least);
        match r.status {
            Status::Holds => {
                o.metrics.push((name.clone(), *least));
                o.notes.push(format!("{d} holds at {at}"));
            }
            _ => {
                o.metrics.push((name.clone(), f64::NAN));
                let why = r
                    .first_broken
                    .first()
                    .map(|b| format!(": {b}"))
                    .unwrap_or_default();
                let what = if r.status == Status::NominalFails {
                    "the nominal run already fails".to_string()
                } else {
                    format!(
                        "breaks at {d} = {}{}{why}",
                        crate::numfmt::readable(d.value_at(*least)),
                        match d.unit() {
                            "" => String::new(),
                            u => format!(" {u}"),
                        }
                    )
                };
                o.failures.push(format!("{name} < {at}: {what}"));
                o.passed = false;
            }
        }
    }
    // The verdict the run computed did not know the margins.
    o.verdict =
        crate::verdict::Verdict::of(o.failures.is_empty(), prep.scenario.expect_fails.is_some());
    let wall = t0.elapsed().as_secs_f64();
    o.timings.total += wall;
    if let Some(dir) = &o.log_dir {
        let report = Report {
            anholonomy_margins: FORMAT,
            scenario: prep.scenario.name.clone(),
            file: prep.scenario.path.clone(),
            model: prep.scenario.model.kind(),
            planner: prep.scenario.planner.kind(),
            search: s,
            gates: gates
                .iter()
                .map(|(d, g)| (d.name().to_string(), *g))
                .collect(),
            thresholds: prep.scenario.thresholds.clone(),
            minimums: prep.scenario.minimums.clone(),
            nominal,
            dimensions,
        };
        let log_error = |e: &dyn std::fmt::Display| crate::error::Error::Log {
            path: prep.scenario.path.clone(),
            message: e.to_string(),
        };
        report.write(dir, wall).map_err(|e| log_error(&e))?;
        amend_summary(&dir.join("summary.json"), o).map_err(|e| log_error(&e))?;
    }
    Ok(())
}

/// The run's `summary.json` with the margins' verdict: `passed`, `failures`
/// and `metrics` as the outcome now has them (the run wrote it before the
/// margins were searched).
fn amend_summary(path: &std::path::Path, o: &RunOutcome) -> Result<(), SummaryError> {
    let text = std::fs::read_to_string(path).map_err(|source| SummaryError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let mut s: serde_json::Value =
        serde_json::from_str(&text).map_err(|source| SummaryError::Parse {
            path: path.to_path_buf(),
            source,
        })?;
    s["passed"] = serde_json::json!(o.passed);
    s["failures"] = serde_json::json!(o.failures);
    s["verdict"] = serde_json::json!(o.verdict);
    let metrics: std::collections::BTreeMap<&str, f64> =
        o.metrics.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    s["metrics"] = serde_json::json!(metrics);
    s["margin_gates"] = serde_json::json!(o.notes);
    s["wall_time_s"]["total"] = serde_json::json!(o.timings.total);
    crate::log::atomic::write_file(path, |w| {
        serde_json::to_writer_pretty(w, &s).map_err(std::io::Error::other)
    })?;
    Ok(())
}

/// Why `summary.json` could not be amended with the margins' verdict.
#[derive(Debug, thiserror::Error)]
enum SummaryError {
    /// The run's summary cannot be read.
    #[error("{}: {source}", crate::echo::path(path))]
    Read {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    /// The run's summary is not JSON.
    #[error("{}: {source}", crate::echo::path(path))]
    Parse {
        path: std::path::PathBuf,
        source: serde_json::Error,
    },
    /// Writing it back failed.
    #[error(transparent)]
    Write(#[from] crate::log::LogError),
}
