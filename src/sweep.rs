//! Monte Carlo sweeps: a scenario with a `[sweep]` table runs `count` variants of itself with
//! randomised friction, mass scale and (rover) switching signal, in parallel (rayon), and
//! reports the success rate and the distribution of final errors and times to goal.
//!
//! Variants are independent and addressed by index: variant i draws its parameters from a
//! ChaCha8 stream seeded with [`variant_seed`]`(seed, i)`, so any subset of indices reproduces
//! exactly the same variants. `--shard I/N` runs the indices i ≡ I (mod N) and writes
//! `sweep-shard-I-of-N.json`, so a sweep can be spread over machines and merged by index.

use crate::error::Error;
use crate::runner::{run, write_atomic, Prepared, RunOptions, RunOutcome, Timings};
use crate::scenario::ModelConfig;
use crate::systems;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use serde_json::json;
use std::time::Instant;

/// `[sweep]`: Monte Carlo variants of the scenario.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SweepConfig {
    /// Number of variants.
    pub count: usize,
    /// Base seed; variant i uses [`variant_seed`]`(seed, i)`.
    #[serde(default)]
    pub seed: u64,
    /// Friction coefficient range [lo, hi] (uniform); default: the scenario's `sim.friction`.
    pub friction: Option<[f64; 2]>,
    /// Range [lo, hi] of a factor applied to every link's mass and inertia (uniform).
    pub mass_scale: Option<[f64; 2]>,
    /// Rover only: the ideal run uses a telegraph σ with this rate (1/s) and the variant's seed.
    pub sigma_rate: Option<f64>,
    /// Metric that decides success (`value ≤ success_max`).
    #[serde(default = "default_success_metric")]
    pub success_metric: String,
    /// Largest `success_metric` value that counts as success.
    pub success_max: f64,
    /// Metric reported as the time to goal (NaN or missing = not reached).
    #[serde(default = "default_time_metric")]
    pub time_metric: String,
    /// `check` fails when the success rate is below this.
    #[serde(default)]
    pub min_success_rate: f64,
}

fn default_success_metric() -> String {
    "sim_goal_position".into()
}

fn default_time_metric() -> String {
    "sim_time_to_goal".into()
}

impl SweepConfig {
    /// Checks ranges and counts (messages name the key).
    pub fn validate(&self) -> Result<(), String> {
        if self.count == 0 || self.count > 1_000_000 {
            return Err("key `sweep.count`: must be in 1..=1000000".into());
        }
        let range = |key: &str, r: Option<[f64; 2]>, min: f64| -> Result<(), String> {
            if let Some([lo, hi]) = r {
                if !(lo.is_finite() && hi.is_finite() && lo >= min && lo <= hi) {
                    return Err(format!(
                        "key `sweep.{key}`: need finite lo ≤ hi with lo ≥ {min}"
                    ));
                }
            }
            Ok(())
        };
        range("friction", self.friction, 0.0)?;
        range("mass_scale", self.mass_scale, 1e-3)?;
        if let Some(r) = self.sigma_rate {
            if !(r.is_finite() && r >= 0.0) {
                return Err("key `sweep.sigma_rate`: must be finite and ≥ 0".into());
            }
        }
        if !(self.success_max.is_finite() && self.success_max >= 0.0) {
            return Err("key `sweep.success_max`: must be finite and ≥ 0".into());
        }
        if !(0.0..=1.0).contains(&self.min_success_rate) {
            return Err("key `sweep.min_success_rate`: must be in [0, 1]".into());
        }
        Ok(())
    }
}

/// A subset of variant indices: those with `index % count == shard`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Shard {
    /// This shard, 0-based.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

impl Shard {
    /// Parses `I/N` (0 ≤ I < N).
    pub fn parse(s: &str) -> Result<Shard, String> {
        let bad = || format!("`{s}`: expected I/N with 0 <= I < N");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// Whether variant `i` belongs to this shard.
    pub fn contains(&self, i: usize) -> bool {
        i % self.count == self.index
    }
}

/// Seed of variant `index`: SplitMix64 of the base seed and the index (independent of sharding
/// and of the order in which variants run).
pub fn variant_seed(seed: u64, index: usize) -> u64 {
    let mut z = seed
        ^ (index as u64)
            .wrapping_add(1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The randomised parameters of one variant.
#[derive(Debug, Clone, Serialize)]
pub struct Variant {
    /// Index in 0..count.
    pub index: usize,
    /// Its seed.
    pub seed: u64,
    /// Friction coefficient.
    pub friction: f64,
    /// Mass and inertia factor.
    pub mass_scale: f64,
    /// Telegraph rate of the ideal run's σ, when swept.
    pub sigma_rate: Option<f64>,
}

/// Draws variant `index` of `cfg` (base friction from the scenario).
pub fn variant(cfg: &SweepConfig, base_friction: f64, index: usize) -> Variant {
    let seed = variant_seed(cfg.seed, index);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut draw = |r: Option<[f64; 2]>, default: f64| match r {
        Some([lo, hi]) => lo + (hi - lo) * rng.random::<f64>(),
        None => default,
    };
    let friction = draw(cfg.friction, base_friction);
    let mass_scale = draw(cfg.mass_scale, 1.0);
    Variant {
        index,
        seed,
        friction,
        mass_scale,
        sigma_rate: cfg.sigma_rate,
    }
}

/// Outcome of one variant.
#[derive(Debug, Clone, Serialize)]
pub struct VariantResult {
    /// Parameters.
    #[serde(flatten)]
    pub variant: Variant,
    /// `success_metric ≤ success_max`.
    pub success: bool,
    /// The success metric's value.
    pub final_error: Option<f64>,
    /// The time metric's value (None: not reached).
    pub time_to_goal: Option<f64>,
    /// Physics steps.
    pub steps: usize,
    /// Wall time, s.
    pub wall_s: f64,
    /// Why the variant could not run, if it could not.
    pub error: Option<String>,
}

fn prepare_variant(prep: &Prepared, v: &Variant) -> Result<Prepared, String> {
    let mut sc = prep.scenario.clone();
    sc.sweep = None;
    sc.sim.friction = v.friction;
    if let Some(rate) = v.sigma_rate {
        match &mut sc.model {
            ModelConfig::Rover(m) => {
                m.switching = systems::rover::SwitchingConfig::Telegraph { seed: v.seed, rate }
            }
            other => {
                return Err(format!(
                    "key `sweep.sigma_rate`: model `{}` has no σ",
                    other.kind()
                ))
            }
        }
    }
    let mut robot = prep.robot.clone();
    for l in &mut robot.links {
        l.inertial.mass.value *= v.mass_scale;
        let i = &mut l.inertial.inertia;
        for x in [
            &mut i.ixx, &mut i.ixy, &mut i.ixz, &mut i.iyy, &mut i.iyz, &mut i.izz,
        ] {
            *x *= v.mass_scale;
        }
    }
    let system = systems::build(&sc.model, &sc.planner)?;
    Ok(Prepared {
        scenario: sc,
        system,
        robot,
    })
}

fn run_variant(prep: &Prepared, cfg: &SweepConfig, v: Variant) -> VariantResult {
    let t0 = Instant::now();
    let opts = RunOptions {
        log_root: None,
        progress: false,
    };
    let res = prepare_variant(prep, &v).and_then(|p| run(&p, &opts).map_err(|e| e.to_string()));
    let finite = |x: Option<f64>| x.filter(|v| v.is_finite());
    match res {
        Ok(o) => {
            let final_error = finite(o.metric(&cfg.success_metric));
            VariantResult {
                success: final_error.is_some_and(|e| e <= cfg.success_max),
                final_error,
                time_to_goal: finite(o.metric(&cfg.time_metric)),
                steps: o.steps,
                wall_s: t0.elapsed().as_secs_f64(),
                error: None,
                variant: v,
            }
        }
        Err(e) => VariantResult {
            variant: v,
            success: false,
            final_error: None,
            time_to_goal: None,
            steps: 0,
            wall_s: t0.elapsed().as_secs_f64(),
            error: Some(e),
        },
    }
}

/// Median, 95th percentile (nearest rank) and maximum; None when empty.
pub fn distribution(values: &[f64]) -> Option<[f64; 3]> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let rank = |p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    Some([rank(0.5), rank(0.95), v[v.len() - 1]])
}

/// Run the sweep of a prepared scenario (which must have `[sweep]`); prints a table and writes
/// `<log_root>/<name>/sweep.json` (or `sweep-shard-I-of-N.json`).
pub fn run_sweep(
    prep: &Prepared,
    opts: &RunOptions,
    shard: Option<Shard>,
) -> Result<RunOutcome, Error> {
    let (outcome, table) = run_sweep_report(prep, opts, shard)?;
    print!("{table}");
    Ok(outcome)
}

/// [`run_sweep`] without printing: the outcome and the table text (so parallel callers can
/// print tables in a fixed order).
pub fn run_sweep_report(
    prep: &Prepared,
    opts: &RunOptions,
    shard: Option<Shard>,
) -> Result<(RunOutcome, String), Error> {
    let t_all = Instant::now();
    let sc = &prep.scenario;
    let cfg = sc
        .sweep
        .as_ref()
        .ok_or_else(|| Error::input(&sc.path, "scenario has no [sweep] table"))?;
    let mut known = crate::runner::metric_spec(prep.model()).names();
    known.extend(prep.system.extra_metric_names());
    for (key, m) in [
        ("success_metric", &cfg.success_metric),
        ("time_metric", &cfg.time_metric),
    ] {
        if !known.contains(m) {
            return Err(Error::input(
                &sc.path,
                format!("key `sweep.{key}`: unknown metric `{m}`"),
            ));
        }
    }
    let variants: Vec<Variant> = (0..cfg.count)
        .filter(|i| shard.is_none_or(|s| s.contains(*i)))
        .map(|i| variant(cfg, sc.sim.friction, i))
        .collect();
    if let Some(v) = variants.first() {
        prepare_variant(prep, v).map_err(|m| Error::input(&sc.path, m))?;
    }
    let bar = ProgressBar::with_draw_target(
        Some(variants.len() as u64),
        if opts.progress {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        },
    );
    if let Ok(style) =
        ProgressStyle::with_template("{prefix:>24} [{bar:40}] {pos}/{len} {elapsed}/{eta}")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(sc.name.clone());
    let results: Vec<VariantResult> = variants
        .into_par_iter()
        .map(|v| {
            let r = run_variant(prep, cfg, v);
            bar.inc(1);
            r
        })
        .collect();
    bar.finish_and_clear();

    let n = results.len();
    let ok = results.iter().filter(|r| r.success).count();
    let rate = if n == 0 { 0.0 } else { ok as f64 / n as f64 };
    let errors: Vec<f64> = results.iter().filter_map(|r| r.final_error).collect();
    let times: Vec<f64> = results
        .iter()
        .filter(|r| r.success)
        .filter_map(|r| r.time_to_goal)
        .collect();
    let failed_to_run: Vec<String> = results
        .iter()
        .filter_map(|r| {
            r.error
                .as_ref()
                .map(|e| format!("variant {}: {e}", r.variant.index))
        })
        .collect();
    let err_d = distribution(&errors);
    let time_d = distribution(&times);
    let mut metrics = vec![
        ("sweep_success_rate".to_string(), rate),
        ("sweep_variants".to_string(), n as f64),
    ];
    for (name, d) in [("sweep_final_error", err_d), ("sweep_time_to_goal", time_d)] {
        for (s, v) in ["median", "p95", "max"]
            .iter()
            .zip(d.unwrap_or([f64::NAN; 3]))
        {
            metrics.push((format!("{name}_{s}"), v));
        }
    }
    let mut failures = failed_to_run.clone();
    if rate < cfg.min_success_rate {
        failures.push(format!(
            "sweep_success_rate = {rate:.3} < {}",
            cfg.min_success_rate
        ));
    }
    let steps = results.iter().map(|r| r.steps).sum();
    let wall = t_all.elapsed().as_secs_f64();

    let fmt = |d: Option<[f64; 3]>| match d {
        Some([a, b, c]) => format!("{a:>9.4} {b:>9.4} {c:>9.4}"),
        None => format!("{:>9} {:>9} {:>9}", "-", "-", "-"),
    };
    use std::fmt::Write as _;
    let mut table = String::new();
    let _ = writeln!(
        table,
        "sweep {} ({} variants{}, {:.1} s): success {}/{} = {:.1} %",
        sc.name,
        n,
        shard
            .map(|s| format!(", shard {}/{}", s.index, s.count))
            .unwrap_or_default(),
        wall,
        ok,
        n,
        100.0 * rate
    );
    let _ = writeln!(
        table,
        "  {:<28} {:>9} {:>9} {:>9}",
        "", "median", "p95", "max"
    );
    let _ = writeln!(
        table,
        "  {:<28} {}",
        format!("final error ({})", cfg.success_metric),
        fmt(err_d)
    );
    let _ = writeln!(
        table,
        "  {:<28} {}",
        "time to goal, s (successes)",
        fmt(time_d)
    );

    let mut outcome = RunOutcome {
        name: sc.name.clone(),
        planner: sc.planner.kind().into(),
        passed: failures.is_empty(),
        failures,
        metrics,
        steps,
        timings: Timings {
            physics: wall,
            total: wall,
            ..Default::default()
        },
        log_dir: None,
    };
    if let Some(root) = &opts.log_root {
        let dir = root.join(&sc.name);
        std::fs::create_dir_all(&dir).map_err(|e| Error::Log {
            path: sc.path.clone(),
            message: format!("{}: {e}", dir.display()),
        })?;
        let file = match shard {
            Some(s) => format!("sweep-shard-{}-of-{}.json", s.index, s.count),
            None => "sweep.json".into(),
        };
        let summary = |d: Option<[f64; 3]>| {
            d.map(|[m, p, x]| json!({"median": m, "p95": p, "max": x}))
                .unwrap_or(serde_json::Value::Null)
        };
        let doc = json!({
            "scenario": sc.name,
            "file": sc.path,
            "sweep": cfg,
            "shard": shard,
            "variants_run": n,
            "successes": ok,
            "success_rate": rate,
            "final_error": summary(err_d),
            "time_to_goal": summary(time_d),
            "passed": outcome.passed,
            "failures": outcome.failures,
            "wall_time_s": wall,
            "results": results,
        });
        write_atomic(&dir.join(file), |w| {
            serde_json::to_writer_pretty(w, &doc).map_err(std::io::Error::other)
        })
        .map_err(|message| Error::Log {
            path: sc.path.clone(),
            message,
        })?;
        outcome.log_dir = Some(dir);
    }
    Ok((outcome, table))
}
