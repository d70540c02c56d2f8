//! The surfaces added in 0.2.0, attacked: declared expressions (a trailing
//! operator, a 25 000-term sum, 50 000 and 100 nested signs, a name of
//! 10 000 characters), URDF geometry echoed as written, a collision STL
//! whose triangle count disagrees with its size, a scenario path with a
//! newline in it, a sweep over an undeclared parameter, a start inside an
//! obstacle. The runtime faults (non-finite drives, `init` onto a symlink
//! loop, a `packages` entry naming no directory, a collision mesh of
//! 300 000 triangles) are in [`faults`].

use super::faults::FaultCase;
use super::*;

/// The trailer planned by the endogenous planner, its URDF made absolute.
pub fn trailer_planned() -> String {
    let dir = root().join("examples/trailer");
    let text = std::fs::read_to_string(dir.join("trailer_endogenous.toml")).unwrap();
    edit(
        &text,
        "urdf = \"trailer.urdf\"",
        &format!("urdf = \"{}\"", dir.join("trailer.urdf").display()),
    )
}

/// The shipped trailer (a declared model), its files made absolute.
pub fn trailer() -> String {
    let dir = root().join("examples/trailer");
    let text = std::fs::read_to_string(dir.join("trailer_forward.toml")).unwrap();
    let text = edit(
        &text,
        "urdf = \"trailer.urdf\"",
        &format!("urdf = \"{}\"", dir.join("trailer.urdf").display()),
    );
    edit(
        &text,
        "path = \"s_curve.csv\"",
        &format!("path = \"{}\"", dir.join("s_curve.csv").display()),
    )
}

/// The trailer with the equation of `theta0` written as `expr`.
fn theta0(expr: &str) -> String {
    edit(
        &trailer(),
        "theta0 = \"omega\"",
        &format!("theta0 = \"{expr}\""),
    )
}

/// A binary STL of `n` triangles (a fan on a sphere of radius `r`, m);
/// its header counts `count` (`None`: `n`).
pub fn stl(n: usize, r: f32, count: Option<u32>) -> Vec<u8> {
    let mut out = vec![0u8; 80];
    out.extend(count.unwrap_or(n as u32).to_le_bytes());
    let rows = (n as f64).sqrt().ceil() as usize;
    let at = |i: usize, j: usize| {
        let th = std::f32::consts::PI * (i as f32 + 0.5) / rows as f32;
        let ph = std::f32::consts::TAU * j as f32 / rows as f32;
        [
            r * th.sin() * ph.cos(),
            r * th.sin() * ph.sin(),
            r * th.cos(),
        ]
    };
    for k in 0..n {
        let (i, j) = (k / rows, k % rows);
        out.extend([0u8; 12]);
        for p in [at(i, j), at(i + 1, j), at(i, j + 1)] {
            for x in p {
                out.extend(x.to_le_bytes());
            }
        }
        out.extend([0u8; 2]);
    }
    out
}

/// The differential drive (`m.urdf`) with its body's collision box
/// replaced by `<mesh filename="MESH"/>`.
pub fn diff_drive_with_mesh(mesh: &str) -> (String, String) {
    let urdf = edit(
        &std::fs::read_to_string(model("diff_drive.urdf")).unwrap(),
        "<collision>\n      <origin xyz=\"-0.05 0 0.03\"/>\n      <geometry><box size=\"0.30 0.22 0.08\"/></geometry>",
        &format!(
            "<collision>\n      <origin xyz=\"-0.05 0 0.03\"/>\n      <geometry><mesh filename=\"{mesh}\"/></geometry>"
        ),
    );
    let scenario = r#"name = "dd"
start = [0.0, 0.0, 0.0]
goal = [0.0, 0.0, 0.0]

[model]
kind = "diff_drive"
urdf = "m.urdf"

[planner]
kind = "file"
path = "p.csv"

[sim]
dt = 0.001
"#;
    (scenario.to_string(), urdf)
}

const PLAN: &[u8] = b"t,v,omega\n0,0,0\n0.1,0,0\n";

pub fn cases(c: &mut Corpus) {
    let k = Some("model.kinematics.theta0");
    // The expression language: a panic, two stack overflows, an unbounded
    // nesting, a line of 20 000 characters.
    c.sc(
        "declared expression with a trailing operator",
        theta0("omega *"),
        Some("theta0 = \"omega *\""),
        k,
    );
    let sum = vec!["omega"; 25_000].join(" + ");
    c.sc(
        "declared expression of 25 000 terms",
        theta0(&sum),
        Some("theta0 = \"omega + omega"),
        k,
    );
    let signs = format!("{}omega", "-".repeat(50_000));
    c.sc(
        "declared expression under 50 000 minus signs",
        theta0(&signs),
        Some("theta0 = \"---"),
        k,
    );
    let signs = format!("{}omega", "- ".repeat(100));
    c.sc(
        "declared expression under 100 minus signs",
        theta0(&signs),
        Some("theta0 = \"- -"),
        k,
    );
    let nested = format!("{}omega{}", "(".repeat(200), ")".repeat(200));
    c.sc(
        "declared expression in 200 parentheses",
        theta0(&nested),
        Some("theta0 = \"(("),
        k,
    );
    let long = "q".repeat(10_000);
    c.sc(
        "declared unknown name of 10 000 characters",
        theta0(&long),
        Some("theta0 = \"qqq"),
        k,
    );
    c.sc(
        "declared read of a link named with 10 000 characters",
        edit(
            &trailer(),
            "theta1 = \"trailer_link.yaw\"",
            &format!("theta1 = \"{long}.yaw\""),
        ),
        Some("theta1 = \"qqq"),
        Some("model.read.theta1"),
    );

    // Velocity reads of a link or joint the URDF lacks, of a fixed joint.
    for (what, read) in [
        (
            "declared velocity read of an unknown link",
            "trailer_lnk.wz",
        ),
        (
            "declared velocity read of an unknown joint",
            "hitchh.velocity",
        ),
        (
            "declared velocity read of a fixed joint",
            "caster_joint.velocity",
        ),
        ("declared read of an unknown velocity", "trailer_link.vq"),
    ] {
        c.sc(
            what,
            edit(
                &trailer(),
                "theta1 = \"trailer_link.yaw\"",
                &format!("theta1 = \"{read}\""),
            ),
            Some(&format!("theta1 = \"{read}")),
            Some("model.read.theta1"),
        );
    }

    // `[model] wheels`: each entry a `[model.drive]` joint.
    for (what, wheel) in [
        ("declared wheel that is a passive joint", "hitch"),
        ("declared wheel that is not a joint", "no_such_joint"),
    ] {
        c.sc(
            what,
            edit(
                &trailer(),
                "frictionless = ",
                &format!("wheels = [\"{wheel}\"]\nfrictionless = "),
            ),
            Some("wheels = "),
            Some("model.wheels"),
        );
    }

    let t = trailer();
    let key = format!("thresholds.{long}");
    c.sc(
        "threshold named with 10 000 characters",
        edit(&t, "[thresholds]", &format!("[thresholds]\n{long} = 1.0")),
        Some(&format!("{long} = 1.0")),
        // The key as messages cut it (crate::echo::bare).
        Some(&format!(
            "{}… ({} characters)",
            key.chars().take(59).collect::<String>(),
            key.chars().count()
        )),
    );
    c.sc(
        "model kind of 10 000 characters",
        edit(&t, "kind = \"declared\"", &format!("kind = \"{long}\"")),
        Some(&format!("kind = \"{long}")),
        Some("model.kind"),
    );

    // URDF geometry: written as in the URDF, not as the parser's structures.
    let (sc, _) = diff_drive_with_mesh("x.stl");
    let dd = sc;
    let mut urdf_case = |name: &str, from: &str, to: &str, at: &str| {
        let urdf = edit(
            &std::fs::read_to_string(model("diff_drive.urdf")).unwrap(),
            from,
            to,
        );
        let line = line_of(&urdf, at);
        c.raw(Case {
            name: name.into(),
            files: vec![
                ("case.toml".into(), dd.clone().into_bytes()),
                ("m.urdf".into(), urdf.into_bytes()),
                ("p.csv".into(), PLAN.to_vec()),
            ],
            special: vec![],
            args: vec!["case.toml".into()],
            run_flags: vec![],
            expect: vec![Shape {
                file: "m.urdf".into(),
                line: Some(line),
                key: Some("URDF link `left_wheel`".into()),
            }],
        });
    };
    urdf_case(
        "urdf cylinder of radius 0",
        "<cylinder radius=\"0.05\" length=\"0.025\"/>",
        "<cylinder radius=\"0\" length=\"0.025\"/>",
        "<cylinder radius=\"0\"",
    );
    urdf_case(
        "urdf mesh scaled by NaN",
        "<geometry><box size=\"0.02 0.027 0.01\"/></geometry>",
        "<geometry><mesh filename=\"w.stl\" scale=\"nan 1 1\"/></geometry>",
        "scale=\"nan 1 1\"",
    );

    // A collision STL whose header counts 4e9 triangles and holds 2.
    let (sc, urdf) = diff_drive_with_mesh("body.stl");
    let line = line_of(&urdf, "body.stl");
    c.raw(Case {
        name: "collision STL counting 4e9 triangles in 184 bytes".into(),
        files: vec![
            ("case.toml".into(), sc.into_bytes()),
            ("m.urdf".into(), urdf.into_bytes()),
            ("body.stl".into(), stl(2, 0.1, Some(4_000_000_000))),
            ("p.csv".into(), PLAN.to_vec()),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "m.urdf".into(),
            line: Some(line),
            key: Some("URDF link `base_link` collision mesh".into()),
        }],
    });

    // A scenario whose path holds a newline: still one line, escaped.
    let bad = theta0("omegaa");
    let line = line_of(&bad, "omegaa");
    c.raw(Case {
        name: "scenario path with a newline".into(),
        files: vec![("a\nb/case.toml".into(), bad.into_bytes())],
        special: vec![],
        args: vec!["a\nb/case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "a\\nb/case.toml".into(),
            line: Some(line),
            key: Some("key `model.kinematics.theta0`".into()),
        }],
    });

    // A sweep over a parameter the model does not declare.
    let sw = trailer()
        + "\n[sweep]\ncount = 2\nsuccess_metric = \"ideal_goal_position\"\nsuccess_max = 100.0\n\
           [sweep.vary]\n\"model.params.d11\" = { grid = [0.4, 0.6] }\n";
    c.sc(
        "sweep over an undeclared parameter",
        sw,
        Some("\"model.params.d11\""),
        Some("sweep.vary.\"model.params.d11\""),
    );

    // The endogenous planner on a declared model: an equation with a kink
    // where it starts (|v| at rest).
    let kink = edit(
        &trailer_planned(),
        "theta1 = \"v / d1 * sin(theta0 - theta1)\"",
        "theta1 = \"v / d1 * sin(theta0 - theta1) + 0.01 * abs(v)\"",
    );
    c.sc(
        "declared model planned through a kink",
        kink,
        Some("+ 0.01 * abs(v)"),
        Some("model.kinematics.theta1"),
    );

    // A robot that starts inside an obstacle.
    let (sc, _) = diff_drive_with_mesh("x.stl");
    let sc = sc.replace("urdf = \"m.urdf\"", &format!("urdf = \"{}\"", model("diff_drive.urdf").display()))
        + "\n[[model.obstacles]]\nname = \"crate\"\ncenter = [0.0, 0.0, 0.1]\nsemi_axes = [0.1, 0.1, 0.1]\n";
    let line = line_of(&sc, "start = ");
    c.raw(Case {
        name: "start inside an obstacle".into(),
        files: vec![
            ("case.toml".into(), sc.into_bytes()),
            ("p.csv".into(), PLAN.to_vec()),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "case.toml".into(),
            line: Some(line),
            key: Some("key `start`".into()),
        }],
    });
}

fn args(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

/// One call on `files`, ending with `code` and every `has` in stderr.
fn fault(
    name: &str,
    files: Vec<(String, Vec<u8>)>,
    call: &[&str],
    code: i32,
    has: &[&str],
) -> FaultCase {
    FaultCase {
        name: name.into(),
        files,
        symlinks: Vec::new(),
        args: args(call),
        code,
        stderr_has: args(has),
        stderr_any: Vec::new(),
        stdout_has: Vec::new(),
        one_line: code == 2,
    }
}

pub fn faults() -> Vec<FaultCase> {
    let mut out = Vec::new();
    let run = ["run", "case.toml", "--no-logs", "--quiet"];
    // Non-finite drives stop the run at once, in `run` and in `check`.
    let zero_r = edit(&trailer(), "r = 0.05 ", "r = 0.0 ").into_bytes();
    let drive = "physics run: key `model.drive.left_wheel_joint` (`(v - omega * b) / r`) gives NaN at t = 0 s, from x = 0, y = 0, theta0 = 0°, theta1 = 0°; v = 0, omega = 0";
    out.push(fault(
        "declared drive NaN from the start",
        vec![("case.toml".into(), zero_r.clone())],
        &run,
        3,
        &[drive],
    ));
    out.push(fault(
        "check with a declared drive NaN from the start",
        vec![("case.toml".into(), zero_r)],
        &["check", "case.toml", "--no-logs", "--quiet"],
        3,
        &[drive],
    ));
    let position = edit(
        &trailer(),
        "[model.read]",
        "[model.drive_position]\nhitch = \"theta0 / 0\"\n\n[model.read]",
    );
    out.push(fault(
        "declared position target NaN from the start",
        vec![("case.toml".into(), position.into_bytes())],
        &run,
        3,
        &["key `model.drive_position.hitch` (`theta0 / 0`) gives NaN at t = 0 s"],
    ));
    // A drive that turns NaN on the way: ln of a negative number once the
    // tractor is past x = 0.5 m.
    let later = edit(
        &trailer(),
        "left_wheel_joint = \"(v - omega * b) / r\"",
        "left_wheel_joint = \"(v - omega * b) / r + 0 * ln(0.5 - x)\"",
    );
    out.push(fault(
        "declared drive NaN past x = 0.5 m",
        vec![("case.toml".into(), later.into_bytes())],
        &run,
        3,
        &[
            "key `model.drive.left_wheel_joint`",
            "gives NaN at t = ",
            ", from x = 0.5",
        ],
    ));
    // The endogenous planner's iteration cap on a declared model: exit 3
    // with the error reached and the iterations used.
    let capped = edit(
        &trailer_planned(),
        "segment_time = 20.0",
        "segment_time = 20.0\nmax_iterations = 5",
    );
    let mut c = fault(
        "declared model planned into the iteration cap",
        vec![("case.toml".into(), capped.into_bytes())],
        &run,
        3,
        &["key `planner`: planner: planner did not converge: segment 1: iteration cap 5 reached with error 4.7"],
    );
    c.one_line = true;
    out.push(c);
    // `init` onto a symlink loop names `init`.
    let mut c = fault(
        "init onto a symlink loop",
        Vec::new(),
        &["init", "loop"],
        2,
        &["error: loop: init: the directory is a symbolic link that does not resolve"],
    );
    c.symlinks = vec![("loop".into(), "loop".into())];
    out.push(c);
    // A `packages` entry that names no directory: the message names it.
    let (sc, urdf) = diff_drive_with_mesh("package://shapes/body.stl");
    let sc = edit(
        &sc,
        "urdf = \"m.urdf\"",
        "urdf = \"m.urdf\"\npackages = { shapes = \"no_such_dir\" }",
    );
    out.push(fault(
        "packages entry naming no directory",
        vec![
            ("case.toml".into(), sc.into_bytes()),
            ("m.urdf".into(), urdf.into_bytes()),
            ("p.csv".into(), PLAN.to_vec()),
        ],
        &["list", "case.toml"],
        2,
        &[
            "[model] packages sets it to `",
            "no_such_dir`, which is not a directory",
        ],
    ));
    // A collision mesh of 300 000 triangles: thinned for its hull, in
    // moments (its exact hull took 37 s), with a warning saying so.
    let (sc, urdf) = diff_drive_with_mesh("body.stl");
    let mut c = fault(
        "collision mesh of 300 000 triangles",
        vec![
            ("case.toml".into(), sc.into_bytes()),
            ("m.urdf".into(), urdf.into_bytes()),
            ("body.stl".into(), stl(300_000, 0.1, None)),
            ("p.csv".into(), PLAN.to_vec()),
        ],
        &run,
        0,
        &["300000 triangles, over the budget of 20000 for a collision hull"],
    );
    c.one_line = false;
    out.push(c);
    out
}
