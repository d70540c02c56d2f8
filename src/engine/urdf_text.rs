//! URDF values as a user writes them in the file, for messages:
//! `<cylinder radius="0" length="0.025"/>`, `xyz="0 0 nan"`, a joint's
//! `type="fixed"`; never the parser's own structures.

use crate::numfmt::shortest;
use urdf_rs::{Geometry, JointType};

/// Numbers as a URDF attribute lists them: `0 0.025 1e-9`.
pub fn numbers(v: &[f64]) -> String {
    v.iter().map(|x| shortest(*x)).collect::<Vec<_>>().join(" ")
}

/// A joint's `type` attribute.
pub(crate) fn joint_type(t: &JointType) -> &'static str {
    match t {
        JointType::Revolute => "revolute",
        JointType::Continuous => "continuous",
        JointType::Prismatic => "prismatic",
        JointType::Fixed => "fixed",
        JointType::Floating => "floating",
        JointType::Planar => "planar",
        JointType::Spherical => "spherical",
    }
}

/// A `<geometry>` child element.
pub fn geometry(g: &Geometry) -> String {
    match g {
        Geometry::Box { size } => format!("<box size=\"{}\"/>", numbers(&size.0)),
        Geometry::Cylinder { radius, length } => format!(
            "<cylinder radius=\"{}\" length=\"{}\"/>",
            shortest(*radius),
            shortest(*length)
        ),
        Geometry::Capsule { radius, length } => format!(
            "<capsule radius=\"{}\" length=\"{}\"/>",
            shortest(*radius),
            shortest(*length)
        ),
        Geometry::Sphere { radius } => format!("<sphere radius=\"{}\"/>", shortest(*radius)),
        Geometry::Mesh { filename, scale } => {
            let scale = scale
                .as_ref()
                .map(|s| format!(" scale=\"{}\"", numbers(&s.0)))
                .unwrap_or_default();
            format!(
                "<mesh filename=\"{}\"{scale}/>",
                crate::echo::bare(filename)
            )
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geometry_reads_as_written() {
        let c = Geometry::Cylinder {
            radius: 0.0,
            length: 0.025,
        };
        assert_eq!(geometry(&c), "<cylinder radius=\"0\" length=\"0.025\"/>");
        let m = Geometry::Mesh {
            filename: "wheel.stl".into(),
            scale: Some(urdf_rs::Vec3([f64::NAN, 1.0, 1e-9])),
        };
        assert_eq!(
            geometry(&m),
            "<mesh filename=\"wheel.stl\" scale=\"NaN 1 1e-9\"/>"
        );
        assert_eq!(joint_type(&JointType::Fixed), "fixed");
    }
}
