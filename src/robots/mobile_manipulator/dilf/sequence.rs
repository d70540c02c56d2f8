//! Sequencing (ours, off by default): the law of Eq. 18 run through
//! intermediate goals, each a rigid motion of the task's goal.
//!
//! Eq. 18 asks every platform to arrive along its own goal axis (the dipole
//! of Eq. 15). Two platforms holding one object form a rigid body that can
//! drive along its heading and turn, like one wide unicycle; a goal that
//! needs the formation to turn and translate at once, or to move sideways,
//! asks the two platforms for headings the object forbids, and the law
//! stalls (`docs/src/research/seed-004.md`). One robot behind a wall stalls
//! where V has a spurious maximum (`seed-004-stall.md`), which depends on
//! the dipole's axis.
//!
//! With `[planner.sequence] mode = "auto"` (the default) the planner tries
//! approach headings ψ, from the direction of travel τ (start centroid to
//! goal centroid) outwards in steps of `step_deg` to both sides, and keeps
//! the first whose phases all converge in the ideal run (exact holds):
//!
//! 1. (two robots) turn the formation in place, about its centroid, to face
//!    ψ, in turns of at most `max_turn_deg`;
//! 2. move it to the goal's centroid facing ψ (one robot: to its goal
//!    position with the dipole along ψ);
//! 3. turn it in place to the goal heading, again in turns of at most
//!    `max_turn_deg` (one robot: the final alignment, turning in place).
//!
//! Each phase is the paper's law on V with that phase's goal, so V̇ ≥ 0
//! holds for the phase's V; at a switch V changes (the task's V is not
//! monotone along a sequenced run). An intermediate goal counts as reached
//! when every platform is within the task's position tolerance and
//! `heading_deg` of its heading (the arm joints converge on the way: every
//! phase's goal has the task goal's joints).
//!
//! Where the law alone goes first: `auto` runs the paper's law first for
//! robots that carry no object (if it converges that is the plan) and the
//! sequences first for a pair carrying one (the law's simultaneous turn
//! and drive strains the object and tilts the platforms more in physics
//! than rigid phases do), the law last; `always` tries the sequences first
//! for every task. If nothing converges the plan is the paper's law, which
//! then stalls and says so, and the plan's details say what each candidate
//! did and when (`note`).
//!
//! **Time.** Each phase gets the task's `horizon`: a plan of n phases (the
//! task's goal included) runs for n × `horizon`, its candidates too, so a
//! sequence is never cut short by a horizon sized for the law alone.
//!
//! The candidates' ideal runs must reach every intermediate goal. The plan
//! itself treats an intermediate goal as a waypoint: where the law stalls
//! short of one (in physics, on Eq. 18's hold branch a few cm out, the
//! sliding surface of the seed-004 note), it moves on to the next phase.

use crate::compare::wrap_angle;
use crate::model::State;
use crate::robots::mobile_manipulator::dilf::potential::Scene;
use crate::robots::mobile_manipulator::dilf::{
    check_configuration, feedback_plan, DilfParams, Policy, Tolerance,
};
use crate::robots::mobile_manipulator::kinematics as mm;
use crate::robots::mobile_manipulator::kinematics::DOF;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::sync::Arc;

/// Whether the planner sequences the law through intermediate goals.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SequenceMode {
    /// The paper's law straight to the goal.
    Off,
    /// The sequence where the law alone does not converge or strains the
    /// object (ours, the default): robots carrying no object get the
    /// paper's law when its ideal run converges, else the first converging
    /// sequence; a pair carrying an object gets the first converging
    /// sequence, the law only if none converges.
    #[default]
    Auto,
    /// The first converging turn–translate–turn sequence for every task,
    /// the law only if none converges (ours).
    Always,
}

/// `[planner.sequence]`: intermediate goals for the law (ours, see the
/// module docs).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct SequenceParams {
    /// `"auto"` (default: the law first without a carried object, the
    /// sequences first with one), `"always"` (the sequences first) or
    /// `"off"` (the paper's law). A plan that is a sequence moves on to the
    /// next phase when the law stalls short of an intermediate goal (the
    /// candidates must reach each one); each phase gets the task's horizon.
    pub mode: SequenceMode,
    /// An intermediate goal is reached when every platform is within the
    /// task's position tolerance and this heading error, degrees.
    #[schemars(extend("exclusiveMinimum" = 0), range(max = 180))]
    pub heading_deg: f64,
    /// Largest turn in place of one phase, degrees; larger turns are split
    /// (default 30: a pair's rod follows smaller turns with less strain).
    #[schemars(extend("exclusiveMinimum" = 0), range(max = 180))]
    pub max_turn_deg: f64,
    /// Approach headings are tried from the direction of travel outwards in
    /// steps of this, degrees (360 / step headings at most).
    #[schemars(extend("exclusiveMinimum" = 0), range(max = 180))]
    pub step_deg: f64,
}

impl Default for SequenceParams {
    fn default() -> Self {
        SequenceParams {
            mode: SequenceMode::Auto,
            heading_deg: 5.0,
            max_turn_deg: 30.0,
            step_deg: 15.0,
        }
    }
}

impl SequenceParams {
    /// Range checks: (parameter, reason) of the first bad one.
    pub fn check(&self) -> Result<(), (&'static str, &'static str)> {
        let deg = |x: f64| x.is_finite() && x > 0.0 && x <= 180.0;
        if !deg(self.heading_deg) {
            return Err(("sequence.heading_deg", "must be in (0, 180] degrees"));
        }
        if !deg(self.max_turn_deg) {
            return Err(("sequence.max_turn_deg", "must be in (0, 180] degrees"));
        }
        if !deg(self.step_deg) {
            return Err(("sequence.step_deg", "must be in (0, 180] degrees"));
        }
        Ok(())
    }

    /// Whether every platform of `q` is within `tolerance.position` and
    /// `heading_deg` of `goal` (an intermediate goal reached).
    pub fn reached(&self, tolerance: &Tolerance, q: &[f64], goal: &[f64]) -> bool {
        (0..q.len() / DOF).all(|r| {
            let i = DOF * r;
            (q[i] - goal[i]).hypot(q[i + 1] - goal[i + 1]) <= tolerance.position
                && wrap_angle(q[i + 2] - goal[i + 2]).abs() <= self.heading_deg.to_radians()
        })
    }
}

/// Centroid of the platforms and their mean heading (circular mean).
pub fn formation(q: &[f64]) -> ([f64; 2], f64) {
    let k = q.len() / DOF;
    let (mut cx, mut cy, mut s, mut c) = (0.0, 0.0, 0.0, 0.0);
    for r in 0..k {
        let i = DOF * r;
        cx += q[i];
        cy += q[i + 1];
        s += q[i + 2].sin();
        c += q[i + 2].cos();
    }
    ([cx / k as f64, cy / k as f64], s.atan2(c))
}

/// `q` moved rigidly in the plane: every platform turned by `angle` about
/// `about` and then shifted by `shift`; the arm joints unchanged (the
/// grasps' relative pose is kept).
pub fn rigid(q: &[f64], about: [f64; 2], angle: f64, shift: [f64; 2]) -> Vec<f64> {
    let (s, c) = angle.sin_cos();
    let mut out = q.to_vec();
    for r in 0..q.len() / DOF {
        let i = DOF * r;
        let (dx, dy) = (q[i] - about[0], q[i + 1] - about[1]);
        out[i] = about[0] + c * dx - s * dy + shift[0];
        out[i + 1] = about[1] + s * dx + c * dy + shift[1];
        out[i + 2] = wrap_angle(q[i + 2] + angle);
    }
    out
}

/// Headings turned through from `from` to `to` in turns of at most
/// `max_turn` (rad): the intermediate ones, then `to`.
fn turns(from: f64, to: f64, max_turn: f64) -> Vec<f64> {
    let delta = wrap_angle(to - from);
    let n = (delta.abs() / max_turn).ceil().max(1.0) as usize;
    (1..=n)
        .map(|j| from + delta * j as f64 / n as f64)
        .collect()
}

/// The goals of the sequence with approach heading `psi` (rad), the task's
/// goal last. Two robots: turns in place at the start centroid to face ψ,
/// the goal formation at its centroid facing ψ, turns in place to the goal;
/// one robot: its goal position facing ψ, then the goal.
pub(crate) fn phase_goals(start: &[f64], goal: &[f64], psi: f64, max_turn: f64) -> Vec<Vec<f64>> {
    let (c_s, h_s) = formation(start);
    let (c_g, h_g) = formation(goal);
    let at_start = [c_s[0] - c_g[0], c_s[1] - c_g[1]];
    let mut out: Vec<Vec<f64>> = Vec::new();
    if goal.len() > DOF {
        for h in turns(h_s, psi, max_turn) {
            out.push(rigid(goal, c_g, wrap_angle(h - h_g), at_start));
        }
    }
    out.push(rigid(goal, c_g, wrap_angle(psi - h_g), [0.0; 2]));
    if goal.len() > DOF {
        for h in turns(psi, h_g, max_turn) {
            out.push(rigid(goal, c_g, wrap_angle(h - h_g), [0.0; 2]));
        }
    }
    out.push(goal.to_vec());
    // Drop a goal equal to the one after it (no motion between them).
    let same = |a: &[f64], b: &[f64]| {
        (0..a.len() / DOF).all(|r| {
            let i = DOF * r;
            (a[i] - b[i]).hypot(a[i + 1] - b[i + 1]) < 1e-6
                && wrap_angle(a[i + 2] - b[i + 2]).abs() < 1e-6
        })
    };
    let mut kept: Vec<Vec<f64>> = Vec::new();
    for g in out.into_iter().rev() {
        if kept.last().is_none_or(|n| !same(&g, n)) {
            kept.push(g);
        }
    }
    kept.reverse();
    kept
}

/// Approach headings to try, best first: the direction of travel τ (start
/// centroid to goal centroid; the goal's heading when they coincide within
/// `position`), then τ ± step, τ ± 2 step, … up to half a turn.
pub(crate) fn candidate_headings(
    start: &[f64],
    goal: &[f64],
    step: f64,
    position: f64,
) -> Vec<f64> {
    let (c_s, _) = formation(start);
    let (c_g, h_g) = formation(goal);
    let (dx, dy) = (c_g[0] - c_s[0], c_g[1] - c_s[1]);
    let tau = if dx.hypot(dy) > position {
        dy.atan2(dx)
    } else {
        h_g
    };
    let n = (PI / step).floor() as i64;
    let mut out = vec![tau];
    for j in 1..=n {
        for sgn in [1.0, -1.0] {
            let h = wrap_angle(tau + sgn * j as f64 * step);
            if out.iter().all(|o| wrap_angle(o - h).abs() > 1e-9) {
                out.push(h);
            }
        }
    }
    out
}

/// How a candidate's ideal run ended.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Outcome {
    /// When it converged on the task's goal, s (`None`: it did not).
    pub converged: Option<f64>,
    /// The plan label it ended with (`converged`, `stalled`, a stop), or
    /// `horizon` when it used its whole budget.
    pub ended: String,
    /// When it ended, s.
    pub at: f64,
    /// The phases it reached (intermediate goals and the task's) of all.
    pub reached: usize,
    pub phases: usize,
    /// The worse platform's distance from the goal of the phase it was in, m.
    pub distance: f64,
}

impl Outcome {
    /// One line: "converged at 41.2 s", "stalled at 30.1 s in phase 2 of
    /// 5, 0.41 m from its goal", "used its 150 s in phase 5 of 5, ...".
    pub fn describe(&self) -> String {
        if let Some(t) = self.converged {
            return format!("converged at {t:.1} s");
        }
        let how = match self.ended.as_str() {
            "horizon" => format!("used its {:.0} s", self.at),
            e => format!("{e} at {:.1} s", self.at),
        };
        format!(
            "{how} in phase {} of {}, {:.2} m from its goal",
            (self.reached + 1).min(self.phases),
            self.phases,
            self.distance
        )
    }
}

/// The ideal run of `policy` from `start` (the harness's ideal run:
/// [`crate::integrate::simulate`] with step `step`, for the policy's
/// budget, [`crate::robots::mobile_manipulator::dilf::feedback_plan`]) and how it ended.
pub(super) fn ideal_outcome(
    policy: &Arc<Policy>,
    start: &State,
    params: &DilfParams,
    step: f64,
) -> Outcome {
    let robots = policy.scene.robots;
    let plan = feedback_plan(policy.clone(), params, serde_json::Value::Null);
    let tr = crate::integrate::simulate(&mm::MobileManipulator { robots }, &plan, start, step);
    let converged_label = 2 * 3usize.pow(robots as u32);
    let last = *tr.label.last().unwrap_or(&0);
    let at = *tr.t.last().unwrap_or(&f64::NAN);
    // The phases passed, as the controller advances through them (a
    // candidate's run does not move past a stalled waypoint).
    let goals: Vec<&[f64]> = policy
        .phases
        .iter()
        .map(|s| s.goal.as_slice())
        .chain([policy.scene.goal.as_slice()])
        .collect();
    let mut reached = 0;
    for q in &tr.q {
        while reached + 1 < goals.len()
            && policy
                .sequence
                .reached(&policy.tolerance, q.as_slice(), goals[reached])
        {
            reached += 1;
        }
    }
    let end = tr.last();
    let goal = goals[reached];
    let distance = (0..robots)
        .map(|r| {
            let i = DOF * r;
            (end[i] - goal[i]).hypot(end[i + 1] - goal[i + 1])
        })
        .fold(0.0, f64::max);
    let converged = (last == converged_label).then_some(at);
    let label = plan.label_name(last).to_string();
    Outcome {
        converged,
        ended: if super::STOPS.contains(&label.as_str()) {
            label
        } else {
            "horizon".into()
        },
        at,
        reached: if converged.is_some() {
            goals.len()
        } else {
            reached
        },
        phases: goals.len(),
        distance,
    }
}

/// `[planner.sequence]` (the module docs): the first converging candidate
/// in the mode's order (`Some`: a sequence; `None`: keep `direct`, the
/// paper's law), with what was tried (for the plan's details: each
/// candidate's outcome, and a `note` when none converged).
pub(super) fn choose_sequence(
    scene: &Arc<Scene>,
    start: &[f64],
    params: &DilfParams,
    direct: &Arc<Policy>,
    policy: impl Fn(Vec<Arc<Scene>>) -> Policy,
    run: impl Fn(&Arc<Policy>) -> Outcome,
) -> (Option<Arc<Policy>>, serde_json::Value) {
    let sq = &params.sequence;
    let law_first = sq.mode == SequenceMode::Auto && scene.object.is_none();
    let deg = |x: f64| (x.to_degrees() * 1e3).round() / 1e3;
    let mut tried: Vec<serde_json::Value> = Vec::new();
    let mut notes: Vec<String> = Vec::new();
    let law = |tried: &mut Vec<serde_json::Value>, notes: &mut Vec<String>| {
        let o = run(direct);
        tried.push(serde_json::json!({"candidate": "direct", "outcome": o.describe()}));
        notes.push(format!("the paper's law {}", o.describe()));
        o.converged
    };
    if law_first {
        if let Some(t) = law(&mut tried, &mut notes) {
            return (
                None,
                serde_json::json!({"chosen": "direct", "tried": 1, "ideal_time": t, "candidates": tried}),
            );
        }
    }
    let headings = candidate_headings(
        start,
        &scene.goal,
        sq.step_deg.to_radians(),
        params.tolerance.position,
    );
    for psi in headings {
        let goals = phase_goals(start, &scene.goal, psi, sq.max_turn_deg.to_radians());
        let phases: Option<Vec<Arc<Scene>>> = goals[..goals.len() - 1]
            .iter()
            .map(|g| {
                let s = scene.with_goal(g.clone()).ok()?;
                // An intermediate goal with a part in an obstacle (V = 0
                // there) cannot be reached.
                check_configuration(&s, g, "goal").ok()?;
                Some(Arc::new(s))
            })
            .collect();
        let Some(phases) = phases else {
            continue;
        };
        let p = Arc::new(policy(phases));
        let o = run(&p);
        tried.push(serde_json::json!({
            "candidate": format!("ψ {:+.0}°", psi.to_degrees()),
            "outcome": o.describe(),
        }));
        notes.push(format!("ψ {:+.0}° {}", psi.to_degrees(), o.describe()));
        if let Some(t) = o.converged {
            let goals: Vec<Vec<f64>> = goals
                .iter()
                .map(|g| {
                    g.chunks(DOF)
                        .flat_map(|r| [r[0], r[1], deg(r[2])])
                        .collect()
                })
                .collect();
            return (
                Some(p.clone()),
                serde_json::json!({
                    "chosen": "sequence",
                    "approach_heading_deg": deg(psi),
                    "goals_x_y_theta_deg": goals,
                    "tried": tried.len(),
                    "ideal_time": t,
                    "budget_s": budget(params, &p),
                    "candidates": tried,
                }),
            );
        }
    }
    let converged = if law_first {
        None
    } else {
        law(&mut tried, &mut notes)
    };
    let found = match converged {
        Some(t) => serde_json::json!({
            "chosen": "direct", "tried": tried.len(), "ideal_time": t, "candidates": tried,
        }),
        None => {
            // Say what each candidate did with its time, the first few in
            // full (the details list all).
            let shown = 4;
            let mut note = format!(
                "sequence: no candidate converged ({} tried, each phase {} s): {}",
                tried.len(),
                params.horizon,
                notes[..notes.len().min(shown)].join("; ")
            );
            if notes.len() > shown {
                note.push_str(&format!(
                    "; {} more in the plan's details",
                    notes.len() - shown
                ));
            }
            serde_json::json!({
                "chosen": "direct", "tried": tried.len(), "converged": false,
                "candidates": tried, "note": note,
            })
        }
    };
    (None, found)
}

/// The run time a policy gets: the task's horizon per phase (its
/// intermediate goals and the task's own).
pub(super) fn budget(params: &DilfParams, policy: &Policy) -> f64 {
    params.horizon * (policy.phases.len() + 1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robots::mobile_manipulator::dilf::object::{grasp_distance, relative_grasp_change};

    fn table_i_start() -> Vec<f64> {
        crate::robots::mobile_manipulator::dilf::object::table_i_start()
    }

    /// Every phase goal is a rigid motion of the goal: the platforms' and
    /// grasps' relative poses are the goal's; the turns in place keep the
    /// centroid, and none turns by more than the limit.
    #[test]
    fn phase_goals_are_rigid_motions_of_the_goal() {
        let start = table_i_start();
        // The start formation turned by 150° about its centroid and moved
        // 3 m sideways: a rigid motion.
        let (c, _) = formation(&start);
        let goal = rigid(&start, c, 150f64.to_radians(), [3.0, 0.5]);
        let psi = 0.4;
        let phases = phase_goals(&start, &goal, psi, 90f64.to_radians());
        assert_eq!(phases.last().unwrap(), &goal);
        let mut prev = start.clone();
        for g in &phases {
            let (pos, rot) = relative_grasp_change(&goal, g);
            assert!(pos < 1e-9 && rot < 1e-6, "{pos} {rot}");
            assert!((grasp_distance(g) - grasp_distance(&goal)).abs() < 1e-9);
            let (_, h0) = formation(&prev);
            let (_, h1) = formation(g);
            assert!(
                wrap_angle(h1 - h0).abs() <= 90f64.to_radians() + 1e-9,
                "{h0} -> {h1}"
            );
            prev = g.clone();
        }
        // Turned in place at the start, moved facing ψ, turned at the goal.
        let (c_g, _) = formation(&goal);
        let facing: Vec<_> = phases
            .iter()
            .filter(|g| wrap_angle(formation(g).1 - psi).abs() < 1e-9)
            .collect();
        assert_eq!(facing.len(), 2);
        let (ca, _) = formation(facing[0]);
        let (cb, _) = formation(facing[1]);
        assert!((ca[0] - c[0]).hypot(ca[1] - c[1]) < 1e-9);
        assert!((cb[0] - c_g[0]).hypot(cb[1] - c_g[1]) < 1e-9);
    }

    /// One robot: its goal position facing ψ, then the goal itself.
    #[test]
    fn one_robot_approaches_facing_psi_then_turns() {
        let start = [-3.0, 1.5, 0.3, 0.0, -1.2, 2.2, 0.0, -0.6, 0.0];
        let goal = [3.0, 0.0, 1.5, 0.0, -1.2, 2.2, 0.0, -0.6, 0.0];
        let phases = phase_goals(&start, &goal, -0.2, 90f64.to_radians());
        assert_eq!(phases.len(), 2);
        assert_eq!(&phases[0][..2], &goal[..2]);
        assert!((phases[0][2] + 0.2).abs() < 1e-12);
        assert_eq!(phases[1], goal.to_vec());
    }

    /// An outcome for the stand-in ideal runs below.
    fn outcome(converges: bool) -> Outcome {
        Outcome {
            converged: converges.then_some(10.0),
            ended: if converges { "converged" } else { "stalled" }.into(),
            at: 10.0,
            reached: 0,
            phases: 1,
            distance: 1.0,
        }
    }

    /// Without a carried object `auto` keeps the paper's law when its ideal
    /// run converges; `always` tries the sequences first and falls back to
    /// the law only when none converges (the run closure stands in for the
    /// ideal run). When nothing converges the details say what each
    /// candidate did (`note`).
    #[test]
    fn always_tries_the_sequence_before_the_paper_law() {
        let goal = vec![2.0, 1.0, 0.5, 0.0, -1.2, 2.2, 0.0, -0.6, 0.0];
        let start = [0.0, 0.0, 0.0, 0.0, -1.2, 2.2, 0.0, -0.6, 0.0];
        let choose = |mode: &str, converges: &dyn Fn(usize) -> bool| {
            let params: DilfParams =
                toml::from_str(&format!("[sequence]\nmode = \"{mode}\"")).unwrap();
            let scene = crate::robots::mobile_manipulator::dilf::open_scene(&params, goal.clone());
            let policy = |phases| Policy::new(scene.clone(), phases, &params, false);
            let direct = Arc::new(policy(Vec::new()));
            let calls = std::cell::RefCell::new(Vec::new());
            let run = |p: &Arc<Policy>| {
                calls.borrow_mut().push(p.phases.len());
                outcome(converges(p.phases.len()))
            };
            let (picked, details) = choose_sequence(&scene, &start, &params, &direct, policy, run);
            (picked.is_some(), details, calls.into_inner())
        };
        let everything = |_: usize| true;
        let (picked, details, calls) = choose("auto", &everything);
        assert_eq!(
            (picked, details["chosen"].clone(), calls),
            (false, "direct".into(), vec![0])
        );
        let (picked, details, calls) = choose("always", &everything);
        assert_eq!(
            (picked, details["chosen"].clone(), calls),
            (true, "sequence".into(), vec![1])
        );
        // No sequence converges: `always` falls back to the law, run last.
        let (picked, details, calls) = choose("always", &|phases| phases == 0);
        assert!(!picked);
        assert_eq!(details["chosen"], "direct");
        assert_eq!(calls.first(), Some(&1));
        assert_eq!(calls.last(), Some(&0));
        assert!(details.get("note").is_none());
        // Nothing converges: the note names each candidate's outcome.
        let (picked, details, calls) = choose("auto", &|_| false);
        assert!(!picked);
        assert_eq!(details["converged"], false);
        assert_eq!(details["candidates"].as_array().unwrap().len(), calls.len());
        let note = details["note"].as_str().unwrap();
        assert!(note.contains("the paper's law stalled at 10.0 s"), "{note}");
        assert!(note.contains("ψ"), "{note}");
    }

    /// With a carried object `auto` tries the sequences first (as `always`)
    /// and the paper's law last.
    #[test]
    fn auto_tries_the_sequence_first_when_the_robots_carry_an_object() {
        let start = table_i_start();
        let (c, _) = formation(&start);
        let goal = rigid(&start, c, 0.5, [1.0, 0.5]);
        let params: DilfParams = toml::from_str("").unwrap();
        let scene = crate::robots::mobile_manipulator::dilf::pair_scene(&params, &start, goal);
        let policy = |phases| Policy::new(scene.clone(), phases, &params, false);
        let direct = Arc::new(policy(Vec::new()));
        let calls = std::cell::RefCell::new(Vec::new());
        let run = |p: &Arc<Policy>| {
            calls.borrow_mut().push(p.phases.len());
            outcome(p.phases.is_empty())
        };
        let (picked, details) = choose_sequence(&scene, &start, &params, &direct, policy, run);
        let calls = calls.into_inner();
        assert!(picked.is_none());
        assert_eq!(details["chosen"], "direct");
        assert!(calls[0] > 0, "{calls:?}");
        assert_eq!(calls.last(), Some(&0));
    }

    /// The candidates start at the direction of travel and cover the
    /// circle once, alternating sides.
    #[test]
    fn candidates_start_at_the_direction_of_travel() {
        let start = [0.0, 0.0, 0.0, 0.0, -1.2, 2.2, 0.0, -0.6, 0.0];
        let goal = [0.0, 2.0, 3.0, 0.0, -1.2, 2.2, 0.0, -0.6, 0.0];
        let c = candidate_headings(&start, &goal, 15f64.to_radians(), 0.02);
        assert!((c[0] - PI / 2.0).abs() < 1e-12);
        assert!((c[1] - (PI / 2.0 + 15f64.to_radians())).abs() < 1e-12);
        assert!((c[2] - (PI / 2.0 - 15f64.to_radians())).abs() < 1e-12);
        assert_eq!(c.len(), 24);
    }
}
