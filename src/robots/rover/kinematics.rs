//! Overconstrained rover (seed 002, Murphey, Eq. 5): one steered, driven front wheel and two
//! fixed, passive rear axles, modelled as a multiple-model (switching) kinematic system.
//!
//! # Coordinates
//! State q = (x, y, θ, ψ): (x, y) is the centre of the **middle** axle (the reference point for
//! which the seed's g_a and g_b are written; checked by the constraint tests below), θ the body
//! heading, ψ the front-wheel steering angle (positive = left). The body x axis points from the
//! back axle through the middle axle to the front wheel: front wheel at +l, back axle at −r.
//!
//! The seed writes q = (x, y, θ, ψ, φ) with φ the front wheel's rolling angle, but prints g_a, g_b,
//! g_3 with four entries. φ is cyclic (no vector field depends on it) and appears only in the
//! front wheel's no-forward-slip constraint ω2, which merely fixes φ' = u1 / ρ (ρ = wheel radius).
//! We drop φ from the state; [`RoverGeometry::g_full`] and [`RoverGeometry::omega_full`] restore
//! it so tests can check every constraint, including ω2, in the seed's five coordinates.
//!
//! # Inputs
//! u1: front-wheel ground speed, m/s (drive); u2: steering rate ψ', rad/s. With u1 the front
//! wheel's speed, the middle axle moves at u1 cos ψ and the body turns at u1 sin ψ / L with L the
//! wheelbase of the axle that holds (L = l for σ = a, L = l + r for σ = b), which is the seed's
//! g_a / g_b. The seed's Section II vector (cos θ, sin θ, 0, 0, 1) at ψ = 0 has φ' = u1, i.e. it
//! silently takes a unit wheel radius; we keep ρ explicit.
//!
//! # Models
//! σ = a: the middle wheels hold sideways (Ω1 = {ω1, ω2, ω3}), the back wheels slip.
//! σ = b: the back wheels hold (Ω2 = {ω1, ω2, ω4}), the middle wheels slip.
//! At ψ = 0 both coincide (straight driving needs no slip).
//!
//! # Default dimensions
//! Rocky 7 (JPL prototype, Volpe et al., "Rocky 7: A Next Generation Mars Rover Prototype",
//! Advanced Robotics 11(4), 1997) measures about 48 × 64 × 32 cm on six wheels in three axle
//! pairs. We place the three axles evenly over a 0.5 m wheelbase inside the 0.64 m body
//! (l = r = 0.25 m) and use Sojourner-class 13 cm wheels (ρ = 0.065 m). These are Rocky-7-like
//! estimates, not measured values. (The seed calls Rocky 7 "the first rover to travel to Mars";
//! that was Sojourner, 1997; Rocky 7 was its research successor and never flew.)

use crate::model::{Input, KinematicModel, State};
use nalgebra::{DMatrix, DVector, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use schemars::JsonSchema;

/// Which rear contact holds (the multiple-model index σ of Eq. 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Sigma {
    /// Middle wheels hold (constraint set Ω1), back wheels slip; wheelbase l.
    A,
    /// Back wheels hold (constraint set Ω2), middle wheels slip; wheelbase l + r.
    B,
}

impl Sigma {
    /// The other model.
    pub fn flipped(self) -> Sigma {
        match self {
            Sigma::A => Sigma::B,
            Sigma::B => Sigma::A,
        }
    }
}

/// Rover dimensions, metres.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize, serde::Serialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct RoverGeometry {
    /// Middle axle to front wheel (the seed's l).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub l: f64,
    /// Back axle to middle axle (the seed's r).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub r: f64,
    /// Front wheel radius ρ (only enters φ' = u1/ρ and the constraint ω2).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub wheel_radius: f64,
}

impl Default for RoverGeometry {
    /// Rocky-7-like estimates, see the module docs.
    fn default() -> Self {
        RoverGeometry {
            l: 0.25,
            r: 0.25,
            wheel_radius: 0.065,
        }
    }
}

/// A rover length that is not finite and positive.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("rover `{name}` must be finite and > 0, got {value}")]
pub struct GeometryError {
    /// The field: `l`, `r` or `wheel_radius`.
    pub name: &'static str,
    /// The value given.
    pub value: f64,
}

impl RoverGeometry {
    /// Checks that all lengths are finite and positive.
    pub fn validate(&self) -> Result<(), GeometryError> {
        for (name, value) in [
            ("l", self.l),
            ("r", self.r),
            ("wheel_radius", self.wheel_radius),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(GeometryError { name, value });
            }
        }
        Ok(())
    }

    /// Wheelbase of the holding axle: l for σ = a, l + r for σ = b.
    pub fn wheelbase(&self, sigma: Sigma) -> f64 {
        match sigma {
            Sigma::A => self.l,
            Sigma::B => self.l + self.r,
        }
    }

    /// g_a(q) of Eq. 5 (four entries: x, y, θ, ψ).
    pub fn g_a(&self, q: &State) -> State {
        self.g_sigma(Sigma::A, q)
    }

    /// g_b(q) of Eq. 5 (four entries: x, y, θ, ψ).
    pub fn g_b(&self, q: &State) -> State {
        self.g_sigma(Sigma::B, q)
    }

    /// g_3 of Eq. 5: steering only.
    pub fn g3(&self) -> State {
        State::from_vec(vec![0.0, 0.0, 0.0, 1.0])
    }

    /// g_σ(q): the drive vector field of model σ.
    pub fn g_sigma(&self, sigma: Sigma, q: &State) -> State {
        let b = self.body_rates(sigma, q[3]);
        let (s, c) = q[2].sin_cos();
        State::from_vec(vec![c * b.x - s * b.y, s * b.x + c * b.y, b.z, 0.0])
    }

    /// Middle-axle velocity in the body frame and yaw rate per unit drive:
    /// (forward, lateral, θ') for model σ at steering angle ψ.
    pub fn body_rates(&self, sigma: Sigma, psi: f64) -> Vector3<f64> {
        let (sp, cp) = psi.sin_cos();
        match sigma {
            Sigma::A => Vector3::new(cp, 0.0, sp / self.l),
            Sigma::B => {
                let lr = self.l + self.r;
                Vector3::new(cp, self.r * sp / lr, sp / lr)
            }
        }
    }

    /// The drive field of model σ lifted to the seed's five coordinates (x, y, θ, ψ, φ):
    /// the rolling angle advances at φ' = u1 / ρ.
    pub fn g_full(&self, sigma: Sigma, q: &State) -> DVector<f64> {
        let g = self.g_sigma(sigma, q);
        DVector::from_vec(vec![g[0], g[1], g[2], 0.0, 1.0 / self.wheel_radius])
    }

    /// g_3 in five coordinates.
    pub fn g3_full(&self) -> DVector<f64> {
        DVector::from_vec(vec![0.0, 0.0, 0.0, 1.0, 0.0])
    }

    /// The four contact constraints as one-forms (rows) on (x, y, θ, ψ, φ), `i` = 1..=4:
    /// ω1 front wheel no side slip, ω2 front wheel rolls without forward slip,
    /// ω3 middle axle no side slip, ω4 back axle no side slip. Derived from the contact point
    /// velocities of the rigid body; `q` needs only (x, y, θ, ψ).
    pub fn omega_full(&self, i: usize, q: &State) -> DVector<f64> {
        let (th, psi) = (q[2], q[3]);
        let (sb, cb) = (th + psi).sin_cos();
        let (st, ct) = th.sin_cos();
        let row = match i {
            1 => [-sb, cb, self.l * psi.cos(), 0.0, 0.0],
            2 => [cb, sb, self.l * psi.sin(), 0.0, -self.wheel_radius],
            3 => [-st, ct, 0.0, 0.0, 0.0],
            4 => [-st, ct, -self.r, 0.0, 0.0],
            _ => [f64::NAN; 5],
        };
        DVector::from_row_slice(&row)
    }

    /// Constraint set of model σ as a 3 × 5 matrix (rows ω): Ω1 = [ω1, ω2, ω3] for σ = a,
    /// Ω2 = [ω1, ω2, ω4] for σ = b. Its kernel is spanned by g_full(σ) and g3_full.
    pub fn omega_set(&self, sigma: Sigma, q: &State) -> DMatrix<f64> {
        let ids = match sigma {
            Sigma::A => [1, 2, 3],
            Sigma::B => [1, 2, 4],
        };
        let rows: Vec<_> = ids
            .iter()
            .map(|&i| self.omega_full(i, q).transpose())
            .collect();
        DMatrix::from_rows(&rows)
    }

    /// All four constraints (the overconstrained A(q) of Section II), 4 × 5.
    pub fn omega_all(&self, q: &State) -> DMatrix<f64> {
        let rows: Vec<_> = (1..=4).map(|i| self.omega_full(i, q).transpose()).collect();
        DMatrix::from_rows(&rows)
    }

    /// Constraint set of model σ on the reduced state (x, y, θ, ψ), 2 × 4: ω2 is the only
    /// constraint involving φ and just defines φ', so it drops out with φ; what remains is
    /// [ω1, ω3] (σ = a) or [ω1, ω4] (σ = b) restricted to the first four coordinates.
    pub fn omega_set_reduced(&self, sigma: Sigma, q: &State) -> DMatrix<f64> {
        let full = self.omega_set(sigma, q);
        DMatrix::from_fn(2, 4, |i, j| full[(if i == 0 { 0 } else { 2 }, j)])
    }
}

/// Result of comparing a measured body velocity with the two-model envelope.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EnvelopeFit {
    /// Euclidean distance (m/s and rad/s weighted alike, as the seed's SE(2) metric does) from
    /// the measured (x', y', θ') to the segment between g_a u1 and g_b u1.
    pub distance: f64,
    /// Position along the segment of the nearest point: 0 = model a, 1 = model b. `None` when
    /// the two models agree (ψ = 0 or u1 = 0), so σ is unobservable.
    pub sigma: Option<f64>,
    /// The nearest allowed (x', y', θ').
    pub nearest: Vector3<f64>,
}

impl EnvelopeFit {
    /// The model the measurement is closer to (ties go to a); `None` when unobservable.
    pub fn closer_model(&self) -> Option<Sigma> {
        self.sigma
            .map(|s| if s <= 0.5 { Sigma::A } else { Sigma::B })
    }
}

/// Distance from a measured body velocity to what the multiple-model system allows for the
/// applied inputs. The allowed set is the convex hull {λ g_a u1 + (1−λ) g_b u1} + g3 u2 (the
/// differential inclusion that lets σ switch arbitrarily fast); g3 has no (x, y, θ) part, so in
/// (x', y', θ') it is the segment between g_a u1 and g_b u1.
pub fn envelope(
    geom: &RoverGeometry,
    q: &State,
    u: &Input,
    measured: &Vector3<f64>,
) -> EnvelopeFit {
    let ga = geom.g_a(q) * u[0];
    let gb = geom.g_b(q) * u[0];
    let a = Vector3::new(ga[0], ga[1], ga[2]);
    let b = Vector3::new(gb[0], gb[1], gb[2]);
    let ab = b - a;
    let len2 = ab.norm_squared();
    // Relative threshold: below it the segment is a point and σ carries no information.
    if len2 <= 1e-24 * (1.0 + a.norm_squared()) {
        return EnvelopeFit {
            distance: (measured - a).norm(),
            sigma: None,
            nearest: a,
        };
    }
    let s = ((measured - a).dot(&ab) / len2).clamp(0.0, 1.0);
    let nearest = a + ab * s;
    EnvelopeFit {
        distance: (measured - nearest).norm(),
        sigma: Some(s),
        nearest,
    }
}

/// The switching signal σ(t).
#[derive(Debug, Clone, PartialEq)]
pub enum SwitchingSignal {
    /// σ ≡ a.
    FixedA,
    /// σ ≡ b.
    FixedB,
    /// Random telegraph process (see [`SwitchingSignal::telegraph`]).
    Telegraph {
        /// RNG seed.
        seed: u64,
        /// Mean switching rate, 1/s.
        rate: f64,
        /// σ on [0, first switch).
        initial: Sigma,
        /// Precomputed, increasing switch times in (0, horizon].
        switches: Vec<f64>,
    },
}

/// Why a random telegraph signal cannot be drawn.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum TelegraphError {
    /// The switching rate is negative or not finite.
    #[error("telegraph rate must be finite and >= 0, got {0}")]
    Rate(f64),
    /// The horizon is negative or not finite.
    #[error("telegraph horizon must be finite and >= 0, got {}", crate::numfmt::readable(*.0))]
    Horizon(f64),
    /// rate × horizon (the expected number of switches) is over 1e7.
    #[error("telegraph rate × horizon = {} exceeds 1e7 switches", crate::numfmt::readable(*.0))]
    TooManySwitches(f64),
}

impl SwitchingSignal {
    /// Random telegraph process: σ(0) is a fair coin, then σ flips at the events of a Poisson
    /// process of `rate` (1/s). Switch times are drawn once from ChaCha8 seeded with `seed` up to
    /// `horizon` seconds, so σ(t) is a pure function of (seed, rate, t): RK4 stages and repeated
    /// runs see the same signal. After `horizon` σ holds its last value.
    pub fn telegraph(seed: u64, rate: f64, horizon: f64) -> Result<Self, TelegraphError> {
        if !(rate.is_finite() && rate >= 0.0) {
            return Err(TelegraphError::Rate(rate));
        }
        if !(horizon.is_finite() && horizon >= 0.0) {
            return Err(TelegraphError::Horizon(horizon));
        }
        if rate * horizon > 1e7 {
            return Err(TelegraphError::TooManySwitches(rate * horizon));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let initial = if rng.random_bool(0.5) {
            Sigma::A
        } else {
            Sigma::B
        };
        let mut switches = Vec::new();
        if rate > 0.0 {
            let mut t = 0.0;
            loop {
                let u: f64 = rng.random(); // [0, 1)
                t += -(1.0 - u).ln() / rate;
                if t > horizon {
                    break;
                }
                switches.push(t);
            }
        }
        Ok(SwitchingSignal::Telegraph {
            seed,
            rate,
            initial,
            switches,
        })
    }

    /// σ(t).
    pub fn at(&self, t: f64) -> Sigma {
        match self {
            SwitchingSignal::FixedA => Sigma::A,
            SwitchingSignal::FixedB => Sigma::B,
            SwitchingSignal::Telegraph {
                initial, switches, ..
            } => {
                let n = switches.partition_point(|&s| s <= t);
                if n % 2 == 0 {
                    *initial
                } else {
                    initial.flipped()
                }
            }
        }
    }
}

/// The multiple-model rover q' = g_σ(t)(q) u1 + g3 u2 with a prescribed switching signal.
#[derive(Debug, Clone)]
pub struct SwitchingRover {
    /// Dimensions.
    pub geometry: RoverGeometry,
    /// σ(t).
    pub signal: SwitchingSignal,
}

impl SwitchingRover {
    /// A rover with the given geometry and switching signal.
    pub fn new(geometry: RoverGeometry, signal: SwitchingSignal) -> Self {
        SwitchingRover { geometry, signal }
    }

    /// G(q) = [g_σ, g3] for a given model.
    pub fn input_matrix_for(&self, sigma: Sigma, q: &State) -> DMatrix<f64> {
        let g = self.geometry.g_sigma(sigma, q);
        DMatrix::from_row_slice(4, 2, &[g[0], 0.0, g[1], 0.0, g[2], 0.0, 0.0, 1.0])
    }
}

impl KinematicModel for SwitchingRover {
    fn position_states(&self) -> Option<[usize; 2]> {
        Some([0, 1])
    }
    fn name(&self) -> &'static str {
        "switching_rover"
    }
    fn state_names(&self) -> &'static [&'static str] {
        &["x", "y", "theta", "psi"]
    }
    fn input_names(&self) -> &'static [&'static str] {
        &["drive", "steer_rate"]
    }
    fn angular_states(&self) -> &'static [usize] {
        &[2, 3]
    }
    /// G(q) of the model active at t = 0 (the trait has no time argument); the true,
    /// time-dependent field is [`KinematicModel::velocity`].
    fn input_matrix(&self, q: &State) -> DMatrix<f64> {
        self.input_matrix_for(self.signal.at(0.0), q)
    }
    fn velocity(&self, t: f64, q: &State, u: &Input) -> State {
        let b = self.geometry.body_rates(self.signal.at(t), q[3]);
        let (s, c) = q[2].sin_cos();
        State::from_vec(vec![
            (c * b.x - s * b.y) * u[0],
            (s * b.x + c * b.y) * u[0],
            b.z * u[0],
            u[1],
        ])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn st(x: f64, y: f64, th: f64, psi: f64) -> State {
        State::from_vec(vec![x, y, th, psi])
    }

    proptest! {
        #![proptest_config(crate::prop_config::config(64))]
        /// Each model annihilates its own constraint set (the seed: "g_a and g_3 annihilate Ω1,
        /// g_b and g_3 annihilate Ω2"), in five coordinates and reduced to four.
        #[test]
        fn models_annihilate_their_constraints(
            x in -10.0..10.0f64, y in -10.0..10.0f64, th in -4.0..4.0f64, psi in -1.2..1.2f64,
            l in 0.1..1.0f64, r in 0.1..1.0f64, rho in 0.02..0.3f64,
        ) {
            let g = RoverGeometry { l, r, wheel_radius: rho };
            let q = st(x, y, th, psi);
            for sigma in [Sigma::A, Sigma::B] {
                let om = g.omega_set(sigma, &q);
                prop_assert!((&om * g.g_full(sigma, &q)).amax() < 1e-12);
                prop_assert!((&om * g.g3_full()).amax() < 1e-12);
                let red = g.omega_set_reduced(sigma, &q);
                prop_assert!((&red * g.g_sigma(sigma, &q)).amax() < 1e-12);
                prop_assert!((&red * g.g3()).amax() < 1e-12);
            }
        }
    }

    /// The models really differ: for ψ ≠ 0 each violates the other's rear constraint, so no drive
    /// field satisfies all four constraints (the seed's "not kinematically well-posed").
    #[test]
    fn each_model_breaks_the_other_rear_constraint() {
        let g = RoverGeometry::default();
        let q = st(1.0, -2.0, 0.7, 0.4);
        assert!(g.omega_full(4, &q).dot(&g.g_full(Sigma::A, &q)).abs() > 1e-3);
        assert!(g.omega_full(3, &q).dot(&g.g_full(Sigma::B, &q)).abs() > 1e-3);
    }

    /// Section II: with all four constraints, the kernel of A(q) is span{g3} for ψ ≠ 0 and
    /// span{g3, (cos θ, sin θ, 0, 0, 1/ρ)} at ψ = 0.
    #[test]
    fn overconstrained_kernel_dimension() {
        let g = RoverGeometry::default();
        let rank = |m: DMatrix<f64>| m.svd(false, false).rank(1e-10);
        let q = st(0.3, 0.1, 1.1, 0.5);
        assert_eq!(5 - rank(g.omega_all(&q)), 1);
        let q0 = st(0.3, 0.1, 1.1, 0.0);
        assert_eq!(5 - rank(g.omega_all(&q0)), 2);
        assert!((g.omega_all(&q0) * g.g_full(Sigma::A, &q0)).amax() < 1e-12);
    }

    proptest! {
        #![proptest_config(crate::prop_config::config(32))]
        /// g_a = g_b at ψ = 0 (no switching uncertainty when driving straight).
        #[test]
        fn models_agree_when_straight(th in -4.0..4.0f64, l in 0.1..1.0f64, r in 0.1..1.0f64) {
            let g = RoverGeometry { l, r, wheel_radius: 0.1 };
            let q = st(0.0, 0.0, th, 0.0);
            prop_assert!((g.g_a(&q) - g.g_b(&q)).amax() < 1e-15);
        }
    }

    /// The seed's printed g_b, entry by entry.
    #[test]
    fn g_b_matches_printed_formula() {
        let g = RoverGeometry {
            l: 0.3,
            r: 0.2,
            wheel_radius: 0.1,
        };
        let (th, psi) = (0.9f64, -0.35f64);
        let gb = g.g_b(&st(0.0, 0.0, th, psi));
        let lr = g.l + g.r;
        let printed = [
            psi.cos() * th.cos() - g.r * th.sin() * psi.sin() / lr,
            psi.cos() * th.sin() + g.r * th.cos() * psi.sin() / lr,
            psi.sin() / lr,
            0.0,
        ];
        for i in 0..4 {
            assert!((gb[i] - printed[i]).abs() < 1e-15);
        }
    }

    #[test]
    fn telegraph_is_deterministic_and_switches_at_rate() {
        let a = SwitchingSignal::telegraph(7, 2.0, 500.0).unwrap();
        let b = SwitchingSignal::telegraph(7, 2.0, 500.0).unwrap();
        assert_eq!(a, b);
        let c = SwitchingSignal::telegraph(8, 2.0, 500.0).unwrap();
        assert_ne!(a, c);
        let SwitchingSignal::Telegraph { switches, .. } = &a else {
            unreachable!()
        };
        // Poisson count over 500 s at 2/s: mean 1000, sd ≈ 32.
        assert!(
            (switches.len() as f64 - 1000.0).abs() < 150.0,
            "{}",
            switches.len()
        );
        // σ flips across each switch time.
        let t = switches[3];
        assert_ne!(a.at(t - 1e-9), a.at(t + 1e-9));
        // Time spent in each model is about half.
        let n = 100_000;
        let in_a = (0..n)
            .filter(|k| a.at(*k as f64 * 500.0 / n as f64) == Sigma::A)
            .count();
        assert!((in_a as f64 / n as f64 - 0.5).abs() < 0.1);
        assert!(SwitchingSignal::telegraph(1, -1.0, 10.0).is_err());
        assert!(SwitchingSignal::telegraph(1, f64::NAN, 10.0).is_err());
    }

    #[test]
    fn velocity_follows_sigma() {
        let g = RoverGeometry::default();
        let q = st(0.0, 0.0, 0.2, 0.3);
        let u = Input::from_vec(vec![0.1, 0.05]);
        let ra = SwitchingRover::new(g, SwitchingSignal::FixedA);
        let rb = SwitchingRover::new(g, SwitchingSignal::FixedB);
        assert!((ra.velocity(3.0, &q, &u) - (g.g_a(&q) * 0.1 + g.g3() * 0.05)).amax() < 1e-15);
        assert!((rb.velocity(3.0, &q, &u) - (g.g_b(&q) * 0.1 + g.g3() * 0.05)).amax() < 1e-15);
        assert!((ra.input_matrix(&q) * &u - ra.velocity(0.0, &q, &u)).amax() < 1e-15);
        let tel = SwitchingRover::new(g, SwitchingSignal::telegraph(3, 1.0, 100.0).unwrap());
        for k in 0..200 {
            let t = k as f64 * 0.37;
            let want = g.g_sigma(tel.signal.at(t), &q) * 0.1 + g.g3() * 0.05;
            assert!((tel.velocity(t, &q, &u) - want).amax() < 1e-15);
        }
    }

    #[test]
    fn envelope_recovers_sigma_and_distance() {
        let g = RoverGeometry::default();
        let q = st(0.5, 0.5, 0.8, 0.4);
        let u = Input::from_vec(vec![0.2, -0.1]);
        let v3 = |s: State| Vector3::new(s[0], s[1], s[2]);
        let va = v3(g.g_a(&q) * 0.2);
        let vb = v3(g.g_b(&q) * 0.2);
        // Pure models and a mixture.
        let fa = envelope(&g, &q, &u, &va);
        assert!(fa.distance < 1e-15 && fa.sigma.unwrap().abs() < 1e-12);
        assert_eq!(fa.closer_model(), Some(Sigma::A));
        let fb = envelope(&g, &q, &u, &vb);
        assert!(fb.distance < 1e-15 && (fb.sigma.unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(fb.closer_model(), Some(Sigma::B));
        let mix = va * 0.3 + vb * 0.7;
        let fm = envelope(&g, &q, &u, &mix);
        assert!(fm.distance < 1e-15 && (fm.sigma.unwrap() - 0.7).abs() < 1e-12);
        // An off-segment measurement: add a component orthogonal to the segment.
        let ab = vb - va;
        let n = ab.cross(&Vector3::new(0.0, 0.0, 1.0)).normalize();
        let off = va * 0.6 + vb * 0.4 + n * 0.01;
        let fo = envelope(&g, &q, &u, &off);
        assert!((fo.distance - 0.01).abs() < 1e-12);
        assert!((fo.sigma.unwrap() - 0.4).abs() < 1e-9);
        // Beyond the b end: clamped, distance to the end point.
        let beyond = vb + ab * 0.5;
        let fbey = envelope(&g, &q, &u, &beyond);
        assert_eq!(fbey.sigma, Some(1.0));
        assert!((fbey.distance - 0.5 * ab.norm()).abs() < 1e-12);
        // Straight wheel: models agree, σ unobservable.
        let q0 = st(0.0, 0.0, 0.8, 0.0);
        let f0 = envelope(&g, &q0, &u, &Vector3::new(0.0, 0.0, 0.0));
        assert_eq!(f0.sigma, None);
        assert!((f0.distance - 0.2).abs() < 1e-12);
    }

    /// A trajectory integrated under σ ≡ a has velocities on the a end of the envelope, and one
    /// under a telegraph σ matches σ(t) wherever the wheel is turned.
    #[test]
    fn envelope_identifies_sigma_along_a_telegraph_run() {
        let g = RoverGeometry::default();
        let rover = SwitchingRover::new(g, SwitchingSignal::telegraph(11, 0.5, 100.0).unwrap());
        let u = Input::from_vec(vec![0.1, 0.02]);
        let mut q = st(0.0, 0.0, 0.0, 0.1);
        for k in 0..500 {
            let t = k as f64 * 0.05;
            let v = rover.velocity(t, &q, &u);
            let fit = envelope(&g, &q, &u, &Vector3::new(v[0], v[1], v[2]));
            assert!(fit.distance < 1e-12);
            assert_eq!(fit.closer_model(), Some(rover.signal.at(t)));
            q += v * 0.05;
        }
    }
}
