//! `[margins]`: the margins `check` gates, and how margins are searched.
//!
//! ```toml
//! [margins]
//! command_latency = 0.02   # check runs once at 20 ms of latency and fails if a gate breaks there
//! resolution = 0.05        # optional: bisect until the edge is within 5 %
//! seeds = 8                # optional: runs per level of a random dimension
//! success_rate = 0.875     # optional: a random level passes at ≥ 7 of 8
//! ```
//!
//! A margin is a perturbation magnitude (see
//! [`crate::engine::perturb::Dimension::value_at`]): the amount itself for
//! latencies, lags and noise, the distance from 1 for factors
//! (`friction_scale = 0.3` asks that the gates hold at 0.7× friction).

use crate::engine::perturb::Dimension;
use crate::error::SetupError;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Default relative resolution of a margin: the search stops when the edge
/// lies between the margin m and m·(1 + resolution).
pub const DEFAULT_RESOLUTION: f64 = 0.05;
/// Default number of seeds per level of a random dimension.
pub const DEFAULT_SEEDS: usize = 8;
/// Default success rate a level of a random dimension needs.
pub const DEFAULT_SUCCESS_RATE: f64 = 0.875;

macro_rules! margins_table {
    ($(
        $(#[$meta:meta])*
        $field:ident : $Var:ident {
            worse: $worse:ident, unit: $unit:literal, reaches: $reaches:ident, random: $random:literal,
            search: [$start:expr, $floor:expr, $ceiling:expr],
            margin: [$(#[$mmeta:meta])*] $(,)?
        }
    ),* $(,)?) => {
        /// `[margins]`: least robustness margins `run`/`check` gate (each checked with one
        /// run at the gate, not searched; reported and baselined as `margin_<dimension>`),
        /// and how `anholonomy margin` searches them. A margin is a perturbation magnitude:
        /// the amount for latencies, lags and noise, the distance from 1 for factors.
        #[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize, JsonSchema)]
        #[serde(deny_unknown_fields)]
        pub struct MarginsConfig {
            $(
                $(#[$mmeta])*
                #[serde(skip_serializing_if = "Option::is_none")]
                pub $field: Option<f64>,
            )*
            /// Relative resolution of the search: bisect until the edge lies within margin·(1 + resolution); default 0.05.
            #[serde(skip_serializing_if = "Option::is_none")]
            #[schemars(range(max = 1), extend("exclusiveMinimum" = 0))]
            pub resolution: Option<f64>,
            /// Seeds per level of a random dimension (`state_noise`); default 8.
            #[serde(skip_serializing_if = "Option::is_none")]
            #[schemars(range(min = 1, max = 1000))]
            pub seeds: Option<usize>,
            /// Fraction of a random level's seeds that must pass; default 0.875.
            #[serde(skip_serializing_if = "Option::is_none")]
            #[schemars(range(max = 1), extend("exclusiveMinimum" = 0))]
            pub success_rate: Option<f64>,
        }

        impl MarginsConfig {
            /// The gated dimensions and their least margins, in row order.
            pub fn gates(&self) -> Vec<(Dimension, f64)> {
                [$( (Dimension::$Var, self.$field) ),*]
                    .into_iter()
                    .filter_map(|(d, g)| g.map(|g| (d, g)))
                    .collect()
            }
        }
    };
}

crate::engine::perturb::dimensions!(margins_table);

impl MarginsConfig {
    /// The metric a gated margin is reported (and baselined) as:
    /// `margin_<dimension>`, the gate when it holds (NaN when it breaks).
    pub fn metric(d: Dimension) -> String {
        format!("margin_{}", d.name())
    }

    /// The search's relative resolution.
    pub fn resolution(&self) -> f64 {
        self.resolution.unwrap_or(DEFAULT_RESOLUTION)
    }

    /// Seeds per level of a random dimension.
    pub fn seeds(&self) -> usize {
        self.seeds.unwrap_or(DEFAULT_SEEDS)
    }

    /// Success rate a level of a random dimension needs.
    pub fn success_rate(&self) -> f64 {
        self.success_rate.unwrap_or(DEFAULT_SUCCESS_RATE)
    }

    /// Default baseline tolerance of a margin metric (relative): two
    /// resolutions, since a search can land one resolution step either way
    /// of an edge that moved by less than that (a gate that held is the
    /// gate itself: any tolerance keeps it).
    pub fn tolerance(&self) -> f64 {
        2.0 * self.resolution()
    }

    /// Ranges (messages start with the key).
    pub fn validate(&self) -> Result<(), SetupError> {
        for (d, g) in self.gates() {
            let top = d.magnitude_limit();
            if !(g >= 0.0 && g < top) {
                return Err(SetupError::key(
                    format!("margins.{d}"),
                    format!(
                        "a margin is a perturbation magnitude ≥ 0{}, got {}",
                        if top.is_finite() {
                            " and < 1 (the distance of the factor from 1)"
                        } else {
                            ""
                        },
                        crate::numfmt::readable(g)
                    ),
                ));
            }
        }
        if let Some(r) = self.resolution {
            if !(r > 0.0 && r <= 1.0) {
                return Err(SetupError::key("margins.resolution", "must be in (0, 1]"));
            }
        }
        if let Some(n) = self.seeds {
            if !(1..=1000).contains(&n) {
                return Err(SetupError::key("margins.seeds", "must be in 1..=1000"));
            }
        }
        if let Some(r) = self.success_rate {
            if !(r > 0.0 && r <= 1.0) {
                return Err(SetupError::key("margins.success_rate", "must be in (0, 1]"));
            }
        }
        Ok(())
    }
}
