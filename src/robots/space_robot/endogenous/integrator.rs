//! The system interface and the fixed-step RK4 of the state and its
//! variational system (Eqs. 17-18).

use crate::robots::space_robot::endogenous::expansion::legendre;
use crate::robots::space_robot::manipulator::SpaceManipulator;
use nalgebra::{DMatrix, SMatrix, SVector, Vector2, Vector3};

/// q' = f + G u at one state, with ∂(f + G u)/∂q.
#[derive(Debug, Clone, Copy)]
pub struct Linearization<const N: usize, const M: usize> {
    /// q' = f(q) + G(q) u.
    pub qdot: SVector<f64, N>,
    /// B(t) = G(q).
    pub g: SMatrix<f64, N, M>,
    /// A(t) = ∂(f + G u)/∂q.
    pub a: SMatrix<f64, N, N>,
}

/// A control-affine system the planner can linearise (fixed sizes, so the
/// inner integration loop stays on the stack).
pub trait EndogenousSystem<const N: usize, const M: usize>: Sync {
    /// q', G and A at (q, u).
    fn linearize(&self, q: &SVector<f64, N>, u: &SVector<f64, M>) -> Linearization<N, M>;
}

impl EndogenousSystem<3, 2> for SpaceManipulator {
    fn linearize(&self, q: &Vector3<f64>, u: &Vector2<f64>) -> Linearization<3, 2> {
        let l = SpaceManipulator::linearize(self, q, u);
        Linearization {
            qdot: l.qdot,
            g: l.g,
            a: l.a,
        }
    }
}

/// Fixed-step RK4 of the state and (optionally) the variational system, with
/// the Legendre basis tabulated at the RK4 nodes (every half step).
///
/// The sensitivity columns are plain `[f64; N]` arrays with hand-written
/// loops: as fast as nalgebra's fixed-size types in release, and far faster
/// when the crate itself is built without optimisation (tests).
pub(super) struct Integrator<const N: usize, const M: usize> {
    h: f64,
    steps: usize,
    pmax: usize,
    /// P_k at node n: phi[n * pmax + k].
    phi: Vec<f64>,
    input_of: Vec<usize>,
    degree_of: Vec<usize>,
    u: Vec<SVector<f64, M>>,
    xi: Vec<[f64; N]>,
    kx: Vec<[f64; N]>,
    acc: Vec<[f64; N]>,
}

impl<const N: usize, const M: usize> Integrator<N, M> {
    pub(super) fn new(duration: f64, steps: usize, terms: &[usize]) -> Self {
        let pmax = terms.iter().copied().max().unwrap_or(0);
        let nodes = 2 * steps + 1;
        let mut phi = vec![0.0; nodes * pmax];
        let mut der = vec![0.0; pmax];
        for n in 0..nodes {
            let s = 2.0 * n as f64 / (nodes - 1) as f64 - 1.0;
            legendre(s, &mut phi[n * pmax..(n + 1) * pmax], &mut der);
        }
        let mut input_of = Vec::new();
        let mut degree_of = Vec::new();
        for (i, &p) in terms.iter().enumerate() {
            for k in 0..p {
                input_of.push(i);
                degree_of.push(k);
            }
        }
        let s = input_of.len();
        Self {
            h: duration / steps as f64,
            steps,
            pmax,
            phi,
            input_of,
            degree_of,
            u: vec![SVector::zeros(); nodes],
            xi: vec![[0.0; N]; s],
            kx: vec![[0.0; N]; s],
            acc: vec![[0.0; N]; s],
        }
    }

    /// Integrates from q0 under λ; fills `jac` (N × s) with ∂q(T)/∂λ when given.
    pub(super) fn run<S: EndogenousSystem<N, M>>(
        &mut self,
        sys: &S,
        q0: &SVector<f64, N>,
        lambda: &[f64],
        jac: Option<&mut DMatrix<f64>>,
    ) -> SVector<f64, N> {
        let pm = self.pmax;
        for (n, u) in self.u.iter_mut().enumerate() {
            let ph = &self.phi[n * pm..(n + 1) * pm];
            let mut acc = [0.0; M];
            for ((l, &i), &k) in lambda.iter().zip(&self.input_of).zip(&self.degree_of) {
                acc[i] += l * ph[k];
            }
            *u = SVector::from(acc);
        }
        let with_jac = jac.is_some();
        let s = lambda.len();
        for j in 0..s {
            self.xi[j] = [0.0; N];
            self.kx[j] = [0.0; N];
            self.acc[j] = [0.0; N];
        }
        // (node offset, stage input coefficient, weight) of classical RK4.
        const STAGES: [(usize, f64, f64); 4] = [
            (0, 0.0, 1.0 / 6.0),
            (1, 0.5, 1.0 / 3.0),
            (1, 0.5, 1.0 / 3.0),
            (2, 1.0, 1.0 / 6.0),
        ];
        let h = self.h;
        let mut q = *q0;
        let mut a = [[0.0; N]; N];
        let mut g = [[0.0; M]; N];
        for step in 0..self.steps {
            let mut kq = SVector::<f64, N>::zeros();
            let mut acc_q = SVector::<f64, N>::zeros();
            for &(dn, c, w) in &STAGES {
                let node = 2 * step + dn;
                let qs = q + kq * (c * h);
                let lin = sys.linearize(&qs, &self.u[node]);
                kq = lin.qdot;
                acc_q += kq * w;
                if !with_jac {
                    continue;
                }
                for (r, (arow, grow)) in a.iter_mut().zip(g.iter_mut()).enumerate() {
                    for (col, x) in arow.iter_mut().enumerate() {
                        *x = lin.a[(r, col)];
                    }
                    for (col, x) in grow.iter_mut().enumerate() {
                        *x = lin.g[(r, col)];
                    }
                }
                let ph = &self.phi[node * pm..(node + 1) * pm];
                let ch = c * h;
                let cols = self
                    .xi
                    .iter()
                    .zip(self.kx.iter_mut())
                    .zip(self.acc.iter_mut());
                for (((xi, kx), acc), (&i, &k)) in
                    cols.zip(self.input_of.iter().zip(&self.degree_of))
                {
                    let mut xs = [0.0; N];
                    for r in 0..N {
                        xs[r] = xi[r] + ch * kx[r];
                    }
                    let b = ph[k];
                    for r in 0..N {
                        let mut v = g[r][i] * b;
                        for col in 0..N {
                            v += a[r][col] * xs[col];
                        }
                        acc[r] += w * v;
                        kx[r] = v;
                    }
                }
            }
            q += acc_q * h;
            if with_jac {
                for (xi, acc) in self.xi.iter_mut().zip(self.acc.iter_mut()) {
                    for r in 0..N {
                        xi[r] += h * acc[r];
                    }
                    *acc = [0.0; N];
                }
            }
        }
        if let Some(jac) = jac {
            for (j, xi) in self.xi.iter().enumerate() {
                for r in 0..N {
                    jac[(r, j)] = xi[r];
                }
            }
        }
        q
    }
}
