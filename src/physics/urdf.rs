//! URDF loading: validation, visual geometry for the logs, and insertion into
//! a Rapier world (rapier3d-urdf, impulse joints, bodies that never sleep).

use crate::record::{LinkVisual, Pose, Shape, Visual};
use crate::scenario::SimConfig;
use nalgebra::UnitQuaternion;
use rapier3d::prelude::*;
use rapier3d_urdf::{UrdfLoaderOptions, UrdfRobot};
use std::collections::{HashMap, HashSet};
use std::path::Path;
use urdf_rs::Robot;

/// Read and validate a URDF file. Errors are one-line, user-facing strings.
///
/// rapier3d-urdf indexes links by name without checking, so dangling joint
/// references, cycles and massless links are rejected here, before it runs.
pub fn read(path: &Path) -> Result<Robot, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read URDF: {e}"))?;
    let robot = urdf_rs::read_from_string(&text)
        .map_err(|e| format!("URDF does not parse: {}", e.to_string().replace('\n', " ")))?;
    if robot.links.is_empty() {
        return Err("URDF has no links".into());
    }
    let names: HashSet<&str> = robot.links.iter().map(|l| l.name.as_str()).collect();
    if names.len() != robot.links.len() {
        return Err("URDF has duplicate link names".into());
    }
    let mut has_parent = HashSet::new();
    for j in &robot.joints {
        for l in [&j.parent.link, &j.child.link] {
            if !names.contains(l.as_str()) {
                return Err(format!("URDF joint `{}` names unknown link `{l}`", j.name));
            }
        }
        if !has_parent.insert(j.child.link.as_str()) {
            return Err(format!(
                "URDF link `{}` has two parent joints",
                j.child.link
            ));
        }
    }
    if has_parent.len() >= robot.links.len() {
        return Err("URDF kinematic graph has no root (cycle)".into());
    }
    for l in &robot.links {
        let m = l.inertial.mass.value;
        if !(m.is_finite() && m > 0.0) {
            return Err(format!(
                "URDF link `{}` needs an <inertial> with mass > 0",
                l.name
            ));
        }
    }
    Ok(robot)
}

/// Radius of the first sphere or cylinder collision of `link`, if any.
pub fn collision_radius(robot: &Robot, link: &str) -> Option<f64> {
    robot
        .links
        .iter()
        .find(|l| l.name == link)?
        .collision
        .iter()
        .find_map(|c| match c.geometry {
            urdf_rs::Geometry::Sphere { radius } | urdf_rs::Geometry::Cylinder { radius, .. } => {
                Some(radius)
            }
            _ => None,
        })
}

/// Check that `link` has a round collision (`what`, e.g. "the wheel") of the
/// scenario's `radius`; the error names both values.
pub fn require_radius(robot: &Robot, link: &str, what: &str, radius: f64) -> Result<(), String> {
    let r = collision_radius(robot, link).ok_or_else(|| {
        format!("URDF needs a link `{link}` with a sphere or cylinder collision ({what})")
    })?;
    if (r - radius).abs() > 1e-6 {
        return Err(format!(
            "URDF radius of {what} ({r} m) differs from the scenario's model.radius ({radius} m)"
        ));
    }
    Ok(())
}

/// URDF pose (xyz, rpy) as a [`Pose`].
pub fn pose_of(p: &urdf_rs::Pose) -> Pose {
    let q = UnitQuaternion::from_euler_angles(p.rpy[0], p.rpy[1], p.rpy[2]);
    Pose {
        translation: [p.xyz[0], p.xyz[1], p.xyz[2]],
        rotation: [q.i, q.j, q.k, q.w],
    }
}

/// Visual geometry of every link, in URDF link order. Meshes are skipped.
pub fn visuals(robot: &Robot) -> Vec<LinkVisual> {
    let named: HashMap<&str, [f64; 4]> = robot
        .materials
        .iter()
        .filter_map(|m| m.color.as_ref().map(|c| (m.name.as_str(), c.rgba.0)))
        .collect();
    robot
        .links
        .iter()
        .map(|l| LinkVisual {
            name: l.name.clone(),
            visuals: l
                .visual
                .iter()
                .filter_map(|v| {
                    let shape = match &v.geometry {
                        urdf_rs::Geometry::Box { size } => Shape::Box { size: size.0 },
                        urdf_rs::Geometry::Cylinder { radius, length } => Shape::Cylinder {
                            radius: *radius,
                            length: *length,
                        },
                        urdf_rs::Geometry::Sphere { radius } => Shape::Sphere { radius: *radius },
                        urdf_rs::Geometry::Capsule { radius, length } => Shape::Capsule {
                            radius: *radius,
                            length: *length,
                        },
                        urdf_rs::Geometry::Mesh { .. } => return None,
                    };
                    let rgba = v
                        .material
                        .as_ref()
                        .and_then(|m| {
                            m.color
                                .as_ref()
                                .map(|c| c.rgba.0)
                                .or_else(|| named.get(m.name.as_str()).copied())
                        })
                        .unwrap_or([0.6, 0.6, 0.6, 1.0]);
                    Some(Visual {
                        shape,
                        origin: pose_of(&v.origin),
                        rgba: rgba.map(|c| c as f32),
                    })
                })
                .collect(),
        })
        .collect()
}

/// A Rapier world holding one URDF robot (and optionally a ground plane).
pub struct SimWorld {
    /// The physics world.
    pub world: PhysicsWorld,
    /// Body of each URDF link, in URDF link order.
    pub links: Vec<RigidBodyHandle>,
    /// Joint handles by URDF joint name.
    pub joints: HashMap<String, ImpulseJointHandle>,
    /// Link index by name.
    pub link_index: HashMap<String, usize>,
    /// The fixed ground body (present even without a ground collider, as a joint anchor).
    pub ground: RigidBodyHandle,
}

/// Settings for [`SimWorld::new`].
pub struct WorldOptions<'a> {
    /// Physics settings.
    pub sim: &'a SimConfig,
    /// Root link pose in the world.
    pub root_pose: rapier3d::math::Pose,
    /// Add a ground plane z = 0 with the scenario's friction.
    pub ground: bool,
}

impl SimWorld {
    /// Build the world; `robot` must come from [`read`].
    pub fn new(robot: &Robot, urdf_dir: &Path, opts: &WorldOptions) -> SimWorld {
        let mut world = PhysicsWorld::new();
        let g = opts.sim.gravity;
        world.gravity = Vector::new(g[0] as Real, g[1] as Real, g[2] as Real);
        world.integration_parameters.dt = opts.sim.dt as Real;
        world.integration_parameters.num_solver_iterations = opts.sim.solver_iterations;
        let mu = opts.sim.friction as Real;
        let ground = world.insert_body(RigidBodyBuilder::fixed());
        if opts.ground {
            let plane = ColliderBuilder::halfspace(nalgebra::Unit::new_unchecked(Vector::Z))
                .friction(mu)
                .friction_combine_rule(CoefficientCombineRule::Min);
            world.insert_collider(plane, Some(ground));
        }
        let options = UrdfLoaderOptions {
            squeeze_empty_fixed_links: false,
            shift: opts.root_pose,
            rigid_body_blueprint: RigidBodyBuilder::dynamic().can_sleep(false),
            collider_blueprint: ColliderBuilder::default()
                .density(0.0)
                .friction(mu)
                .friction_combine_rule(CoefficientCombineRule::Min),
            ..Default::default()
        };
        let urdf = UrdfRobot::from_robot(robot, options, urdf_dir);
        let handles = urdf.insert_using_impulse_joints(
            &mut world.bodies,
            &mut world.colliders,
            &mut world.impulse_joints,
        );
        let links: Vec<RigidBodyHandle> = handles.links.iter().map(|l| l.body).collect();
        let joints = robot
            .joints
            .iter()
            .zip(&handles.joints)
            .map(|(j, h)| (j.name.clone(), h.joint))
            .collect();
        let link_index = robot
            .links
            .iter()
            .enumerate()
            .map(|(i, l)| (l.name.clone(), i))
            .collect();
        SimWorld {
            world,
            links,
            joints,
            link_index,
            ground,
        }
    }

    /// Body handle of a named link.
    pub fn link(&self, name: &str) -> Option<RigidBodyHandle> {
        self.link_index.get(name).map(|&i| self.links[i])
    }

    /// Body of a link the system needs; the error names the missing link.
    pub fn require_link(&self, name: &str) -> Result<RigidBodyHandle, String> {
        self.link(name)
            .ok_or_else(|| format!("URDF has no link `{name}`"))
    }

    /// Handle of a joint the system needs; the error names the missing joint.
    pub fn require_joint(&self, name: &str) -> Result<ImpulseJointHandle, String> {
        self.joints
            .get(name)
            .copied()
            .ok_or_else(|| format!("URDF has no joint `{name}`"))
    }

    /// A world with a ground plane, the robot's root at `root_pose`.
    pub fn on_ground(
        robot: &Robot,
        urdf_dir: &Path,
        sim: &SimConfig,
        root_pose: rapier3d::math::Pose,
    ) -> SimWorld {
        SimWorld::new(
            robot,
            urdf_dir,
            &WorldOptions {
                sim,
                root_pose,
                ground: true,
            },
        )
    }

    /// World pose of every link, in URDF order.
    pub fn link_poses(&self) -> Vec<Pose> {
        self.links
            .iter()
            .map(|h| to_pose(self.world.bodies[*h].position()))
            .collect()
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
                .set_motor_velocity(JointAxis::AngX, rate as Real, gain as Real)
                .set_motor_max_force(JointAxis::AngX, max_torque as Real);
        }
    }
}

/// Rapier pose (f32) as a record [`Pose`].
pub fn to_pose(p: &rapier3d::math::Pose) -> Pose {
    let t = p.translation;
    let r = p.rotation;
    Pose {
        translation: [t.x as f64, t.y as f64, t.z as f64],
        rotation: [r.x as f64, r.y as f64, r.z as f64, r.w as f64],
    }
}
