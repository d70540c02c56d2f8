//! The beam two mobile manipulators carry, in the physics world: a
//! [`PhysicsBeam`] fixed to both tools at the planner's grasp offsets, and
//! what the harness reads from it.
//!
//! The beam is inserted along the FE model's centreline at the start grasps
//! (the planner's `Carried::at_rest` makes it straight there but for its
//! sag under gravity), so the replay starts near equilibrium. Contacts between the beam and the tools are
//! off by the collision groups (see the module above), so no grip clearance
//! joints are needed.
//!
//! Deformation read-back, in the FE model's convention ([`FeBeam`]): with
//! P0, P1, P2 the world poses of the chain's node bodies (end 0, the middle,
//! end 2), q_s = log((g⁰)⁻¹ P0⁻¹ P2) and q_o = (P0⁻¹ P1 translation − (L/2,
//! 0, 0), rotation vector of P0⁻¹ P1): the physics beam's q_f. Next to it
//! the FE model's q_f at the *simulated* grasps (tool poses times the grasp
//! offsets), so the two differ only by what the FE model leaves out
//! (dynamics, the compliance of the fixed joints, large rotations of the
//! chain) and not by where the robots went.

use crate::engine::rapier::prelude::*;
use crate::engine::real::{f, from_spatial, to_pose, to_spatial};
use crate::error::SetupError;
use crate::model::spatial::{self, Pose as SPose};
use crate::record::{LinkVisual, Pose, Shape, Visual};
use crate::robots::mobile_manipulator::beam::physics::{Attachment, BeamOptions, PhysicsBeam};
use crate::robots::mobile_manipulator::beam::se3_log;
use crate::robots::mobile_manipulator::beam::{Beam, FeBeam};
use crate::robots::mobile_manipulator::physics::gripper_balance::GripperBalance;

/// The beam as the physics needs it (plain data, from the planner's grasp).
#[derive(Debug, Clone)]
pub struct CarriedBeam {
    /// Material, section and rest length.
    pub beam: Beam,
    /// Tool frame → beam end frame: robot 1 holds end 0, robot 2 end 2.
    pub grasp: [SPose<f64>; 2],
    /// Chain resolution and damping.
    pub options: BeamOptions,
}

/// Channels of a pair (after the single robot's): `robot_clearance` (m),
/// `body_contacts` (robot–robot, beam–platform, beam–ground and non-wheel
/// ground contacts), robot 2's `slip_lateral_2`, `joint_rate_error_2` and
/// `tilt_2_deg`,
/// then ‖q_f‖∞ of the physics beam (`beam_deformation`) and of the FE model
/// at the simulated grasps (`fe_deformation`), the middle node's translation
/// q_o[0..3] in the end-0 frame from both (`beam_mid_*`, `fe_mid_*`, m; the
/// paper's Fig. 17 quantity), and the wrench magnitudes each gripper exerts
/// on the beam (`grasp1_force` N, `grasp1_torque` N m, `grasp2_*`).
pub const PAIR_CHANNELS: [&str; 17] = [
    "robot_clearance",
    "body_contacts",
    "slip_lateral_2",
    "joint_rate_error_2",
    "tilt_2_deg",
    "beam_deformation",
    "fe_deformation",
    "beam_mid_x",
    "beam_mid_y",
    "beam_mid_z",
    "fe_mid_x",
    "fe_mid_y",
    "fe_mid_z",
    "grasp1_force",
    "grasp1_torque",
    "grasp2_force",
    "grasp2_torque",
];

/// The beam in the world, held by two tools.
pub(super) struct Held {
    beam: PhysicsBeam,
    /// The grippers' balance through compliant wrists (the grasp wrenches
    /// from it); `None` with rigid wrists (from the beam's own balance).
    balance: Option<GripperBalance>,
    /// The segments' colliders.
    colliders: Vec<ColliderHandle>,
    fe: FeBeam,
    grasp: [SPose<f64>; 2],
    tools: [RigidBodyHandle; 2],
}

fn norm(v: Vector) -> f64 {
    f(v.length())
}

/// The FE model's q_f at the simulated grasps (the tools' poses times the
/// grasp offsets), under the world's gravity.
fn fe_deformation(
    fe: &FeBeam,
    grasp: &[SPose<f64>; 2],
    tools: [RigidBodyHandle; 2],
    world: &PhysicsWorld,
) -> [f64; 12] {
    let g = |k: usize| to_spatial(world.bodies[tools[k]].position()).then(&grasp[k]);
    let (g0, g2) = (g(0), g(1));
    let w = world.gravity;
    let grav = spatial::mul_mtv(&g0.r, [f(w.x), f(w.y), f(w.z)]);
    fe.deformation(&g0.inverse().then(&g2), grav)
}

impl Held {
    /// Insert the beam straight from robot 1's grasp frame, its ends fixed
    /// to `tools` (robot 1's, robot 2's); colliders in `groups`.
    pub(super) fn insert(
        world: &mut PhysicsWorld,
        spec: &CarriedBeam,
        tools: [RigidBodyHandle; 2],
        wrists: Option<([RigidBodyHandle; 2], [ImpulseJointHandle; 2])>,
        groups: InteractionGroups,
    ) -> Result<Held, SetupError> {
        let fe = FeBeam::new(&spec.beam)?;
        // Start in the FE model's equilibrium under gravity (not straight),
        // so the replay does not begin with the rod dropping into its sag.
        let q_f = fe_deformation(&fe, &spec.grasp, tools, world);
        let end0 = to_spatial(world.bodies[tools[0]].position()).then(&spec.grasp[0]);
        let line = |s: Real| from_spatial(&end0.then(&fe.centerline(&q_f, f(s))));
        let opts = BeamOptions {
            grip_clearance: 0.0,
            ..spec.options
        };
        let at = |k: usize| {
            Some(Attachment {
                body: tools[k],
                frame: from_spatial(&spec.grasp[k]),
            })
        };
        let beam = PhysicsBeam::insert(world, &spec.beam, &opts, &line, [at(0), at(1)], groups)?;
        let colliders = beam
            .bodies()
            .iter()
            .flat_map(|b| world.bodies[*b].colliders().iter().copied())
            .collect();
        let balance = wrists.map(|(flanges, joints)| {
            GripperBalance::new(
                world,
                tools,
                flanges,
                joints,
                spec.grasp.map(|g| from_spatial(&g)),
            )
        });
        Ok(Held {
            beam,
            balance,
            colliders,
            fe,
            grasp: spec.grasp,
            tools,
        })
    }

    /// Record the step's velocities (for the grasp wrenches).
    pub(super) fn after_step(&mut self, world: &PhysicsWorld) {
        self.beam.after_step(world);
        if let Some(b) = &mut self.balance {
            b.after_step(world);
        }
    }

    /// The segments' colliders.
    pub(super) fn colliders(&self) -> &[ColliderHandle] {
        &self.colliders
    }

    /// Each segment's centre pose, x along it (the order of [`link_visuals`]).
    pub(super) fn segment_poses(&self, world: &PhysicsWorld) -> Vec<Pose> {
        self.beam
            .segment_poses(world)
            .iter()
            .map(|(p, _, _)| to_pose(p))
            .collect()
    }

    /// The physics beam's q_f (FE convention, see the module doc).
    fn measured(&self, world: &PhysicsWorld) -> [f64; 12] {
        let [p0, p1, p2] = self.beam.node_poses(world).map(|p| to_spatial(&p));
        let inv = p0.inverse();
        let (rel1, rel2) = (inv.then(&p1), inv.then(&p2));
        let l = self.fe.beam().length;
        let qs = self.fe.grasp_deformation(&rel2);
        let w1 = se3_log(&rel1);
        let mut out = [0.0; 12];
        out[..6].copy_from_slice(&qs);
        out[6..9].copy_from_slice(&[rel1.p[0] - 0.5 * l, rel1.p[1], rel1.p[2]]);
        out[9..].copy_from_slice(&w1[3..]);
        out
    }

    /// The beam's part of [`PAIR_CHANNELS`] (from `beam_deformation` on).
    pub(super) fn channels(&self, world: &PhysicsWorld) -> [f64; 12] {
        let q = self.measured(world);
        let m = fe_deformation(&self.fe, &self.grasp, self.tools, world);
        let inf = |v: &[f64; 12]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let w = match &self.balance {
            Some(b) => b.wrenches(world).map(Some),
            None => self.beam.grasp_wrenches(world),
        };
        let mag = |k: usize| w[k].map_or([f64::NAN; 2], |w| [norm(w.force), norm(w.torque)]);
        let ([f1, t1], [f2, t2]) = (mag(0), mag(1));
        [
            inf(&q),
            inf(&m),
            q[6],
            q[7],
            q[8],
            m[6],
            m[7],
            m[8],
            f1,
            t1,
            f2,
            t2,
        ]
    }
}

/// The logs' name of URDF link `link` of robot `r` (1-based): robot 1's
/// links keep their names, robot r's get the prefix `r<r>_`.
pub fn robot_link_name(r: usize, link: &str) -> String {
    if r == 1 {
        link.to_string()
    } else {
        format!("r{r}_{link}")
    }
}

/// The links the logs draw for `robots` copies of a robot (robot 2's link
/// names prefixed `r2_`) and the beam's segments (`beam_0` … `beam_N`,
/// capsules along the segment): the order of the physics' link poses.
pub fn link_visuals(
    robot: Vec<LinkVisual>,
    robots: usize,
    beam: Option<&CarriedBeam>,
) -> Vec<LinkVisual> {
    let mut out = Vec::with_capacity(robots * robot.len());
    for r in 1..=robots {
        out.extend(robot.iter().map(|l| LinkVisual {
            name: robot_link_name(r, &l.name),
            visuals: l.visuals.clone(),
        }));
    }
    if let Some(b) = beam {
        let n = b.options.segments;
        let l = b.beam.length / n as f64;
        let radius = b.beam.section.outer_diameter / 2.0;
        // Record capsules run along z: turn z onto the segment's x.
        let s = std::f64::consts::FRAC_1_SQRT_2;
        let origin = Pose {
            translation: [0.0; 3],
            rotation: [0.0, s, 0.0, s],
        };
        out.extend((0..=n).map(|k| LinkVisual {
            name: format!("beam_{k}"),
            visuals: vec![Visual {
                shape: Shape::Capsule {
                    radius,
                    length: if k == 0 || k == n { 0.5 * l } else { l },
                },
                origin,
                rgba: [0.95, 0.8, 0.2, 1.0],
            }],
        }));
    }
    out
}
