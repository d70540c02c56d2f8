//! `anholonomy fit`: known parameters recovered from synthetic recordings
//! made by another integrator (closed-form unicycle arcs, not the harness's
//! RK4) on random plans, with noise, a time offset and a gap; recordings in
//! rosbag2 bags written by `rosbags` (Odometry, PoseStamped, a tf frame);
//! the shipped examples (the skid steer twin, the MuJoCo recording);
//! `[compare] reference` in `run`.

use crate::common::legs::unicycle_arc;
use crate::common::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A declared unicycle whose ideal run the fit moves: a speed scale `kv`
/// (a wheel radius off) and a turn efficiency `kw`, both 1 in the file.
fn scenario(dir: &Path, reference: Option<&str>) -> PathBuf {
    let compare = reference
        .map(|r| format!("[compare]\nreference = \"{r}\"\n"))
        .unwrap_or_default();
    let text = format!(
        r#"name = "synthetic"
start = [0.5, -0.3, 20.0]
goal = [0.0, 0.0, 0.0]

[model]
kind = "declared"
urdf = "{}"
states = ["x", "y", "theta"]
angles = ["theta"]
inputs = ["v", "omega"]
frictionless = ["caster"]

[model.params]
b = 0.13
r = 0.05
kv = 1.0
kw = 1.0

[model.kinematics]
x = "kv * v * cos(theta)"
y = "kv * v * sin(theta)"
theta = "kw * omega"

[model.drive]
left_wheel_joint = "(v - omega * b) / r"
right_wheel_joint = "(v + omega * b) / r"

[model.read]
x = "base_link.x"
y = "base_link.y"
theta = "base_link.yaw"

[planner]
kind = "file"
path = "plan.csv"

[sim]
dt = 0.01
settle = 0.5
{compare}"#,
        model("diff_drive.urdf").display()
    );
    let p = dir.join("synthetic.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// Random held commands, one per second for six seconds: (t, v, omega),
/// the last row the plan's end.
fn random_plan(rng: &mut ChaCha8Rng) -> Vec<(f64, f64, f64)> {
    let mut rows: Vec<(f64, f64, f64)> = (0..6)
        .map(|k| {
            (
                k as f64,
                rng.random_range(0.1..0.5),
                rng.random_range(-1.0..1.0),
            )
        })
        .collect();
    rows.push((6.0, 0.0, 0.0));
    rows
}

fn write_plan(dir: &Path, rows: &[(f64, f64, f64)]) {
    let mut s = "t,v,omega\n".to_string();
    for (t, v, w) in rows {
        let _ = writeln!(s, "{t},{v},{w}");
    }
    std::fs::write(dir.join("plan.csv"), s).unwrap();
}

/// The pose at plan time `t` of a unicycle from the origin whose speed is
/// `kv` v and turn rate `kw` omega, by closed-form arcs (held before 0 and
/// after the end).
fn truth(rows: &[(f64, f64, f64)], kv: f64, kw: f64, t: f64) -> [f64; 3] {
    let mut q = [0.0; 3];
    for w in rows.windows(2) {
        let (t0, v, om) = w[0];
        let t1 = w[1].0;
        if t <= t0 {
            break;
        }
        q = unicycle_arc(q, kv * v, kw * om, t.min(t1) - t0);
    }
    q
}

fn normal(rng: &mut ChaCha8Rng) -> f64 {
    // Box–Muller.
    let (u, v): (f64, f64) = (rng.random_range(1e-12..1.0), rng.random());
    (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
}

/// A recording CSV at 20 Hz from plan time -1 s to 7 s: `clock` added to
/// t, noise of `sigma` m on x and y (and 5 sigma degrees on the heading),
/// samples in `gaps` (plan time) left out.
fn write_recording(
    dir: &Path,
    rows: &[(f64, f64, f64)],
    (kv, kw): (f64, f64),
    clock: f64,
    sigma: f64,
    gaps: &[(f64, f64)],
    rng: &mut ChaCha8Rng,
) -> usize {
    let mut s = "t,x,y,theta_deg\n".to_string();
    let mut inside = 0;
    for k in -20..=140 {
        let t = k as f64 * 0.05;
        if gaps.iter().any(|(a, b)| t > *a && t < *b) {
            continue;
        }
        let q = truth(rows, kv, kw, t);
        let n = [normal(rng), normal(rng), normal(rng)];
        let _ = writeln!(
            s,
            "{},{},{},{}",
            t + clock,
            q[0] + sigma * n[0],
            q[1] + sigma * n[1],
            q[2].to_degrees() + 5.0 * sigma * n[2]
        );
        if (0.0..=6.5).contains(&t) {
            inside += 1;
        }
    }
    std::fs::write(dir.join("rec.csv"), s).unwrap();
    inside
}

fn fit_json(dir: &Path, args: &[&str], threads: Option<usize>) -> Value {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"));
    cmd.arg("fit")
        .args(args)
        .args(["--json", "--quiet"])
        .current_dir(dir);
    if let Some(n) = threads {
        cmd.env("RAYON_NUM_THREADS", n.to_string());
    }
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "fit {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn param(v: &Value, k: &str) -> f64 {
    v["params"][k]
        .as_f64()
        .unwrap_or_else(|| panic!("{k} in {v}"))
}

/// The fit within `tol` of the truth, inside its interval.
fn recovered(v: &Value, key: &str, truth: f64, tol: f64) {
    let got = param(v, key);
    assert!(
        (got - truth).abs() < tol,
        "{key}: fitted {got}, truth {truth}"
    );
    let i = &v["intervals"][key];
    let (lo, hi) = (i[0].as_f64().unwrap(), i[1].as_f64().unwrap());
    assert!(
        lo < got && got < hi,
        "{key}: {got} outside its interval {lo}..{hi}"
    );
}

/// The truth inside the reported interval too (noise alone in the data:
/// the values at which the residual rises 5 % lie several standard errors out).
fn inside(v: &Value, key: &str, truth: f64) {
    let i = &v["intervals"][key];
    let (lo, hi) = (i[0].as_f64().unwrap(), i[1].as_f64().unwrap());
    assert!(
        lo <= truth && truth <= hi,
        "{key}: truth {truth} outside the interval {lo}..{hi}"
    );
}

const KEYS: [&str; 4] = [
    "--param",
    "model.params.kv=0.8..1.2",
    "--param",
    "model.params.kw=0.5..1.1",
];

#[test]
fn recovers_known_parameters_from_a_noisy_recording() {
    let mut rng = ChaCha8Rng::seed_from_u64(4901);
    for _ in 0..2 {
        let dir = tempfile::tempdir().unwrap();
        let rows = random_plan(&mut rng);
        write_plan(dir.path(), &rows);
        let (kv, kw) = (rng.random_range(0.9..1.1), rng.random_range(0.6..0.95));
        write_recording(dir.path(), &rows, (kv, kw), 0.0, 0.005, &[], &mut rng);
        let sc = scenario(dir.path(), None);
        // One noisy sample at time 0 would place the whole recording: lay
        // it over the run by a least-squares fit instead.
        let mut args = vec![
            sc.to_str().unwrap(),
            "--against",
            "rec.csv",
            "--frame",
            "fit",
        ];
        args.extend(KEYS);
        let v = fit_json(dir.path(), &args, None);
        recovered(&v, "model.params.kv", kv, 0.01);
        recovered(&v, "model.params.kw", kw, 0.01);
        inside(&v, "model.params.kv", kv);
        inside(&v, "model.params.kw", kw);
        let (before, after) = (
            v["residual_before"].as_f64().unwrap(),
            v["residual_after"].as_f64().unwrap(),
        );
        // What is left is the noise: 5 mm on x and on y (7 mm together).
        assert!(after < 0.009 && before > 2.0 * after, "{before} -> {after}");
    }
}

#[test]
fn recovers_parameters_and_the_time_offset_of_a_recording_on_its_own_clock() {
    let mut rng = ChaCha8Rng::seed_from_u64(4902);
    let dir = tempfile::tempdir().unwrap();
    let rows = random_plan(&mut rng);
    write_plan(dir.path(), &rows);
    let (kv, kw) = (1.06, 0.78);
    // The recorder's clock reads 1000.0 s one second before the first command.
    write_recording(
        dir.path(),
        &rows,
        (kv, kw),
        1001.0 + 0.37,
        0.002,
        &[],
        &mut rng,
    );
    let sc = scenario(dir.path(), None);
    let mut args = vec![
        sc.to_str().unwrap(),
        "--against",
        "rec.csv",
        "--time-offset",
        "1000..1004",
    ];
    args.extend(KEYS);
    let v = fit_json(dir.path(), &args, None);
    recovered(&v, "time_offset", 1001.37, 0.02);
    recovered(&v, "model.params.kv", kv, 0.01);
    recovered(&v, "model.params.kw", kw, 0.01);
    assert!(v["toml"]
        .as_str()
        .unwrap()
        .contains("[compare]\nreference = \"rec.csv\"\ntime_offset = 1001.3"));
    // The same answer on one thread and on two.
    let one = fit_json(dir.path(), &args, Some(1));
    let two = fit_json(dir.path(), &args, Some(2));
    assert_eq!(one["params"], two["params"]);
    assert_eq!(one["residual_after"], two["residual_after"]);
}

#[test]
fn recovers_parameters_from_a_recording_with_gaps() {
    let mut rng = ChaCha8Rng::seed_from_u64(4903);
    let dir = tempfile::tempdir().unwrap();
    let rows = random_plan(&mut rng);
    write_plan(dir.path(), &rows);
    let (kv, kw) = (0.93, 0.7);
    let gaps = [(1.5, 3.2), (4.0, 4.6)];
    let inside = write_recording(dir.path(), &rows, (kv, kw), 0.0, 0.003, &gaps, &mut rng);
    let sc = scenario(dir.path(), None);
    let mut args = vec![sc.to_str().unwrap(), "--against", "rec.csv"];
    args.extend(KEYS);
    let v = fit_json(dir.path(), &args, None);
    recovered(&v, "model.params.kv", kv, 0.01);
    recovered(&v, "model.params.kw", kw, 0.01);
    // Only the recorded samples inside the run are compared.
    assert_eq!(v["after"]["samples"].as_u64().unwrap() as usize, inside);
}

/// A bag like a robot's: /cmd_vel, /odom, /pose and /tf (each tf message
/// with the wheel's transform beside the base's), written by rosbags.
const BAG_SCRIPT: &str = r#"
import math, sys
import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer
from rosbags.typesys import Stores, get_typestore
out, kv, kw = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
rows = [tuple(map(float, l.split(','))) for l in open(sys.argv[4]).read().split()[1:]]
S = get_typestore(Stores.ROS2_JAZZY); T = S.types
def v3(x=0.0, y=0.0, z=0.0): return T['geometry_msgs/msg/Vector3'](x=x, y=y, z=z)
def stamp(ns): return T['builtin_interfaces/msg/Time'](sec=ns // 10**9, nanosec=ns % 10**9)
def hdr(ns, f): return T['std_msgs/msg/Header'](stamp=stamp(ns), frame_id=f)
def quat(th): return T['geometry_msgs/msg/Quaternion'](x=0.0, y=0.0, z=math.sin(th/2), w=math.cos(th/2))
def pose(q): return T['geometry_msgs/msg/Pose'](position=T['geometry_msgs/msg/Point'](x=q[0], y=q[1], z=0.05), orientation=quat(q[2]))
def arc(q, v, w, tau):
    x, y, th = q
    if abs(w) < 1e-12: return (x + v*tau*math.cos(th), y + v*tau*math.sin(th), th)
    return (x + v/w*(math.sin(th + w*tau) - math.sin(th)), y - v/w*(math.cos(th + w*tau) - math.cos(th)), th + w*tau)
def truth(t):
    q = (0.0, 0.0, 0.0)
    for (t0, v, w), (t1, _, _) in zip(rows, rows[1:]):
        if t <= t0: break
        q = arc(q, kv*v, kw*w, min(t, t1) - t0)
    return q
T0 = 1_700_000_000 * 10**9 + 123_456_789
lead = 700_000_000  # the recorder starts 0.7 s before the first command
msgs = []
with Writer(out, version=9, storage_plugin=StoragePlugin.MCAP) as w:
    c = {n: w.add_connection(n, t, typestore=S) for n, t in [('/cmd_vel', 'geometry_msgs/msg/Twist'), ('/odom', 'nav_msgs/msg/Odometry'), ('/pose', 'geometry_msgs/msg/PoseStamped'), ('/tf', 'tf2_msgs/msg/TFMessage')]}
    for t, v, om in rows[:-1]:
        msgs.append((T0 + lead + int(t*1e9), '/cmd_vel', T['geometry_msgs/msg/Twist'](linear=v3(x=v), angular=v3(z=om))))
    for k in range(0, 151):
        t = k * 0.05 - 0.7
        ns = T0 + lead + int(round(t*1e9))
        q = truth(t)
        z = np.zeros(36)
        msgs.append((ns, '/odom', T['nav_msgs/msg/Odometry'](header=hdr(ns, 'odom'), child_frame_id='base_link', pose=T['geometry_msgs/msg/PoseWithCovariance'](pose=pose(q), covariance=z), twist=T['geometry_msgs/msg/TwistWithCovariance'](twist=T['geometry_msgs/msg/Twist'](linear=v3(), angular=v3()), covariance=z))))
        msgs.append((ns, '/pose', T['geometry_msgs/msg/PoseStamped'](header=hdr(ns, 'map'), pose=pose(q))))
        tf = lambda parent, child, x, y, th: T['geometry_msgs/msg/TransformStamped'](header=hdr(ns, parent), child_frame_id=child, transform=T['geometry_msgs/msg/Transform'](translation=v3(x, y, 0.0), rotation=quat(th)))
        msgs.append((ns, '/tf', T['tf2_msgs/msg/TFMessage'](transforms=[tf('base_link', 'left_wheel', 0.0, 0.13, 0.3*k), tf('odom', 'base_link', q[0], q[1], q[2])])))
    for ns, topic, m in sorted(msgs, key=lambda x: x[0]):
        w.write(c[topic], ns, bytes(S.serialize_cdr(m, c[topic].msgtype)))
"#;

#[test]
fn recovers_parameters_from_bag_topics_written_by_rosbags() {
    let mut rng = ChaCha8Rng::seed_from_u64(4904);
    let dir = tempfile::tempdir().unwrap();
    let rows = random_plan(&mut rng);
    write_plan(dir.path(), &rows);
    let (kv, kw) = (1.04, 0.82);
    std::fs::write(dir.path().join("make_bag.py"), BAG_SCRIPT).unwrap();
    let st = std::process::Command::new(python::python_with("rosbags"))
        .args([
            "make_bag.py",
            "robot_bag",
            &kv.to_string(),
            &kw.to_string(),
            "plan.csv",
        ])
        .current_dir(dir.path())
        .status()
        .unwrap();
    assert!(st.success());
    // The plan from the bag's /cmd_vel: the recording shares its clock.
    let text = std::fs::read_to_string(scenario(dir.path(), None))
        .unwrap()
        .replace(
            "path = \"plan.csv\"",
            "path = \"robot_bag\"\ntopic = \"/cmd_vel\"",
        );
    std::fs::write(dir.path().join("bag.toml"), text).unwrap();
    for reference in [
        "robot_bag:/odom",
        "robot_bag:/pose",
        "robot_bag/robot_bag.mcap:/tf:base_link",
    ] {
        let mut args = vec!["bag.toml", "--against", reference];
        args.extend(KEYS);
        let v = fit_json(dir.path(), &args, None);
        let r = v["residual_after"].as_f64().unwrap();
        assert!(r < 1e-3, "{reference}: residual {r}");
        recovered(&v, "model.params.kv", kv, 0.002);
        recovered(&v, "model.params.kw", kw, 0.002);
        assert!(
            v["alignment"]
                .as_str()
                .unwrap()
                .contains("on the bag's clock"),
            "{}",
            v["alignment"]
        );
    }
    // `[compare]` in `run`: the recording as the third run, with its metrics.
    let text = std::fs::read_to_string(dir.path().join("bag.toml"))
        .unwrap()
        .replace("kv = 1.0", &format!("kv = {kv}"))
        .replace("kw = 1.0", &format!("kw = {kw}"))
        + "[compare]\nreference = \"robot_bag:/tf:base_link\"\n";
    std::fs::write(dir.path().join("bag.toml"), text).unwrap();
    let o = run_file(&dir.path().join("bag.toml"), Some(&dir.path().join("logs")));
    let m = |k: &str| o.metric(k).unwrap_or_else(|| panic!("{k}"));
    // The twin with the true values follows the recording (RK4 at 10 ms
    // against exact arcs, 20 Hz samples).
    assert!(
        m("real_ideal_position_max") < 1e-3,
        "{}",
        m("real_ideal_position_max")
    );
    assert!(m("real_ideal_heading_deg_max") < 0.05);
    assert!(m("real_sim_position_rms") > 0.0 && m("real_goal_position") >= 0.0);
    let series = std::fs::read_to_string(dir.path().join("logs/synthetic/series.json")).unwrap();
    assert!(series.contains("\"path_real\""));
}

#[test]
fn the_skid_steer_twin_passes_its_arc_and_a_plan_it_was_not_fitted_on() {
    use anholonomy::verdict::Verdict;
    let ex = root().join("examples/skid_steer");
    for f in ["skid_steer_declared.toml", "skid_steer_slalom.toml"] {
        let o = run_file(&ex.join(f), None);
        assert_eq!(o.verdict, Verdict::Pass, "{f}: {:?}", o.failures);
        // With eta = 1, the plain unicycle, both fail.
        let text = std::fs::read_to_string(ex.join(f)).unwrap();
        let dir = tempfile::tempdir().unwrap();
        for n in ["skid_steer.urdf", "arc.csv", "slalom.csv"] {
            std::fs::copy(ex.join(n), dir.path().join(n)).unwrap();
        }
        let unicycle = text.replace("eta = 0.722 ", "eta = 1.0 ");
        assert_ne!(unicycle, text);
        std::fs::write(dir.path().join(f), unicycle).unwrap();
        let o = run_file(&dir.path().join(f), None);
        assert!(o.metric("sim_goal_position").unwrap() > 0.3, "{f}");
    }
    // The fit finds eta again from the unicycle's value.
    let v = fit_json(
        &ex,
        &[
            "skid_steer_declared.toml",
            "--param",
            "model.params.eta=0.5..1",
        ],
        None,
    );
    recovered(&v, "model.params.eta", 0.722, 0.003);
}

#[test]
fn the_mujoco_recording_fits_friction_and_wheel_radius() {
    let dir = root().join("examples/fit_mujoco");
    let v = fit_json(
        &dir,
        &[
            "diff_drive_mujoco.toml",
            "--param",
            "sim.friction=0.1..1.2",
            "--param",
            "sim.perturb.wheel_radius_scale=0.9..1.1",
        ],
        None,
    );
    // MuJoCo's tyres are 4 % larger than the URDF's.
    let s = param(&v, "sim.perturb.wheel_radius_scale");
    assert!((s - 1.04).abs() < 0.005, "wheel radius scale {s}");
    let f = param(&v, "sim.friction");
    assert!((0.45..0.65).contains(&f), "friction {f}");
    let (before, after) = (
        v["residual_before"].as_f64().unwrap(),
        v["residual_after"].as_f64().unwrap(),
    );
    assert!(before > 0.05 && after < 0.005, "{before} -> {after}");
    assert_eq!(v["compared"], "the physics run with the recording");
}
