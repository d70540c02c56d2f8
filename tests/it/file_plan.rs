//! `[planner] kind = "file"`: plans read from CSV, JSON and run logs.
//!
//! Replays of logged runs: what a zero-order hold of the logged commands
//! at the logged rate reproduces exactly, and why the rest cannot match
//! (see `docs/src/own-planner.md`, "Replaying a logged run"). Random held
//! plans are checked against a closed-form integration of the disk.

use crate::common::*;
use anholonomy::runner::{run, Prepared, RunOptions, RunOutcome};
use anholonomy::scenario::Scenario;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};

fn opts(logs: Option<&Path>) -> RunOptions {
    RunOptions {
        log_root: logs.map(Path::to_path_buf),
        progress: Default::default(),
        pose_rate: anholonomy::runner::DEFAULT_POSE_RATE,
        cancel: Default::default(),
        keep: anholonomy::log::Keep::All,
        batch: true,
    }
}

/// A shipped scenario with its `[planner]` table replaced by `planner`
/// (TOML lines), written to `dir/<name>.toml`.
fn with_planner(shipped: &str, name: &str, planner: &str, dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(scenario(shipped))
        .unwrap()
        .replace(
            "../models/",
            &format!("{}/", root().join("models").display()),
        )
        .replace("open_loop_replay = true\n", "");
    let mut out = format!("name = \"{name}\"\n");
    let mut skipping = false;
    for line in text.lines() {
        if line.starts_with('[') {
            skipping = line.trim() == "[planner]";
        }
        if !skipping {
            out.push_str(line);
            out.push('\n');
        }
    }
    out.push_str(&format!("\n[planner]\n{planner}\n"));
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, out).unwrap();
    path
}

/// Run `shipped` with logs, then replay its `topic` with a zero-order hold.
fn replay(shipped: &str, topics: &[&str]) -> (RunOutcome, Vec<RunOutcome>) {
    let dir = tempfile::tempdir().unwrap();
    let logs = dir.path().join("logs");
    let original = run_file(&scenario(shipped), Some(&logs));
    let stem = shipped.trim_end_matches(".toml");
    let mcap = logs.join(stem).join("run.mcap");
    let replays = topics
        .iter()
        .enumerate()
        .map(|(i, topic)| {
            let planner = format!(
                "kind = \"file\"\npath = \"{}\"\ntopic = \"{topic}\"\nhold = \"zero_order\"",
                mcap.display()
            );
            let path = with_planner(shipped, &format!("replay{i}"), &planner, dir.path());
            run(
                &Prepared::new(Scenario::load(&path).unwrap()).unwrap(),
                &opts(None),
            )
            .unwrap()
        })
        .collect();
    (original, replays)
}

/// |a − b| per metric whose name passes `pick`.
fn diffs(a: &RunOutcome, b: &RunOutcome, pick: impl Fn(&str) -> bool) -> Vec<(String, f64)> {
    a.metrics
        .iter()
        .filter(|(n, _)| pick(n))
        .map(|(n, v)| {
            let w = b.metric(n).unwrap();
            let d = if v.is_nan() && w.is_nan() {
                0.0
            } else {
                (v - w).abs()
            };
            (n.clone(), d)
        })
        .collect()
}

fn assert_within(what: &str, d: &[(String, f64)], tol: f64) {
    assert!(!d.is_empty(), "{what}: no metrics");
    let bad: Vec<_> = d.iter().filter(|(_, x)| x.is_nan() || *x > tol).collect();
    assert!(bad.is_empty(), "{what}: beyond {tol}: {bad:?}");
}

/// The disk's plan is continuous: the ideal run evaluates u(t) at every
/// RK4 stage, the physics at every step's midpoint. `/sim/command` holds
/// what the physics applied, so its replay reproduces the physics run bit
/// for bit. Its ideal run integrates those midpoint values held over each
/// step, which trails the continuous plan by (dt²/24)·u'(t) at the samples
/// (the midpoint rule's error): zero where u' = 0, at the ends of the
/// ramped legs, so the goal metrics agree to 1e-9, but not mid-ramp, where
/// the tracking maxima are taken. `/plan/command` holds u at each step's
/// start: held, the physics gets it half a step early, an O(dt) change.
#[test]
fn the_disks_logged_commands_replay() {
    let (orig, r) = replay("disk_paper.toml", &["/sim/command", "/plan/command"]);
    let (sim_cmd, plan_cmd) = (&r[0], &r[1]);
    let sim = diffs(&orig, sim_cmd, |n| n.starts_with("sim_"));
    assert!(sim.iter().all(|(_, d)| *d == 0.0), "{sim:?}");
    assert_within(
        "ideal via /sim/command",
        &diffs(&orig, sim_cmd, |n| n.starts_with("ideal_")),
        1e-9,
    );
    // The tracking metrics differ by the midpoint rule's error, no more:
    // max |θ''| = 30 rad/s² (4 rad/s, quintic ramps of 0.25 s), dt = 1 ms.
    let dt: f64 = 1e-3;
    let bound_rad = 1.5 * dt * dt / 24.0 * 30.0;
    let track = diffs(&orig, sim_cmd, |n| n.starts_with("tracking_"));
    for (n, d) in &track {
        let bound = if n.contains("_deg_") {
            bound_rad.to_degrees()
        } else {
            0.25 * bound_rad * 2.0
        };
        assert!(*d <= bound, "{n}: {d} > {bound}");
    }
    let theta_max = track
        .iter()
        .find(|(n, _)| n == "tracking_theta_deg_max")
        .unwrap()
        .1;
    assert!(
        theta_max > 0.5 * (dt * dt / 24.0 * 30.0).to_degrees(),
        "the midpoint rule's error is what separates them: {theta_max}"
    );
    // Step-start samples held: the physics is half a step early.
    let early = diffs(&orig, plan_cmd, |n| n == "sim_goal_theta_deg")[0].1;
    assert!(early > 1e-5, "{early}");
}

/// The rover's policy is a feedback law held for 50 ms. `/plan/command`
/// holds the ideal run's commands: replayed, the ideal run is the built-in
/// one (within 1e-9: the held path and the file's jump-split path round
/// their step sizes differently). `/sim/command` holds the physics run's:
/// replayed, the physics run is the built-in one, bit for bit, with its slip
/// and envelope metrics. No single command stream reproduces both runs:
/// the built-in runs each applied their own (closed loop), so the tracking
/// metrics of a replay compare different runs.
#[test]
fn the_rovers_logged_commands_replay() {
    let (orig, r) = replay("rover_paper.toml", &["/plan/command", "/sim/command"]);
    let (plan_cmd, sim_cmd) = (&r[0], &r[1]);
    assert_within(
        "ideal via /plan/command",
        &diffs(&orig, plan_cmd, |n| n.starts_with("ideal_")),
        1e-9,
    );
    let physics =
        |n: &str| n.starts_with("sim_") || n.starts_with("envelope_") || n.starts_with("slip_");
    let d = diffs(&orig, sim_cmd, physics);
    assert!(d.len() >= 8 && d.iter().all(|(_, x)| *x == 0.0), "{d:?}");
    assert_eq!(orig.steps, sim_cmd.steps);
    // The other stream's run is another run.
    assert!(diffs(&orig, plan_cmd, |n| n == "sim_goal_position")[0].1 > 1.0);
}

/// The disk's exact motion under a held input (θ', α') over `tau`.
fn disk_exact(r: f64, q: [f64; 4], u: [f64; 2], tau: f64) -> [f64; 4] {
    let [x, y, th, a] = q;
    let [ut, ua] = u;
    let a1 = a + ua * tau;
    let (dx, dy) = if ua.abs() > 1e-12 {
        (
            r * ut * (a.cos() - a1.cos()) / ua,
            r * ut * (a1.sin() - a.sin()) / ua,
        )
    } else {
        (r * ut * tau * a.sin(), r * ut * tau * a.cos())
    };
    [x + dx, y + dy, th + ut * tau, a1]
}

fn disk_file_scenario(dir: &Path, name: &str, plan: &str, hold: &str) -> PathBuf {
    let text = format!(
        r#"name = "{name}"
start = [0.1, -0.2, 0.0, 30.0]
goal = [0.0, 0.0, 0.0, 0.0]

[model]
kind = "rolling_disk"
radius = 0.25
urdf = "{}"

[planner]
kind = "file"
path = "{plan}"
hold = "{hold}"

[sim]
dt = 0.001
"#,
        model("rolling_disk.urdf").display()
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Random held plans with samples off the step grid: the ideal run splits
/// its steps at every jump, so it matches the closed-form motion of the
/// piecewise-constant input (an independent integration) to round-off.
#[test]
fn random_held_plans_match_the_closed_form_motion() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    for case in 0..6 {
        let n = rng.random_range(3..40);
        let mut t = vec![0.0];
        for _ in 1..n {
            let last = *t.last().unwrap();
            t.push(last + rng.random_range(0.0003..0.2));
        }
        let u: Vec<[f64; 2]> = (0..n)
            .map(|_| [rng.random_range(-4.0..4.0), rng.random_range(-2.0..2.0)])
            .collect();
        // Columns in another order than the model's inputs, a label column.
        let mut csv = String::from("# random plan\nalpha_rate,label,t,theta_rate\n");
        for k in 0..n {
            csv.push_str(&format!(
                "{:?},leg{},{:?},{:?}\n",
                u[k][1],
                k % 3,
                t[k],
                u[k][0]
            ));
        }
        std::fs::write(dir.path().join(format!("p{case}.csv")), csv).unwrap();
        let path = disk_file_scenario(
            dir.path(),
            &format!("c{case}"),
            &format!("p{case}.csv"),
            "zero_order",
        );
        let prep = Prepared::new(Scenario::load(&path).unwrap()).unwrap();
        let (start, _) = prep.start_goal();
        let tr = anholonomy::integrate::simulate(prep.model(), &prep.planned, &start, 1e-3);
        let mut q = [start[0], start[1], start[2], start[3]];
        for k in 0..n - 1 {
            q = disk_exact(0.25, q, u[k], t[k + 1] - t[k]);
        }
        let end = tr.last();
        // The run ends on the step grid at or after the plan's end; the
        // last sample's value holds from its time on.
        let t_run = *tr.t.last().unwrap();
        q = disk_exact(0.25, q, u[n - 1], t_run - t[n - 1]);
        for i in 0..4 {
            assert!(
                (end[i] - q[i]).abs() < 1e-9,
                "case {case}, coordinate {i}: {} vs {}",
                end[i],
                q[i]
            );
        }
        assert_eq!(
            prep.planned.labels,
            vec!["leg0", "leg1", "leg2"][..n.min(3)]
        );
    }
}

/// Linear hold on the step grid: the angles are pure integrals of the
/// inputs, and RK4 integrates a linear input exactly, so they end at the
/// trapezoid sums of the samples.
#[test]
fn linear_hold_integrates_the_samples_trapezoid() {
    let dir = tempfile::tempdir().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let n = 300;
    let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.004).collect();
    let u: Vec<[f64; 2]> = (0..n)
        .map(|_| [rng.random_range(-3.0..3.0), rng.random_range(-1.0..1.0)])
        .collect();
    let json = serde_json::json!({
        "t": t,
        "u": {
            "theta_rate": u.iter().map(|x| x[0]).collect::<Vec<_>>(),
            "alpha_rate": u.iter().map(|x| x[1]).collect::<Vec<_>>(),
        }
    });
    std::fs::write(dir.path().join("p.json"), json.to_string()).unwrap();
    let path = disk_file_scenario(dir.path(), "lin", "p.json", "linear");
    let prep = Prepared::new(Scenario::load(&path).unwrap()).unwrap();
    let (start, _) = prep.start_goal();
    let tr = anholonomy::integrate::simulate(prep.model(), &prep.planned, &start, 1e-3);
    let trap = |i: usize| -> f64 {
        (0..n - 1)
            .map(|k| 0.5 * (u[k][i] + u[k + 1][i]) * (t[k + 1] - t[k]))
            .sum()
    };
    let end = tr.last();
    assert!(
        (end[2] - start[2] - trap(0)).abs() < 1e-12,
        "{}",
        end[2] - start[2] - trap(0)
    );
    assert!((end[3] - start[3] - trap(1)).abs() < 1e-12);
    assert!((tr.t.last().unwrap() - t[n - 1]).abs() < 1e-12);
}

/// The same samples as CSV and as JSON make the same plan, bit for bit.
#[test]
fn csv_and_json_are_the_same_plan() {
    let dir = tempfile::tempdir().unwrap();
    let t = [0.0, 0.1, 0.30000000000000004, 0.7];
    let a = [0.1, 1.0 / 3.0, -2.5e-3, 0.0];
    let b = [2.0f64.sqrt(), -0.7, 1e-17, 0.0];
    let mut csv = String::from("t,theta_rate,alpha_rate\n");
    for k in 0..4 {
        csv.push_str(&format!("{:?},{:?},{:?}\n", t[k], a[k], b[k]));
    }
    std::fs::write(dir.path().join("p.csv"), csv).unwrap();
    let json = serde_json::json!({"t": t, "u": {"theta_rate": a, "alpha_rate": b}});
    std::fs::write(dir.path().join("p.json"), json.to_string()).unwrap();
    let runs: Vec<RunOutcome> = ["p.csv", "p.json"]
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let path = disk_file_scenario(dir.path(), &format!("f{i}"), p, "zero_order");
            run(
                &Prepared::new(Scenario::load(&path).unwrap()).unwrap(),
                &opts(None),
            )
            .unwrap()
        })
        .collect();
    assert_eq!(runs[0].metrics, runs[1].metrics);
}
