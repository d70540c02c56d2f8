//! Geometric (A)-(B)-(A) planner for the rolling sphere (seed 003, §3).
//!
//! Actions (Euler chart of [`RollingSphere`], frame-1 inputs ω¹ = Rz(−α) ω):
//! (A) ω¹_x = 0: roll straight along the x₁ axis, only θ and the position change;
//! (B) ω¹_y = 0: θ = θ' fixed, the centre runs on a circle of radius a tan θ' about C and the
//! point F (where θ would be 0) on a circle of radius a (tan θ' − θ') about the same C.
//!
//! Plan (world-frame inputs (ω_x, ω_y), labels in brackets):
//! 1. [initial (A)] roll θ₀ → 0 along α₀: the sphere stands at F_i = Q₀ − aθ₀(cos α₀, sin α₀)
//!    (Eq. 11) upright with yaw β_i = α₀ + φ₀ (Eq. 12).
//! 2. [(A) straight roll out] roll θ: 0 → θ' along α_i (Eq. 15).
//! 3. [(B) circular arc about C] turn α by Δα, θ = θ' (ω rotates with α, so this leg is not a
//!    straight leg in ∫u space and gets its own closure).
//! 4. [(A) straight roll in] roll θ: θ' → 0 along α_f = α_i + Δα, arriving at F_f.
//! 5. [final (A)] only when the goal is tilted (θ_g ≠ 0): roll θ: 0 → θ_g along α_g. The
//!    paper's goal is upright (θ_g = 0, Eq. 10b); this leg generalises it at no cost.
//!
//! The (A)-(B)-(A) sequence translates F by the chord r = |F_f − F_i| (Eq. 13) and turns the
//! yaw by Δβ = Δα (1 − sec θ') (Eq. 8), with the chord fixing θ' through
//! sin(|Δα|/2) = r / (2a (tan θ' − θ')) (Eq. 9, fraction restored from the flattened OCR
//! `r/2 (tanθ' − θ')`). Eq. 9b's two cases are the two arcsin branches; this code scans
//! δ = |Δα| ∈ (0, 2π) directly, which covers both. With σ = +1 (counter-clockwise) Δβ < 0,
//! with σ = −1 (clockwise) Δβ > 0, and |Δβ| ∈ (r/a, ∞) (it tends to r/a as Δα → 0), so the
//! direct Δβ = β_f − β_i is shifted by multiples of 2π into that range (§5 uses −3.5π).
//! Among direction/shift candidates the one with the least total rolling is chosen.
//!
//! Misprints in §3/§5 (the tests assert the justified values):
//! * Eq. 14 prints sin(Δα/2) = r / (2(a² + b²)) and "(tan θ' − θ') = a² + b²": both need
//!   √(a² + b²) (the distance |C F_f|); with the printed C = (3.15, 2.15), a² + b² = 14.5 but
//!   tan θ' − θ' = 3.81 = √14.5.
//! * Eq. 26 prints r = 7.07, which is |(x₀, y₀)| = √50; Eq. 13 with Eq. 24's (x_i, y_i) gives
//!   r = 7.31, and only r = 7.31 reproduces the printed Δα = 2.56, θ' = 1.38 and C (r = 7.07
//!   would give Δα = 2.68).
//! * Eq. 27 prints Δα = 146.7°, the solution is 146.78° (2.5618 rad): truncated, not rounded.
//!   Likewise α_i = 67.5° is 67.56° truncated (so 67.6° rounded).

use crate::model::{Input, State};
use crate::plan::{ControlLaw, Limits, Plan, RampProfile, Segment};
use crate::planner::PlanError;
use crate::robots::rolling_sphere::kinematics::RollingSphere;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::sync::Arc;

/// Sense of the circular arc (B).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum ArcDirection {
    /// Try both and keep the shorter plan.
    Auto,
    /// Counter-clockwise (Δα > 0, Δβ < 0).
    Ccw,
    /// Clockwise (Δα < 0, Δβ > 0).
    Cw,
}

/// Seed 003 §3 geometric planner: roll straight (A), along a circular arc (B),
/// straight again (A).
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SphereGeometricParams {
    /// Arc sense; `auto` picks the shorter.
    pub direction: ArcDirection,
    /// Number of feasible 2π shifts of Δβ considered per direction (the shortest plan wins).
    #[schemars(range(min = 1))]
    pub candidate_turns: u32,
    /// Grid points per half of the Δα scan (root bracketing).
    #[schemars(range(min = 8))]
    pub scan_points: usize,
    /// Upper bound on θ'; near 90° Δβ becomes very sensitive to θ' (paper remark 1).
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 90))]
    pub max_theta_prime_deg: f64,
    /// Bisection iteration cap per root.
    #[schemars(range(min = 1))]
    pub max_iter: usize,
    /// Chord r (in radii) below which F_i = F_f and the arc is a full circle.
    #[schemars(range(min = 0))]
    pub zero_distance: f64,
}

impl Default for SphereGeometricParams {
    fn default() -> Self {
        Self {
            direction: ArcDirection::Auto,
            candidate_turns: 3,
            scan_points: 256,
            max_theta_prime_deg: 89.5,
            max_iter: 200,
            zero_distance: 1e-9,
        }
    }
}

/// The solved (A)-(B)-(A) manoeuvre (lengths in metres, angles in radians).
#[derive(Debug, Clone, Serialize)]
pub struct AbaSolution {
    /// F_i after the initial (A) (Eq. 11).
    pub x_i: f64,
    /// F_i after the initial (A) (Eq. 11).
    pub y_i: f64,
    /// Yaw when upright at F_i (Eq. 12).
    pub beta_i: f64,
    /// Chord |F_f − F_i| (Eq. 13).
    pub r: f64,
    /// β_f − β_i wrapped to (−π, π].
    pub delta_beta_direct: f64,
    /// The Δβ actually produced (direct value plus 2πk).
    pub delta_beta: f64,
    /// k of the 2π shift.
    pub turns: i64,
    /// +1 counter-clockwise, −1 clockwise.
    pub sigma: f64,
    /// Δα (Eq. 9b), sign = σ.
    pub delta_alpha: f64,
    /// θ' (Eq. 8/9).
    pub theta_prime: f64,
    /// Centre of rotation C = (a, b) of action (B) (Eq. 14).
    pub center: [f64; 2],
    /// Rolling direction of the first (A) of the sequence (Eq. 15).
    pub alpha_i: f64,
    /// Rolling direction of the last (A) of the sequence, α_i + Δα.
    pub alpha_f: f64,
    /// Total rolled angle of the whole plan, rad (the selection cost).
    pub rolled_angle: f64,
}

/// Labels of the plan's segments.
pub const LABELS: [&str; 5] = [
    "initial (A): tilt upright",
    "(A) straight roll out",
    "(B) circular arc about C",
    "(A) straight roll in",
    "final (A): tilt to goal",
];

use crate::planner::check_param as check;

/// Checks shared by both sphere planners: radius, and 5 finite Euler coordinates.
pub(crate) fn validate_task(
    model: &RollingSphere,
    start: &State,
    goal: &State,
) -> Result<(), PlanError> {
    check(
        "radius",
        model.a.is_finite() && model.a > 0.0,
        "must be a positive number",
    )?;
    check(
        "start",
        start.len() == 5 && start.iter().all(|v| v.is_finite()),
        "need 5 finite values",
    )?;
    check(
        "goal",
        goal.len() == 5 && goal.iter().all(|v| v.is_finite()),
        "need 5 finite values",
    )?;
    Ok(())
}

fn wrap(a: f64) -> f64 {
    let x = (a + PI).rem_euclid(TAU) - PI;
    if x <= -PI {
        x + TAU
    } else {
        x
    }
}

/// T = tan θ' solving tan θ' − θ' = R (R ≥ 0), i.e. T − atan T = R.
///
/// Newton from T = R + π/2 (the function is increasing and convex, so the iterates decrease
/// monotonically onto the root).
pub(crate) fn tan_theta_prime(rf: f64) -> f64 {
    let mut t = rf + FRAC_PI_2;
    for _ in 0..200 {
        let f = t - t.atan() - rf;
        let df = t * t / (1.0 + t * t);
        if df.is_nan() || df <= 0.0 {
            break;
        }
        let next = t - f / df;
        if next.is_nan() || next >= t || next <= 0.0 {
            break;
        }
        let done = t - next <= 1e-16 * t;
        t = next;
        if done {
            break;
        }
    }
    t
}

/// |Δβ| = δ (sec θ' − 1) for |Δα| = δ (Eq. 8), θ' from the chord (Eq. 9), given `v` and the half
/// (`upper`: δ = 2π − v, else δ = v). Parametrising each half by its distance v to the end
/// keeps sin(δ/2) = sin(v/2) accurate near δ = 2π. Returns (|Δβ|, T = tan θ').
fn abs_dbeta(rho: f64, v: f64, upper: bool) -> (f64, f64) {
    let delta = if upper { TAU - v } else { v };
    let rf = rho / (2.0 * (0.5 * v).sin());
    let t = tan_theta_prime(rf);
    // sec θ' − 1 without cancellation.
    (delta * t * t / ((1.0 + t * t).sqrt() + 1.0), t)
}

/// Roots δ ∈ (0, 2π) of |Δβ|(δ) = target, each with tan θ', for chord `rho` (radii).
fn solve_delta(rho: f64, target: f64, p: &SphereGeometricParams) -> Vec<(f64, f64)> {
    let n = p.scan_points;
    let mut out = Vec::new();
    for upper in [false, true] {
        // Grid v_j = π j / n; v = 0 is the limit: |Δβ| → ρ (lower) or ∞ (upper).
        let g = |v: f64| -> f64 {
            if v == 0.0 {
                if upper {
                    f64::INFINITY
                } else {
                    rho - target
                }
            } else {
                abs_dbeta(rho, v, upper).0 - target
            }
        };
        let mut roots = Vec::new();
        let mut prev_v = 0.0;
        let mut prev = g(0.0);
        for j in 1..=n {
            let v = PI * j as f64 / n as f64;
            let cur = g(v);
            if cur == 0.0 {
                roots.push(v);
            } else if prev != 0.0 && prev.signum() != cur.signum() {
                let (mut lo, mut hi, mut flo) = (prev_v, v, prev);
                for _ in 0..p.max_iter {
                    let mid = 0.5 * (lo + hi);
                    if mid <= lo || mid >= hi {
                        break;
                    }
                    let fm = g(mid);
                    if fm == 0.0 {
                        (lo, hi) = (mid, mid);
                        break;
                    }
                    if fm.signum() == flo.signum() {
                        lo = mid;
                        flo = fm;
                    } else {
                        hi = mid;
                    }
                }
                let v = if lo == 0.0 { hi } else { 0.5 * (lo + hi) };
                roots.push(v);
            }
            prev_v = v;
            prev = cur;
        }
        for v in roots {
            let (_, t) = abs_dbeta(rho, v, upper);
            out.push((if upper { TAU - v } else { v }, t));
        }
    }
    out
}

/// The farthest start–goal distance solved, in radii of the ball.
pub const MAX_RADII: f64 = 1e5;

/// Solves the whole manoeuvre for `start` → `goal` (Euler-chart states).
pub fn solve(
    model: &RollingSphere,
    start: &State,
    goal: &State,
    p: &SphereGeometricParams,
) -> Result<AbaSolution, PlanError> {
    validate(model, start, goal, p)?;
    let a = model.a;
    let (x0, y0, al0, th0, ph0) = (start[0], start[1], start[2], start[3], start[4]);
    let (xg, yg, alg, thg, phg) = (goal[0], goal[1], goal[2], goal[3], goal[4]);
    let (x_i, y_i) = (x0 - a * th0 * al0.cos(), y0 - a * th0 * al0.sin());
    let (x_f, y_f) = (xg - a * thg * alg.cos(), yg - a * thg * alg.sin());
    let beta_i = wrap(al0 + ph0);
    let beta_f = alg + phg;
    let r = ((x_f - x_i).powi(2) + (y_f - y_i).powi(2)).sqrt();
    let rho = r / a;
    // The candidate search walks Δβ in steps of 2π up to about ρ: a goal
    // 1e300 m away would never end it (it hung). Far beyond any plan the
    // step budget allows, refused as unreachable.
    if rho.is_nan() || rho > MAX_RADII {
        return Err(PlanError::Unreachable(format!(
            "start and goal are {} m apart, {} radii of the ball: at most {} radii",
            crate::numfmt::readable((x_f - x_i).hypot(y_f - y_i)),
            crate::numfmt::readable((x_f - x_i).hypot(y_f - y_i) / a),
            crate::numfmt::readable(MAX_RADII)
        )));
    }
    let db0 = wrap(beta_f - beta_i);
    let max_tp = p.max_theta_prime_deg.to_radians();
    let fixed = th0.abs() + thg.abs();
    let sigmas: &[f64] = match p.direction {
        ArcDirection::Auto => &[1.0, -1.0],
        ArcDirection::Ccw => &[1.0],
        ArcDirection::Cw => &[-1.0],
    };
    if rho < p.zero_distance && db0.abs() < 1e-15 {
        // Already there up to the final tilt: the sequence is empty.
        return Ok(AbaSolution {
            x_i,
            y_i,
            beta_i,
            r,
            delta_beta_direct: db0,
            delta_beta: 0.0,
            turns: 0,
            sigma: 0.0,
            delta_alpha: 0.0,
            theta_prime: 0.0,
            center: [x_i, y_i],
            alpha_i: 0.0,
            alpha_f: 0.0,
            rolled_angle: fixed,
        });
    }
    let mut best: Option<AbaSolution> = None;
    for &sigma in sigmas {
        // Δβ = −σ t with t > 0: t_k = −σ (Δβ₀ + 2πk), in increasing order.
        let t0 = (-sigma * db0).rem_euclid(TAU);
        let t0 = if t0 <= 0.0 { t0 + TAU } else { t0 };
        let mut found = 0;
        let mut n = 0u32;
        while found < p.candidate_turns
            && (t0 + TAU * n as f64) <= rho + TAU * (p.candidate_turns as f64 + 1.0)
        {
            let t = t0 + TAU * n as f64;
            n += 1;
            let turns = ((-sigma * t - db0) / TAU).round() as i64;
            let roots: Vec<(f64, f64)> = if rho < p.zero_distance {
                // F_i = F_f: full circle, sec θ' = 1 + t/(2π).
                let sec = 1.0 + t / TAU;
                vec![(TAU, (sec * sec - 1.0).sqrt())]
            } else {
                solve_delta(rho, t, p)
            };
            let mut any = false;
            for (delta, tt) in roots {
                let tp = tt.atan();
                if !tt.is_finite() || tp.is_nan() || tp > max_tp {
                    continue;
                }
                any = true;
                let dalpha = sigma * delta;
                let rf = a * (tt - tp);
                let chord_dir = if r > 0.0 {
                    (y_f - y_i).atan2(x_f - x_i)
                } else {
                    0.0
                };
                let alpha_i = if rho < p.zero_distance {
                    0.0
                } else {
                    wrap(chord_dir - sigma * FRAC_PI_2 - 0.5 * dalpha)
                };
                let center = [x_i - rf * alpha_i.cos(), y_i - rf * alpha_i.sin()];
                let rolled = fixed + 2.0 * tp + delta * tt;
                let cand = AbaSolution {
                    x_i,
                    y_i,
                    beta_i,
                    r,
                    delta_beta_direct: db0,
                    delta_beta: -sigma * t,
                    turns,
                    sigma,
                    delta_alpha: dalpha,
                    theta_prime: tp,
                    center,
                    alpha_i,
                    alpha_f: alpha_i + dalpha,
                    rolled_angle: rolled,
                };
                if best.as_ref().is_none_or(|b| rolled < b.rolled_angle) {
                    best = Some(cand);
                }
            }
            if any {
                found += 1;
            }
        }
    }
    best.ok_or_else(|| {
        PlanError::Unreachable(format!(
            "no (A)-(B)-(A) solution with θ' ≤ {}° for r = {r:.6} m, Δβ = {:.4}° (direction = \"{}\"); \
             raise max_theta_prime_deg or candidate_turns",
            p.max_theta_prime_deg,
            db0.to_degrees(),
            match p.direction {
                ArcDirection::Auto => "auto",
                ArcDirection::Ccw => "ccw",
                ArcDirection::Cw => "cw",
            }
        ))
    })
}

fn validate(
    model: &RollingSphere,
    start: &State,
    goal: &State,
    p: &SphereGeometricParams,
) -> Result<(), PlanError> {
    validate_task(model, start, goal)?;
    check(
        "candidate_turns",
        p.candidate_turns >= 1,
        "must be at least 1",
    )?;
    check("scan_points", p.scan_points >= 8, "must be at least 8")?;
    check("max_iter", p.max_iter >= 1, "must be at least 1")?;
    check(
        "max_theta_prime_deg",
        p.max_theta_prime_deg > 0.0 && p.max_theta_prime_deg < 90.0,
        "must lie in (0, 90)",
    )?;
    check(
        "zero_distance",
        p.zero_distance.is_finite() && p.zero_distance >= 0.0,
        "must be a non-negative number",
    )
}

/// One piece of the open-loop plan, in ∫ω space.
#[derive(Debug, Clone)]
enum Piece {
    /// Constant direction: total ∫ω.
    Straight([f64; 2]),
    /// Action (B): α(s) = α₀ + Δα s, ω = −Δα tan θ' (cos α, sin α) ṡ.
    Arc {
        alpha0: f64,
        dalpha: f64,
        tan_tp: f64,
    },
}

impl Piece {
    /// dΩ/ds at progress s ∈ [0, 1].
    fn slope(&self, s: f64) -> [f64; 2] {
        match *self {
            Piece::Straight(d) => d,
            Piece::Arc {
                alpha0,
                dalpha,
                tan_tp,
            } => {
                let al = alpha0 + dalpha * s;
                let w = -dalpha * tan_tp;
                [w * al.cos(), w * al.sin()]
            }
        }
    }
    /// Per-input bound on ∫|ω_i| used for the timing.
    fn extent(&self) -> Input {
        match *self {
            Piece::Straight(d) => Input::from_vec(vec![d[0], d[1]]),
            Piece::Arc { dalpha, tan_tp, .. } => {
                let l = (dalpha * tan_tp).abs();
                Input::from_vec(vec![l, l])
            }
        }
    }
}

/// s(τ) = ∫₀^τ rate: progress along a [`RampProfile`], in [0, 1].
pub(crate) fn ramp_progress(p: &RampProfile, tau: f64) -> f64 {
    p.progress(tau)
}

/// Builds the open-loop plan from pieces (skipping empty ones), timed like `plan_from_legs`.
fn build_plan(pieces: Vec<(usize, Piece)>, limits: &Limits, details: serde_json::Value) -> Plan {
    let mut timed: Vec<(f64, usize, Piece, RampProfile)> = Vec::new();
    let mut segments = Vec::new();
    let mut t = 0.0;
    for (label, piece) in pieces {
        let ext = piece.extent();
        if ext.amax() == 0.0 {
            continue;
        }
        let prof = limits.profile(&ext);
        segments.push(Segment {
            label,
            start: t,
            end: t + prof.duration,
        });
        timed.push((t, label, piece, prof));
        t += prof.duration;
    }
    let last_label = timed.last().map(|x| x.1).unwrap_or(0);
    let law = ControlLaw::OpenLoop(Arc::new(move |time: f64| {
        let idx = timed.partition_point(|x| x.0 <= time).saturating_sub(1);
        match timed.get(idx) {
            Some((t0, label, piece, prof)) if time <= t0 + prof.duration => {
                let tau = time - t0;
                let sl = piece.slope(ramp_progress(prof, tau));
                let rate = prof.rate(tau);
                (Input::from_vec(vec![sl[0] * rate, sl[1] * rate]), *label)
            }
            _ => (Input::zeros(2), last_label),
        }
    }));
    Plan {
        labels: LABELS.iter().map(|s| s.to_string()).collect(),
        segments,
        duration: t,
        law,
        details,
    }
}

/// ∫ω of an (A) roll changing θ by `dtheta` along direction α: ω = θ̇ (−sin α, cos α).
fn action_a(alpha: f64, dtheta: f64) -> [f64; 2] {
    [-dtheta * alpha.sin(), dtheta * alpha.cos()]
}

/// Plans `start` → `goal` (both in the Euler chart (x, y, α, θ, φ) of `model`).
///
/// The goal is reached exactly in the ideal run; only α_g + φ_g matters when θ_g = 0.
/// `limits.max_rate` bounds |ω_x|, |ω_y| (rad/s).
pub fn plan(
    model: &RollingSphere,
    start: &State,
    goal: &State,
    params: &SphereGeometricParams,
    limits: &Limits,
) -> Result<Plan, PlanError> {
    check(
        "limits.max_rate",
        limits.max_rate.len() == 2 && limits.max_rate.iter().all(|m| *m > 0.0 && m.is_finite()),
        "need two positive rates (omega_x, omega_y)",
    )?;
    let sol = solve(model, start, goal, params)?;
    let tan_tp = sol.theta_prime.tan();
    let mut pieces = vec![(0, Piece::Straight(action_a(start[2], -start[3])))];
    if sol.sigma != 0.0 {
        pieces.push((1, Piece::Straight(action_a(sol.alpha_i, sol.theta_prime))));
        pieces.push((
            2,
            Piece::Arc {
                alpha0: sol.alpha_i,
                dalpha: sol.delta_alpha,
                tan_tp,
            },
        ));
        pieces.push((3, Piece::Straight(action_a(sol.alpha_f, -sol.theta_prime))));
    }
    pieces.push((4, Piece::Straight(action_a(goal[2], goal[3]))));
    let details = serde_json::json!({
        "planner": "sphere_geometric",
        "x_i": sol.x_i,
        "y_i": sol.y_i,
        "beta_i_deg": sol.beta_i.to_degrees(),
        "r": sol.r,
        "delta_beta_direct_deg": sol.delta_beta_direct.to_degrees(),
        "delta_beta_deg": sol.delta_beta.to_degrees(),
        "delta_beta_turns": sol.turns,
        "direction": if sol.sigma > 0.0 { "ccw" } else if sol.sigma < 0.0 { "cw" } else { "none" },
        "delta_alpha_deg": sol.delta_alpha.to_degrees(),
        "theta_prime_deg": sol.theta_prime.to_degrees(),
        "center": sol.center,
        "alpha_i_deg": sol.alpha_i.to_degrees(),
        "alpha_f_deg": sol.alpha_f.to_degrees(),
        "rolled_angle_rad": sol.rolled_angle,
    });
    Ok(build_plan(pieces, limits, details))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robots::rolling_sphere::test_support::*;
    use proptest::prelude::*;

    fn st(v: [f64; 5]) -> State {
        State::from_vec(v.to_vec())
    }

    /// §5.1, Eqs. 23-28, counter-clockwise as in the paper.
    #[test]
    fn paper_geometric_numbers() {
        let m = RollingSphere { a: 1.0 };
        let start = deg_state(5.0, 5.0, -60.0, 45.0, -30.0);
        let goal = st([0.0; 5]);
        let p = SphereGeometricParams {
            direction: ArcDirection::Ccw,
            ..Default::default()
        };
        let s = solve(&m, &start, &goal, &p).unwrap();
        // Eq. 24-25.
        assert_eq!(round_to(s.x_i, 2), 4.61);
        assert_eq!(round_to(s.y_i, 2), 5.68);
        assert_eq!(round_to(s.beta_i.to_degrees(), 6), -90.0);
        // Eq. 26: printed r = 7.07 is |(x0, y0)|; Eq. 13 gives 7.31 (misprint, see module doc).
        assert_eq!(round_to(s.r, 2), 7.31);
        assert_eq!(round_to(s.delta_beta_direct.to_degrees(), 6), 90.0);
        // Direct π/2 and π/2 − 2π are infeasible for ccw (need Δβ < −r); −3.5π is used.
        assert!((s.delta_beta + 3.5 * PI).abs() < 1e-12 && s.turns == -2);
        // Eq. 27.
        assert_eq!(round_to(s.delta_alpha, 2), 2.56);
        assert_eq!(round_to(s.delta_alpha.to_degrees(), 1), 146.8); // printed 146.7 (truncated)
        assert_eq!(round_to(s.theta_prime, 2), 1.38);
        assert_eq!(round_to(s.theta_prime.to_degrees(), 1), 79.1);
        // Eq. 28.
        assert_eq!(round_to(s.center[0], 2), 3.15);
        assert_eq!(round_to(s.center[1], 2), 2.15);
        // Eq. 15: printed 67.5 is 67.56 truncated.
        assert_eq!(round_to(s.alpha_i.to_degrees(), 1), 67.6);
        let t = (s.y_i - s.center[1]).atan2(s.x_i - s.center[0]);
        assert!((t - s.alpha_i).abs() < 1e-12);
        // Eq. 14 with the restored square root; Eq. 8 and Eq. 9.
        let dist = s.center[0].hypot(s.center[1]);
        assert!((dist - (s.x_i - s.center[0]).hypot(s.y_i - s.center[1])).abs() < 1e-12);
        assert!(((0.5 * s.delta_alpha).sin() - s.r / (2.0 * dist)).abs() < 1e-12);
        assert!((s.theta_prime.tan() - s.theta_prime - dist).abs() < 1e-11);
        let db = s.delta_alpha * (1.0 - 1.0 / s.theta_prime.cos());
        assert!((db - s.delta_beta).abs() < 1e-9);
        // The printed a² + b² (no root) is not tan θ' − θ'.
        assert!((s.theta_prime.tan() - s.theta_prime - dist * dist).abs() > 10.0);
    }

    /// The paper's scenario reaches the goal in the ideal (quaternion) run, ccw and auto.
    #[test]
    fn paper_geometric_ideal_run() {
        let m = RollingSphere { a: 1.0 };
        let start = deg_state(5.0, 5.0, -60.0, 45.0, -30.0);
        let goal = st([0.0; 5]);
        for dir in [ArcDirection::Ccw, ArcDirection::Auto, ArcDirection::Cw] {
            let p = SphereGeometricParams {
                direction: dir,
                ..Default::default()
            };
            let plan = plan(&m, &start, &goal, &p, &limits()).unwrap();
            assert_reaches(1.0, &plan, &start, &goal, &format!("{dir:?}: "));
            assert_eq!(plan.segments.len(), 4);
        }
    }

    /// Large Δβ, radius ≠ 1, a tilted goal, and the start already upright at the goal spot.
    #[test]
    fn other_scenarios_reach_goal() {
        let cases = [
            (
                0.5,
                deg_state(1.0, -2.0, 30.0, 120.0, 170.0),
                deg_state(0.0, 0.0, 0.0, 0.0, -175.0),
            ),
            (
                1.0,
                deg_state(0.3, 0.1, 0.0, 0.0, 10.0),
                deg_state(0.0, 0.0, 0.0, 0.0, 0.0),
            ),
            (
                2.0,
                deg_state(0.0, 0.0, 0.0, 0.0, 0.0),
                deg_state(0.0, 0.0, 0.0, 0.0, 90.0),
            ),
            (
                1.0,
                deg_state(-3.0, 4.0, 100.0, 170.0, -50.0),
                deg_state(1.0, 2.0, 45.0, 60.0, 20.0),
            ),
        ];
        for (a, start, goal) in cases {
            let m = RollingSphere { a };
            let plan = plan(
                &m,
                &start,
                &goal,
                &SphereGeometricParams::default(),
                &limits(),
            )
            .unwrap();
            assert_reaches(a, &plan, &start, &goal, "");
        }
    }

    #[test]
    fn ramp_progress_integrates_rate() {
        let p = RampProfile {
            duration: 1.3,
            ramp: 0.4,
        };
        let n = 13000;
        let mut acc = 0.0;
        for k in 0..n {
            let t = (k as f64 + 0.5) * 1.3 / n as f64;
            acc += p.rate(t) * 1.3 / n as f64;
            let s = ramp_progress(&p, (k + 1) as f64 * 1.3 / n as f64);
            assert!((s - acc).abs() < 1e-7);
        }
        assert!((ramp_progress(&p, 1.3) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn tan_theta_prime_inverts() {
        for rf in [1e-12, 1e-6, 0.01, 1.0, 3.8, 100.0, 1e6] {
            let t = tan_theta_prime(rf);
            assert!(((t - t.atan()) - rf).abs() <= 1e-12 * rf.max(1e-3), "{rf}");
        }
    }

    #[test]
    fn invalid_parameters_are_reported() {
        let m = RollingSphere { a: 1.0 };
        let p = SphereGeometricParams {
            max_theta_prime_deg: 95.0,
            ..Default::default()
        };
        let e = solve(&m, &st([0.0; 5]), &st([1.0, 0.0, 0.0, 0.0, 0.0]), &p).unwrap_err();
        assert!(matches!(e, PlanError::InvalidParameter { .. }));
        let e = solve(
            &RollingSphere { a: -1.0 },
            &st([0.0; 5]),
            &st([0.0; 5]),
            &Default::default(),
        );
        assert!(matches!(e, Err(PlanError::InvalidParameter { .. })));
        let e = solve(
            &m,
            &st([f64::NAN, 0.0, 0.0, 0.0, 0.0]),
            &st([0.0; 5]),
            &Default::default(),
        );
        assert!(matches!(e, Err(PlanError::InvalidParameter { .. })));
    }

    /// A tight θ' cap can leave no solution: a clear `Unreachable`, not a silent failure.
    #[test]
    fn capped_theta_prime_is_unreachable() {
        let m = RollingSphere { a: 1.0 };
        let p = SphereGeometricParams {
            max_theta_prime_deg: 5.0,
            ..Default::default()
        };
        let e = solve(&m, &deg_state(5.0, 5.0, 0.0, 0.0, 0.0), &st([0.0; 5]), &p).unwrap_err();
        assert!(matches!(e, PlanError::Unreachable(_)), "{e:?}");
    }

    proptest! {
        #![proptest_config(crate::prop_config::config(12))]
        #[test]
        fn random_starts_reach_goal(
            x in -4.0..4.0f64, y in -4.0..4.0f64,
            al in -180.0..180.0f64, th in 0.0..180.0f64, ph in -180.0..180.0f64,
            bf in -180.0..180.0f64,
        ) {
            let m = RollingSphere { a: 1.0 };
            let start = deg_state(x, y, al, th, ph);
            let goal = deg_state(0.0, 0.0, 0.0, 0.0, bf);
            let plan = plan(&m, &start, &goal, &SphereGeometricParams::default(), &limits()).unwrap();
            let (dp, dr) = ideal_error_dt(1.0, &plan, &start, &goal, DT_FINE);
            prop_assert!(dp < 1e-9 && dr < 1e-9, "{} {}", dp, dr);
        }
    }
}
