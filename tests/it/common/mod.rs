//! Helpers shared by the integration tests (`crate::common`).
#![allow(dead_code)]

pub mod dopri;
pub mod legs;
pub mod log_fixture;
#[path = "../../../src/prop_config.rs"]
pub mod prop_config;
pub mod python;

use anholonomy::runner::{run, Prepared, RunOptions, RunOutcome};
use anholonomy::scenario::Scenario;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Repository root.
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Absolute path of a shipped scenario file.
pub fn scenario(file: &str) -> PathBuf {
    root().join("scenarios").join(file)
}

/// A scenario file, loaded and validated.
pub fn prepared(path: &Path) -> Prepared {
    Prepared::new(Scenario::load(path).unwrap()).unwrap()
}

/// Run a prepared scenario without progress bars, logging under `logs` if given.
pub fn run_prepared(prep: &Prepared, logs: Option<&Path>) -> RunOutcome {
    let opts = RunOptions {
        log_root: logs.map(Path::to_path_buf),
        progress: Default::default(),
        pose_rate: anholonomy::runner::DEFAULT_POSE_RATE,
        cancel: Default::default(),
        keep: anholonomy::log::Keep::All,
        batch: true,
    };
    run(prep, &opts).unwrap()
}

/// Load and run a scenario file.
pub fn run_file(path: &Path, logs: Option<&Path>) -> RunOutcome {
    run_prepared(&prepared(path), logs)
}

/// A run that slipped: it is reported as failing `sim_goal_position`, ends more
/// than `min_error` m from the goal, while its ideal run hits the goal.
pub fn assert_slip_failure(o: &RunOutcome, min_error: f64) {
    assert!(!o.passed);
    let broke = o
        .failures
        .iter()
        .any(|f| f.starts_with("sim_goal_position"));
    assert!(broke, "{:?}", o.failures);
    let sim = o.metric("sim_goal_position").unwrap();
    assert!(
        sim > min_error,
        "sim goal error {sim} not above {min_error}"
    );
    assert!(o.metric("ideal_goal_position").unwrap() < 1e-9);
}

/// Absolute path of a model file.
pub fn model(name: &str) -> PathBuf {
    root().join("models").join(name)
}

/// Run the CLI with `args` in `cwd`.
pub fn cli(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .args(args)
        .current_dir(cwd)
        .output()
        .expect("binary runs")
}

/// A disk scenario text with the given overrides appended to the main table
/// (`extra_top`) and to the sim table (`extra_sim`).
pub fn disk_scenario(urdf: &Path, extra_top: &str, extra_sim: &str) -> String {
    format!(
        r#"{extra_top}
start = [0.0, 0.0, 0.0, 0.0]
goal = [-0.4, 1.0, 180.0, 22.5]

[model]
kind = "rolling_disk"
radius = 0.25
urdf = "{}"

[planner]
kind = "stokes_disk"

[sim]
dt = 0.001
{extra_sim}
"#,
        urdf.display()
    )
}

/// Every file below `dir`, recursively.
pub fn files_below(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(rd) = std::fs::read_dir(dir) {
        for e in rd.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(files_below(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}
