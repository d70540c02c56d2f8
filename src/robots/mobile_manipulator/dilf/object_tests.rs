//! Tests of `object.rs`.

use super::*;
use crate::robots::mobile_manipulator::beam::GFRP_ROD_10MM;
use crate::robots::mobile_manipulator::dilf::potential::tests::{
    assert_field_is_scaled_gradient, assert_field_is_scaled_gradient_at,
};
use crate::robots::mobile_manipulator::dilf::potential::{
    GoalFrame, PotentialParams, Scene, SingularityEnclosure,
};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

fn beam() -> Beam {
    let (material, section) = GFRP_ROD_10MM;
    Beam {
        material,
        section,
        length: 1.0,
    }
}

fn carried(q: &[f64], q_max: f64) -> Carried {
    Carried::at_rest(&beam(), None, q, q_max, 8, 0.02).unwrap()
}

pub(crate) fn scene(q0: &[f64], goal: Vec<f64>, q_max: f64) -> Scene {
    Scene::new(
        2,
        mm::default_parts(),
        Vec::new(),
        goal,
        PotentialParams {
            lambda: 1.0,
            kv: 3.0,
            goal_frame: GoalFrame::Platform,
            dipole: Default::default(),
            singularity: SingularityEnclosure::default(),
            field_power: 2.0,
        },
    )
    .unwrap()
    .with_object(carried(q0, q_max))
}

pub(crate) fn perturbed(q: &[f64], rng: &mut ChaCha8Rng, size: f64) -> Vec<f64> {
    q.iter()
        .map(|x| x + rng.random_range(-size..size))
        .collect()
}

#[test]
fn at_rest_only_gravity_deforms_the_beam() {
    let q = table_i_start();
    let c = carried(&q, 4.0);
    let st = c.state(&q);
    // q_s (node 2) vanishes: the grasps hold the beam straight.
    for x in &st.q_f[..6] {
        assert!(x.abs() < 1e-9, "{:?}", st.q_f);
    }
    // Node 1 sags under its weight: clamped–clamped w L⁴ / (384 E I).
    let b = c.fe.beam();
    let w = b.mass_per_length() * 9.81;
    let sag = w * b.length.powi(4) / (384.0 * b.bending_stiffness());
    let z_world = spatial::mul_mv(&st.end0.r, [st.q_f[6], st.q_f[7], st.q_f[8]])[2];
    assert!(
        (z_world + sag).abs() < 1e-6 * sag.max(1.0),
        "sag {z_world} vs {sag}"
    );
    // A wrong rest length is refused.
    let err = Carried::at_rest(&beam(), Some(3.0), &q, 4.0, 4, 0.03).unwrap_err();
    assert!(err.to_string().contains("cannot hold"), "{err}");
}

/// q_f depends only on the grasps' relative pose: moving and turning both
/// platforms together (a rigid motion of the whole system) leaves it.
#[test]
fn deformation_is_invariant_under_a_common_rigid_motion() {
    let q0 = table_i_start();
    let c = carried(&q0, 4.0);
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    for _ in 0..20 {
        let q = perturbed(&q0, &mut rng, 0.2);
        let (dx, dy, a) = (
            rng.random_range(-5.0..5.0),
            rng.random_range(-5.0..5.0),
            rng.random_range(-PI..PI),
        );
        let mut moved = q.clone();
        for r in 0..2 {
            let (x, y) = (q[DOF * r], q[DOF * r + 1]);
            moved[DOF * r] = a.cos() * x - a.sin() * y + dx;
            moved[DOF * r + 1] = a.sin() * x + a.cos() * y + dy;
            moved[DOF * r + 2] += a;
        }
        let (s0, s1) = (c.state(&q), c.state(&moved));
        for (u, v) in s0.q_f.iter().zip(&s1.q_f) {
            assert!((u - v).abs() < 1e-9, "{:?} vs {:?}", s0.q_f, s1.q_f);
        }
    }
}

#[test]
fn v_with_the_beam_has_exact_gradients() {
    let q0 = table_i_start();
    let mut goal = q0.clone();
    goal[0] += 2.0;
    goal[DOF] += 2.0;
    let s = scene(&q0, goal, 1.0);
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut checked = 0;
    while checked < 8 {
        let q = perturbed(&q0, &mut rng, 0.15);
        let e = s.evaluate::<f64>(&q, &mut s.warm()).unwrap();
        if !(e.v > 0.0 && e.min_beta > 0.02) {
            continue;
        }
        checked += 1;
        let what = format!("pair with beam, sample {checked}");
        assert_field_is_scaled_gradient(&s, &q, 1e-5, &what);
    }
}

/// The default compliant wrist of `[model.wrist]` (400 N/m, 50 N m/rad).
fn soft_wrist() -> Wrist {
    Wrist::Compliant(
        crate::robots::mobile_manipulator::kinematics::CompliantWrist {
            stiffness: [400.0, 400.0, 400.0, 50.0, 50.0, 50.0],
            damping: [25.0, 25.0, 25.0, 2.0, 2.0, 2.0],
            travel: [0.2, 0.2, 0.2, 0.35, 0.35, 0.35],
        },
    )
}

/// The wrench bound (b_f from the grasp wrenches of the carried chain's
/// statics), with rigid and with compliant wrists: the law's field is
/// V's gradient (central differences), and so is ln b_f's dual-number
/// derivative along random directions, on random admissible
/// configurations near Table I's start.
#[test]
fn the_wrench_bound_has_exact_gradients() {
    use num_dual::Dual64 as Dual;
    let (q0, goal) = table_i_start_and_goal_ahead();
    let bound = Bound::Wrench {
        force: 60.0,
        moment: 8.0,
    };
    // Step h of the central differences per wrist. With rigid wrists a
    // tenth of a millimetre of grasp distance is tens of newtons, so ln
    // b_f and V are steep in q: on sample 1 ln b_f's central difference
    // at h = 1e-5, 3e-6, 1e-6, 1e-7 is 2445.5, 2436.3, 2435.46, 2435.36
    // against the dual number's 2435.36, and on sample 4 dV/dx's at h =
    // 1e-6, 1e-7, 1e-8 is -2432.4, -2413.24, -2413.061 against the
    // field's -2413.059: the h² truncation term shrinking 100x per
    // decade down to 1e-8 (no round-off floor yet), so rigid wrists use
    // h = 1e-8. The compliant wrists
    // take the stretch in series and are smooth at 1e-6. Both
    // differences are Richardson-extrapolated from h/2 and h.
    for (wrist, size, h) in [(Wrist::Rigid, 0.002, 1e-8), (soft_wrist(), 0.05, 1e-6)] {
        let mut s = scene(&q0, goal.clone(), 1.0);
        let c = s.object.take().unwrap().with_grasps(bound, wrist).unwrap();
        s = s.with_object(c);
        let c = s.object.as_ref().unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(29);
        let (mut checked, mut tries) = (0, 0);
        while checked < 6 {
            tries += 1;
            assert!(tries < 2000, "{wrist:?}: no admissible sample");
            let q = perturbed(&q0, &mut rng, size);
            let e = s.evaluate::<f64>(&q, &mut s.warm()).unwrap();
            let st = c.state(&q);
            // Well inside the set, where b_f is smooth at h = 1e-6.
            if !(e.v > 0.0 && e.min_beta > 0.02 && c.margin(&st.q_f, &st.gravity) > 0.05) {
                continue;
            }
            checked += 1;
            let what = format!("wrench bound, {wrist:?}, sample {checked}");
            assert_field_is_scaled_gradient_at(&s, &q, 1e-5, h, &what);
            let lnb = |q: &[f64]| {
                let st = c.state(q);
                c.ln_admissible(&st.q_f, &st.gravity).unwrap()
            };
            let dir: Vec<f64> = (0..q.len()).map(|_| rng.random_range(-1.0..1.0)).collect();
            let qd: Vec<Dual> = q.iter().zip(&dir).map(|(x, d)| Dual::new(*x, *d)).collect();
            let std = c.state(&qd);
            let exact = c.ln_admissible(&std.q_f, &std.gravity).unwrap().eps;
            let central = |h: f64| {
                let (qp, qm): (Vec<f64>, Vec<f64>) = q
                    .iter()
                    .zip(&dir)
                    .map(|(x, d)| (x + h * d, x - h * d))
                    .unzip();
                (lnb(&qp) - lnb(&qm)) / (2.0 * h)
            };
            let fd = (4.0 * central(0.5 * h) - central(h)) / 3.0;
            // 1e-5 relative: the Richardson difference at these steps
            // is within 1e-6 of the exact value on every sample.
            assert!(
                (fd - exact).abs() <= 1e-5 * exact.abs().max(1.0),
                "{what}: d ln b_f exact {exact:e}, fd {fd:e}"
            );
        }
    }
}

/// The law on measured grasps: with a fixed correction of each flange
/// (as `grasps = "measured"` applies per sample), the field is still
/// V's gradient.
#[test]
fn the_field_on_measured_grasps_is_the_gradient_of_v() {
    use crate::model::spatial::{rot_x, rot_y};
    let (q0, goal) = table_i_start_and_goal_ahead();
    let bound = Bound::Wrench {
        force: 60.0,
        moment: 8.0,
    };
    let mut s = scene(&q0, goal, 1.0);
    let c = s
        .object
        .take()
        .unwrap()
        .with_grasps(bound, soft_wrist())
        .unwrap();
    s = s.with_object(c);
    // Each flange 1 cm off and tilted by 0.01 rad (a platform rocking on
    // its casters).
    let corr: crate::robots::mobile_manipulator::dilf::potential::GraspCorrection = [
        Pose {
            r: rot_x(0.01),
            p: [0.01, 0.0, -0.005],
        },
        Pose {
            r: rot_y(-0.01),
            p: [0.0, 0.01, 0.005],
        },
    ];
    let (e, f) = s.field_with(&q0, Some(&corr), &mut s.warm()).unwrap();
    let dp = e.d.powf(s.params.field_power);
    let v = |q: &[f64]| {
        s.evaluate_with::<f64>(q, Some(&corr), &mut s.warm())
            .unwrap()
            .v
    };
    let scale = f.iter().map(|x| x.abs()).fold(0.0, f64::max) / dp;
    for i in 0..q0.len() {
        let central = |h: f64| {
            let (mut qp, mut qm) = (q0.clone(), q0.clone());
            qp[i] += h;
            qm[i] -= h;
            (v(&qp) - v(&qm)) / (2.0 * h)
        };
        let fd = (4.0 * central(5e-7) - central(1e-6)) / 3.0;
        let exact = f[i] / dp;
        assert!(
            (fd - exact).abs() <= 1e-5 * scale.max(exact.abs()),
            "coord {i}: exact {exact:e}, fd {fd:e}"
        );
    }
    // The correction matters: V differs from the unmeasured one.
    let plain = s.evaluate::<f64>(&q0, &mut s.warm()).unwrap().v;
    assert!((plain - e.v).abs() > 1e-6 * plain, "{plain} vs {}", e.v);
}

/// b_f (Eq. 12): V vanishes exactly when a node leaves its ball, and the
/// start/goal check refuses such a configuration.
#[test]
fn overstraining_the_beam_zeroes_v() {
    let (q0, goal) = table_i_start_and_goal_ahead();
    let s = scene(&q0, goal, 0.5);
    let mut q = q0.clone();
    let mut last_v = f64::INFINITY;
    // Pull robot 2 away along the beam: q_s grows by the same amount.
    for step in 1..=12 {
        q[DOF + 1] = q0[DOF + 1];
        q[DOF] = q0[DOF] + 0.05 * step as f64;
        let e = s.evaluate::<f64>(&q, &mut s.warm()).unwrap();
        let stretch = grasp_distance(&q) - grasp_distance(&q0);
        if e.overstrained() {
            assert_eq!(e.v, 0.0);
            assert!(
                e.max_deformation > 0.5 / 3f64.sqrt(),
                "{}",
                e.max_deformation
            );
            let err = crate::robots::mobile_manipulator::dilf::check_configuration(&s, &q, "goal")
                .unwrap_err();
            assert!(err.to_string().contains("beyond its bound"), "{err}");
            return;
        }
        assert!(
            stretch < 0.5 + 1e-9,
            "stretched {stretch} m and still admissible"
        );
        assert!(e.v > 0.0 && e.v.is_finite());
        last_v = e.v;
    }
    panic!("never overstrained (last V {last_v})");
}

/// The pair carries the beam 2 m forward (a rigid motion of the
/// formation, so the goal leaves the beam straight). The ideal run (RK4
/// on the kinematic model, independent of the potential's code) keeps
/// ‖q_f‖∞ within q_F and every pair apart at every sample, and closes
/// most of the distance within 40 s (convergence is asymptotic).
#[test]
fn the_pair_carries_the_beam_forward_within_its_bound() {
    use crate::model::State;
    use crate::robots::mobile_manipulator::dilf::{self, DilfParams};
    use crate::robots::mobile_manipulator::kinematics::MobileManipulator;
    let (q0, goal) = table_i_start_and_goal_ahead();
    let q_max = 0.3;
    let s = std::sync::Arc::new(scene(&q0, goal.clone(), q_max));
    let params: DilfParams = toml::from_str(
        "field_power = 1.75\nhorizon = 40.0\nka = [50.0, 50.0, 50.0, 300.0, 300.0, 3000.0]",
    )
    .unwrap();
    let plan = dilf::plan(s.clone(), &State::from_vec(q0.clone()), &params, 0.004).unwrap();
    let model = MobileManipulator { robots: 2 };
    let tr = crate::integrate::simulate(&model, &plan, &State::from_vec(q0.clone()), 0.01);
    let dist = |q: &[f64]| {
        (0..2)
            .map(|r| (q[DOF * r] - goal[DOF * r]).hypot(q[DOF * r + 1] - goal[DOF * r + 1]))
            .fold(0.0, f64::max)
    };
    let c = s.object.as_ref().unwrap();
    for (q, t) in tr.q.iter().zip(&tr.t).step_by(10) {
        let q = q.as_slice();
        let st = c.state(q);
        assert!(
            st.max_deformation() < q_max,
            "t = {t}: ‖q_f‖∞ = {}",
            st.max_deformation()
        );
        let e = s.evaluate::<f64>(q, &mut s.warm()).unwrap();
        assert!(e.min_beta > 0.0, "t = {t}: contact");
    }
    let end = tr.q.last().unwrap().as_slice();
    assert!(
        dist(end) < 0.1 * dist(&q0),
        "{} of {} m left",
        dist(end),
        dist(&q0)
    );
}
