//! Harness overheads: the validation pass (parse, URDF, plan, physics at the
//! start pose) and log writing.
//!
//! `cargo bench --bench harness -- --warm-up-time 1 --measurement-time 4`.
//! Medians are quoted in the README.

use anholonomy::log::{write_mcap, write_rrd};
use anholonomy::scenario::Scenario;
use anholonomy::validate::{prepare_all, Call, Prepared};
use criterion::{criterion_group, criterion_main, Criterion};
use std::path::Path;

#[path = "../tests/it/common/log_fixture.rs"]
mod log_fixture;

fn validation(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut g = c.benchmark_group("validate");
    g.sample_size(10);
    // What every `run`/`check`/`plan`/`list` call does before anything runs.
    g.bench_function("all_shipped_scenarios", |b| {
        b.iter(|| {
            prepare_all(&[root.join("scenarios")], &Call::default())
                .map_err(|e| e.len())
                .expect("valid")
        })
    });
    // The most expensive single scenarios (planning dominates).
    for name in [
        "space_manipulator_s1",
        "rover_open_loop",
        "sphere_triangle_two",
    ] {
        let sc = Scenario::load(&root.join(format!("scenarios/{name}.toml"))).expect("load");
        g.bench_function(name, |b| {
            b.iter(|| {
                Prepared::new(sc.clone())
                    .map_err(|e| e.to_string())
                    .expect("prepare")
            })
        });
    }
    g.finish();
}

fn log_write(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("tempdir");
    let fx = log_fixture::Fixture::new(3000);
    let rec = fx.record();
    let mut g = c.benchmark_group("log_write");
    g.sample_size(10);
    g.bench_function("mcap_3000_samples", |b| {
        b.iter(|| write_mcap(&dir.path().join("a.mcap"), &rec).expect("mcap"))
    });
    g.bench_function("rrd_3000_samples", |b| {
        b.iter(|| write_rrd(&dir.path().join("a.rrd"), &rec).expect("rrd"))
    });
    g.finish();
}

criterion_group!(benches, validation, log_write);
criterion_main!(benches);
