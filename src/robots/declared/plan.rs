//! Seed 001's endogenous planner for a declared model (`[model] kind =
//! "declared"` with `[planner] kind = "endogenous"`): the generic planner
//! of [`crate::planner::endogenous`] with A(t) = ∂f/∂q and B(t) = ∂f/∂u by
//! forward-mode automatic differentiation of the compiled equations
//! ([`Declared::linearize`]).
//!
//! Start, goal and via points are in the declared units: states listed in
//! `angles` in degrees in the file (radians here), the others as declared.
//! An equation that is not differentiable where an iteration starts (`abs`
//! or `sign` at 0, `min`/`max` of equal values, `atan2(0, 0)`, `sqrt` at 0)
//! is refused, naming its key.

use crate::model::{KinematicModel, State};
use crate::plan::{Limits, Plan};
use crate::planner::endogenous::{
    self, EndogenousParams, EndogenousSystem, Fixed, Linearization, Sizes,
};
use crate::planner::PlanError;
use crate::robots::declared::kinematics::{Declared, Kink};

impl EndogenousSystem for Declared {
    type Dims = Sizes;
    fn dims(&self) -> Sizes {
        Sizes {
            n: self.state_names().len(),
            m: self.input_names().len(),
        }
    }
    fn linearize(&self, q: &[f64], u: &[f64], out: &mut Linearization) {
        Declared::linearize(self, q, u, &mut out.qdot, &mut out.a, &mut out.b);
    }
    fn check_start(&self, q: &[f64], u: &[f64]) -> Result<(), PlanError> {
        let (n, m) = (q.len(), u.len());
        let mut l = Linearization::zeros(n, m);
        let kink = Declared::linearize(self, q, u, &mut l.qdot, &mut l.a, &mut l.b);
        let bad_row = |i: usize| {
            !l.qdot[i].is_finite()
                || l.a[i * n..(i + 1) * n].iter().any(|x| !x.is_finite())
                || l.b[i * m..(i + 1) * m].iter().any(|x| !x.is_finite())
        };
        let (i, why) = match kink {
            Some((i, k)) => (i, kink_text(&k)),
            None => match (0..n).find(|&i| bad_row(i)) {
                Some(i) => (i, "its value or a derivative is not finite".to_string()),
                None => return Ok(()),
            },
        };
        let state = self.state_names()[i];
        let text = self.equations().nth(i).map(|(_, t)| t).unwrap_or("");
        Err(PlanError::Model {
            key: format!("model.kinematics.{state}"),
            reason: format!(
                "{} is not differentiable where the planner starts ({why}), at {}: the Jacobian the planner needs is undefined there; start elsewhere, set u_start away from the kink, or write a smooth expression",
                crate::echo::code(text),
                crate::model::point_text(self, q, u)
            ),
        })
    }
}

/// A declared model whose sizes are known to the compiler: the planner's
/// integration loops are then unrolled (2.7× fewer instructions in the
/// integrator at 3 states, measured with callgrind). For the sizes of the
/// usual wheeled models; others plan at [`Sizes`].
struct AtSize<'a, const N: usize, const M: usize>(&'a Declared);

impl<const N: usize, const M: usize> EndogenousSystem for AtSize<'_, N, M> {
    type Dims = Fixed<N, M>;
    fn dims(&self) -> Fixed<N, M> {
        Fixed
    }
    fn linearize(&self, q: &[f64], u: &[f64], out: &mut Linearization) {
        Declared::linearize(self.0, q, u, &mut out.qdot, &mut out.a, &mut out.b);
    }
    fn check_start(&self, q: &[f64], u: &[f64]) -> Result<(), PlanError> {
        self.0.check_start(q, u)
    }
}

/// What is not differentiable, in the expression's terms.
fn kink_text(k: &Kink) -> String {
    use crate::robots::declared::expr::Fun;
    let r = crate::numfmt::readable;
    match k.fun {
        Some(f @ (Fun::Min | Fun::Max)) => {
            format!("`{}` of two equal values, {}", f.name(), r(k.args[0]))
        }
        Some(Fun::Atan2) => "`atan2(0, 0)`".to_string(),
        Some(f) => format!("`{}` at {}", f.name(), r(k.args[0])),
        None => format!("`{}^{}`", r(k.args[0]), r(k.args[1])),
    }
}

/// Plan start → via points (`params.via_deg`) → goal on `model`, one
/// segment of `segment_time` each (states in radians where declared
/// angles, as the scenario layer hands them over).
pub fn plan(
    model: &Declared,
    start: &State,
    goal: &State,
    params: &EndogenousParams,
    limits: &Limits,
) -> Result<Plan, PlanError> {
    let (n, m) = (model.state_names().len(), model.input_names().len());
    let angles = model.angular_states();
    let mut targets: Vec<Vec<f64>> = Vec::new();
    for (k, v) in params.via_deg.iter().enumerate() {
        if v.len() != n || v.iter().any(|x| !x.is_finite()) {
            return Err(PlanError::InvalidParameter {
                name: "via_deg".into(),
                reason: format!(
                    "via point {k} needs {n} finite numbers, one per state ({}; angles in degrees)",
                    model.state_names().join(", ")
                ),
            });
        }
        let via = v.iter().enumerate().map(|(i, x)| {
            if angles.contains(&i) {
                x.to_radians()
            } else {
                *x
            }
        });
        targets.push(via.collect());
    }
    targets.push(goal.as_slice().to_vec());
    if !limits.max_rate.is_empty() && limits.max_rate.len() != m {
        return Err(PlanError::InvalidParameter {
            name: "limits.max_rate".into(),
            reason: format!("needs one entry per input ({m})"),
        });
    }
    let start = start.as_slice();
    let sol = match (n, m) {
        (3, 2) => endogenous::solve(&AtSize::<3, 2>(model), start, &targets, params),
        (4, 2) => endogenous::solve(&AtSize::<4, 2>(model), start, &targets, params),
        (5, 2) => endogenous::solve(&AtSize::<5, 2>(model), start, &targets, params),
        _ => endogenous::solve(model, start, &targets, params),
    }?;
    endogenous::check_rate_limits(&sol, params, limits, model.input_names(), "")?;
    Ok(endogenous::into_plan(
        sol,
        params,
        m,
        serde_json::json!({ "model": "declared" }),
    ))
}
