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
//! The planner knows a system only through [`EndogenousSystem`] (q' = f(q,
//! u) with A = ∂f/∂q and B = ∂f/∂u): each robot implements it next to its
//! model, the space manipulator in `systems::space_robot` (analytic), a
//! declared model in `robots::declared::plan` (automatic differentiation).
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

use crate::model::Input;
use crate::plan::{ControlLaw, Limits, Plan, Segment};
use crate::planner::PlanError;
use std::sync::Arc;

mod expansion;
pub(crate) mod integrator;
mod params;
pub(crate) mod solver;

pub use expansion::{legendre, ControlExpansion};
pub use integrator::{Dims, EndogenousSystem, Fixed, Linearization, Sizes};
pub use params::{Continuity, ControlConstraint, ControlPoint, EndogenousParams, Order};
pub use solver::{extended_step, pinv_solve, SegmentReport, Solution};

use params::Settings;
use solver::{solve_segment, MAX_RK4_STEPS};

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

fn validate(p: &EndogenousParams, n: usize, m: usize) -> Result<(), PlanError> {
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
                format!(
                    "must be positive and finite, got {}",
                    crate::numfmt::readable(v)
                ),
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
        if v.len() != n || v.iter().any(|x| !x.is_finite()) {
            return Err(invalid(
                "via_deg",
                format!("via point {i} needs {n} finite entries"),
            ));
        }
    }
    check_vec("u_start", &p.u_start, m)?;
    check_vec("du_start", &p.du_start, m)?;
    check_vec("u_end", &p.u_end, m)?;
    check_vec("du_end", &p.du_end, m)?;
    let total = p.segment_time * (p.via_deg.len() + 1) as f64;
    for cp in &p.control_points {
        if !(cp.time.is_finite() && (0.0..=total).contains(&cp.time)) {
            return Err(invalid(
                "control_points",
                format!(
                    "time {} outside [0, {}]",
                    crate::numfmt::readable(cp.time),
                    crate::numfmt::readable(total)
                ),
            ));
        }
        check_vec("control_points.value", &cp.value, m)?;
        check_vec("control_points.derivative", &cp.derivative, m)?;
    }
    Ok(())
}

/// Plans q0 → targets\[0\] at T → targets\[1\] at 2T → … for any system
/// (states in the system's units).
pub fn solve<S: EndogenousSystem>(
    sys: &S,
    start: &[f64],
    targets: &[Vec<f64>],
    params: &EndogenousParams,
) -> Result<Solution, PlanError> {
    let (n, m) = (sys.dims().n(), sys.dims().m());
    validate(params, n, m)?;
    if targets.is_empty() {
        return Err(invalid("goal", "at least one target is needed"));
    }
    if let Some(bad) = std::iter::once(start)
        .chain(targets.iter().map(Vec::as_slice))
        .find(|v| v.len() != n || v.iter().any(|x| !x.is_finite()))
    {
        return Err(invalid(
            "goal",
            format!(
                "start and targets need {n} finite coordinates, got {}",
                bad.len()
            ),
        ));
    }
    let t_seg = params.segment_time;
    let terms = vec![params.basis_terms; m];
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
    let mut q = start.to_vec();
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
        if n + cons.len() * m > s {
            return Err(invalid(
                "basis_terms",
                format!(
                    "{label}: {} task + {} constraint rows exceed the {s} parameters; raise basis_terms",
                    n,
                    cons.len() * m
                ),
            ));
        }
        let out = solve_segment(sys, &q, target, t_seg, &terms, cons, &set, &label)?;
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

/// Peak |u_i| of a solution's `m` inputs, sampled at the RK4 nodes of
/// `steps` per segment.
pub(crate) fn peak_rate(sol: &Solution, steps: usize, m: usize) -> Vec<f64> {
    let mut peak = vec![0.0f64; m];
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

/// `Unreachable` when `enforce_rate_limits` is set and a planned |u_i|
/// peaks above `limits.max_rate[i]` (`inputs` names them, `unit` their unit).
pub(crate) fn check_rate_limits(
    sol: &Solution,
    params: &EndogenousParams,
    limits: &Limits,
    inputs: &[&str],
    unit: &str,
) -> Result<(), PlanError> {
    if !params.enforce_rate_limits {
        return Ok(());
    }
    let peak = peak_rate(sol, params.rk4_steps, inputs.len());
    for ((p, lim), name) in peak.iter().zip(&limits.max_rate).zip(inputs) {
        if p > lim {
            return Err(PlanError::Unreachable(format!(
                "planned |{name}| peaks at {p:.4}{unit} above the rate limit {lim:.4}; lengthen segment_time"
            )));
        }
    }
    Ok(())
}

/// Wraps a solution for `m` inputs into an open-loop [`Plan`] (labels
/// "segment 1", …).
pub(crate) fn into_plan(
    sol: Solution,
    params: &EndogenousParams,
    m: usize,
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
        "parameters_per_segment": params.basis_terms * m,
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
        "peak_rate": peak_rate(&sol, params.rk4_steps, m),
        "extra": extra,
    });
    let sol = Arc::new(sol);
    let law = ControlLaw::OpenLoop(Arc::new(move |t: f64| {
        if !(-1e-9..=duration + 1e-9).contains(&t) {
            return (Input::zeros(m), if t < 0.0 { 0 } else { n - 1 });
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
