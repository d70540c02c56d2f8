//! `[regression]`: the tolerances of the baseline check (`crate::baseline`),
//! as a scenario writes them.

use crate::error::SetupError;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Default relative tolerance (why 2 %: docs/src/operations/ci-gates.md).
pub const DEFAULT_REL: f64 = 0.02;

/// Absolute floor of a metric with neither a gate nor a unit floor
/// (fractions, counts, ratios), in its own unit.
pub const DEFAULT_ABS: f64 = 1e-9;

/// Share of a metric's gate (its `[thresholds]` or `[minimums]` value) below
/// which a change is never a regression (why: docs/src/operations/ci-gates.md).
pub const GATE_SHARE: f64 = 0.1;

/// The floor of a metric without a gate, by the unit written after its
/// values: 0.1 mm, 0.01°, 1 mm/s, 10 ms; [`DEFAULT_ABS`] for any other unit.
pub fn unit_floor(unit: &str) -> f64 {
    match unit {
        "m" => 1e-4,
        "°" => 0.01,
        "m/s" => 1e-3,
        "s" => 0.01,
        _ => DEFAULT_ABS,
    }
}

/// A metric's default absolute floor: [`GATE_SHARE`] of its gate when it
/// has a finite, non-zero one, else its [`unit_floor`].
pub fn default_floor(gate: Option<f64>, unit: &str) -> f64 {
    match gate {
        Some(g) if g.is_finite() && g != 0.0 => GATE_SHARE * g.abs(),
        _ => unit_floor(unit),
    }
}

/// A relative and an absolute tolerance; unset fields fall back to the level above.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Tolerance {
    /// Relative to |baseline|.
    #[schemars(range(min = 0))]
    pub rel: Option<f64>,
    /// Absolute floor, in the metric's unit (replaces the default floor).
    #[schemars(range(min = 0))]
    pub abs: Option<f64>,
}

/// `[regression]` in a scenario file: tolerance overrides for the baseline check.
///
/// ```toml
/// [regression]
/// rel = 0.05                                    # every metric of this scenario
/// metrics.sim_time_to_goal = { rel = 0.2 }      # one metric
/// ```
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RegressionConfig {
    /// Relative tolerance for every metric.
    #[schemars(range(min = 0))]
    pub rel: Option<f64>,
    /// Absolute floor for every metric, in each metric's unit (replaces the
    /// default floor: 10 % of the metric's gate, else its unit's floor).
    #[schemars(range(min = 0))]
    pub abs: Option<f64>,
    /// Per-metric overrides.
    #[serde(default)]
    pub metrics: BTreeMap<String, Tolerance>,
}

impl RegressionConfig {
    /// Values must be finite and ≥ 0 (messages name the key).
    pub fn validate(&self) -> Result<(), SetupError> {
        let ok = |key: String, v: Option<f64>| match v {
            Some(x) if !(x.is_finite() && x >= 0.0) => {
                Err(SetupError::key(key, "must be finite and ≥ 0"))
            }
            _ => Ok(()),
        };
        ok("regression.rel".into(), self.rel)?;
        ok("regression.abs".into(), self.abs)?;
        for (m, t) in &self.metrics {
            ok(format!("regression.metrics.{m}.rel"), t.rel)?;
            ok(format!("regression.metrics.{m}.abs"), t.abs)?;
        }
        Ok(())
    }

    /// The unknown metric names among the overrides.
    pub fn unknown_metrics<'a>(&'a self, known: &'a [String]) -> impl Iterator<Item = &'a str> {
        self.metrics
            .keys()
            .filter(move |k| !known.contains(k))
            .map(String::as_str)
    }

    /// `(rel, abs)` for a metric whose default floor is `floor`
    /// ([`default_floor`]): the overrides win over it.
    pub fn tolerance(&self, metric: &str, floor: f64) -> (f64, f64) {
        let t = self.metrics.get(metric).copied().unwrap_or_default();
        (
            t.rel.or(self.rel).unwrap_or(DEFAULT_REL),
            t.abs.or(self.abs).unwrap_or(floor),
        )
    }
}
