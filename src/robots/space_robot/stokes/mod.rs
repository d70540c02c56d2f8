//! Stokes / surface-integral planner for the planar space robot (seed 000, §4.1).
//!
//! 1. Path OA: θ1, θ2 go straight to their goal values; θ0 drifts to θ0d (the
//!    line integral of Eq. 13 along OA, Gauss-Legendre quadrature).
//! 2. The remainder θ̄0 = θ0f − θ0d is produced by n cycles of a rectangle in the
//!    θ1-θ2 plane with one side on θ2 = θ2f and A = (θ1f, θ2f) on that side.
//!    By Green's theorem (Eq. 16-19) one cycle rotates the vehicle by exactly
//!
//!    M I0 · w · (1/Δ(γ) − 1/Δ(θ2f)) = θ̄0 / n,    i.e. Eq. 19-20 with k = θ̄0/(n M I0),
//!
//!    where w = λ − θ1f is the (signed) θ1 width and γ the far θ2 side. One of
//!    λ or γ is a parameter, the other is solved for. The result does not
//!    depend on where the rectangle sits along θ1 (the integrand ∂(1/Δ)/∂θ2 is
//!    free of θ1), so a joint limit |θ1| ≤ L is met by translating the
//!    rectangle along BA (the paper's ADMN) or, failing that, by more cycles
//!    (smaller rectangles, the paper's AXYZ).
//!
//! The loop from A visits (x_b, θ2f) → (x_b, γ) → (x_o, γ) → (x_o, θ2f) → A with
//! x_b = θ1f + w − sgn(w)·s, x_o = θ1f − sgn(w)·s, s ∈ [0, |w|] the translation
//! along BA; zero-length legs are dropped, so s = 0 gives ABCD and s = |w|
//! gives ADMN (both 4 legs), other s give a 5-leg loop with A mid-edge.
//!
//! Repeatable motion (end of §4.1): a rectangle with θ2u + θ2l = 2nπ has
//! cos θ2u = cos θ2l, so it returns θ0 too; [`plan_repeatable`] builds such cycles.
//!
//! OCR misprints in §4.1 (resolved by integration, see the tests):
//! * "γ = 0.596 radians or 53.36 degrees": 53.36° is 0.931 rad; 0.5967 is cos γ.
//! * The paper truncates rather than rounds: γ = 53.3679° prints as 53.36,
//!   λ = 125° as 2.181 rad, θ̄0 = −0.124450 rad as −0.1244.
//! * λ = 76.084° (γ = 75°, 4 cycles) follows from the rounded θ̄0 = −7.13°;
//!   the full-precision drift (θ0d = −12.86953°) gives λ = 76.0856°.
//! * Eq. 20's first line reads (θ1f − θ1i)(1/(A+B cos θ2f) − 1/(A+B cos θ2i)):
//!   these are the rectangle's upper/lower sides (θ1u − θ1l, θ2u, θ2l) of
//!   Eq. 19, not the task's initial/final values; the trailing "cos θ" is
//!   cos θ2f = cos 0.
//! * "three generalized coordinates θ_1, i = 0, 1, 2" means θ_i.

use crate::model::{Input, State};
use crate::plan::{plan_from_legs, Limits, Plan};
use crate::planner::PlanError;
use crate::robots::space_robot::kinematics::{SpaceRobot, SpaceRobotModel};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

mod params;
mod search;

pub use params::{Cost, FixedSide, StokesSpaceParams, PAPER_GAMMA_DEG, PAPER_LAMBDA_DEG};
pub use search::{design, search};

/// The chosen rectangle and the numbers behind it (also put in `Plan::details`).
#[derive(Debug, Clone, Serialize)]
pub struct Design {
    /// A of Eq. 17.
    pub coeff_a: f64,
    /// B of Eq. 17.
    pub coeff_b: f64,
    /// θ0 drift along OA, rad.
    pub drift_oa: f64,
    /// θ0 at A, rad.
    pub theta0_d: f64,
    /// Required rotation θ̄0 = θ0f − θ0d (wrapped if asked), rad.
    pub theta0_bar: f64,
    /// Number of cycles n (0 when no rotation is needed).
    pub cycles: usize,
    /// k = θ̄0 / (n M I0) of Eq. 18-19 (per cycle).
    pub k: f64,
    /// λ = θ1f + w, rad (before translation).
    pub lambda: f64,
    /// γ, rad.
    pub gamma: f64,
    /// Signed θ1 width w = λ − θ1f, rad.
    pub width: f64,
    /// Translation along BA, rad.
    pub shift: f64,
    /// θ1 extent of the rectangle actually used, rad.
    pub theta1_span: [f64; 2],
    /// Joint-space deltas of one cycle (zero legs dropped), rad.
    pub cycle_legs: Vec<[f64; 2]>,
    /// Candidates rejected before this one, with reasons.
    pub rejected: Vec<String>,
    /// The configuration chosen: fixed side and value, where it came from, θ̄0.
    pub choice: String,
    /// Total joint travel |Δθ1| + |Δθ2| of the plan (OA and the cycles), rad.
    pub joint_travel: f64,
}

const GL5_X: [f64; 5] = [
    -0.906_179_845_938_664,
    -0.538_469_310_105_683,
    0.0,
    0.538_469_310_105_683,
    0.906_179_845_938_664,
];
const GL5_W: [f64; 5] = [
    0.236_926_885_056_189,
    0.478_628_670_499_366,
    0.568_888_888_888_889,
    0.478_628_670_499_366,
    0.236_926_885_056_189,
];

/// θ0 change along the straight joint-space segment p → q (θ1, θ2), from the
/// line integral of Eq. 13 (composite 5-point Gauss-Legendre, panels ≤ 0.02 rad
/// in θ2; the integrand is analytic so this is accurate to rounding).
pub(crate) fn segment_rotation(robot: &SpaceRobot, p: [f64; 2], q: [f64; 2]) -> f64 {
    let (d1, d2) = (q[0] - p[0], q[1] - p[1]);
    let panels = ((d2.abs() / 0.02).ceil() as usize).clamp(1, 1_000_000);
    let h = 1.0 / panels as f64;
    let mut sum = 0.0;
    for i in 0..panels {
        let mid = (i as f64 + 0.5) * h;
        for (x, w) in GL5_X.iter().zip(GL5_W) {
            let s = mid + 0.5 * h * x;
            let (fa, fb) = robot.one_form(p[1] + s * d2);
            sum += 0.5 * h * w * (fa * d1 + fb * d2);
        }
    }
    sum
}

/// Surface integral of Eq. 19 for the rectangle [θ1l, θ1u] × [θ2l, θ2u]
/// (the quantity set equal to k).
pub fn rectangle_integral(robot: &SpaceRobot, theta1: [f64; 2], theta2: [f64; 2]) -> f64 {
    (theta1[1] - theta1[0]) * (1.0 / robot.delta(theta2[1]) - 1.0 / robot.delta(theta2[0]))
}

/// k of Eq. 18 for one of n cycles producing θ̄0.
pub(crate) fn k_per_cycle(robot: &SpaceRobot, theta0_bar: f64, cycles: usize) -> f64 {
    theta0_bar / (cycles as f64 * robot.m_i0())
}

/// λ solving Eq. 20 for a given γ: (λ − θ1f)(1/Δ(γ) − 1/Δ(θ2f)) = k.
/// `None` when cos γ = cos θ2f (the rectangle cannot rotate the vehicle).
pub(crate) fn solve_lambda(robot: &SpaceRobot, goal: [f64; 2], gamma: f64, k: f64) -> Option<f64> {
    let alpha = 1.0 / robot.delta(gamma) - 1.0 / robot.delta(goal[1]);
    if alpha.abs() <= 1e-12 / robot.delta(goal[1]).abs() {
        return None;
    }
    Some(goal[0] + k / alpha)
}

/// γ solving Eq. 20 for a given λ: the root nearest θ2f (ties: the larger).
/// `None` when λ = θ1f or no real γ exists (|cos γ| > 1).
pub(crate) fn solve_gamma(robot: &SpaceRobot, goal: [f64; 2], lambda: f64, k: f64) -> Option<f64> {
    let w = lambda - goal[0];
    if w.abs() < 1e-12 {
        return None;
    }
    let inv = 1.0 / robot.delta(goal[1]) + k / w;
    if inv == 0.0 {
        return None;
    }
    let c = (1.0 / inv - robot.coeff_a()) / robot.coeff_b();
    if !(-1.0..=1.0).contains(&c) || !c.is_finite() {
        return None;
    }
    let g = c.acos();
    let near = |x: f64| x + 2.0 * PI * ((goal[1] - x) / (2.0 * PI)).round();
    let (g1, g2) = (near(g), near(-g));
    let (d1, d2) = ((g1 - goal[1]).abs(), (g2 - goal[1]).abs());
    Some(
        if d1 < d2 - 1e-12 || ((d1 - d2).abs() <= 1e-12 && g1 >= g2) {
            g1
        } else {
            g2
        },
    )
}

fn wrap(a: f64) -> f64 {
    let r = a.rem_euclid(2.0 * PI);
    if r > PI {
        r - 2.0 * PI
    } else {
        r
    }
}

fn invalid(name: &str, reason: impl Into<String>) -> PlanError {
    PlanError::InvalidParameter {
        name: name.into(),
        reason: reason.into(),
    }
}

/// One cycle's joint-space legs for width w, far side γ and translation s.
fn cycle_legs(goal: [f64; 2], w: f64, gamma: f64, shift: f64) -> Vec<[f64; 2]> {
    let sg = w.signum();
    [
        [w - sg * shift, 0.0],
        [0.0, gamma - goal[1]],
        [-w, 0.0],
        [0.0, goal[1] - gamma],
        [sg * shift, 0.0],
    ]
    .into_iter()
    .filter(|d| d[0] != 0.0 || d[1] != 0.0)
    .collect()
}

fn span(goal: [f64; 2], w: f64, shift: f64) -> [f64; 2] {
    let sg = w.signum();
    let (xb, xo) = (goal[0] + (w - sg * shift), goal[0] - sg * shift);
    [xb.min(xo), xb.max(xo)]
}

/// Translations s ∈ [0, |w|] keeping the θ1 span within |θ1| ≤ limit, or None.
fn feasible_shifts(theta1f: f64, w: f64, limit: f64) -> Option<[f64; 2]> {
    // Mirror so that the rectangle extends towards +θ1 (the limit is symmetric).
    let a = w.signum() * theta1f;
    let lo = (a + w.abs() - limit).max(0.0);
    let hi = (a + limit).min(w.abs());
    (lo <= hi + 1e-12).then_some([lo, hi.max(lo)])
}

fn check_state(name: &str, q: &State) -> Result<(), PlanError> {
    if q.len() != 3 || q.iter().any(|v| !v.is_finite()) {
        return Err(invalid(name, "must be 3 finite numbers (θ0, θ1, θ2)"));
    }
    Ok(())
}

/// Joins "n = k: reason" entries, merging runs of consecutive n with the
/// same reason into "n = a…b: reason" (a fixed λ gives the same width, hence
/// the same reason, for every n).
fn summarize_rejections(rejected: &[String]) -> String {
    let mut groups: Vec<(String, String, String)> = Vec::new(); // (first n, last n, reason)
    for r in rejected {
        let (n, reason) = match r.strip_prefix("n = ").and_then(|t| t.split_once(": ")) {
            Some((n, reason)) => (n.to_string(), reason.to_string()),
            None => (String::new(), r.clone()),
        };
        match groups.last_mut() {
            Some(g) if g.2 == reason && !n.is_empty() => g.1 = n,
            _ => groups.push((n.clone(), n, reason)),
        }
    }
    groups
        .into_iter()
        .map(|(a, b, reason)| match (a.is_empty(), a == b) {
            (true, _) => reason,
            (false, true) => format!("n = {a}: {reason}"),
            (false, false) => format!("n = {a}…{b}: {reason}"),
        })
        .collect::<Vec<_>>()
        .join("; ")
}

fn corner_letters(names: &Option<String>) -> Vec<char> {
    names.as_deref().unwrap_or("ABCDE").chars().collect()
}

fn cycle_plan_legs(
    labels: &mut Vec<String>,
    legs: &mut Vec<(usize, Input)>,
    cycle: &[[f64; 2]],
    cycles: usize,
    letters: &[char],
) {
    for c in 1..=cycles {
        for (i, dl) in cycle.iter().enumerate() {
            let to = if i + 1 == cycle.len() {
                letters[0]
            } else {
                letters[i + 1]
            };
            labels.push(format!("cycle {c}: {}{}", letters[i], to));
            legs.push((labels.len() - 1, Input::from_vec(dl.to_vec())));
        }
    }
}

/// Plans start → goal: OA, then n cycles of the chosen rectangle.
pub fn plan(
    model: &SpaceRobotModel,
    start: &State,
    goal: &State,
    params: &StokesSpaceParams,
    limits: &Limits,
) -> Result<Plan, PlanError> {
    if limits.max_rate.len() != 2 || limits.max_rate.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
        return Err(invalid(
            "limits.max_rate",
            "needs two positive rates (θ1', θ2')",
        ));
    }
    let d = search(&model.robot, start, goal, params, Some(limits))?;
    let letters = corner_letters(&params.corner_names);
    if letters.len() < d.cycle_legs.len() {
        return Err(invalid(
            "corner_names",
            format!(
                "the chosen loop has {} corners, only {} names given",
                d.cycle_legs.len(),
                letters.len()
            ),
        ));
    }
    let mut labels = vec!["OA".to_string()];
    let mut legs = vec![(
        0,
        Input::from_vec(vec![goal[1] - start[1], goal[2] - start[2]]),
    )];
    cycle_plan_legs(&mut labels, &mut legs, &d.cycle_legs, d.cycles, &letters);
    let details = serde_json::json!({
        "A": d.coeff_a,
        "B": d.coeff_b,
        "theta0_drift_oa_deg": d.drift_oa.to_degrees(),
        "theta0_d_deg": d.theta0_d.to_degrees(),
        "theta0_bar_deg": d.theta0_bar.to_degrees(),
        "cycles": d.cycles,
        "k": d.k,
        "lambda_deg": d.lambda.to_degrees(),
        "gamma_deg": d.gamma.to_degrees(),
        "width_deg": d.width.to_degrees(),
        "shift_deg": d.shift.to_degrees(),
        "theta1_span_deg": [d.theta1_span[0].to_degrees(), d.theta1_span[1].to_degrees()],
        "legs_per_cycle": d.cycle_legs.len(),
        "rejected": d.rejected,
        "choice": d.choice,
        "joint_travel_deg": d.joint_travel.to_degrees(),
    });
    Ok(plan_from_legs(labels, legs, limits, details))
}

/// Parameters of a repeatable cycle (θ2u + θ2l = 2nπ): joints and vehicle all
/// return to their start.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct RepeatableParams {
    /// Signed θ1 width of the rectangle, degrees.
    pub width_deg: f64,
    /// n in θ2u = 2nπ − θ2l (θ2l = the start's θ2).
    pub turns: i32,
    /// Number of cycles.
    pub cycles: usize,
    /// Joint-1 limit |θ1| ≤ L; `None` = unconstrained.
    pub theta1_limit_deg: Option<f64>,
}

impl Default for RepeatableParams {
    fn default() -> Self {
        Self {
            width_deg: 60.0,
            turns: 0,
            cycles: 1,
            theta1_limit_deg: None,
        }
    }
}

/// θ2u = 2nπ − θ2l: the far θ2 side of a repeatable rectangle.
pub fn repeatable_gamma(theta2_l: f64, turns: i32) -> f64 {
    2.0 * PI * f64::from(turns) - theta2_l
}

/// A pure repeatable motion from `start`: `cycles` rectangles with
/// θ1 ∈ [θ1s, θ1s + width] and θ2 between θ2s and 2nπ − θ2s.
pub fn plan_repeatable(
    model: &SpaceRobotModel,
    start: &State,
    params: &RepeatableParams,
    limits: &Limits,
) -> Result<Plan, PlanError> {
    model
        .robot
        .validate()
        .map_err(|r| invalid("model", r.to_string()))?;
    check_state("start", start)?;
    if limits.max_rate.len() != 2 || limits.max_rate.iter().any(|r| !(r.is_finite() && *r > 0.0)) {
        return Err(invalid(
            "limits.max_rate",
            "needs two positive rates (θ1', θ2')",
        ));
    }
    let w = params.width_deg.to_radians();
    if !w.is_finite() || w == 0.0 {
        return Err(invalid("width_deg", "must be finite and non-zero"));
    }
    if params.cycles == 0 || params.cycles > 10_000 {
        return Err(invalid("cycles", "must be in [1, 10000]"));
    }
    let a = [start[1], start[2]];
    let gamma = repeatable_gamma(a[1], params.turns);
    if (gamma - a[1]).abs() < 1e-9 {
        return Err(invalid(
            "turns",
            "θ2u = θ2l: the rectangle is degenerate (choose another n)",
        ));
    }
    let sp = span(a, w, 0.0);
    if let Some(l) = params.theta1_limit_deg {
        if !l.is_finite() || l <= 0.0 {
            return Err(invalid(
                "theta1_limit_deg",
                format!("must be positive, got {l}"),
            ));
        }
        let l = l.to_radians();
        if sp[0] < -l - 1e-12 || sp[1] > l + 1e-12 {
            return Err(PlanError::Unreachable(format!(
                "θ1 span [{:.3}°, {:.3}°] violates |θ1| ≤ {:.3}°",
                sp[0].to_degrees(),
                sp[1].to_degrees(),
                l.to_degrees()
            )));
        }
    }
    let cycle = cycle_legs(a, w, gamma, 0.0);
    let mut labels = Vec::new();
    let mut legs = Vec::new();
    cycle_plan_legs(
        &mut labels,
        &mut legs,
        &cycle,
        params.cycles,
        &corner_letters(&None),
    );
    let details = serde_json::json!({
        "gamma_deg": gamma.to_degrees(),
        "width_deg": params.width_deg,
        "cycles": params.cycles,
        "rotation_per_cycle_deg": (model.robot.m_i0() * rectangle_integral(&model.robot, [a[0], a[0] + w], [a[1], gamma])).to_degrees(),
    });
    Ok(plan_from_legs(labels, legs, limits, details))
}

#[cfg(test)]
mod tests;
