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
//! Each dimension is one row of `dimensions!`: its key, its unit, which
//! way reality gets worse, what it reaches and its margin search range; the
//! `[sim.perturb]` table, [`Dimension`] and the `[margins]` table are
//! generated from the rows. Which dimensions reach a robot follows from its
//! [`Exposure`] ([`crate::robots::System::exposure`]).
//! [`reality::Reality`] applies the command and observation perturbations
//! inside the replay loop; the world ones are [`crate::engine::PhysicsSettings`]
//! fields (and [`world`]'s edits of the URDF).
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

pub mod reality;
pub mod world;

use crate::error::SetupError;
use crate::plan::{ControlLaw, Plan};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The perturbation dimensions, one row each. Calls `$then!` with the rows,
/// so every table made of them (`[sim.perturb]` here, `[margins]` in the
/// scenario layer) is generated from the same rows. A row: the field's docs
/// and schema attributes, `key: Variant`, then
/// * `worse`: which way reality gets worse with the magnitude m — `Add`
///   (an amount: m itself, nominal 0), `Less` (a factor 1 − m: weaker,
///   slipperier, smaller), `More` (a factor 1 + m: heavier);
/// * `unit` of the value (and of an amount's margin);
/// * `reaches`: what a robot needs for the dimension to reach it
///   ([`Reaches`], against its [`Exposure`]);
/// * `random`: whether it draws random numbers (a margin level then needs
///   several seeds);
/// * `search`: the margin search's first level, floor and ceiling (magnitudes);
/// * `margin`: the `[margins]` key's docs and schema attributes.
macro_rules! dimensions {
    ($then:ident) => {
        $then! {
            /// Delay from the controller to the drives, s: the drives receive each command this much later (at most the plan's duration, or the horizon of a feedback law).
            #[schemars(range(min = 0))]
            command_latency: CommandLatency {
                worse: Add, unit: "s", reaches: Drives, random: false,
                search: [0.01, 1e-6, 2.0],
                margin: [
                    /// Least command-latency margin, s: `check` runs the scenario once at this latency and fails when a gate breaks there.
                    #[schemars(range(min = 0))]
                ],
            },
            /// Time constant of a first-order lag on each drive's command, s (at most the plan's duration, or the horizon of a feedback law).
            #[schemars(range(min = 0))]
            actuator_tau: ActuatorTau {
                worse: Add, unit: "s", reaches: Drives, random: false,
                search: [0.01, 1e-6, 2.0],
                margin: [
                    /// Least actuator-lag margin, s.
                    #[schemars(range(min = 0))]
                ],
            },
            /// Factor on each drive's effective torque limit, whatever its source (the URDF's `<limit effort>`, a model key or `sim.motor_max_torque`).
            #[schemars(extend("exclusiveMinimum" = 0))]
            torque_scale: TorqueScale {
                worse: Less, unit: "", reaches: Drives, random: false,
                search: [0.05, 1e-4, 0.99],
                margin: [
                    /// Least torque-loss margin (fraction of the torque limit).
                    #[schemars(range(min = 0), extend("exclusiveMaximum" = 1))]
                ],
            },
            /// Standard deviation of the Gaussian noise on each coordinate of the
            /// state a feedback law sees (m, rad, in each coordinate's SI unit); feedback laws only.
            #[schemars(range(min = 0))]
            state_noise: StateNoise {
                worse: Add, unit: "m|rad", reaches: Feedback, random: true,
                search: [1e-3, 1e-7, 1.0],
                margin: [
                    /// Least state-noise margin (σ, m or rad): checked with `seeds` runs at this σ.
                    #[schemars(range(min = 0))]
                ],
            },
            /// Age of the state a feedback law sees, s (feedback laws only; at most the horizon).
            #[schemars(range(min = 0))]
            state_latency: StateLatency {
                worse: Add, unit: "s", reaches: Feedback, random: false,
                search: [0.01, 1e-6, 2.0],
                margin: [
                    /// Least state-latency margin, s.
                    #[schemars(range(min = 0))]
                ],
            },
            /// Factor on the simulated wheels' radius; the model and the controller keep the nominal one (wheeled models only).
            #[schemars(extend("exclusiveMinimum" = 0))]
            wheel_radius_scale: WheelRadiusScale {
                worse: Less, unit: "", reaches: Wheels, random: false,
                search: [0.01, 1e-5, 0.5],
                margin: [
                    /// Least wheel-wear margin (fraction of the radius).
                    #[schemars(range(min = 0), extend("exclusiveMaximum" = 1))]
                ],
            },
            /// Factor on every friction coefficient (`sim.friction`).
            #[schemars(extend("exclusiveMinimum" = 0))]
            friction_scale: FrictionScale {
                worse: Less, unit: "", reaches: Friction, random: false,
                search: [0.05, 1e-4, 0.99],
                margin: [
                    /// Least friction-loss margin (fraction of the coefficient).
                    #[schemars(range(min = 0), extend("exclusiveMaximum" = 1))]
                ],
            },
            /// Factor on every URDF link's mass and inertia (the model keeps the URDF's).
            #[schemars(extend("exclusiveMinimum" = 0))]
            mass_scale: MassScale {
                worse: More, unit: "", reaches: Drives, random: false,
                search: [0.1, 1e-4, 9.0],
                margin: [
                    /// Least added-mass margin (fraction of the masses).
                    #[schemars(range(min = 0))]
                ],
            },
        }
    };
}
pub(crate) use dimensions;

/// Which way reality gets worse with a perturbation's magnitude m.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Worse {
    /// An amount added to nothing: the value is m (nominal 0, must be ≥ 0).
    Add,
    /// A factor that shrinks: 1 − m (nominal 1, must be > 0).
    Less,
    /// A factor that grows: 1 + m (nominal 1, must be > 0).
    More,
}

/// What a robot needs for a dimension to reach it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reaches {
    /// Every physics system: its drives and bodies.
    Drives,
    /// Robots that touch something through friction.
    Friction,
    /// Robots that roll on wheels (a disk or a ball is a wheel).
    Wheels,
    /// Feedback laws closed on the simulated state (what the law sees).
    Feedback,
}

/// What of a robot, under its plan, a perturbation can reach: asked of
/// every robot through [`crate::robots::System::exposure`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Exposure {
    /// It touches the ground or objects through friction.
    pub friction: bool,
    /// It rolls on wheels whose radius can differ from the model's.
    pub wheels: bool,
    /// Its commands come from a feedback law closed on the simulated state.
    pub feedback: bool,
}

impl Exposure {
    /// Friction, no wheels, and a feedback law when `plan` is one.
    pub fn of(plan: &Plan) -> Exposure {
        Exposure {
            friction: true,
            wheels: false,
            feedback: matches!(plan.law, ControlLaw::Feedback { .. }),
        }
    }
}

/// The margin search range of a dimension, in magnitudes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Search {
    /// The first level tried.
    pub start: f64,
    /// The smallest level searched.
    pub floor: f64,
    /// The largest level searched.
    pub ceiling: f64,
}

/// One dimension's row.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Row {
    /// The dimension.
    pub dimension: Dimension,
    /// Its key in `[sim.perturb]` and `[margins]`.
    pub name: &'static str,
    /// Which way reality gets worse.
    pub worse: Worse,
    /// Unit of the value (empty for factors).
    pub unit: &'static str,
    /// What it reaches.
    pub reaches: Reaches,
    /// Whether it draws random numbers.
    pub random: bool,
    /// Its margin search range.
    pub search: Search,
}

macro_rules! perturbation_table {
    ($(
        $(#[$meta:meta])*
        $field:ident : $Var:ident {
            worse: $worse:ident, unit: $unit:literal, reaches: $reaches:ident, random: $random:literal,
            search: [$start:expr, $floor:expr, $ceiling:expr],
            margin: [$(#[$mmeta:meta])*] $(,)?
        }
    ),* $(,)?) => {
        /// `[sim.perturb]`: what reality adds to the physics replay, every value off
        /// (0 or 1) by default. The ideal run is never perturbed; a key that does not
        /// apply to the system or plan is refused.
        #[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize, JsonSchema)]
        #[serde(deny_unknown_fields, default)]
        pub struct Perturbation {
            $( $(#[$meta])* pub $field: f64, )*
            /// Seed of the state noise (ChaCha8): the same seed gives the same run.
            pub seed: u64,
        }

        impl Default for Perturbation {
            fn default() -> Self {
                Perturbation {
                    $( $field: Worse::$worse.nominal(), )*
                    seed: 0,
                }
            }
        }

        /// A perturbation dimension (a key of `[sim.perturb]`).
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
        #[serde(rename_all = "snake_case")]
        pub enum Dimension {
            $( #[doc = concat!("`", stringify!($field), "`.")] $Var, )*
        }

        /// Every dimension's row, in the order of `[sim.perturb]`.
        pub const ROWS: &[Row] = &[
            $( Row {
                dimension: Dimension::$Var,
                name: stringify!($field),
                worse: Worse::$worse,
                unit: $unit,
                reaches: Reaches::$reaches,
                random: $random,
                search: Search { start: $start, floor: $floor, ceiling: $ceiling },
            }, )*
        ];

        impl Dimension {
            /// The value in `p`.
            pub fn value(self, p: &Perturbation) -> f64 {
                match self { $( Dimension::$Var => p.$field, )* }
            }

            /// Set the value in `p`.
            pub fn set(self, p: &mut Perturbation, v: f64) {
                match self { $( Dimension::$Var => p.$field = v, )* }
            }
        }
    };
}

dimensions!(perturbation_table);

impl Worse {
    /// The unperturbed value: 0 for an amount, 1 for a factor.
    pub const fn nominal(self) -> f64 {
        match self {
            Worse::Add => 0.0,
            Worse::Less | Worse::More => 1.0,
        }
    }
}

impl Perturbation {
    /// The dimensions set away from nominal (the seed is not a dimension).
    pub fn active(&self) -> Vec<Dimension> {
        Dimension::all()
            .filter(|d| d.value(self) != d.nominal())
            .collect()
    }

    /// Checks the ranges; the message starts with the key (`sim.perturb.<name>`).
    pub fn validate(&self) -> Result<(), SetupError> {
        for d in Dimension::all() {
            let v = d.value(self);
            let (bad, need) = match d.row().worse {
                Worse::Less | Worse::More => (!(v > 0.0 && v.is_finite()), "a factor > 0"),
                Worse::Add => (!(v >= 0.0 && v.is_finite()), "≥ 0"),
            };
            if bad {
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

impl Dimension {
    /// Every dimension, in the order of `[sim.perturb]`.
    pub fn all() -> impl Iterator<Item = Dimension> {
        ROWS.iter().map(|r| r.dimension)
    }

    /// Its row.
    pub fn row(self) -> &'static Row {
        // The rows are in the enum's order (both come from one list).
        &ROWS[self as usize]
    }

    /// The key name.
    pub fn name(self) -> &'static str {
        self.row().name
    }

    /// The dimension of a key name.
    pub fn parse(name: &str) -> Option<Dimension> {
        ROWS.iter().find(|r| r.name == name).map(|r| r.dimension)
    }

    /// Whether the value is a factor (1 nominal) rather than an amount (0 nominal).
    pub fn is_factor(self) -> bool {
        self.row().worse != Worse::Add
    }

    /// The nominal (unperturbed) value.
    pub fn nominal(self) -> f64 {
        self.row().worse.nominal()
    }

    /// Unit of the value (and of a margin of an amount), for messages.
    pub fn unit(self) -> &'static str {
        self.row().unit
    }

    pub(crate) fn unit_suffix(self) -> String {
        match self.unit() {
            "" => String::new(),
            u => format!(" {u}"),
        }
    }

    /// Whether it draws random numbers (a margin then needs several seeds per level).
    pub fn random(self) -> bool {
        self.row().random
    }

    /// Whether it acts on the state a feedback law sees (so only on feedback laws).
    pub fn observes(self) -> bool {
        self.row().reaches == Reaches::Feedback
    }

    /// Whether it reaches a robot of this exposure.
    pub fn reaches(self, e: &Exposure) -> bool {
        match self.row().reaches {
            Reaches::Drives => true,
            Reaches::Friction => e.friction,
            Reaches::Wheels => e.wheels,
            Reaches::Feedback => e.feedback,
        }
    }

    /// The dimensions that reach a robot of this exposure, in row order.
    pub fn reaching(e: &Exposure) -> Vec<Dimension> {
        Dimension::all().filter(|d| d.reaches(e)).collect()
    }

    /// The value at perturbation magnitude `m` ≥ 0 (what a margin measures):
    /// the amount itself; for factors the way reality gets worse: weaker
    /// drives, less friction and worn (smaller) wheels are 1 − m, heavier
    /// links 1 + m.
    pub fn value_at(self, m: f64) -> f64 {
        match self.row().worse {
            Worse::Add => m,
            Worse::Less => 1.0 - m,
            Worse::More => 1.0 + m,
        }
    }

    /// The magnitude of a value (inverse of [`Dimension::value_at`]).
    pub fn magnitude_of(self, v: f64) -> f64 {
        match self.row().worse {
            Worse::Add => v,
            Worse::Less => 1.0 - v,
            Worse::More => v - 1.0,
        }
    }

    /// The largest magnitude `[margins]` accepts: below 1 for a factor
    /// that shrinks (1 − m must stay > 0), unbounded otherwise.
    pub fn magnitude_limit(self) -> f64 {
        match self.row().worse {
            Worse::Less => 1.0,
            Worse::Add | Worse::More => f64::INFINITY,
        }
    }
}

impl std::fmt::Display for Dimension {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_magnitudes() {
        let mut p = Perturbation::default();
        assert!(p.active().is_empty());
        p.validate().unwrap();
        for (i, d) in Dimension::all().enumerate() {
            assert_eq!(d as usize, i, "rows in the enum's order");
            assert_eq!(Dimension::parse(d.name()), Some(d));
            let v = d.value_at(0.25);
            assert!((d.magnitude_of(v) - 0.25).abs() < 1e-15);
            assert_eq!(d.value_at(0.0), d.nominal());
            let mut q = p;
            d.set(&mut q, v);
            assert_eq!(q.active(), vec![d]);
            d.set(&mut q, if d.is_factor() { 0.0 } else { -1.0 });
            let e = q.validate().unwrap_err().to_string();
            assert!(e.starts_with(&format!("key `sim.perturb.{d}`")), "{e}");
        }
        p.mass_scale = 1.5;
        assert_eq!(p.active_json(), serde_json::json!({"mass_scale": 1.5}));
    }
}
