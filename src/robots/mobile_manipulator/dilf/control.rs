//! The closed-loop kinematic controller of seed 004 (Eq. 18), for k robots.
//!
//! With f = (Σ‖h2‖²)² ∂V/∂q and, for robot r, f_r = (f_x, f_y, f_θ, f_a):
//!
//! * v_r = k_v sign(f_x cos θ + f_y sin θ) ‖f‖  (18a; ‖f‖ is the whole field;
//!   opt-in, ours: v_r = k_v (f_x cos θ + f_y sin θ), [`SpeedLaw`])
//! * ω_r = k_o (θ_d − θ) when w_r ≥ 0, else −v_r (f_x cos θ + f_y sin θ) / f_θ  (18b)
//! * u_a = K_a f_a  (18c)
//!
//! with θ_d = atan2(−sign(x) f_y, −sign(x) f_x) and
//! w_r = v_r (f_x cos θ + f_y sin θ) + k_o f_θ (θ_d − θ), in the goal frame of
//! robot r's platform (origin at its goal, x along its goal heading).
//!
//! Resolved misprints: Eq. 18b prints the second branch without its minus
//! sign; Appendix G's proof uses −v_r(…)/f_θ, which is what makes the
//! platform's contribution to V̇ vanish (and V̇ ≥ 0 hold). The text uses k_v
//! both for the exponent of Eq. 15 and for the speed gain of Eq. 18a: they are
//! two parameters here (`kv_exponent`, `kv_gain`). θ_d − θ is wrapped to
//! (−π, π].
//!
//! θ_d, two refinements of ours (V̇ ≥ 0 holds for any θ_d in the steer branch,
//! so neither touches the proof):
//!
//! * The dipole's plane γ = 0 passes through the goal, so while the arm still
//!   converges the field's maximum along the goal axis sits a little in front
//!   of the goal (at |x| = √(arm part of Σ‖h2‖²)), and between it and the goal
//!   the field points away from the goal: the printed θ_d (the field's
//!   direction for x < 0) then turns the platform around, and back again once
//!   the arm has converged (seen in the ideal run and in physics). In that
//!   band, recognised within 0.5 m of the goal as the part of the cone
//!   |y| < |x| about the goal axis where x f_x > 0 (the pure dipole field
//!   points towards the goal throughout the cone), θ_d is whichever of the field's direction and its
//!   opposite lies on the goal heading's side: the platform backs off along
//!   the axis instead. Outside the band both rules agree near the axis, so θ_d
//!   stays continuous at its edge.
//! * Where the planar field is negligible (below `heading_deadzone` · ‖f‖)
//!   θ_d is undefined in effect: it flips by π from sample to sample and the
//!   platform spins in place; there θ_d = θ.
//!
//! Final alignment (ours): within half the task's position tolerance the platform
//! stops translating and turns in place to the goal heading (ω = k_o(θ* − θ),
//! v = 0) while the arm keeps following Eq. 18c. A unicycle corrects a lateral
//! error δ at distance d only with a heading swing of order δ/d, so at
//! millimetres from the goal the field swings the heading by tens of degrees
//! (seen in physics) to remove an error the task accepts, and where both v and
//! f_θ are tiny Eq. 18b's hold branch turns the platform aimlessly. This
//! phase may lower V; the V̇ ≥ 0 check counts only samples outside it. The
//! controller also hands a platform over to it anywhere within the whole
//! tolerance once the law stops making progress, and keeps it aligning
//! while it stays within the tolerance ([`control_aligning`], [`crate::robots::mobile_manipulator::dilf::stall`]).
//!
//! Physical limits (ours), chosen so that V̇ ≥ 0 still holds: |v| is capped
//! first (a state-dependent k_v ≤ the configured one) and Eq. 18b is applied
//! with the capped v; in the steer branch ω = k_o(θ_d − θ) is clamped (which
//! only shrinks a possibly negative ω f_θ), in the hold branch v and ω are
//! scaled down together (their V̇ term stays 0). Each arm's joint rates are
//! scaled down together (their term f_aᵀK_a f_a stays ≥ 0).

use crate::compare::wrap_angle;
use crate::robots::mobile_manipulator::kinematics::{DOF, INPUTS};
use serde::{Deserialize, Serialize};

/// Gains and limits of Eq. 18.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Gains {
    /// k_v of Eq. 18a (speed gain).
    pub kv_gain: f64,
    /// k_o of Eq. 18b.
    pub ko: f64,
    /// K_a of Eq. 18c (diagonal, one per joint).
    pub ka: [f64; 6],
    /// Largest platform speed |v|, m/s.
    pub max_speed: f64,
    /// Largest platform turn rate |ω|, rad/s.
    pub max_turn_rate: f64,
    /// Largest joint rate, rad/s.
    pub max_joint_rate: f64,
    /// θ_d is held at θ while the planar field ‖(f_x, f_y)‖ is below this
    /// fraction of ‖f‖ (see the module docs).
    pub heading_deadzone: f64,
    /// Within this distance (the task's position tolerance) θ_d is the goal
    /// heading itself, m.
    pub goal_lock_radius: f64,
    /// Within this distance of its goal a platform's heading stays within
    /// `approach_heading` of the goal heading (ours, see the module docs), m;
    /// 0: no cap (the paper's law).
    pub approach_radius: f64,
    /// The cap on |θ − θ_goal| within `approach_radius`, rad.
    pub approach_heading: f64,
    /// Eq. 18a's speed law, or our continuous alternative.
    pub speed: SpeedLaw,
    /// θ_d's side of the dipole plane from the formation's mean goal-frame
    /// x rather than each platform's own (with `dipole = "formation"`).
    pub formation_side: bool,
    /// In the final alignment the arm joints go to their goal angles at
    /// this gain, 1/s (ours); 0: Eq. 18c's rates there too.
    #[serde(default)]
    pub align_joint_gain: f64,
}

/// How v_r follows the field (Eq. 18a or ours).
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum SpeedLaw {
    /// Eq. 18a: v = k_v sign(f·h) ‖f‖. Where the field is nearly
    /// perpendicular to the heading, f·h changes sign from sample to sample
    /// and v jumps between ±the speed limit.
    Sign,
    /// Ours (the default): v = k_v (f·h), the field's component along the
    /// heading h = (cos θ, sin θ). Continuous, zero where the field is
    /// perpendicular to the heading; the platform's V̇ term k_v (f·h)² stays
    /// ≥ 0.
    #[default]
    Projection,
}

/// Which branch of Eq. 18b robot r took.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Branch {
    /// w ≥ 0: ω = k_o (θ_d − θ).
    Steer,
    /// w < 0: ω keeps the platform's V̇ contribution at 0.
    Hold,
    /// Within the position tolerance: the platform turns in place to the
    /// goal heading (ours, see the module docs).
    Align,
}

impl Branch {
    /// Index in 0..3 (for plan labels).
    pub fn index(self) -> usize {
        match self {
            Branch::Steer => 0,
            Branch::Hold => 1,
            Branch::Align => 2,
        }
    }

    /// Name in plan labels.
    pub fn name(i: usize) -> &'static str {
        ["steer", "hold", "align"][i.min(2)]
    }
}

/// How far from its goal a platform looks for the band (see the module
/// docs), m: beyond the arm-induced offset √(arm part of Σ‖h2‖²) of the
/// shipped tasks; farther out, obstacles also turn the field away from the
/// goal and there the printed rule must steer around them.
const BAND_RADIUS: f64 = 0.5;

/// sign with sign(0) = +1 (Appendix G).
fn sign(x: f64) -> f64 {
    if x >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// Eq. 18 for every robot: the inputs (8 per robot) and the branch each took.
pub fn control(q: &[f64], f: &[f64], goal: &[f64], g: &Gains) -> (Vec<f64>, Vec<Branch>) {
    control_aligning(q, f, goal, g, &[])
}

/// As [`control`], with robot r turning in place to its goal heading also
/// where `aligning[r]` (the controller's hand-over, [`crate::robots::mobile_manipulator::dilf::stall`]), not
/// only within `goal_lock_radius`.
pub fn control_aligning(
    q: &[f64],
    f: &[f64],
    goal: &[f64],
    g: &Gains,
    aligning: &[bool],
) -> (Vec<f64>, Vec<Branch>) {
    let robots = q.len() / DOF;
    let norm_f = f.iter().map(|x| x * x).sum::<f64>().sqrt();
    let mut u = vec![0.0; INPUTS * robots];
    let mut branches = Vec::with_capacity(robots);
    let x_mean = (0..robots)
        .map(|r| {
            let i = DOF * r;
            let (c, s) = (goal[i + 2].cos(), goal[i + 2].sin());
            (q[i] - goal[i]) * c + (q[i + 1] - goal[i + 1]) * s
        })
        .sum::<f64>();
    for r in 0..robots {
        let (i, j) = (DOF * r, INPUTS * r);
        let (th, th_goal) = (q[i + 2], goal[i + 2]);
        let (fx, fy, fth) = (f[i], f[i + 1], f[i + 2]);
        let proj = fx * th.cos() + fy * th.sin();
        // The speed limit acts as a state-dependent k_v ≤ the configured one.
        let v = match g.speed {
            SpeedLaw::Sign => (g.kv_gain * norm_f).min(g.max_speed) * sign(proj),
            SpeedLaw::Projection => (g.kv_gain * proj).clamp(-g.max_speed, g.max_speed),
        };
        // Goal frame: origin at the platform's goal, x along the goal heading.
        let (c, s) = (th_goal.cos(), th_goal.sin());
        let x_goal = (q[i] - goal[i]) * c + (q[i + 1] - goal[i + 1]) * s;
        let (gx, gy) = (fx * c + fy * s, -fx * s + fy * c);
        let sx = sign(if g.formation_side { x_mean } else { x_goal });
        let dist = (q[i] - goal[i]).hypot(q[i + 1] - goal[i + 1]);
        let y_goal = -(q[i] - goal[i]) * s + (q[i + 1] - goal[i + 1]) * c;
        // The band next to the goal where the field points away from it
        // although the platform is within 45° of the goal axis (the pure
        // dipole field points towards the goal throughout that cone).
        let band = dist <= BAND_RADIUS && x_goal * gx > 0.0 && y_goal.abs() < x_goal.abs();
        let theta_d = if band {
            // Of the field's direction and its opposite, the one on the goal
            // heading's side: the platform backs off instead of turning round.
            let phi = gy.atan2(gx);
            let phi = if phi.abs() <= std::f64::consts::FRAC_PI_2 {
                phi
            } else {
                phi + std::f64::consts::PI
            };
            phi + th_goal
        } else if gx.hypot(gy) <= g.heading_deadzone * norm_f {
            th
        } else {
            (-sx * gy).atan2(-sx * gx) + th_goal
        };
        let e = wrap_angle(theta_d - th);
        let w = v * proj + g.ko * fth * e;
        let align = dist <= g.goal_lock_radius || aligning.get(r).copied().unwrap_or(false);
        let (v, omega, branch) = if align {
            let omega = (g.ko * wrap_angle(th_goal - th)).clamp(-g.max_turn_rate, g.max_turn_rate);
            (0.0, omega, Branch::Align)
        } else if w >= 0.0 {
            // Clamping ω only shrinks a possibly negative ω f_θ: w stays ≥ 0.
            let omega = (g.ko * e).clamp(-g.max_turn_rate, g.max_turn_rate);
            (v, omega, Branch::Steer)
        } else if fth != 0.0 {
            let omega = -v * proj / fth;
            // Scaling v and ω together keeps the platform's V̇ term at 0.
            let scale = (g.max_turn_rate / omega.abs()).min(1.0);
            (v * scale, omega * scale, Branch::Hold)
        } else {
            (v, 0.0, Branch::Hold)
        };
        // The approach cap: near the goal ω may not turn the platform
        // further from its goal heading than the cap (ω → 0 keeps the
        // platform's V̇ term ≥ 0 in every branch: v·proj ≥ 0).
        let off = wrap_angle(th - th_goal);
        let omega = if branch != Branch::Align
            && g.approach_radius > 0.0
            && dist <= g.approach_radius
            && off.abs() >= g.approach_heading
            && omega * off > 0.0
        {
            0.0
        } else {
            omega
        };
        u[j] = v;
        u[j + 1] = omega;
        // The final alignment suspends Eq. 18 for the platform; with a gain
        // the arm goes straight to its goal angles too (ours, opt-in).
        let rates: Vec<f64> = if branch == Branch::Align && g.align_joint_gain > 0.0 {
            (0..6)
                .map(|a| g.align_joint_gain * wrap_angle(goal[i + 3 + a] - q[i + 3 + a]))
                .collect()
        } else {
            (0..6).map(|a| g.ka[a] * f[i + 3 + a]).collect()
        };
        let peak = rates.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let arm = (g.max_joint_rate / peak).min(1.0);
        for a in 0..6 {
            u[j + 2 + a] = rates[a] * arm;
        }
        branches.push(branch);
    }
    (u, branches)
}

/// V̇ / D² under input u: f · q̇(u) (the sign of V̇, Eq. 17).
pub(crate) fn vdot_scaled(q: &[f64], f: &[f64], u: &[f64]) -> f64 {
    let robots = q.len() / DOF;
    let mut out = 0.0;
    for r in 0..robots {
        let (i, j) = (DOF * r, INPUTS * r);
        let th = q[i + 2];
        out += f[i] * u[j] * th.cos() + f[i + 1] * u[j] * th.sin() + f[i + 2] * u[j + 1];
        for a in 0..6 {
            out += f[i + 3 + a] * u[j + 2 + a];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn gains() -> Gains {
        Gains {
            kv_gain: 0.7,
            ko: 1.3,
            ka: [0.5, 0.4, 0.3, 0.6, 0.2, 0.9],
            max_speed: 0.4,
            max_turn_rate: 0.6,
            max_joint_rate: 0.5,
            heading_deadzone: 0.05,
            goal_lock_radius: 0.02,
            approach_radius: 0.0,
            approach_heading: 0.0,
            speed: SpeedLaw::Sign,
            formation_side: false,
            align_joint_gain: 0.0,
        }
    }

    /// Appendix G: every robot's platform contributes w ≥ 0 or exactly 0, its
    /// arm f_aᵀK_a f_a ≥ 0, so V̇ ≥ 0 for any field, with or without limits.
    #[test]
    fn vdot_is_never_negative() {
        let mut rng = ChaCha8Rng::seed_from_u64(18);
        for robots in [1, 2] {
            for _ in 0..2000 {
                let q: Vec<f64> = (0..DOF * robots)
                    .map(|_| rng.random_range(-3.0..3.0))
                    .collect();
                let mut f: Vec<f64> = (0..DOF * robots)
                    .map(|_| rng.random_range(-2.0..2.0))
                    .collect();
                if rng.random_bool(0.25) {
                    // f_θ = 0: no ω can make up for the speed law, v·(f·h)
                    // itself must be ≥ 0.
                    for r in 0..robots {
                        f[DOF * r + 2] = 0.0;
                    }
                }
                let goal: Vec<f64> = (0..DOF * robots)
                    .map(|_| rng.random_range(-3.0..3.0))
                    .collect();
                let mut g = gains();
                if rng.random_bool(0.5) {
                    // The continuous speed law (ours): k_v (f·h)² ≥ 0.
                    g.speed = SpeedLaw::Projection;
                }
                if rng.random_bool(0.5) {
                    // The approach cap (ours) must keep V̇ ≥ 0 as well.
                    g.approach_radius = rng.random_range(0.0..6.0);
                    g.approach_heading = rng.random_range(0.01..3.2);
                }
                let (u, branches) = control(&q, &f, &goal, &g);
                let vd = vdot_scaled(&q, &f, &u);
                let size = f.iter().map(|x| x * x).sum::<f64>() * 10.0;
                assert!(vd >= -1e-12 * size, "V̇ = {vd}");
                // Each platform's own term, which the arms' could mask.
                for (r, b) in branches.iter().enumerate() {
                    let (i, j) = (DOF * r, INPUTS * r);
                    let th = q[i + 2];
                    let term = (f[i] * th.cos() + f[i + 1] * th.sin()) * u[j] + f[i + 2] * u[j + 1];
                    assert!(
                        *b == Branch::Align || term >= -1e-12 * size,
                        "robot {r}: {term}"
                    );
                }
                let g = gains();
                for r in 0..robots {
                    assert!(u[INPUTS * r].abs() <= g.max_speed * (1.0 + 1e-12));
                    assert!(u[INPUTS * r + 1].abs() <= g.max_turn_rate * (1.0 + 1e-12));
                }
            }
        }
    }

    /// Near the goal with the approach cap, a platform at the cap is not
    /// turned further from its goal heading, may turn back towards it, and
    /// outside the radius (or without the cap) the law is Eq. 18's.
    #[test]
    fn the_approach_cap_stops_turning_away_from_the_goal_heading() {
        // 0.3 m behind the goal and 0.05 m beside its axis, heading 20°: the
        // field (45°) pulls it further left.
        let f = [1.0, 1.0, 0.01, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let goal = [0.0; 9];
        let q = |th: f64| [-0.3, -0.05, th, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let at_cap = q(20f64.to_radians());
        let mut g = gains();
        let (free, _) = control(&at_cap, &f, &goal, &g);
        assert!(free[1] > 0.1, "Eq. 18 turns left: ω = {}", free[1]);
        g.approach_radius = 0.5;
        g.approach_heading = 20f64.to_radians();
        let (capped, _) = control(&at_cap, &f, &goal, &g);
        assert_eq!(capped[1], 0.0);
        assert_eq!(capped[0], free[0], "v is Eq. 18a's");
        // Below the cap, or beyond the radius, ω is Eq. 18's.
        let below = q(10f64.to_radians());
        assert_eq!(
            control(&below, &f, &goal, &g).0[1],
            control(&below, &f, &goal, &gains()).0[1]
        );
        g.approach_radius = 0.2;
        assert_eq!(control(&at_cap, &f, &goal, &g).0[1], free[1]);
        // Beyond the cap on the other side the law may turn back (left).
        g.approach_radius = 0.5;
        let right = q(-30f64.to_radians());
        let (back, _) = control(&right, &f, &goal, &g);
        assert!(back[1] > 0.0 && back[1] == control(&right, &f, &goal, &gains()).0[1]);
    }

    /// Where the field turns perpendicular to the heading, Eq. 18a's v jumps
    /// between ±the speed limit; the projection law passes through 0, is
    /// k_v (f·h) below the limit and saturates as Eq. 18a does.
    #[test]
    fn the_projection_speed_is_continuous_across_a_perpendicular_field() {
        let goal = [0.0; 9];
        // Heading east, field (±ε, 1): f·h = ±ε.
        let q = [-2.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let f = |fx: f64| [fx, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let mut g = gains();
        let v = |g: &Gains, fx: f64| control(&q, &f(fx), &goal, g).0[0];
        assert_eq!(v(&g, 1e-6), g.max_speed);
        assert_eq!(v(&g, -1e-6), -g.max_speed);
        g.speed = SpeedLaw::Projection;
        assert!((v(&g, 1e-6) - g.kv_gain * 1e-6).abs() < 1e-15);
        assert!((v(&g, -1e-6) + g.kv_gain * 1e-6).abs() < 1e-15);
        assert!((v(&g, 0.1) - g.kv_gain * 0.1).abs() < 1e-12);
        assert_eq!(v(&g, 3.0), g.max_speed);
        assert_eq!(v(&g, -3.0), -g.max_speed);
    }

    #[test]
    fn the_hold_branch_zeroes_the_platform_term() {
        // Heading perpendicular to a field that wants to turn the other way.
        let q = [0.0, -1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let f = [0.2, 1.0, -0.05, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let goal = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        let mut g = gains();
        g.max_speed = 1e9;
        g.max_turn_rate = 1e9;
        let (u, b) = control(&q, &f, &goal, &g);
        let platform = f[0] * u[0] + f[2] * u[1];
        if b[0] == Branch::Hold {
            assert!(platform.abs() < 1e-12);
        } else {
            assert!(platform >= 0.0);
        }
    }

    /// In the final alignment with `align_joint_gain` the arm joints go to
    /// their goal angles (gain × error, scaled together within the joint
    /// rate limit); without it, or off the alignment, they follow Eq. 18c.
    #[test]
    fn the_final_alignment_drives_the_arm_to_its_goal_angles() {
        let goal = [0.0, 0.0, 0.5, 0.1, -0.2, 0.3, 0.0, 0.4, -0.1];
        // At the goal position (within the lock radius), heading off.
        let mut q = goal;
        q[2] = 0.0;
        q[3] = 0.05;
        q[4] = -0.2 - 0.02;
        q[8] = -0.1 + 0.04;
        let f = [0.1, 0.2, 0.3, 0.01, -0.02, 0.03, 0.0, 0.01, 0.02];
        let mut g = gains();
        let (eq18c, b) = control(&q, &f, &goal, &g);
        assert_eq!(b[0], Branch::Align);
        for a in 0..6 {
            assert!((eq18c[2 + a] - g.ka[a] * f[3 + a]).abs() < 1e-15);
        }
        g.align_joint_gain = 2.0;
        let (u, _) = control(&q, &f, &goal, &g);
        let want = [0.1, 0.04, 0.0, 0.0, 0.0, -0.08];
        for a in 0..6 {
            assert!((u[2 + a] - want[a]).abs() < 1e-12, "{a}: {}", u[2 + a]);
        }
        assert_eq!(
            (u[0], u[1]),
            (eq18c[0], eq18c[1]),
            "the platform's turn is unchanged"
        );
        // The rates keep their ratios under the limit.
        g.max_joint_rate = 0.05;
        let (u, _) = control(&q, &f, &goal, &g);
        assert!((u[2] - 0.05).abs() < 1e-12 && (u[7] + 0.04).abs() < 1e-12);
        // Away from the goal (not aligning) Eq. 18c again.
        let mut far = q;
        far[0] = -1.0;
        let (u, b) = control(&far, &f, &goal, &g);
        assert_ne!(b[0], Branch::Align);
        let (e, _) = control(&far, &f, &goal, &gains());
        assert_eq!(&u[2..], &e[2..]);
    }
}
