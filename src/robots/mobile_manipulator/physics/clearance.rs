//! Clearances and contacts of the mobile manipulators' physics world: the
//! least distance to the obstacles and between the robots (parry queries
//! behind an AABB cut), and the contact pairs that count as collisions.

use super::{MobileManipulatorPhysics, RobotBodies};
use crate::engine::rapier::prelude::*;
use crate::engine::real::f;

impl MobileManipulatorPhysics {
    pub(super) fn refresh_clearances(&mut self) {
        self.clearance = self.min_clearance();
        if self.robots.len() == 2 {
            self.robot_clearance = self.robot_robot_clearance();
        }
    }

    /// Least distance between any robot or beam collider and any obstacle
    /// (m); 0 when touching or overlapping.
    pub fn min_clearance(&self) -> f64 {
        let cs = &self.sim.world.colliders;
        let beam = self.beam.iter().flat_map(|b| b.colliders().iter().copied());
        let moving = self
            .robots
            .iter()
            .flat_map(|r| r.colliders.iter().copied())
            .chain(beam);
        let obstacles: Vec<(ColliderHandle, Aabb)> = self
            .obstacles
            .iter()
            .copied()
            .zip(self.obstacle_aabbs.iter().copied())
            .collect();
        least_distance(cs, &with_aabbs(cs, moving), &obstacles)
    }

    /// Least distance between the two robots' colliders (m).
    pub fn robot_robot_clearance(&self) -> f64 {
        let cs = &self.sim.world.colliders;
        let set = |r: &RobotBodies| with_aabbs(cs, r.colliders.iter().copied());
        least_distance(cs, &set(&self.robots[0]), &set(&self.robots[1]))
    }

    /// Collider pairs in contact that are collisions, obstacles aside: robot
    /// against robot, the beam against a platform or the ground, any robot
    /// body but a wheel or caster on the ground.
    pub fn body_contacts(&self) -> usize {
        let ground = self.sim.ground_collider;
        let rolling = |c: ColliderHandle| self.robots.iter().any(|r| r.rolling.contains(&c));
        self.sim
            .world
            .narrow_phase
            .contact_pairs()
            .filter(|p| p.has_any_active_contact())
            .filter(|p| {
                let (a, b) = (p.collider1, p.collider2);
                let obstacle = self.obstacles.contains(&a) || self.obstacles.contains(&b);
                let on_ground = Some(a) == ground && rolling(b) || Some(b) == ground && rolling(a);
                !obstacle && !on_ground
            })
            .count()
    }

    /// Robot– and beam–obstacle collider pairs with an active contact.
    pub fn obstacle_contacts(&self) -> usize {
        self.obstacles
            .iter()
            .map(|o| {
                self.sim
                    .world
                    .narrow_phase
                    .contact_pairs_with(*o)
                    .filter(|p| p.has_any_active_contact())
                    .count()
            })
            .sum()
    }
}

/// Colliders with their current world AABBs.
fn with_aabbs(
    cs: &ColliderSet,
    colliders: impl Iterator<Item = ColliderHandle>,
) -> Vec<(ColliderHandle, Aabb)> {
    colliders.map(|c| (c, cs[c].compute_aabb())).collect()
}

/// Least distance (m, parry queries) between any collider of `a` and any of
/// `b`; pairs whose AABBs are farther apart than the best so far are skipped.
fn least_distance(
    cs: &ColliderSet,
    a: &[(ColliderHandle, Aabb)],
    b: &[(ColliderHandle, Aabb)],
) -> f64 {
    let mut best = f64::INFINITY;
    for (ca, ba) in a {
        for (cb, bb) in b {
            let gap = (ba.mins - bb.maxs).max(bb.mins - ba.maxs).max(Vector::ZERO);
            if f(gap.length()) >= best {
                continue;
            }
            let (x, y) = (&cs[*ca], &cs[*cb]);
            if let Ok(d) = crate::engine::rapier::parry::query::distance(
                x.position(),
                x.shape(),
                y.position(),
                y.shape(),
            ) {
                best = best.min(f(d.distance));
            }
        }
    }
    best
}
