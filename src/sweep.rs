//! Monte Carlo sweeps: a scenario with a `[sweep]` table runs `count` variants of itself with
//! randomised friction, mass scale and (rover) switching signal, in parallel (rayon), and
//! reports the success rate and the distribution of final errors and times to goal.
//!
//! Variants are independent and addressed by index: variant i draws its parameters from a
//! ChaCha8 stream seeded with [`variant_seed`]`(seed, i)`, so any subset of indices reproduces
//! exactly the same variants. `--shard I/N` runs the indices i ≡ I (mod N) and writes
//! `sweep-shard-I-of-N.json`, so a sweep can be spread over machines and merged by index.

use crate::error::Error;
use crate::log::unit::LogUnit;
use crate::runner::{run, write_atomic, RunOptions, RunOutcome, Timings};
pub use crate::scenario::{variant_seed, SweepConfig, Variant};
use crate::validate::Prepared;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;
use serde_json::json;
use std::path::Path;
use std::time::Instant;

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
    /// Wall time, s (in `sweep.json` under `wall_time_s.variants`, with the other timings).
    #[serde(skip)]
    pub wall_s: f64,
    /// Why the variant could not run, if it could not.
    pub error: Option<String>,
}

fn run_variant(prep: &Prepared, cfg: &SweepConfig, v: Variant) -> VariantResult {
    let t0 = Instant::now();
    let opts = RunOptions {
        log_root: None,
        progress: false,
    };
    let res = prep
        .variant(&v)
        .and_then(|p| run(&p, &opts))
        .map_err(|e| e.to_string());
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

pub use crate::scenario::sweep_metric_names as metric_names;

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
    crate::suite::emit(&table);
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
    let variants: Vec<Variant> = (0..cfg.count)
        .filter(|i| shard.is_none_or(|s| s.contains(*i)))
        .map(|i| cfg.variant(sc.sim.friction, i))
        .collect();
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
        let (rate, floor) = crate::numfmt::breach(rate, cfg.min_success_rate);
        failures.push(format!("sweep_success_rate = {rate} < {floor}"));
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
            "results": results,
            // Everything that depends on the clock, and only that.
            "wall_time_s": {
                "total": wall,
                "variants": results.iter().map(|r| r.wall_s).collect::<Vec<_>>(),
            },
        });
        let dir = write_sweep_doc(root, &sc.name, shard, &doc).map_err(|message| Error::Log {
            path: sc.path.clone(),
            message,
        })?;
        outcome.log_dir = Some(dir);
    }
    Ok((outcome, table))
}

/// Files of a single run or an unsharded sweep: stale beside shard files.
const UNIT_FILES: [&str; 4] = ["run.mcap", "run.rrd", "summary.json", "sweep.json"];

/// Write the sweep document as a unit. Unsharded: `sweep.json` replaces the
/// whole `<root>/<name>` directory, like a run's logs. Sharded: the shards of
/// one sweep share the directory (they may run at once, on several
/// machines), so `sweep-shard-I-of-N.json` is written atomically on its own
/// and the files of a previous single run or unsharded sweep are removed.
fn write_sweep_doc(
    root: &Path,
    name: &str,
    shard: Option<Shard>,
    doc: &serde_json::Value,
) -> Result<std::path::PathBuf, String> {
    let write = |path: &Path| {
        write_atomic(path, |w| {
            serde_json::to_writer_pretty(w, doc).map_err(std::io::Error::other)
        })
    };
    match shard {
        None => {
            let unit = LogUnit::begin(root, name).map_err(|e| e.to_string())?;
            write(&unit.dir().join("sweep.json"))?;
            unit.commit().map_err(|e| e.to_string())
        }
        Some(s) => {
            let dir = root.join(name);
            std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            write(&dir.join(format!("sweep-shard-{}-of-{}.json", s.index, s.count)))?;
            for f in UNIT_FILES {
                let _ = std::fs::remove_file(dir.join(f));
            }
            Ok(dir)
        }
    }
}
