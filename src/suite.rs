//! Several scenarios of one `run`/`check` call, in parallel.
//!
//! Scenarios are independent (each builds its own world, single-threaded and
//! deterministic), so they run on rayon's pool; results come back in input
//! order and sweep tables are printed in input order once everything is done.
//! No two scenarios of one call share a name, hence a log directory (the
//! validation pass refuses it). A single scenario runs on the calling thread
//! with its own progress bar; several share one bar counting finished
//! scenarios.

use crate::error::Error;
use crate::runner::{run, RunOptions, RunOutcome};
use crate::sweep::records::Scan;
use crate::sweep::{run_sweep_report, Shard};
use crate::validate::Prepared;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;
use std::time::Instant;

/// The result of one scenario and its wall time, s (JUnit reports it for failures too).
pub type Ran = (Result<RunOutcome, Error>, f64);

/// Run every prepared scenario (sweeps as sweeps, restricted to `shard`,
/// continuing `resumed[i]` when given); one result per scenario, in input order.
pub fn run_all(
    preps: &[Prepared],
    opts: &RunOptions,
    shard: Option<Shard>,
    resumed: &[Option<Scan>],
) -> Vec<Ran> {
    let resume = |i: usize| resumed.get(i).and_then(Option::as_ref);
    if preps.len() == 1 {
        let (res, table, wall) = run_one_report(&preps[0], opts, shard, resume(0));
        crate::emit(&table);
        return vec![(res, wall)];
    }
    // Longest work first keeps both cores busy to the end.
    let mut order: Vec<usize> = (0..preps.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(cost(&preps[i])));
    let bar = overall_bar(preps.len(), opts.progress);
    let quiet = RunOptions {
        progress: false,
        ..opts.clone()
    };
    let mut done: Vec<(usize, Ran, String)> = order
        .par_iter()
        .with_max_len(1)
        .map(|&i| {
            let (res, table, wall) = run_one_report(&preps[i], &quiet, shard, resume(i));
            bar.inc(1);
            (i, (res, wall), table)
        })
        .collect();
    bar.finish_and_clear();
    done.sort_by_key(|(i, _, _)| *i);
    done.into_iter()
        .map(|(_, ran, table)| {
            crate::emit(&table);
            ran
        })
        .collect()
}

/// One scenario: its outcome, for a sweep its table, and its wall time.
fn run_one_report(
    prep: &Prepared,
    opts: &RunOptions,
    shard: Option<Shard>,
    resume: Option<&Scan>,
) -> (Result<RunOutcome, Error>, String, f64) {
    let t0 = Instant::now();
    let (res, table) = if prep.scenario.sweep.is_some() {
        match run_sweep_report(prep, opts, shard, resume) {
            Ok((o, t)) => (Ok(o), t),
            Err(e) => (Err(e), String::new()),
        }
    } else {
        // `[margins]`: the gated margins are searched after the nominal run.
        let res = run(prep, opts).and_then(|mut o| {
            crate::margin::gate(prep, &mut o)?;
            Ok(o)
        });
        (res, String::new())
    };
    (res, table, t0.elapsed().as_secs_f64())
}

/// A rough cost for scheduling: simulated steps (× variants for sweeps).
pub fn cost(prep: &Prepared) -> u64 {
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
