//! Fixed obstacles (boxes and vertical cylinders) in the world of any robot
//! built on a [`SimWorld`], and what the logs and metrics read from them:
//! the least distance between the robot's colliders and the obstacles
//! (parry distance queries, as the mobile manipulator measures its
//! clearance), the number of robot–obstacle contact pairs, and wireframes.
//!
//! [`WithObstacles`] wraps a model's physics, so one `[[model.obstacles]]`
//! table means the same solid for every wheeled model.

pub mod config;

use crate::engine::rapier::prelude::*;
use crate::engine::real::{f, r, vector};
use crate::engine::world::{origin, SimWorld};
use crate::engine::PhysicsSystem;
use crate::error::SetupError;
use crate::model::{Input, State};
use crate::record::{Overlay, Pose};

/// Names of the channels [`WithObstacles`] adds.
pub const CHANNELS: [&str; 2] = ["obstacle_clearance", "obstacle_contacts"];

/// Colliders closer than this (m) touch.
const TOUCH: f64 = 1e-4;

/// The solid of an obstacle, in its own frame (centred on its origin).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Solid {
    /// A box of these half extents along its x, y, z, m.
    Box {
        /// Half extents, m.
        half: [f64; 3],
    },
    /// A cylinder about its z axis.
    Cylinder {
        /// Radius, m.
        radius: f64,
        /// Half height, m.
        half_height: f64,
    },
}

/// One fixed obstacle.
#[derive(Debug, Clone, PartialEq)]
pub struct Obstacle {
    /// Name (logs, messages).
    pub name: String,
    /// Centre in the world, m.
    pub center: [f64; 3],
    /// Orientation, URDF roll-pitch-yaw, rad.
    pub rpy: [f64; 3],
    /// The solid.
    pub solid: Solid,
}

impl Obstacle {
    fn pose(&self) -> crate::engine::rapier::math::Pose {
        origin(&urdf_rs::Pose {
            xyz: urdf_rs::Vec3(self.center),
            rpy: urdf_rs::Vec3(self.rpy),
        })
    }

    fn collider(&self, friction: f64) -> ColliderBuilder {
        let b = match self.solid {
            Solid::Box { half } => ColliderBuilder::cuboid(r(half[0]), r(half[1]), r(half[2])),
            Solid::Cylinder {
                radius,
                half_height,
            } => ColliderBuilder::cylinder(r(half_height), r(radius)),
        };
        // parry's cylinders run along their y axis: turn it onto z.
        let upright = match self.solid {
            Solid::Box { .. } => crate::engine::rapier::math::Pose::IDENTITY,
            Solid::Cylinder { .. } => origin(&urdf_rs::Pose {
                xyz: urdf_rs::Vec3([0.0; 3]),
                rpy: urdf_rs::Vec3([std::f64::consts::FRAC_PI_2, 0.0, 0.0]),
            }),
        };
        b.position(self.pose() * upright).friction(r(friction))
    }

    /// The solid's edges as world-frame polylines (box: two rectangles and
    /// four uprights; cylinder: two rings and four uprights).
    pub fn wireframe(&self, rgba: [f32; 4]) -> Vec<Overlay> {
        let pose = self.pose();
        let world = |p: [f64; 3]| {
            let w = pose.transform_point(vector(p[0], p[1], p[2]));
            [f(w.x), f(w.y), f(w.z)]
        };
        let (ring, hz): (Vec<[f64; 2]>, f64) = match self.solid {
            Solid::Box { half } => {
                let [a, b, c] = half;
                (vec![[a, b], [-a, b], [-a, -b], [a, -b], [a, b]], c)
            }
            Solid::Cylinder {
                radius,
                half_height,
            } => (
                (0..=48)
                    .map(|i| {
                        let t = std::f64::consts::TAU * i as f64 / 48.0;
                        [radius * t.cos(), radius * t.sin()]
                    })
                    .collect(),
                half_height,
            ),
        };
        let mut lines: Vec<Vec<[f64; 3]>> = [-hz, hz]
            .iter()
            .map(|&z| ring.iter().map(|p| world([p[0], p[1], z])).collect())
            .collect();
        let step = (ring.len() - 1) / 4;
        for p in ring.iter().step_by(step.max(1)).take(4) {
            lines.push(vec![world([p[0], p[1], -hz]), world([p[0], p[1], hz])]);
        }
        lines
            .into_iter()
            .enumerate()
            .map(|(k, points)| Overlay {
                name: format!("obstacle_{}_{k}", self.name),
                points,
                link: None,
                rgba,
            })
            .collect()
    }
}

/// A robot's physics with fixed obstacles added to its world, and two more
/// channels: [`CHANNELS`] (least robot–obstacle distance, m, 0 when
/// touching; robot–obstacle collider pairs touching or overlapping).
pub struct WithObstacles {
    inner: Box<dyn PhysicsSystem>,
    obstacles: Vec<ColliderHandle>,
    clearance: f64,
    contacts: usize,
}

impl WithObstacles {
    /// Add `obstacles` to the world of `inner` (which must have a
    /// [`SimWorld`]); `friction` is the robot's (`[sim] friction`). A robot
    /// that starts inside an obstacle (deeper than `TOUCH`) is refused,
    /// naming `start` and the obstacle: the contact solver would push it out
    /// at once, and the run would measure that, not the plan.
    pub fn new(
        mut inner: Box<dyn PhysicsSystem>,
        obstacles: &[Obstacle],
        friction: f64,
    ) -> Result<Self, SetupError> {
        let sw = inner
            .sim_world()
            .ok_or_else(|| SetupError::other("this model's physics cannot hold obstacles"))?;
        let ground = sw.ground;
        let handles: Vec<ColliderHandle> = obstacles
            .iter()
            .map(|o| sw.world.insert_collider(o.collider(friction), Some(ground)))
            .collect();
        if let Some((k, depth)) = overlap(sw, &handles) {
            return Err(SetupError::key(
                "start",
                format!(
                    "the robot starts inside obstacle {} ({} m deep): move the start or the obstacle",
                    crate::echo::code(&obstacles[k].name),
                    crate::numfmt::readable(depth)
                ),
            ));
        }
        let mut me = WithObstacles {
            inner,
            obstacles: handles,
            clearance: f64::INFINITY,
            contacts: 0,
        };
        me.measure();
        Ok(me)
    }

    fn measure(&mut self) {
        let obstacles = self.obstacles.clone();
        let Some(sw) = self.inner.sim_world() else {
            return;
        };
        (self.clearance, self.contacts) = least_distance(sw, &obstacles);
    }
}

/// The first obstacle a robot collider penetrates deeper than [`TOUCH`],
/// and how deep.
fn overlap(sw: &SimWorld, obstacles: &[ColliderHandle]) -> Option<(usize, f64)> {
    let cs = &sw.world.colliders;
    for (k, o) in obstacles.iter().enumerate() {
        for c in &sw.robot.colliders {
            let (x, y) = (&cs[*c], &cs[*o]);
            let contact = crate::engine::rapier::parry::query::contact(
                x.position(),
                x.shape(),
                y.position(),
                y.shape(),
                r(0.0),
            );
            if let Ok(Some(c)) = contact {
                let depth = -f(c.dist);
                if depth > TOUCH {
                    return Some((k, depth));
                }
            }
        }
    }
    None
}

/// Least distance between the robot's colliders and the obstacles, m, and
/// the number of robot–obstacle collider pairs within [`TOUCH`] (from the
/// same queries: Rapier's own contact points are also speculative or
/// recycled from earlier steps); pairs whose bounding boxes are farther
/// apart than that and than the best so far are skipped.
fn least_distance(sw: &SimWorld, obstacles: &[ColliderHandle]) -> (f64, usize) {
    let cs = &sw.world.colliders;
    let boxes: Vec<_> = obstacles
        .iter()
        .map(|h| (*h, cs[*h].compute_aabb()))
        .collect();
    let mut best = f64::INFINITY;
    let mut touching = 0;
    for c in &sw.robot.colliders {
        let a = cs[*c].compute_aabb();
        for (o, b) in &boxes {
            let gap = (a.mins - b.maxs).max(b.mins - a.maxs).max(Vector::ZERO);
            let gap = f(gap.length());
            if gap >= best && gap > TOUCH {
                continue;
            }
            let (x, y) = (&cs[*c], &cs[*o]);
            if let Ok(d) = crate::engine::rapier::parry::query::distance(
                x.position(),
                x.shape(),
                y.position(),
                y.shape(),
            ) {
                best = best.min(f(d.distance));
                touching += usize::from(f(d.distance) <= TOUCH);
            }
        }
    }
    (best, touching)
}

impl PhysicsSystem for WithObstacles {
    fn state(&self) -> State {
        self.inner.state()
    }
    fn apply(&mut self, u: &Input) {
        self.inner.apply(u)
    }
    fn fault(&self) -> Option<crate::engine::Fault> {
        self.inner.fault()
    }
    fn step(&mut self) {
        self.inner.step();
        self.measure();
    }
    fn link_poses(&self) -> Vec<Pose> {
        self.inner.link_poses()
    }
    fn channel_names(&self) -> Vec<String> {
        let mut n = self.inner.channel_names();
        n.extend(CHANNELS.map(String::from));
        n
    }
    fn channels(&self) -> Vec<f64> {
        let mut c = self.inner.channels();
        c.extend([self.clearance, self.contacts as f64]);
        c
    }
    fn measurement(&self) -> Option<Vec<f64>> {
        self.inner.measurement()
    }
    // No `sim_world`: the obstacles belong to this robot's world, so it is
    // never batched into a shared one (where they would meet other robots).
    fn reading(&self) -> crate::engine::reading::UrdfReading {
        self.inner.reading()
    }
}
