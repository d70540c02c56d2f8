//! Scenario files: [sim.perturb], [margins], [thresholds], [sweep] and
//! [sweep.vary]; the other systems' parameters and refusals.

use super::*;

pub fn cases(c: &mut Corpus) {
    let d = disk();

    // [sim.perturb]: ranges, unknown keys, dimensions that do not apply.
    let pert = |base: &str, body: &str| format!("{base}\n[sim.perturb]\n{body}\n");
    for (what, line, key) in [
        (
            "latency negative",
            "command_latency = -0.01",
            "sim.perturb.command_latency",
        ),
        (
            "tau negative",
            "actuator_tau = -0.5",
            "sim.perturb.actuator_tau",
        ),
        (
            "state latency negative",
            "state_latency = -1e-3",
            "sim.perturb.state_latency",
        ),
        (
            "noise negative",
            "state_noise = -0.1",
            "sim.perturb.state_noise",
        ),
        (
            "torque scale zero",
            "torque_scale = 0.0",
            "sim.perturb.torque_scale",
        ),
        (
            "mass scale negative",
            "mass_scale = -2.0",
            "sim.perturb.mass_scale",
        ),
        (
            "friction scale zero",
            "friction_scale = 0",
            "sim.perturb.friction_scale",
        ),
        (
            "wheel scale negative",
            "wheel_radius_scale = -0.9",
            "sim.perturb.wheel_radius_scale",
        ),
        (
            "perturb unknown key",
            "latency = 0.02",
            "sim.perturb.latency",
        ),
        ("perturb seed float", "seed = 1.5", "sim.perturb.seed"),
        (
            "noise on an open-loop plan",
            "state_noise = 0.01",
            "sim.perturb.state_noise",
        ),
        (
            "state latency on an open-loop plan",
            "state_latency = 0.01",
            "sim.perturb.state_latency",
        ),
    ] {
        c.sc(
            &format!("perturb {what}"),
            pert(&d, line),
            Some(line),
            Some(key),
        );
    }
    let ol = shipped("rover_open_loop.toml");
    c.sc(
        "perturb noise on the rover's open-loop replay",
        pert(&ol, "state_noise = 0.01"),
        Some("state_noise"),
        Some("sim.perturb.state_noise"),
    );
    let space = shipped("space_robot_paper.toml");
    for (what, line, key) in [
        (
            "wheel wear on the space robot",
            "wheel_radius_scale = 0.9",
            "sim.perturb.wheel_radius_scale",
        ),
        (
            "friction on the space robot",
            "friction_scale = 0.5",
            "sim.perturb.friction_scale",
        ),
    ] {
        c.sc(
            &format!("perturb {what}"),
            pert(&space, line),
            Some(line),
            Some(key),
        );
    }

    // [margins]: gates on dimensions that exist and apply, search settings.
    let mar = |base: &str, body: &str| format!("{base}\n[margins]\n{body}\n");
    for (what, line, key) in [
        ("unknown dimension", "latency = 0.02", "margins.latency"),
        (
            "negative margin",
            "command_latency = -0.02",
            "margins.command_latency",
        ),
        (
            "factor margin of 1",
            "friction_scale = 1.0",
            "margins.friction_scale",
        ),
        ("resolution zero", "resolution = 0.0", "margins.resolution"),
        ("seeds zero", "seeds = 0", "margins.seeds"),
        (
            "success rate above 1",
            "success_rate = 1.5",
            "margins.success_rate",
        ),
        (
            "noise on an open-loop plan",
            "state_noise = 0.01",
            "margins.state_noise",
        ),
    ] {
        c.sc(
            &format!("margins {what}"),
            mar(&d, line),
            Some(line),
            Some(key),
        );
    }
    c.sc(
        "margins on a sweep",
        mar(
            &shipped("rover_sweep.toml").replace("count = 100", "count = 4"),
            "command_latency = 0.01",
        ),
        Some("[margins]"),
        Some("margins"),
    );

    // [thresholds].
    let thr = |body: &str| format!("{d}\n[thresholds]\n{body}\n");
    c.sc(
        "unknown metric",
        thr("sim_goal_teleport = 1.0"),
        Some("teleport"),
        Some("thresholds.sim_goal_teleport"),
    );
    c.sc(
        "negative threshold",
        thr("sim_goal_position = -1.0"),
        Some("sim_goal_position"),
        Some("thresholds.sim_goal_position"),
    );
    c.sc(
        "threshold string",
        thr("sim_goal_position = \"small\""),
        Some("sim_goal_position"),
        Some("thresholds.sim_goal_position"),
    );
    c.sc(
        "threshold nan",
        thr("sim_goal_position = nan"),
        Some("sim_goal_position"),
        Some("thresholds.sim_goal_position"),
    );

    // [sweep] (rover and disk).
    let sw = shipped("rover_sweep.toml").replace("count = 100", "count = 4");
    for (what, from, to, key) in [
        ("sweep count zero", "count = 4", "count = 0", "sweep.count"),
        (
            "sweep count huge",
            "count = 4",
            "count = 100000000",
            "sweep.count",
        ),
        (
            "sweep count string",
            "count = 4",
            "count = \"many\"",
            "sweep.count",
        ),
        (
            "sweep friction reversed",
            "friction = [0.5, 1.0]",
            "friction = [1.0, 0.5]",
            "sweep.friction",
        ),
        (
            "sweep friction negative",
            "friction = [0.5, 1.0]",
            "friction = [-0.5, 1.0]",
            "sweep.friction[0]",
        ),
        (
            "sweep friction length",
            "friction = [0.5, 1.0]",
            "friction = [0.5]",
            "sweep.friction",
        ),
        (
            "sweep mass scale zero",
            "mass_scale = [0.7, 1.3]",
            "mass_scale = [0.0, 1.3]",
            "sweep.mass_scale[0]",
        ),
        (
            "sweep sigma rate negative",
            "sigma_rate = 0.5",
            "sigma_rate = -0.5",
            "sweep.sigma_rate",
        ),
        (
            "sweep success max nan",
            "success_max = 0.1",
            "success_max = nan",
            "sweep.success_max",
        ),
        (
            "sweep min rate above 1",
            "min_success_rate = 0.9",
            "min_success_rate = 2.0",
            "sweep.min_success_rate",
        ),
        (
            "sweep unknown metric",
            "success_metric = \"sim_goal_se2\"",
            "success_metric = \"sim_goal_xyz\"",
            "sweep.success_metric",
        ),
        (
            "sweep unknown time metric",
            "time_metric = \"sim_time_to_goal\"",
            "time_metric = \"t\"",
            "sweep.time_metric",
        ),
        (
            "sweep unknown key",
            "seed = 2002",
            "seed = 2002\nseeds = 1",
            "sweep.seeds",
        ),
    ] {
        c.sc(
            what,
            edit(&sw, from, to),
            Some(to.lines().last().unwrap()),
            Some(key),
        );
    }
    // [sweep.vary]: any numeric key by dotted path.
    for (what, entry, key) in [
        (
            "sweep vary unknown key",
            "\"sim.frictoin\" = { uniform = [0.5, 1.0] }",
            "sweep.vary.\"sim.frictoin\"",
        ),
        (
            "sweep vary unknown table",
            "\"plannerr.k1\" = { uniform = [0.5, 1.0] }",
            "sweep.vary.\"plannerr.k1\"",
        ),
        (
            "sweep vary not a number",
            "\"model.urdf\" = { values = [1.0] }",
            "sweep.vary.\"model.urdf\"",
        ),
        (
            "sweep vary element past the end",
            "\"start[4]\" = { uniform = [0.0, 1.0] }",
            "sweep.vary.\"start[4]\"",
        ),
        (
            "sweep vary not a path",
            "\"planner..k1\" = { uniform = [0.5, 1.0] }",
            "sweep.vary.\"planner..k1\"",
        ),
        (
            "sweep vary lo above hi",
            "\"planner.k1\" = { uniform = [1.0, 0.5] }",
            "sweep.vary.\"planner.k1\"",
        ),
        (
            "sweep vary negative sigma",
            "\"start[0]\" = { normal = [0.0, -0.1] }",
            "sweep.vary.\"start[0]\"",
        ),
        (
            "sweep vary empty list",
            "\"planner.k2\" = { values = [] }",
            "sweep.vary.\"planner.k2\"",
        ),
        (
            "sweep vary unknown distribution",
            "\"planner.k1\" = { gaussian = [1.0, 0.1] }",
            "sweep.vary.\"planner.k1\".gaussian",
        ),
        (
            "sweep vary value out of range",
            "\"sim.dt\" = { values = [0.004, 0.5] }",
            "sweep.vary.\"sim.dt\"",
        ),
        (
            "sweep vary integer key continuous",
            "\"sim.solver_iterations\" = { uniform = [1.0, 4.0] }",
            "sweep.vary.\"sim.solver_iterations\"",
        ),
        (
            "sweep vary friction twice",
            "\"sim.friction\" = { values = [0.7] }",
            "sweep.vary.\"sim.friction\"",
        ),
    ] {
        c.sc(
            what,
            format!("{sw}\n[sweep.vary]\n{entry}\n"),
            Some(entry),
            Some(key),
        );
    }
    c.sc(
        "sweep count not a multiple of the grid",
        format!("{sw}\n[sweep.vary]\n\"planner.k1\" = {{ grid = [0.7, 0.8, 0.9] }}\n"),
        Some("count = 4"),
        Some("sweep.count"),
    );
    c.sc(
        "sweep success max missing",
        edit(&sw, "success_max = 0.1\n", ""),
        Some("[sweep]"),
        Some("sweep.success_max"),
    );
    c.sc(
        "sweep sigma rate on a disk",
        format!("{d}\n[sweep]\ncount = 2\nsigma_rate = 1.0\nsuccess_max = 1.0\ntime_metric = \"sim_goal_position\"\n"),
        Some("sigma_rate"),
        Some("sweep.sigma_rate"),
    );
    c.sc(
        "sweep time metric the disk lacks",
        format!("{d}\n[sweep]\ncount = 2\nsuccess_max = 1.0\ntime_metric = \"sim_time_to_goal\"\n"),
        Some("time_metric ="),
        Some("sweep.time_metric"),
    );
    let sr = shipped("space_robot_paper.toml");
    c.sc(
        "sweep wheel wear the space robot lacks",
        format!("{sr}\n[sweep]\ncount = 2\nsuccess_metric = \"sim_goal_theta0_deg\"\ntime_metric = \"sim_goal_theta0_deg\"\nsuccess_max = 1.0\n[sweep.vary]\n\"sim.perturb.wheel_radius_scale\" = {{ uniform = [0.9, 1.0] }}\n"),
        Some("[sweep]"),
        Some("sweep"),
    );

    // Other systems: parameters, physics at the start pose, planner refusals.
    c.sc(
        "space robot gravity",
        edit(
            &sr,
            "gravity = [0.0, 0.0, 0.0]",
            "gravity = [0.0, 0.0, -9.81]",
        ),
        Some("gravity = [0.0, 0.0, -9.81]"),
        Some("sim.gravity"),
    );
    c.sc(
        "space robot start length",
        edit(&sr, "start = [0.0, 15.0, 15.0]", "start = [0.0, 15.0]"),
        Some("start ="),
        Some("start"),
    );
    c.sc(
        "space robot unreachable goal",
        edit(
            &sr,
            "kind = \"stokes_space\"",
            "kind = \"stokes_space\"\ntheta1_limit_deg = 30.0",
        ),
        Some("goal ="),
        Some("goal"),
    );
    c.sc(
        "space robot fixed side",
        edit(&sr, "fixed_side = \"lambda\"", "fixed_side = \"both\""),
        Some("fixed_side"),
        Some("planner.fixed_side"),
    );
    let s1 = shipped("space_manipulator_s1.toml");
    c.sc(
        "via point of 2 angles",
        edit(
            &s1,
            "via_deg = [[0.0, 0.0, 22.5]]",
            "via_deg = [[0.0, 22.5]]",
        ),
        Some("via_deg"),
        Some("planner.via_deg"),
    );
    c.sc(
        "segment time zero",
        edit(&s1, "segment_time = 20.0", "segment_time = 0.0"),
        Some("segment_time"),
        Some("planner.segment_time"),
    );
    c.sc(
        "endogenous on a sphere",
        edit(
            &shipped("sphere_triangle_paper.toml"),
            "kind = \"sphere_triangle\"",
            "kind = \"endogenous\"",
        ),
        Some("\"endogenous\""),
        Some("planner.kind"),
    );
    let rv = shipped("rover_paper.toml");
    c.sc(
        "rover switching kind",
        edit(&rv, "kind = \"telegraph\"", "kind = \"random\""),
        Some("switching = {"),
        Some("model.switching.kind"),
    );
    c.sc(
        "rover telegraph rate negative",
        edit(&rv, "rate = 0.5 }", "rate = -0.5 }"),
        Some("switching = {"),
        Some("model.switching.rate"),
    );
    c.sc(
        "rover envelope tolerance",
        edit(&rv, "[planner]", "envelope_tolerance = -1.0\n\n[planner]"),
        Some("envelope_tolerance"),
        Some("model.envelope_tolerance"),
    );
    c.sc(
        "rover geometry",
        edit(&rv, "[planner]", "geometry = { l = -0.25 }\n\n[planner]"),
        Some("geometry"),
        Some("model.geometry.l"),
    );
    c.sc(
        "rover turn",
        edit(&rv, "turn = \"left\"", "turn = \"up\""),
        Some("turn ="),
        Some("planner.turn"),
    );
    c.sc(
        "rover goal length",
        edit(&rv, "goal = [8.0, 2.0, 90.0, 0.0]", "goal = [8.0, 2.0]"),
        Some("goal ="),
        Some("goal"),
    );
    let sp = shipped("sphere_triangle_paper.toml");
    c.sc(
        "sphere radius differs from the URDF",
        edit(&sp, "radius = 1.0", "radius = 0.5"),
        Some("radius ="),
        Some("model.radius"),
    );
    c.sc(
        "sphere start of 6 values",
        edit(
            &sp,
            "start = [-0.998460, -1.497690, 0.0, 0.0, 0.0]",
            "start = [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]",
        ),
        Some("start ="),
        Some("start"),
    );
}
