//! Seed 004, Eq. 1: k mobile manipulators, each a unicycle platform carrying
//! a PUMA 560 arm ([`crate::robots::mobile_manipulator::puma560`]).
//!
//! Robot r has state (x_r, y_r, θ_r, q_r¹…q_r⁶) and inputs (v_r, ω_r,
//! u_r¹…u_r⁶): x' = v cos θ, y' = v sin θ, θ' = ω, q_a' = u_a. (x, y) is the
//! midpoint of the drive-wheel axle, on the ground.
//!
//! Frames (shared with `models/mobile_manipulator.urdf`): `base_link` at
//! (x, y, 0) turned by θ; the arm's DH frame 0 at `MobileManipulator::mount`
//! in `base_link`; URDF links `link1`…`link6` as in [`crate::robots::mobile_manipulator::puma560`]; `tool`
//! fixed to the flange (DH frame 6) with the grasp point on its z axis.
//!
//! Every rigid body is covered by ellipsoids ([`Part`]): seed 004 §III
//! represents the robot as a union of ellipsoids and gives each body its own
//! workspace copy; here each ellipsoid is its own "part" (§III-A's groups
//! R^{p_m}, which also fix a body's orientation through several points). The
//! cover must contain the URDF collision shapes, which the tests check.

use crate::model::spatial::{self, k, Pose, Scalar};
use crate::model::{Input, KinematicModel, State};
use crate::robots::mobile_manipulator::ellipsoid::Superellipsoid;
use crate::robots::mobile_manipulator::puma560;
use nalgebra::DMatrix;

/// Which rigid body a part or a collision shape belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Link {
    /// The platform (`base_link`, with the pedestal).
    Base,
    /// Arm link 1..=6 (URDF `link<i>`).
    Arm(u8),
    /// The gripper (`tool`), fixed to the flange.
    Tool,
}

impl Link {
    /// URDF link name.
    pub fn urdf_name(self) -> &'static str {
        match self {
            Link::Base => "base_link",
            Link::Arm(1) => "link1",
            Link::Arm(2) => "link2",
            Link::Arm(3) => "link3",
            Link::Arm(4) => "link4",
            Link::Arm(5) => "link5",
            Link::Arm(_) => "link6",
            Link::Tool => "tool",
        }
    }
}

/// One ellipsoid of a robot's cover, in its link's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// Name (unique within a robot), used in logs and messages.
    pub name: &'static str,
    /// The body it moves with.
    pub link: Link,
    /// The ellipsoid (n = 1), in the link frame.
    pub shape: Superellipsoid,
}

/// A simple collision shape of the URDF, in its link frame (for clearance checks
/// in the ideal run and the cover test).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CollisionShape {
    /// Box: centre, half extents (axis-aligned in the link frame).
    Cuboid {
        /// Centre.
        center: [f64; 3],
        /// Half extents.
        half: [f64; 3],
    },
    /// Cylinder: centre, axis (unit, link frame), radius, half length.
    Cylinder {
        /// Centre.
        center: [f64; 3],
        /// Unit axis.
        axis: [f64; 3],
        /// Radius.
        radius: f64,
        /// Half length.
        half_length: f64,
    },
    /// Sphere.
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius.
        radius: f64,
    },
}

impl CollisionShape {
    /// Points on the shape's boundary (corners, rims, extreme points): enough
    /// to test that a convex set contains the shape.
    pub fn hull_points(&self) -> Vec<[f64; 3]> {
        match *self {
            CollisionShape::Cuboid { center, half } => (0..8)
                .map(|i| {
                    std::array::from_fn(|k| {
                        center[k] + if (i >> k) & 1 == 1 { half[k] } else { -half[k] }
                    })
                })
                .collect(),
            CollisionShape::Cylinder {
                center,
                axis,
                radius,
                half_length,
            } => {
                let a = if axis[0].abs() < 0.9 {
                    [1.0, 0.0, 0.0]
                } else {
                    [0.0, 1.0, 0.0]
                };
                let u = normalize(cross(axis, a));
                let v = cross(axis, u);
                let mut out = Vec::new();
                for s in [-1.0, 1.0] {
                    for i in 0..32 {
                        let t = std::f64::consts::TAU * i as f64 / 32.0;
                        out.push(std::array::from_fn(|k| {
                            center[k]
                                + s * half_length * axis[k]
                                + radius * (t.cos() * u[k] + t.sin() * v[k])
                        }));
                    }
                }
                out
            }
            CollisionShape::Sphere { center, radius } => {
                let mut out = Vec::new();
                for i in 0..=12 {
                    let th = std::f64::consts::PI * i as f64 / 12.0;
                    for j in 0..24 {
                        let ph = std::f64::consts::TAU * j as f64 / 24.0;
                        out.push([
                            center[0] + radius * th.sin() * ph.cos(),
                            center[1] + radius * th.sin() * ph.sin(),
                            center[2] + radius * th.cos(),
                        ]);
                    }
                }
                out
            }
        }
    }
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn normalize(v: [f64; 3]) -> [f64; 3] {
    let n = spatial::norm(v);
    spatial::scale(v, 1.0 / n)
}

/// Wheel radius of the differential drive, m.
pub const WHEEL_RADIUS: f64 = 0.1;
/// Half the track width (axle centre to each wheel), m.
pub const HALF_TRACK: f64 = 0.32;
/// The arm's DH frame 0 (the shoulder) in `base_link`, m.
pub const MOUNT: [f64; 3] = [0.3, 0.0, 0.95];
/// The grasp point on the tool's z axis, from the flange, m.
pub const GRASP_OFFSET: f64 = 0.16;

const A2: f64 = puma560::DH[1].a;
const A3: f64 = puma560::DH[2].a;
const D3: f64 = puma560::DH[2].d;
const D4: f64 = puma560::DH[3].d;

/// The URDF's collision shapes (all links of one robot but the wheels, which
/// are [`Link::Base`] spheres here since they only spin about their axle).
pub(crate) fn collision_shapes() -> Vec<(Link, CollisionShape)> {
    use CollisionShape::*;
    let x = [1.0, 0.0, 0.0];
    let y = [0.0, 1.0, 0.0];
    let z = [0.0, 0.0, 1.0];
    vec![
        (
            Link::Base,
            Cuboid {
                center: [0.0, 0.0, 0.23],
                half: [0.45, 0.3, 0.15],
            },
        ),
        (
            Link::Base,
            Cylinder {
                center: [MOUNT[0], 0.0, 0.615],
                axis: z,
                radius: 0.08,
                half_length: 0.235,
            },
        ),
        (
            Link::Base,
            Sphere {
                center: [0.35, 0.0, 0.05],
                radius: 0.05,
            },
        ),
        (
            Link::Base,
            Sphere {
                center: [-0.35, 0.0, 0.05],
                radius: 0.05,
            },
        ),
        (
            Link::Base,
            Sphere {
                center: [0.0, HALF_TRACK, WHEEL_RADIUS],
                radius: WHEEL_RADIUS,
            },
        ),
        (
            Link::Base,
            Sphere {
                center: [0.0, -HALF_TRACK, WHEEL_RADIUS],
                radius: WHEEL_RADIUS,
            },
        ),
        (
            Link::Arm(1),
            Cylinder {
                center: [0.0, 0.0, -0.01],
                axis: z,
                radius: 0.1,
                half_length: 0.11,
            },
        ),
        (
            Link::Arm(2),
            Cylinder {
                center: [0.5 * A2, 0.0, D3],
                axis: x,
                radius: 0.06,
                half_length: 0.5 * A2,
            },
        ),
        (
            Link::Arm(3),
            Cylinder {
                center: [A3, 0.17, D3],
                axis: y,
                radius: 0.05,
                half_length: 0.17,
            },
        ),
        (
            Link::Arm(4),
            Cylinder {
                center: [0.0, 0.0, D4 - 0.07],
                axis: z,
                radius: 0.045,
                half_length: 0.06,
            },
        ),
        (
            Link::Arm(5),
            Sphere {
                center: [0.0; 3],
                radius: 0.05,
            },
        ),
        (
            Link::Arm(6),
            Cylinder {
                center: [0.0, 0.0, 0.03],
                axis: z,
                radius: 0.035,
                half_length: 0.03,
            },
        ),
        (
            Link::Tool,
            Cuboid {
                center: [0.0, 0.0, 0.08],
                half: [0.03, 0.055, 0.02],
            },
        ),
        (
            Link::Tool,
            Cuboid {
                center: [0.0, 0.045, 0.15],
                half: [0.01, 0.0075, 0.05],
            },
        ),
        (
            Link::Tool,
            Cuboid {
                center: [0.0, -0.045, 0.15],
                half: [0.01, 0.0075, 0.05],
            },
        ),
    ]
}

/// The default ellipsoid cover of one robot (n = 1 ellipsoids in link frames).
pub fn default_parts() -> Vec<Part> {
    let e = Superellipsoid::ellipsoid;
    vec![
        Part {
            name: "platform",
            link: Link::Base,
            shape: e([0.0, 0.0, 0.2], [0.8, 0.55, 0.33]),
        },
        Part {
            name: "column",
            link: Link::Base,
            shape: e([MOUNT[0], 0.0, 0.72], [0.15, 0.15, 0.48]),
        },
        Part {
            name: "upper_arm",
            link: Link::Arm(2),
            shape: e([0.5 * A2, 0.0, D3], [0.36, 0.095, 0.095]),
        },
        Part {
            name: "forearm",
            link: Link::Arm(3),
            shape: e([A3, 0.17, D3], [0.08, 0.26, 0.08]),
        },
        Part {
            name: "wrist",
            link: Link::Arm(5),
            shape: e([0.0; 3], [0.14; 3]),
        },
        Part {
            name: "gripper",
            link: Link::Tool,
            shape: e([0.0, 0.0, 0.13], [0.07, 0.11, 0.11]),
        },
        Part {
            name: "finger",
            link: Link::Tool,
            shape: e([0.0, 0.045, 0.15], [0.03, 0.03, 0.07]),
        },
    ]
}

/// The passive wrist between a robot's flange and its gripper (ours; seed
/// 004 grasps rigidly).
///
/// A compliant wrist is a six-axis spring–damper whose centre of compliance
/// is the grasp point ([`GRASP_OFFSET`] on the tool's z axis), its axes the
/// tool frame's: a remote-centre-compliance device, so a force at the grasp
/// translates the gripper without turning it and a moment turns it about
/// the grasp point. Each axis has its own stiffness, damping and travel (a
/// hard stop at ± travel).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Wrist {
    /// The gripper is fixed to the flange (the paper's rigid grasp).
    #[default]
    Rigid,
    /// A spring–damper per axis ([`CompliantWrist`]).
    Compliant(CompliantWrist),
}

/// Per-axis spring, damper and travel of a compliant [`Wrist`], in the tool
/// frame at the grasp point: translations x, y, z (N/m, N s/m, m), then
/// rotations about x, y, z (N m/rad, N m s/rad, rad).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompliantWrist {
    /// Stiffness per axis (> 0).
    pub stiffness: [f64; 6],
    /// Damping per axis (≥ 0).
    pub damping: [f64; 6],
    /// Travel per axis, each way (> 0).
    pub travel: [f64; 6],
}

impl CompliantWrist {
    /// The wrench (force, moment about the grasp point; tool axes) the
    /// spring–damper exerts on the gripper at deflection `x` (the gripper's
    /// translation and small rotation from the flange's rest pose, tool axes)
    /// and deflection rate `v`: −K x − D v per axis (the closed form the
    /// physics joint reproduces).
    pub fn wrench(&self, x: [f64; 6], v: [f64; 6]) -> [f64; 6] {
        std::array::from_fn(|i| -self.stiffness[i] * x[i] - self.damping[i] * v[i])
    }

    /// The 6 × 6 stiffness (translations, then rotations, about the grasp
    /// point) in the axes of a frame whose axes, in tool coordinates, are
    /// the columns of `r`: Rᵀ K R per 3 × 3 block.
    pub fn stiffness_in(&self, r: &spatial::M3<f64>) -> nalgebra::SMatrix<f64, 6, 6> {
        let r = nalgebra::Matrix3::from_fn(|i, j| r[i][j]);
        let block = |k: &[f64]| {
            r.transpose()
                * nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::from_column_slice(k))
                * r
        };
        let mut m = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        m.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&block(&self.stiffness[..3]));
        m.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&block(&self.stiffness[3..]));
        m
    }

    /// Why the wrist is unusable, if it is: `(field, message)`.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let ok = |v: &[f64; 6], zero: bool| {
            v.iter()
                .all(|x| x.is_finite() && (*x > 0.0 || zero && *x == 0.0))
        };
        if !ok(&self.stiffness, false) {
            return Err((
                "stiffness",
                format!(
                    "every axis must be > 0 (N/m, N m/rad), got {}",
                    crate::numfmt::list(&self.stiffness)
                ),
            ));
        }
        if !ok(&self.damping, true) {
            return Err((
                "damping",
                format!(
                    "every axis must be ≥ 0 (N s/m, N m s/rad), got {}",
                    crate::numfmt::list(&self.damping)
                ),
            ));
        }
        if !ok(&self.travel, false) {
            return Err((
                "travel",
                format!(
                    "every axis must be > 0 (m, rad), got {}",
                    crate::numfmt::list(&self.travel)
                ),
            ));
        }
        if self.travel[3..]
            .iter()
            .any(|t| *t >= std::f64::consts::FRAC_PI_2)
        {
            return Err((
                "travel",
                format!(
                    "rotational travel must be below 90° (rad), got {}",
                    crate::numfmt::list(&self.travel[3..])
                ),
            ));
        }
        Ok(())
    }
}

/// World poses of one robot's bodies.
#[derive(Debug, Clone, Copy)]
pub struct RobotFrames<T: Scalar> {
    /// `base_link`.
    pub base: Pose<T>,
    /// URDF `link1`…`link6`.
    pub arm: [Pose<T>; 6],
    /// `tool` (= the flange, DH frame 6).
    pub tool: Pose<T>,
}

impl<T: Scalar> RobotFrames<T> {
    /// Pose of a body.
    pub fn link(&self, l: Link) -> &Pose<T> {
        match l {
            Link::Base => &self.base,
            Link::Arm(i) => &self.arm[(i as usize).clamp(1, 6) - 1],
            Link::Tool => &self.tool,
        }
    }
}

/// Forward kinematics of one robot from its 9 coordinates.
pub fn frames<T: Scalar>(q: &[T]) -> RobotFrames<T> {
    let base = Pose {
        r: spatial::rot_z(q[2]),
        p: [q[0], q[1], k(0.0)],
    };
    let arm0 = base.then(&Pose::translation(spatial::lift(MOUNT)));
    let f = puma560::frames(&arm0, &q[3..9]);
    RobotFrames {
        base,
        arm: [f[0], f[1], f[2], f[3], f[4], f[5]],
        tool: f[6],
    }
}

/// The grasp point (world) of one robot.
pub(crate) fn grasp_point<T: Scalar>(q: &[T]) -> [T; 3] {
    frames(q)
        .tool
        .apply(spatial::lift([0.0, 0.0, GRASP_OFFSET]))
}

/// k mobile manipulators (Eq. 1).
#[derive(Debug, Clone)]
pub struct MobileManipulator {
    /// Number of robots k (1 or 2).
    pub robots: usize,
}

const STATE_1: [&str; 9] = ["x", "y", "theta", "q1", "q2", "q3", "q4", "q5", "q6"];
const INPUT_1: [&str; 8] = ["v", "omega", "u1", "u2", "u3", "u4", "u5", "u6"];
const STATE_2: [&str; 18] = [
    "x1", "y1", "theta1", "q1_1", "q1_2", "q1_3", "q1_4", "q1_5", "q1_6", "x2", "y2", "theta2",
    "q2_1", "q2_2", "q2_3", "q2_4", "q2_5", "q2_6",
];
const INPUT_2: [&str; 16] = [
    "v1", "omega1", "u1_1", "u1_2", "u1_3", "u1_4", "u1_5", "u1_6", "v2", "omega2", "u2_1", "u2_2",
    "u2_3", "u2_4", "u2_5", "u2_6",
];
const ANGULAR_1: [usize; 7] = [2, 3, 4, 5, 6, 7, 8];
const ANGULAR_2: [usize; 14] = [2, 3, 4, 5, 6, 7, 8, 11, 12, 13, 14, 15, 16, 17];

/// Coordinates per robot.
pub const DOF: usize = 9;
/// Inputs per robot.
pub const INPUTS: usize = 8;

/// Numbers per robot in the physics' measurement: the flange's (link 6's)
/// world position, then its rotation matrix row by row.
pub const FLANGE_MEASUREMENT: usize = 12;

/// Robot `r`'s flange pose in a measurement of [`FLANGE_MEASUREMENT`]
/// numbers per robot.
pub fn flange_from_measurement(measured: &[f64], r: usize) -> Pose<f64> {
    let m = &measured[FLANGE_MEASUREMENT * r..FLANGE_MEASUREMENT * (r + 1)];
    Pose {
        p: [m[0], m[1], m[2]],
        r: std::array::from_fn(|i| std::array::from_fn(|j| m[3 + 3 * i + j])),
    }
}

impl KinematicModel for MobileManipulator {
    fn name(&self) -> &'static str {
        "mobile_manipulator"
    }
    fn state_names(&self) -> &'static [&'static str] {
        if self.robots == 2 {
            &STATE_2
        } else {
            &STATE_1
        }
    }
    fn input_names(&self) -> &'static [&'static str] {
        if self.robots == 2 {
            &INPUT_2
        } else {
            &INPUT_1
        }
    }
    fn angular_states(&self) -> &'static [usize] {
        if self.robots == 2 {
            &ANGULAR_2
        } else {
            &ANGULAR_1
        }
    }
    fn position_states(&self) -> Option<[usize; 2]> {
        Some([0, 1])
    }
    fn robot_positions(&self) -> Vec<[usize; 2]> {
        (0..self.robots).map(|r| [DOF * r, DOF * r + 1]).collect()
    }
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        let mut g = DMatrix::zeros(DOF * self.robots, INPUTS * self.robots);
        for r in 0..self.robots {
            let (i, j) = (DOF * r, INPUTS * r);
            let th = q[i + 2];
            g[(i, j)] = th.cos();
            g[(i + 1, j)] = th.sin();
            g[(i + 2, j + 1)] = 1.0;
            for a in 0..6 {
                g[(i + 3 + a, j + 2 + a)] = 1.0;
            }
        }
        g
    }
    fn velocity(&self, _t: f64, q: &State, u: &Input) -> State {
        let mut dq = State::zeros(q.len());
        for r in 0..self.robots {
            let (i, j) = (DOF * r, INPUTS * r);
            let th = q[i + 2];
            dq[i] = u[j] * th.cos();
            dq[i + 1] = u[j] * th.sin();
            dq[i + 2] = u[j + 1];
            for a in 0..6 {
                dq[i + 3 + a] = u[j + 2 + a];
            }
        }
        dq
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cover_contains_every_collision_shape() {
        // In the world at random configurations: a part may cover a body it is
        // not attached to (the column covers link 1, symmetric about its axis).
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(8);
        let parts = default_parts();
        for _ in 0..20 {
            let q: Vec<f64> = (0..9).map(|_| rng.random_range(-3.0..3.0)).collect();
            let f = frames::<f64>(&q);
            let placed: Vec<_> = parts
                .iter()
                .map(|p| p.shape.placed(f.link(p.link)))
                .collect();
            for (link, shape) in collision_shapes() {
                for p in shape.hull_points() {
                    let w = f.link(link).apply(p);
                    let inside = placed.iter().any(|e| e.value(w) <= 0.0);
                    assert!(
                        inside,
                        "{link:?} point {p:?} of {shape:?} is outside the cover"
                    );
                }
            }
        }
    }

    #[test]
    fn velocity_is_g_times_u() {
        let m = MobileManipulator { robots: 2 };
        let q = State::from_fn(18, |i, _| 0.1 * i as f64 - 0.4);
        let u = Input::from_fn(16, |i, _| 0.3 - 0.05 * i as f64);
        let a = m.velocity(0.0, &q, &u);
        let b = m.input_matrix(&q) * &u;
        assert!((a - b).amax() < 1e-15);
    }

    #[test]
    fn grasp_point_moves_with_the_platform() {
        let mut q = [0.0; 9];
        q[3..9].copy_from_slice(&[0.3, -0.8, 2.0, 0.1, -0.5, 0.2]);
        let g0 = grasp_point::<f64>(&q);
        q[0] = 1.0;
        q[1] = -2.0;
        let g1 = grasp_point::<f64>(&q);
        assert!((g1[0] - g0[0] - 1.0).abs() < 1e-12 && (g1[1] - g0[1] + 2.0).abs() < 1e-12);
    }
}
