//! The metrics of a recorded run (`[compare] reference`), declared as rows
//! in [`crate::metric::REAL`]. Each
//! compares the recording (lined up, [`crate::recording::align`]) at its own samples
//! with a run sampled at the same times, or its last sample with the goal.

use crate::compare::wrap_angle;
use crate::integrate::Trajectory;
use crate::metric::{Unit, REAL as METRICS};
use crate::model::State;
use crate::record::Track;
use crate::recording::align::{errors, rms, PoseIndex};

/// The names a model with (or without) a heading reports.
pub fn names(heading: bool) -> Vec<String> {
    METRICS
        .iter()
        .filter(|m| heading || m.unit != Unit::Degree)
        .map(|m| m.name.to_string())
        .collect()
}

/// The metrics of `track` against the two runs and the goal.
pub(crate) fn compute(
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
        crate::recording::align::rigid_fit(&track.pose, &runs)
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
    fn heading_metrics_are_the_ones_in_degrees() {
        for m in METRICS {
            assert_eq!(
                m.name.contains("_deg"),
                m.unit == Unit::Degree,
                "{}",
                m.name
            );
        }
        assert_eq!(names(false).len(), 5);
        assert_eq!(names(true).len(), METRICS.len());
    }
}
