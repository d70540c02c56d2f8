//! Metric directions: which way a metric gets worse. Systems declare
//! exceptions ([`crate::robots::System::metric_direction`]); the baseline
//! comparison and the margin gates read them. A module of its own so that
//! systems and baselines both depend on it and not on each other.

use serde::{Deserialize, Serialize};

/// Which way a metric gets worse.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Errors, maxima, times, counts: a rise is a regression.
    LowerIsBetter,
    /// Success rates, fractions inside an envelope, minimum clearances: a fall is a regression.
    HigherIsBetter,
    /// Reported when it changes, never a regression.
    Informational,
}

/// Metrics of the harness itself that are informational.
const INFORMATIONAL: [&str; 1] = ["sweep_variants"];

impl Direction {
    /// The harness convention (module docs), used when a system does not declare a direction.
    pub fn conventional(name: &str) -> Direction {
        if INFORMATIONAL.contains(&name) {
            return Direction::Informational;
        }
        let higher = name.ends_with("success_rate")
            || name
                .split('_')
                .any(|t| matches!(t, "min" | "clearance" | "margin"));
        if higher {
            Direction::HigherIsBetter
        } else {
            Direction::LowerIsBetter
        }
    }

    pub(crate) fn symbol(self) -> &'static str {
        match self {
            Direction::LowerIsBetter => "lower",
            Direction::HigherIsBetter => "higher",
            Direction::Informational => "info",
        }
    }
}

/// The value of metric `name` in a run's `(name, value)` list.
pub fn find(metrics: &[(String, f64)], name: &str) -> Option<f64> {
    metrics.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
}
