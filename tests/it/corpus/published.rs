//! Robots and recordings as their makers publish them, gone wrong: a
//! description package including two packages nobody has, xacro's own
//! errors (a syntax error, an undefined property, a missing argument), a
//! ROS 1 bag, a sqlite3 bag file that is no database, a plan CSV of numpy
//! reprs and a steering-angle column for a car steered by rate. The xacro
//! cases run with the `xacro` command on `PATH` ([`Special::XacroOnPath`]).

use super::*;
use crate::xacro_packages::{package_files, PKG};

const URDF: &str = "own_bot_description/urdf/own_bot.urdf.xacro";

/// A diff_drive scenario of the test package, planning from `s_curve.csv`.
fn own_bot_scenario(model_extra: &str) -> String {
    format!(
        r#"name = "own_bot"
start = [0.0, 0.0, 0.0]
goal = [0.0, 0.0, 0.0]

[model]
kind = "diff_drive"
urdf = "{URDF}"
left_wheel_joint = "wheel_left_joint"
right_wheel_joint = "wheel_right_joint"
caster_links = ["caster_back_link"]
{model_extra}

[planner]
kind = "file"
path = "s_curve.csv"

[sim]
dt = 0.001
motor_max_torque = 0.5
"#
    )
}

/// The test package (with its accessories or not), `edit` made to the
/// robot's xacro, a scenario; the error names `URDF` and starts with `what`.
fn xacro_case(c: &mut Corpus, name: &str, accessories: bool, edit: (&str, &str), what: &str) {
    let mut files = package_files(accessories);
    let robot = format!("{PKG}/urdf/own_bot.urdf.xacro");
    for (n, bytes) in &mut files {
        if *n == robot {
            let text = String::from_utf8(bytes.clone()).unwrap();
            *bytes = super::edit(&text, edit.0, edit.1).into_bytes();
        }
    }
    files.push(("case.toml".into(), own_bot_scenario("").into_bytes()));
    files.push((
        "s_curve.csv".into(),
        std::fs::read(root().join("examples/ros_robot/s_curve.csv")).unwrap(),
    ));
    c.raw(Case {
        name: name.into(),
        files,
        special: vec![Special::XacroOnPath],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: URDF.into(),
            line: None,
            key: Some(what.into()),
        }],
    });
}

pub fn cases(c: &mut Corpus) {
    let nothing = (
        "<xacro:arg name=\"lidar\" default=\"false\"/>",
        "<xacro:arg name=\"lidar\" default=\"false\"/>",
    );
    xacro_case(
        c,
        "xacro two absent packages",
        true,
        nothing,
        "xacro needs 2 ROS packages not found in [model] packages, the package.xml above the URDF, ROS_PACKAGE_PATH or AMENT_PREFIX_PATH: `acme_lidar_description` (in accessories.urdf.xacro), `acme_camera_description` (in accessories.urdf.xacro)",
    );
    xacro_case(
        c,
        "xacro syntax error",
        false,
        (
            "<link name=\"base_footprint\"/>",
            "<link name=\"base_footprint\">",
        ),
        "xacro failed: XML parsing error: mismatched tag",
    );
    xacro_case(
        c,
        "xacro undefined property",
        false,
        ("y=\"0.10\"", "y=\"${nope}\""),
        "xacro failed: name 'nope' is not defined (when evaluating expression 'nope'",
    );
    xacro_case(
        c,
        "xacro missing argument",
        false,
        (
            "<link name=\"base_footprint\"/>",
            "<link name=\"$(arg frame_prefix)base_footprint\"/>",
        ),
        "xacro failed: Undefined substitution argument frame_prefix",
    );

    // A ROS 1 bag: refused at `path`, with the command that converts it.
    let mut text = super::ros_bags::bag_scenario("drive.bag", "", "");
    let line = line_of(&text, "path =");
    c.raw(Case {
        name: "ROS 1 bag".into(),
        files: vec![
            ("case.toml".into(), std::mem::take(&mut text).into_bytes()),
            ("drive.bag".into(), b"#ROSBAG V2.0\n".to_vec()),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "case.toml".into(),
            line: Some(line),
            key: Some("key `planner.path`: drive.bag: a ROS 1 bag, which is not read here: convert it to a ROS 2 bag without ROS, `pip install rosbags` then `rosbags-convert --src drive.bag --dst drive_ros2`".into()),
        }],
    });
    // A sqlite3 bag whose file is not a database.
    let meta = std::fs::read(root().join("tests/data/ros_bags/sqlite3/metadata.yaml")).unwrap();
    c.raw(Case {
        name: "bag sqlite3 file not a database".into(),
        files: vec![
            (
                "case.toml".into(),
                super::ros_bags::bag_scenario("sqlite3", "", "").into_bytes(),
            ),
            ("sqlite3/metadata.yaml".into(), meta),
            ("sqlite3/sqlite3.db3".into(), vec![b'x'; 4096]),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "sqlite3/sqlite3.db3".into(),
            line: None,
            key: Some("not a readable sqlite3 bag file".into()),
        }],
    });

    // numpy 2 reprs in a plan CSV.
    let d = disk();
    c.raw(Case {
        name: "plan csv of numpy reprs".into(),
        files: vec![
            (
                "case.toml".into(),
                super::own_plan::file_scenario(&d, "plan.csv").into_bytes(),
            ),
            (
                "plan.csv".into(),
                b"t,theta_rate,alpha_rate\nnp.float64(0.0),np.float64(0.5),np.float64(0.0)\nnp.float64(1.0),np.float64(0.0),np.float64(0.0)\n".to_vec(),
            ),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "plan.csv".into(),
            line: Some(2),
            key: Some("column `t`: `np.float64(0.0)` is not a number (numpy's repr of a scalar: write plain numbers, `float(x)` for each value or `array.tolist()` before writing)".into()),
        }],
    });

    // A steering-angle column for a car steered by rate.
    let car = format!(
        r#"name = "car"
start = [0.0, 0.0, 0.0, 0.0]
goal = [0.0, 0.0, 0.0, 0.0]

[model]
kind = "car"
urdf = "{}"

[planner]
kind = "file"
path = "steer.csv"

[sim]
dt = 0.001
"#,
        model("car.urdf").display()
    );
    c.raw(Case {
        name: "plan csv steer column on a rate-steered car".into(),
        files: vec![
            ("case.toml".into(), car.into_bytes()),
            ("steer.csv".into(), b"t,v,steer\n0,0.5,0.1\n1,0,0\n".to_vec()),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "steer.csv".into(),
            line: Some(1),
            key: Some("column `steer`: unknown column (expected t, v, steer_rate and optionally label); `steer` is a steering angle: steer the car by angle with `[model] steering = \"angle\"`".into()),
        }],
    });
}
