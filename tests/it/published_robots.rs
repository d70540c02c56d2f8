//! Robot descriptions as the field publishes them: massless frames lumped,
//! every URDF problem at once, meshes found through packages and the ROS
//! environment, xacro, cylinder wheels that roll, and what the harness read
//! said back (`summary.json`'s `model.read_from_urdf`).

use crate::common::*;
use anholonomy::engine::mesh::Search;
use anholonomy::engine::urdf::{SimWorld, WorldOptions};
use anholonomy::engine::PhysicsSettings;
use nalgebra::{Matrix3, Vector3};
use std::path::{Path, PathBuf};

fn example(rel: &str) -> PathBuf {
    root().join("examples").join(rel)
}

const INERTIA: &str = r#"<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.03"/>"#;

/// A link with a mass at `com` (inertia diag(0.01, 0.02, 0.03) about it),
/// or a frame (mass 0: no <inertial>).
fn link(name: &str, mass: f64, com: [f64; 3]) -> String {
    if mass == 0.0 {
        return format!("<link name=\"{name}\"/>");
    }
    format!(
        "<link name=\"{name}\"><inertial><origin xyz=\"{} {} {}\"/><mass value=\"{mass}\"/>{INERTIA}</inertial></link>",
        com[0], com[1], com[2]
    )
}

fn joint(kind: &str, parent: &str, child: &str, xyz: [f64; 3], rpy: [f64; 3]) -> String {
    format!(
        "<joint name=\"{parent}_to_{child}\" type=\"{kind}\"><parent link=\"{parent}\"/><child link=\"{child}\"/>\
         <origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/><axis xyz=\"0 1 0\"/></joint>",
        xyz[0], xyz[1], xyz[2], rpy[0], rpy[1], rpy[2]
    )
}

/// Inertia about a body's CoM of point-free parts: Σ (R I Rᵀ + m (|d|² 1 − d dᵀ)).
fn parallel_axis(parts: &[(f64, Vector3<f64>, Matrix3<f64>)]) -> (f64, Vector3<f64>, Matrix3<f64>) {
    let m: f64 = parts.iter().map(|p| p.0).sum();
    let c = parts.iter().map(|p| p.1 * p.0).sum::<Vector3<f64>>() / m;
    let mut i = Matrix3::zeros();
    for (mk, ck, ik) in parts {
        let d = ck - c;
        i += ik + (Matrix3::identity() * d.norm_squared() - d * d.transpose()) * *mk;
    }
    (m, c, i)
}

#[test]
fn frames_are_lumped_and_the_lumped_inertia_is_the_sum_of_the_parts() {
    // base_footprint (a frame) → base_link (2 kg) → a 0.5 kg bumper fixed
    // ahead and turned 90° about z, and an imu frame; a wheel on a joint.
    let turn = std::f64::consts::FRAC_PI_2;
    let urdf = format!(
        "<robot name=\"r\">{}</robot>",
        [
            link("base_footprint", 0.0, [0.0; 3]),
            link("base_link", 2.0, [-0.05, 0.0, 0.02]),
            link("bumper", 0.5, [0.01, 0.0, 0.0]),
            link("imu_link", 0.0, [0.0; 3]),
            link("wheel", 0.3, [0.0; 3]),
            joint(
                "fixed",
                "base_footprint",
                "base_link",
                [0.0, 0.0, 0.05],
                [0.0; 3]
            ),
            joint(
                "fixed",
                "base_link",
                "bumper",
                [0.2, 0.0, 0.0],
                [0.0, 0.0, turn]
            ),
            joint("fixed", "base_link", "imu_link", [0.0, 0.0, 0.1], [0.0; 3]),
            joint(
                "continuous",
                "base_link",
                "wheel",
                [0.0, 0.15, 0.0],
                [0.0; 3]
            ),
        ]
        .concat()
    );
    let robot = urdf_rs::read_from_string(&urdf).unwrap();
    anholonomy::engine::urdf::validate(&robot).unwrap();
    let settings = PhysicsSettings {
        gravity: [0.0; 3],
        ..Default::default()
    };
    let opts = WorldOptions {
        settings: &settings,
        root_pose: anholonomy::engine::rapier::math::Pose::IDENTITY,
        ground: false,
        keep_fixed: &[],
    };
    let mut sw = SimWorld::new(&robot, Path::new("."), &opts).unwrap();
    sw.world.integration_parameters.dt = 0.0;
    sw.world.step();
    // Three links share base_link's body; the wheel has its own.
    let base = sw.robot.link("base_link").unwrap();
    for l in ["base_footprint", "bumper", "imu_link"] {
        assert_eq!(sw.robot.link(l), Some(base), "{l}");
    }
    assert_ne!(sw.robot.link("wheel"), Some(base));
    let dynamic = sw
        .world
        .bodies
        .iter()
        .filter(|(_, b)| b.is_dynamic())
        .count();
    assert_eq!(dynamic, 2);
    // By hand, in base_link's frame: the bumper's CoM at (0.2, 0, 0) + Rz(90°)(0.01, 0, 0),
    // its inertia turned: diag(0.02, 0.01, 0.03).
    let base_i = Matrix3::from_diagonal(&Vector3::new(0.01, 0.02, 0.03));
    let bumper_i = Matrix3::from_diagonal(&Vector3::new(0.02, 0.01, 0.03));
    let (m, c, i) = parallel_axis(&[
        (2.0, Vector3::new(-0.05, 0.0, 0.02), base_i),
        (0.5, Vector3::new(0.2, 0.01, 0.0), bumper_i),
    ]);
    let mp = sw.world.bodies[base].mass_properties().local_mprops;
    assert!((mp.mass() - m).abs() < 1e-12, "{} vs {m}", mp.mass());
    let com = mp.local_com;
    assert!((Vector3::new(com.x, com.y, com.z) - c).norm() < 1e-12);
    let got = mp.reconstruct_inertia_matrix().to_cols_array();
    let got = Matrix3::from_column_slice(&got);
    assert!((got - i).norm() < 1e-12 * i.norm(), "{got} vs {i}");
    // Every link is still posed: the frame sits 0.05 m below its body.
    let poses = sw.link_poses();
    assert!((poses[0].translation[2] - 0.0).abs() < 1e-12);
    assert!((poses[1].translation[2] - 0.05).abs() < 1e-12);
    assert!((poses[3].translation[2] - 0.15).abs() < 1e-12);
}

/// A scenario for the ROS-style example robot with `urdf` and extra `[model]` keys.
fn pocket_bot(dir: &Path, urdf: &str, model_extra: &str) -> PathBuf {
    let ex = example("ros_robot");
    std::fs::copy(ex.join("s_curve.csv"), dir.join("s_curve.csv")).unwrap();
    let text = format!(
        r#"start = [0.0, 0.0, 0.0]
goal = [1.43388, 1.11276, 0.0]
[model]
kind = "diff_drive"
urdf = "{urdf}"
left_wheel_joint = "wheel_left_joint"
right_wheel_joint = "wheel_right_joint"
caster_links = ["caster_back_link"]
{model_extra}
[planner]
kind = "file"
path = "s_curve.csv"
hold = "linear"
[sim]
dt = 0.001
friction = 0.8
motor_max_torque = 0.5
"#
    );
    let p = dir.join("case.toml");
    std::fs::write(&p, text).unwrap();
    p
}

/// A copy of the example's description package in `dir` (to edit).
fn copy_package(dir: &Path) -> PathBuf {
    let from = example("ros_robot/pocket_bot_description");
    let to = dir.join("pkg");
    for sub in ["urdf", "meshes"] {
        std::fs::create_dir_all(to.join(sub)).unwrap();
        for e in std::fs::read_dir(from.join(sub)).unwrap().flatten() {
            std::fs::copy(e.path(), to.join(sub).join(e.file_name())).unwrap();
        }
    }
    to
}

/// exit 2, one `error:` line per expected needle, nothing written.
fn refused(out: &std::process::Output, dir: &Path, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), needles.len(), "{stderr}");
    for (l, n) in lines.iter().zip(needles) {
        assert!(l.starts_with("error: "), "{l}");
        assert!(l.contains(n), "`{n}` not in {l}");
    }
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        files_below(&dir.join("logs")).is_empty(),
        "a log file was written"
    );
}

#[test]
fn moving_massless_links_are_refused_all_in_one_message() {
    let dir = tempfile::tempdir().unwrap();
    let pkg = copy_package(dir.path());
    let path = pkg.join("urdf/pocket_bot.urdf");
    let text = std::fs::read_to_string(&path).unwrap();
    // Both wheels lose their <inertial>: each is a frame that moves.
    let stripped = regex_free_strip(&text, "wheel_left_link");
    let stripped = regex_free_strip(&stripped, "wheel_right_link");
    std::fs::write(&path, stripped).unwrap();
    let sc = pocket_bot(
        dir.path(),
        "pkg/urdf/pocket_bot.urdf",
        "packages = { pocket_bot_description = \"pkg\" }",
    );
    let out = cli(dir.path(), &["run", sc.to_str().unwrap(), "--logs", "logs"]);
    refused(
        &out,
        dir.path(),
        &["links `wheel_left_link`, `wheel_right_link` move (child of a non-fixed joint) but"],
    );
}

/// `text` with the <inertial> of link `name` removed.
fn regex_free_strip(text: &str, name: &str) -> String {
    let start = text.find(&format!("<link name=\"{name}\">")).unwrap();
    let a = start + text[start..].find("<inertial>").unwrap();
    let b = a + text[a..].find("</inertial>").unwrap() + "</inertial>".len();
    format!("{}{}", &text[..a], &text[b..])
}

#[test]
fn meshes_resolve_through_packages_ros_package_path_and_ament_prefix_path() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Three packages, one found each way.
    let put = |p: &Path| {
        std::fs::create_dir_all(p.join("meshes")).unwrap();
        std::fs::write(p.join("meshes/m.stl"), b"x").unwrap();
    };
    put(&d.join("mine"));
    put(&d.join("ros/other"));
    put(&d.join("prefix/share/third"));
    put(&d.join("ros_self/selfpkg"));
    let s = Search {
        packages: [("mine".to_string(), d.join("mine"))].into(),
        ros_package_path: vec![d.join("ros"), d.join("ros_self/selfpkg")],
        ament_prefix_path: vec![d.join("prefix")],
        ..Default::default()
    };
    let here = Path::new("/nowhere");
    assert_eq!(
        s.resolve("package://mine/meshes/m.stl", here).unwrap(),
        d.join("mine/meshes/m.stl")
    );
    assert_eq!(
        s.resolve("package://other/meshes/m.stl", here).unwrap(),
        d.join("ros/other/meshes/m.stl")
    );
    assert_eq!(
        s.resolve("package://selfpkg/meshes/m.stl", here).unwrap(),
        d.join("ros_self/selfpkg/meshes/m.stl")
    );
    assert_eq!(
        s.resolve("package://third/meshes/m.stl", here).unwrap(),
        d.join("prefix/share/third/meshes/m.stl")
    );
    let file = format!("file://{}", d.join("mine/meshes/m.stl").display());
    assert_eq!(s.resolve(&file, here).unwrap(), d.join("mine/meshes/m.stl"));
    assert_eq!(
        s.resolve("meshes/m.stl", &d.join("mine")).unwrap(),
        d.join("mine/meshes/m.stl")
    );
    // [model] packages first: a package in both places is the scenario's.
    put(&d.join("ros/mine"));
    assert_eq!(
        s.resolve("package://mine/meshes/m.stl", here).unwrap(),
        d.join("mine/meshes/m.stl")
    );
    let e = s
        .resolve("package://nope/meshes/m.stl", here)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("package `nope`") && e.contains("ROS_PACKAGE_PATH"),
        "{e}"
    );

    // Through the environment, end to end: the example's package found by
    // ROS_PACKAGE_PATH and by AMENT_PREFIX_PATH, without [model] packages.
    let sc = pocket_bot(
        d,
        &example("ros_robot/pocket_bot_description/urdf/pocket_bot.urdf")
            .display()
            .to_string(),
        "",
    );
    let share = d.join("ament/share");
    std::fs::create_dir_all(&share).unwrap();
    std::os::unix::fs::symlink(
        example("ros_robot/pocket_bot_description"),
        share.join("pocket_bot_description"),
    )
    .unwrap();
    for (var, value) in [
        ("ROS_PACKAGE_PATH", example("ros_robot")),
        ("AMENT_PREFIX_PATH", d.join("ament")),
    ] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
            .current_dir(d)
            .env(var, &value)
            .args(["plan", sc.to_str().unwrap(), "--json"])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{var}: {stderr}");
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        let warnings = v["read_from_urdf"]["warnings"].to_string();
        assert!(!warnings.contains("mesh"), "{var}: {warnings}");
    }
    // Without either, the visual meshes are left out with a warning (the
    // lidar's collision mesh made a cylinder: a collision mesh must be found).
    let pkg = copy_package(d);
    let urdf = pkg.join("urdf/pocket_bot.urdf");
    let text = std::fs::read_to_string(&urdf).unwrap().replace(
        "<collision>\n      <geometry>\n        <mesh filename=\"package://pocket_bot_description/meshes/lidar.stl\"/>",
        "<collision>\n      <geometry>\n        <cylinder radius=\"0.035\" length=\"0.03\"/>",
    );
    std::fs::write(&urdf, text).unwrap();
    let sc = pocket_bot(d, "pkg/urdf/pocket_bot.urdf", "");
    let out = cli(d, &["plan", sc.to_str().unwrap(), "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let warnings = v["read_from_urdf"]["warnings"].to_string();
    assert!(
        warnings.contains("visual mesh") && warnings.contains("drawn without it"),
        "{warnings}"
    );
}

#[test]
fn bad_meshes_are_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let pkg = copy_package(dir.path());
    let urdf = pkg.join("urdf/pocket_bot.urdf");
    let text = std::fs::read_to_string(&urdf).unwrap();
    // The lidar's collision mesh: missing, unknown format, truncated.
    let lidar = "package://pocket_bot_description/meshes/lidar.stl\"/>\n      </geometry>\n    </collision>";
    assert!(text.contains(lidar));
    let cases: [(&str, &str, &str); 3] = [
        ("missing.stl", "", "collision mesh: `package://pocket_bot_description/meshes/missing.stl`: no file `meshes/missing.stl` in package `pocket_bot_description`"),
        ("lidar.ply", "ply\n", "unknown mesh format `.ply`"),
        ("cut.stl", "", "binary STL whose header counts 320 triangles"),
    ];
    let stl = std::fs::read(pkg.join("meshes/lidar.stl")).unwrap();
    std::fs::write(pkg.join("meshes/cut.stl"), &stl[..stl.len() / 2]).unwrap();
    for (file, content, needle) in cases {
        if !content.is_empty() {
            std::fs::write(pkg.join("meshes").join(file), content).unwrap();
        }
        let edited = text.replace(lidar, &lidar.replace("lidar.stl", file));
        std::fs::write(&urdf, edited).unwrap();
        let sc = pocket_bot(
            dir.path(),
            "pkg/urdf/pocket_bot.urdf",
            "packages = { pocket_bot_description = \"pkg\" }",
        );
        let out = cli(dir.path(), &["run", sc.to_str().unwrap(), "--logs", "logs"]);
        refused(&out, dir.path(), &[needle]);
    }
    // A package that nothing resolves, for a collision mesh: exit 2 naming it.
    std::fs::write(&urdf, &text).unwrap();
    let sc = pocket_bot(dir.path(), "pkg/urdf/pocket_bot.urdf", "");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .current_dir(dir.path())
        .env_remove("ROS_PACKAGE_PATH")
        .env_remove("AMENT_PREFIX_PATH")
        .args(["run", sc.to_str().unwrap(), "--logs", "logs"])
        .output()
        .unwrap();
    refused(&out, dir.path(), &["package `pocket_bot_description`"]);
}

fn xacro_scenario(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(example("ros_robot/pocket_bot_xacro.toml")).unwrap();
    let ex = example("ros_robot");
    let text = text
        .replace(
            "\"pocket_bot_description",
            &format!("\"{}/pocket_bot_description", ex.display()),
        )
        .replace(
            "\"s_curve.csv\"",
            &format!("\"{}/s_curve.csv\"", ex.display()),
        );
    let p = dir.join("x.toml");
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn xacro_without_the_xacro_command_is_refused_naming_it() {
    let dir = tempfile::tempdir().unwrap();
    let sc = xacro_scenario(dir.path());
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .current_dir(dir.path())
        .env("PATH", python::path_without_xacro())
        .args(["run", sc.to_str().unwrap(), "--logs", "logs"])
        .output()
        .unwrap();
    refused(
        &out,
        dir.path(),
        &["holds xacro markup (xacro elements): install the `xacro` command"],
    );
}

#[test]
fn xacro_is_expanded_when_the_command_is_there() {
    // `xacro` from PATH, or from the test venv (made once with pip).
    let dir = tempfile::tempdir().unwrap();
    let sc = xacro_scenario(dir.path());
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .current_dir(dir.path())
        .env("PATH", python::path_with_xacro())
        .args(["plan", sc.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let r = &v["read_from_urdf"];
    // The prefix argument reached every name.
    assert_eq!(r["bodies"][0]["link"], "pb_base_link");
    assert_eq!(r["wheels"][0]["joint"], "pb_wheel_left_joint");
    assert!(r["notes"].to_string().contains("xacro"), "{r}");
}

#[test]
fn cylinder_wheels_roll_without_sideways_slip_on_random_arcs() {
    // Arcs nobody tuned: 6 seeded plans of 4 arcs each, |v| ≤ 0.3 m/s,
    // |ω| ≤ 1.5 rad/s, ramped (linear hold), on the example's cylinder wheels.
    use rand::{Rng, SeedableRng};
    let dir = tempfile::tempdir().unwrap();
    let ex = example("ros_robot");
    let mut worst: f64 = 0.0;
    for seed in 0..6u64 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let mut csv = String::from("t,v,omega\n0,0,0\n");
        let mut t = 0.0;
        for _ in 0..4 {
            let (v, w) = (rng.random_range(-0.3..0.3), rng.random_range(-1.5..1.5));
            let hold = rng.random_range(1.0..3.0);
            csv += &format!("{},{v},{w}\n{},{v},{w}\n", t + 1.0, t + 1.0 + hold);
            t += 1.0 + hold;
        }
        csv += &format!("{},0,0\n", t + 1.0);
        std::fs::write(dir.path().join("arcs.csv"), csv).unwrap();
        let text = std::fs::read_to_string(ex.join("pocket_bot_plan.toml"))
            .unwrap()
            .replace(
                "\"pocket_bot_description",
                &format!("\"{}/pocket_bot_description", ex.display()),
            )
            .replace("\"s_curve.csv\"", "\"arcs.csv\"");
        // Only the slip is asked here (the goal is wherever the arcs end).
        let text = text[..text.find("[thresholds]").unwrap()].to_string();
        let sc = dir.path().join(format!("arcs{seed}.toml"));
        std::fs::write(&sc, text).unwrap();
        let o = run_file(&sc, None);
        let lat = o.metric("slip_lateral_max").unwrap();
        worst = worst.max(lat);
    }
    assert!(worst < 0.005, "lateral slip {worst} m/s on cylinder wheels");
}

#[test]
fn the_summary_says_what_was_read_from_the_urdf() {
    let dir = tempfile::tempdir().unwrap();
    let ex = example("ros_robot/pocket_bot_plan.toml");
    let prep = prepared(&ex);
    let o = run_prepared(&prep, Some(dir.path()));
    assert!(o.passed, "{:?}", o.failures);
    let s: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path().join("pocket_bot_plan/summary.json")).unwrap(),
    )
    .unwrap();
    let r = &s["model"]["read_from_urdf"];
    assert_eq!(s["model"]["kind"], "diff_drive");
    // Bodies: the frames and fixed parts in base_link's, 2 + 0.02 + 0.12 kg.
    assert_eq!(r["bodies"][0]["link"], "base_link");
    assert!((r["bodies"][0]["mass"].as_f64().unwrap() - 2.14).abs() < 1e-12);
    let lumped = r["bodies"][0]["lumped"].to_string();
    for l in [
        "base_footprint",
        "imu_link",
        "camera_optical_frame",
        "caster_back_link",
        "base_scan",
    ] {
        assert!(lumped.contains(l), "{l}: {lumped}");
    }
    assert_eq!(r["bodies"].as_array().unwrap().len(), 3);
    assert_eq!(r["wheels"][0]["radius"], 0.04);
    assert_eq!(r["wheels"][0]["shape"], "cylinder");
    assert_eq!(r["geometry"][0][0], "track_m");
    assert!((r["geometry"][0][1][0].as_f64().unwrap() - 0.2).abs() < 1e-12);
    // The scenario sets [sim] motor_max_torque: the cap is its choice, no warning.
    assert_eq!(r["drives"][0]["source"], "scenario");
    assert_eq!(r["drives"][0]["torque_limit"], 0.5);
    assert!(!r["warnings"].to_string().contains("limit effort"), "{r}");
    // The report says the same.
    let out = cli(dir.path(), &["report", dir.path().to_str().unwrap()]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let html = std::fs::read_to_string(dir.path().join("pocket_bot_plan/report.html")).unwrap();
    assert!(html.contains("Robot as read from the URDF"));
    assert!(html.contains("[sim] motor_max_torque"));
    assert!(!html.contains("gives no &lt;limit effort&gt;"));
    assert!(
        html.contains("caster_back_link, imu_link"),
        "lumped links listed"
    );
}

#[test]
fn casters_of_any_shape_are_checked_against_the_wheels_plane() {
    let dir = tempfile::tempdir().unwrap();
    let pkg = copy_package(dir.path());
    let urdf = pkg.join("urdf/pocket_bot.urdf");
    let text = std::fs::read_to_string(&urdf).unwrap();
    // The box caster 5 mm too high: it would tip the robot.
    let edited = text.replace(
        "<origin xyz=\"-0.16 0 -0.03\"",
        "<origin xyz=\"-0.16 0 -0.025\"",
    );
    assert_ne!(edited, text);
    std::fs::write(&urdf, edited).unwrap();
    let sc = pocket_bot(
        dir.path(),
        "pkg/urdf/pocket_bot.urdf",
        "packages = { pocket_bot_description = \"pkg\" }",
    );
    let out = cli(dir.path(), &["run", sc.to_str().unwrap(), "--logs", "logs"]);
    refused(
        &out,
        dir.path(),
        &["`caster_back_link`: the lowest point of its box collision is 0.0050 m above"],
    );
}

#[test]
fn the_published_style_and_skid_steer_examples_keep_their_verdicts() {
    use anholonomy::verdict::Verdict;
    for (f, want) in [
        ("ros_robot/pocket_bot_plan.toml", Verdict::Pass),
        // Open loop, the skid steer turns 31° short: the expected failure.
        ("skid_steer/skid_steer_plan.toml", Verdict::Xfail),
    ] {
        let o = run_file(&example(f), None);
        assert_eq!(o.verdict, want, "{f}: {:?}", o.failures);
    }
}

/// A makers' description package, fetched outside the project (never
/// committed), run unmodified.
struct Maker {
    /// Its directory under `ANHOLONOMY_PUBLISHED`.
    dir: &'static str,
    /// The description, relative to `dir`.
    urdf: &'static str,
    /// Left and right wheel joints.
    left: &'static [&'static str],
    right: &'static [&'static str],
    casters: &'static str,
    /// Packages its xacro looks up that the fetch does not hold.
    absent: &'static [&'static str],
    /// Goal (x m, y m, heading deg) and gates (m, deg).
    goal: [f64; 3],
    gates: [f64; 2],
    /// Whether the go-to-pose law must pass in physics.
    passes: bool,
}

const MAKERS: &[Maker] = &[
    Maker {
        dir: "turtlebot3-2.2.6",
        urdf: "turtlebot3_description/urdf/turtlebot3_burger.urdf",
        left: &["wheel_left_joint"],
        right: &["wheel_right_joint"],
        casters: "[\"caster_back_link\"]",
        absent: &[],
        goal: [1.0, 0.6, 90.0],
        gates: [0.012, 1.2],
        passes: true,
    },
    Maker {
        dir: "turtlebot3-main",
        urdf: "turtlebot3_description/urdf/turtlebot3_burger.urdf",
        left: &["wheel_left_joint"],
        right: &["wheel_right_joint"],
        casters: "[\"caster_back_link\"]",
        absent: &[],
        goal: [1.0, 0.6, 90.0],
        gates: [0.012, 1.2],
        passes: true,
    },
    Maker {
        dir: "husky-noetic",
        urdf: "husky_description/urdf/husky.urdf.xacro",
        left: &["front_left_wheel", "rear_left_wheel"],
        right: &["front_right_wheel", "rear_right_wheel"],
        casters: "[]",
        absent: &[
            "fath_pivot_mount_description",
            "flir_camera_description",
            "lms1xx",
            "velodyne_description",
        ],
        goal: [1.5, 1.0, 90.0],
        gates: [0.02, 2.0],
        passes: true,
    },
    Maker {
        dir: "husky-humble",
        urdf: "husky_description/urdf/husky.urdf.xacro",
        left: &["front_left_wheel_joint", "rear_left_wheel_joint"],
        right: &["front_right_wheel_joint", "rear_right_wheel_joint"],
        casters: "[]",
        absent: &["husky_control"],
        goal: [1.5, 1.0, 90.0],
        gates: [0.02, 2.0],
        passes: true,
    },
    // Loads unmodified; under this law it circles 3-4 cm from the goal
    // (docs/src/own-robot.md, "Description packages as published").
    Maker {
        dir: "jackal-noetic",
        urdf: "jackal_description/urdf/jackal.urdf.xacro",
        left: &["front_left_wheel", "rear_left_wheel"],
        right: &["front_right_wheel", "rear_right_wheel"],
        casters: "[]",
        absent: &[
            "sick_tim",
            "lms1xx",
            "velodyne_description",
            "pointgrey_camera_description",
            "flir_camera_description",
        ],
        goal: [1.5, 1.0, 90.0],
        gates: [0.02, 2.0],
        passes: false,
    },
];

/// The makers' own description packages, as fetched from their public
/// repositories into `$ANHOLONOMY_PUBLISHED` (docs/src/own-robot.md says
/// how): each expanded by xacro as published (absent accessory packages
/// first named, then expanded to nothing), read as `diff_drive` on two or
/// four wheel joints, and driven to a pose by the go-to-pose law in physics.
#[test]
#[ignore = "needs the makers' packages: ANHOLONOMY_PUBLISHED=DIR cargo test --release --test it -- --ignored published_robots::makers_packages"]
fn makers_packages() {
    let root_dir = std::env::var_os("ANHOLONOMY_PUBLISHED").map(PathBuf::from).expect(
        "set ANHOLONOMY_PUBLISHED to the directory the makers' packages were fetched into (docs/src/own-robot.md)",
    );
    crate::xacro_packages::assert_no_ros_python();
    let law = example("diff_drive_law/law.py");
    let path = python::path_with_xacro();
    let work = tempfile::tempdir().unwrap();
    let mut report = Vec::new();
    for m in MAKERS {
        let urdf = root_dir.join(m.dir).join(m.urdf);
        assert!(urdf.is_file(), "{}: not fetched", urdf.display());
        let list = |js: &[&str]| {
            js.iter()
                .map(|j| format!("\"{j}\""))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let [gx, gy, gth] = m.goal;
        let scenario = |name: &str, extra: &str| {
            format!(
                r#"name = "{name}"
start = [0.0, 0.0, 0.0]
goal = [{gx:?}, {gy:?}, {gth:?}]
[model]
kind = "diff_drive"
urdf = "{}"
left_wheel_joints = [{}]
right_wheel_joints = [{}]
caster_links = {}
{extra}
[planner]
kind = "external"
command = ["python3", "{}", "{gx:?}", "{gy:?}", "{gth:?}"]
period = 0.05
horizon = 60.0
[sim]
dt = 0.001
friction = 0.8
settle = 0.5
[thresholds]
ideal_goal_position = 0.01
ideal_goal_theta_deg = 1.0
sim_goal_position = {:?}
sim_goal_theta_deg = {:?}
"#,
                urdf.display(),
                list(m.left),
                list(m.right),
                m.casters,
                law.display(),
                m.gates[0],
                m.gates[1]
            )
        };
        let run = |file: &str, text: String| {
            let sc = work.path().join(file);
            std::fs::write(&sc, text).unwrap();
            std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
                .current_dir(work.path())
                .env("PATH", &path)
                .env_remove("ROS_PACKAGE_PATH")
                .env_remove("AMENT_PREFIX_PATH")
                .args(["run", file, "--logs", "logs", "--quiet"])
                .output()
                .unwrap()
        };
        let name = m.dir.replace(['-', '.'], "_");
        // Absent packages: all named in one message, by default.
        if !m.absent.is_empty() {
            let out = run(
                &format!("{name}_strict.toml"),
                scenario(&format!("{name}_strict"), ""),
            );
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{}: {err}", m.dir);
            assert_eq!(err.lines().count(), 1, "{err}");
            for p in m.absent {
                assert!(
                    err.contains(&format!("`{p}` (in ")),
                    "{}: `{p}` not named: {err}",
                    m.dir
                );
            }
        }
        let extra = if m.absent.is_empty() {
            ""
        } else {
            "missing_packages = \"empty\""
        };
        let out = run(&format!("{name}.toml"), scenario(&name, extra));
        let err = String::from_utf8_lossy(&out.stderr).into_owned();
        let summary = work.path().join("logs").join(&name).join("summary.json");
        let s: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(&summary)
                .unwrap_or_else(|e| panic!("{}: {e}; stderr: {err}", m.dir)),
        )
        .unwrap();
        let r = &s["model"]["read_from_urdf"];
        assert_eq!(
            r["wheels"].as_array().map(Vec::len),
            Some(m.left.len() + m.right.len()),
            "{}: {r}",
            m.dir
        );
        let absent_warned = err
            .lines()
            .filter(|l| l.contains("xacro found no package"))
            .count();
        assert_eq!(
            absent_warned,
            usize::from(!m.absent.is_empty()),
            "{}: {err}",
            m.dir
        );
        let metric = |k: &str| s["metrics"][k].as_f64().unwrap_or(f64::NAN);
        report.push(format!(
            "{:<18} {:>8} sim_goal_position {:.4} m, sim_goal_theta_deg {:.2}, slip_lateral_max {:.4} m/s",
            m.dir,
            s["verdict"].as_str().unwrap_or("?"),
            metric("sim_goal_position"),
            metric("sim_goal_theta_deg"),
            metric("slip_lateral_max"),
        ));
        if m.passes {
            assert_eq!(
                s["verdict"], "PASS",
                "{}: {:?}; stderr: {err}",
                m.dir, s["failures"]
            );
        }
    }
    eprintln!("{}", report.join("\n"));
}
