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
    fixture(dir, "", "[regression]\nabs = -0.001\n");
    let o = cli(dir, &["run", "s.toml", "--logs", "logs"]);
    one_line_input_error(&o, "key `regression.abs`: must be");
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
    // A feedback law's tracking metrics are n/a: not in its baseline.
    let path = root().join("baselines/diff_drive_go_to_pose.json");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains("sim_goal_position"), "{text}");
    assert!(!text.contains("tracking_"), "{text}");
}

/// The value of `metric` in baseline file `file`, replaced by `f(value)`.
fn edit_baseline(file: &Path, metric: &str, f: impl Fn(f64) -> f64) -> f64 {
    let text = std::fs::read_to_string(file).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let x = v["metrics"][metric]
        .as_f64()
        .unwrap_or_else(|| panic!("{metric} in {text}"));
    v["metrics"][metric] = serde_json::json!(f(x));
    std::fs::write(file, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    x
}

#[test]
fn changes_below_the_floor_pass_a_longer_time_to_goal_fails() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    // A gate on the goal distance (10 mm: floor 1 mm); none on the clearance-free
    // tracking metrics (unit floor 0.1 mm) or the time to goal (10 ms).
    fixture(dir, "", "[thresholds]\nsim_goal_position = 0.01\n");
    let args = [
        "check",
        "s.toml",
        "--baseline",
        "base",
        "--no-logs",
        "--quiet",
    ];
    let mut write = args.to_vec();
    write.push("--update-baseline");
    let o = cli(dir, &write);
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
    let file = dir.join("base/disk_fixture.json");
    let pristine = std::fs::read_to_string(&file).unwrap();

    // Worse by 0.9 mm under a 10 mm gate, and by 0.09 mm on an ungated
    // length: both far beyond 2 %, both below their floors.
    let g = edit_baseline(&file, "sim_goal_position", |x| (x - 9e-4).max(0.0));
    assert!(
        g >= 9e-4 && 9e-4 > 0.02 * g,
        "goal error {g}: pick another margin"
    );
    let t = edit_baseline(&file, "tracking_position_final", |x| x - 9e-5);
    assert!(t > 9e-5 && 9e-5 > 0.02 * (t - 9e-5), "tracking {t}");
    let o = cli(dir, &args);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(0), "{out}\n{err}");

    // A 13 % longer time to goal still fails (the shipped car parking run,
    // no gate on its time: 10 ms floor, 2 % of 12.7 s).
    let car = root().join("scenarios/car_parking.toml");
    let car = car.to_str().unwrap();
    let o = cli(
        dir,
        &[
            "baseline",
            car,
            "--baseline",
            "cars",
            "--no-logs",
            "--quiet",
        ],
    );
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
    let cars = dir.join("cars/car_parking.json");
    let tt = edit_baseline(&cars, "sim_time_to_goal", |x| x / 1.13);
    assert!(tt.is_finite() && tt > 1.0, "time to goal {tt}");
    let car_check = ["check", car, "--baseline", "cars", "--no-logs", "--quiet"];
    let o = cli(dir, &car_check);
    let (out, err) = text(&o);
    assert_eq!(o.status.code(), Some(1), "{out}\n{err}");
    let rows: Vec<&str> = out.lines().filter(|l| l.contains("REGRESSED")).collect();
    assert_eq!(rows.len(), 1, "{out}");
    assert!(rows[0].contains("sim_time_to_goal"), "{out}");
    // 1 % longer: within 2 %.
    edit_baseline(&cars, "sim_time_to_goal", |_| tt / 1.01);
    let o = cli(dir, &car_check);
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));

    // `[regression]` overrides keep working: a relative tolerance of 1e6 on
    // the disk's tracking error accepts a tenfold one.
    std::fs::write(&file, &pristine).unwrap();
    edit_baseline(&file, "tracking_position_final", |x| x / 10.0);
    let o = cli(dir, &args);
    assert_eq!(o.status.code(), Some(1), "{:?}", text(&o));
    fixture(
        dir,
        "",
        "[thresholds]\nsim_goal_position = 0.01\n[regression]\nmetrics.tracking_position_final = { rel = 1e6 }\n",
    );
    let o = cli(dir, &args);
    assert_eq!(o.status.code(), Some(0), "{:?}", text(&o));
}
