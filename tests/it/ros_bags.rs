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

/// Writes one recording with rosbags in sqlite3 storage (the Iron+ layout,
/// with message definitions), converts it to MCAP with rosbags' own
/// converter, and copies it into ROS 2 Humble's sqlite3 layout (schema 3:
/// no `message_definitions` table, as `ros2 bag record` on Humble leaves
/// it). Commands: `N` seeded random Twists at 20 Hz with receive-time
/// jitter, and a second topic that is not the commands.
const SQLITE_AND_MCAP: &str = r#"
import random, shutil, sqlite3, subprocess, sys
from pathlib import Path
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore

out, seed, n = Path(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
st = get_typestore(Stores.ROS2_HUMBLE)
T = st.types
TW, F64 = "geometry_msgs/msg/Twist", "std_msgs/msg/Float64"
V3 = T["geometry_msgs/msg/Vector3"]
rng = random.Random(seed)
ns = 1_700_000_000 * 10**9
with Writer(out / "rec_sqlite3", version=9, storage_plugin=StoragePlugin.SQLITE3) as w:
    cmd = w.add_connection("/cmd_vel", TW, typestore=st)
    other = w.add_connection("/battery", F64, typestore=st)
    for k in range(n):
        ns += 50_000_000 + rng.randint(-3_000_000, 3_000_000)
        v, om = rng.uniform(-0.3, 0.3), rng.uniform(-1.0, 1.0)
        msg = T[TW](linear=V3(x=v, y=0.0, z=0.0), angular=V3(x=0.0, y=0.0, z=om))
        w.write(cmd, ns, bytes(st.serialize_cdr(msg, TW)))
        if k % 10 == 0:
            w.write(other, ns + 1, bytes(st.serialize_cdr(T[F64](data=12.0), F64)))
subprocess.run(
    [sys.executable, "-m", "rosbags.convert", "--src", str(out / "rec_sqlite3"),
     "--dst", str(out / "rec_mcap"), "--dst-storage", "mcap"],
    check=True,
)
src = out / "rec_sqlite3"
humble = out / "rec_humble"
humble.mkdir()
old = sqlite3.connect(src / "rec_sqlite3.db3")
new = sqlite3.connect(humble / "rec_humble_0.db3")
new.executescript("""
CREATE TABLE schema(schema_version INTEGER PRIMARY KEY, ros_distro TEXT NOT NULL);
INSERT INTO schema VALUES (3, 'humble');
CREATE TABLE metadata(id INTEGER PRIMARY KEY, metadata_version INTEGER NOT NULL, metadata TEXT NOT NULL);
CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL,
  serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);
CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL,
  timestamp INTEGER NOT NULL, data BLOB NOT NULL);
CREATE INDEX timestamp_idx ON messages (timestamp ASC);
""")
new.executemany("INSERT INTO topics VALUES (?, ?, ?, ?, ?)",
    old.execute("SELECT id, name, type, serialization_format, offered_qos_profiles FROM topics"))
new.executemany("INSERT INTO messages VALUES (?, ?, ?, ?)",
    old.execute("SELECT id, topic_id, timestamp, data FROM messages"))
new.commit()
meta = (src / "metadata.yaml").read_text()
(humble / "metadata.yaml").write_text(
    meta.replace("rec_sqlite3.db3", "rec_humble_0.db3").replace("version: 9", "version: 5"))
"#;

/// A rosbag2 bag in sqlite3 storage replays with exactly the commands of
/// the same bag converted to MCAP (by rosbags' converter), and so does its
/// copy in Humble's layout, which stores no message definitions (the
/// common command types are built in): identical metrics, bit for bit, in
/// the ideal run and in physics.
#[test]
fn a_sqlite3_bag_replays_the_commands_of_its_mcap_conversion() {
    let python = python::python_with("rosbags");
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("write.py");
    std::fs::write(&script, SQLITE_AND_MCAP).unwrap();
    let n = 120;
    for seed in [3u64, 8] {
        let bags = dir.path().join(format!("seed{seed}"));
        std::fs::create_dir_all(&bags).unwrap();
        let out = std::process::Command::new(&python)
            .arg(&script)
            .arg(&bags)
            .args([seed.to_string(), n.to_string()])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "write.py: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let meta = std::fs::read_to_string(bags.join("rec_mcap/metadata.yaml")).unwrap();
        assert!(meta.contains("storage_identifier: mcap"), "{meta}");
        let outcomes: Vec<RunOutcome> = ["rec_sqlite3", "rec_mcap", "rec_humble"]
            .iter()
            .map(|b| {
                let path = bags.join(b);
                let sc = scenario(
                    &bags,
                    b,
                    &diff_drive(),
                    [0.1, -0.2, 15.0],
                    &format!("path = \"{}\"", path.display()),
                );
                let prep = Prepared::new(Scenario::load(&sc).unwrap_or_else(|e| panic!("{e}")))
                    .unwrap_or_else(|e| panic!("{b}: {e}"));
                let details = prep.planned.details.to_string();
                assert!(
                    details.contains(&format!("\"messages\":{n}")),
                    "{b}: {details}"
                );
                assert!(details.contains("\"topic\":\"/cmd_vel\""), "{b}: {details}");
                run(&prep, &opts()).unwrap()
            })
            .collect();
        let (sq, mc, hu) = (&outcomes[0], &outcomes[1], &outcomes[2]);
        assert!(sq.metrics.len() > 10);
        for (what, other) in [("MCAP conversion", mc), ("Humble layout", hu)] {
            let differ: Vec<_> = sq
                .metrics
                .iter()
                .filter(|(k, v)| {
                    let w = other.metric(k).unwrap();
                    !(v.to_bits() == w.to_bits() || (v.is_nan() && w.is_nan()))
                })
                .collect();
            assert!(
                differ.is_empty(),
                "seed {seed}, sqlite3 vs {what}: {differ:?}"
            );
        }
        // The commands moved the robot (the comparison is not of two stills).
        assert!(sq.metric("ideal_goal_position").unwrap() > 0.05);
    }
}

/// The committed sqlite3 bag (make_bags.py: twist_steps' commands in
/// sqlite3 storage), as a directory and as its one `.db3` file, plans what
/// the MCAP bag plans.
#[test]
fn the_committed_sqlite3_bag_plans_what_its_mcap_twin_plans() {
    let dir = tempfile::tempdir().unwrap();
    let start = [0.3, 0.1, -40.0];
    let end = |name: &str, path: PathBuf| {
        let sc = scenario(
            dir.path(),
            name,
            &diff_drive(),
            start,
            &format!("path = \"{}\"\ntopic = \"/cmd_vel\"", path.display()),
        );
        ideal_end(&sc)
    };
    let (s0, mcap) = end("mcap", bag("twist_steps"));
    assert_close("closed form", mcap, closed_form(s0, &STEPS), 1e-9);
    for (name, path) in [
        ("sqlite3_dir", bag("sqlite3")),
        ("sqlite3_file", bag("sqlite3/sqlite3.db3")),
    ] {
        let (_, got) = end(name, path);
        assert_eq!(got.map(f64::to_bits), mcap.map(f64::to_bits), "{name}");
    }
}
