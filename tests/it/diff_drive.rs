//! The differential drive (`diff_drive`): the unicycle against an
//! independent integrator on random tasks, and `models/diff_drive.urdf` in
//! physics following commands on flat ground within stated tolerances.

use crate::common::legs;

use anholonomy::engine::{replay, PhysicsSettings, PhysicsSystem, ReplayOptions};
use anholonomy::integrate::simulate;
use anholonomy::model::State;
use anholonomy::record::SimTrajectory;
use anholonomy::robots::diff_drive::kinematics::Unicycle;
use anholonomy::robots::diff_drive::physics::{DiffDriveNames, DiffDrivePhysics};
use proptest::prelude::*;
use std::f64::consts::PI;
use std::path::Path;

fn robot(text: &str) -> urdf_rs::Robot {
    let r = urdf_rs::read_from_string(text).unwrap();
    anholonomy::engine::urdf::validate(&r).unwrap();
    r
}

fn shipped() -> String {
    std::fs::read_to_string(crate::common::model("diff_drive.urdf")).unwrap()
}

fn names() -> DiffDriveNames {
    DiffDriveNames {
        base: "base_link".into(),
        left: vec!["left_wheel_joint".into()],
        right: vec!["right_wheel_joint".into()],
        casters: vec!["caster".into()],
    }
}

fn settings() -> PhysicsSettings {
    PhysicsSettings {
        friction: 0.8,
        ..Default::default()
    }
}

fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

/// Largest |slip| over the channels whose names end in `suffix`.
fn slip_max(out: &SimTrajectory, suffix: &str) -> f64 {
    out.channels
        .iter()
        .filter(|(n, _)| n.starts_with("slip_") && n.ends_with(suffix))
        .flat_map(|(_, v)| v.iter())
        .fold(0.0, |m: f64, v| m.max(v.abs()))
}

/// Where legs `(Δs, Δθ)` from `start` end, by the independent integrator.
fn exact(start: [f64; 3], l: &[(f64, f64)]) -> [f64; 3] {
    l.iter()
        .fold(start, |q, &(ds, dth)| legs::unicycle_leg(q, ds, dth))
}

proptest! {
    #![proptest_config(crate::common::prop_config::config(32))]

    /// Random arcs from random starts: the harness's RK4 (in time, through
    /// the model) lands where the arc-length integration says, within 1e-9 m
    /// and 1e-9 rad.
    #[test]
    fn kinematics_match_an_independent_integrator(
        start in (-3.0..3.0f64, -3.0..3.0f64, -PI..PI),
        l in prop::collection::vec((-2.0..2.0f64, -3.0..3.0f64), 1..5),
    ) {
        let start = [start.0, start.1, start.2];
        let dt = 1e-3;
        let plan = legs::plan(&l, [0.5, 2.0], 0.25, dt);
        let ideal = simulate(&Unicycle, &plan, &State::from_column_slice(&start), dt);
        let (q, want) = (ideal.last(), exact(start, &l));
        prop_assert!((q[0] - want[0]).hypot(q[1] - want[1]) < 1e-9, "{q} vs {want:?}");
        prop_assert!((q[2] - want[2]).abs() < 1e-9, "{q} vs {want:?}");
    }

    /// Random start and goal: turn towards the goal, drive, turn to the goal
    /// heading; the harness's run ends on the goal.
    #[test]
    fn kinematics_reach_random_goals(
        start in (-3.0..3.0f64, -3.0..3.0f64, -PI..PI),
        goal in (-3.0..3.0f64, -3.0..3.0f64, -PI..PI),
    ) {
        let (dx, dy) = (goal.0 - start.0, goal.1 - start.1);
        let course = dy.atan2(dx);
        let l = [
            (0.0, wrap(course - start.2)),
            (dx.hypot(dy), 0.0),
            (0.0, wrap(goal.2 - course)),
        ];
        let dt = 1e-3;
        let plan = legs::plan(&l, [0.5, 2.0], 0.25, dt);
        let s = State::from_column_slice(&[start.0, start.1, start.2]);
        let q = simulate(&Unicycle, &plan, &s, dt).last().clone();
        prop_assert!((q[0] - goal.0).hypot(q[1] - goal.1) < 1e-9, "{q} vs {goal:?}");
        prop_assert!(wrap(q[2] - goal.2).abs() < 1e-9, "{q} vs {goal:?}");
    }
}

/// Replay `l` from `start` on the URDF `text`; returns (final position
/// error, final heading error, largest position deviation from the ideal
/// run, the wheels' travel Σ |Δs| + b |Δθ|, the run).
fn follow(
    start: [f64; 3],
    l: &[(f64, f64)],
    text: &str,
    names: &DiffDriveNames,
) -> (f64, f64, f64, f64, SimTrajectory) {
    let sim = settings();
    let plan = legs::plan(l, [0.4, 1.0], 0.5, sim.dt);
    let mut sys = DiffDrivePhysics::new(&robot(text), Path::new("."), names, &start, &sim).unwrap();
    let ideal = simulate(&Unicycle, &plan, &State::from_column_slice(&start), sim.dt);
    let out = replay(&mut sys, &plan, &ReplayOptions::new(sim.dt, 0.0), &mut ()).unwrap();
    let want = exact(start, l);
    let q = out.traj.last();
    let dev = ideal
        .q
        .iter()
        .zip(&out.traj.q)
        .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
        .fold(0.0, f64::max);
    let travel: f64 = l.iter().map(|(s, t)| s.abs() + 0.13 * t.abs()).sum();
    (
        (q[0] - want[0]).hypot(q[1] - want[1]),
        (q[2] - want[2]).abs(),
        dev,
        travel,
        out,
    )
}

proptest! {
    #![proptest_config(crate::common::prop_config::config(6))]

    /// Random arcs at up to 0.4 m/s and 1 rad/s on friction 0.8. The wheels
    /// sink ~0.5 mm into the ground under the robot's weight (Rapier's
    /// allowed penetration), so they roll on a radius ~0.5 % short, like a
    /// deflected tyre: the robot covers ~0.5 % less than commanded and
    /// turns ~0.5 % less (24 random tasks: at most 0.7 % of the wheels'
    /// travel, 0.6 % of the turning). Stated tolerances: final position and
    /// every sample within 5 mm + 1.5 % of the wheels' travel of the
    /// independent integration and the ideal run, heading within
    /// 0.2° + 1.2 % of the turning, lateral slip below 1 mm/s.
    #[test]
    fn physics_follows_random_arcs(
        start in (-2.0..2.0f64, -2.0..2.0f64, -PI..PI),
        l in prop::collection::vec((-1.2..1.2f64, -2.0..2.0f64), 2..4),
    ) {
        let start = [start.0, start.1, start.2];
        let (pos, head, dev, travel, out) = follow(start, &l, &shipped(), &names());
        let turning: f64 = l.iter().map(|(_, t)| t.abs()).sum();
        let tol = 0.005 + 0.015 * travel;
        prop_assert!(pos < tol, "final position error {pos} m over {travel} m");
        prop_assert!(dev < tol, "deviation {dev} m over {travel} m");
        let head_tol = 0.2f64.to_radians() + 0.012 * turning;
        prop_assert!(head < head_tol, "final heading error {} deg", head.to_degrees());
        let lat = slip_max(&out, "_lat");
        prop_assert!(lat < 1e-3, "lateral slip {lat} m/s");
    }
}

/// The geometry read from the URDF, and the robot at rest where it starts.
#[test]
fn geometry_from_the_urdf_and_rest() {
    let start = [1.0, -2.0, 2.5];
    let sim = settings();
    let mut sys =
        DiffDrivePhysics::new(&robot(&shipped()), Path::new("."), &names(), &start, &sim).unwrap();
    let g = sys.geometry();
    assert_eq!(g.half_track, 0.13);
    assert_eq!(
        g.wheels.iter().map(|w| w.radius).collect::<Vec<_>>(),
        [0.05, 0.05]
    );
    assert_eq!((g.point, g.ground), ([0.0, 0.0], -0.05));
    assert_eq!(g.effort, [Some(1.0), Some(1.0)]);
    assert_eq!(sys.state().as_slice(), &start);
    let plan = legs::plan(&[], [0.4, 1.0], 0.5, sim.dt);
    let out = replay(&mut sys, &plan, &ReplayOptions::new(sim.dt, 1.0), &mut ()).unwrap();
    // Settling onto the caster pitches the body and rolls the held wheels a little.
    let q = out.traj.last();
    assert!((q[0] - 1.0).hypot(q[1] + 2.0) < 1e-3, "{q}");
    assert!((q[2] - 2.5).abs() < 1e-3, "{q}");
}

/// A user's URDF: other names (set in `[model]`), the body frame elsewhere
/// (0.1 m above the axle, 0.07 m ahead of it) and wheel axes along −y: the
/// same motion as the shipped robot. Names and axes give the same numbers
/// to 1e-14; the moved frame changes the solver's arithmetic (0.4 mm
/// after 1.6 m), within 1 mm.
#[test]
fn own_urdf_with_other_names_frames_and_axes() {
    let text = shipped()
        .replace("left_wheel_joint", "wheel_l")
        .replace("right_wheel_joint", "wheel_r")
        .replace("\"caster\"", "\"ball\"")
        .replace("\"base_link\"", "\"chassis\"")
        .replace("<axis xyz=\"0 1 0\"/>", "<axis xyz=\"0 -1 0\"/>");
    // Move the body frame: every origin in `chassis` shifts by (−0.07, 0, −0.1).
    let text = text
        .replace(
            "<origin xyz=\"0 0.13 0\"",
            "<origin xyz=\"-0.07 0.13 -0.1\"",
        )
        .replace(
            "<origin xyz=\"0 -0.13 0\"",
            "<origin xyz=\"-0.07 -0.13 -0.1\"",
        )
        .replace(
            "<origin xyz=\"-0.16 0 -0.025\"",
            "<origin xyz=\"-0.23 0 -0.125\"",
        )
        .replace(
            "<origin xyz=\"-0.04 0 0.03\"/>",
            "<origin xyz=\"-0.11 0 -0.07\"/>",
        )
        .replace(
            "<origin xyz=\"-0.05 0 0.03\"/>",
            "<origin xyz=\"-0.12 0 -0.07\"/>",
        )
        .replace(
            "<origin xyz=\"0.09 0 0.075\"/>",
            "<origin xyz=\"0.02 0 -0.025\"/>",
        );
    let own = DiffDriveNames {
        base: "chassis".into(),
        left: vec!["wheel_l".into()],
        right: vec!["wheel_r".into()],
        casters: vec!["ball".into()],
    };
    let start = [0.3, 0.2, -1.0];
    let l = [(1.0, 1.2), (-0.6, 0.0)];
    let (pos, head, ..) = follow(start, &l, &text, &own);
    let (pos0, head0, ..) = follow(start, &l, &shipped(), &names());
    assert!(
        (pos - pos0).abs() < 1e-3 && (head - head0).abs() < 1e-4,
        "{pos} {pos0} {head} {head0}"
    );
    let sim = settings();
    let sys = DiffDrivePhysics::new(&robot(&text), Path::new("."), &own, &start, &sim).unwrap();
    let g = sys.geometry();
    assert!((g.point[0] + 0.07).abs() < 1e-12 && (g.ground + 0.15).abs() < 1e-12);
    assert_eq!(
        g.wheels.iter().map(|w| w.sign).collect::<Vec<_>>(),
        [-1.0, -1.0]
    );
}

/// What the physics refuses, naming the joint or link.
#[test]
fn urdf_that_does_not_fit_is_refused() {
    let sim = settings();
    let err = |text: String, names: &DiffDriveNames| {
        DiffDrivePhysics::new(&robot(&text), Path::new("."), names, &[0.0; 3], &sim)
            .err()
            .unwrap()
            .to_string()
    };
    let swapped = DiffDriveNames {
        left: vec!["right_wheel_joint".into()],
        right: vec!["left_wheel_joint".into()],
        ..names()
    };
    let e = err(shipped(), &swapped);
    assert!(e.contains("left and right swapped"), "{e}");
    let e = err(
        shipped().replace("<axis xyz=\"0 1 0\"/>", "<axis xyz=\"1 0 0\"/>"),
        &names(),
    );
    assert!(
        e.starts_with("URDF joint `left_wheel_joint` axis must be horizontal"),
        "{e}"
    );
    let e = err(
        shipped().replace(
            "<origin xyz=\"-0.16 0 -0.025\"",
            "<origin xyz=\"-0.16 0 -0.015\"",
        ),
        &names(),
    );
    assert!(
        e.contains("URDF link `caster`") && e.contains("0.0100 m above"),
        "{e}"
    );
    let e = err(
        shipped().replace("<origin xyz=\"0 -0.13 0\"", "<origin xyz=\"0.02 -0.13 0\""),
        &names(),
    );
    assert!(e.contains("must put both wheels on one axle"), "{e}");
    let e = err(
        shipped().replacen("type=\"continuous\"", "type=\"revolute\"", 1),
        &names(),
    );
    assert!(e.contains("`left_wheel_joint` must be continuous"), "{e}");
}

/// Flooring it from rest: the drives' 1 N·m exceeds what friction 0.8
/// transmits (~0.7 N·m per wheel), so the wheels spin: the slip metric sees it.
#[test]
fn hard_acceleration_spins_the_wheels() {
    let (_, _, _, _, gentle) = follow([0.0; 3], &[(1.0, 0.0)], &shipped(), &names());
    let sim = settings();
    let plan = legs::plan(&[(1.0, 0.0)], [1.0, 1.0], 0.02, sim.dt);
    let mut sys = DiffDrivePhysics::new(
        &robot(&shipped()),
        Path::new("."),
        &names(),
        &[0.0; 3],
        &sim,
    )
    .unwrap();
    let out = replay(&mut sys, &plan, &ReplayOptions::new(sim.dt, 0.5), &mut ()).unwrap();
    let (g, h) = (slip_max(&gentle, "_lon"), slip_max(&out, "_lon"));
    assert!(g < 0.01 && h > 0.05, "gentle {g} m/s, hard {h} m/s");
}
