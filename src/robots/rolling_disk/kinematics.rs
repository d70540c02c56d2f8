//! The disk rolling without slipping (seed 000, Eq. 3).
//!
//! State (x, y, θ, α): contact point, rolling angle, heading. Inputs (θ', α').
//! The paper measures α from the +y axis towards +x: x' = r sin α θ', y' = r cos α θ'.

use crate::model::{Input, KinematicModel, State};
use nalgebra::DMatrix;

/// Rolling disk of radius `r`.
#[derive(Debug, Clone, Copy)]
pub struct RollingDisk {
    /// Wheel radius in metres.
    pub r: f64,
}

impl KinematicModel for RollingDisk {
    fn name(&self) -> &'static str {
        "rolling_disk"
    }
    fn state_names(&self) -> &'static [&'static str] {
        &["x", "y", "theta", "alpha"]
    }
    fn input_names(&self) -> &'static [&'static str] {
        &["theta_rate", "alpha_rate"]
    }
    fn angular_states(&self) -> &'static [usize] {
        &[2, 3]
    }
    fn position_states(&self) -> Option<[usize; 2]> {
        Some([0, 1])
    }
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        let a = q[3];
        DMatrix::from_row_slice(
            4,
            2,
            &[
                self.r * a.sin(),
                0.0,
                self.r * a.cos(),
                0.0,
                1.0,
                0.0,
                0.0,
                1.0,
            ],
        )
    }
    fn velocity(&self, _t: f64, q: &State, u: &Input) -> State {
        let a = q[3];
        State::from_vec(vec![
            self.r * a.sin() * u[0],
            self.r * a.cos() * u[0],
            u[0],
            u[1],
        ])
    }
}
