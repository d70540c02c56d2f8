//! The system interface and the fixed-step RK4 of the state and its
//! variational system (Eqs. 17-18).

use crate::planner::endogenous::expansion::legendre;
use crate::planner::PlanError;
use nalgebra::DMatrix;

/// A system's sizes: the state's n and the input's m. [`Fixed`] sizes are
/// known to the compiler (its loops over n and m are unrolled: a compiled
/// model); [`Sizes`] are read at run time (a model declared in a scenario).
pub trait Dims: Copy + Send + Sync {
    /// State size n.
    fn n(self) -> usize;
    /// Input size m.
    fn m(self) -> usize;
}

/// Sizes fixed at compile time.
#[derive(Debug, Clone, Copy, Default)]
pub struct Fixed<const N: usize, const M: usize>;

impl<const N: usize, const M: usize> Dims for Fixed<N, M> {
    #[inline(always)]
    fn n(self) -> usize {
        N
    }
    #[inline(always)]
    fn m(self) -> usize {
        M
    }
}

/// Sizes known at run time.
#[derive(Debug, Clone, Copy)]
pub struct Sizes {
    /// State size.
    pub n: usize,
    /// Input size.
    pub m: usize,
}

impl Dims for Sizes {
    #[inline]
    fn n(self) -> usize {
        self.n
    }
    #[inline]
    fn m(self) -> usize {
        self.m
    }
}

/// q' = f(q, u) at one point with A(t) = ∂f/∂q and B(t) = ∂f/∂u, both
/// row-major (A is n × n, B is n × m).
#[derive(Debug, Clone, PartialEq)]
pub struct Linearization {
    /// q'.
    pub qdot: Vec<f64>,
    /// ∂f/∂q, row-major: a[r · n + c].
    pub a: Vec<f64>,
    /// ∂f/∂u, row-major: b[r · m + c] (G(q) for a control-affine system).
    pub b: Vec<f64>,
}

impl Linearization {
    /// Zeros of sizes `n`, `m`.
    pub fn zeros(n: usize, m: usize) -> Linearization {
        Linearization {
            qdot: vec![0.0; n],
            a: vec![0.0; n * n],
            b: vec![0.0; n * m],
        }
    }
}

/// A system the planner can linearise: any q' = f(q, u) with its
/// Jacobians. The planner knows nothing else of it (each robot implements
/// this next to its model).
pub trait EndogenousSystem: Sync {
    /// How its sizes are known.
    type Dims: Dims;
    /// Its sizes.
    fn dims(&self) -> Self::Dims;
    /// q', A and B at (q, u), into `out` (sized by [`Linearization::zeros`]).
    fn linearize(&self, q: &[f64], u: &[f64], out: &mut Linearization);
    /// A refusal to plan from (q, u), where a segment's iteration starts
    /// (an equation that is not differentiable there); `Ok` by default.
    fn check_start(&self, _q: &[f64], _u: &[f64]) -> Result<(), PlanError> {
        Ok(())
    }
    /// The unit of the endpoint error in messages (` rad`; empty for a
    /// state of mixed units).
    fn error_unit(&self) -> &'static str {
        ""
    }
}

/// Fixed-step RK4 of the state and (optionally) the variational system, with
/// the Legendre basis tabulated at the RK4 nodes (every half step).
///
/// Vectors are flat slices with hand-written loops: with [`Fixed`] sizes
/// they compile to the unrolled loops of fixed-size arrays, and they are
/// far faster than nalgebra's types when the crate itself is built without
/// optimisation (tests).
pub(crate) struct Integrator<D: Dims> {
    d: D,
    h: f64,
    steps: usize,
    pmax: usize,
    /// P_k at node n: phi[n * pmax + k].
    phi: Vec<f64>,
    input_of: Vec<usize>,
    degree_of: Vec<usize>,
    /// u at node n: u[n * m + i].
    u: Vec<f64>,
    /// Sensitivity column j: xi[j * n + r] (kx, acc alike).
    xi: Vec<f64>,
    kx: Vec<f64>,
    acc: Vec<f64>,
    lin: Linearization,
}

/// States up to this size keep the integrator's state vectors on the stack
/// (in registers, for [`Fixed`] sizes).
const ON_STACK: usize = 16;

impl<D: Dims> Integrator<D> {
    pub(crate) fn new(d: D, duration: f64, steps: usize, terms: &[usize]) -> Self {
        let (n, m) = (d.n(), d.m());
        let pmax = terms.iter().copied().max().unwrap_or(0);
        let nodes = 2 * steps + 1;
        let mut phi = vec![0.0; nodes * pmax];
        let mut der = vec![0.0; pmax];
        for k in 0..nodes {
            let s = 2.0 * k as f64 / (nodes - 1) as f64 - 1.0;
            legendre(s, &mut phi[k * pmax..(k + 1) * pmax], &mut der);
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
            d,
            h: duration / steps as f64,
            steps,
            pmax,
            phi,
            input_of,
            degree_of,
            u: vec![0.0; nodes * m],
            xi: vec![0.0; s * n],
            kx: vec![0.0; s * n],
            acc: vec![0.0; s * n],
            lin: Linearization::zeros(n, m),
        }
    }

    /// u(t) of λ at the start (node 0).
    pub(crate) fn u_start(&mut self, lambda: &[f64]) -> Vec<f64> {
        self.controls(lambda);
        self.u[..self.d.m()].to_vec()
    }

    /// u at every node from λ.
    fn controls(&mut self, lambda: &[f64]) {
        let (m, pm) = (self.d.m(), self.pmax);
        for (k, u) in self.u.chunks_exact_mut(m).enumerate() {
            let ph = &self.phi[k * pm..(k + 1) * pm];
            u.fill(0.0);
            for ((l, &i), &deg) in lambda.iter().zip(&self.input_of).zip(&self.degree_of) {
                u[i] += l * ph[deg];
            }
        }
    }

    /// Integrates from q0 under λ; fills `jac` (n × s) with ∂q(T)/∂λ when given.
    pub(crate) fn run<S: EndogenousSystem<Dims = D>>(
        &mut self,
        sys: &S,
        q0: &[f64],
        lambda: &[f64],
        jac: Option<&mut DMatrix<f64>>,
    ) -> Vec<f64> {
        self.controls(lambda);
        let (n, m, pm) = (self.d.n(), self.d.m(), self.pmax);
        let with_jac = jac.is_some();
        self.xi.fill(0.0);
        self.kx.fill(0.0);
        self.acc.fill(0.0);
        // (node offset, stage input coefficient, weight) of classical RK4.
        const STAGES: [(usize, f64, f64); 4] = [
            (0, 0.0, 1.0 / 6.0),
            (1, 0.5, 1.0 / 3.0),
            (1, 0.5, 1.0 / 3.0),
            (2, 1.0, 1.0 / 6.0),
        ];
        let (h, steps) = (self.h, self.steps);
        let Self {
            phi,
            input_of,
            degree_of,
            u,
            xi,
            kx,
            acc,
            lin,
            ..
        } = self;
        // State, stage slope, weighted slopes, stage state, stage column:
        // slices of the sizes' lengths, on the stack when small. With
        // [`Fixed`] sizes the compiler knows every index below is in range
        // (no bounds checks, loops unrolled, values in registers).
        let mut stack = [0.0; 5 * ON_STACK];
        let mut heap;
        let buf: &mut [f64] = if n <= ON_STACK {
            &mut stack[..5 * n]
        } else {
            heap = vec![0.0; 5 * n];
            &mut heap
        };
        let (q, rest) = buf.split_at_mut(n);
        let (kq, rest) = rest.split_at_mut(n);
        let (acc_q, rest) = rest.split_at_mut(n);
        let (qs, xs) = rest.split_at_mut(n);
        q.copy_from_slice(&q0[..n]);
        for step in 0..steps {
            kq.fill(0.0);
            acc_q.fill(0.0);
            for &(dn, c, w) in &STAGES {
                let node = 2 * step + dn;
                for r in 0..n {
                    qs[r] = q[r] + kq[r] * (c * h);
                }
                sys.linearize(qs, &u[node * m..(node + 1) * m], lin);
                kq.copy_from_slice(&lin.qdot[..n]);
                for r in 0..n {
                    acc_q[r] += kq[r] * w;
                }
                if !with_jac {
                    continue;
                }
                let (a, g) = (&lin.a[..n * n], &lin.b[..n * m]);
                let ph = &phi[node * pm..(node + 1) * pm];
                let ch = c * h;
                let cols = xi
                    .chunks_exact(n)
                    .zip(kx.chunks_exact_mut(n))
                    .zip(acc.chunks_exact_mut(n));
                for (((xi, kx), acc), (&i, &k)) in cols.zip(input_of.iter().zip(degree_of.iter())) {
                    let (xi, kx, acc) = (&xi[..n], &mut kx[..n], &mut acc[..n]);
                    for r in 0..n {
                        xs[r] = xi[r] + ch * kx[r];
                    }
                    let b = ph[k];
                    // Row r: v = G[r][i] P_k + Σ_c A[r][c] xs[c], summed in
                    // that order (iterators: no bounds checks).
                    let rows = a.chunks_exact(n).zip(g.chunks_exact(m));
                    for ((a_row, g_row), (acc_r, kx_r)) in
                        rows.zip(acc.iter_mut().zip(kx.iter_mut()))
                    {
                        let v = a_row
                            .iter()
                            .zip(xs.iter())
                            .fold(g_row[i] * b, |v, (a, x)| v + a * x);
                        *acc_r += w * v;
                        *kx_r = v;
                    }
                }
            }
            for r in 0..n {
                q[r] += acc_q[r] * h;
            }
            if with_jac {
                for (x, a) in xi.iter_mut().zip(acc.iter_mut()) {
                    *x += h * *a;
                    *a = 0.0;
                }
            }
        }
        if let Some(jac) = jac {
            for j in 0..input_of.len() {
                for r in 0..n {
                    jac[(r, j)] = xi[j * n + r];
                }
            }
        }
        q.to_vec()
    }
}
