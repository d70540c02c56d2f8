//! Daily-use details: a disk sweep with no time metric written, one variant
//! re-run with full logs, log retention levels, `--junit` inside a `--logs`
//! directory that does not exist yet, `plan` in the file's units, `list`
//! aligned, and a full disk named as such.

use crate::common::*;
use std::path::Path;
use std::process::{Command, Output};

fn bin(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap()
}

fn ok(o: &Output) -> String {
    assert!(
        o.status.success(),
        "exit {:?}\n{}\n{}",
        o.status,
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// A cheap disk sweep over `sim.friction` with no `time_metric` written.
fn friction_sweep() -> String {
    let base = disk_scenario(&model("rolling_disk.urdf"), "name = \"fs\"", "")
        .replace("dt = 0.001", "dt = 0.004")
        .replace(
            "goal = [-0.4, 1.0, 180.0, 22.5]",
            "goal = [-0.2, 0.3, 90.0, 10.0]",
        );
    format!(
        "{base}\n[sweep]\ncount = 4\nseed = 5\nsuccess_max = 0.05\n\n[sweep.vary]\n\
         \"sim.friction\" = {{ uniform = [0.6, 1.0] }}\n"
    )
}

#[test]
fn a_disk_friction_sweep_needs_no_time_metric_and_one_variant_reruns_with_logs() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("fs.toml"), friction_sweep()).unwrap();
    let out = ok(&bin(dir.path(), &["run", "fs.toml", "--quiet", "--report"]));
    assert!(out.contains("final error (sim_goal_position)"), "{out}");
    assert!(
        out.contains("time to goal: not reported (the model has no time-to-goal metric"),
        "{out}"
    );
    assert!(!out.contains("time to goal, s"), "{out}");
    let sweep: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("logs/fs/sweep.json")).unwrap(),
    )
    .unwrap();
    assert!(sweep["sweep"]["time_metric"].is_null());
    assert!(sweep["time_to_goal"].is_null());
    let page = std::fs::read_to_string(dir.path().join("logs/fs/report.html")).unwrap();
    assert!(page.contains("<h2>Distributions</h2>") && page.contains("<svg"));
    assert!(
        page.contains("no time metric"),
        "the report must say there is none"
    );

    // Variant 2 again, as a single run with every log file.
    let v2 = sweep["results"][2]["params"]["sim.friction"]
        .as_f64()
        .unwrap();
    let out = ok(&bin(
        dir.path(),
        &["run", "fs.toml", "--variant", "2", "--quiet"],
    ));
    assert!(
        out.contains(&format!("variant 2 of fs: sim.friction = {v2}")),
        "{out}"
    );
    let logs = dir.path().join("logs/fs-variant-2");
    for f in ["run.mcap", "run.rrd", "series.json", "summary.json"] {
        assert!(logs.join(f).is_file(), "{f} missing");
    }
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(logs.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["sim_settings"]["friction"].as_f64(), Some(v2));
    let final_error = sweep["results"][2]["final_error"].as_f64().unwrap();
    assert_eq!(
        s["metrics"]["sim_goal_position"].as_f64(),
        Some(final_error)
    );
    // The sweep's own logs are still there, and `report` indexes both.
    assert!(dir.path().join("logs/fs/sweep.json").is_file());
    let out = ok(&bin(dir.path(), &["report"]));
    assert!(out.contains("(2 scenarios"), "{out}");

    let o = bin(dir.path(), &["run", "fs.toml", "--variant", "4"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("key `sweep.count`: --variant 4 is not a variant"),
        "{err}"
    );
}

#[test]
fn keep_levels_and_junit_in_a_new_log_directory() {
    let dir = tempfile::tempdir().unwrap();
    let text = disk_scenario(&model("rolling_disk.urdf"), "name = \"k\"", "");
    std::fs::write(dir.path().join("k.toml"), &text).unwrap();
    // --junit inside a --logs directory that the run creates.
    ok(&bin(
        dir.path(),
        &[
            "check",
            "k.toml",
            "--quiet",
            "--logs",
            "out/logs",
            "--junit",
            "out/logs/junit.xml",
            "--keep",
            "report",
            "--report",
        ],
    ));
    assert!(dir.path().join("out/logs/junit.xml").is_file());
    let names = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    let k = dir.path().join("out/logs/k");
    assert_eq!(names(&k), ["report.html", "series.json", "summary.json"]);
    let page = std::fs::read_to_string(k.join("report.html")).unwrap();
    assert!(!page.contains("run.rrd"), "links to dropped logs");
    ok(&bin(
        dir.path(),
        &[
            "run", "k.toml", "--quiet", "--logs", "out/logs", "--keep", "summary",
        ],
    ));
    assert_eq!(names(&k), ["summary.json"]);
    let o = bin(dir.path(), &["report", "out/logs"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--keep summary"));
    ok(&bin(
        dir.path(),
        &["run", "k.toml", "--quiet", "--logs", "out/logs"],
    ));
    assert_eq!(
        names(&k),
        ["run.mcap", "run.rrd", "series.json", "summary.json"]
    );
    // A --junit directory that nothing creates is still refused.
    let o = bin(
        dir.path(),
        &["run", "k.toml", "--quiet", "--junit", "elsewhere/j.xml"],
    );
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn plan_prints_the_files_units_and_list_is_aligned() {
    let out = ok(&bin(&root(), &["plan", "scenarios/disk_paper.toml"]));
    let line = out
        .lines()
        .find(|l| l.contains("ideal final state"))
        .unwrap();
    assert!(line.contains(" m, ") && line.contains(" deg"), "{line}");
    // disk_paper's goal heading, written in degrees in the file.
    let text = std::fs::read_to_string(root().join("scenarios/disk_paper.toml")).unwrap();
    let goal = text.lines().find(|l| l.starts_with("goal")).unwrap();
    let theta: f64 = goal.split(',').nth(2).unwrap().trim().parse().unwrap();
    let shown = line
        .split("theta = ")
        .nth(1)
        .unwrap()
        .split(' ')
        .next()
        .unwrap();
    let shown: f64 = shown.parse().unwrap();
    assert!((shown - theta).abs() < 1e-3, "{line} vs {goal}");

    let out = ok(&bin(&root(), &["list"]));
    let lines: Vec<&str> = out.lines().collect();
    assert!(lines.len() > 20);
    // The model, planner and description columns start at the same place on every line.
    for col in ["model", "planner", "description"] {
        let at = lines[0].find(col).unwrap();
        for l in &lines[1..] {
            let before = &l[..l.char_indices().nth(at).map_or(l.len(), |(i, _)| i)];
            assert!(
                before.ends_with("  ") && !l[before.len()..].starts_with(' '),
                "`{col}` misaligned:\n{}\n{l}",
                lines[0]
            );
        }
    }
    // Every shipped scenario has a description.
    for l in &lines[1..] {
        let desc = &l[lines[0].find("description").unwrap()..];
        assert!(!desc.trim().is_empty(), "no description: {l}");
    }
}

/// A write the OS refuses names the OS error, not the MCAP writer's
/// "attempted another write after a write method failed". The file size
/// limit (`ulimit -f`, SIGXFSZ ignored) makes writes fail with EFBIG the way
/// a full disk makes them fail with ENOSPC, without a file system to fill.
#[test]
fn a_refused_write_names_the_os_error() {
    let dir = tempfile::tempdir().unwrap();
    let text = disk_scenario(&model("rolling_disk.urdf"), "name = \"f\"", "");
    std::fs::write(dir.path().join("f.toml"), &text).unwrap();
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "trap '' XFSZ; ulimit -f 64; exec '{}' run f.toml --quiet",
            env!("CARGO_BIN_EXE_anholonomy")
        ))
        .current_dir(dir.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(3), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("File too large (os error 27)"), "{err}");
    assert!(!err.contains("attempted another write"), "{err}");
    // Nothing half-written is left as the run's logs.
    assert!(!dir.path().join("logs/f/summary.json").exists());
}
