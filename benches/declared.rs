//! A declared model's cost: the ideal run of the unicycle written in the
//! scenario (`examples/declared_diff_drive/`) against the built-in
//! `diff_drive`'s, on the same plan (the S curve, 11 s at 1 ms: 11 000 RK4
//! steps). The goal is at most 1.5× the built-in's time.
//!
//! Then seed 001's endogenous planner's time on the built-in space
//! manipulator and on the same model declared (`endogenous_plan`).
//!
//! `cargo bench --bench declared -- --warm-up-time 1 --measurement-time 4`.

use anholonomy::integrate::simulate;
use anholonomy::model::State;
use anholonomy::scenario::Scenario;
use anholonomy::validate::Prepared;
use criterion::{criterion_group, criterion_main, Criterion};
use std::path::Path;

fn ideal_runs(c: &mut Criterion) {
    let ex = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/declared_diff_drive");
    let text = std::fs::read_to_string(ex.join("declared_diff_drive.toml")).expect("example");
    // The built-in model: the declaration dropped, the same URDF and plan.
    let a = text.find("states = ").expect("states");
    let b = text.find("[planner]").expect("planner");
    let builtin = format!("{}\n{}", &text[..a], &text[b..])
        .replace("kind = \"declared\"", "kind = \"diff_drive\"");
    let load = |t: &str| {
        Prepared::new(Scenario::parse(&ex.join("bench.toml"), t).expect("parse")).expect("prepare")
    };
    let mut g = c.benchmark_group("ideal_run");
    for (name, prep) in [
        ("declared_unicycle", load(&text)),
        ("builtin_diff_drive", load(&builtin)),
    ] {
        let start = State::from_vec(prep.scenario.start.clone());
        let plan = prep.planned.clone();
        g.bench_function(name, |b| {
            b.iter(|| simulate(prep.model(), &plan, &start, prep.scenario.sim.dt))
        });
    }
    g.finish();
}

/// Seed 001's endogenous planner on the space manipulator, built in
/// (analytic A and B) and written as a declared model (A and B by forward-
/// mode automatic differentiation of the declared equations): the same
/// task (scenarios/space_manipulator_s3.toml), the same 766 iterations, so
/// the ratio of the plan times is the ratio per iteration.
fn endogenous_plans(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let load = |p: &Path| Prepared::new(Scenario::load(p).expect("parse")).expect("prepare");
    let mut g = c.benchmark_group("endogenous_plan");
    g.sample_size(20);
    for (name, path) in [
        (
            "builtin_space_manipulator_s3",
            root.join("scenarios/space_manipulator_s3.toml"),
        ),
        (
            "declared_space_manipulator_s3",
            root.join("tests/data/declared/space_manipulator_s3.toml"),
        ),
    ] {
        let prep = load(&path);
        g.bench_function(name, |b| b.iter(|| prep.plan().expect("plan")));
    }
    g.finish();
}

criterion_group!(benches, ideal_runs, endogenous_plans);
criterion_main!(benches);
