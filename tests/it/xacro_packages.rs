//! Description packages as makers publish them, reproduced on small
//! packages this project writes (so CI, which fetches nothing, still fails
//! when a mechanism breaks): a commented-out xacro include, `$(find
//! own_pkg)` includes found through the package's own `package.xml`,
//! `package://` meshes, accessories including packages that are absent,
//! and xacro's own errors (a syntax error, an undefined property, a missing
//! argument). xacro is the `xacro` command from PyPI (`python::path_with_xacro`:
//! the test venv when `PATH` has none), with no ROS Python module.

use crate::common::*;
use std::path::{Path, PathBuf};
use std::process::Output;

/// The package's name.
pub const PKG: &str = "own_bot_description";

/// The two packages its accessories include, which nobody has.
pub const ABSENT: [&str; 2] = ["acme_lidar_description", "acme_camera_description"];

const WHEEL: &str = r#"<?xml version="1.0"?>
<robot xmlns:xacro="http://ros.org/wiki/xacro">
  <xacro:macro name="wheel" params="side y">
    <joint name="wheel_${side}_joint" type="continuous">
      <parent link="base_link"/>
      <child link="wheel_${side}_link"/>
      <origin xyz="0 ${y} 0" rpy="${-pi/2} 0 0"/>
      <axis xyz="0 0 1"/>
    </joint>
    <link name="wheel_${side}_link">
      <visual>
        <geometry><mesh filename="package://own_bot_description/meshes/wheel.stl"/></geometry>
      </visual>
      <collision>
        <geometry><cylinder radius="${wheel_radius}" length="0.02"/></geometry>
      </collision>
      <inertial>
        <mass value="0.1"/>
        <inertia ixx="0.0000433" ixy="0" ixz="0" iyy="0.0000433" iyz="0" izz="0.00008"/>
      </inertial>
    </link>
  </xacro:macro>
</robot>
"#;

/// Accessories of both absent packages, included whether or not they are
/// switched on (as published accessory files do); their macros are used
/// only when `lidar` is.
const ACCESSORIES: &str = r#"<?xml version="1.0"?>
<robot xmlns:xacro="http://ros.org/wiki/xacro">
  <xacro:include filename="$(find acme_lidar_description)/urdf/lidar.urdf.xacro"/>
  <xacro:include filename="$(find acme_camera_description)/urdf/camera.urdf.xacro"/>
  <xacro:if value="$(arg lidar)">
    <xacro:acme_lidar parent="base_link"/>
  </xacro:if>
</robot>
"#;

/// The robot: `ACCESSORIES_LINE` is where the accessories are included.
const ROBOT: &str = r#"<?xml version="1.0"?>
<robot name="own_bot" xmlns:xacro="http://ros.org/wiki/xacro">
  <!-- <xacro:include filename="$(find old_common_description)/urdf/common.urdf.xacro"/> -->
  <xacro:arg name="lidar" default="false"/>
  <xacro:property name="wheel_radius" value="0.04"/>
  <xacro:include filename="$(find own_bot_description)/urdf/wheel.urdf.xacro"/>
  ACCESSORIES_LINE

  <link name="base_footprint"/>
  <joint name="base_joint" type="fixed">
    <parent link="base_footprint"/>
    <child link="base_link"/>
    <origin xyz="0 0 ${wheel_radius}"/>
  </joint>
  <link name="base_link">
    <visual>
      <origin xyz="-0.04 0 0"/>
      <geometry><mesh filename="package://own_bot_description/meshes/base.stl"/></geometry>
    </visual>
    <collision>
      <origin xyz="-0.04 0 0.035"/>
      <geometry><box size="0.24 0.18 0.07"/></geometry>
    </collision>
    <inertial>
      <origin xyz="-0.04 0 0.035"/>
      <mass value="2.0"/>
      <inertia ixx="0.0062167" ixy="0" ixz="0" iyy="0.0104167" iyz="0" izz="0.015"/>
    </inertial>
  </link>
  <xacro:wheel side="left" y="0.10"/>
  <xacro:wheel side="right" y="-0.10"/>
  <joint name="caster_back_joint" type="fixed">
    <parent link="base_link"/>
    <child link="caster_back_link"/>
    <origin xyz="-0.16 0 ${-wheel_radius + 0.01}"/>
  </joint>
  <link name="caster_back_link">
    <collision><geometry><box size="0.03 0.03 0.02"/></geometry></collision>
    <inertial>
      <mass value="0.02"/>
      <inertia ixx="0.000002" ixy="0" ixz="0" iyy="0.000002" iyz="0" izz="0.000003"/>
    </inertial>
  </link>
</robot>
"#;

/// The files of the package under `dir/own_bot_description/` (its name,
/// text or bytes): with the accessories include or without.
pub fn package_files(accessories: bool) -> Vec<(String, Vec<u8>)> {
    let line = if accessories {
        r#"<xacro:include filename="$(find own_bot_description)/urdf/accessories.urdf.xacro"/>"#
    } else {
        ""
    };
    let meshes = root().join("examples/ros_robot/pocket_bot_description/meshes");
    let mut out = vec![
        (
            format!("{PKG}/package.xml"),
            format!("<?xml version=\"1.0\"?>\n<package format=\"3\">\n  <name>{PKG}</name>\n  <version>0.1.0</version>\n  <description>A test robot</description>\n  <license>MIT</license>\n</package>\n").into_bytes(),
        ),
        (format!("{PKG}/urdf/wheel.urdf.xacro"), WHEEL.into()),
        (format!("{PKG}/urdf/accessories.urdf.xacro"), ACCESSORIES.into()),
        (
            format!("{PKG}/urdf/own_bot.urdf.xacro"),
            ROBOT.replace("ACCESSORIES_LINE", line).into_bytes(),
        ),
    ];
    for m in ["wheel.stl", "base.stl"] {
        out.push((
            format!("{PKG}/meshes/{m}"),
            std::fs::read(meshes.join(m)).unwrap(),
        ));
    }
    out
}

/// The package written in `dir`; the path of its URDF.
fn write_package(dir: &Path, accessories: bool) -> PathBuf {
    for (name, bytes) in package_files(accessories) {
        let f = dir.join(name);
        std::fs::create_dir_all(f.parent().unwrap()).unwrap();
        std::fs::write(f, bytes).unwrap();
    }
    dir.join(PKG).join("urdf/own_bot.urdf.xacro")
}

/// A diff_drive scenario of the URDF at `urdf` (relative to `dir`) driven
/// to a pose by the go-to-pose law, with `model_extra` in `[model]`.
pub fn law_scenario(urdf: &str, model_extra: &str) -> String {
    let law = root().join("examples/diff_drive_law/law.py");
    format!(
        r#"start = [0.0, 0.0, 0.0]
goal = [1.0, 0.6, 90.0]

[model]
kind = "diff_drive"
urdf = "{urdf}"
left_wheel_joint = "wheel_left_joint"
right_wheel_joint = "wheel_right_joint"
caster_links = ["caster_back_link"]
{model_extra}

[planner]
kind = "external"
command = ["python3", "{}", "1.0", "0.6", "90"]
period = 0.05
horizon = 60.0

[sim]
dt = 0.001
friction = 0.8
settle = 0.5
motor_max_torque = 0.5

[thresholds]
ideal_goal_position = 0.01
ideal_goal_theta_deg = 1.0
sim_goal_position = 0.012
sim_goal_theta_deg = 1.2
"#,
        law.display()
    )
}

/// Run the binary in `dir` with `PATH` = `path` and no ROS package paths.
fn anholonomy(dir: &Path, path: &std::ffi::OsStr, args: &[&str]) -> Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .current_dir(dir)
        .env("PATH", path)
        .env_remove("ROS_PACKAGE_PATH")
        .env_remove("AMENT_PREFIX_PATH")
        .args(args)
        .output()
        .unwrap()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `plan --json` of `scenario` in `dir`: what was read from the URDF.
fn read_from_urdf(dir: &Path, path: &std::ffi::OsStr, scenario: &str) -> serde_json::Value {
    std::fs::write(dir.join("case.toml"), scenario).unwrap();
    let out = anholonomy(dir, path, &["plan", "case.toml", "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["read_from_urdf"].clone()
}

/// exit 2 with one `error:` line holding every needle; no log written.
fn refused(dir: &Path, path: &std::ffi::OsStr, scenario: &str, needles: &[&str]) -> String {
    std::fs::write(dir.join("case.toml"), scenario).unwrap();
    let out = anholonomy(dir, path, &["run", "case.toml", "--logs", "refused_logs"]);
    let err = stderr(&out);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: "), "{err}");
    for n in needles {
        assert!(err.contains(n), "`{n}` not in {err}");
    }
    assert!(files_below(&dir.join("refused_logs")).is_empty());
    err
}

/// The venv xacro runs in has xacro and no ROS Python module: `$(find)`
/// is answered by the harness's resolver, nothing else.
pub fn assert_no_ros_python() {
    let path = python::path_with_xacro();
    let xacro = std::env::split_paths(&path)
        .map(|d| d.join("xacro"))
        .find(|p| p.is_file())
        .expect("a xacro command");
    let script = std::fs::read_to_string(&xacro).unwrap();
    let python = script
        .lines()
        .next()
        .and_then(|l| l.strip_prefix("#!"))
        .map(|s| s.trim().to_string())
        .expect("xacro is a Python script");
    let out = std::process::Command::new(&python)
        .args(["-c", "import ament_index_python"])
        .env_remove("PYTHONPATH")
        .output()
        .unwrap();
    assert!(
        !out.status.success(),
        "{python} imports ament_index_python: these tests would not show the harness's resolver at work"
    );
}

#[test]
fn a_commented_xacro_include_is_not_markup() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // The example's plain URDF (the xacro namespace declared, no xacro) as a
    // published one often is: its only xacro a commented-out include.
    let ex = root().join("examples/ros_robot/pocket_bot_description");
    let pkg = d.join("pocket_bot_description");
    for sub in ["urdf", "meshes"] {
        std::fs::create_dir_all(pkg.join(sub)).unwrap();
    }
    for m in ["base.stl", "wheel.stl", "lidar.stl", "camera.stl"] {
        std::fs::copy(ex.join("meshes").join(m), pkg.join("meshes").join(m)).unwrap();
    }
    std::fs::copy(ex.join("package.xml"), pkg.join("package.xml")).unwrap();
    let text = std::fs::read_to_string(ex.join("urdf/pocket_bot.urdf")).unwrap();
    assert!(text.contains("xmlns:xacro=\"http://ros.org/wiki/xacro\""));
    let start = text.find("<robot").unwrap();
    let end = start + text[start..].find('>').unwrap() + 1;
    let text = format!(
        "{}\n  <!-- <xacro:include filename=\"$(find pocket_bot_description)/urdf/common_properties.urdf\"/> -->{}",
        &text[..end],
        &text[end..]
    );
    std::fs::write(pkg.join("urdf/pocket_bot.urdf"), text).unwrap();
    let sc = law_scenario("pocket_bot_description/urdf/pocket_bot.urdf", "");
    // Without xacro: plain URDF, read as it is.
    let r = read_from_urdf(d, &python::path_without_xacro(), &sc);
    assert_eq!(r["wheels"][0]["joint"], "wheel_left_joint");
    assert!(r["notes"].is_null(), "{r}");
    // With it: expanded (xacro keeps the comment, which is no markup).
    let r = read_from_urdf(d, &python::path_with_xacro(), &sc);
    assert!(
        r["notes"].to_string().contains("expanded with xacro"),
        "{r}"
    );
    // The meshes came through the package.xml beside the URDF's directory.
    assert!(!r["warnings"].to_string().contains("mesh"), "{r}");
}

#[test]
fn find_of_its_own_package_resolves_through_its_package_xml_and_runs() {
    assert_no_ros_python();
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_package(d, false);
    let urdf = format!("{PKG}/urdf/own_bot.urdf.xacro");
    let path = python::path_with_xacro();
    // No [model] packages, no ROS environment: the package.xml names it.
    let sc = law_scenario(&urdf, "");
    let r = read_from_urdf(d, &path, &sc);
    assert_eq!(r["wheels"][1]["joint"], "wheel_right_joint");
    assert!(!r["warnings"].to_string().contains("mesh"), "{r}");
    // And the go-to-pose law reaches the pose in physics.
    std::fs::write(d.join("own_bot.toml"), &sc).unwrap();
    let out = anholonomy(d, &path, &["run", "own_bot.toml", "--logs", "logs"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(d.join("logs/own_bot/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(summary["verdict"], "PASS", "{summary}");
    // Without its package.xml, [model] packages names it, and ROS_PACKAGE_PATH does.
    std::fs::remove_file(d.join(PKG).join("package.xml")).unwrap();
    let sc_packages = law_scenario(&urdf, &format!("packages = {{ {PKG} = \"{PKG}\" }}"));
    let r = read_from_urdf(d, &path, &sc_packages);
    assert!(!r["warnings"].to_string().contains("mesh"), "{r}");
    std::fs::write(d.join("case.toml"), &sc).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .current_dir(d)
        .env("PATH", &path)
        .env("ROS_PACKAGE_PATH", d)
        .env_remove("AMENT_PREFIX_PATH")
        .args(["plan", "case.toml"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    // Found nowhere: named, with the file that looks it up.
    refused(
        d,
        &path,
        &sc,
        &[
            "xacro needs 1 ROS package not found",
            "`own_bot_description` (in own_bot.urdf.xacro)",
            "[model] packages = { own_bot_description = \"DIR\" }",
        ],
    );
}

#[test]
fn absent_packages_are_named_together_or_expanded_to_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_package(d, true);
    let urdf = format!("{PKG}/urdf/own_bot.urdf.xacro");
    let path = python::path_with_xacro();
    // Both absent packages in one message, each with the file including it.
    let err = refused(
        d,
        &path,
        &law_scenario(&urdf, ""),
        &[
            "xacro needs 2 ROS packages not found",
            "`acme_lidar_description` (in accessories.urdf.xacro)",
            "`acme_camera_description` (in accessories.urdf.xacro)",
            "missing_packages = \"empty\"",
        ],
    );
    assert!(
        err.contains(&format!("{}:", d.join(&urdf).display())) || err.contains(&urdf),
        "{err}"
    );
    // Expanded to nothing: the robot loads, one warning names both.
    let sc = law_scenario(&urdf, "missing_packages = \"empty\"");
    let r = read_from_urdf(d, &path, &sc);
    let warnings: Vec<String> = r["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap().to_string())
        .collect();
    let about: Vec<&String> = warnings
        .iter()
        .filter(|w| ABSENT.iter().any(|p| w.contains(p)))
        .collect();
    assert_eq!(about.len(), 1, "{warnings:?}");
    assert!(
        about[0].contains("xacro found no packages `acme_lidar_description`")
            && about[0].contains("`acme_camera_description` (in accessories.urdf.xacro)"),
        "{}",
        about[0]
    );
    // Switched on, the accessory's macro is missing: xacro's own error,
    // with the absent packages noted.
    let sc = law_scenario(
        &urdf,
        "missing_packages = \"empty\"\nxacro_args = { lidar = \"true\" }",
    );
    refused(
        d,
        &path,
        &sc,
        &[
            "xacro failed: unknown macro name: xacro:acme_lidar",
            "(absent packages expanded to nothing: `acme_lidar_description`, `acme_camera_description`)",
        ],
    );
}

#[test]
fn xacro_errors_carry_xacros_first_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let urdf_path = write_package(d, false);
    let urdf = format!("{PKG}/urdf/own_bot.urdf.xacro");
    let path = python::path_with_xacro();
    let good = std::fs::read_to_string(&urdf_path).unwrap();
    let cases: [(&str, &str, &[&str]); 3] = [
        (
            "<xacro:wheel side=\"left\" y=\"0.10\"/>",
            "<xacro:wheel side=\"left\" y=\"${nope}\"/>",
            &[
                "xacro failed: name 'nope' is not defined",
                "when evaluating expression 'nope'",
            ],
        ),
        (
            "<link name=\"base_footprint\"/>",
            "<link name=\"$(arg frame_prefix)base_footprint\"/>",
            &[
                "xacro failed: Undefined substitution argument frame_prefix",
                "in ",
            ],
        ),
        (
            "<link name=\"base_footprint\"/>",
            "<link name=\"base_footprint\">",
            &["xacro failed: XML parsing error: mismatched tag"],
        ),
    ];
    for (from, to, needles) in cases {
        assert!(good.contains(from));
        std::fs::write(&urdf_path, good.replacen(from, to, 1)).unwrap();
        let err = refused(d, &path, &law_scenario(&urdf, ""), needles);
        assert!(!err.contains("when processing file"), "{err}");
    }
}
