//! The chain of [`Chain::Impulse`](super::Chain::Impulse): the segments
//! joined by impulse joints whose force-based motors are the springs and
//! dampers.
//!
//! A force-based motor row is an implicit spring–damper: Rapier solves
//! k (0 − (θ + dt v⁺)) − c v⁺ on the row with its effective mass, so a row
//! stays stable at any stiffness. What the multibody does and this chain
//! does not is converge a load along the chain within the substep: each
//! row is swept Gauss–Seidel with the rest of the world. That converges
//! where every spring is soft against the inertia it moves at the substep,
//! ω = √(k/I) with ω·dt_sub well below 1: the 10 mm rod in 4 joints over
//! 3.3 m bends at ω ≈ 60 rad/s (ω·dt_sub = 0.06 at 1 ms substeps), but in
//! 20 joints over 2 m at ω ≈ 4000 rad/s, where one sweep per substep left a
//! cantilever's tip metres off (the module docs above). The stiff rows (the
//! rod's axial spring, its torsion on the segments' thin-rod roll inertia)
//! saturate and act as locks, as the rod's axial and torsional compliance
//! is far below the wrists' the harness holds it with.

use super::{JointHandle, Seg, SpringJoint};
use crate::physics::rapier::prelude::*;

/// Join the placed segments `segs` (N + 1 of them, frames at arclengths
/// `frame_s`, joints at the midpoints (k − ½) l) into a chain bent to the
/// joint rotations of `centreline`, with the beam's springs `stiffness`
/// (axial of the end joints, torsion, bending) and dampers β k. Moves the
/// segments onto the chain (rotations only: the chain starts at its rest
/// length, as the multibody's).
pub(super) fn chain(
    world: &mut PhysicsWorld,
    segs: &[Seg],
    l: Real,
    frame_s: &dyn Fn(usize) -> Real,
    centreline: &dyn Fn(Real) -> Pose,
    stiffness: [Real; 3],
    beta: Real,
) -> Vec<SpringJoint> {
    let n = segs.len() - 1;
    let [_, kt, kb] = stiffness;
    let at = |x: Real| Pose::from_translation(Vector::new(x, 0.0, 0.0));
    let mut pose = centreline(frame_s(0));
    world.bodies[segs[0].handle].set_position(pose, true);
    let mut joints = Vec::with_capacity(n);
    for k in 1..=n {
        let s = (k as Real - 0.5) * l;
        let (at1, at2) = (s - frame_s(k - 1), s - frame_s(k));
        // Axially rigid: the rod's axial compliance L/(EA) is four orders
        // below what holds it (the wrists' 1/400 m/N), and a spring row that
        // stiff on a few grams saturates into a lock anyway.
        let axial = false;
        // The centreline's rotation across the joint; the body follows its
        // neighbour through the joint point.
        let f1 = centreline(frame_s(k - 1)) * at(at1);
        let f2 = centreline(frame_s(k)) * at(at2);
        let rot = Pose::from_rotation((f1.inverse() * f2).rotation);
        pose = pose * at(at1) * rot * at(-at2);
        world.bodies[segs[k].handle].set_position(pose, true);
        let mut j = GenericJoint::new(JointAxesMask::LIN_AXES);
        j.set_local_frame1(at(at1))
            .set_local_frame2(at(at2))
            .set_contacts_enabled(false);
        let springs = [
            (JointAxis::AngX, kt),
            (JointAxis::AngY, kb),
            (JointAxis::AngZ, kb),
        ];
        for (axis, k) in springs {
            j.set_motor_model(axis, MotorModel::ForceBased)
                .set_motor(axis, 0.0, 0.0, k, beta * k);
        }
        world.insert_impulse_joint(segs[k - 1].handle, segs[k].handle, j);
        joints.push(SpringJoint {
            handle: JointHandle::Impulse,
            at1,
            at2,
            axial,
        });
    }
    joints
}

/// The joint coordinates the motors act on, in the multibody's order
/// (LinX, LinY, LinZ, AngX, AngY, AngZ): frame 2's offset from frame 1 in
/// frame 1's axes, and per axis 2 asin of the relative rotation's
/// quaternion component (the hemisphere of a positive scalar part), as
/// Rapier's angular motor reads it.
pub(super) fn coords(f1: &Pose, f2: &Pose) -> [Real; 6] {
    let rel = f1.inverse() * *f2;
    let mut q = rel.rotation;
    if q.w < 0.0 {
        q = -q;
    }
    let angle = |c: Real| 2.0 * c.clamp(-1.0, 1.0).asin();
    let t = rel.translation;
    [t.x, t.y, t.z, angle(q.x), angle(q.y), angle(q.z)]
}
