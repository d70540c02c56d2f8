//! Rover benchmarks: physics step rate with five wheel contacts (driving and turning) beside a
//! plain step of the same URDF without a ground plane (joints only, no contacts).
//!
//! `cargo bench --bench rover`.

use anholonomy::engine::urdf::{SimWorld, WorldOptions};
mod common;
use common::{bench_driven_steps, prepared, STEPS};
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use std::path::Path;

fn physics_steps(c: &mut Criterion) {
    let prep = prepared("rover_paper");
    let mut g = c.benchmark_group("rover_physics");
    g.throughput(Throughput::Elements(STEPS));
    g.sample_size(20);
    // 100 settling steps first, so every sample has five contacts.
    bench_driven_steps(
        &mut g,
        "1000_steps_five_contacts_driving_turning",
        &prep,
        &[0.4, 0.2],
        100,
    );
    let dir = prep
        .scenario
        .urdf
        .parent()
        .unwrap_or(Path::new("."))
        .to_path_buf();
    g.bench_function("1000_steps_same_urdf_no_ground", |b| {
        b.iter_batched(
            || {
                let settings = prep.scenario.sim.physics();
                let opts = WorldOptions {
                    settings: &settings,
                    root_pose: anholonomy::engine::rapier::math::Pose::IDENTITY,
                    ground: false,
                    keep_fixed: &[],
                };
                SimWorld::new(&prep.robot, &dir, &opts).unwrap()
            },
            |mut w| {
                for _ in 0..STEPS {
                    w.world.step();
                }
                w.link_poses()
            },
            BatchSize::LargeInput,
        )
    });
    g.finish();
}

criterion_group!(benches, physics_steps);
criterion_main!(benches);
