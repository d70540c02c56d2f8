//! Perturbations of the physics replay (`[sim.perturb]`) and robustness
//! margins (`anholonomy margin`, `[margins]` gates in `check`).

use crate::common::*;
use anholonomy::engine::perturb::Perturbation;
use anholonomy::engine::{replay, ReplayOptions};
use anholonomy::integrate::step_count;
use anholonomy::model::{Input, State};
use anholonomy::plan::{ControlLaw, Plan};
use anholonomy::runner::{run, RunOptions, RunOutcome};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

/// A shipped scenario's text with its URDF path made absolute.
fn shipped(file: &str) -> String {
    std::fs::read_to_string(scenario(file)).unwrap().replace(
        "../models/",
        &format!("{}/", root().join("models").display()),
    )
}

/// `text` with `body` appended as the `[sim.perturb]` table (after `[sim]`).
fn with_perturb(text: &str, body: &str) -> String {
    text.replacen("[sim]\n", &format!("[sim.perturb]\n{body}\n[sim]\n"), 1)
}

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn run_logged(path: &Path, logs: &Path) -> RunOutcome {
    let opts = RunOptions {
        log_root: Some(logs.to_path_buf()),
        progress: Default::default(),
        pose_rate: 0.0,
        keep: Default::default(),
        cancel: Default::default(),
        batch: true,
    };
    run(&prepared(path), &opts).unwrap()
}

fn bits(o: &RunOutcome) -> Vec<(String, u64)> {
    o.metrics
        .iter()
        .map(|(k, v)| (k.clone(), v.to_bits()))
        .collect()
}

/// Every `/sim/channels` message of a run.mcap: (t, name → value).
fn channels(mcap_path: &Path) -> Vec<(f64, BTreeMap<String, f64>)> {
    let bytes = std::fs::read(mcap_path).unwrap();
    let mut out = Vec::new();
    for msg in mcap::MessageStream::new(&bytes).unwrap() {
        let msg = msg.unwrap();
        if msg.channel.topic != "/sim/channels" {
            continue;
        }
        let v: serde_json::Value = serde_json::from_slice(&msg.data).unwrap();
        let values = v["values"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(k, x)| (k.clone(), x.as_f64().unwrap_or(f64::NAN)))
            .collect();
        out.push((v["t"].as_f64().unwrap(), values));
    }
    out
}

/// Every dimension written out at its nominal value (and a seed) gives the
/// run of the file without `[sim.perturb]`, bit for bit, and the same logs:
/// open loop (disk) and feedback (rover).
#[test]
fn zero_perturbation_equals_the_nominal_run_bit_for_bit() {
    let dir = tempfile::tempdir().unwrap();
    let zeros = "command_latency = 0.0\nactuator_tau = 0.0\ntorque_scale = 1.0\n\
                 state_noise = 0.0\nstate_latency = 0.0\nwheel_radius_scale = 1.0\n\
                 friction_scale = 1.0\nmass_scale = 1.0\nseed = 17\n";
    for file in ["disk_paper.toml", "rover_behind.toml"] {
        let text = shipped(file);
        let a = write(dir.path(), "a.toml", &format!("name = \"x\"\n{text}"));
        let b = write(
            dir.path(),
            "b.toml",
            &format!("name = \"x\"\n{}", with_perturb(&text, zeros)),
        );
        let (la, lb) = (dir.path().join("la"), dir.path().join("lb"));
        let (oa, ob) = (run_logged(&a, &la), run_logged(&b, &lb));
        assert_eq!(bits(&oa), bits(&ob), "{file}");
        assert_eq!(oa.steps, ob.steps);
        for f in ["run.mcap", "series.json"] {
            let (x, y) = (
                std::fs::read(la.join("x").join(f)).unwrap(),
                std::fs::read(lb.join("x").join(f)).unwrap(),
            );
            assert!(x == y, "{file}: {f} differs");
        }
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(lb.join("x/summary.json")).unwrap()).unwrap();
        assert_eq!(
            s["perturbation"],
            serde_json::json!({}),
            "nothing is active"
        );
    }
}

/// A latency of L (a multiple of dt) shifts the drive commands in the logs
/// by exactly L: what the drives received at t is what the controller
/// issued at t − L (zero before L), open loop and in closed loop; the run
/// lasts L longer; summary.json records the perturbation.
#[test]
fn latency_shifts_the_logged_drive_commands_by_exactly_l() {
    let dir = tempfile::tempdir().unwrap();
    for (file, n) in [("disk_paper.toml", 37usize), ("rover_behind.toml", 11)] {
        let text = shipped(file);
        let dt = if file.starts_with("disk") {
            0.001
        } else {
            0.002
        };
        let l = n as f64 * dt;
        let p = write(
            dir.path(),
            file,
            &with_perturb(&text, &format!("command_latency = {l:?}\n")),
        );
        let logs = dir.path().join("logs");
        let o = run_logged(&p, &logs);
        let name = file.trim_end_matches(".toml");
        let rows = channels(&logs.join(name).join("run.mcap"));
        let issued: Vec<&String> = rows[0]
            .1
            .keys()
            .filter(|k| k.starts_with("drive_issued_"))
            .collect();
        assert_eq!(issued.len(), 2, "{:?}", rows[0].1.keys());
        let mut nonzero = 0;
        // The last sample repeats the command before it (as `/plan/command` does).
        for (k, (t, v)) in rows[..rows.len() - 1].iter().enumerate() {
            for name in &issued {
                let got = v[&name.replace("issued", "received")];
                let want = if k >= n { rows[k - n].1[*name] } else { 0.0 };
                assert_eq!(got.to_bits(), want.to_bits(), "{file} t = {t} {name}");
                nonzero += usize::from(got != 0.0);
            }
            assert!((t - k as f64 * dt).abs() < 1e-9);
        }
        assert!(nonzero > 100, "{file}: the commands are not all zero");
        let s: serde_json::Value =
            serde_json::from_slice(&std::fs::read(logs.join(name).join("summary.json")).unwrap())
                .unwrap();
        assert_eq!(s["perturbation"]["command_latency"].as_f64(), Some(l));
        if file.starts_with("disk") {
            // Open loop: the plan plus settle, then L more.
            let plan = prepared(&p).planned.duration;
            assert_eq!(o.steps, step_count(plan, dt) + n);
        }
    }
}

/// The actuator lag end to end on the disk's wheel: a unit step of θ' with
/// τ = 0.1 s reaches the drive as the mean over each step of 1 − e^(−t/τ),
/// and the wheel turns by its integral t − τ(1 − e^(−t/τ)).
#[test]
fn actuator_lag_matches_its_closed_form_step_response() {
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "d.toml",
        &disk_scenario(&model("rolling_disk.urdf"), "", ""),
    );
    let prep = prepared(&p);
    let step = Plan {
        labels: vec!["step".into()],
        segments: Vec::new(),
        duration: 0.6,
        law: ControlLaw::OpenLoop(Arc::new(|_t| (Input::from_vec(vec![1.0, 0.0]), 0))),
        details: serde_json::Value::Null,
    };
    let (tau, dt) = (0.1, 0.001);
    let pert = Perturbation {
        actuator_tau: tau,
        ..Default::default()
    };
    let opts = ReplayOptions {
        dt,
        settle: 0.0,
        link_pose_every: None,
        perturbation: pert,
    };
    let mut sys = prep.physics().unwrap();
    let sim = replay(sys.as_mut(), &step, &opts, &mut ()).unwrap();
    assert_eq!(sim.received.len(), sim.traj.t.len());
    for k in 0..600 {
        let (t0, t1) = (k as f64 * dt, (k + 1) as f64 * dt);
        let mean = 1.0 - tau * ((-t0 / tau).exp() - (-t1 / tau).exp()) / dt;
        assert!((sim.received[k][0] - mean).abs() < 1e-12, "step {k}");
        assert_eq!(sim.received[k][1], 0.0);
        let theta: &State = &sim.traj.q[k + 1];
        let exact = t1 - tau * (1.0 - (-t1 / tau).exp());
        assert!(
            (theta[2] - exact).abs() < 2e-3,
            "t = {t1}: wheel at {} rad, lag's integral {exact}",
            theta[2]
        );
    }
    // Without the lag the wheel would be 0.1 rad ahead by the end: the check can fail.
    assert!(0.6 - (0.6 - tau * (1.0 - (-6.0f64).exp())) > 0.09);
}

/// State noise: the same seed gives the same run, another seed another run,
/// and the ideal run never sees it.
#[test]
fn state_noise_is_reproducible_per_seed_and_absent_from_the_ideal_run() {
    let dir = tempfile::tempdir().unwrap();
    let text = shipped("rover_behind.toml");
    let file = |seed: u64| {
        write(
            dir.path(),
            &format!("s{seed}.toml"),
            &with_perturb(&text, &format!("state_noise = 0.02\nseed = {seed}\n")),
        )
    };
    let nominal = run_file(&write(dir.path(), "n.toml", &text), None);
    let a = run_file(&file(1), None);
    let b = run_file(&file(1), None);
    let c = run_file(&file(2), None);
    assert_eq!(bits(&a), bits(&b));
    let sim = |o: &RunOutcome| o.metric("sim_goal_se2").unwrap();
    assert_ne!(sim(&a), sim(&c), "another seed, another run");
    assert_ne!(sim(&a), sim(&nominal), "the noise reaches the physics run");
    for o in [&a, &c] {
        for (k, v) in o.metrics.iter().filter(|(k, _)| k.starts_with("ideal_")) {
            assert_eq!(v.to_bits(), nominal.metric(k).unwrap().to_bits(), "{k}");
        }
    }
}

/// Noise on an open-loop plan, an unknown `--dimension`, a dimension that
/// applies to no scenario of the call: bad input, one line, exit 2.
#[test]
fn bad_margin_requests_are_refused_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "d.toml", &shipped("disk_paper.toml"));
    let cases: [(&[&str], &str); 8] = [
        (
            &["margin", "d.toml", "--dimension", "latency"],
            "error: --dimension: unknown dimension `latency`",
        ),
        // Negative values reach the range checks (clap took `-1` for a flag
        // and printed its usage, naming `-0` for `-0.1`).
        (
            &["margin", "d.toml", "--max-runs", "-1"],
            "error: --max-runs: -1: must be in 1..=100000",
        ),
        (
            &["margin", "d.toml", "--resolution", "-0.1"],
            "error: --resolution: -0.1: must be in (0, 1]",
        ),
        // Two output formats: refused, not one of them silently.
        (
            &["margin", "d.toml", "--markdown", "--json"],
            "error: the argument '--markdown' cannot be used with '--json'",
        ),
        (
            &["margin", "d.toml", "--dimensoin", "mass_scale"],
            "error: unexpected argument '--dimensoin' found (tip: a similar argument exists: '--dimension')",
        ),
        (
            &["margin", "d.toml", "--dimension", "state_noise"],
            "error: ",
        ),
        (
            &["margin", "d.toml", "--resolution", "0"],
            "error: --resolution: ",
        ),
        (&["margin", "d.toml", "--seeds", "0"], "error: --seeds: "),
    ];
    for (args, want) in cases {
        let o = cli(dir.path(), args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with(want), "{args:?}: {err}");
        assert!(o.stdout.is_empty() && !dir.path().join("logs").exists());
    }
    let o = cli(
        dir.path(),
        &["margin", "d.toml", "--dimension", "state_noise"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with("error: d.toml: option `--dimension state_noise`")
            && err.contains("open loop"),
        "{err}"
    );
}

/// Every dimension asked for has a row: one that does not apply reads n/a
/// with why and is not run; a scenario expected to fail has one row saying
/// so and is not run (no logs, no margins.json).
#[test]
fn inapplicable_dimensions_and_expected_failures_have_rows_not_runs() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "d.toml", &shipped("disk_paper.toml"));
    write(dir.path(), "s.toml", &shipped("space_robot_paper.toml"));
    write(dir.path(), "x.toml", &shipped("rover_open_loop.toml"));
    let o = cli(
        dir.path(),
        &[
            "margin",
            "d.toml",
            "s.toml",
            "x.toml",
            "--dimension",
            "wheel_radius_scale",
            "--markdown",
            "--logs",
            "L",
            "--quiet",
        ],
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: Vec<&str> = out.lines().skip(2).collect();
    assert_eq!(rows.len(), 3, "{out}");
    assert!(
        rows[0].starts_with("| d | wheel_radius_scale | 0.00"),
        "{out}"
    );
    assert!(
        rows[1].starts_with("| s | wheel_radius_scale | n/a |") && rows[1].contains("no wheels"),
        "{out}"
    );
    assert!(
        rows[2].starts_with("| x | – |") && rows[2].contains("expected to fail"),
        "{out}"
    );
    let m = margins_json(&dir.path().join("L/d/margins.json"));
    assert_eq!(m["dimensions"].as_array().unwrap().len(), 1);
    // Nothing ran for the other two.
    assert!(!dir.path().join("L/s").exists() && !dir.path().join("L/x").exists());
}

fn margins_json(path: &Path) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap();
    v.as_object_mut().unwrap().remove("wall_time_s");
    v
}

/// `margin` on the disk: a table row per dimension asked, margins.json with
/// every level, identical on one and two threads, and the HTML report plots it.
#[test]
fn margins_are_the_same_on_one_and_two_threads_and_reported() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "d.toml", &shipped("disk_paper.toml"));
    let mut out = Vec::new();
    for threads in ["1", "2"] {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
            .args([
                "margin",
                "d.toml",
                "--dimension",
                "friction_scale",
                "--dimension",
                "command_latency",
                "--logs",
                threads,
                "--report",
                "--quiet",
            ])
            .env("RAYON_NUM_THREADS", threads)
            .current_dir(dir.path())
            .output()
            .unwrap();
        let stdout = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(
            stdout.contains("friction_scale") && stdout.contains("command_latency"),
            "{stdout}"
        );
        out.push(margins_json(
            &dir.path().join(threads).join("d/margins.json"),
        ));
        let page = std::fs::read_to_string(dir.path().join(threads).join("d/report.html")).unwrap();
        assert!(page.contains("Robustness margins") && page.matches("<svg").count() >= 2);
    }
    assert_eq!(out[0], out[1]);
    let dims = out[0]["dimensions"].as_array().unwrap();
    assert_eq!(dims.len(), 2);
    for d in dims {
        assert_eq!(d["status"], "found", "{d}");
        let (m, hi) = (
            d["margin"].as_f64().unwrap(),
            d["first_failing"].as_f64().unwrap(),
        );
        assert!(
            m > 0.0 && hi > m && hi <= m * 1.05 * (1.0 + 1e-12),
            "{m} {hi}"
        );
        // The levels passed below the margin and failed at and above the first failure.
        for l in d["levels"].as_array().unwrap() {
            let x = l["level"].as_f64().unwrap();
            assert_eq!(l["passed"].as_bool().unwrap(), x <= m, "level {x}");
        }
    }
}

/// `[margins]` gates in `check` cost one run: the level at the gate, not a
/// search. The gate is reported as a metric (`margin_<dimension>`: the gate
/// when it holds, a lower bound of the margin) that goes into the baseline,
/// the table says "holds at 0.02 s", and margins.json holds the nominal
/// level and the one gate level. When the margin drops below the gate,
/// `check` exits 1 naming it, and against the baseline it regresses. The
/// rover's latency margin is about one control period: sampling every
/// 15 ms instead of 50 ms leaves less than the 20 ms the gate asks for.
#[test]
fn check_runs_a_gate_once_and_fails_when_a_gated_margin_drops() {
    let dir = tempfile::tempdir().unwrap();
    let text = shipped("rover_paper.toml");
    assert!(
        text.contains("[margins]\ncommand_latency = 0.02"),
        "rover_paper gates a margin in CI"
    );
    write(dir.path(), "rover_paper.toml", &text);
    let o = cli(
        dir.path(),
        &[
            "baseline",
            "rover_paper.toml",
            "--baseline",
            "b",
            "--logs",
            "L",
            "--quiet",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("PASS (command_latency holds at 0.02 s)"),
        "{stdout}"
    );
    let base: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.path().join("b/rover_paper.json")).unwrap())
            .unwrap();
    assert_eq!(
        base["metrics"]["margin_command_latency"].as_f64(),
        Some(0.02)
    );
    // One level at the gate, one run: no search.
    let m = margins_json(&dir.path().join("L/rover_paper/margins.json"));
    let d = &m["dimensions"][0];
    assert_eq!(d["status"], "holds", "{d}");
    assert_eq!(d["runs"], 1, "{d}");
    let levels: Vec<f64> = d["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| l["level"].as_f64().unwrap())
        .collect();
    assert_eq!(levels, [0.0, 0.02]);
    let faster = text.replace("horizon = 300.0\n", "horizon = 300.0\nperiod = 0.015\n");
    assert_ne!(faster, text);
    write(dir.path(), "rover_paper.toml", &faster);
    let o = cli(
        dir.path(),
        &[
            "check",
            "rover_paper.toml",
            "--baseline",
            "b",
            "--no-logs",
            "--quiet",
        ],
    );
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert_eq!(o.status.code(), Some(1), "{stdout}");
    assert!(
        stdout.contains(
            "FAIL: margin_command_latency < 0.02 s: breaks at command_latency = 0.02 s: envelope_outside_fraction = "
        ),
        "{stdout}"
    );
    let regressed = stdout
        .lines()
        .any(|l| l.contains("margin_command_latency") && l.contains("REGRESSED"));
    assert!(regressed, "{stdout}");
}

/// The early-stop rules are sound on real runs: over any prefix, a running
/// maximum is at most its final value, a running minimum at least, and a
/// first passage is either the final value or not reached yet (then the
/// final one is later or never). Gates of every family, four systems.
#[test]
fn early_stop_families_hold_on_prefixes_of_real_runs() {
    use anholonomy::margin::early::{family, prefix};
    use anholonomy::margin::level::Ctx;
    use anholonomy::metric::Family;
    use anholonomy::record::SimTrajectory;
    let mut checked = BTreeMap::<&str, usize>::new();
    for file in [
        "disk_paper.toml",
        "rover_behind.toml",
        "space_manipulator_s2.toml",
        "dilf_single_open.toml",
    ] {
        let prep = prepared(&scenario(file));
        let ctx = Ctx::new(&prep);
        let sc = &prep.scenario;
        let opts = ReplayOptions {
            link_pose_every: None,
            ..ReplayOptions::new(sc.sim.dt, sc.sim.settle)
        };
        let mut sys = prep.physics().unwrap();
        let sim = replay(sys.as_mut(), &prep.planned, &opts, &mut ()).unwrap();
        let full = ctx.metrics(&ctx.ideal, &sim);
        let value =
            |m: &[(String, f64)], k: &str| m.iter().find(|(n, _)| n == k).map(|(_, v)| *v).unwrap();
        let n = sim.traj.t.len();
        for cut in [n / 7, n / 3, 2 * n / 3, n - 2] {
            let part = SimTrajectory {
                traj: anholonomy::integrate::Trajectory {
                    t: sim.traj.t[..cut].to_vec(),
                    q: sim.traj.q[..cut].to_vec(),
                    u: sim.traj.u[..cut - 1].to_vec(),
                    label: sim.traj.label[..cut - 1].to_vec(),
                },
                channels: sim
                    .channels
                    .iter()
                    .map(|(k, v)| (k.clone(), v[..cut].to_vec()))
                    .collect(),
                steps: cut - 1,
                ..Default::default()
            };
            let pre = prefix(&part);
            let t = pre.traj.t[cut - 1];
            let m = ctx.metrics(&ctx.ideal_until(t), &pre);
            for (k, _) in full.iter().filter(|(k, _)| !k.starts_with("ideal_")) {
                let (p, f) = (value(&m, k), value(&full, k));
                let minimum = k.split('_').any(|t| t == "min" || t == "clearance");
                let fam = family(k, minimum);
                let ok = match fam {
                    Family::RunningMax => p <= f || p.is_nan() || f.is_nan(),
                    Family::RunningMin => p >= f || p.is_nan() || f.is_nan(),
                    Family::FirstPassage => (p.is_nan() && (f.is_nan() || f >= t)) || p == f,
                    Family::EndOnly => continue,
                };
                assert!(
                    ok,
                    "{file}: {k} ({fam:?}) is {p} over [0, {t}] s but {f} at the end"
                );
                *checked
                    .entry(match fam {
                        Family::RunningMax => "max",
                        Family::RunningMin => "min",
                        _ => "first",
                    })
                    .or_default() += 1;
            }
        }
    }
    // Every family was exercised.
    assert!(
        checked.len() == 3 && checked.values().all(|&c| c >= 4),
        "{checked:?}"
    );
}

/// A level stopped early breaks the same gate as the whole run would: the
/// disk with 30 % less torque breaks `tracking_theta_deg_max` long before
/// the plan ends, and the full run confirms it.
#[test]
fn a_run_stopped_early_breaks_what_the_whole_run_breaks() {
    use anholonomy::margin::level::{run as level_run, Ctx};
    let dir = tempfile::tempdir().unwrap();
    let text = shipped("disk_paper.toml");
    let weak = Perturbation {
        torque_scale: 0.1,
        ..Default::default()
    };
    let prep = prepared(&write(dir.path(), "d.toml", &text));
    let ctx = Ctx::new(&prep);
    let early = level_run(&ctx, &weak, None);
    let t = early.stopped_at_s.expect("stopped early");
    assert!(!early.passed && t < prep.planned.duration * 0.6, "{t}");
    let full = run_file(
        &write(
            dir.path(),
            "w.toml",
            &with_perturb(&text, "torque_scale = 0.1\n"),
        ),
        None,
    );
    assert!(!full.passed);
    for b in &early.broken {
        let v = full.metric(&b.metric).unwrap();
        assert!(
            v > b.bound && v >= b.value,
            "{}: {v} at the end, {} early",
            b.metric,
            b.value
        );
    }
    assert!(full.steps > early.steps);
}
