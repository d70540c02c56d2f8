//! External feedback law round trips: one control sample through the line
//! protocol with a trivial Python law (it parses the request and answers a
//! constant input), the start and stop of a law process, and, for scale,
//! one sample of a built-in law (the rover's feedback primitives) in process.
//!
//! `cargo bench --bench external` (needs python3).

use anholonomy::model::State;
use anholonomy::sources::external::{self, ExternalParams};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use std::path::PathBuf;
mod common;

/// A trivial law: read a request, answer zeros for the disk's two inputs.
const TRIVIAL: &str = r#"
import json, sys
read, write, flush = sys.stdin.readline, sys.stdout.write, sys.stdout.flush
while True:
    line = read()
    if not line:
        break
    msg = json.loads(line)
    write(json.dumps({"u": [0.0, 0.0], "label": "trivial"}) + "\n")
    flush()
"#;

/// The interpreter itself (a version manager's shim only adds start time).
fn python() -> PathBuf {
    let out = std::process::Command::new("python3")
        .args(["-c", "import sys; print(sys.executable)"])
        .output()
        .expect("the external-law bench needs python3");
    PathBuf::from(String::from_utf8(out.stdout).unwrap().trim())
}

fn law_plan() -> anholonomy::plan::Plan {
    let program = python();
    let params = ExternalParams {
        command: vec![program.display().to_string(), "-c".into(), TRIVIAL.into()],
        period: 0.02,
        horizon: 1.0,
        timeout: 5.0,
        base: PathBuf::from("."),
    };
    external::plan(
        &params,
        program,
        &["x", "y", "theta", "alpha"],
        &["theta_rate", "alpha_rate"],
    )
}

fn round_trips(c: &mut Criterion) {
    let plan = law_plan();
    let q = State::from_vec(vec![0.123456789, -1.0 / 3.0, 2.5, 0.7]);
    let mut g = c.benchmark_group("external_law");
    g.throughput(Throughput::Elements(1));
    {
        let mut ctl = plan.controller();
        let mut t = 0.0;
        g.bench_function("python_round_trip", |b| {
            b.iter(|| {
                // A new time every sample (a repeat would be answered from cache).
                t += 0.02;
                let c = ctl.command(t, &q);
                assert!(ctl.fault().is_none(), "{:?}", ctl.fault());
                c
            })
        });
    }
    g.sample_size(20);
    g.bench_function("python_start_first_answer_stop", |b| {
        b.iter(|| {
            let mut ctl = plan.controller();
            let c = ctl.command(0.0, &q);
            assert!(ctl.fault().is_none(), "{:?}", ctl.fault());
            c
        })
    });
    g.sample_size(100);
    let rover = common::prepared("rover_paper");
    let (start, _) = rover.start_goal();
    let mut ctl = rover.planned.controller();
    let mut t = 0.0;
    g.bench_function("builtin_rover_primitives_sample", |b| {
        b.iter(|| {
            t += 0.05;
            ctl.command(t, &start)
        })
    });
    g.finish();
}

criterion_group!(benches, round_trips);
criterion_main!(benches);
