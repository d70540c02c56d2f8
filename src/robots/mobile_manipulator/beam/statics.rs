//! The carried chain in static equilibrium: wrist 1, the beam's two
//! elements, wrist 2, between the two flanges' grasp frames (ours: seed 004
//! grasps rigidly).
//!
//! Everything is linear and expressed in the **end-0 frame at rest** (the
//! flange-1 grasp frame, [`crate::robots::mobile_manipulator::beam::fe`]'s conventions), on five nodes:
//! A (flange 1's grasp point, clamped), the beam's nodes 0, 1, 2, and B
//! (flange 2's grasp point, displaced by the grasp twist ξ = q_s). A wrist is
//! a 6 × 6 spring between A and node 0 (between node 2 and B), its centre of
//! compliance at the grasp point: node 0 and A coincide at rest. A rigid
//! wrist ties the two nodes together instead. The beam carries its
//! consistent self-weight load for gravity g (end-0 frame).
//!
//! Outputs, each a linear map of (ξ, g): the beam's nodal displacements
//! (nodes 0, 1, 2, relative to A: so a wrist's deflection moves the beam
//! rigidly) and the wrench the grippers apply to the beam at nodes 0 and 2
//! (force, then moment about the node; N, N m): W = (K q − f) at those
//! nodes, which with a compliant wrist is the wrist's spring force. With
//! both wrists rigid the middle node is [`crate::robots::mobile_manipulator::beam::FeBeam`]'s condensation.

use crate::model::spatial::{k, Scalar};
use crate::robots::mobile_manipulator::beam::{BeamError, FeBeam};
use nalgebra::{DMatrix, SMatrix};

/// A wrist's stiffness in end-0 axes (6 × 6, translations then rotations,
/// about the grasp point), or `None` for a rigid one.
pub type WristStiffness = Option<SMatrix<f64, 6, 6>>;

/// Linear maps from (ξ, g) to the chain's nodes and grasp wrenches.
#[derive(Debug, Clone)]
pub struct GraspStatics {
    /// Rows: nodes 0, 1, 2 (6 each); columns: ξ.
    nodes_xi: [[f64; 6]; 18],
    /// Rows as `nodes_xi`; columns: g.
    nodes_g: [[f64; 3]; 18],
    /// Rows: the wrench on the beam at node 0, then at node 2; columns: ξ.
    wrench_xi: [[f64; 6]; 12],
    /// Rows as `wrench_xi`; columns: g.
    wrench_g: [[f64; 3]; 12],
}

/// `m` as a row-major array.
fn rows<const R: usize, const C: usize>(m: &DMatrix<f64>, r0: usize) -> [[f64; C]; R] {
    std::array::from_fn(|i| std::array::from_fn(|j| m[(r0 + i, j)]))
}

/// Σ_j m[i][j] x[j] per row (generic scalar, constant matrix).
fn apply<T: Scalar, const R: usize, const C: usize>(m: &[[f64; C]; R], x: &[T; C]) -> [T; R] {
    std::array::from_fn(|i| {
        let mut acc = k::<T>(0.0);
        for (a, b) in m[i].iter().zip(x) {
            acc += *b * *a;
        }
        acc
    })
}

impl GraspStatics {
    /// Solve the chain once (fails only if the stiffness is singular).
    pub fn new(fe: &FeBeam, wrists: [WristStiffness; 2]) -> Result<GraspStatics, BeamError> {
        // DOFs: A 0..6, node 0 6..12, node 1 12..18, node 2 18..24, B 24..30.
        let n = 30;
        let mut kk = DMatrix::<f64>::zeros(n, n);
        let kb = fe.stiffness();
        for i in 0..18 {
            for j in 0..18 {
                kk[(6 + i, 6 + j)] = kb[(i, j)];
            }
        }
        let kbeam = kk.clone();
        for (w, (a, b)) in wrists.iter().zip([(0, 6), (18, 24)]) {
            if let Some(kw) = w {
                for i in 0..6 {
                    for j in 0..6 {
                        kk[(a + i, a + j)] += kw[(i, j)];
                        kk[(b + i, b + j)] += kw[(i, j)];
                        kk[(a + i, b + j)] -= kw[(i, j)];
                        kk[(b + i, a + j)] -= kw[(i, j)];
                    }
                }
            }
        }
        // Unit gravity loads on the beam's nodes (columns g_x, g_y, g_z).
        let mut f = DMatrix::<f64>::zeros(n, 3);
        for c in 0..3 {
            let mut g = [0.0; 3];
            g[c] = 1.0;
            let load = fe.gravity_load(g);
            for i in 0..18 {
                f[(6 + i, c)] = load[i];
            }
        }
        // Prescribed DOFs: A = 0, B = ξ, and a rigid wrist's beam node with them.
        // `xi_of[d]`: Some(j) when DOF d is prescribed to ξ_j, Some(None) when 0.
        let mut prescribed: Vec<Option<Option<usize>>> = vec![None; n];
        for d in 0..6 {
            prescribed[d] = Some(None);
            prescribed[24 + d] = Some(Some(d));
            if wrists[0].is_none() {
                prescribed[6 + d] = Some(None);
            }
            if wrists[1].is_none() {
                prescribed[18 + d] = Some(Some(d));
            }
        }
        let free: Vec<usize> = (0..n).filter(|d| prescribed[*d].is_none()).collect();
        let mut qp = DMatrix::<f64>::zeros(n, 6);
        for (d, p) in prescribed.iter().enumerate() {
            if let Some(Some(j)) = p {
                qp[(d, *j)] = 1.0;
            }
        }
        let nf = free.len();
        let kff = DMatrix::from_fn(nf, nf, |i, j| kk[(free[i], free[j])]);
        let chol = kff.cholesky().ok_or(BeamError::ChainBlock)?;
        // q_F = K_FF⁻¹ (f_F g − K_F· q_P ξ).
        let kq = &kk * &qp;
        let rhs_xi = DMatrix::from_fn(nf, 6, |i, j| -kq[(free[i], j)]);
        let rhs_g = DMatrix::from_fn(nf, 3, |i, j| f[(free[i], j)]);
        let (sol_xi, sol_g) = (chol.solve(&rhs_xi), chol.solve(&rhs_g));
        let mut q_xi = qp;
        let mut q_g = DMatrix::<f64>::zeros(n, 3);
        for (i, d) in free.iter().enumerate() {
            for j in 0..6 {
                q_xi[(*d, j)] = sol_xi[(i, j)];
            }
            for j in 0..3 {
                q_g[(*d, j)] = sol_g[(i, j)];
            }
        }
        // The beam's own balance: what its supports (the grippers) apply.
        let w_xi = &kbeam * &q_xi;
        let w_g = &kbeam * &q_g - &f;
        let pick = |m: &DMatrix<f64>, c: usize| {
            let mut out = DMatrix::<f64>::zeros(12, c);
            for (r, d) in (6..12).chain(18..24).enumerate() {
                for j in 0..c {
                    out[(r, j)] = m[(d, j)];
                }
            }
            out
        };
        Ok(GraspStatics {
            nodes_xi: rows(&q_xi, 6),
            nodes_g: rows(&q_g, 6),
            wrench_xi: rows(&pick(&w_xi, 6), 0),
            wrench_g: rows(&pick(&w_g, 3), 0),
        })
    }

    /// The beam's nodal displacements (nodes 0, 1, 2; end-0 frame, relative
    /// to flange 1's grasp frame) at grasp twist ξ and gravity g.
    pub fn nodes<T: Scalar>(&self, xi: &[T; 6], g: &[T; 3]) -> [[T; 6]; 3] {
        let a = apply(&self.nodes_xi, xi);
        let b = apply(&self.nodes_g, g);
        std::array::from_fn(|n| std::array::from_fn(|i| a[6 * n + i] + b[6 * n + i]))
    }

    /// The wrenches the grippers apply to the beam at node 0 and node 2
    /// (force N, moment N m about the node; end-0 axes).
    pub fn wrenches<T: Scalar>(&self, xi: &[T; 6], g: &[T; 3]) -> [[T; 6]; 2] {
        let a = apply(&self.wrench_xi, xi);
        let b = apply(&self.wrench_g, g);
        std::array::from_fn(|e| std::array::from_fn(|i| a[6 * e + i] + b[6 * e + i]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robots::mobile_manipulator::beam::{Beam, GFRP_ROD_10MM};

    fn fe(length: f64) -> FeBeam {
        let (material, section) = GFRP_ROD_10MM;
        FeBeam::new(&Beam {
            material,
            section,
            length,
        })
        .unwrap()
    }

    fn diag(t: f64, r: f64) -> SMatrix<f64, 6, 6> {
        SMatrix::from_diagonal(&nalgebra::Vector6::new(t, t, t, r, r, r))
    }

    /// With rigid wrists the middle node is the FE model's condensation and
    /// the grasp wrench at node 2 is the clamped beam's: EA/L per metre of
    /// stretch, 12EI/L³ per metre of lateral offset (with −6EI/L² of moment).
    #[test]
    fn rigid_wrists_give_the_clamped_beam() {
        let fe = fe(3.0);
        let s = GraspStatics::new(&fe, [None, None]).unwrap();
        let b = fe.beam();
        let l = b.length;
        let xi = [1e-3, 2e-3, 0.0, 0.0, 0.0, 0.0];
        let g = [0.0, 0.0, -9.81];
        let n = s.nodes(&xi, &g);
        let q = fe.deformation(
            &crate::model::spatial::Pose::translation([l + 1e-3, 2e-3, 0.0]),
            g,
        );
        for i in 0..6 {
            assert!(n[0][i].abs() < 1e-15);
            assert!((n[2][i] - xi[i]).abs() < 1e-15);
            // q_s from the log differs from ξ at second order only.
            assert!((n[1][i] - q[6 + i]).abs() < 1e-7, "{:?} vs {:?}", n[1], q);
        }
        let w = s.wrenches(&xi, &[0.0; 3]);
        let ea = b.axial_stiffness() / l;
        let shear = 12.0 * b.bending_stiffness() / l.powi(3);
        assert!((w[1][0] - ea * 1e-3).abs() < 1e-9 * ea);
        assert!((w[1][1] - shear * 2e-3).abs() < 1e-9 * shear);
        // Node 0 holds the opposite force.
        assert!((w[0][0] + w[1][0]).abs() < 1e-9 * ea);
        // Gravity alone: each grasp carries half the weight, upwards.
        let w = s.wrenches(&[0.0; 6], &g);
        let half = 0.5 * b.mass_per_length() * 9.81 * l;
        for e in &w {
            assert!((e[2] - half).abs() < 1e-9 * half, "{e:?}");
        }
    }

    /// Two equal wrists in series with the (axially rigid) rod: a stretch ξ
    /// deflects each wrist by ξ/2 (less the rod's micrometres) and the force
    /// is k ξ / 2; the beam moves rigidly by the first wrist's deflection.
    #[test]
    fn compliant_wrists_take_the_stretch_in_series() {
        let fe = fe(3.0);
        let k = 800.0;
        let s = GraspStatics::new(&fe, [Some(diag(k, 50.0)), Some(diag(k, 50.0))]).unwrap();
        let xi = [0.1, 0.0, 0.0, 0.0, 0.0, 0.0];
        let n = s.nodes(&xi, &[0.0; 3]);
        let w = s.wrenches(&xi, &[0.0; 3]);
        let ea = fe.beam().axial_stiffness() / 3.0;
        let series = 1.0 / (2.0 / k + 1.0 / ea);
        assert!((w[1][0] - series * 0.1).abs() < 1e-9 * series, "{:?}", w[1]);
        assert!((n[0][0] + w[0][0] / k).abs() < 1e-12, "{:?}", n[0]);
        assert!((n[0][0] - 0.05).abs() < 1e-4 && (n[2][0] - 0.05).abs() < 1e-4);
        assert!((n[1][0] - 0.05).abs() < 1e-4);
    }
}
