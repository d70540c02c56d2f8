//! The point-world transformations of seed 004 §III-A, as printed, for one
//! workspace copy W^p: H0 (an ellipsoid to a unit sphere), T_R (the unit
//! sphere to the point h_p), the analytic switches (Eqs. 6 and 8), H1 (Eq. 7)
//! and H2 (Eq. 9), acting on workspace points.
//!
//! The potential ([`crate::robots::mobile_manipulator::dilf::potential`]) does not map workspace points: it needs
//! where the *part's own point* h_p lands in the final point world. H1 sends
//! the whole boundary of the part to h_p, so the obstacle function seen at
//! h_p is the limit of b_O ∘ H1⁻¹ there, which depends on the direction of
//! approach (Remark 1); [`crate::robots::mobile_manipulator::dilf::contact`] takes its least value (the only
//! choice that vanishes exactly at contact) and the tests below check that
//! this is what sampling H1 near the part's boundary converges to.

use crate::model::spatial::{self, Scalar};
use crate::robots::mobile_manipulator::ellipsoid::PlacedEllipsoid;

/// Sign-preserving power s·|s|^n (so H0 works for any real n).
fn spow(s: f64, n: f64) -> f64 {
    s.signum() * s.abs().powf(n)
}

/// H0 of one ellipsoid (the map before T_R): each normalised local
/// coordinate u_k is raised to the n-th power, so ‖H0(x) − h_j‖² = b(x) + 1
/// and the ellipsoid's boundary goes to the unit sphere about its centre h_j.
pub fn h0(e: &PlacedEllipsoid<f64>, x: [f64; 3]) -> [f64; 3] {
    let u = e.local(x);
    let w = [spow(u[0], e.n), spow(u[1], e.n), spow(u[2], e.n)];
    spatial::add(e.center, spatial::mul_mv(&e.rot, w))
}

/// T_R (after Eq. 6's definitions): the unit sphere about h_j to the point
/// h_p, T = (b/(b+1))^{1/2} (h0 − h_j) + h_p.
pub fn t_robot(e: &PlacedEllipsoid<f64>, x: [f64; 3], hp: [f64; 3]) -> [f64; 3] {
    let b = e.value(x);
    let s = (b / (b + 1.0)).max(0.0).sqrt();
    spatial::add(spatial::scale(spatial::sub(h0(e, x), e.center), s), hp)
}

/// Analytic switches σ_j = ‖h‖ Π_{i≠j} b_i / (‖h‖ Π_{i≠j} b_i + λ b_j)
/// (Eqs. 6 and 8 have this form, with h = h_p resp. h1^p).
pub(crate) fn switches(h_norm: f64, b: &[f64], lambda: f64) -> Vec<f64> {
    (0..b.len())
        .map(|j| {
            let others: f64 = b
                .iter()
                .enumerate()
                .filter(|(i, _)| *i != j)
                .map(|(_, v)| v)
                .product();
            let num = h_norm * others;
            if num == 0.0 && b[j] == 0.0 {
                // On the boundary of two bodies at once: no single limit.
                f64::NAN
            } else {
                num / (num + lambda * b[j])
            }
        })
        .collect()
}

/// H1 (Eq. 7) for a body made of the ellipsoids `parts`, reduced to `hp`:
/// h1 = h0 (1 − Σσ) + Σ σ_j T_j. With several ellipsoids the printed h0 is
/// ambiguous (each has its own H0); we use each ellipsoid's own h0 in its
/// own term, h1 = x (1 − Σσ) + Σ σ_j T_j, which is the printed form for one.
pub fn h1(parts: &[PlacedEllipsoid<f64>], x: [f64; 3], hp: [f64; 3], lambda: f64) -> [f64; 3] {
    let b: Vec<f64> = parts.iter().map(|e| e.value(x)).collect();
    let sigma = switches(spatial::norm(hp), &b, lambda);
    let base = if parts.len() == 1 {
        h0(&parts[0], x)
    } else {
        x
    };
    let total: f64 = sigma.iter().sum();
    let mut out = spatial::scale(base, 1.0 - total);
    for (e, s) in parts.iter().zip(&sigma) {
        out = spatial::add(out, spatial::scale(t_robot(e, x, hp), *s));
    }
    out
}

/// T_O: the deformed obstacle i to its point h_Oi,
/// T = (b/(b+1))^{1/2} (h1 − h_O) + h_O.
pub(crate) fn t_obstacle(b: f64, h1: [f64; 3], h_o: [f64; 3]) -> [f64; 3] {
    let s = (b / (b + 1.0)).max(0.0).sqrt();
    spatial::add(spatial::scale(spatial::sub(h1, h_o), s), h_o)
}

/// H2 (Eq. 9): h2 = h1 (1 − Σσ) + Σ σ_i T_Oi, with the obstacle functions `b`
/// evaluated for the point (the deformed obstacles' functions at h1) and the
/// obstacle points `h_o`.
pub fn h2(h1: [f64; 3], b: &[f64], h_o: &[[f64; 3]], lambda: f64) -> [f64; 3] {
    let sigma = switches(spatial::norm(h1), b, lambda);
    let total: f64 = sigma.iter().sum();
    let mut out = spatial::scale(h1, 1.0 - total);
    for ((bi, o), s) in b.iter().zip(h_o).zip(&sigma) {
        out = spatial::add(out, spatial::scale(t_obstacle(*bi, h1, *o), *s));
    }
    out
}

/// The same switches computed in logarithms, for many obstacles and
/// bounded obstacle functions b̃ ∈ (0, 1): σ_j = 1 / (1 + exp(r_j)) with
/// r_j = ln λ + ln b̃_j − ln‖h‖ − Σ_{i≠j} ln b̃_i (no overflow, no 0/0).
pub fn switches_log<T: Scalar>(ln_h: T, ln_b: &[T], ln_lambda: f64) -> Vec<T> {
    let total: T = ln_b.iter().copied().sum();
    ln_b.iter()
        .map(|&lb| switch_log(switch_exponent(ln_h, lb, total, ln_lambda)))
        .collect()
}

/// r_j of [`switches_log`] from ln b̃_j and `total` = Σ_i ln b̃_i.
#[inline]
pub(crate) fn switch_exponent<T: Scalar>(ln_h: T, lb: T, total: T, ln_lambda: f64) -> T {
    lb + lb - total - ln_h + ln_lambda
}

/// σ = 1 / (1 + exp(r)), written to stay finite for large |r|.
#[inline]
pub(crate) fn switch_log<T: Scalar>(r: T) -> T {
    if r.re() > 0.0 {
        let e = (-r).exp();
        e / (e + 1.0)
    } else {
        (r.exp() + 1.0).recip()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robots::mobile_manipulator::dilf::contact;
    use crate::robots::mobile_manipulator::ellipsoid::Superellipsoid;

    fn part() -> PlacedEllipsoid<f64> {
        Superellipsoid {
            center: [0.3, -0.2, 0.5],
            semi_axes: [0.4, 0.15, 0.25],
            exponent: 1.0,
            rpy: [0.2, 0.5, -0.4],
        }
        .at_rest()
    }

    fn surface_point(e: &PlacedEllipsoid<f64>, th: f64, ph: f64) -> [f64; 3] {
        e.to_world([
            e.semi[0] * th.sin() * ph.cos(),
            e.semi[1] * th.sin() * ph.sin(),
            e.semi[2] * th.cos(),
        ])
    }

    #[test]
    fn h0_sends_the_boundary_to_the_unit_sphere() {
        for n in [1.0, 2.0, 4.5] {
            let mut e = part();
            e.n = n;
            let r = e.radial_projection([2.0, 1.0, -0.5]);
            let h = h0(&e, r);
            assert!((spatial::norm(spatial::sub(h, e.center)) - 1.0).abs() < 1e-12);
            // ‖h0 − h_j‖² = b + 1 everywhere.
            let x = [1.3, -0.7, 0.2];
            let d = spatial::norm(spatial::sub(h0(&e, x), e.center));
            assert!((d * d - e.value(x) - 1.0).abs() < 1e-12 * (1.0 + e.value(x)));
        }
    }

    #[test]
    fn h1_collapses_the_part_boundary_to_hp() {
        let e = part();
        let hp = [1.0, 2.0, 0.5];
        for (th, ph) in [(0.3, 0.1), (1.2, 2.5), (2.9, -1.0)] {
            let x = surface_point(&e, th, ph);
            let h = h1(&[e], x, hp, 0.7);
            assert!(spatial::norm(spatial::sub(h, hp)) < 1e-7, "{h:?}");
        }
        // Two ellipsoids: a point on one boundary (outside the other) goes to hp too.
        let mut other = part();
        other.center = [2.0, 0.0, 0.5];
        let x = surface_point(&e, 1.1, 3.0);
        let h = h1(&[e, other], x, hp, 0.7);
        assert!(spatial::norm(spatial::sub(h, hp)) < 1e-7, "{h:?}");
    }

    #[test]
    fn switches_vanish_at_the_origin_and_switch_on_at_a_boundary() {
        let s = switches(0.0, &[0.5, 2.0, 0.1], 1.0);
        assert!(s.iter().all(|v| *v == 0.0));
        let s = switches(1.5, &[0.0, 2.0, 0.1], 1.0);
        assert_eq!(s[0], 1.0);
        assert_eq!((s[1], s[2]), (0.0, 0.0));
        // The log form agrees with the direct one.
        let b = [0.3f64, 0.8, 0.05];
        let lb: Vec<f64> = b.iter().map(|v| v.ln()).collect();
        let direct = switches(0.9, &b, 2.0);
        let logs = switches_log(0.9f64.ln(), &lb, 2.0f64.ln());
        for (a, c) in direct.iter().zip(&logs) {
            assert!((a - c).abs() < 1e-14);
        }
        // At the goal (‖h‖ = 0) H1 is H0 and H2 the identity.
        let e = part();
        let x = [1.0, 1.0, 1.0];
        assert_eq!(h1(&[e], x, [0.0; 3], 1.0), h0(&e, x));
        assert_eq!(
            h2([0.0; 3], &[0.4, 0.2], &[[1.0; 3], [2.0; 3]], 1.0),
            [0.0; 3]
        );
    }

    #[test]
    fn h2_collapses_an_obstacle_boundary_to_its_point() {
        let h_o = [[3.0, 0.0, 0.0], [-2.0, 1.0, 0.0]];
        let h = h2([2.5, 0.4, 0.1], &[0.0, 1.5], &h_o, 0.8);
        assert!(spatial::norm(spatial::sub(h, h_o[0])) < 1e-12);
    }

    /// β (the least limit of the deformed obstacle function at h_p) is what
    /// the obstacle function takes at preimages of points approaching h_p:
    /// points just outside the part map next to h_p under H1, and the least
    /// b_O among them tends to β.
    #[test]
    fn beta_is_the_limit_of_the_deformed_obstacle_function_at_hp() {
        let e = part();
        let obst = Superellipsoid {
            center: [1.6, 0.4, 0.3],
            semi_axes: [0.5, 0.7, 0.3],
            exponent: 3.0,
            rpy: [0.0, 0.3, 0.9],
        }
        .at_rest();
        let beta = contact::solve(&e, &obst, None).unwrap().value;
        let hp = [0.2, 0.1, 0.0];
        let mut prev_dist = f64::INFINITY;
        for (scale, tol) in [(1.01, 0.5), (1.0001, 5e-3)] {
            let mut least = f64::INFINITY;
            let mut dist: f64 = 0.0;
            for i in 0..=180 {
                for j in 0..360 {
                    let (th, ph) = (i as f64 * 0.0174533, j as f64 * 0.0174533);
                    let s = surface_point(&e, th, ph);
                    let x =
                        spatial::add(e.center, spatial::scale(spatial::sub(s, e.center), scale));
                    let h = h1(&[e], x, hp, 1.0);
                    dist = dist.max(spatial::norm(spatial::sub(h, hp)));
                    least = least.min(obst.value(x));
                }
            }
            assert!(
                (least - beta).abs() < tol * (1.0 + beta.abs()),
                "{least} vs β = {beta}"
            );
            // The sampled points' images close in on h_p.
            assert!(dist < 0.4 * prev_dist.min(1.0), "{dist} after {prev_dist}");
            prev_dist = dist;
        }
    }
}
