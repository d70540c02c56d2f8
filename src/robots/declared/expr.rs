//! The expression language of declared models: `+ - * / ^`, parentheses,
//! the [`FUNCTIONS`], `pi`, numbers and names.
//!
//! Expressions are parsed once by `evalexpr` (a well-kept expression
//! crate), its operator tree checked against the language and compiled to
//! a short stack program over f64 slots: an evaluation is a loop over a few
//! instructions, as fast as the arithmetic it does.
//!
//! Bounded: `evalexpr` builds its tree recursively (one level per sign or
//! power applied to another) and drops it recursively, so the text is
//! measured first, iteratively: at most [`MAX_CHARS`] characters and
//! [`MAX_DEPTH`] levels of nesting ([`nesting`]). The compiler walks the
//! tree with an explicit stack, and the tree is taken apart iteratively, so
//! a long sum (a tree as deep as it has terms) needs no stack either.

use crate::echo;
use evalexpr::{Node, Operator, Value};
use num_dual::{Dual64, DualNum};
use thiserror::Error;

/// Most characters in one expression.
pub const MAX_CHARS: usize = 4096;

/// Most levels of nesting in one expression ([`nesting`]).
pub const MAX_DEPTH: usize = 64;

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

/// A function of the language.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fun {
    /// sin
    Sin,
    /// cos
    Cos,
    /// tan
    Tan,
    /// asin
    Asin,
    /// acos
    Acos,
    /// atan
    Atan,
    /// atan2(y, x)
    Atan2,
    /// sqrt
    Sqrt,
    /// abs
    Abs,
    /// min(a, b)
    Min,
    /// max(a, b)
    Max,
    /// exp
    Exp,
    /// ln
    Ln,
    /// sign (−1, 0 or 1)
    Sign,
    /// sinh
    Sinh,
    /// cosh
    Cosh,
    /// tanh
    Tanh,
}

impl Fun {
    /// The function called `name`.
    pub fn named(name: &str) -> Option<Fun> {
        Some(match name {
            "sin" => Fun::Sin,
            "cos" => Fun::Cos,
            "tan" => Fun::Tan,
            "asin" => Fun::Asin,
            "acos" => Fun::Acos,
            "atan" => Fun::Atan,
            "atan2" => Fun::Atan2,
            "sqrt" => Fun::Sqrt,
            "abs" => Fun::Abs,
            "min" => Fun::Min,
            "max" => Fun::Max,
            "exp" => Fun::Exp,
            "ln" => Fun::Ln,
            "sign" => Fun::Sign,
            "sinh" => Fun::Sinh,
            "cosh" => Fun::Cosh,
            "tanh" => Fun::Tanh,
            _ => return None,
        })
    }

    /// The name as written.
    pub fn name(self) -> &'static str {
        match self {
            Fun::Sin => "sin",
            Fun::Cos => "cos",
            Fun::Tan => "tan",
            Fun::Asin => "asin",
            Fun::Acos => "acos",
            Fun::Atan => "atan",
            Fun::Atan2 => "atan2",
            Fun::Sqrt => "sqrt",
            Fun::Abs => "abs",
            Fun::Min => "min",
            Fun::Max => "max",
            Fun::Exp => "exp",
            Fun::Ln => "ln",
            Fun::Sign => "sign",
            Fun::Sinh => "sinh",
            Fun::Cosh => "cosh",
            Fun::Tanh => "tanh",
        }
    }

    /// One argument's value.
    #[inline]
    pub fn one(self, a: f64) -> f64 {
        match self {
            Fun::Sin => a.sin(),
            Fun::Cos => a.cos(),
            Fun::Tan => a.tan(),
            Fun::Asin => a.asin(),
            Fun::Acos => a.acos(),
            Fun::Atan => a.atan(),
            Fun::Sqrt => a.sqrt(),
            Fun::Abs => a.abs(),
            Fun::Exp => a.exp(),
            Fun::Ln => a.ln(),
            Fun::Sign => sign(a),
            Fun::Sinh => a.sinh(),
            Fun::Cosh => a.cosh(),
            Fun::Tanh => a.tanh(),
            Fun::Atan2 | Fun::Min | Fun::Max => f64::NAN,
        }
    }

    /// Two arguments' value.
    #[inline]
    pub fn two(self, a: f64, b: f64) -> f64 {
        match self {
            Fun::Atan2 => a.atan2(b),
            Fun::Min => a.min(b),
            Fun::Max => a.max(b),
            _ => f64::NAN,
        }
    }
}

/// How near a kink (|x| of `abs(x)`, |a − b| of `min(a, b)`) a point is at
/// it: the planner's linearisation there would be one side's, by round-off.
pub const KINK: f64 = 1e-9;

/// A one-argument function on a dual number; a kink (or a derivative that
/// is not finite) where `a` moves is noted. Where `a` does not move, the
/// derivative is 0 (not 0 · ∞). At a kink the derivative is one side's
/// (`abs` and `sign` take `sign(x)` and 0), so an iteration that passes
/// through one goes on; only where it starts is a kink refused.
fn dual_one(f: Fun, a: Dual64, note: &mut impl FnMut(Kink)) -> Dual64 {
    let value = f.one(a.re);
    if a.eps == 0.0 {
        return Dual64::from_re(value);
    }
    let kink = Kink {
        fun: Some(f),
        args: [a.re, 0.0],
    };
    if matches!(f, Fun::Abs | Fun::Sign) && a.re.abs() <= KINK {
        note(kink);
    }
    let d = match f {
        Fun::Abs => return Dual64::new(value, sign(a.re) * a.eps),
        Fun::Sign => return Dual64::from_re(value),
        Fun::Sin => a.sin(),
        Fun::Cos => a.cos(),
        Fun::Tan => a.tan(),
        Fun::Asin => a.asin(),
        Fun::Acos => a.acos(),
        Fun::Atan => a.atan(),
        Fun::Sqrt => a.sqrt(),
        Fun::Exp => a.exp(),
        Fun::Ln => a.ln(),
        Fun::Sinh => a.sinh(),
        Fun::Cosh => a.cosh(),
        Fun::Tanh => a.tanh(),
        Fun::Atan2 | Fun::Min | Fun::Max => Dual64::new(f64::NAN, f64::NAN),
    };
    if !d.eps.is_finite() && value.is_finite() {
        note(kink);
    }
    Dual64::new(value, d.eps)
}

/// A two-argument function on dual numbers (see [`dual_one`]).
fn dual_two(f: Fun, a: Dual64, b: Dual64, note: &mut impl FnMut(Kink)) -> Dual64 {
    let value = f.two(a.re, b.re);
    if a.eps == 0.0 && b.eps == 0.0 {
        return Dual64::from_re(value);
    }
    let kink = Kink {
        fun: Some(f),
        args: [a.re, b.re],
    };
    let near = (a.re - b.re).abs() <= KINK * (1.0 + a.re.abs() + b.re.abs());
    if matches!(f, Fun::Min | Fun::Max) && near && a.eps != b.eps {
        note(kink);
    }
    let eps = match f {
        Fun::Min => {
            if a.re <= b.re {
                a.eps
            } else {
                b.eps
            }
        }
        Fun::Max => {
            if a.re >= b.re {
                a.eps
            } else {
                b.eps
            }
        }
        Fun::Atan2 if a.re.abs() <= KINK && b.re.abs() <= KINK => {
            note(kink);
            0.0
        }
        Fun::Atan2 => a.atan2(b).eps,
        _ => f64::NAN,
    };
    Dual64::new(value, eps)
}

/// a ^ b on dual numbers: the value is `f64::powf`'s; the exponent's part
/// of the derivative (a^b ln a · b') only where the exponent moves, so a
/// negative base with a constant exponent (`x^2`) is differentiable.
fn dual_pow(a: Dual64, b: Dual64, note: &mut impl FnMut(Kink)) -> Dual64 {
    let value = a.re.powf(b.re);
    let mut eps = 0.0;
    if a.eps != 0.0 {
        eps += b.re * a.re.powf(b.re - 1.0) * a.eps;
    }
    if b.eps != 0.0 {
        eps += value * a.re.ln() * b.eps;
    }
    if !eps.is_finite() && value.is_finite() {
        note(Kink {
            fun: None,
            args: [a.re, b.re],
        });
    }
    Dual64::new(value, eps)
}

/// −1, 0 or 1.
pub fn sign(a: f64) -> f64 {
    if a > 0.0 {
        1.0
    } else if a < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// One instruction of a compiled expression (a stack machine).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Op {
    /// Push slot i's value.
    Slot(usize),
    /// Push a number.
    Const(f64),
    /// a + b
    Add,
    /// a − b
    Sub,
    /// a · b
    Mul,
    /// a / b
    Div,
    /// a ^ b
    Pow,
    /// −a
    Neg,
    /// A one-argument function.
    F1(Fun),
    /// A two-argument function.
    F2(Fun),
}

/// Why an expression was refused; one line, echoing the text shortened.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ExprError {
    /// Nothing but blanks.
    #[error("the expression is empty")]
    Empty,
    /// Over [`MAX_CHARS`].
    #[error("the expression has {chars} characters, over the limit of {MAX_CHARS}")]
    TooLong {
        /// Its length in characters.
        chars: usize,
    },
    /// Over [`MAX_DEPTH`] levels of nesting.
    #[error(
        "expression {}: {depth} levels of nesting (parentheses, and signs or powers applied one to another), over the limit of {MAX_DEPTH}",
        echo::code(.text)
    )]
    TooDeep {
        /// The expression.
        text: String,
        /// Its nesting, as far as it was measured.
        depth: usize,
    },
    /// What the parser said.
    #[error("expression {} does not parse: {why}", echo::code(.text))]
    Parse {
        /// The expression.
        text: String,
        /// The parser's complaint, on one line.
        why: String,
    },
    /// Parsed, but not an expression of the language.
    #[error("expression {}: {why}", echo::code(.text))]
    Language {
        /// The expression.
        text: String,
        /// What is wrong.
        why: LanguageError,
    },
}

/// Why a parsed tree is not an expression of the language.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LanguageError {
    /// A binary operator without two operands (the operator as written).
    #[error("`{0}` needs an operand on each side")]
    Operands(String),
    /// `()`.
    #[error("an empty pair of parentheses")]
    EmptyParens,
    /// Several expressions where one is wanted.
    #[error("several expressions in one")]
    Several,
    /// A unary minus without its operand.
    #[error("`-` needs an operand")]
    Negation,
    /// A constant that is not a number (as written).
    #[error("{} is not a number", echo::code(.0))]
    NotNumber(String),
    /// A name that is not a slot, with the nearest known one and the known ones.
    #[error("{0}")]
    UnknownName(String),
    /// A function that is not one of [`FUNCTIONS`].
    #[error("unknown function {} (functions: {})", echo::code(.0), function_list())]
    UnknownFunction(String),
    /// A call with another number of arguments than the function takes.
    #[error("`{name}` takes {arity} argument{}, got {got}", if *arity == 1 { "" } else { "s" })]
    Arity {
        /// The function.
        name: String,
        /// Arguments it takes.
        arity: usize,
        /// Arguments given.
        got: usize,
    },
    /// An operator outside + - * / ^, parentheses, functions, numbers and names.
    #[error(
        "{} is not part of the language (+ - * / ^, parentheses, functions, numbers, names)",
        echo::code(.0)
    )]
    Foreign(String),
    /// The program does not leave exactly one value.
    #[error("not one value")]
    NotOneValue,
}

/// The functions' names, comma-separated.
fn function_list() -> String {
    FUNCTIONS.iter().map(|f| f.0).collect::<Vec<_>>().join(", ")
}

/// Nesting of `text`, measured on the characters (the tree `evalexpr`
/// builds is no deeper than this, plus a few levels per parenthesis, and
/// its recursion follows it): each parenthesis opens a level, and signs and
/// powers applied one to another (`- - x`, `a^b^c`) each add one, counted
/// from the last `+ - * / ,` between operands. Stops counting past `limit`.
pub fn nesting(text: &str, limit: usize) -> usize {
    // (base, run) of each enclosing parenthesis.
    let mut open: Vec<(usize, usize)> = Vec::new();
    let (mut base, mut run, mut deepest) = (0usize, 0usize, 0usize);
    // After an operand (a name, a number, `)`): the next `-` is binary.
    let mut operand = false;
    for c in text.chars() {
        match c {
            '(' => {
                open.push((base, run));
                base += run + 2;
                run = 0;
                operand = false;
            }
            ')' => {
                if let Some((b, r)) = open.pop() {
                    (base, run) = (b, r);
                }
                operand = true;
            }
            '+' | '-' if !operand => run += 1,
            '^' => {
                run += 1;
                operand = false;
            }
            '+' | '-' | '*' | '/' | '%' | ',' => {
                run = 0;
                operand = false;
            }
            c if c.is_whitespace() => {}
            c if c.is_alphanumeric() || c == '_' || c == '.' => operand = true,
            _ => operand = false,
        }
        deepest = deepest.max(base + run + 1);
        if deepest > limit {
            return deepest;
        }
    }
    deepest
}

/// Take `tree` apart without recursion (dropping a deep `evalexpr` tree
/// recurses once per level).
fn dismantle(tree: Node) {
    let mut stack = vec![tree];
    while let Some(mut n) = stack.pop() {
        stack.append(n.children_mut());
    }
}

/// One parsed expression, compiled.
#[derive(Debug, Clone)]
pub struct Expr {
    ops: Vec<Op>,
    depth: usize,
    text: String,
    /// The slots it reads, increasing.
    slots: Vec<usize>,
}

/// A point where an expression is not differentiable: `abs` or `sign` at
/// 0, `min` or `max` of two equal values, `atan2(0, 0)`, or a derivative
/// that is not finite (`sqrt` at 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Kink {
    /// The function (`None`: an operator, `^` or `/`).
    pub fun: Option<Fun>,
    /// Its arguments there.
    pub args: [f64; 2],
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

/// "unknown name" with the nearest known one and the known ones.
fn unknown_name(identifier: &str, names: &[&str]) -> String {
    let best = names
        .iter()
        .map(|n| (strsim::jaro_winkler(identifier, n), *n))
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .filter(|(s, _)| *s >= 0.8)
        .map(|(_, n)| format!(" (did you mean {}?)", echo::code(n)))
        .unwrap_or_default();
    let fs: Vec<&str> = FUNCTIONS.iter().map(|f| f.0).collect();
    format!(
        "unknown name {}{best}; known: {}, pi, and the functions {}",
        echo::code(identifier),
        names
            .iter()
            .map(|n| echo::bare(n))
            .collect::<Vec<_>>()
            .join(", "),
        fs.join(", ")
    )
}

/// The stack program of `tree` over slots `names`, and its stack depth.
/// Post-order with an explicit stack of pending work.
fn compile(tree: &Node, names: &[&str]) -> Result<(Vec<Op>, usize), LanguageError> {
    enum Work<'a> {
        Visit(&'a Node),
        Emit(Op, usize),
    }
    let mut work = vec![Work::Visit(tree)];
    let (mut ops, mut depth, mut max) = (Vec::new(), 0usize, 0usize);
    while let Some(w) = work.pop() {
        let node = match w {
            Work::Emit(op, pops) => {
                ops.push(op);
                // Every operand was pushed before its operator.
                depth = depth + 1 - pops;
                max = max.max(depth);
                continue;
            }
            Work::Visit(node) => node,
        };
        let kids = node.children();
        let operator = node.operator();
        let binary = match operator {
            Operator::Add => Some(Op::Add),
            Operator::Sub => Some(Op::Sub),
            Operator::Mul => Some(Op::Mul),
            Operator::Div => Some(Op::Div),
            Operator::Exp => Some(Op::Pow),
            _ => None,
        };
        if let Some(op) = binary {
            let [a, b] = kids else {
                return Err(LanguageError::Operands(operator.to_string()));
            };
            work.extend([Work::Emit(op, 2), Work::Visit(b), Work::Visit(a)]);
            continue;
        }
        match operator {
            Operator::RootNode => match kids {
                [one] => work.push(Work::Visit(one)),
                [] => return Err(LanguageError::EmptyParens),
                _ => return Err(LanguageError::Several),
            },
            Operator::Neg => {
                let [a] = kids else {
                    return Err(LanguageError::Negation);
                };
                work.extend([Work::Emit(Op::Neg, 1), Work::Visit(a)]);
            }
            Operator::Const { value } => {
                let v = match value {
                    Value::Float(f) => *f,
                    Value::Int(i) => *i as f64,
                    other => return Err(LanguageError::NotNumber(other.to_string())),
                };
                work.push(Work::Emit(Op::Const(v), 0));
            }
            Operator::VariableIdentifierRead { identifier } => {
                let op = if identifier == "pi" {
                    Op::Const(std::f64::consts::PI)
                } else if let Some(i) = names.iter().position(|n| n == identifier) {
                    Op::Slot(i)
                } else {
                    return Err(LanguageError::UnknownName(unknown_name(identifier, names)));
                };
                work.push(Work::Emit(op, 0));
            }
            Operator::FunctionIdentifier { identifier } => {
                let (Some(f), Some(&(_, arity))) = (
                    Fun::named(identifier),
                    FUNCTIONS.iter().find(|f| f.0 == identifier),
                ) else {
                    return Err(LanguageError::UnknownFunction(identifier.to_string()));
                };
                let got = match kids {
                    [a] => args(a),
                    _ => Vec::new(),
                };
                if got.len() != arity {
                    return Err(LanguageError::Arity {
                        name: identifier.to_string(),
                        arity,
                        got: got.len(),
                    });
                }
                let op = if arity == 1 { Op::F1(f) } else { Op::F2(f) };
                work.push(Work::Emit(op, arity));
                work.extend(got.into_iter().rev().map(Work::Visit));
            }
            other => return Err(LanguageError::Foreign(other.to_string())),
        }
    }
    if depth != 1 {
        return Err(LanguageError::NotOneValue);
    }
    Ok((ops, max))
}

impl Expr {
    /// Parse `text` over `names` (the value vector's slot names). The error
    /// is one line: a limit, the parser's complaint, a wrong call, or the
    /// unknown name with the nearest known one.
    pub fn parse(text: &str, names: &[&str]) -> Result<Expr, ExprError> {
        if text.trim().is_empty() {
            return Err(ExprError::Empty);
        }
        let chars = text.chars().count();
        if chars > MAX_CHARS {
            return Err(ExprError::TooLong { chars });
        }
        let depth = nesting(text, MAX_DEPTH);
        if depth > MAX_DEPTH {
            return Err(ExprError::TooDeep {
                text: text.into(),
                depth,
            });
        }
        let tree = evalexpr::build_operator_tree(text).map_err(|e| ExprError::Parse {
            text: text.into(),
            why: echo::escaped(&e.to_string().replace('\n', " ")),
        })?;
        let compiled = compile(&tree, names);
        dismantle(tree);
        let (ops, depth) = compiled.map_err(|why| ExprError::Language {
            text: text.into(),
            why,
        })?;
        let mut slots: Vec<usize> = ops
            .iter()
            .filter_map(|op| match op {
                Op::Slot(i) => Some(*i),
                _ => None,
            })
            .collect();
        slots.sort_unstable();
        slots.dedup();
        Ok(Expr {
            ops,
            depth,
            text: text.to_string(),
            slots,
        })
    }

    /// The slots it reads, increasing.
    pub fn slots(&self) -> &[usize] {
        &self.slots
    }

    /// Value and derivative at dual slot values (forward-mode automatic
    /// differentiation of the program, with `num-dual`): the value is
    /// [`Expr::eval`]'s up to rounding, the derivative is along the
    /// values' dual parts. The first [`Kink`] met on the way, where the
    /// derivative is not defined, goes to `kink`.
    pub fn eval_dual(&self, values: &[Dual64], kink: &mut Option<Kink>) -> Dual64 {
        let mut small = [Dual64::from_re(0.0); 16];
        let mut big;
        let stack: &mut [Dual64] = if self.depth <= small.len() {
            &mut small
        } else {
            big = vec![Dual64::from_re(0.0); self.depth];
            &mut big
        };
        let mut sp = 0;
        let mut note = |k: Kink| {
            kink.get_or_insert(k);
        };
        for op in &self.ops {
            match *op {
                Op::Slot(i) => {
                    stack[sp] = values[i];
                    sp += 1;
                }
                Op::Const(v) => {
                    stack[sp] = Dual64::from_re(v);
                    sp += 1;
                }
                Op::Neg => stack[sp - 1] = -stack[sp - 1],
                Op::F1(f) => stack[sp - 1] = dual_one(f, stack[sp - 1], &mut note),
                op => {
                    sp -= 1;
                    let (a, b) = (stack[sp - 1], stack[sp]);
                    stack[sp - 1] = match op {
                        Op::Add => a + b,
                        Op::Sub => a - b,
                        Op::Mul => a * b,
                        // By hand: the value is then `eval`'s to the bit.
                        Op::Div => {
                            Dual64::new(a.re / b.re, (a.eps * b.re - b.eps * a.re) / (b.re * b.re))
                        }
                        Op::Pow => dual_pow(a, b, &mut note),
                        Op::F2(f) => dual_two(f, a, b, &mut note),
                        _ => unreachable!("one-operand instructions are above"),
                    };
                }
            }
        }
        stack[0]
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
                Op::F1(f) => stack[sp - 1] = f.one(stack[sp - 1]),
                op => {
                    sp -= 1;
                    let (a, b) = (stack[sp - 1], stack[sp]);
                    stack[sp - 1] = match op {
                        Op::Add => a + b,
                        Op::Sub => a - b,
                        Op::Mul => a * b,
                        Op::Div => a / b,
                        Op::Pow => a.powf(b),
                        Op::F2(f) => f.two(a, b),
                        _ => unreachable!("one-operand instructions are above"),
                    };
                }
            }
        }
        stack[0]
    }

    /// The program (for evaluators over other number types).
    pub fn ops(&self) -> &[Op] {
        &self.ops
    }

    /// Most values on the stack during an evaluation.
    pub fn stack_depth(&self) -> usize {
        self.depth
    }

    /// The expression as written.
    pub fn text(&self) -> &str {
        &self.text
    }
}

#[cfg(test)]
#[path = "expr_tests.rs"]
mod tests;
