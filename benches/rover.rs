//! Rover benchmarks: physics step rate with five wheel contacts (driving and turning) beside a
//! plain step of the same URDF without a ground plane (joints only, no contacts).
//!
//! `cargo bench --bench rover`.

use anholonomy::model::Input;
use anholonomy::physics::urdf::{SimWorld, WorldOptions};
use anholonomy::runner::Prepared;
use anholonomy::scenario::Scenario;
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use std::path::Path;

fn prepared() -> Prepared {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/rover_paper.toml");
    Prepared::new(Scenario::load(&path).expect("scenario")).expect("prepared")
}

fn physics_steps(c: &mut Criterion) {
    let prep = prepared();
    const STEPS: u64 = 1000;
    let mut g = c.benchmark_group("rover_physics");
    g.throughput(Throughput::Elements(STEPS));
    g.sample_size(20);
    g.bench_function("1000_steps_five_contacts_driving_turning", |b| {
        b.iter_batched(
            || {
                let mut sys = prep.physics().expect("physics");
                // Settle onto the ground first so every sample has five contacts.
                for _ in 0..100 {
                    sys.step();
                }
                sys
            },
            |mut sys| {
                let u = Input::from_vec(vec![0.4, 0.2]);
                for _ in 0..STEPS {
                    sys.apply(&u);
                    sys.step();
                }
                sys.state()
            },
            BatchSize::LargeInput,
        )
    });
    let dir = prep
        .scenario
        .urdf
        .parent()
        .unwrap_or(Path::new("."))
        .to_path_buf();
    g.bench_function("1000_steps_same_urdf_no_ground", |b| {
        b.iter_batched(
            || {
                let opts = WorldOptions {
                    sim: &prep.scenario.sim,
                    root_pose: rapier3d::math::Pose::IDENTITY,
                    ground: false,
                };
                SimWorld::new(&prep.robot, &dir, &opts)
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
