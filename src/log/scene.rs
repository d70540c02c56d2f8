//! Helpers shared by the MCAP and Rerun writers: segment names, paths, colours.

use std::borrow::Cow;

use crate::integrate::Trajectory;
use crate::record::RunRecord;

/// Ideal path colour (green), RGBA.
pub(crate) const IDEAL_RGBA: [f32; 4] = [0.18, 0.80, 0.25, 1.0];
/// Simulated path colour (orange), RGBA.
pub(crate) const SIM_RGBA: [f32; 4] = [1.0, 0.55, 0.0, 1.0];
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

/// Planar path (x, y) of a trajectory, when the record has a planar position.
pub(crate) fn planar_path(rec: &RunRecord<'_>, traj: &Trajectory) -> Option<Vec<[f64; 2]>> {
    let [ix, iy] = rec.position?;
    Some(traj.q.iter().map(|q| [q[ix], q[iy]]).collect())
}

/// Goal position (x, y) and heading (first angular coordinate), when available.
pub(crate) fn goal_pose(rec: &RunRecord<'_>) -> Option<([f64; 2], Option<f64>)> {
    let [ix, iy] = rec.position?;
    let p = [*rec.goal.get(ix)?, *rec.goal.get(iy)?];
    let heading = rec.goal_heading;
    Some((p, heading))
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
