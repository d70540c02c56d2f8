//! Stokes / surface-integral planner for the rolling disk (seed 000, §4.2).
//!
//! The independent variables (θ, α) are first converged on a straight line in
//! the θ–α plane; the dependent variables (x, y) are then converged with closed
//! loops whose enclosed area is sized by Green's theorem (Eqs. 21–24).
//!
//! Two algorithms:
//! * [`Algorithm::SingularityAvoiding`]: one loop converging x and y together
//!   (Eqs. 25–26), with the three-step detour of Fig. 9 when the loop is near
//!   the singularity of Eq. 27.
//! * [`Algorithm::SingularityFree`]: one loop converging x (or y) alone, then a
//!   loop that is repeatable in x (or y) converging the other (Eqs. 28–29).
//!
//! Loops are parallelograms PQMNP (α changes only while the disk rolls): the
//! two horizontal sides (constant α, length |a|) carry the surface integral, the
//! slanted sides (Δθ = `slant`·|a|, Δα = b) cancel each other exactly.
//!
//! Misprints in the OCR'd §4.2 (the tests assert the justified values):
//! * Eq. 28 reads b = −2α_f ± nπ; only odd multiples of π make x repeatable,
//!   so b = π − 2α_f (mod 2π) is used.
//! * The printed b = 0.01808, a = 132.72 follow from the rounded drift
//!   (0.1522, 0.7654); the exact drift gives b = 0.01813, a = 132.38 — the
//!   loop is that sensitive near the singularity.
//! * The detour loop's printed b = 0.8034 rad, a = 3.068 rad also follow from the
//!   rounded drift, truncated (0.80348, 3.0687); 175.78° is the truncated
//!   3.068 rad converted (exact drift: b = 0.80353, a = 3.0688 rad = 175.83°).
//! * Eq. 26's a > 0 cannot hold for b ∈ (2π, 4π); a is signed here (negative:
//!   loop traversed backwards, as the paper itself does for Eq. 28).
//! * "a = −1.05 radians, or 60.15 degrees": the degrees lost their sign, and
//!   come from the rounded y'_d = 1.485 (exact: −60.16°).

use crate::model::{Input, State};
use crate::plan::{plan_from_legs, Limits, Plan};
use crate::planner::PlanError;
use crate::robots::rolling_disk::kinematics::RollingDisk;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

/// Which §4.2 algorithm to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Algorithm {
    /// Eqs. 25–26 plus the Fig. 9 detour.
    SingularityAvoiding,
    /// Eq. 23/24 then Eq. 28/29.
    SingularityFree,
}

/// Where the singularity-avoiding detour puts the loop (point R of Fig. 9).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Detour {
    /// The paper's choice: R = (θ_i, α_i), falling back to `optimal` when that is near-singular too.
    Start,
    /// R at the heading that makes b = π (smallest loop).
    Optimal,
}

/// Order of convergence for the singularity-free algorithm.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Order {
    /// x first when |cos α_f| ≥ |sin α_f| (the paper's rule), else y first.
    Auto,
    /// Eq. 23 then Eq. 28.
    XFirst,
    /// Eq. 24 then Eq. 29.
    YFirst,
}

/// Seed 000 §4.2 Stokes planner for the rolling disk: (θ, α) converge on a
/// line, then (x, y) with closed loops sized by Green's theorem.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct StokesDiskParams {
    /// Algorithm of §4.2.
    pub algorithm: Algorithm,
    /// Loops with sin(b/2) below this are "near the singularity" (Eq. 26's a ≥ 1/this × its minimum).
    #[schemars(range(min = 0), extend("exclusiveMaximum" = 1))]
    pub min_sin_half_b: f64,
    /// Detour point choice.
    pub detour: Detour,
    /// Singularity-free: convergence order.
    pub order: Order,
    /// Singularity-free: b of the first loop in degrees (paper: 60). `None`: best-conditioned b.
    #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 360))]
    pub b_first_deg: Option<f64>,
    /// Δθ of a parallelogram's slanted sides as a fraction of |a| (0 gives the rectangle PQRSP).
    #[schemars(range(min = 0))]
    pub slant: f64,
}

impl Default for StokesDiskParams {
    fn default() -> Self {
        Self {
            algorithm: Algorithm::SingularityAvoiding,
            min_sin_half_b: 0.2,
            detour: Detour::Start,
            order: Order::Auto,
            b_first_deg: None,
            slant: 0.5,
        }
    }
}

/// One closed loop in the θ–α plane, based at (θ, α) = `base`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Loop {
    /// Base point (θ, α), rad.
    pub base: [f64; 2],
    /// Signed θ extent, rad (negative: traversed against the usual direction).
    pub a: f64,
    /// α extent, rad, in (0, 2π).
    pub b: f64,
}

impl Loop {
    /// (Δx, Δy) produced by one traversal (Eqs. 23–24 with α_f → base α).
    pub fn displacement(&self, r: f64) -> [f64; 2] {
        let (al, h) = (self.base[1], 0.5 * self.b);
        let k = 2.0 * self.a * r * h.sin();
        [-k * (al + h).cos(), k * (al + h).sin()]
    }
}

/// Drift (Δx, Δy) of a straight line in the θ–α plane from `from` to `to`.
///
/// Closed form of ∫ r sin α dθ, ∫ r cos α dθ with θ, α linear in a common parameter.
pub(crate) fn line_drift(r: f64, from: [f64; 2], to: [f64; 2]) -> [f64; 2] {
    let (dth, dal) = (to[0] - from[0], to[1] - from[1]);
    let mid = from[1] + 0.5 * dal;
    let half = 0.5 * dal;
    let sinc = if half.abs() < 1e-8 {
        1.0 - half * half / 6.0
    } else {
        half.sin() / half
    };
    [r * dth * mid.sin() * sinc, r * dth * mid.cos() * sinc]
}

/// Solve Eqs. 25–26 for a loop based at heading `alpha` producing `delta`.
/// Returns (a, b) with b ∈ (0, 2π) and signed a (negative: the loop is
/// traversed against the usual direction); `None` for zero displacement.
///
/// Eq. 25 allows 0 < b < 4π, but for b/2 ∈ (π, 2π) Eq. 26 then needs a < 0;
/// here b/2 is reduced to (0, π] and the sign moves into a.
pub(crate) fn solve_xy_loop(r: f64, alpha: f64, delta: [f64; 2]) -> Option<(f64, f64)> {
    let rho = delta[0].hypot(delta[1]);
    if rho == 0.0 {
        return None;
    }
    // Δx = −ρ cos ψ, Δy = ρ sin ψ with ψ = α + b/2 (Eqs. 23–24).
    let psi = delta[1].atan2(-delta[0]);
    let raw = psi - alpha;
    let half = raw.rem_euclid(PI);
    let half = if half == 0.0 { PI } else { half };
    // half = raw + kπ: an odd k flips the direction of (Δx, Δy), so a changes sign.
    let k = ((half - raw) / PI).round() as i64;
    let sign = if k.rem_euclid(2) == 0 { 1.0 } else { -1.0 };
    Some((sign * rho / (2.0 * r * half.sin()), 2.0 * half))
}

/// Output of the planner before time parameterisation.
#[derive(Debug, Clone, Serialize)]
pub struct Geometry {
    /// Drift of the dependent variables after the straight convergence of (θ, α).
    pub drift: [f64; 2],
    /// Near-singular loop that triggered a detour (singularity-avoiding only).
    pub rejected: Option<Loop>,
    /// Loops in execution order, with their names.
    pub loops: Vec<(String, Loop)>,
    /// Path legs: (name, Δθ, Δα).
    pub legs: Vec<(String, [f64; 2])>,
}

fn check_finite(name: &str, v: f64) -> Result<f64, PlanError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(PlanError::InvalidParameter {
            name: name.into(),
            reason: "must be a finite number".into(),
        })
    }
}

fn loop_legs(name: &str, lp: &Loop, slant: f64, legs: &mut Vec<(String, [f64; 2])>) {
    let (a, b) = (lp.a.abs(), lp.b);
    let s = slant * a;
    let fwd = [
        ("PQ", [a, 0.0]),
        ("QM", [s, b]),
        ("MN", [-a, 0.0]),
        ("NP", [-s, -b]),
    ];
    let rev = [
        ("PN", [s, b]),
        ("NM", [a, 0.0]),
        ("MQ", [-s, -b]),
        ("QP", [-a, 0.0]),
    ];
    for (side, d) in if lp.a >= 0.0 { fwd } else { rev } {
        legs.push((format!("{name}: {side}"), d));
    }
}

/// The geometric plan (loops and legs) for a disk of radius `r`.
pub fn geometry(
    r: f64,
    start: [f64; 4],
    goal: [f64; 4],
    p: &StokesDiskParams,
) -> Result<Geometry, PlanError> {
    check_finite("r", r)?;
    if r <= 0.0 {
        return Err(PlanError::InvalidParameter {
            name: "r".into(),
            reason: "radius must be > 0".into(),
        });
    }
    if !(0.0..1.0).contains(&check_finite("min_sin_half_b", p.min_sin_half_b)?) {
        return Err(PlanError::InvalidParameter {
            name: "min_sin_half_b".into(),
            reason: "must be in [0, 1)".into(),
        });
    }
    if check_finite("slant", p.slant)? < 0.0 {
        return Err(PlanError::InvalidParameter {
            name: "slant".into(),
            reason: "must be ≥ 0".into(),
        });
    }
    let o = [start[2], start[3]];
    let pf = [goal[2], goal[3]];
    let op = line_drift(r, o, pf);
    let drift = [start[0] + op[0], start[1] + op[1]];
    let delta = [goal[0] - drift[0], goal[1] - drift[1]];
    let mut g = Geometry {
        drift,
        rejected: None,
        loops: vec![],
        legs: vec![],
    };
    let op_leg = ("OP".to_string(), [pf[0] - o[0], pf[1] - o[1]]);
    match p.algorithm {
        Algorithm::SingularityAvoiding => {
            let Some((a, b)) = solve_xy_loop(r, pf[1], delta) else {
                g.legs.push(op_leg);
                return Ok(g);
            };
            let direct = Loop { base: pf, a, b };
            if (0.5 * b).sin() >= p.min_sin_half_b {
                g.legs.push(op_leg);
                loop_legs("loop", &direct, p.slant, &mut g.legs);
                g.loops.push(("loop".into(), direct));
                return Ok(g);
            }
            g.rejected = Some(direct);
            // Fig. 9, step 1: pick R with α'_f ≠ α_f such that the loop is well conditioned.
            if p.detour == Detour::Start {
                if let Some((a, b)) = solve_xy_loop(r, o[1], delta) {
                    if (0.5 * b).sin() >= p.min_sin_half_b {
                        // R = O: O→P→O is redundant, so the path is the loop at O, then OP.
                        let lp = Loop { base: o, a, b };
                        loop_legs("loop at O", &lp, p.slant, &mut g.legs);
                        g.loops.push(("loop at O".into(), lp));
                        g.legs.push(op_leg);
                        return Ok(g);
                    }
                }
            }
            // b = π: heading α' = ψ − π/2; roll to it at 45° in the θ–α plane, loop, retrace.
            let psi = delta[1].atan2(-delta[0]);
            let dal = (psi - 0.5 * PI - pf[1] + PI).rem_euclid(TAU) - PI;
            let rp = [pf[0] + dal.abs(), pf[1] + dal];
            let (a, b) = solve_xy_loop(r, rp[1], delta).expect("nonzero displacement");
            let lp = Loop { base: rp, a, b };
            g.legs.push(op_leg);
            g.legs.push(("PR".into(), [rp[0] - pf[0], rp[1] - pf[1]]));
            loop_legs("loop at R", &lp, p.slant, &mut g.legs);
            g.loops.push(("loop at R".into(), lp));
            g.legs.push(("RP".into(), [pf[0] - rp[0], pf[1] - rp[1]]));
            Ok(g)
        }
        Algorithm::SingularityFree => {
            let al = pf[1];
            let x_first = match p.order {
                Order::XFirst => true,
                Order::YFirst => false,
                Order::Auto => al.cos().abs() >= al.sin().abs(),
            };
            // First loop converges one coordinate; its conditioning factor is
            // sin(b/2)cos(α+b/2) = ½[sin(α+b) − sin α] (x) or ½[cos α − cos(α+b)] (y).
            let factor = |b: f64| {
                if x_first {
                    -0.5 * ((al + b).sin() - al.sin())
                } else {
                    0.5 * (al.cos() - (al + b).cos())
                }
            };
            let b1 = match p.b_first_deg {
                Some(deg) => {
                    let b = check_finite("b_first_deg", deg)?.to_radians();
                    if !(b > 0.0 && b < TAU) {
                        return Err(PlanError::InvalidParameter {
                            name: "b_first_deg".into(),
                            reason: "must be in (0, 360)".into(),
                        });
                    }
                    if factor(b).abs() < 1e-3 {
                        return Err(PlanError::InvalidParameter {
                            name: "b_first_deg".into(),
                            reason: format!(
                                "b = {deg}° makes the first loop singular for α_f = {:.3}°; omit it to let the planner choose",
                                al.to_degrees()
                            ),
                        });
                    }
                    b
                }
                None => {
                    // Maximise |factor|: sin(α+b) = −sign(sin α) (x) or cos(α+b) = −sign(cos α) (y).
                    let target = if x_first {
                        -PI / 2.0 * if al.sin() >= 0.0 { 1.0 } else { -1.0 }
                    } else if al.cos() >= 0.0 {
                        PI
                    } else {
                        0.0
                    };
                    let b = (target - al).rem_euclid(TAU);
                    if b == 0.0 {
                        TAU / 2.0
                    } else {
                        b
                    }
                }
            };
            let (d1, d2) = if x_first {
                (delta[0], delta[1])
            } else {
                (delta[1], delta[0])
            };
            // Eq. 28 divides by cos α_f, Eq. 29 by sin α_f.
            let divisor = if x_first { al.cos() } else { al.sin() };
            if divisor.abs() < 1e-6 {
                return Err(PlanError::InvalidParameter {
                    name: "order".into(),
                    reason: format!(
                        "α_f = {:.3}° makes the repeatable loop of Eq. {} singular; use order = \"auto\"",
                        al.to_degrees(),
                        if x_first { 28 } else { 29 }
                    ),
                });
            }
            let a1 = d1 / (2.0 * r * factor(b1));
            let first = Loop {
                base: pf,
                a: a1,
                b: b1,
            };
            let moved = first.displacement(r);
            // The other coordinate drifted; the repeatable loop converges it (Eq. 28/29).
            let rest = if x_first {
                d2 - moved[1]
            } else {
                d2 - moved[0]
            };
            let a2 = rest / (2.0 * r * divisor);
            let b2 = if x_first { PI - 2.0 * al } else { -2.0 * al }.rem_euclid(TAU);
            let b2 = if b2 == 0.0 { TAU / 2.0 } else { b2 };
            let second = Loop {
                base: pf,
                a: a2,
                b: b2,
            };
            let (n1, n2) = if x_first {
                ("loop x", "loop y")
            } else {
                ("loop y", "loop x")
            };
            g.legs.push(op_leg);
            for (name, lp) in [(n1, first), (n2, second)] {
                if lp.a != 0.0 {
                    loop_legs(name, &lp, p.slant, &mut g.legs);
                }
                g.loops.push((name.into(), lp));
            }
            Ok(g)
        }
    }
}

/// Plan a disk motion from `start` to `goal` (x, y, θ, α; rad).
pub fn plan(
    disk: &RollingDisk,
    start: &State,
    goal: &State,
    params: &StokesDiskParams,
    limits: &Limits,
) -> Result<Plan, PlanError> {
    let s = [start[0], start[1], start[2], start[3]];
    let f = [goal[0], goal[1], goal[2], goal[3]];
    let g = geometry(disk.r, s, f, params)?;
    let mut labels: Vec<String> = Vec::new();
    let mut legs = Vec::new();
    for (name, d) in &g.legs {
        let label = labels.iter().position(|l| l == name).unwrap_or_else(|| {
            labels.push(name.clone());
            labels.len() - 1
        });
        legs.push((label, Input::from_vec(d.to_vec())));
    }
    if labels.is_empty() {
        labels.push("hold".into());
    }
    let details = serde_json::json!({
        "algorithm": params.algorithm,
        "drift_after_OP": g.drift,
        "rejected_loop": g.rejected,
        "loops": g.loops.iter().map(|(n, l)| serde_json::json!({
            "name": n, "base_deg": [l.base[0].to_degrees(), l.base[1].to_degrees()],
            "a_rad": l.a, "b_rad": l.b, "a_deg": l.a.to_degrees(), "b_deg": l.b.to_degrees(),
        })).collect::<Vec<_>>(),
    });
    Ok(plan_from_legs(labels, legs, limits, details))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::simulate;
    use proptest::prelude::*;

    const R: f64 = 0.25;
    const START: [f64; 4] = [0.0, 0.0, 0.0, 0.0];
    const GOAL: [f64; 4] = [-0.4, 1.0, PI, PI / 8.0];

    /// Printed precision: within one unit of the last printed digit (the
    /// paper truncates as often as it rounds).
    fn printed(value: f64, printed: f64, decimals: i32) {
        let ulp = 10f64.powi(-decimals);
        assert!(
            (value - printed).abs() <= ulp,
            "computed {value} does not match printed {printed} to {decimals} decimals"
        );
    }

    fn limits() -> Limits {
        Limits {
            max_rate: vec![4.0, 2.0],
            ramp: 0.25,
            step: 1e-3,
        }
    }

    fn ideal_final(start: [f64; 4], goal: [f64; 4], p: &StokesDiskParams) -> State {
        let disk = RollingDisk { r: R };
        let s = State::from_vec(start.to_vec());
        let plan = plan(&disk, &s, &State::from_vec(goal.to_vec()), p, &limits()).unwrap();
        simulate(&disk, &plan, &s, 1e-3).last().clone()
    }

    fn avoiding() -> StokesDiskParams {
        StokesDiskParams::default()
    }

    fn free60() -> StokesDiskParams {
        StokesDiskParams {
            algorithm: Algorithm::SingularityFree,
            b_first_deg: Some(60.0),
            ..Default::default()
        }
    }

    #[test]
    fn drift_after_oz_matches_paper_and_integration() {
        let d = line_drift(R, [0.0, 0.0], [PI, PI / 8.0]);
        printed(d[0], 0.1522, 4);
        printed(d[1], 0.7654, 4);
        // The closed form agrees with RK4 along the straight leg.
        let disk = RollingDisk { r: R };
        let lim = limits();
        let plan = plan_from_legs(
            vec!["OZ".into()],
            vec![(0, Input::from_vec(vec![PI, PI / 8.0]))],
            &lim,
            serde_json::Value::Null,
        );
        let q = simulate(&disk, &plan, &State::zeros(4), 1e-3)
            .last()
            .clone();
        assert!(
            (q[0] - d[0]).abs() < 1e-12 && (q[1] - d[1]).abs() < 1e-12,
            "{q}"
        );
    }

    #[test]
    fn near_singular_loop_printed_values_follow_rounded_drift() {
        // Printed: b = 0.01808, a = 132.72, from the rounded drift (0.1522, 0.7654).
        let (a, b) = solve_xy_loop(R, PI / 8.0, [-0.4 - 0.1522, 1.0 - 0.7654]).unwrap();
        printed(b, 0.01808, 5);
        printed(a, 132.72, 2);
        // With the exact drift the loop is b = 0.01813, a = 132.38 (documented misprint).
        let g = geometry(R, START, GOAL, &avoiding()).unwrap();
        let rej = g.rejected.expect("near-singular loop must be rejected");
        printed(rej.b, 0.01813, 5);
        printed(rej.a, 132.38, 2);
    }

    #[test]
    fn detour_loop_at_o_matches_paper() {
        // Printed b = 0.8034 rad = 46.03°, a = 3.068 rad = 175.78°: from the rounded
        // drift, truncated; 175.78° is the truncated 3.068 rad converted.
        let (a, b) = solve_xy_loop(R, 0.0, [-0.4 - 0.1522, 1.0 - 0.7654]).unwrap();
        printed(b, 0.8034, 4);
        printed(b.to_degrees(), 46.03, 2);
        printed(a, 3.068, 3);
        printed(3.068f64.to_degrees(), 175.78, 2);
        // Exact drift: b = 0.80353 rad = 46.039°, a = 3.0688 rad = 175.83°.
        let g = geometry(R, START, GOAL, &avoiding()).unwrap();
        let (name, lp) = &g.loops[0];
        assert_eq!(name, "loop at O");
        assert_eq!(lp.base, [0.0, 0.0]);
        printed(lp.b, 0.80353, 5);
        printed(lp.a, 3.0688, 4);
        printed(lp.a.to_degrees(), 175.83, 2);
        // Path OPQROZ: the loop first, then the straight line.
        let names: Vec<&str> = g.legs.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(
            names,
            [
                "loop at O: PQ",
                "loop at O: QM",
                "loop at O: MN",
                "loop at O: NP",
                "OP"
            ]
        );
    }

    #[test]
    fn singularity_free_matches_paper() {
        let g = geometry(R, START, GOAL, &free60()).unwrap();
        let (n1, l1) = &g.loops[0];
        let (n2, l2) = &g.loops[1];
        assert_eq!((n1.as_str(), n2.as_str()), ("loop x", "loop y"));
        printed(l1.b, 1.047, 3);
        printed(l1.a, 3.628, 3);
        // Printed 207.87° is the truncated 3.628 rad in degrees; exact 207.90°.
        printed(3.628f64.to_degrees(), 207.87, 2);
        // y drifts to y'_d = 1.485 while x converges.
        let y_d_prime = g.drift[1] + l1.displacement(R)[1];
        printed(y_d_prime, 1.485, 3);
        printed(g.drift[0] + l1.displacement(R)[0], -0.4, 12);
        // Eq. 28: b = 135°, a = -1.05 rad (the printed "60.15 degrees" lost its sign
        // and comes from the rounded y'_d; exact -60.16°).
        printed(l2.b.to_degrees(), 135.0, 9);
        printed(l2.b, 2.356, 3);
        printed(l2.a, -1.05, 2);
        printed(l2.a.to_degrees(), -60.16, 2);
        let from_rounded = (1.0 - 1.485) / (2.0 * R * (PI / 8.0).cos());
        printed(from_rounded.to_degrees(), -60.15, 2);
        // The second loop is repeatable in x.
        assert!(l2.displacement(R)[0].abs() < 1e-15);
    }

    #[test]
    fn ideal_runs_reach_the_goal() {
        for p in [avoiding(), free60()] {
            let q = ideal_final(START, GOAL, &p);
            for i in 0..4 {
                assert!((q[i] - GOAL[i]).abs() < 1e-9, "{:?}: {q}", p.algorithm);
            }
        }
    }

    #[test]
    fn exact_singularity_uses_optimal_detour() {
        let goal = [-1.0, 0.0, 0.0, 0.0];
        let g = geometry(R, START, goal, &avoiding()).unwrap();
        assert!(g.rejected.is_some());
        assert_eq!(g.loops[0].0, "loop at R");
        assert!((g.loops[0].1.b - PI).abs() < 1e-12);
        let q = ideal_final(START, goal, &avoiding());
        assert!(
            (q[0] + 1.0).abs() < 1e-9 && q[1].abs() < 1e-9 && q[2].abs() < 1e-9,
            "{q}"
        );
    }

    #[test]
    fn bad_parameters_are_reported() {
        let p = StokesDiskParams {
            min_sin_half_b: f64::NAN,
            ..Default::default()
        };
        assert!(matches!(
            geometry(R, START, GOAL, &p),
            Err(PlanError::InvalidParameter { .. })
        ));
        let p = StokesDiskParams {
            algorithm: Algorithm::SingularityFree,
            order: Order::XFirst,
            ..Default::default()
        };
        let goal = [1.0, 1.0, 0.0, PI / 2.0];
        assert!(matches!(
            geometry(R, START, goal, &p),
            Err(PlanError::InvalidParameter { .. })
        ));
        // b = 90° - ... chosen so that cos(α + b/2) = 0 for α = 60°.
        let p = StokesDiskParams {
            b_first_deg: Some(60.0),
            ..free60()
        };
        let goal = [1.0, 1.0, 0.0, PI / 3.0];
        let p = StokesDiskParams {
            order: Order::XFirst,
            ..p
        };
        assert!(matches!(
            geometry(R, START, goal, &p),
            Err(PlanError::InvalidParameter { .. })
        ));
    }

    fn config() -> impl Strategy<Value = [f64; 4]> {
        (-3.0..3.0f64, -3.0..3.0f64, -7.0..7.0f64, -7.0..7.0f64)
            .prop_map(|(x, y, t, a)| [x, y, t, a])
    }

    proptest! {
        #![proptest_config(crate::prop_config::config(64))]
        #[test]
        fn random_tasks_reach_the_goal(s in config(), g in config(), free in any::<bool>()) {
            let p = StokesDiskParams {
                algorithm: if free { Algorithm::SingularityFree } else { Algorithm::SingularityAvoiding },
                ..Default::default()
            };
            let geo = geometry(R, s, g, &p).unwrap();
            for (_, lp) in &geo.loops {
                prop_assert!(lp.a.is_finite() && lp.b.is_finite());
                prop_assert!(lp.a.abs() < 1e4);
            }
            let q = ideal_final(s, g, &p);
            for i in 0..4 {
                prop_assert!((q[i] - g[i]).abs() < 1e-9, "coord {} : {} vs {}", i, q[i], g[i]);
            }
        }
    }
}
