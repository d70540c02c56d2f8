//! Kinematic models declared in a scenario: q' = f(q, u), one expression
//! per state, over the states, the inputs and named parameters.
//!
//! Expressions are parsed once by `evalexpr` (a well-kept expression
//! crate), its operator tree checked against the language and compiled to
//! a short stack program over f64 slots: an evaluation is a loop over a few
//! instructions, as fast as the arithmetic it does. The language is exactly
//! + − * / ^, parentheses, the [`FUNCTIONS`], `pi`, numbers and names.

use crate::model::{Input, KinematicModel, State};
use evalexpr::{Node, Operator, Value};
use nalgebra::DMatrix;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// Functions of the expression language: (name, arity).
pub const FUNCTIONS: [(&str, usize); 17] = [
    ("sin", 1),
    ("cos", 1),
    ("tan", 1),
    ("asin", 1),
    ("acos", 1),
    ("atan", 1),
    ("atan2", 2),
    ("sqrt", 1),
    ("abs", 1),
    ("min", 2),
    ("max", 2),
    ("exp", 1),
    ("ln", 1),
    ("sign", 1),
    ("sinh", 1),
    ("cosh", 1),
    ("tanh", 1),
];

/// Whether `name` is a function or constant of the language.
pub fn reserved(name: &str) -> bool {
    name == "pi" || FUNCTIONS.iter().any(|(f, _)| *f == name)
}

fn sign(a: f64) -> f64 {
    if a > 0.0 {
        1.0
    } else if a < 0.0 {
        -1.0
    } else {
        0.0
    }
}

fn unary(name: &str) -> Option<fn(f64) -> f64> {
    Some(match name {
        "sin" => f64::sin,
        "cos" => f64::cos,
        "tan" => f64::tan,
        "asin" => f64::asin,
        "acos" => f64::acos,
        "atan" => f64::atan,
        "sqrt" => f64::sqrt,
        "abs" => f64::abs,
        "exp" => f64::exp,
        "ln" => f64::ln,
        "sign" => sign,
        "sinh" => f64::sinh,
        "cosh" => f64::cosh,
        "tanh" => f64::tanh,
        _ => return None,
    })
}

fn binary(name: &str) -> Option<fn(f64, f64) -> f64> {
    Some(match name {
        "atan2" => f64::atan2,
        "min" => f64::min,
        "max" => f64::max,
        _ => return None,
    })
}

/// One instruction of a compiled expression (a stack machine).
#[derive(Debug, Clone, Copy)]
enum Op {
    Slot(usize),
    Const(f64),
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Neg,
    F1(fn(f64) -> f64),
    F2(fn(f64, f64) -> f64),
}

/// One parsed expression, compiled.
#[derive(Debug, Clone)]
pub struct Expr {
    ops: Vec<Op>,
    depth: usize,
    text: String,
}

/// Compiles an evalexpr tree into [`Op`]s.
struct Compiler<'a> {
    names: &'a [&'a str],
    text: &'a str,
    ops: Vec<Op>,
    depth: usize,
    max: usize,
}

impl Compiler<'_> {
    fn push(&mut self, op: Op, pops: usize) {
        self.ops.push(op);
        self.depth = self.depth + 1 - pops;
        self.max = self.max.max(self.depth);
    }

    /// The arguments of a call: a tuple's items, or one node.
    fn args(node: &Node) -> Vec<&Node> {
        let mut n = node;
        while matches!(n.operator(), Operator::RootNode) && n.children().len() == 1 {
            n = &n.children()[0];
        }
        match n.operator() {
            Operator::Tuple => n.children().iter().collect(),
            _ => vec![n],
        }
    }

    fn node(&mut self, node: &Node) -> Result<(), String> {
        let text = self.text;
        let kids = node.children();
        let two = |c: &mut Self, op: Op| -> Result<(), String> {
            c.node(&kids[0])?;
            c.node(&kids[1])?;
            c.push(op, 2);
            Ok(())
        };
        match node.operator() {
            Operator::RootNode => match kids {
                [one] => self.node(one),
                [] => Err(format!("expression `{text}`: an empty pair of parentheses")),
                _ => Err(format!("expression `{text}`: several expressions in one")),
            },
            Operator::Add => two(self, Op::Add),
            Operator::Sub => two(self, Op::Sub),
            Operator::Mul => two(self, Op::Mul),
            Operator::Div => two(self, Op::Div),
            Operator::Exp => two(self, Op::Pow),
            Operator::Neg => {
                self.node(&kids[0])?;
                self.push(Op::Neg, 1);
                Ok(())
            }
            Operator::Const { value } => {
                let v = match value {
                    Value::Float(f) => *f,
                    Value::Int(i) => *i as f64,
                    other => {
                        return Err(format!(
                            "expression `{text}`: `{other}` is not a number"
                        ))
                    }
                };
                self.push(Op::Const(v), 0);
                Ok(())
            }
            Operator::VariableIdentifierRead { identifier } => {
                if identifier == "pi" {
                    self.push(Op::Const(std::f64::consts::PI), 0);
                    return Ok(());
                }
                if let Some(i) = self.names.iter().position(|n| n == identifier) {
                    self.push(Op::Slot(i), 0);
                    return Ok(());
                }
                let best = self
                    .names
                    .iter()
                    .map(|n| (strsim::jaro_winkler(identifier, n), *n))
                    .max_by(|a, b| a.0.total_cmp(&b.0))
                    .filter(|(s, _)| *s >= 0.8)
                    .map(|(_, n)| format!(" (did you mean `{n}`?)"))
                    .unwrap_or_default();
                let fs: Vec<&str> = FUNCTIONS.iter().map(|f| f.0).collect();
                Err(format!(
                    "expression `{text}`: unknown name `{identifier}`{best}; known: {}, pi, and the functions {}",
                    self.names.join(", "),
                    fs.join(", ")
                ))
            }
            Operator::FunctionIdentifier { identifier } => {
                let Some(&(_, arity)) = FUNCTIONS.iter().find(|f| f.0 == identifier) else {
                    let fs: Vec<&str> = FUNCTIONS.iter().map(|f| f.0).collect();
                    return Err(format!(
                        "expression `{text}`: unknown function `{identifier}` (functions: {})",
                        fs.join(", ")
                    ));
                };
                let args = Self::args(&kids[0]);
                if args.len() != arity {
                    return Err(format!(
                        "expression `{text}`: `{identifier}` takes {arity} argument{}, got {}",
                        if arity == 1 { "" } else { "s" },
                        args.len()
                    ));
                }
                for a in &args {
                    self.node(a)?;
                }
                match (unary(identifier), binary(identifier)) {
                    (Some(f), _) => self.push(Op::F1(f), 1),
                    (_, Some(f)) => self.push(Op::F2(f), 2),
                    _ => unreachable!("every function of FUNCTIONS has an implementation"),
                }
                Ok(())
            }
            other => Err(format!(
                "expression `{text}`: `{other}` is not part of the language (+ - * / ^, parentheses, functions, numbers, names)"
            )),
        }
    }
}

impl Expr {
    /// Parse `text` over `names` (the value vector's slot names). The error
    /// is one line: the parser's complaint, a wrong call, or the unknown
    /// name with the nearest known one.
    pub fn parse(text: &str, names: &[&str]) -> Result<Expr, String> {
        if text.trim().is_empty() {
            return Err("the expression is empty".into());
        }
        let tree = evalexpr::build_operator_tree(text).map_err(|e| {
            format!(
                "expression `{text}` does not parse: {}",
                e.to_string().replace('\n', " ")
            )
        })?;
        let mut c = Compiler {
            names,
            text,
            ops: Vec::new(),
            depth: 0,
            max: 0,
        };
        c.node(&tree)?;
        if c.depth != 1 {
            return Err(format!("expression `{text}`: not one value"));
        }
        Ok(Expr {
            ops: c.ops,
            depth: c.max,
            text: text.to_string(),
        })
    }

    /// The value for the slot values `values`.
    #[inline]
    pub fn eval(&self, values: &[f64]) -> f64 {
        let mut small = [0.0f64; 16];
        let mut big;
        let stack: &mut [f64] = if self.depth <= small.len() {
            &mut small
        } else {
            big = vec![0.0; self.depth];
            &mut big
        };
        let mut sp = 0;
        for op in &self.ops {
            match *op {
                Op::Slot(i) => {
                    stack[sp] = values[i];
                    sp += 1;
                }
                Op::Const(v) => {
                    stack[sp] = v;
                    sp += 1;
                }
                Op::Neg => stack[sp - 1] = -stack[sp - 1],
                Op::F1(f) => stack[sp - 1] = f(stack[sp - 1]),
                op => {
                    sp -= 1;
                    let (a, b) = (stack[sp - 1], stack[sp]);
                    stack[sp - 1] = match op {
                        Op::Add => a + b,
                        Op::Sub => a - b,
                        Op::Mul => a * b,
                        Op::Div => a / b,
                        Op::Pow => a.powf(b),
                        Op::F2(f) => f(a, b),
                        _ => unreachable!("one-operand instructions are above"),
                    };
                }
            }
        }
        stack[0]
    }

    /// The expression as written.
    pub fn text(&self) -> &str {
        &self.text
    }
}

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
        let e = Expr::parse("v * cos(thetta)", &names).unwrap_err();
        assert!(
            e.contains("unknown name `thetta` (did you mean `theta`?)"),
            "{e}"
        );
        let e = Expr::parse("v * (cos(theta)", &names).unwrap_err();
        assert!(e.contains("does not parse"), "{e}");
        // Outside the language, and wrong calls.
        assert!(Expr::parse("log10(x)", &names)
            .unwrap_err()
            .contains("unknown function `log10`"));
        assert!(Expr::parse("E * x", &names)
            .unwrap_err()
            .contains("unknown name `E`"));
        assert!(Expr::parse("x == v", &names)
            .unwrap_err()
            .contains("not part of the language"));
        let e = Expr::parse("sin(x, v)", &names).unwrap_err();
        assert!(e.contains("`sin` takes 1 argument, got 2"), "{e}");
        let e = Expr::parse("atan2(x)", &names).unwrap_err();
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
        let b = crate::robots::diff_drive::kinematics::Unicycle.velocity(0.0, &q, &u);
        assert_eq!(a, b);
        assert_eq!(m.position_states(), Some([0, 1]));
        assert_eq!(m.state_names(), &["x", "y", "theta"]);
        assert!((m.input_matrix(&q) * &u - a).amax() < 1e-15);
    }
}
