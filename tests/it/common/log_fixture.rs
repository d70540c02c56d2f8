//! A synthetic run record for the log writers (shared by `tests/log_roundtrip.rs`
//! and `benches/harness.rs`): a car-like body driving along a gentle curve.
#![allow(dead_code)]

use anholonomy::integrate::Trajectory;
use anholonomy::record::{Comparison, LinkVisual, Pose, RunRecord, Shape, SimTrajectory, Visual};
use nalgebra::DVector;
use std::f64::consts::FRAC_1_SQRT_2;

pub const STATE: [&str; 4] = ["x", "y", "theta", "phi"];
pub const INPUT: [&str; 2] = ["v", "omega"];

/// A car-like body driving along a gentle curve: 4 coordinates, 2 links
/// (box chassis + cylinder/sphere/capsule "wheel" link).
pub struct Fixture {
    pub labels: Vec<String>,
    pub goal: Vec<f64>,
    pub ideal: Trajectory,
    pub sim: SimTrajectory,
    pub comparison: Comparison,
    pub links: Vec<LinkVisual>,
    pub metrics: Vec<(String, f64)>,
}

fn yaw(theta: f64) -> [f64; 4] {
    [0.0, 0.0, (0.5 * theta).sin(), (0.5 * theta).cos()]
}

impl Fixture {
    pub fn new(n: usize) -> Self {
        let dt = 0.01;
        let state = |t: f64, bias: f64| {
            DVector::from_vec(vec![
                t + bias,
                0.2 * (0.5 * t).sin() + bias,
                0.1 * t,
                0.05 * (t).cos(),
            ])
        };
        let mut ideal = Trajectory::default();
        let mut sim = SimTrajectory::default();
        for k in 0..n {
            let t = k as f64 * dt;
            let label = if k < n / 2 { 0 } else { 1 };
            ideal.t.push(t);
            ideal.q.push(state(t, 0.0));
            ideal
                .u
                .push(DVector::from_vec(vec![1.0, 0.1 * label as f64]));
            ideal.label.push(label);

            let q = state(t, 0.001 * t);
            let base = Pose {
                translation: [q[0], q[1], 0.1],
                rotation: yaw(q[2]),
            };
            let wheel = Pose {
                translation: [q[0] + 0.3, q[1], 0.1],
                rotation: yaw(q[2] + q[3]),
            };
            sim.traj.t.push(t);
            sim.traj.q.push(q);
            sim.traj
                .u
                .push(DVector::from_vec(vec![1.0, 0.1 * label as f64]));
            sim.traj.label.push(label);
            sim.link_poses.push(vec![base, wheel]);
            sim.link_pose_index.push(k);
        }
        sim.channels.push((
            "slip".to_string(),
            (0..n).map(|k| 1e-3 * k as f64).collect(),
        ));
        sim.steps = n;
        let coord_error = (0..STATE.len())
            .map(|i| (0..n).map(|k| sim.traj.q[k][i] - ideal.q[k][i]).collect())
            .collect();
        let position_error = (0..n)
            .map(|k| {
                let (a, b) = (&sim.traj.q[k], &ideal.q[k]);
                (a[0] - b[0]).hypot(a[1] - b[1])
            })
            .collect();
        let comparison = Comparison {
            t: ideal.t.clone(),
            coord_error,
            position_error: Some(position_error),
            robot_position_error: Vec::new(),
        };
        let visual = |shape, origin| Visual {
            shape,
            origin,
            rgba: [0.3, 0.4, 0.8, 1.0],
        };
        let links = vec![
            LinkVisual {
                name: "base_link".into(),
                visuals: vec![visual(
                    Shape::Box {
                        size: [0.5, 0.3, 0.1],
                    },
                    Pose::IDENTITY,
                )],
            },
            LinkVisual {
                name: "wheel".into(),
                visuals: vec![
                    visual(
                        Shape::Cylinder {
                            radius: 0.05,
                            length: 0.03,
                        },
                        Pose {
                            translation: [0.0; 3],
                            rotation: [FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2],
                        },
                    ),
                    visual(Shape::Sphere { radius: 0.02 }, Pose::IDENTITY),
                    visual(
                        Shape::Capsule {
                            radius: 0.01,
                            length: 0.1,
                        },
                        Pose {
                            translation: [0.0, 0.0, 0.05],
                            rotation: [0.0, 0.0, 0.0, 1.0],
                        },
                    ),
                ],
            },
        ];
        Fixture {
            labels: vec!["straight".into(), "turn".into()],
            goal: vec![1.0, 0.0, 0.1, 0.0],
            ideal,
            sim,
            comparison,
            links,
            metrics: vec![
                ("final_position_error".into(), 0.0123),
                ("steps".into(), n as f64),
            ],
        }
    }

    pub fn record(&self) -> RunRecord<'_> {
        RunRecord {
            scenario: "synthetic_line",
            state_names: &STATE,
            input_names: &INPUT,
            angular: &[2, 3],
            robot_positions: vec![[0, 1]],
            goal: &self.goal,
            labels: &self.labels,
            ideal: &self.ideal,
            sim: &self.sim,
            comparison: &self.comparison,
            links: &self.links,
            metrics: &self.metrics,
            goal_heading: self.goal.get(2).copied(),
            overlays: &[],
            series: &[],
            command: &serde_json::Value::Null,
            tracking_meaningful: true,
            real: None,
        }
    }
}
