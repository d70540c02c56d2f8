//! Same scenario, same result: `summary.json` (everything outside
//! `wall_time_s`) and `plan --json` are identical across two processes, and a
//! sweep's results do not depend on the number of threads.

use crate::common::*;
use std::path::Path;

/// A JSON document without its timing section.
fn without_timings(path: &Path) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    let timings = v
        .as_object_mut()
        .unwrap()
        .remove("wall_time_s")
        .expect("a wall_time_s section");
    assert!(timings.is_object(), "{timings}");
    v
}

fn ok(out: &std::process::Output) {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Two processes, one disk and one endogenous scenario (whose planner used to
/// put its wall time into the plan details).
#[test]
fn summaries_and_plans_are_identical_across_processes() {
    let dir = tempfile::tempdir().unwrap();
    let files = [
        "disk_paper.toml",
        "space_manipulator_s2.toml",
        "dilf_single_open.toml",
    ];
    for logs in ["a", "b"] {
        let mut args = vec![
            "run".to_string(),
            "--quiet".into(),
            "--logs".into(),
            logs.into(),
        ];
        args.extend(files.iter().map(|f| scenario(f).display().to_string()));
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        ok(&cli(dir.path(), &args));
    }
    for name in ["disk_paper", "space_manipulator_s2", "dilf_single_open"] {
        let a = without_timings(&dir.path().join("a").join(name).join("summary.json"));
        let b = without_timings(&dir.path().join("b").join(name).join("summary.json"));
        assert_eq!(a, b, "{name}: summary.json differs outside wall_time_s");
        assert!(a["metrics"].as_object().unwrap().len() > 10);
    }
    for f in files {
        let path = scenario(f).display().to_string();
        let a = cli(dir.path(), &["plan", &path, "--json"]);
        let b = cli(dir.path(), &["plan", &path, "--json"]);
        ok(&a);
        assert!(!a.stdout.is_empty());
        assert_eq!(
            a.stdout, b.stdout,
            "{f}: plan --json differs between two runs"
        );
    }
}

/// A small disk sweep on 1 and on 2 threads gives the same sweep.json.
#[test]
fn sweep_results_do_not_depend_on_threads() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "{}\n[sweep]\ncount = 4\nseed = 7\nfriction = [0.3, 1.0]\nmass_scale = [0.8, 1.2]\n\
         success_max = 0.05\ntime_metric = \"sim_goal_position\"\n",
        disk_scenario(&model("rolling_disk.urdf"), "name = \"mini\"", "")
    );
    std::fs::write(dir.path().join("mini.toml"), text).unwrap();
    for (threads, logs) in [("1", "one"), ("2", "two")] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
            .args(["run", "mini.toml", "--quiet", "--logs", logs])
            .env("RAYON_NUM_THREADS", threads)
            .current_dir(dir.path())
            .output()
            .unwrap();
        ok(&out);
    }
    let a = without_timings(&dir.path().join("one/mini/sweep.json"));
    let b = without_timings(&dir.path().join("two/mini/sweep.json"));
    assert_eq!(a["variants_run"], 4);
    assert_eq!(a, b, "sweep.json differs between 1 and 2 threads");
    // Per-variant timings sit under wall_time_s only.
    assert!(a["results"][0].get("wall_s").is_none());
}
