//! Kinematic models declared in a scenario: q' = f(q, u), one expression
//! per state, over the states, the inputs and named parameters. The
//! expression language is [`super::expr`].

use super::{Input, KinematicModel, State};
use nalgebra::DMatrix;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

pub use super::expr::{reserved, Expr, ExprError, FUNCTIONS};

/// A `&'static` copy of `names`, made once per distinct list: the model
/// trait hands out static names, and sweeps build a declared system per
/// variant.
pub fn static_names(names: &[String]) -> &'static [&'static str] {
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
pub fn static_indices(v: &[usize]) -> &'static [usize] {
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
        let b = super::super::unicycle::Unicycle.velocity(0.0, &q, &u);
        assert_eq!(a, b);
        assert_eq!(m.position_states(), Some([0, 1]));
        assert_eq!(m.state_names(), &["x", "y", "theta"]);
        assert!((m.input_matrix(&q) * &u - a).amax() < 1e-15);
    }
}
