//! The dipolar inverse Lyapunov function of seed 004 (Eq. 15) and its field
//! (Eq. 17), with exact gradients.
//!
//! For every robot part p (one ellipsoid of a robot's cover, in its own
//! workspace copy W^p):
//!
//! * h_p: the part's point in coordinates where its goal is the origin
//!   (the platform part: the platform position in the goal frame, whose x axis
//!   is the goal heading; arm parts: see [`GoalFrame`]);
//! * β_pi ([`crate::robots::mobile_manipulator::dilf::contact`]): the obstacle function of obstacle i seen from
//!   h_p after H1; b̃_pi = β/(β + 1) ∈ (0, 1), which is also the square of T's
//!   contraction factor;
//! * σ_pi: the analytic switches of Eq. 8 on ‖h_p‖ and the b̃ (in logarithms,
//!   [`crate::robots::mobile_manipulator::dilf::point_world::switches_log`]);
//! * H2 (Eq. 9) moves the part's point to h2^p = h_p + Σ_i σ_i (√b̃_i − 1)(h_p − h_Oi);
//!   on contact with obstacle i it lands exactly on h_Oi;
//! * the proximity d_p (after Eq. 9) as the product of the normalised distances
//!   ρ_pi = ‖h2^p − h_Oi‖ / ‖h_p − h_Oi‖ ∈ [0, 1] (1 far away, 0 on contact).
//!
//! V = [Π_p Π_i ρ_pi · b_s]^{1/k_v} · Π_r γ_r / Σ_p ‖h2^p‖²
//!
//! with γ_r = |⟨e1, h2^{c_r}⟩| the dipole of robot r's platform and b_s the
//! singularity term ([`SingularityEnclosure`], Eq. 13). The field is
//! f = (Σ_p ‖h2^p‖²)² ∂V/∂q (Eq. 17).
//!
//! Choices the paper leaves open, and one change, all in docs/src/research/seed-004.md:
//! the printed d_p = Π‖h2^p − h_Oi‖ grows with the distance to every
//! obstacle's *centre*, so far obstacles would repel as strongly as near ones
//! and the raw superellipsoid functions (∝ distance^{2n}) overflow the
//! switches' products; dividing each factor by the undeformed distance
//! ‖h_p − h_Oi‖ keeps its zero set (contact) and the point-world construction
//! and bounds it by 1, and the switches use the bounded b̃.
//!
//! Derivatives: the whole evaluation is generic over the scalar; with forward
//! dual numbers (`num_dual::DualSVec64<N>`, N = 9k) one pass gives V and ∂V/∂q
//! ([`Scene::field_dual`], the reference). The inner minimisations contribute
//! exactly through the envelope theorem ([`crate::robots::mobile_manipulator::dilf::contact::Contact::beta`]).
//! [`Scene::field`] computes the same gradient in reverse, by hand
//! ([`crate::robots::mobile_manipulator::dilf::adjoint`]), several times faster.

use crate::model::spatial::{self, k, Pose, Scalar, V3};
use crate::robots::mobile_manipulator::dilf::contact::{self, Contact, ContactError};
use crate::robots::mobile_manipulator::dilf::object::Carried;
use crate::robots::mobile_manipulator::dilf::point_world::switches_log;
use crate::robots::mobile_manipulator::dilf::scratch::Scratch;
use crate::robots::mobile_manipulator::ellipsoid::{PlacedEllipsoid, Superellipsoid};
use crate::robots::mobile_manipulator::kinematics::{self as mm, Link, Part, DOF};
use crate::robots::mobile_manipulator::puma560;
use num_dual::DualSVec64;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

pub use crate::robots::mobile_manipulator::dilf::terms::{TermGradients, Terms};

/// Where the arm parts' goal points live (the paper: "in an appropriate
/// coordinate system the desired configuration of every h_p is the origin").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum GoalFrame {
    /// Arm parts are measured in their own platform's frame: their goal term
    /// depends on the arm joints only, so a far goal does not stretch the arm
    /// towards it (default).
    #[default]
    Platform,
    /// Every part is measured in the world (goal frame): a literal reading.
    World,
}

/// How the robots' dipole factors γ_r combine in V (Eq. 15).
///
/// Eq. 15 prints Π_r γ_r over Σ_p ‖h2^p‖². For k = 1 that tends to infinity
/// at the goal (γ/‖h‖² ~ 1/‖h‖ along the goal axis), as Definition 1 and
/// Theorem 3 (ii) require of an inverse Lyapunov function. For k = 2 it does
/// not: numerator and denominator are both of degree 2, so V stays bounded
/// (→ 1/2 as both robots close in along their axes) and has no maximum at
/// the goal; the pair stalls far from it (Table I: 5 m short). The
/// geometric mean (Π_r γ_r)^{1/k} keeps Eq. 15 unchanged for one robot,
/// keeps the dipole planes γ_r = 0 as V's zero sets (the 2k regions of
/// Lemma 2), and restores degree −1, so V → ∞ at the goal for any k.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum DipoleProduct {
    /// (Π_r γ_r)^{1/k} (default).
    #[default]
    GeometricMean,
    /// Π_r γ_r as printed (identical for one robot).
    Printed,
    /// Ours: one dipole for the whole formation, γ = |(1/k) Σ_r x_r| with
    /// x_r the signed coordinate of robot r's platform point along its goal
    /// heading (after H2). For a formation whose goal headings agree it is
    /// the dipole of the platforms' centroid: V's zero set is the one plane
    /// through the goal centroid across the goal heading, and no robot is
    /// asked to approach along its own axis (identical for one robot).
    Formation,
}

/// Singular sets of each arm (zeros of the three factors of det J, see
/// [`puma560`]) enclosed in slabs |f_k| ≤ δ_k: generalized ellipsoids in the
/// factor coordinates. δ = 0 disables a factor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SingularityEnclosure {
    /// Shoulder: wrist centre's reach in the arm plane, m.
    #[schemars(range(min = 0))]
    pub shoulder: f64,
    /// Elbow: d4 c3 + a3 s3, m.
    #[schemars(range(min = 0))]
    pub elbow: f64,
    /// Wrist: |sin q5|.
    #[schemars(range(min = 0))]
    pub wrist: f64,
}

impl Default for SingularityEnclosure {
    fn default() -> Self {
        SingularityEnclosure {
            shoulder: 0.05,
            elbow: 0.05,
            wrist: 0.1,
        }
    }
}

impl SingularityEnclosure {
    fn deltas(&self) -> [f64; 3] {
        [self.shoulder, self.elbow, self.wrist]
    }

    /// Obstacle functions s_k = (f_k/δ_k)² − 1 of the enabled factors (< 0 inside).
    pub fn values<T: Scalar>(&self, arm: &[T]) -> Vec<(usize, T)> {
        self.value_array(arm)
            .into_iter()
            .enumerate()
            .filter_map(|(i, s)| s.map(|s| (i, s)))
            .collect()
    }

    /// As [`SingularityEnclosure::values`], `None` for a disabled factor (allocation-free).
    pub fn value_array<T: Scalar>(&self, arm: &[T]) -> [Option<T>; 3] {
        let f = puma560::singularity_factors(arm);
        let d = self.deltas();
        std::array::from_fn(|i| {
            (d[i] > 0.0).then(|| {
                let u = f[i] * (1.0 / d[i]);
                u * u - 1.0
            })
        })
    }
}

/// Parameters of V.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PotentialParams {
    /// λ of the switches (Eqs. 6, 8).
    pub lambda: f64,
    /// The exponent k_v of Eqs. 10, 14, 15.
    pub kv: f64,
    /// Coordinates of the arm parts' goal points.
    pub goal_frame: GoalFrame,
    /// How the dipole factors of several robots combine.
    pub dipole: DipoleProduct,
    /// Singularity enclosures (Eq. 13).
    pub singularity: SingularityEnclosure,
    /// p in f = (Σ‖h2‖²)^p ∂V/∂q; Eq. 17 prints p = 2.
    pub field_power: f64,
}

/// The measured flanges of a pair relative to their kinematic poses: robot
/// r's flange in the world is `frames(q_r).tool ∘ c[r]`. In the physics
/// replay the planar state (x, y, θ, joints) cannot see a platform's tilt
/// or the rod's pull on the arms; the 3D flange poses can. Held fixed over
/// a policy sample, the correction turns V and its field into those of the
/// measured grasps: a joint or platform motion moves a corrected flange by
/// the same rigid motion as the kinematic one, so the adjoint field is exact.
pub type GraspCorrection = [Pose<f64>; 2];

/// A named static obstacle.
#[derive(Debug, Clone)]
pub struct Obstacle {
    /// Name (for messages).
    pub name: String,
    /// Shape in the world.
    pub shape: PlacedEllipsoid<f64>,
}

/// Everything V depends on besides q.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Number of robots k.
    pub robots: usize,
    /// Each robot's cover; part 0 is the platform part, centred above the axle.
    pub parts: Vec<Part>,
    /// Static obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Goal configuration, 9k coordinates.
    pub goal: Vec<f64>,
    /// Parameters.
    pub params: PotentialParams,
    /// The carried beam (two robots), if any: its deformation enters V
    /// through b_f and its ellipsoids are obstacles of every part.
    pub object: Option<Carried>,
    /// Per (robot, part): the goal point in the part's goal coordinates.
    pub(super) goal_points: Vec<[f64; 3]>,
}

/// Warm starts of the inner solves, one slot per (part, obstacle) pair, and
/// the buffers of [`Scene::field`] (reused: no allocations per call).
#[derive(Debug, Clone, Default)]
pub struct Warm {
    pub(super) slots: Vec<Option<[f64; 3]>>,
    pub(super) scratch: Scratch,
}

/// V at one configuration.
#[derive(Debug, Clone, Copy)]
pub struct Evaluation<T: Scalar> {
    /// V (Eq. 15); 0 in collision.
    pub v: T,
    /// Σ_p ‖h2^p‖².
    pub d: f64,
    /// Least β over all part–obstacle pairs (< 0: overlap).
    pub min_beta: f64,
    /// Least singularity function s_k over arms and factors (< 0: inside an enclosure).
    pub min_singular: f64,
    /// ‖q_f‖∞ of the carried beam (Eq. 5); 0 without one.
    pub max_deformation: f64,
    /// The beam's least admissibility factor ([`Carried::margin`]); ∞
    /// without one.
    pub admissible: f64,
}

impl<T: Scalar> Evaluation<T> {
    /// Whether b_f ≤ 0: the beam outside its admissible set (V = 0).
    pub fn overstrained(&self) -> bool {
        self.admissible <= 0.0
    }
}

/// Which pair is closest (for messages).
#[derive(Debug, Clone, PartialEq)]
pub struct Closest {
    /// "robot r part" description.
    pub part: String,
    /// Obstacle description.
    pub obstacle: String,
    /// β of the pair.
    pub beta: f64,
}

/// Why a scene cannot be built (user-facing).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// λ is not finite and > 0.
    #[error("`lambda` must be > 0")]
    Lambda,
    /// The velocity exponent is not finite and > 0.
    #[error("`kv_exponent` must be > 0")]
    KvExponent,
    /// The first part is not the platform centred above the axle.
    #[error("part 0 must be the platform, centred above the axle")]
    Platform,
}

impl Scene {
    /// Build a scene; errors are user-facing.
    pub fn new(
        robots: usize,
        parts: Vec<Part>,
        obstacles: Vec<Obstacle>,
        goal: Vec<f64>,
        params: PotentialParams,
    ) -> Result<Scene, SceneError> {
        if !(params.lambda.is_finite() && params.lambda > 0.0) {
            return Err(SceneError::Lambda);
        }
        if !(params.kv.is_finite() && params.kv > 0.0) {
            return Err(SceneError::KvExponent);
        }
        match parts.first() {
            Some(p) if p.link == Link::Base && p.shape.center[..2] == [0.0, 0.0] => {}
            _ => return Err(SceneError::Platform),
        }
        let mut s = Scene {
            robots,
            parts,
            obstacles,
            goal,
            params,
            object: None,
            goal_points: Vec::new(),
        };
        let goal = s.goal.clone();
        s.goal_points = (0..robots)
            .flat_map(|r| {
                let q = &goal[DOF * r..DOF * (r + 1)];
                let f = mm::frames::<f64>(q);
                let heading = Pose::<f64>::rotation(spatial::rot_z(q[2]));
                s.parts
                    .iter()
                    .enumerate()
                    .map(|(i, p)| {
                        let c = p.shape.placed(f.link(p.link)).center;
                        match (i, s.params.goal_frame) {
                            (0, _) | (_, GoalFrame::World) => heading.apply_inv(c),
                            (_, GoalFrame::Platform) => f.base.apply_inv(c),
                        }
                    })
                    .collect::<Vec<_>>()
            })
            .collect();
        Ok(s)
    }

    /// The same scene (obstacles, beam, parameters) with another goal.
    pub fn with_goal(&self, goal: Vec<f64>) -> Result<Scene, SceneError> {
        let s = Scene::new(
            self.robots,
            self.parts.clone(),
            self.obstacles.clone(),
            goal,
            self.params,
        )?;
        Ok(match &self.object {
            Some(o) => s.with_object(o.clone()),
            None => s,
        })
    }

    /// The scene with a carried beam (two robots).
    pub fn with_object(mut self, object: Carried) -> Scene {
        self.object = Some(object);
        self
    }

    /// Number of (part, obstacle) pairs, robot-robot and robot-beam pairs included.
    pub fn pair_count(&self) -> usize {
        let n = self.parts.len();
        let beam = self.object.as_ref().map_or(0, |o| o.segments);
        self.robots * n * (self.obstacles.len() + (self.robots - 1) * n + beam)
            + beam * self.obstacles.len()
    }

    /// A fresh warm-start cache.
    pub fn warm(&self) -> Warm {
        Warm {
            slots: vec![None; self.pair_count()],
            scratch: Scratch::default(),
        }
    }

    /// Placed parts of every robot at q, robot-major.
    pub fn placed_parts<T: Scalar>(&self, q: &[T]) -> Vec<PlacedEllipsoid<T>> {
        (0..self.robots)
            .flat_map(|r| {
                let f = mm::frames(&q[DOF * r..DOF * (r + 1)]);
                self.parts
                    .iter()
                    .map(move |p| placed_generic(&p.shape, f.link(p.link)))
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    /// V at q (value and, with dual numbers, derivatives).
    pub fn evaluate<T: Scalar>(
        &self,
        q: &[T],
        warm: &mut Warm,
    ) -> Result<Evaluation<T>, ContactError> {
        self.evaluate_with(q, None, warm)
    }

    /// As [`Scene::evaluate`], with the beam held at the measured flanges:
    /// robot r's flange is its kinematic one times `measured[r]` (see
    /// [`GraspCorrection`]).
    pub fn evaluate_with<T: Scalar>(
        &self,
        q: &[T],
        measured: Option<&GraspCorrection>,
        warm: &mut Warm,
    ) -> Result<Evaluation<T>, ContactError> {
        self.evaluate_terms(q, measured, warm).map(|(e, _)| e)
    }

    /// As [`Scene::evaluate_with`], with ln V split into its factors
    /// ([`Terms`]; for diagnostics).
    pub fn evaluate_terms<T: Scalar>(
        &self,
        q: &[T],
        measured: Option<&GraspCorrection>,
        warm: &mut Warm,
    ) -> Result<(Evaluation<T>, Terms<T>), ContactError> {
        let n = self.parts.len();
        let n_static = self.obstacles.len();
        let n_robots = (self.robots - 1) * n;
        let mut terms = Terms::<T>::default();
        let placed = self.placed_parts(q);
        let beam = self.object.as_ref().map(|o| {
            let st = match measured {
                None => o.state(q),
                Some(c) => o.state_from_tools(
                    &mm::frames(&q[..DOF]).tool.then_const(&c[0]),
                    &mm::frames(&q[DOF..2 * DOF]).tool.then_const(&c[1]),
                ),
            };
            (
                o.ellipsoids(&st),
                o.ln_admissible(&st.q_f, &st.gravity),
                st.max_deformation(),
                o.margin(&st.q_f.map(|x| x.re()), &st.gravity.map(|x| x.re())),
            )
        });
        let ln_lambda = self.params.lambda.ln();
        let mut ln_num = k::<T>(0.0);
        let mut d = k::<T>(0.0);
        let mut gamma = k::<T>(1.0);
        let mut x_sum = k::<T>(0.0);
        let mut min_beta = f64::INFINITY;
        let mut slot = 0;
        let mut collided = false;
        for r in 0..self.robots {
            let qr = &q[DOF * r..DOF * (r + 1)];
            let base_rot_t = spatial::rot_z(qr[2]);
            let goal_heading = self.goal[DOF * r + 2];
            let heading = spatial::rot_z(k::<T>(goal_heading));
            for (i, _) in self.parts.iter().enumerate() {
                let part = &placed[r * n + i];
                let part_re = part.re();
                let c = part.center;
                // The part's point and the rotation from world to its goal coordinates.
                let (h_now, rot) = match (i, self.params.goal_frame) {
                    (0, _) | (_, GoalFrame::World) => (spatial::mul_mtv(&heading, c), heading),
                    (_, GoalFrame::Platform) => {
                        let base_p = [qr[0], qr[1], k(0.0)];
                        (
                            spatial::mul_mtv(&base_rot_t, spatial::sub(c, base_p)),
                            base_rot_t,
                        )
                    }
                };
                let h = spatial::sub(h_now, spatial::lift(self.goal_points[r * n + i]));
                // Every obstacle this part sees: static ones (constant: only
                // the part carries derivatives), then the other robots' parts.
                let mut seen: Vec<(T, V3<T>)> = Vec::with_capacity(self.obstacles.len() + n);
                for o in &self.obstacles {
                    let sol = self.solve(&part_re, &o.shape, &mut warm.slots[slot])?;
                    slot += 1;
                    min_beta = min_beta.min(sol.value);
                    collided |= sol.value <= 0.0;
                    let beta = part.value(spatial::lift(sol.x)) * sol.mu + sol.value;
                    seen.push((beta, spatial::sub(c, spatial::lift(o.shape.center))));
                }
                for j in (0..self.robots)
                    .filter(|&o| o != r)
                    .flat_map(|o| (0..n).map(move |j| o * n + j))
                {
                    let o = &placed[j];
                    let sol = self.solve(&part_re, &o.re(), &mut warm.slots[slot])?;
                    slot += 1;
                    min_beta = min_beta.min(sol.value);
                    collided |= sol.value <= 0.0;
                    seen.push((sol.beta(part, o), spatial::sub(c, o.center)));
                }
                if let (Some(obj), Some((segs, _, _, _))) = (&self.object, &beam) {
                    for (j, o) in segs.iter().enumerate() {
                        let s_slot = slot;
                        slot += 1;
                        if obj.held(r, &self.parts[i], j) {
                            continue;
                        }
                        // Roles swapped: the minimum of the part's function over the
                        // thin segment. Zero at contact like the other order, and far
                        // better conditioned than a 2 cm-thin obstacle function.
                        let sol = self.solve(&o.re(), &part_re, &mut warm.slots[s_slot])?;
                        min_beta = min_beta.min(sol.value);
                        collided |= sol.value <= 0.0;
                        seen.push((sol.beta(o, part), spatial::sub(c, o.center)));
                    }
                }
                if collided {
                    continue;
                }
                // Eq. 9 on the part's point, then the normalised proximities.
                let ln_b: Vec<T> = seen.iter().map(|(b, _)| (*b / (*b + 1.0)).ln()).collect();
                let hh = spatial::dot(h, h);
                let mut shift = spatial::lift::<T>([0.0; 3]);
                if hh.re() > 1e-24 && !seen.is_empty() {
                    let sigma = switches_log(hh.ln() * 0.5, &ln_b, ln_lambda);
                    for ((s, lb), (_, delta)) in sigma.iter().zip(&ln_b).zip(&seen) {
                        let sqrt_b = (*lb * 0.5).exp();
                        shift = spatial::add(shift, spatial::scale(*delta, *s * (sqrt_b - 1.0)));
                    }
                }
                for (j, (_, delta)) in seen.iter().enumerate() {
                    let moved = spatial::add(*delta, shift);
                    let l = (spatial::dot(moved, moved) / spatial::dot(*delta, *delta)).ln() * 0.5;
                    ln_num += l;
                    if j < n_static {
                        terms.obstacles += l;
                    } else if j < n_static + n_robots {
                        terms.robots += l;
                    } else {
                        terms.beam_parts += l;
                    }
                }
                let h2 = spatial::add(h, spatial::mul_mtv(&rot, shift));
                d += spatial::dot(h2, h2);
                if i == 0 {
                    // The dipole: |x| in the goal frame, with sign(0) = +1 (App. G).
                    let g = if h2[0].re() >= 0.0 { h2[0] } else { -h2[0] };
                    gamma *= g;
                    x_sum += h2[0];
                    terms.gammas.push(g);
                }
            }
        }
        // The beam as a body (§III-B: its ellipsoids are modelled like the
        // manipulator's): each segment against each static obstacle enters
        // V as a factor b̃ = β/(1+β), so V vanishes when the beam touches a
        // wall, as it does for the robots' parts. (The robots' parts against
        // the beam are above, in their own workspace copies.)
        if let Some((segs, _, _, _)) = &beam {
            for seg in segs {
                let seg_re = seg.re();
                for o in &self.obstacles {
                    let sol = self.solve(&seg_re, &o.shape, &mut warm.slots[slot])?;
                    slot += 1;
                    min_beta = min_beta.min(sol.value);
                    collided |= sol.value <= 0.0;
                    if !collided {
                        // Envelope theorem: the obstacle is fixed, the segment moves.
                        let b = seg.value(spatial::lift(sol.x)) * sol.mu + sol.value;
                        let l = (b / (b + 1.0)).ln();
                        ln_num += l;
                        terms.beam_obstacles += l;
                    }
                }
            }
        }
        let mut min_singular = f64::INFINITY;
        for r in 0..self.robots {
            for (_, s) in self
                .params
                .singularity
                .values(&q[DOF * r + 3..DOF * (r + 1)])
            {
                min_singular = min_singular.min(s.re());
                if s.re() > 0.0 {
                    let l = (s / (s + 1.0)).ln();
                    ln_num += l;
                    terms.singular += l;
                }
            }
        }
        let (max_deformation, admissible) = match &beam {
            Some((_, ln_bf, m, margin)) => {
                if let Some(l) = ln_bf {
                    ln_num += *l;
                    terms.admissible = *l;
                }
                (*m, *margin)
            }
            None => (0.0, f64::INFINITY),
        };
        // The same factors: ln b_f is None exactly when the margin is ≤ 0.
        let overstrained = admissible <= 0.0;
        let v = if collided || overstrained || min_singular <= 0.0 {
            k(0.0)
        } else {
            let gamma = match self.params.dipole {
                DipoleProduct::GeometricMean if self.robots > 1 => {
                    gamma.powf(1.0 / self.robots as f64)
                }
                DipoleProduct::Formation => {
                    let m = x_sum * (1.0 / self.robots as f64);
                    if m.re() >= 0.0 {
                        m
                    } else {
                        -m
                    }
                }
                _ => gamma,
            };
            gamma * (ln_num * (1.0 / self.params.kv)).exp() / d
        };
        let inv_kv = 1.0 / self.params.kv;
        let inv_k = match self.params.dipole {
            DipoleProduct::GeometricMean => 1.0 / self.robots as f64,
            _ => 1.0,
        };
        terms.dipole = match self.params.dipole {
            DipoleProduct::Formation => {
                let m = x_sum * (1.0 / self.robots as f64);
                (if m.re() >= 0.0 { m } else { -m }).ln()
            }
            _ => terms
                .gammas
                .iter()
                .fold(k::<T>(0.0), |acc, g| acc + g.ln() * inv_k),
        };
        terms.d = d.ln();
        for t in [
            &mut terms.obstacles,
            &mut terms.robots,
            &mut terms.beam_parts,
            &mut terms.beam_obstacles,
            &mut terms.singular,
            &mut terms.admissible,
        ] {
            *t *= inv_kv;
        }
        Ok((
            Evaluation {
                v,
                d: d.re(),
                min_beta,
                min_singular,
                max_deformation,
                admissible,
            },
            terms,
        ))
    }

    pub(super) fn solve(
        &self,
        part: &PlacedEllipsoid<f64>,
        obstacle: &PlacedEllipsoid<f64>,
        warm: &mut Option<[f64; 3]>,
    ) -> Result<Contact, ContactError> {
        let c = contact::solve(part, obstacle, *warm)?;
        *warm = Some(c.y);
        Ok(c)
    }

    /// As [`Scene::field`], by one evaluation in forward dual numbers (9k
    /// derivatives everywhere): slower, kept as the reference the fast path
    /// is tested against.
    pub fn field_dual(
        &self,
        q: &[f64],
        warm: &mut Warm,
    ) -> Result<(Evaluation<f64>, Vec<f64>), ContactError> {
        match self.robots {
            1 => self.field_n::<9>(q, warm),
            _ => self.field_n::<18>(q, warm),
        }
    }

    fn field_n<const N: usize>(
        &self,
        q: &[f64],
        warm: &mut Warm,
    ) -> Result<(Evaluation<f64>, Vec<f64>), ContactError> {
        let qd: Vec<DualSVec64<N>> = q
            .iter()
            .enumerate()
            .map(|(i, &x)| DualSVec64::<N>::from_re(x).derivative(i))
            .collect();
        let e = self.evaluate(&qd, warm)?;
        let grad: Vec<f64> = match e.v.eps.0 {
            Some(g) => g.iter().copied().collect(),
            None => vec![0.0; N],
        };
        let d2 = e.d.powf(self.params.field_power);
        Ok((
            Evaluation {
                v: e.v.re,
                d: e.d,
                min_beta: e.min_beta,
                min_singular: e.min_singular,
                max_deformation: e.max_deformation,
                admissible: e.admissible,
            },
            grad.iter().map(|g| d2 * g).collect(),
        ))
    }

    /// The closest part–obstacle pair at q (for messages and checks).
    pub fn closest(&self, q: &[f64]) -> Result<Option<Closest>, ContactError> {
        let n = self.parts.len();
        let placed = self.placed_parts(q);
        let mut best: Option<Closest> = None;
        for r in 0..self.robots {
            for (i, part) in self.parts.iter().enumerate() {
                let p = &placed[r * n + i];
                let mut consider =
                    |name: String, o: &PlacedEllipsoid<f64>| -> Result<(), ContactError> {
                        let c = contact::solve(p, o, None)?;
                        if best.as_ref().is_none_or(|b| c.value < b.beta) {
                            best = Some(Closest {
                                part: format!("robot {} part `{}`", r + 1, part.name),
                                obstacle: name,
                                beta: c.value,
                            });
                        }
                        Ok(())
                    };
                for o in &self.obstacles {
                    consider(format!("obstacle `{}`", o.name), &o.shape)?;
                }
                for o in (0..self.robots).filter(|&o| o != r) {
                    for (j, other) in self.parts.iter().enumerate() {
                        consider(
                            format!("robot {} part `{}`", o + 1, other.name),
                            &placed[o * n + j],
                        )?;
                    }
                }
            }
        }
        if let Some(obj) = &self.object {
            let st = obj.state::<f64>(q);
            for (j, seg) in obj.ellipsoids(&st).iter().enumerate() {
                for o in &self.obstacles {
                    let c = contact::solve(seg, &o.shape, None)?;
                    if best.as_ref().is_none_or(|b| c.value < b.beta) {
                        best = Some(Closest {
                            part: format!("the beam's segment {} of {}", j + 1, obj.segments),
                            obstacle: format!("obstacle `{}`", o.name),
                            beta: c.value,
                        });
                    }
                }
            }
        }
        Ok(best)
    }
}

/// A link-frame shape placed by a `T` pose.
pub(crate) fn placed_generic<T: Scalar>(s: &Superellipsoid, pose: &Pose<T>) -> PlacedEllipsoid<T> {
    // The local pose is constant: multiply by it in f64 terms.
    let rot = if s.rpy == [0.0; 3] {
        pose.r
    } else {
        spatial::mul_mm_const(&pose.r, &s.rotation())
    };
    PlacedEllipsoid {
        center: spatial::add(spatial::mul_mv_const(&pose.r, s.center), pose.p),
        rot,
        semi: s.semi_axes,
        n: s.exponent,
    }
}

/// Diagnostics: ln V's factors with their gradients ([`crate::robots::mobile_manipulator::dilf::terms`]).
impl Scene {
    /// ln V's factors at q and their gradients (forward dual numbers; for
    /// diagnostics, [`Terms::named`] order). `None` in collision, outside
    /// the beam's admissible set or inside a singularity enclosure (V = 0).
    pub fn term_gradients(&self, q: &[f64]) -> Result<Option<TermGradients>, ContactError> {
        match self.robots {
            1 => self.term_gradients_n::<9>(q),
            _ => self.term_gradients_n::<18>(q),
        }
    }

    fn term_gradients_n<const N: usize>(
        &self,
        q: &[f64],
    ) -> Result<Option<TermGradients>, ContactError> {
        let qd: Vec<DualSVec64<N>> = q
            .iter()
            .enumerate()
            .map(|(i, &x)| DualSVec64::<N>::from_re(x).derivative(i))
            .collect();
        let (e, t) = self.evaluate_terms(&qd, None, &mut self.warm())?;
        if e.v.re <= 0.0 {
            return Ok(None);
        }
        let grad = |x: &DualSVec64<N>| match &x.eps.0 {
            Some(g) => g.iter().copied().collect(),
            None => vec![0.0; N],
        };
        let terms = t
            .named()
            .into_iter()
            .map(|(name, x)| (name, x.re, grad(&x)))
            .collect();
        let gammas = t.gammas.iter().map(|g| g.re).collect();
        Ok(Some(TermGradients { terms, gammas }))
    }
}

#[cfg(test)]
pub(crate) mod tests;
