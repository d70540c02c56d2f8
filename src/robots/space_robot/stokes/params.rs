//! Parameters of the Stokes space planner and their checks.

use crate::planner::PlanError;
use crate::robots::space_robot::stokes::invalid;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The paper's λ for ABCD (seed 000 §4.1), degrees.
pub const PAPER_LAMBDA_DEG: f64 = 125.0;
/// The paper's γ for AXYZ, degrees.
pub const PAPER_GAMMA_DEG: f64 = 75.0;

/// Which side of the rectangle is given; the other is solved from Eq. 20.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FixedSide {
    /// Try the paper's λ = 125° and γ = 75°, each also mirrored about the
    /// goal, on every goal branch θ0 + 2πk; keep the cheapest feasible plan.
    Auto,
    /// λ, the far θ1 side (absolute joint-1 angle before any translation), is given.
    Lambda,
    /// γ, the far θ2 side (absolute joint-2 angle), is given.
    Gamma,
}

/// What "cheapest" means when several rectangles are feasible.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Cost {
    /// Plan duration under the rate limits.
    Duration,
    /// Total joint travel |Δθ1| + |Δθ2|.
    Travel,
}

/// Seed 000 §4.1 Stokes planner for the space robot: rectangles in the joint
/// plane whose enclosed area turns the vehicle. Angles in degrees.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct StokesSpaceParams {
    /// Which side is fixed (`auto`: search, see [`FixedSide::Auto`]).
    pub fixed_side: FixedSide,
    /// λ or γ in degrees (default: the paper's λ = 125, γ = 75); only with
    /// `fixed_side = "lambda"` or `"gamma"`.
    pub fixed_value_deg: Option<f64>,
    /// When the configured side and value give no plan within the limits, try
    /// the mirrored value, the other side and the other goal branches
    /// (as `auto` does); `false` keeps to the configured choice.
    pub alternatives: bool,
    /// What the search minimises among feasible plans.
    pub cost: Cost,
    /// Number of cycles n tried first.
    #[schemars(range(min = 1, max = 10000))]
    pub cycles: usize,
    /// Most cycles tried when the rectangle violates the joint limit; at least `planner.cycles`.
    #[schemars(range(min = 1, max = 10000))]
    pub max_cycles: usize,
    /// Joint-1 limit |θ1| ≤ L (paper: 120); `None` = unconstrained.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub theta1_limit_deg: Option<f64>,
    /// Translation of the rectangle along BA in [0, |w|] (0 = ABCD-type,
    /// |w| = ADMN-type); `None` = automatic (0, then |w|, then the smallest
    /// translation meeting the joint limit).
    #[schemars(range(min = 0))]
    pub shift_deg: Option<f64>,
    /// Wrap the required rotation θ̄0 to (−180°, 180°] and also try the
    /// neighbouring branches θ̄0 ± 360°; `false`: θ̄0 exactly as written.
    pub wrap_vehicle_angle: bool,
    /// Plans whose total joint travel |Δθ1| + |Δθ2| exceeds this (degrees)
    /// are rejected (degenerate rectangles turn joint 1 dozens of times).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_joint_travel_deg: f64,
    /// Plans longer than this (s, under the rate limits) are rejected.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_duration_s: f64,
    /// Corner letters used in labels, starting with the loop's start point
    /// (e.g. "ADMN"); default "ABCDE".
    pub corner_names: Option<String>,
}

impl Default for StokesSpaceParams {
    fn default() -> Self {
        Self {
            fixed_side: FixedSide::Auto,
            fixed_value_deg: None,
            alternatives: true,
            cost: Cost::Duration,
            cycles: 3,
            max_cycles: 12,
            theta1_limit_deg: None,
            shift_deg: None,
            wrap_vehicle_angle: true,
            max_joint_travel_deg: 7200.0,
            max_duration_s: 600.0,
            corner_names: None,
        }
    }
}

impl StokesSpaceParams {
    /// The configured fixed value in degrees (the paper's for the side when
    /// not given); `None` for `auto`.
    pub fn fixed_deg(&self) -> Option<f64> {
        match self.fixed_side {
            FixedSide::Auto => None,
            FixedSide::Lambda => Some(self.fixed_value_deg.unwrap_or(PAPER_LAMBDA_DEG)),
            FixedSide::Gamma => Some(self.fixed_value_deg.unwrap_or(PAPER_GAMMA_DEG)),
        }
    }
}

pub(super) fn check_params(p: &StokesSpaceParams) -> Result<(), PlanError> {
    if let Some(v) = p.fixed_value_deg {
        if !v.is_finite() {
            return Err(invalid("fixed_value_deg", "must be finite"));
        }
        if p.fixed_side == FixedSide::Auto {
            return Err(invalid(
                "fixed_value_deg",
                "needs fixed_side = \"lambda\" or \"gamma\" (auto tries λ = 125° and γ = 75°)",
            ));
        }
    }
    if p.cycles == 0 {
        return Err(invalid("cycles", "must be at least 1"));
    }
    if p.max_cycles < p.cycles || p.max_cycles > 10_000 {
        return Err(invalid(
            "max_cycles",
            format!("must be in [cycles, 10000], got {}", p.max_cycles),
        ));
    }
    if let Some(l) = p.theta1_limit_deg {
        if !l.is_finite() || l <= 0.0 {
            return Err(invalid(
                "theta1_limit_deg",
                format!("must be positive, got {l}"),
            ));
        }
    }
    if let Some(s) = p.shift_deg {
        if !s.is_finite() || s < 0.0 {
            return Err(invalid("shift_deg", format!("must be ≥ 0, got {s}")));
        }
    }
    for (name, v) in [
        ("max_joint_travel_deg", p.max_joint_travel_deg),
        ("max_duration_s", p.max_duration_s),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(invalid(
                name,
                format!(
                    "must be positive and finite, got {}",
                    crate::numfmt::readable(v)
                ),
            ));
        }
    }
    if let Some(n) = &p.corner_names {
        if n.chars().count() < 4 {
            return Err(invalid("corner_names", "needs at least 4 letters"));
        }
    }
    Ok(())
}
