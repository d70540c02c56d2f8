//! Free-floating planar two-link space robot (seed 000, §4.1, Eqs. 13-14).
//!
//! State q = (θ0, θ1, θ2): vehicle orientation, joint 1 angle (link 1 relative
//! to the vehicle), joint 2 angle (link 2 relative to link 1). Inputs
//! u = (θ1', θ2'). Zero total angular momentum (and linear momentum, the system
//! centre of mass stays put) gives the single nonholonomic constraint
//!
//! θ0' = (a θ1' + b θ2') / Δ                                          (Eq. 13)
//!
//! Δ = (½m1+m2)² l1² + ¼m2² l2² − (m0+½m1) m2 l1 l2 cos θ2
//!     − M (I + (¼m1+m2) l1² + ¼ m2 l2²)
//! a = −Δ − M I0
//! b = M (I2 + ¼m2 l2² + ½m2 l1 l2 cos θ2) − ¼m2² l2² − ½m2(½m1+m2) l1 l2 cos θ2   (Eq. 14)
//!
//! with M = m0+m1+m2 and I = I0+I1+I2. Writing Δ = A + B cos θ2 gives Eq. 17:
//! A = (½m1+m2)² l1² + ¼m2² l2² − M (I + (¼m1+m2) l1² + ¼m2 l2²), B = −(m0+½m1) m2 l1 l2.
//!
//! # Geometry implied by Eqs. 13-14 (for building the URDF)
//!
//! Deriving the angular momentum of the three bodies about the (fixed) system
//! centre of mass reproduces Eq. 13-14 term by term if and only if:
//!
//! * **Joint 1 sits exactly at the vehicle's centre of mass** (offset (0, 0) in
//!   the vehicle frame). Any offset d ≠ 0 would add terms in d·cos θ1 and make
//!   Δ depend on θ1, which Eq. 14 does not.
//! * **Link 1 is a uniform rod**: its centre of mass is at l1/2 = **0.25 m**
//!   from joint 1 along the link (the ½m1 and ¼m1 factors), and joint 2 is at
//!   l1 = **0.50 m** from joint 1 at the link's far end.
//! * **Link 2 is a uniform rod**: its centre of mass is at l2/2 = **0.175 m**
//!   from joint 2 along the link (the ½m2, ¼m2 factors); its tip is at
//!   l2 = 0.35 m.
//! * I0, I1, I2 are the bodies' moments of inertia about their own centres of
//!   mass (1.52, 0.115, 0.028 kg m²); masses 27.44, 5.38, 2.64 kg.
//! * Angles: all counter-clockwise; the absolute orientations are
//!   φ0 = θ0, φ1 = θ0+θ1, φ2 = θ0+θ1+θ2. At θ1 = 0 link 1 points along the
//!   vehicle's body x axis; at θ2 = 0 link 2 continues link 1 straight.
//!
//! [`SpaceRobot::body_poses`] and [`SpaceRobot::angular_momentum`] implement
//! this multibody model directly (system CoM at the origin) so the geometry can
//! be checked against Eq. 13-14 and against a physics model.
//!
//! OCR notes: the seed's table labels link 2's length `l_1 = 0.35`; it is l2.
//! Eq. 17 prints `M(l + …)`: the `l` is the total inertia I = I0+I1+I2.

use crate::model::{Input, KinematicModel, State};
use nalgebra::{DMatrix, Vector2};
use serde::{Deserialize, Serialize};

/// Masses (kg), inertias about each body's CoM (kg m²) and link lengths (m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpaceRobot {
    /// Vehicle mass m0.
    pub m0: f64,
    /// Vehicle inertia I0.
    pub i0: f64,
    /// Link 1 mass m1.
    pub m1: f64,
    /// Link 1 inertia I1.
    pub i1: f64,
    /// Link 1 length l1.
    pub l1: f64,
    /// Link 2 mass m2.
    pub m2: f64,
    /// Link 2 inertia I2.
    pub i2: f64,
    /// Link 2 length l2.
    pub l2: f64,
}

impl Default for SpaceRobot {
    /// The aluminium robot of the seed's table (§4.1).
    fn default() -> Self {
        Self {
            m0: 27.44,
            i0: 1.52,
            m1: 5.38,
            i1: 0.115,
            l1: 0.50,
            m2: 2.64,
            i2: 0.028,
            l2: 0.35,
        }
    }
}

/// Position (m) and absolute orientation (rad) of one body's centre of mass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyPose {
    /// CoM position in the inertial frame whose origin is the system CoM.
    pub position: Vector2<f64>,
    /// Absolute orientation φ.
    pub angle: f64,
}

fn unit(phi: f64) -> Vector2<f64> {
    Vector2::new(phi.cos(), phi.sin())
}

fn cross(a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    a.x * b.y - a.y * b.x
}

/// Why a free-floating two-link robot's parameters are not usable.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RobotError {
    /// A mass, inertia or length is not positive and finite.
    #[error("{name} must be positive and finite, got {value}")]
    NotPositive {
        /// The parameter (`m0`, `i0`, `l1`, ...).
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// |A| ≤ |B|, so Δ(θ2) of Eq. 13 is zero for some θ2.
    #[error("Δ = A + B cos θ2 vanishes somewhere (A = {a}, B = {b})")]
    DeltaVanishes {
        /// Coefficient A.
        a: f64,
        /// Coefficient B.
        b: f64,
    },
}

impl SpaceRobot {
    /// Checks the parameters are physical and that Δ(θ2) never vanishes
    /// (|A| > |B|), so Eq. 13 is defined everywhere.
    pub fn validate(&self) -> Result<(), RobotError> {
        let named = [
            ("m0", self.m0),
            ("i0", self.i0),
            ("m1", self.m1),
            ("i1", self.i1),
            ("l1", self.l1),
            ("m2", self.m2),
            ("i2", self.i2),
            ("l2", self.l2),
        ];
        for (name, value) in named {
            if !value.is_finite() || value <= 0.0 {
                return Err(RobotError::NotPositive { name, value });
            }
        }
        let (a, b) = (self.coeff_a(), self.coeff_b());
        if a.abs() <= b.abs() {
            return Err(RobotError::DeltaVanishes { a, b });
        }
        Ok(())
    }

    /// Total mass M.
    pub fn total_mass(&self) -> f64 {
        self.m0 + self.m1 + self.m2
    }

    /// Sum of the body inertias I = I0 + I1 + I2.
    pub fn total_inertia(&self) -> f64 {
        self.i0 + self.i1 + self.i2
    }

    /// M I0: the factor between Δθ0 and the surface integral (Eq. 16, 18).
    pub fn m_i0(&self) -> f64 {
        self.total_mass() * self.i0
    }

    /// A of Eq. 17 (Δ = A + B cos θ2).
    pub fn coeff_a(&self) -> f64 {
        let (m1, m2, l1, l2) = (self.m1, self.m2, self.l1, self.l2);
        (0.5 * m1 + m2).powi(2) * l1 * l1 + 0.25 * m2 * m2 * l2 * l2
            - self.total_mass()
                * (self.total_inertia() + (0.25 * m1 + m2) * l1 * l1 + 0.25 * m2 * l2 * l2)
    }

    /// B of Eq. 17.
    pub fn coeff_b(&self) -> f64 {
        -(self.m0 + 0.5 * self.m1) * self.m2 * self.l1 * self.l2
    }

    /// Δ(θ2) of Eq. 14.
    pub fn delta(&self, theta2: f64) -> f64 {
        self.coeff_a() + self.coeff_b() * theta2.cos()
    }

    /// a(θ2) of Eq. 14.
    pub fn a(&self, theta2: f64) -> f64 {
        -self.delta(theta2) - self.m_i0()
    }

    /// b(θ2) of Eq. 14.
    pub fn b(&self, theta2: f64) -> f64 {
        let (m1, m2, l1, l2) = (self.m1, self.m2, self.l1, self.l2);
        let c = theta2.cos();
        self.total_mass() * (self.i2 + 0.25 * m2 * l2 * l2 + 0.5 * m2 * l1 * l2 * c)
            - 0.25 * m2 * m2 * l2 * l2
            - 0.5 * m2 * (0.5 * m1 + m2) * l1 * l2 * c
    }

    /// The connection one-form coefficients (a/Δ, b/Δ): dθ0 = (a/Δ) dθ1 + (b/Δ) dθ2.
    pub fn one_form(&self, theta2: f64) -> (f64, f64) {
        let d = self.delta(theta2);
        (self.a(theta2) / d, self.b(theta2) / d)
    }

    /// θ0' from Eq. 13.
    pub fn theta0_rate(&self, theta2: f64, theta1_dot: f64, theta2_dot: f64) -> f64 {
        let (p, q) = self.one_form(theta2);
        p * theta1_dot + q * theta2_dot
    }

    /// CoM poses of vehicle, link 1, link 2 (in that order) at q = (θ0, θ1, θ2),
    /// with the system CoM at the origin (the geometry documented above).
    pub fn body_poses(&self, q: &State) -> [BodyPose; 3] {
        let (p0, p1, p2) = (q[0], q[0] + q[1], q[0] + q[1] + q[2]);
        // CoMs relative to joint 1 (= vehicle CoM).
        let s1 = unit(p1) * (0.5 * self.l1);
        let s2 = unit(p1) * self.l1 + unit(p2) * (0.5 * self.l2);
        let r0 = -(s1 * self.m1 + s2 * self.m2) / self.total_mass();
        [
            BodyPose {
                position: r0,
                angle: p0,
            },
            BodyPose {
                position: r0 + s1,
                angle: p1,
            },
            BodyPose {
                position: r0 + s2,
                angle: p2,
            },
        ]
    }

    /// Joint 1, joint 2 and the tip of link 2 (system CoM at the origin), for drawing.
    pub fn joint_positions(&self, q: &State) -> [Vector2<f64>; 3] {
        let r0 = self.body_poses(q)[0].position;
        let (p1, p2) = (q[0] + q[1], q[0] + q[1] + q[2]);
        let j2 = r0 + unit(p1) * self.l1;
        [r0, j2, j2 + unit(p2) * self.l2]
    }

    /// CoM velocities and angular rates of the three bodies (analytic
    /// derivative of [`Self::body_poses`]) for qdot = (θ0', θ1', θ2').
    pub fn body_velocities(&self, q: &State, qdot: &State) -> [(Vector2<f64>, f64); 3] {
        let (p1, p2) = (q[0] + q[1], q[0] + q[1] + q[2]);
        let (w0, w1, w2) = (qdot[0], qdot[0] + qdot[1], qdot[0] + qdot[1] + qdot[2]);
        let perp = |phi: f64| Vector2::new(-phi.sin(), phi.cos());
        let v1 = perp(p1) * (0.5 * self.l1 * w1);
        let v2 = perp(p1) * (self.l1 * w1) + perp(p2) * (0.5 * self.l2 * w2);
        let v0 = -(v1 * self.m1 + v2 * self.m2) / self.total_mass();
        [(v0, w0), (v0 + v1, w1), (v0 + v2, w2)]
    }

    /// Total angular momentum about the system CoM, Σ m r×v + I φ', from the
    /// full planar multibody model. Zero along every admissible motion.
    pub fn angular_momentum(&self, q: &State, qdot: &State) -> f64 {
        let poses = self.body_poses(q);
        let vels = self.body_velocities(q, qdot);
        let masses = [self.m0, self.m1, self.m2];
        let inertias = [self.i0, self.i1, self.i2];
        (0..3)
            .map(|i| masses[i] * cross(&poses[i].position, &vels[i].0) + inertias[i] * vels[i].1)
            .sum()
    }

    /// θ0' making the multibody angular momentum zero (it is affine in θ0'),
    /// an independent check of Eq. 13.
    pub fn theta0_rate_multibody(&self, q: &State, theta1_dot: f64, theta2_dot: f64) -> f64 {
        let l0 = self.angular_momentum(q, &State::from_vec(vec![0.0, theta1_dot, theta2_dot]));
        let l1 = self.angular_momentum(q, &State::from_vec(vec![1.0, theta1_dot, theta2_dot]));
        -l0 / (l1 - l0)
    }
}

/// The kinematic model q' = G(q) u of Eq. 13 (driftless).
#[derive(Debug, Clone, Default)]
pub struct SpaceRobotModel {
    /// Physical parameters.
    pub robot: SpaceRobot,
}

impl KinematicModel for SpaceRobotModel {
    fn name(&self) -> &'static str {
        "space_robot"
    }
    fn state_names(&self) -> &'static [&'static str] {
        &["theta0", "theta1", "theta2"]
    }
    fn input_names(&self) -> &'static [&'static str] {
        &["theta1_dot", "theta2_dot"]
    }
    fn angular_states(&self) -> &'static [usize] {
        &[0, 1, 2]
    }
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        let (p, r) = self.robot.one_form(q[2]);
        DMatrix::from_row_slice(3, 2, &[p, r, 1.0, 0.0, 0.0, 1.0])
    }
    fn velocity(&self, _t: f64, q: &State, u: &Input) -> State {
        State::from_vec(vec![self.robot.theta0_rate(q[2], u[0], u[1]), u[0], u[1]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn eq17_constants_match_print() {
        let r = SpaceRobot::default();
        r.validate().unwrap();
        // Printed: A = -89.848, B = -13.92.
        assert!((r.coeff_a() - -89.848).abs() < 5e-4, "A = {}", r.coeff_a());
        assert!((r.coeff_b() - -13.92).abs() < 5e-3, "B = {}", r.coeff_b());
        // Eq. 14's a, b satisfy a = -Δ - M I0 and Δ = A + B cos θ2.
        for t in [0.0, 0.7, 2.0, -3.0] {
            assert!((r.delta(t) - (r.coeff_a() + r.coeff_b() * f64::cos(t))).abs() < 1e-12);
            assert!((r.a(t) + r.delta(t) + r.m_i0()).abs() < 1e-12);
        }
    }

    #[test]
    fn analytic_velocities_match_finite_differences() {
        let r = SpaceRobot::default();
        let q = State::from_vec(vec![0.3, -1.1, 2.2]);
        let qd = State::from_vec(vec![0.4, 0.9, -0.6]);
        let h = 1e-6;
        let plus = r.body_poses(&(&q + &qd * h));
        let minus = r.body_poses(&(&q - &qd * h));
        let v = r.body_velocities(&q, &qd);
        for i in 0..3 {
            let fd = (plus[i].position - minus[i].position) / (2.0 * h);
            assert!((fd - v[i].0).norm() < 1e-8, "body {i}");
            assert!(((plus[i].angle - minus[i].angle) / (2.0 * h) - v[i].1).abs() < 1e-8);
        }
    }

    #[test]
    fn system_com_stays_at_origin() {
        let r = SpaceRobot::default();
        let q = State::from_vec(vec![1.0, 0.4, -2.5]);
        let p = r.body_poses(&q);
        let com = p[0].position * r.m0 + p[1].position * r.m1 + p[2].position * r.m2;
        assert!(com.norm() < 1e-14);
        // Joint 1 coincides with the vehicle CoM; link CoMs at mid-length.
        let j = r.joint_positions(&q);
        assert!((j[0] - p[0].position).norm() < 1e-15);
        assert!(((p[1].position - j[0]).norm() - 0.25).abs() < 1e-12);
        assert!(((p[2].position - j[1]).norm() - 0.175).abs() < 1e-12);
    }

    proptest! {
        #![proptest_config(crate::prop_config::config(64))]
        /// The multibody zero-angular-momentum rate equals Eq. 13 everywhere,
        /// which validates the geometry documented at the top of this module.
        #[test]
        fn multibody_matches_eq13(
            t0 in -3.2f64..3.2, t1 in -3.2f64..3.2, t2 in -3.2f64..3.2,
            u1 in -2.0f64..2.0, u2 in -2.0f64..2.0,
        ) {
            let r = SpaceRobot::default();
            let q = State::from_vec(vec![t0, t1, t2]);
            let eq13 = r.theta0_rate(t2, u1, u2);
            let mb = r.theta0_rate_multibody(&q, u1, u2);
            prop_assert!((eq13 - mb).abs() < 1e-12 * (1.0 + eq13.abs()), "{eq13} vs {mb}");
            // And the full admissible velocity has zero angular momentum.
            let qd = State::from_vec(vec![eq13, u1, u2]);
            prop_assert!(r.angular_momentum(&q, &qd).abs() < 1e-12);
        }

        /// Same check with velocities from finite differences of the CoM
        /// positions (independent of the analytic velocity code).
        #[test]
        fn multibody_finite_difference_momentum_zero(
            t0 in -3.2f64..3.2, t1 in -3.2f64..3.2, t2 in -3.2f64..3.2,
            u1 in -2.0f64..2.0, u2 in -2.0f64..2.0,
        ) {
            let r = SpaceRobot::default();
            let q = State::from_vec(vec![t0, t1, t2]);
            let qd = State::from_vec(vec![r.theta0_rate(t2, u1, u2), u1, u2]);
            let h = 1e-5;
            let (p, m) = (r.body_poses(&(&q + &qd * h)), r.body_poses(&(&q - &qd * h)));
            let c = r.body_poses(&q);
            let masses = [r.m0, r.m1, r.m2];
            let inertias = [r.i0, r.i1, r.i2];
            let l: f64 = (0..3).map(|i| {
                let v = (p[i].position - m[i].position) / (2.0 * h);
                let w = (p[i].angle - m[i].angle) / (2.0 * h);
                masses[i] * cross(&c[i].position, &v) + inertias[i] * w
            }).sum();
            prop_assert!(l.abs() < 1e-7, "L = {l}");
        }
    }
}
