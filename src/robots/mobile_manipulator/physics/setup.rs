//! Setting up one mobile manipulator in the world: the URDF checked against
//! the planner's DH table, the robot's bodies and joints looked up and its
//! arm placed at the start.

use super::*;

/// Check the URDF's arm joints against the DH table the planner uses.
pub(super) fn check_urdf(robot: &urdf_rs::Robot) -> Result<(), SetupError> {
    for (i, name) in ARM_JOINTS.iter().enumerate() {
        let j = robot
            .joints
            .iter()
            .find(|j| j.name == *name)
            .ok_or_else(|| SetupError::urdf(format!("URDF has no joint `{name}`")))?;
        let (xyz, rpy) = if i == 0 {
            (MOUNT, [0.0; 3])
        } else {
            let r = puma560::DH[i - 1];
            ([r.a, 0.0, r.d], [r.alpha, 0.0, 0.0])
        };
        let bad = (0..3).any(|k| {
            (j.origin.xyz[k] - xyz[k]).abs() > 1e-9 || (j.origin.rpy[k] - rpy[k]).abs() > 1e-9
        }) || j.axis.xyz.0 != [0.0, 0.0, 1.0];
        if bad {
            return Err(SetupError::urdf_at("joint", name.to_string(), format!(
                "URDF joint `{name}` differs from the PUMA 560 model (origin xyz=\"{}\" rpy=\"{}\", axis z expected)",
                crate::engine::urdf_text::numbers(&xyz),
                crate::engine::urdf_text::numbers(&rpy)
            )));
        }
    }
    Ok(())
}

/// Look up one robot's bodies and joints, put its arm at the start angles
/// (the URDF loads at q = 0) and free its casters.
pub(super) fn place_robot(
    sw: &mut SimWorld,
    h: &RobotHandles,
    q: &[f64],
) -> Result<RobotBodies, SetupError> {
    let frames = mm::frames::<f64>(q);
    let base = h.require_link("base_link")?;
    let wheels = [h.require_link(WHEELS[0])?, h.require_link(WHEELS[1])?];
    let wheel_joints = [
        h.require_joint(WHEEL_JOINTS[0])?,
        h.require_joint(WHEEL_JOINTS[1])?,
    ];
    let mut arm = [base; 6];
    let mut arm_joints = [wheel_joints[0]; 6];
    for i in 0..6 {
        arm[i] = h.require_link(Link::Arm(i as u8 + 1).urdf_name())?;
        arm_joints[i] = h.require_joint(ARM_JOINTS[i])?;
    }
    for (body, pose) in arm.iter().zip(&frames.arm) {
        sw.world.bodies[*body].set_position(rl::from_spatial(pose), true);
    }
    let tool = h.require_link("tool")?;
    sw.world.bodies[tool].set_position(rl::from_spatial(&frames.tool), true);
    let tool_joint = h.require_joint("tool_joint")?;
    let mut rolling = Vec::new();
    for name in CASTERS {
        for c in h.colliders_of(name)?.to_vec() {
            if let Some(col) = sw.world.colliders.get_mut(c) {
                // Casters roll freely: no friction.
                col.set_friction(0.0);
            }
            rolling.push(c);
        }
    }
    for w in WHEELS {
        rolling.extend(h.colliders_of(w)?.iter().copied());
    }
    Ok(RobotBodies {
        base,
        wheels,
        wheel_joints,
        arm,
        arm_joints,
        tool,
        tool_joint,
        colliders: h.colliders.clone(),
        rolling,
        links: h.links.clone(),
        theta: q[2],
        q: std::array::from_fn(|i| q[3 + i]),
        q_ref: std::array::from_fn(|i| q[3 + i]),
    })
}

/// Whether collider `c` is a platform box: a cuboid on the base body.
pub(super) fn is_platform(sw: &SimWorld, base: RigidBodyHandle, c: ColliderHandle) -> bool {
    sw.world
        .colliders
        .get(c)
        .is_some_and(|col| col.parent() == Some(base) && col.shape().as_cuboid().is_some())
}
