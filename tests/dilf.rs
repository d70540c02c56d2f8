//! Seed 004, one mobile manipulator: the shipped door scenario end to end,
//! bad input, and random open-field tasks checked by an independent
//! integrator.

mod common;
use anholonomy::integrate::simulate;
use anholonomy::model::mobile_manipulator::{MobileManipulator, DOF};
use anholonomy::model::State;
use anholonomy::planner::dilf::potential::{
    GoalFrame, PotentialParams, Scene, SingularityEnclosure,
};
use anholonomy::planner::dilf::{self, DilfParams};
use common::*;
use proptest::prelude::*;
use std::sync::Arc;

/// The paper's claims on its own kind of task: through a door, converged in
/// the ideal run with clearance all along and V̇ ≥ 0 at every policy sample;
/// the physics replay reaches the goal without touching an obstacle.
#[test]
fn door_converges_with_clearance_in_both_runs() {
    let o = run_file(&scenario("dilf_single_door.toml"), None);
    let m = |n: &str| o.metric(n).unwrap_or_else(|| panic!("metric {n}"));
    assert!(o.passed, "{:?}", o.failures);
    // The tolerance is 2 cm / 2°; time to goal is finite only when every
    // coordinate is inside it.
    assert!(m("ideal_time_to_goal") < 40.0);
    assert!(m("sim_time_to_goal") < 40.0);
    assert!(m("ideal_goal_position") <= 0.02 && m("sim_goal_position") <= 0.02);
    for j in 1..=6 {
        assert!(m(&format!("sim_goal_q{j}_deg")) <= 2.0);
    }
    assert!(m("ideal_min_obstacle_function") > 0.0);
    assert!(m("ideal_min_clearance") > 0.1 && m("sim_min_clearance") > 0.1);
    assert_eq!(m("sim_obstacle_contacts"), 0.0);
    assert_eq!(m("ideal_vdot_violations"), 0.0);
    // The platform passed the wall at x = 0 (start x = −3, goal x = 3).
    assert!(m("sim_goal_x") < 0.02);
}

fn dilf_text(start: &str, goal: &str, obstacle: &str) -> String {
    format!(
        r#"start = {start}
goal = {goal}

[model]
kind = "mobile_manipulator"
urdf = "{}"

{obstacle}

[planner]
kind = "dilf"
horizon = 5.0
"#,
        model("mobile_manipulator.urdf").display()
    )
}

const WALL: &str = r#"[[model.obstacles]]
name = "wall"
center = [0.0, 0.0, 1.0]
semi_axes = [0.1, 2.0, 1.0]
exponent = 4.0"#;
const START: &str = "[-2.0, 0.0, 0.0, 0.0, -70.0, 125.0, 0.0, -35.0, 0.0]";
const GOAL: &str = "[2.0, 0.0, 0.0, 0.0, -70.0, 125.0, 0.0, -35.0, 0.0]";

/// Run `text` as a scenario: exit 2, one line, naming the file, `line_of`'s
/// line and `key`; nothing written.
fn bad(text: &str, key: &str, line_of: &str) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.toml"), text).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    let line = text.lines().position(|l| l.contains(line_of)).unwrap() + 1;
    assert!(
        err.contains(&format!("bad.toml:{line}:")),
        "line {line} not in: {err}"
    );
    assert!(err.contains(&format!("`{key}`")), "`{key}` not in: {err}");
    assert!(files_below(&dir.path().join("logs")).is_empty());
}

#[test]
fn start_inside_an_obstacle_is_bad_input() {
    let start = "[-0.2, 0.0, 0.0, 0.0, -70.0, 125.0, 0.0, -35.0, 0.0]";
    bad(&dilf_text(start, GOAL, WALL), "start", "start =");
}

#[test]
fn goal_inside_an_obstacle_is_bad_input() {
    let goal = "[0.3, 0.0, 0.0, 0.0, -70.0, 125.0, 0.0, -35.0, 0.0]";
    bad(&dilf_text(START, goal, WALL), "goal", "goal =");
}

#[test]
fn non_positive_semi_axis_is_bad_input() {
    let wall = WALL.replace("[0.1, 2.0, 1.0]", "[0.1, 0.0, 1.0]");
    bad(
        &dilf_text(START, GOAL, &wall),
        "model.obstacles[0].semi_axes",
        "semi_axes",
    );
}

#[test]
fn exponent_below_one_half_is_bad_input() {
    let wall = WALL.replace("exponent = 4.0", "exponent = 0.4");
    bad(
        &dilf_text(START, GOAL, &wall),
        "model.obstacles[0].exponent",
        "exponent",
    );
}

#[test]
fn unknown_joint_name_in_the_urdf_is_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = std::fs::read_to_string(model("mobile_manipulator.urdf"))
        .unwrap()
        .replace("\"joint3\"", "\"elbow\"");
    let path = dir.path().join("mm.urdf");
    std::fs::write(&path, urdf).unwrap();
    let text = dilf_text(START, GOAL, WALL).replace(
        &model("mobile_manipulator.urdf").display().to_string(),
        &path.display().to_string(),
    );
    std::fs::write(dir.path().join("bad.toml"), &text).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("joint3"), "{err}");
    assert!(files_below(&dir.path().join("logs")).is_empty());
}

/// The exact motion of the unicycle + arm under a held input: an independent
/// check of the harness's RK4 ideal run.
fn exact_step(q: &mut [f64], u: &[f64], h: f64) {
    let (v, w) = (u[0], u[1]);
    let th = q[2];
    if w.abs() < 1e-12 {
        q[0] += v * th.cos() * h;
        q[1] += v * th.sin() * h;
    } else {
        q[0] += v / w * ((th + w * h).sin() - th.sin());
        q[1] -= v / w * ((th + w * h).cos() - th.cos());
    }
    q[2] += w * h;
    for a in 0..6 {
        q[3 + a] += u[2 + a] * h;
    }
}

fn open_field_task(start: [f64; 9], goal: [f64; 9]) -> (f64, f64, usize) {
    let params: DilfParams = toml::from_str("field_power = 1.75\nhorizon = 80.0").unwrap();
    let scene = Scene::new(
        1,
        anholonomy::model::mobile_manipulator::default_parts(),
        Vec::new(),
        goal.to_vec(),
        PotentialParams {
            lambda: params.lambda,
            kv: params.kv_exponent,
            goal_frame: GoalFrame::Platform,
            singularity: SingularityEnclosure::default(),
            field_power: params.field_power,
        },
    )
    .unwrap();
    let start = State::from_vec(start.to_vec());
    let plan = dilf::plan(Arc::new(scene), &start, &params).unwrap();
    let dt = 0.002;
    let tr = simulate(&MobileManipulator { robots: 1 }, &plan, &start, dt);
    // Re-integrate the recorded (held) inputs exactly.
    let mut q = start.as_slice().to_vec();
    for k in 0..tr.t.len() - 1 {
        exact_step(&mut q, tr.u[k].as_slice(), tr.t[k + 1] - tr.t[k]);
    }
    let last = tr.last();
    let gap = (0..DOF).map(|i| (q[i] - last[i]).abs()).fold(0.0, f64::max);
    let reached = params.tolerance.reached(last.as_slice(), &goal);
    (
        gap,
        if reached {
            *tr.t.last().unwrap()
        } else {
            f64::NAN
        },
        tr.t.len(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]

    /// Random starts and goals in the open: the ideal closed loop converges
    /// within the tolerance, and integrating its recorded inputs exactly
    /// lands where RK4 did.
    #[test]
    fn random_open_field_tasks_converge(
        x0 in -4.0f64..4.0, y0 in -4.0f64..4.0, th0 in -180.0f64..180.0,
        th1 in -180.0f64..180.0,
        a0 in proptest::array::uniform6(-0.3f64..0.3),
        a1 in proptest::array::uniform6(-0.3f64..0.3),
    ) {
        prop_assume!(x0.hypot(y0) > 1.0);
        // Around a collision-free arm pose, q5 kept ≥ 18° from the wrist
        // singularity: nearer, joints 4 and 6 turn almost the same axis, the
        // parts' points barely tell q4 − q6 apart and that difference converges
        // over minutes (a property of the point-based goal term; e.g. q5 → −13°
        // leaves q4, q6 at ±5° after 80 s). 18° was not enough: a goal with
        // q5 = −19.7° (start (−1.65, −0.93, 160.9°), goal heading 169.9°) did
        // not converge within 80 s, so the goal's q5 stays at or below −29°.
        let base = [0.0, -70.0f64.to_radians(), 125.0f64.to_radians(), 0.0, -35.0f64.to_radians(), 0.0];
        let mut start = [x0, y0, th0.to_radians(), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let mut goal = [0.0, 0.0, th1.to_radians(), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        for j in 0..6 {
            start[3 + j] = base[j] + a0[j];
            goal[3 + j] = base[j] + a1[j];
        }
        goal[7] = goal[7].min(-29f64.to_radians());
        let (gap, t, n) = open_field_task(start, goal);
        prop_assert!(gap < 1e-6, "exact re-integration ends {gap} away from RK4 ({n} samples)");
        prop_assert!(t.is_finite(), "did not converge within 80 s: start {start:?} goal {goal:?}");
    }
}

/// Table I's initial configuration, both robots (degrees).
const PAIR_START: &str = "[-11.0, 3.0, -90.0, 90.0, -90.0, 120.0, 0.0, -30.0, 0.0, \
                          -8.0, 3.0, -90.0, -60.0, -90.0, 120.0, 0.0, -45.0, 0.0]";
const PAIR_GOAL: &str = "[-11.0, 1.0, -90.0, 90.0, -90.0, 120.0, 0.0, -30.0, 0.0, \
                         -8.0, 1.0, -90.0, -60.0, -90.0, 120.0, 0.0, -45.0, 0.0]";

fn pair_text(beam: &str) -> String {
    dilf_text(
        PAIR_START,
        PAIR_GOAL,
        &format!("robots = 2\n\n[model.beam]\n{beam}"),
    )
}

#[test]
fn a_beam_the_table_i_grasps_cannot_hold_is_bad_input() {
    // Table I's grasp points are 3.28 m apart: a 3 m beam does not fit.
    bad(
        &pair_text("max_deformation = 4.0\nlength = 3.0"),
        "model.beam.length",
        "length =",
    );
}

#[test]
fn negative_stiffness_and_bound_are_bad_input() {
    bad(
        &pair_text("max_deformation = 4.0\nyoungs_modulus = -40e9"),
        "model.beam.youngs_modulus",
        "youngs_modulus =",
    );
    bad(
        &pair_text("max_deformation = -1.0"),
        "model.beam.max_deformation",
        "max_deformation =",
    );
}

#[test]
fn the_pair_is_refused_until_its_physics_exists() {
    // The ideal side is built (and unit-tested in planner::dilf::object); a
    // replay of robot 1 alone would answer another question, so the pair is
    // refused with the key, not run half.
    bad(
        &pair_text("max_deformation = 4.0"),
        "model.robots",
        "robots = 2",
    );
}
