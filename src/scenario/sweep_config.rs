//! `[sweep]`: Monte Carlo variants of a scenario (run by [`crate::sweep`]).
//!
//! A variant is the scenario file with some numbers replaced: `[sweep.vary]`
//! names any numeric key by its dotted path (`"sim.friction"`,
//! `"planner.k1"`, `"start[2]"`) with a distribution, and the variant is
//! parsed and range-checked like the file itself ([`crate::scenario::Scenario::variant`]).
//! `friction`, `mass_scale` and `sigma_rate` are the older shorthands:
//! `friction = [lo, hi]` is `"sim.friction" = { uniform = [lo, hi] }` and
//! `mass_scale = [lo, hi]` is `"sim.perturb.mass_scale" = { uniform = [lo,
//! hi] }` (both drawn from the same stream as before, so old sweeps keep
//! their variants), `sigma_rate` gives the rover's ideal run a telegraph σ
//! seeded per variant.

use crate::error::SetupError;
use crate::numfmt::readable;
use crate::scenario::keypath::KeyPath;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// `[sweep]`: Monte Carlo variants of the scenario.
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SweepConfig {
    /// Number of variants.
    #[schemars(range(min = 1, max = 1000000))]
    pub count: usize,
    /// Base seed; variant i uses [`variant_seed`]`(seed, i)`.
    #[serde(default)]
    pub seed: u64,
    /// Shorthand for `"sim.friction" = { uniform = [lo, hi] }`.
    #[schemars(extend("minimum" = 0))]
    pub friction: Option<[f64; 2]>,
    /// Shorthand for `"sim.perturb.mass_scale" = { uniform = [lo, hi] }`.
    #[schemars(extend("minimum" = 0.001))]
    pub mass_scale: Option<[f64; 2]>,
    /// Rover only: the ideal run uses a telegraph σ with this rate (1/s) and the variant's seed.
    #[schemars(range(min = 0))]
    pub sigma_rate: Option<f64>,
    /// Any numeric scenario key by dotted path (quoted: `"planner.k1" = { uniform = [0.6, 1.0] }`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub vary: BTreeMap<String, Dist>,
    /// Metric that decides success (`value ≤ success_max`); models without a planar
    /// position must name one (e.g. `sim_goal_theta0_deg`).
    #[serde(default = "default_success_metric")]
    pub success_metric: String,
    /// Largest `success_metric` value that counts as success.
    #[schemars(range(min = 0))]
    pub success_max: f64,
    /// Metric reported as the time to goal (NaN = not reached). Default:
    /// `sim_time_to_goal` when the model reports it (rover, mobile manipulator),
    /// else none: the sweep then reports no times.
    #[serde(default)]
    pub time_metric: Option<String>,
    /// `check` fails when the success rate is below this.
    #[serde(default)]
    #[schemars(range(min = 0, max = 1))]
    pub min_success_rate: f64,
    /// A variant succeeds only if it also passes every `[thresholds]` and
    /// `[minimums]` gate of the scenario (for verdicts made of several
    /// criteria: position, heading, contacts, tilt, ...).
    #[serde(default)]
    pub success_requires_gates: bool,
}

/// How a swept key's value is chosen for each variant.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields, rename_all = "snake_case")]
pub enum Dist {
    /// `{ uniform = [lo, hi] }`.
    Uniform([f64; 2]),
    /// `{ normal = [mean, sigma] }`.
    Normal([f64; 2]),
    /// `{ values = [a, b, ...] }`: one of them at random.
    Values(Vec<f64>),
    /// `{ grid = [a, b, ...] }`: an axis of the Cartesian grid of every `grid` key.
    Grid(Vec<f64>),
}

/// Why a `[sweep.vary]` distribution's parameters are unusable (the
/// message without the key).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DistError {
    /// `uniform = [lo, hi]` with a non-finite end or lo > hi.
    #[error("uniform [{}, {}]: need finite lo ≤ hi", readable(*.lo), readable(*.hi))]
    Uniform {
        /// Lower end.
        lo: f64,
        /// Upper end.
        hi: f64,
    },
    /// `normal = [mean, sigma]` with a non-finite one or σ < 0.
    #[error("normal [{}, {}]: need a finite mean and σ ≥ 0", readable(*.mean), readable(*.sigma))]
    Normal {
        /// Mean.
        mean: f64,
        /// Standard deviation.
        sigma: f64,
    },
    /// `values` or `grid` empty or with a non-finite value.
    #[error("needs at least one value, all finite")]
    Values,
}

impl Dist {
    /// Checks the parameters.
    fn check(&self) -> Result<(), DistError> {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        match self {
            Dist::Uniform([lo, hi]) if !(finite(&[*lo, *hi]) && lo <= hi) => {
                Err(DistError::Uniform { lo: *lo, hi: *hi })
            }
            Dist::Normal([m, s]) if !(finite(&[*m, *s]) && *s >= 0.0) => Err(DistError::Normal {
                mean: *m,
                sigma: *s,
            }),
            Dist::Values(v) | Dist::Grid(v) if v.is_empty() || !finite(v) => Err(DistError::Values),
            _ => Ok(()),
        }
    }

    /// Whether it can produce a non-integer (so an integer key cannot take it).
    pub fn continuous(&self) -> bool {
        matches!(self, Dist::Uniform(_) | Dist::Normal(_))
    }

    /// Values a variant can take that validation tries on the scenario: both
    /// ends of a range, the mean, every listed value.
    pub fn probes(&self) -> Vec<f64> {
        match self {
            Dist::Uniform([lo, hi]) => {
                let mid = 0.5 * (lo + hi);
                // A value off the integers, so an integer key is caught.
                let off = if mid.fract() == 0.0 && hi > lo {
                    mid + 0.5 * (hi - mid).min(0.5)
                } else {
                    mid
                };
                vec![*lo, *hi, off]
            }
            Dist::Normal([m, _]) => vec![*m],
            Dist::Values(v) | Dist::Grid(v) => v.clone(),
        }
    }
}

fn default_success_metric() -> String {
    "sim_goal_position".into()
}

/// The time metric a sweep reports when `time_metric` is not written, if the
/// model reports it.
pub const DEFAULT_TIME_METRIC: &str = "sim_time_to_goal";

/// Key of the `[sweep.vary]` entry `path` as messages write it.
pub fn vary_key(path: &str) -> String {
    format!("sweep.vary.\"{path}\"")
}

impl SweepConfig {
    /// Checks ranges and counts (messages name the key). The key paths of
    /// `vary` are checked against the file by [`crate::scenario::Scenario::parse`].
    pub fn validate(&self) -> Result<(), SetupError> {
        if self.count == 0 || self.count > 1_000_000 {
            return Err(SetupError::key("sweep.count", "must be in 1..=1000000"));
        }
        let range = |key: &str, r: Option<[f64; 2]>, min: f64| -> Result<(), SetupError> {
            if let Some([lo, hi]) = r {
                if !(lo.is_finite() && hi.is_finite() && lo >= min && lo <= hi) {
                    return Err(SetupError::key(
                        format!("sweep.{key}"),
                        format!("need finite lo ≤ hi with lo ≥ {min}"),
                    ));
                }
            }
            Ok(())
        };
        range("friction", self.friction, 0.0)?;
        range("mass_scale", self.mass_scale, 1e-3)?;
        if let Some(r) = self.sigma_rate {
            if !(r.is_finite() && r >= 0.0) {
                return Err(SetupError::key(
                    "sweep.sigma_rate",
                    "must be finite and ≥ 0",
                ));
            }
        }
        if !(self.success_max.is_finite() && self.success_max >= 0.0) {
            return Err(SetupError::key(
                "sweep.success_max",
                "must be finite and ≥ 0",
            ));
        }
        if !(0.0..=1.0).contains(&self.min_success_rate) {
            return Err(SetupError::key(
                "sweep.min_success_rate",
                "must be in [0, 1]",
            ));
        }
        for (path, dist) in &self.vary {
            let key = vary_key(path);
            let kp = KeyPath::parse(path).map_err(|e| SetupError::key(key.clone(), e))?;
            dist.check().map_err(|e| SetupError::key(key.clone(), e))?;
            if kp.to_string() == "sim.friction" && self.friction.is_some() {
                return Err(SetupError::key(
                    key.to_string(),
                    "`sweep.friction` already sweeps sim.friction (keep one)",
                ));
            }
            if kp.to_string() == "sim.perturb.mass_scale" && self.mass_scale.is_some() {
                return Err(SetupError::key(
                    key.to_string(),
                    "`sweep.mass_scale` already sweeps sim.perturb.mass_scale (keep one)",
                ));
            }
            if kp.root() == "sweep" {
                return Err(SetupError::key(
                    key.to_string(),
                    "a sweep cannot vary its own table",
                ));
            }
        }
        let g = self.grid_size();
        if g > 1_000_000 {
            return Err(SetupError::key(
                "sweep.vary",
                format!("the grid has {g} points (at most 1000000)"),
            ));
        }
        if !self.count.is_multiple_of(g) {
            return Err(SetupError::key(
                "sweep.count",
                format!("{} is not a multiple of the grid's {g} points", self.count),
            ));
        }
        Ok(())
    }

    /// Points of the Cartesian grid of the `grid` keys (1 without any).
    pub fn grid_size(&self) -> usize {
        self.vary
            .values()
            .map(|d| match d {
                Dist::Grid(v) => v.len().max(1),
                _ => 1,
            })
            .fold(1usize, |a, n| a.saturating_mul(n))
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

/// ChaCha8 stream of one `[sweep.vary]` key (FNV-1a of its path; the shorthands use stream 0),
/// so adding or removing a key leaves the values of the others unchanged.
fn key_rng(seed: u64, path: &str) -> ChaCha8Rng {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in path.bytes() {
        h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(h | 1);
    rng
}

use crate::engine::perturb::reality::standard_normal;

/// The randomised parameters of one variant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Variant {
    /// Index in 0..count.
    pub index: usize,
    /// Its seed.
    pub seed: u64,
    /// Mass and inertia factor (`sweep.mass_scale`, applied as
    /// `sim.perturb.mass_scale`; 1 without the shorthand).
    pub mass_scale: f64,
    /// Telegraph rate of the ideal run's σ, when swept.
    pub sigma_rate: Option<f64>,
    /// Scenario key path → value written into the variant's file.
    pub params: BTreeMap<String, f64>,
}

impl SweepConfig {
    /// Draws variant `index`.
    pub fn variant(&self, index: usize) -> Variant {
        let seed = variant_seed(self.seed, index);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut params = BTreeMap::new();
        if let Some([lo, hi]) = self.friction {
            params.insert("sim.friction".into(), lo + (hi - lo) * rng.random::<f64>());
        }
        let mass_scale = match self.mass_scale {
            Some([lo, hi]) => lo + (hi - lo) * rng.random::<f64>(),
            None => 1.0,
        };
        // Grid coordinates: mixed radix of index % size, the last grid key fastest.
        let mut rest = index % self.grid_size();
        let mut coords = BTreeMap::new();
        for (k, d) in self.vary.iter().rev() {
            if let Dist::Grid(v) = d {
                coords.insert(k.as_str(), rest % v.len());
                rest /= v.len();
            }
        }
        for (k, d) in &self.vary {
            let mut r = key_rng(seed, k);
            let x = match d {
                Dist::Uniform([lo, hi]) => lo + (hi - lo) * r.random::<f64>(),
                Dist::Normal([m, s]) => m + s * standard_normal(&mut r),
                Dist::Values(v) => v[r.random_range(0..v.len())],
                Dist::Grid(v) => v[coords[k.as_str()]],
            };
            params.insert(k.clone(), x);
        }
        Variant {
            index,
            seed,
            mass_scale,
            sigma_rate: self.sigma_rate,
            params,
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

#[cfg(test)]
mod tests {
    use super::*;

    fn cfg(vary: &[(&str, Dist)]) -> SweepConfig {
        SweepConfig {
            count: 12,
            seed: 9,
            friction: Some([0.5, 1.0]),
            mass_scale: Some([0.7, 1.3]),
            sigma_rate: None,
            vary: vary
                .iter()
                .map(|(k, d)| (k.to_string(), d.clone()))
                .collect(),
            success_metric: "m".into(),
            success_max: 1.0,
            time_metric: Some("t".into()),
            min_success_rate: 0.0,
            success_requires_gates: false,
        }
    }

    #[test]
    fn shorthands_keep_their_stream_and_keys_are_independent() {
        let a = cfg(&[]);
        let b = cfg(&[
            ("planner.k1", Dist::Uniform([1.0, 2.0])),
            ("start[2]", Dist::Normal([90.0, 2.0])),
        ]);
        let c = cfg(&[("planner.k1", Dist::Uniform([1.0, 2.0]))]);
        for i in 0..12 {
            let (va, vb, vc) = (a.variant(i), b.variant(i), c.variant(i));
            assert_eq!(va.params["sim.friction"], vb.params["sim.friction"]);
            assert_eq!(va.mass_scale, vb.mass_scale);
            assert_eq!(vb.params["planner.k1"], vc.params["planner.k1"]);
            assert!((1.0..=2.0).contains(&vb.params["planner.k1"]));
            assert_ne!(vb.params["start[2]"], 90.0);
            assert_eq!(vb, b.variant(i), "a variant depends on (seed, index) only");
        }
        assert_ne!(b.variant(0).params, b.variant(1).params);
    }

    #[test]
    fn grid_is_cartesian_and_count_must_be_a_multiple() {
        let g = cfg(&[
            ("a", Dist::Grid(vec![1.0, 2.0])),
            ("b", Dist::Grid(vec![10.0, 20.0, 30.0])),
        ]);
        assert_eq!(g.grid_size(), 6);
        let pts: Vec<(f64, f64)> = (0..6)
            .map(|i| {
                let v = g.variant(i);
                (v.params["a"], v.params["b"])
            })
            .collect();
        assert_eq!(
            pts,
            [
                (1.0, 10.0),
                (1.0, 20.0),
                (1.0, 30.0),
                (2.0, 10.0),
                (2.0, 20.0),
                (2.0, 30.0)
            ]
        );
        assert_eq!(g.variant(7).params["b"], 20.0);
        g.validate().unwrap();
        let mut bad = g.clone();
        bad.count = 7;
        assert!(bad.validate().unwrap_err().to_string().contains("multiple"));
    }

    #[test]
    fn bad_distributions_name_the_key() {
        for (d, want) in [
            (Dist::Uniform([2.0, 1.0]), "lo ≤ hi"),
            (Dist::Normal([1.0, -0.1]), "σ ≥ 0"),
            (Dist::Values(vec![]), "at least one"),
        ] {
            let e = cfg(&[("planner.k1", d)])
                .validate()
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with("key `sweep.vary.\"planner.k1\"`") && e.contains(want),
                "{e}"
            );
        }
        let e = cfg(&[("sim.friction", Dist::Values(vec![1.0]))])
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("already sweeps"), "{e}");
        let e = cfg(&[("a..b", Dist::Values(vec![1.0]))])
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a key path"), "{e}");
    }
}
