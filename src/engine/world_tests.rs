//! Tests of `world.rs`.

use super::*;
use crate::engine::real::{arr, quat};
use nalgebra::{Isometry3, Matrix3, Translation3, UnitQuaternion, Vector3};
use proptest::prelude::*;
use std::fmt::Write as _;

/// A random link: mass, principal moments, inertial origin (xyz, rpy), inertia rotation.
type LinkSpec = (f64, [f64; 3], [f64; 3], [f64; 3], [f64; 3]);
/// A random joint: type index, origin (xyz, rpy), axis, limits.
type JointSpec = (usize, [f64; 3], [f64; 3], [f64; 3], [f64; 2]);

const TYPES: [&str; 4] = ["revolute", "continuous", "prismatic", "fixed"];

fn rot(rpy: [f64; 3]) -> UnitQuaternion<f64> {
    // nalgebra's convention is the URDF one: Rz(yaw) Ry(pitch) Rx(roll).
    UnitQuaternion::from_euler_angles(rpy[0], rpy[1], rpy[2])
}

/// Full inertia tensor of a link in its inertial frame: R diag(d) Rᵀ.
fn inertia(l: &LinkSpec) -> Matrix3<f64> {
    let r = rot(l.4).to_rotation_matrix().into_inner();
    r * Matrix3::from_diagonal(&Vector3::from(l.1)) * r.transpose()
}

fn urdf(links: &[LinkSpec], joints: &[JointSpec]) -> String {
    let mut s = String::from("<robot name=\"r\">");
    for (i, l) in links.iter().enumerate() {
        let t = inertia(l);
        let (x, o) = (l.2, l.3);
        let _ = write!(
            s,
            "<link name=\"l{i}\"><inertial><origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/>\
             <mass value=\"{}\"/><inertia ixx=\"{}\" ixy=\"{}\" ixz=\"{}\" iyy=\"{}\" iyz=\"{}\" izz=\"{}\"/>\
             </inertial><collision><origin xyz=\"0.1 0 0\" rpy=\"{} {} {}\"/>\
             <geometry><cylinder radius=\"0.05\" length=\"0.2\"/></geometry></collision></link>",
            x[0], x[1], x[2], o[0], o[1], o[2], l.0,
            t[(0, 0)], t[(0, 1)], t[(0, 2)], t[(1, 1)], t[(1, 2)], t[(2, 2)],
            o[2], o[0], o[1],
        );
    }
    for (i, j) in joints.iter().enumerate() {
        let (x, o, a, lim) = (j.1, j.2, j.3, j.4);
        let _ = write!(
            s,
            "<joint name=\"j{i}\" type=\"{}\"><parent link=\"l{i}\"/><child link=\"l{}\"/>\
             <origin xyz=\"{} {} {}\" rpy=\"{} {} {}\"/><axis xyz=\"{} {} {}\"/>\
             <limit lower=\"{}\" upper=\"{}\" effort=\"1\" velocity=\"1\"/></joint>",
            TYPES[j.0],
            i + 1,
            x[0],
            x[1],
            x[2],
            o[0],
            o[1],
            o[2],
            a[0],
            a[1],
            a[2],
            lim[0],
            lim[1],
        );
    }
    s + "</robot>"
}

fn v3() -> impl Strategy<Value = [f64; 3]> {
    [-0.5..0.5f64, -0.5..0.5f64, -0.5..0.5f64]
}
fn angles() -> impl Strategy<Value = [f64; 3]> {
    [-3.0..3.0f64, -1.5..1.5f64, -3.0..3.0f64]
}
fn link() -> impl Strategy<Value = LinkSpec> {
    (
        0.1..10.0f64,
        [0.01..1.0f64, 0.01..1.0f64, 0.01..1.0f64],
        v3(),
        angles(),
        angles(),
    )
}
fn joint() -> impl Strategy<Value = JointSpec> {
    let axis = [-1.0..1.0f64, -1.0..1.0f64, 0.2..1.0f64];
    (
        0..4usize,
        v3(),
        angles(),
        axis,
        [-2.0..-0.1f64, 0.1..2.0f64],
    )
}

fn iso(p: &RPose) -> Isometry3<f64> {
    let q = quat(&p.rotation);
    Isometry3::from_parts(
        Translation3::from(Vector3::from(arr(p.translation))),
        UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[3], q[0], q[1], q[2])),
    )
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * (1.0 + b.abs())
}

proptest! {
    #![proptest_config(crate::prop_config::config(48))]

    /// Bodies, inertials, collisions and joints of random chains match an independent
    /// forward-kinematics computation (nalgebra, URDF conventions).
    #[test]
    fn loader_matches_independent_kinematics(
        links in prop::collection::vec(link(), 2..5),
        joint_specs in prop::collection::vec(joint(), 4),
        root_xyz in v3(),
        root_rpy in angles(),
    ) {
        let joints = &joint_specs[..links.len() - 1];
        let robot = urdf_rs::read_from_string(&urdf(&links, joints)).unwrap();
        crate::engine::urdf::validate(&robot).unwrap();
        let root = RPose::from_parts(
            vector(root_xyz[0], root_xyz[1], root_xyz[2]),
            origin(&urdf_rs::Pose { xyz: urdf_rs::Vec3([0.0; 3]), rpy: urdf_rs::Vec3(root_rpy) }).rotation,
        );
        let settings = PhysicsSettings { gravity: [0.0; 3], ..Default::default() };
        // Every joint kept: each link is checked as a body of its own.
        let names: Vec<String> = (0..joints.len()).map(|i| format!("j{i}")).collect();
        let keep: Vec<&str> = names.iter().map(String::as_str).collect();
        let opts = WorldOptions { settings: &settings, root_pose: root, ground: false, keep_fixed: &keep };
        let mut sw = SimWorld::new(&robot, Path::new("."), &opts).unwrap();
        // A zero-length step applies the user changes (mass properties) and moves nothing.
        sw.world.integration_parameters.dt = 0.0;
        sw.world.step();

        let mut expect = vec![Isometry3::from_parts(Translation3::from(Vector3::from(root_xyz)), rot(root_rpy))];
        for j in joints {
            let o = Isometry3::from_parts(Translation3::from(Vector3::from(j.1)), rot(j.2));
            expect.push(expect.last().unwrap() * o);
        }
        for (i, l) in links.iter().enumerate() {
            let b = &sw.world.bodies[sw.robot.links[i]];
            let got = iso(b.position());
            prop_assert!((got.translation.vector - expect[i].translation.vector).norm() < 1e-12);
            prop_assert!(got.rotation.angle_to(&expect[i].rotation) < 1e-9);
            let mp = &b.mass_properties().local_mprops;
            prop_assert!(close(f(mp.mass()), l.0, 1e-12));
            // CoM and inertia in the link frame: inertial origin and R I Rᵀ.
            let com = Vector3::from(arr(mp.local_com));
            prop_assert!((com - Vector3::from(l.2)).norm() < 1e-12);
            let r_in = rot(l.3).to_rotation_matrix().into_inner();
            let want = r_in * inertia(l) * r_in.transpose();
            let m = mp.reconstruct_inertia_matrix();
            let got = Matrix3::from_column_slice(&m.to_cols_array().map(f));
            prop_assert!((got - want).norm() < 1e-9 * want.norm(), "{got} vs {want}");
            // The cylinder collision stands along the collision frame's z axis.
            let c = &sw.world.colliders[sw.robot.colliders[i]];
            let axis = Vector3::from(arr(c.position().rotation * Vector::Y));
            let col = expect[i] * Isometry3::from_parts(Translation3::new(0.1, 0.0, 0.0), rot([l.3[2], l.3[0], l.3[1]]));
            prop_assert!((axis - col.rotation * Vector3::z()).norm() < 1e-9);
        }
        for (i, j) in joints.iter().enumerate() {
            let data = &sw.world.impulse_joints.get(sw.robot.joints[&format!("j{i}")]).unwrap().data;
            // The free axis (local x of the parent-side frame) is the URDF axis in the joint frame.
            let x = Vector3::from(arr(data.local_frame1.rotation * Vector::X));
            let want = rot(j.2) * Vector3::from(j.3).normalize();
            if j.0 != 3 {
                prop_assert!((x - want).norm() < 1e-9, "{x} vs {want}");
            }
            let lim = data.limits(match j.0 { 2 => JointAxis::LinX, _ => JointAxis::AngX });
            match j.0 {
                0 | 2 => {
                    let l = lim.unwrap();
                    prop_assert!(close(f(l.min), j.4[0], 1e-12) && close(f(l.max), j.4[1], 1e-12));
                }
                _ => prop_assert!(lim.is_none()),
            }
        }
    }
}

/// A second copy of a robot lands at its own root pose with its own handles,
/// and collision groups apply per robot.
#[test]
fn second_robot_has_its_own_handles() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("models/rover.urdf");
    let robot = crate::engine::urdf::read(&path).unwrap();
    let settings = PhysicsSettings::default();
    let mut sw = SimWorld::on_ground(&robot, Path::new("."), &settings, RPose::IDENTITY).unwrap();
    let shift = RPose::from_parts(vector(2.0, -1.0, 0.0), Rotation::from_rotation_z(r(0.5)));
    let b = sw.add_robot(&robot, Path::new("."), shift).unwrap();
    assert_eq!(b.links.len(), sw.robot.links.len());
    assert!(b.links.iter().all(|h| !sw.robot.links.contains(h)));
    assert!(b
        .joints
        .values()
        .all(|h| !sw.robot.joints.values().any(|a| a == h)));
    let (a_poses, b_poses) = (sw.link_poses(), b.link_poses(&sw.world.bodies));
    for (pa, pb) in a_poses.iter().zip(&b_poses) {
        let pa = shift.transform_point(vector(
            pa.translation[0],
            pa.translation[1],
            pa.translation[2],
        ));
        let d: f64 = (0..3).map(|k| (f(pa[k]) - pb.translation[k]).powi(2)).sum();
        assert!(d.sqrt() < 1e-12);
    }
    assert_eq!(
        b.require_link("chassis").unwrap(),
        b.links[b.link_index["chassis"]]
    );
    assert!(b
        .require_joint("no_such_joint")
        .unwrap_err()
        .to_string()
        .contains("no_such_joint"));
    let groups = InteractionGroups::new(Group::GROUP_2, Group::GROUP_1, InteractionTestMode::And);
    let cs = b.colliders.clone();
    sw.set_collision_groups(&cs, groups);
    assert!(b
        .colliders
        .iter()
        .all(|c| sw.world.colliders[*c].collision_groups() == groups));
    assert!(sw
        .robot
        .colliders
        .iter()
        .all(|c| sw.world.colliders[*c].collision_groups() != groups));
}
