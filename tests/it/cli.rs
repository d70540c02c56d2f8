//! The command-line interface: help, list, plan, run/check exit codes.

use crate::common::*;

#[test]
fn help_explains_each_command() {
    let out = cli(&root(), &["--help"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for word in ["run", "check", "plan", "list", "Exit status"] {
        assert!(text.contains(word), "{word} missing from --help:\n{text}");
    }
    for (cmd, words) in [
        ("run", &["--logs", "--shard", "summary.json"][..]),
        ("check", &["Exit status", "threshold", "--shard"][..]),
        ("plan", &["--json", "validated", "ideal final state"][..]),
        ("list", &["stderr", "exit status", "scenarios/"][..]),
    ] {
        let out = cli(&root(), &[cmd, "--help"]);
        assert!(out.status.success(), "{cmd} --help");
        let text = String::from_utf8_lossy(&out.stdout);
        assert!(text.len() > 400, "{cmd} --help too short:\n{text}");
        for w in words {
            assert!(text.contains(w), "{w} missing from {cmd} --help:\n{text}");
        }
    }
}

#[test]
fn list_shows_shipped_scenarios() {
    let out = cli(&root(), &["list"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    for name in [
        "disk_paper",
        "disk_singularity_free",
        "disk_singular_exact",
        "disk_long_trip",
    ] {
        assert!(text.contains(name), "{name} not listed:\n{text}");
    }
}

#[test]
fn plan_json_reaches_the_goal_without_physics() {
    let out = cli(&root(), &["plan", "scenarios/disk_paper.toml", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let fin: Vec<f64> = serde_json::from_value(v["ideal_final_state"].clone()).unwrap();
    let goal = [-0.4, 1.0, std::f64::consts::PI, std::f64::consts::PI / 8.0];
    for (a, b) in fin.iter().zip(goal) {
        assert!((a - b).abs() < 1e-9, "{fin:?}");
    }
    assert_eq!(v["labels"][0], "loop at O: PQ");
    assert!(v["details"]["loops"][0]["b_rad"].as_f64().unwrap() > 0.8);
}

#[test]
fn check_exits_1_on_a_broken_threshold_and_run_does_not() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "{}\n[thresholds]\nsim_goal_position = 1e-9\n",
        disk_scenario(&model("rolling_disk.urdf"), "", "")
    );
    std::fs::write(dir.path().join("tight.toml"), text).unwrap();
    let out = cli(dir.path(), &["check", "tight.toml", "--no-logs"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stdout).contains("FAIL"));
    let out = cli(dir.path(), &["run", "tight.toml", "--logs", "out"]);
    assert_eq!(out.status.code(), Some(0));
    assert!(dir.path().join("out/tight/run.mcap").is_file());
}

/// Hidden entries of a directory (editor locks such as `.#a.toml`, often
/// dangling symlinks) are not scenarios.
#[cfg(unix)]
#[test]
fn hidden_entries_of_a_directory_are_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("set");
    std::fs::create_dir(&d).unwrap();
    std::fs::write(
        d.join("a.toml"),
        disk_scenario(&model("rolling_disk.urdf"), "", ""),
    )
    .unwrap();
    std::os::unix::fs::symlink("nobody@host.1234", d.join(".#a.toml")).unwrap();
    let out = cli(dir.path(), &["list", "set"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("rolling_disk"));
}
