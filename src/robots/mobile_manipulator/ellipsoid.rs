//! Generalized n-ellipsoids (seed 004 §III): the shape every robot part and
//! every obstacle is made of.
//!
//! In a frame aligned with its semi-axes (a, b, c), centred at (x₀, y₀, z₀),
//! the surface is the zero set of
//!
//! b(x, y, z) = ((x−x₀)/a)^{2n} + ((y−y₀)/b)^{2n} + ((z−z₀)/c)^{2n} − 1,
//!
//! negative inside, zero on the surface and growing away from it. n = 1 is an
//! ordinary ellipsoid; large n approaches a box (walls, tables); n ≥ ½ keeps
//! the set convex. Odd powers are taken of |·| so every real n works.

use crate::model::spatial::{self, Scalar, M3};
use serde::{Deserialize, Serialize};

/// A generalized ellipsoid in the world frame (or in a link frame, for robot parts).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Superellipsoid {
    /// Centre, m.
    pub center: [f64; 3],
    /// Semi-axes (a, b, c) along the local x, y, z axes, m.
    pub semi_axes: [f64; 3],
    /// Exponent n ≥ ½ (1 = ellipsoid).
    #[serde(default = "one")]
    pub exponent: f64,
    /// Orientation as URDF roll-pitch-yaw, rad.
    #[serde(default)]
    pub rpy: [f64; 3],
}

fn one() -> f64 {
    1.0
}

/// Below n = 1, |u|^{2n} has a kink (n = ½) or an infinite second
/// derivative at u = 0; it is rounded there as (u² + ε²)^n − ε^{2n}, which
/// changes b by less than ε^{2n} ≤ 1e-9 and keeps Newton's method usable.
pub const KINK_EPS: f64 = 1e-9;

/// |u|^{2n}, smooth in u for n ≥ 1 (integer exponents use `powi`); rounded
/// at u = 0 below n = 1 (see [`KINK_EPS`]).
#[inline]
pub(crate) fn pow2n<T: Scalar>(u: T, n: f64) -> T {
    if n < 1.0 {
        let e2 = KINK_EPS * KINK_EPS;
        return (u * u + e2).powf(n) - e2.powf(n);
    }
    if n == 1.0 {
        // The common case (every robot part), without the generic power.
        return u * u;
    }
    let two_n = 2.0 * n;
    if two_n.fract() == 0.0 && two_n <= 64.0 {
        if (two_n as i32) % 2 == 0 {
            u.powi(two_n as i32)
        } else {
            u.abs().powi(two_n as i32)
        }
    } else {
        (u * u).powf(n)
    }
}

/// φ(u) = |u|^{2n}, φ′ and φ″, with the kink of n < 1 rounded over `eps`
/// (as (u² + ε²)^n − ε^{2n}, see [`KINK_EPS`]): the one-dimensional pieces of
/// b's value, gradient and Hessian.
#[inline]
pub(crate) fn pow2n_derivatives(u: f64, n: f64, eps: f64) -> (f64, f64, f64) {
    let u2 = u * u;
    if n < 1.0 {
        let e2 = eps * eps;
        let w = u2 + e2;
        let p = w.powf(n - 1.0);
        return (
            w * p - e2.powf(n),
            2.0 * n * u * p,
            2.0 * n * p * (1.0 + 2.0 * (n - 1.0) * u2 / w),
        );
    }
    // d/du |u|^{2n} = 2n u |u|^{2n−2}; second derivative 2n(2n−1)|u|^{2n−2}.
    let p = if n == 1.0 {
        1.0
    } else if n.fract() == 0.0 {
        u2.powi(n as i32 - 1)
    } else {
        u2.powf(n - 1.0)
    };
    (p * u2, 2.0 * n * u * p, 2.0 * n * (2.0 * n - 1.0) * p)
}

/// Why a superellipsoid is unusable; messages name the field.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ShapeError {
    /// A semi-axis is not finite and > 0.
    #[error("`semi_axes` must be finite and > 0, got {}", crate::numfmt::list(.0))]
    SemiAxes([f64; 3]),
    /// The exponent is below 1/2 (or not finite): the set is not convex.
    #[error("`exponent` n must be ≥ 1/2 (the set is not convex below), got {0}")]
    ExponentLow(f64),
    /// The exponent is over 32: |u|^2n overflows.
    #[error("`exponent` n must be ≤ 32 (beyond, |u|^2n overflows), got {0}")]
    ExponentHigh(f64),
    /// The centre or the roll-pitch-yaw angles are not finite.
    #[error("`center` and `rpy` must be finite")]
    NotFinite,
}

impl Superellipsoid {
    /// A plain ellipsoid (n = 1) with the given centre and semi-axes, axis-aligned.
    pub fn ellipsoid(center: [f64; 3], semi_axes: [f64; 3]) -> Self {
        Superellipsoid {
            center,
            semi_axes,
            exponent: 1.0,
            rpy: [0.0; 3],
        }
    }

    /// Why the shape is unusable, if it is (messages name the field).
    pub fn validate(&self) -> Result<(), ShapeError> {
        if self.semi_axes.iter().any(|a| !(a.is_finite() && *a > 0.0)) {
            return Err(ShapeError::SemiAxes(self.semi_axes));
        }
        if !(self.exponent.is_finite() && self.exponent >= 0.5) {
            return Err(ShapeError::ExponentLow(self.exponent));
        }
        if self.exponent > 32.0 {
            return Err(ShapeError::ExponentHigh(self.exponent));
        }
        if self.center.iter().chain(&self.rpy).any(|v| !v.is_finite()) {
            return Err(ShapeError::NotFinite);
        }
        Ok(())
    }

    /// Rotation of the local frame (columns: local axes in the parent frame).
    pub fn rotation(&self) -> M3<f64> {
        spatial::rpy(self.rpy)
    }

    /// The shape placed by `pose` (for parts given in a link frame).
    pub fn placed(&self, pose: &spatial::Pose<f64>) -> PlacedEllipsoid<f64> {
        let local = spatial::Pose::<f64>::from_xyz_rpy(self.center, self.rpy);
        let world = pose.then(&local);
        PlacedEllipsoid {
            center: world.p,
            rot: world.r,
            semi: self.semi_axes,
            n: self.exponent,
        }
    }

    /// The shape in its own parent frame.
    pub fn at_rest(&self) -> PlacedEllipsoid<f64> {
        self.placed(&spatial::Pose::identity())
    }

    /// Radius of the smallest sphere about the centre containing the shape.
    pub fn bounding_radius(&self) -> f64 {
        // The farthest point of a superellipsoid from its centre is at most the
        // box corner; for n = 1 the largest semi-axis.
        let [a, b, c] = self.semi_axes;
        if self.exponent <= 1.0 {
            a.max(b).max(c)
        } else {
            (a * a + b * b + c * c).sqrt()
        }
    }

    /// Surface points on a (latitude × longitude) grid: a closed triangle mesh
    /// (vertices in the parent frame, counter-clockwise triangles seen from
    /// outside), for drawing and for convex-hull colliders.
    pub fn mesh(&self, lat: usize, lon: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
        let lat = lat.max(2);
        let lon = lon.max(3);
        let placed = self.at_rest();
        let e = 1.0 / self.exponent;
        // Signed power keeps the octant: the superquadric parameterisation.
        let sp = |c: f64| c.signum() * c.abs().powf(e);
        let mut v = Vec::with_capacity((lat - 1) * lon + 2);
        v.push(placed.to_world([0.0, 0.0, self.semi_axes[2]]));
        for i in 1..lat {
            let phi = std::f64::consts::PI * (0.5 - i as f64 / lat as f64);
            for j in 0..lon {
                let th = std::f64::consts::TAU * j as f64 / lon as f64;
                let local = [
                    self.semi_axes[0] * sp(phi.cos()) * sp(th.cos()),
                    self.semi_axes[1] * sp(phi.cos()) * sp(th.sin()),
                    self.semi_axes[2] * sp(phi.sin()),
                ];
                v.push(placed.to_world(local));
            }
        }
        v.push(placed.to_world([0.0, 0.0, -self.semi_axes[2]]));
        let bottom = (v.len() - 1) as u32;
        let ring = |i: usize, j: usize| (1 + i * lon + j % lon) as u32;
        let mut t = Vec::with_capacity(2 * lat * lon);
        for j in 0..lon {
            t.push([0, ring(0, j), ring(0, j + 1)]);
        }
        for i in 0..lat - 2 {
            for j in 0..lon {
                let (a, b, c, d) = (
                    ring(i, j),
                    ring(i, j + 1),
                    ring(i + 1, j),
                    ring(i + 1, j + 1),
                );
                t.push([a, c, b]);
                t.push([b, c, d]);
            }
        }
        for j in 0..lon {
            t.push([bottom, ring(lat - 2, j + 1), ring(lat - 2, j)]);
        }
        (v, t)
    }
}

/// A generalized ellipsoid at a pose, with entries in scalar `T`.
#[derive(Debug, Clone, Copy)]
pub struct PlacedEllipsoid<T: Scalar> {
    /// Centre in the world.
    pub center: [T; 3],
    /// Rotation: columns are the local axes in the world.
    pub rot: M3<T>,
    /// Semi-axes.
    pub semi: [f64; 3],
    /// Exponent n.
    pub n: f64,
}

impl<T: Scalar> PlacedEllipsoid<T> {
    /// Normalised local coordinates u = diag(1/semi) Rᵀ (x − c).
    #[inline]
    pub fn local(&self, x: [T; 3]) -> [T; 3] {
        let d = spatial::mul_mtv(&self.rot, spatial::sub(x, self.center));
        [
            d[0] * (1.0 / self.semi[0]),
            d[1] * (1.0 / self.semi[1]),
            d[2] * (1.0 / self.semi[2]),
        ]
    }

    /// The function b(x) of the section doc: < 0 inside, 0 on the surface.
    #[inline]
    pub fn value(&self, x: [T; 3]) -> T {
        let u = self.local(x);
        pow2n(u[0], self.n) + pow2n(u[1], self.n) + pow2n(u[2], self.n) - 1.0
    }

    /// Real parts.
    pub fn re(&self) -> PlacedEllipsoid<f64> {
        PlacedEllipsoid {
            center: spatial::re(self.center),
            rot: spatial::re_m(&self.rot),
            semi: self.semi,
            n: self.n,
        }
    }
}

impl PlacedEllipsoid<f64> {
    /// Local (semi-axis frame, unnormalised) point to the world.
    pub fn to_world(&self, local: [f64; 3]) -> [f64; 3] {
        spatial::add(spatial::mul_mv(&self.rot, local), self.center)
    }

    /// ∇b(x) in world coordinates: the exact derivative of [`PlacedEllipsoid::value`]
    /// (kink rounded over [`KINK_EPS`] below n = 1), without the Hessian.
    pub fn grad(&self, x: [f64; 3]) -> [f64; 3] {
        let u = self.local(x);
        let du: [f64; 3] =
            std::array::from_fn(|k| pow2n_derivatives(u[k], self.n, KINK_EPS).1 / self.semi[k]);
        spatial::mul_mv(&self.rot, du)
    }

    /// b(x), its gradient and Hessian in world coordinates (kink rounded
    /// over [`KINK_EPS`] below n = 1).
    pub fn value_grad_hess(&self, x: [f64; 3]) -> (f64, [f64; 3], [[f64; 3]; 3]) {
        let u = self.local(x);
        let mut val = -1.0;
        let mut du = [0.0; 3];
        let mut ddu = [0.0; 3];
        for k in 0..3 {
            let s = self.semi[k];
            let (f, d1, d2) = pow2n_derivatives(u[k], self.n, KINK_EPS);
            val += f;
            du[k] = d1 / s;
            ddu[k] = d2 / (s * s);
        }
        // Back to world: ∇ = R du, ∇² = R diag(ddu) Rᵀ.
        let r = &self.rot;
        let g = spatial::mul_mv(r, du);
        let mut h = [[0.0; 3]; 3];
        for (i, row) in h.iter_mut().enumerate() {
            for (j, x) in row.iter_mut().enumerate() {
                *x = (0..3).map(|k| r[i][k] * ddu[k] * r[j][k]).sum();
            }
        }
        (val, g, h)
    }

    /// Gauge (Σ|u_k|^{2n})^{1/2n} of a point: 1 on the surface, scales linearly along rays from the centre.
    pub fn gauge(&self, x: [f64; 3]) -> f64 {
        (self.value(x) + 1.0).max(0.0).powf(0.5 / self.n)
    }

    /// The surface point on the ray from the centre through `x` (x ≠ centre).
    pub fn radial_projection(&self, x: [f64; 3]) -> [f64; 3] {
        let g = self.gauge(x);
        if g <= 0.0 {
            return self.to_world([self.semi[0], 0.0, 0.0]);
        }
        let d = spatial::sub(x, self.center);
        spatial::add(self.center, spatial::scale(d, 1.0 / g))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shape(n: f64) -> Superellipsoid {
        Superellipsoid {
            center: [0.5, -1.0, 0.25],
            semi_axes: [0.6, 0.3, 1.2],
            exponent: n,
            rpy: [0.3, -0.2, 1.1],
        }
    }

    #[test]
    fn mesh_vertices_lie_on_the_surface() {
        for n in [0.5, 1.0, 2.5, 6.0] {
            let s = shape(n);
            let p = s.at_rest();
            let (v, t) = s.mesh(12, 20);
            for x in &v {
                assert!(p.value(*x).abs() < 1e-8, "n = {n}: b = {}", p.value(*x));
            }
            assert!(t.iter().flatten().all(|&i| (i as usize) < v.len()));
            // Closed surface: V − E + F = 2.
            assert_eq!(v.len() as i64 - 3 * t.len() as i64 / 2 + t.len() as i64, 2);
        }
    }

    #[test]
    fn gradient_and_hessian_match_finite_differences() {
        for n in [1.0, 1.5, 4.0] {
            let p = shape(n).at_rest();
            let x = [0.9, -0.6, 0.8];
            let (_, g, h) = p.value_grad_hess(x);
            let e = 1e-6;
            for i in 0..3 {
                let (mut xp, mut xm) = (x, x);
                xp[i] += e;
                xm[i] -= e;
                let fd = (p.value(xp) - p.value(xm)) / (2.0 * e);
                assert!((fd - g[i]).abs() < 1e-6 * (1.0 + g[i].abs()), "n {n} g{i}");
                let (_, gp, _) = p.value_grad_hess(xp);
                let (_, gm, _) = p.value_grad_hess(xm);
                for j in 0..3 {
                    let fd = (gp[j] - gm[j]) / (2.0 * e);
                    assert!(
                        (fd - h[i][j]).abs() < 1e-5 * (1.0 + h[i][j].abs()),
                        "n {n} h{i}{j}"
                    );
                }
            }
        }
    }

    #[test]
    fn grad_matches_value_grad_hess() {
        for n in [0.5, 0.75, 1.0, 1.5, 3.0, 4.5] {
            let p = shape(n).at_rest();
            for x in [[0.9, -0.6, 0.8], [0.5, -1.0, 2.0], [-0.4, 0.1, 0.3]] {
                let (_, g, _) = p.value_grad_hess(x);
                let h = p.grad(x);
                for i in 0..3 {
                    assert!((h[i] - g[i]).abs() <= 1e-13 * (1.0 + g[i].abs()), "n {n}");
                }
            }
        }
    }

    #[test]
    fn radial_projection_lands_on_the_surface() {
        let p = shape(3.0).at_rest();
        let q = p.radial_projection([3.0, 2.0, -1.0]);
        assert!(p.value(q).abs() < 1e-12);
    }

    #[test]
    fn validation_names_the_field() {
        let mut s = shape(1.0);
        s.semi_axes[1] = 0.0;
        assert!(s.validate().unwrap_err().to_string().contains("semi_axes"));
        let mut s = shape(0.4);
        assert!(s.validate().unwrap_err().to_string().contains("exponent"));
        s.exponent = 0.5;
        assert!(s.validate().is_ok());
    }
}
