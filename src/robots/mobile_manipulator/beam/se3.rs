//! Exponential coordinates on SE(3), generic over the scalar so that dual
//! numbers carry exact derivatives through them.
//!
//! A twist is ξ = (v, ω) ∈ ℝ⁶ (translational part first). `se3_exp(ξ)` is the
//! pose exp(ξ̂) = (R, p) with R = exp(\[ω\]×) and p = V(ω) v; `se3_log` is its
//! inverse for rotation angles θ = ‖ω‖ ∈ [0, π].
//!
//! Robustness: near the identity the θ-dependent coefficients are evaluated
//! by Taylor series in θ² (or sin²θ), never by dividing by a vanishing sine or
//! taking the square root of zero, so values *and* dual derivatives stay exact
//! at the beam's rest pose. For θ > π/2 the rotation axis is read from the
//! symmetric part of R (R + Rᵀ = 2cI + 2(1 − c) n nᵀ), which stays well
//! conditioned up to θ = π where the antisymmetric part vanishes. At exactly
//! θ = π the sign of the axis is arbitrary (both logs are valid).

use crate::model::spatial::{dot, k, Pose, Scalar, M3, V3};

/// a × b.
#[inline]
fn cross<T: Scalar>(a: V3<T>, b: V3<T>) -> V3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The pose exp(ξ̂) of a twist ξ = (v, ω).
pub fn se3_exp<T: Scalar>(xi: &[T; 6]) -> Pose<T> {
    let v = [xi[0], xi[1], xi[2]];
    let w = [xi[3], xi[4], xi[5]];
    let t2 = dot(w, w);
    // R = I + a W + b W², p = v + b ω×v + c ω×(ω×v).
    let (a, b, c) = if t2.re() < 1e-3 {
        // Series; the first omitted terms are O(θ⁸)/9! ≈ 1e-17 here.
        let t4 = t2 * t2;
        let t6 = t4 * t2;
        (
            k::<T>(1.0) - t2 / 6.0 + t4 / 120.0 - t6 / 5040.0,
            k::<T>(0.5) - t2 / 24.0 + t4 / 720.0 - t6 / 40320.0,
            k::<T>(1.0 / 6.0) - t2 / 120.0 + t4 / 5040.0 - t6 / 362880.0,
        )
    } else {
        let t = t2.sqrt();
        let (s, co) = t.sin_cos();
        (s / t, (k::<T>(1.0) - co) / t2, (t - s) / (t2 * t))
    };
    let hat: M3<T> = [
        [k(0.0), -w[2], w[1]],
        [w[2], k(0.0), -w[0]],
        [-w[1], w[0], k(0.0)],
    ];
    let r: M3<T> = std::array::from_fn(|i| {
        std::array::from_fn(|j| {
            // W² = ω ωᵀ − θ² I.
            let delta = if i == j { 1.0 } else { 0.0 };
            k::<T>(delta) + a * hat[i][j] + b * (w[i] * w[j] - t2 * delta)
        })
    });
    let wv = cross(w, v);
    let wwv = cross(w, wv);
    let p = std::array::from_fn(|i| v[i] + b * wv[i] + c * wwv[i]);
    Pose { r, p }
}

/// The twist ξ = (v, ω) with exp(ξ̂) = g and ‖ω‖ ≤ π.
pub fn se3_log<T: Scalar>(g: &Pose<T>) -> [T; 6] {
    let r = &g.r;
    let c = (r[0][0] + r[1][1] + r[2][2] - 1.0) * 0.5; // cos θ
    let a = [
        (r[2][1] - r[1][2]) * 0.5,
        (r[0][2] - r[2][0]) * 0.5,
        (r[1][0] - r[0][1]) * 0.5,
    ]; // sin θ · n
    let w: V3<T> = if c.re() > 0.0 {
        // θ < π/2: ω = (θ / sin θ) a.
        let s2 = dot(a, a);
        let f = if s2.re() < 1e-3 {
            // asin(s)/s; the first omitted term is 63/2816 s¹⁰ < 3e-17.
            let s4 = s2 * s2;
            k::<T>(1.0)
                + s2 / 6.0
                + s4 * 3.0 / 40.0
                + s4 * s2 * 5.0 / 112.0
                + s4 * s4 * 35.0 / 1152.0
        } else {
            let s = s2.sqrt();
            s.atan2(c) / s
        };
        [a[0] * f, a[1] * f, a[2] * f]
    } else {
        // θ ∈ [π/2, π]: n from n nᵀ = ((R + Rᵀ)/2 − c I) / (1 − c), using the
        // column of the largest diagonal entry (≥ 1/3), sign from a.
        let one_c = k::<T>(1.0) - c;
        let m = |i: usize, j: usize| {
            let sym = (r[i][j] + r[j][i]) * 0.5;
            if i == j {
                (sym - c) / one_c
            } else {
                sym / one_c
            }
        };
        let diag = [m(0, 0).re(), m(1, 1).re(), m(2, 2).re()];
        let kk = (0..3)
            .max_by(|&i, &j| diag[i].total_cmp(&diag[j]))
            .unwrap_or(0);
        let nk = m(kk, kk).sqrt();
        let mut n: V3<T> = std::array::from_fn(|j| if j == kk { nk } else { m(j, kk) / nk });
        if dot(n, a).re() < 0.0 {
            n = [-n[0], -n[1], -n[2]];
        }
        let theta = dot(n, a).atan2(c);
        [n[0] * theta, n[1] * theta, n[2] * theta]
    };
    // v = V⁻¹ p, V⁻¹ = I − ½W + β W², β = (1 − (θ/2) cot(θ/2)) / θ².
    let t2 = dot(w, w);
    let beta = if t2.re() < 1e-2 {
        // Series; the first omitted term is ≈ 2e-8 θ⁸ < 1e-23 here.
        let t4 = t2 * t2;
        k::<T>(1.0 / 12.0) + t2 / 720.0 + t4 / 30240.0 + t4 * t2 / 1209600.0
    } else {
        let half = t2.sqrt() * 0.5;
        let (s, co) = half.sin_cos();
        (k::<T>(1.0) - half * co / s) / t2
    };
    let p = g.p;
    let wp = cross(w, p);
    let wwp = cross(w, wp);
    [
        p[0] - wp[0] * 0.5 + beta * wwp[0],
        p[1] - wp[1] * 0.5 + beta * wwp[1],
        p[2] - wp[2] * 0.5 + beta * wwp[2],
        w[0],
        w[1],
        w[2],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix4;
    use num_dual::DualSVec64;
    use proptest::prelude::*;

    fn hat4(xi: &[f64; 6]) -> Matrix4<f64> {
        let (v, w) = (&xi[..3], &xi[3..]);
        Matrix4::new(
            0.0, -w[2], w[1], v[0], w[2], 0.0, -w[0], v[1], -w[1], w[0], 0.0, v[2], 0.0, 0.0, 0.0,
            0.0,
        )
    }

    fn twist(v: [f64; 3], axis: [f64; 3], angle: f64) -> [f64; 6] {
        let n = (axis[0].powi(2) + axis[1].powi(2) + axis[2].powi(2))
            .sqrt()
            .max(1e-12);
        [
            v[0],
            v[1],
            v[2],
            axis[0] / n * angle,
            axis[1] / n * angle,
            axis[2] / n * angle,
        ]
    }

    fn angle_strategy() -> impl Strategy<Value = f64> {
        // Tiny, small and large angles, up to just below π.
        prop_oneof![
            Just(0.0),
            (-12.0f64..-3.0).prop_map(|e| 10f64.powf(e)),
            // Up to just below a half turn (π itself is tested separately).
            0.0f64..(std::f64::consts::PI - 1.6e-3),
        ]
    }

    proptest! {
        #![proptest_config(crate::prop_config::config(256))]

        /// exp against nalgebra's matrix exponential of the 4×4 twist
        /// matrix, and log(exp ξ) = ξ.
        #[test]
        fn exp_matches_matrix_exponential_and_log_inverts_it(
            v in prop::array::uniform3(-2.0f64..2.0),
            axis in prop::array::uniform3(-1.0f64..1.0),
            angle in angle_strategy(),
        ) {
            let xi = twist(v, axis, angle);
            let g = se3_exp(&xi);
            let m = hat4(&xi).exp();
            for i in 0..3 {
                for j in 0..3 {
                    prop_assert!((g.r[i][j] - m[(i, j)]).abs() < 1e-12);
                }
                prop_assert!((g.p[i] - m[(i, 3)]).abs() < 1e-12);
            }
            let back = se3_log(&g);
            for i in 0..6 {
                prop_assert!((back[i] - xi[i]).abs() < 1e-9, "{i}: {back:?} vs {xi:?}");
            }
        }

        /// d/dt log(exp(ξ + t η)) at t = 0 through dual numbers equals the
        /// central difference, including at and near the identity and near π.
        #[test]
        fn log_exp_derivatives_match_differences(
            v in prop::array::uniform3(-2.0f64..2.0),
            axis in prop::array::uniform3(-1.0f64..1.0),
            angle in angle_strategy(),
            eta in prop::array::uniform6(-1.0f64..1.0),
        ) {
            let xi = twist(v, axis, angle.min(3.0));
            // ξ + t η with dt/dt = 1 in the dual part.
            let xd: [DualSVec64<1>; 6] = std::array::from_fn(|i| {
                DualSVec64::<1>::from_re(0.0).derivative(0) * eta[i] + xi[i]
            });
            let out = se3_log(&se3_exp(&xd));
            let h = 1e-6;
            let plus = se3_log(&se3_exp(&std::array::from_fn(|i| xi[i] + h * eta[i])));
            let minus = se3_log(&se3_exp(&std::array::from_fn(|i| xi[i] - h * eta[i])));
            for i in 0..6 {
                let d = out[i].eps.0.map_or(0.0, |e| e[0]);
                let fd = (plus[i] - minus[i]) / (2.0 * h);
                prop_assert!(d.is_finite());
                // log ∘ exp is the identity: its derivative is η.
                prop_assert!((d - eta[i]).abs() < 1e-9, "{i}: {d} vs {}", eta[i]);
                prop_assert!((d - fd).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn log_near_pi_is_stable() {
        for angle in [std::f64::consts::PI - 1e-9, std::f64::consts::PI] {
            let xi = twist([0.3, -0.2, 0.1], [0.2, 0.5, -0.7], angle);
            let g = se3_exp(&xi);
            let back = se3_log(&g);
            // At exactly π the axis sign is free: compare the poses.
            let g2 = se3_exp(&back);
            for i in 0..3 {
                for j in 0..3 {
                    assert!((g.r[i][j] - g2.r[i][j]).abs() < 1e-12);
                }
                assert!((g.p[i] - g2.p[i]).abs() < 1e-9);
            }
            let t = (back[3].powi(2) + back[4].powi(2) + back[5].powi(2)).sqrt();
            assert!((t - angle).abs() < 1e-9);
        }
    }
}
