//! `[sweep]`: Monte Carlo variants of a scenario (run by [`crate::sweep`]).

use super::{ModelConfig, Scenario};
use crate::systems::rover::SwitchingConfig;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// `[sweep]`: Monte Carlo variants of the scenario.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SweepConfig {
    /// Number of variants.
    pub count: usize,
    /// Base seed; variant i uses [`variant_seed`]`(seed, i)`.
    #[serde(default)]
    pub seed: u64,
    /// Friction coefficient range [lo, hi] (uniform); default: the scenario's `sim.friction`.
    pub friction: Option<[f64; 2]>,
    /// Range [lo, hi] of a factor applied to every link's mass and inertia (uniform).
    pub mass_scale: Option<[f64; 2]>,
    /// Rover only: the ideal run uses a telegraph σ with this rate (1/s) and the variant's seed.
    pub sigma_rate: Option<f64>,
    /// Metric that decides success (`value ≤ success_max`).
    #[serde(default = "default_success_metric")]
    pub success_metric: String,
    /// Largest `success_metric` value that counts as success.
    pub success_max: f64,
    /// Metric reported as the time to goal (NaN or missing = not reached).
    #[serde(default = "default_time_metric")]
    pub time_metric: String,
    /// `check` fails when the success rate is below this.
    #[serde(default)]
    pub min_success_rate: f64,
}

fn default_success_metric() -> String {
    "sim_goal_position".into()
}

fn default_time_metric() -> String {
    "sim_time_to_goal".into()
}

impl SweepConfig {
    /// Checks ranges and counts (messages name the key).
    pub fn validate(&self) -> Result<(), String> {
        if self.count == 0 || self.count > 1_000_000 {
            return Err("key `sweep.count`: must be in 1..=1000000".into());
        }
        let range = |key: &str, r: Option<[f64; 2]>, min: f64| -> Result<(), String> {
            if let Some([lo, hi]) = r {
                if !(lo.is_finite() && hi.is_finite() && lo >= min && lo <= hi) {
                    return Err(format!(
                        "key `sweep.{key}`: need finite lo ≤ hi with lo ≥ {min}"
                    ));
                }
            }
            Ok(())
        };
        range("friction", self.friction, 0.0)?;
        range("mass_scale", self.mass_scale, 1e-3)?;
        if let Some(r) = self.sigma_rate {
            if !(r.is_finite() && r >= 0.0) {
                return Err("key `sweep.sigma_rate`: must be finite and ≥ 0".into());
            }
        }
        if !(self.success_max.is_finite() && self.success_max >= 0.0) {
            return Err("key `sweep.success_max`: must be finite and ≥ 0".into());
        }
        if !(0.0..=1.0).contains(&self.min_success_rate) {
            return Err("key `sweep.min_success_rate`: must be in [0, 1]".into());
        }
        Ok(())
    }
}

/// Seed of variant `index`: SplitMix64 of the base seed and the index (independent of sharding
/// and of the order in which variants run).
pub fn variant_seed(seed: u64, index: usize) -> u64 {
    let mut z = seed
        ^ (index as u64)
            .wrapping_add(1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The randomised parameters of one variant.
#[derive(Debug, Clone, Serialize)]
pub struct Variant {
    /// Index in 0..count.
    pub index: usize,
    /// Its seed.
    pub seed: u64,
    /// Friction coefficient.
    pub friction: f64,
    /// Mass and inertia factor.
    pub mass_scale: f64,
    /// Telegraph rate of the ideal run's σ, when swept.
    pub sigma_rate: Option<f64>,
}

impl SweepConfig {
    /// Draws variant `index` (base friction from the scenario).
    pub fn variant(&self, base_friction: f64, index: usize) -> Variant {
        let cfg = self;
        let seed = variant_seed(cfg.seed, index);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut draw = |r: Option<[f64; 2]>, default: f64| match r {
            Some([lo, hi]) => lo + (hi - lo) * rng.random::<f64>(),
            None => default,
        };
        let friction = draw(cfg.friction, base_friction);
        let mass_scale = draw(cfg.mass_scale, 1.0);
        Variant {
            index,
            seed,
            friction,
            mass_scale,
            sigma_rate: cfg.sigma_rate,
        }
    }
}

impl Variant {
    /// Apply the variant to a copy of the scenario and its URDF: friction,
    /// every link's mass and inertia scaled, and (rover) the ideal run's σ.
    /// The copy has no `[sweep]`.
    pub fn apply(&self, sc: &mut Scenario, robot: &mut urdf_rs::Robot) {
        sc.sweep = None;
        sc.sim.friction = self.friction;
        if let (Some(rate), ModelConfig::Rover(m)) = (self.sigma_rate, &mut sc.model) {
            m.switching = SwitchingConfig::Telegraph {
                seed: self.seed,
                rate,
            };
        }
        for l in &mut robot.links {
            l.inertial.mass.value *= self.mass_scale;
            let i = &mut l.inertial.inertia;
            for x in [
                &mut i.ixx, &mut i.ixy, &mut i.ixz, &mut i.iyy, &mut i.iyz, &mut i.izz,
            ] {
                *x *= self.mass_scale;
            }
        }
    }
}

/// Names of the metrics a sweep reports (the sweep's outcome carries these instead of the
/// single-run metrics).
pub fn sweep_metric_names() -> Vec<String> {
    let mut out = vec![
        "sweep_success_rate".to_string(),
        "sweep_variants".to_string(),
    ];
    for name in ["sweep_final_error", "sweep_time_to_goal"] {
        for s in ["median", "p95", "max"] {
            out.push(format!("{name}_{s}"));
        }
    }
    out
}
