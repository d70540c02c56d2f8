//! Feedback primitives P1–P3 for the overconstrained rover (seed 002, Murphey, Sec. IV-B).
//!
//! The plan is a feedback policy (the switching σ is unknown to the controller), built from:
//! - **P1** turn with the wheel at a fixed angle (default π/6, as in the seed's simulation)
//!   until the heading makes the approach angle (default π/6) with the line N through the goal
//!   at the goal heading, pointing towards N. The wheel is set and straightened with u1 = 0
//!   (g3 moves only ψ, so this is exact and slip-free).
//! - **P2** the linear law u1 = k, u2 = −k1·e − k2·(θ − θf) − k3·ψ, which stabilises the rover to
//!   N for both models; e is the signed distance to N (positive left of N when facing θf).
//! - **P3** straighten the wheel in place, then drive straight (forward or backward) to the
//!   point of the line of travel closest to the goal; at ψ = 0 both models coincide, so this leg
//!   accumulates no switching error.
//!
//! # Reading the seed
//! - The control law's "−k3 φ" uses φ, the rolling angle, which is cyclic and unbounded; the
//!   damping term must act on the steering angle ψ. We use ψ.
//! - "k1 (g⁻¹(q0 − qf))" is a vector where a scalar is needed (and q0 where the current q is
//!   meant): we read it as the lateral component of the current pose error expressed in the goal
//!   frame, i.e. the signed distance e to N. This matches the proof, which stabilises dist_N.
//! - P1 says N leaves "(x0, y0) (the vehicle's initial position)", but the proof and the Fig. 2
//!   caption (N = (8, s) for the goal (8, 2, π/2)) put N through the goal: we use the goal.
//! - The proof's claim that V = dist_N is a common Lyapunov function cannot hold (its derivative
//!   is k·sin(θ − θf), sign-indefinite). [`p2_routh_margins`] checks instead that the linearised
//!   loop is Hurwitz for both models; the tests also check a common quadratic Lyapunov function.
//!
//! # Deviations, and why
//! - **Saturated lateral term.** P2's law is linear, hence local ("sufficiently well aligned").
//!   P1 leaves the rover up to metres from N (8 m in the seed's example), where −k1·e would command
//!   full lock and make the rover circle. We clip e to ±e_sat with e_sat = (k2/k1)·approach angle,
//!   so the state P1 hands over (heading at the approach angle towards N, ψ = 0) is an equilibrium
//!   of P2's law: the rover drives straight towards N and the linear regime starts within e_sat.
//!   P1's target heading θ*(e) = θf − approach·clamp(e/e_sat, −1, 1) is the same equilibrium.
//! - **Turning direction.** The seed's run always turns one way (left, in its Fig. 2: from π/2
//!   to π/3 the long way, 11π/6 ≈ "nearly 2π" rad). [`TurnDirection::Shortest`] (default) turns
//!   the shorter way to θ*; `Left`/`Right` reproduce the seed's fixed-direction behaviour.
//! - **Stopping rule.** The printed P2 rule (|e| < ε/2, |θ − θf| < ε/(2d), d = distance to the
//!   goal) does not guarantee ending within ε in the seed's metric √(Δx² + Δy² + Δθ²): P3 drives
//!   along the heading, so its closest approach to the goal misses by |e cos δ − s sin δ| ≤
//!   |e| + d|δ| < ε (not ε/2 as the proof claims, so P3's "within ε/2" may be impossible), and the
//!   metric also counts |δ| itself, which the printed bound ε/(2d) leaves unbounded as d → 0
//!   (e.g. d = 0.5 m, e = 0.05 m, δ = 0.1 rad ends 0.14 > ε = 0.1 away). The tightened rule
//!   [`StopRule::Tightened`] stops when |e| ≤ ε/4 and |δ| ≤ ε/(4·max(d, 1 m)): then the miss is
//!   ≤ ε/4 + ε/4 and |δ| ≤ ε/4, so the final error is ≤ ε·√(1/4 + 1/16) ≈ 0.56 ε.
//! - **P3 end.** Rather than "within ε/2 of (xf, yf)", P3 stops at the closest approach (it slows
//!   down over the last control period so it lands there exactly); `done` is reported as soon as
//!   the pose is within ε of the goal in the seed's metric (heading error wrapped to (−π, π]).

use crate::model::{Input, State};
use crate::plan::{Command, ControlLaw, Controller, Limits, Plan, PolicyFactory};
use crate::planner::PlanError;
use crate::robots::rover::kinematics::{RoverGeometry, Sigma, SwitchingRover};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::sync::Arc;

/// Label indices of the primitives in [`Plan::labels`].
pub const LABEL_P1: usize = 0;
/// P2 label index.
pub const LABEL_P2: usize = 1;
/// P3 label index.
pub const LABEL_P3: usize = 2;

/// Which way P1 turns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum TurnDirection {
    /// The shorter way to the approach heading (ties: left).
    Shortest,
    /// Always left (ψ > 0), as the seed's run in Fig. 2 did.
    Left,
    /// Always right (ψ < 0).
    Right,
}

/// When P2 hands over to P3.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum StopRule {
    /// |e| ≤ ε/4 and |δ| ≤ ε/(4·max(d, 1 m)): guarantees ending within ε (module docs).
    Tightened,
    /// The seed's printed rule |e| < ε/2 and |δ| < ε/(2d); does not guarantee ε.
    Printed,
}

/// Seed 002 feedback primitives P1–P3 (turn, follow the line through the goal,
/// drive straight): a feedback policy. Angles in degrees.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct RoverPrimitiveParams {
    /// Drive speed k of P1 and P2 and top speed of P3, m/s (front-wheel ground speed).
    /// The default gains place P2's poles for the default speed; for a speed k choose
    /// k3 = 3p, k2 = 3p²l/k, k1 = p³l/k² (a triple pole −p, wheelbase l).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub speed: f64,
    /// Lateral gain k1, rad/(s·m).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub k1: f64,
    /// Heading gain k2, 1/s.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub k2: f64,
    /// Steering-angle damping k3, 1/s.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub k3: f64,
    /// Goal tolerance ε in the seed's SE(2) metric (m and rad alike).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub epsilon: f64,
    /// Wheel angle held during P1 (the seed chose π/6), deg; at most `max_steer_deg`.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub p1_wheel_deg: f64,
    /// Angle between the heading and N at which P1 ends (the seed: π/6), deg.
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 90))]
    pub approach_deg: f64,
    /// P1 is skipped when the heading is already this close to the approach heading, deg;
    /// below `approach_deg`.
    #[schemars(range(min = 0))]
    pub p1_tolerance_deg: f64,
    /// Turning direction of P1.
    pub turn: TurnDirection,
    /// P2 → P3 hand-over rule.
    pub stop_rule: StopRule,
    /// Steering-rate limit |u2|, deg/s.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub steer_rate_deg: f64,
    /// Steering-angle limit |ψ| enforced by the controller, deg.
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 90))]
    pub max_steer_deg: f64,
    /// The wheel counts as set (P1) or straight (P1, P3) within this angle, deg. In the ideal
    /// model the deadbeat steering command lands exactly; a physical servo needs slack, and
    /// P3 keeps steering towards ψ = 0 while it drives.
    #[schemars(range(min = 0, max = 1))]
    pub steer_tolerance_deg: f64,
    /// Control (sample-and-hold) period, s.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub period: f64,
    /// Time horizon of the run, s: at least one control period (`planner.period`).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub horizon: f64,
}

impl Default for RoverPrimitiveParams {
    /// Gains place the linearised P2 loop of model a (wheelbase l = 0.25 m) at a triple pole
    /// −p with p = 0.2 /s for k = 0.1 m/s: k3 = 3p, k2 = 3p²l/k, k1 = p³l/k² (length scale
    /// k/p = 0.5 m, one wheelbase). Model b is then Hurwitz as well.
    fn default() -> Self {
        RoverPrimitiveParams {
            speed: 0.1,
            k1: 0.2,
            k2: 0.3,
            k3: 0.6,
            epsilon: 0.1,
            p1_wheel_deg: 30.0,
            approach_deg: 30.0,
            p1_tolerance_deg: 1.0,
            turn: TurnDirection::Shortest,
            stop_rule: StopRule::Tightened,
            steer_rate_deg: 30.0,
            max_steer_deg: 45.0,
            steer_tolerance_deg: 0.05,
            period: 0.05,
            horizon: 1200.0,
        }
    }
}

/// Validated parameters in SI units (radians).
#[derive(Debug, Clone, Copy)]
struct Resolved {
    speed: f64,
    k1: f64,
    k2: f64,
    k3: f64,
    eps: f64,
    psi1: f64,
    approach: f64,
    p1_tol: f64,
    turn: TurnDirection,
    stop_rule: StopRule,
    rate: f64,
    psi_max: f64,
    psi_tol: f64,
    period: f64,
    e_sat: f64,
}

fn bad(name: &str, reason: impl Into<String>) -> PlanError {
    PlanError::InvalidParameter {
        name: name.to_string(),
        reason: reason.into(),
    }
}

/// Routh–Hurwitz margins k3·a1 − a0 of P2's linearisation about N for models a and b.
///
/// With e' = k(δ + ρ_σ ψ), δ' = kψ/L_σ, ψ' = −k1 e − k2 δ − k3 ψ (ρ_a = 0, ρ_b = r/(l+r),
/// L_a = l, L_b = l + r) the characteristic polynomial is s³ + k3 s² + a1 s + a0 with
/// a1 = k2 k/L + k1 k ρ, a0 = k1 k²/L; it is Hurwitz iff all coefficients and the margin are > 0.
pub fn p2_routh_margins(geom: &RoverGeometry, k: f64, k1: f64, k2: f64, k3: f64) -> [f64; 2] {
    [Sigma::A, Sigma::B].map(|s| {
        let big_l = geom.wheelbase(s);
        let rho = if s == Sigma::B {
            geom.r / (geom.l + geom.r)
        } else {
            0.0
        };
        let a1 = k2 * k / big_l + k1 * k * rho;
        let a0 = k1 * k * k / big_l;
        k3 * a1 - a0
    })
}

use crate::numfmt::readable;

impl RoverPrimitiveParams {
    fn resolve(&self, geom: &RoverGeometry, limits: &Limits) -> Result<Resolved, PlanError> {
        let pos = |name: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(bad(
                    name,
                    format!("must be finite and > 0, got {}", readable(v)),
                ))
            }
        };
        geom.validate()
            .map_err(|e| bad("geometry", e.to_string()))?;
        let speed = pos("speed", self.speed)?;
        let (k1, k2, k3) = (
            pos("k1", self.k1)?,
            pos("k2", self.k2)?,
            pos("k3", self.k3)?,
        );
        let eps = pos("epsilon", self.epsilon)?;
        let period = pos("period", self.period)?;
        let horizon = pos("horizon", self.horizon)?;
        if horizon < period {
            return Err(bad("horizon", "must be at least one control period"));
        }
        let mut rate = pos("steer_rate_deg", self.steer_rate_deg)?.to_radians();
        let max_steer = pos("max_steer_deg", self.max_steer_deg)?;
        if max_steer >= 90.0 {
            return Err(bad("max_steer_deg", "must be < 90"));
        }
        let psi1 = pos("p1_wheel_deg", self.p1_wheel_deg)?;
        if psi1 > max_steer {
            return Err(bad(
                "p1_wheel_deg",
                format!("exceeds max_steer_deg = {}", readable(max_steer)),
            ));
        }
        let approach = pos("approach_deg", self.approach_deg)?;
        if approach >= 90.0 {
            return Err(bad("approach_deg", "must be < 90 (P2 must move towards N)"));
        }
        let p1_tol = self.p1_tolerance_deg;
        if !(p1_tol.is_finite() && (0.0..approach).contains(&p1_tol)) {
            return Err(bad(
                "p1_tolerance_deg",
                format!("must be in [0, approach_deg), got {}", readable(p1_tol)),
            ));
        }
        if let Some(&m) = limits.max_rate.first() {
            if m.is_finite() && speed > m {
                return Err(bad(
                    "speed",
                    format!(
                        "{} exceeds the drive limit {}",
                        readable(speed),
                        readable(m)
                    ),
                ));
            }
        }
        if let Some(&m) = limits.max_rate.get(1) {
            if m.is_finite() && m > 0.0 {
                rate = rate.min(m);
            }
        }
        let margins = p2_routh_margins(geom, speed, k1, k2, k3);
        for (m, name) in margins.iter().zip(["a", "b"]) {
            if *m <= 0.0 {
                return Err(bad(
                    "k1, k2, k3",
                    format!(
                        "P2's linearised loop is not Hurwitz for model {name} (margin {m:.3e})"
                    ),
                ));
            }
        }
        let psi_tol = self.steer_tolerance_deg;
        if !(psi_tol.is_finite() && (0.0..=1.0).contains(&psi_tol)) {
            return Err(bad(
                "steer_tolerance_deg",
                format!("must be in [0, 1], got {}", readable(psi_tol)),
            ));
        }
        let psi_tol = psi_tol.to_radians().max(1e-12);
        let approach = approach.to_radians();
        Ok(Resolved {
            speed,
            k1,
            k2,
            k3,
            eps,
            psi1: psi1.to_radians(),
            approach,
            p1_tol: p1_tol.to_radians(),
            turn: self.turn,
            stop_rule: self.stop_rule,
            rate,
            psi_max: max_steer.to_radians(),
            psi_tol,
            period,
            e_sat: k2 / k1 * approach,
        })
    }
}

/// Wraps an angle to (−π, π].
pub fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(2.0 * PI);
    if w > PI {
        w - 2.0 * PI
    } else {
        w
    }
}

/// The seed's SE(2) metric √(Δx² + Δy² + Δθ²) between (x, y, θ) poses, with Δθ wrapped.
pub fn se2_distance(q: &State, goal: &State) -> f64 {
    let (dx, dy, dth) = (q[0] - goal[0], q[1] - goal[1], wrap(q[2] - goal[2]));
    (dx * dx + dy * dy + dth * dth).sqrt()
}

/// Goal-frame errors of a pose: (s along N, e across N (positive left), δ = θ − θf wrapped).
pub(crate) fn goal_frame_errors(q: &State, goal: &State) -> (f64, f64, f64) {
    let (sf, cf) = goal[2].sin_cos();
    let (dx, dy) = (q[0] - goal[0], q[1] - goal[1]);
    (cf * dx + sf * dy, -sf * dx + cf * dy, wrap(q[2] - goal[2]))
}

/// The final SE(2) error of P3 from pose `q` (ψ = 0): the goal's distance to the line of travel
/// and the unchanged heading error.
pub fn p3_final_error(q: &State, goal: &State) -> f64 {
    let (s, e, d) = goal_frame_errors(q, goal);
    let miss = e * d.cos() - s * d.sin();
    (miss * miss + d * d).sqrt()
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Phase {
    P1Steer,
    P1Drive,
    P1Straighten,
    P2,
    P3Steer,
    P3Drive,
    Finished,
}

impl Phase {
    fn label(self) -> usize {
        match self {
            Phase::P1Steer | Phase::P1Drive | Phase::P1Straighten => LABEL_P1,
            Phase::P2 => LABEL_P2,
            _ => LABEL_P3,
        }
    }
}

/// The P1–P3 controller; its only memory is the primitive in force and P1's turn bookkeeping.
struct PrimitiveController {
    p: Resolved,
    goal: [f64; 3],
    phase: Phase,
    /// +1 left, −1 right; chosen when P1 starts.
    dir: f64,
    /// Remaining turn angle (in direction `dir`) at the previous sample.
    prev_remaining: f64,
}

/// Outcome of evaluating one phase: a command, or a move to the next phase.
enum Step {
    Hold(f64, f64),
    Next(Phase),
}

impl PrimitiveController {
    fn new(p: Resolved, goal: [f64; 3]) -> Self {
        PrimitiveController {
            p,
            goal,
            phase: Phase::P1Steer,
            dir: 0.0,
            prev_remaining: 0.0,
        }
    }

    fn goal_state(&self) -> State {
        State::from_row_slice(&self.goal)
    }

    /// Steering rate that moves ψ to `target` in one period, within the rate limit.
    fn steer_to(&self, psi: f64, target: f64) -> f64 {
        ((target - psi) / self.p.period).clamp(-self.p.rate, self.p.rate)
    }

    /// P1's target heading: P2's ψ = 0 equilibrium heading for lateral error e.
    fn approach_heading(&self, e: f64) -> f64 {
        self.goal[2] - self.p.approach * (e / self.p.e_sat).clamp(-1.0, 1.0)
    }

    /// Angle still to turn in direction `dir` to reach θ*, in [0, 2π).
    fn remaining(&self, theta: f64, e: f64) -> f64 {
        (self.dir * (self.approach_heading(e) - theta)).rem_euclid(2.0 * PI)
    }

    fn p2_should_stop(&self, e: f64, delta: f64, d: f64) -> bool {
        let eps = self.p.eps;
        match self.p.stop_rule {
            StopRule::Tightened => e.abs() <= eps / 4.0 && delta.abs() <= eps / (4.0 * d.max(1.0)),
            StopRule::Printed => e.abs() < eps / 2.0 && d * delta.abs() < eps / 2.0,
        }
    }

    fn step(&mut self, q: &State) -> Step {
        let g = self.goal_state();
        let (_, e, delta) = goal_frame_errors(q, &g);
        let (theta, psi) = (q[2], q[3]);
        let p = self.p;
        match self.phase {
            Phase::P1Steer => {
                if self.dir == 0.0 {
                    let gap = wrap(self.approach_heading(e) - theta);
                    if gap.abs() <= p.p1_tol {
                        return Step::Next(Phase::P1Straighten);
                    }
                    self.dir = match p.turn {
                        TurnDirection::Shortest => {
                            if gap >= 0.0 || gap == -PI {
                                1.0
                            } else {
                                -1.0
                            }
                        }
                        TurnDirection::Left => 1.0,
                        TurnDirection::Right => -1.0,
                    };
                    self.prev_remaining = self.remaining(theta, e);
                }
                let target = self.dir * p.psi1;
                if (psi - target).abs() <= p.psi_tol {
                    Step::Next(Phase::P1Drive)
                } else {
                    Step::Hold(0.0, self.steer_to(psi, target))
                }
            }
            Phase::P1Drive => {
                let rem = self.remaining(theta, e);
                // Per period the heading moves far less than π, so a jump up means θ* was passed.
                let crossed = rem <= 1e-12 || rem > self.prev_remaining + PI;
                self.prev_remaining = rem;
                if crossed {
                    Step::Next(Phase::P1Straighten)
                } else {
                    Step::Hold(p.speed, self.steer_to(psi, self.dir * p.psi1))
                }
            }
            Phase::P1Straighten => {
                if psi.abs() <= p.psi_tol {
                    Step::Next(Phase::P2)
                } else {
                    Step::Hold(0.0, self.steer_to(psi, 0.0))
                }
            }
            Phase::P2 => {
                let d = (q[0] - g[0]).hypot(q[1] - g[1]);
                if self.p2_should_stop(e, delta, d) {
                    return Step::Next(Phase::P3Steer);
                }
                let e_c = e.clamp(-p.e_sat, p.e_sat);
                let u2 = (-p.k1 * e_c - p.k2 * delta - p.k3 * psi).clamp(-p.rate, p.rate);
                let u2 = u2.clamp((-p.psi_max - psi) / p.period, (p.psi_max - psi) / p.period);
                Step::Hold(p.speed, u2)
            }
            Phase::P3Steer => {
                if psi.abs() <= p.psi_tol {
                    Step::Next(Phase::P3Drive)
                } else {
                    Step::Hold(0.0, self.steer_to(psi, 0.0))
                }
            }
            Phase::P3Drive => {
                let (st, ct) = theta.sin_cos();
                // Along-heading distance to the goal's foot point; with ψ = 0 the motion is a
                // straight line, so u1 = s/T lands on it exactly at the end of the period.
                let s = ct * (g[0] - q[0]) + st * (g[1] - q[1]);
                if s.abs() <= 1e-9 {
                    Step::Next(Phase::Finished)
                } else {
                    Step::Hold(
                        (s / p.period).clamp(-p.speed, p.speed),
                        self.steer_to(psi, 0.0),
                    )
                }
            }
            Phase::Finished => Step::Hold(0.0, 0.0),
        }
    }
}

impl Controller for PrimitiveController {
    fn command(&mut self, _t: f64, q: &State) -> Command {
        let done = se2_distance(q, &self.goal_state()) <= self.p.eps;
        let mut u = (0.0, 0.0);
        if !done {
            // Phase changes are instantaneous: at most one pass through each phase.
            for _ in 0..8 {
                match self.step(q) {
                    Step::Hold(u1, u2) => {
                        u = (u1, u2);
                        break;
                    }
                    Step::Next(ph) => self.phase = ph,
                }
            }
        }
        Command {
            u: Input::from_vec(vec![u.0, u.1]),
            label: self.phase.label(),
            done,
        }
    }
}

struct Factory {
    p: Resolved,
    goal: [f64; 3],
}

impl PolicyFactory for Factory {
    fn start(&self) -> Box<dyn Controller> {
        Box::new(PrimitiveController::new(self.p, self.goal))
    }
}

/// Builds the P1–P3 feedback policy from `start` (x, y, θ, ψ) to `goal` (x, y, θ[, ψ ignored]).
///
/// The policy uses no knowledge of σ; the model supplies only its geometry, for the stability
/// check of P2's gains. `limits.max_rate` (if given) caps the drive speed (error if exceeded)
/// and the steering rate (the smaller limit wins).
pub fn plan(
    model: &SwitchingRover,
    start: &State,
    goal: &State,
    params: &RoverPrimitiveParams,
    limits: &Limits,
) -> Result<Plan, PlanError> {
    let p = params.resolve(&model.geometry, limits)?;
    if start.len() != 4 || start.iter().any(|v| !v.is_finite()) {
        return Err(bad("start", "needs 4 finite entries (x, y, theta, psi)"));
    }
    if !(3..=4).contains(&goal.len()) || goal.iter().any(|v| !v.is_finite()) {
        return Err(bad(
            "goal",
            "needs 3 or 4 finite entries (x, y, theta[, psi])",
        ));
    }
    if start[3].abs() > p.psi_max {
        return Err(bad("start", "initial steering angle exceeds max_steer_deg"));
    }
    let goal3 = [goal[0], goal[1], goal[2]];
    // Predict P1's choice from the start (the controller decides again, identically, at t = 0).
    let mut probe = PrimitiveController::new(p, goal3);
    let first = probe.command(0.0, start);
    let (s0, e0, d0) = goal_frame_errors(start, &State::from_row_slice(&goal3));
    let turn = if probe.dir == 0.0 {
        "none"
    } else if probe.dir > 0.0 {
        "left"
    } else {
        "right"
    };
    let p1_turn = if probe.dir == 0.0 {
        0.0
    } else {
        probe.prev_remaining
    };
    let margins = p2_routh_margins(&model.geometry, p.speed, p.k1, p.k2, p.k3);
    let details = serde_json::json!({
        "already_within_epsilon": first.done,
        "start_goal_frame": {"along": s0, "lateral": e0, "heading_error": d0},
        "p1_direction": turn,
        "p1_turn_rad": p1_turn,
        "p1_target_heading_rad": probe.approach_heading(e0),
        "e_sat_m": p.e_sat,
        "gains": {"k": p.speed, "k1": p.k1, "k2": p.k2, "k3": p.k3},
        "routh_margin": {"a": margins[0], "b": margins[1]},
        "steer_rate_rad_s": p.rate,
        "stop_rule": params.stop_rule,
        "epsilon": p.eps,
    });
    Ok(Plan {
        labels: vec!["P1".into(), "P2".into(), "P3".into()],
        segments: Vec::new(),
        duration: params.horizon,
        law: ControlLaw::Feedback {
            factory: Arc::new(Factory { p, goal: goal3 }),
            period: p.period,
        },
        details,
    })
}

#[cfg(test)]
mod tests;
