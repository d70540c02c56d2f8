//! Spherical-triangle planner for the rolling sphere (seed 003, §4).
//!
//! Steps (all straight rolls, so the plan is built with `plan_from_legs`; inputs are the
//! world-frame (ω_x, ω_y) and a straight roll of ground length ℓ along heading h is
//! ∫ω = (ℓ/a)(−sin h, cos h)):
//! 1. [roll to goal position] roll straight to the goal spot F_g. Skipped when step 2 alone
//!    leaves the ball within d < π radii of F_g (e.g. any upright start that close, such as
//!    §5.2's, which then plans step 3 only).
//! 2. [roll P upright] roll straight so that P (the body z axis) points up; the ball ends at
//!    distance d ≤ aπ from F_g, upright with some yaw β₃.
//! 3. [triangle k: side a / b / c] one spherical-triangle manoeuvre (or two) that rolls back by
//!    (d, φ) and turns the yaw by α = β_f − β₃ ∈ (−π, π]: roll a along heading ψ − 90°, turn by
//!    π − C, roll b, turn by π − A, roll c. Left turns (left-handed) give α = π − (A+B+C) < 0
//!    (Eq. 21a), right turns give α = A+B+C − π > 0 (Eq. 21b); the handedness follows the
//!    sign of α. The displacement is Eq. 17 / Eq. 18.
//! 4. [final (A): tilt to goal] only for a tilted goal (θ_g ≠ 0), as in the geometric planner;
//!    F_g is the spot where the upright ball must stand.
//!
//! Solving the triangle: a, b, C are the unknowns, A, B, c follow by Napier's analogies
//! (Eq. 22). (d, α) are two equations for three unknowns; the paper closes the system by
//! fixing ψ (ψ = 66.31° = φ + 10° in §5.2) and solving Eqs. 17, 18, 21 together: that is the
//! `psi_offset_deg` mode (Newton from a coarse grid of seeds). By default ψ is left free, as
//! §4.2 allows ("ψ is assigned suitably to satisfy Eq. 18"): b = κa (κ = `side_ratio`), C comes
//! in closed form from the area (tan(E/2) = t sin C / (1 + t cos C), t = tan(a/2) tan(b/2),
//! E = |α|), a from a bracketed 1-D root of Eq. 17, and ψ from Eq. 18. It takes tens of µs.
//!
//! One triangle reaches only a band around d ≈ |α| in the (d, |α|) plane (Fig. 8; e.g. never
//! α = 0 with d > 0, nor d = 0 with α ≠ 0). Outside it two triangles are used (§4.3): yaws
//! α₁ = ±ℓ₁ (on the band's diagonal) and α₂ = α − α₁, ground displacements of lengths ℓ₁,
//! α₁ near the band centre for |D₁| = ℓ₁, α₂ = α − α₁, |D₂| = ℓ₂ near the band centre for α₂
//! (clamped so that D₁ + D₂ = D closes); ℓ₁ is scanned and the shortest pair kept. The band
//! is |α| ∈ ≈[0.63 d, 0.66 d + 0.3] for κ = 1 (it is not the diagonal |α| = d).
//!
//! OCR notes: Eq. 18's arctan is only defined modulo π; the code uses atan2 on the local
//! displacement (for §5.2 the principal branch happens to be right: φ − ψ = −10°). Eq. 22
//! is used with atan2 for A + B (which exceeds π when a + b > π). Eq. 30: solving Eqs. 17,
//! 18, 21a with d = 1.8, φ − ψ = −10°, α = −90° gives a, b, c, B as printed (1.862, 1.198,
//! 1.760, 70.78°) but A = 103.83°, C = 95.39° where 103.81°, 95.41° are printed. The printed
//! set is not self-consistent (Napier on the printed a, b, C gives B = 70.76°, area 89.98°);
//! A and C shift by 0.02° for a 0.002° change of ψ − φ, so the paper's solve was looser than
//! its printed digits. The tests assert the solved values.

use crate::model::{Input, State};
use crate::plan::{plan_from_legs, Limits, Plan};
use crate::planner::PlanError;
use crate::robots::rolling_sphere::kinematics::{euler_to_rotation, RollingSphere};
use nalgebra::{Rotation3, Unit, UnitQuaternion, Vector3};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, PI, TAU};

/// Turning sense of a triangle manoeuvre.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Handedness {
    /// Left turns, yaw α = π − (A+B+C) ≤ 0 (Eq. 21a).
    Left,
    /// Right turns, yaw α = A+B+C − π ≥ 0 (Eq. 21b).
    Right,
}

impl Handedness {
    /// +1 for left (counter-clockwise heading changes), −1 for right.
    pub fn sign(self) -> f64 {
        match self {
            Handedness::Left => 1.0,
            Handedness::Right => -1.0,
        }
    }
}

/// Seed 003 §4 spherical-triangle planner: closed paths whose spherical
/// triangles' area turns the sphere.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SphereTriangleParams {
    /// b / a of the free-ψ triangle family.
    #[schemars(extend("exclusiveMinimum" = 0.05, "exclusiveMaximum" = 20))]
    pub side_ratio: f64,
    /// Paper mode: ψ = φ + offset (deg) fixed and (a, b, C) solved from Eqs. 17, 18, 21
    /// (single triangle only). `None`: ψ free (default).
    pub psi_offset_deg: Option<f64>,
    /// Grid points of the 1-D root scan over a.
    #[schemars(range(min = 8))]
    pub scan_points: usize,
    /// Iteration cap of the bisection / Newton solves.
    #[schemars(range(min = 1))]
    pub max_iter: usize,
    /// Number of ℓ₁ values tried for the two-triangle split.
    #[schemars(range(min = 2))]
    pub split_candidates: usize,
    /// |d| (radii) and |α| (rad) below which nothing is left to do.
    #[schemars(range(min = 0))]
    pub zero_tol: f64,
}

impl Default for SphereTriangleParams {
    fn default() -> Self {
        Self {
            side_ratio: 1.0,
            psi_offset_deg: None,
            scan_points: 96,
            max_iter: 200,
            split_candidates: 24,
            zero_tol: 1e-12,
        }
    }
}

/// A solved triangle manoeuvre (sides in radians of the unit sphere, i.e. rolled angle).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct SphericalTriangle {
    /// Side MN, rolled first.
    pub a: f64,
    /// Side NL, rolled second.
    pub b: f64,
    /// Side LM, rolled last.
    pub c: f64,
    /// Angle at L (opposite a).
    #[serde(rename = "A")]
    pub big_a: f64,
    /// Angle at M (opposite b).
    #[serde(rename = "B")]
    pub big_b: f64,
    /// Angle at N (opposite c), between the a and b legs.
    #[serde(rename = "C")]
    pub big_c: f64,
    /// Turning sense.
    pub handed: Handedness,
    /// Initial rolling direction, from the −y axis counter-clockwise (Fig. 6).
    pub psi: f64,
    /// Ground displacement length (radii), Eq. 17.
    pub d: f64,
    /// Ground displacement direction from +x, Eq. 18.
    pub phi: f64,
    /// Net yaw (rad), Eq. 21.
    pub yaw: f64,
}

impl SphericalTriangle {
    /// Ground headings (from +x) and side lengths of the three legs.
    pub fn legs(&self) -> [(f64, f64); 3] {
        let s = self.handed.sign();
        let h0 = self.psi - FRAC_PI_2;
        [
            (h0, self.a),
            (h0 + s * (PI - self.big_c), self.b),
            (h0 + s * (TAU - self.big_a - self.big_c), self.c),
        ]
    }
}

/// Napier's analogies (Eq. 22): from two sides a, b and the included angle C, the angles
/// A, B and the third side c. Valid for 0 < a, b < π, 0 < C < π.
///
/// A ± B come from the first two analogies (atan2 for A + B, which exceeds π when
/// a + b > π). The third analogy for c is 0/0 at a + b = π (tan((a+b)/2) cos((A+B)/2)), so c
/// is taken from the equivalent, everywhere well-conditioned atan2 form of the cosine rule;
/// [`napier_c`] keeps Eq. 22's form for cross-checks.
pub(crate) fn napier(a: f64, b: f64, big_c: f64) -> (f64, f64, f64) {
    let (hs, hd) = (0.5 * (a + b), 0.5 * (a - b));
    let tc = (0.5 * big_c).tan();
    let a_minus_b = 2.0 * (hd.sin() / (hs.sin() * tc)).atan();
    let a_plus_b = 2.0 * hd.cos().atan2(hs.cos() * tc);
    let big_a = 0.5 * (a_plus_b + a_minus_b);
    let big_b = 0.5 * (a_plus_b - a_minus_b);
    let (sa, ca) = a.sin_cos();
    let (sb, cb) = b.sin_cos();
    let (sc, cc) = big_c.sin_cos();
    let y = (sa * cb - ca * sb * cc).hypot(sb * sc);
    let c = y.atan2(ca * cb + sa * sb * cc);
    (big_a, big_b, c)
}

/// Eq. 22's third analogy: tan(c/2) = tan((a+b)/2) cos((A+B)/2) / cos((A−B)/2).
pub fn napier_c(a: f64, b: f64, big_a: f64, big_b: f64) -> f64 {
    2.0 * ((0.5 * (a + b)).tan() * (0.5 * (big_a + big_b)).cos() / (0.5 * (big_a - big_b)).cos())
        .atan()
}

/// Eq. 17: ground displacement length of the manoeuvre.
pub(crate) fn eq17_d(a: f64, b: f64, c: f64, big_a: f64, big_c: f64) -> f64 {
    (a * a + b * b + c * c + 2.0 * a * c * (big_a + big_c).cos()
        - 2.0 * a * b * big_c.cos()
        - 2.0 * b * c * big_a.cos())
    .max(0.0)
    .sqrt()
}

/// Ground displacement (radii) with the first leg along +x.
fn local_displacement(a: f64, b: f64, c: f64, big_a: f64, big_c: f64, s: f64) -> (f64, f64) {
    let h1 = s * (PI - big_c);
    let h2 = s * (TAU - big_a - big_c);
    (a + b * h1.cos() + c * h2.cos(), b * h1.sin() + c * h2.sin())
}

fn wrap(a: f64) -> f64 {
    let x = (a + PI).rem_euclid(TAU) - PI;
    if x <= -PI {
        x + TAU
    } else {
        x
    }
}

/// The full triangle from (a, b, C), handedness and ψ.
fn make_triangle(a: f64, b: f64, big_c: f64, handed: Handedness, psi: f64) -> SphericalTriangle {
    let (big_a, big_b, c) = napier(a, b, big_c);
    let s = handed.sign();
    let (x, y) = local_displacement(a, b, c, big_a, big_c, s);
    let e = big_a + big_b + big_c - PI;
    SphericalTriangle {
        a,
        b,
        c,
        big_a,
        big_b,
        big_c,
        handed,
        psi,
        d: x.hypot(y),
        phi: wrap(psi - FRAC_PI_2 + y.atan2(x)),
        yaw: -s * e,
    }
}

/// Free-ψ solve: b = κa, C from the area in closed form, a from Eq. 17 = d. Shortest
/// perimeter among roots. `e` = |α| > 0, `d` > 0 (radii).
fn solve_family(
    d: f64,
    e: f64,
    phi: f64,
    handed: Handedness,
    p: &SphereTriangleParams,
) -> Option<SphericalTriangle> {
    let k = p.side_ratio;
    let a_max = PI.min(PI / k);
    // C of branch j for side a, when the triangle exists, with Napier's (A, c).
    let c_of = |a: f64, j: usize| -> Option<(f64, f64, f64)> {
        let b = k * a;
        let t = (0.5 * a).tan() * (0.5 * b).tan();
        let s = (0.5 * e).sin() / t;
        if s.is_nan() || s > 1.0 || a <= 0.0 || a >= a_max {
            return None;
        }
        let c = if j == 0 {
            0.5 * e + s.asin()
        } else {
            0.5 * e + PI - s.asin()
        };
        if !(c > 0.0 && c < PI) {
            return None;
        }
        let (ba, bb, cc) = napier(a, b, c);
        ((ba + bb + c - PI - e).abs() < 1e-9).then_some((c, ba, cc))
    };
    let f = |a: f64, j: usize| -> Option<f64> {
        let (c, ba, cc) = c_of(a, j)?;
        Some(eq17_d(a, k * a, cc, ba, c) - d)
    };
    let n = p.scan_points;
    let mut best: Option<(f64, f64, f64, f64)> = None; // perimeter, a, b, C
    for j in 0..2 {
        let mut prev: Option<(f64, f64)> = None;
        for i in 1..n {
            let a = a_max * i as f64 / n as f64;
            let cur = f(a, j).map(|v| (a, v));
            if let (Some((a0, f0)), Some((a1, f1))) = (prev, cur) {
                if f0 == 0.0 || f0.signum() != f1.signum() {
                    let (mut lo, mut hi, mut flo) = (a0, a1, f0);
                    let mut ok = true;
                    for _ in 0..p.max_iter {
                        let mid = 0.5 * (lo + hi);
                        if mid <= lo || mid >= hi || flo == 0.0 {
                            break;
                        }
                        match f(mid, j) {
                            Some(fm) if fm.signum() == flo.signum() => {
                                lo = mid;
                                flo = fm;
                            }
                            Some(_) => hi = mid,
                            None => {
                                ok = false;
                                break;
                            }
                        }
                    }
                    let a = if flo == 0.0 { lo } else { 0.5 * (lo + hi) };
                    // A sign change across a jump of the branch is not a root.
                    let ok = ok && f(a, j).is_some_and(|v| v.abs() < 1e-10);
                    if let (true, Some((c, _, cc))) = (ok, c_of(a, j)) {
                        let b = k * a;
                        let per = a + b + cc;
                        if best.is_none_or(|bst| per < bst.0) {
                            best = Some((per, a, b, c));
                        }
                    }
                }
            }
            prev = cur;
        }
    }
    let (_, a, b, c) = best?;
    let t0 = make_triangle(a, b, c, handed, 0.0);
    // Rotate the whole manoeuvre so that its displacement points along φ (Eq. 18 for ψ).
    let tri = make_triangle(a, b, c, handed, wrap(phi - t0.phi));
    check_triangle(&tri, d, phi, -handed.sign() * e)
}

/// Accept a solved triangle only if it meets (d, φ, yaw) to 1e-10.
fn check_triangle(t: &SphericalTriangle, d: f64, phi: f64, yaw: f64) -> Option<SphericalTriangle> {
    let ok = (t.d - d).abs() < 1e-10
        && (d < 1e-9 || wrap(t.phi - phi).abs() * d < 1e-10)
        && (t.yaw - yaw).abs() < 1e-10
        && [t.a, t.b, t.c, t.big_a, t.big_b, t.big_c]
            .iter()
            .all(|v| *v > 0.0 && *v < PI);
    ok.then_some(*t)
}

/// Paper mode: ψ fixed, (a, b, C) from Eqs. 17, 18, 21 by Newton (numerical Jacobian) from
/// the best seeds of a 7³ grid. Returns the shortest converged triangle.
pub(crate) fn solve_fixed_psi(
    d: f64,
    phi: f64,
    yaw: f64,
    psi: f64,
    p: &SphereTriangleParams,
) -> Option<SphericalTriangle> {
    let handed = if yaw < 0.0 {
        Handedness::Left
    } else {
        Handedness::Right
    };
    let res = |x: &[f64; 3]| -> [f64; 3] {
        let t = make_triangle(x[0], x[1], x[2], handed, psi);
        [t.d - d, t.yaw - yaw, wrap(t.phi - phi)]
    };
    let norm = |r: &[f64; 3]| r.iter().map(|v| v * v).sum::<f64>().sqrt();
    let inside = |x: &[f64; 3]| x.iter().all(|v| *v > 1e-6 && *v < PI - 1e-6);
    let g = 7;
    let mut seeds: Vec<(f64, [f64; 3])> = Vec::new();
    for i in 1..=g {
        for j in 1..=g {
            for k in 1..=g {
                let x = [
                    PI * i as f64 / (g + 1) as f64,
                    PI * j as f64 / (g + 1) as f64,
                    PI * k as f64 / (g + 1) as f64,
                ];
                seeds.push((norm(&res(&x)), x));
            }
        }
    }
    seeds.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best: Option<SphericalTriangle> = None;
    for (_, mut x) in seeds.into_iter().take(12) {
        let mut r = res(&x);
        for _ in 0..p.max_iter {
            if norm(&r) < 1e-13 {
                break;
            }
            let mut jac = nalgebra::Matrix3::zeros();
            for c in 0..3 {
                let h = 1e-7;
                let (mut xp, mut xm) = (x, x);
                xp[c] += h;
                xm[c] -= h;
                let (rp, rm) = (res(&xp), res(&xm));
                for rr in 0..3 {
                    jac[(rr, c)] = (rp[rr] - rm[rr]) / (2.0 * h);
                }
            }
            let Some(step) = jac.lu().solve(&nalgebra::Vector3::new(r[0], r[1], r[2])) else {
                break;
            };
            // Damped step staying inside the domain.
            let mut lam = 1.0;
            let n0 = norm(&r);
            loop {
                let xn = [
                    x[0] - lam * step[0],
                    x[1] - lam * step[1],
                    x[2] - lam * step[2],
                ];
                if inside(&xn) {
                    let rn = res(&xn);
                    if norm(&rn) < n0 || lam < 1e-3 {
                        x = xn;
                        r = rn;
                        break;
                    }
                }
                lam *= 0.5;
                if lam < 1e-4 {
                    break;
                }
            }
            if lam < 1e-4 {
                break;
            }
        }
        if let Some(t) = check_triangle(&make_triangle(x[0], x[1], x[2], handed, psi), d, phi, yaw)
        {
            if best.is_none_or(|b| t.a + t.b + t.c < b.a + b.b + b.c) {
                best = Some(t);
            }
        }
    }
    best
}

/// Centre of the one-triangle band (isosceles family, κ = 1): the yaw best reached with a
/// displacement ℓ. Empirical fit of Fig. 8's band, |α| ∈ ≈[0.63ℓ, 0.66ℓ + 0.3]; only used to
/// seed the two-triangle split, every candidate is solved and checked exactly.
fn band_yaw(l: f64) -> f64 {
    (l + 0.15) / 1.5
}

/// Inverse of [`band_yaw`]: the displacement best paired with yaw `y`.
fn band_length(y: f64) -> f64 {
    (1.5 * y.abs() - 0.15).max(1.2 * y.abs())
}

/// One triangle reaching displacement (d, φ) (radii) and yaw `yaw` ∈ [−π, π], ψ free.
pub(crate) fn solve_single(
    d: f64,
    phi: f64,
    yaw: f64,
    p: &SphereTriangleParams,
) -> Option<SphericalTriangle> {
    if d <= p.zero_tol || yaw.abs() <= p.zero_tol || yaw.abs() > PI {
        return None; // outside the one-triangle band (Fig. 8)
    }
    let handed = if yaw < 0.0 {
        Handedness::Left
    } else {
        Handedness::Right
    };
    solve_family(d, yaw.abs(), phi, handed, p)
}

/// One or two triangles reaching (d, φ, yaw); empty when nothing is to be done.
pub fn solve_triangles(
    d: f64,
    phi: f64,
    yaw: f64,
    p: &SphereTriangleParams,
) -> Result<Vec<SphericalTriangle>, PlanError> {
    if d <= p.zero_tol && yaw.abs() <= p.zero_tol {
        return Ok(vec![]);
    }
    if let Some(off) = p.psi_offset_deg {
        return solve_fixed_psi(d, phi, yaw, phi + off.to_radians(), p)
            .map(|t| vec![t])
            .ok_or_else(|| {
                PlanError::Unreachable(format!(
                    "no single spherical triangle with ψ = φ + {}° reaches d = {}, α = {}°; \
                 unset psi_offset_deg to let ψ (and a second triangle) be chosen",
                    crate::numfmt::readable(off),
                    crate::numfmt::with_digits(d, 7),
                    crate::numfmt::with_digits(yaw.to_degrees(), 5)
                ))
            });
    }
    if let Some(t) = solve_single(d, phi, yaw, p) {
        return Ok(vec![t]);
    }
    // Two triangles (§4.3).
    let (dx, dy) = (d * phi.cos(), d * phi.sin());
    let mut best: Option<(f64, SphericalTriangle, SphericalTriangle)> = None;
    let n = p.split_candidates;
    for i in 1..=n {
        let l1 = PI * i as f64 / (n + 1) as f64;
        for (sgn, shift) in [1.0, -1.0]
            .into_iter()
            .flat_map(|s| [0.0, -0.15, 0.15].map(|x| (s, x)))
        {
            let y1 = sgn * (band_yaw(l1) + shift);
            let y2 = yaw - y1;
            if y1.abs() <= p.zero_tol || y2.abs() > PI - 1e-9 || y2.abs() <= p.zero_tol {
                continue;
            }
            let l2 = band_length(y2).clamp((d - l1).abs(), d + l1);
            if l2 >= PI {
                continue;
            }
            // Direction of D1 so that |D − D1| = ℓ2.
            let g1 = if d > p.zero_tol {
                ((l1 * l1 + d * d - l2 * l2) / (2.0 * l1 * d))
                    .clamp(-1.0, 1.0)
                    .acos()
            } else {
                0.0
            };
            let phi1 = phi + g1;
            let (x1, y1v) = (l1 * phi1.cos(), l1 * phi1.sin());
            let (x2, y2v) = (dx - x1, dy - y1v);
            // Lazily: most candidates already fail on the first triangle.
            let Some(t1) = solve_single(l1, phi1, y1, p) else {
                continue;
            };
            let Some(t2) = solve_single(x2.hypot(y2v), y2v.atan2(x2), y2, p) else {
                continue;
            };
            let cost = t1.a + t1.b + t1.c + t2.a + t2.b + t2.c;
            if best.as_ref().is_none_or(|b| cost < b.0) {
                best = Some((cost, t1, t2));
            }
        }
    }
    best.map(|(_, t1, t2)| vec![t1, t2]).ok_or_else(|| {
        PlanError::Unreachable(format!(
            "no one- or two-triangle manoeuvre found for d = {d:.6}, α = {:.4}° (side_ratio {}); \
             try side_ratio = 1 or more split_candidates",
            yaw.to_degrees(),
            p.side_ratio
        ))
    })
}

/// The contact point's path on the ball (unit vectors in the body frame) while rolling
/// `legs` (ground heading, rolled angle) from body orientation `r0`. `samples` points per
/// leg plus the start. For a triangle manoeuvre the path is the closed spherical triangle.
pub(crate) fn ball_trace(
    r0: &UnitQuaternion<f64>,
    legs: &[(f64, f64)],
    samples: usize,
) -> Vec<[f64; 3]> {
    let mut r = *r0;
    let down = Vector3::new(0.0, 0.0, -1.0);
    let body = |r: &UnitQuaternion<f64>| {
        let v = r.inverse_transform_vector(&down);
        [v.x, v.y, v.z]
    };
    let mut out = vec![body(&r)];
    for &(h, len) in legs {
        let axis = Unit::new_normalize(Vector3::new(-h.sin(), h.cos(), 0.0));
        for k in 1..=samples.max(1) {
            let rk =
                UnitQuaternion::from_axis_angle(&axis, len * k as f64 / samples.max(1) as f64) * r;
            out.push(body(&rk));
        }
        r = UnitQuaternion::from_axis_angle(&axis, len) * r;
    }
    out
}

/// For visualisation: the spherical triangles traced on the ball (body frame, unit sphere)
/// by the plan `start` → `goal`, one closed polyline per triangle.
pub(crate) fn triangle_traces(
    model: &RollingSphere,
    start: &State,
    goal: &State,
    params: &SphereTriangleParams,
    samples_per_leg: usize,
) -> Result<Vec<Vec<[f64; 3]>>, PlanError> {
    let sol = solve(model, start, goal, params)?;
    let mut r = UnitQuaternion::from_rotation_matrix(&Rotation3::from_axis_angle(
        &Vector3::z_axis(),
        sol.beta3,
    ));
    let mut out = Vec::new();
    for t in &sol.triangles {
        out.push(ball_trace(&r, &t.legs(), samples_per_leg));
        r = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), t.yaw) * r;
    }
    Ok(out)
}

/// Everything the planner decided (metres, radians).
#[derive(Debug, Clone, Serialize)]
pub struct TriangleSolution {
    /// Spot where the upright ball must stand (the goal itself when θ_g = 0).
    pub f_goal: [f64; 2],
    /// Required final yaw α_g + φ_g.
    pub beta_f: f64,
    /// ∫ω of step 1 (roll to F_g).
    pub roll1: [f64; 2],
    /// ∫ω of step 2 (bring P upright); its norm is the tilt of P at F_g.
    pub roll2: [f64; 2],
    /// Centre after step 2.
    pub q3: [f64; 2],
    /// Yaw after step 2.
    pub beta3: f64,
    /// Displacement still to go, in radii (d of Eq. 29).
    pub d: f64,
    /// Its direction (φ of Eq. 29).
    pub phi: f64,
    /// Yaw still to go (α of Eq. 29).
    pub alpha: f64,
    /// The triangle manoeuvres (0, 1 or 2).
    pub triangles: Vec<SphericalTriangle>,
}

/// Solves steps 1-3 for `start` → `goal` (Euler-chart states of `model`).
pub fn solve(
    model: &RollingSphere,
    start: &State,
    goal: &State,
    p: &SphereTriangleParams,
) -> Result<TriangleSolution, PlanError> {
    validate(model, start, goal, p)?;
    let a = model.a;
    let (xg, yg, alg, thg, phg) = (goal[0], goal[1], goal[2], goal[3], goal[4]);
    let f_goal = [xg - a * thg * alg.cos(), yg - a * thg * alg.sin()];
    let beta_f = alg + phg;
    let r0 = UnitQuaternion::from_rotation_matrix(&euler_to_rotation(start[2], start[3], start[4]));
    let rot = |w: [f64; 2]| {
        let v = Vector3::new(w[0], w[1], 0.0);
        UnitQuaternion::from_scaled_axis(v)
    };
    // Step 1 is skipped when bringing P upright from the start already leaves the ball within
    // reach of the triangles (d < π radii): then an upright start plans step 3 alone, as §5.2
    // simulates it ("the first two steps are trivial").
    let skip1 = {
        let pz = r0 * Vector3::z();
        let cross = pz.cross(&Vector3::z());
        let ang = cross.norm().atan2(pz.z);
        let axis = if cross.norm() > 1e-15 {
            cross / cross.norm()
        } else {
            Vector3::x()
        };
        let q = [start[0] + a * axis.y * ang, start[1] - a * axis.x * ang];
        (f_goal[0] - q[0]).hypot(f_goal[1] - q[1]) / a < PI * (1.0 - 1e-9)
    };
    // Step 1: ∫ω = (−Δy, Δx)/a.
    let (roll1, p1) = if skip1 {
        ([0.0, 0.0], [start[0], start[1]])
    } else {
        (
            [-(f_goal[1] - start[1]) / a, (f_goal[0] - start[0]) / a],
            f_goal,
        )
    };
    let r1 = rot(roll1) * r0;
    // Step 2: rotate P = R k onto k about the horizontal axis P × k.
    let pz = r1 * Vector3::z();
    let cross = pz.cross(&Vector3::z());
    let ang = cross.norm().atan2(pz.z);
    let axis = if cross.norm() > 1e-15 {
        cross / cross.norm()
    } else {
        Vector3::x()
    };
    let roll2 = if ang > 0.0 {
        [axis.x * ang, axis.y * ang]
    } else {
        [0.0, 0.0]
    };
    let r3 = rot(roll2) * r1;
    let q3 = [p1[0] + a * roll2[1], p1[1] - a * roll2[0]];
    let m = r3.to_rotation_matrix();
    let beta3 = m[(1, 0)].atan2(m[(0, 0)]);
    let (dx, dy) = ((f_goal[0] - q3[0]) / a, (f_goal[1] - q3[1]) / a);
    let d = dx.hypot(dy);
    let phi = dy.atan2(dx);
    let alpha = wrap(beta_f - beta3);
    let triangles = solve_triangles(d, phi, alpha, p)?;
    Ok(TriangleSolution {
        f_goal,
        beta_f,
        roll1,
        roll2,
        q3,
        beta3,
        d,
        phi,
        alpha,
        triangles,
    })
}

use crate::planner::check_param as check;

fn validate(
    model: &RollingSphere,
    start: &State,
    goal: &State,
    p: &SphereTriangleParams,
) -> Result<(), PlanError> {
    crate::robots::rolling_sphere::geometric::validate_task(model, start, goal)?;
    check(
        "side_ratio",
        p.side_ratio.is_finite() && p.side_ratio > 0.05 && p.side_ratio < 20.0,
        "must lie in (0.05, 20)",
    )?;
    check(
        "psi_offset_deg",
        p.psi_offset_deg.is_none_or(|v| v.is_finite()),
        "must be a finite angle",
    )?;
    check("scan_points", p.scan_points >= 8, "must be at least 8")?;
    check("max_iter", p.max_iter >= 1, "must be at least 1")?;
    check(
        "split_candidates",
        p.split_candidates >= 2,
        "must be at least 2",
    )?;
    check(
        "zero_tol",
        p.zero_tol.is_finite() && p.zero_tol >= 0.0,
        "must be a non-negative number",
    )
}

/// Labels of the plan's segments.
pub const LABELS: [&str; 9] = [
    "roll to goal position",
    "roll P upright",
    "triangle 1: side a",
    "triangle 1: side b",
    "triangle 1: side c",
    "triangle 2: side a",
    "triangle 2: side b",
    "triangle 2: side c",
    "final (A): tilt to goal",
];

/// Plans `start` → `goal` (Euler-chart states (x, y, α, θ, φ) of `model`); only α_g + φ_g
/// matters when θ_g = 0. `limits.max_rate` bounds |ω_x|, |ω_y| (rad/s).
pub fn plan(
    model: &RollingSphere,
    start: &State,
    goal: &State,
    params: &SphereTriangleParams,
    limits: &Limits,
) -> Result<Plan, PlanError> {
    check(
        "limits.max_rate",
        limits.max_rate.len() == 2 && limits.max_rate.iter().all(|m| *m > 0.0 && m.is_finite()),
        "need two positive rates (omega_x, omega_y)",
    )?;
    let sol = solve(model, start, goal, params)?;
    let iv = |w: [f64; 2]| Input::from_vec(vec![w[0], w[1]]);
    let mut legs = vec![(0, iv(sol.roll1)), (1, iv(sol.roll2))];
    for (k, t) in sol.triangles.iter().enumerate() {
        for (j, (h, len)) in t.legs().into_iter().enumerate() {
            legs.push((2 + 3 * k + j, iv([-len * h.sin(), len * h.cos()])));
        }
    }
    legs.push((8, iv([-goal[3] * goal[2].sin(), goal[3] * goal[2].cos()])));
    let tri_json: Vec<_> = sol
        .triangles
        .iter()
        .map(|t| {
            serde_json::json!({
                "a": t.a, "b": t.b, "c": t.c,
                "A_deg": t.big_a.to_degrees(), "B_deg": t.big_b.to_degrees(), "C_deg": t.big_c.to_degrees(),
                "handed": t.handed, "psi_deg": t.psi.to_degrees(),
                "d": t.d, "phi_deg": t.phi.to_degrees(), "yaw_deg": t.yaw.to_degrees(),
            })
        })
        .collect();
    let details = serde_json::json!({
        "planner": "sphere_triangle",
        "tilt_of_P_at_goal_deg": (sol.roll2[0].hypot(sol.roll2[1])).to_degrees(),
        "d": sol.d,
        "phi_deg": sol.phi.to_degrees(),
        "alpha_deg": sol.alpha.to_degrees(),
        "triangles": tri_json,
    });
    Ok(plan_from_legs(
        LABELS.iter().map(|s| s.to_string()).collect(),
        legs,
        limits,
        details,
    ))
}

#[cfg(test)]
mod tests;
