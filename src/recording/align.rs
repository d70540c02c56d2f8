//! A recording lined up with a plan, and its distance from a run.
//!
//! **Time.** A recording's t becomes plan time as t − `time_offset`, where
//! t is counted from the plan's first command when the recording and the
//! plan come from the same bag (the bag's clock: log or header time, as the
//! plan reads it), and is the recording's own time otherwise (a CSV's `t`,
//! or the time since the topic's first message). So `time_offset` is the
//! recording time at which the commands start (0 for a shared bag clock).
//!
//! **Space.** With [`Frame::Start`] (the default) the recording is moved
//! rigidly (a rotation about z and a shift) so that its pose at plan time 0
//! is the scenario's start; [`Frame::Recorded`] takes its coordinates as
//! the scenario's.
//!
//! Only samples inside the runs' span (plan time 0 to the end of settling)
//! are kept: a gap in the recording simply contributes no samples.

use crate::compare::{sample, wrap_angle};
use crate::integrate::Trajectory;
use crate::record::Track;
use crate::recording::{Recording, RecordingError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Which frame a recording's coordinates are in.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Frame {
    /// Moved rigidly so that its pose at plan time 0 is the scenario's start.
    #[default]
    Start,
    /// As recorded: its coordinates are the scenario's.
    Recorded,
    /// Laid over each run it is compared with by the rotation and shift
    /// that fit best (least squares over the positions): steadier than one
    /// noisy sample at time 0, but it also hides a constant heading error.
    Fit,
}

impl Frame {
    /// As written in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Frame::Start => "start",
            Frame::Recorded => "recorded",
            Frame::Fit => "fit",
        }
    }

    /// From its name.
    pub fn parse(s: &str) -> Option<Frame> {
        match s {
            "start" => Some(Frame::Start),
            "recorded" => Some(Frame::Recorded),
            "fit" => Some(Frame::Fit),
            _ => None,
        }
    }
}

/// How to line a recording up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Alignment {
    /// The recording's time of the plan's t = 0 on a shared bag clock
    /// (recording t + `shared` is t since the first command), else 0.
    pub shared: f64,
    /// Recording time at which the commands start (on top of `shared`), s.
    pub time_offset: f64,
    /// The frame.
    pub frame: Frame,
}

/// The shift that puts a recording on its plan's bag clock: its t = 0 is
/// `rec_ns`, the plan's `plan_ns` (bag times, ns).
pub(crate) fn shared_clock(rec_ns: i64, plan_ns: i64) -> f64 {
    (rec_ns - plan_ns) as f64 * 1e-9
}

/// Where the recording is in plan time, for messages.
fn span_text(t: &[f64]) -> String {
    format!(
        "{} s to {} s",
        crate::numfmt::readable(t[0]),
        crate::numfmt::readable(t[t.len() - 1])
    )
}

/// Line `rec` up with a plan whose runs span 0..`end` s and start at
/// `start` (x, y, yaw).
pub fn align(
    rec: &Recording,
    a: &Alignment,
    start: [f64; 3],
    end: f64,
) -> Result<Track, RecordingError> {
    let t: Vec<f64> = rec.t.iter().map(|t| t + a.shared - a.time_offset).collect();
    let inside: Vec<usize> = (0..t.len())
        .filter(|&i| t[i] >= -1e-9 && t[i] <= end + 1e-9)
        .collect();
    if inside.len() < 2 {
        return Err(RecordingError::Alignment(format!(
            "{}: the recording does not overlap the plan: in plan time it spans {}, the runs 0 s to {} s ({} of its samples inside; {}); set the time offset (the recording time at which the commands start)",
            rec.source,
            span_text(&t),
            crate::numfmt::readable(end),
            inside.len(),
            if a.shared != 0.0 {
                "lined up on the bag's clock with the plan's commands".to_string()
            } else {
                format!("time offset {} s", crate::numfmt::readable(a.time_offset))
            }
        )));
    }
    let pose0 = pose_at(&t, &rec.pose, 0.0);
    let (c, s, shift) = match a.frame {
        Frame::Recorded | Frame::Fit => (1.0, 0.0, [0.0, 0.0, 0.0]),
        Frame::Start => {
            let d = start[2] - pose0[2];
            let (s, c) = d.sin_cos();
            let x = start[0] - (c * pose0[0] - s * pose0[1]);
            let y = start[1] - (s * pose0[0] + c * pose0[1]);
            (c, s, [x, y, d])
        }
    };
    let pose = inside
        .iter()
        .map(|&i| {
            let [x, y, h] = rec.pose[i];
            [
                c * x - s * y + shift[0],
                s * x + c * y + shift[1],
                h + shift[2],
            ]
        })
        .collect();
    Ok(Track {
        source: rec.source.clone(),
        t: inside.iter().map(|&i| t[i]).collect(),
        pose,
        fit_frame: a.frame == Frame::Fit,
    })
}

/// The pose at `at` by linear interpolation (yaw along the shorter way),
/// held at the ends.
fn pose_at(t: &[f64], pose: &[[f64; 3]], at: f64) -> [f64; 3] {
    let k = t.partition_point(|&s| s <= at);
    if k == 0 {
        return pose[0];
    }
    if k >= t.len() {
        return pose[t.len() - 1];
    }
    let w = (at - t[k - 1]) / (t[k] - t[k - 1]);
    let (a, b) = (pose[k - 1], pose[k]);
    [
        a[0] + w * (b[0] - a[0]),
        a[1] + w * (b[1] - a[1]),
        a[2] + w * wrap_angle(b[2] - a[2]),
    ]
}

/// Where a model's planar pose is in its state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PoseIndex {
    /// x and y.
    pub position: [usize; 2],
    /// The heading, when the model has one.
    pub heading: Option<usize>,
}

impl PoseIndex {
    /// The planar pose of `model`: its position and the angle named like a
    /// heading (`theta`, `yaw`, `heading`, `psi`); `None` without a position.
    pub fn of(model: &dyn crate::model::KinematicModel) -> Option<PoseIndex> {
        let position = model.position_states()?;
        let names = model.state_names();
        let heading = ["theta", "yaw", "heading", "psi"].iter().find_map(|h| {
            model
                .angular_states()
                .iter()
                .copied()
                .find(|&i| names.get(i) == Some(h))
        });
        Some(PoseIndex { position, heading })
    }

    /// The (x, y, yaw) of state `q` (yaw 0 without a heading).
    pub fn pose(&self, q: &[f64]) -> [f64; 3] {
        [
            q[self.position[0]],
            q[self.position[1]],
            self.heading.map_or(0.0, |h| q[h]),
        ]
    }

    /// A run as a track (every sample).
    pub fn track(&self, run: &Trajectory, source: &str) -> Track {
        Track {
            source: source.into(),
            t: run.t.clone(),
            pose: run.q.iter().map(|q| self.pose(q.as_slice())).collect(),
            fit_frame: false,
        }
    }
}

/// A run's errors from a track, at the track's samples.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Errors {
    /// Plan time, s.
    pub t: Vec<f64>,
    /// Position error, m.
    pub position: Vec<f64>,
    /// Heading error (wrapped), rad; empty without a heading.
    pub heading: Vec<f64>,
}

/// The errors of `run` (sampled at the track's times, held at its ends)
/// from `track`.
pub fn errors(track: &Track, run: &Trajectory, idx: &PoseIndex) -> Errors {
    let mut e = Errors::default();
    let runs: Vec<[f64; 3]> = track
        .t
        .iter()
        .map(|t| idx.pose(sample(run, *t).as_slice()))
        .collect();
    let laid;
    let poses = if track.fit_frame {
        laid = rigid_fit(&track.pose, &runs);
        &laid
    } else {
        &track.pose
    };
    for ((t, p), r) in track.t.iter().zip(poses).zip(&runs) {
        e.t.push(*t);
        e.position.push((r[0] - p[0]).hypot(r[1] - p[1]));
        if idx.heading.is_some() {
            e.heading.push(wrap_angle(r[2] - p[2]));
        }
    }
    e
}

/// `from` moved by the rotation about z and the shift that bring its
/// positions closest to `to`'s in least squares (2D Procrustes).
pub(crate) fn rigid_fit(from: &[[f64; 3]], to: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n = from.len().max(1) as f64;
    let mean = |v: &[[f64; 3]], i: usize| v.iter().map(|p| p[i]).sum::<f64>() / n;
    let (fx, fy, tx, ty) = (mean(from, 0), mean(from, 1), mean(to, 0), mean(to, 1));
    let (mut sc, mut ss) = (0.0, 0.0);
    for (a, b) in from.iter().zip(to) {
        let (ax, ay, bx, by) = (a[0] - fx, a[1] - fy, b[0] - tx, b[1] - ty);
        sc += ax * bx + ay * by;
        ss += ax * by - ay * bx;
    }
    let phi = ss.atan2(sc);
    let (s, c) = phi.sin_cos();
    from.iter()
        .map(|p| {
            let (x, y) = (p[0] - fx, p[1] - fy);
            [c * x - s * y + tx, s * x + c * y + ty, p[2] + phi]
        })
        .collect()
}

/// Root mean square (0 for no values).
pub fn rms(v: &[f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt()
}

impl Errors {
    /// The residual: the root mean square over the samples of the pose
    /// error, with the heading error counted as its arc at `length` m,
    /// sqrt(mean(|Δp|² + (length · Δθ)²)).
    pub fn residual(&self, length: f64) -> f64 {
        if self.t.is_empty() {
            return 0.0;
        }
        let h = |i: usize| self.heading.get(i).map_or(0.0, |d| length * d);
        let s: f64 = (0..self.t.len())
            .map(|i| self.position[i].powi(2) + h(i).powi(2))
            .sum();
        (s / self.t.len() as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::State;

    fn rec(t: &[f64], pose: &[[f64; 3]]) -> Recording {
        Recording {
            source: "r".into(),
            t: t.to_vec(),
            pose: pose.to_vec(),
            bag_clock: None,
        }
    }

    #[test]
    fn start_frame_moves_the_pose_at_time_zero_onto_the_start() {
        let r = rec(
            &[9.0, 10.0, 11.0, 12.0],
            &[
                [5.0, 5.0, 1.0],
                [5.0, 5.0, 1.0],
                [6.0, 5.0, 1.0],
                [7.0, 5.0, 1.0],
            ],
        );
        let a = Alignment {
            shared: 0.0,
            time_offset: 10.0,
            frame: Frame::Start,
        };
        let tr = align(&r, &a, [1.0, 2.0, 0.5], 5.0).unwrap();
        assert_eq!(tr.t, vec![0.0, 1.0, 2.0]);
        let p0 = tr.pose[0];
        assert!((p0[0] - 1.0).abs() < 1e-12 && (p0[1] - 2.0).abs() < 1e-12);
        assert!((p0[2] - 0.5).abs() < 1e-12);
        // One metre along the recorded +x is one metre along yaw -0.5 from the start.
        let p1 = tr.pose[1];
        assert!((p1[0] - (1.0 + (-0.5f64).cos())).abs() < 1e-12, "{p1:?}");
        assert!((p1[1] - (2.0 + (-0.5f64).sin())).abs() < 1e-12, "{p1:?}");
        let recorded = Alignment {
            frame: Frame::Recorded,
            ..a
        };
        assert_eq!(
            align(&r, &recorded, [1.0, 2.0, 0.5], 5.0).unwrap().pose[2],
            [7.0, 5.0, 1.0]
        );
    }

    #[test]
    fn a_fitted_frame_undoes_a_rigid_motion() {
        let to = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 2.0, 1.0]];
        let (s, c) = 0.7f64.sin_cos();
        let from: Vec<[f64; 3]> = to
            .iter()
            .map(|p| {
                [
                    c * p[0] - s * p[1] + 3.0,
                    s * p[0] + c * p[1] - 1.0,
                    p[2] + 0.7,
                ]
            })
            .collect();
        for (a, b) in rigid_fit(&from, &to).iter().zip(&to) {
            for i in 0..3 {
                assert!((a[i] - b[i]).abs() < 1e-12, "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn no_overlap_is_refused() {
        let r = rec(&[0.0, 1.0], &[[0.0; 3], [0.0; 3]]);
        let a = Alignment {
            shared: 0.0,
            time_offset: 30.0,
            frame: Frame::Start,
        };
        let e = align(&r, &a, [0.0; 3], 10.0).unwrap_err().to_string();
        assert!(e.contains("does not overlap the plan"), "{e}");
    }

    #[test]
    fn residual_counts_heading_as_an_arc() {
        let run = Trajectory {
            t: vec![0.0, 1.0],
            q: vec![
                State::from_vec(vec![0.0, 0.0, 0.0]),
                State::from_vec(vec![1.0, 0.0, 0.0]),
            ],
            ..Default::default()
        };
        let track = Track {
            source: "r".into(),
            t: vec![0.0, 1.0],
            pose: vec![[0.0, 0.3, 0.0], [1.0, 0.0, 0.1]],
            fit_frame: false,
        };
        let idx = PoseIndex {
            position: [0, 1],
            heading: Some(2),
        };
        let e = errors(&track, &run, &idx);
        let r = e.residual(2.0);
        assert!((r - ((0.09 + 0.04) / 2.0f64).sqrt()).abs() < 1e-12, "{r}");
    }
}
