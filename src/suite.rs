//! Several scenarios of one `run`/`check` call, in parallel.
//!
//! Scenarios are independent (each builds its own world, single-threaded and
//! deterministic), so they run on rayon's pool; results come back in input
//! order, sweep tables are printed in input order once everything is done,
//! and scenarios that share a name (hence a log directory) run one after the
//! other in input order, so the logs left behind are those of the last one,
//! as in a serial run. A single scenario runs on the calling thread with its
//! own progress bar; several share one bar counting finished scenarios.

use crate::error::Error;
use crate::runner::{run, Prepared, RunOptions, RunOutcome};
use crate::sweep::{run_sweep_report, Shard};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::collections::BTreeMap;

/// Run every prepared scenario (sweeps as sweeps, restricted to `shard`);
/// one result per scenario, in input order.
pub fn run_all(
    preps: &[Prepared],
    opts: &RunOptions,
    shard: Option<Shard>,
) -> Vec<Result<RunOutcome, Error>> {
    if preps.len() == 1 {
        return vec![run_one_report(&preps[0], opts, shard).map(|(o, table)| {
            print!("{table}");
            o
        })];
    }
    // Chains of indices sharing a log directory name, each in input order.
    let mut chains: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, p) in preps.iter().enumerate() {
        chains.entry(p.scenario.name.as_str()).or_default().push(i);
    }
    let mut chains: Vec<Vec<usize>> = chains.into_values().collect();
    // Longest work first keeps both cores busy to the end.
    chains.sort_by_key(|c| std::cmp::Reverse(c.iter().map(|&i| cost(&preps[i])).sum::<u64>()));
    let bar = overall_bar(preps.len(), opts.progress);
    let quiet = RunOptions {
        progress: false,
        ..opts.clone()
    };
    let mut done: Vec<(usize, Result<RunOutcome, Error>, String)> = chains
        .par_iter()
        .flat_map_iter(|chain| {
            chain
                .iter()
                .map(|&i| {
                    let (res, table) = match run_one_report(&preps[i], &quiet, shard) {
                        Ok((o, t)) => (Ok(o), t),
                        Err(e) => (Err(e), String::new()),
                    };
                    bar.inc(1);
                    (i, res, table)
                })
                .collect::<Vec<_>>()
        })
        .collect();
    bar.finish_and_clear();
    done.sort_by_key(|(i, _, _)| *i);
    done.into_iter()
        .map(|(_, res, table)| {
            print!("{table}");
            res
        })
        .collect()
}

/// One scenario: its outcome and, for a sweep, its table.
fn run_one_report(
    prep: &Prepared,
    opts: &RunOptions,
    shard: Option<Shard>,
) -> Result<(RunOutcome, String), Error> {
    if prep.scenario.sweep.is_some() {
        run_sweep_report(prep, opts, shard)
    } else {
        run(prep, opts).map(|o| (o, String::new()))
    }
}

/// A rough cost for scheduling: simulated steps (× variants for sweeps).
fn cost(prep: &Prepared) -> u64 {
    let sc = &prep.scenario;
    let variants = sc.sweep.as_ref().map_or(1, |s| s.count) as u64;
    let steps = (1.0 / sc.sim.dt.max(1e-6)) as u64;
    variants * steps
}

fn overall_bar(n: usize, enabled: bool) -> ProgressBar {
    let target = if enabled {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let bar = ProgressBar::with_draw_target(Some(n as u64), target);
    if let Ok(style) =
        ProgressStyle::with_template("{prefix:>24} [{bar:40}] {pos}/{len} {elapsed}/{eta}")
    {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix("scenarios");
    bar
}
