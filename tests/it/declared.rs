//! Kinematic models declared in the scenario (`[model] kind = "declared"`):
//! the declared unicycle is the built-in one, the trailer's ideal run is
//! its ODE (checked by another integrator), its physics follows on a gentle
//! plan, sweeps vary its parameters, and bad declarations are refused with
//! the key that is wrong.

use crate::common::*;
use anholonomy::runner::{run_detailed, RunOptions};
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};

fn example(rel: &str) -> PathBuf {
    root().join("examples").join(rel)
}

fn quiet() -> RunOptions {
    RunOptions {
        progress: Default::default(),
        ..RunOptions::default()
    }
}

/// A scenario text with its relative paths made absolute (to run it from a
/// temporary directory).
fn absolute(text: &str, dir: &Path) -> String {
    let mut out = String::new();
    for line in text.lines() {
        let l = match line.split_once(" = \"") {
            Some((k, v)) if ["urdf", "path"].contains(&k.trim()) => {
                format!("{k} = \"{}/{v}", dir.display())
            }
            _ => line.to_string(),
        };
        out.push_str(&l);
        out.push('\n');
    }
    out
}

/// Random ramped commands (t, v, ω) on the 0.25 s grid, seeded.
fn random_plan(seed: u64, legs: usize) -> String {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut csv = String::from("t,v,omega\n0,0,0\n");
    let mut t = 0.0;
    for _ in 0..legs {
        let (v, w) = (rng.random_range(-0.25..0.3), rng.random_range(-1.0..1.0));
        let hold = 0.25 * rng.random_range(2..10) as f64;
        csv += &format!("{},{v},{w}\n{},{v},{w}\n", t + 0.5, t + 0.5 + hold);
        t += 0.5 + hold;
    }
    csv += &format!("{},0,0\n", t + 0.5);
    csv
}

#[test]
fn the_declared_diff_drive_is_the_built_in_one() {
    let ex = example("declared_diff_drive");
    let text = absolute(
        &std::fs::read_to_string(ex.join("declared_diff_drive.toml")).unwrap(),
        &ex,
    );
    // The built-in model on the same URDF and plan: the [model] table's
    // declaration dropped.
    let a = text.find("states = ").unwrap();
    let b = text.find("[planner]").unwrap();
    let builtin = format!("{}\n{}", &text[..a], &text[b..])
        .replace("kind = \"declared\"", "kind = \"diff_drive\"");
    let dir = tempfile::tempdir().unwrap();
    for (seed, plan) in [(None, None), (Some(7u64), Some(random_plan(7, 5)))] {
        let mut texts = [text.clone(), builtin.clone()];
        if let Some(p) = &plan {
            let f = dir.path().join(format!("plan{}.csv", seed.unwrap()));
            std::fs::write(&f, p).unwrap();
            for t in &mut texts {
                let from = format!("{}/s_curve.csv", ex.display());
                *t = t.replace(&from, &f.display().to_string());
            }
        }
        let runs: Vec<_> = texts
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let f = dir.path().join(format!("m{i}.toml"));
                std::fs::write(&f, t).unwrap();
                run_detailed(&prepared(&f), &quiet()).unwrap()
            })
            .collect();
        let (d, b) = (&runs[0], &runs[1]);
        let ideal = (d.ideal.last() - b.ideal.last()).amax();
        assert!(
            ideal <= 1e-12,
            "seed {seed:?}: ideal end states differ by {ideal}"
        );
        let sim = (d.sim.traj.last() - b.sim.traj.last()).amax();
        assert!(
            sim <= 1e-6,
            "seed {seed:?}: simulated end states differ by {sim}"
        );
        assert_eq!(d.sim.traj.q.len(), b.sim.traj.q.len());
    }
}

/// The trailer's equations, integrated by Dormand–Prince 5(4) with an
/// adaptive step (not the harness's fixed-step RK4), the input the linear
/// interpolation of the plan's rows, each row a step boundary.
fn trailer_reference(rows: &[(f64, f64, f64)], d1: f64, q0: [f64; 4]) -> [f64; 4] {
    let u_at = |t: f64| -> (f64, f64) {
        let k = rows
            .iter()
            .rposition(|r| r.0 <= t)
            .unwrap_or(0)
            .min(rows.len() - 2);
        let (a, b) = (rows[k], rows[k + 1]);
        let s = ((t - a.0) / (b.0 - a.0)).clamp(0.0, 1.0);
        (a.1 + s * (b.1 - a.1), a.2 + s * (b.2 - a.2))
    };
    let f = |t: f64, q: &[f64; 4]| -> [f64; 4] {
        let (v, w) = u_at(t);
        [
            v * q[2].cos(),
            v * q[2].sin(),
            w,
            v / d1 * (q[2] - q[3]).sin(),
        ]
    };
    // Each row a step boundary: the input's kinks fall between steps.
    let mut q = q0.to_vec();
    for win in rows.windows(2) {
        let g = |t: f64, y: &[f64]| f(t, &[y[0], y[1], y[2], y[3]]).to_vec();
        q = crate::common::dopri::dopri(&g, q, win[0].0, win[1].0);
    }
    [q[0], q[1], q[2], q[3]]
}

#[test]
fn the_trailers_ideal_run_is_its_ode_by_another_integrator() {
    let ex = example("trailer");
    let dir = tempfile::tempdir().unwrap();
    for seed in [3u64, 11, 29] {
        let csv = random_plan(seed, 6);
        let rows: Vec<(f64, f64, f64)> = csv
            .lines()
            .skip(1)
            .map(|l| {
                let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
                (v[0], v[1], v[2])
            })
            .collect();
        std::fs::write(dir.path().join("p.csv"), &csv).unwrap();
        let text = absolute(
            &std::fs::read_to_string(ex.join("trailer_forward.toml")).unwrap(),
            &ex,
        )
        .replace(
            &format!("{}/s_curve.csv", ex.display()),
            &dir.path().join("p.csv").display().to_string(),
        )
        .replace(
            "start = [0.0, 0.0, 0.0, 0.0]",
            "start = [0.3, -0.2, 10.0, -5.0]",
        );
        // Only the ideal run is asked here.
        let text = text[..text.find("[thresholds]").unwrap()].to_string();
        let f = dir.path().join("t.toml");
        std::fs::write(&f, text).unwrap();
        let run = run_detailed(&prepared(&f), &quiet()).unwrap();
        let got = run.ideal.last();
        let want = trailer_reference(
            &rows,
            0.6,
            [0.3, -0.2, 10f64.to_radians(), -5f64.to_radians()],
        );
        for n in 0..4 {
            assert!(
                (got[n] - want[n]).abs() <= 1e-8,
                "seed {seed}, state {n}: {} vs {}",
                got[n],
                want[n]
            );
        }
    }
}

#[test]
fn the_trailers_hitch_follows_in_physics_on_a_gentle_plan() {
    let o = run_file(&example("trailer/trailer_forward.toml"), None);
    assert!(o.passed, "{:?}", o.failures);
    // The documented bound (examples/trailer/trailer_forward.toml).
    assert!(o.metric("tracking_theta1_deg_max").unwrap() <= 0.5);
    // Closed loop, backing: the physics run parks within 1.5 cm.
    if std::process::Command::new("python3")
        .arg("-c")
        .arg("")
        .status()
        .is_ok_and(|s| s.success())
    {
        let o = run_file(&example("trailer/trailer_law.toml"), None);
        assert!(o.passed, "{:?}", o.failures);
    }
}

#[test]
fn a_sweep_varies_the_declared_parameters() {
    let ex = example("trailer");
    let dir = tempfile::tempdir().unwrap();
    let text = absolute(
        &std::fs::read_to_string(ex.join("trailer_forward.toml")).unwrap(),
        &ex,
    )
        + "\n[sweep]\ncount = 3\nsuccess_metric = \"ideal_goal_position\"\nsuccess_max = 100.0\n\
           [sweep.vary]\n\"model.params.d1\" = { grid = [0.4, 0.6, 0.9] }\n";
    std::fs::write(dir.path().join("sw.toml"), text).unwrap();
    let out = cli(dir.path(), &["run", "sw.toml", "--logs", "logs", "--quiet"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lines = std::fs::read_to_string(dir.path().join("logs/sw/variants.jsonl")).unwrap();
    let mut seen = Vec::new();
    for l in lines.lines().filter(|l| l.contains("\"params\"")) {
        let v: serde_json::Value = serde_json::from_str(l).unwrap();
        let d1 = v["params"]["model.params.d1"]
            .as_f64()
            .unwrap_or_else(|| panic!("{v}"));
        let th1 = v["metrics"]["ideal_goal_theta1_deg"].as_f64().unwrap();
        seen.push((d1, th1));
    }
    seen.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_eq!(
        seen.iter().map(|s| s.0).collect::<Vec<_>>(),
        [0.4, 0.6, 0.9]
    );
    // A longer tongue follows the tractor's turn more slowly: the hitch
    // error at the end of the S curve differs per variant (d1 = 0.6 is the goal's).
    assert!(seen[1].1 < 0.01, "{seen:?}");
    assert!(seen[0].1 > 0.1 && seen[2].1 > 0.1, "{seen:?}");
}

/// The trailer scenario with one edit, run in a fresh directory: exit 2,
/// one line naming the file, the line and `key`, nothing written.
fn refused(from: &str, to: &str, key: &str, at: &str) {
    let ex = example("trailer");
    let text = absolute(
        &std::fs::read_to_string(ex.join("trailer_forward.toml")).unwrap(),
        &ex,
    );
    assert!(text.contains(from), "{from}");
    let text = text.replacen(from, to, 1);
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.toml"), &text).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "{from} -> {to}: {stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    let line = text.lines().position(|l| l.starts_with(at)).map(|i| i + 1);
    let want = format!("error: bad.toml:{}: key `{key}`", line.unwrap_or(0));
    assert!(
        stderr.starts_with(&want),
        "{from} -> {to}: `{want}` not at the start of {stderr}"
    );
    assert!(files_below(&dir.path().join("logs")).is_empty());
}

#[test]
fn bad_declarations_name_file_line_and_key() {
    // An expression that does not parse, an unknown name.
    let k = "model.kinematics";
    refused(
        "theta0 = \"omega\"",
        "theta0 = \"omega * (\"",
        "model.kinematics.theta0",
        "theta0 = \"omega",
    );
    refused(
        "theta0 = \"omega\"",
        "theta0 = \"omegaa\"",
        "model.kinematics.theta0",
        "theta0 = \"omega",
    );
    // A state without an equation, an equation without a state.
    refused("theta0 = \"omega\"\n", "", k, "[model.kinematics]");
    refused(
        "theta0 = \"omega\"",
        "theta0 = \"omega\"\ntheta2 = \"0\"",
        "model.kinematics.theta2",
        "theta2",
    );
    // A read-back link, a driven joint missing from the URDF; a drive on a fixed joint.
    refused(
        "theta1 = \"trailer_link.yaw\"",
        "theta1 = \"trailer_lnk.yaw\"",
        "model.read.theta1",
        "theta1 = \"trailer_lnk",
    );
    refused(
        "left_wheel_joint = \"(v",
        "left_wheel_jnt = \"(v",
        "model.drive.left_wheel_jnt",
        "left_wheel_jnt",
    );
    refused(
        "left_wheel_joint = \"(v",
        "caster_joint = \"0\"\nleft_wheel_joint = \"(v",
        "model.drive.caster_joint",
        "caster_joint",
    );
    // NaN and inf parameters.
    refused("d1 = 0.6", "d1 = nan", "model.params.d1", "d1 = nan");
    refused("d1 = 0.6", "d1 = inf", "model.params.d1", "d1 = inf");
    // An angle that is not a state.
    refused(
        "angles = [\"theta0\", \"theta1\"]",
        "angles = [\"theta0\", \"phi\"]",
        "model.angles",
        "angles = ",
    );
}

#[test]
fn a_non_finite_equation_stops_the_run_naming_the_state_and_time() {
    let ex = example("trailer");
    let dir = tempfile::tempdir().unwrap();
    let good = absolute(
        &std::fs::read_to_string(ex.join("trailer_forward.toml")).unwrap(),
        &ex,
    );
    // theta1' = 1 / (t-dependent zero): the heading crosses zero at once.
    let bad = good
        .replace(
            "theta1 = \"v / d1 * sin(theta0 - theta1)\"",
            "theta1 = \"v / d1 * sin(theta0 - theta1) / theta0\"",
        )
        .replace("description = ", "name = \"zz_bad\"\ndescription = ");
    let set = dir.path().join("set");
    std::fs::create_dir(&set).unwrap();
    std::fs::write(set.join("a.toml"), &good).unwrap();
    std::fs::write(set.join("b.toml"), &bad).unwrap();
    let out = cli(dir.path(), &["run", "set", "--logs", "logs", "--quiet"]);
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("ideal run: state `theta1` became NaN at t = 0 s")
            || stderr.contains("ideal run: state `theta1` became"),
        "{stderr}"
    );
    assert!(stderr.contains("at t = "), "{stderr}");
    // The good scenario's logs are there and whole.
    assert!(dir.path().join("logs/a/summary.json").is_file(), "{stderr}");
    assert!(!stderr.contains("panicked"));
}

/// The trailer pulled through its S curve with wheels of `scale` × their
/// radius (`[model] wheels` when given): where the physics run ends.
fn trailer_on_worn_wheels(scale: f64, wheels: &str) -> anholonomy::runner::RunOutcome {
    let ex = example("trailer");
    let dir = tempfile::tempdir().unwrap();
    let text = absolute(
        &std::fs::read_to_string(ex.join("trailer_forward.toml")).unwrap(),
        &ex,
    )
    .replacen("frictionless = ", &format!("{wheels}\nfrictionless = "), 1)
        + &format!("\n[sim.perturb]\nwheel_radius_scale = {scale}\n");
    let path = dir.path().join("worn.toml");
    std::fs::write(&path, text).unwrap();
    run_file(&path, None)
}

#[test]
fn worn_wheels_keep_a_declared_model_on_the_ground() {
    // 1 % smaller or larger drive wheels: 1 % less or more travel on a
    // 1.9 m curve, about 2 cm; wheels in the air would leave the robot
    // standing (1.6 m short of its end).
    let nominal = trailer_on_worn_wheels(1.0, "");
    let base = nominal.metric("tracking_position_final").unwrap();
    for s in [0.99, 1.01] {
        let o = trailer_on_worn_wheels(s, "");
        let d = o.metric("tracking_position_final").unwrap();
        assert!(d < 0.03 && d > base, "scale {s}: {d} m (nominal {base} m)");
    }
    // The drive wheels named: the same robot.
    let named = trailer_on_worn_wheels(
        0.99,
        "wheels = [\"left_wheel_joint\", \"right_wheel_joint\"]",
    );
    let found = trailer_on_worn_wheels(0.99, "");
    assert_eq!(named.metrics, found.metrics);
}

#[test]
fn a_wheel_must_be_a_driven_joint() {
    for wheel in ["hitch", "trailer_left_wheel_joint", "no_such_joint"] {
        refused(
            "frictionless = ",
            &format!("wheels = [\"{wheel}\"]\nfrictionless = "),
            "model.wheels",
            "wheels = ",
        );
    }
}

#[test]
fn declared_models_read_link_and_joint_velocities() {
    // The declared diff drive with three more states, each integrating
    // nothing (q' = 0) and read back as a velocity: the tracking error of
    // each is then the largest velocity the physics run read.
    let ex = example("declared_diff_drive");
    let dir = tempfile::tempdir().unwrap();
    let text = absolute(
        &std::fs::read_to_string(ex.join("declared_diff_drive.toml")).unwrap(),
        &ex,
    )
    .replace(
        "start = [0.0, 0.0, 0.0]",
        "start = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]",
    )
    .replace(
        "goal = [1.43388, 1.11276, 0.0]",
        "goal = [1.43388, 1.11276, 0.0, 0.0, 0.0, 0.0, 0.0]",
    )
    .replace(
        "states = [\"x\", \"y\", \"theta\"]",
        "states = [\"x\", \"y\", \"theta\", \"fwd\", \"side\", \"yaw_rate\", \"wheel\"]",
    )
    .replace(
        "theta = \"omega\"\n",
        "theta = \"omega\"\nfwd = \"0\"\nside = \"0\"\nyaw_rate = \"0\"\nwheel = \"0\"\n",
    )
    .replace(
        "theta = \"base_link.yaw\"\n",
        "theta = \"base_link.yaw\"\nfwd = \"base_link.vx\"\nside = \"base_link.vy\"\n\
         yaw_rate = \"base_link.wz\"\nwheel = \"right_wheel_joint.velocity\"\n",
    );
    let path = dir.path().join("v.toml");
    std::fs::write(&path, &text).unwrap();
    let o = run_file(&path, None);
    let m = |k: &str| {
        o.metric(k)
            .unwrap_or_else(|| panic!("{k}: {:?}", o.metrics))
    };
    // The plan (s_curve.csv): 0.25 m/s forward, turns at ±0.8 rad/s; the
    // outer wheel at (0.25 + 0.8 · 0.13) / 0.05 = 7.08 rad/s. Rolling: no
    // sideways speed.
    assert!(
        (m("tracking_fwd_max") - 0.25).abs() < 0.02,
        "{}",
        m("tracking_fwd_max")
    );
    assert!(m("tracking_side_max") < 0.01, "{}", m("tracking_side_max"));
    assert!(
        (m("tracking_yaw_rate_max") - 0.8).abs() < 0.06,
        "{}",
        m("tracking_yaw_rate_max")
    );
    assert!(
        (m("tracking_wheel_max") - 7.08).abs() < 0.3,
        "{}",
        m("tracking_wheel_max")
    );
    // The shipped example: wheel speeds with a first-order lag, read back
    // as joint velocities, pass their gates.
    let o = run_file(&example("declared_diff_drive/speed_lag.toml"), None);
    assert!(o.passed, "{:?}", o.failures);
}
