//! Baselines: write, compare, regress, update; bad baseline files.

use crate::common::*;
use std::path::Path;
use std::process::Output;

/// A disk scenario named `disk_fixture` (same name for the worsened variant, so the
/// worsened run is compared with the unchanged run's baseline).
fn fixture(dir: &Path, extra_sim: &str, extra: &str) {
    let text = format!(
        "{}\n{extra}\n",
        disk_scenario(
            &model("rolling_disk.urdf"),
            "name = \"disk_fixture\"",
            extra_sim
        )
    );
    std::fs::write(dir.join("s.toml"), text).unwrap();
}

fn text(o: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}

fn one_line_input_error(o: &Output, needle: &str) -> String {
    let (_, err) = text(o);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert_eq!(
        err.trim_end().lines().count(),
        1,
        "one line expected: {err}"
    );
    assert!(
        err.starts_with("error: ") && !err.contains("panicked"),
        "{err}"
    );
    assert!(err.contains(needle), "`{needle}` not in {err}");
    err
}

#[test]
fn worsened_run_fails_unchanged_passes_update_resets() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    fixture(dir, "", "");
    let o = cli(
        dir,
        &[
            "baseline",
            "s.toml",
            "--baseline",
            "base",
            "--no-logs",
            "--quiet",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
    let file = dir.join("base/disk_fixture.json");
    let written = std::fs::read_to_string(&file).unwrap();
    let v: serde_json::Value = serde_json::from_str(&written).unwrap();
    assert_eq!(v["scenario"], "disk_fixture");
    let keys: Vec<&String> = v["metrics"].as_object().unwrap().keys().collect();
    let mut sorted = keys.clone();
    sorted.sort();
    assert_eq!(keys, sorted, "metrics sorted by name in the file");
    assert!(written.find("\"ideal_goal_alpha_deg\"") < written.find("\"tracking_y_rms\""));

    // The same scenario again: every metric within tolerance.
    let o = cli(
        dir,
        &[
            "check",
            "s.toml",
            "--baseline",
            "base",
            "--no-logs",
            "--quiet",
        ],
    );
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}\n{err}");
    assert!(out.contains("every metric within tolerance"), "{out}");

    // Worsened: pure velocity motors instead of servo drives (a deliberate regression).
    fixture(dir, "motor_angle_gain = 0.0", "");
    let o = cli(
        dir,
        &[
            "check",
            "s.toml",
            "--baseline",
            "base",
            "--no-logs",
            "--quiet",
        ],
    );
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}\n{err}");
    assert!(err.contains("regressed against their baseline"), "{err}");
    let header = out
        .lines()
        .find(|l| l.starts_with("scenario") && l.contains("baseline") && l.contains("change"))
        .expect("regression table header");
    for col in ["metric", "now"] {
        assert!(header.contains(col), "{header}");
    }
    let regressed: Vec<&str> = out.lines().filter(|l| l.contains("REGRESSED")).collect();
    assert!(!regressed.is_empty(), "{out}");
    assert!(
        regressed.iter().all(|l| l.starts_with("disk_fixture")),
        "{out}"
    );
    // Every regressed row is a lower-is-better metric that rose beyond its tolerance.
    for l in &regressed {
        let f: Vec<&str> = l.split_whitespace().collect();
        let (base, now): (f64, f64) = (f[3].parse().unwrap(), f[4].parse().unwrap());
        assert_eq!(f[2], "lower", "{l}");
        assert!(
            now > base + base.abs() * anholonomy::scenario::regression::DEFAULT_REL,
            "{l}"
        );
    }
    assert_eq!(
        std::fs::read_to_string(&file).unwrap(),
        written,
        "check must not write baselines"
    );

    // A generous per-scenario tolerance accepts the worsened run.
    fixture(dir, "motor_angle_gain = 0.0", "[regression]\nrel = 1e6\n");
    let o = cli(
        dir,
        &[
            "check",
            "s.toml",
            "--baseline",
            "base",
            "--no-logs",
            "--quiet",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));

    // --update-baseline accepts the new numbers; then check passes.
    fixture(dir, "motor_angle_gain = 0.0", "");
    let o = cli(
        dir,
        &[
            "check",
            "s.toml",
            "--baseline",
            "base",
            "--update-baseline",
            "--no-logs",
            "--quiet",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
    assert_ne!(std::fs::read_to_string(&file).unwrap(), written);
    let o = cli(
        dir,
        &[
            "check",
            "s.toml",
            "--baseline",
            "base",
            "--no-logs",
            "--quiet",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
}

#[test]
fn bad_baselines_are_input_errors_and_nothing_is_written() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    fixture(dir, "", "");
    std::fs::create_dir(dir.join("base")).unwrap();
    let file = dir.join("base/disk_fixture.json");
    let check = || {
        cli(
            dir,
            &["check", "s.toml", "--baseline", "base", "--logs", "logs"],
        )
    };

    // Missing.
    let e = one_line_input_error(&check(), "no baseline for scenario `disk_fixture`");
    assert!(e.contains("anholonomy baseline"), "{e}");
    // Corrupt (truncated JSON): file and line.
    let corrupt = "{\n  \"anholonomy_baseline\": 1,\n  \"scenario\": \"disk_fixture\",\n  \"metrics\": {\n    \"x\": 1.0,";
    std::fs::write(&file, corrupt).unwrap();
    let e = one_line_input_error(&check(), "base/disk_fixture.json:");
    assert!(e.contains("not a baseline file"), "{e}");
    assert_eq!(
        std::fs::read_to_string(&file).unwrap(),
        corrupt,
        "baseline overwritten"
    );
    // From another scenario: names the key and its line.
    let other = "{\n  \"anholonomy_baseline\": 1,\n  \"scenario\": \"disk_paper\",\n  \"planner\": \"stokes_disk\",\n  \"metrics\": {}\n}\n";
    std::fs::write(&file, other).unwrap();
    let e = one_line_input_error(&check(), "disk_fixture.json:3: key `scenario`");
    assert!(e.contains("disk_paper"), "{e}");
    // A metric that is not a number.
    let text_metric = other
        .replace("disk_paper", "disk_fixture")
        .replace("{}", "{\"x\": \"1\"}");
    std::fs::write(&file, text_metric).unwrap();
    one_line_input_error(
        &check(),
        "key `x`: must be a number, \"inf\", \"-inf\" or null",
    );
    assert!(
        files_below(&dir.join("logs")).is_empty(),
        "logs written despite bad input"
    );
}

#[test]
fn regression_table_keys_are_checked() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    fixture(
        dir,
        "",
        "[regression]\nrel = 0.1\nmetrics.not_a_metric = { rel = 0.5 }\n",
    );
    let o = cli(dir, &["run", "s.toml", "--logs", "logs"]);
    let e = one_line_input_error(&o, "key `regression.metrics.not_a_metric`: unknown metric");
    let text = std::fs::read_to_string(dir.join("s.toml")).unwrap();
    let line = text
        .lines()
        .position(|l| l.contains("not_a_metric"))
        .unwrap()
        + 1;
    assert!(e.contains(&format!("s.toml:{line}:")), "{e}");
    fixture(dir, "", "[regression]\nrel = -0.1\n");
    let o = cli(dir, &["run", "s.toml", "--logs", "logs"]);
    one_line_input_error(&o, "key `regression.rel`: must be ≥ 0");
    fixture(dir, "", "[regression]\nrelative = 0.1\n");
    let o = cli(dir, &["run", "s.toml", "--logs", "logs"]);
    one_line_input_error(&o, "relative");
}

#[test]
fn shipped_baselines_match_their_scenarios() {
    // Every shipped scenario has a committed baseline for it (CI gates on them).
    let scenarios = anholonomy::scenario::collect(&[root().join("scenarios")]).unwrap();
    for f in scenarios {
        let sc = anholonomy::scenario::Scenario::load(&f).unwrap();
        let path = anholonomy::baseline::path_for(&root().join("baselines"), &sc.name);
        let b = anholonomy::baseline::Baseline::load(&path, &sc.name, sc.planner.kind())
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(!b.metrics.is_empty(), "{}", path.display());
    }
}
