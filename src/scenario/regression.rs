//! `[regression]`: the tolerances of the baseline check (`crate::baseline`),
//! as a scenario writes them.

use crate::error::SetupError;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Default relative tolerance (why 2 %: docs/src/operations/ci-gates.md).
pub const DEFAULT_REL: f64 = 0.02;

/// Default absolute tolerance, in the metric's own unit; below any meaningful
/// value of every metric (m, deg, fractions, counts, kg m²/s).
pub const DEFAULT_ABS: f64 = 1e-9;

/// A relative and an absolute tolerance; unset fields fall back to the level above.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Tolerance {
    /// Relative to |baseline|.
    #[schemars(range(min = 0))]
    pub rel: Option<f64>,
    /// In the metric's unit.
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
    /// Absolute tolerance for every metric.
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

    /// `(rel, abs)` for a metric.
    pub fn tolerance(&self, metric: &str) -> (f64, f64) {
        let t = self.metrics.get(metric).copied().unwrap_or_default();
        (
            t.rel.or(self.rel).unwrap_or(DEFAULT_REL),
            t.abs.or(self.abs).unwrap_or(DEFAULT_ABS),
        )
    }
}
