//! Unit and property tests of `planner::rover_primitives`.

use crate::integrate::{simulate, Trajectory};
use crate::model::KinematicModel;
use crate::robots::rover::kinematics::SwitchingSignal;
use crate::robots::rover::primitives::*;
use proptest::prelude::*;

const DT: f64 = 0.01;

fn limits() -> Limits {
    Limits {
        max_rate: vec![],
        ramp: 0.0,
        step: DT,
    }
}

fn st(v: &[f64]) -> State {
    State::from_row_slice(v)
}

fn rover(signal: SwitchingSignal) -> SwitchingRover {
    SwitchingRover::new(RoverGeometry::default(), signal)
}

fn telegraph(seed: u64, rate: f64) -> SwitchingRover {
    rover(SwitchingSignal::telegraph(seed, rate, 2000.0).unwrap())
}

fn run(
    model: &SwitchingRover,
    start: &State,
    goal: &State,
    p: &RoverPrimitiveParams,
) -> Trajectory {
    let plan = plan(model, start, goal, p, &limits()).unwrap();
    simulate(model, &plan, start, DT)
}

fn reached(tr: &Trajectory, goal: &State, eps: f64) -> bool {
    se2_distance(tr.last(), goal) <= eps && tr.t.last().unwrap() < &1199.0
}

/// Heading change during P1 and the sign of ψ while P1 drives.
fn p1_turn(tr: &Trajectory) -> (f64, f64) {
    let idx: Vec<usize> = (0..tr.len()).filter(|&k| tr.label[k] == LABEL_P1).collect();
    let (a, b) = (idx[0], *idx.last().unwrap());
    let turned = tr.q[b + 1][2] - tr.q[a][2];
    let psi_sign = tr.q[(a + b) / 2][3].signum();
    (turned, psi_sign)
}

fn paper_start() -> State {
    st(&[0.0, 0.0, PI / 2.0, 0.0])
}

#[test]
fn default_gains_stabilise_both_models() {
    let p = RoverPrimitiveParams::default();
    let m = p2_routh_margins(&RoverGeometry::default(), p.speed, p.k1, p.k2, p.k3);
    assert!(m[0] > 0.0 && m[1] > 0.0, "{m:?}");
    // The gains must be able to fail the check.
    let m = p2_routh_margins(&RoverGeometry::default(), p.speed, 5.0, p.k2, 0.05);
    assert!(m[0] < 0.0);
}

/// A common quadratic Lyapunov function for both linearisations (stability under arbitrary
/// switching, which per-model Hurwitz alone does not give): P solves A_aᵀP + PA_a = −I and
/// must also make A_bᵀP + PA_b negative definite.
#[test]
fn common_quadratic_lyapunov_function() {
    use nalgebra::{Matrix3, SymmetricEigen};
    let p = RoverPrimitiveParams::default();
    let g = RoverGeometry::default();
    let a_of = |s: Sigma| {
        let big_l = g.wheelbase(s);
        let rho = if s == Sigma::B {
            g.r / (g.l + g.r)
        } else {
            0.0
        };
        let k = p.speed;
        Matrix3::new(0.0, k, k * rho, 0.0, 0.0, k / big_l, -p.k1, -p.k2, -p.k3)
    };
    let (aa, ab) = (a_of(Sigma::A), a_of(Sigma::B));
    // Solve the Lyapunov equation by vectorisation: (I⊗Aᵀ + Aᵀ⊗I) vec(P) = −vec(I).
    let at = aa.transpose();
    let mut big = nalgebra::DMatrix::<f64>::zeros(9, 9);
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                // (AᵀP)_{ij} = Σ_k Aᵀ_{ik} P_{kj};  (PA)_{ij} = Σ_k P_{ik} A_{kj}.
                big[(i + 3 * j, k + 3 * j)] += at[(i, k)];
                big[(i + 3 * j, i + 3 * k)] += aa[(k, j)];
            }
        }
    }
    let rhs = nalgebra::DVector::from_fn(9, |r, _| if r % 4 == 0 { -1.0 } else { 0.0 });
    let v = big.lu().solve(&rhs).unwrap();
    let pm = Matrix3::from_fn(|i, j| v[i + 3 * j]);
    let pm = (pm + pm.transpose()) * 0.5;
    assert!(SymmetricEigen::new(pm).eigenvalues.min() > 0.0);
    let qa = aa.transpose() * pm + pm * aa;
    let qb = ab.transpose() * pm + pm * ab;
    assert!(SymmetricEigen::new(qa).eigenvalues.max() < 0.0);
    assert!(SymmetricEigen::new(qb).eigenvalues.max() < 0.0, "{qb}");
}

/// The seed's task (0, 0, π/2) → (8, 2, π/2), ε = 0.1, for 100 telegraph σ seeds with rates
/// from 0.05 to 20 switches/s. To keep the suite fast this test integrates with dt = 0.025 s
/// (two RK4 steps per 0.05 s control period; the other tests use 0.01 s).
#[test]
fn paper_task_reached_for_100_switching_seeds() {
    let goal = st(&[8.0, 2.0, PI / 2.0]);
    let p = RoverPrimitiveParams::default();
    let handles: Vec<_> = (0..2u64)
        .map(|half| {
            let (goal, p) = (goal.clone(), p.clone());
            std::thread::spawn(move || {
                let mut worst: f64 = 0.0;
                for seed in (half * 50)..(half * 50 + 50) {
                    let rate = 0.05 * 400f64.powf(seed as f64 / 99.0);
                    let m = telegraph(seed, rate);
                    let pl = plan(&m, &paper_start(), &goal, &p, &limits()).unwrap();
                    let tr = simulate(&m, &pl, &paper_start(), 0.025);
                    assert!(
                        reached(&tr, &goal, 0.1),
                        "seed {seed}: {}",
                        se2_distance(tr.last(), &goal)
                    );
                    worst = worst.max(*tr.t.last().unwrap());
                }
                worst
            })
        })
        .collect();
    for h in handles {
        let worst = h.join().unwrap();
        assert!(worst < 600.0, "slowest run {worst} s");
    }
}

/// Fig. 2 narrative: turning always left, the rover turns 11π/6 ≈ "nearly 2π" rad on the seed's
/// task but only π/6 on the mirrored goal (−8, 2, π/2), which therefore finishes faster.
/// The shortest-way rule turns π/6 (right) on the original task too.
#[test]
fn p1_turn_direction_and_paper_speedup() {
    let m = telegraph(42, 1.0);
    let goal = st(&[8.0, 2.0, PI / 2.0]);
    let mirror = st(&[-8.0, 2.0, PI / 2.0]);
    let paper = RoverPrimitiveParams {
        turn: TurnDirection::Left,
        ..Default::default()
    };
    let short = RoverPrimitiveParams::default();

    let tp = run(&m, &paper_start(), &goal, &paper);
    let tpm = run(&m, &paper_start(), &mirror, &paper);
    let ts = run(&m, &paper_start(), &goal, &short);
    let tsm = run(&m, &paper_start(), &mirror, &short);
    for (tr, g) in [(&tp, &goal), (&tpm, &mirror), (&ts, &goal), (&tsm, &mirror)] {
        assert!(reached(tr, g, 0.1));
    }
    // Overshoot of the crossing test is at most one period of turning: k sin(π/6)/l · T.
    let slack = 0.1 * 0.5 / 0.25 * 0.05 + 1e-9;
    let (turn_p, sign_p) = p1_turn(&tp);
    assert!(
        turn_p >= 11.0 * PI / 6.0 && turn_p <= 11.0 * PI / 6.0 + slack,
        "{turn_p}"
    );
    assert_eq!(sign_p, 1.0);
    let (turn_pm, _) = p1_turn(&tpm);
    assert!(
        turn_pm >= PI / 6.0 && turn_pm <= PI / 6.0 + slack,
        "{turn_pm}"
    );
    let (turn_s, sign_s) = p1_turn(&ts);
    assert!(
        -turn_s >= PI / 6.0 && -turn_s <= PI / 6.0 + slack,
        "{turn_s}"
    );
    assert_eq!(sign_s, -1.0);
    let (turn_sm, sign_sm) = p1_turn(&tsm);
    assert!(turn_sm >= PI / 6.0 && turn_sm <= PI / 6.0 + slack && sign_sm == 1.0);

    let time = |tr: &Trajectory| *tr.t.last().unwrap();
    // The seed: the mirrored goal "works much more quickly".
    assert!(
        time(&tpm) + 20.0 < time(&tp),
        "{} vs {}",
        time(&tpm),
        time(&tp)
    );
    // Ours: the original task is the mirror image of the mirrored one (the model is
    // symmetric under ψ → −ψ and both runs see the same σ(t)), so it is just as quick.
    assert!(time(&ts) + 20.0 < time(&tp));
    assert!(
        (time(&ts) - time(&tsm)).abs() < 0.1,
        "{} vs {}",
        time(&ts),
        time(&tsm)
    );
}

/// Under a fixed σ the mirrored task is the exact mirror image: same duration.
#[test]
fn mirror_symmetry_under_fixed_sigma() {
    let m = rover(SwitchingSignal::FixedB);
    let p = RoverPrimitiveParams::default();
    let a = run(&m, &paper_start(), &st(&[8.0, 2.0, PI / 2.0]), &p);
    let b = run(&m, &paper_start(), &st(&[-8.0, 2.0, PI / 2.0]), &p);
    assert_eq!(a.len(), b.len());
    let (qa, qb) = (a.last(), b.last());
    assert!((qa[0] + qb[0]).abs() < 1e-6 && (qa[1] - qb[1]).abs() < 1e-6);
}

#[test]
fn goal_behind_is_reached() {
    let p = RoverPrimitiveParams::default();
    let start = st(&[0.0, 0.0, 0.0, 0.0]);
    for (i, goal) in [
        st(&[-3.0, 0.5, 0.0]),
        st(&[-4.0, -1.0, PI]),
        st(&[-2.0, 0.0, 0.0]),
    ]
    .into_iter()
    .enumerate()
    {
        for seed in 0..3 {
            let tr = run(
                &telegraph(100 + seed + 10 * i as u64, 2.0),
                &start,
                &goal,
                &p,
            );
            assert!(
                reached(&tr, &goal, 0.1),
                "goal {goal:?}: {}",
                se2_distance(tr.last(), &goal)
            );
            // P3 really reverses when the goal lies behind along N.
            if i != 1 {
                assert!(tr
                    .u
                    .iter()
                    .zip(&tr.label)
                    .any(|(u, l)| *l == LABEL_P3 && u[0] < 0.0));
            }
        }
    }
}

/// Labels appear in order P1 → P2 → P3 and P3 keeps ψ = 0 while driving.
#[test]
fn primitives_run_in_order() {
    let m = telegraph(5, 3.0);
    let tr = run(
        &m,
        &paper_start(),
        &st(&[8.0, 2.0, PI / 2.0]),
        &RoverPrimitiveParams::default(),
    );
    let mut seen = vec![tr.label[0]];
    for &l in &tr.label {
        if l != *seen.last().unwrap() {
            seen.push(l);
        }
    }
    assert_eq!(seen, vec![LABEL_P1, LABEL_P2, LABEL_P3]);
    for k in 0..tr.len() {
        if tr.label[k] == LABEL_P3 && tr.u[k][0] != 0.0 {
            assert!(tr.q[k][3].abs() < 1e-9);
        }
    }
}

/// The printed P2 stopping rule can end outside ε; the tightened one cannot.
#[test]
fn printed_stop_rule_counterexample() {
    let goal = st(&[0.0, 0.0, 0.0]);
    // d ≈ 0.5 m behind the goal on N's left, heading turned away: |e| < ε/2, d|δ| < ε/2.
    let (e, delta) = (0.049, 0.099);
    let q = st(&[-0.5, e, delta, 0.0]);
    let d = 0.5f64.hypot(e);
    assert!(e < 0.05 && d * delta < 0.05);
    let mut c = PrimitiveController::new(
        RoverPrimitiveParams::default()
            .resolve(&RoverGeometry::default(), &limits())
            .unwrap(),
        [0.0, 0.0, 0.0],
    );
    c.p.stop_rule = StopRule::Printed;
    assert!(c.p2_should_stop(e, delta, d));
    c.p.stop_rule = StopRule::Tightened;
    assert!(!c.p2_should_stop(e, delta, d));
    // Run P3 from there: closest approach stays outside ε.
    let fin = run_p3(&q, &goal);
    assert!(
        se2_distance(&fin, &goal) > 0.13,
        "{}",
        se2_distance(&fin, &goal)
    );
    assert!((se2_distance(&fin, &goal) - p3_final_error(&q, &goal)).abs() < 1e-9);
}

/// Runs only P3 (steer straight in place, drive to closest approach) on σ = a.
fn run_p3(q: &State, goal: &State) -> State {
    let geom = RoverGeometry::default();
    let p = RoverPrimitiveParams {
        epsilon: 1e-6,
        ..Default::default()
    };
    let mut c = PrimitiveController::new(
        p.resolve(&geom, &limits()).unwrap(),
        [goal[0], goal[1], goal[2]],
    );
    c.phase = Phase::P3Steer;
    let m = rover(SwitchingSignal::FixedA);
    let mut q = q.clone();
    let mut t = 0.0;
    while c.phase != Phase::Finished && t < 1000.0 {
        let u = c.command(t, &q).u;
        for _ in 0..5 {
            let mut f = |s: f64, x: &State| m.velocity(s, x, &u);
            q = crate::integrate::rk4_step(&mut f, t, &q, DT);
            t += DT;
        }
    }
    q
}

proptest! {
    #![proptest_config(crate::prop_config::config(48))]
    /// Any pose meeting the tightened rule ends within ε after P3 (bound ≈ 0.56 ε).
    #[test]
    fn tightened_stop_rule_guarantees_epsilon(
        s in -20.0..20.0f64, ue in -1.0..1.0f64, ud in -1.0..1.0f64, psi in -0.5..0.5f64,
    ) {
        let eps = 0.1;
        let e = ue * eps / 4.0;
        let d = s.hypot(e);
        let delta = ud * eps / (4.0 * d.max(1.0));
        let goal = st(&[1.0, -2.0, 0.7]);
        let (sf, cf) = 0.7f64.sin_cos();
        let q = st(&[1.0 + cf * s - sf * e, -2.0 + sf * s + cf * e, 0.7 + delta, psi]);
        let fin = run_p3(&q, &goal);
        prop_assert!(se2_distance(&fin, &goal) <= 0.5591 * eps);
    }
}

proptest! {
    #![proptest_config(crate::prop_config::config(12))]
    /// Lemma 4.1 (completeness): random start/goal pairs within 6 m are reached under a
    /// random telegraph σ.
    #[test]
    fn random_tasks_reached(
        x0 in -3.0..3.0f64, y0 in -3.0..3.0f64, th0 in -PI..PI, psi0 in -0.5..0.5f64,
        xf in -3.0..3.0f64, yf in -3.0..3.0f64, thf in -PI..PI, seed in 0u64..1000,
        rate in 0.1..10.0f64,
    ) {
        let (start, goal) = (st(&[x0, y0, th0, psi0]), st(&[xf, yf, thf]));
        let tr = run(&telegraph(seed, rate), &start, &goal, &RoverPrimitiveParams::default());
        prop_assert!(reached(&tr, &goal, 0.1), "{}", se2_distance(tr.last(), &goal));
    }
}

#[test]
fn invalid_parameters_are_rejected() {
    let m = rover(SwitchingSignal::FixedA);
    let (s, g) = (st(&[0.0, 0.0, 0.0, 0.0]), st(&[1.0, 1.0, 0.0]));
    let cases = [
        RoverPrimitiveParams {
            speed: 0.0,
            ..Default::default()
        },
        RoverPrimitiveParams {
            k1: f64::NAN,
            ..Default::default()
        },
        RoverPrimitiveParams {
            approach_deg: 95.0,
            ..Default::default()
        },
        RoverPrimitiveParams {
            p1_wheel_deg: 50.0,
            ..Default::default()
        },
        RoverPrimitiveParams {
            k1: 5.0,
            k3: 0.05,
            ..Default::default()
        },
        RoverPrimitiveParams {
            period: -1.0,
            ..Default::default()
        },
    ];
    for c in cases {
        assert!(matches!(
            plan(&m, &s, &g, &c, &limits()),
            Err(PlanError::InvalidParameter { .. })
        ));
    }
    let slow = Limits {
        max_rate: vec![0.05, 1.0],
        ramp: 0.0,
        step: DT,
    };
    assert!(plan(&m, &s, &g, &RoverPrimitiveParams::default(), &slow).is_err());
    assert!(plan(
        &m,
        &st(&[0.0, 0.0, 0.0]),
        &g,
        &RoverPrimitiveParams::default(),
        &limits()
    )
    .is_err());
    let json = r#"{"speed": 0.1, "bogus": 1}"#;
    assert!(serde_json::from_str::<RoverPrimitiveParams>(json).is_err());
    let json = r#"{"turn": "left", "stop_rule": "printed"}"#;
    let p: RoverPrimitiveParams = serde_json::from_str(json).unwrap();
    assert_eq!(
        (p.turn, p.stop_rule),
        (TurnDirection::Left, StopRule::Printed)
    );
}

#[test]
fn details_report_the_p1_choice() {
    let m = rover(SwitchingSignal::FixedA);
    let goal = st(&[8.0, 2.0, PI / 2.0]);
    let paper = RoverPrimitiveParams {
        turn: TurnDirection::Left,
        ..Default::default()
    };
    let pl = plan(&m, &paper_start(), &goal, &paper, &limits()).unwrap();
    assert_eq!(pl.details["p1_direction"], "left");
    let turn = pl.details["p1_turn_rad"].as_f64().unwrap();
    assert!((turn - 11.0 * PI / 6.0).abs() < 1e-12);
    // N = (8, s): the start is 8 m left of N and the approach heading is π/3.
    assert!((pl.details["start_goal_frame"]["lateral"].as_f64().unwrap() - 8.0).abs() < 1e-12);
    assert!((pl.details["p1_target_heading_rad"].as_f64().unwrap() - PI / 3.0).abs() < 1e-12);
    let pl = plan(
        &m,
        &paper_start(),
        &goal,
        &RoverPrimitiveParams::default(),
        &limits(),
    )
    .unwrap();
    assert_eq!(pl.details["p1_direction"], "right");
    assert_eq!(pl.labels, vec!["P1", "P2", "P3"]);
}
