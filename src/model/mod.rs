//! Kinematic models: control-affine systems q' = f(q) + G(q) u.
//!
//! Every model in the harness implements [`KinematicModel`]; the ideal run
//! integrates it with the shared fixed-step RK4 of [`crate::integrate`].

pub mod spatial;

use nalgebra::{DMatrix, DVector};

/// Configuration vector (model-specific coordinates, see `state_names`).
pub type State = DVector<f64>;
/// Input (velocity command) vector, see `input_names`.
pub type Input = DVector<f64>;

/// A control-affine kinematic system q' = f(q) + G(q) u.
pub trait KinematicModel: Send + Sync {
    /// Short identifier, e.g. `"rolling_disk"`.
    fn name(&self) -> &'static str;
    /// Names of the state coordinates, in order (used in logs and tables).
    fn state_names(&self) -> &'static [&'static str];
    /// Names of the inputs, in order.
    fn input_names(&self) -> &'static [&'static str];
    /// Indices of state coordinates that are angles: their errors are wrapped to (-π, π].
    fn angular_states(&self) -> &'static [usize] {
        &[]
    }
    /// Indices of a planar position (x, y) in the state, if the model has one.
    fn position_states(&self) -> Option<[usize; 2]> {
        None
    }
    /// Every robot's planar position (x, y) indices, one pair per robot:
    /// position metrics report the worst robot and, with several, each one.
    /// Defaults to [`KinematicModel::position_states`] (one robot).
    fn robot_positions(&self) -> Vec<[usize; 2]> {
        self.position_states().into_iter().collect()
    }
    /// Drift f(q); zero for driftless systems.
    fn drift(&self, q: &State) -> State {
        State::zeros(q.len())
    }
    /// Input matrix G(q), n × m.
    fn input_matrix(&self, q: &State) -> DMatrix<f64>;
    /// Where state `i`'s equation is written, for messages: a declared
    /// model's `key `model.kinematics.NAME` (`EXPRESSION`)`; `None` for a
    /// compiled model.
    fn equation_source(&self, _i: usize) -> Option<String> {
        None
    }
    /// q' at time t. Models with a time-varying structure (e.g. switching) override this.
    fn velocity(&self, _t: f64, q: &State, u: &Input) -> State {
        self.drift(q) + self.input_matrix(q) * u
    }
}

/// A state and an input as a scenario writes them, for messages: `x = 0.1,
/// theta = 90°; v = 0.2, omega = 0` (angles in degrees).
pub(crate) fn point_text(model: &dyn KinematicModel, q: &[f64], u: &[f64]) -> String {
    let angular = model.angular_states();
    let state: Vec<String> = model
        .state_names()
        .iter()
        .zip(q)
        .enumerate()
        .map(|(i, (n, v))| {
            if angular.contains(&i) {
                format!("{n} = {}°", crate::numfmt::readable(v.to_degrees()))
            } else {
                format!("{n} = {}", crate::numfmt::readable(*v))
            }
        })
        .collect();
    let input: Vec<String> = model
        .input_names()
        .iter()
        .zip(u)
        .map(|(n, v)| format!("{n} = {}", crate::numfmt::readable(*v)))
        .collect();
    format!("{}; {}", state.join(", "), input.join(", "))
}
