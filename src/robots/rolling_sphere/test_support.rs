//! What the tests of the two rolling-sphere planners share: the harness's
//! limits, the ideal run on the quaternion model, and the check that it
//! ends on the goal.

use crate::integrate::simulate;
use crate::model::State;
use crate::plan::{Limits, Plan};
use crate::robots::rolling_sphere::kinematics::{
    euler_state_to_quat_state, quat_state_error, RollingSphereQuat,
};

/// Integration step of the ideal runs: the harness's 1e-3 s. The quintic smoothstep ramps
/// keep u, u̇ and ü continuous (also where a ramp meets the cruise phase off the dt grid),
/// so RK4 stays fourth order: ideal goal errors are ~1e-12 (the cycloidal ramps this code
/// was first written for needed 2.5e-4 s for 1e-9).
pub const DT: f64 = 1e-3;
/// Random starts can produce very short legs (e.g. a 0.015-rad tilt), whose ramps last only
/// a few 1e-3 s steps: RK4 then loses its order (measured 4.8e-7 at dt = 1e-3 for a
/// 0.0146-rad leg). The random tests integrate with a finer step.
pub const DT_FINE: f64 = 2.5e-4;

pub fn limits() -> Limits {
    Limits {
        max_rate: vec![2.0, 2.0],
        ramp: 0.25,
        step: 1e-3,
    }
}

/// (x, y, α, θ, φ) with the angles in degrees.
pub fn deg_state(x: f64, y: f64, al: f64, th: f64, ph: f64) -> State {
    State::from_vec(vec![
        x,
        y,
        al.to_radians(),
        th.to_radians(),
        ph.to_radians(),
    ])
}

/// (position error, geodesic orientation error) of the ideal quaternion run.
pub(crate) fn ideal_error(a: f64, plan: &Plan, start: &State, goal: &State) -> (f64, f64) {
    ideal_error_dt(a, plan, start, goal, DT)
}

/// As [`ideal_error`] with step `dt`.
pub(crate) fn ideal_error_dt(
    a: f64,
    plan: &Plan,
    start: &State,
    goal: &State,
    dt: f64,
) -> (f64, f64) {
    let traj = simulate(
        &RollingSphereQuat::new(a),
        plan,
        &euler_state_to_quat_state(start),
        dt,
    );
    quat_state_error(traj.last(), &euler_state_to_quat_state(goal))
}

/// The ideal run of `plan` on a sphere of radius `a` ends within 1e-9 of
/// `goal` in position and orientation; `what` names the case.
pub(crate) fn assert_reaches(a: f64, plan: &Plan, start: &State, goal: &State, what: &str) {
    let (dp, dr) = ideal_error(a, plan, start, goal);
    assert!(
        dp < 1e-9 && dr < 1e-9,
        "{what}{start} -> {goal}: {dp:e} {dr:e}"
    );
}

pub(crate) fn round_to(x: f64, digits: i32) -> f64 {
    let s = 10f64.powi(digits);
    (x * s).round() / s
}
