//! The user examples for the wheeled models: the parking plan file (its
//! script regenerates the committed CSV byte for byte, and the car parks in
//! physics within the scenario's gates) and the Python go-to-pose law
//! (reaches its goal in both runs); a URDF lacking several declared names
//! is refused in one line naming them all (exit 2).

use crate::common::*;
use std::path::Path;

#[test]
fn parking_script_writes_the_committed_plan_and_the_car_parks() {
    let dir = tempfile::tempdir().unwrap();
    let ex = root().join("examples/parking");
    let out = dir.path().join("p.csv");
    let st = std::process::Command::new(python::python_with("numpy"))
        .arg(ex.join("plan_parking.py"))
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    // The same rows; numbers equal to 1e-12 (numpy builds differ in the
    // last digit of their trigonometry, so the bytes may not be equal).
    let rows = |p: &std::path::Path| -> Vec<Vec<String>> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .map(|l| l.split(',').map(String::from).collect())
            .collect()
    };
    let (got, want) = (rows(&out), rows(&ex.join("parking.csv")));
    assert_eq!(
        got.len(),
        want.len(),
        "plan_parking.py no longer writes the committed parking.csv"
    );
    for (k, (g, w)) in got.iter().zip(&want).enumerate() {
        let same = g.len() == w.len()
            && g.iter()
                .zip(w)
                .all(|(a, b)| match (a.parse::<f64>(), b.parse::<f64>()) {
                    (Ok(x), Ok(y)) => (x - y).abs() <= 1e-12,
                    _ => a == b,
                });
        assert!(
            same,
            "parking.csv row {k}: script writes {g:?}, committed {w:?}"
        );
    }
    let o = run_file(&ex.join("parking.toml"), None);
    assert!(o.passed, "{:?}", o.failures);
    let m = |n: &str| o.metric(n).unwrap();
    assert!(m("ideal_goal_position") < 1e-6 && m("steer_clipped_fraction") == 0.0);
    assert!(m("sim_goal_position") < 0.02 && m("sim_goal_theta_deg") < 1.0);
}

#[test]
fn python_go_to_pose_law_reaches_its_goal_in_both_runs() {
    // law.py imports only the standard library: any python3 runs it.
    let o = run_file(
        &root().join("examples/diff_drive_law/go_to_pose.toml"),
        None,
    );
    assert!(o.passed, "{:?}", o.failures);
    let m = |n: &str| o.metric(n).unwrap();
    assert!(m("ideal_goal_position") < 0.01 && m("sim_goal_position") < 0.012);
    assert!(m("sim_goal_theta_deg") < 1.2);
}

/// `check` on a car scenario whose URDF lacks three declared joints and the
/// body link: exit 2, one line naming all four and the keys that rename them.
#[test]
fn urdf_lacking_several_names_is_one_error() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = std::fs::read_to_string(model("car.urdf"))
        .unwrap()
        .replace("rear_left_wheel_joint", "rl")
        .replace("front_right_steer_joint", "frs")
        .replace("front_left_wheel_joint", "flw")
        .replace("\"base_link\"", "\"body\"");
    std::fs::write(dir.path().join("car.urdf"), urdf).unwrap();
    let plan = std::fs::read_to_string(root().join("examples/parking/parking.csv")).unwrap();
    std::fs::write(dir.path().join("parking.csv"), plan).unwrap();
    let sc = std::fs::read_to_string(root().join("examples/parking/parking.toml"))
        .unwrap()
        .replace("../../models/car.urdf", "car.urdf");
    std::fs::write(dir.path().join("s.toml"), sc).unwrap();
    let logs = dir.path().join("logs");
    let out = cli(
        dir.path(),
        &["check", "s.toml", "--logs", logs.to_str().unwrap()],
    );
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(
        lines[0].contains(
            "URDF lacks joints `rear_left_wheel_joint`, `front_right_steer_joint`, `front_left_wheel_joint` and link `base_link`"
        ) && lines[0].contains("car.urdf"),
        "{err}"
    );
    assert!(
        lines[0].contains("base_link, rear_left_wheel_joint"),
        "{err}"
    );
    assert!(!Path::new(&logs).exists());
}
