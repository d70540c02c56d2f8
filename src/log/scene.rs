//! Helpers shared by the MCAP and Rerun writers: segment names, paths, colours.

use std::borrow::Cow;

use crate::integrate::Trajectory;
use crate::record::RunRecord;

/// Ideal path colour (green), RGBA.
pub(crate) const IDEAL_RGBA: [f32; 4] = [0.18, 0.80, 0.25, 1.0];
/// Simulated path colour (orange), RGBA.
pub(crate) const SIM_RGBA: [f32; 4] = [1.0, 0.55, 0.0, 1.0];
/// Recorded path colour (grey), RGBA.
pub(crate) const REAL_RGBA: [f32; 4] = [0.55, 0.55, 0.58, 1.0];
/// Goal marker colour (red), RGBA.
pub(crate) const GOAL_RGBA: [f32; 4] = [0.90, 0.10, 0.15, 1.0];

/// Name of label `label` (falls back to its index when the name is missing).
pub(crate) fn segment_name<'a>(labels: &'a [String], label: usize) -> Cow<'a, str> {
    match labels.get(label) {
        Some(s) => Cow::Borrowed(s.as_str()),
        None => Cow::Owned(format!("#{label}")),
    }
}

/// Label in force at time `t` in the ideal run (the last sample with `t_k <= t`).
pub(crate) fn label_at(ideal: &Trajectory, t: f64) -> Option<usize> {
    let k = ideal.t.partition_point(|&tk| tk <= t + 1e-12);
    ideal.label.get(k.saturating_sub(1)).copied()
}

/// Time in integer nanoseconds (negative and NaN times clamp to 0).
pub(crate) fn nanos(t: f64) -> u64 {
    if t.is_finite() && t > 0.0 {
        (t * 1e9).round() as u64
    } else {
        0
    }
}

/// Every robot's planar path (x, y) of a trajectory, the first robot's
/// first (none when the model has no planar position).
pub(crate) fn planar_paths(rec: &RunRecord<'_>, traj: &Trajectory) -> Vec<Vec<[f64; 2]>> {
    rec.robot_positions
        .iter()
        .map(|&[ix, iy]| traj.q.iter().map(|q| [q[ix], q[iy]]).collect())
        .collect()
}

/// Every robot's goal position (x, y), the first robot's first.
pub(crate) fn goal_points(rec: &RunRecord<'_>) -> Vec<[f64; 2]> {
    rec.robot_positions
        .iter()
        .filter_map(|&[ix, iy]| Some([*rec.goal.get(ix)?, *rec.goal.get(iy)?]))
        .collect()
}

/// What a robot's paths and goal are called in the logs: `ideal`, `sim`,
/// `goal` for the first robot (the names a one-robot log has always had),
/// with `_2`, `_3`, ... for the others.
pub(crate) fn robot_suffix(r: usize) -> String {
    if r == 0 {
        String::new()
    } else {
        format!("_{}", r + 1)
    }
}

/// Frame / entity name of a link (a link literally called `world` would
/// shadow the root frame in Foxglove, so it is renamed).
pub(crate) fn link_frame(name: &str) -> Cow<'_, str> {
    if name == "world" {
        Cow::Borrowed("world_link")
    } else {
        Cow::Borrowed(name)
    }
}

/// Display name of state coordinate `i`; ensures non-empty names.
pub(crate) fn coord_name<'a>(names: &'a [&'static str], i: usize) -> Cow<'a, str> {
    match names.get(i) {
        Some(n) if !n.is_empty() => Cow::Borrowed(n),
        _ => Cow::Owned(format!("q{i}")),
    }
}

/// Marker size: 3 % of the path's extent, within [5 cm, 1 m].
pub(crate) fn marker_scale(path: &[[f64; 2]]) -> f64 {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in path.iter().filter(|p| p[0].is_finite() && p[1].is_finite()) {
        for i in 0..2 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    if extent.is_finite() {
        (0.03 * extent).clamp(0.05, 1.0)
    } else {
        0.1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn marker_scale_is_bounded() {
        assert_eq!(marker_scale(&[]), 0.1);
        assert_eq!(marker_scale(&[[0.0, 0.0], [100.0, 0.0]]), 1.0);
        assert_eq!(marker_scale(&[[0.0, 0.0], [0.1, 0.0]]), 0.05);
    }
}
