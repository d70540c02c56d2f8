//! The carried object of seed 004 as the planner sees it (§II, §III-B): a
//! beam rigidly grasped by two robots, its nodal deformations q_f from the
//! grasps (the finite-element model [`FeBeam`]), the admissible balls of its
//! nodes (Eqs. 11–12) and its ellipsoids, which every robot part meets as
//! obstacles in its own workspace copy.
//!
//! Grasps: end 0 of the beam is fixed to robot 1's tool frame, end 2 to robot
//! 2's, each by a constant offset ([`Carried::grasp`]). [`Carried::at_rest`]
//! chooses the offsets so that the beam is straight (q_s = 0) at a given
//! configuration of both robots: end 0 at robot 1's grasp point with its x
//! axis towards robot 2's grasp point and its z axis as close to world up as
//! that allows; end 2 the same frame translated by the beam length.
//!
//! b_f ([`Bound`]): with the printed bound, Eq. 12 multiplies, per node,
//! q_F² − ‖q_fi‖² (the ball under the ∞-norm box of Eq. 5, |q_fi,j| ≤ q_F).
//! Like the proximities of V, each factor is normalised by q_F², b_fi = 1 −
//! ‖q_fi‖²/q_F² ∈ (−∞, 1], so that b_f keeps its zero set and does not
//! scale V by q_F^4; b_f ≤ 0 is the deformation "collision" (V = 0). With
//! the wrench bound (ours) the factors are 1 − |F_e|²/F_max² and 1 −
//! |M_e|²/M_max² of the wrench each gripper applies to the beam (end e = 0,
//! 2), from the statics of the carried chain ([`GraspStatics`]).
//!
//! Wrists ([`Wrist`]): a compliant wrist is a spring between a flange and
//! its gripper, centred at the grasp point. The grasps are then the
//! flanges' grasp frames (what the arms' joints fix), q_s = ξ their
//! relative twist, which the wrists' deflections and the beam's deformation
//! share: the beam's nodes (and so its ellipsoids) and the middle node of
//! q_f come from the chain's statics, the beam moving with the wrists.

use crate::model::spatial::{self, k, Pose, Scalar, M3};
use crate::robots::mobile_manipulator::beam::{Beam, BeamError, FeBeam, GraspStatics};
use crate::robots::mobile_manipulator::ellipsoid::PlacedEllipsoid;
use crate::robots::mobile_manipulator::kinematics::{self as mm, Wrist, DOF};

/// Standard gravity, world frame (z up), m/s².
pub const GRAVITY: [f64; 3] = [0.0, 0.0, -9.81];

/// The beam's admissible set (Eqs. 5, 11–12).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Bound {
    /// Eq. 11's balls on the nodes of q_f: ‖q_fi‖ ≤ q_F, m and rad alike
    /// (the SI reading of the paper's units).
    #[default]
    Printed,
    /// What the beam and the robots bear (ours): at each grasp the force
    /// the gripper applies to the beam |F| ≤ `force` (N) and its moment
    /// about the grasp point |M| ≤ `moment` (N m).
    Wrench {
        /// F_max, N.
        force: f64,
        /// M_max, N m.
        moment: f64,
    },
}

/// A beam held by robots 1 and 2.
#[derive(Debug, Clone)]
pub struct Carried {
    /// Finite-element model.
    pub fe: FeBeam,
    /// Tool frame → beam end frame, robot 1 (end 0) and robot 2 (end 2).
    pub grasp: [Pose<f64>; 2],
    /// q_F of Eq. 5 (m and rad, as q_f mixes them); used by [`Bound::Printed`].
    pub q_max: f64,
    /// The admissible set.
    pub bound: Bound,
    /// The wrists (both robots alike).
    pub wrist: Wrist,
    /// The carried chain's statics, when the bound or the wrists need it.
    statics: Option<GraspStatics>,
    /// Number of ellipsoids along the beam.
    pub segments: usize,
    /// Cross semi-axes of the beam's ellipsoids, m (the rod's radius plus a margin).
    pub radius: f64,
    /// Bound on the grasps' axial deformation |q_f\[0\]| (stretch or
    /// shortening along the beam), m, if any (ours, see [`Carried::with_max_stretch`]).
    pub max_stretch: Option<f64>,
}

/// The beam at one configuration.
#[derive(Debug, Clone)]
pub struct BeamState<T: Scalar> {
    /// World pose of end 0 (flange 1's grasp frame).
    pub end0: Pose<T>,
    /// q_f = (q_s, q_o): node 2 then node 1 (see [`FeBeam`]).
    pub q_f: [T; 12],
    /// Gravity in the end-0 frame, m/s².
    pub gravity: [T; 3],
}

impl<T: Scalar> BeamState<T> {
    /// ‖q_f‖∞ (Eq. 5).
    pub fn max_deformation(&self) -> f64 {
        self.q_f.iter().fold(0.0f64, |m, x| m.max(x.re().abs()))
    }
}

/// Why a beam cannot be carried between the two grasps.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CarriedError {
    /// The grasp points' distance at the start differs from the beam's length.
    #[error(
        "the grasp points are {dist:.4} m apart at the start, the beam is {length:.4} m long: \
         the grasps cannot hold it undeformed"
    )]
    Apart {
        /// Distance between the grasp points, m.
        dist: f64,
        /// The beam's rest length, m.
        length: f64,
    },
    /// The two grasp points are at the same place.
    #[error("the two grasp points coincide")]
    Coincide,
    /// The beam or its stiffness model is unusable.
    #[error(transparent)]
    Beam(#[from] BeamError),
    /// The force bound is not finite and > 0.
    #[error("`max_force` must be > 0 N, got {}", crate::numfmt::readable(*.0))]
    MaxForce(f64),
    /// The moment bound is not finite and > 0.
    #[error("`max_moment` must be > 0 N m, got {}", crate::numfmt::readable(*.0))]
    MaxMoment(f64),
}

/// A frame at `p` whose x axis points along `x` and whose z axis is as close
/// to world up as that allows.
fn frame_along(p: [f64; 3], x: [f64; 3]) -> Result<Pose<f64>, CarriedError> {
    let n = spatial::dot(x, x).sqrt();
    if n < 1e-6 {
        return Err(CarriedError::Coincide);
    }
    let ex = [x[0] / n, x[1] / n, x[2] / n];
    let up = if ex[2].abs() < 0.99 {
        [0.0, 0.0, 1.0]
    } else {
        [1.0, 0.0, 0.0]
    };
    let ey = spatial::cross(up, ex);
    let m = spatial::dot(ey, ey).sqrt();
    let ey = [ey[0] / m, ey[1] / m, ey[2] / m];
    let ez = spatial::cross(ex, ey);
    let r: M3<f64> = std::array::from_fn(|i| [ex[i], ey[i], ez[i]]);
    Ok(Pose { r, p })
}

impl Carried {
    /// A beam straight (q_s = 0) at configuration `q` (both robots). `length`:
    /// the beam's rest length, or `None` for the distance between the grasp
    /// points at `q`. Errors (user-facing): the grasps cannot hold a beam of
    /// that length at `q`, or the beam is invalid.
    pub fn at_rest(
        beam: &Beam,
        length: Option<f64>,
        q: &[f64],
        q_max: f64,
        segments: usize,
        radius: f64,
    ) -> Result<Carried, CarriedError> {
        let (t1, t2) = (mm::frames(&q[..DOF]).tool, mm::frames(&q[DOF..]).tool);
        let (p1, p2) = (mm::grasp_point(&q[..DOF]), mm::grasp_point(&q[DOF..]));
        let d = spatial::sub(p2, p1);
        let dist = spatial::dot(d, d).sqrt();
        let length = length.unwrap_or(dist);
        if (dist - length).abs() > 1e-3 {
            return Err(CarriedError::Apart { dist, length });
        }
        let beam = Beam { length, ..*beam };
        let fe = FeBeam::new(&beam)?;
        let end0 = frame_along(p1, d)?;
        let end2 = end0.then(&Pose::translation([length, 0.0, 0.0]));
        Ok(Carried {
            fe,
            grasp: [t1.inverse().then(&end0), t2.inverse().then(&end2)],
            q_max,
            bound: Bound::Printed,
            wrist: Wrist::Rigid,
            statics: None,
            segments: segments.max(1),
            radius,
            max_stretch: None,
        })
    }

    /// The same beam with `bound` and `wrist`: solves the carried chain's
    /// statics when either needs it. Errors name the offending field.
    pub fn with_grasps(mut self, bound: Bound, wrist: Wrist) -> Result<Carried, CarriedError> {
        if let Bound::Wrench { force, moment } = bound {
            if !(force.is_finite() && force > 0.0) {
                return Err(CarriedError::MaxForce(force));
            }
            if !(moment.is_finite() && moment > 0.0) {
                return Err(CarriedError::MaxMoment(moment));
            }
        }
        // In end-0 axes (the end frames share them at rest): the grasp
        // offset's rotation has the end frame's axes in tool coordinates.
        let stiffness = |g: &Pose<f64>| match wrist {
            Wrist::Rigid => None,
            Wrist::Compliant(w) => Some(w.stiffness_in(&g.r)),
        };
        self.statics = match (bound, wrist) {
            (Bound::Printed, Wrist::Rigid) => None,
            _ => Some(GraspStatics::new(
                &self.fe,
                [stiffness(&self.grasp[0]), stiffness(&self.grasp[1])],
            )?),
        };
        self.bound = bound;
        self.wrist = wrist;
        Ok(self)
    }

    /// Whether the wrists are compliant (the beam's nodes then come from
    /// the chain's statics).
    fn compliant(&self) -> Option<&GraspStatics> {
        match self.wrist {
            Wrist::Rigid => None,
            Wrist::Compliant(_) => self.statics.as_ref(),
        }
    }

    /// The wrenches the grippers apply to the beam (end 0, end 2: force N,
    /// moment N m about the grasp point, end-0 axes) at the state's
    /// deformation, from the chain's statics (`None` with the printed bound
    /// and rigid wrists, where they are not modelled).
    pub fn wrenches<T: Scalar>(&self, q_f: &[T; 12], g: &[T; 3]) -> Option<[[T; 6]; 2]> {
        let xi: [T; 6] = std::array::from_fn(|i| q_f[i]);
        self.statics.as_ref().map(|s| s.wrenches(&xi, g))
    }

    /// The wrists' deflections (wrist 1, wrist 2: translation m, rotation
    /// rad; end-0 axes) at a state, `None` with rigid wrists.
    pub fn wrist_deflections<T: Scalar>(&self, q_f: &[T; 12], g: &[T; 3]) -> Option<[[T; 6]; 2]> {
        let xi: [T; 6] = std::array::from_fn(|i| q_f[i]);
        self.compliant().map(|s| {
            let n = s.nodes(&xi, g);
            [n[0], std::array::from_fn(|i| xi[i] - n[2][i])]
        })
    }

    /// Bound the axial component of q_s, |q_f\[0\]| ≤ `eps` (m), besides Eq.
    /// 5. Eq. 5 bounds every component alike, in m and rad, but a solid rod
    /// is ~10⁵ times stiffer in stretch than in bending: a few millimetres
    /// of stretch are kilonewtons, which a real pair of grippers does not
    /// hold, while Eq. 5's q_F lets the plan stretch the beam's model by
    /// decimetres. The bound enters b_f as one more factor 1 − (q_f\[0\]/ε)²
    /// (zero at the bound), like the nodes' balls.
    pub fn with_max_stretch(mut self, eps: Option<f64>) -> Carried {
        self.max_stretch = eps;
        self
    }

    /// The admissible set's factors at (q_f, g), in order, to `each`: with
    /// the printed bound per node 1 − ‖q_fi‖²/q_F² (Eq. 12's balls,
    /// normalised); with the wrench bound per grasp 1 − |F|²/F_max², 1 −
    /// |M|²/M_max²; then 1 − (q_f[0]/ε)² under a stretch bound. Inside the
    /// set when every factor is > 0; b_f is their product.
    fn admissible_factors<T: Scalar>(&self, q_f: &[T; 12], g: &[T; 3], mut each: impl FnMut(T)) {
        let sq = |v: &[T]| {
            let mut s = k::<T>(0.0);
            for x in v {
                s += *x * *x;
            }
            s
        };
        match (self.bound, self.wrenches(q_f, g)) {
            (Bound::Wrench { force, moment }, Some(w)) => {
                for e in &w {
                    each(k::<T>(1.0) - sq(&e[..3]) * (1.0 / (force * force)));
                    each(k::<T>(1.0) - sq(&e[3..]) * (1.0 / (moment * moment)));
                }
            }
            _ => {
                for node in q_f.chunks(6) {
                    each(k::<T>(1.0) - sq(node) * (1.0 / (self.q_max * self.q_max)));
                }
            }
        }
        if let Some(eps) = self.max_stretch {
            let u = q_f[0] * (1.0 / eps);
            each(k::<T>(1.0) - u * u);
        }
    }

    /// The least admissibility factor at (q_f, g)
    /// (`Carried::admissible_factors`): ≤ 0 outside the admissible set.
    pub fn margin(&self, q_f: &[f64; 12], g: &[f64; 3]) -> f64 {
        let mut m = f64::INFINITY;
        self.admissible_factors(q_f, g, |b| m = m.min(b));
        m
    }

    /// End-0 pose and q_f at q (both robots), generic for exact derivatives.
    pub fn state<T: Scalar>(&self, q: &[T]) -> BeamState<T> {
        self.state_from_tools(
            &mm::frames(&q[..DOF]).tool,
            &mm::frames(&q[DOF..2 * DOF]).tool,
        )
    }

    /// As [`Carried::state`], from the two robots' tool frames (world).
    pub fn state_from_tools<T: Scalar>(&self, tool1: &Pose<T>, tool2: &Pose<T>) -> BeamState<T> {
        let g0 = tool1.then_const(&self.grasp[0]);
        let g2 = tool2.then_const(&self.grasp[1]);
        let rel = g0.inverse().then(&g2);
        let g = spatial::mul_mtv(&g0.r, spatial::lift(GRAVITY));
        let q_f = match self.compliant() {
            // The flanges' twist is shared by the wrists and the beam.
            Some(s) => {
                let xi = self.fe.grasp_deformation(&rel);
                let middle = s.nodes(&xi, &g)[1];
                std::array::from_fn(|i| if i < 6 { xi[i] } else { middle[i - 6] })
            }
            None => self.fe.deformation(&rel, g),
        };
        BeamState {
            end0: g0,
            q_f,
            gravity: g,
        }
    }

    /// ln b_f (Eq. 12, normalised per factor), or `None` when the
    /// deformation leaves its admissible set.
    pub fn ln_admissible<T: Scalar>(&self, q_f: &[T; 12], g: &[T; 3]) -> Option<T> {
        let mut out = Some(k::<T>(0.0));
        self.admissible_factors(q_f, g, |b| {
            out = match out {
                Some(acc) if b.re() > 0.0 => Some(acc + b.ln()),
                _ => None,
            }
        });
        out
    }

    /// The beam's ellipsoids (world), segment j centred at s = (j + ½) L / N
    /// on the deformed centreline, its long axis along the tangent.
    pub fn ellipsoids<T: Scalar>(&self, st: &BeamState<T>) -> Vec<PlacedEllipsoid<T>> {
        self.segment_frames(&st.q_f, &st.gravity)
            .iter()
            .map(|f| self.placed(&st.end0.then(f)))
            .collect()
    }

    /// Segment `j` of [`Carried::ellipsoids`].
    pub fn segment<T: Scalar>(&self, st: &BeamState<T>, j: usize) -> PlacedEllipsoid<T> {
        self.placed(&st.end0.then(&self.segment_frame(&st.q_f, &st.gravity, j)))
    }

    /// A segment's ellipsoid at its world frame `f`.
    fn placed<T: Scalar>(&self, f: &Pose<T>) -> PlacedEllipsoid<T> {
        let l = self.fe.beam().length;
        let n = self.segments;
        PlacedEllipsoid {
            center: f.p,
            rot: f.r,
            semi: [0.5 * l / n as f64, self.radius, self.radius],
            n: 1.0,
        }
    }

    /// Segment `j`'s frame in the end-0 frame (its world pose is end0 ∘ this).
    pub fn segment_frame<T: Scalar>(&self, q_f: &[T; 12], g: &[T; 3], j: usize) -> Pose<T> {
        let s = (j as f64 + 0.5) * self.fe.beam().length / self.segments as f64;
        match self.compliant() {
            Some(st) => {
                let xi: [T; 6] = std::array::from_fn(|i| q_f[i]);
                self.fe.centerline_of_nodes(&st.nodes(&xi, g), s)
            }
            None => self.fe.centerline(q_f, s),
        }
    }

    /// Every segment's frame, as [`Carried::segment_frame`] gives them (the
    /// same arithmetic, bit for bit), the chain's statics solved once.
    pub fn segment_frames<T: Scalar>(&self, q_f: &[T; 12], g: &[T; 3]) -> Vec<Pose<T>> {
        let (l, n) = (self.fe.beam().length, self.segments as f64);
        let nodes = self.compliant().map(|st| {
            let xi: [T; 6] = std::array::from_fn(|i| q_f[i]);
            st.nodes(&xi, g)
        });
        (0..self.segments)
            .map(|j| {
                let s = (j as f64 + 0.5) * l / n;
                match &nodes {
                    Some(nodes) => self.fe.centerline_of_nodes(nodes, s),
                    None => self.fe.centerline(q_f, s),
                }
            })
            .collect()
    }

    /// Whether robot `r`'s part `part` carries segment `seg`: robot r's arm,
    /// gripper and column against its own half of the beam. The gripper
    /// holds its end by construction, and with the arm folded as in Table I
    /// (grippers up, wrist by the shoulder, grasp 1.05 m high) the upper arm
    /// lies along that half and the column's ellipsoid (up to 1.2 m) reaches
    /// it: such pairs are part of one kinematic chain, not obstacles (nor
    /// collision pairs in physics). The platforms, and each robot against the
    /// other robot's half, are checked.
    pub fn held(&self, r: usize, part: &mm::Part, seg: usize) -> bool {
        let own_half = if r == 0 {
            2 * seg < self.segments
        } else {
            2 * seg >= self.segments
        };
        own_half && part.name != "platform"
    }
}

/// Table I's initial configuration of both robots (x, y, θ, q1..q6 each; rad).
pub fn table_i_start() -> Vec<f64> {
    use std::f64::consts::PI;
    let arm = |q1: f64, q5: f64| [q1, -PI / 2.0, 2.0 * PI / 3.0, 0.0, q5, 0.0];
    let mut q = vec![-11.0, 3.0, -PI / 2.0];
    q.extend(arm(PI / 2.0, -PI / 6.0));
    q.extend([-8.0, 3.0, -PI / 2.0]);
    q.extend(arm(-PI / 3.0, -PI / 4.0));
    q
}

/// Table I's start, and a goal 2 m ahead of both robots (their heading is
/// −y, so the dipole terms do not vanish): the tests' transport task.
#[cfg(test)]
pub(crate) fn table_i_start_and_goal_ahead() -> (Vec<f64>, Vec<f64>) {
    let q0 = table_i_start();
    let mut goal = q0.clone();
    goal[1] -= 2.0;
    goal[DOF + 1] -= 2.0;
    (q0, goal)
}

/// Table I's desired configuration of both robots (rad).
pub(crate) fn table_i_goal() -> Vec<f64> {
    use std::f64::consts::PI;
    let arm = |q1: f64| [q1, -PI / 2.0, 2.0 * PI / 3.0, 0.0, -PI / 6.0, 0.0];
    let mut q = vec![0.0, -2.0, 0.0];
    q.extend(arm(PI / 3.0));
    q.extend([0.0, 2.0, 0.0]);
    q.extend(arm(-PI / 2.0));
    q
}

/// How far the grasps' relative pose at `b` is from the one at `a`:
/// translation (m) and rotation (rad) of tool 2 in tool 1's frame. A solid
/// object held at both needs both 0.
pub(crate) fn relative_grasp_change(a: &[f64], b: &[f64]) -> (f64, f64) {
    let rel = |q: &[f64]| {
        mm::frames::<f64>(&q[..DOF])
            .tool
            .inverse()
            .then(&mm::frames::<f64>(&q[DOF..2 * DOF]).tool)
    };
    let (ra, rb) = (rel(a), rel(b));
    let d = spatial::sub(rb.p, ra.p);
    // tr(Raᵀ Rb) = 1 + 2 cos(angle).
    let mut tr = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            tr += ra.r[i][j] * rb.r[i][j];
        }
    }
    (
        spatial::dot(d, d).sqrt(),
        ((tr - 1.0) / 2.0).clamp(-1.0, 1.0).acos(),
    )
}

/// Distance between the grasp points of two robots at q (for messages).
pub fn grasp_distance(q: &[f64]) -> f64 {
    let d = spatial::sub(
        mm::grasp_point(&q[DOF..2 * DOF]),
        mm::grasp_point(&q[..DOF]),
    );
    spatial::dot(d, d).sqrt()
}

#[cfg(test)]
#[path = "object_tests.rs"]
pub(crate) mod tests;
