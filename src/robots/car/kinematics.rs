//! The kinematic bicycle: a car-like robot reduced to one rear and one
//! steered front wheel on its centre line.
//!
//! Steered by rate ([`Steering::Rate`], the default): state (x, y, θ, φ):
//! the midpoint of the rear axle, the heading (the car's +x axis, from the
//! world +x towards +y) and the steering angle of the virtual centre front
//! wheel. Inputs (v, φ'): forward speed of the rear-axle midpoint, m/s, and
//! steering rate, rad/s.
//!
//! x' = v cos θ, y' = v sin θ, θ' = v tan φ / L, φ' = φ'  (L: wheelbase).
//!
//! The steering angle is limited to |φ| ≤ φ_max like the real steering: at
//! the limit a steering rate that pushes further is dropped (φ' = 0), so
//! [`KinematicModel::velocity`] is not [`KinematicModel::input_matrix`]
//! times u there; inside the limit it is.
//!
//! Steered by angle ([`Steering::Angle`]): state (x, y, θ), inputs (v, φ)
//! with φ the commanded steering angle, rad (what an Ackermann drive
//! message or a path planner gives). The steering is assumed to reach the
//! commanded angle at once; an angle beyond ±φ_max stops at the limit:
//! θ' = v tan(clamp(φ, −φ_max, φ_max)) / L.

use crate::model::{Input, KinematicModel, State};
use nalgebra::DMatrix;

/// What the bicycle's second input is.
#[derive(
    Debug,
    Clone,
    Copy,
    Default,
    PartialEq,
    Eq,
    serde::Deserialize,
    serde::Serialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum Steering {
    /// Inputs v and `steer_rate` (φ', rad/s); states x, y, θ and φ.
    #[default]
    Rate,
    /// Inputs v and `steer` (φ, rad); states x, y, θ. The steering joints are
    /// servoed to the commanded angle.
    Angle,
}

impl Steering {
    /// The name as written in scenario files.
    pub fn name(self) -> &'static str {
        match self {
            Steering::Rate => "rate",
            Steering::Angle => "angle",
        }
    }
}

/// The kinematic bicycle.
#[derive(Debug, Clone, Copy)]
pub struct Bicycle {
    /// Wheelbase L (rear axle to front axle), m.
    pub wheelbase: f64,
    /// Steering limit φ_max, rad (0 < φ_max < π/2).
    pub max_steer: f64,
    /// The second input: steering rate or steering angle.
    pub steering: Steering,
}

impl Bicycle {
    /// Whether a steering rate `rate` at angle `phi` is dropped by the limit.
    pub fn clipped(&self, phi: f64, rate: f64) -> bool {
        (phi >= self.max_steer && rate > 0.0) || (phi <= -self.max_steer && rate < 0.0)
    }

    /// Whether the ideal run's sample `(q, u)` asked for more steering than
    /// the limit gives: a rate pushing past it ([`Steering::Rate`]), or an
    /// angle beyond it ([`Steering::Angle`]).
    pub fn sample_clipped(&self, q: &State, u: &Input) -> bool {
        match self.steering {
            Steering::Rate => self.clipped(q[3], u[1]),
            Steering::Angle => u[1].abs() > self.max_steer,
        }
    }

    /// The steering angle the bicycle turns with for input `u` in state `q`:
    /// φ, or the commanded angle within ±φ_max.
    pub fn steer_angle(&self, q: &State, u: &Input) -> f64 {
        match self.steering {
            Steering::Rate => q[3],
            Steering::Angle => u[1].clamp(-self.max_steer, self.max_steer),
        }
    }
}

/// Ackermann steering: the angles (rad) of the left and right front wheels,
/// steered about pivots `half_track` (m) either side of the centre line,
/// whose axles meet the rear axle's line where the bicycle with steering
/// angle `phi` turns: tan δ = L tan φ / (L ∓ h tan φ) (left wheel inner in a
/// left turn, φ > 0).
pub fn ackermann(phi: f64, wheelbase: f64, half_track: f64) -> [f64; 2] {
    let (s, c) = phi.sin_cos();
    let l = wheelbase;
    [
        (l * s).atan2(l * c - half_track * s),
        (l * s).atan2(l * c + half_track * s),
    ]
}

/// dδ/dφ of each wheel's [`ackermann`] angle (left, right): how fast each
/// front wheel turns per unit of bicycle angle, (L / (L ∓ h tan φ))² (1 +
/// tan² φ) / (1 + tan² δ).
pub(crate) fn ackermann_slope(phi: f64, wheelbase: f64, half_track: f64) -> [f64; 2] {
    let t = phi.tan();
    let l = wheelbase;
    let side = |h: f64| {
        let d = l - h * t;
        let tan_delta = l * t / d;
        (l / d).powi(2) * (1.0 + t * t) / (1.0 + tan_delta * tan_delta)
    };
    [side(half_track), side(-half_track)]
}

/// The bicycle steering angle that [`ackermann`] maps to left wheel angle
/// `delta` (`side` 0) or right wheel angle (`side` 1).
pub fn bicycle_angle(delta: f64, side: usize, wheelbase: f64, half_track: f64) -> f64 {
    let (s, c) = delta.sin_cos();
    let h = if side == 0 { half_track } else { -half_track };
    (wheelbase * s).atan2(wheelbase * c + h * s)
}

/// Ground speeds of the left and right rear wheels when the rear-axle
/// midpoint moves at `v` with steering angle `phi`: v (1 ∓ h tan φ / L).
pub fn rear_speeds(v: f64, phi: f64, wheelbase: f64, half_track: f64) -> [f64; 2] {
    let k = half_track * phi.tan() / wheelbase;
    [v * (1.0 - k), v * (1.0 + k)]
}

impl KinematicModel for Bicycle {
    fn name(&self) -> &'static str {
        "car"
    }
    fn state_names(&self) -> &'static [&'static str] {
        match self.steering {
            Steering::Rate => &["x", "y", "theta", "phi"],
            Steering::Angle => &["x", "y", "theta"],
        }
    }
    fn input_names(&self) -> &'static [&'static str] {
        match self.steering {
            Steering::Rate => &["v", "steer_rate"],
            Steering::Angle => &["v", "steer"],
        }
    }
    fn angular_states(&self) -> &'static [usize] {
        match self.steering {
            Steering::Rate => &[2, 3],
            Steering::Angle => &[2],
        }
    }
    fn position_states(&self) -> Option<[usize; 2]> {
        Some([0, 1])
    }
    /// Steered by angle the bicycle is not control-affine (θ' = v tan φ / L):
    /// the columns are f(q, e_j) − f(q, 0), as for a declared model (the
    /// speed's column at straight steering; nothing uses it to plan).
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        let (s, c) = q[2].sin_cos();
        match self.steering {
            Steering::Rate => {
                let k = q[3].tan() / self.wheelbase;
                DMatrix::from_row_slice(4, 2, &[c, 0.0, s, 0.0, k, 0.0, 0.0, 1.0])
            }
            Steering::Angle => DMatrix::from_row_slice(3, 2, &[c, 0.0, s, 0.0, 0.0, 0.0]),
        }
    }
    fn velocity(&self, _t: f64, q: &State, u: &Input) -> State {
        let (s, c) = q[2].sin_cos();
        let turn = u[0] * self.steer_angle(q, u).tan() / self.wheelbase;
        match self.steering {
            Steering::Rate => {
                let rate = if self.clipped(q[3], u[1]) { 0.0 } else { u[1] };
                State::from_vec(vec![u[0] * c, u[0] * s, turn, rate])
            }
            Steering::Angle => State::from_vec(vec![u[0] * c, u[0] * s, turn]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both front axles and the rear axle meet at one turning centre, and
    /// the rear wheels' speeds are proportional to their turning radii.
    #[test]
    fn ackermann_axles_meet_at_the_turning_centre() {
        let (l, h) = (0.32, 0.12);
        for phi in [-0.6, -0.2, 0.05, 0.3, 0.55] {
            let [dl, dr] = ackermann(phi, l, h);
            // Turning centre on the rear axle's line: (0, R) with R = L / tan φ.
            let r = l / f64::tan(phi);
            for (d, y) in [(dl, h), (dr, -h)] {
                // The wheel's axle through (L, y) along (−sin δ, cos δ) passes (0, R).
                let t = -l / -d.sin();
                assert!(
                    (y + t * d.cos() - r).abs() < 1e-12 * r.abs().max(1.0),
                    "{phi}"
                );
            }
            assert!((bicycle_angle(dl, 0, l, h) - phi).abs() < 1e-14);
            let e = 1e-6;
            let (a, b) = (ackermann(phi + e, l, h), ackermann(phi - e, l, h));
            let slope = ackermann_slope(phi, l, h);
            for i in 0..2 {
                assert!(((a[i] - b[i]) / (2.0 * e) - slope[i]).abs() < 1e-8, "{phi}");
            }
            assert!((bicycle_angle(dr, 1, l, h) - phi).abs() < 1e-14);
            let [vl, vr] = rear_speeds(1.0, phi, l, h);
            assert!((vl / vr - (r - h) / (r + h)).abs() < 1e-12, "{phi}");
        }
        assert_eq!(ackermann(0.0, l, h), [0.0, 0.0]);
    }

    #[test]
    fn velocity_and_the_steering_limit() {
        let m = Bicycle {
            wheelbase: 0.3,
            max_steer: 0.5,
            steering: Steering::Rate,
        };
        let q = State::from_vec(vec![0.3, -1.0, 2.1, 0.2]);
        let u = Input::from_vec(vec![0.7, -0.4]);
        let v = m.velocity(0.0, &q, &u);
        assert!((m.input_matrix(&q) * &u - &v).amax() < 1e-15);
        assert!((v[2] - 0.7 * 0.2f64.tan() / 0.3).abs() < 1e-15);
        // At the limit: pushing further is dropped, turning back is not.
        let at = State::from_vec(vec![0.0, 0.0, 0.0, 0.5]);
        assert_eq!(
            m.velocity(0.0, &at, &Input::from_vec(vec![1.0, 0.3]))[3],
            0.0
        );
        assert_eq!(
            m.velocity(0.0, &at, &Input::from_vec(vec![1.0, -0.3]))[3],
            -0.3
        );
        let at = State::from_vec(vec![0.0, 0.0, 0.0, -0.5]);
        assert_eq!(
            m.velocity(0.0, &at, &Input::from_vec(vec![1.0, -0.3]))[3],
            0.0
        );
    }

    /// Steered by angle: the heading turns at v tan φ / L, the angle stops
    /// at the limit, and an angle past it is a clipped sample.
    #[test]
    fn steered_by_angle() {
        let m = Bicycle {
            wheelbase: 0.3,
            max_steer: 0.5,
            steering: Steering::Angle,
        };
        assert_eq!(m.state_names(), ["x", "y", "theta"]);
        assert_eq!(m.input_names(), ["v", "steer"]);
        let q = State::from_vec(vec![0.3, -1.0, 2.1]);
        let v = m.velocity(0.0, &q, &Input::from_vec(vec![0.7, -0.4]));
        assert_eq!(v.len(), 3);
        assert!((v[0] - 0.7 * 2.1f64.cos()).abs() < 1e-15);
        assert!((v[2] - 0.7 * (-0.4f64).tan() / 0.3).abs() < 1e-15);
        let past = Input::from_vec(vec![0.7, -0.9]);
        assert_eq!(m.velocity(0.0, &q, &past)[2], 0.7 * (-0.5f64).tan() / 0.3);
        assert!(m.sample_clipped(&q, &past));
        assert!(!m.sample_clipped(&q, &Input::from_vec(vec![0.7, 0.5])));
        let g = m.input_matrix(&q);
        assert_eq!((g.nrows(), g.ncols()), (3, 2));
    }
}
