//! Robustness margins: for each perturbation dimension (others nominal),
//! the largest perturbation at which every gate of a scenario still holds.
//!
//! The search ([`search`]) brackets the edge and bisects it to a relative
//! resolution; each level is a physics run ([`level`]) of the plan made
//! once, against the ideal run made once, stopped as soon as a gate is
//! certain to break ([`early`]). The levels of a round run in parallel
//! (rayon) and are chosen by the search alone, so the result is the same on
//! any number of threads. A random dimension (`state_noise`) runs `seeds`
//! seeds per level (seeds 0, 1, …: `[sim.perturb] seed` reproduces any
//! one) and passes when at least `success_rate` of them do.
//!
//! `anholonomy margin` prints the margins ([`output`]) and writes
//! `margins.json` beside the nominal run's logs; `[margins]` in a scenario
//! makes `run`/`check` check each gated dimension at its gate, one level
//! each ([`gate`]: not a search), and report it as a metric
//! `margin_<dimension>`, so baselines hold them too.

pub mod caps;
pub mod early;
mod gate;
pub mod jumps;
pub mod level;
pub mod output;
pub mod search;

pub use gate::{check_gate, gate};

use crate::engine::perturb::{Dimension, Perturbation};
use crate::gate::Breach;
use crate::runner::RunOutcome;
use crate::scenario::MarginsConfig;
use crate::validate::Prepared;
use level::{Ctx, Run};
use rayon::prelude::*;
use search::{Spec, Status};
use serde::Serialize;
use std::time::Instant;

/// Format version of `margins.json`.
pub const FORMAT: u64 = 1;

/// Levels per round by default: the two cores this was tuned on (a larger
/// batch probes more levels per round, not different margins).
pub const DEFAULT_BATCH: usize = 2;

/// How margins are searched.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Settings {
    /// Relative resolution of the edge.
    pub resolution: f64,
    /// Seeds per level of a random dimension.
    pub seeds: usize,
    /// Success rate a random level needs.
    pub success_rate: f64,
    /// Levels per round.
    pub batch: usize,
    /// At most this many runs per dimension (None: until the resolution).
    pub max_runs: Option<usize>,
}

impl Settings {
    /// The scenario's `[margins]` settings (defaults where unset).
    pub fn of(cfg: &MarginsConfig) -> Settings {
        Settings {
            resolution: cfg.resolution(),
            seeds: cfg.seeds(),
            success_rate: cfg.success_rate(),
            batch: DEFAULT_BATCH,
            max_runs: None,
        }
    }
}

/// The largest level of `d` a run of `prep` can take: what `[sim.perturb]`
/// accepts (a time no longer than the run; a latency whose extra steps fit
/// the step budget), within its row's search ceiling.
pub(crate) fn ceiling(d: Dimension, prep: &Prepared) -> f64 {
    let crate::engine::perturb::Search { floor, ceiling, .. } = d.row().search;
    if d.unit() != "s" {
        return ceiling;
    }
    let sc = &prep.scenario;
    let run = prep.planned.duration;
    let mut cap = run;
    if d == Dimension::CommandLatency {
        let steps_left = prep.max_steps as f64 * sc.sim.dt - run - sc.sim.settle;
        cap = cap.min(steps_left);
    }
    ceiling.min(cap).max(floor)
}

/// The search spec of `d`; a gated dimension's ladder starts at its gate
/// (a level the verdict needs anyway).
pub fn spec(d: Dimension, s: &Settings, gate: Option<f64>, ceiling: f64) -> Spec {
    let crate::engine::perturb::Search { start, floor, .. } = d.row().search;
    let start = match gate {
        Some(g) if g > 0.0 => g.clamp(floor, ceiling),
        _ => start,
    };
    // A random level costs `seeds` runs.
    let per_level = if d.random() { s.seeds.max(1) } else { 1 };
    Spec {
        start,
        floor,
        ceiling,
        resolution: s.resolution,
        batch: s.batch,
        max_levels: s.max_runs.map(|r| (r / per_level).max(1)),
    }
}

/// The nominal run (level 0): passed, what it broke, its gated metrics.
#[derive(Debug, Clone, Serialize)]
pub struct Nominal {
    /// Every gate held.
    pub passed: bool,
    /// What it broke.
    pub broken: Vec<Breach>,
    /// The gated metrics (NaN as null).
    pub gates: std::collections::BTreeMap<String, f64>,
}

impl Nominal {
    /// From a finished run.
    pub fn of(prep: &Prepared, o: &RunOutcome) -> Nominal {
        let sc = &prep.scenario;
        let broken = crate::gate::breaches(&sc.thresholds, &sc.minimums, &o.metrics);
        Nominal {
            passed: broken.is_empty(),
            broken,
            gates: sc
                .thresholds
                .keys()
                .chain(sc.minimums.keys())
                .map(|k| (k.clone(), o.metric(k).unwrap_or(f64::NAN)))
                .collect(),
        }
    }
}

/// One level of a search.
#[derive(Debug, Clone, Serialize)]
pub struct Level {
    /// The magnitude.
    pub level: f64,
    /// The `[sim.perturb]` value it sets.
    pub value: f64,
    /// Passed (random dimensions: success rate reached).
    pub passed: bool,
    /// The search round that ran it (0: the nominal run).
    pub round: usize,
    /// Runs that passed.
    pub successes: usize,
    /// The runs.
    pub runs: Vec<Run>,
}

/// The margin of one dimension.
#[derive(Debug, Clone, Serialize)]
pub struct DimensionResult {
    /// The dimension.
    pub dimension: Dimension,
    /// Unit of the margin.
    pub unit: &'static str,
    /// How the search ended.
    pub status: Status,
    /// The margin (a magnitude; 0 below the floor or when the nominal run fails).
    pub margin: f64,
    /// The `[sim.perturb]` value at the margin.
    pub value_at_margin: f64,
    /// The smallest failing level (the edge lies between the margin and it); null when none failed.
    pub first_failing: Option<f64>,
    /// Whether a pass was found above a failure.
    pub non_monotone: bool,
    /// (failing level, passing level above it) pairs.
    pub inversions: Vec<[f64; 2]>,
    /// The gates broken at the first failing level, most frequent first.
    pub first_broken: Vec<Breach>,
    /// The metric plotted against the level: the first broken gate, or the
    /// gate nearest its bound when nothing broke.
    pub breaking_metric: Option<String>,
    /// Gated metrics that jump between neighbouring levels ([`jumps`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub jumps: Vec<jumps::Jump>,
    /// The default torque caps a torque or mass margin is measured against.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub default_caps: Option<caps::DefaultCaps>,
    /// Physics runs, nominal excluded.
    pub runs: usize,
    /// Rounds of parallel runs.
    pub rounds: usize,
    /// Seeds per level (random dimensions).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seeds: Option<usize>,
    /// Every level, by magnitude (level 0 is the nominal run).
    pub levels: Vec<Level>,
    /// Wall time, s (not serialized here: `margins.json` keeps clock values apart).
    #[serde(skip)]
    pub wall_s: f64,
    /// CPU time of its runs, s (likewise).
    #[serde(skip)]
    pub cpu_s: f64,
}

impl DimensionResult {
    /// What the margin alone does not say: a ceiling or floor reached, a
    /// failing nominal run, a non-monotone pattern.
    pub fn note(&self) -> String {
        let mut notes = Vec::new();
        match self.status {
            Status::Ceiling => notes.push("never broke up to the ceiling".to_string()),
            Status::BelowFloor => notes.push(format!(
                "broke at every level down to {}",
                crate::numfmt::readable(self.dimension.row().search.floor)
            )),
            Status::NominalFails => notes.push("the nominal run already fails".into()),
            Status::Budget => notes.push(format!("run budget ({} runs) spent", self.runs)),
            Status::Holds => notes.push("holds at the gate (one level run, not searched)".into()),
            Status::Breaks => notes.push("breaks at the gate (one level run, not searched)".into()),
            Status::Found => {}
        }
        if self.non_monotone {
            let pairs: Vec<String> = self
                .inversions
                .iter()
                .take(3)
                .map(|[f, p]| {
                    format!(
                        "fails at {}, passes at {}",
                        crate::numfmt::readable(*f),
                        crate::numfmt::readable(*p)
                    )
                })
                .collect();
            notes.push(format!("NON-MONOTONE: {}", pairs.join("; ")));
        }
        notes.extend(self.jumps.iter().take(2).map(jumps::Jump::note));
        if let Some(c) = &self.default_caps {
            notes.push(c.note());
        }
        notes.join("; ")
    }
}

/// Search the margin of `d` (the nominal run already made: `nominal`).
pub(crate) fn search_dimension(
    ctx: &Ctx<'_>,
    d: Dimension,
    nominal: &Nominal,
    s: &Settings,
) -> DimensionResult {
    let t0 = Instant::now();
    let base = ctx.prep.scenario.sim.perturb;
    let seeds = if d.random() { s.seeds.max(1) } else { 1 };
    let at = |m: f64, seed: u64| {
        let mut p: Perturbation = base;
        d.set(&mut p, d.value_at(m));
        if d.random() {
            p.seed = seed;
        }
        p
    };
    let nominal_level = Level {
        level: 0.0,
        value: d.value_at(0.0),
        passed: nominal.passed,
        round: 0,
        successes: usize::from(nominal.passed),
        runs: Vec::new(),
    };
    let mut eval = |levels: &[f64]| -> Vec<(bool, Level)> {
        let jobs: Vec<(f64, u64)> = levels
            .iter()
            .flat_map(|&m| (0..seeds as u64).map(move |k| (m, k)))
            .collect();
        // One task per run, results in job order whatever thread ran them.
        let runs: Vec<Run> = jobs
            .par_iter()
            .with_max_len(1)
            .map(|&(m, k)| level::run(ctx, &at(m, k), d.random().then_some(k)))
            .collect();
        levels
            .iter()
            .zip(runs.chunks(seeds))
            .map(|(&m, runs)| {
                let successes = runs.iter().filter(|r| r.passed).count();
                let passed = if d.random() {
                    successes as f64 >= s.success_rate * seeds as f64 - 1e-9
                } else {
                    successes == 1
                };
                let level = Level {
                    level: m,
                    value: d.value_at(m),
                    passed,
                    round: 0,
                    successes,
                    runs: runs.to_vec(),
                };
                (passed, level)
            })
            .collect()
    };
    let outcome = if nominal.passed {
        let gate = ctx
            .prep
            .scenario
            .margins
            .gates()
            .into_iter()
            .find_map(|(g, least)| (g == d).then_some(least));
        search::search(&spec(d, s, gate, ceiling(d, ctx.prep)), &mut eval)
    } else {
        search::Outcome {
            status: Status::NominalFails,
            margin: 0.0,
            hi: 0.0,
            probes: Vec::new(),
            inversions: Vec::new(),
            rounds: 0,
        }
    };
    let runs = outcome.probes.iter().map(|p| p.data.runs.len()).sum();
    let cpu_s = outcome
        .probes
        .iter()
        .flat_map(|p| &p.data.runs)
        .map(|r| r.cpu_s)
        .sum();
    let mut levels = vec![nominal_level];
    levels.extend(outcome.probes.into_iter().map(|p| Level {
        round: p.round,
        ..p.data
    }));
    let first_fail = levels.iter().find(|l| !l.passed);
    let first_broken = match first_fail {
        Some(l) if l.level == 0.0 => nominal.broken.clone(),
        Some(l) => most_frequent(&l.runs),
        None => Vec::new(),
    };
    let breaking_metric = first_broken
        .first()
        .map(|b| b.metric.clone())
        .or_else(|| nearest_gate(ctx, levels.last()));
    DimensionResult {
        dimension: d,
        unit: d.unit(),
        status: outcome.status,
        margin: outcome.margin,
        value_at_margin: d.value_at(outcome.margin),
        first_failing: outcome.hi.is_finite().then_some(outcome.hi),
        non_monotone: !outcome.inversions.is_empty(),
        inversions: outcome.inversions.iter().map(|(a, b)| [*a, *b]).collect(),
        first_broken,
        breaking_metric,
        jumps: ctx
            .gates
            .iter()
            .filter(|g| !crate::robots::reads_ideal_run(&g.metric))
            .flat_map(|g| jumps::jumps(&levels, g, s.resolution))
            .collect(),
        default_caps: caps::default_caps(ctx.prep, d),
        runs,
        rounds: outcome.rounds,
        seeds: d.random().then_some(seeds),
        levels,
        wall_s: t0.elapsed().as_secs_f64(),
        cpu_s,
    }
}

/// The breaches of the failing runs, each gate once, most frequent first
/// (ties in gate order).
fn most_frequent(runs: &[Run]) -> Vec<Breach> {
    let mut seen: Vec<(usize, Breach)> = Vec::new();
    for b in runs.iter().filter(|r| !r.passed).flat_map(|r| &r.broken) {
        match seen.iter_mut().find(|(_, s)| s.metric == b.metric) {
            Some((n, _)) => *n += 1,
            None => seen.push((1, b.clone())),
        }
    }
    if seen.is_empty() {
        // Runs that could not finish break no named gate.
        if let Some(e) = runs.iter().find_map(|r| r.error.clone()) {
            seen.push((
                1,
                Breach {
                    metric: format!("run failed: {e}"),
                    value: f64::NAN,
                    bound: f64::NAN,
                    minimum: false,
                },
            ));
        }
    }
    seen.sort_by_key(|(n, _)| std::cmp::Reverse(*n));
    seen.into_iter().map(|(_, b)| b).collect()
}

/// The gate closest to its bound at `level` (largest value/bound for a
/// maximum, bound/value for a minimum), when nothing broke.
fn nearest_gate(ctx: &Ctx<'_>, level: Option<&Level>) -> Option<String> {
    let runs = &level?.runs;
    let ratio = |g: &level::Gate| {
        runs.iter()
            .filter_map(|r| r.gates.get(&g.metric))
            .map(|&v| if g.minimum { g.bound / v } else { v / g.bound })
            .filter(|x| x.is_finite())
            .fold(f64::NEG_INFINITY, f64::max)
    };
    ctx.gates
        .iter()
        .filter(|g| !crate::robots::reads_ideal_run(&g.metric))
        .map(|g| (ratio(g), g))
        .filter(|(r, _)| r.is_finite())
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, g)| g.metric.clone())
}

/// The margins of one scenario.
#[derive(Debug, Clone, Serialize)]
pub struct Report {
    /// Format version.
    pub anholonomy_margins: u64,
    /// Scenario name.
    pub scenario: String,
    /// Scenario file.
    pub file: std::path::PathBuf,
    /// Model kind.
    pub model: &'static str,
    /// Planner kind.
    pub planner: &'static str,
    /// How the margins were searched.
    pub search: Settings,
    /// The nominal run.
    pub nominal: Nominal,
    /// The gates (`[margins]`), dimension → least margin.
    pub gates: std::collections::BTreeMap<String, f64>,
    /// The scenario's `[thresholds]` (every run's gates).
    pub thresholds: std::collections::BTreeMap<String, f64>,
    /// The scenario's `[minimums]`.
    pub minimums: std::collections::BTreeMap<String, f64>,
    /// One per dimension searched.
    pub dimensions: Vec<DimensionResult>,
}

impl Report {
    /// `margins.json`: the report, then `wall_time_s` (per dimension: wall
    /// and the CPU time of its runs; total), the only clock-dependent
    /// member, last.
    pub fn to_json(&self, total_wall_s: f64) -> serde_json::Value {
        let mut v = serde_json::to_value(self).unwrap_or_default();
        let mut wall = serde_json::Map::new();
        for d in &self.dimensions {
            // Each run's CPU time by round: a round's longest run bounds
            // its wall time on idle cores, whatever else the machine ran.
            let runs: Vec<[f64; 2]> = d
                .levels
                .iter()
                .flat_map(|l| l.runs.iter().map(|r| [l.round as f64, r.cpu_s]))
                .collect();
            wall.insert(
                d.dimension.name().into(),
                serde_json::json!({"wall": d.wall_s, "cpu": d.cpu_s, "runs_cpu": runs}),
            );
        }
        wall.insert("total".into(), serde_json::json!(total_wall_s));
        v["wall_time_s"] = serde_json::Value::Object(wall);
        v
    }

    /// Write `dir/margins.json` (atomically).
    pub fn write(
        &self,
        dir: &std::path::Path,
        total_wall_s: f64,
    ) -> Result<(), crate::log::LogError> {
        let v = self.to_json(total_wall_s);
        crate::log::atomic::write_file(&dir.join("margins.json"), |w| {
            serde_json::to_writer_pretty(w, &v).map_err(std::io::Error::other)
        })
    }
}

/// Search the margins of `dims` for a prepared scenario whose nominal run
/// is `nominal`. The dimensions are searched in parallel (each its own
/// sequence of rounds, so the results do not depend on it); `each` sees
/// each result as it is found.
pub fn margins(
    prep: &Prepared,
    nominal: Nominal,
    dims: &[Dimension],
    s: &Settings,
    each: &(dyn Fn(&DimensionResult) + Sync),
) -> Report {
    let ctx = Ctx::new(prep);
    let sc = &prep.scenario;
    let dimensions = dims
        .par_iter()
        .with_max_len(1)
        .map(|&d| {
            let r = search_dimension(&ctx, d, &nominal, s);
            each(&r);
            r
        })
        .collect();
    Report {
        anholonomy_margins: FORMAT,
        scenario: sc.name.clone(),
        file: sc.path.clone(),
        model: sc.model.kind(),
        planner: sc.planner.kind(),
        search: *s,
        nominal,
        gates: sc
            .margins
            .gates()
            .into_iter()
            .map(|(d, g)| (d.name().to_string(), g))
            .collect(),
        thresholds: sc.thresholds.clone(),
        minimums: sc.minimums.clone(),
        dimensions,
    }
}
