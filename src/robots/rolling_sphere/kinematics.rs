//! The sphere rolling without slipping on a plane: the ball-plate problem (seed 003, Eq. 2).
//!
//! Two charts of the same system, driven by the same inputs so that one plan runs on both:
//!
//! * [`RollingSphere`]: state (x, y, α, θ, φ), centre position plus z-y-z Euler angles
//!   R = Rz(α) Ry(θ) Rz(φ) (body to world), exactly the paper's coordinates. Singular at
//!   θ = 0 and θ = π, which is where the planners' goal (P upright, θ = 0) sits.
//! * [`RollingSphereQuat`]: state (x, y, qw, qx, qy, qz), centre position plus a unit
//!   quaternion (body to world). Singularity free: use it for the ideal run.
//!
//! Inputs of both: the world-frame angular velocity (ω_x, ω_y), with ω_z = 0 (no spin about
//! the vertical). No slip at the contact point −a k gives v = a ω × k, i.e.
//! ẋ = a ω_y, ẏ = −a ω_x, and Ṙ = \[ω\]× R.
//!
//! The paper writes Eq. 2 with the frame-1 components ω¹ = Rz(−α) ω (frame 1 is the world frame
//! turned by α about z, sharing its z axis, so ω¹_z = ω_z = 0). Substituting
//! ω = Rz(α) ω¹ into the model below gives Eq. 2 verbatim:
//! ẋ = ω¹_y cos α + ω¹_x sin α, ẏ = ω¹_y sin α − ω¹_x cos α, θ̇ = ω¹_y,
//! α̇ = −ω¹_x cot θ, φ̇ = ω¹_x csc θ.
//!
//! Misprint note: Eq. 2d (α̇ = −ω¹_x cot θ) is right; it follows from the angular velocity
//! of z-y-z Euler angles, ω¹ = (φ̇ sin θ, θ̇, α̇ + φ̇ cos θ), with ω¹_z = 0, and it is the sign
//! that makes Eq. 5 (Δφ = −sec θ' Δα) and the paper's geometry (|FC| = tan θ' − θ') hold. The
//! reduced model Eq. 16 (and its Lie-bracket matrix) prints α̇ = +cot θ ω¹_x: that sign is the
//! misprint (the rank argument is unaffected). The test `euler_and_quaternion_models_agree`
//! integrates both charts and would fail with the printed Eq. 16 sign.

use crate::model::{Input, KinematicModel, State};
use nalgebra::{DMatrix, Quaternion, Rotation3, UnitQuaternion, Vector3};

/// Sphere of radius `a` in the z-y-z Euler chart (x, y, α, θ, φ); inputs (ω_x, ω_y), world frame.
#[derive(Debug, Clone, Copy)]
pub struct RollingSphere {
    /// Sphere radius, m.
    pub a: f64,
}

impl KinematicModel for RollingSphere {
    fn position_states(&self) -> Option<[usize; 2]> {
        Some([0, 1])
    }
    fn name(&self) -> &'static str {
        "rolling_sphere"
    }
    fn state_names(&self) -> &'static [&'static str] {
        &["x", "y", "alpha", "theta", "phi"]
    }
    fn input_names(&self) -> &'static [&'static str] {
        &["omega_x", "omega_y"]
    }
    fn angular_states(&self) -> &'static [usize] {
        &[2, 3, 4]
    }
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        let (sa, ca) = q[2].sin_cos();
        let (st, ct) = q[3].sin_cos();
        let cot = ct / st;
        #[rustfmt::skip]
        let g = DMatrix::from_row_slice(5, 2, &[
            0.0, self.a,
            -self.a, 0.0,
            -cot * ca, -cot * sa,
            -sa, ca,
            ca / st, sa / st,
        ]);
        g
    }
}

/// Sphere of radius `a` as position plus unit quaternion (x, y, qw, qx, qy, qz);
/// inputs (ω_x, ω_y), world frame. q̇ = ½ (0, ω) ⊗ q.
///
/// The exact flow keeps |q| = 1; RK4 drifts by O((|ω| dt)^5) per step (≈1e-19 at
/// |ω| dt = 1e-3), far below the 1e-9 targets, so the shared integrator needs no projection.
/// Readers of the state ([`quat_of_state`]) normalise. For long runs a constraint-stabilising
/// drift `norm_gain · (1 − |q|²) q` can be switched on: it vanishes on the unit sphere, so it
/// leaves the exact solution unchanged and only pulls numerical drift back.
#[derive(Debug, Clone, Copy)]
pub struct RollingSphereQuat {
    /// Sphere radius, m.
    pub a: f64,
    /// Gain (1/s) of the norm-restoring drift; 0 disables it (the default in [`Self::new`]).
    pub norm_gain: f64,
}

impl RollingSphereQuat {
    /// Radius `a`, no norm stabilisation.
    pub fn new(a: f64) -> Self {
        Self { a, norm_gain: 0.0 }
    }
}

impl KinematicModel for RollingSphereQuat {
    fn position_states(&self) -> Option<[usize; 2]> {
        Some([0, 1])
    }
    fn name(&self) -> &'static str {
        "rolling_sphere_quat"
    }
    fn state_names(&self) -> &'static [&'static str] {
        &["x", "y", "qw", "qx", "qy", "qz"]
    }
    fn input_names(&self) -> &'static [&'static str] {
        &["omega_x", "omega_y"]
    }
    fn drift(&self, q: &State) -> State {
        let mut f = State::zeros(6);
        if self.norm_gain != 0.0 {
            let n2 = q.rows(2, 4).norm_squared();
            let k = self.norm_gain * (1.0 - n2);
            for i in 2..6 {
                f[i] = k * q[i];
            }
        }
        f
    }
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        let (w, x, y, z) = (q[2], q[3], q[4], q[5]);
        #[rustfmt::skip]
        let g = DMatrix::from_row_slice(6, 2, &[
            0.0, self.a,
            -self.a, 0.0,
            -0.5 * x, -0.5 * y,
            0.5 * w, 0.5 * z,
            -0.5 * z, 0.5 * w,
            0.5 * y, -0.5 * x,
        ]);
        g
    }
}

/// R = Rz(α) Ry(θ) Rz(φ) (body to world).
pub fn euler_to_rotation(alpha: f64, theta: f64, phi: f64) -> Rotation3<f64> {
    Rotation3::from_axis_angle(&Vector3::z_axis(), alpha)
        * Rotation3::from_axis_angle(&Vector3::y_axis(), theta)
        * Rotation3::from_axis_angle(&Vector3::z_axis(), phi)
}

/// z-y-z Euler angles (α, θ, φ) of `r`, θ ∈ [0, π], α, φ ∈ (−π, π].
///
/// At the chart singularities only α + φ (θ = 0) or φ − α (θ = π) is defined: there α = 0 is
/// returned and φ carries the whole angle.
pub(crate) fn rotation_to_euler(r: &Rotation3<f64>) -> (f64, f64, f64) {
    let m = r.matrix();
    let theta = m[(2, 2)].clamp(-1.0, 1.0).acos();
    let s = (m[(0, 2)].powi(2) + m[(1, 2)].powi(2)).sqrt();
    if s > 1e-12 {
        (
            m[(1, 2)].atan2(m[(0, 2)]),
            theta,
            m[(2, 1)].atan2(-m[(2, 0)]),
        )
    } else if m[(2, 2)] > 0.0 {
        (0.0, 0.0, m[(1, 0)].atan2(m[(0, 0)]))
    } else {
        (0.0, std::f64::consts::PI, m[(1, 0)].atan2(-m[(0, 0)]))
    }
}

/// Geodesic distance on SO(3): the angle in [0, π] of the rotation taking `r1` to `r2`.
pub(crate) fn geodesic_angle(r1: &UnitQuaternion<f64>, r2: &UnitQuaternion<f64>) -> f64 {
    let d = r1.inverse() * r2;
    2.0 * d.imag().norm().atan2(d.w.abs())
}

/// The (normalised) orientation of a quaternion-model state.
pub fn quat_of_state(q: &State) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(Quaternion::new(q[2], q[3], q[4], q[5]))
}

/// The orientation of an Euler-model state.
pub(crate) fn quat_of_euler_state(q: &State) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(&euler_to_rotation(q[2], q[3], q[4]))
}

/// (x, y, α, θ, φ) → (x, y, qw, qx, qy, qz).
pub(crate) fn euler_state_to_quat_state(q: &State) -> State {
    let u = quat_of_euler_state(q);
    State::from_vec(vec![q[0], q[1], u.w, u.i, u.j, u.k])
}

/// (x, y, qw, qx, qy, qz) → (x, y, α, θ, φ) (see [`rotation_to_euler`] at the singularities).
pub(crate) fn quat_state_to_euler_state(q: &State) -> State {
    let (al, th, ph) = rotation_to_euler(&quat_of_state(q).to_rotation_matrix());
    State::from_vec(vec![q[0], q[1], al, th, ph])
}

/// Position error and geodesic orientation error between two quaternion-model states.
pub fn quat_state_error(q1: &State, q2: &State) -> (f64, f64) {
    let dp = ((q1[0] - q2[0]).powi(2) + (q1[1] - q2[1]).powi(2)).sqrt();
    (dp, geodesic_angle(&quat_of_state(q1), &quat_of_state(q2)))
}

/// The world-frame angular velocity (ω_x, ω_y) that rolls the centre by ground displacement
/// (dx, dy) in a straight line: ω = k × v / a.
pub fn roll_omega(a: f64, dx: f64, dy: f64) -> Input {
    Input::from_vec(vec![-dy / a, dx / a])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::simulate;
    use crate::plan::{plan_from_legs, Limits};
    use std::f64::consts::PI;

    fn wrap(a: f64) -> f64 {
        let mut x = (a + PI).rem_euclid(2.0 * PI) - PI;
        if x <= -PI {
            x += 2.0 * PI;
        }
        x
    }

    #[test]
    fn euler_round_trip() {
        for &(al, th, ph) in &[(0.3, 0.7, -1.2), (-2.9, 2.5, 3.0), (1.0, 1e-3, 0.5)] {
            let r = euler_to_rotation(al, th, ph);
            let (a2, t2, p2) = rotation_to_euler(&r);
            assert!(
                (wrap(a2 - al)).abs() < 1e-9
                    && (t2 - th).abs() < 1e-12
                    && wrap(p2 - ph).abs() < 1e-9
            );
        }
        // Singular chart: only α + φ survives.
        let (a2, t2, p2) = rotation_to_euler(&euler_to_rotation(0.4, 0.0, 0.5));
        assert!(t2 == 0.0 && wrap(a2 + p2 - 0.9).abs() < 1e-12);
        let (a2, t2, p2) = rotation_to_euler(&euler_to_rotation(0.4, PI, 0.9));
        assert!((t2 - PI).abs() < 1e-9 && wrap(p2 - a2 - 0.5).abs() < 1e-7);
        let q0 = State::from_vec(vec![1.0, 2.0, 0.3, 0.7, -1.2]);
        let back = quat_state_to_euler_state(&euler_state_to_quat_state(&q0));
        assert!((back - q0).norm() < 1e-12);
    }

    #[test]
    fn geodesic_angle_is_rotation_angle() {
        let r1 = quat_of_euler_state(&State::from_vec(vec![0.0, 0.0, 0.3, 0.7, -1.2]));
        let r2 = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.4) * r1;
        assert!((geodesic_angle(&r1, &r2) - 0.4).abs() < 1e-12);
        let r3 = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 3.0) * r1;
        assert!((geodesic_angle(&r3, &r1) - 3.0).abs() < 1e-12);
    }

    /// Both charts, same world-frame inputs, away from θ = 0: they must agree. Also checks
    /// the no-slip sign: rolling in +x is a rotation about +y.
    #[test]
    fn euler_and_quaternion_models_agree() {
        let a = 0.7;
        let e = RollingSphere { a };
        let qm = RollingSphereQuat::new(a);
        let limits = Limits {
            max_rate: vec![1.0, 1.0],
            ramp: 0.3,
            step: 1e-3,
        };
        let legs = vec![
            (0, Input::from_vec(vec![0.3, 0.2])),
            (0, Input::from_vec(vec![-0.4, 0.5])),
            (0, Input::from_vec(vec![0.1, -0.6])),
        ];
        let plan = plan_from_legs(vec!["leg".into()], legs, &limits, serde_json::Value::Null);
        let q0 = State::from_vec(vec![0.5, -1.0, 0.4, 1.1, -0.3]);
        let te = simulate(&e, &plan, &q0, 1e-3);
        let tq = simulate(&qm, &plan, &euler_state_to_quat_state(&q0), 1e-3);
        let mut max_err: f64 = 0.0;
        for (qe, qq) in te.q.iter().zip(&tq.q) {
            assert!(qe[3] > 0.2, "test path must stay away from the singularity");
            let (dp, dr) = quat_state_error(&euler_state_to_quat_state(qe), qq);
            max_err = max_err.max(dp).max(dr);
        }
        assert!(max_err < 1e-10, "charts disagree by {max_err}");
        // Pure roll: centre displacement = a × ∫ω rotated; orientation = rotation about k × v.
        let plan = plan_from_legs(
            vec!["x".into()],
            vec![(0, roll_omega(a, 0.5, 0.0))],
            &limits,
            serde_json::Value::Null,
        );
        let q0 = State::from_vec(vec![0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
        let qf = simulate(&qm, &plan, &q0, 1e-3).last().clone();
        // The quintic ramps are C² everywhere, so RK4 at dt = 1e-3 is far below 1e-11 here.
        assert!((qf[0] - 0.5).abs() < 1e-11 && qf[1].abs() < 1e-12, "{qf}");
        let want = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.5 / a);
        assert!(geodesic_angle(&quat_of_state(&qf), &want) < 1e-11);
    }

    #[test]
    fn norm_gain_restores_unit_quaternion() {
        let m = RollingSphereQuat {
            a: 1.0,
            norm_gain: 2.0,
        };
        let q = State::from_vec(vec![0.0, 0.0, 1.01, 0.0, 0.0, 0.0]);
        let f = m.drift(&q);
        assert!(f[2] < 0.0);
        let q = State::from_vec(vec![0.0, 0.0, 0.6, 0.8, 0.0, 0.0]);
        assert!(m.drift(&q).norm() < 1e-15);
    }
}
