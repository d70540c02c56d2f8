//! Scenario files: TOML and file-level problems, names, and the [model],
//! [planner], [limits] and [sim] tables.

use super::*;

pub fn cases(c: &mut Corpus) {
    let d = disk();

    // TOML and file-level problems.
    c.sc(
        "syntax",
        edit(&d, "dt = 0.001", "dt = = 1"),
        Some("= ="),
        None,
    );
    c.sc(
        "unterminated string",
        edit(&d, "name = \"d\"", "name = \"d"),
        Some("name ="),
        None,
    );
    c.sc(
        "duplicate key",
        edit(&d, "dt = 0.001", "dt = 0.001\ndt = 0.002"),
        Some("dt = 0.002"),
        None,
    );
    let dup = format!("{d}\n[sim]\nfriction = 1.0\n");
    let second_sim = dup.lines().count() - 1;
    c.sc_line("duplicate table", dup, Some(second_sim), None);
    c.sc_line("empty file", String::new(), Some(1), Some("model"));
    c.sc_line(
        "only a comment",
        "# nothing\n".into(),
        Some(1),
        Some("model"),
    );
    c.sc(
        "unknown top-level key",
        edit(&d, "name = \"d\"", "name = \"d\"\nstat = 1"),
        Some("stat ="),
        Some("stat"),
    );
    c.sc(
        "expect fails without a reason",
        edit(&d, "name = \"d\"", "name = \"d\"\nexpect = \"fails\""),
        Some("expect ="),
        Some("expect"),
    );
    c.sc(
        "reason without expect",
        edit(&d, "name = \"d\"", "name = \"d\"\nreason = \"why\""),
        Some("reason ="),
        Some("reason"),
    );
    c.sc(
        "expect is not passes or fails",
        edit(
            &d,
            "name = \"d\"",
            "name = \"d\"\nexpect = \"maybe\"\nreason = \"x\"",
        ),
        Some("expect ="),
        Some("expect"),
    );
    c.sc(
        "sim.dt above its documented range",
        edit(&d, "dt = 0.001", "dt = 0.5"),
        Some("dt = 0.5"),
        Some("sim.dt"),
    );
    c.sc_line(
        "missing start",
        edit(&d, "start = [0.0, 0.0, 0.0, 0.0]\n", ""),
        Some(1),
        Some("start"),
    );
    c.sc_line(
        "missing goal",
        edit(&d, "goal = [-0.4, 1.0, 180.0, 22.5]\n", ""),
        Some(1),
        Some("goal"),
    );
    c.sc(
        "start is a string",
        edit(&d, "start = [0.0, 0.0, 0.0, 0.0]", "start = \"origin\""),
        Some("start ="),
        Some("start"),
    );
    c.sc(
        "goal is a number",
        edit(&d, "goal = [-0.4, 1.0, 180.0, 22.5]", "goal = 3"),
        Some("goal ="),
        Some("goal"),
    );
    c.sc(
        "goal element is a bool",
        edit(&d, "goal = [-0.4,", "goal = [true,"),
        Some("goal ="),
        Some("goal[0]"),
    );
    c.sc(
        "start too short",
        edit(&d, "start = [0.0, 0.0, 0.0, 0.0]", "start = [0.0, 0.0]"),
        Some("start ="),
        Some("start"),
    );
    c.sc(
        "goal empty",
        edit(&d, "goal = [-0.4, 1.0, 180.0, 22.5]", "goal = []"),
        Some("goal ="),
        Some("goal"),
    );
    c.sc(
        "goal nan",
        edit(&d, "goal = [-0.4,", "goal = [nan,"),
        Some("goal ="),
        Some("goal[0]"),
    );
    c.sc(
        "start inf",
        edit(&d, "start = [0.0,", "start = [-inf,"),
        Some("start ="),
        Some("start[0]"),
    );
    c.sc(
        "name is a number",
        edit(&d, "name = \"d\"", "name = 5"),
        Some("name ="),
        Some("name"),
    );
    c.sc(
        "description is an array",
        edit(&d, "name = \"d\"", "name = \"d\"\ndescription = [1]"),
        Some("description"),
        Some("description"),
    );

    // Names: log directory names.
    for (what, name) in [
        ("empty name", "\"\""),
        ("name with slash", "\"a/b\""),
        ("name escaping the log dir", "\"../x\""),
        ("hidden name", "\".x\""),
        ("name with NUL", "\"a\\u0000b\""),
        ("name with tab", "\"a\\tb\""),
        ("name with trailing space", "\"a \""),
        ("name with colon", "\"a:b\""),
    ] {
        c.sc(
            what,
            edit(&d, "name = \"d\"", &format!("name = {name}")),
            Some("name ="),
            Some("name"),
        );
    }
    let long = "x".repeat(300);
    c.sc(
        "name of 300 chars",
        edit(&d, "name = \"d\"", &format!("name = \"{long}\"")),
        Some("name ="),
        Some("name"),
    );

    // [model].
    c.sc_line(
        "no model table",
        edit(
            &d,
            "[model]\nkind = \"rolling_disk\"\nradius = 0.25\n",
            "[stuff]\n",
        )
        .replace(
            &format!("urdf = \"{}\"", model("rolling_disk.urdf").display()),
            "a = 1",
        ),
        Some(1),
        Some("model"),
    );
    c.sc(
        "model is a number",
        format!("model = 3\n{}", edit(&d, "[model]", "[model_]")),
        Some("model = 3"),
        Some("model"),
    );
    c.sc(
        "model kind missing",
        edit(&d, "kind = \"rolling_disk\"\n", ""),
        Some("[model]"),
        Some("model.kind"),
    );
    c.sc(
        "model kind not a string",
        edit(&d, "kind = \"rolling_disk\"", "kind = 4"),
        Some("kind = 4"),
        Some("model.kind"),
    );
    c.sc(
        "unknown model",
        edit(&d, "kind = \"rolling_disk\"", "kind = \"submarine\""),
        Some("\"submarine\""),
        Some("model.kind"),
    );
    c.sc(
        "radius is a string",
        edit(&d, "radius = 0.25", "radius = \"big\""),
        Some("radius ="),
        Some("model.radius"),
    );
    c.sc(
        "radius negative",
        edit(&d, "radius = 0.25", "radius = -0.25"),
        Some("radius ="),
        Some("model.radius"),
    );
    c.sc(
        "radius zero",
        edit(&d, "radius = 0.25", "radius = 0.0"),
        Some("radius ="),
        Some("model.radius"),
    );
    c.sc(
        "radius nan",
        edit(&d, "radius = 0.25", "radius = nan"),
        Some("radius ="),
        Some("model.radius"),
    );
    c.sc(
        "radius inf",
        edit(&d, "radius = 0.25", "radius = inf"),
        Some("radius ="),
        Some("model.radius"),
    );
    c.sc(
        "radius missing",
        edit(&d, "radius = 0.25\n", ""),
        Some("[model]"),
        Some("model.radius"),
    );
    c.sc(
        "radius differs from the URDF",
        edit(&d, "radius = 0.25", "radius = 0.3"),
        Some("radius ="),
        Some("model.radius"),
    );
    c.sc(
        "unknown model key",
        edit(&d, "radius = 0.25", "radius = 0.25\nwidth = 1.0"),
        Some("width"),
        Some("model.width"),
    );
    c.sc(
        "urdf key missing",
        edit(
            &d,
            &format!("urdf = \"{}\"\n", model("rolling_disk.urdf").display()),
            "",
        ),
        Some("[model]"),
        Some("model.urdf"),
    );
    c.sc(
        "urdf is a number",
        edit(
            &d,
            &format!("urdf = \"{}\"", model("rolling_disk.urdf").display()),
            "urdf = 3",
        ),
        Some("urdf ="),
        Some("model.urdf"),
    );
    c.sc(
        "urdf file missing",
        edit(&d, "rolling_disk.urdf", "nothing.urdf"),
        Some("urdf ="),
        Some("model.urdf"),
    );

    // [planner].
    c.sc_line(
        "no planner table",
        edit(&d, "[planner]\nkind = \"stokes_disk\"\n", ""),
        Some(1),
        Some("planner"),
    );
    c.sc(
        "planner kind missing",
        edit(&d, "kind = \"stokes_disk\"", "slant = 0.5"),
        Some("[planner]"),
        Some("planner.kind"),
    );
    c.sc(
        "unknown planner",
        edit(&d, "kind = \"stokes_disk\"", "kind = \"teleport\""),
        Some("teleport"),
        Some("planner.kind"),
    );
    c.sc(
        "planner of another model",
        edit(&d, "kind = \"stokes_disk\"", "kind = \"sphere_triangle\""),
        Some("sphere_triangle"),
        Some("planner.kind"),
    );
    c.sc(
        "unknown planner key",
        edit(
            &d,
            "kind = \"stokes_disk\"",
            "kind = \"stokes_disk\"\nalgoritm = \"x\"",
        ),
        Some("algoritm"),
        Some("planner.algoritm"),
    );
    c.sc(
        "planner enum value",
        edit(
            &d,
            "kind = \"stokes_disk\"",
            "kind = \"stokes_disk\"\nalgorithm = \"fast\"",
        ),
        Some("\"fast\""),
        Some("planner.algorithm"),
    );
    c.sc(
        "planner parameter type",
        edit(
            &d,
            "kind = \"stokes_disk\"",
            "kind = \"stokes_disk\"\nslant = \"x\"",
        ),
        Some("slant"),
        Some("planner.slant"),
    );
    c.sc(
        "planner parameter range",
        edit(
            &d,
            "kind = \"stokes_disk\"",
            "kind = \"stokes_disk\"\nslant = -5.0",
        ),
        Some("slant"),
        Some("planner.slant"),
    );

    // [limits].
    let lim = |body: &str| format!("{d}\n[limits]\n{body}\n");
    c.sc(
        "max_rate length",
        lim("max_rate = [1.0]"),
        Some("max_rate"),
        Some("limits.max_rate"),
    );
    c.sc(
        "max_rate negative",
        lim("max_rate = [1.0, -1.0]"),
        Some("max_rate"),
        Some("limits.max_rate[1]"),
    );
    c.sc(
        "max_rate zero",
        lim("max_rate = [0.0, 1.0]"),
        Some("max_rate"),
        Some("limits.max_rate[0]"),
    );
    c.sc(
        "max_rate string",
        lim("max_rate = \"fast\""),
        Some("max_rate"),
        Some("limits.max_rate"),
    );
    c.sc(
        "ramp negative",
        lim("ramp = -1.0"),
        Some("ramp"),
        Some("limits.ramp"),
    );
    c.sc(
        "unknown limits key",
        lim("rampp = 1.0"),
        Some("rampp"),
        Some("limits.rampp"),
    );

    // [sim].
    for (what, from, to, key) in [
        ("dt zero", "dt = 0.001", "dt = 0.0", "sim.dt"),
        ("dt negative", "dt = 0.001", "dt = -0.001", "sim.dt"),
        ("dt too large", "dt = 0.001", "dt = 0.5", "sim.dt"),
        ("dt string", "dt = 0.001", "dt = \"1ms\"", "sim.dt"),
        ("dt overflow", "dt = 0.001", "dt = 1e999", "sim.dt"),
    ] {
        c.sc(what, edit(&d, from, to), Some(to), Some(key));
    }
    for (what, line, key) in [
        (
            "solver iterations zero",
            "solver_iterations = 0",
            "sim.solver_iterations",
        ),
        (
            "solver iterations huge",
            "solver_iterations = 5000",
            "sim.solver_iterations",
        ),
        (
            "solver iterations negative",
            "solver_iterations = -1",
            "sim.solver_iterations",
        ),
        (
            "solver iterations float",
            "solver_iterations = 1.5",
            "sim.solver_iterations",
        ),
        (
            "solver iterations overflow",
            "solver_iterations = 99999999999999999999",
            "sim.solver_iterations",
        ),
        ("friction negative", "friction = -1.0", "sim.friction"),
        ("friction nan", "friction = nan", "sim.friction"),
        ("gravity length", "gravity = [0.0, 0.0]", "sim.gravity"),
        ("gravity string", "gravity = \"down\"", "sim.gravity"),
        (
            "motor torque zero",
            "motor_max_torque = 0.0",
            "sim.motor_max_torque",
        ),
        ("motor gain negative", "motor_gain = -1.0", "sim.motor_gain"),
        ("settle negative", "settle = -1.0", "sim.settle"),
        ("unknown sim key", "fricton = 0.5", "sim.fricton"),
    ] {
        c.sc(
            what,
            disk_scenario(&model("rolling_disk.urdf"), "name = \"d\"", line),
            Some(line),
            Some(key),
        );
    }

    // `[regression]` floors: negative ones, scenario-wide or per metric.
    for (what, table, at, key) in [
        (
            "negative regression floor",
            "[regression]\nabs = -0.001",
            "abs =",
            "regression.abs",
        ),
        (
            "negative per-metric floor",
            "[regression]\nmetrics.sim_goal_position = { abs = -1e-4 }",
            "metrics.sim_goal_position",
            "regression.metrics.sim_goal_position.abs",
        ),
    ] {
        c.sc(what, format!("{d}\n{table}\n"), Some(at), Some(key));
    }
}
