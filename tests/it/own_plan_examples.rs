//! The examples of "Validate your own planner" run as a user runs them:
//! the minimal external-law clients (Python and Rust) on the disk, and a
//! built-in run's logged plan replayed from its run.mcap.

use crate::common::*;
use std::path::{Path, PathBuf};

fn summary_metrics(path: &Path) -> serde_json::Map<String, serde_json::Value> {
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    v["metrics"].as_object().unwrap().clone()
}

/// `cargo test` builds the examples next to the test binaries.
fn built_example(name: &str) -> PathBuf {
    let exe = std::env::current_exe().unwrap();
    let dir = exe.parent().unwrap().parent().unwrap().join("examples");
    let p = dir.join(name);
    assert!(p.is_file(), "{} not built", p.display());
    p
}

/// Copy `files` (paths from the repository root) into `dir`, keeping their places.
fn workspace(dir: &Path, files: &[&str]) {
    for f in files {
        let to = dir.join(f);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(root().join(f), &to).unwrap();
    }
}

/// Both minimal clients run the same law and pass their gates; they read
/// the same requests and answer the same inputs (the Rust client's serde_json
/// may round the state's last bit, so the physics runs agree to 1e-12, not
/// bit for bit).
#[test]
fn the_minimal_clients_pass() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ex = "examples/external_law";
    workspace(
        d,
        &[
            "models/rolling_disk.urdf",
            &format!("{ex}/minimal_client.py"),
            &format!("{ex}/disk_heading.toml"),
            &format!("{ex}/disk_heading_rust.toml"),
        ],
    );
    // The shipped scenario runs the release build; this test runs whichever
    // build cargo made.
    let rust = format!("{ex}/disk_heading_rust.toml");
    let text = std::fs::read_to_string(d.join(&rust)).unwrap();
    let shipped = "command = [\"../../target/release/examples/minimal_client\"]";
    assert!(text.contains(shipped), "{text}");
    let built = built_example("minimal_client");
    std::fs::write(
        d.join(&rust),
        text.replace(
            shipped,
            &format!("command = [{:?}]", built.display().to_string()),
        ),
    )
    .unwrap();
    let out = cli(d, &["check", ex, "--logs", "logs", "--quiet"]);
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let py = summary_metrics(&d.join("logs/disk_heading/summary.json"));
    let rs = summary_metrics(&d.join("logs/disk_heading_rust/summary.json"));
    for (k, v) in &py {
        let (a, b) = (v.as_f64().unwrap(), rs[k].as_f64().unwrap());
        assert!((a - b).abs() <= 1e-12, "{k}: {a} vs {b}");
    }
    // The law said done at 3 s.
    let s: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("logs/disk_heading/summary.json")).unwrap())
            .unwrap();
    assert_eq!(s["ideal"]["end_time_s"], 3.0);
}

/// rover_open_loop's logged plan replayed from its run.mcap, exactly as the
/// example's comment says to run it, gives rover_open_loop's metrics: the
/// physics ones bit for bit, the ideal ones within 1e-9.
#[test]
fn the_logged_plan_replays_with_the_same_metrics() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let example = "examples/replay_logged_plan/rover_open_loop_replay.toml";
    workspace(
        d,
        &[
            "models/rover.urdf",
            "scenarios/rover_open_loop.toml",
            example,
        ],
    );
    for args in [
        &["run", "scenarios/rover_open_loop.toml", "--quiet"][..],
        &["check", example, "--quiet"][..],
    ] {
        let out = cli(d, args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let a = summary_metrics(&d.join("logs/rover_open_loop/summary.json"));
    let b = summary_metrics(&d.join("logs/rover_open_loop_replay/summary.json"));
    assert_eq!(a.len(), b.len());
    let mut exact = 0;
    for (k, v) in &a {
        let (x, y) = (v.as_f64(), b[k].as_f64());
        let physics = k.starts_with("sim_") || k.starts_with("envelope_") || k.starts_with("slip_");
        if physics {
            assert_eq!(x, y, "{k}");
            exact += 1;
        } else if let (Some(x), Some(y)) = (x, y) {
            assert!((x - y).abs() <= 1e-9, "{k}: {x} vs {y}");
        } else {
            assert_eq!(x, y, "{k}");
        }
    }
    assert!(exact >= 10, "{exact}");
}

/// The plan-file example of the tutorial passes its gates; its goal is the
/// disk's closed-form motion under the held inputs (written in the
/// scenario), which the ideal run reaches to round-off.
#[test]
fn the_plan_file_example_passes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let ex = "examples/plan_file";
    workspace(
        d,
        &[
            "models/rolling_disk.urdf",
            &format!("{ex}/disk_turn.csv"),
            &format!("{ex}/disk_turn.toml"),
        ],
    );
    let out = cli(d, &["check", ex, "--logs", "logs", "--quiet"]);
    assert!(
        out.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let m = summary_metrics(&d.join("logs/disk_turn/summary.json"));
    let ideal = m["ideal_goal_position"].as_f64().unwrap();
    assert!(ideal < 1e-9, "{ideal}");
    // Broken plan files are refused at their row and column.
    std::fs::write(
        d.join(format!("{ex}/disk_turn.csv")),
        "t,theta_rate,alpha_rate\n0.0,2.0,0.0\n1.0,2.0,NaN\n2.0,0.0,0.0\n",
    )
    .unwrap();
    let out = cli(d, &["check", ex, "--quiet"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("disk_turn.csv:3: column `alpha_rate`"),
        "{err}"
    );
}
