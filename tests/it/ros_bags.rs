//! ROS 2 bags as plan files (`[planner] kind = "file"`, `path` = a bag).
//!
//! The bags are the committed ones of `tests/data/ros_bags/`, written by
//! `examples/ros_bags/make_bags.py` with the rosbags library (a standard
//! rosbag2 writer: CDR serialization and MCAP storage are its, not ours);
//! `bags_are_what_make_bags_writes` checks they still are. The commands
//! below are the script's, restated here: each test integrates them in
//! closed form (arcs under a zero-order hold) and compares with the ideal
//! run the bag's plan gives, from random starts.

use crate::common::*;
use anholonomy::runner::{run, Prepared, RunOptions, RunOutcome};
use anholonomy::scenario::Scenario;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};

/// make_bags.py's STEPS: (v m/s, omega rad/s), each held 0.25 s.
const STEPS: [(f64, f64); 6] = [
    (0.5, 0.0),
    (0.5, 1.0),
    (0.25, -0.5),
    (0.0, 0.75),
    (-0.375, 0.0),
    (0.5, -1.25),
];
/// make_bags.py's STEERS: (speed m/s, steering angle rad), each held 0.25 s.
const STEERS: [(f64, f64); 6] = [
    (0.5, 0.0),
    (0.5, 0.25),
    (0.25, -0.375),
    (0.0, 0.125),
    (-0.375, 0.3125),
    (0.5, 0.0),
];
const HOLD: f64 = 0.25;
/// The car scenario's wheelbase (that of models/car.urdf).
const WHEELBASE: f64 = 0.32;

fn bag(name: &str) -> PathBuf {
    root().join("tests/data/ros_bags").join(name)
}

/// A scenario of `model` (a `[model]` table body) planning from `plan`
/// (`[planner]` keys after `kind = "file"`), from `start`.
fn scenario(dir: &Path, name: &str, model: &str, start: [f64; 3], planner: &str) -> PathBuf {
    let text = format!(
        r#"name = "{name}"
start = [{:?}, {:?}, {:?}]
goal = [0.0, 0.0, 0.0]

[model]
{model}

[planner]
kind = "file"
{planner}

[sim]
dt = 0.001
settle = 0.2
"#,
        start[0], start[1], start[2]
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

fn diff_drive() -> String {
    format!(
        "kind = \"diff_drive\"\nurdf = \"{}\"",
        model("diff_drive.urdf").display()
    )
}

fn car() -> String {
    format!(
        "kind = \"car\"\nurdf = \"{}\"\nsteering = \"angle\"\nwheelbase = {WHEELBASE:?}",
        model("car.urdf").display()
    )
}

/// The closed-form end of `(v, omega)` commands each held `HOLD` (the plan
/// ends one median period, `HOLD`, after the last, stopped).
fn closed_form(start: [f64; 3], commands: &[(f64, f64)]) -> [f64; 3] {
    commands
        .iter()
        .fold(start, |q, &(v, w)| legs::unicycle_arc(q, v, w, HOLD))
}

/// The ideal run's end state of scenario `path`, and its start.
fn ideal_end(path: &Path) -> ([f64; 3], [f64; 3]) {
    let prep = Prepared::new(Scenario::load(path).unwrap_or_else(|e| panic!("{e}")))
        .unwrap_or_else(|e| panic!("{e}"));
    let (start, _) = prep.start_goal();
    let tr = anholonomy::integrate::simulate(prep.model(), &prep.planned, &start, 1e-3);
    let end = tr.last();
    assert_eq!(end.len(), 3, "states x, y, theta");
    ([start[0], start[1], start[2]], [end[0], end[1], end[2]])
}

fn random_starts(seed: u64) -> Vec<[f64; 3]> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..3)
        .map(|_| {
            [
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(-180.0..180.0),
            ]
        })
        .collect()
}

fn assert_close(what: &str, got: [f64; 3], want: [f64; 3], tol: f64) {
    for i in 0..3 {
        assert!(
            (got[i] - want[i]).abs() < tol,
            "{what}, state {i}: {} vs closed form {} (off {:e})",
            got[i],
            want[i],
            got[i] - want[i]
        );
    }
}

/// Twist (log time) and TwistStamped (header time) bags of piecewise-
/// constant commands end where the arcs of the same commands end.
#[test]
fn twist_bags_end_at_the_closed_form_arcs() {
    let dir = tempfile::tempdir().unwrap();
    for (i, s) in random_starts(39).into_iter().enumerate() {
        for (name, planner) in [
            (
                "twist_log",
                format!("path = \"{}\"", bag("twist_steps").display()),
            ),
            (
                "twist_stamped_header",
                format!(
                    "path = \"{}\"\ntime = \"header\"",
                    bag("twist_stamped_steps").display()
                ),
            ),
            (
                "twist_mcap_file",
                format!(
                    "path = \"{}\"",
                    bag("twist_steps/twist_steps.mcap").display()
                ),
            ),
        ] {
            let path = scenario(
                dir.path(),
                &format!("{name}{i}"),
                &diff_drive(),
                s,
                &planner,
            );
            let (start, end) = ideal_end(&path);
            let want = closed_form(start, &STEPS);
            assert_close(&format!("{name}, start {s:?}"), end, want, 1e-9);
        }
    }
}

/// The TwistStamped bag's log times trail its stamps by 1 to 7 ms of
/// jitter: with the log time the plan is another one (so the header-time
/// test above does read the stamps).
#[test]
fn log_time_of_a_stamped_bag_is_the_receive_time() {
    let dir = tempfile::tempdir().unwrap();
    let planner = format!("path = \"{}\"", bag("twist_stamped_steps").display());
    let path = scenario(dir.path(), "log", &diff_drive(), [0.0; 3], &planner);
    let (start, end) = ideal_end(&path);
    let grid = closed_form(start, &STEPS);
    let off = (0..2).map(|i| (end[i] - grid[i]).abs()).fold(0.0, f64::max);
    assert!(off > 1e-4, "log time ends {off} m from the stamps' end");
}

/// AckermannDriveStamped on the car steered by angle: circular arcs of
/// radius L / tan(steer).
#[test]
fn ackermann_bag_ends_at_the_closed_form_circles() {
    let dir = tempfile::tempdir().unwrap();
    let commands: Vec<(f64, f64)> = STEERS
        .iter()
        .map(|&(v, steer)| (v, v * steer.tan() / WHEELBASE))
        .collect();
    for (i, s) in random_starts(40).into_iter().enumerate() {
        for time in ["log", "header"] {
            let planner = format!(
                "path = \"{}\"\ntime = \"{time}\"",
                bag("ackermann_steps").display()
            );
            let path = scenario(dir.path(), &format!("a{time}{i}"), &car(), s, &planner);
            let (start, end) = ideal_end(&path);
            let want = closed_form(start, &commands);
            assert_close(&format!("time = {time}, start {s:?}"), end, want, 1e-9);
        }
    }
}

/// A made-up message type (a header, a nested message, a fixed array, a
/// string, a sequence) mapped by `[planner.map]`, with either time.
#[test]
fn custom_type_through_planner_map() {
    let dir = tempfile::tempdir().unwrap();
    for time in ["log", "header"] {
        let planner = format!(
            "path = \"{}\"\ntime = \"{time}\"\n[planner.map]\nv = \"motion.forward\"\nomega = \"motion.turn\"",
            bag("custom_steps").display()
        );
        let path = scenario(
            dir.path(),
            &format!("c{time}"),
            &diff_drive(),
            [0.3, -0.2, 40.0],
            &planner,
        );
        let (start, end) = ideal_end(&path);
        assert_close(
            &format!("time = {time}"),
            end,
            closed_form(start, &STEPS),
            1e-9,
        );
    }
    // An element of the fixed array (gains = [1.0, 0.5, 0.25]) as the speed.
    let planner = format!(
        "path = \"{}\"\n[planner.map]\nv = \"gains[2]\"\nomega = \"motion.turn\"",
        bag("custom_steps").display()
    );
    let path = scenario(dir.path(), "gain", &diff_drive(), [0.0; 3], &planner);
    let (start, end) = ideal_end(&path);
    let want: Vec<(f64, f64)> = STEPS.iter().map(|&(_, w)| (0.25, w)).collect();
    assert_close("v = gains[2]", end, closed_form(start, &want), 1e-9);
}

fn opts() -> RunOptions {
    RunOptions {
        log_root: None,
        progress: Default::default(),
        pose_rate: anholonomy::runner::DEFAULT_POSE_RATE,
        cancel: Default::default(),
        keep: anholonomy::log::Keep::All,
        batch: true,
    }
}

fn run_path(path: &Path) -> RunOutcome {
    run(
        &Prepared::new(Scenario::load(path).unwrap()).unwrap(),
        &opts(),
    )
    .unwrap()
}

/// The same commands as a CSV plan: identical metrics, ideal and physics.
#[test]
fn a_csv_of_the_same_commands_gives_identical_metrics() {
    let dir = tempfile::tempdir().unwrap();
    let csv = |cols: &str, rows: &[(f64, f64)]| {
        let mut s = format!("t,{cols}\n");
        for (k, (a, b)) in rows.iter().enumerate() {
            s.push_str(&format!("{:?},{a:?},{b:?}\n", k as f64 * HOLD));
        }
        // The plan's end, one period after the last command: stopped.
        s.push_str(&format!("{:?},0.0,0.0\n", rows.len() as f64 * HOLD));
        s
    };
    std::fs::write(dir.path().join("twist.csv"), csv("v,omega", &STEPS)).unwrap();
    std::fs::write(dir.path().join("steer.csv"), csv("v,steer", &STEERS)).unwrap();
    let start = [0.2, -0.1, 30.0];
    for (name, model, bag_keys, file) in [
        (
            "dd",
            diff_drive(),
            format!("path = \"{}\"", bag("twist_steps").display()),
            "twist.csv",
        ),
        (
            "car",
            car(),
            format!(
                "path = \"{}\"\ntime = \"header\"",
                bag("ackermann_steps").display()
            ),
            "steer.csv",
        ),
    ] {
        let a = run_path(&scenario(
            dir.path(),
            &format!("{name}_bag"),
            &model,
            start,
            &bag_keys,
        ));
        let b = run_path(&scenario(
            dir.path(),
            &format!("{name}_csv"),
            &model,
            start,
            &format!("path = \"{file}\""),
        ));
        assert!(a.metrics.len() > 10, "{:?}", a.metrics);
        let differ: Vec<_> = a
            .metrics
            .iter()
            .filter(|(n, v)| {
                let w = b.metric(n).unwrap();
                !(v.to_bits() == w.to_bits() || (v.is_nan() && w.is_nan()))
            })
            .map(|(n, v)| (n, v, b.metric(n).unwrap()))
            .collect();
        assert!(differ.is_empty(), "{name}: bag vs CSV: {differ:?}");
    }
}

/// The committed bags are what `make_bags.py` writes with rosbags, byte
/// for byte (so the tests above read bags of a standard rosbag2 writer,
/// and a change to the script shows in the bags). Python with rosbags and
/// numpy comes from `crate::common::python` (a venv under target/ when python3
/// lacks them).
#[test]
fn bags_are_what_make_bags_writes() {
    let python = python::python_with("rosbags");
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("examples/ros_bags/make_bags.py");
    std::fs::create_dir_all(script.parent().unwrap()).unwrap();
    std::fs::copy(root().join("examples/ros_bags/make_bags.py"), &script).unwrap();
    let out = std::process::Command::new(&python)
        .arg(&script)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "make_bags.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut compared = 0;
    for sub in ["examples/ros_bags", "tests/data/ros_bags"] {
        let written = files_below(&dir.path().join(sub));
        for f in written {
            let rel = f.strip_prefix(dir.path()).unwrap();
            if rel.extension().is_some_and(|e| e == "py") {
                continue;
            }
            let committed = std::fs::read(root().join(rel))
                .unwrap_or_else(|e| panic!("{}: {e} (not committed)", rel.display()));
            assert!(
                committed == std::fs::read(&f).unwrap(),
                "{} differs from what make_bags.py writes: run python3 examples/ros_bags/make_bags.py",
                rel.display()
            );
            compared += 1;
        }
    }
    assert!(compared >= 20, "{compared} files");
}
