//! Unit tests of the endogenous planner on seed 001's space manipulator
//! (basis, Jacobian, pseudo-inverse, the three scenarios of §5, parameter
//! checks).
use crate::integrate::simulate;
use crate::model::State;
use crate::plan::{Limits, Plan};
use crate::planner::endogenous::integrator::Integrator;
use crate::planner::endogenous::solver::{constraint_rows, null_space};
use crate::planner::endogenous::*;
use crate::planner::PlanError;
use crate::robots::space_robot::manipulator::SpaceManipulator;
use crate::robots::space_robot::manipulator::SpaceManipulatorParams;
use crate::robots::space_robot::plan_endogenous as plan;
use nalgebra::Vector3;
use nalgebra::{DMatrix, DVector};
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
        let mut integ = Integrator::new(Fixed::<3, 2>, T, 100, &terms);
        let mut jac = DMatrix::zeros(3, s);
        let q_end = integ.run(&model, q0().as_slice(), &lambda, Some(&mut jac));
        let q_plain = integ.run(&model, q0().as_slice(), &lambda, None);
        assert_eq!(q_end, q_plain);
        let h = 1e-6;
        for j in 0..s {
            let (mut lp, mut lm) = (lambda.clone(), lambda.clone());
            lp[j] += h;
            lm[j] -= h;
            let fd = (DVector::from_vec(integ.run(&model, q0().as_slice(), &lp, None))
                - DVector::from_vec(integ.run(&model, q0().as_slice(), &lm, None)))
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
    let mut integ = Integrator::new(Fixed::<3, 2>, T, 50, &terms);
    let mut jac = DMatrix::zeros(3, 16);
    integ.run(&model, q0().as_slice(), &[0.0; 16], Some(&mut jac));
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
    let mut integ = Integrator::new(Fixed::<3, 2>, T, 100, &terms);
    let mut jac = DMatrix::zeros(3, 14);
    integ.run(&model, q0().as_slice(), &lambda, Some(&mut jac));
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
    let sol = solve(
        &model,
        q0().as_slice(),
        &[y1().as_slice().to_vec(), yf().as_slice().to_vec()],
        &params,
    )
    .unwrap();
    let plan = into_plan(sol.clone(), &params, 2, serde_json::Value::Null);
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
    let sol = solve(
        &SpaceManipulator::default(),
        q0().as_slice(),
        &[y1().as_slice().to_vec()],
        &params,
    )
    .unwrap();
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
    let sol = solve(
        &model,
        q0().as_slice(),
        &[y1().as_slice().to_vec()],
        &params,
    )
    .unwrap();
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
    let free = solve(
        &model,
        q0().as_slice(),
        &[yf().as_slice().to_vec()],
        &params,
    )
    .unwrap();
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
    match solve(
        &model,
        q0().as_slice(),
        &[yf().as_slice().to_vec()],
        &capped,
    ) {
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
    let sol = solve(
        &model,
        q0().as_slice(),
        &[yf().as_slice().to_vec()],
        &enough,
    )
    .unwrap();
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
