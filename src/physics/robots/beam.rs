//! The deformable beam of seed 004 in Rapier: a chain of rigid segments
//! joined by compliant joints whose motors act as the beam's springs.
//!
//! # Why not Rapier's soft bodies
//!
//! Evaluated from the 0.36.1 source and tests (`dynamics/soft_body/`,
//! `dynamics/solver/soft_constraint/`, `dynamics/solver/soft_fem/`,
//! `tests/it/soft_body_joints.rs`), without enabling the `fem` feature (a
//! dependency rebuild on a shared machine, while the project moves to
//! `rapier3d-f64`):
//! - **Cells.** `SoftBodyBuilder::cuboid(center, half_extents, nx, ny, nz)`
//!   tetrahedralises a particle grid, five linear tetrahedra per cube;
//!   `SoftBodyCellModel::Corotational` (or `NeoHookean`) cells take
//!   `SoftBodyMaterial::young_modulus`/`poisson_ratio`. Corotational cells
//!   exist *without* `fem`: they are then constraints swept Gauss–Seidel with
//!   the joints. `fem` only adds `SoftBodySolver::Fem` (implicit Euler, one
//!   factorisation per step, conjugate gradient above `max_dense_dofs` = 600
//!   DOFs, capped at 20 iterations).
//! - **Mesh for a 10 mm × 2 m rod.** A circular section becomes a square of
//!   side 0.877 d (equal I). Linear tetrahedra lock in bending unless there
//!   are several cells through the thickness; the minimum (2 × 2 particles
//!   across, one cube) with cubes of aspect ≤ 3 needs ≥ 67 cubes along the
//!   rod (335 cells, 272 particles), aspect 1 needs 200 cubes (1000 cells,
//!   804 particles = 2412 DOFs, past the dense limit: the FEM solver then runs
//!   truncated CG, "under-relaxed, only slower to settle", its doc says).
//! - **Stability at dt = 2 ms, E = 40 GPa.** The axial wave speed
//!   √(E/ρ) = 4.5 km/s crosses a 10 mm cell in 2.2 µs, ~1000× below dt: an
//!   explicit scheme is out; Rapier's cells are implicit soft constraints
//!   (ω = √(k w) mapped to ERP/CFM), stable at any stiffness, but a cell far
//!   stiffer than the substep rate *saturates* to a rigid constraint and the
//!   body's actual stiffness is then set by how far 4–8 Gauss–Seidel sweeps
//!   propagate a load (one cell per sweep) along 67–200 cells, not by E. The
//!   bending modes that matter (1.6 Hz for the 2 m cantilever, 4.4 Hz for a
//!   3 m clamped–clamped beam) would be far too soft and iteration-dependent.
//!   The `Fem` solver is converged per substep but hits the DOF limit above.
//! - **Cost.** 335–1000 cells plus the contact/recovery machinery per step
//!   against 20 rigid bodies and 20 joints for the chain below.
//! - **Attachments** work (clusters with proxy rigid bodies take impulse
//!   joints, `tests/it/soft_body_joints.rs`), but the grasp wrench would have to
//!   be read from cluster impulses.
//!
//! Hence the fallback the issue names, which handles large rotations
//! exactly (each segment is a rigid body, each joint rotation is finite).
//!
//! # The chain
//!
//! N (even) joints at s = (k − ½) l, l = L/N, k = 1..N, split the beam into
//! N + 1 rigid bodies: two end half-segments [0, l/2] and [L − l/2, L] and
//! N − 1 full segments centred at s = k l. Each joint stands for the beam
//! length l around it (the midpoint rule), so a uniform moment or torque is
//! reproduced exactly, a tip load's tip rotation too, and its tip deflection
//! is PL³/(3EI)·(1 − 1/(4N²)). The middle FE node is body N/2's frame.
//!
//! Joint k frames sit at the joint point, x along the rest tangent: shear
//! (LinY, LinZ) locked (Timoshenko shear flexibility of a slender rod,
//! ~(d/l)², is negligible), springs with rest 0 on the three rotations:
//! torsion GJ/l on AngX, bending EI/l on AngY and AngZ (a ball joint, the
//! discrete inextensible Kirchhoff rod). The axial compliance L/(EA) of the
//! whole beam sits in the two end joints (k = 1 and N), which also slide
//! along LinX with a spring 2 EA/L each: in series EA/L, so the static axial
//! force and the total (and the middle node's) stretch are the beam's, while
//! the interior joints are axially rigid. Spreading it over every joint
//! (EA/l each, as the chain first did) resolved axial modes of 0.5–7 kHz
//! (2 m rod) that the harness never excites (the stretch is micrometres)
//! and cost 4N instead of 3N + 2 DOFs in the multibody's dense mass matrix.
//! Damping is stiffness-proportional, c = β k with β =
//! [`BeamOptions::damping_time`] (default 2 ms: ζ = β ω / 2, about 1 % at the
//! 2 m cantilever's 1.6 Hz, 3 % at 4.4 Hz, the range of GFRP's structural
//! damping; the chain's own high modes, ω ≳ 1/β, come out over-damped).
//!
//! **Multibody, not impulse joints.** The chain is one Rapier multibody
//! (reduced coordinates) whose joint springs (`MultibodyJoint::set_spring`)
//! and joint-space dampers (`Multibody::damping_mut`) are integrated
//! implicitly in the articulated mass matrix: the static equilibrium is
//! exact whatever the stiffness/inertia ratio. The first build used impulse
//! joints with force-based motors as springs; at these ratios (EI/l on a
//! 16 g segment: ω ≈ 4000 rad/s against a 0.5 ms substep) each motor row is
//! saturated and one Gauss–Seidel sweep per substep cannot carry a load
//! along the chain: a 0.1 N tip load on the 2 m cantilever (N = 20, β up to
//! 50 ms, 4 or 20 iterations, with or without joint warm-starting) swung
//! the tip by 0.1–1.9 m against the closed form's 13.6 mm. The multibody's
//! cost is a dense mass matrix (two, with and without the Coriolis terms),
//! assembled and LU-factorised in its 6 + 3N + 2 DOFs at every substep:
//! ~O(N³), hence N = 10 by default and few substeps (see `benches/beam.rs`).
//! The tests validate the chain at dt = 2 ms under 4 substeps of one
//! Gauss–Seidel sweep and under one substep of 16 sweeps: the second costs a
//! quarter of the multibody work and converges the impulse joints at the
//! ends further (the clamped–clamped sag reaches the chain's own static
//! value), at ~1 % more numerical damping of the first bending mode
//! (implicit Euler over 2 ms instead of 0.5 ms).
//!
//! End attachments are impulse fixed joints (loop closures through the
//! holders); impulse joints without locked axes switch contacts off between
//! each holder and the segments within [`BeamOptions::grip_clearance`].
//! Each body carries the mass ρ A of its length, centred, and the inertia of
//! a rod of that length; colliders are massless capsules along x.
//!
//! A curved initial centreline is imposed through the joint rotations (the
//! chain starts unstretched). Released from a strongly bent shape (κ = 0.5 m⁻¹) a free beam leaves its
//! first steps with a spurious linear momentum of ~0.01 kg m/s (a COM drift
//! of 3 cm/s), nearly constant afterwards (it changes by 2·10⁻⁵ kg m/s over
//! 5 s at 4 substeps, 3·10⁻⁴ at one substep: Rapier's reduced-coordinate
//! integration is not exactly momentum-conserving); straight or gently bent
//! starts (the harness's) do not show it.
//!
//! # Read-back
//!
//! Node poses (end 0, middle, end 2, x along the deformed tangent), every
//! body's pose, and the wrench each end attachment exerts on the beam. The
//! wrench is not read from joint impulses (Rapier orthogonalises a joint's
//! rows, so the stored impulses are not in a physical basis): it is the
//! Newton–Euler balance of the end body and its neighbour, with the joints'
//! moments and the end joints' axial forces from the spring laws on the
//! multibody's joint coordinates and the shear from the neighbour's
//! rotational balance.
//! Accelerations come from velocity differences, so call
//! [`PhysicsBeam::after_step`] after every step.

use crate::error::SetupError;
use crate::model::beam::Beam;
use crate::physics::rapier::prelude::*;

/// Chain resolution and damping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamOptions {
    /// Number of compliant joints N (even, ≥ 2); N + 1 bodies.
    pub segments: usize,
    /// Stiffness-proportional damping time β, s: each spring k gets a damper
    /// β k.
    pub damping_time: Real,
    /// Beam length, m, from each attached end over which the beam's segments
    /// never touch the attached body (contacts disabled pairwise).
    pub grip_clearance: Real,
}

impl Default for BeamOptions {
    fn default() -> Self {
        BeamOptions {
            segments: 10,
            damping_time: 2e-3,
            grip_clearance: 0.25,
        }
    }
}

/// A rigid attachment of a beam end to a body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attachment {
    /// The body holding the end.
    pub body: RigidBodyHandle,
    /// The end frame in that body's frame.
    pub frame: Pose,
}

/// A force and a torque, world frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wrench {
    /// Force, N.
    pub force: Vector,
    /// Torque, N m.
    pub torque: Vector,
}

/// Per-body constants.
#[derive(Debug, Clone, Copy)]
struct Seg {
    handle: RigidBodyHandle,
    mass: Real,
    /// Centre of mass in the body frame (on x).
    com: Real,
    /// Principal inertia (axial, transverse, transverse) about the centre.
    inertia: Vector,
}

/// One spring joint: handle and its frames' x offsets on both bodies.
#[derive(Debug, Clone, Copy)]
struct SpringJoint {
    handle: MultibodyJointHandle,
    at1: Real,
    at2: Real,
    /// Whether the joint slides axially (the two end joints).
    axial: bool,
}

/// A beam inserted in a [`PhysicsWorld`].
#[derive(Debug, Clone)]
pub struct PhysicsBeam {
    segs: Vec<Seg>,
    joints: Vec<SpringJoint>,
    ends: [Option<ImpulseJointHandle>; 2],
    length: Real,
    radius: Real,
    /// (axial, torsion, bending) stiffness of a joint, N/m and N m/rad;
    /// the axial one of each of the two end joints.
    stiffness: [Real; 3],
    damping_time: Real,
    /// Velocities after the last step and the accelerations over it.
    last: Vec<(Vector, Vector)>,
    accel: Vec<(Vector, Vector)>,
}

fn real(v: f64) -> Real {
    v
}

impl PhysicsBeam {
    /// Insert `beam` into `world`, its centreline at s ∈ [0, L] given by
    /// `centreline(s)` (world pose, x along the tangent; the rest shape is
    /// straight, so a curved initial centreline starts loaded). `ends[0]`
    /// and `ends[1]` fix end 0 and end 2 to bodies (`None`: free). All
    /// colliders get `groups`; the attached bodies never touch the beam
    /// within `grip_clearance` of their end.
    pub fn insert(
        world: &mut PhysicsWorld,
        beam: &Beam,
        opts: &BeamOptions,
        centreline: &dyn Fn(Real) -> Pose,
        ends: [Option<Attachment>; 2],
        groups: InteractionGroups,
    ) -> Result<PhysicsBeam, SetupError> {
        beam.validate()?;
        let n = opts.segments;
        if n < 2 || !n.is_multiple_of(2) {
            return Err(SetupError::other(format!(
                "beam segments must be even and ≥ 2, got {n}"
            )));
        }
        if !(opts.damping_time.is_finite() && opts.damping_time >= 0.0) {
            return Err(SetupError::other(
                "beam damping_time must be ≥ 0".to_string(),
            ));
        }
        let len = real(beam.length);
        let l = len / n as Real;
        let rho_a = real(beam.mass_per_length());
        let ro = real(beam.section.outer_diameter) / 2.0;
        let ri = real(beam.section.inner_diameter) / 2.0;
        let r2 = (ro * ro + ri * ri) / 4.0;
        // The two end joints carry the axial compliance of the whole beam,
        // L/(EA), in series: 2 EA/L each.
        let stiffness = [
            2.0 * real(beam.axial_stiffness()) / len,
            real(beam.torsional_stiffness()) / l,
            real(beam.bending_stiffness()) / l,
        ];
        // Body k: frame arclength, extent [a, b].
        let frame_s = |k: usize| match k {
            0 => 0.0,
            k if k == n => len,
            k => k as Real * l,
        };
        let extent = |k: usize| {
            let a = if k == 0 { 0.0 } else { (k as Real - 0.5) * l };
            let b = if k == n { len } else { (k as Real + 0.5) * l };
            (a, b)
        };
        let mut segs = Vec::with_capacity(n + 1);
        for k in 0..=n {
            let (a, b) = extent(k);
            let s0 = frame_s(k);
            let seg_len = b - a;
            let mass = rho_a * seg_len;
            let com = 0.5 * (a + b) - s0;
            let it = mass * (r2 + seg_len * seg_len / 12.0);
            let inertia = Vector::new(2.0 * mass * r2, it, it);
            let props = MassProperties::new(Vector::new(com, 0.0, 0.0), mass, inertia);
            let body = RigidBodyBuilder::dynamic()
                .pose(centreline(s0))
                .additional_mass_properties(props)
                .can_sleep(false);
            let handle = world.insert_body(body);
            let collider = ColliderBuilder::capsule_x(0.5 * seg_len, ro)
                .position(Pose::from_translation(Vector::new(com, 0.0, 0.0)))
                .density(0.0)
                .collision_groups(groups);
            world.insert_collider(collider, Some(handle));
            segs.push(Seg {
                handle,
                mass,
                com,
                inertia,
            });
        }
        let beta = opts.damping_time;
        let [ka, kt, kb] = stiffness;
        let mut joints = Vec::with_capacity(n);
        for k in 1..=n {
            let s = (k as Real - 0.5) * l;
            let (at1, at2) = (s - frame_s(k - 1), s - frame_s(k));
            let axial = k == 1 || k == n;
            let locked = if axial {
                JointAxesMask::LIN_Y | JointAxesMask::LIN_Z
            } else {
                JointAxesMask::LIN_AXES
            };
            let mut j = GenericJoint::new(locked);
            j.set_local_frame1(Pose::from_translation(Vector::new(at1, 0.0, 0.0)))
                .set_local_frame2(Pose::from_translation(Vector::new(at2, 0.0, 0.0)))
                .set_contacts_enabled(false);
            let handle = world
                .insert_multibody_joint(segs[k - 1].handle, segs[k].handle, j)
                .ok_or("beam: Rapier refused a multibody joint of the chain")?;
            joints.push(SpringJoint {
                handle,
                at1,
                at2,
                axial,
            });
        }
        // Springs and joint-space dampers on the free DOFs, in Rapier's order
        // ([LinX,] AngX, AngY, AngZ), both integrated implicitly.
        let (mb, _) = world
            .multibody_joints
            .get_mut(joints[0].handle)
            .ok_or("beam: chain multibody missing")?;
        let mut dofs = Vec::new();
        for (link, sj) in mb.links_mut().skip(1).zip(&joints) {
            let axes: &[(usize, Real)] = if sj.axial {
                &[(0, ka), (3, kt), (4, kb), (5, kb)]
            } else {
                &[(3, kt), (4, kb), (5, kb)]
            };
            let a = link.assembly_id();
            for (i, &(axis, stiff)) in axes.iter().enumerate() {
                link.joint.set_spring(axis, stiff, 0.0);
                dofs.push((a + i, stiff));
            }
        }
        for (i, stiff) in dofs {
            mb.damping_mut()[i] = beta * stiff;
        }
        // A curved initial centreline: joint coordinates from the placed
        // bodies (Rapier otherwise snaps the chain straight at the first step).
        let mut disp = vec![0.0; mb.ndofs()];
        for (j, sj) in joints.iter().enumerate() {
            let f = |k: usize, at: Real| {
                centreline(frame_s(k)) * Pose::from_translation(Vector::new(at, 0.0, 0.0))
            };
            // Rotations only: the chain starts at its rest length (the gaps
            // between neighbouring tangents of a curved centreline are its
            // discretisation, not a stretch).
            let rel = f(j, sj.at1).inverse() * f(j + 1, sj.at2);
            let rot = rel.rotation.to_scaled_axis();
            let a = mb.link(j + 1).map_or(0, |l| l.assembly_id()) + usize::from(sj.axial);
            disp[a..a + 3].copy_from_slice(&[rot.x, rot.y, rot.z]);
        }
        mb.apply_displacements(&disp);
        mb.forward_kinematics(&world.bodies, true);
        let poses: Vec<Pose> = mb.links().map(|l| *l.local_to_world()).collect();
        for (seg, pose) in segs.iter().zip(poses) {
            world.bodies[seg.handle].set_position(pose, true);
        }
        let mut end_joints = [None, None];
        for (e, att) in ends.iter().enumerate() {
            let Some(att) = att else { continue };
            let beam_body = if e == 0 {
                segs[0].handle
            } else {
                segs[n].handle
            };
            if world.bodies.get(att.body).is_none() {
                return Err(SetupError::other(format!(
                    "beam end {}: attachment body not in the world",
                    2 * e
                )));
            }
            let mut j = GenericJoint::new(JointAxesMask::LOCKED_FIXED_AXES);
            j.set_local_frame1(att.frame)
                .set_local_frame2(Pose::IDENTITY)
                .set_contacts_enabled(false);
            end_joints[e] = Some(world.insert_impulse_joint(att.body, beam_body, j));
            // Joints without locked axes only switch contacts off between the
            // holder and the segments near the grip.
            for (k, seg) in segs.iter().enumerate() {
                let (a, b) = extent(k);
                let near = if e == 0 {
                    a < opts.grip_clearance
                } else {
                    b > len - opts.grip_clearance
                };
                let attached = (e == 0 && k == 0) || (e == 1 && k == n);
                if near && !attached {
                    let mut free = GenericJoint::new(JointAxesMask::empty());
                    free.set_contacts_enabled(false);
                    world.insert_impulse_joint(att.body, seg.handle, free);
                }
            }
        }
        let mut out = PhysicsBeam {
            segs,
            joints,
            ends: end_joints,
            length: len,
            radius: ro,
            stiffness,
            damping_time: beta,
            last: Vec::new(),
            accel: vec![(Vector::ZERO, Vector::ZERO); n + 1],
        };
        out.last = out.velocities(world);
        Ok(out)
    }

    /// Number of spring joints N.
    pub fn segments(&self) -> usize {
        self.joints.len()
    }

    /// The N + 1 rigid bodies, end 0 first.
    pub fn bodies(&self) -> Vec<RigidBodyHandle> {
        self.segs.iter().map(|s| s.handle).collect()
    }

    /// The fixed joints of the end attachments (end 0, end 2).
    pub fn end_joints(&self) -> [Option<ImpulseJointHandle>; 2] {
        self.ends
    }

    fn velocities(&self, world: &PhysicsWorld) -> Vec<(Vector, Vector)> {
        self.segs
            .iter()
            .map(|s| {
                let b = &world.bodies[s.handle];
                (b.linvel(), b.angvel())
            })
            .collect()
    }

    /// Record the velocities after a step of length `dt` (accelerations for
    /// [`PhysicsBeam::grasp_wrenches`]); call after every `world.step()`.
    pub fn after_step(&mut self, world: &PhysicsWorld) {
        let dt = world.integration_parameters.dt;
        let now = self.velocities(world);
        for ((acc, new), old) in self.accel.iter_mut().zip(&now).zip(&self.last) {
            *acc = ((new.0 - old.0) / dt, (new.1 - old.1) / dt);
        }
        self.last = now;
    }

    /// World pose of body `k`'s frame.
    fn pose(&self, world: &PhysicsWorld, k: usize) -> Pose {
        *world.bodies[self.segs[k].handle].position()
    }

    /// World poses of the three FE nodes: end 0, the middle (s = L/2) and
    /// end 2, x along the deformed tangent.
    pub fn node_poses(&self, world: &PhysicsWorld) -> [Pose; 3] {
        let n = self.segments();
        [
            self.pose(world, 0),
            self.pose(world, n / 2),
            self.pose(world, n),
        ]
    }

    /// For drawing: each body's centre pose (x along the segment), half
    /// length and radius, end 0 first.
    pub fn segment_poses(&self, world: &PhysicsWorld) -> Vec<(Pose, Real, Real)> {
        let n = self.segments();
        let l = self.length / n as Real;
        (0..=n)
            .map(|k| {
                let half = if k == 0 || k == n { 0.25 * l } else { 0.5 * l };
                let p = self.pose(world, k)
                    * Pose::from_translation(Vector::new(self.segs[k].com, 0.0, 0.0));
                (p, half, self.radius)
            })
            .collect()
    }

    /// The spring wrench joint `j` (index 0..N, between bodies j and j+1)
    /// exerts on its second body, about the joint point, with the joint's
    /// axial force along the first body's axis (NaN for an interior,
    /// axially rigid joint): (force, torque, point, axis).
    fn spring(&self, world: &PhysicsWorld, j: usize) -> (Real, Vector, Vector, Vector) {
        let sj = &self.joints[j];
        let (b1, b2) = (
            &world.bodies[self.segs[j].handle],
            &world.bodies[self.segs[j + 1].handle],
        );
        let (p1, p2) = (b1.position(), b2.position());
        let f1 = *p1 * Pose::from_translation(Vector::new(sj.at1, 0.0, 0.0));
        let f2 = *p2 * Pose::from_translation(Vector::new(sj.at2, 0.0, 0.0));
        let [ka, kt, kb] = self.stiffness;
        // Implicit Euler: the spring acts at q + dt v⁺, the damper β k v⁺.
        let beta = self.damping_time + world.integration_parameters.dt;
        let r1 = f1.rotation;
        let x1 = r1 * Vector::X;
        // Axial: stretch along x1 and its rate at the joint point.
        let point = f2.translation;
        let v1 = b1.linvel() + b1.angvel().cross(point - b1.center_of_mass());
        let v2 = b2.linvel() + b2.angvel().cross(point - b2.center_of_mass());
        // The multibody's own joint coordinates: what its springs act on, and
        // exact where a difference of world positions would lose the axial
        // stretch (nm) to rounding.
        let q = match world.multibody_joints.get(sj.handle) {
            Some((mb, link)) => mb.link(link).map_or([0.0; 6], |l| l.joint().coords()),
            None => [0.0; 6],
        };
        // Interior joints are axially rigid: their force is a reaction, not a spring's.
        let axial = if sj.axial {
            -ka * (q[0] + beta * (v2 - v1).dot(x1))
        } else {
            Real::NAN
        };
        let theta = Vector::new(q[3], q[4], q[5]);
        let w = r1.inverse() * (b2.angvel() - b1.angvel());
        let k = Vector::new(kt, kb, kb);
        let local = -(k * (theta + beta * w));
        (axial, r1 * local, point, x1)
    }

    /// Body `k`'s inertial wrench terms: m (a − g) − f_user and
    /// I α + ω × I ω − τ_user about its centre of mass, and that centre.
    fn inertial(&self, world: &PhysicsWorld, k: usize) -> (Vector, Vector, Vector) {
        let s = &self.segs[k];
        let b = &world.bodies[s.handle];
        let (a, alpha) = self.accel[k];
        let rot = b.position().rotation;
        let inertia = |v: Vector| rot * (s.inertia * (rot.inverse() * v));
        let w = b.angvel();
        let g = world.gravity * b.gravity_scale();
        let f = s.mass * (a - g) - b.user_force();
        let t = inertia(alpha) + w.cross(inertia(w)) - b.user_torque();
        (f, t, b.center_of_mass())
    }

    /// Full wrench (force, torque about the joint point) that joint `j`
    /// exerts on body j+1, with the locked shear from body `via`'s
    /// rotational balance (`via` = j+1 or j, an interior body).
    fn joint_wrench(&self, world: &PhysicsWorld, j: usize) -> (Vector, Vector, Vector) {
        let (axial, torque, point, x1) = self.spring(world, j);
        // Body j+1 must be interior (1..N-1), or use body j (interior) for the last joint.
        let n = self.segments();
        let (via, sign) = if j + 1 < n { (j + 1, 1.0) } else { (j, -1.0) };
        // Balance of body `via` between its joints jin = via-1 (force F_in on it)
        // and jout = via (force -F_out on it): F_out = F_in - f_inert.
        let (fi, ti, c) = self.inertial(world, via);
        let (_, m_in, p_in, _) = self.spring(world, via - 1);
        let (_, m_out, p_out, _) = self.spring(world, via);
        let (d, e) = (p_in - c, p_out - c);
        // I α + ω×Iω − τ = M_in − M_out + d × F_in − e × (F_in − f_inert)
        //   ⇒ (d − e) × F_in = ti − M_in + M_out − e × fi
        let u = d - e;
        let rhs = ti - m_in + m_out - e.cross(fi);
        let f_perp = rhs.cross(u) / u.dot(u);
        // The unknown joint is `via`'s incoming (sign 1) or outgoing (sign −1) one.
        let f_in = {
            // F_in along u is free here; fix it by the axial spring of the joint we want.
            let uh = u.normalize();
            if sign > 0.0 {
                let beta_ = (axial - f_perp.dot(x1)) / uh.dot(x1);
                f_perp + beta_ * uh
            } else {
                // F_out = F_in − fi must have F_out · x1 = axial.
                let beta_ = (axial + fi.dot(x1) - f_perp.dot(x1)) / uh.dot(x1);
                f_perp + beta_ * uh
            }
        };
        let force = if sign > 0.0 { f_in } else { f_in - fi };
        (force, torque, point)
    }

    /// The wrench each end attachment exerts on the beam (force, and torque
    /// about the end frame's origin; world frame), `None` for a free end.
    /// The holder feels the opposite. Needs [`PhysicsBeam::after_step`]
    /// after every step for the inertial terms.
    pub fn grasp_wrenches(&self, world: &PhysicsWorld) -> [Option<Wrench>; 2] {
        let n = self.segments();
        let mut out = [None, None];
        if self.ends[0].is_some() {
            // Body 0: F_A − F_1 = fi, M_A + (p0 − c) × F_A − M_1 − (p1 − c) × F_1 = ti.
            let (fi, ti, c) = self.inertial(world, 0);
            let (f1, m1, p1) = self.joint_wrench(world, 0);
            let p0 = self.pose(world, 0).translation;
            let fa = fi + f1;
            let ma = ti - (p0 - c).cross(fa) + m1 + (p1 - c).cross(f1);
            out[0] = Some(Wrench {
                force: fa,
                torque: ma,
            });
        }
        if self.ends[1].is_some() {
            // Body N: F_N + F_A = fi, M_N + (pN − c) × F_N + M_A + (pe − c) × F_A = ti.
            let (fi, ti, c) = self.inertial(world, n);
            let (fnn, mn, pn) = self.joint_wrench(world, n - 1);
            let pe = self.pose(world, n).translation;
            let fa = fi - fnn;
            let ma = ti - mn - (pn - c).cross(fnn) - (pe - c).cross(fa);
            out[1] = Some(Wrench {
                force: fa,
                torque: ma,
            });
        }
        out
    }
}

#[cfg(test)]
mod tests;
