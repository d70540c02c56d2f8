//! Tests of the finite-element beam against closed forms and independent
//! computations (issue 11's "Must show" for the FE model).

use nalgebra::{SMatrix, SVector};
use num_dual::DualSVec64;
use proptest::prelude::*;

use crate::model::spatial::{mul_mm, rot_x, rot_y, rot_z, Pose, Scalar};
use crate::robots::mobile_manipulator::beam::fe::FeBeam;
use crate::robots::mobile_manipulator::beam::se3::se3_exp;
use crate::robots::mobile_manipulator::beam::{Beam, Material, Section, GFRP_ROD_10MM};

fn gfrp(length: f64) -> Beam {
    Beam {
        material: GFRP_ROD_10MM.0,
        section: GFRP_ROD_10MM.1,
        length,
    }
}

/// Random beams whose axial/bending stiffness ratio stays below ~1e8.
fn beam_strategy() -> impl Strategy<Value = Beam> {
    (
        1e9f64..2e11,
        0.2f64..0.5,
        500.0f64..8000.0,
        0.005f64..0.05,
        0.0f64..0.8,
        0.5f64..5.0,
    )
        .prop_map(|(e, g_ratio, rho, d, hollow, l)| Beam {
            material: Material {
                youngs_modulus: e,
                shear_modulus: e * g_ratio,
                density: rho,
            },
            section: Section {
                outer_diameter: d,
                inner_diameter: d * hollow,
            },
            length: l,
        })
}

fn close(a: f64, b: f64, rel: f64, what: &str) -> Result<(), TestCaseError> {
    let tol = rel * a.abs().max(b.abs()).max(1e-300);
    prop_assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
    Ok(())
}

/// The six rigid motions of the three rest nodes (columns: translations x, y,
/// z, rotations about x, y, z through node 0).
fn rigid_modes(l: f64) -> SMatrix<f64, 18, 6> {
    let mut r = SMatrix::<f64, 18, 6>::zeros();
    for node in 0..3 {
        let x = [node as f64 * l / 2.0, 0.0, 0.0];
        let o = 6 * node;
        for d in 0..3 {
            r[(o + d, d)] = 1.0;
            r[(o + 3 + d, 3 + d)] = 1.0;
        }
        // Translation part of a rotation ω about node 0: ω × x.
        for a in 0..3 {
            let mut w = [0.0; 3];
            w[a] = 1.0;
            let wx = [
                w[1] * x[2] - w[2] * x[1],
                w[2] * x[0] - w[0] * x[2],
                w[0] * x[1] - w[1] * x[0],
            ];
            for d in 0..3 {
                r[(o + d, 3 + a)] = wx[d];
            }
        }
    }
    r
}

fn check_stiffness(beam: &Beam) -> Result<(), TestCaseError> {
    let fe = FeBeam::new(beam).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let k = fe.stiffness();
    prop_assert_eq!(k, &k.transpose());
    let eig = k.symmetric_eigen();
    let lmax = eig.eigenvalues.max();
    let tol = 1e-10 * lmax;
    prop_assert!(
        eig.eigenvalues.iter().all(|&l| l >= -tol),
        "negative eigenvalue"
    );
    let zero: Vec<usize> = (0..18)
        .filter(|&i| eig.eigenvalues[i].abs() <= tol)
        .collect();
    prop_assert_eq!(zero.len(), 6, "eigenvalues {}", eig.eigenvalues);
    // The rigid motions are in the null space and span it.
    let r = rigid_modes(beam.length);
    prop_assert!((k * r).abs().max() <= tol, "K r = {}", (k * r).abs().max());
    let q = r.qr().q();
    for &i in &zero {
        let v = eig.eigenvectors.column(i).into_owned();
        let residual = v - q * (q.transpose() * v);
        prop_assert!(residual.norm() < 1e-8, "zero mode {i} is not rigid");
    }
    Ok(())
}

/// Node 0 clamped, load `f` on nodes 1 and 2: displacements of nodes 1, 2.
fn cantilever(fe: &FeBeam, f: &SVector<f64, 12>) -> SVector<f64, 12> {
    let kff: SMatrix<f64, 12, 12> = fe.stiffness().fixed_view::<12, 12>(6, 6).into_owned();
    kff.cholesky()
        .expect("clamped K is positive definite")
        .solve(f)
}

fn check_cantilever(beam: &Beam) -> Result<(), TestCaseError> {
    let fe = FeBeam::new(beam).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let (l, ei, ea, gj) = (
        beam.length,
        beam.bending_stiffness(),
        beam.axial_stiffness(),
        beam.torsional_stiffness(),
    );
    // Loads sized for a 1 % tip deflection / rotation.
    let p = 0.03 * ei / l.powi(2);
    let t = 0.01 * gj / l;
    let m = 0.01 * ei / l;
    // (tip DOF loaded, load, [(node-1/2 DOF, expected)]).
    type Case = (usize, f64, [(usize, f64); 4]);
    let cases: [Case; 5] = [
        // (tip DOF loaded, load, [(node-1/2 DOF, expected)]).
        (
            1,
            p,
            [
                (7, p * l.powi(3) / (3.0 * ei)),
                (11, p * l * l / (2.0 * ei)),
                (1, 5.0 * p * l.powi(3) / (48.0 * ei)),
                (5, 3.0 * p * l * l / (8.0 * ei)),
            ],
        ),
        (
            2,
            p,
            [
                (8, p * l.powi(3) / (3.0 * ei)),
                (10, -p * l * l / (2.0 * ei)),
                (2, 5.0 * p * l.powi(3) / (48.0 * ei)),
                (4, -3.0 * p * l * l / (8.0 * ei)),
            ],
        ),
        (
            0,
            p,
            [
                (6, p * l / ea),
                (0, p * l / (2.0 * ea)),
                (6, p * l / ea),
                (0, p * l / (2.0 * ea)),
            ],
        ),
        (
            3,
            t,
            [
                (9, t * l / gj),
                (3, t * l / (2.0 * gj)),
                (9, t * l / gj),
                (3, t * l / (2.0 * gj)),
            ],
        ),
        (
            5,
            m,
            [
                (7, m * l * l / (2.0 * ei)),
                (11, m * l / ei),
                (1, m * l * l / (8.0 * ei)),
                (5, m * l / (2.0 * ei)),
            ],
        ),
    ];
    for (dof, load, expected) in cases {
        let mut f = SVector::<f64, 12>::zeros();
        f[6 + dof] = load;
        let u = cantilever(&fe, &f);
        let scale = u.abs().max();
        for (i, want) in expected {
            close(u[i], want, 1e-9, &format!("load on {dof}, dof {i}"))?;
        }
        // Nothing else moves (decoupled axial, torsion and the two planes).
        let mut listed = [false; 12];
        for (i, _) in expected {
            listed[i] = true;
        }
        for i in (0..12).filter(|&i| !listed[i]) {
            prop_assert!(
                u[i].abs() <= 1e-12 * scale,
                "load on {dof}: dof {i} = {}",
                u[i]
            );
        }
    }

    // The same through `deformation`: impose the closed-form tip
    // displacement of a combined tip load (P_y, P_z, P_x, T); the condensed
    // middle node must equal the closed-form cantilever middle.
    let tip = [
        p * l / ea,
        p * l.powi(3) / (3.0 * ei),
        -0.5 * p * l.powi(3) / (3.0 * ei),
        t * l / gj,
        0.5 * p * l * l / (2.0 * ei),
        p * l * l / (2.0 * ei),
    ];
    let rel = fe.rest_end2().then(&se3_exp(&tip));
    let q = fe.deformation(&rel, [0.0; 3]);
    // The axial part is ~1e-7 of the bending part and carries the rounding
    // of L + u − L: compare against the vector's scale.
    let scale = tip.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    for i in 0..6 {
        prop_assert!(
            (q[i] - tip[i]).abs() <= 1e-9 * scale,
            "q_s[{i}]: {} vs {}",
            q[i],
            tip[i]
        );
    }
    let mid = [
        p * l / (2.0 * ea),
        5.0 * p * l.powi(3) / (48.0 * ei),
        -0.5 * 5.0 * p * l.powi(3) / (48.0 * ei),
        t * l / (2.0 * gj),
        0.5 * 3.0 * p * l * l / (8.0 * ei),
        3.0 * p * l * l / (8.0 * ei),
    ];
    for i in 0..6 {
        let err = (q[6 + i] - mid[i]).abs();
        prop_assert!(err <= 1e-9 * scale, "q_o[{i}]: {} vs {}", q[6 + i], mid[i]);
    }
    Ok(())
}

fn check_sag(beam: &Beam) -> Result<(), TestCaseError> {
    let fe = FeBeam::new(beam).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let (l, ei, ea) = (
        beam.length,
        beam.bending_stiffness(),
        beam.axial_stiffness(),
    );
    let w = beam.mass_per_length() * 9.81;
    let rest = fe.rest_end2();
    for (axis, want) in [
        (0, -w * l * l / (8.0 * ea)),
        (1, -w * l.powi(4) / (384.0 * ei)),
        (2, -w * l.powi(4) / (384.0 * ei)),
    ] {
        let mut g = [0.0; 3];
        g[axis] = -9.81;
        let q = fe.deformation(&rest, g);
        prop_assert!(
            q[..6].iter().all(|&x| x == 0.0),
            "q_s at rest {:?}",
            &q[..6]
        );
        close(q[6 + axis], want, 1e-9, &format!("sag along {axis}"))?;
        for i in (0..6).filter(|&i| i != axis) {
            prop_assert!(
                q[6 + i].abs() <= 1e-9 * want.abs(),
                "q_o[{i}] = {}",
                q[6 + i]
            );
        }
        // The centreline passes through the nodes.
        let mid = fe.centerline(&q, l / 2.0);
        let mut expect = [l / 2.0, 0.0, 0.0];
        expect[axis] += want;
        for (d, e) in expect.iter().enumerate() {
            prop_assert!((mid.p[d] - e).abs() <= 1e-12 * l, "centreline at L/2");
        }
        let start = fe.centerline(&q, 0.0);
        prop_assert!(start.p.iter().all(|x| x.abs() < 1e-15));
    }
    Ok(())
}

/// The middle of a single element of length L with node 0 clamped and the
/// end displaced by `qs` (no interior load): linear axial/torsion, cubic
/// Hermite bending, evaluated at L/2.
fn single_element_middle(qs: &[f64; 6], l: f64) -> [f64; 6] {
    [
        qs[0] / 2.0,
        qs[1] / 2.0 - l * qs[5] / 8.0,
        qs[2] / 2.0 + l * qs[4] / 8.0,
        qs[3] / 2.0,
        -1.5 * qs[2] / l - 0.25 * qs[4],
        1.5 * qs[1] / l - 0.25 * qs[5],
    ]
}

fn check_rigid_limit(beam: &Beam, qs: &[f64; 6]) -> Result<(), TestCaseError> {
    let g = [0.3, -1.0, -9.81];
    let base = FeBeam::new(beam).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let rest = base.rest_end2();
    let sag1 = base.deformation(&rest, g);
    let sag1_norm = sag1[6..].iter().fold(0.0f64, |m, x| m.max(x.abs()));
    prop_assert!(sag1_norm > 0.0);
    let rel = rest.then(&se3_exp(qs));
    for stiffer in [1.0, 1e3, 1e6, 1e9] {
        let mut b = *beam;
        b.material.youngs_modulus *= stiffer;
        b.material.shear_modulus *= stiffer;
        let fe = FeBeam::new(&b).map_err(|e| TestCaseError::fail(e.to_string()))?;
        // Grasps at the rest geometry: the sag shrinks as 1/E and vanishes.
        let sag = fe.deformation(&rest, g);
        for i in 6..12 {
            let err = (sag[i] * stiffer - sag1[i]).abs();
            prop_assert!(err <= 1e-6 * sag1_norm, "sag {i} × {stiffer}: {err}");
        }
        let sag_norm = sag[6..].iter().fold(0.0f64, |m, x| m.max(x.abs()));
        prop_assert!(sag_norm <= sag1_norm / stiffer * (1.0 + 1e-6));
        // Displaced grasps: the condensed middle node tends to the load-free
        // single-element interpolation of the end displacement.
        let q = fe.deformation(&rel, g);
        let want = single_element_middle(qs, b.length);
        let scale = qs.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for i in 0..6 {
            let err = (q[6 + i] - want[i]).abs();
            prop_assert!(
                err <= 1e-9 * scale * (1.0 + 2.0 / b.length) + 1.5 * sag1_norm / stiffer,
                "stiffer {stiffer}: q_o[{i}] = {} vs {}",
                q[6 + i],
                want[i]
            );
        }
    }
    Ok(())
}

/// The relative pose as a function of (x, y, z offset from rest, roll,
/// pitch, yaw).
fn pose_of<T: Scalar>(x: &[T], l: f64) -> Pose<T> {
    Pose {
        r: mul_mm(&rot_z(x[5]), &mul_mm(&rot_y(x[4]), &rot_x(x[3]))),
        p: [x[0] + l, x[1], x[2]],
    }
}

fn check_derivatives(beam: &Beam, x: [f64; 9]) -> Result<(), TestCaseError> {
    let fe = FeBeam::new(beam).map_err(|e| TestCaseError::fail(e.to_string()))?;
    let l = beam.length;
    let xd: [DualSVec64<9>; 9] = std::array::from_fn(|i| DualSVec64::from_re(x[i]).derivative(i));
    let q = fe.deformation(&pose_of(&xd[..6], l), [xd[6], xd[7], xd[8]]);
    let eval = |y: &[f64; 9]| fe.deformation(&pose_of(&y[..6], l), [y[6], y[7], y[8]]);
    for j in 0..9 {
        // q_f is linear in gravity: a unit step is exact and avoids rounding.
        let h = if j < 6 { 1e-6 } else { 1.0 };
        let (mut plus, mut minus) = (x, x);
        plus[j] += h;
        minus[j] -= h;
        let (qp, qm) = (eval(&plus), eval(&minus));
        let fd: [f64; 12] = std::array::from_fn(|i| (qp[i] - qm[i]) / (2.0 * h));
        let exact: [f64; 12] = std::array::from_fn(|i| q[i].eps.0.map_or(0.0, |e| e[j]));
        let scale = fd.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        prop_assert!(scale > 0.0, "column {j} vanishes");
        for i in 0..12 {
            prop_assert!(exact[i].is_finite());
            prop_assert!(
                (exact[i] - fd[i]).abs() <= 1e-6 * scale,
                "∂q_f[{i}]/∂x[{j}]: dual {} vs difference {}",
                exact[i],
                fd[i]
            );
        }
    }
    // The real parts are the f64 evaluation (up to the last bit: dual
    // products round in a different order).
    let q0 = eval(&x);
    for i in 0..12 {
        prop_assert!((q[i].re - q0[i]).abs() <= 1e-14 * q0[i].abs().max(1.0));
    }
    Ok(())
}

#[test]
fn stiffness_of_the_chosen_rod() {
    for l in [3.0, 4.0, 4.5] {
        check_stiffness(&gfrp(l)).unwrap();
    }
}

#[test]
fn cantilever_and_sag_of_the_chosen_rod() {
    check_cantilever(&gfrp(3.0)).unwrap();
    check_sag(&gfrp(3.0)).unwrap();
    // 10 mm GFRP over 3 m sags ≈ 17 mm under its own weight, clamped–clamped.
    let fe = FeBeam::new(&gfrp(3.0)).unwrap();
    let q = fe.deformation(&fe.rest_end2(), [0.0, 0.0, -9.81]);
    assert!((q[8] + 0.0166).abs() < 0.001, "sag {}", q[8]);
}

#[test]
fn derivatives_at_rest_and_near_half_turn() {
    let beam = gfrp(3.0);
    check_derivatives(&beam, [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -9.81]).unwrap();
    check_derivatives(&beam, [-0.2, 0.1, 0.3, 0.05, -0.1, 3.1, 0.0, 0.0, -9.81]).unwrap();
    check_derivatives(&beam, [0.1, -0.3, 0.2, 3.05, 0.02, 0.0, 1.0, -2.0, -9.0]).unwrap();
}

#[test]
fn invalid_beam_is_refused() {
    let mut b = gfrp(3.0);
    b.material.youngs_modulus = -1.0;
    assert!(FeBeam::new(&b)
        .unwrap_err()
        .to_string()
        .contains("youngs_modulus"));
}

proptest! {
    #![proptest_config(crate::prop_config::config(48))]

    #[test]
    fn stiffness_is_symmetric_psd_with_six_rigid_modes(beam in beam_strategy()) {
        check_stiffness(&beam)?;
    }

    #[test]
    fn cantilever_and_sag_match_euler_bernoulli(beam in beam_strategy()) {
        check_cantilever(&beam)?;
        check_sag(&beam)?;
    }

    #[test]
    fn rigid_limit(beam in beam_strategy(), qs in prop::array::uniform6(-0.05f64..0.05)) {
        check_rigid_limit(&beam, &qs)?;
    }

    #[test]
    fn deformation_derivatives_match_central_differences(
        beam in beam_strategy(),
        offset in prop::array::uniform3(-0.3f64..0.3),
        angles in (-1.0f64..1.0, -1.0f64..1.0, -3.1f64..3.1),
        g in prop::array::uniform3(-10.0f64..10.0),
    ) {
        let x = [
            offset[0] * beam.length,
            offset[1] * beam.length,
            offset[2] * beam.length,
            angles.0,
            angles.1,
            angles.2,
            g[0],
            g[1],
            g[2],
        ];
        check_derivatives(&beam, x)?;
    }
}
