//! Scenarios of one `check` call run in parallel: the printed results, their
//! order and every logged metric are the same on one and on two threads.
//! (Two scenarios of one call never share a name, hence a log directory: the
//! validation pass refuses that, `tests/bad_input.rs`.)

use crate::common::*;
use std::path::Path;
use std::process::Command;

/// A shipped scenario's text with its URDF path made absolute.
fn shipped(file: &str) -> String {
    std::fs::read_to_string(scenario(file)).unwrap().replace(
        "../models/",
        &format!("{}/", root().join("models").display()),
    )
}

/// `check` on `dir` with `threads` rayon threads, logs under `logs`; stdout.
fn check(dir: &Path, threads: &str, logs: &str) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .args(["check", ".", "--quiet", "--logs", logs])
        .env("RAYON_NUM_THREADS", threads)
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The printed results without wall times (the steps/s and wall columns, the sweep's seconds).
fn without_timings(stdout: &str) -> Vec<String> {
    stdout
        .lines()
        .map(|l| {
            if let Some((head, tail)) = l.split_once(" variants, ") {
                return format!("{head}{}", &tail[tail.find(')').unwrap()..]);
            }
            let f: Vec<&str> = l.split_whitespace().collect();
            if f.len() > 5 && (f[0] == "scenario" || f[2].parse::<usize>().is_ok()) {
                [&f[..3], &f[5..]].concat().join(" ")
            } else {
                l.to_string()
            }
        })
        .collect()
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
fn one_and_two_threads_print_and_log_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for f in [
        "disk_paper.toml",
        "space_robot_paper.toml",
        "sphere_triangle_paper.toml",
    ] {
        std::fs::write(d.join(f), shipped(f)).unwrap();
    }
    let sweep = shipped("rover_sweep.toml")
        .replace("count = 100", "count = 4")
        .replace("min_success_rate = 0.9", "min_success_rate = 0.0");
    std::fs::write(d.join("rover_sweep.toml"), sweep).unwrap();
    // Two more disks, cheap, listed first: results stay in input order.
    let disk = disk_scenario(&model("rolling_disk.urdf"), "name = \"disk_a\"", "");
    std::fs::write(d.join("a_disk.toml"), &disk).unwrap();
    let other = disk.replace("disk_a", "disk_b").replace(
        "goal = [-0.4, 1.0, 180.0, 22.5]",
        "goal = [0.3, 0.5, 90.0, 10.0]",
    );
    std::fs::write(d.join("b_disk.toml"), other).unwrap();

    let one = check(d, "1", "logs1");
    let two = check(d, "2", "logs2");
    assert_eq!(without_timings(&one), without_timings(&two), "{one}\n{two}");
    let rows: Vec<&str> = one
        .lines()
        .skip_while(|l| !l.starts_with("scenario "))
        .skip(1)
        .map(|l| l.split_whitespace().next().unwrap())
        .collect();
    assert_eq!(
        rows,
        [
            "disk_a",
            "disk_b",
            "disk_paper",
            "rover_sweep",
            "space_robot_paper",
            "sphere_triangle_paper"
        ]
    );
    for name in [
        "disk_paper",
        "space_robot_paper",
        "sphere_triangle_paper",
        "disk_a",
        "disk_b",
    ] {
        let (a, b) = (
            json(&d.join("logs1").join(name).join("summary.json")),
            json(&d.join("logs2").join(name).join("summary.json")),
        );
        assert_eq!(a["metrics"], b["metrics"], "{name}");
        assert_eq!(a["sim"], b["sim"], "{name}");
    }
    let strip = |mut v: serde_json::Value| {
        for r in v["results"].as_array_mut().unwrap() {
            r.as_object_mut().unwrap().remove("wall_s");
        }
        v["results"].clone()
    };
    assert_eq!(
        strip(json(&d.join("logs1/rover_sweep/sweep.json"))),
        strip(json(&d.join("logs2/rover_sweep/sweep.json")))
    );
}
