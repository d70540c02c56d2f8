//! Responses that are not continuous: a gated metric that jumps between
//! two neighbouring levels of a search (levels within the search's final
//! spacing), by more than half its gate. The edge found there is a cliff,
//! and the margin's note says so instead of presenting a clean edge.

use crate::margin::level::Gate;
use crate::margin::Level;
use crate::metric::Family;
use serde::Serialize;

/// A jump of a gated metric between two neighbouring levels.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Jump {
    /// The gated metric.
    pub metric: String,
    /// The lower level and the metric there.
    pub from: [f64; 2],
    /// The higher level and the metric there.
    pub to: [f64; 2],
}

impl Jump {
    /// The note's words.
    pub fn note(&self) -> String {
        let r = crate::numfmt::readable;
        format!(
            "JUMP: {} {} → {} between {} and {}",
            self.metric,
            r(self.from[1]),
            r(self.to[1]),
            r(self.from[0]),
            r(self.to[0])
        )
    }
}

/// Levels are neighbours when the higher is at most this factor of
/// `resolution` above the lower (the bisection's last steps).
const NEIGHBOURS: f64 = 2.0;

/// Share of a gate's bound a change between neighbours must exceed to be a jump.
const SHARE: f64 = 0.5;

/// The jumps of `gate`'s metric over `levels` (searched levels; the nominal
/// run, level 0, has no neighbour at a relative spacing). A level's value
/// is the mean over its runs of the metric where finite; a run stopped
/// early counts only for a running maximum or minimum (its prefix value is
/// a bound of the whole run's; an end value of a prefix is not).
pub fn jumps(levels: &[Level], gate: &Gate, resolution: f64) -> Vec<Jump> {
    let mut pts: Vec<[f64; 2]> = levels
        .iter()
        .filter(|l| l.level > 0.0)
        .filter_map(|l| {
            let v: Vec<f64> = l
                .runs
                .iter()
                .filter(|r| {
                    r.stopped_at_s.is_none()
                        || matches!(gate.family, Family::RunningMax | Family::RunningMin)
                })
                .filter_map(|r| r.gates.get(&gate.metric).copied())
                .filter(|x| x.is_finite())
                .collect();
            (!v.is_empty()).then(|| [l.level, v.iter().sum::<f64>() / v.len() as f64])
        })
        .collect();
    pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
    pts.windows(2)
        .filter(|w| w[1][0] <= w[0][0] * (1.0 + NEIGHBOURS * resolution))
        .filter(|w| (w[1][1] - w[0][1]).abs() > SHARE * gate.bound.abs())
        .map(|w| Jump {
            metric: gate.metric.clone(),
            from: w[0],
            to: w[1],
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::margin::level::Run;

    fn level(at: f64, v: f64) -> Level {
        stopped(at, v, None)
    }

    fn stopped(at: f64, v: f64, stop: Option<f64>) -> Level {
        Level {
            level: at,
            value: 1.0 - at,
            passed: true,
            round: 1,
            successes: 1,
            runs: vec![Run {
                seed: None,
                passed: true,
                broken: Vec::new(),
                gates: [("m".to_string(), v)].into_iter().collect(),
                stopped_at_s: stop,
                steps: 0,
                error: None,
                cpu_s: 0.0,
            }],
        }
    }

    #[test]
    fn a_cliff_between_neighbours_is_a_jump_a_slope_is_not() {
        let gate = Gate {
            metric: "m".into(),
            bound: 0.02,
            minimum: false,
            family: Family::EndOnly,
        };
        // Gradual: 1 mm per 5 % of level up to the gate.
        let slope: Vec<Level> = (1..=8)
            .map(|i| level(0.8 + 0.02 * i as f64, 0.002 * i as f64))
            .collect();
        assert!(jumps(&slope, &gate, 0.05).is_empty());
        // A cliff: 3 mm, then 0.5 m one 2 % step on.
        let cliff = vec![level(0.5, 0.001), level(0.94, 0.003), level(0.96, 0.5)];
        let j = jumps(&cliff, &gate, 0.05);
        assert_eq!(j.len(), 1, "{j:?}");
        assert_eq!(j[0].from, [0.94, 0.003]);
        assert_eq!(j[0].to, [0.96, 0.5]);
        assert!(
            j[0].note()
                .starts_with("JUMP: m 0.003 → 0.5 between 0.94 and 0.96"),
            "{}",
            j[0].note()
        );
        // A run stopped early: its end value is a prefix's, not compared;
        // a running maximum's is.
        let early = vec![level(0.94, 0.003), stopped(0.96, 0.5, Some(1.0))];
        assert!(jumps(&early, &gate, 0.05).is_empty());
        let running = Gate {
            family: Family::RunningMax,
            ..gate.clone()
        };
        assert_eq!(jumps(&early, &running, 0.05).len(), 1);
        // Far apart (the doubling phase): not neighbours.
        let far = vec![level(0.2, 0.001), level(0.4, 0.5)];
        assert!(jumps(&far, &gate, 0.05).is_empty());
    }
}
