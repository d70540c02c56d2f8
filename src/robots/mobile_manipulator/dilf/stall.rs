//! Progress of the feedback law (ours): the stall stop and the hand-over to
//! the final alignment.
//!
//! Eq. 18 keeps V̇ ≥ 0, and Proposition 2 concludes convergence from it
//! only where V has no critical point but the goal ("v_r vanishes only at
//! the origin", Appendix G). A V with a spurious local maximum (a wall
//! across the dipole's field line: `docs/src/research/seed-004-stall.md`),
//! or a sliding motion on the switching surface of Eq. 18a where V̇ = 0 with
//! v ≠ 0 on either side, leaves the law moving without raising V until the
//! horizon. [`Progress`] watches for that:
//!
//! * **progress** is V rising by the factor `1 + gain` above the best value
//!   seen so far, or, while a platform turns in place to its goal heading,
//!   the largest heading error of the aligning platforms shrinking by the
//!   same factor (that turn converges by itself, V need not rise);
//! * **stall**: no progress for `time` seconds ends the run (label
//!   `stalled`);
//! * **hand-over**: a platform within the position tolerance whose law has
//!   made no progress for `handover_time` seconds starts the final
//!   alignment even if it is not within half the tolerance (where the
//!   alignment normally starts), and a platform that has started aligning
//!   keeps aligning while it stays within the tolerance (in physics its
//!   axle drifts by millimetres while it turns).

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `[planner.stall]`: when the law counts as stalled.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct StallParams {
    /// No progress for this long ends the run with the label `stalled`, s;
    /// 0 disables the stop (the run goes on to the horizon).
    #[schemars(range(min = 0))]
    pub time: f64,
    /// Relative rise of V (and relative fall of the aligning platforms'
    /// heading error) that counts as progress.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub gain: f64,
    /// No progress for this long hands a platform within the position
    /// tolerance over to the final alignment, s.
    #[schemars(range(min = 0))]
    pub handover_time: f64,
}

impl Default for StallParams {
    /// 10 s: 2.5 times the longest in-place turn the limits allow (π at
    /// 0.8 rad/s), and twice the longest stretch without 1 % of progress in
    /// the shipped runs that reach their goal or stop for another reason
    /// (4.7 s, `dilf_paper`'s physics replay). 3 s for the hand-over: near
    /// its goal Eq. 18 may turn a platform for a second or two with V
    /// nearly flat before it closes in, and handing over then only makes
    /// the alignment start farther out.
    fn default() -> Self {
        StallParams {
            time: 10.0,
            gain: 0.01,
            handover_time: 3.0,
        }
    }
}

impl StallParams {
    /// Range checks: (parameter, reason) of the first bad one.
    pub fn check(&self) -> Result<(), (&'static str, &'static str)> {
        if !(self.time.is_finite() && self.time >= 0.0) {
            return Err(("stall.time", "must be ≥ 0 s (0 disables the stall stop)"));
        }
        if !(self.gain.is_finite() && self.gain > 0.0) {
            return Err(("stall.gain", "must be > 0 (a relative rise of V)"));
        }
        if !(self.handover_time.is_finite() && self.handover_time >= 0.0) {
            return Err(("stall.handover_time", "must be ≥ 0 s"));
        }
        Ok(())
    }
}

/// What the law's progress says at one policy sample.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Progress within the last `handover_time` seconds.
    Moving,
    /// No progress for `handover_time` seconds: platforms within the
    /// position tolerance start aligning.
    HandOver,
    /// No progress for `time` seconds: the run ends.
    Stalled,
}

/// The progress tracker of one run (one per controller instance).
#[derive(Debug, Clone)]
pub struct Progress {
    params: StallParams,
    ln_factor: f64,
    /// ln V at the last progress.
    best_ln_v: f64,
    /// Largest heading error of the aligning platforms at the last progress
    /// (∞ while none aligns).
    best_heading: f64,
    /// Time of the last progress, s.
    since: f64,
}

impl Progress {
    /// A tracker for a run starting at t = 0.
    pub fn new(params: StallParams) -> Progress {
        Progress {
            params,
            ln_factor: params.gain.ln_1p(),
            best_ln_v: f64::NEG_INFINITY,
            best_heading: f64::INFINITY,
            since: 0.0,
        }
    }

    /// Record the sample at time `t` with potential `v` (> 0) and the largest
    /// heading error of the platforms turning in place (`None` when none
    /// does), and say what it means.
    pub fn observe(&mut self, t: f64, v: f64, aligning_heading: Option<f64>) -> Verdict {
        let ln_v = v.ln();
        let mut progress = false;
        // Strict: V = 0 (ln V = −∞, on a dipole plane) is never progress.
        if ln_v > self.best_ln_v + self.ln_factor {
            self.best_ln_v = ln_v;
            progress = true;
        }
        match aligning_heading {
            Some(h) if h * (1.0 + self.params.gain) <= self.best_heading => {
                self.best_heading = h;
                progress = true;
            }
            Some(_) => {}
            // Nobody turns in place: a later alignment starts afresh.
            None => self.best_heading = f64::INFINITY,
        }
        if progress {
            self.since = t;
        }
        let idle = t - self.since;
        if self.params.time > 0.0 && idle > self.params.time {
            Verdict::Stalled
        } else if idle > self.params.handover_time {
            Verdict::HandOver
        } else {
            Verdict::Moving
        }
    }

    /// Count the time without progress from `t` on (a new goal: V is
    /// another function).
    pub fn restart(&mut self, t: f64) {
        self.since = t;
    }

    /// Time of the last progress, s.
    pub fn since(&self) -> f64 {
        self.since
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::State;
    use crate::plan::{Command, Controller};
    use crate::robots::mobile_manipulator::dilf::{open_scene, DilfController, DilfParams, Policy};
    use std::sync::Arc;

    /// One robot in the open, goal at the origin facing +x, and its
    /// controller (the shipped defaults but `field_power`).
    fn controller() -> (DilfController, Vec<f64>) {
        controller_through(&[], false)
    }

    /// The same, through intermediate goals `via`, yielding on a stall
    /// short of one or not.
    fn controller_through(via: &[Vec<f64>], yield_on_stall: bool) -> (DilfController, Vec<f64>) {
        let params: DilfParams = toml::from_str("field_power = 1.75").unwrap();
        let goal = vec![0.0, 0.0, 0.0, 0.0, -1.2, 2.2, 0.0, -0.6, 0.0];
        let scene = open_scene(&params, goal.clone());
        let phases = via
            .iter()
            .map(|g| Arc::new(scene.with_goal(g.clone()).unwrap()))
            .collect();
        let policy = Arc::new(Policy::new(scene.clone(), phases, &params, yield_on_stall));
        let c = DilfController {
            warm: scene.warm(),
            guard_warm: scene.warm(),
            combos: 3,
            progress: Progress::new(params.stall),
            aligning: vec![false],
            phase: 0,
            policy,
        };
        (c, goal)
    }

    fn label(c: &mut DilfController, t: f64, q: &[f64]) -> (String, Command) {
        let cmd = c.command(t, &State::from_vec(q.to_vec()));
        (
            crate::robots::mobile_manipulator::dilf::labels(1)[cmd.label].clone(),
            cmd,
        )
    }

    /// The controller's rules on a state where nothing moves between
    /// samples (no progress): 1.5 cm from the goal (inside the 2 cm
    /// tolerance, outside its half) Eq. 18 runs for `handover_time`, then
    /// the platform turns in place; once aligning it keeps aligning up to
    /// the tolerance and not beyond. 0.5 m from the goal the same lack of
    /// progress ends the run after `time`, with zero input.
    #[test]
    fn the_controller_hands_over_latches_and_stops() {
        let (mut c, goal) = controller();
        // Off the dipole plane x = 0 (V = 0 there), `d` from the goal.
        let at = |d: f64| {
            let mut q = goal.clone();
            q[0] = -0.009;
            q[1] = (d * d - 0.009f64.powi(2)).sqrt();
            q[2] = 0.5;
            q
        };
        let q = at(0.015);
        let s = StallParams::default();
        let mut first_align = None;
        for k in 0..250 {
            let t = 0.02 * k as f64;
            let (l, _) = label(&mut c, t, &q);
            if l.starts_with("align") {
                first_align.get_or_insert(t);
            } else {
                assert!(first_align.is_none(), "left the alignment at {t} s: {l}");
            }
        }
        let t = first_align.expect("never handed over");
        assert!(t > s.handover_time && t <= s.handover_time + 0.021, "{t}");
        // Latched: 1.9 cm still aligns, 2.1 cm no longer, nor 1.9 cm again.
        assert!(label(&mut c, 5.0, &at(0.019)).0.starts_with("align"));
        assert!(!label(&mut c, 5.02, &at(0.021)).0.starts_with("align"));
        assert!(!label(&mut c, 5.04, &at(0.019)).0.starts_with("align"));

        let (mut c, goal) = controller();
        let mut q = goal.clone();
        q[0] = -0.5;
        q[2] = 0.3;
        let mut stop = None;
        for k in 0..1000 {
            let t = 0.02 * k as f64;
            let (l, cmd) = label(&mut c, t, &q);
            if l == "stalled" {
                assert!(cmd.done && cmd.u.iter().all(|u| *u == 0.0));
                stop = Some(t);
                break;
            }
        }
        let t = stop.expect("never stalled");
        assert!(t > s.time && t <= s.time + 0.021, "{t}");
    }

    /// A plan through an intermediate goal moves on to the task's goal when
    /// it stalls short of it (the label never says `stalled`, and the next
    /// stall, on the task's goal, ends the run `time` later); a candidate
    /// run (no yielding) ends at the first stall.
    #[test]
    fn a_stall_short_of_an_intermediate_goal_moves_on() {
        let s = StallParams::default();
        let first_stop = |yield_on_stall: bool| {
            let goal = vec![0.0, 0.0, 0.0, 0.0, -1.2, 2.2, 0.0, -0.6, 0.0];
            let mut via = goal.clone();
            via[0] = 1.0;
            via[1] = 1.0;
            let (mut c, _) = controller_through(&[via], yield_on_stall);
            // Frozen 0.5 m from both goals: no progress on either.
            let q = [0.5, 0.3, 0.3, 0.0, -1.2, 2.2, 0.0, -0.6, 0.0];
            (0..2000)
                .map(|k| 0.02 * k as f64)
                .find(|t| label(&mut c, *t, &q).0 == "stalled")
                .map(|t| (t, c.phase))
        };
        let (t, phase) = first_stop(false).expect("the candidate never stalled");
        assert!(t > s.time && t <= s.time + 0.021, "{t}");
        assert_eq!(phase, 0);
        let (t, phase) = first_stop(true).expect("the plan never stalled");
        // The yield at the first stall's sample; the new phase's first
        // sample is progress (its V is a new function); `time` after it.
        assert!(t > 2.0 * s.time && t <= 2.0 * s.time + 0.061, "{t}");
        assert_eq!(phase, 1);
    }

    /// V rising by less than the gain is no progress; by more, it is. The
    /// stop comes `time` after the last progress, the hand-over after
    /// `handover_time`, both strictly after.
    #[test]
    fn stalls_after_the_stated_time_without_progress() {
        let p = StallParams {
            time: 3.0,
            gain: 0.01,
            handover_time: 0.5,
        };
        let mut g = Progress::new(p);
        let dt = 0.02;
        let mut v = 1.0;
        let mut t = 0.0;
        // 2 s of a 2 %/s rise: progress every ~0.5 s.
        while t < 2.0 {
            assert_ne!(g.observe(t, v, None), Verdict::Stalled);
            v *= 1.0 + 0.02 * dt;
            t += dt;
        }
        let last = g.since();
        assert!(last > 1.4, "{last}");
        // Then a creep to 0.9 % above the last progress: never progress again.
        let best = g.best_ln_v.exp();
        let mut verdicts = Vec::new();
        for k in 0..400 {
            let t = 2.0 + k as f64 * dt;
            verdicts.push((
                t,
                g.observe(t, best * (1.0 + 0.009 * k as f64 / 400.0), None),
            ));
        }
        let first = |want| verdicts.iter().find(|(_, x)| *x == want).unwrap().0;
        assert!((first(Verdict::HandOver) - (last + 0.5)).abs() <= dt + 1e-9);
        assert!((first(Verdict::Stalled) - (last + 3.0)).abs() <= dt + 1e-9);
        assert_eq!(g.since(), last);
    }

    /// A platform turning in place counts as progress while its heading
    /// error shrinks, even with V constant; time 0 disables the stop.
    #[test]
    fn turning_in_place_is_progress_and_time_zero_never_stalls() {
        let mut g = Progress::new(StallParams {
            time: 1.0,
            gain: 0.01,
            handover_time: 0.2,
        });
        let mut h = 3.0f64;
        for k in 0..200 {
            let t = k as f64 * 0.02;
            assert_eq!(g.observe(t, 2.0, Some(h)), Verdict::Moving, "t = {t}");
            h *= 0.98;
        }
        let mut off = Progress::new(StallParams {
            time: 0.0,
            ..StallParams::default()
        });
        for k in 0..5000 {
            assert_ne!(off.observe(k as f64 * 0.02, 1.0, None), Verdict::Stalled);
        }
    }
}
