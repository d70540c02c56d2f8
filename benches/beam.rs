//! Physics beam alone: steps/s of a 3 m GFRP beam clamped at both ends
//! under gravity, at N spring joints, dt = 2 ms: `beam_step` with 4
//! substeps of one Gauss–Seidel sweep (Rapier's default sweeps),
//! `beam_step_1x16` with one substep of 16 sweeps (the multibody's mass
//! matrix is rebuilt once per substep).
//!
//! `cargo bench --bench beam -- --warm-up-time 1 --measurement-time 4`.

use anholonomy::engine::rapier::prelude::*;
use anholonomy::robots::mobile_manipulator::beam::physics::{Attachment, BeamOptions, PhysicsBeam};
use anholonomy::robots::mobile_manipulator::beam::{Beam, GFRP_ROD_10MM};
use criterion::{criterion_group, criterion_main, Criterion};

fn clamped(n: usize, substeps: usize, sweeps: usize) -> (PhysicsWorld, PhysicsBeam) {
    let beam = Beam {
        material: GFRP_ROD_10MM.0,
        section: GFRP_ROD_10MM.1,
        length: 3.0,
    };
    let mut w = PhysicsWorld::new();
    w.gravity = Vector::new(0.0, 0.0, -9.81);
    w.integration_parameters.dt = 0.002;
    w.integration_parameters.num_solver_iterations = substeps;
    w.integration_parameters.num_internal_pgs_iterations = sweeps;
    let ground = w.insert_body(RigidBodyBuilder::fixed());
    let at = |x: Real| Attachment {
        body: ground,
        frame: Pose::from_translation(Vector::new(x, 0.0, 1.0)),
    };
    let opts = BeamOptions {
        segments: n,
        ..Default::default()
    };
    let line = |s: Real| Pose::from_translation(Vector::new(s, 0.0, 1.0));
    let b = PhysicsBeam::insert(
        &mut w,
        &beam,
        &opts,
        &line,
        [Some(at(0.0)), Some(at(3.0))],
        InteractionGroups::all(),
    )
    .expect("beam");
    (w, b)
}

fn steps(c: &mut Criterion) {
    for (group, substeps, sweeps, sizes) in [
        ("beam_step", 4, 1, &[6, 10, 20][..]),
        ("beam_step_1x16", 1, 16, &[10][..]),
    ] {
        let mut g = c.benchmark_group(group);
        for &n in sizes {
            let (mut w, mut b) = clamped(n, substeps, sweeps);
            g.bench_function(format!("N{n}"), |bench| {
                bench.iter(|| {
                    w.step();
                    b.after_step(&w);
                })
            });
        }
        g.finish();
    }
}

criterion_group!(benches, steps);
criterion_main!(benches);
