//! Rolling-disk benchmarks: physics step rate, plan + ideal run, full pipeline.
//!
//! `cargo bench --bench disk`. Medians are quoted in the README.

use anholonomy::integrate::simulate;
use anholonomy::model::Input;
use anholonomy::runner::{run, Prepared, RunOptions};
use anholonomy::scenario::Scenario;
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use std::path::Path;

fn prepared() -> Prepared {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/disk_paper.toml");
    Prepared::new(Scenario::load(&path).expect("scenario")).expect("prepared")
}

fn physics_steps(c: &mut Criterion) {
    let prep = prepared();
    const STEPS: u64 = 1000;
    let mut g = c.benchmark_group("disk_physics");
    g.throughput(Throughput::Elements(STEPS));
    g.sample_size(20);
    g.bench_function("1000_steps_rolling_and_turning", |b| {
        b.iter_batched(
            || prep.physics().expect("physics"),
            |mut sys| {
                let u = Input::from_vec(vec![4.0, 1.0]);
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

fn plan_and_ideal(c: &mut Criterion) {
    let prep = prepared();
    let (start, _) = prep.start_goal();
    c.bench_function("disk_paper_plan_plus_ideal_run", |b| {
        b.iter(|| {
            let plan = prep.plan().expect("plan");
            simulate(prep.model(), &plan, &start, prep.scenario.sim.dt)
        })
    });
}

fn full_run(c: &mut Criterion) {
    let prep = prepared();
    let logs = tempfile::tempdir().expect("tempdir");
    let opts = RunOptions {
        log_root: Some(logs.path().to_path_buf()),
        progress: false,
    };
    let mut g = c.benchmark_group("disk_paper_full_run");
    g.sample_size(10);
    g.bench_function("plan_ideal_physics_logs", |b| {
        b.iter(|| run(&prep, &opts).expect("run"))
    });
    g.finish();
}

criterion_group!(benches, physics_steps, plan_and_ideal, full_run);
criterion_main!(benches);
