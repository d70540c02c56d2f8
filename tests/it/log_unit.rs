//! A run's logs are one unit: `kill -9` at any moment of a re-run leaves
//! either the previous run's four files or the new run's, never a mix, and
//! the next run cleans up what the killed one left.

use crate::common::*;
use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Duration;

const FILES: [&str; 4] = ["run.mcap", "run.rrd", "series.json", "summary.json"];

fn read_set(dir: &Path) -> Option<BTreeMap<&'static str, Vec<u8>>> {
    if !dir.exists() {
        return None;
    }
    let names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    let mut sorted = names.clone();
    sorted.sort();
    assert_eq!(sorted, FILES, "exactly the four files of one run");
    Some(
        FILES
            .iter()
            .map(|f| (*f, std::fs::read(dir.join(f)).unwrap()))
            .collect(),
    )
}

/// `disk_long_trip` named `k`, with goal x = `x` (each re-run changes it).
fn scenario_text(x: f64) -> String {
    let text = std::fs::read_to_string(scenario("disk_long_trip.toml"))
        .unwrap()
        .replace(
            "../models/",
            &format!("{}/", root().join("models").display()),
        );
    let goal = "goal = [4.0, -4.5, 720.0, 200.0]";
    assert!(text.contains(goal));
    format!(
        "name = \"k\"\n{}",
        text.replace(goal, &format!("goal = [{x}, -4.5, 720.0, 200.0]"))
    )
}

#[test]
fn killed_rerun_never_leaves_a_mix_of_two_runs() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("k.toml");
    let run = |x: f64| {
        std::fs::write(&file, scenario_text(x)).unwrap();
        Command::new(env!("CARGO_BIN_EXE_anholonomy"))
            .args(["run", "k.toml", "--quiet", "--logs", "logs"])
            .current_dir(dir.path())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap()
    };
    let target = dir.path().join("logs/k");
    assert!(run(0.5).wait().unwrap().success());
    let mut prev = read_set(&target);
    assert!(prev.is_some());
    // Kill points spread over planning, physics, log writing and the swap.
    for (i, ms) in [0u64, 40, 120, 250, 400, 550, 700, 900].iter().enumerate() {
        let x = 0.6 + 0.1 * i as f64;
        let mut child = run(x);
        std::thread::sleep(Duration::from_millis(*ms));
        let _ = child.kill();
        let finished = child.wait().unwrap().success();
        let now = read_set(&target);
        match (&prev, &now) {
            (Some(p), Some(n)) => {
                let same: Vec<bool> = FILES.iter().map(|f| p[f] == n[f]).collect();
                assert!(
                    same.iter().all(|s| *s) || same.iter().all(|s| !*s),
                    "kill after {ms} ms: files of two runs side by side ({same:?})"
                );
                if same.iter().all(|s| !*s) {
                    let s: serde_json::Value = serde_json::from_slice(&n["summary.json"]).unwrap();
                    let gx = s["goal"]["x"].as_f64().unwrap();
                    assert!(
                        (gx - x).abs() < 1e-12,
                        "new set is from this run: {gx} vs {x}"
                    );
                }
            }
            (_, None) => assert!(!finished, "a finished run leaves its logs"),
            (None, Some(_)) => {}
        }
        prev = now;
    }
    // A complete run afterwards leaves nothing of the killed ones behind.
    assert!(run(2.0).wait().unwrap().success());
    let names: Vec<String> = std::fs::read_dir(dir.path().join("logs"))
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["k"], "staging directories left: {names:?}");
    read_set(&target).unwrap();
}
