//! Free-floating planar space manipulator: a vehicle (base) carrying a
//! two-link arm, seed 001 Eq. 29 (Ratajczak 2025), with the robot of seed 000
//! §4.1 (Mukherjee & Anderson 1992).
//!
//! # State and inputs
//!
//! State q = (φ, θ1, θ2) in the order of seed 001 (φ is the base orientation,
//! called θ0 in seed 000; θ1, θ2 are the joint angles, θ2 relative to link 1).
//! Inputs u = (θ1', θ2'), the joint rates:
//!
//! ```text
//! φ'  = p/F(θ2) − G(θ2)/F(θ2) u1 − H(θ2)/F(θ2) u2
//! θ1' = u1
//! θ2' = u2
//! ```
//!
//! # Derivation (and the misprints of seed 001)
//!
//! Geometry: joint 1 sits at the vehicle's centre of mass (neither seed has a
//! vehicle offset term), link i has its centre of mass at distance d_i from
//! its proximal joint; seed 000's formulas assume uniform links, d_i = l_i/2,
//! which is the default here. With the system's centre of mass as origin
//! (linear momentum conserved), the reduced kinetic energy is
//!
//! ```text
//! L = ½ A (x̄'² + ȳ'²) + ½ I φ'² + ½ B (φ'+θ1')² + ½ C (φ'+θ1'+θ2')²
//!     + D cos θ2 (φ'+θ1')(φ'+θ1'+θ2')
//! ```
//!
//! Seed 001 prints the C term as ½C(φ'+θ1')² and the D term as
//! D cos θ2 (φ'+θ1')(φ'+θ1'); both are misprints (θ2' would then not appear
//! at all, giving H = 0 and contradicting Eq. 28). The conserved momentum
//! ∂L/∂φ' = p of the corrected form yields exactly Eq. 28's
//! F = I + B + C + 2D cos θ2, G = B + C + 2D cos θ2, H = C + D cos θ2, and
//! its translational part is what seed 001's A, B, C, D formulas compute
//! (½ Σ m_i|ρ_i'|² − |Σ m_i ρ_i'|²/(2A) with ρ_i the positions of the
//! centres of mass relative to the vehicle's).
//!
//! Seed 001's A, B, C, D (its "M" is the vehicle mass m0, m12 = m1 + m2) are
//! those of point-mass links. Rigid links add ½ I1 (φ'+θ1')² + ½ I2 (φ'+θ1'+θ2')²,
//! so the link inertias enter as B = B_pm + I1, C = C_pm + I2, while I = I0
//! is the vehicle's own inertia. Under this reading Eq. 29 coincides with
//! seed 000's Eq. 13-14, θ0' = (a θ1' + b θ2')/Δ with I = I0 + I1 + I2 there:
//! one checks Δ = −M F, a = M G, b = M H (M = total mass), so a/Δ = −G/F and
//! b/Δ = −H/F (tested in [`SpaceManipulator::seed000_base_rate`]). Seed 000's
//! A = −89.848 and B = −13.92 of its Eq. 17 are Δ = A + B cos θ2, i.e.
//! A = −M (I + B + C), B = −2 M D, also tested.
//!
//! With seed 000's robot: I = 1.52, B = 0.9110, C = 0.1028, D = 0.1963 (kg m²).

use crate::model::{Input, KinematicModel, State};
use nalgebra::{DMatrix, Matrix3, Matrix3x2, Vector2, Vector3};

/// Physical parameters (SI units). Defaults: seed 000 §4.1's aluminium robot.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SpaceManipulatorParams {
    /// Vehicle mass m0, kg.
    pub m0: f64,
    /// Vehicle moment of inertia about its centre of mass I0, kg m².
    pub i0: f64,
    /// Link 1 mass, kg.
    pub m1: f64,
    /// Link 1 moment of inertia about its centre of mass, kg m².
    pub i1: f64,
    /// Link 1 length (joint 1 to joint 2), m.
    pub l1: f64,
    /// Distance from joint 1 to link 1's centre of mass, m.
    pub d1: f64,
    /// Link 2 mass, kg.
    pub m2: f64,
    /// Link 2 moment of inertia about its centre of mass, kg m².
    pub i2: f64,
    /// Link 2 length, m.
    pub l2: f64,
    /// Distance from joint 2 to link 2's centre of mass, m.
    pub d2: f64,
    /// Conserved angular momentum p about the system's centre of mass, kg m²/s.
    pub p: f64,
}

impl Default for SpaceManipulatorParams {
    fn default() -> Self {
        Self {
            m0: 27.44,
            i0: 1.52,
            m1: 5.38,
            i1: 0.115,
            l1: 0.50,
            d1: 0.25,
            m2: 2.64,
            i2: 0.028,
            l2: 0.35,
            d2: 0.175,
            p: 0.0,
        }
    }
}

/// Inertia coefficients of the reduced Lagrangian (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct InertiaCoefficients {
    /// Total mass (seed 001's **A**), kg.
    pub a: f64,
    /// Link-1 coefficient **B** (point-mass part plus I1), kg m².
    pub b: f64,
    /// Link-2 coefficient **C** (point-mass part plus I2), kg m².
    pub c: f64,
    /// Coupling coefficient **D**, kg m².
    pub d: f64,
    /// Vehicle inertia **I** = I0, kg m².
    pub i: f64,
}

/// The free-floating planar space manipulator, q = (φ, θ1, θ2), u = (θ1', θ2').
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpaceManipulator {
    /// Physical parameters.
    pub params: SpaceManipulatorParams,
    /// Derived coefficients, cached.
    pub coeffs: InertiaCoefficients,
}

impl Default for SpaceManipulator {
    fn default() -> Self {
        Self::new(SpaceManipulatorParams::default())
    }
}

/// q' = f + G u at one state together with its linearisation.
#[derive(Debug, Clone, Copy)]
pub struct Linearization3 {
    /// q' = f(q) + G(q) u.
    pub qdot: Vector3<f64>,
    /// G(q).
    pub g: Matrix3x2<f64>,
    /// ∂(f + G u)/∂q.
    pub a: Matrix3<f64>,
}

/// Why a space manipulator's parameters do not describe a physical robot.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ParamsError {
    /// A mass, base inertia or length is not positive and finite.
    #[error("{name} must be positive and finite, got {value}")]
    NotPositive {
        /// The parameter (`m0`, `i0`, `m1`, `l1`, `m2`, `l2`).
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A link inertia or offset is negative or not finite.
    #[error("{name} must be non-negative and finite, got {value}")]
    Negative {
        /// The parameter (`i1`, `i2`, `d1`, `d2`).
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// The initial momentum `p` is not finite.
    #[error("p must be finite")]
    PNotFinite,
}

impl SpaceManipulator {
    /// Builds the model and its coefficients. Parameters are not validated
    /// here (see [`SpaceManipulator::validate`]).
    pub fn new(params: SpaceManipulatorParams) -> Self {
        let SpaceManipulatorParams {
            m0,
            i0,
            m1,
            i1,
            l1,
            d1,
            m2,
            i2,
            l2: _,
            d2,
            p: _,
        } = params;
        let mt = m0 + m1 + m2;
        // Seed 001's formulas (its "M" is the vehicle mass m0) plus link inertias.
        let b_pm = (m1 * m2 * (l1 - d1).powi(2) + m0 * (m1 * d1 * d1 + m2 * l1 * l1)) / mt;
        let c_pm = (m0 + m1) * m2 * d2 * d2 / mt;
        let d = (m1 * m2 * (l1 - d1) * d2 + m0 * m2 * l1 * d2) / mt;
        let coeffs = InertiaCoefficients {
            a: mt,
            b: b_pm + i1,
            c: c_pm + i2,
            d,
            i: i0,
        };
        Self { params, coeffs }
    }

    /// Checks that the parameters describe a physical robot.
    pub fn validate(&self) -> Result<(), ParamsError> {
        let p = &self.params;
        let positive = [
            ("m0", p.m0),
            ("i0", p.i0),
            ("m1", p.m1),
            ("l1", p.l1),
            ("m2", p.m2),
            ("l2", p.l2),
        ];
        for (name, value) in positive {
            if !(value.is_finite() && value > 0.0) {
                return Err(ParamsError::NotPositive { name, value });
            }
        }
        for (name, value) in [("i1", p.i1), ("i2", p.i2), ("d1", p.d1), ("d2", p.d2)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ParamsError::Negative { name, value });
            }
        }
        if !p.p.is_finite() {
            return Err(ParamsError::PNotFinite);
        }
        Ok(())
    }

    /// F(θ2) = I + B + C + 2D cos θ2 (always ≥ I0 > 0: F is the system's
    /// inertia about its centre of mass with the joints locked).
    pub fn f_coef(&self, theta2: f64) -> f64 {
        let k = &self.coeffs;
        k.i + k.b + k.c + 2.0 * k.d * theta2.cos()
    }

    /// G(θ2) = B + C + 2D cos θ2.
    pub fn g_coef(&self, theta2: f64) -> f64 {
        let k = &self.coeffs;
        k.b + k.c + 2.0 * k.d * theta2.cos()
    }

    /// H(θ2) = C + D cos θ2.
    pub fn h_coef(&self, theta2: f64) -> f64 {
        let k = &self.coeffs;
        k.c + k.d * theta2.cos()
    }

    /// Seed 000 Eq. 13-14: θ0' = (a θ1' + b θ2')/Δ, with its own coefficient
    /// formulas (I = I0 + I1 + I2, uniform links; p = 0 only). Valid for
    /// d_i = l_i/2; kept as an independent cross-check of Eq. 29.
    pub fn seed000_base_rate(&self, theta2: f64, dtheta1: f64, dtheta2: f64) -> f64 {
        let SpaceManipulatorParams {
            m0,
            i0,
            m1,
            i1,
            l1,
            m2,
            i2,
            l2,
            ..
        } = self.params;
        let mt = m0 + m1 + m2;
        let inertia = i0 + i1 + i2;
        let c2 = theta2.cos();
        let delta = (0.5 * m1 + m2).powi(2) * l1 * l1 + 0.25 * m2 * m2 * l2 * l2
            - (m0 + 0.5 * m1) * m2 * l1 * l2 * c2
            - mt * (inertia + (0.25 * m1 + m2) * l1 * l1 + 0.25 * m2 * l2 * l2);
        let a = -delta - mt * i0;
        let b = mt * (i2 + 0.25 * m2 * l2 * l2 + 0.5 * m2 * l1 * l2 * c2)
            - 0.25 * m2 * m2 * l2 * l2
            - 0.5 * m2 * (0.5 * m1 + m2) * l1 * l2 * c2;
        (a * dtheta1 + b * dtheta2) / delta
    }

    /// Seed 000 Eq. 17's constants (A, B) with Δ = A + B cos θ2.
    pub fn seed000_eq17(&self) -> (f64, f64) {
        let SpaceManipulatorParams {
            m0,
            i0,
            m1,
            i1,
            l1,
            m2,
            i2,
            l2,
            ..
        } = self.params;
        let mt = m0 + m1 + m2;
        let a = (0.5 * m1 + m2).powi(2) * l1 * l1 + 0.25 * m2 * m2 * l2 * l2
            - mt * (i0 + i1 + i2 + (0.25 * m1 + m2) * l1 * l1 + 0.25 * m2 * l2 * l2);
        let b = -(m0 + 0.5 * m1) * m2 * l1 * l2;
        (a, b)
    }

    /// Drift f(q) = (p/F(θ2), 0, 0).
    pub fn drift3(&self, q: &Vector3<f64>) -> Vector3<f64> {
        Vector3::new(self.params.p / self.f_coef(q[2]), 0.0, 0.0)
    }

    /// Input matrix G(q) of Eq. 29.
    pub fn input_matrix3(&self, q: &Vector3<f64>) -> Matrix3x2<f64> {
        let f = self.f_coef(q[2]);
        Matrix3x2::new(
            -self.g_coef(q[2]) / f,
            -self.h_coef(q[2]) / f,
            1.0,
            0.0,
            0.0,
            1.0,
        )
    }

    /// q' = f(q) + G(q) u, fixed size.
    pub fn velocity3(&self, q: &Vector3<f64>, u: &Vector2<f64>) -> Vector3<f64> {
        self.drift3(q) + self.input_matrix3(q) * u
    }

    /// q', G and the analytic ∂(f + G u)/∂q in one pass (one cos/sin).
    ///
    /// Only θ2 enters: with F' = G' = −2D sin θ2 and H' = −D sin θ2,
    /// ∂φ'/∂θ2 = [−p F' − (G'F − G F') u1 − (H'F − H F') u2] / F².
    pub fn linearize(&self, q: &Vector3<f64>, u: &Vector2<f64>) -> Linearization3 {
        let k = &self.coeffs;
        let (s2, c2) = q[2].sin_cos();
        let f = k.i + k.b + k.c + 2.0 * k.d * c2;
        let g = k.b + k.c + 2.0 * k.d * c2;
        let h = k.c + k.d * c2;
        let df = -2.0 * k.d * s2;
        let dg = df;
        let dh = -k.d * s2;
        let inv_f = 1.0 / f;
        let p = self.params.p;
        let phidot = (p - g * u[0] - h * u[1]) * inv_f;
        let dphi = (-p * df - (dg * f - g * df) * u[0] - (dh * f - h * df) * u[1]) * inv_f * inv_f;
        let mut a = Matrix3::zeros();
        a[(0, 2)] = dphi;
        Linearization3 {
            qdot: Vector3::new(phidot, u[0], u[1]),
            g: Matrix3x2::new(-g * inv_f, -h * inv_f, 1.0, 0.0, 0.0, 1.0),
            a,
        }
    }
}

impl KinematicModel for SpaceManipulator {
    fn name(&self) -> &'static str {
        "space_manipulator"
    }
    fn state_names(&self) -> &'static [&'static str] {
        &["phi", "theta1", "theta2"]
    }
    fn input_names(&self) -> &'static [&'static str] {
        &["dtheta1", "dtheta2"]
    }
    fn angular_states(&self) -> &'static [usize] {
        &[0, 1, 2]
    }
    fn drift(&self, q: &State) -> State {
        State::from_column_slice(self.drift3(&Vector3::new(q[0], q[1], q[2])).as_slice())
    }
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        let g = self.input_matrix3(&Vector3::new(q[0], q[1], q[2]));
        DMatrix::from_column_slice(3, 2, g.as_slice())
    }
    fn velocity(&self, _t: f64, q: &State, u: &Input) -> State {
        let v = self.velocity3(&Vector3::new(q[0], q[1], q[2]), &Vector2::new(u[0], u[1]));
        State::from_column_slice(v.as_slice())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn coefficients_of_seed000_robot() {
        let m = SpaceManipulator::default();
        let k = m.coeffs;
        assert!((k.a - 35.46).abs() < 1e-12);
        assert!((k.i - 1.52).abs() < 1e-12);
        assert!((k.b - 0.91096).abs() < 5e-5, "B = {}", k.b);
        assert!((k.c - 0.10283).abs() < 5e-5, "C = {}", k.c);
        assert!((k.d - 0.19628).abs() < 5e-5, "D = {}", k.d);
    }

    /// Seed 000 prints A = −89.848, B = −13.92 (Eq. 17); Δ = −M F ties them to Eq. 28.
    #[test]
    fn seed000_eq17_constants() {
        let m = SpaceManipulator::default();
        let (a, b) = m.seed000_eq17();
        assert!((a - (-89.848)).abs() < 5e-4, "A = {a}");
        assert!((b - (-13.92)).abs() < 5e-3, "B = {b}");
        let k = m.coeffs;
        assert!((a + k.a * (k.i + k.b + k.c)).abs() < 1e-9);
        assert!((b + 2.0 * k.a * k.d).abs() < 1e-9);
    }

    #[test]
    fn angular_momentum_is_conserved_by_eq29() {
        // F φ' + G θ1' + H θ2' = p along any admissible velocity.
        let m = SpaceManipulator::new(SpaceManipulatorParams {
            p: 0.37,
            ..Default::default()
        });
        let q = Vector3::new(0.3, -1.1, 2.2);
        let u = Vector2::new(0.4, -0.9);
        let v = m.velocity3(&q, &u);
        let mom = m.f_coef(q[2]) * v[0] + m.g_coef(q[2]) * v[1] + m.h_coef(q[2]) * v[2];
        assert!((mom - 0.37).abs() < 1e-13);
    }

    #[test]
    fn dynamic_interface_matches_fixed_size() {
        let m = SpaceManipulator::new(SpaceManipulatorParams {
            p: -0.2,
            ..Default::default()
        });
        let q = State::from_vec(vec![0.1, 0.2, 0.7]);
        let u = Input::from_vec(vec![0.3, -0.5]);
        let v1 = m.velocity(0.0, &q, &u);
        let v2 = m.drift(&q) + m.input_matrix(&q) * &u;
        assert!((v1 - v2).amax() < 1e-15);
    }

    proptest! {
        #![proptest_config(crate::prop_config::config(64))]

        /// Seed 000's θ0' (Eq. 13-14) equals seed 001's Eq. 29 (p = 0) for the same robot.
        #[test]
        fn seed000_and_seed001_agree(th2 in -10.0f64..10.0, w1 in -2.0f64..2.0, w2 in -2.0f64..2.0,
                                     phi in -4.0f64..4.0, th1 in -4.0f64..4.0) {
            let m = SpaceManipulator::default();
            let v = m.velocity3(&Vector3::new(phi, th1, th2), &Vector2::new(w1, w2));
            let v000 = m.seed000_base_rate(th2, w1, w2);
            prop_assert!((v[0] - v000).abs() < 1e-13 * (1.0 + v000.abs()), "{} vs {}", v[0], v000);
            prop_assert_eq!(v[1], w1);
            prop_assert_eq!(v[2], w2);
        }

        /// The analytic linearisation matches central differences (p ≠ 0 too).
        #[test]
        fn linearization_matches_finite_differences(q0 in -3.0f64..3.0, q1 in -3.0f64..3.0,
                                                    q2 in -3.0f64..3.0, u0 in -1.0f64..1.0,
                                                    u1 in -1.0f64..1.0, p in -1.0f64..1.0) {
            let m = SpaceManipulator::new(SpaceManipulatorParams { p, ..Default::default() });
            let q = Vector3::new(q0, q1, q2);
            let u = Vector2::new(u0, u1);
            let lin = m.linearize(&q, &u);
            prop_assert!((lin.qdot - m.velocity3(&q, &u)).amax() < 1e-15);
            prop_assert!((lin.g - m.input_matrix3(&q)).amax() < 1e-15);
            let h = 1e-6;
            for j in 0..3 {
                let mut dq = Vector3::zeros();
                dq[j] = h;
                let fd = (m.velocity3(&(q + dq), &u) - m.velocity3(&(q - dq), &u)) / (2.0 * h);
                prop_assert!((lin.a.column(j) - fd).amax() < 1e-8);
            }
        }
    }
}
