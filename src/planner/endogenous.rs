//! Endogenous configuration space Jacobian planner with end/via-point control
//! constraints (seed 001, Ratajczak 2025, Eqs. 15-27).
//!
//! Each input is a truncated Legendre series on its segment,
//! u_i(t) = Σ_k λ_ik P_k(2t/T − 1) (Eq. 15). The end-point map λ ↦ q(T) is
//! integrated with a fixed-step RK4 together with its variational system
//! ξ' = A(t) ξ + B(t) P(t) (Eqs. 17-18), which gives the Jacobian J = ξ(T)
//! (output k(q) = q, so C = I). Control constraints u(t_k) = w_k and
//! u'(t_k) = d_k are rows Ψ of P(t_k), dP/dt(t_k) appended to J (Eq. 25); the
//! initial parameters solve Ψ λ0 = (w, d) with the Moore–Penrose inverse
//! (Eq. 27, u0 = 0 when there are no constraints) and the update of Eq. 26,
//! dλ/dϑ = −γ J_ext^# (e, 0), is integrated with an Euler step Δϑ:
//! λ ← λ − γ Δϑ J_ext^# (e, 0). Because the Ψ-part of the right-hand side is
//! zero, every step keeps Ψ λ = (w, d) exactly (to round-off).
//!
//! The right pseudo-inverse is an SVD pseudo-inverse with singular values
//! below `rcond`·σ_max dropped. It must be rank-safe: at u = 0 (and p = 0) the
//! state does not move, A(t) = 0, and J = G(q0) ∫ P has rank 2 < 3 (the base
//! orientation is reachable only through Lie brackets), so the plain
//! J^T (J J^T)^-1 is singular. Where J_ext has full row rank the SVD
//! pseudo-inverse equals J^T (J J^T)^-1 (tested).
//!
//! Multi-segment tasks (q0 → y1 at T → … → yf at kT, §5) are planned segment
//! after segment, as the paper's "sequence of two subtasks": segment j starts
//! from the state actually reached by segment j−1 and, with C0 (C1)
//! continuity, inherits u (and u') at its start from segment j−1's end as
//! constraints.
//!
//! Numbers: seed 001 prints no iteration counts, errors, times or control
//! amplitudes, only the task data (q0, y1, yf, T = 20, γ = 0.02, p = 0,
//! du/dt(0) = 0.01), which the tests use. It does not state the number of
//! basis terms, how Eq. 26 is integrated in ϑ or the stopping tolerance, so
//! its figures cannot be reproduced quantitatively; only their qualitative
//! claims are tested (S1 jumps at T, S2 is C0 with a kink, S3 is C1). Our
//! choices: 8 Legendre terms per input, the literal discrete iteration
//! λ ← λ − γ J^# e (Euler step Δϑ = 1, so γ = 0.02 is the step), finished by
//! full Gauss–Newton steps once ‖e‖ < 1e-3 rad (`newton_below`), tolerance
//! 1e-8 rad, 100 RK4 steps per segment. The Euler phase shrinks ‖e‖ by
//! exactly (1 − γΔϑ) per iteration (tested), so its length is determined:
//! ⌈ln(1e-3/‖e0‖)/ln(0.98)⌉ = 322 for segment 1 (‖e0‖ = 0.668 rad).
//! The controls depend on the ϑ-discretisation (γ only rescales ϑ, but the
//! Euler step γΔϑ changes the path, most visibly in S3: max_i,t |u_i| ≈ 1.29,
//! 1.07, 1.94 rad/s for γΔϑ = 0.01, 0.02, 0.04), another reason the paper's
//! plots cannot be matched. The task needs large joint motions (the base
//! turns by at most ≈ 0.07 rad per rad² of joint-space loop area), hence
//! peak joint rates of 1-5 rad/s at T = 20 s.
//!
//! At a join without continuity u jumps; the open-loop law returns the
//! midpoint of the one-sided limits at the join instant, so fixed-step RK4
//! through the join errs by ≈ ±dt/12·jump in the steps before and after it,
//! which cancel at the end (q(T) itself still carries ≈ dt/12·jump: the S1
//! test therefore simulates with dt = 1e-4).

use crate::model::space_manipulator::SpaceManipulator;
use crate::model::{Input, KinematicModel, State};
use crate::plan::{ControlLaw, Limits, Plan, Segment};
use crate::planner::PlanError;
use nalgebra::{DMatrix, DVector, SMatrix, SVector, Vector2, Vector3};
use std::sync::Arc;

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

/// Legendre polynomials P_0..P_{p−1}(s) and their derivatives d/ds (p = vals.len()).
pub fn legendre(s: f64, vals: &mut [f64], ders: &mut [f64]) {
    let p = vals.len();
    if p == 0 {
        return;
    }
    vals[0] = 1.0;
    ders[0] = 0.0;
    if p == 1 {
        return;
    }
    vals[1] = s;
    ders[1] = 1.0;
    for k in 1..p - 1 {
        let kf = k as f64;
        vals[k + 1] = ((2.0 * kf + 1.0) * s * vals[k] - kf * vals[k - 1]) / (kf + 1.0);
        ders[k + 1] = ders[k - 1] + (2.0 * kf + 1.0) * vals[k];
    }
}

/// Value (order 0) or first time derivative (order 1) of the control.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Order {
    /// u(t).
    Value,
    /// du/dt.
    Derivative,
}

/// A constraint u(t) = target or du/dt(t) = target at a segment-local time.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ControlConstraint {
    /// Local time in [0, T], s.
    pub time: f64,
    /// Value or derivative.
    pub order: Order,
    /// Target, one entry per input (rad/s or rad/s²).
    pub target: Vec<f64>,
}

/// One segment's control: a Legendre series per input (Eq. 15).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ControlExpansion {
    /// Global start time, s.
    pub start: f64,
    /// Segment duration T, s.
    pub duration: f64,
    /// Number of Legendre terms per input.
    pub terms: Vec<usize>,
    /// Parameters λ, input after input.
    pub lambda: Vec<f64>,
}

impl ControlExpansion {
    fn offsets(terms: &[usize]) -> Vec<usize> {
        terms
            .iter()
            .scan(0, |acc, &p| {
                let o = *acc;
                *acc += p;
                Some(o)
            })
            .collect()
    }

    /// Row of P(t) (order Value) or dP/dt (Derivative) for input `input`:
    /// the coefficients c with u_input(t) (or u'_input) = c · λ.
    pub fn basis_row(
        terms: &[usize],
        duration: f64,
        local_t: f64,
        order: Order,
        input: usize,
    ) -> Vec<f64> {
        let s_total: usize = terms.iter().sum();
        let pmax = terms.iter().copied().max().unwrap_or(0);
        let (mut v, mut d) = (vec![0.0; pmax], vec![0.0; pmax]);
        legendre(2.0 * local_t / duration - 1.0, &mut v, &mut d);
        let off = Self::offsets(terms)[input];
        let mut row = vec![0.0; s_total];
        for k in 0..terms[input] {
            row[off + k] = match order {
                Order::Value => v[k],
                Order::Derivative => d[k] * 2.0 / duration,
            };
        }
        row
    }

    /// u(t) (order Value) or du/dt (Derivative) at global time t (not clamped).
    pub fn eval(&self, t: f64, order: Order) -> Vec<f64> {
        let pmax = self.terms.iter().copied().max().unwrap_or(0);
        // Stack buffers for the usual sizes: this runs at every RK4 stage of a replay.
        let (mut sv, mut sd) = ([0.0; 64], [0.0; 64]);
        let (mut hv, mut hd);
        let (v, d): (&mut [f64], &mut [f64]) = if pmax <= 64 {
            (&mut sv[..pmax], &mut sd[..pmax])
        } else {
            hv = vec![0.0; pmax];
            hd = vec![0.0; pmax];
            (&mut hv, &mut hd)
        };
        legendre(2.0 * (t - self.start) / self.duration - 1.0, v, d);
        let scale = 2.0 / self.duration;
        let mut off = 0;
        let mut out = Vec::with_capacity(self.terms.len());
        for &p in &self.terms {
            let lam = &self.lambda[off..off + p];
            let val: f64 = match order {
                Order::Value => lam.iter().zip(v.iter()).map(|(l, b)| l * b).sum(),
                Order::Derivative => {
                    scale * lam.iter().zip(d.iter()).map(|(l, b)| l * b).sum::<f64>()
                }
            };
            out.push(val);
            off += p;
        }
        out
    }
}

/// Continuity imposed on u at the joins between segments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Continuity {
    /// Segments are planned independently (u may jump, scenario S1).
    None,
    /// u continuous (S2).
    C0,
    /// u and du/dt continuous (S3).
    C1,
}

/// A prescribed control value and/or derivative at a global time (a via
/// point of the control when strictly inside a segment). At a join time it
/// applies to both adjacent segments.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct ControlPoint {
    /// Global time, s.
    pub time: f64,
    /// u(time), rad/s per input.
    #[serde(default)]
    pub value: Option<Vec<f64>>,
    /// du/dt(time), rad/s² per input.
    #[serde(default)]
    pub derivative: Option<Vec<f64>>,
}

/// Planner parameters. Control constraints are in model units (rad/s,
/// rad/s²) like the paper's du/dt(0) = 0.01; only waypoints are in degrees.
#[derive(Debug, Clone, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct EndogenousParams {
    /// Duration T of every segment, s (paper: 20).
    pub segment_time: f64,
    /// Intermediate targets y1, y2, … (full states, degrees), reached at T, 2T, …;
    /// the goal is reached at (len + 1) T.
    pub via_deg: Vec<Vec<f64>>,
    /// Legendre terms per input (s = m · basis_terms parameters per segment).
    pub basis_terms: usize,
    /// Error decay rate γ of Eq. 26 (paper: 0.02).
    pub gamma: f64,
    /// Euler step Δϑ of the ϑ-integration of Eq. 26 (γΔϑ ≤ 1; 1 = Newton step).
    pub dtheta: f64,
    /// Below this error (rad) the step becomes a full Gauss–Newton step
    /// (γΔϑ = 1) to finish quickly; 0 follows Eq. 26 to the end.
    pub newton_below: f64,
    /// Fixed RK4 steps per segment for the state and variational system.
    pub rk4_steps: usize,
    /// Iteration cap per segment.
    pub max_iterations: usize,
    /// Stop when ‖q(T) − y‖ ≤ tolerance (rad).
    pub tolerance: f64,
    /// Relative SVD cut-off of the pseudo-inverse.
    pub rcond: f64,
    /// Give up when the best error has not dropped by 0.1 % for this many iterations.
    pub stall_iterations: usize,
    /// u(0), rad/s per input.
    pub u_start: Option<Vec<f64>>,
    /// du/dt(0), rad/s² per input.
    pub du_start: Option<Vec<f64>>,
    /// u at the final time, rad/s per input.
    pub u_end: Option<Vec<f64>>,
    /// du/dt at the final time, rad/s² per input.
    pub du_end: Option<Vec<f64>>,
    /// Continuity at the joins.
    pub continuity: Continuity,
    /// Further value/derivative constraints at given times.
    pub control_points: Vec<ControlPoint>,
    /// Fail with `Unreachable` when the planned |u_i| exceeds `Limits::max_rate`.
    pub enforce_rate_limits: bool,
}

impl Default for EndogenousParams {
    fn default() -> Self {
        Self {
            segment_time: 20.0,
            via_deg: Vec::new(),
            basis_terms: 8,
            gamma: 0.02,
            dtheta: 1.0,
            newton_below: 1e-3,
            rk4_steps: 100,
            max_iterations: 2000,
            tolerance: 1e-8,
            rcond: 1e-10,
            stall_iterations: 200,
            u_start: None,
            du_start: None,
            u_end: None,
            du_end: None,
            continuity: Continuity::None,
            control_points: Vec::new(),
            enforce_rate_limits: true,
        }
    }
}

/// How one segment's iteration went.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SegmentReport {
    /// Iterations performed: Jacobian updates, plus one per grid refinement
    /// (the re-evaluation of the end-point map on the finer grid).
    pub iterations: usize,
    /// ‖e‖ before the first update, rad.
    pub initial_error: f64,
    /// ‖e‖ at exit (internal integrator), rad.
    pub final_error: f64,
    /// q(T) on the verification grid (twice as fine as the final one).
    pub endpoint: Vec<f64>,
    /// RK4 steps of the grid the iteration ended on (`rk4_steps`, doubled
    /// until a grid twice as fine agrees within twice the tolerance).
    pub rk4_steps: usize,
    /// Constraints imposed on this segment.
    pub constraints: Vec<ControlConstraint>,
    /// ‖e‖ at every iteration.
    #[serde(skip)]
    pub error_history: Vec<f64>,
}

/// The planner's result before it is wrapped into a [`Plan`].
#[derive(Debug, Clone, serde::Serialize)]
pub struct Solution {
    /// One expansion per segment, in time order.
    pub segments: Vec<ControlExpansion>,
    /// One report per segment.
    pub reports: Vec<SegmentReport>,
}

impl Solution {
    /// u(t) (or du/dt) and the segment index; segment j covers [jT, (j+1)T),
    /// the last one also its end.
    pub fn eval(&self, t: f64, order: Order) -> (Vec<f64>, usize) {
        let n = self.segments.len();
        let t_seg = self.segments[0].duration;
        let idx = ((t / t_seg).floor().max(0.0) as usize).min(n - 1);
        (self.segments[idx].eval(t, order), idx)
    }

    /// Total duration, s.
    pub fn duration(&self) -> f64 {
        self.segments.iter().map(|s| s.duration).sum()
    }
}

struct Settings {
    step: f64,
    newton_below: f64,
    rk4_steps: usize,
    max_iterations: usize,
    tolerance: f64,
    rcond: f64,
    stall_iterations: usize,
}

/// Fixed-step RK4 of the state and (optionally) the variational system, with
/// the Legendre basis tabulated at the RK4 nodes (every half step).
///
/// The sensitivity columns are plain `[f64; N]` arrays with hand-written
/// loops: as fast as nalgebra's fixed-size types in release, and far faster
/// when the crate itself is built without optimisation (tests).
struct Integrator<const N: usize, const M: usize> {
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
    fn new(duration: f64, steps: usize, terms: &[usize]) -> Self {
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
    fn run<S: EndogenousSystem<N, M>>(
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

/// Solves a x = b in the minimum-norm least-squares sense with an SVD,
/// dropping singular values below rcond·σ_max (rank-safe right inverse).
pub fn pinv_solve(a: &DMatrix<f64>, b: &DVector<f64>, rcond: f64) -> DVector<f64> {
    let svd = a.clone().svd(true, true);
    let smax = svd.singular_values.max();
    let eps = (rcond * smax).max(f64::MIN_POSITIVE);
    svd.solve(b, eps).expect("U and V were computed")
}

/// Ψ (one row per constrained input component) and its target vector.
fn constraint_rows(
    terms: &[usize],
    duration: f64,
    cons: &[ControlConstraint],
) -> (DMatrix<f64>, DVector<f64>) {
    let s: usize = terms.iter().sum();
    let m = terms.len();
    let rows = cons.len() * m;
    let mut psi = DMatrix::zeros(rows, s);
    let mut w = DVector::zeros(rows);
    for (c, con) in cons.iter().enumerate() {
        for i in 0..m {
            let row = ControlExpansion::basis_row(terms, duration, con.time, con.order, i);
            psi.row_mut(c * m + i).copy_from_slice(&row);
            w[c * m + i] = con.target[i];
        }
    }
    (psi, w)
}

/// Orthonormal basis (columns) of the null space of `psi` (s × s identity when empty).
fn null_space(psi: &DMatrix<f64>, s: usize) -> DMatrix<f64> {
    if psi.nrows() == 0 {
        return DMatrix::identity(s, s);
    }
    // Right singular vectors of Ψ padded to a square matrix: the SVD of Ψᵀ Ψ (s × s).
    let gram = psi.transpose() * psi;
    let eig = gram.symmetric_eigen();
    let smax = eig.eigenvalues.amax();
    let cols: Vec<usize> = (0..s)
        .filter(|&j| eig.eigenvalues[j] <= 1e-12 * smax)
        .collect();
    DMatrix::from_fn(s, cols.len(), |r, c| eig.eigenvectors[(r, cols[c])])
}

/// The Euler step −h J_ext^# (e, 0) of Eq. 26 in the paper's literal form
/// (SVD pseudo-inverse of the stacked [J; Ψ]); the planner uses the
/// equivalent null-space form, this one is kept as its reference.
pub fn extended_step(
    jac: &DMatrix<f64>,
    psi: &DMatrix<f64>,
    e: &DVector<f64>,
    step: f64,
    rcond: f64,
) -> DVector<f64> {
    let (r, s) = (jac.nrows(), jac.ncols());
    let c = psi.nrows();
    let mut jext = DMatrix::zeros(r + c, s);
    jext.rows_mut(0, r).copy_from(jac);
    jext.rows_mut(r, c).copy_from(psi);
    let mut rhs = DVector::zeros(r + c);
    rhs.rows_mut(0, r).copy_from(&(e * -step));
    pinv_solve(&jext, &rhs, rcond)
}

struct SegmentOutcome<const N: usize> {
    lambda: Vec<f64>,
    report: SegmentReport,
    endpoint: SVector<f64, N>,
}

/// Most RK4 steps per segment the grid refinement may reach (the
/// `rk4_steps` parameter's own bound).
const MAX_RK4_STEPS: usize = 1_000_000;

fn no_conv(label: &str, why: String) -> PlanError {
    PlanError::NoConvergence(format!("{label}: {why}"))
}

#[allow(clippy::too_many_arguments)]
fn solve_segment<const N: usize, const M: usize, S: EndogenousSystem<N, M>>(
    sys: &S,
    q0: &SVector<f64, N>,
    target: &SVector<f64, N>,
    duration: f64,
    terms: &[usize],
    constraints: Vec<ControlConstraint>,
    set: &Settings,
    label: &str,
) -> Result<SegmentOutcome<N>, PlanError> {
    let s: usize = terms.iter().sum();
    let (psi, w) = constraint_rows(terms, duration, &constraints);
    // Eq. 27: λ0 from Ψ λ0 = (w, d) with the Moore–Penrose inverse (λ0 = 0 without constraints).
    let mut lambda = if psi.nrows() > 0 {
        pinv_solve(&psi, &w, 1e-12)
    } else {
        DVector::zeros(s)
    };
    if psi.nrows() > 0 {
        let res = (&psi * &lambda - &w).amax();
        if res > 1e-9 * (1.0 + w.amax()) {
            return Err(PlanError::InvalidParameter {
                name: "basis_terms".into(),
                reason: format!("{label}: the control constraints are inconsistent or need more basis terms (residual {res:.2e})"),
            });
        }
    }
    // Orthonormal basis of ker Ψ: the update μ = Z ν with J Z ν = −h e, ν of
    // minimum norm, is exactly the extended right pseudo-inverse step of Eq. 26
    // (min ‖μ‖ subject to J μ = −h e, Ψ μ = 0) but can never leak into Ψ μ ≠ 0
    // when the SVD cut-off drops a direction of J.
    let z = null_space(&psi, s);
    let mut steps = set.rk4_steps;
    let mut integ = Integrator::<N, M>::new(duration, steps, terms);
    let mut jac = DMatrix::zeros(N, s);
    let mut best = f64::INFINITY;
    let mut best_it = 0;
    let mut initial = f64::NAN;
    let mut history = Vec::new();
    // A `loop`, not `for it in 0..=max_iterations`: every pass either
    // returns or goes on to the next evaluation at the bottom, and both ways
    // on (a Jacobian step, a grid refinement) check the cap first, so the
    // loop cannot run out without an answer. (The `for` form had a refinement
    // at the last iteration leave the loop and reach an `unreachable!()`:
    // found by the property tests, `endogenous_refinement_at_the_iteration_cap`.)
    let mut it = 0;
    loop {
        let q_end = integ.run(sys, q0, lambda.as_slice(), Some(&mut jac));
        let e = q_end - target;
        let norm = e.norm();
        if it == 0 {
            initial = norm;
        }
        history.push(norm);
        if !norm.is_finite() || lambda.iter().any(|l| !l.is_finite()) {
            return Err(no_conv(
                label,
                format!("non-finite error after {it} iterations"),
            ));
        }
        if norm <= set.tolerance {
            // The plan is the control, not this grid's picture of it: with
            // large controls 100 steps over 20 s put the true endpoint 7e-5
            // rad off while this grid read 1e-8 (found by the property
            // tests). A grid twice as fine (16× smaller RK4 error) must
            // agree; otherwise refine and iterate on from the current λ.
            let fine = Integrator::<N, M>::new(duration, 2 * steps, terms).run(
                sys,
                q0,
                lambda.as_slice(),
                None,
            );
            let e_fine = (fine - target).norm();
            if e_fine <= 2.0 * set.tolerance {
                return Ok(SegmentOutcome {
                    lambda: lambda.as_slice().to_vec(),
                    report: SegmentReport {
                        iterations: it,
                        initial_error: initial,
                        final_error: norm,
                        endpoint: fine.as_slice().to_vec(),
                        rk4_steps: steps,
                        constraints,
                        error_history: history,
                    },
                    endpoint: fine,
                });
            }
            if 2 * steps > MAX_RK4_STEPS {
                return Err(no_conv(
                    label,
                    format!(
                        "on {steps} RK4 steps the endpoint meets {:.1e} rad, on {} it is {e_fine:.3e} rad off: \
                         the controls are too fast for the integration grid (shorten the task or lengthen segment_time)",
                        set.tolerance,
                        2 * steps
                    ),
                ));
            }
            if it == set.max_iterations {
                return Err(no_conv(
                    label,
                    format!(
                        "iteration cap {it} reached while refining the integration grid: on {steps} RK4 steps \
                         the endpoint meets {:.1e} rad, on {} it is {e_fine:.3e} rad off and needs further \
                         iterations (the controls are too fast for the grid: shorten the task, lengthen \
                         segment_time or raise max_iterations)",
                        set.tolerance,
                        2 * steps
                    ),
                ));
            }
            // Refine and iterate on from the current λ; the re-evaluation on
            // the finer grid is the next iteration.
            steps *= 2;
            integ = Integrator::<N, M>::new(duration, steps, terms);
            best = f64::INFINITY;
            best_it = it;
            it += 1;
            continue;
        }
        if it == set.max_iterations {
            return Err(no_conv(
                label,
                format!("iteration cap {it} reached with error {norm:.3e} rad"),
            ));
        }
        if norm < best * (1.0 - 1e-3) {
            best = norm;
            best_it = it;
        } else if it - best_it > set.stall_iterations {
            return Err(no_conv(
                label,
                format!(
                    "error stalled at {best:.3e} rad for {} iterations (singular configuration?)",
                    it - best_it
                ),
            ));
        }
        if norm > 1e3 * (1.0 + initial) {
            return Err(no_conv(
                label,
                format!("diverged: error {norm:.3e} rad after {it} iterations"),
            ));
        }
        let step = if norm < set.newton_below {
            1.0
        } else {
            set.step
        };
        let rhs = DVector::from_column_slice(e.as_slice()) * -step;
        let nu = pinv_solve(&(&jac * &z), &rhs, set.rcond);
        lambda += &z * nu;
        it += 1;
    }
}

fn invalid(name: &str, reason: impl Into<String>) -> PlanError {
    PlanError::InvalidParameter {
        name: name.into(),
        reason: reason.into(),
    }
}

fn check_vec(name: &str, v: &Option<Vec<f64>>, m: usize) -> Result<(), PlanError> {
    if let Some(v) = v {
        if v.len() != m {
            return Err(invalid(name, format!("needs {m} entries, got {}", v.len())));
        }
        if v.iter().any(|x| !x.is_finite()) {
            return Err(invalid(name, "entries must be finite"));
        }
    }
    Ok(())
}

fn validate<const N: usize, const M: usize>(p: &EndogenousParams) -> Result<(), PlanError> {
    let positive = [
        ("segment_time", p.segment_time),
        ("gamma", p.gamma),
        ("dtheta", p.dtheta),
        ("tolerance", p.tolerance),
        ("rcond", p.rcond),
    ];
    for (name, v) in positive {
        if !(v.is_finite() && v > 0.0) {
            return Err(invalid(
                name,
                format!("must be positive and finite, got {v}"),
            ));
        }
    }
    if !(p.newton_below.is_finite() && p.newton_below >= 0.0) {
        return Err(invalid("newton_below", "must be non-negative and finite"));
    }
    if p.gamma * p.dtheta > 1.0 {
        return Err(invalid(
            "dtheta",
            "gamma * dtheta must not exceed 1 (a full Newton step)",
        ));
    }
    if p.rcond >= 1.0 {
        return Err(invalid("rcond", "must be below 1"));
    }
    if p.basis_terms == 0 || p.basis_terms > 64 {
        return Err(invalid("basis_terms", "must be in 1..=64"));
    }
    if p.rk4_steps == 0 || p.rk4_steps > MAX_RK4_STEPS {
        return Err(invalid("rk4_steps", "must be in 1..=1000000"));
    }
    if p.max_iterations == 0 {
        return Err(invalid("max_iterations", "must be at least 1"));
    }
    if p.stall_iterations == 0 {
        return Err(invalid("stall_iterations", "must be at least 1"));
    }
    for (i, v) in p.via_deg.iter().enumerate() {
        if v.len() != N || v.iter().any(|x| !x.is_finite()) {
            return Err(invalid(
                "via_deg",
                format!("via point {i} needs {N} finite entries"),
            ));
        }
    }
    check_vec("u_start", &p.u_start, M)?;
    check_vec("du_start", &p.du_start, M)?;
    check_vec("u_end", &p.u_end, M)?;
    check_vec("du_end", &p.du_end, M)?;
    let total = p.segment_time * (p.via_deg.len() + 1) as f64;
    for cp in &p.control_points {
        if !(cp.time.is_finite() && (0.0..=total).contains(&cp.time)) {
            return Err(invalid(
                "control_points",
                format!("time {} outside [0, {total}]", cp.time),
            ));
        }
        check_vec("control_points.value", &cp.value, M)?;
        check_vec("control_points.derivative", &cp.derivative, M)?;
    }
    Ok(())
}

/// Plans q0 → targets[0] at T → targets[1] at 2T → … for any fixed-size system.
pub fn solve<const N: usize, const M: usize, S: EndogenousSystem<N, M>>(
    sys: &S,
    start: &SVector<f64, N>,
    targets: &[SVector<f64, N>],
    params: &EndogenousParams,
) -> Result<Solution, PlanError> {
    validate::<N, M>(params)?;
    if targets.is_empty() {
        return Err(invalid("goal", "at least one target is needed"));
    }
    let t_seg = params.segment_time;
    let terms = vec![params.basis_terms; M];
    let set = Settings {
        step: params.gamma * params.dtheta,
        newton_below: params.newton_below,
        rk4_steps: params.rk4_steps,
        max_iterations: params.max_iterations,
        tolerance: params.tolerance,
        rcond: params.rcond,
        stall_iterations: params.stall_iterations,
    };
    let n_seg = targets.len();
    let mut q = *start;
    let mut segments: Vec<ControlExpansion> = Vec::new();
    let mut reports = Vec::new();
    for (k, target) in targets.iter().enumerate() {
        let label = format!("segment {}", k + 1);
        let t0 = k as f64 * t_seg;
        let mut cons = Vec::new();
        let push =
            |cons: &mut Vec<ControlConstraint>, time: f64, order: Order, v: &Option<Vec<f64>>| {
                if let Some(v) = v {
                    cons.push(ControlConstraint {
                        time,
                        order,
                        target: v.clone(),
                    });
                }
            };
        let inherited = |order: Order| -> bool {
            k > 0
                && match (params.continuity, order) {
                    (Continuity::None, _) => false,
                    (Continuity::C0, o) => o == Order::Value,
                    (Continuity::C1, _) => true,
                }
        };
        if k == 0 {
            push(&mut cons, 0.0, Order::Value, &params.u_start);
            push(&mut cons, 0.0, Order::Derivative, &params.du_start);
        } else if let Some(prev) = segments.last() {
            for order in [Order::Value, Order::Derivative] {
                if inherited(order) {
                    cons.push(ControlConstraint {
                        time: 0.0,
                        order,
                        target: prev.eval(t0, order),
                    });
                }
            }
        }
        if k + 1 == n_seg {
            push(&mut cons, t_seg, Order::Value, &params.u_end);
            push(&mut cons, t_seg, Order::Derivative, &params.du_end);
        }
        for cp in &params.control_points {
            let local = cp.time - t0;
            if local < -1e-9 || local > t_seg + 1e-9 {
                continue;
            }
            let local = local.clamp(0.0, t_seg);
            for (order, v) in [
                (Order::Value, &cp.value),
                (Order::Derivative, &cp.derivative),
            ] {
                if local == 0.0 && inherited(order) {
                    continue; // already imposed through continuity with the previous segment
                }
                push(&mut cons, local, order, v);
            }
        }
        let s: usize = terms.iter().sum();
        if N + cons.len() * M > s {
            return Err(invalid(
                "basis_terms",
                format!(
                    "{label}: {} task + {} constraint rows exceed the {s} parameters; raise basis_terms",
                    N,
                    cons.len() * M
                ),
            ));
        }
        let out = solve_segment::<N, M, S>(sys, &q, target, t_seg, &terms, cons, &set, &label)?;
        q = out.endpoint;
        segments.push(ControlExpansion {
            start: t0,
            duration: t_seg,
            terms: terms.clone(),
            lambda: out.lambda,
        });
        reports.push(out.report);
    }
    // No wall time here: plan details must be identical across runs (the
    // harness times planning itself, `wall_time_s.plan` in summary.json).
    Ok(Solution { segments, reports })
}

/// Peak |u_i| of a solution, sampled at the RK4 nodes of `steps` per segment.
fn peak_rate<const M: usize>(sol: &Solution, steps: usize) -> Vec<f64> {
    let mut peak = vec![0.0f64; M];
    for seg in &sol.segments {
        for n in 0..=2 * steps {
            let t = seg.start + seg.duration * n as f64 / (2 * steps) as f64;
            for (p, u) in peak.iter_mut().zip(seg.eval(t, Order::Value)) {
                *p = p.max(u.abs());
            }
        }
    }
    peak
}

/// Wraps a solution into an open-loop [`Plan`] (labels "segment 1", …).
pub fn into_plan<const M: usize>(
    sol: Solution,
    params: &EndogenousParams,
    extra: serde_json::Value,
) -> Plan {
    let n = sol.segments.len();
    let t_seg = params.segment_time;
    let duration = sol.duration();
    let labels: Vec<String> = (1..=n).map(|k| format!("segment {k}")).collect();
    let segments = (0..n)
        .map(|k| Segment {
            label: k,
            start: k as f64 * t_seg,
            end: (k + 1) as f64 * t_seg,
        })
        .collect();
    let joins: Vec<serde_json::Value> = (1..n)
        .map(|k| {
            let t = k as f64 * t_seg;
            let jump = |o: Order| {
                let (a, b) = (sol.segments[k - 1].eval(t, o), sol.segments[k].eval(t, o));
                a.iter().zip(&b).map(|(x, y)| (y - x).abs()).fold(0.0, f64::max)
            };
            serde_json::json!({ "time": t, "u_jump": jump(Order::Value), "du_jump": jump(Order::Derivative) })
        })
        .collect();
    let details = serde_json::json!({
        "planner": "endogenous",
        "segment_time": t_seg,
        "basis_terms": params.basis_terms,
        "parameters_per_segment": params.basis_terms * M,
        "gamma": params.gamma,
        "dtheta": params.dtheta,
        "rk4_steps": params.rk4_steps,
        "tolerance": params.tolerance,
        "continuity": params.continuity,
        "iterations": sol.reports.iter().map(|r| r.iterations).sum::<usize>(),
        "final_errors": sol.reports.iter().map(|r| r.final_error).collect::<Vec<_>>(),
        "segments": sol.reports.iter().zip(&sol.segments).zip(&labels).map(|((r, s), l)| serde_json::json!({
            "label": l,
            "iterations": r.iterations,
            "initial_error": r.initial_error,
            "final_error": r.final_error,
            "endpoint": r.endpoint,
            "constraints": r.constraints,
            "rk4_steps": r.rk4_steps,
            "start": s.start,
            "duration": s.duration,
            "lambda": s.lambda,
        })).collect::<Vec<_>>(),
        "joins": joins,
        "peak_rate": peak_rate::<M>(&sol, params.rk4_steps),
        "extra": extra,
    });
    let sol = Arc::new(sol);
    let law = ControlLaw::OpenLoop(Arc::new(move |t: f64| {
        if !(-1e-9..=duration + 1e-9).contains(&t) {
            return (Input::zeros(M), if t < 0.0 { 0 } else { n - 1 });
        }
        let t = t.clamp(0.0, duration);
        // At a join u may jump (no continuity imposed); the ideal run splits
        // its steps there and reads each side strictly inside its segment
        // (`Plan::jumps`), so the value at the instant itself is never used.
        let (u, idx) = sol.eval(t, Order::Value);
        (Input::from_vec(u), idx)
    }));
    Plan {
        labels,
        segments,
        duration,
        law,
        details,
    }
}

/// Entry point for the space manipulator: start → via points (`params.via_deg`)
/// → goal, one segment of `segment_time` each. States are (φ, θ1, θ2) in rad.
pub fn plan(
    model: &SpaceManipulator,
    start: &State,
    goal: &State,
    params: &EndogenousParams,
    limits: &Limits,
) -> Result<Plan, PlanError> {
    model.validate().map_err(|r| invalid("model", r))?;
    let to3 = |name: &str, v: &State| -> Result<Vector3<f64>, PlanError> {
        if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
            return Err(invalid(
                name,
                "needs 3 finite coordinates (phi, theta1, theta2)",
            ));
        }
        Ok(Vector3::new(v[0], v[1], v[2]))
    };
    let q0 = to3("start", start)?;
    let mut targets: Vec<Vector3<f64>> = Vec::new();
    for v in &params.via_deg {
        if v.len() != 3 || v.iter().any(|x| !x.is_finite()) {
            return Err(invalid("via_deg", "each via point needs 3 finite angles"));
        }
        targets.push(Vector3::new(v[0], v[1], v[2]).map(f64::to_radians));
    }
    targets.push(to3("goal", goal)?);
    if !limits.max_rate.is_empty() && limits.max_rate.len() != 2 {
        return Err(invalid("limits.max_rate", "needs one entry per input (2)"));
    }
    let sol = solve::<3, 2, _>(model, &q0, &targets, params)?;
    let peak = peak_rate::<2>(&sol, params.rk4_steps);
    if params.enforce_rate_limits {
        for (i, (p, lim)) in peak.iter().zip(&limits.max_rate).enumerate() {
            if p > lim {
                return Err(PlanError::Unreachable(format!(
                    "planned |u{}| peaks at {p:.4} rad/s above the rate limit {lim:.4}; lengthen segment_time",
                    i + 1
                )));
            }
        }
    }
    Ok(into_plan::<2>(
        sol,
        params,
        serde_json::json!({ "model": model.name() }),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::integrate::simulate;
    use crate::model::space_manipulator::SpaceManipulatorParams;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::PI;

    const T: f64 = 20.0;

    fn q0() -> Vector3<f64> {
        Vector3::new(PI / 8.0, -PI / 6.0, PI / 6.0)
    }
    fn y1() -> Vector3<f64> {
        Vector3::new(0.0, 0.0, PI / 8.0)
    }
    fn yf() -> Vector3<f64> {
        Vector3::new(PI / 8.0, -PI / 8.0, PI / 6.0)
    }
    fn dv(v: &Vector3<f64>) -> State {
        State::from_column_slice(v.as_slice())
    }
    fn no_limits() -> Limits {
        Limits {
            max_rate: vec![],
            ramp: 0.0,
            step: 1e-3,
        }
    }

    /// The three scenarios of §5 (S1 unconstrained, S2 rest-to-rest C0, S3 C1 with u'(0) = 0.01).
    fn scenario(k: usize) -> EndogenousParams {
        let mut p = EndogenousParams {
            via_deg: vec![y1().map(f64::to_degrees).as_slice().to_vec()],
            ..Default::default()
        };
        if k >= 2 {
            p.u_start = Some(vec![0.0, 0.0]);
            p.u_end = Some(vec![0.0, 0.0]);
            p.continuity = Continuity::C0;
        }
        if k >= 3 {
            p.du_start = Some(vec![0.01, 0.01]);
            p.continuity = Continuity::C1;
        }
        p
    }

    #[test]
    fn legendre_values_derivatives_and_orthogonality() {
        let (mut v, mut d) = (vec![0.0; 9], vec![0.0; 9]);
        for (s, sign) in [(1.0, 1.0f64), (-1.0, -1.0)] {
            legendre(s, &mut v, &mut d);
            for k in 0..9 {
                let kf = k as f64;
                assert!((v[k] - sign.powi(k as i32)).abs() < 1e-13);
                // P_k'(±1) = (±1)^(k+1) k(k+1)/2
                assert!((d[k] - sign.powi(k as i32 + 1) * kf * (kf + 1.0) / 2.0).abs() < 1e-11);
            }
        }
        legendre(0.3, &mut v, &mut d);
        assert!((v[2] - (3.0 * 0.09 - 1.0) / 2.0).abs() < 1e-15);
        assert!((v[3] - (5.0 * 0.027 - 3.0 * 0.3) / 2.0).abs() < 1e-15);
        assert!((d[3] - (15.0 * 0.09 - 3.0) / 2.0).abs() < 1e-14);
        // ∫ P_j P_k = 2/(2k+1) δ_jk (Gauss–Legendre-free check: composite Simpson).
        let n = 2000;
        let mut gram = [[0.0; 6]; 6];
        for i in 0..=n {
            let s = -1.0 + 2.0 * i as f64 / n as f64;
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            } * (2.0 / n as f64)
                / 3.0;
            legendre(s, &mut v[..6], &mut d[..6]);
            for (row, vj) in gram.iter_mut().zip(&v) {
                for (g, vk) in row.iter_mut().zip(&v) {
                    *g += w * vj * vk;
                }
            }
        }
        for (j, row) in gram.iter().enumerate() {
            for (k, g) in row.iter().enumerate() {
                let want = if j == k {
                    2.0 / (2.0 * k as f64 + 1.0)
                } else {
                    0.0
                };
                assert!((g - want).abs() < 1e-8, "{j} {k} {g}");
            }
        }
    }

    /// The variational Jacobian (Eqs. 17-18) equals central differences of the end-point map.
    #[test]
    fn jacobian_matches_finite_differences() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        for p in [0.0, 0.3] {
            let model = SpaceManipulator::new(SpaceManipulatorParams {
                p,
                ..Default::default()
            });
            let terms = [6, 5];
            let s = 11;
            let lambda: Vec<f64> = (0..s).map(|_| rng.random_range(-0.2..0.2)).collect();
            let mut integ = Integrator::<3, 2>::new(T, 100, &terms);
            let mut jac = DMatrix::zeros(3, s);
            let q_end = integ.run(&model, &q0(), &lambda, Some(&mut jac));
            let q_plain = integ.run(&model, &q0(), &lambda, None);
            assert_eq!(q_end, q_plain);
            let h = 1e-6;
            for j in 0..s {
                let (mut lp, mut lm) = (lambda.clone(), lambda.clone());
                lp[j] += h;
                lm[j] -= h;
                let fd = (integ.run(&model, &q0(), &lp, None)
                    - integ.run(&model, &q0(), &lm, None))
                    / (2.0 * h);
                for r in 0..3 {
                    assert!(
                        (jac[(r, j)] - fd[r]).abs() < 1e-7 * (1.0 + fd[r].abs()),
                        "p {p} J[{r},{j}] = {} vs fd {}",
                        jac[(r, j)],
                        fd[r]
                    );
                }
            }
        }
    }

    /// At u = 0 (p = 0) J has rank 2: the plain right inverse J^T (J J^T)^-1 is singular,
    /// the SVD pseudo-inverse still gives a finite step that keeps Ψ μ = 0.
    #[test]
    fn rank_deficient_at_zero_control_and_safe_inverse() {
        let model = SpaceManipulator::default();
        let terms = [8, 8];
        let mut integ = Integrator::<3, 2>::new(T, 50, &terms);
        let mut jac = DMatrix::zeros(3, 16);
        integ.run(&model, &q0(), &[0.0; 16], Some(&mut jac));
        let sv = jac.clone().singular_values();
        assert!(sv.min() < 1e-12 * sv.max(), "singular values {sv}");
        let cons = vec![
            ControlConstraint {
                time: 0.0,
                order: Order::Value,
                target: vec![0.0, 0.0],
            },
            ControlConstraint {
                time: T,
                order: Order::Derivative,
                target: vec![0.0, 0.0],
            },
        ];
        let (psi, _) = constraint_rows(&terms, T, &cons);
        let e = DVector::from_column_slice((q0() - y1()).as_slice());
        let mu = extended_step(&jac, &psi, &e, 0.02, 1e-10);
        assert!(mu.iter().all(|x| x.is_finite()));
        assert!((&psi * &mu).amax() < 1e-12);
        let z = null_space(&psi, 16);
        let mu_z = &z * pinv_solve(&(&jac * &z), &(&e * -0.02), 1e-10);
        assert!(
            (&mu - &mu_z).amax() < 1e-10 * (1.0 + mu.amax()),
            "{mu} vs {mu_z}"
        );
    }

    /// Where [J; Ψ] has full row rank the SVD step is the right inverse
    /// J^T (J J^T)^-1 of Eq. 26, and the null-space form used by the planner equals it.
    #[test]
    fn pseudo_inverse_is_the_right_inverse_at_full_rank() {
        let model = SpaceManipulator::default();
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let terms = [7, 7];
        let lambda: Vec<f64> = (0..14).map(|_| rng.random_range(-0.3..0.3)).collect();
        let mut integ = Integrator::<3, 2>::new(T, 100, &terms);
        let mut jac = DMatrix::zeros(3, 14);
        integ.run(&model, &q0(), &lambda, Some(&mut jac));
        let cons = vec![
            ControlConstraint {
                time: 0.0,
                order: Order::Value,
                target: vec![0.0, 0.0],
            },
            ControlConstraint {
                time: 0.0,
                order: Order::Derivative,
                target: vec![0.01, 0.01],
            },
            ControlConstraint {
                time: 7.0,
                order: Order::Value,
                target: vec![0.1, -0.1],
            },
        ];
        let (psi, _) = constraint_rows(&terms, T, &cons);
        let e = DVector::from_vec(vec![0.1, -0.2, 0.05]);
        let mu = extended_step(&jac, &psi, &e, 0.02, 1e-10);
        let mut jext = DMatrix::zeros(9, 14);
        jext.rows_mut(0, 3).copy_from(&jac);
        jext.rows_mut(3, 6).copy_from(&psi);
        let mut rhs = DVector::zeros(9);
        rhs.rows_mut(0, 3).copy_from(&(&e * -0.02));
        let gram = &jext * jext.transpose();
        let plain = jext.transpose() * gram.lu().solve(&rhs).unwrap();
        assert!((&mu - &plain).amax() < 1e-9 * (1.0 + plain.amax()));
        let z = null_space(&psi, 14);
        let mu_z = &z * pinv_solve(&(&jac * &z), &(&e * -0.02), 1e-10);
        assert!((&mu - &mu_z).amax() < 1e-9 * (1.0 + mu.amax()));
        assert!((&jac * &mu + &e * 0.02).amax() < 1e-12);
    }

    struct Checked {
        sol: Solution,
        plan: Plan,
    }

    /// Plans scenario k, checks the ideal errors with the shared `simulate`,
    /// every imposed constraint, and prints the timing.
    fn run_scenario(k: usize, dt: f64) -> Checked {
        let model = SpaceManipulator::default();
        let params = scenario(k);
        let sol = solve::<3, 2, _>(&model, &q0(), &[y1(), yf()], &params).unwrap();
        let plan = into_plan::<2>(sol.clone(), &params, serde_json::Value::Null);
        let traj = simulate(&model, &plan, &dv(&q0()), dt);
        let i_t = (T / dt).round() as usize;
        assert!((traj.t[i_t] - T).abs() < 1e-9);
        let e1 = (&traj.q[i_t] - dv(&y1())).norm();
        let e2 = (traj.last() - dv(&yf())).norm();
        println!(
            "S{k}: iterations {:?}, internal errors {:?}, simulate (dt {dt}) errors {e1:.2e} {e2:.2e}, joins {}, peak |u| {}",
            sol.reports.iter().map(|r| r.iterations).collect::<Vec<_>>(),
            sol.reports.iter().map(|r| r.final_error).collect::<Vec<_>>(),
            plan.details["joins"],
            plan.details["peak_rate"]
        );
        assert!(e1 < 1e-4, "S{k}: |q(T) - y1| = {e1}");
        assert!(e2 < 1e-4, "S{k}: |q(2T) - yf| = {e2}");
        // Every imposed constraint, on the returned expansions.
        for (seg, rep) in sol.segments.iter().zip(&sol.reports) {
            for c in &rep.constraints {
                let got = seg.eval(seg.start + c.time, c.order);
                for (g, w) in got.iter().zip(&c.target) {
                    assert!((g - w).abs() < 1e-9, "S{k}: constraint {c:?} gives {got:?}");
                }
            }
        }
        // The plan's open-loop law reproduces the expansions.
        let mut ctl = plan.controller();
        for t in [0.0, 3.3, 19.5, 20.5, 39.9, 40.0] {
            let cmd = ctl.command(t, &dv(&q0()));
            let (u, idx) = sol.eval(t, Order::Value);
            assert_eq!(cmd.label, idx);
            assert!((cmd.u[0] - u[0]).abs() < 1e-15 && (cmd.u[1] - u[1]).abs() < 1e-15);
        }
        assert_eq!(
            plan.labels,
            vec!["segment 1".to_string(), "segment 2".to_string()]
        );
        assert_eq!(plan.duration, 2.0 * T);
        // Planning time (aim < 0.2 s) is a criterion benchmark: `cargo bench --bench space_robot`.
        Checked { sol, plan }
    }

    fn jumps(sol: &Solution) -> (f64, f64) {
        let j = |o: Order| {
            let (a, b) = (sol.segments[0].eval(T, o), sol.segments[1].eval(T, o));
            (a[0] - b[0]).abs().max((a[1] - b[1]).abs())
        };
        (j(Order::Value), j(Order::Derivative))
    }

    /// S1: no constraints. The controls jump at T (the ideal run splits its
    /// steps there, `Plan::jumps`).
    #[test]
    fn scenario1_unconstrained() {
        let c = run_scenario(1, 1e-4);
        let (du, ddu) = jumps(&c.sol);
        assert!(du > 0.1, "u jump {du}");
        assert!(ddu > 1e-3, "u' jump {ddu}");
        // Nothing forces rest: u(0) and u(2T) are not zero.
        assert!(c
            .sol
            .eval(0.0, Order::Value)
            .0
            .iter()
            .any(|u| u.abs() > 1e-3));
        assert!(c
            .sol
            .eval(40.0, Order::Value)
            .0
            .iter()
            .any(|u| u.abs() > 1e-3));
        // The plan reports the jump, and each side of it belongs to its segment.
        assert_eq!(c.plan.jumps(), vec![T]);
        let eps = crate::plan::jump_offset(T);
        let mut ctl = c.plan.controller();
        let (before, after) = (
            ctl.command(T - eps, &dv(&q0())).u,
            ctl.command(T + eps, &dv(&q0())).u,
        );
        let (a, b) = (
            c.sol.segments[0].eval(T, Order::Value),
            c.sol.segments[1].eval(T, Order::Value),
        );
        assert!((before[0] - a[0]).abs() < 1e-8 && (after[0] - b[0]).abs() < 1e-8);
    }

    /// S2: u(0) = u(2T) = 0, C0 at T; u' jumps at T.
    #[test]
    fn scenario2_rest_to_rest_c0() {
        let c = run_scenario(2, 1e-3);
        let (du, ddu) = jumps(&c.sol);
        assert!(du < 1e-9, "u jump {du}");
        assert!(ddu > 0.1, "u' jump {ddu}");
        for t in [0.0, 40.0] {
            assert!(c.sol.eval(t, Order::Value).0.iter().all(|u| u.abs() < 1e-9));
        }
    }

    /// S3: as S2 plus u'(0) = 0.01 and C1 at T.
    #[test]
    fn scenario3_rest_to_rest_c1() {
        let c = run_scenario(3, 1e-3);
        let (du, ddu) = jumps(&c.sol);
        assert!(du < 1e-9 && ddu < 1e-9, "jumps {du} {ddu}");
        for u in c.sol.eval(0.0, Order::Derivative).0 {
            assert!((u - 0.01).abs() < 1e-9);
        }
        // Independent check of u'(0) on the plan's law (forward difference).
        let mut ctl = c.plan.controller();
        let h = 1e-5;
        let (u0, u1) = (ctl.command(0.0, &dv(&q0())).u, ctl.command(h, &dv(&q0())).u);
        for i in 0..2 {
            assert!(((u1[i] - u0[i]) / h - 0.01).abs() < 1e-4);
        }
    }

    /// Along the Euler phase the task error decays by (1 − γΔϑ) per iteration
    /// (Eq. 8), once the rank-deficient start at u = 0 is left behind.
    #[test]
    fn error_decays_exponentially() {
        let params = EndogenousParams {
            newton_below: 0.0,
            tolerance: 1e-3,
            ..scenario(2)
        };
        let sol = solve::<3, 2, _>(&SpaceManipulator::default(), &q0(), &[y1()], &params).unwrap();
        let h = params.gamma * params.dtheta;
        let hist = &sol.reports[0].error_history;
        for k in 20..hist.len() - 1 {
            let ratio = hist[k + 1] / hist[k];
            assert!(
                (ratio - (1.0 - h)).abs() < 2e-3,
                "iteration {k}: ratio {ratio}"
            );
        }
        // Number of iterations follows: (1 − h)^k e0 ≤ tol.
        let predicted = ((1e-3 / hist[0]).ln() / (1.0 - h).ln()).ceil() as usize;
        assert!(
            sol.reports[0].iterations.abs_diff(predicted) <= 3,
            "{} vs {predicted}",
            sol.reports[0].iterations
        );
    }

    #[test]
    fn nonzero_momentum_single_segment() {
        let model = SpaceManipulator::new(SpaceManipulatorParams {
            p: 0.05,
            ..Default::default()
        });
        let params = EndogenousParams {
            u_start: Some(vec![0.0, 0.0]),
            u_end: Some(vec![0.0, 0.0]),
            ..Default::default()
        };
        let plan = plan(&model, &dv(&q0()), &dv(&yf()), &params, &no_limits()).unwrap();
        assert_eq!(plan.labels, vec!["segment 1".to_string()]);
        let traj = simulate(&model, &plan, &dv(&q0()), 1e-3);
        assert!((traj.last() - dv(&yf())).norm() < 1e-4);
        assert!(plan.details["iterations"].as_u64().unwrap() > 0);
        assert!(
            plan.details.get("wall_time_s").is_none(),
            "timings stay out of plan details"
        );
    }

    #[test]
    fn via_point_control_constraint_inside_a_segment() {
        let model = SpaceManipulator::default();
        let params = EndogenousParams {
            control_points: vec![ControlPoint {
                time: 7.5,
                value: Some(vec![0.05, -0.02]),
                derivative: Some(vec![0.0, 0.0]),
            }],
            ..Default::default()
        };
        let sol = solve::<3, 2, _>(&model, &q0(), &[y1()], &params).unwrap();
        let u = sol.eval(7.5, Order::Value).0;
        let du = sol.eval(7.5, Order::Derivative).0;
        assert!((u[0] - 0.05).abs() < 1e-9 && (u[1] + 0.02).abs() < 1e-9);
        assert!(du[0].abs() < 1e-9 && du[1].abs() < 1e-9);
        assert!(sol.reports[0].final_error <= 1e-8);
    }

    #[test]
    fn invalid_parameters_are_rejected() {
        let model = SpaceManipulator::default();
        let (s, g) = (dv(&q0()), dv(&yf()));
        let bad = |p: EndogenousParams, name: &str| match plan(&model, &s, &g, &p, &no_limits()) {
            Err(PlanError::InvalidParameter { name: n, .. }) => assert_eq!(n, name),
            Err(e) => panic!("expected invalid {name}, got {e}"),
            Ok(_) => panic!("expected invalid {name}, got a plan"),
        };
        bad(
            EndogenousParams {
                gamma: -1.0,
                ..Default::default()
            },
            "gamma",
        );
        bad(
            EndogenousParams {
                gamma: f64::NAN,
                ..Default::default()
            },
            "gamma",
        );
        bad(
            EndogenousParams {
                dtheta: 100.0,
                ..Default::default()
            },
            "dtheta",
        );
        bad(
            EndogenousParams {
                basis_terms: 0,
                ..Default::default()
            },
            "basis_terms",
        );
        bad(
            EndogenousParams {
                rk4_steps: 0,
                ..Default::default()
            },
            "rk4_steps",
        );
        bad(
            EndogenousParams {
                u_start: Some(vec![0.0]),
                ..Default::default()
            },
            "u_start",
        );
        bad(
            EndogenousParams {
                via_deg: vec![vec![1.0, 2.0]],
                ..Default::default()
            },
            "via_deg",
        );
        // S3 needs 3 + 4 rows in segment 1 and 3 + 6 in segment 2: 4 terms per input are too few.
        bad(
            EndogenousParams {
                basis_terms: 4,
                ..scenario(3)
            },
            "basis_terms",
        );
        let bad_model = SpaceManipulator::new(SpaceManipulatorParams {
            m0: -1.0,
            ..Default::default()
        });
        assert!(matches!(
            plan(
                &bad_model,
                &s,
                &g,
                &EndogenousParams::default(),
                &no_limits()
            ),
            Err(PlanError::InvalidParameter { .. })
        ));
    }

    #[test]
    fn iteration_cap_reports_no_convergence() {
        let p = EndogenousParams {
            max_iterations: 5,
            ..Default::default()
        };
        match plan(
            &SpaceManipulator::default(),
            &dv(&q0()),
            &dv(&yf()),
            &p,
            &no_limits(),
        ) {
            Err(PlanError::NoConvergence(why)) => assert!(why.contains("iteration cap"), "{why}"),
            other => panic!("expected NoConvergence, got {:?}", other.map(|p| p.details)),
        }
    }

    /// A grid refinement at the last allowed iteration is refused with the
    /// reason (it once fell out of the iteration loop into `unreachable!()`);
    /// one iteration more lets the refined grid finish, as without a cap.
    #[test]
    fn grid_refinement_at_the_iteration_cap_is_refused() {
        let model = SpaceManipulator::default();
        // 4 RK4 steps over 20 s: the coarse grid's picture of the endpoint
        // is wrong, so its first convergence needs a refinement.
        let params = EndogenousParams {
            rk4_steps: 4,
            ..Default::default()
        };
        let free = solve::<3, 2, _>(&model, &q0(), &[yf()], &params).unwrap();
        let rep = &free.reports[0];
        assert!(rep.rk4_steps > 4, "no refinement: {}", rep.rk4_steps);
        // The first iteration whose error met the tolerance on the 4-step grid.
        let first = rep
            .error_history
            .iter()
            .position(|&e| e <= params.tolerance)
            .unwrap();
        assert!(first < rep.iterations);
        let capped = EndogenousParams {
            max_iterations: first,
            ..params.clone()
        };
        match solve::<3, 2, _>(&model, &q0(), &[yf()], &capped) {
            Err(PlanError::NoConvergence(why)) => {
                assert!(
                    why.contains("iteration cap") && why.contains("refining"),
                    "{why}"
                )
            }
            other => panic!("expected NoConvergence, got {:?}", other.map(|s| s.reports)),
        }
        let enough = EndogenousParams {
            max_iterations: rep.iterations,
            ..params
        };
        let sol = solve::<3, 2, _>(&model, &q0(), &[yf()], &enough).unwrap();
        assert_eq!(sol.segments[0].lambda, free.segments[0].lambda);
    }

    #[test]
    fn rate_limits_are_enforced() {
        let limits = Limits {
            max_rate: vec![0.01, 0.01],
            ramp: 0.5,
            step: 1e-3,
        };
        let r = plan(
            &SpaceManipulator::default(),
            &dv(&q0()),
            &dv(&yf()),
            &EndogenousParams::default(),
            &limits,
        );
        assert!(matches!(r, Err(PlanError::Unreachable(_))));
        let relaxed = EndogenousParams {
            enforce_rate_limits: false,
            ..Default::default()
        };
        let ok = plan(
            &SpaceManipulator::default(),
            &dv(&q0()),
            &dv(&yf()),
            &relaxed,
            &limits,
        )
        .unwrap();
        assert!(ok.details["peak_rate"][0].as_f64().unwrap() > 0.01);
    }

    #[test]
    fn params_deserialize_with_defaults() {
        let p: EndogenousParams = serde_json::from_str(
            r#"{"via_deg": [[0, 0, 22.5]], "continuity": "c1", "du_start": [0.01, 0.01]}"#,
        )
        .unwrap();
        assert_eq!(p.continuity, Continuity::C1);
        assert_eq!(p.gamma, 0.02);
        assert!(serde_json::from_str::<EndogenousParams>(r#"{"gama": 1}"#).is_err());
    }
}
