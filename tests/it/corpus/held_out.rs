//! Held-out fault cases of issue 37 that are bad input: perturbations
//! longer than the run or than the step budget allows (a latency of 1e300 s
//! panicked, one of 1e6 s aborted allocating 4 GB), a horizon or a plan
//! file's last `t` of 1e300 s (blamed on `goal`), a goal the sphere planner
//! searched for ever, and values of ±1e300 whose messages printed 300
//! digits. Each is refused before anything runs, naming its key or row.

use super::*;

/// `text` with `[sim.perturb]` holding `body`, before `[sim]`.
fn perturbed(text: &str, body: &str) -> String {
    edit(
        text,
        "[sim]\n",
        &format!("[sim.perturb]\n{body}\n\n[sim]\n"),
    )
}

pub fn cases(c: &mut Corpus) {
    let d = disk();
    for (name, body, key) in [
        (
            "perturb: command latency 1e300 s",
            "command_latency = 1e300",
            "sim.perturb.command_latency",
        ),
        (
            "perturb: command latency 1e6 s",
            "command_latency = 1e6",
            "sim.perturb.command_latency",
        ),
        (
            "perturb: command latency longer than the plan",
            "command_latency = 10.0",
            "sim.perturb.command_latency",
        ),
        (
            "perturb: actuator lag 1e300 s",
            "actuator_tau = 1e300",
            "sim.perturb.actuator_tau",
        ),
        (
            "perturb: actuator lag 1e6 s",
            "actuator_tau = 1e6",
            "sim.perturb.actuator_tau",
        ),
        (
            "perturb: negative latency of -1e300 s",
            "command_latency = -1e300",
            "sim.perturb.command_latency",
        ),
    ] {
        let at = body.split(" =").next().unwrap();
        c.sc(name, perturbed(&d, body), Some(at), Some(key));
    }
    // A latency within the plan whose extra steps break the step budget:
    // the disk at dt = 2.5 µs fits its 4.4 s plan in 1.75e6 steps of the
    // 2e6; 2 s more do not, and the latency is named, not dt.
    let fine = edit(&d, "dt = 0.001", "dt = 2.5e-6");
    c.sc(
        "perturb: latency over the step budget",
        perturbed(&fine, "command_latency = 2.0"),
        Some("command_latency = 2.0"),
        Some("sim.perturb.command_latency"),
    );

    // A feedback law's state latency and a gated latency beyond its horizon.
    let rover = shipped("rover_behind.toml");
    for (name, body, key) in [
        (
            "perturb: state latency 1e300 s",
            "state_latency = 1e300",
            "sim.perturb.state_latency",
        ),
        (
            "perturb: state latency 1e6 s",
            "state_latency = 1e6",
            "sim.perturb.state_latency",
        ),
    ] {
        let at = body.split(" =").next().unwrap();
        c.sc(name, perturbed(&rover, body), Some(at), Some(key));
    }
    c.sc(
        "margins: latency gate longer than the horizon",
        edit(
            &rover,
            "[sim]\n",
            "[margins]\ncommand_latency = 1e300\n\n[sim]\n",
        ),
        Some("command_latency = 1e300"),
        Some("margins.command_latency"),
    );

    // A sweep drawing latencies longer than the horizon: refused up front
    // (variants 1..n failed one by one at run time).
    let sweep = edit(&shipped("rover_sweep.toml"), "count = 100", "count = 4")
        + "\n[sweep.vary]\n\"sim.perturb.command_latency\" = { uniform = [0.0, 1000.0] }\n";
    c.sc(
        "sweep: latencies beyond the horizon",
        sweep,
        Some("\"sim.perturb.command_latency\" = "),
        Some("sweep.vary.\"sim.perturb.command_latency\""),
    );

    // Durations of 1e300 s: the key that set them, not the goal.
    let law = "command = [\"sh\", \"law.sh\"]\nperiod = 0.02\nhorizon = 1e300";
    c.sc(
        "external horizon 1e300",
        edit(
            &d,
            "kind = \"stokes_disk\"",
            &format!("kind = \"external\"\n{law}"),
        ),
        Some("horizon = 1e300"),
        Some("planner.horizon"),
    );
    c.raw(Case {
        name: "plan csv last t 1e300".into(),
        files: vec![
            (
                "case.toml".into(),
                edit(
                    &d,
                    "kind = \"stokes_disk\"",
                    "kind = \"file\"\npath = \"p.csv\"",
                )
                .into_bytes(),
            ),
            (
                "p.csv".into(),
                b"t,theta_rate,alpha_rate\n0,0.1,0.1\n1e300,0.1,0.1\n".to_vec(),
            ),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "p.csv".into(),
            line: Some(3),
            key: Some("column `t`: 1e300 s is past the longest plan".into()),
        }],
    });

    // The sphere's geometric planner searched candidate turns up to the
    // distance in radii: a start 1e300 m away never ended.
    let sphere = shipped("sphere_geometric_paper.toml");
    c.sc(
        "sphere geometric start 1e300 m away",
        edit(&sphere, "start = [5.0, 5.0", "start = [1e300, 5.0"),
        Some("goal = ["),
        Some("goal"),
    );

    // ±1e300 where a range is checked: one line, the number as `1e300`
    // (the corpus checks no number is printed in 20 digits or more).
    c.sc(
        "threshold -1e300",
        format!("{d}\n[thresholds]\nsim_goal_position = -1e300\n"),
        Some("sim_goal_position = -1e300"),
        Some("thresholds.sim_goal_position"),
    );
    c.sc(
        "sim.dt 1e300",
        edit(&d, "dt = 0.001", "dt = 1e300"),
        Some("dt = 1e300"),
        Some("sim.dt"),
    );
    c.sc(
        "solver iterations 1e300 (a float for an integer)",
        edit(&d, "dt = 0.001", "dt = 0.001\nsolver_iterations = 1e300"),
        Some("solver_iterations = 1e300"),
        Some("sim.solver_iterations"),
    );
    c.sc(
        "margins resolution 1e300",
        edit(
            &rover,
            "[sim]\n",
            "[margins]\nresolution = 1e300\n\n[sim]\n",
        ),
        Some("resolution = 1e300"),
        Some("margins.resolution"),
    );
    c.sc(
        "rover speed -1e300",
        edit(&rover, "speed = 0.4", "speed = -1e300"),
        Some("speed = -1e300"),
        Some("planner.speed"),
    );
}
