//! Kinematic models declared in a scenario: q' = f(q, u), one expression
//! per state, over the states, the inputs and named parameters. The
//! expression language is [`crate::robots::declared::expr`].

use crate::model::{Input, KinematicModel, State};
use nalgebra::DMatrix;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

pub use crate::robots::declared::expr::{reserved, Expr, ExprError, Kink, FUNCTIONS};
use num_dual::Dual64;

/// A `&'static` copy of `names`, made once per distinct list: the model
/// trait hands out static names, and sweeps build a declared system per
/// variant.
pub(crate) fn static_names(names: &[String]) -> &'static [&'static str] {
    static INTERNED: OnceLock<Mutex<HashMap<Vec<String>, &'static [&'static str]>>> =
        OnceLock::new();
    let map = INTERNED.get_or_init(Default::default);
    let mut map = map.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(s) = map.get(names) {
        return s;
    }
    let leaked: Vec<&'static str> = names
        .iter()
        .map(|n| &*Box::leak(n.clone().into_boxed_str()))
        .collect();
    let s: &'static [&'static str] = Box::leak(leaked.into_boxed_slice());
    map.insert(names.to_vec(), s);
    s
}

/// A `&'static` copy of an index list (see [`static_names`]).
pub(crate) fn static_indices(v: &[usize]) -> &'static [usize] {
    static INTERNED: OnceLock<Mutex<HashMap<Vec<usize>, &'static [usize]>>> = OnceLock::new();
    let map = INTERNED.get_or_init(Default::default);
    let mut map = map.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(s) = map.get(v) {
        return s;
    }
    let s: &'static [usize] = Box::leak(v.to_vec().into_boxed_slice());
    map.insert(v.to_vec(), s);
    s
}

/// A kinematic model declared in a scenario.
#[derive(Debug, Clone)]
pub struct Declared {
    states: &'static [&'static str],
    inputs: &'static [&'static str],
    angular: &'static [usize],
    position: Option<[usize; 2]>,
    /// Parameter values, in slot order after the states and inputs.
    params: Vec<f64>,
    /// q'_i = f_i(q, u, params).
    f: Vec<Expr>,
}

impl Declared {
    /// The model from its names, parameters and one expression per state
    /// (already parsed over [`Declared::slot_names`]).
    pub fn new(
        states: &[String],
        inputs: &[String],
        angles: &[usize],
        params: Vec<f64>,
        f: Vec<Expr>,
    ) -> Declared {
        let pos = |n: &str| states.iter().position(|s| s == n);
        Declared {
            states: static_names(states),
            inputs: static_names(inputs),
            angular: static_indices(angles),
            position: pos("x").zip(pos("y")).map(|(x, y)| [x, y]),
            params,
            f,
        }
    }

    /// The slot names expressions are parsed over: states, inputs, parameters.
    pub fn slot_names<'a>(
        states: &'a [String],
        inputs: &'a [String],
        params: &'a [String],
    ) -> Vec<&'a str> {
        states
            .iter()
            .chain(inputs)
            .chain(params)
            .map(String::as_str)
            .collect()
    }

    /// The slot values for state `q` and input `u`.
    pub fn values(&self, q: &[f64], u: &[f64], out: &mut Vec<f64>) {
        out.clear();
        out.extend_from_slice(q);
        out.extend_from_slice(u);
        out.extend_from_slice(&self.params);
    }

    /// q' = f(q, u) with A = ∂f/∂q and B = ∂f/∂u (row-major, n × n and
    /// n × m) by forward-mode automatic differentiation of each compiled
    /// equation ([`Expr::eval_dual`]): one pass per state or input the
    /// equation reads. q' is [`KinematicModel::velocity`]'s to the bit.
    /// Returns the first point met where an equation is not
    /// differentiable: its state's index and the kink.
    pub fn linearize(
        &self,
        q: &[f64],
        u: &[f64],
        qdot: &mut [f64],
        a: &mut [f64],
        b: &mut [f64],
    ) -> Option<(usize, Kink)> {
        let (n, m) = (q.len(), u.len());
        let mut small = [0.0; 32];
        let mut small_d = [Dual64::from_re(0.0); 32];
        let (mut heap, mut heap_d);
        let total = n + m + self.params.len();
        let (values, duals): (&mut [f64], &mut [Dual64]) = if total <= small.len() {
            (&mut small[..total], &mut small_d[..total])
        } else {
            heap = vec![0.0; total];
            heap_d = vec![Dual64::from_re(0.0); total];
            (&mut heap, &mut heap_d)
        };
        values[..n].copy_from_slice(q);
        values[n..n + m].copy_from_slice(u);
        values[n + m..].copy_from_slice(&self.params);
        for (d, v) in duals.iter_mut().zip(values.iter()) {
            *d = Dual64::from_re(*v);
        }
        a.fill(0.0);
        b.fill(0.0);
        let mut first = None;
        for (i, f) in self.f.iter().enumerate() {
            let moving = f.slots().iter().take_while(|&&j| j < n + m);
            if moving.clone().next().is_none() {
                qdot[i] = f.eval(values);
            }
            for &j in moving {
                duals[j].eps = 1.0;
                let mut kink = None;
                let d = f.eval_dual(duals, &mut kink);
                duals[j].eps = 0.0;
                // A dual pass's value is `eval`'s to the bit.
                qdot[i] = d.re;
                if j < n {
                    a[i * n + j] = d.eps;
                } else {
                    b[i * m + j - n] = d.eps;
                }
                if let (None, Some(k)) = (&first, kink) {
                    first = Some((i, k));
                }
            }
        }
        first
    }

    /// The equations as written, one per state.
    pub fn equations(&self) -> impl Iterator<Item = (&'static str, &str)> {
        self.states
            .iter()
            .copied()
            .zip(self.f.iter().map(Expr::text))
    }
}

impl KinematicModel for Declared {
    fn name(&self) -> &'static str {
        "declared"
    }
    fn state_names(&self) -> &'static [&'static str] {
        self.states
    }
    fn input_names(&self) -> &'static [&'static str] {
        self.inputs
    }
    fn angular_states(&self) -> &'static [usize] {
        self.angular
    }
    fn position_states(&self) -> Option<[usize; 2]> {
        self.position
    }
    fn equation_source(&self, i: usize) -> Option<String> {
        let (s, e) = (self.states.get(i)?, self.f.get(i)?);
        Some(format!(
            "key `model.kinematics.{s}` ({})",
            crate::echo::code(e.text())
        ))
    }
    /// Columns f(q, e_j) − f(q, 0): the input matrix of a control-affine
    /// model (a general model's linearisation at u = 0 is not this; no
    /// built-in planner uses it for declared models).
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        let m = self.inputs.len();
        let f0 = self.velocity(0.0, q, &Input::zeros(m));
        let mut g = DMatrix::zeros(q.len(), m);
        for j in 0..m {
            let mut e = Input::zeros(m);
            e[j] = 1.0;
            let fj = self.velocity(0.0, q, &e);
            g.set_column(j, &(fj - &f0));
        }
        g
    }
    fn drift(&self, q: &State) -> State {
        self.velocity(0.0, q, &Input::zeros(self.inputs.len()))
    }
    fn velocity(&self, _t: f64, q: &State, u: &Input) -> State {
        let mut buf = [0.0; 16];
        let n = q.len() + u.len() + self.params.len();
        let mut heap;
        let values: &mut [f64] = if n <= buf.len() {
            &mut buf[..n]
        } else {
            heap = vec![0.0; n];
            &mut heap
        };
        values[..q.len()].copy_from_slice(q.as_slice());
        values[q.len()..q.len() + u.len()].copy_from_slice(u.as_slice());
        values[q.len() + u.len()..].copy_from_slice(&self.params);
        State::from_iterator(q.len(), self.f.iter().map(|e| e.eval(values)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn expressions_read_their_slots_and_the_documented_functions() {
        let names = ["x", "theta", "v", "d1"];
        let e = Expr::parse("v * cos(theta) + atan2(x, d1) - sign(-2) + pi", &names).unwrap();
        let vals = [0.3, 0.7, 2.0, 0.6];
        let want = 2.0 * 0.7f64.cos() + 0.3f64.atan2(0.6) + 1.0 + std::f64::consts::PI;
        assert!((e.eval(&vals) - want).abs() < 1e-15);
        let got = Expr::parse("min(x, d1) + max(x, d1) + abs(-x) + sqrt(d1)^2", &names)
            .unwrap()
            .eval(&vals);
        assert_eq!(got, 0.3 + 0.6 + 0.3 + 0.6f64.sqrt().powf(2.0));
        assert_eq!(
            Expr::parse("-x^2", &names).unwrap().eval(&vals),
            -(0.3f64.powf(2.0))
        );
        assert_eq!(Expr::parse("1/2", &names).unwrap().eval(&vals), 0.5);
        let e = Expr::parse("v * cos(thetta)", &names)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("unknown name `thetta` (did you mean `theta`?)"),
            "{e}"
        );
        let e = Expr::parse("v * (cos(theta)", &names)
            .unwrap_err()
            .to_string();
        assert!(e.contains("does not parse"), "{e}");
        // Outside the language, and wrong calls.
        assert!(Expr::parse("log10(x)", &names)
            .unwrap_err()
            .to_string()
            .contains("unknown function `log10`"));
        assert!(Expr::parse("E * x", &names)
            .unwrap_err()
            .to_string()
            .contains("unknown name `E`"));
        assert!(Expr::parse("x == v", &names)
            .unwrap_err()
            .to_string()
            .contains("not part of the language"));
        let e = Expr::parse("sin(x, v)", &names).unwrap_err().to_string();
        assert!(e.contains("`sin` takes 1 argument, got 2"), "{e}");
        let e = Expr::parse("atan2(x)", &names).unwrap_err().to_string();
        assert!(e.contains("`atan2` takes 2 arguments, got 1"), "{e}");
    }

    fn model(eqs: &[&str]) -> Declared {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let (states, inputs) = (s(&["x", "y", "th"]), s(&["v", "w"]));
        let params = s(&["k"]);
        let names = Declared::slot_names(&states, &inputs, &params);
        let f = eqs
            .iter()
            .map(|t| Expr::parse(t, &names).unwrap())
            .collect();
        Declared::new(&states, &inputs, &[2], vec![0.7], f)
    }

    /// A and B by forward-mode AD against central differences of f, on
    /// every function of the language, at random points.
    #[test]
    fn forward_mode_jacobians_match_central_differences() {
        use rand::{Rng, SeedableRng};
        let m = model(&[
            "v * cos(th) + atan2(y, x) * w - sqrt(x^2 + 1) + abs(v - 2) * min(x, y)",
            "exp(-x) * sinh(w) + ln(2 + y) * cosh(v) + tanh(th) * max(v, w) / k",
            "tan(th / 4) + asin(y / 3) * acos(x / 3) + atan(w) * sign(v) + (x + 2)^(y + 1) + y^2",
        ]);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let (mut qdot, mut a, mut b) = (vec![0.0; 3], vec![0.0; 9], vec![0.0; 6]);
        for _ in 0..200 {
            let q: Vec<f64> = (0..3).map(|_| rng.random_range(-1.0..1.0)).collect();
            let u: Vec<f64> = (0..2).map(|_| rng.random_range(-1.0..1.0)).collect();
            assert_eq!(m.linearize(&q, &u, &mut qdot, &mut a, &mut b), None);
            let f = |q: &[f64], u: &[f64]| {
                m.velocity(
                    0.0,
                    &State::from_column_slice(q),
                    &Input::from_column_slice(u),
                )
            };
            assert_eq!(qdot.as_slice(), f(&q, &u).as_slice());
            let h = 1e-6;
            for j in 0..5 {
                let (mut qp, mut qm, mut up, mut um) = (q.clone(), q.clone(), u.clone(), u.clone());
                if j < 3 {
                    qp[j] += h;
                    qm[j] -= h;
                } else {
                    up[j - 3] += h;
                    um[j - 3] -= h;
                }
                let fd = (f(&qp, &up) - f(&qm, &um)) / (2.0 * h);
                for i in 0..3 {
                    let ad = if j < 3 {
                        a[i * 3 + j]
                    } else {
                        b[i * 2 + j - 3]
                    };
                    assert!(
                        (ad - fd[i]).abs() < 1e-6 * (1.0 + fd[i].abs()),
                        "∂f{i}/∂x{j} at {q:?} {u:?}: AD {ad}, differences {}",
                        fd[i]
                    );
                }
            }
        }
    }

    /// Kinks where they are, and not where the functions are smooth.
    #[test]
    fn kinks_are_found_where_an_equation_is_not_differentiable() {
        let (mut qdot, mut a, mut b) = (vec![0.0; 3], vec![0.0; 9], vec![0.0; 6]);
        let at = |eq: &str, q: [f64; 3], u: [f64; 2]| {
            let m = model(&[eq, "0", "0"]);
            let (mut qdot, mut a, mut b) = (vec![0.0; 3], vec![0.0; 9], vec![0.0; 6]);
            m.linearize(&q, &u, &mut qdot, &mut a, &mut b)
                .map(|(i, k)| (i, k.fun.map(|f| f.name())))
        };
        let rest = [0.0, 0.0];
        assert_eq!(at("abs(v)", [0.0; 3], rest), Some((0, Some("abs"))));
        assert_eq!(at("sign(v) * w", [0.0; 3], rest), Some((0, Some("sign"))));
        assert_eq!(
            at("min(x, y)", [0.3, 0.3, 0.0], rest),
            Some((0, Some("min")))
        );
        assert_eq!(at("max(v, w)", [0.0; 3], rest), Some((0, Some("max"))));
        assert_eq!(at("atan2(y, x)", [0.0; 3], rest), Some((0, Some("atan2"))));
        assert_eq!(at("sqrt(x)", [0.0; 3], rest), Some((0, Some("sqrt"))));
        // Smooth there: away from the kink, a constant argument, x^2 at x < 0.
        assert_eq!(at("abs(v)", [0.0; 3], [0.2, 0.0]), None);
        assert_eq!(at("abs(k) * v", [0.0; 3], rest), None);
        assert_eq!(at("min(x, x) + x^2", [-0.5, 0.0, 0.0], rest), None);
        // A kink still gives finite one-sided derivatives (an iteration
        // passing through goes on).
        let m = model(&["abs(v)", "0", "0"]);
        m.linearize(&[0.0; 3], &rest, &mut qdot, &mut a, &mut b);
        assert!(a.iter().chain(&b).all(|x| x.is_finite()));
    }

    #[test]
    fn the_declared_unicycle_is_the_unicycle() {
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let (states, inputs) = (s(&["x", "y", "theta"]), s(&["v", "omega"]));
        let names = Declared::slot_names(&states, &inputs, &[]);
        let f = ["v * cos(theta)", "v * sin(theta)", "omega"]
            .iter()
            .map(|t| Expr::parse(t, &names).unwrap())
            .collect();
        let m = Declared::new(&states, &inputs, &[2], vec![], f);
        let q = State::from_vec(vec![0.2, -0.1, 1.3]);
        let u = Input::from_vec(vec![0.4, -0.9]);
        let a = m.velocity(0.0, &q, &u);
        let b = crate::robots::diff_drive::kinematics::Unicycle.velocity(0.0, &q, &u);
        assert_eq!(a, b);
        assert_eq!(m.position_states(), Some([0, 1]));
        assert_eq!(m.state_names(), &["x", "y", "theta"]);
        assert!((m.input_matrix(&q) * &u - a).amax() < 1e-15);
    }
}
