//! A Rapier world built from URDF robots: the loader (links → dynamic bodies
//! with the URDF inertials, `<collision>` → colliders, joints → impulse joints
//! with their limits), an optional ground half-space, and the handles the
//! systems use. Robots come from [`crate::engine::urdf::read`], which has rejected
//! everything this loader cannot represent.
//!
//! Impulse joints (not multibody joints): every joint impulse acts equally and
//! oppositely on two bodies, so the solver conserves linear and angular
//! momentum (the space robot relies on it). Bodies never sleep. Colliders
//! carry no mass (density 0): mass properties come from `<inertial>` only.

use crate::engine::rapier::math::{Matrix, Pose as RPose};
use crate::engine::rapier::na::Unit;
use crate::engine::rapier::prelude::*;
use crate::engine::real::{f, r, to_pose, vector};
use crate::engine::settings::PhysicsSettings;
use crate::error::SetupError;
use crate::record::Pose;
use std::collections::HashMap;
use std::path::Path;
use urdf_rs::{Geometry, JointType, Robot};

pub use crate::engine::real::origin;

/// Mass, centre of mass and inertia of an `<inertial>` (inertia given about
/// the CoM in the inertial frame, which may be rotated).
pub fn mass_properties(i: &urdf_rs::Inertial) -> MassProperties {
    let o = origin(&i.origin);
    let t = &i.inertia;
    let mass = r(i.mass.value);
    if t.ixy == 0.0 && t.ixz == 0.0 && t.iyz == 0.0 {
        // Diagonal: the principal frame is the inertial frame itself, exactly.
        let principal = vector(t.ixx, t.iyy, t.izz);
        return MassProperties::with_principal_inertia_frame(
            o.translation,
            mass,
            principal,
            o.rotation,
        );
    }
    let m = Matrix::from_cols_array(&[
        r(t.ixx),
        r(t.ixy),
        r(t.ixz),
        r(t.ixy),
        r(t.iyy),
        r(t.iyz),
        r(t.ixz),
        r(t.iyz),
        r(t.izz),
    ]);
    let rot = Matrix::from_quat(o.rotation);
    MassProperties::with_inertia_matrix(o.translation, mass, rot * m * rot.transpose())
}

/// Collision shape of a URDF geometry and its pose in the geometry frame
/// (URDF cylinders are along z, Rapier's along y). A mesh becomes its
/// convex hull; `None` for a mesh file that cannot be read (the validation
/// pass has refused those, `crate::validate::urdf`, with its file name
/// resolved).
fn collision_shape(g: &Geometry) -> Option<(SharedShape, RPose)> {
    Some(match g {
        Geometry::Box { size } => (
            SharedShape::cuboid(r(size[0] / 2.0), r(size[1] / 2.0), r(size[2] / 2.0)),
            RPose::IDENTITY,
        ),
        Geometry::Cylinder { radius, length } => (
            SharedShape::cylinder(r(length / 2.0), r(*radius)),
            RPose::from_rotation(Rotation::from_rotation_x(r(std::f64::consts::FRAC_PI_2))),
        ),
        Geometry::Capsule { radius, length } => (
            SharedShape::capsule_z(r(length / 2.0), r(*radius)),
            RPose::IDENTITY,
        ),
        Geometry::Sphere { radius } => (SharedShape::ball(r(*radius)), RPose::IDENTITY),
        Geometry::Mesh { filename, scale } => {
            let m = crate::engine::mesh::load(
                Path::new(filename),
                crate::engine::mesh::scale_of(scale),
            )
            .ok()?;
            (crate::engine::mesh_limits::hull(&m)?, RPose::IDENTITY)
        }
    })
}

/// The height of the lowest point of a URDF collision geometry placed at
/// `at` (the geometry frame in some frame of reference): the bottom of its
/// bounding box there, exact for every convex shape. `None` for a mesh that
/// is not loaded.
pub(crate) fn lowest_point(g: &Geometry, at: &RPose) -> Option<f64> {
    let (shape, local) = collision_shape(g)?;
    Some(f(shape.compute_aabb(&(*at * local)).mins.z))
}

/// The impulse joint for a URDF joint whose child link frame sits at the
/// joint frame (URDF convention). The joint's free axis is its local x.
fn joint_data(j: &urdf_rs::Joint, parent: Option<RPose>, child: Option<RPose>) -> GenericJoint {
    let locked = match j.joint_type {
        JointType::Fixed => JointAxesMask::LOCKED_FIXED_AXES,
        JointType::Continuous | JointType::Revolute => JointAxesMask::LOCKED_REVOLUTE_AXES,
        JointType::Prismatic => JointAxesMask::LOCKED_PRISMATIC_AXES,
        JointType::Floating => JointAxesMask::empty(),
        JointType::Planar => JointAxesMask::ANG_AXES | JointAxesMask::LIN_X,
        JointType::Spherical => JointAxesMask::LOCKED_SPHERICAL_AXES,
    };
    let a = j.axis.xyz;
    let axis = vector(a[0], a[1], a[2]).normalize_or_zero();
    // One basis for both sides (x = joint axis), so the joint is satisfied at rest.
    let basis = if axis == Vector::ZERO {
        RPose::IDENTITY
    } else {
        RPose::from_rotation(GenericJoint::complete_ang_frame(axis))
    };
    // Links lumped into a body ([`crate::engine::lump`]) sit at an offset in its frame.
    let frame1 = origin(&j.origin) * basis;
    let mut b = GenericJointBuilder::new(locked)
        .contacts_enabled(false)
        .local_frame1(parent.map_or(frame1, |o| o * frame1))
        .local_frame2(child.map_or(basis, |o| o * basis));
    let limits = [r(j.limit.lower), r(j.limit.upper)];
    match j.joint_type {
        JointType::Revolute => b = b.limits(JointAxis::AngX, limits),
        JointType::Prismatic => b = b.limits(JointAxis::LinX, limits),
        _ => {}
    }
    b.build()
}

/// World pose of every link (URDF order) with the root link at `root`; each
/// child sits at its parent's pose times the joint origin (all joints at 0).
fn initial_poses(robot: &Robot, root: RPose) -> Vec<RPose> {
    let index: HashMap<&str, usize> = robot
        .links
        .iter()
        .enumerate()
        .map(|(i, l)| (l.name.as_str(), i))
        .collect();
    let mut pose: Vec<Option<RPose>> = vec![None; robot.links.len()];
    let mut has_parent = vec![false; robot.links.len()];
    for j in &robot.joints {
        has_parent[index[j.child.link.as_str()]] = true;
    }
    for (p, parent) in pose.iter_mut().zip(&has_parent) {
        if !parent {
            *p = Some(root);
        }
    }
    // read() guarantees a tree, so every pass places at least one more link.
    let mut placed = pose.iter().filter(|p| p.is_some()).count();
    while placed < pose.len() {
        let before = placed;
        for j in &robot.joints {
            let (pi, ci) = (index[j.parent.link.as_str()], index[j.child.link.as_str()]);
            if let (Some(p), None) = (pose[pi], pose[ci]) {
                pose[ci] = Some(p * origin(&j.origin));
                placed += 1;
            }
        }
        if placed == before {
            break;
        }
    }
    pose.into_iter().map(|p| p.unwrap_or(root)).collect()
}

/// The refusal for a link the URDF lacks.
fn no_link(name: &str) -> SetupError {
    SetupError::urdf(format!("URDF has no link `{name}`"))
}

/// Handles of one robot in a [`SimWorld`].
#[derive(Debug, Clone, Default)]
pub struct RobotHandles {
    /// Body of each URDF link, in URDF link order (links lumped into one
    /// body share its handle: [`crate::engine::lump`]).
    pub links: Vec<RigidBodyHandle>,
    /// Each link's pose in its body's frame (`None`: the body's own link).
    pub offsets: Vec<Option<RPose>>,
    /// Joint handles by URDF joint name (lumped fixed joints have none).
    pub joints: HashMap<String, ImpulseJointHandle>,
    /// Link index by name.
    pub link_index: HashMap<String, usize>,
    /// Every collider of the robot (for collision groups).
    pub colliders: Vec<ColliderHandle>,
    /// The colliders of each link's own `<collision>` elements, URDF order.
    pub link_colliders: Vec<Vec<ColliderHandle>>,
}

impl RobotHandles {
    /// Body handle of a named link.
    pub fn link(&self, name: &str) -> Option<RigidBodyHandle> {
        self.link_index.get(name).map(|&i| self.links[i])
    }

    /// Body of a link the system needs and whose body's pose it reads as
    /// the link's pose; the error names the missing link, or the body it
    /// was lumped into (the system then needs [`RobotHandles::require_frame`]).
    pub fn require_link(&self, name: &str) -> Result<RigidBodyHandle, SetupError> {
        let i = *self.link_index.get(name).ok_or_else(|| no_link(name))?;
        if self.offsets[i].is_some() {
            return Err(SetupError::urdf_at(
                "link",
                name,
                format!("URDF link `{name}` is fixed to another link and lumped into its body: this model reads its pose, so give it the mass (an <inertial>) or attach it by a non-fixed joint"),
            ));
        }
        Ok(self.links[i])
    }

    /// Body of a named link and the link's pose in the body frame
    /// (identity for a body's own link).
    pub fn require_frame(&self, name: &str) -> Result<(RigidBodyHandle, RPose), SetupError> {
        let i = *self.link_index.get(name).ok_or_else(|| no_link(name))?;
        Ok((self.links[i], self.offsets[i].unwrap_or(RPose::IDENTITY)))
    }

    /// The colliders of a named link's own `<collision>` elements.
    pub fn colliders_of(&self, name: &str) -> Result<&[ColliderHandle], SetupError> {
        self.link_index
            .get(name)
            .map(|&i| self.link_colliders[i].as_slice())
            .ok_or_else(|| no_link(name))
    }

    /// Handle of a joint the system needs; the error names the missing joint.
    pub fn require_joint(&self, name: &str) -> Result<ImpulseJointHandle, SetupError> {
        self.joints.get(name).copied().ok_or_else(|| {
            SetupError::urdf(format!("URDF has no joint `{name}` between two bodies"))
        })
    }

    /// World pose of every link, in URDF order.
    pub fn link_poses(&self, bodies: &RigidBodySet) -> Vec<Pose> {
        self.links
            .iter()
            .zip(&self.offsets)
            .map(|(h, o)| match o {
                None => to_pose(bodies[*h].position()),
                Some(o) => to_pose(&(*bodies[*h].position() * *o)),
            })
            .collect()
    }
}

/// Insert `robot` (validated by [`crate::engine::urdf::read`]) into `world` with its
/// root link at `root`; every collider gets friction `mu` (combined with the
/// other side by the minimum). Fixed joints are lumped ([`crate::engine::lump`])
/// except those named in `keep`.
pub(crate) fn insert_robot(
    world: &mut PhysicsWorld,
    robot: &Robot,
    root: RPose,
    mu: f64,
    keep: &[&str],
) -> Result<RobotHandles, SetupError> {
    let lumping = crate::engine::lump::lump(robot, keep)?;
    let poses = initial_poses(robot, root);
    let n = robot.links.len();
    let mut out = RobotHandles {
        links: vec![RigidBodyHandle::invalid(); n],
        offsets: lumping.offset.clone(),
        link_colliders: vec![Vec::new(); n],
        ..Default::default()
    };
    for (i, link) in robot.links.iter().enumerate() {
        out.link_index.insert(link.name.clone(), i);
    }
    // Bodies are inserted at their first link in URDF order, each link's
    // colliders right after: an unlumped robot gets the handles, and so the
    // solver order, it always had.
    for (i, link) in robot.links.iter().enumerate() {
        let b = lumping.body[i];
        if out.links[b] == RigidBodyHandle::invalid() {
            // The body's inertia: its own link's, plus every lumped link's
            // moved into its frame (parry adds them about the joint CoM).
            let mut mass = mass_properties(&robot.links[b].inertial);
            for k in (0..n).filter(|&k| lumping.body[k] == b && k != b) {
                let l = &robot.links[k];
                if !crate::engine::lump::is_frame(l) {
                    let o = lumping.offset[k].expect("a lumped link has an offset");
                    mass += mass_properties(&l.inertial).transform_by(&o);
                }
            }
            let body = RigidBodyBuilder::dynamic()
                .can_sleep(false)
                .pose(poses[b])
                .additional_mass_properties(mass);
            out.links[b] = world.insert_body(body);
        }
        let h = out.links[b];
        out.links[i] = h;
        for c in &link.collision {
            if let Some((shape, local)) = collision_shape(&c.geometry) {
                let at = origin(&c.origin) * local;
                let at = lumping.offset[i].map_or(at, |o| o * at);
                let collider = ColliderBuilder::new(shape)
                    .position(at)
                    .density(0.0)
                    .friction(r(mu))
                    .friction_combine_rule(CoefficientCombineRule::Min);
                let ch = world
                    .colliders
                    .insert_with_parent(collider, h, &mut world.bodies);
                out.colliders.push(ch);
                out.link_colliders[i].push(ch);
            }
        }
    }
    for (k, j) in robot.joints.iter().enumerate() {
        if !lumping.joint_kept[k] {
            continue;
        }
        let (p, c) = (
            out.link_index[&j.parent.link],
            out.link_index[&j.child.link],
        );
        let data = joint_data(j, lumping.offset[p], lumping.offset[c]);
        let h = world
            .impulse_joints
            .insert(out.links[p], out.links[c], data, true);
        out.joints.insert(j.name.clone(), h);
    }
    Ok(out)
}

/// A Rapier world holding one URDF robot (more with [`SimWorld::add_robot`])
/// and optionally a ground plane.
pub struct SimWorld {
    /// The physics world (boxed: a batched sweep swaps one shared world in
    /// and out of its systems, see [`crate::engine::batch`]).
    pub world: Box<PhysicsWorld>,
    /// Handles of the first robot (links, joints, colliders).
    pub robot: RobotHandles,
    /// The fixed ground body (present even without a ground collider, as a joint anchor).
    pub ground: RigidBodyHandle,
    /// The ground half-space z ≤ 0, when the world has one.
    pub ground_collider: Option<ColliderHandle>,
    /// The settings the world was built with (friction for robots added
    /// later, motor gains and limits for [`SimWorld::drive`]).
    pub settings: PhysicsSettings,
    /// The robot was built into a batch's shared world, which the batch
    /// steps ([`SimWorld::step`] then does nothing).
    hosted: bool,
    /// Fixed joints kept as joints (not lumped) in every robot of the world.
    keep_fixed: Vec<String>,
}

/// Settings for [`SimWorld::new`].
pub struct WorldOptions<'a> {
    /// Physics settings.
    pub settings: &'a PhysicsSettings,
    /// Root link pose in the world.
    pub root_pose: RPose,
    /// Add a ground plane z = 0 with the settings' friction.
    pub ground: bool,
    /// Fixed joints the system needs as joints: not lumped ([`crate::engine::lump`]).
    pub keep_fixed: &'a [&'a str],
}

impl SimWorld {
    /// Build the world; `robot` must come from [`crate::engine::urdf::read`] (its
    /// mesh file names resolved). The error is a lumping refusal
    /// ([`crate::engine::lump::lump`]): a kept fixed joint whose child has no mass.
    pub fn new(
        robot: &Robot,
        _urdf_dir: &Path,
        opts: &WorldOptions,
    ) -> Result<SimWorld, SetupError> {
        let s = opts.settings;
        // Inside `batch::Host::build`: join the batch's world when there is one.
        let joined = crate::engine::shared_world::join(opts.settings, opts.ground);
        let hosted = joined.is_some();
        let (mut world, ground, ground_collider) = match joined {
            Some(Some(shared)) => shared,
            _ => {
                let (world, ground, ground_collider) = Self::fresh_world(opts);
                (Box::new(world), ground, ground_collider)
            }
        };
        // Heavier links than the model believes (`mass_scale`): the URDF's own
        // numbers scaled, so a sweep variant and a margin level agree exactly.
        let scaled = crate::engine::perturb::world::scaled_masses(robot, s.mass_scale);
        let robot = insert_robot(
            &mut world,
            scaled.as_ref().unwrap_or(robot),
            opts.root_pose,
            s.friction,
            opts.keep_fixed,
        )?;
        if hosted {
            crate::engine::shared_world::keep_apart(
                &mut world,
                &robot.colliders,
                ground_collider,
                s.friction,
            );
        }
        Ok(SimWorld {
            world,
            robot,
            ground,
            ground_collider,
            settings: s.clone(),
            hosted,
            keep_fixed: opts.keep_fixed.iter().map(|k| k.to_string()).collect(),
        })
    }

    /// An empty world with the settings' integration parameters and gravity,
    /// its ground body and (with `opts.ground`) the ground half-space.
    fn fresh_world(opts: &WorldOptions) -> (PhysicsWorld, RigidBodyHandle, Option<ColliderHandle>) {
        let s = opts.settings;
        let mut world = PhysicsWorld::new();
        world.gravity = vector(s.gravity[0], s.gravity[1], s.gravity[2]);
        let p = &mut world.integration_parameters;
        p.dt = r(s.dt);
        p.num_solver_iterations = s.solver_iterations;
        p.num_internal_pgs_iterations = s.pgs_iterations;
        // The relax pass (an unbiased re-solve after the position update) removes the
        // velocity that contact correction added, but it leaks angular momentum (docs/src/reference/physics.md): by default only worlds with a ground get it.
        p.num_internal_stabilization_iterations = usize::from(s.relax_pass.unwrap_or(opts.ground));
        let ground = world.insert_body(RigidBodyBuilder::fixed());
        let ground_collider = opts.ground.then(|| {
            let plane = ColliderBuilder::halfspace(Unit::new_unchecked(Vector::Z))
                .friction(r(s.friction))
                .friction_combine_rule(CoefficientCombineRule::Min);
            world
                .colliders
                .insert_with_parent(plane, ground, &mut world.bodies)
        });
        (world, ground, ground_collider)
    }

    /// Advance the world one step, unless a batch owns it (then the batch
    /// has stepped it, once for all its robots, before this call).
    pub fn step(&mut self) {
        if !self.hosted {
            self.world.step();
        }
    }

    /// Whether the robot lives in a batch's shared world.
    pub fn is_hosted(&self) -> bool {
        self.hosted
    }

    /// A world with a ground plane, the robot's root at `root_pose`.
    pub fn on_ground(
        robot: &Robot,
        urdf_dir: &Path,
        settings: &PhysicsSettings,
        root_pose: RPose,
    ) -> Result<SimWorld, SetupError> {
        SimWorld::new(
            robot,
            urdf_dir,
            &WorldOptions {
                settings,
                root_pose,
                ground: true,
                keep_fixed: &[],
            },
        )
    }

    /// Insert another robot (another URDF, or a second copy of the same one)
    /// with its root link at `root_pose`; its handles are its own.
    pub fn add_robot(
        &mut self,
        robot: &Robot,
        _urdf_dir: &Path,
        root_pose: RPose,
    ) -> Result<RobotHandles, SetupError> {
        let scaled = crate::engine::perturb::world::scaled_masses(robot, self.settings.mass_scale);
        let robot = scaled.as_ref().unwrap_or(robot);
        let keep: Vec<&str> = self.keep_fixed.iter().map(String::as_str).collect();
        insert_robot(
            &mut self.world,
            robot,
            root_pose,
            self.settings.friction,
            &keep,
        )
    }

    /// The colliders of a named link of the first robot (see [`RobotHandles::colliders_of`]).
    pub fn colliders_of(&self, name: &str) -> Result<Vec<ColliderHandle>, SetupError> {
        self.robot.colliders_of(name).map(<[_]>::to_vec)
    }

    /// Body of a named link of the first robot and the link's pose in it
    /// (see [`RobotHandles::require_frame`]).
    pub fn require_frame(&self, name: &str) -> Result<(RigidBodyHandle, RPose), SetupError> {
        self.robot.require_frame(name)
    }

    /// Put `colliders` (e.g. the first robot's or [`RobotHandles::colliders`])
    /// in collision groups: two colliders interact only when each one's
    /// memberships intersect the other's filter.
    pub fn set_collision_groups(
        &mut self,
        colliders: &[ColliderHandle],
        groups: InteractionGroups,
    ) {
        for c in colliders {
            if let Some(c) = self.world.colliders.get_mut(*c) {
                c.set_collision_groups(groups);
            }
        }
    }

    /// Body handle of a named link of the first robot.
    pub fn link(&self, name: &str) -> Option<RigidBodyHandle> {
        self.robot.link(name)
    }

    /// Body of a link of the first robot the system needs (see [`RobotHandles::require_link`]).
    pub fn require_link(&self, name: &str) -> Result<RigidBodyHandle, SetupError> {
        self.robot.require_link(name)
    }

    /// Handle of a joint of the first robot (see [`RobotHandles::require_joint`]).
    pub fn require_joint(&self, name: &str) -> Result<ImpulseJointHandle, SetupError> {
        self.robot.require_joint(name)
    }

    /// World pose of every link of the first robot, in URDF order.
    pub fn link_poses(&self) -> Vec<Pose> {
        self.robot.link_poses(&self.world.bodies)
    }

    /// Set a velocity motor on the free axis of a revolute joint.
    pub fn drive_joint(
        &mut self,
        joint: ImpulseJointHandle,
        rate: f64,
        gain: f64,
        max_torque: f64,
    ) {
        if let Some(j) = self.world.impulse_joints.get_mut(joint, false) {
            j.data
                .set_motor_velocity(JointAxis::AngX, r(rate), r(gain))
                .set_motor_max_force(JointAxis::AngX, r(max_torque));
        }
    }
}

impl SimWorld {
    /// The position of a one-axis joint: the child's angle about the joint
    /// axis relative to the parent (rad, in (−π, π]), or its travel along it
    /// for a prismatic joint (m).
    pub fn joint_position(&self, joint: ImpulseJointHandle) -> Option<f64> {
        let j = self.world.impulse_joints.get(joint)?;
        let b = &self.world.bodies;
        let f1 = *b.get(j.body1())?.position() * j.data.local_frame1;
        let f2 = *b.get(j.body2())?.position() * j.data.local_frame2;
        let rel = f1.inverse() * f2;
        Some(if j.data.locked_axes.contains(JointAxesMask::LIN_X) {
            crate::engine::angles::about_axis(&rel.rotation, 0)
        } else {
            f(rel.translation.x)
        })
    }

    /// Move a one-axis joint to `value` (rad, or m for a prismatic joint)
    /// by turning (sliding) every body below it about (along) its axis:
    /// for placing a start configuration, before any step.
    pub fn set_joint_position(
        &mut self,
        joint: ImpulseJointHandle,
        value: f64,
    ) -> Result<(), SetupError> {
        let now = self
            .joint_position(joint)
            .ok_or_else(|| SetupError::other("set_joint_position: no such joint"))?;
        let j = self
            .world
            .impulse_joints
            .get(joint)
            .ok_or_else(|| SetupError::other("set_joint_position: no such joint"))?;
        let frame = *self.world.bodies[j.body1()].position() * j.data.local_frame1;
        let axis = frame.rotation * Vector::X;
        let slider = !j.data.locked_axes.contains(JointAxesMask::LIN_X);
        let motion = if slider {
            RPose::from_translation(axis * r(value - now))
        } else {
            let turn = Rotation::from_axis_angle(axis, r(value - now));
            let a = frame.translation;
            RPose::from_translation(a) * RPose::from_rotation(turn) * RPose::from_translation(-a)
        };
        // The child and everything jointed below it.
        let mut below = vec![j.body2()];
        let mut i = 0;
        while i < below.len() {
            let at = below[i];
            for (_, other) in self.world.impulse_joints.iter() {
                if other.body1() == at && !below.contains(&other.body2()) {
                    below.push(other.body2());
                }
            }
            i += 1;
        }
        for h in below {
            let b = &mut self.world.bodies[h];
            let p = motion * *b.position();
            b.set_position(p, true);
        }
        Ok(())
    }
}

/// A joint axis commanded in velocity, driven like a real servo drive: the
/// Rapier motor gets the command u as its target velocity and the commanded
/// angle (the running integral of u) as its target position, so a velocity
/// error left by the iterative solver is corrected instead of integrating
/// into an angle error (see `PhysicsSettings::motor_angle_gain`).
#[derive(Debug, Clone, Copy)]
pub struct Drive {
    /// The joint.
    pub joint: ImpulseJointHandle,
    /// Its driven axis.
    pub axis: JointAxis,
    /// Commanded joint angle at the start of the next step, rad (unwrapped).
    pub angle: f64,
    /// Joint limits of the axis, if any (the commanded angle stays inside).
    limits: Option<[f64; 2]>,
    /// This drive's torque limit, N·m (`None`: the settings' `motor_max_torque`).
    pub max_torque: Option<f64>,
}

impl SimWorld {
    /// A [`Drive`] on `axis` of `joint`, whose joint angle is now `angle`.
    pub fn drive_for(&self, joint: ImpulseJointHandle, axis: JointAxis, angle: f64) -> Drive {
        let limits = self
            .world
            .impulse_joints
            .get(joint)
            .and_then(|j| j.data.limits(axis))
            .map(|l| [f(l.min), f(l.max)]);
        Drive {
            joint,
            axis,
            angle,
            limits,
            max_torque: None,
        }
    }

    /// Command `rate` (rad/s) on `d` for the next step.
    ///
    /// Rapier rebuilds the motor row at the start of each of its `n` substeps
    /// from the pose there, against one target position per step; the target
    /// is the commanded angle at the mean of those substep start times,
    /// t + (n − 1)/(2n)·dt, so the angle error averages to zero over a step
    /// (at the step midpoint the servo would run (n + 1)/(2n)·u·dt ahead).
    pub fn drive(&mut self, d: &mut Drive, rate: f64) {
        let s = &self.settings;
        let n = s.solver_iterations.max(1) as f64;
        let clamp = |a: f64| match d.limits {
            Some([lo, hi]) if lo <= hi => a.clamp(lo, hi),
            _ => a,
        };
        let target = clamp(d.angle + (n - 1.0) / (2.0 * n) * s.dt * rate);
        d.angle = clamp(d.angle + s.dt * rate);
        let (k, c) = (s.motor_gain * s.motor_angle_gain, s.motor_gain);
        // Rapier compares angular targets modulo 2π; a slider's is a length.
        let target = if d.axis == JointAxis::LinX {
            target
        } else {
            crate::compare::wrap_angle(target)
        };
        if let Some(j) = self.world.impulse_joints.get_mut(d.joint, false) {
            j.data
                .set_motor(d.axis, r(target), r(rate), r(k), r(c))
                .set_motor_max_force(
                    d.axis,
                    r(d.max_torque.unwrap_or(s.motor_max_torque) * s.torque_scale),
                );
        }
    }
}

#[cfg(test)]
#[path = "world_tests.rs"]
mod tests;
