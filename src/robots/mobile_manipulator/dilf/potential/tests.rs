//! Tests of [`crate::robots::mobile_manipulator::dilf::potential`]: the gradient against central differences, V at the
//! goal and on obstacle boundaries; and the room-corner scene and field
//! checks that other modules' tests share.

use crate::robots::mobile_manipulator::dilf::potential::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A room corner: a wall with a door gap and a table, box-like (n = 4).
pub(crate) fn scene(robots: usize, goal_frame: GoalFrame) -> Scene {
    let wall = |name: &str, c: [f64; 3], s: [f64; 3]| Obstacle {
        name: name.into(),
        shape: Superellipsoid {
            center: c,
            semi_axes: s,
            exponent: 4.0,
            rpy: [0.0; 3],
        }
        .at_rest(),
    };
    let obstacles = vec![
        wall("wall_left", [0.0, 3.0, 1.25], [0.1, 2.2, 1.25]),
        wall("wall_right", [0.0, -3.0, 1.25], [0.1, 2.2, 1.25]),
        wall("table", [3.0, 0.0, 0.35], [0.6, 0.4, 0.35]),
    ];
    let mut goal = vec![3.2, 2.0, 0.3, 0.4, -1.2, 2.2, 0.1, -0.6, 0.3];
    if robots == 2 {
        goal.extend([3.0, -2.0, -0.2, -0.5, -1.4, 2.0, 0.0, -0.5, 0.1]);
    }
    Scene::new(
        robots,
        mm::default_parts(),
        obstacles,
        goal,
        PotentialParams {
            lambda: 1.0,
            kv: 3.0,
            goal_frame,
            dipole: Default::default(),
            singularity: SingularityEnclosure::default(),
            field_power: 2.0,
        },
    )
    .unwrap()
}

/// A random collision-free configuration in front of the wall.
pub(crate) fn random_q(s: &Scene, rng: &mut ChaCha8Rng) -> Vec<f64> {
    loop {
        let mut q = Vec::new();
        for r in 0..s.robots {
            let y0 = if r == 0 { 1.0 } else { -1.0 };
            q.extend([
                rng.random_range(-4.0..-1.2),
                y0 + rng.random_range(-1.0..1.0),
                rng.random_range(-3.1..3.1),
                rng.random_range(-2.5..2.5),
                rng.random_range(-2.0..-0.6),
                rng.random_range(1.6..2.8),
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.2..-0.3),
                rng.random_range(-1.5..1.5),
            ]);
        }
        let e = s.evaluate::<f64>(&q, &mut s.warm()).unwrap();
        if e.min_beta > 0.05 && e.min_singular > 0.0 && e.v > 0.0 {
            return q;
        }
    }
}

#[test]
fn gradient_matches_central_differences() {
    for (robots, frame) in [
        (1, GoalFrame::Platform),
        (1, GoalFrame::World),
        (2, GoalFrame::Platform),
    ] {
        let s = scene(robots, frame);
        let mut rng = ChaCha8Rng::seed_from_u64(40 + robots as u64);
        for trial in 0..12 {
            let q = random_q(&s, &mut rng);
            let what = format!("k={robots} {frame:?} trial {trial}");
            assert_field_is_scaled_gradient(&s, &q, 1e-6, &what);
        }
    }
}

/// f / D^p at q against central differences of V (relative to the
/// largest component), Richardson-extrapolated: near a robot's dipole
/// plane (γ_r → 0) the pair's (γ1 γ2)^{1/2} curves so fast that plain
/// central differences at h = 1e-6 are off by 1e-5 (h → 1e-8 converges
/// to the exact value there).
pub(crate) fn assert_field_is_scaled_gradient(s: &Scene, q: &[f64], rel: f64, what: &str) {
    assert_field_is_scaled_gradient_at(s, q, rel, 1e-6, what);
}

/// As [`assert_field_is_scaled_gradient`], Richardson from steps h/2 and h.
pub(crate) fn assert_field_is_scaled_gradient_at(
    s: &Scene,
    q: &[f64],
    rel: f64,
    h: f64,
    what: &str,
) {
    let (e, f) = s.field(q, &mut s.warm()).unwrap();
    let dp = e.d.powf(s.params.field_power);
    let v = |q: &[f64]| s.evaluate::<f64>(q, &mut s.warm()).unwrap().v;
    let scale = f.iter().map(|x| x.abs()).fold(0.0, f64::max) / dp;
    for i in 0..q.len() {
        let central = |h: f64| {
            let (mut qp, mut qm) = (q.to_vec(), q.to_vec());
            qp[i] += h;
            qm[i] -= h;
            (v(&qp) - v(&qm)) / (2.0 * h)
        };
        let fd = (4.0 * central(0.5 * h) - central(h)) / 3.0;
        let exact = f[i] / dp;
        assert!(
            (fd - exact).abs() <= rel * scale.max(exact.abs()),
            "{what} coord {i}: exact {exact:e}, fd {fd:e}"
        );
    }
}

/// Definition 1 (ii): V grows without bound as the goal is approached
/// along the dipole axis (every other coordinate at its goal): V ~ c/t.
#[test]
fn v_tends_to_infinity_at_the_goal() {
    let s = scene(1, GoalFrame::Platform);
    let g = s.goal.clone();
    let mut last = 0.0;
    let mut vt = Vec::new();
    for t in [0.5, 0.1, 0.01, 1e-3, 1e-4] {
        let mut q = g.clone();
        q[0] -= t * g[2].cos();
        q[1] -= t * g[2].sin();
        let v = s.evaluate::<f64>(&q, &mut s.warm()).unwrap().v;
        assert!(v > last, "V = {v} at {t} m not above {last}");
        last = v;
        vt.push(v * t);
    }
    // V·t tends to a positive constant: V grows like 1/t.
    let (a, b) = (vt[3], vt[4]);
    assert!((a - b).abs() < 0.01 * b && b > 0.0, "V·t = {vt:?}");
    assert!(last > 1e3, "V = {last} at 0.1 mm from the goal");
}

/// Definition 1 (i) on the obstacle boundaries: V → 0 as a part closes in
/// on an obstacle (β → 0⁺), like β^{1/(2 k_v)} (the point-world distance
/// is ∝ √β), and is 0 once they touch.
#[test]
fn v_vanishes_on_obstacle_boundaries() {
    let s = scene(1, GoalFrame::Platform);
    // Drive the platform along +x towards the wall at x = 0 (y = 3 is
    // behind `wall_left`): bisect for the first contact.
    let q_at = |x: f64| {
        let mut q = s.goal.clone();
        q[0] = x;
        q[1] = 3.0;
        q
    };
    let beta = |x: f64| s.evaluate::<f64>(&q_at(x), &mut s.warm()).unwrap().min_beta;
    let (mut free, mut hit) = (-3.0, 0.0);
    assert!(beta(free) > 0.0 && beta(hit) <= 0.0);
    for _ in 0..80 {
        let mid = 0.5 * (free + hit);
        if beta(mid) > 0.0 {
            free = mid;
        } else {
            hit = mid;
        }
    }
    let v = |x: f64| s.evaluate::<f64>(&q_at(x), &mut s.warm()).unwrap().v;
    assert_eq!(v(hit), 0.0, "V on contact");
    let far = v(-3.0);
    let mut ratios = Vec::new();
    for d in [1e-3, 1e-6, 1e-9] {
        let x = free - d;
        let (b, vv) = (beta(x), v(x));
        assert!(b > 0.0 && vv > 0.0 && vv < far);
        ratios.push(vv / b.powf(1.0 / (2.0 * s.params.kv)));
    }
    // V / β^{1/(2k_v)} settles: V → 0 at the rate the construction predicts.
    let spread = ratios
        .iter()
        .fold(0.0f64, |m, r| m.max((r / ratios[2] - 1.0).abs()));
    assert!(spread < 0.2, "ratios {ratios:?}");
}

/// Σ‖h2‖² (the denominator of V) vanishes only at the goal: the parts'
/// points fix every coordinate, the heading through the dipole.
#[test]
fn goal_distance_vanishes_only_at_the_goal() {
    let s = scene(1, GoalFrame::Platform);
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for _ in 0..200 {
        let mut q = s.goal.clone();
        let i = rng.random_range(0..9);
        if i == 2 {
            continue; // the heading enters through γ, not Σ‖h2‖²
        }
        q[i] += rng.random_range(0.01..0.5) * if rng.random::<bool>() { 1.0 } else { -1.0 };
        let e = s.evaluate::<f64>(&q, &mut s.warm()).unwrap();
        assert!(e.d > 1e-8, "coordinate {i}: Σ‖h2‖² = {}", e.d);
    }
    let e = s.evaluate::<f64>(&s.goal, &mut s.warm()).unwrap();
    assert!(e.d < 1e-24);
}
