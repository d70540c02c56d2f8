//! Plain data describing one finished run: what the loggers (MCAP, Rerun,
//! summary) consume. Built by the runner; no logic beyond accessors.

use crate::integrate::Trajectory;
use serde::Serialize;

/// A recording in plan time and the scenario's frame, inside the runs' span.
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    /// What it was read from.
    pub source: String,
    /// Plan time of each sample, s.
    pub t: Vec<f64>,
    /// (x, y, yaw) per sample.
    pub pose: Vec<[f64; 3]>,
    /// Laid over each run by a best rigid fit (`recording::align::Frame::Fit`).
    pub fit_frame: bool,
}

/// A rigid transform in f64: translation and unit quaternion (x, y, z, w).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pose {
    /// Translation, m.
    pub translation: [f64; 3],
    /// Rotation quaternion (x, y, z, w).
    pub rotation: [f64; 4],
}

impl Pose {
    /// The identity transform.
    pub const IDENTITY: Pose = Pose {
        translation: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
    };
}

/// Visual geometry of a URDF link, in the link frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub enum Shape {
    /// A box.
    Box {
        /// Full edge lengths, m.
        size: [f64; 3],
    },
    /// A cylinder, its axis along local z (URDF convention).
    Cylinder {
        /// Radius, m.
        radius: f64,
        /// Length along z, m.
        length: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius, m.
        radius: f64,
    },
    /// A capsule along local z.
    Capsule {
        /// Radius, m.
        radius: f64,
        /// Length of the cylindrical part along z, m.
        length: f64,
    },
    /// A triangle mesh from a file (its vertices in the visual's frame, scaled).
    Mesh {
        /// The mesh file.
        file: String,
        /// Its triangles.
        #[serde(skip)]
        mesh: std::sync::Arc<TriMesh>,
    },
}

/// A triangle mesh.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMesh {
    /// Vertex positions, m.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles (indices into `vertices`).
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Unit normal per vertex: the area-weighted mean of its triangles'
    /// normals (for shading in the viewers).
    pub fn vertex_normals(&self) -> Vec<[f64; 3]> {
        let mut n = vec![[0.0; 3]; self.vertices.len()];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.vertices[i as usize]);
            let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
            let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
            let f = [
                u[1] * v[2] - u[2] * v[1],
                u[2] * v[0] - u[0] * v[2],
                u[0] * v[1] - u[1] * v[0],
            ];
            for &i in t {
                for k in 0..3 {
                    n[i as usize][k] += f[k];
                }
            }
        }
        for v in &mut n {
            let l = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            if l > 0.0 {
                *v = v.map(|x| x / l);
            }
        }
        n
    }

    /// The largest distance of a vertex from the origin, m.
    pub fn radius(&self) -> f64 {
        self.vertices
            .iter()
            .map(|v| (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt())
            .fold(0.0, f64::max)
    }
}

/// One `<visual>` element.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Visual {
    /// Geometry.
    pub shape: Shape,
    /// Pose of the geometry in the link frame.
    pub origin: Pose,
    /// RGBA in [0, 1].
    pub rgba: [f32; 4],
}

/// A link with its visuals.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinkVisual {
    /// URDF link name.
    pub name: String,
    /// Visual elements.
    pub visuals: Vec<Visual>,
}

/// The physics replay, sampled every sim step.
#[derive(Debug, Clone, Default)]
pub struct SimTrajectory {
    /// Model coordinates read back from the simulation, with the commands applied.
    pub traj: Trajectory,
    /// World pose of each link (same order as [`RunRecord::links`]) at the
    /// samples [`SimTrajectory::link_pose_index`] names (every sample, or
    /// fewer: only the 3D logs read them).
    pub link_poses: Vec<Vec<Pose>>,
    /// Sample index (into `traj`) of each row of `link_poses`, increasing.
    pub link_pose_index: Vec<usize>,
    /// Extra named time series (slip, momentum, ...), one value per sample.
    pub channels: Vec<(String, Vec<f64>)>,
    /// Number of physics steps taken.
    pub steps: usize,
    /// Steps with the plan in force (`traj.u[..plan_steps]`); the rest
    /// settle with zero input.
    pub plan_steps: usize,
    /// What the drives received from `traj.t[k]` on, when a perturbation
    /// delays or lags the commands (`traj.u` is what was issued); empty
    /// otherwise.
    pub received: Vec<crate::model::Input>,
}

impl SimTrajectory {
    /// The series of a named channel, if the system records it.
    pub fn channel(&self, name: &str) -> Option<&[f64]> {
        self.channels
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.as_slice())
    }

    /// Time of each row of `link_poses`, s.
    pub fn link_pose_times(&self) -> impl Iterator<Item = f64> + '_ {
        self.link_pose_index.iter().map(|&k| self.traj.t[k])
    }
}

/// A named time series computed after the run by the system (e.g. the
/// planner's potential along each run), on its own time grid.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Series {
    /// Name, `/`-separated (e.g. `V/ideal`).
    pub name: String,
    /// Sample times, s.
    pub t: Vec<f64>,
    /// Values.
    pub values: Vec<f64>,
}

impl Series {
    /// An empty series.
    pub fn new(name: String) -> Self {
        Series {
            name,
            ..Default::default()
        }
    }

    /// Append a sample.
    pub fn push(&mut self, t: f64, v: f64) {
        self.t.push(t);
        self.values.push(v);
    }
}

/// Errors of the simulated run against the ideal run on one time grid.
#[derive(Debug, Clone, Default, Serialize)]
pub struct Comparison {
    /// Common time grid, s.
    pub t: Vec<f64>,
    /// Per-coordinate error sim − ideal (angles wrapped, in rad), one series per state coordinate.
    pub coord_error: Vec<Vec<f64>>,
    /// Position error ‖p_sim − p_ideal‖ (models with a planar position), m;
    /// with several robots, the worst robot's at each instant.
    pub position_error: Option<Vec<f64>>,
    /// With several robots, each robot's position error (robot order), m;
    /// empty for one robot (its series is `position_error`).
    pub robot_position_error: Vec<Vec<f64>>,
}

/// A named polyline in the world frame, drawn with the paths (e.g. a target line).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Overlay {
    /// Entity name.
    pub name: String,
    /// Points, m, in the world frame or, with `link`, in that link's frame.
    pub points: Vec<[f64; 3]>,
    /// URDF link the points are attached to (they move with it); `None`: world.
    pub link: Option<String>,
    /// RGBA in [0, 1].
    pub rgba: [f32; 4],
}

/// Everything about one run that a logger may show.
pub struct RunRecord<'a> {
    /// Scenario name.
    pub scenario: &'a str,
    /// State coordinate names.
    pub state_names: &'a [&'static str],
    /// Input names.
    pub input_names: &'a [&'static str],
    /// Indices of angular coordinates.
    pub angular: &'a [usize],
    /// Every robot's planar position indices (x, y) in the state, the
    /// first robot's first; empty when the model has no planar position.
    pub robot_positions: Vec<[usize; 2]>,
    /// Goal state.
    pub goal: &'a [f64],
    /// Goal heading as a world yaw (rad, from +x towards +y), when the model has one.
    pub goal_heading: Option<f64>,
    /// Extra polylines for the 3D views.
    pub overlays: &'a [Overlay],
    /// System series (e.g. the potential along each run).
    pub series: &'a [Series],
    /// Label names (plan segments / primitives).
    pub labels: &'a [String],
    /// The ideal kinematic run.
    pub ideal: &'a Trajectory,
    /// The physics run.
    pub sim: &'a SimTrajectory,
    /// Comparison on the common grid.
    pub comparison: &'a Comparison,
    /// URDF visual geometry per link.
    pub links: &'a [LinkVisual],
    /// Scalar metrics (name → value), as in the summary.
    pub metrics: &'a [(String, f64)],
    /// How the logged commands relate to the plan ([`crate::plan::Plan::command_info`]).
    pub command: &'a serde_json::Value,
    /// Whether the tracking errors mean anything (the commands depend on time alone:
    /// [`crate::runner::tracking_meaningful`]); a feedback policy's sim run reacts to its own
    /// state, so its distance to the ideal run is not a tracking error.
    pub tracking_meaningful: bool,
    /// A recorded run (`[compare] reference`), lined up with the plan: the third path.
    pub real: Option<&'a Track>,
}

impl RunRecord<'_> {
    /// Indices of the (first robot's) planar position, when the model has one.
    pub fn position(&self) -> Option<[usize; 2]> {
        self.robot_positions.first().copied()
    }
}
