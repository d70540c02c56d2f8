//! `series.json`: a compact copy of a run's time series for the HTML report.
//!
//! Written by every run next to `run.mcap` (the MCAP holds every sample but
//! reading it back for the whole suite takes far longer than the report's
//! 2 s budget). Each series is min/max-decimated to at most
//! 2 × [`BUCKETS`] + 2 points, so spikes survive; the planar paths are
//! stride-decimated to at most [`PATH_POINTS`] points (x and y must stay
//! paired). Values are f32 (plenty for figures); NaN is `null`.

use crate::integrate::Trajectory;
use crate::record::RunRecord;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Format version of `series.json`.
pub const FORMAT: u32 = 1;
/// Buckets of the min/max decimation: about one minimum and one maximum per
/// two pixels of the report's 485-pixel plot area, which keeps every spike.
pub const BUCKETS: usize = 250;
/// Largest number of points of a planar path.
pub const PATH_POINTS: usize = 1500;

/// One named series on its own time grid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Series {
    /// Name (state coordinate, input, channel, ...).
    pub name: String,
    /// Sample times, s.
    pub t: Vec<f32>,
    /// Values (None: NaN).
    pub v: Vec<Option<f32>>,
}

/// A span of constant plan label in the ideal run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Span {
    /// Label (segment or primitive name).
    pub label: String,
    /// Start, s.
    pub start: f64,
    /// End, s.
    pub end: f64,
}

/// A polyline overlay (world frame unless `link` is set).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OverlayData {
    /// Name.
    pub name: String,
    /// Points, m.
    pub points: Vec<[f64; 3]>,
    /// Link the points are attached to (None: world).
    pub link: Option<String>,
    /// RGBA in [0, 1].
    pub rgba: [f32; 4],
}

/// Everything the report draws for one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeriesFile {
    /// [`FORMAT`].
    pub format: u32,
    /// Scenario name.
    pub scenario: String,
    /// State coordinate names.
    pub state_names: Vec<String>,
    /// Input names.
    pub input_names: Vec<String>,
    /// Indices of angular state coordinates (rad in the series).
    pub angular: Vec<usize>,
    /// Indices of the planar position, when the model has one.
    pub position: Option<[usize; 2]>,
    /// Start state (model coordinates, SI).
    pub start: Vec<f64>,
    /// Goal state.
    pub goal: Vec<f64>,
    /// Goal heading (world yaw, rad), when the model has one.
    pub goal_heading: Option<f64>,
    /// Overlays of the 3D views (target lines, obstacles, ...).
    pub overlays: Vec<OverlayData>,
    /// Label spans of the ideal run.
    pub segments: Vec<Span>,
    /// Ideal state, one series per coordinate.
    pub ideal: Vec<Series>,
    /// Simulated state, one series per coordinate.
    pub sim: Vec<Series>,
    /// Commands (ideal run).
    pub commands: Vec<Series>,
    /// Tracking error sim − ideal per coordinate (rad for angles), then `position`.
    pub errors: Vec<Series>,
    /// The system's physics channels.
    pub channels: Vec<Series>,
    /// Planar paths (x, y), when the model has a planar position.
    pub path_ideal: Vec<[f32; 2]>,
    /// Simulated planar path.
    pub path_sim: Vec<[f32; 2]>,
    /// A recorded run's planar path (`[compare] reference`), lined up with the plan.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub path_real: Vec<[f32; 2]>,
    /// The other robots' planar position indices and paths (models with
    /// several robots; `position`, `path_ideal` and `path_sim` are the
    /// first robot's).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub other_robots: Vec<RobotPaths>,
    /// The system's analysis series (`V/sim`, `grasp_force/sim`,
    /// `grasp_force/bound`, ...), as in the Rerun log's `analysis/`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub analysis: Vec<Series>,
    /// Label spans of the simulated run, when it has its own (a feedback
    /// policy's modes on the simulated state; it may run longer than the ideal run).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sim_segments: Vec<Span>,
}

/// One more robot's planar paths ([`SeriesFile::other_robots`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotPaths {
    /// Indices of its planar position (x, y) in the state.
    pub position: [usize; 2],
    /// Its ideal path.
    pub ideal: Vec<[f32; 2]>,
    /// Its simulated path.
    pub sim: Vec<[f32; 2]>,
}

fn opt(x: f64) -> Option<f32> {
    x.is_finite().then_some(x as f32)
}

/// Indices kept by min/max decimation of `v` (length `n`) into [`BUCKETS`] buckets.
pub(crate) fn decimate(n: usize, v: impl Fn(usize) -> f64) -> Vec<usize> {
    if n <= 2 * BUCKETS {
        return (0..n).collect();
    }
    // The end points are always kept, so a decimated series spans the whole run.
    let mut out = Vec::with_capacity(2 * BUCKETS + 2);
    out.push(0);
    for b in 0..BUCKETS {
        let (lo, hi) = (b * n / BUCKETS, (b + 1) * n / BUCKETS);
        let (mut imin, mut imax, mut inan) = (lo, lo, None);
        for i in lo..hi {
            let x = v(i);
            if x.is_nan() {
                inan.get_or_insert(i);
                continue;
            }
            let (a, c) = (v(imin), v(imax));
            if a.is_nan() || x < a {
                imin = i;
            }
            if c.is_nan() || x > c {
                imax = i;
            }
        }
        let mut idx = [Some(imin), Some(imax), inan];
        idx.sort();
        for i in idx.into_iter().flatten() {
            if out.last() != Some(&i) {
                out.push(i);
            }
        }
    }
    if out.last() != Some(&(n - 1)) {
        out.push(n - 1);
    }
    out
}

fn series(name: &str, t: &[f64], v: impl Fn(usize) -> f64) -> Series {
    let idx = decimate(t.len(), &v);
    Series {
        name: name.to_string(),
        t: idx.iter().map(|&i| t[i] as f32).collect(),
        v: idx.iter().map(|&i| opt(v(i))).collect(),
    }
}

fn path(tr: &Trajectory, [ix, iy]: [usize; 2]) -> Vec<[f32; 2]> {
    let n = tr.q.len();
    let stride = n.div_ceil(PATH_POINTS).max(1);
    let mut out: Vec<[f32; 2]> = (0..n)
        .step_by(stride)
        .map(|k| [tr.q[k][ix] as f32, tr.q[k][iy] as f32])
        .collect();
    if n > 0 && !(n - 1).is_multiple_of(stride) {
        out.push([tr.q[n - 1][ix] as f32, tr.q[n - 1][iy] as f32]);
    }
    out
}

/// Label spans of a trajectory.
pub(crate) fn spans(tr: &Trajectory, labels: &[String]) -> Vec<Span> {
    let mut out: Vec<Span> = Vec::new();
    for (k, &l) in tr.label.iter().enumerate() {
        let name = labels.get(l).cloned().unwrap_or_else(|| format!("#{l}"));
        let t = tr.t[k];
        match out.last_mut() {
            Some(s) if s.label == name => s.end = t,
            _ => {
                if let Some(s) = out.last_mut() {
                    s.end = t;
                }
                out.push(Span {
                    label: name,
                    start: t,
                    end: t,
                })
            }
        }
    }
    out
}

impl SeriesFile {
    /// The report data of a finished run.
    pub fn from_record(rec: &RunRecord<'_>) -> SeriesFile {
        let names: Vec<String> = rec.state_names.iter().map(|s| s.to_string()).collect();
        let ideal = rec.ideal;
        let sim = &rec.sim.traj;
        let per_coord = |tr: &Trajectory| -> Vec<Series> {
            names
                .iter()
                .enumerate()
                .map(|(i, n)| series(n, &tr.t, |k| tr.q[k][i]))
                .collect()
        };
        let c = rec.comparison;
        let mut errors: Vec<Series> = names
            .iter()
            .enumerate()
            .map(|(i, n)| series(n, &c.t, |k| c.coord_error[i][k]))
            .collect();
        if let Some(p) = &c.position_error {
            errors.push(series("position", &c.t, |k| p[k]));
        }
        for (r, p) in c.robot_position_error.iter().enumerate() {
            errors.push(series(&format!("position_{}", r + 1), &c.t, |k| p[k]));
        }
        SeriesFile {
            format: FORMAT,
            scenario: rec.scenario.to_string(),
            input_names: rec.input_names.iter().map(|s| s.to_string()).collect(),
            angular: rec.angular.to_vec(),
            position: rec.position(),
            start: ideal
                .q
                .first()
                .map(|q| q.iter().copied().collect())
                .unwrap_or_default(),
            goal: rec.goal.to_vec(),
            goal_heading: rec.goal_heading,
            overlays: rec
                .overlays
                .iter()
                .map(|o| OverlayData {
                    name: o.name.clone(),
                    points: o.points.clone(),
                    link: o.link.clone(),
                    rgba: o.rgba,
                })
                .collect(),
            segments: spans(ideal, rec.labels),
            ideal: per_coord(ideal),
            sim: per_coord(sim),
            commands: rec
                .input_names
                .iter()
                .enumerate()
                .map(|(j, n)| series(n, &ideal.t, |k| ideal.u[k][j]))
                .collect(),
            errors,
            channels: rec
                .sim
                .channels
                .iter()
                .map(|(n, v)| series(n, &sim.t, |k| v[k]))
                .collect(),
            path_ideal: rec.position().map(|p| path(ideal, p)).unwrap_or_default(),
            path_sim: rec.position().map(|p| path(sim, p)).unwrap_or_default(),
            path_real: rec
                .real
                .map(|r| {
                    let stride = r.pose.len().div_ceil(PATH_POINTS).max(1);
                    r.pose
                        .iter()
                        .step_by(stride)
                        .chain(r.pose.last())
                        .map(|p| [p[0] as f32, p[1] as f32])
                        .collect()
                })
                .unwrap_or_default(),
            other_robots: rec
                .robot_positions
                .iter()
                .skip(1)
                .map(|&p| RobotPaths {
                    position: p,
                    ideal: path(ideal, p),
                    sim: path(sim, p),
                })
                .collect(),
            analysis: rec
                .series
                .iter()
                .map(|s| series(&s.name, &s.t, |k| s.values[k]))
                .collect(),
            sim_segments: if sim.label.len() == sim.t.len() {
                spans(sim, rec.labels)
            } else {
                Vec::new()
            },
            state_names: names,
        }
    }
}

/// Write `series.json` for a run (compact JSON, atomically).
pub fn write(path: &Path, rec: &RunRecord<'_>) -> Result<(), crate::log::LogError> {
    let data = SeriesFile::from_record(rec);
    crate::log::atomic::write_file(path, |w| {
        serde_json::to_writer(w, &data).map_err(std::io::Error::other)
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(crate::prop_config::config(256))]
        /// Decimation keeps the extremes of every bucket, hence of the whole series,
        /// and the end points; indices are increasing.
        #[test]
        fn decimation_keeps_extremes(v in proptest::collection::vec(-1e6f64..1e6, 1..5000)) {
            let idx = decimate(v.len(), |i| v[i]);
            prop_assert!(idx.len() <= 2 * BUCKETS + 3 || idx.len() == v.len());
            prop_assert!(idx.windows(2).all(|w| w[0] < w[1]));
            prop_assert_eq!(idx[0], 0);
            prop_assert_eq!(*idx.last().unwrap(), v.len() - 1);
            let max = v.iter().cloned().fold(f64::MIN, f64::max);
            let min = v.iter().cloned().fold(f64::MAX, f64::min);
            prop_assert!(idx.iter().any(|&i| v[i] == max));
            prop_assert!(idx.iter().any(|&i| v[i] == min));
        }
    }

    #[test]
    fn nan_survives_decimation() {
        let mut v = vec![1.0; 10_000];
        v[5000] = f64::NAN;
        let idx = decimate(v.len(), |i| v[i]);
        assert!(idx.contains(&5000));
    }
}
