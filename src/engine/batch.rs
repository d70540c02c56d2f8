//! Batched stepping: several systems of one kind (the variants of a sweep)
//! in one Rapier world, stepped together, each with its own replay.
//!
//! A world step has a fixed cost besides the per-body and per-constraint
//! work (stage bookkeeping of the island solver, buffer resets, the broad
//! phase); one world holding K robots pays it once instead of K times, and
//! the solver fills its 4-lane SIMD contact chunks across robots.
//!
//! **Same results as alone.** Each robot's colliders get their own collision
//! group (the ground collides with all of them), so robots never touch and
//! the broad phase never pairs them. Rapier's solver orders constraints by
//! colour (constraints of one colour share no body) and solves small colours
//! serially after the large ones; as long as every colour stays below
//! Rapier's "parallel" sizes (64 joints, or 32 SIMD chunks of contacts; the
//! `LAYOUT_REF_WORKERS` layout of rapier 0.36), each robot's constraints are
//! solved in the same order with the same arithmetic as in a world of its
//! own, so every variant's trajectory is bit-identical to its unbatched run
//! ([`capacity`] keeps batches below those sizes; the sweep test
//! `batched_sweep_equals_unbatched` checks it). One assumption more: Rapier
//! puts a pair's second and later contact manifolds, and pairs beyond a
//! colour's capacity, in an overflow colour that it groups across every
//! body of the world, so a robot whose own parts make such contacts could be
//! solved in another order beside other robots. The bit-identity test
//! passes for every batched system (rover, disk, sphere, car, diff drive),
//! which it would not if their contacts went there. Robots that finish early are disabled, which removes their bodies
//! from the solver.
//!
//! **Building.** A system builds its own [`SimWorld`](crate::engine::world::SimWorld) in its constructor;
//! [`Host::build`] runs that constructor with the batch's world parked in a
//! thread-local slot, and [`SimWorld::new`](crate::engine::world::SimWorld::new) inserts the robot there instead
//! of into a fresh world. Between calls the shared world is lent to one
//! system at a time (its [`SimWorld::world`](crate::engine::world::SimWorld::world) box is swapped in and out), so
//! the systems' own code runs unchanged.

use crate::cancel::Cancel;
use crate::engine::rapier::math::Vector;
use crate::engine::rapier::prelude::*;
use crate::engine::shared_world::{ClearSlot, Shared, Slot, WorldKey, MAX_ROBOTS, SLOT};
use crate::engine::{PhysicsSystem, Replay, ReplayError, ReplayOptions};
use crate::plan::Plan;
use crate::record::SimTrajectory;

/// Contacts per colour below Rapier's parallel threshold (32 chunks of 4).
const CONTACTS_PER_COLOR: usize = 124;
/// Joints per colour below Rapier's parallel threshold (64).
const JOINTS_PER_COLOR: usize = 63;

/// How many robots like `sys` can share a world with unchanged results
/// (see the module docs); `None` when the system cannot share one.
pub fn capacity(sys: &mut dyn PhysicsSystem) -> Option<usize> {
    let sw = sys.sim_world()?;
    let w = &sw.world;
    // Within one colour constraints share no body, so a robot puts at most
    // one contact per collider and one joint per dynamic body in a colour.
    let colliders = w.colliders.len() - usize::from(sw.ground_collider.is_some());
    let bodies = w.bodies.iter().filter(|(_, b)| b.is_dynamic()).count();
    let joints_ok = JOINTS_PER_COLOR / bodies.max(1);
    let contacts_ok = CONTACTS_PER_COLOR / colliders.max(1);
    Some(MAX_ROBOTS.min(joints_ok).min(contacts_ok).max(1))
}

/// A batch being built: the shared world and what its robots agreed on.
#[derive(Default)]
pub struct Host {
    world: Option<Shared>,
    key: Option<WorldKey>,
    /// Integration parameters and gravity after the first robot's build.
    params: Option<(IntegrationParameters, Vector)>,
    robots: usize,
    /// A constructor failed after its robot joined: the shared world went
    /// with it, and the robots built before have none.
    lost: bool,
}

/// One system of a batch replay: the system (built by [`Host::build`]),
/// its plan and replay options.
pub struct Lane<'a> {
    /// The hosted system.
    pub sys: &'a mut dyn PhysicsSystem,
    /// Its plan.
    pub plan: &'a Plan,
    /// Its replay options (the step must be the world's), with its command
    /// and observation perturbations (the world ones are in the system already).
    pub opts: ReplayOptions,
}

/// A built system: in the batch's world, or alone (it could not join).
pub enum Built {
    /// Shares the batch's world.
    Hosted(Box<dyn PhysicsSystem>),
    /// Has a world of its own; replay it alone.
    Alone(Box<dyn PhysicsSystem>),
}

impl Host {
    /// A host with no world yet (the first robot built creates it).
    pub fn new() -> Host {
        Host::default()
    }

    /// Robots in the shared world.
    pub fn len(&self) -> usize {
        self.robots
    }

    /// Whether no robot joined yet.
    pub fn is_empty(&self) -> bool {
        self.robots == 0
    }

    /// Whether a failed constructor took the shared world with it: the
    /// hosted systems cannot run and must be rebuilt alone.
    pub fn is_lost(&self) -> bool {
        self.lost
    }

    /// Run `build` (a system constructor) so that the robot it builds joins
    /// the shared world. A system that cannot share a world, or whose
    /// constructor changed the world's integration parameters differently
    /// from the first robot's, comes back [`Built::Alone`] (rebuilt alone in
    /// the latter case).
    pub fn build<E>(
        &mut self,
        mut build: impl FnMut() -> Result<Box<dyn PhysicsSystem>, E>,
    ) -> Result<Built, E> {
        SLOT.with(|s| {
            *s.borrow_mut() = Some(Slot {
                key: self.key.clone(),
                world: self.world.take(),
                group: self.robots,
                joined: false,
            })
        });
        // Emptied on every way out, a panic in `build` included: a slot left
        // behind would host the next world made on this thread, which would
        // then never step.
        let _clear = ClearSlot;
        let res = build();
        let slot = SLOT
            .with(|s| s.borrow_mut().take())
            .expect("slot set above");
        // The world stays parked when the robot did not join.
        self.world = slot.world;
        if res.is_err() && slot.joined && self.robots > 0 {
            self.lost = true;
        }
        let mut sys = res?;
        let hosted = sys.sim_world().is_some_and(|sw| sw.is_hosted());
        if !hosted {
            return Ok(Built::Alone(sys));
        }
        let sw = sys.sim_world().expect("hosted above");
        let mut world = std::mem::replace(&mut sw.world, Box::new(PhysicsWorld::new()));
        let params = (world.integration_parameters, world.gravity);
        match &self.params {
            Some(p) if *p != params => {
                // Undo: the robot leaves, the world gets its settings back.
                world.integration_parameters = p.0;
                world.gravity = p.1;
                for h in sw.robot.links.clone() {
                    world.remove_body(h);
                }
                self.world = Some((world, sw.ground, sw.ground_collider));
                drop(sys);
                return build().map(Built::Alone);
            }
            Some(_) => {}
            None => self.params = Some(params),
        }
        self.key = slot.key;
        self.world = Some((world, sw.ground, sw.ground_collider));
        self.robots += 1;
        Ok(Built::Hosted(sys))
    }

    /// Replay every hosted system on its plan in lockstep: one world step per
    /// step of all running systems, each system's own replay
    /// ([`Replay`]) around it. Results in the order of `lanes`; all
    /// [`ReplayError::Cancelled`] once `cancel` is set (checked before every
    /// step).
    pub fn replay(
        self,
        lanes: &mut [Lane<'_>],
        cancel: &Cancel,
    ) -> Vec<Result<SimTrajectory, ReplayError>> {
        let Some((mut world, _, _)) = self.world else {
            return lanes
                .iter()
                .map(|_| Err(ReplayError::Diverged("batch has no world".into())))
                .collect();
        };
        let mut results: Vec<Option<Result<SimTrajectory, ReplayError>>> =
            lanes.iter().map(|_| None).collect();
        let mut runs: Vec<Option<Replay>> = Vec::with_capacity(lanes.len());
        for (i, l) in lanes.iter_mut().enumerate() {
            let start = lend(&mut world, &mut *l.sys, |s| {
                Replay::start(s, l.plan, &l.opts)
            });
            match start {
                Ok(run) => runs.push(Some(run)),
                Err(e) => {
                    runs.push(None);
                    results[i] = Some(Err(e));
                    retire(&mut world, &mut *l.sys);
                }
            }
        }
        let mut stepping = vec![false; lanes.len()];
        loop {
            if cancel.is_cancelled() {
                return lanes.iter().map(|_| Err(ReplayError::Cancelled)).collect();
            }
            for (i, l) in lanes.iter_mut().enumerate() {
                let sys = &mut *l.sys;
                stepping[i] = false;
                let Some(run) = runs[i].as_mut() else {
                    continue;
                };
                match lend(&mut world, sys, |s| run.command(s)) {
                    Ok(true) => stepping[i] = true,
                    Ok(false) => {
                        if let Some(run) = runs[i].take() {
                            results[i] = Some(Ok(lend(&mut world, sys, |s| run.finish(s))));
                        }
                        retire(&mut world, sys);
                    }
                    Err(e) => {
                        runs[i] = None;
                        results[i] = Some(Err(e));
                        retire(&mut world, sys);
                    }
                }
            }
            if !stepping.contains(&true) {
                break;
            }
            world.step();
            for (i, l) in lanes.iter_mut().enumerate() {
                let sys = &mut *l.sys;
                let (true, Some(run)) = (stepping[i], runs[i].as_mut()) else {
                    continue;
                };
                let rec = lend(&mut world, sys, |s| {
                    s.step();
                    run.record_step(s)
                });
                if let Err(e) = rec {
                    runs[i] = None;
                    results[i] = Some(Err(e));
                    retire(&mut world, sys);
                }
            }
        }
        results
            .into_iter()
            .map(|r| r.unwrap_or_else(|| Err(ReplayError::Diverged("not replayed".into()))))
            .collect()
    }
}

/// Run `f` on `sys` with the shared world swapped into its [`SimWorld`](crate::engine::world::SimWorld).
fn lend<T>(
    world: &mut Box<PhysicsWorld>,
    sys: &mut dyn PhysicsSystem,
    f: impl FnOnce(&mut dyn PhysicsSystem) -> T,
) -> T {
    if let Some(sw) = sys.sim_world() {
        std::mem::swap(&mut sw.world, world);
    }
    let out = f(&mut *sys);
    if let Some(sw) = sys.sim_world() {
        std::mem::swap(&mut sw.world, world);
    }
    out
}

/// Take a finished robot out of the solver (its bodies stay, disabled).
fn retire(world: &mut PhysicsWorld, sys: &mut dyn PhysicsSystem) {
    if let Some(sw) = sys.sim_world() {
        for h in &sw.robot.links {
            if let Some(b) = world.bodies.get_mut(*h) {
                b.set_enabled(false);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A constructor that panics inside [`Host::build`] must not leave the
    /// slot behind: the next world made on the thread would join it and
    /// never step.
    #[test]
    fn a_panicking_constructor_leaves_no_slot_behind() {
        let settings = crate::engine::PhysicsSettings::default();
        let mut host = Host::new();
        let caught = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            let _ = host.build(|| -> Result<Box<dyn PhysicsSystem>, ()> {
                panic!("the constructor fails")
            });
        }));
        assert!(caught.is_err());
        let joined = crate::engine::shared_world::join(&settings, true);
        assert!(joined.is_none(), "a slot outlived the build");
    }
}
