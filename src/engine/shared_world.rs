//! The thread's shared world while a batch builds its systems
//! ([`crate::engine::batch::Host::build`]): [`SimWorld::new`](crate::engine::world::SimWorld::new)
//! looks here and inserts its robot into the batch's world instead of a
//! fresh one. Plain data and two functions, so that the world loader and
//! the batch both depend on this, not on each other.

use crate::engine::rapier::prelude::*;
use crate::engine::PhysicsSettings;
use std::cell::RefCell;

/// Most robots in one batch world: collision groups are 32 bits, one is the
/// ground's.
pub const MAX_ROBOTS: usize = 31;

/// What must agree for two robots to share a world.
#[derive(Debug, Clone, PartialEq)]
pub struct WorldKey {
    dt: f64,
    solver_iterations: usize,
    pgs_iterations: usize,
    relax_pass: bool,
    gravity: [f64; 3],
    ground: bool,
}

impl WorldKey {
    /// The key of a world with settings `s`, with or without a ground.
    pub fn of(s: &PhysicsSettings, ground: bool) -> WorldKey {
        WorldKey {
            dt: s.dt,
            solver_iterations: s.solver_iterations,
            pgs_iterations: s.pgs_iterations,
            relax_pass: s.relax_pass.unwrap_or(ground),
            gravity: s.gravity,
            ground,
        }
    }
}

/// The shared world between builds, with its ground.
pub type Shared = (Box<PhysicsWorld>, RigidBodyHandle, Option<ColliderHandle>);

/// The thread-local slot [`SimWorld::new`](crate::engine::world::SimWorld::new) looks in while `Host::build` runs.
pub struct Slot {
    /// What the world's robots agreed on.
    pub key: Option<WorldKey>,
    /// The shared world, between builds.
    pub world: Option<Shared>,
    /// Collision group index of the next robot.
    pub group: usize,
    /// Set by [`join`]: the robot joined (a fresh world when `world` was None).
    pub joined: bool,
}

thread_local! {
    /// This thread's slot: the world the next robot built here joins.
    pub static SLOT: RefCell<Option<Slot>> = const { RefCell::new(None) };
}

/// Empties this thread's slot when dropped.
pub struct ClearSlot;

impl Drop for ClearSlot {
    fn drop(&mut self) {
        SLOT.with(|s| s.borrow_mut().take());
    }
}

/// For [`SimWorld::new`](crate::engine::world::SimWorld::new): `None` outside a batch build (or when the robot
/// cannot join this batch: other world settings, or no collision group
/// left), then it builds a world of its own; `Some(None)` for the batch's
/// first robot (a fresh world that becomes the shared one); `Some(Some(w))`
/// to insert the robot into the shared world.
pub fn join(settings: &PhysicsSettings, ground: bool) -> Option<Option<Shared>> {
    SLOT.with(|slot| {
        let mut slot = slot.borrow_mut();
        let slot = slot.as_mut()?;
        let key = WorldKey::of(settings, ground);
        if slot.joined || slot.group >= MAX_ROBOTS || slot.key.as_ref().is_some_and(|k| *k != key) {
            return None;
        }
        slot.key = Some(key);
        slot.joined = true;
        Some(slot.world.take())
    })
}

/// For [`SimWorld::new`](crate::engine::world::SimWorld::new) after inserting a joining robot: its own collision
/// group (the ground stays in group 1 and meets everyone), and ground
/// friction at least the robot's (contacts take the smaller coefficient, so
/// each robot keeps its own).
pub(crate) fn keep_apart(
    world: &mut PhysicsWorld,
    colliders: &[ColliderHandle],
    ground: Option<ColliderHandle>,
    friction: f64,
) {
    let group = SLOT.with(|slot| slot.borrow().as_ref().map_or(0, |s| s.group));
    let bit = Group::from_bits_truncate(1 << (group + 1));
    let mine = InteractionGroups::new(bit, bit | Group::GROUP_1, InteractionTestMode::And);
    for c in colliders {
        if let Some(c) = world.colliders.get_mut(*c) {
            c.set_collision_groups(mine);
        }
    }
    if let Some(g) = ground.and_then(|g| world.colliders.get_mut(g)) {
        g.set_collision_groups(InteractionGroups::new(
            Group::GROUP_1,
            Group::ALL,
            InteractionTestMode::And,
        ));
        if g.friction() < friction {
            g.set_friction(friction);
        }
    }
}
