//! Space-robot benchmarks: planning time of each endogenous scenario (issue
//! target < 0.2 s), the Stokes planner, and physics steps per second.
//!
//! `cargo bench --bench space_robot`. Medians are quoted in the README.

mod common;
use common::{bench_driven_steps, prepared, STEPS};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::time::Duration;

fn planning(c: &mut Criterion) {
    let mut g = c.benchmark_group("space_plan");
    g.sample_size(20);
    g.measurement_time(Duration::from_secs(4));
    for name in [
        "space_manipulator_s1",
        "space_manipulator_s2",
        "space_manipulator_s3",
        "space_robot_paper",
    ] {
        let prep = prepared(name);
        g.bench_function(name, |b| b.iter(|| prep.plan().expect("plan")));
    }
    g.finish();
}

fn physics_steps(c: &mut Criterion) {
    let prep = prepared("space_robot_paper");
    let mut g = c.benchmark_group("space_robot_physics");
    g.throughput(Throughput::Elements(STEPS));
    g.sample_size(20);
    bench_driven_steps(
        &mut g,
        "1000_steps_both_joints_driven",
        &prep,
        &[0.8, -0.5],
        0,
    );
    g.finish();
}

criterion_group!(benches, planning, physics_steps);
criterion_main!(benches);
