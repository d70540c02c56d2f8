//! Several scenarios of one `run`/`check` call, in parallel.
//!
//! Scenarios are independent (each builds its own world, single-threaded and
//! deterministic), so they run on rayon's pool; results come back in input
//! order, each sweep's table with it. No two scenarios of one call share a
//! name, hence a log directory (the validation pass refuses it). A single
//! scenario runs on the calling thread and reports its own progress;
//! several report only how many have finished ([`Work::Scenarios`]).

use crate::error::Error;
use crate::progress::{Progress, Work};
use crate::runner::{run, RunOptions, RunOutcome};
use crate::sweep::records::Scan;
use crate::sweep::{run_sweep_report, Shard};
use crate::validate::Prepared;
use rayon::prelude::*;
use std::time::Instant;

/// What one scenario of a call gave.
pub struct Ran {
    /// Its outcome.
    pub result: Result<RunOutcome, Error>,
    /// Its wall time, s (JUnit reports it for failures too).
    pub wall: f64,
    /// A sweep's table (empty for a single run), to show the user.
    pub table: String,
}

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
        return vec![run_one_report(&preps[0], opts, shard, resume(0))];
    }
    // Longest work first keeps both cores busy to the end.
    let mut order: Vec<usize> = (0..preps.len()).collect();
    order.sort_by_key(|&i| std::cmp::Reverse(cost(&preps[i])));
    let progress = &opts.progress;
    progress.started(Work::Scenarios, "scenarios", preps.len() as u64);
    let quiet = RunOptions {
        progress: Progress::silent(),
        ..opts.clone()
    };
    let mut done: Vec<(usize, Ran)> = order
        .par_iter()
        .with_max_len(1)
        .map(|&i| {
            let ran = run_one_report(&preps[i], &quiet, shard, resume(i));
            progress.advanced(Work::Scenarios, "scenarios", 1);
            (i, ran)
        })
        .collect();
    progress.finished(Work::Scenarios, "scenarios");
    done.sort_by_key(|(i, _)| *i);
    done.into_iter().map(|(_, ran)| ran).collect()
}

/// One scenario: its outcome, for a sweep its table, and its wall time.
fn run_one_report(
    prep: &Prepared,
    opts: &RunOptions,
    shard: Option<Shard>,
    resume: Option<&Scan>,
) -> Ran {
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
    Ran {
        result: res,
        wall: t0.elapsed().as_secs_f64(),
        table,
    }
}

/// A rough cost for scheduling: simulated steps (× variants for sweeps).
pub fn cost(prep: &Prepared) -> u64 {
    let sc = &prep.scenario;
    let variants = sc.sweep.as_ref().map_or(1, |s| s.count) as u64;
    let steps = (1.0 / sc.sim.dt.max(1e-6)) as u64;
    variants * steps
}
