//! Why the arm joints carry their armature: a light link between a stiff
//! joint servo and a compliant wrist. Link 6 of the PUMA 560 (4·10⁻⁵ kg m²
//! about its axis) is held by the servo on one side and pulled by the
//! wrist's spring–damper on the other; the damper's time constant on that
//! inertia (I/c = 20 µs) is far below the 1 ms substep, so both joints act
//! as rigid velocity constraints on the link and the solver settles between
//! them: the joint leaves its reference although the servo's torque stays
//! far below its limit. The rotor's reflected inertia (armature, Jm·G²)
//! makes the wrist a spring again on the link's time scale.

use crate::robots::mobile_manipulator::physics::joints::add_rotor_inertia;
use crate::robots::mobile_manipulator::physics::*;

/// The link's largest angle (rad) over 2 s while a 0.5 kg gripper beyond
/// the wrist is twisted by ±10 N m at 2 Hz about the joint axis (half the
/// joint's torque limit); the servo holds angle 0 with the harness's gains.
fn link_excursion(armature: f64) -> f64 {
    let mut world = PhysicsWorld::new();
    world.gravity = vector(0.0, 0.0, 0.0);
    world.integration_parameters.dt = rl::r(0.004);
    world.integration_parameters.num_solver_iterations = 4;
    let base = world.insert_body(RigidBodyBuilder::fixed());
    let link = world.insert_body(
        RigidBodyBuilder::dynamic()
            .can_sleep(false)
            .additional_mass_properties(MassProperties::new(
                vector(0.0, 0.0, 0.032),
                rl::r(0.09),
                vector(0.15e-3, 0.15e-3, 0.04e-3),
            )),
    );
    add_rotor_inertia(&mut world.bodies[link], armature).unwrap();
    let gripper = world.insert_body(
        RigidBodyBuilder::dynamic()
            .can_sleep(false)
            .additional_mass_properties(MassProperties::new(
                vector(0.0, 0.0, GRASP_OFFSET),
                rl::r(0.5),
                vector(5e-4, 5e-4, 5e-4),
            )),
    );
    let gain = PhysicsSettings::default().motor_gain;
    let servo = RevoluteJointBuilder::new(Vector::Z)
        .motor_position(0.0, rl::r(gain / SERVO_TIME), rl::r(gain))
        .motor_max_force(rl::r(puma560::MAX_TORQUE[5]));
    world.insert_impulse_joint(base, link, servo);
    let w = CompliantWrist {
        stiffness: [400.0, 400.0, 400.0, 50.0, 50.0, 50.0],
        damping: [25.0, 25.0, 25.0, 2.0, 2.0, 2.0],
        travel: [0.2, 0.2, 0.2, 0.35, 0.35, 0.35],
    };
    world.insert_impulse_joint(link, gripper, compliant_wrist_joint(&w));
    let mut worst = 0.0f64;
    for step in 1..=500 {
        let t = step as f64 * 0.004;
        let m = 10.0 * (std::f64::consts::TAU * 2.0 * t).sin();
        let g = &mut world.bodies[gripper];
        g.reset_torques(false);
        g.add_torque(vector(0.0, 0.0, m), true);
        world.step();
        let q = angles::about_axis(world.bodies[link].rotation(), 2);
        worst = worst.max(q.abs());
    }
    worst
}

/// With joint 6's published armature the servo holds the link (to 10⁻⁴°
/// here); the bare link leaves its reference (0.33° in this rig; in the
/// transport, with the rod's chain beyond the gripper, by tens of degrees).
#[test]
fn the_armature_lets_the_servo_hold_a_light_link_against_the_wrist() {
    let bare = link_excursion(0.0);
    let with = link_excursion(puma560::ARMATURE[5]);
    eprintln!(
        "bare link {:.3}°, with armature {:.3}°",
        bare.to_degrees(),
        with.to_degrees()
    );
    assert!(
        with.to_degrees() < 0.5,
        "with armature: {}°",
        with.to_degrees()
    );
    assert!(bare > 4.0 * with, "bare {}°", bare.to_degrees());
}
