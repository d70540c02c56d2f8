//! Rolling-disk benchmarks: physics step rate, plan + ideal run, full run of a validated scenario.
//!
//! `cargo bench --bench disk`. Medians are quoted in the README.

use anholonomy::integrate::simulate;
use anholonomy::runner::{run, RunOptions};
mod common;
use common::{bench_driven_steps, prepared, STEPS};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

fn physics_steps(c: &mut Criterion) {
    let prep = prepared("disk_paper");
    let mut g = c.benchmark_group("disk_physics");
    g.throughput(Throughput::Elements(STEPS));
    g.sample_size(20);
    bench_driven_steps(
        &mut g,
        "1000_steps_rolling_and_turning",
        &prep,
        &[4.0, 1.0],
        0,
    );
    g.finish();
}

fn plan_and_ideal(c: &mut Criterion) {
    let prep = prepared("disk_paper");
    let (start, _) = prep.start_goal();
    c.bench_function("disk_paper_plan_plus_ideal_run", |b| {
        b.iter(|| {
            let plan = prep.plan().expect("plan");
            simulate(prep.model(), &plan, &start, prep.scenario.sim.dt)
        })
    });
}

fn full_run(c: &mut Criterion) {
    let prep = prepared("disk_paper");
    let logs = tempfile::tempdir().expect("tempdir");
    let opts = RunOptions {
        log_root: Some(logs.path().to_path_buf()),
        progress: Default::default(),
        pose_rate: anholonomy::runner::DEFAULT_POSE_RATE,
        cancel: Default::default(),
        keep: anholonomy::log::Keep::All,
        batch: true,
    };
    let mut g = c.benchmark_group("disk_paper_full_run");
    g.sample_size(10);
    // The plan was made by validation (`prepared`); `run` replays it.
    g.bench_function("ideal_physics_logs", |b| {
        b.iter(|| run(&prep, &opts).expect("run"))
    });
    g.finish();
}

criterion_group!(benches, physics_steps, plan_and_ideal, full_run);
criterion_main!(benches);
