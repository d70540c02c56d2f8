//! The planner's parameters (`[planner]` of `kind = "dilf"`): tolerance, gains, limits, the approach and their defaults.

use super::*;

/// When the task counts as done.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Tolerance {
    /// Platform position error, m.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub position: f64,
    /// Platform heading error, degrees.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub heading_deg: f64,
    /// Every joint's error, degrees.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub joint_deg: f64,
}

impl Default for Tolerance {
    fn default() -> Self {
        Tolerance {
            position: 0.02,
            heading_deg: 2.0,
            joint_deg: 2.0,
        }
    }
}

impl Tolerance {
    /// Whether q is within tolerance of the goal (every robot, every coordinate).
    pub fn reached(&self, q: &[f64], goal: &[f64]) -> bool {
        let robots = q.len() / DOF;
        (0..robots).all(|r| {
            let i = DOF * r;
            let pos = (q[i] - goal[i]).hypot(q[i + 1] - goal[i + 1]);
            let head = crate::compare::wrap_angle(q[i + 2] - goal[i + 2]).abs();
            let joints = (3..DOF)
                .map(|a| crate::compare::wrap_angle(q[i + a] - goal[i + a]).abs())
                .fold(0.0, f64::max);
            pos <= self.position
                && head <= self.heading_deg.to_radians()
                && joints <= self.joint_deg.to_radians()
        })
    }
}

/// Seed 004 dipolar inverse Lyapunov function: the feedback law of Eq. 18
/// (a feedback policy).
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DilfParams {
    /// λ of the analytic switches (Eqs. 6, 8).
    #[serde(default = "default_lambda")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub lambda: f64,
    /// The exponent k_v of Eq. 15 (larger: obstacles felt less far away).
    #[serde(default = "default_kv_exponent")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub kv_exponent: f64,
    /// The speed gain k_v of Eq. 18a.
    #[serde(default = "default_kv_gain")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub kv_gain: f64,
    /// k_o of Eq. 18b.
    #[serde(default = "default_ko")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub ko: f64,
    /// K_a of Eq. 18c: one gain per joint.
    #[serde(default = "default_ka")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub ka: [f64; 6],
    /// Largest platform speed, m/s.
    #[serde(default = "default_max_speed")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_speed: f64,
    /// Largest platform turn rate, rad/s.
    #[serde(default = "default_max_turn_rate")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_turn_rate: f64,
    /// Largest joint rate, rad/s.
    #[serde(default = "default_max_joint_rate")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_joint_rate: f64,
    /// Hold the heading while the platform's planar field is below this
    /// fraction of ‖f‖ (θ_d is undefined there; 0 disables).
    #[serde(default = "default_deadzone")]
    #[schemars(range(min = 0), extend("exclusiveMaximum" = 1))]
    pub heading_deadzone: f64,
    /// While a platform turns in place to its goal heading (the final
    /// alignment, ours), its arm joints go to their goal angles at this
    /// gain, 1/s (rate = gain × error, within `max_joint_rate`), instead of
    /// Eq. 18c's rates, which vanish there (default 1); 0: Eq. 18c
    /// throughout, the paper's law.
    #[serde(default = "default_align_joint_gain")]
    #[schemars(range(min = 0))]
    pub align_joint_gain: f64,
    /// The policy is evaluated every `period` seconds and held in between.
    #[serde(default = "default_period")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub period: f64,
    /// Run length if the goal is never reached, s.
    #[serde(default = "default_horizon")]
    #[schemars(range(max = 100000), extend("exclusiveMinimum" = 0))]
    pub horizon: f64,
    /// Coordinates of the arm parts' goal points.
    #[serde(default)]
    pub goal_frame: GoalFrame,
    /// How several robots' dipole factors combine in V (Eq. 15; see
    /// [`DipoleProduct`]): `"geometric_mean"` (default), `"printed"` or
    /// `"formation"` (ours).
    #[serde(default)]
    pub dipole: DipoleProduct,
    /// p of the field f = (Σ‖h2‖²)^p ∂V/∂q; Eq. 17 prints p = 2 (the research notes on seed 004 discuss it).
    #[serde(default = "default_field_power")]
    #[schemars(extend("exclusiveMinimum" = 1.5))]
    pub field_power: f64,
    /// Singularity enclosures (Eq. 13).
    #[serde(default)]
    pub singularity: SingularityEnclosure,
    /// Convergence test.
    #[serde(default)]
    pub tolerance: Tolerance,
    /// The hold guard ([`guard`]): scale each held input down until the
    /// predicted end of the hold keeps every barrier at half its value or
    /// more (ours: Eq. 18 is a continuous-time law, sampled here).
    #[serde(default = "default_hold_guard")]
    pub hold_guard: bool,
    /// When the law counts as stalled, and the hand-over to the final
    /// alignment ([`stall`]).
    #[serde(default)]
    pub stall: StallParams,
    /// Where the law reads a carried beam's grasps in the physics replay
    /// ([`Grasps`]).
    #[serde(default)]
    pub grasps: Grasps,
    /// A cap on the heading Eq. 18 may demand near the goal (ours; off by
    /// default, the paper's law).
    #[serde(default)]
    pub approach: Approach,
    /// The platform's speed law, `"projection"` (default, ours) or
    /// `"sign"` (Eq. 18a); both saturate at `max_speed`.
    #[serde(default)]
    pub speed: SpeedLaw,
    /// Intermediate goals: turn, translate, turn (ours; by default where the
    /// law alone does not converge or strains a carried object;
    /// `mode = "off"` is the paper's law straight to the goal; [`sequence`]).
    #[serde(default)]
    pub sequence: SequenceParams,
}

/// `[planner.approach]`: near its goal a platform's heading stays within
/// `heading_deg` of its goal heading (ours). A unicycle removes a lateral
/// error δ at distance d only with a heading swing of order δ/d, so on its
/// last centimetres Eq. 18 turns a platform by tens of degrees; two
/// platforms holding one object cannot turn that far apart. Within
/// `radius` of its goal the law's ω is set to 0 whenever it would turn the
/// platform further than the cap from its goal heading; V̇ ≥ 0 still holds
/// (the platform's term v·proj + ω f_θ keeps v·proj ≥ 0 when ω → 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Approach {
    /// Distance from the goal within which the cap holds, m; 0: no cap.
    #[schemars(range(min = 0))]
    pub radius: f64,
    /// Largest |θ − θ_goal| the law may turn to within `radius`, degrees.
    #[schemars(extend("exclusiveMinimum" = 0), range(max = 180))]
    pub heading_deg: f64,
}

impl Default for Approach {
    fn default() -> Self {
        Approach {
            radius: 0.0,
            heading_deg: 180.0,
        }
    }
}

/// Where the law reads the flanges that hold a beam (its q_f, its
/// ellipsoids, the grasp wrench) in the physics replay.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Grasps {
    /// From the planar state through the kinematic model (as in the ideal run).
    #[default]
    Model,
    /// From the simulated 3D flange poses (ours): a tipped platform or an
    /// arm pulled off its servo reference moves them, the planar state not.
    Measured,
}

fn default_hold_guard() -> bool {
    true
}

fn default_lambda() -> f64 {
    1.0
}
fn default_kv_exponent() -> f64 {
    3.0
}
fn default_kv_gain() -> f64 {
    5.0
}
fn default_ko() -> f64 {
    1.0
}
/// K_a roughly ∝ 1/(lever arm)²: the wrist joints move the parts' points
/// little, so their goal terms are weak.
fn default_ka() -> [f64; 6] {
    [50.0, 50.0, 50.0, 300.0, 300.0, 3000.0]
}
fn default_max_speed() -> f64 {
    0.5
}
fn default_max_turn_rate() -> f64 {
    0.8
}
fn default_max_joint_rate() -> f64 {
    0.6
}
fn default_horizon() -> f64 {
    60.0
}
fn default_period() -> f64 {
    0.02
}
fn default_deadzone() -> f64 {
    0.0
}
/// The arm's joints go to their goal angles in the final alignment at 1/s:
/// on random single-robot goals behind a wall Eq. 18c alone left a wrist
/// joint 2.1°–2.8° off in 5 of 20 physics runs, at 1/s none
/// (docs/src/research/seed-004.md).
fn default_align_joint_gain() -> f64 {
    1.0
}
fn default_field_power() -> f64 {
    2.0
}

impl DilfParams {
    /// The potential's own parameters (Eq. 14's λ, k_v, goal frame, dipole,
    /// singularity and field power).
    pub fn potential(&self) -> potential::PotentialParams {
        potential::PotentialParams {
            lambda: self.lambda,
            kv: self.kv_exponent,
            goal_frame: self.goal_frame,
            dipole: self.dipole,
            singularity: self.singularity,
            field_power: self.field_power,
        }
    }

    /// Range checks; messages name the parameter.
    pub fn validate(&self) -> Result<(), PlanError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        check_param("lambda", pos(self.lambda), "must be > 0")?;
        check_param("kv_exponent", pos(self.kv_exponent), "must be > 0")?;
        check_param("kv_gain", pos(self.kv_gain), "must be > 0")?;
        check_param("ko", pos(self.ko), "must be > 0")?;
        check_param(
            "ka",
            self.ka.iter().all(|k| pos(*k)),
            "K_a must be positive definite: every gain > 0",
        )?;
        check_param("max_speed", pos(self.max_speed), "must be > 0")?;
        check_param("max_turn_rate", pos(self.max_turn_rate), "must be > 0")?;
        check_param("max_joint_rate", pos(self.max_joint_rate), "must be > 0")?;
        check_param("period", pos(self.period), "must be > 0")?;
        check_param(
            "align_joint_gain",
            self.align_joint_gain.is_finite() && self.align_joint_gain >= 0.0,
            "must be ≥ 0 (1/s; 0: Eq. 18c throughout)",
        )?;
        check_param(
            "heading_deadzone",
            (0.0..1.0).contains(&self.heading_deadzone),
            "must be in [0, 1)",
        )?;
        check_param(
            "field_power",
            self.field_power.is_finite() && self.field_power > 1.5,
            "must be > 1.5 (f must vanish at the goal, where V ~ 1/r)",
        )?;
        check_param(
            "horizon",
            pos(self.horizon) && self.horizon <= 1e5,
            "must be in (0, 1e5] s",
        )?;
        check_param(
            "approach.radius",
            self.approach.radius.is_finite() && self.approach.radius >= 0.0,
            "must be ≥ 0 m (0: no cap)",
        )?;
        check_param(
            "approach.heading_deg",
            self.approach.heading_deg > 0.0 && self.approach.heading_deg <= 180.0,
            "must be in (0, 180] degrees",
        )?;
        let s = &self.singularity;
        check_param(
            "singularity",
            [s.shoulder, s.elbow, s.wrist]
                .iter()
                .all(|d| d.is_finite() && *d >= 0.0),
            "enclosure half-widths must be ≥ 0",
        )?;
        let t = &self.tolerance;
        check_param(
            "tolerance",
            [t.position, t.heading_deg, t.joint_deg]
                .iter()
                .all(|v| pos(*v)),
            "every tolerance must be > 0",
        )?;
        if let Err((name, reason)) = self.sequence.check() {
            return Err(PlanError::InvalidParameter {
                name: name.into(),
                reason: reason.into(),
            });
        }
        if let Err((name, reason)) = self.stall.check() {
            return Err(PlanError::InvalidParameter {
                name: name.into(),
                reason: reason.into(),
            });
        }
        Ok(())
    }

    /// Gains of Eq. 18.
    pub fn gains(&self) -> Gains {
        Gains {
            kv_gain: self.kv_gain,
            ko: self.ko,
            ka: self.ka,
            max_speed: self.max_speed,
            max_turn_rate: self.max_turn_rate,
            max_joint_rate: self.max_joint_rate,
            heading_deadzone: self.heading_deadzone,
            goal_lock_radius: 0.5 * self.tolerance.position,
            approach_radius: self.approach.radius,
            approach_heading: self.approach.heading_deg.to_radians(),
            speed: self.speed,
            formation_side: self.dipole == DipoleProduct::Formation,
            align_joint_gain: self.align_joint_gain,
        }
    }
}
