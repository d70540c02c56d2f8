//! Small spatial algebra over a generic scalar: 3-vectors, rotation matrices
//! and rigid poses whose entries may be plain `f64` or forward-mode dual
//! numbers (`num_dual`), so the same forward kinematics gives values and exact
//! derivatives.
//!
//! Fixed-size arrays rather than `nalgebra` types: dual numbers are `Copy`
//! here and the few operations needed stay allocation-free and obvious.

use num_dual::DualNum;

/// A scalar the kinematics can be evaluated in: `f64` or a dual number over `f64`.
pub trait Scalar: DualNum<Primitive = f64> + Copy + Send + Sync {}
impl<T: DualNum<Primitive = f64> + Copy + Send + Sync> Scalar for T {}

/// A constant as a scalar.
#[inline]
pub fn k<T: Scalar>(x: f64) -> T {
    T::from(x)
}

/// Column 3-vector.
pub type V3<T> = [T; 3];
/// 3×3 matrix, row-major (`m[row][col]`).
pub type M3<T> = [[T; 3]; 3];

/// a + b.
#[inline]
pub fn add<T: Scalar>(a: V3<T>, b: V3<T>) -> V3<T> {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// a − b.
#[inline]
pub fn sub<T: Scalar>(a: V3<T>, b: V3<T>) -> V3<T> {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// s · a.
#[inline]
pub fn scale<T: Scalar>(a: V3<T>, s: T) -> V3<T> {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// a · b.
#[inline]
pub(crate) fn dot<T: Scalar>(a: V3<T>, b: V3<T>) -> T {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// a × b.
#[inline]
pub fn cross<T: Scalar>(a: V3<T>, b: V3<T>) -> V3<T> {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// ‖a‖.
#[inline]
pub fn norm<T: Scalar>(a: V3<T>) -> T {
    dot(a, a).sqrt()
}

/// Lift a constant vector.
#[inline]
pub(crate) fn lift<T: Scalar>(a: [f64; 3]) -> V3<T> {
    [k(a[0]), k(a[1]), k(a[2])]
}

/// Real parts of a vector.
#[inline]
pub fn re<T: Scalar>(a: V3<T>) -> [f64; 3] {
    [a[0].re(), a[1].re(), a[2].re()]
}

/// m · v.
#[inline]
pub(crate) fn mul_mv<T: Scalar>(m: &M3<T>, v: V3<T>) -> V3<T> {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// mᵀ · v.
#[inline]
pub(crate) fn mul_mtv<T: Scalar>(m: &M3<T>, v: V3<T>) -> V3<T> {
    [
        m[0][0] * v[0] + m[1][0] * v[1] + m[2][0] * v[2],
        m[0][1] * v[0] + m[1][1] * v[1] + m[2][1] * v[2],
        m[0][2] * v[0] + m[1][2] * v[1] + m[2][2] * v[2],
    ]
}

/// a · b.
#[inline]
pub(crate) fn mul_mm<T: Scalar>(a: &M3<T>, b: &M3<T>) -> M3<T> {
    let mut out = [[k::<T>(0.0); 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    out
}

/// a · b with a constant `b` (cheaper for dual numbers than lifting b).
#[inline]
pub(crate) fn mul_mm_const<T: Scalar>(a: &M3<T>, b: &[[f64; 3]; 3]) -> M3<T> {
    let mut out = [[k::<T>(0.0); 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, x) in row.iter_mut().enumerate() {
            *x = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    out
}

/// m · v with a constant `v`.
#[inline]
pub(crate) fn mul_mv_const<T: Scalar>(m: &M3<T>, v: [f64; 3]) -> V3<T> {
    std::array::from_fn(|i| m[i][0] * v[0] + m[i][1] * v[1] + m[i][2] * v[2])
}

/// Column `j` of `m`.
#[inline]
pub fn col<T: Scalar>(m: &M3<T>, j: usize) -> V3<T> {
    [m[0][j], m[1][j], m[2][j]]
}

/// Rotation about z by `a`.
#[inline]
pub(crate) fn rot_z<T: Scalar>(a: T) -> M3<T> {
    let (s, c) = (a.sin(), a.cos());
    let (o, l) = (k::<T>(0.0), k::<T>(1.0));
    [[c, -s, o], [s, c, o], [o, o, l]]
}

/// Rotation about x by `a`.
#[inline]
pub(crate) fn rot_x<T: Scalar>(a: T) -> M3<T> {
    let (s, c) = (a.sin(), a.cos());
    let (o, l) = (k::<T>(0.0), k::<T>(1.0));
    [[l, o, o], [o, c, -s], [o, s, c]]
}

/// Rotation about y by `a`.
#[inline]
pub(crate) fn rot_y<T: Scalar>(a: T) -> M3<T> {
    let (s, c) = (a.sin(), a.cos());
    let (o, l) = (k::<T>(0.0), k::<T>(1.0));
    [[c, o, s], [o, l, o], [-s, o, c]]
}

/// Rotation from URDF roll-pitch-yaw (fixed axes x, then y, then z: R = Rz Ry Rx).
pub fn rpy<T: Scalar>(r: [f64; 3]) -> M3<T> {
    mul_mm(&rot_z(k(r[2])), &mul_mm(&rot_y(k(r[1])), &rot_x(k(r[0]))))
}

/// The identity rotation.
#[inline]
pub fn identity<T: Scalar>() -> M3<T> {
    let (o, l) = (k::<T>(0.0), k::<T>(1.0));
    [[l, o, o], [o, l, o], [o, o, l]]
}

/// Real parts of a matrix.
pub(crate) fn re_m<T: Scalar>(m: &M3<T>) -> [[f64; 3]; 3] {
    m.map(|r| r.map(|x| x.re()))
}

/// A rigid transform x ↦ r x + p.
#[derive(Debug, Clone, Copy)]
pub struct Pose<T: Scalar> {
    /// Rotation (columns: the frame's axes in the parent frame).
    pub r: M3<T>,
    /// Origin in the parent frame.
    pub p: V3<T>,
}

impl<T: Scalar> Pose<T> {
    /// The identity.
    pub fn identity() -> Self {
        Pose {
            r: identity(),
            p: lift([0.0; 3]),
        }
    }

    /// A pure rotation.
    pub fn rotation(r: M3<T>) -> Self {
        Pose {
            r,
            p: lift([0.0; 3]),
        }
    }

    /// A pure translation.
    pub fn translation(p: V3<T>) -> Self {
        Pose { r: identity(), p }
    }

    /// A constant pose from URDF xyz / rpy.
    pub fn from_xyz_rpy(xyz: [f64; 3], r: [f64; 3]) -> Self {
        Pose {
            r: rpy(r),
            p: lift(xyz),
        }
    }

    /// self ∘ other (apply `other` first).
    #[inline]
    pub fn then(&self, other: &Pose<T>) -> Pose<T> {
        Pose {
            r: mul_mm(&self.r, &other.r),
            p: add(mul_mv(&self.r, other.p), self.p),
        }
    }

    /// Image of a point.
    #[inline]
    pub fn apply(&self, x: V3<T>) -> V3<T> {
        add(mul_mv(&self.r, x), self.p)
    }

    /// Pre-image of a point (the inverse transform applied).
    #[inline]
    pub fn apply_inv(&self, x: V3<T>) -> V3<T> {
        mul_mtv(&self.r, sub(x, self.p))
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Pose<T> {
        let rt: M3<T> = std::array::from_fn(|i| std::array::from_fn(|j| self.r[j][i]));
        Pose {
            p: scale(mul_mv(&rt, self.p), k(-1.0)),
            r: rt,
        }
    }

    /// self ∘ other for a constant `other` (cheaper than lifting it).
    #[inline]
    pub fn then_const(&self, other: &Pose<f64>) -> Pose<T> {
        Pose {
            r: mul_mm_const(&self.r, &other.r),
            p: add(mul_mv_const(&self.r, other.p), self.p),
        }
    }

    /// Real parts.
    pub fn re(&self) -> Pose<f64> {
        Pose {
            r: re_m(&self.r),
            p: re(self.p),
        }
    }

    /// Unit quaternion (x, y, z, w) of the rotation (real parts).
    pub fn quaternion(&self) -> [f64; 4] {
        let m = re_m(&self.r);
        let q = nalgebra::UnitQuaternion::from_matrix(&nalgebra::Matrix3::from_row_slice(&[
            m[0][0], m[0][1], m[0][2], m[1][0], m[1][1], m[1][2], m[2][0], m[2][1], m[2][2],
        ]));
        [q.i, q.j, q.k, q.w]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rpy_matches_nalgebra() {
        let r = [0.3, -0.7, 1.9];
        let m: M3<f64> = rpy(r);
        let n = nalgebra::Rotation3::from_euler_angles(r[0], r[1], r[2]);
        for i in 0..3 {
            for j in 0..3 {
                assert!((m[i][j] - n[(i, j)]).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn pose_inverse_round_trips() {
        let p = Pose::<f64>::from_xyz_rpy([1.0, -2.0, 0.5], [0.2, 0.4, -1.1]);
        let x = [0.3, 0.7, -0.9];
        let back = p.apply_inv(p.apply(x));
        for i in 0..3 {
            assert!((back[i] - x[i]).abs() < 1e-14);
        }
        let q = p.then(&p);
        let y = q.apply(x);
        let z = p.apply(p.apply(x));
        for i in 0..3 {
            assert!((y[i] - z[i]).abs() < 1e-14);
        }
    }
}
