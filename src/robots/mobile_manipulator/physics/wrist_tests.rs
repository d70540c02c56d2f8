//! The compliant wrist joint against the closed form of its spring law
//! ([`CompliantWrist::wrench`]): a 1 kg gripper hung from a fixed flange by
//! [`compliant_wrist_joint`] is a mass–spring–damper per axis.

use crate::robots::mobile_manipulator::physics::*;

const DT: f64 = 0.001;

fn wrist() -> CompliantWrist {
    CompliantWrist {
        stiffness: [400.0, 300.0, 500.0, 50.0, 40.0, 60.0],
        // ζ = c / (2 √(k m)) = 0.1 on the z axis (m = 1 kg).
        damping: [25.0, 25.0, 4.472, 2.0, 2.0, 2.0],
        travel: [0.2, 0.2, 0.2, 0.35, 0.35, 0.35],
    }
}

/// A fixed flange at the origin and a 1 kg gripper (inertia 0.01 kg m²
/// about its centre, at the grasp point) on the wrist joint.
fn rig(w: &CompliantWrist, gravity: f64) -> (PhysicsWorld, RigidBodyHandle) {
    let mut world = PhysicsWorld::new();
    world.gravity = vector(0.0, 0.0, -gravity);
    world.integration_parameters.dt = rl::r(DT);
    let flange = world.insert_body(RigidBodyBuilder::fixed());
    // Never asleep (as the harness's bodies): a sleeping gripper freezes at
    // a turning point of its ringing, 7 % off m g / k at ζ = 0.1.
    let gripper = world.insert_body(
        RigidBodyBuilder::dynamic()
            .can_sleep(false)
            .additional_mass_properties(MassProperties::new(
                vector(0.0, 0.0, GRASP_OFFSET),
                rl::r(1.0),
                vector(0.01, 0.01, 0.01),
            )),
    );
    world.insert_impulse_joint(flange, gripper, compliant_wrist_joint(w));
    (world, gripper)
}

/// Under gravity (−z) the gripper follows the underdamped closed form
/// x(t) = δ (1 − e^{−ζωt} (cos ω_d t + ζ/√(1−ζ²) sin ω_d t)), δ = m g / k,
/// and settles at δ; the other axes stay at rest.
#[test]
fn the_wrist_spring_follows_the_mass_spring_damper_closed_form() {
    let w = wrist();
    let (mut world, gripper) = rig(&w, 9.81);
    let (k, c, m) = (w.stiffness[2], w.damping[2], 1.0);
    let omega = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    let wd = omega * (1.0 - zeta * zeta).sqrt();
    let delta = m * 9.81 / k;
    let closed = |t: f64| {
        -delta
            * (1.0
                - (-zeta * omega * t).exp()
                    * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin()))
    };
    let mut worst: f64 = 0.0;
    for step in 1..=3000 {
        world.step();
        let t = step as f64 * DT;
        let p = world.bodies[gripper].translation();
        let z = rl::f(p.z);
        worst = worst.max((z - closed(t)).abs());
        assert!(
            rl::f(p.x).abs() < 1e-6 && rl::f(p.y).abs() < 1e-6,
            "t {t}: {p:?}"
        );
    }
    let z = rl::f(world.bodies[gripper].translation().z);
    eprintln!(
        "wrist z: static {:.5} m (closed form {:.5}), worst transient gap {:.2} mm",
        z,
        -delta,
        worst * 1e3
    );
    assert!((z + delta).abs() < 0.01 * delta, "static {z} vs −{delta}");
    // 3 % of δ over the first 3 s: the implicit spring's period error at
    // ω dt = 0.02 accumulates over the ~10 ringing periods.
    assert!(
        worst < 0.03 * delta,
        "transient off the closed form by {worst} m"
    );
}

/// A constant moment about each rotation axis turns the gripper by M / k,
/// a force beyond k × travel stops it at the travel.
#[test]
fn the_wrist_turns_by_the_moment_over_its_stiffness_and_stops_at_its_travel() {
    let w = wrist();
    for axis in 0..3 {
        let (mut world, gripper) = rig(&w, 0.0);
        let mut tau = [0.0; 3];
        tau[axis] = 4.0;
        world.bodies[gripper].add_torque(vector(tau[0], tau[1], tau[2]), true);
        for _ in 0..3000 {
            world.step();
        }
        let (ax, angle) = world.bodies[gripper].rotation().to_axis_angle();
        let turned = rl::f(angle) * rl::f([ax.x, ax.y, ax.z][axis]);
        let expect = 4.0 / w.stiffness[3 + axis];
        assert!(
            (turned - expect).abs() < 0.01 * expect,
            "axis {axis}: turned {turned} rad, closed form {expect}"
        );
    }
    // 2 k × travel along x: the spring alone would deflect twice the travel.
    let (mut world, gripper) = rig(&w, 0.0);
    world.bodies[gripper].add_force(vector(2.0 * w.stiffness[0] * w.travel[0], 0.0, 0.0), true);
    for _ in 0..3000 {
        world.step();
    }
    let x = rl::f(world.bodies[gripper].translation().x);
    assert!(
        (x - w.travel[0]).abs() < 0.005 * w.travel[0],
        "stopped at {x} m, travel {}",
        w.travel[0]
    );
    // The closed form the planner's statics use agrees at rest.
    let f = w.wrench([x, 0.0, 0.0, 0.0, 0.0, 0.0], [0.0; 6]);
    assert_eq!(f[0], -w.stiffness[0] * x);
}
