//! Angle read-back shared by the physics systems: Rapier quaternions to
//! model angles, and continuous unwrapping across steps.

use crate::engine::rapier::math::Rotation;
use crate::engine::real::quat;

pub use crate::compare::wrap_angle as wrap;

/// Heading (rotation about world z, from +x towards +y) of an orientation.
pub fn yaw(q: &Rotation) -> f64 {
    let [x, y, z, w] = quat(q);
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

/// Angle of a rotation about one of its own axes (0 = x, 1 = y, 2 = z), in
/// (−π, π]; exact when the rotation is about that axis.
pub(crate) fn about_axis(q: &Rotation, axis: usize) -> f64 {
    let [x, y, z, w] = quat(q);
    let s = if w < 0.0 { -1.0 } else { 1.0 };
    let v = [x, y, z][axis.min(2)];
    wrap(2.0 * (s * v).atan2(s * w))
}

/// The continuous angle closest to `prev` that equals `raw` modulo 2π.
pub fn unwrap(prev: f64, raw: f64) -> f64 {
    prev + wrap(raw - prev)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unwrap_follows_a_spinning_angle() {
        let mut a = 0.0;
        for k in 1..=100 {
            let truth = 0.3 * k as f64;
            a = unwrap(a, wrap(truth));
            assert!((a - truth).abs() < 1e-12);
        }
    }

    #[test]
    fn yaw_and_axis_angles_read_back() {
        let q = Rotation::from_rotation_z(2.5);
        assert!((yaw(&q) - 2.5).abs() < 1e-6);
        assert!((about_axis(&q, 2) - 2.5).abs() < 1e-6);
        let q = Rotation::from_rotation_y(-1.2);
        assert!((about_axis(&q, 1) + 1.2).abs() < 1e-6);
    }
}
