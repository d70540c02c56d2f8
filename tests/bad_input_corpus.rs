//! The bad-input corpus: every case through `run`, `check`, `plan` and `list`
//! (one test per command, so they run in parallel). Each invocation must exit
//! 2 within a time limit, print one `error: FILE[:LINE]: ...` line per
//! expected error (with the expected file, line and key), never panic, and
//! write nothing (the log directory is not even created).

mod common;
use common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// One expected stderr line: `error: {file}` then `:{line}` (or nothing),
/// then `: ` and, when given, `{key}` at the start of the message.
#[derive(Clone, Debug)]
struct Shape {
    file: String,
    line: Option<usize>,
    key: Option<String>,
}

#[derive(Clone, Debug)]
enum Special {
    Fifo(&'static str),
    Symlink(&'static str, &'static str),
    Dir(&'static str),
    /// A sparse file of this many bytes.
    Sized(&'static str, u64),
}

#[derive(Clone, Debug)]
struct Case {
    name: String,
    files: Vec<(String, Vec<u8>)>,
    special: Vec<Special>,
    args: Vec<String>,
    /// Extra flags of `run`/`check`; such cases are about those flags and
    /// skip `plan` and `list`.
    run_flags: Vec<String>,
    expect: Vec<Shape>,
}

/// 1-based line of the first line of `text` containing `needle`.
fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("`{needle}` not in:\n{text}"))
        + 1
}

/// `text` with `from` replaced (which must occur: a case must change its base).
fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "`{from}` not in:\n{text}");
    text.replacen(from, to, 1)
}

fn shipped(file: &str) -> String {
    let text = std::fs::read_to_string(scenario(file)).unwrap();
    text.replace(
        "../models/",
        &format!("{}/", root().join("models").display()),
    )
}

fn disk() -> String {
    disk_scenario(&model("rolling_disk.urdf"), "name = \"d\"", "")
}

struct Corpus(Vec<Case>);

impl Corpus {
    /// A single scenario `case.toml`; the error is at the line containing
    /// `at` (None: no line) and names `key`.
    fn sc(&mut self, name: &str, text: String, at: Option<&str>, key: Option<&str>) {
        let line = at.map(|n| line_of(&text, n));
        self.sc_line(name, text, line, key);
    }

    fn sc_line(&mut self, name: &str, text: String, line: Option<usize>, key: Option<&str>) {
        self.0.push(Case {
            name: name.into(),
            files: vec![("case.toml".into(), text.into_bytes())],
            special: vec![],
            args: vec!["case.toml".into()],
            run_flags: vec![],
            expect: vec![Shape {
                file: "case.toml".into(),
                line,
                key: key.map(|k| format!("key `{k}`")),
            }],
        });
    }

    /// A scenario with its own URDF `m.urdf` (the shipped `urdf_file` edited
    /// by `edit`); the error is in `m.urdf` at the line containing `at`.
    fn urdf(
        &mut self,
        name: &str,
        scenario_text: &str,
        urdf_file: &str,
        edits: &[(&str, &str)],
        at: Option<&str>,
        key: &str,
    ) {
        let mut urdf = std::fs::read_to_string(model(urdf_file)).unwrap();
        for (from, to) in edits {
            urdf = edit(&urdf, from, to);
        }
        let line = at.map(|n| line_of(&urdf, n));
        let text = scenario_text.replace(&model(urdf_file).display().to_string(), "m.urdf");
        assert!(
            text.contains("\"m.urdf\""),
            "{name}: scenario does not use the URDF"
        );
        self.0.push(Case {
            name: name.into(),
            files: vec![
                ("case.toml".into(), text.into_bytes()),
                ("m.urdf".into(), urdf.into_bytes()),
            ],
            special: vec![],
            args: vec!["case.toml".into()],
            run_flags: vec![],
            expect: vec![Shape {
                file: "m.urdf".into(),
                line,
                key: Some(key.into()),
            }],
        });
    }

    fn raw(&mut self, case: Case) {
        self.0.push(case);
    }
}

fn no_line(file: &str) -> Shape {
    Shape {
        file: file.into(),
        line: None,
        key: None,
    }
}

fn corpus() -> Vec<Case> {
    let mut c = Corpus(Vec::new());
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
        edit(&d, "kind = \"rolling_disk\"", "kind = \"car\""),
        Some("\"car\""),
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
            "sweep.friction",
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
            "sweep.mass_scale",
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
        format!("{d}\n[sweep]\ncount = 2\nsuccess_max = 1.0\n"),
        Some("[sweep]"),
        Some("sweep.time_metric"),
    );
    let sr = shipped("space_robot_paper.toml");
    c.sc(
        "sweep mass scale the space robot refuses",
        format!("{sr}\n[sweep]\ncount = 2\nmass_scale = [0.5, 1.5]\nsuccess_metric = \"sim_goal_theta0_deg\"\ntime_metric = \"sim_goal_theta0_deg\"\nsuccess_max = 1.0\n"),
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
        Some("model.switching"),
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
        Some("model.geometry"),
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

    // URDFs (the disk's unless said).
    let du = "rolling_disk.urdf";
    let wheel_ixx = "ixx=\"0.031517\"";
    c.urdf(
        "urdf nan inertia",
        &d,
        du,
        &[(wheel_ixx, "ixx=\"nan\"")],
        Some("ixx=\"nan\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf negative inertia",
        &d,
        du,
        &[(wheel_ixx, "ixx=\"-0.031517\"")],
        Some("ixx=\"-0.031517\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf indefinite inertia",
        &d,
        du,
        &[("ixx=\"0.031517\" ixy=\"0\"", "ixx=\"0.031517\" ixy=\"0.5\"")],
        Some("ixy=\"0.5\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf inf inertia",
        &d,
        du,
        &[("izz=\"0.031517\"", "izz=\"inf\"")],
        Some("izz=\"inf\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf zero mass",
        &d,
        du,
        &[("<mass value=\"2.0\"/>", "<mass value=\"0\"/>")],
        Some("name=\"wheel\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf negative mass",
        &d,
        du,
        &[("<mass value=\"2.0\"/>", "<mass value=\"-2\"/>")],
        Some("name=\"wheel\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf nan mass",
        &d,
        du,
        &[("<mass value=\"2.0\"/>", "<mass value=\"nan\"/>")],
        Some("name=\"wheel\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf nan joint origin",
        &d,
        du,
        &[(
            "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n    <axis",
            "<origin xyz=\"nan 0 0\" rpy=\"0 0 0\"/>\n    <axis",
        )],
        Some("xyz=\"nan 0 0\""),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf inf joint rpy",
        &d,
        du,
        &[(
            "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n    <axis",
            "<origin xyz=\"0 0 0\" rpy=\"0 inf 0\"/>\n    <axis",
        )],
        Some("rpy=\"0 inf 0\""),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf zero axis",
        &d,
        du,
        &[("<axis xyz=\"0 1 0\"/>", "<axis xyz=\"0 0 0\"/>")],
        Some("<axis xyz=\"0 0 0\"/>"),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf nan axis",
        &d,
        du,
        &[("<axis xyz=\"0 1 0\"/>", "<axis xyz=\"nan 1 0\"/>")],
        Some("<axis xyz=\"nan"),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf dangling joint",
        &d,
        du,
        &[("<child link=\"wheel\"/>", "<child link=\"ghost\"/>")],
        Some("name=\"wheel_joint\""),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf duplicate link",
        &d,
        du,
        &[("<link name=\"wheel\">", "<link name=\"yoke\">")],
        None,
        "URDF has duplicate",
    );
    c.urdf(
        "urdf wheel missing",
        &d,
        du,
        &[
            ("<link name=\"wheel\">", "<link name=\"wheal\">"),
            ("<child link=\"wheel\"/>", "<child link=\"wheal\"/>"),
        ],
        None,
        "URDF needs a link `wheel`",
    );
    c.urdf(
        "urdf negative visual radius",
        &d,
        du,
        &[("<cylinder radius=\"0.25\"", "<cylinder radius=\"-0.25\"")],
        Some("radius=\"-0.25\""),
        "URDF link `wheel` visual 1",
    );
    c.urdf("urdf nan collision length", &d, du, &[("<collision>\n      <origin xyz=\"0 0 0\" rpy=\"1.5707963267948966 0 0\"/>\n      <geometry><cylinder radius=\"0.25\" length=\"0.04\"", "<collision>\n      <origin xyz=\"0 0 0\" rpy=\"1.5707963267948966 0 0\"/>\n      <geometry><cylinder radius=\"0.25\" length=\"nan\"")], Some("length=\"nan\""), "URDF link `wheel` collision 1");
    c.urdf(
        "urdf malformed XML",
        &d,
        du,
        &[("</robot>", "")],
        None,
        "URDF does not parse",
    );
    c.urdf(
        "urdf nan visual origin",
        &d,
        du,
        &[(
            "<visual>\n      <origin xyz=\"0 0 0\"",
            "<visual>\n      <origin xyz=\"0 0 nan\"",
        )],
        Some("xyz=\"0 0 nan\""),
        "URDF link `wheel` visual 1",
    );
    c.urdf(
        "urdf nan colour",
        &d,
        du,
        &[("rgba=\"0.15 0.15", "rgba=\"nan 0.15")],
        Some("rgba=\"nan"),
        "URDF material `tyre`",
    );
    c.urdf(
        "urdf colour of 5 values",
        &d,
        du,
        &[("rgba=\"0.15 0.15", "rgba=\"0.1 0.15 0.15")],
        None,
        "URDF does not parse",
    );
    c.urdf(
        "urdf inertia attribute missing",
        &d,
        du,
        &[(" izz=\"0.002\"", "")],
        None,
        "URDF does not parse",
    );
    c.urdf(
        "urdf zero box",
        &d,
        du,
        &[(
            "<box size=\"0.22 0.042 0.03\"/>",
            "<box size=\"0 0.042 0.03\"/>",
        )],
        Some("<box size=\"0 "),
        "URDF link `wheel` visual 2",
    );
    c.urdf(
        "space robot urdf mass",
        &sr,
        "space_robot.urdf",
        &[("<mass value=\"27.44\"/>", "<mass value=\"20\"/>")],
        Some("name=\"vehicle\""),
        "URDF link `vehicle`",
    );
    c.urdf(
        "rover urdf limit reversed",
        &rv,
        "rover.urdf",
        &[(
            "lower=\"-0.8\" upper=\"0.8\"",
            "lower=\"0.8\" upper=\"-0.8\"",
        )],
        Some("lower=\"0.8\""),
        "URDF joint",
    );
    for (what, urdf) in [
        ("urdf empty file", ""),
        ("urdf not a robot", "<foo/>"),
        ("urdf without links", "<robot name=\"r\"></robot>"),
    ] {
        c.raw(Case {
            name: what.into(),
            files: vec![
                (
                    "case.toml".into(),
                    d.replace(&model(du).display().to_string(), "m.urdf")
                        .into_bytes(),
                ),
                ("m.urdf".into(), urdf.as_bytes().to_vec()),
            ],
            special: vec![],
            args: vec!["case.toml".into()],
            run_flags: vec![],
            expect: vec![no_line("m.urdf")],
        });
    }

    // Files that are not regular files, too large or not text.
    let file_case = |name: &str,
                     special: Vec<Special>,
                     files: Vec<(String, Vec<u8>)>,
                     arg: &str,
                     expect: Shape| Case {
        name: name.into(),
        files,
        special,
        args: vec![arg.into()],
        run_flags: vec![],
        expect: vec![expect],
    };
    c.raw(file_case(
        "missing scenario",
        vec![],
        vec![],
        "nope.toml",
        no_line("nope.toml"),
    ));
    c.raw(file_case(
        "empty directory",
        vec![Special::Dir("empty")],
        vec![],
        "empty",
        no_line("empty"),
    ));
    c.raw(file_case(
        "FIFO as scenario",
        vec![Special::Fifo("fifo.toml")],
        vec![],
        "fifo.toml",
        no_line("fifo.toml"),
    ));
    c.raw(file_case(
        "/dev/zero as scenario",
        vec![Special::Symlink("/dev/zero", "zero.toml")],
        vec![],
        "zero.toml",
        no_line("zero.toml"),
    ));
    c.raw(file_case(
        "dangling symlink",
        vec![Special::Symlink("/nonexistent/x.toml", "gone.toml")],
        vec![],
        "gone.toml",
        no_line("gone.toml"),
    ));
    c.raw(file_case(
        "scenario of 2 MB",
        vec![Special::Sized("big.toml", 2 << 20)],
        vec![],
        "big.toml",
        no_line("big.toml"),
    ));
    c.raw(file_case(
        "not UTF-8",
        vec![],
        vec![("bin.toml".into(), b"name = \"\xff\xfe\"\n".to_vec())],
        "bin.toml",
        Shape {
            file: "bin.toml".into(),
            line: Some(1),
            key: None,
        },
    ));
    c.raw(file_case(
        "FIFO among the scenarios of a directory",
        vec![Special::Dir("dir"), Special::Fifo("dir/b.toml")],
        vec![],
        "dir",
        no_line("dir/b.toml"),
    ));
    let with_urdf = |name: &str, special: Special, urdf: &str| Case {
        name: name.into(),
        files: vec![(
            "case.toml".into(),
            d.replace(&model(du).display().to_string(), urdf)
                .into_bytes(),
        )],
        special: vec![special],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![no_line(urdf)],
    };
    c.raw(with_urdf("FIFO as URDF", Special::Fifo("m.urdf"), "m.urdf"));
    c.raw(with_urdf(
        "/dev/zero as URDF",
        Special::Symlink("/dev/zero", "m.urdf"),
        "m.urdf",
    ));
    c.raw(with_urdf(
        "directory as URDF",
        Special::Dir("m.urdf"),
        "m.urdf",
    ));
    c.raw(with_urdf(
        "URDF of 17 MB",
        Special::Sized("m.urdf", 17 << 20),
        "m.urdf",
    ));

    // Several scenarios in one call.
    let named = |n: &str| edit(&d, "name = \"d\"", &format!("name = \"{n}\""));
    c.raw(Case {
        name: "duplicate names".into(),
        files: vec![
            ("a.toml".into(), named("same").into_bytes()),
            ("b.toml".into(), named("Same").into_bytes()),
        ],
        special: vec![],
        args: vec!["a.toml".into(), "b.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "b.toml".into(),
            line: Some(1),
            key: Some("key `name`".into()),
        }],
    });
    c.raw(Case {
        name: "the same file twice".into(),
        files: vec![("a.toml".into(), d.clone().into_bytes())],
        special: vec![],
        args: vec!["a.toml".into(), "a.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "a.toml".into(),
            line: Some(1),
            key: Some("key `name`".into()),
        }],
    });
    c.raw(Case {
        name: "good scenario first, bad one after".into(),
        files: vec![
            ("dir/a_good.toml".into(), named("good").into_bytes()),
            (
                "dir/b_bad.toml".into(),
                edit(&named("bad"), "dt = 0.001", "dt = 0.5").into_bytes(),
            ),
        ],
        special: vec![],
        args: vec!["dir".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "dir/b_bad.toml".into(),
            line: Some(line_of(&d, "dt = 0.001")),
            key: Some("key `sim.dt`".into()),
        }],
    });
    c.raw(Case {
        name: "two bad scenarios, two errors".into(),
        files: vec![
            (
                "dir/a.toml".into(),
                edit(&named("a"), "radius = 0.25", "radius = -1.0").into_bytes(),
            ),
            (
                "dir/b.toml".into(),
                edit(&named("b"), "dt = 0.001", "dt = 0.5").into_bytes(),
            ),
        ],
        special: vec![],
        args: vec!["dir".into()],
        run_flags: vec![],
        expect: vec![
            Shape {
                file: "dir/a.toml".into(),
                line: Some(line_of(&d, "radius")),
                key: Some("key `model.radius`".into()),
            },
            Shape {
                file: "dir/b.toml".into(),
                line: Some(line_of(&d, "dt = 0.001")),
                key: Some("key `sim.dt`".into()),
            },
        ],
    });

    // Flags of run/check.
    let flagged = |name: &str, flags: &[&str], expect: Shape| Case {
        name: name.into(),
        files: vec![
            ("case.toml".into(), d.clone().into_bytes()),
            ("logfile".into(), b"x".to_vec()),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: flags.iter().map(|s| s.to_string()).collect(),
        expect: vec![expect],
    };
    c.raw(flagged(
        "--shard on a scenario without [sweep]",
        &["--shard", "0/2"],
        no_line("case.toml"),
    ));
    c.raw(flagged(
        "--shard out of range",
        &["--shard", "2/2"],
        no_line("--shard"),
    ));
    c.raw(flagged(
        "--shard not I/N",
        &["--shard", "x"],
        no_line("--shard"),
    ));
    c.raw(flagged(
        "--logs is a file",
        &["--logs", "logfile"],
        no_line("logfile"),
    ));
    c.0
}

/// Run the binary in `dir`, killing it after `limit`. Returns (exit code, stdout, stderr).
fn run_limited(dir: &Path, args: &[String], limit: Duration) -> (Option<i32>, String, String) {
    let out = dir.join(".stdout");
    let err = dir.join(".stderr");
    let mut child = Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!(
                "hang: `anholonomy {}` killed after {limit:?}",
                args.join(" ")
            );
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let read = |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap()).into_owned();
    let (o, e) = (read(&out), read(&err));
    let _ = std::fs::remove_file(out);
    let _ = std::fs::remove_file(err);
    (status.code(), o, e)
}

fn setup(case: &Case) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    for s in &case.special {
        match s {
            Special::Dir(d) => std::fs::create_dir_all(p.join(d)).unwrap(),
            Special::Fifo(f) => {
                let ok = Command::new("mkfifo")
                    .arg(p.join(f))
                    .status()
                    .unwrap()
                    .success();
                assert!(ok, "mkfifo");
            }
            Special::Symlink(target, link) => {
                #[cfg(unix)]
                std::os::unix::fs::symlink(target, p.join(link)).unwrap();
            }
            Special::Sized(f, n) => {
                std::fs::File::create(p.join(f))
                    .unwrap()
                    .set_len(*n)
                    .unwrap();
            }
        }
    }
    for (name, bytes) in &case.files {
        let f = p.join(name);
        std::fs::create_dir_all(f.parent().unwrap()).unwrap();
        std::fs::write(f, bytes).unwrap();
    }
    dir
}

/// Check one stderr line against its shape; returns a description of the mismatch.
fn shape_mismatch(line: &str, s: &Shape) -> Option<String> {
    let prefix = format!("error: {}", s.file);
    let Some(rest) = line.strip_prefix(&prefix) else {
        return Some(format!("does not start with `{prefix}`"));
    };
    let rest = match s.line {
        Some(n) => match rest.strip_prefix(&format!(":{n}: ")) {
            Some(r) => r,
            None => return Some(format!("line {n} expected")),
        },
        None => match rest.strip_prefix(": ") {
            Some(r) => r,
            None => return Some("no line expected".into()),
        },
    };
    if let Some(k) = &s.key {
        if !rest.starts_with(k.as_str()) {
            return Some(format!("message should start with `{k}`"));
        }
    }
    None
}

/// All cases through one command; every problem is collected, then reported.
fn check_command(cmd: &str) {
    let cases = corpus();
    assert!(cases.len() >= 150, "{} cases", cases.len());
    let mut problems = Vec::new();
    let mut invocations = 0;
    for case in &cases {
        let single =
            case.args.len() == 1 && !case.args[0].ends_with("dir") && case.expect.len() == 1;
        let args: Vec<String> = match cmd {
            "run" | "check" => {
                let mut a = vec![cmd.to_string()];
                a.extend(case.args.iter().cloned());
                a.extend(["--quiet".to_string()]);
                if !case.run_flags.contains(&"--logs".to_string()) {
                    a.extend(["--logs".to_string(), "logs".to_string()]);
                }
                a.extend(case.run_flags.iter().cloned());
                a
            }
            "plan" if single && case.run_flags.is_empty() && case.name != "empty directory" => {
                vec!["plan".into(), case.args[0].clone(), "--json".into()]
            }
            "list" if case.run_flags.is_empty() => {
                let mut a = vec!["list".to_string()];
                a.extend(case.args.iter().cloned());
                a
            }
            _ => continue,
        };
        let dir = setup(case);
        let (code, stdout, stderr) = run_limited(dir.path(), &args, Duration::from_secs(60));
        invocations += 1;
        let mut bad = |what: String| {
            problems.push(format!(
                "[{}] `{}`: {what}\n  stderr: {stderr}",
                case.name,
                args.join(" ")
            ))
        };
        if code != Some(2) {
            bad(format!("exit {code:?}, expected 2"));
        }
        if stderr.contains("panicked") || stderr.contains("RUST_BACKTRACE") {
            bad("panic".into());
        }
        let lines: Vec<&str> = stderr.lines().collect();
        if lines.len() != case.expect.len() {
            bad(format!(
                "{} stderr lines, expected {}",
                lines.len(),
                case.expect.len()
            ));
        } else {
            for (l, s) in lines.iter().zip(&case.expect) {
                if let Some(m) = shape_mismatch(l, s) {
                    bad(format!("{m} (expected {s:?})"));
                }
            }
        }
        if cmd != "list" && !stdout.is_empty() {
            bad(format!("stdout not empty: {stdout}"));
        }
        let written: Vec<PathBuf> = files_below(&dir.path().join("logs"));
        if dir.path().join("logs").exists() {
            bad(format!("log directory created: {written:?}"));
        }
    }
    assert!(
        problems.is_empty(),
        "{} of {invocations} `{cmd}` invocations broke the contract:\n{}",
        problems.len(),
        problems.join("\n")
    );
    eprintln!("{cmd}: {invocations} invocations, all exit 2 with the expected error lines");
}

#[test]
fn corpus_through_run() {
    check_command("run");
}

#[test]
fn corpus_through_check() {
    check_command("check");
}

#[test]
fn corpus_through_plan() {
    check_command("plan");
}

#[test]
fn corpus_through_list() {
    check_command("list");
}

/// The corpus really is bad input only because of its edits: the unedited
/// bases pass validation (so each case tests what it says).
#[test]
fn corpus_bases_are_valid() {
    let dir = tempfile::tempdir().unwrap();
    let bases = [
        ("disk.toml", disk()),
        (
            "rover_sweep.toml",
            shipped("rover_sweep.toml").replace("count = 100", "count = 4"),
        ),
        ("space.toml", shipped("space_robot_paper.toml")),
        ("s1.toml", shipped("space_manipulator_s1.toml")),
        ("rover.toml", shipped("rover_paper.toml")),
        ("sphere.toml", shipped("sphere_triangle_paper.toml")),
    ];
    for (f, text) in &bases {
        std::fs::write(dir.path().join(f), text).unwrap();
    }
    let args: Vec<String> = std::iter::once("list".to_string())
        .chain(bases.iter().map(|(f, _)| f.to_string()))
        .collect();
    let (code, stdout, stderr) = run_limited(dir.path(), &args, Duration::from_secs(60));
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(stdout.lines().count(), bases.len() + 1, "{stdout}");
}
