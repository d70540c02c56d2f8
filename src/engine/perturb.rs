//! Perturbations of the physics replay: what a real robot adds to the
//! simulated one. The ideal run is never perturbed.
//!
//! A [`Perturbation`] is a set of plain numbers (`[sim.perturb]` in a
//! scenario), each off by default:
//!
//! * on the **command path** (every physics system): `command_latency` (s,
//!   the drives receive each command this much later), `actuator_tau` (s, a
//!   first-order lag on each drive's command), `torque_scale` (the drives'
//!   torque limit);
//! * on the **state a feedback law sees** (feedback laws only):
//!   `state_noise` (Gaussian, σ per coordinate in its SI unit, seeded by
//!   `seed`) and `state_latency` (s, the law sees a state this old);
//! * on the **world**: `friction_scale`, `mass_scale` (every URDF link's mass
//!   and inertia) and `wheel_radius_scale` (wheeled systems only: the
//!   model and the controller believe the nominal radius, the simulated
//!   wheels have the scaled one).
//!
//! Which dimensions reach which system is declared by the system
//! ([`crate::robots::System::perturbable`], default [`Dimension::common`]).
//! [`Reality`] applies the command and observation perturbations inside the
//! replay loop; the world ones are [`crate::engine::PhysicsSettings`] fields.
//!
//! Exact definitions (tests check them):
//! * Latency L = (n + f)·dt, 0 ≤ f < 1: the replay applies a command c_k
//!   (constant over step k); the drives receive, over step k, the mean of
//!   the delayed signal c(t − L) over that step, (1 − f)·c_{k−n} + f·c_{k−n−1}
//!   (c_j = 0 for j < 0). For L a multiple of dt this is c_{k−n} exactly.
//!   The run lasts ⌈L/dt⌉ steps longer, so every command arrives.
//! * Lag τ: the actuator state a obeys τ a' = c − a, a(0) = 0, with c
//!   constant over each step (exact discretisation); the drives receive the
//!   mean of a over the step, so their integrated angle is exact.
//! * State latency Ls = (m + g)·dt: the law sees the recorded state at
//!   t − Ls, interpolated linearly between the two samples around it (the
//!   start state before t = Ls).
//! * Noise σ: each time the law is sampled, every coordinate of what it sees
//!   gets an independent N(0, σ²) deviate (ChaCha8 seeded with `seed`).

use crate::error::SetupError;
use crate::model::{Input, State};
use crate::plan::{ControlLaw, Plan};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `[sim.perturb]`: what reality adds to the physics replay, every value off
/// (0 or 1) by default. The ideal run is never perturbed; a key that does not
/// apply to the system or plan is refused.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct Perturbation {
    /// Delay from the controller to the drives, s: the drives receive each command this much later (at most the plan's duration, or the horizon of a feedback law).
    #[schemars(range(min = 0))]
    pub command_latency: f64,
    /// Time constant of a first-order lag on each drive's command, s (at most the plan's duration, or the horizon of a feedback law).
    #[schemars(range(min = 0))]
    pub actuator_tau: f64,
    /// Factor on each drive's effective torque limit, whatever its source (the URDF's `<limit effort>`, a model key or `sim.motor_max_torque`).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub torque_scale: f64,
    /// Standard deviation of the Gaussian noise on each coordinate of the
    /// state a feedback law sees (m, rad, in each coordinate's SI unit); feedback laws only.
    #[schemars(range(min = 0))]
    pub state_noise: f64,
    /// Age of the state a feedback law sees, s (feedback laws only; at most the horizon).
    #[schemars(range(min = 0))]
    pub state_latency: f64,
    /// Factor on the simulated wheels' radius; the model and the controller keep the nominal one (wheeled models only).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub wheel_radius_scale: f64,
    /// Factor on every friction coefficient (`sim.friction`).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub friction_scale: f64,
    /// Factor on every URDF link's mass and inertia (the model keeps the URDF's).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub mass_scale: f64,
    /// Seed of the state noise (ChaCha8): the same seed gives the same run.
    pub seed: u64,
}

impl Default for Perturbation {
    fn default() -> Self {
        Perturbation {
            command_latency: 0.0,
            actuator_tau: 0.0,
            torque_scale: 1.0,
            state_noise: 0.0,
            state_latency: 0.0,
            wheel_radius_scale: 1.0,
            friction_scale: 1.0,
            mass_scale: 1.0,
            seed: 0,
        }
    }
}

impl Perturbation {
    /// The dimensions set away from nominal (the seed is not a dimension).
    pub fn active(&self) -> Vec<Dimension> {
        Dimension::ALL
            .into_iter()
            .filter(|d| d.value(self) != d.nominal())
            .collect()
    }

    /// Checks the ranges; the message starts with the key (`sim.perturb.<name>`).
    pub fn validate(&self) -> Result<(), SetupError> {
        for d in Dimension::ALL {
            let v = d.value(self);
            let bad = match d.kind() {
                Kind::Scale => !(v > 0.0 && v.is_finite()),
                Kind::Amount => !(v >= 0.0 && v.is_finite()),
            };
            if bad {
                let need = match d.kind() {
                    Kind::Scale => "a factor > 0",
                    Kind::Amount => "≥ 0",
                };
                return Err(SetupError::key(
                    format!("sim.perturb.{}", d.name()),
                    format!(
                        "must be {need}, got {}{}",
                        crate::numfmt::readable(v),
                        d.unit_suffix()
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The active dimensions as a JSON object (name → value), for logs.
    pub fn active_json(&self) -> serde_json::Value {
        let mut m = serde_json::Map::new();
        for d in self.active() {
            m.insert(d.name().into(), serde_json::json!(d.value(self)));
        }
        if self.state_noise > 0.0 {
            m.insert("seed".into(), serde_json::json!(self.seed));
        }
        serde_json::Value::Object(m)
    }
}

/// A perturbation dimension (a key of `[sim.perturb]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dimension {
    /// `command_latency`.
    CommandLatency,
    /// `actuator_tau`.
    ActuatorTau,
    /// `torque_scale`.
    TorqueScale,
    /// `state_noise`.
    StateNoise,
    /// `state_latency`.
    StateLatency,
    /// `wheel_radius_scale`.
    WheelRadiusScale,
    /// `friction_scale`.
    FrictionScale,
    /// `mass_scale`.
    MassScale,
}

/// Whether a dimension is an amount added to nothing (0 nominal) or a factor (1 nominal).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// 0 is nominal; must be ≥ 0.
    Amount,
    /// 1 is nominal; must be > 0.
    Scale,
}

impl Dimension {
    /// Every dimension, in the order of `[sim.perturb]`.
    pub const ALL: [Dimension; 8] = [
        Dimension::CommandLatency,
        Dimension::ActuatorTau,
        Dimension::TorqueScale,
        Dimension::StateNoise,
        Dimension::StateLatency,
        Dimension::WheelRadiusScale,
        Dimension::FrictionScale,
        Dimension::MassScale,
    ];

    /// The key name.
    pub fn name(self) -> &'static str {
        match self {
            Dimension::CommandLatency => "command_latency",
            Dimension::ActuatorTau => "actuator_tau",
            Dimension::TorqueScale => "torque_scale",
            Dimension::StateNoise => "state_noise",
            Dimension::StateLatency => "state_latency",
            Dimension::WheelRadiusScale => "wheel_radius_scale",
            Dimension::FrictionScale => "friction_scale",
            Dimension::MassScale => "mass_scale",
        }
    }

    /// The dimension of a key name.
    pub fn parse(name: &str) -> Option<Dimension> {
        Dimension::ALL.into_iter().find(|d| d.name() == name)
    }

    /// Amount or factor.
    pub fn kind(self) -> Kind {
        match self {
            Dimension::TorqueScale
            | Dimension::WheelRadiusScale
            | Dimension::FrictionScale
            | Dimension::MassScale => Kind::Scale,
            _ => Kind::Amount,
        }
    }

    /// The nominal (unperturbed) value.
    pub fn nominal(self) -> f64 {
        match self.kind() {
            Kind::Amount => 0.0,
            Kind::Scale => 1.0,
        }
    }

    /// Unit of the value (and of a margin of an amount), for messages.
    pub fn unit(self) -> &'static str {
        match self {
            Dimension::CommandLatency | Dimension::ActuatorTau | Dimension::StateLatency => "s",
            Dimension::StateNoise => "m|rad",
            _ => "",
        }
    }

    fn unit_suffix(self) -> String {
        match self.unit() {
            "" => String::new(),
            u => format!(" {u}"),
        }
    }

    /// Whether it draws random numbers (a margin then needs several seeds per level).
    pub fn random(self) -> bool {
        self == Dimension::StateNoise
    }

    /// Whether it acts on the state a feedback law sees (so only on feedback laws).
    pub fn observes(self) -> bool {
        matches!(self, Dimension::StateNoise | Dimension::StateLatency)
    }

    /// The value in `p`.
    pub fn value(self, p: &Perturbation) -> f64 {
        match self {
            Dimension::CommandLatency => p.command_latency,
            Dimension::ActuatorTau => p.actuator_tau,
            Dimension::TorqueScale => p.torque_scale,
            Dimension::StateNoise => p.state_noise,
            Dimension::StateLatency => p.state_latency,
            Dimension::WheelRadiusScale => p.wheel_radius_scale,
            Dimension::FrictionScale => p.friction_scale,
            Dimension::MassScale => p.mass_scale,
        }
    }

    /// Set the value in `p`.
    pub fn set(self, p: &mut Perturbation, v: f64) {
        let slot = match self {
            Dimension::CommandLatency => &mut p.command_latency,
            Dimension::ActuatorTau => &mut p.actuator_tau,
            Dimension::TorqueScale => &mut p.torque_scale,
            Dimension::StateNoise => &mut p.state_noise,
            Dimension::StateLatency => &mut p.state_latency,
            Dimension::WheelRadiusScale => &mut p.wheel_radius_scale,
            Dimension::FrictionScale => &mut p.friction_scale,
            Dimension::MassScale => &mut p.mass_scale,
        };
        *slot = v;
    }

    /// The value at perturbation magnitude `m` ≥ 0 (what a margin measures):
    /// the amount itself; for factors the way reality gets worse: weaker
    /// drives, less friction and worn (smaller) wheels are 1 − m, heavier
    /// links 1 + m.
    pub fn value_at(self, m: f64) -> f64 {
        match self {
            Dimension::MassScale => 1.0 + m,
            d if d.kind() == Kind::Scale => 1.0 - m,
            _ => m,
        }
    }

    /// The magnitude of a value (inverse of [`Dimension::value_at`]).
    pub fn magnitude_of(self, v: f64) -> f64 {
        match self {
            Dimension::MassScale => v - 1.0,
            d if d.kind() == Kind::Scale => 1.0 - v,
            _ => v,
        }
    }

    /// The dimensions every physics system takes: the command path, masses
    /// and friction, and for a feedback law what it sees. Systems without
    /// contact drop friction, wheeled systems add the wheel radius.
    pub fn common(plan: &Plan) -> Vec<Dimension> {
        let mut out = vec![
            Dimension::CommandLatency,
            Dimension::ActuatorTau,
            Dimension::TorqueScale,
            Dimension::FrictionScale,
            Dimension::MassScale,
        ];
        if matches!(plan.law, ControlLaw::Feedback { .. }) {
            out.extend([Dimension::StateNoise, Dimension::StateLatency]);
        }
        out
    }
}

impl std::fmt::Display for Dimension {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A standard normal deviate (Box–Muller, one of the pair). Not `rand_distr`:
/// it turns on num-traits' `libm` feature, which rebuilds nalgebra, Rapier
/// and the Rerun SDK.
pub fn standard_normal(r: &mut ChaCha8Rng) -> f64 {
    // u1 in (0, 1], so the logarithm is finite.
    let u1 = 1.0 - r.random::<f64>();
    let u2 = r.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// A duration as whole steps plus a fraction of a step: (n, f), 0 ≤ f < 1
/// (f snapped to 0 within round-off of the grid).
fn steps_and_fraction(duration: f64, dt: f64) -> (usize, f64) {
    if duration <= 0.0 {
        return (0, 0.0);
    }
    let x = duration / dt;
    let n = (x + 1e-9).floor();
    let f = x - n;
    (n as usize, if f < 1e-9 { 0.0 } else { f })
}

/// Steps a replay under `p` is extended by, so every delayed command arrives.
pub fn extra_steps(p: &Perturbation, dt: f64) -> usize {
    let (n, f) = steps_and_fraction(p.command_latency, dt);
    n.saturating_add(usize::from(f > 0.0))
}

/// The command and observation perturbations of one replay (module docs).
pub struct Reality {
    /// Latency: whole steps and the fraction of a step.
    lat: (usize, f64),
    /// The last `lat.0 + 2` commands, newest last.
    issued: std::collections::VecDeque<Input>,
    /// Lag: actuator state, e^(−dt/τ), and the mean of the step response
    /// over one step, (τ/dt)(1 − e^(−dt/τ)).
    lag: Option<(Input, f64, f64)>,
    /// State latency: whole steps and fraction.
    obs: (usize, f64),
    noise: f64,
    rng: ChaCha8Rng,
}

impl Reality {
    /// The perturbations of `p` for a replay with step `dt` and `inputs` inputs.
    pub fn new(p: &Perturbation, dt: f64, inputs: usize) -> Reality {
        let lag = (p.actuator_tau > 0.0).then(|| {
            let x = dt / p.actuator_tau;
            let decay = (-x).exp();
            // −expm1(−x)/x keeps full precision for τ ≫ dt.
            (Input::zeros(inputs), decay, -(-x).exp_m1() / x)
        });
        Reality {
            lat: steps_and_fraction(p.command_latency, dt),
            issued: std::collections::VecDeque::new(),
            lag,
            obs: steps_and_fraction(p.state_latency, dt),
            noise: p.state_noise,
            rng: ChaCha8Rng::seed_from_u64(p.seed),
        }
    }

    /// Whether the drives receive something other than what was issued.
    pub fn acts(&self) -> bool {
        self.lat != (0, 0.0) || self.lag.is_some()
    }

    /// Whether a feedback law sees something other than the current state.
    pub fn observes(&self) -> bool {
        self.obs != (0, 0.0) || self.noise > 0.0
    }

    /// What the drives receive over the next step, given the command issued for it.
    pub fn actuate(&mut self, issued: &Input) -> Input {
        let (n, f) = self.lat;
        let delayed = if (n, f) == (0, 0.0) {
            issued.clone()
        } else {
            self.issued.push_back(issued.clone());
            while self.issued.len() > n + 2 {
                self.issued.pop_front();
            }
            // c_{k−j} is at index len − 1 − j (zero before the first command).
            let len = self.issued.len();
            let at = |j: usize| {
                len.checked_sub(1 + j)
                    .map(|i| self.issued[i].clone())
                    .unwrap_or_else(|| Input::zeros(issued.len()))
            };
            if f == 0.0 {
                at(n)
            } else {
                at(n) * (1.0 - f) + at(n + 1) * f
            }
        };
        match &mut self.lag {
            None => delayed,
            Some((a, decay, mean)) => {
                // Mean over the step of c + (a0 − c) e^(−s/τ), then the state at its end.
                let out = &delayed + (&*a - &delayed) * *mean;
                *a = &delayed + (&*a - &delayed) * *decay;
                out
            }
        }
    }

    /// What a feedback law sees at sample `k` of the recorded states `q`
    /// (`q[k]` is the current one).
    pub fn observe(&mut self, q: &[State], k: usize) -> State {
        let (m, g) = self.obs;
        let at = |j: usize| &q[k.saturating_sub(j).min(q.len() - 1)];
        let mut seen = if g == 0.0 || k < m + 1 {
            at(m).clone()
        } else {
            at(m) * (1.0 - g) + at(m + 1) * g
        };
        if self.noise > 0.0 {
            for v in seen.iter_mut() {
                *v += self.noise * standard_normal(&mut self.rng);
            }
        }
        seen
    }
}

/// Channels `drive_issued_<input>` and `drive_received_<input>` (what the
/// controller sent, what the drives got, from each sample on) added to `sim`
/// when the commands were delayed or lagged (`sim.received` not empty), so
/// the logs show both: MCAP `/sim/channels`, Rerun `sim/drive_*`.
pub fn add_drive_channels(sim: &mut crate::record::SimTrajectory, input_names: &[&str]) {
    if sim.received.len() != sim.traj.u.len() {
        return;
    }
    for (j, name) in input_names.iter().enumerate() {
        let issued = sim.traj.u.iter().map(|u| u[j]).collect();
        sim.channels.push((format!("drive_issued_{name}"), issued));
    }
    for (j, name) in input_names.iter().enumerate() {
        let got = sim.received.iter().map(|u| u[j]).collect();
        sim.channels.push((format!("drive_received_{name}"), got));
    }
}

/// `robot` with its wheels' collision radius scaled by `s`
/// (`wheel_radius_scale`): itself when `s` is 1, else
/// [`shrink_round_collisions`] of `links`.
pub fn worn_wheels<'r>(
    robot: &'r urdf_rs::Robot,
    links: &[&str],
    s: f64,
) -> std::borrow::Cow<'r, urdf_rs::Robot> {
    if s == 1.0 {
        std::borrow::Cow::Borrowed(robot)
    } else {
        std::borrow::Cow::Owned(shrink_round_collisions(robot, links, s, None))
    }
}

/// `robot` with the collision radius of every sphere and cylinder of the
/// named links multiplied by `s` (wheel wear), or shrunk by `by` m when
/// `absolute` (tyres worn by the same depth everywhere).
pub fn shrink_round_collisions(
    robot: &urdf_rs::Robot,
    links: &[&str],
    s: f64,
    absolute: Option<f64>,
) -> urdf_rs::Robot {
    let mut out = robot.clone();
    for l in out
        .links
        .iter_mut()
        .filter(|l| links.contains(&l.name.as_str()))
    {
        for c in &mut l.collision {
            match &mut c.geometry {
                urdf_rs::Geometry::Sphere { radius }
                | urdf_rs::Geometry::Cylinder { radius, .. } => {
                    *radius = match absolute {
                        Some(by) => *radius - by,
                        None => *radius * s,
                    };
                }
                _ => {}
            }
        }
    }
    out
}

/// `robot` with every link's mass and inertia multiplied by `s` (`None` at 1).
pub fn scaled_masses(robot: &urdf_rs::Robot, s: f64) -> Option<urdf_rs::Robot> {
    if s == 1.0 {
        return None;
    }
    let mut out = robot.clone();
    for l in &mut out.links {
        l.inertial.mass.value *= s;
        let i = &mut l.inertial.inertia;
        for x in [
            &mut i.ixx, &mut i.ixy, &mut i.ixz, &mut i.iyy, &mut i.iyz, &mut i.izz,
        ] {
            *x *= s;
        }
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn input(v: f64) -> Input {
        Input::from_vec(vec![v, -2.0 * v])
    }

    #[test]
    fn latency_on_the_grid_is_an_exact_shift() {
        let dt = 0.002;
        let p = Perturbation {
            command_latency: 7.0 * dt,
            ..Default::default()
        };
        let mut r = Reality::new(&p, dt, 2);
        assert!(r.acts() && !r.observes());
        assert_eq!(extra_steps(&p, dt), 7);
        let c: Vec<f64> = (0..40).map(|k| (k as f64 * 0.37).sin() + 0.1).collect();
        for (k, ck) in c.iter().enumerate() {
            let got = r.actuate(&input(*ck));
            let want = if k >= 7 { input(c[k - 7]) } else { input(0.0) };
            assert_eq!(got, want, "step {k}");
        }
    }

    #[test]
    fn latency_between_steps_blends_the_two_commands_it_straddles() {
        let dt = 0.01;
        let p = Perturbation {
            command_latency: 2.25 * dt,
            ..Default::default()
        };
        let mut r = Reality::new(&p, dt, 2);
        assert_eq!(extra_steps(&p, dt), 3);
        let c: Vec<f64> = (0..20).map(|k| k as f64 * k as f64).collect();
        for (k, _) in c.iter().enumerate() {
            let got = r.actuate(&input(c[k]))[0];
            let at = |j: isize| if j >= 0 { c[j as usize] } else { 0.0 };
            let want = 0.75 * at(k as isize - 2) + 0.25 * at(k as isize - 3);
            assert!((got - want).abs() < 1e-12, "step {k}: {got} vs {want}");
        }
    }

    /// The step response of the lag against its closed form: the mean over
    /// each step of 1 − e^(−t/τ), and the integral t − τ(1 − e^(−t/τ)).
    #[test]
    fn lag_matches_the_closed_form_step_response() {
        for (tau, dt) in [(0.05, 0.002), (0.003, 0.002), (2.0, 0.001)] {
            let p = Perturbation {
                actuator_tau: tau,
                ..Default::default()
            };
            let mut r = Reality::new(&p, dt, 2);
            let mut integral = 0.0;
            for k in 0..500 {
                let got = r.actuate(&input(1.0));
                let (t0, t1) = (k as f64 * dt, (k + 1) as f64 * dt);
                let mean = 1.0 - tau * ((-t0 / tau).exp() - (-t1 / tau).exp()) / dt;
                assert!((got[0] - mean).abs() < 1e-12, "τ {tau} step {k}");
                assert!((got[1] + 2.0 * mean).abs() < 1e-12);
                integral += got[0] * dt;
                let exact = t1 - tau * (1.0 - (-t1 / tau).exp());
                assert!(
                    (integral - exact).abs() < 1e-12 * (1.0 + t1),
                    "τ {tau} t {t1}"
                );
            }
        }
    }

    #[test]
    fn state_latency_interpolates_and_noise_follows_the_seed() {
        let dt = 0.01;
        let q: Vec<State> = (0..10)
            .map(|k| State::from_vec(vec![k as f64, 10.0 * k as f64]))
            .collect();
        let p = Perturbation {
            state_latency: 2.5 * dt,
            ..Default::default()
        };
        let mut r = Reality::new(&p, dt, 2);
        assert!(r.observes() && !r.acts());
        assert_eq!(r.observe(&q, 9).as_slice(), &[6.5, 65.0]);
        assert_eq!(
            r.observe(&q, 1).as_slice(),
            &[0.0, 0.0],
            "start state before t = Ls"
        );
        let noisy = |seed| {
            let p = Perturbation {
                state_noise: 0.1,
                seed,
                ..Default::default()
            };
            let mut r = Reality::new(&p, dt, 2);
            (0..200)
                .flat_map(|k| r.observe(&q, k % 10).as_slice().to_vec())
                .collect::<Vec<f64>>()
        };
        let (a, b, c) = (noisy(3), noisy(3), noisy(4));
        assert_eq!(a, b);
        assert_ne!(a, c);
        // The deviates: mean ~0, σ ~0.1.
        let dev: Vec<f64> = (0..400).map(|i| a[i] - q[(i / 2) % 10][i % 2]).collect();
        let mean = dev.iter().sum::<f64>() / 400.0;
        let sd = (dev.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / 399.0).sqrt();
        assert!(mean.abs() < 0.02 && (sd - 0.1).abs() < 0.015, "{mean} {sd}");
    }

    #[test]
    fn ranges_and_magnitudes() {
        let mut p = Perturbation::default();
        assert!(p.active().is_empty());
        p.validate().unwrap();
        for d in Dimension::ALL {
            assert_eq!(Dimension::parse(d.name()), Some(d));
            let v = d.value_at(0.25);
            assert!((d.magnitude_of(v) - 0.25).abs() < 1e-15);
            assert_eq!(d.value_at(0.0), d.nominal());
            let mut q = p;
            d.set(&mut q, v);
            assert_eq!(q.active(), vec![d]);
            d.set(&mut q, if d.kind() == Kind::Scale { 0.0 } else { -1.0 });
            let e = q.validate().unwrap_err().to_string();
            assert!(e.starts_with(&format!("key `sim.perturb.{d}`")), "{e}");
        }
        p.mass_scale = 1.5;
        assert_eq!(p.active_json(), serde_json::json!({"mass_scale": 1.5}));
    }
}
