//! The unicycle: kinematics of a differential-drive robot.
//!
//! State (x, y, θ): the midpoint of the drive axle and the heading (the
//! robot's +x axis, from the world +x towards +y). Inputs (v, ω): forward
//! speed of the axle midpoint, m/s, and turn rate, rad/s.
//! x' = v cos θ, y' = v sin θ, θ' = ω.

use crate::model::{Input, KinematicModel, State};
use nalgebra::DMatrix;

/// The unicycle (no parameters: the wheel radius and the track only map
/// (v, ω) to wheel rates, in the physics).
#[derive(Debug, Clone, Copy, Default)]
pub struct Unicycle;

impl KinematicModel for Unicycle {
    fn name(&self) -> &'static str {
        "diff_drive"
    }
    fn state_names(&self) -> &'static [&'static str] {
        &["x", "y", "theta"]
    }
    fn input_names(&self) -> &'static [&'static str] {
        &["v", "omega"]
    }
    fn angular_states(&self) -> &'static [usize] {
        &[2]
    }
    fn position_states(&self) -> Option<[usize; 2]> {
        Some([0, 1])
    }
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        let (s, c) = q[2].sin_cos();
        DMatrix::from_row_slice(3, 2, &[c, 0.0, s, 0.0, 0.0, 1.0])
    }
    fn velocity(&self, _t: f64, q: &State, u: &Input) -> State {
        let (s, c) = q[2].sin_cos();
        State::from_vec(vec![u[0] * c, u[0] * s, u[1]])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn velocity_is_the_input_matrix_times_u() {
        let m = Unicycle;
        let q = State::from_vec(vec![0.3, -1.0, 2.1]);
        let u = Input::from_vec(vec![0.7, -0.4]);
        let v = m.velocity(0.0, &q, &u);
        assert!((m.input_matrix(&q) * &u - &v).amax() < 1e-15);
        assert!((v[0] - 0.7 * 2.1f64.cos()).abs() < 1e-15);
        assert_eq!(v[2], -0.4);
    }
}
