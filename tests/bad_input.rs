//! Bad input: one-line error, exit code 2, no panic, no log file.

mod common;
use common::*;
use std::path::Path;

/// Write `text` as a scenario in a fresh directory, run `anholonomy run` on it
/// and check the contract. Returns stderr.
fn expect_input_error(text: &str, needle: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bad.toml");
    std::fs::write(&file, text).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    check_contract(&out, dir.path(), needle)
}

fn check_contract(out: &std::process::Output, dir: &Path, needle: &str) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "one line expected: {stderr}"
    );
    assert!(stderr.starts_with("error: "), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains(needle), "`{needle}` not in: {stderr}");
    assert!(
        files_below(&dir.join("logs")).is_empty(),
        "a log file was written"
    );
    stderr
}

#[test]
fn missing_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = cli(dir.path(), &["run", "nope.toml", "--logs", "logs"]);
    check_contract(&out, dir.path(), "nope.toml");
}

#[test]
fn toml_syntax_error_names_line() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "friction = = 1");
    let err = expect_input_error(&text, "bad.toml:");
    // The broken line is the last one of the [sim] table.
    let line = text.lines().position(|l| l.contains("= =")).unwrap() + 1;
    assert!(err.contains(&format!(":{line}:")), "{err}");
}

#[test]
fn unknown_key_names_key_and_line() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "fricton = 0.5");
    let err = expect_input_error(&text, "fricton");
    let line = text.lines().position(|l| l.contains("fricton")).unwrap() + 1;
    assert!(err.contains(&format!(":{line}:")), "{err}");
}

#[test]
fn unknown_planner() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "")
        .replace("kind = \"stokes_disk\"", "kind = \"teleport\"");
    expect_input_error(&text, "teleport");
}

#[test]
fn nan_and_infinite_numbers() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "friction = nan");
    expect_input_error(&text, "sim.friction");
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "")
        .replace("goal = [-0.4,", "goal = [-inf,");
    expect_input_error(&text, "goal[0]");
    let text =
        disk_scenario(&model("rolling_disk.urdf"), "", "").replace("dt = 0.001", "dt = 1e999");
    expect_input_error(&text, "sim.dt");
}

#[test]
fn missing_urdf() {
    let text = disk_scenario(Path::new("/nonexistent/disk.urdf"), "", "");
    expect_input_error(&text, "model.urdf");
}

#[test]
fn urdf_that_does_not_parse() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("broken.urdf");
    std::fs::write(&urdf, "<robot name=\"x\"><link name=\"a\"></robot>").unwrap();
    let file = dir.path().join("bad.toml");
    std::fs::write(&file, disk_scenario(&urdf, "", "")).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    check_contract(&out, dir.path(), "URDF does not parse");
}

#[test]
fn urdf_with_dangling_joint() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("dangling.urdf");
    let text = std::fs::read_to_string(model("rolling_disk.urdf"))
        .unwrap()
        .replace("<child link=\"wheel\"/>", "<child link=\"ghost\"/>");
    std::fs::write(&urdf, text).unwrap();
    std::fs::write(dir.path().join("bad.toml"), disk_scenario(&urdf, "", "")).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    check_contract(&out, dir.path(), "ghost");
}

#[test]
fn radius_mismatch_with_urdf() {
    let text =
        disk_scenario(&model("rolling_disk.urdf"), "", "").replace("radius = 0.25", "radius = 0.3");
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.toml"), text).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    check_contract(&out, dir.path(), "radius");
}

#[test]
fn unknown_threshold_metric() {
    let text = format!(
        "{}\n[thresholds]\nsim_goal_teleport = 1.0\n",
        disk_scenario(&model("rolling_disk.urdf"), "", "")
    );
    expect_input_error(&text, "sim_goal_teleport");
}

#[test]
fn wrong_state_length() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "")
        .replace("start = [0.0, 0.0, 0.0, 0.0]", "start = [0.0, 0.0]");
    expect_input_error(&text, "start");
}

#[test]
fn check_on_bad_input_also_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = cli(dir.path(), &["check", "missing_dir/"]);
    check_contract(&out, dir.path(), "missing_dir");
}

#[test]
fn unknown_planner_key_names_its_line() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "").replace(
        "kind = \"stokes_disk\"",
        "kind = \"stokes_disk\"\nalgoritm = \"x\"",
    );
    let err = expect_input_error(&text, "algoritm");
    let line = text
        .lines()
        .position(|l| l.starts_with("algoritm"))
        .unwrap()
        + 1;
    assert!(err.contains(&format!(":{line}:")), "{err}");
}

#[test]
fn solver_and_drive_settings_out_of_range() {
    for (sim, needle) in [
        ("solver_pgs_iterations = 0", "sim.solver_pgs_iterations"),
        ("motor_angle_gain = -1.0", "sim.motor_angle_gain"),
        ("solver_relax_pass = 1", "expected a boolean"),
    ] {
        let text = disk_scenario(&model("rolling_disk.urdf"), "", sim);
        expect_input_error(&text, needle);
    }
}

#[test]
fn urdf_the_loader_cannot_represent() {
    // A mesh collision, and a second root link: both named, nothing simulated.
    let base = std::fs::read_to_string(model("rolling_disk.urdf")).unwrap();
    for (edit, needle) in [
        (
            base.replace(
                "<collision>",
                "<collision><geometry><mesh filename=\"w.stl\"/></geometry></collision><collision>",
            ),
            "mesh <collision>",
        ),
        (
            base.replace(
                "</robot>",
                "<link name=\"stray\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link></robot>",
            ),
            "2 root links",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let urdf = dir.path().join("edited.urdf");
        std::fs::write(&urdf, edit).unwrap();
        std::fs::write(dir.path().join("bad.toml"), disk_scenario(&urdf, "", "")).unwrap();
        let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
        check_contract(&out, dir.path(), needle);
    }
}
