//! The 6-DOF arm of the mobile manipulators of seed 004: a PUMA 560.
//!
//! Seed 004 mounts "a fully actuated six DOF manipulator" on each platform
//! without giving its geometry. We use the Unimation PUMA 560 in standard
//! Denavit–Hartenberg form as published in P. I. Corke, *Robotics Toolbox for
//! MATLAB* (`mdl_puma560`, after P. I. Corke and B. Armstrong-Hélouvry, "A
//! search for consensus among model parameters reported for the PUMA 560
//! robot", Proc. IEEE ICRA 1994, pp. 1608–1613, and B. Armstrong, O. Khatib,
//! J. Burdick, "The explicit dynamic model and inertial parameters of the
//! PUMA 560 arm", Proc. IEEE ICRA 1986, pp. 510–518):
//!
//! | i | a_i (m) | d_i (m) | α_i   | m_i (kg) | centre of mass in frame i (m) | I_xx, I_yy, I_zz (kg m²) |
//! |---|---------|---------|-------|----------|-------------------------------|--------------------------|
//! | 1 | 0       | 0       | π/2   | (0)      | (0, 0, 0)                     | (0, 0.35, 0)             |
//! | 2 | 0.4318  | 0       | 0     | 17.4     | (−0.3638, 0.006, 0.2275)      | (0.13, 0.524, 0.539)     |
//! | 3 | 0.0203  | 0.15005 | −π/2  | 4.8      | (−0.0203, −0.0141, 0.070)     | (0.066, 0.086, 0.0125)   |
//! | 4 | 0       | 0.4318  | π/2   | 0.82     | (0, 0.019, 0)                 | (1.8, 1.3, 1.8)·10⁻³     |
//! | 5 | 0       | 0       | −π/2  | 0.34     | (0, 0, 0)                     | (0.3, 0.4, 0.3)·10⁻³     |
//! | 6 | 0       | 0       | 0     | 0.09     | (0, 0, 0.032)                 | (0.15, 0.15, 0.04)·10⁻³  |
//!
//! Frame i−1 to frame i: Rz(q_i) Tz(d_i) Tx(a_i) Rx(α_i). Link 1's mass is
//! not part of the published set (it only turns about the vertical); the
//! URDF gives it 10 kg (a choice, stated in `models/mobile_manipulator.urdf`).
//!
//! URDF link frames: the frame of URDF link `link<i>` is DH frame i−1 turned
//! by q_i about its z axis (so every URDF joint turns about its own z axis and
//! its origin is the constant part Tz(d) Tx(a) Rx(α) of the previous row).
//!
//! Singularities: the manipulator Jacobian J (6×6) has
//! det J = κ · f_shoulder · f_elbow · f_wrist with
//! f_shoulder = a2 c2 + a3 c23 − d4 s23 (the wrist centre's reach in the arm
//! plane: zero when the wrist centre is above the shoulder), f_elbow =
//! d4 c3 + a3 s3 (zero when the arm is stretched), f_wrist = s5 (joints 4
//! and 6 aligned), and κ = a2; `det(JᵀJ) = 0` exactly on their zero
//! sets (checked against a numerical Jacobian in the tests).

use crate::model::spatial::{self, k, Pose, Scalar};

/// One row of the standard DH table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DhRow {
    /// Link length a_i, m.
    pub a: f64,
    /// Link offset d_i, m.
    pub d: f64,
    /// Twist α_i, rad.
    pub alpha: f64,
}

/// Published inertial parameters of one link (DH frame i).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinkInertia {
    /// Mass, kg.
    pub mass: f64,
    /// Centre of mass in DH frame i, m.
    pub com: [f64; 3],
    /// Principal moments about the centre of mass, in DH frame i axes, kg m².
    pub inertia: [f64; 3],
}

/// The PUMA 560 DH table (Corke, `mdl_puma560`).
pub const DH: [DhRow; 6] = [
    DhRow {
        a: 0.0,
        d: 0.0,
        alpha: std::f64::consts::FRAC_PI_2,
    },
    DhRow {
        a: 0.4318,
        d: 0.0,
        alpha: 0.0,
    },
    DhRow {
        a: 0.0203,
        d: 0.15005,
        alpha: -std::f64::consts::FRAC_PI_2,
    },
    DhRow {
        a: 0.0,
        d: 0.4318,
        alpha: std::f64::consts::FRAC_PI_2,
    },
    DhRow {
        a: 0.0,
        d: 0.0,
        alpha: -std::f64::consts::FRAC_PI_2,
    },
    DhRow {
        a: 0.0,
        d: 0.0,
        alpha: 0.0,
    },
];

/// Published inertial parameters (Armstrong et al. 1986 as compiled by Corke);
/// link 1's mass is ours (see the module docs).
pub const INERTIA: [LinkInertia; 6] = [
    LinkInertia {
        mass: 10.0,
        com: [0.0, 0.0, 0.0],
        inertia: [0.2, 0.35, 0.2],
    },
    LinkInertia {
        mass: 17.4,
        com: [-0.3638, 0.006, 0.2275],
        inertia: [0.13, 0.524, 0.539],
    },
    LinkInertia {
        mass: 4.8,
        com: [-0.0203, -0.0141, 0.070],
        inertia: [0.066, 0.086, 0.0125],
    },
    LinkInertia {
        mass: 0.82,
        com: [0.0, 0.019, 0.0],
        inertia: [1.8e-3, 1.3e-3, 1.8e-3],
    },
    LinkInertia {
        mass: 0.34,
        com: [0.0, 0.0, 0.0],
        inertia: [0.3e-3, 0.4e-3, 0.3e-3],
    },
    LinkInertia {
        mass: 0.09,
        com: [0.0, 0.0, 0.032],
        inertia: [0.15e-3, 0.15e-3, 0.04e-3],
    },
];

/// Largest torque of each joint, N m: the PUMA 560's maximum joint torques
/// as tabulated with Corke's Robotics Toolbox model (`mdl_puma560`) in
/// robotics course material, next to the arm's joint speed limits (8, 10,
/// 10, 5, 5, 5) rad/s and breakaway friction torques (6.3, 5.5, 2.6, 1.3,
/// 1.0, 1.2) N m. The wrist joints (4–6) hold about a tenth of the shoulder.
pub const MAX_TORQUE: [f64; 6] = [97.6, 186.4, 89.4, 24.2, 20.1, 21.3];

/// Each joint's armature, kg m²: the motor rotor's inertia reflected through
/// the gears, Jm·G², with Corke's `mdl_puma560` rotor inertias Jm = (200,
/// 200, 200, 33, 33, 33)·10⁻⁶ kg m² and gear ratios G = (−62.6111,
/// 107.815, −53.7063, 76.0364, 71.923, 76.686). For the wrist it is some
/// 5000 times link 6's own inertia about its axis.
pub const ARMATURE: [f64; 6] = [
    200e-6 * 62.6111 * 62.6111,
    200e-6 * 107.815 * 107.815,
    200e-6 * 53.7063 * 53.7063,
    33e-6 * 76.0364 * 76.0364,
    33e-6 * 71.923 * 71.923,
    33e-6 * 76.686 * 76.686,
];

/// The constant part Tz(d) Tx(a) Rx(α) of row `i`.
pub(crate) fn row_offset<T: Scalar>(i: usize) -> Pose<T> {
    let r = DH[i];
    Pose {
        r: spatial::rot_x(k(r.alpha)),
        p: [k(r.a), k(0.0), k(r.d)],
    }
}

/// Frames of the arm given its base (DH frame 0) pose: `[L1, …, L6, F6]` where
/// L_i is URDF link i's frame (DH frame i−1 turned by q_i) and F6 is DH frame 6
/// (the flange).
pub fn frames<T: Scalar>(base: &Pose<T>, q: &[T]) -> [Pose<T>; 7] {
    let mut out = [*base; 7];
    let mut prev = *base;
    for i in 0..6 {
        let li = prev.then(&Pose::rotation(spatial::rot_z(q[i])));
        out[i] = li;
        // The row's constant part, multiplied in as constants (cheaper for
        // dual numbers than lifting it).
        let r = DH[i];
        let off = row_offset::<f64>(i);
        prev = Pose {
            r: spatial::mul_mm_const(&li.r, &off.r),
            p: spatial::add(spatial::mul_mv_const(&li.r, [r.a, 0.0, r.d]), li.p),
        };
    }
    out[6] = prev;
    out
}

/// The three factors of det J (see the module docs).
pub(crate) fn singularity_factors<T: Scalar>(q: &[T]) -> [T; 3] {
    let (a2, a3, d4) = (DH[1].a, DH[2].a, DH[3].d);
    let (c2, c3, s3) = (q[1].cos(), q[2].cos(), q[2].sin());
    let q23 = q[1] + q[2];
    let (c23, s23) = (q23.cos(), q23.sin());
    [c2 * a2 + c23 * a3 - s23 * d4, c3 * d4 + s3 * a3, q[4].sin()]
}

/// Geometric Jacobian (rows: linear velocity of the flange origin, angular
/// velocity; columns: q1..q6) in DH frame 0.
pub fn jacobian(q: &[f64]) -> [[f64; 6]; 6] {
    let f = frames::<f64>(&Pose::identity(), q);
    let pe = f[6].p;
    let mut j = [[0.0; 6]; 6];
    for (i, fi) in f.iter().take(6).enumerate() {
        // Joint i turns about the z axis of URDF frame L_i (= DH frame i−1's z).
        let z = spatial::col(&fi.r, 2);
        let r = spatial::sub(pe, fi.p);
        let v = [
            z[1] * r[2] - z[2] * r[1],
            z[2] * r[0] - z[0] * r[2],
            z[0] * r[1] - z[1] * r[0],
        ];
        for k in 0..3 {
            j[k][i] = v[k];
            j[k + 3][i] = z[k];
        }
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn det6(m: [[f64; 6]; 6]) -> f64 {
        nalgebra::Matrix6::from_fn(|i, j| m[i][j]).determinant()
    }

    #[test]
    fn det_j_is_the_product_of_the_three_factors() {
        let mut rng = ChaCha8Rng::seed_from_u64(560);
        let mut kappa = None;
        for _ in 0..50 {
            let q: Vec<f64> = (0..6).map(|_| rng.random_range(-3.0..3.0)).collect();
            let f = singularity_factors::<f64>(&q);
            let ratio = det6(jacobian(&q)) / (f[0] * f[1] * f[2]);
            let k0 = *kappa.get_or_insert(ratio);
            assert!((ratio - k0).abs() < 1e-9, "{ratio} vs {k0}");
        }
        // κ = a2.
        assert!((kappa.unwrap() - DH[1].a).abs() < 1e-9);
    }

    #[test]
    fn zero_angles_put_the_flange_where_corke_does() {
        // Corke's `p560.fkine(qz)`: translation (0.4521, −0.1500, 0.4318).
        let f = frames::<f64>(&Pose::identity(), &[0.0; 6]);
        let p = f[6].p;
        assert!((p[0] - 0.4521).abs() < 1e-12, "{p:?}");
        assert!((p[1] + 0.15005).abs() < 1e-12, "{p:?}");
        assert!((p[2] - 0.4318).abs() < 1e-12, "{p:?}");
    }
}
