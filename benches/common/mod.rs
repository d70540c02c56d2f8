//! Helpers shared by the benchmarks (included with `mod common;`).
#![allow(dead_code)]

use anholonomy::model::Input;
use anholonomy::runner::Prepared;
use anholonomy::scenario::Scenario;
use criterion::measurement::WallTime;
use criterion::{BatchSize, BenchmarkGroup};
use std::path::Path;

/// Physics steps per measured iteration.
pub const STEPS: u64 = 1000;

/// A shipped scenario by file stem, loaded and validated.
pub fn prepared(stem: &str) -> Prepared {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenarios/{stem}.toml"));
    Prepared::new(Scenario::load(&path).expect("scenario")).expect("prepared")
}

/// Bench [`STEPS`] physics steps under the constant input `u`, on a fresh
/// system each iteration that first took `settle` unactuated steps.
pub fn bench_driven_steps(
    g: &mut BenchmarkGroup<'_, WallTime>,
    name: &str,
    prep: &Prepared,
    u: &[f64],
    settle: usize,
) {
    let u = Input::from_vec(u.to_vec());
    g.bench_function(name, |b| {
        b.iter_batched(
            || {
                let mut sys = prep.physics().expect("physics");
                for _ in 0..settle {
                    sys.step();
                }
                sys
            },
            |mut sys| {
                for _ in 0..STEPS {
                    sys.apply(&u);
                    sys.step();
                }
                sys.state()
            },
            BatchSize::LargeInput,
        )
    });
}
