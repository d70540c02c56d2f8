//! Space-robot benchmarks: planning time of each endogenous scenario (issue
//! target < 0.2 s), the Stokes planner, and physics steps per second.
//!
//! `cargo bench --bench space_robot`. Medians are quoted in the README.

use anholonomy::model::Input;
use anholonomy::runner::Prepared;
use anholonomy::scenario::Scenario;
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use std::path::Path;
use std::time::Duration;

fn prepared(name: &str) -> Prepared {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenarios/{name}.toml"));
    Prepared::new(Scenario::load(&path).expect("scenario")).expect("prepared")
}

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
    const STEPS: u64 = 1000;
    let mut g = c.benchmark_group("space_robot_physics");
    g.throughput(Throughput::Elements(STEPS));
    g.sample_size(20);
    g.bench_function("1000_steps_both_joints_driven", |b| {
        b.iter_batched(
            || prep.physics().expect("physics"),
            |mut sys| {
                let u = Input::from_vec(vec![0.8, -0.5]);
                for _ in 0..STEPS {
                    sys.apply(&u);
                    sys.step();
                }
                sys.state()
            },
            BatchSize::LargeInput,
        )
    });
    g.finish();
}

criterion_group!(benches, planning, physics_steps);
criterion_main!(benches);
