//! The search: minimise an objective over the unit box [0, 1]^n (each
//! parameter's range mapped onto [0, 1]).
//!
//! 1. **Scan**: the start point and `4n + 4` points of a Halton sequence
//!    spread over the box, evaluated in parallel (they are independent).
//! 2. **Nelder–Mead** (argmin's) from the best of them, its first simplex
//!    (steps of 0.1 along each axis, into the box) evaluated in parallel and
//!    then one point at a time as the method asks. Points outside the box
//!    cost the residual at the nearest point of the box plus a penalty that
//!    grows with the distance, so the search stays inside.
//!
//! Every value is cached by its coordinates, and the method's steps depend
//! on values only, so the result is the same on any number of threads.

use argmin::core::{CostFunction, Error as ArgminError, Executor, State};
use argmin::solver::neldermead::NelderMead;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// Where the search is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// The parallel scan.
    Scan,
    /// Nelder–Mead.
    Search,
    /// The evaluations around the optimum (sensitivity).
    Sensitivity,
}

/// What the search reports after each evaluation.
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// Where it is.
    pub phase: Phase,
    /// Evaluations so far.
    pub evaluations: usize,
    /// The best value so far.
    pub best: f64,
    /// The evaluation budget.
    pub budget: usize,
}

/// The result of a search.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// The best point (in the box).
    pub best: Vec<f64>,
    /// Its value.
    pub value: f64,
    /// Nelder–Mead iterations.
    pub iterations: u64,
    /// Whether the simplex's values agreed to the tolerance (else the
    /// budget ended it).
    pub converged: bool,
}

/// The objective with its cache, counter and progress.
pub struct Objective<'a> {
    f: &'a (dyn Fn(&[f64]) -> f64 + Sync),
    cache: Mutex<HashMap<Vec<u64>, f64>>,
    evaluations: AtomicUsize,
    best: Mutex<f64>,
    phase: Mutex<Phase>,
    budget: usize,
    progress: &'a (dyn Fn(&Progress) + Sync),
}

fn clamp(u: &[f64]) -> (Vec<f64>, f64) {
    let c: Vec<f64> = u.iter().map(|x| x.clamp(0.0, 1.0)).collect();
    let d = u
        .iter()
        .zip(&c)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    (c, d)
}

fn key(u: &[f64]) -> Vec<u64> {
    u.iter().map(|x| x.to_bits()).collect()
}

impl<'a> Objective<'a> {
    /// `f` on the box, reporting to `progress`.
    pub fn new(
        f: &'a (dyn Fn(&[f64]) -> f64 + Sync),
        budget: usize,
        progress: &'a (dyn Fn(&Progress) + Sync),
    ) -> Objective<'a> {
        Objective {
            f,
            cache: Mutex::new(HashMap::new()),
            evaluations: AtomicUsize::new(0),
            best: Mutex::new(f64::INFINITY),
            phase: Mutex::new(Phase::Scan),
            budget,
            progress,
        }
    }

    /// Evaluations so far.
    pub fn evaluations(&self) -> usize {
        self.evaluations.load(Ordering::SeqCst)
    }

    /// Set the phase progress reports.
    pub fn phase(&self, p: Phase) {
        *self.phase.lock().unwrap_or_else(|e| e.into_inner()) = p;
    }

    fn cached(&self, c: &[f64]) -> Option<f64> {
        self.cache
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(&key(c))
            .copied()
    }

    /// The value at a point of the box (evaluated once).
    fn at(&self, c: &[f64]) -> f64 {
        if let Some(v) = self.cached(c) {
            return v;
        }
        let v = (self.f)(c);
        let v = if v.is_nan() { f64::MAX } else { v };
        self.cache
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .insert(key(c), v);
        let n = self.evaluations.fetch_add(1, Ordering::SeqCst) + 1;
        let best = {
            let mut b = self.best.lock().unwrap_or_else(|e| e.into_inner());
            *b = b.min(v);
            *b
        };
        let phase = *self.phase.lock().unwrap_or_else(|e| e.into_inner());
        (self.progress)(&Progress {
            phase,
            evaluations: n,
            best,
            budget: self.budget,
        });
        v
    }

    /// The value anywhere: inside the box, `at`; outside, the value at the
    /// nearest point of the box plus a penalty growing with the distance.
    pub fn value(&self, u: &[f64]) -> f64 {
        let (c, d) = clamp(u);
        let v = self.at(&c);
        if d > 0.0 {
            v * (1.0 + 10.0 * d) + d
        } else {
            v
        }
    }

    /// The values at several points, the new ones evaluated in parallel.
    pub fn batch(&self, points: &[Vec<f64>]) -> Vec<f64> {
        let mut todo: Vec<Vec<f64>> = Vec::new();
        for p in points {
            let (c, _) = clamp(p);
            if self.cached(&c).is_none() && !todo.contains(&c) {
                todo.push(c);
            }
        }
        todo.par_iter().with_max_len(1).for_each(|c| {
            self.at(c);
        });
        points.iter().map(|p| self.value(p)).collect()
    }
}

struct Problem<'o, 'a>(&'o Objective<'a>);

impl CostFunction for Problem<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, u: &Vec<f64>) -> Result<f64, ArgminError> {
        Ok(self.0.value(u))
    }
}

/// Radical inverse of `i` in base `b`: the Halton sequence's coordinate.
fn radical_inverse(mut i: usize, b: usize) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while i > 0 {
        f /= b as f64;
        r += f * (i % b) as f64;
        i /= b;
    }
    r
}

/// The scan's points: `count` Halton points in the box (indices from 1).
pub(crate) fn halton(n: usize, count: usize) -> Vec<Vec<f64>> {
    const PRIMES: [usize; 12] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37];
    (1..=count)
        .map(|i| (0..n).map(|d| radical_inverse(i, PRIMES[d % 12])).collect())
        .collect()
}

/// Minimise `obj` over the box from `start`, within about `budget`
/// evaluations.
pub(crate) fn minimize(obj: &Objective<'_>, start: &[f64], budget: usize) -> Outcome {
    let n = start.len();
    obj.phase(Phase::Scan);
    let mut scan = vec![start.to_vec()];
    scan.extend(halton(n, 4 * n + 4));
    let values = obj.batch(&scan);
    // The first best in scan order on ties.
    let (bi, _) =
        values.iter().enumerate().fold(
            (0, f64::INFINITY),
            |(bi, bv), (i, &v)| if v < bv { (i, v) } else { (bi, bv) },
        );
    let x0 = scan[bi].clone();
    let mut simplex = vec![x0.clone()];
    for d in 0..n {
        let mut x = x0.clone();
        x[d] += if x[d] + 0.1 <= 1.0 { 0.1 } else { -0.1 };
        simplex.push(x);
    }
    obj.phase(Phase::Search);
    let first = obj.batch(&simplex);
    let scale = first.iter().cloned().fold(f64::INFINITY, f64::min).max(0.0);
    let tol = 1e-5 * scale + 1e-12;
    // An iteration evaluates one or two points (a shrink n).
    let left = (budget.saturating_sub(obj.evaluations()) / 2).max(n + 2);
    let nm = match NelderMead::new(simplex.clone()).with_sd_tolerance(tol) {
        Ok(nm) => nm,
        Err(_) => NelderMead::new(simplex),
    };
    let res = Executor::new(Problem(obj), nm)
        .configure(|s| s.max_iters(left as u64))
        .run();
    match res {
        Ok(r) => {
            let st = r.state();
            let best = st
                .get_best_param()
                .map(|p| clamp(p).0)
                .unwrap_or_else(|| x0.clone());
            let value = obj.value(&best);
            let converged = matches!(
                st.get_termination_reason(),
                Some(argmin::core::TerminationReason::SolverConverged)
            );
            Outcome {
                best,
                value,
                iterations: st.get_iter(),
                converged,
            }
        }
        // The cost never fails; keep the scan's best if the method does.
        Err(_) => Outcome {
            value: obj.value(&x0),
            best: x0,
            iterations: 0,
            converged: false,
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_minimum_of_a_bowl_in_the_box() {
        let f = |u: &[f64]| ((u[0] - 0.3).powi(2) + 4.0 * (u[1] - 0.8).powi(2)).sqrt();
        let quiet = |_: &Progress| {};
        let obj = Objective::new(&f, 400, &quiet);
        let o = minimize(&obj, &[0.5, 0.5], 400);
        assert!(
            (o.best[0] - 0.3).abs() < 1e-3 && (o.best[1] - 0.8).abs() < 1e-3,
            "{o:?}"
        );
        // A minimum outside the box ends on its edge.
        let g = |u: &[f64]| (u[0] - 1.4).abs();
        let obj = Objective::new(&g, 200, &quiet);
        let o = minimize(&obj, &[0.5], 200);
        assert!((o.best[0] - 1.0).abs() < 1e-6, "{o:?}");
    }

    #[test]
    fn halton_points_fill_the_box() {
        let h = halton(2, 4);
        assert_eq!(h[0], vec![0.5, 1.0 / 3.0]);
        assert_eq!(h[1], vec![0.25, 2.0 / 3.0]);
    }
}
