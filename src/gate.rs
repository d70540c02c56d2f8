//! Gates: a scenario's `[thresholds]` (maxima) and `[minimums]` checked
//! against a run's metrics. The runner reports the breaches as text; the
//! margin search needs them as data (which metric broke, by how much).

use serde::Serialize;
use std::collections::BTreeMap;

/// One broken gate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Breach {
    /// Metric name.
    pub metric: String,
    /// Its value (NaN: not produced or undefined, which breaks any gate).
    pub value: f64,
    /// The bound it broke.
    pub bound: f64,
    /// A `[minimums]` gate (the value fell below the bound), else a `[thresholds]` one.
    pub minimum: bool,
}

impl std::fmt::Display for Breach {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let (v, b) = crate::numfmt::breach(self.value, self.bound);
        let op = if self.minimum { "<" } else { ">" };
        write!(f, "{} = {v} {op} {b}", self.metric)
    }
}

/// The gates `metrics` break: thresholds in name order, then minimums. A
/// metric the run did not produce counts as NaN.
pub(crate) fn breaches(
    thresholds: &BTreeMap<String, f64>,
    minimums: &BTreeMap<String, f64>,
    metrics: &[(String, f64)],
) -> Vec<Breach> {
    let value = |k: &str| {
        metrics
            .iter()
            .find(|(n, _)| n == k)
            .map(|(_, v)| *v)
            .unwrap_or(f64::NAN)
    };
    let mut out = Vec::new();
    for (k, limit) in thresholds {
        let v = value(k);
        if v.is_nan() || v > *limit {
            out.push(Breach {
                metric: k.clone(),
                value: v,
                bound: *limit,
                minimum: false,
            });
        }
    }
    for (k, floor) in minimums {
        let v = value(k);
        if v.is_nan() || v < *floor {
            out.push(Breach {
                metric: k.clone(),
                value: v,
                bound: *floor,
                minimum: true,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn breaches_in_order_with_the_runner_text() {
        let t = BTreeMap::from([("b".to_string(), 1.0), ("a".to_string(), 2.0)]);
        let m = BTreeMap::from([("c".to_string(), 0.5)]);
        let metrics = vec![("a".to_string(), 3.0), ("b".to_string(), 1.0)];
        let b = breaches(&t, &m, &metrics);
        let text: Vec<String> = b.iter().map(|b| b.to_string()).collect();
        assert_eq!(text, ["a = 3 > 2", "c = NaN < 0.5"]);
        assert!(b[1].minimum && b[1].value.is_nan());
    }
}
