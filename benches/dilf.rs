//! Seed 004 benchmarks: the feedback policy (V, ∂V/∂q by dual numbers, and
//! Eq. 18) for the door scenario, and that scenario's full run.
//!
//! `cargo bench --bench dilf`. Medians are quoted in the README.

use anholonomy::integrate::simulate;
use anholonomy::runner::{run, RunOptions};
mod common;
use common::prepared;
use criterion::{criterion_group, criterion_main, BatchSize, Criterion};

fn policy(c: &mut Criterion) {
    let prep = prepared("dilf_single_door");
    let (start, _) = prep.start_goal();
    let plan = prep.plan().expect("plan");
    // States the policy meets along the ideal run (every 20 ms).
    let ideal = simulate(prep.model(), &plan, &start, prep.scenario.sim.dt);
    let states: Vec<_> = ideal.q.iter().step_by(10).cloned().collect();
    let mut g = c.benchmark_group("dilf_door_policy");
    // A fresh controller: every part–obstacle solve starts cold.
    g.bench_function("cold_at_start", |b| {
        b.iter_batched(
            || plan.controller(),
            |mut ctl| ctl.command(0.0, &start),
            BatchSize::SmallInput,
        )
    });
    // One controller along the run: solves start from the previous minimiser.
    let mut ctl = plan.controller();
    let mut k = 0;
    g.bench_function("warm_along_ideal_run", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            ctl.command(0.0, &states[k])
        })
    });
    g.finish();
}

fn full_run(c: &mut Criterion) {
    let prep = prepared("dilf_single_door");
    let logs = tempfile::tempdir().expect("tempdir");
    let opts = RunOptions {
        log_root: Some(logs.path().to_path_buf()),
        progress: false,
    };
    let mut g = c.benchmark_group("dilf_single_door_full_run");
    g.sample_size(10);
    g.bench_function("ideal_physics_logs", |b| {
        b.iter(|| run(&prep, &opts).expect("run"))
    });
    g.finish();
}

criterion_group!(benches, policy, full_run);
criterion_main!(benches);
