//! Rolling-sphere benchmarks: planner solve times (both planners, the paper's cases), the
//! planner as the harness calls it, and the physics step rate.
//!
//! `cargo bench --bench sphere`. Medians are quoted in the README.

use anholonomy::model::State;
use anholonomy::robots::rolling_sphere::geometric::{self, ArcDirection, SphereGeometricParams};
use anholonomy::robots::rolling_sphere::kinematics::RollingSphere;
use anholonomy::robots::rolling_sphere::triangle::{self, SphereTriangleParams};
mod common;
use common::{bench_driven_steps, prepared, STEPS};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::hint::black_box;

fn deg_state(v: [f64; 5]) -> State {
    State::from_vec(vec![
        v[0],
        v[1],
        v[2].to_radians(),
        v[3].to_radians(),
        v[4].to_radians(),
    ])
}

fn planners(c: &mut Criterion) {
    let m = RollingSphere { a: 1.0 };
    let mut g = c.benchmark_group("sphere_planner");
    // §5.1: the (A)-(B)-(A) solve (root scan over Δα, Newton for θ').
    let start = deg_state([5.0, 5.0, -60.0, 45.0, -30.0]);
    let goal = deg_state([0.0; 5]);
    let ccw = SphereGeometricParams {
        direction: ArcDirection::Ccw,
        ..Default::default()
    };
    g.bench_function("geometric_solve_paper_ccw", |b| {
        b.iter(|| geometric::solve(&m, black_box(&start), &goal, &ccw).expect("solve"))
    });
    let auto = SphereGeometricParams::default();
    g.bench_function("geometric_solve_paper_auto", |b| {
        b.iter(|| geometric::solve(&m, black_box(&start), &goal, &auto).expect("solve"))
    });
    // §5.2: one triangle, paper's fixed ψ (Newton on Eqs. 17, 18, 21) and free ψ (default).
    let (d, phi, yaw) = (1.8, 56.31f64.to_radians(), -std::f64::consts::FRAC_PI_2);
    let paper = SphereTriangleParams {
        psi_offset_deg: Some(10.0),
        ..Default::default()
    };
    g.bench_function("triangle_solve_paper_fixed_psi", |b| {
        b.iter(|| triangle::solve_triangles(black_box(d), phi, yaw, &paper).expect("solve"))
    });
    let free = SphereTriangleParams::default();
    g.bench_function("triangle_solve_paper_free_psi", |b| {
        b.iter(|| triangle::solve_triangles(black_box(d), phi, yaw, &free).expect("solve"))
    });
    // Two triangles: a pure translation (α = 0).
    g.bench_function("triangle_solve_two_triangles", |b| {
        b.iter(|| triangle::solve_triangles(black_box(2.06), -0.245, 0.0, &free).expect("solve"))
    });
    g.finish();
    // The planner as the harness runs it (conversion, solve, plan assembly).
    let mut g = c.benchmark_group("sphere_plan_scenario");
    for name in ["sphere_geometric_paper", "sphere_triangle_paper"] {
        let prep = prepared(name);
        g.bench_function(name, |b| b.iter(|| prep.plan().expect("plan")));
    }
    g.finish();
}

fn physics_steps(c: &mut Criterion) {
    let prep = prepared("sphere_geometric_paper");
    let mut g = c.benchmark_group("sphere_physics");
    g.throughput(Throughput::Elements(STEPS));
    g.sample_size(20);
    bench_driven_steps(&mut g, "1000_steps_rolling", &prep, &[0.5, 0.8], 0);
    g.finish();
}

criterion_group!(benches, planners, physics_steps);
criterion_main!(benches);
