//! The kinematic bicycle: a car-like robot reduced to one rear and one
//! steered front wheel on its centre line.
//!
//! State (x, y, θ, φ): the midpoint of the rear axle, the heading (the car's
//! +x axis, from the world +x towards +y) and the steering angle of the
//! virtual centre front wheel. Inputs (v, φ'): forward speed of the
//! rear-axle midpoint, m/s, and steering rate, rad/s.
//!
//! x' = v cos θ, y' = v sin θ, θ' = v tan φ / L, φ' = φ'  (L: wheelbase).
//!
//! The steering angle is limited to |φ| ≤ φ_max like the real steering: at
//! the limit a steering rate that pushes further is dropped (φ' = 0), so
//! [`KinematicModel::velocity`] is not [`KinematicModel::input_matrix`]
//! times u there; inside the limit it is.

use super::{Input, KinematicModel, State};
use nalgebra::DMatrix;

/// The kinematic bicycle.
#[derive(Debug, Clone, Copy)]
pub struct Bicycle {
    /// Wheelbase L (rear axle to front axle), m.
    pub wheelbase: f64,
    /// Steering limit φ_max, rad (0 < φ_max < π/2).
    pub max_steer: f64,
}

impl Bicycle {
    /// Whether a steering rate `rate` at angle `phi` is dropped by the limit.
    pub fn clipped(&self, phi: f64, rate: f64) -> bool {
        (phi >= self.max_steer && rate > 0.0) || (phi <= -self.max_steer && rate < 0.0)
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
        &["x", "y", "theta", "phi"]
    }
    fn input_names(&self) -> &'static [&'static str] {
        &["v", "steer_rate"]
    }
    fn angular_states(&self) -> &'static [usize] {
        &[2, 3]
    }
    fn position_states(&self) -> Option<[usize; 2]> {
        Some([0, 1])
    }
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        let (s, c) = q[2].sin_cos();
        let k = q[3].tan() / self.wheelbase;
        DMatrix::from_row_slice(4, 2, &[c, 0.0, s, 0.0, k, 0.0, 0.0, 1.0])
    }
    fn velocity(&self, _t: f64, q: &State, u: &Input) -> State {
        let (s, c) = q[2].sin_cos();
        let rate = if self.clipped(q[3], u[1]) { 0.0 } else { u[1] };
        State::from_vec(vec![
            u[0] * c,
            u[0] * s,
            u[0] * q[3].tan() / self.wheelbase,
            rate,
        ])
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
}
