//! The wrench each gripper exerts on the carried beam, read from the
//! gripper's own balance through its compliant wrist.
//!
//! Between the flange and the gripper sits the compliant wrist
//! (`joints::compliant_wrist_joint`): six force-based motor rows with
//! limits and no locked row, so Rapier solves each on its own axis and the
//! impulse it keeps per row (`motors[i].impulse`, `limits[i].impulse`, over
//! the last substep) is the wrist's force along that axis of the flange's
//! grasp frame, or its moment about it. What the wrist, gravity and the
//! gripper's inertia leave over is what the beam exerts on the gripper
//! (Newton–Euler of the gripper, its accelerations from velocity
//! differences over the step), and the gripper exerts the opposite on the
//! beam: what a force–torque sensor in the wrist, compensated for the
//! gripper, reads. The beam's own balance ([`PhysicsBeam::grasp_wrenches`])
//! also counts the solver's correction of the start poses in the first
//! step (some 170 N for one step, which no part of the rod feels: the
//! seed-004 note); the grippers' balance does not. A rigid wrist has no
//! such rows, and there the beam's balance is read.
//!
//! [`PhysicsBeam::grasp_wrenches`]: crate::robots::mobile_manipulator::beam::physics::PhysicsBeam::grasp_wrenches

use crate::engine::rapier::prelude::*;
use crate::robots::mobile_manipulator::beam::physics::Wrench;
use crate::robots::mobile_manipulator::physics::joints::grasp_frame;

/// The two grippers holding the beam, and their last velocities.
pub(super) struct GripperBalance {
    tools: [RigidBodyHandle; 2],
    flanges: [RigidBodyHandle; 2],
    /// The wrist joints (flange to gripper).
    wrists: [ImpulseJointHandle; 2],
    /// The beam's end frames in the tool frames (the grasp offsets).
    ends: [Pose; 2],
    last: [(Vector, Vector); 2],
    accel: [(Vector, Vector); 2],
}

impl GripperBalance {
    /// The grippers `tools` on the flanges `flanges` through `wrist`,
    /// holding the beam's ends at `ends` (tool frame).
    pub(super) fn new(
        world: &PhysicsWorld,
        tools: [RigidBodyHandle; 2],
        flanges: [RigidBodyHandle; 2],
        wrists: [ImpulseJointHandle; 2],
        ends: [Pose; 2],
    ) -> GripperBalance {
        let mut me = GripperBalance {
            tools,
            flanges,
            wrists,
            ends,
            last: [(Vector::ZERO, Vector::ZERO); 2],
            accel: [(Vector::ZERO, Vector::ZERO); 2],
        };
        me.last = me.velocities(world);
        me
    }

    fn velocities(&self, world: &PhysicsWorld) -> [(Vector, Vector); 2] {
        self.tools.map(|t| {
            let b = &world.bodies[t];
            (b.linvel(), b.angvel())
        })
    }

    /// Record the step's velocity change (call after every step).
    pub(super) fn after_step(&mut self, world: &PhysicsWorld) {
        let dt = world.integration_parameters.dt;
        let now = self.velocities(world);
        for ((acc, new), old) in self.accel.iter_mut().zip(&now).zip(&self.last) {
            *acc = ((new.0 - old.0) / dt, (new.1 - old.1) / dt);
        }
        self.last = now;
    }

    /// The wrist's force (at the gripper's grasp point) and moment on
    /// gripper `k`, world frame: its rows' impulses over the last substep.
    fn wrist_on_gripper(&self, world: &PhysicsWorld, k: usize) -> (Vector, Vector, Vector) {
        let (flange, tool) = (&world.bodies[self.flanges[k]], &world.bodies[self.tools[k]]);
        let f1 = *flange.position() * grasp_frame();
        let at = (*tool.position() * grasp_frame()).translation;
        let p = &world.integration_parameters;
        let dt_sub = p.dt / p.num_solver_iterations.max(1) as Real;
        let Some(j) = world.impulse_joints.get(self.wrists[k]) else {
            return (Vector::ZERO, Vector::ZERO, at);
        };
        let (mut force, mut moment) = (Vector::ZERO, Vector::ZERO);
        for i in 0..3 {
            let n = f1.rotation * [Vector::X, Vector::Y, Vector::Z][i];
            let lin = j.data.motors[i].impulse + j.data.limits[i].impulse;
            let ang = j.data.motors[3 + i].impulse + j.data.limits[3 + i].impulse;
            force -= n * (lin / dt_sub);
            moment -= n * (ang / dt_sub);
        }
        (force, moment, at)
    }

    /// The wrench each gripper exerts on the beam: force, and torque about
    /// the beam's end frame origin, world frame.
    pub(super) fn wrenches(&self, world: &PhysicsWorld) -> [Wrench; 2] {
        std::array::from_fn(|k| {
            let tool = &world.bodies[self.tools[k]];
            let (fw, mw, at) = self.wrist_on_gripper(world, k);
            let c = tool.center_of_mass();
            let (a, alpha) = self.accel[k];
            let inertia = tool.mass_properties().effective_angular_inertia();
            let w = tool.angvel();
            let g = world.gravity * tool.gravity_scale();
            // The beam's wrench on the gripper, about its centre of mass.
            let f = tool.mass() * (a - g) - fw - tool.user_force();
            let m = inertia * alpha + w.cross(inertia * w)
                - mw
                - (at - c).cross(fw)
                - tool.user_torque();
            let end = (*tool.position() * self.ends[k]).translation;
            Wrench {
                force: -f,
                torque: -(m + (c - end).cross(f)),
            }
        })
    }
}
