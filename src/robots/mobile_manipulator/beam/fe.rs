//! Seed 004's finite-element beam (§II, Eq. 3–4, §III-B): two 3D
//! Euler–Bernoulli frame elements on three nodes (0: grasp 1, 1: middle,
//! 2: grasp 2), the grasp-related deformation from exponential coordinates and
//! the object-related one by static condensation.
//!
//! # Conventions
//! - Everything is expressed in the **end-0 frame** (node 0 = the floating
//!   frame of reference {R}, clamped). The rest axis is its x axis; at rest
//!   node i sits at (i L/2, 0, 0).
//! - Nodal DOFs, 6 per node, in this order: translations (u_x, u_y, u_z) in m,
//!   then small rotations (θ_x, θ_y, θ_z) in rad about the end-0 axes
//!   (right-hand rule). Global DOF index = 6 · node + local index; `K` is
//!   18 × 18 over nodes 0, 1, 2.
//! - Bending: v = u_y with slope v' = θ_z, w = u_z with slope w' = −θ_y;
//!   axial u_x and torsion θ_x are linear in each element.
//! - Grasp-related deformation q_s = log((g⁰)⁻¹ · rel) with rel = g₀⁻¹ g₂ the
//!   actual end-2 pose in the end-0 frame and g⁰ = translation (L, 0, 0) its
//!   rest value: a twist (v, ω) expressed in the rest end-2 frame, whose axes
//!   are the end-0 axes. It is taken as node 2's nodal displacement
//!   (translations v, rotations ω), which agrees with the linear theory to
//!   first order.
//! - Object-related deformation q_o (node 1) = K_oo⁻¹ (f_o − K_os q_s), with
//!   node 0 clamped, node 2 prescribed, f_o the consistent self-weight load on
//!   node 1 for the gravity acceleration g given in the end-0 frame (m/s²;
//!   load per length ρ A g).
//! - q_f = (q_s, q_o) ∈ ℝ¹²: indices 0–5 node 2, 6–11 node 1. Units mix m
//!   and rad, as the paper's ‖q_f‖∞ does.
//! - [`FeBeam::centerline`] interpolates the nodal values with the element
//!   shape functions (cubic Hermite in bending, linear in axial and torsion)
//!   and returns a frame whose x axis is the unit tangent of the deformed
//!   centreline, turned about it by the interpolated twist θ_x.

use nalgebra::{SMatrix, SVector};

use crate::model::spatial::{dot, k, lift, mul_mm, rot_x, Pose, Scalar, M3};
use crate::robots::mobile_manipulator::beam::{Beam, BeamError};

use crate::robots::mobile_manipulator::beam::se3::se3_log;

/// 18 × 18 assembled stiffness (nodes 0, 1, 2).
pub type Stiffness = SMatrix<f64, 18, 18>;
/// 12 × 12 element stiffness.
pub type ElementStiffness = SMatrix<f64, 12, 12>;

/// The precomputed two-element model of a [`Beam`].
#[derive(Debug, Clone)]
pub struct FeBeam {
    beam: Beam,
    k: Stiffness,
    /// −K_oo⁻¹ K_os: q_o per unit q_s.
    condensation: [[f64; 6]; 6],
    /// K_oo⁻¹ f_o per unit gravity acceleration (columns: g_x, g_y, g_z).
    gravity_response: [[f64; 3]; 6],
}

impl FeBeam {
    /// Precompute stiffness and condensation (fails if the beam is invalid).
    pub fn new(beam: &Beam) -> Result<Self, BeamError> {
        beam.validate()?;
        let k = assemble(&element_stiffness(beam, beam.length / 2.0));
        let koo: SMatrix<f64, 6, 6> = k.fixed_view::<6, 6>(6, 6).into_owned();
        let kos: SMatrix<f64, 6, 6> = k.fixed_view::<6, 6>(6, 12).into_owned();
        let chol = koo.cholesky().ok_or(BeamError::MiddleBlock)?;
        let cond = -chol.solve(&kos);
        let g = unit_gravity_load(beam);
        let go: SMatrix<f64, 6, 3> = g.fixed_view::<6, 3>(6, 0).into_owned();
        let resp = chol.solve(&go);
        Ok(FeBeam {
            beam: *beam,
            k,
            condensation: std::array::from_fn(|i| std::array::from_fn(|j| cond[(i, j)])),
            gravity_response: std::array::from_fn(|i| std::array::from_fn(|j| resp[(i, j)])),
        })
    }

    /// The beam this model was built from.
    pub fn beam(&self) -> &Beam {
        &self.beam
    }

    /// One element's 12 × 12 stiffness (length L/2, local = end-0 axes).
    pub fn element_stiffness(&self) -> ElementStiffness {
        element_stiffness(&self.beam, self.beam.length / 2.0)
    }

    /// The assembled, unconstrained 18 × 18 stiffness K.
    pub fn stiffness(&self) -> &Stiffness {
        &self.k
    }

    /// The consistent self-weight load (18) for gravity `g` (m/s², end-0 frame).
    pub fn gravity_load(&self, g: [f64; 3]) -> SVector<f64, 18> {
        unit_gravity_load(&self.beam) * SVector::<f64, 3>::from(g)
    }

    /// C = −K_oo⁻¹ K_os (row-major, `[i][j]` = ∂q_o\[i\]/∂q_s\[j\]).
    pub fn condensation(&self) -> &[[f64; 6]; 6] {
        &self.condensation
    }

    /// K_oo⁻¹ f_o per unit gravity (`[i][j]` = ∂q_o\[i\]/∂g\[j\]).
    pub fn gravity_response(&self) -> &[[f64; 3]; 6] {
        &self.gravity_response
    }

    /// The rest pose g⁰ of end 2 in the end-0 frame.
    pub fn rest_end2(&self) -> Pose<f64> {
        Pose::translation([self.beam.length, 0.0, 0.0])
    }

    /// q_s = log((g⁰)⁻¹ · rel): the grasp-related deformation (node 2's
    /// nodal displacement) of the end-2 pose `rel` in the end-0 frame.
    pub fn grasp_deformation<T: Scalar>(&self, rel: &Pose<T>) -> [T; 6] {
        // g⁰ is a pure translation along x.
        se3_log(&Pose {
            r: rel.r,
            p: [rel.p[0] - self.beam.length, rel.p[1], rel.p[2]],
        })
    }

    /// q_f = (q_s, q_o) for the actual end-2 pose `rel` = g₀⁻¹ g₂ in the end-0
    /// frame and gravity `gravity_in_end0` (m/s²). Allocation-free.
    pub fn deformation<T: Scalar>(&self, rel: &Pose<T>, gravity_in_end0: [T; 3]) -> [T; 12] {
        let qs = self.grasp_deformation(rel);
        let mut out = [k::<T>(0.0); 12];
        out[..6].copy_from_slice(&qs);
        for i in 0..6 {
            let c = &self.condensation[i];
            let gr = &self.gravity_response[i];
            let mut acc = k::<T>(0.0);
            for j in 0..6 {
                acc += qs[j] * c[j];
            }
            for j in 0..3 {
                acc += gravity_in_end0[j] * gr[j];
            }
            out[6 + i] = acc;
        }
        out
    }

    /// Nodal displacements of nodes 0 (clamped, zero), 1 (q_o) and 2 (q_s).
    pub fn nodal_displacements<T: Scalar>(q_f: &[T; 12]) -> [[T; 6]; 3] {
        [
            [k::<T>(0.0); 6],
            std::array::from_fn(|i| q_f[6 + i]),
            std::array::from_fn(|i| q_f[i]),
        ]
    }

    /// The deformed centreline's frame at arc parameter `s` ∈ [0, L]
    /// (clamped) in the end-0 frame: origin on the centreline, x axis along
    /// the unit tangent, turned about it by the interpolated twist.
    pub fn centerline<T: Scalar>(&self, q_f: &[T; 12], s: f64) -> Pose<T> {
        self.centerline_of_nodes(&Self::nodal_displacements(q_f), s)
    }

    /// As [`FeBeam::centerline`], from the three nodes' displacements (node
    /// 0 need not be clamped: a compliant wrist moves it).
    pub fn centerline_of_nodes<T: Scalar>(&self, nodes: &[[T; 6]; 3], s: f64) -> Pose<T> {
        let l = self.beam.length;
        let le = l / 2.0;
        let s = s.clamp(0.0, l);
        let e = usize::from(s > le);
        let xi = (s - e as f64 * le) / le;
        let (a, b) = (&nodes[e], &nodes[e + 1]);
        // Hermite shape functions and their x-derivatives.
        let (x2, x3) = (xi * xi, xi * xi * xi);
        let n = [
            1.0 - 3.0 * x2 + 2.0 * x3,
            le * (xi - 2.0 * x2 + x3),
            3.0 * x2 - 2.0 * x3,
            le * (x3 - x2),
        ];
        let dn = [
            (6.0 * x2 - 6.0 * xi) / le,
            1.0 - 4.0 * xi + 3.0 * x2,
            (6.0 * xi - 6.0 * x2) / le,
            3.0 * x2 - 2.0 * xi,
        ];
        let hermite = |nn: &[f64; 4], y0: T, r0: T, y1: T, r1: T| {
            y0 * nn[0] + r0 * nn[1] + y1 * nn[2] + r1 * nn[3]
        };
        let u = a[0] * (1.0 - xi) + b[0] * xi;
        let du = (b[0] - a[0]) / le;
        let v = hermite(&n, a[1], a[5], b[1], b[5]);
        let dv = hermite(&dn, a[1], a[5], b[1], b[5]);
        // w' = −θ_y.
        let w = hermite(&n, a[2], -a[4], b[2], -b[4]);
        let dw = hermite(&dn, a[2], -a[4], b[2], -b[4]);
        let twist = a[3] * (1.0 - xi) + b[3] * xi;
        let t = [du + 1.0, dv, dw];
        let tn = dot(t, t).sqrt();
        let x = [t[0] / tn, t[1] / tn, t[2] / tn];
        // Minimal rotation taking e_x to x: I + [c]× + [c]×² / (1 + x₀), c = e_x × x.
        let c = [k::<T>(0.0), -x[2], x[1]];
        let cc = dot(c, c);
        let f = (x[0] + 1.0).recip();
        let hat: M3<T> = [
            [k(0.0), -c[2], c[1]],
            [c[2], k(0.0), -c[0]],
            [-c[1], c[0], k(0.0)],
        ];
        let rmin: M3<T> = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let delta = if i == j { 1.0 } else { 0.0 };
                k::<T>(delta) + hat[i][j] + (c[i] * c[j] - cc * delta) * f
            })
        });
        Pose {
            r: mul_mm(&rmin, &rot_x(twist)),
            p: [u + s, v, w],
        }
    }

    /// The undeformed centreline frame at `s` (for drawing the rest shape).
    pub fn rest_centerline(&self, s: f64) -> Pose<f64> {
        Pose::translation(lift([s.clamp(0.0, self.beam.length), 0.0, 0.0]))
    }
}

/// The 3D Euler–Bernoulli frame element of length `le` along x.
fn element_stiffness(beam: &Beam, le: f64) -> ElementStiffness {
    let ea = beam.axial_stiffness() / le;
    let gj = beam.torsional_stiffness() / le;
    let b = beam.bending_stiffness() / le.powi(3);
    let (b6, b4, b2) = (6.0 * le * b, 4.0 * le * le * b, 2.0 * le * le * b);
    let b12 = 12.0 * b;
    let mut m = ElementStiffness::zeros();
    let mut set = |i: usize, j: usize, x: f64| {
        m[(i, j)] = x;
        m[(j, i)] = x;
    };
    // Axial (0, 6) and torsion (3, 9).
    set(0, 0, ea);
    set(6, 6, ea);
    set(0, 6, -ea);
    set(3, 3, gj);
    set(9, 9, gj);
    set(3, 9, -gj);
    // Bending in x–y: v (1, 7), θ_z (5, 11), v' = θ_z.
    set(1, 1, b12);
    set(7, 7, b12);
    set(1, 7, -b12);
    set(1, 5, b6);
    set(1, 11, b6);
    set(5, 7, -b6);
    set(7, 11, -b6);
    set(5, 5, b4);
    set(11, 11, b4);
    set(5, 11, b2);
    // Bending in x–z: w (2, 8), θ_y (4, 10), w' = −θ_y flips the couplings.
    set(2, 2, b12);
    set(8, 8, b12);
    set(2, 8, -b12);
    set(2, 4, -b6);
    set(2, 10, -b6);
    set(4, 8, b6);
    set(8, 10, b6);
    set(4, 4, b4);
    set(10, 10, b4);
    set(4, 10, b2);
    m
}

/// K of elements (0, 1) and (1, 2).
fn assemble(ke: &ElementStiffness) -> Stiffness {
    let mut k = Stiffness::zeros();
    for e in 0..2 {
        let mut block = k.fixed_view_mut::<12, 12>(6 * e, 6 * e);
        block += ke;
    }
    k
}

/// Consistent nodal load (18 × 3) per unit gravity acceleration: per element
/// of length L_e and load q = ρ A g per length, forces q L_e / 2 at both
/// nodes and moments ±q L_e² / 12 (θ_z: +q_y at the first node; θ_y: −q_z,
/// from w' = −θ_y).
fn unit_gravity_load(beam: &Beam) -> SMatrix<f64, 18, 3> {
    let le = beam.length / 2.0;
    let mu = beam.mass_per_length();
    let (f, m) = (mu * le / 2.0, mu * le * le / 12.0);
    let mut g = SMatrix::<f64, 18, 3>::zeros();
    for e in 0..2 {
        for (node, sign) in [(e, 1.0), (e + 1, -1.0)] {
            let o = 6 * node;
            for d in 0..3 {
                g[(o + d, d)] += f;
            }
            g[(o + 5, 1)] += sign * m;
            g[(o + 4, 2)] -= sign * m;
        }
    }
    g
}
