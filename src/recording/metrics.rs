//! The metrics of a recorded run (`[compare] reference`), declared in one
//! place: name, unit, which way they get worse, what they measure. Each
//! compares the recording (lined up, [`super::align`]) at its own samples
//! with a run sampled at the same times, or its last sample with the goal.

use super::align::{errors, rms, PoseIndex, Track};
use crate::compare::wrap_angle;
use crate::integrate::Trajectory;
use crate::metric::Direction;
use crate::model::State;

/// One metric of a recorded run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RealMetric {
    /// Its name in summaries, thresholds and baselines.
    pub name: &'static str,
    /// Its unit.
    pub unit: &'static str,
    /// Which way it gets worse.
    pub direction: Direction,
    /// Whether it needs the model's heading.
    pub heading: bool,
    /// What it measures.
    pub what: &'static str,
}

const fn m(
    name: &'static str,
    unit: &'static str,
    heading: bool,
    what: &'static str,
) -> RealMetric {
    RealMetric {
        name,
        unit,
        direction: Direction::LowerIsBetter,
        heading,
        what,
    }
}

/// Every metric a recorded run adds.
pub const METRICS: &[RealMetric] = &[
    m(
        "real_goal_position",
        "m",
        false,
        "distance from the recording's last sample to the goal position",
    ),
    m(
        "real_goal_heading_deg",
        "deg",
        true,
        "heading error of the recording's last sample from the goal",
    ),
    m(
        "real_sim_position_rms",
        "m",
        false,
        "RMS distance between the recording and the physics run",
    ),
    m(
        "real_sim_position_max",
        "m",
        false,
        "largest distance between the recording and the physics run",
    ),
    m(
        "real_sim_heading_deg_rms",
        "deg",
        true,
        "RMS heading difference between the recording and the physics run",
    ),
    m(
        "real_sim_heading_deg_max",
        "deg",
        true,
        "largest heading difference between the recording and the physics run",
    ),
    m(
        "real_ideal_position_rms",
        "m",
        false,
        "RMS distance between the recording and the ideal run",
    ),
    m(
        "real_ideal_position_max",
        "m",
        false,
        "largest distance between the recording and the ideal run",
    ),
    m(
        "real_ideal_heading_deg_rms",
        "deg",
        true,
        "RMS heading difference between the recording and the ideal run",
    ),
    m(
        "real_ideal_heading_deg_max",
        "deg",
        true,
        "largest heading difference between the recording and the ideal run",
    ),
];

/// The names a model with (or without) a heading reports.
pub fn names(heading: bool) -> Vec<String> {
    METRICS
        .iter()
        .filter(|m| heading || !m.heading)
        .map(|m| m.name.to_string())
        .collect()
}

/// The declaration of `name`, if it is one of these.
pub fn find(name: &str) -> Option<&'static RealMetric> {
    METRICS.iter().find(|m| m.name == name)
}

/// The metrics of `track` against the two runs and the goal.
pub fn compute(
    track: &Track,
    ideal: &Trajectory,
    sim: &Trajectory,
    goal: &State,
    idx: &PoseIndex,
) -> Vec<(String, f64)> {
    let max = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    // A fitted frame: the recording as laid over the physics run.
    let laid = if track.fit_frame {
        let runs: Vec<[f64; 3]> = track
            .t
            .iter()
            .map(|t| idx.pose(crate::compare::sample(sim, *t).as_slice()))
            .collect();
        super::align::rigid_fit(&track.pose, &runs)
    } else {
        track.pose.clone()
    };
    let last = laid[laid.len() - 1];
    let g = idx.pose(goal.as_slice());
    let mut out = vec![
        (
            "real_goal_position".to_string(),
            (last[0] - g[0]).hypot(last[1] - g[1]),
        ),
        (
            "real_goal_heading_deg".to_string(),
            wrap_angle(last[2] - g[2]).abs().to_degrees(),
        ),
    ];
    for (run, name) in [(sim, "sim"), (ideal, "ideal")] {
        let e = errors(track, run, idx);
        out.push((format!("real_{name}_position_rms"), rms(&e.position)));
        out.push((format!("real_{name}_position_max"), max(&e.position)));
        out.push((
            format!("real_{name}_heading_deg_rms"),
            rms(&e.heading).to_degrees(),
        ));
        out.push((
            format!("real_{name}_heading_deg_max"),
            max(&e.heading).to_degrees(),
        ));
    }
    let keep = names(idx.heading.is_some());
    out.retain(|(n, _)| keep.contains(n));
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declared_directions_are_the_harness_convention() {
        // Baselines read the convention; a declared exception must be added there.
        for m in METRICS {
            assert_eq!(Direction::conventional(m.name), m.direction, "{}", m.name);
            assert_eq!(m.name.contains("_deg"), m.unit == "deg", "{}", m.name);
        }
        assert_eq!(names(false).len(), 5);
        assert_eq!(names(true).len(), METRICS.len());
    }
}
