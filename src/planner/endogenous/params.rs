//! Planner parameters, control constraints and the iteration settings.
use schemars::JsonSchema;

/// Value (order 0) or first time derivative (order 1) of the control.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Order {
    /// u(t).
    Value,
    /// du/dt.
    Derivative,
}

/// A constraint u(t) = target or du/dt(t) = target at a segment-local time.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ControlConstraint {
    /// Local time in [0, T], s.
    pub time: f64,
    /// Value or derivative.
    pub order: Order,
    /// Target, one entry per input (rad/s or rad/s²).
    pub target: Vec<f64>,
}

/// Continuity imposed on u at the joins between segments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Continuity {
    /// Segments are planned independently (u may jump, scenario S1).
    None,
    /// u continuous (S2).
    C0,
    /// u and du/dt continuous (S3).
    C1,
}

/// A prescribed control value and/or derivative at a global time (a via
/// point of the control when strictly inside a segment). At a join time it
/// applies to both adjacent segments.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ControlPoint {
    /// Global time, s.
    pub time: f64,
    /// u(time), per input (rad/s for the space robot).
    #[serde(default)]
    pub value: Option<Vec<f64>>,
    /// du/dt(time), per input (rad/s² for the space robot).
    #[serde(default)]
    pub derivative: Option<Vec<f64>>,
}

/// Seed 001 endogenous-configuration-space planner: Legendre-series controls
/// iterated on the end-point map (Eq. 26). Control constraints are in model units (rad/s,
/// rad/s², or a declared model's input units) like the paper's du/dt(0) = 0.01; only
/// waypoints' angles are in degrees.
#[derive(Debug, Clone, serde::Deserialize, serde::Serialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct EndogenousParams {
    /// Duration T of every segment, s (paper: 20).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub segment_time: f64,
    /// Intermediate targets y1, y2, … (full states: angles in degrees, a declared
    /// model's other states in their units), reached at T, 2T, …; the goal is
    /// reached at (len + 1) T.
    pub via_deg: Vec<Vec<f64>>,
    /// Legendre terms per input (s = m · basis_terms parameters per segment); the
    /// parameters must at least match the segment's task and constraint rows.
    #[schemars(range(min = 1, max = 64))]
    pub basis_terms: usize,
    /// Error decay rate γ of Eq. 26 (paper: 0.02).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub gamma: f64,
    /// Euler step Δϑ of the ϑ-integration of Eq. 26 (γΔϑ ≤ 1; 1 = Newton step).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub dtheta: f64,
    /// Below this error (rad, or the model's units) the step becomes a full Gauss–Newton step
    /// (γΔϑ = 1) to finish quickly; 0 follows Eq. 26 to the end.
    #[schemars(range(min = 0))]
    pub newton_below: f64,
    /// Fixed RK4 steps per segment for the state and variational system.
    #[schemars(range(min = 1, max = 1000000))]
    pub rk4_steps: usize,
    /// Iteration cap per segment.
    #[schemars(range(min = 1))]
    pub max_iterations: usize,
    /// Stop when ‖q(T) − y‖ ≤ tolerance (rad, or the model's units).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub tolerance: f64,
    /// Relative SVD cut-off of the pseudo-inverse.
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 1))]
    pub rcond: f64,
    /// Give up when the best error has not dropped by 0.1 % for this many iterations.
    #[schemars(range(min = 1))]
    pub stall_iterations: usize,
    /// u(0), per input (rad/s for the space robot).
    pub u_start: Option<Vec<f64>>,
    /// du/dt(0), per input (rad/s² for the space robot).
    pub du_start: Option<Vec<f64>>,
    /// u at the final time, per input.
    pub u_end: Option<Vec<f64>>,
    /// du/dt at the final time, per input.
    pub du_end: Option<Vec<f64>>,
    /// Continuity at the joins.
    pub continuity: Continuity,
    /// Further value/derivative constraints at given times.
    pub control_points: Vec<ControlPoint>,
    /// Fail with `Unreachable` when the planned |u_i| exceeds `Limits::max_rate`.
    pub enforce_rate_limits: bool,
}

impl Default for EndogenousParams {
    fn default() -> Self {
        Self {
            segment_time: 20.0,
            via_deg: Vec::new(),
            basis_terms: 8,
            gamma: 0.02,
            dtheta: 1.0,
            newton_below: 1e-3,
            rk4_steps: 100,
            max_iterations: 2000,
            tolerance: 1e-8,
            rcond: 1e-10,
            stall_iterations: 200,
            u_start: None,
            du_start: None,
            u_end: None,
            du_end: None,
            continuity: Continuity::None,
            control_points: Vec::new(),
            enforce_rate_limits: true,
        }
    }
}

pub(super) struct Settings {
    pub(super) step: f64,
    pub(super) newton_below: f64,
    pub(super) rk4_steps: usize,
    pub(super) max_iterations: usize,
    pub(super) tolerance: f64,
    pub(super) rcond: f64,
    pub(super) stall_iterations: usize,
}
