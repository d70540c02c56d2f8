//! Seed 004 (Tanner, Loizou & Kyriakopoulos, "Nonholonomic navigation and
//! control of cooperating mobile manipulators"): a dipolar inverse Lyapunov
//! function on a point world, and the discontinuous feedback law of Eq. 18.
//!
//! * [`contact`]: the obstacle function a robot part sees after H1 (a convex
//!   minimisation, with envelope-theorem derivatives);
//! * [`point_world`]: H0, T, the switches, H1 and H2 as printed (Eqs. 6–9);
//! * [`potential`]: V (Eq. 15) and f (Eq. 17), exact gradients by dual numbers;
//! * [`adjoint`]: the same gradient by hand-written adjoints (the fast path;
//!   its buffers in `scratch`, so that `potential` does not import it);
//! * [`control`]: Eq. 18;
//! * [`stall`]: the law's progress: the `stalled` stop and the hand-over to
//!   the final alignment (ours).
//!
//! The planner's output is a feedback policy ([`crate::plan::ControlLaw::Feedback`]):
//! the harness evaluates it on the ideal state and, in physics, on the
//! simulated state.

pub mod adjoint;
pub mod contact;
pub mod control;
pub mod guard;
pub mod object;
mod params;
pub mod point_world;
pub mod potential;
mod scratch;
pub mod sequence;
pub mod stall;
pub mod terms;

use crate::model::{Input, State};
use crate::plan::{Command, ControlLaw, Controller, Plan, PolicyFactory};
use crate::planner::{check_param, PlanError};
use crate::robots::mobile_manipulator::kinematics::{self as mm, DOF, INPUTS};
pub use control::SpeedLaw;
use control::{Branch, Gains};
pub use params::{Approach, DilfParams, Grasps, Tolerance};
use potential::{DipoleProduct, GoalFrame, GraspCorrection, Scene, SingularityEnclosure, Warm};
use schemars::JsonSchema;
pub use sequence::{SequenceMode, SequenceParams};
use serde::{Deserialize, Serialize};
use stall::{Progress, StallParams, Verdict};
use std::sync::Arc;

/// The labels on which the law stops: a run that ends on any other label
/// ran out of time (the horizon).
pub const STOPS: [&str; 6] = [
    "converged",
    "collision",
    "singular",
    "solver failure",
    "overstrained",
    "stalled",
];

/// Label indices of the plan: one per combination of the robots' Eq. 18b
/// branches, the same combinations with the input scaled down by the hold
/// guard, then these.
fn labels(robots: usize) -> Vec<String> {
    let combos: Vec<String> = (0..3usize.pow(robots as u32))
        .map(|code| {
            (0..robots)
                .map(|r| Branch::name(code / 3usize.pow(r as u32) % 3))
                .collect::<Vec<_>>()
                .join("/")
        })
        .collect();
    let mut out = combos.clone();
    out.extend(combos.iter().map(|c| format!("{c} (guarded)")));
    out.extend(STOPS.map(String::from));
    out
}

/// Index of a plan label (e.g. `"stalled"`) for `robots` robots.
pub(crate) fn label_index(robots: usize, name: &str) -> Option<usize> {
    labels(robots).iter().position(|l| l == name)
}

struct Policy {
    /// The task: V on the task's goal.
    scene: Arc<Scene>,
    /// The intermediate goals' scenes, in order (empty: straight to the
    /// goal), and when one counts as reached.
    phases: Vec<Arc<Scene>>,
    sequence: SequenceParams,
    gains: Gains,
    tolerance: Tolerance,
    /// Hold period, s, and whether the hold guard acts.
    period: f64,
    hold_guard: bool,
    stall: StallParams,
    grasps: Grasps,
    /// Whether a stall in an intermediate phase moves on to the next phase
    /// (the run's plan) instead of ending the run (the sequence's candidate
    /// runs, which must reach every intermediate goal).
    yield_on_stall: bool,
}

impl Policy {
    /// The law of `params` on `scene` (the task), through `phases`.
    fn new(
        scene: Arc<Scene>,
        phases: Vec<Arc<Scene>>,
        params: &DilfParams,
        yield_on_stall: bool,
    ) -> Policy {
        Policy {
            scene,
            phases,
            sequence: params.sequence,
            gains: params.gains(),
            tolerance: params.tolerance,
            period: params.period,
            hold_guard: params.hold_guard,
            stall: params.stall,
            grasps: params.grasps,
            yield_on_stall,
        }
    }
}

/// One robot in the open with `params`' potential and `goal` (tests).
#[cfg(test)]
fn open_scene(params: &DilfParams, goal: Vec<f64>) -> Arc<Scene> {
    let potential = params.potential();
    let parts = crate::robots::mobile_manipulator::kinematics::default_parts();
    Arc::new(Scene::new(1, parts, Vec::new(), goal, potential).unwrap())
}

/// Two robots in the open carrying the default rod grasped at `start`,
/// with `params`' potential and `goal` (tests).
#[cfg(test)]
fn pair_scene(params: &DilfParams, start: &[f64], goal: Vec<f64>) -> Arc<Scene> {
    use crate::robots::mobile_manipulator::beam::{Beam, GFRP_ROD_10MM};
    let potential = params.potential();
    let (material, section) = GFRP_ROD_10MM;
    let rod = Beam {
        material,
        section,
        length: 1.0,
    };
    let carried = object::Carried::at_rest(&rod, None, start, 4.0, 8, 0.02).unwrap();
    let parts = crate::robots::mobile_manipulator::kinematics::default_parts();
    let scene = Scene::new(2, parts, Vec::new(), goal, potential).unwrap();
    Arc::new(scene.with_object(carried))
}

struct DilfController {
    policy: Arc<Policy>,
    warm: Warm,
    /// Warm starts of the guard's evaluations at predicted states.
    guard_warm: Warm,
    /// Number of branch combinations (3^k): the guarded ones follow, then
    /// "converged" at 2 · combos.
    combos: usize,
    /// The law's progress (stall stop, hand-over).
    progress: Progress,
    /// Per robot: turning in place to its goal heading (Eq. 18 suspended).
    aligning: Vec<bool>,
    /// Index of the current intermediate goal (`phases.len()`: the task's).
    phase: usize,
}

impl DilfController {
    /// The scene of the current phase.
    fn scene(&self) -> &Arc<Scene> {
        let p = &self.policy;
        p.phases.get(self.phase).unwrap_or(&p.scene)
    }

    /// Move on past every intermediate goal that `q` has reached: the law's
    /// progress restarts, and a platform already within the position
    /// tolerance of the new goal turns in place to its heading.
    fn advance(&mut self, t: f64, q: &[f64]) {
        let p = self.policy.clone();
        let mut moved = false;
        while self.phase < p.phases.len()
            && p.sequence
                .reached(&p.tolerance, q, &p.phases[self.phase].goal)
        {
            self.phase += 1;
            moved = true;
        }
        if moved {
            self.enter_phase(t, q);
        }
    }

    /// The law's progress restarts on the current phase's goal, and a
    /// platform already within the position tolerance of it turns in place.
    fn enter_phase(&mut self, t: f64, q: &[f64]) {
        let p = self.policy.clone();
        {
            self.progress = Progress::new(p.stall);
            self.progress.restart(t);
            let goal = &self.scene().goal;
            let within: Vec<bool> = (0..self.aligning.len())
                .map(|r| {
                    let i = DOF * r;
                    (q[i] - goal[i]).hypot(q[i + 1] - goal[i + 1]) <= p.tolerance.position
                })
                .collect();
            self.aligning = within;
        }
    }

    /// Which robots turn in place from this sample on: those within half the
    /// position tolerance; those already turning, while within the whole
    /// tolerance; and, when the law has made no progress for
    /// `handover_time`, every robot within the tolerance. `Err(())` when it
    /// has made none for `stall.time`: the run ends.
    fn hand_over(&mut self, t: f64, q: &[f64], v: f64) -> Result<(), ()> {
        let p = &self.policy;
        let goal = &p.phases.get(self.phase).unwrap_or(&p.scene).goal;
        let dist = |r: usize| {
            let i = DOF * r;
            (q[i] - goal[i]).hypot(q[i + 1] - goal[i + 1])
        };
        let tolerance = p.tolerance.position;
        for (r, a) in self.aligning.iter_mut().enumerate() {
            let d = dist(r);
            *a = d <= p.gains.goal_lock_radius || (*a && d <= tolerance);
        }
        // The in-place turn is progress while a heading is still off.
        let heading = (0..self.aligning.len())
            .filter(|&r| self.aligning[r])
            .map(|r| crate::compare::wrap_angle(q[DOF * r + 2] - goal[DOF * r + 2]).abs())
            .filter(|h| *h > p.tolerance.heading_deg.to_radians())
            .reduce(f64::max);
        match self.progress.observe(t, v, heading) {
            // An intermediate goal is only a waypoint: a stall short of it
            // (in physics, the hold branch's sliding surface a few cm out)
            // moves on to the next phase; the task's own goal ends the run.
            Verdict::Stalled if p.yield_on_stall && self.phase < p.phases.len() => {
                self.phase += 1;
                self.enter_phase(t, q);
            }
            Verdict::Stalled => return Err(()),
            Verdict::HandOver => {
                for (r, a) in self.aligning.iter_mut().enumerate() {
                    *a |= dist(r) <= tolerance;
                }
            }
            Verdict::Moving => {}
        }
        Ok(())
    }
}

impl Controller for DilfController {
    fn command(&mut self, t: f64, q: &State) -> Command {
        self.decide(t, q.as_slice(), None)
    }

    /// With `grasps = "measured"` and a carried beam, the flanges' 3D poses
    /// (12 numbers per robot: position, rotation row by row) replace the
    /// kinematic ones for the beam ([`GraspCorrection`]).
    fn command_measured(&mut self, t: f64, q: &State, measured: &[f64]) -> Command {
        let q = q.as_slice();
        let p = &self.policy;
        if p.grasps != Grasps::Measured
            || p.scene.object.is_none()
            || measured.len() < 2 * mm::FLANGE_MEASUREMENT
        {
            return self.decide(t, q, None);
        }
        let corr: GraspCorrection = std::array::from_fn(|r| {
            let flange = mm::flange_from_measurement(measured, r);
            mm::frames::<f64>(&q[DOF * r..DOF * (r + 1)])
                .tool
                .inverse()
                .then(&flange)
        });
        self.decide(t, q, Some(&corr))
    }
}

impl DilfController {
    fn decide(&mut self, t: f64, q: &[f64], measured: Option<&GraspCorrection>) -> Command {
        let p = self.policy.clone();
        let robots = p.scene.robots;
        let stop = |label: usize| Command {
            u: Input::zeros(INPUTS * robots),
            label,
            done: true,
        };
        let done = 2 * self.combos;
        if p.tolerance.reached(q, &p.scene.goal) {
            return stop(done);
        }
        self.advance(t, q);
        let scene = self.scene().clone();
        let (e, f) = match scene.field_with(q, measured, &mut self.warm) {
            Ok(x) => x,
            Err(_) => return stop(done + 3),
        };
        if e.min_beta <= 0.0 {
            return stop(done + 1);
        }
        if e.min_singular <= 0.0 {
            return stop(done + 2);
        }
        // The beam outside its admissible set (b_f ≤ 0): V = 0 there, the
        // law is undefined, as at a collision. (Only a simulated state can
        // get there: the ideal run keeps V̇ ≥ 0.)
        if e.overstrained() {
            return stop(done + 4);
        }
        if self.hand_over(t, q, e.v).is_err() {
            return stop(done + 5);
        }
        let (mut u, branches) =
            control::control_aligning(q, &f, &scene.goal, &p.gains, &self.aligning);
        let mut label = branches
            .iter()
            .enumerate()
            .map(|(r, b)| b.index() * 3usize.pow(r as u32))
            .sum();
        if p.hold_guard {
            let now = guard::Barriers::of(&e);
            let warm = &mut self.guard_warm;
            if guard::guard(&scene, q, measured, &now, &mut u, p.period, warm) > 0 {
                label += self.combos;
            }
        }
        Command {
            u: Input::from_vec(u),
            label,
            done: false,
        }
    }
}

struct Factory(Arc<Policy>);

impl PolicyFactory for Factory {
    fn start(&self) -> Box<dyn Controller> {
        Box::new(DilfController {
            policy: self.0.clone(),
            warm: self.0.scene.warm(),
            guard_warm: self.0.scene.warm(),
            combos: 3usize.pow(self.0.scene.robots as u32),
            progress: Progress::new(self.0.stall),
            aligning: vec![false; self.0.scene.robots],
            phase: 0,
        })
    }
}

/// Refuse a configuration (`what`: the scenario key, `start` or `goal`) that
/// puts a robot part inside an obstacle or an arm inside a singularity
/// enclosure: V is 0 there and Eq. 18 cannot start (or end).
pub(crate) fn check_configuration(scene: &Scene, q: &[f64], what: &str) -> Result<(), PlanError> {
    let bad = |reason: String| PlanError::InvalidParameter {
        name: what.into(),
        reason,
    };
    let closest = scene
        .closest(q)
        .map_err(|e| PlanError::NoConvergence(e.to_string()))?;
    if let Some(c) = closest.filter(|c| c.beta <= 0.0) {
        return Err(bad(format!(
            "puts {} inside {} (their ellipsoids overlap: β = {:.3e} ≤ 0)",
            c.part, c.obstacle, c.beta
        )));
    }
    let e = scene
        .evaluate::<f64>(q, &mut scene.warm())
        .map_err(|e| PlanError::NoConvergence(e.to_string()))?;
    if e.min_singular <= 0.0 {
        return Err(bad(
            "puts an arm inside a singularity enclosure (see planner.singularity)".into(),
        ));
    }
    if let (true, Some(o)) = (e.overstrained(), &scene.object) {
        let st = o.state::<f64>(q);
        use crate::numfmt::readable as r;
        let stretch = o.max_stretch.map_or(String::new(), |eps| {
            format!(
                ", stretch {} m against max_stretch = {}",
                r(st.q_f[0]),
                r(eps)
            )
        });
        let bound = match (o.bound, o.wrenches(&st.q_f, &st.gravity)) {
            (object::Bound::Wrench { force, moment }, Some(w)) => {
                let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
                format!(
                    "a grasp wrench leaves |F| ≤ {} N, |M| ≤ {} N m (grasp 1: {} N, \
                     {} N m; grasp 2: {} N, {} N m)",
                    r(force),
                    r(moment),
                    r(norm(&w[0][..3])),
                    r(norm(&w[0][3..])),
                    r(norm(&w[1][..3])),
                    r(norm(&w[1][3..]))
                )
            }
            _ => format!("a node leaves the ball ‖q_fi‖ ≤ q_F = {}", r(o.q_max)),
        };
        return Err(bad(format!(
            "deforms the beam beyond its bound: {bound} or the stretch bound \
             (‖q_f‖∞ = {}{stretch}, grasp points {} m apart, beam {} m)",
            r(e.max_deformation),
            r(object::grasp_distance(q)),
            r(o.fe.beam().length)
        )));
    }
    Ok(())
}

/// The feedback plan for `scene` (whose goal is the task's goal) from
/// `start`. `step`: the ideal run's integration step (the scenario's
/// `sim.dt`), with which `[planner.sequence]` runs its candidates, so that
/// its choice is the ideal run's outcome.
pub fn plan(
    scene: Arc<Scene>,
    start: &State,
    params: &DilfParams,
    step: f64,
) -> Result<Plan, PlanError> {
    params.validate()?;
    let q = start.as_slice();
    check_configuration(&scene, q, "start")?;
    check_configuration(&scene, &scene.goal, "goal")?;
    let e = scene
        .evaluate::<f64>(q, &mut scene.warm())
        .map_err(|e| PlanError::NoConvergence(e.to_string()))?;
    let mut details = serde_json::json!({
        "robots": scene.robots,
        "parts_per_robot": scene.parts.iter().map(|p| p.name).collect::<Vec<_>>(),
        "obstacles": scene.obstacles.iter().map(|o| o.name.clone()).collect::<Vec<_>>(),
        "pairs": scene.pair_count(),
        "start_v": e.v,
        "start_min_beta": e.min_beta,
        "start_sum_h2": e.d,
        "start_max_deformation": e.max_deformation,
    });
    let policy = |phases: Vec<Arc<Scene>>| Policy::new(scene.clone(), phases, params, false);
    let mut chosen = Arc::new(policy(Vec::new()));
    if params.sequence.mode != SequenceMode::Off {
        let run = |p: &Arc<Policy>| sequence::ideal_outcome(p, start, params, step);
        let (picked, found) = sequence::choose_sequence(&scene, q, params, &chosen, policy, run);
        if let Some(note) = found.get("note") {
            details["note"] = note.clone();
        }
        details["sequence"] = found;
        if let Some(p) = picked {
            // The candidate reached every intermediate goal in the ideal
            // run; the plan may move past one it stalls short of.
            chosen = Arc::new(Policy::new(scene.clone(), p.phases.clone(), params, true));
        }
    }
    Ok(feedback_plan(chosen, params, details))
}

/// The plan of `policy`: its law for its budget (the horizon per phase,
/// [`sequence::budget`]).
fn feedback_plan(policy: Arc<Policy>, params: &DilfParams, details: serde_json::Value) -> Plan {
    Plan {
        labels: labels(policy.scene.robots),
        segments: Vec::new(),
        duration: sequence::budget(params, &policy),
        law: ControlLaw::Feedback {
            factory: Arc::new(Factory(policy)),
            period: params.period,
        },
        details,
    }
}
