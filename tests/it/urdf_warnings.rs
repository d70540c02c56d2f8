//! What the harness says about a robot it fills in or that looks wrong:
//! once per cause, and only when true. A joint without `<limit effort>`
//! is capped at `[sim] motor_max_torque` (one warning naming every such
//! joint, none when the scenario sets the cap); wheels that no drive turns
//! (a skid steer driven on two of its four wheels) are named.

use crate::common::*;
use std::path::Path;

/// `plan --json`'s `read_from_urdf` for the skid steer example (its URDF
/// at `urdf`) driven on the wheel joints `left`/`right`, with `sim_extra`
/// in `[sim]`.
fn skid_steer(
    dir: &Path,
    urdf: &Path,
    left: &[&str],
    right: &[&str],
    sim_extra: &str,
) -> serde_json::Value {
    let ex = root().join("examples/skid_steer");
    let list = |js: &[&str]| {
        js.iter()
            .map(|j| format!("\"{j}\""))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let text = format!(
        r#"start = [0.0, 0.0, 0.0]
goal = [1.0, 0.0, 0.0]
[model]
kind = "diff_drive"
urdf = "{}"
left_wheel_joints = [{}]
right_wheel_joints = [{}]
caster_links = []
[planner]
kind = "file"
path = "{}"
[sim]
dt = 0.001
{sim_extra}
"#,
        urdf.display(),
        list(left),
        list(right),
        ex.join("arc.csv").display()
    );
    std::fs::write(dir.join("case.toml"), text).unwrap();
    let out = cli(dir, &["plan", "case.toml", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["read_from_urdf"].clone()
}

fn warnings(r: &serde_json::Value) -> Vec<String> {
    r["warnings"]
        .as_array()
        .map(|a| a.iter().map(|w| w.as_str().unwrap().to_string()).collect())
        .unwrap_or_default()
}

fn example_urdf() -> std::path::PathBuf {
    root().join("examples/skid_steer/skid_steer.urdf")
}

const ALL_LEFT: [&str; 2] = ["front_left_wheel_joint", "rear_left_wheel_joint"];
const ALL_RIGHT: [&str; 2] = ["front_right_wheel_joint", "rear_right_wheel_joint"];

#[test]
fn the_effort_cap_is_said_once_and_not_when_the_scenario_sets_it() {
    let dir = tempfile::tempdir().unwrap();
    // The example's URDF without its <limit effort>s: one warning for the
    // four joints.
    let text = std::fs::read_to_string(example_urdf()).unwrap();
    let bare = text.replace("<limit effort=\"4.0\" velocity=\"20.0\"/>", "");
    assert_eq!(text.matches("<limit").count(), 4);
    assert_eq!(bare.matches("<limit").count(), 0);
    let urdf = dir.path().join("bare.urdf");
    std::fs::write(&urdf, bare).unwrap();
    let r = skid_steer(dir.path(), &urdf, &ALL_LEFT, &ALL_RIGHT, "");
    let w = warnings(&r);
    let effort: Vec<&String> = w.iter().filter(|w| w.contains("limit effort")).collect();
    assert_eq!(effort.len(), 1, "{w:?}");
    for j in ALL_LEFT.iter().chain(&ALL_RIGHT) {
        assert!(effort[0].contains(&format!("`{j}`")), "{j}: {}", effort[0]);
    }
    assert!(
        effort[0].contains("motor_max_torque = 50 N·m"),
        "{}",
        effort[0]
    );
    assert_eq!(r["drives"][0]["source"], "default");
    // The scenario sets the cap: its choice, no warning.
    let r = skid_steer(
        dir.path(),
        &urdf,
        &ALL_LEFT,
        &ALL_RIGHT,
        "motor_max_torque = 2.0",
    );
    assert!(
        !warnings(&r).iter().any(|w| w.contains("limit effort")),
        "{r}"
    );
    assert_eq!(r["drives"][3]["source"], "scenario");
    assert_eq!(r["drives"][3]["torque_limit"], 2.0);
}

#[test]
fn wheels_no_drive_turns_are_named() {
    let dir = tempfile::tempdir().unwrap();
    // All four driven: nothing to say.
    let r = skid_steer(dir.path(), &example_urdf(), &ALL_LEFT, &ALL_RIGHT, "");
    assert!(warnings(&r).is_empty(), "{r}");
    // Two of four: the rear pair rolls freely.
    let r = skid_steer(
        dir.path(),
        &example_urdf(),
        &ALL_LEFT[..1],
        &ALL_RIGHT[..1],
        "",
    );
    let w = warnings(&r);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].starts_with(
            "continuous joints `rear_left_wheel_joint`, `rear_right_wheel_joint` look like wheels"
        ),
        "{}",
        w[0]
    );
}
