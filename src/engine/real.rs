//! Conversions between the engine's scalar ([`Real`], f64 in this build) and
//! the harness's f64, in one place so the physics code compiles unchanged
//! against f32 Rapier (used to measure f32 against f64, docs/src/research/space-robot.md).
#![allow(clippy::unnecessary_cast)] // the casts are no-ops in f64 builds only

use crate::engine::rapier::math::{Matrix, Pose as RPose, Real, Rotation, Vector};
use crate::model::spatial::Pose as SPose;
use crate::record::Pose;

/// Engine scalar → f64.
#[inline]
pub fn f(x: Real) -> f64 {
    x as f64
}

/// f64 → engine scalar.
#[inline]
pub fn r(x: f64) -> Real {
    x as Real
}

/// Engine vector → f64 array.
#[inline]
pub fn arr(v: Vector) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

/// f64 components → engine vector.
#[inline]
pub fn vector(x: f64, y: f64, z: f64) -> Vector {
    Vector::new(x as Real, y as Real, z as Real)
}

/// Engine rotation → (x, y, z, w) in f64.
#[inline]
pub fn quat(q: &Rotation) -> [f64; 4] {
    [q.x as f64, q.y as f64, q.z as f64, q.w as f64]
}

/// f64 quaternion (x, y, z, w) → engine rotation (normalised).
#[inline]
pub fn rotation(x: f64, y: f64, z: f64, w: f64) -> Rotation {
    Rotation::from_xyzw(x as Real, y as Real, z as Real, w as Real).normalize()
}

/// Engine pose → record [`Pose`].
#[inline]
pub(crate) fn to_pose(p: &RPose) -> Pose {
    Pose {
        translation: arr(p.translation),
        rotation: quat(&p.rotation),
    }
}

/// Model pose ([`crate::model::spatial::Pose`]) → engine pose.
pub(crate) fn from_spatial(p: &SPose<f64>) -> RPose {
    let q = p.quaternion();
    RPose::from_parts(
        vector(p.p[0], p.p[1], p.p[2]),
        rotation(q[0], q[1], q[2], q[3]),
    )
}

/// Engine pose → model pose.
pub(crate) fn to_spatial(p: &RPose) -> SPose<f64> {
    let m = Matrix::from_quat(p.rotation);
    let cols = [m.x_axis, m.y_axis, m.z_axis];
    SPose {
        r: std::array::from_fn(|i| std::array::from_fn(|j| f(cols[j][i]))),
        p: arr(p.translation),
    }
}

/// URDF `<origin>` (xyz, fixed-axis roll-pitch-yaw) as an engine pose:
/// R = Rz(yaw) Ry(pitch) Rx(roll).
pub fn origin(p: &urdf_rs::Pose) -> RPose {
    RPose::from_parts(
        vector(p.xyz[0], p.xyz[1], p.xyz[2]),
        Rotation::from_euler(
            crate::engine::rapier::glamx::EulerRot::ZYX,
            r(p.rpy[2]),
            r(p.rpy[1]),
            r(p.rpy[0]),
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn engine_and_model_poses_agree() {
        let sp = SPose::<f64>::from_xyz_rpy([0.3, -1.2, 2.0], [0.4, -0.7, 2.5]);
        let back = to_spatial(&from_spatial(&sp));
        for i in 0..3 {
            assert!((back.p[i] - sp.p[i]).abs() < 1e-12);
            for j in 0..3 {
                assert!(
                    (back.r[i][j] - sp.r[i][j]).abs() < 1e-12,
                    "{back:?} vs {sp:?}"
                );
            }
        }
    }
}
