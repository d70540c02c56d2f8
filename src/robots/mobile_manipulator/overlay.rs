//! What the logs and metrics of the dilf system draw and measure besides
//! the planner: obstacle and ellipsoid wireframes, and the clearance of the
//! ideal run (the URDF collision shapes placed by forward kinematics, and
//! the carried beam's FE centreline, against the obstacles' convex hulls:
//! the same parry queries as the physics channel).

use crate::engine::rapier::parry::bounding_volume::Aabb;
use crate::engine::rapier::parry::shape::{
    Ball, Capsule, ConvexPolyhedron, Cuboid, Cylinder, Shape,
};
use crate::engine::rapier::prelude::Vector;
use crate::engine::real as rl;
use crate::record::Overlay;
use crate::robots::mobile_manipulator::dilf::object::Carried;
use crate::robots::mobile_manipulator::ellipsoid::Superellipsoid;
use crate::robots::mobile_manipulator::kinematics::{self as mm, CollisionShape, Link};

/// Three principal rings and two latitude rings of a shape, as overlays.
pub(super) fn wireframe(
    name: &str,
    s: &Superellipsoid,
    link: Option<&str>,
    rgba: [f32; 4],
) -> Vec<Overlay> {
    let placed = s.at_rest();
    let e = 1.0 / s.exponent;
    let sp = |c: f64| c.signum() * c.abs().powf(e);
    let ring = |f: &dyn Fn(f64) -> [f64; 3]| -> Vec<[f64; 3]> {
        (0..=48)
            .map(|i| placed.to_world(f(std::f64::consts::TAU * i as f64 / 48.0)))
            .collect()
    };
    let [a, b, c] = s.semi_axes;
    let mut rings: Vec<Vec<[f64; 3]>> = vec![
        ring(&|t| [a * sp(t.cos()), b * sp(t.sin()), 0.0]),
        ring(&|t| [a * sp(t.cos()), 0.0, c * sp(t.sin())]),
        ring(&|t| [0.0, b * sp(t.cos()), c * sp(t.sin())]),
    ];
    for lat in [-0.6f64, 0.6] {
        let (cl, sl) = (sp(lat.cos()), sp(lat.sin()));
        rings.push(ring(&|t| {
            [a * cl * sp(t.cos()), b * cl * sp(t.sin()), c * sl]
        }));
    }
    rings
        .into_iter()
        .enumerate()
        .map(|(k, points)| Overlay {
            name: format!("{name}_{k}"),
            points,
            link: link.map(String::from),
            rgba,
        })
        .collect()
}

/// Distances between the robot's URDF collision shapes (placed by forward
/// kinematics) and the obstacle colliders (the same convex hulls the physics
/// uses), for the ideal run.
pub(super) struct ClearanceProbe {
    obstacles: Vec<(ConvexPolyhedron, Aabb)>,
    links: Vec<(Link, Box<dyn Shape>, crate::model::spatial::Pose<f64>)>,
}

impl ClearanceProbe {
    pub(super) fn new(obstacles: &[(String, Superellipsoid)]) -> Self {
        use crate::model::spatial::{rot_x, rot_y, Pose};
        let obstacles = obstacles
            .iter()
            .filter_map(|(_, s)| {
                let (v, _) = s.mesh(16, 32);
                let pts: Vec<Vector> = v.iter().map(|p| rl::vector(p[0], p[1], p[2])).collect();
                let hull = ConvexPolyhedron::from_convex_hull(&pts)?;
                let aabb = hull.local_aabb();
                Some((hull, aabb))
            })
            .collect();
        let links = mm::collision_shapes()
            .into_iter()
            .map(|(link, shape)| -> (Link, Box<dyn Shape>, Pose<f64>) {
                match shape {
                    CollisionShape::Cuboid { center, half } => (
                        link,
                        Box::new(Cuboid::new(rl::vector(half[0], half[1], half[2]))),
                        Pose::translation(center),
                    ),
                    CollisionShape::Sphere { center, radius } => (
                        link,
                        Box::new(Ball::new(rl::r(radius))),
                        Pose::translation(center),
                    ),
                    CollisionShape::Cylinder {
                        center,
                        axis,
                        radius,
                        half_length,
                    } => {
                        // parry cylinders run along their local y axis.
                        let r = if axis[0].abs() > 0.5 {
                            rot_z_f(-std::f64::consts::FRAC_PI_2)
                        } else if axis[2].abs() > 0.5 {
                            rot_x(std::f64::consts::FRAC_PI_2)
                        } else {
                            rot_y(0.0)
                        };
                        (
                            link,
                            Box::new(Cylinder::new(rl::r(half_length), rl::r(radius))),
                            Pose { r, p: center },
                        )
                    }
                }
            })
            .collect();
        ClearanceProbe { obstacles, links }
    }

    /// Least distance at configuration q (every robot), m.
    /// Least distance at configuration q (every robot, and the beam's FE
    /// centreline when two robots carry one), m.
    pub(super) fn clearance(&self, q: &[f64], beam: Option<&Carried>) -> f64 {
        let robots = q
            .chunks(mm::DOF)
            .map(|r| self.clearance_one(r))
            .fold(f64::INFINITY, f64::min);
        beam.map_or(robots, |b| robots.min(self.beam_clearance(q, b)))
    }

    fn clearance_one(&self, q: &[f64]) -> f64 {
        let f = mm::frames::<f64>(q);
        let placed = self.links.iter().map(|(link, shape, local)| {
            (shape.as_ref(), rl::from_spatial(&f.link(*link).then(local)))
        });
        self.nearest(placed)
    }

    /// The rod (its true radius) as capsules along the FE model's deformed
    /// centreline, one per beam ellipsoid.
    fn beam_clearance(&self, q: &[f64], beam: &Carried) -> f64 {
        let st = beam.state::<f64>(q);
        let b = beam.fe.beam();
        let half = 0.5 * b.length / beam.segments as f64;
        let rod = Capsule::new(
            rl::vector(-half, 0.0, 0.0),
            rl::vector(half, 0.0, 0.0),
            rl::r(0.5 * b.section.outer_diameter),
        );
        let poses: Vec<_> = beam
            .ellipsoids(&st)
            .iter()
            .map(|e| {
                rl::from_spatial(&crate::model::spatial::Pose {
                    r: e.rot,
                    p: e.center,
                })
            })
            .collect();
        self.nearest(poses.into_iter().map(|p| (&rod as &dyn Shape, p)))
    }

    /// Least distance between any placed shape and any obstacle hull.
    fn nearest<'a>(
        &self,
        placed: impl Iterator<Item = (&'a dyn Shape, crate::engine::rapier::math::Pose)>,
    ) -> f64 {
        let mut best = f64::INFINITY;
        let id = crate::engine::rapier::math::Pose::IDENTITY;
        for (shape, pose) in placed {
            let aabb = shape.compute_aabb(&pose);
            for (hull, ob) in &self.obstacles {
                let d = (aabb.mins - ob.maxs)
                    .max(ob.mins - aabb.maxs)
                    .max(Vector::ZERO);
                if rl::f(d.length()) >= best {
                    continue;
                }
                if let Ok(d) =
                    crate::engine::rapier::parry::query::distance(&pose, shape, &id, hull)
                {
                    best = best.min(rl::f(d.distance));
                }
            }
        }
        best
    }
}

fn rot_z_f(a: f64) -> crate::model::spatial::M3<f64> {
    crate::model::spatial::rot_z(a)
}
