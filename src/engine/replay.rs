//! The physics replay: a plan's commands (or its feedback law, on the
//! simulated state) applied to a [`PhysicsSystem`] step by step, under the
//! command and observation perturbations of [`perturb`], recorded at every
//! step. One entry point, [`replay`], with an observer for progress, early
//! stops and cancellation; [`Replay`] is the same loop a step at a time
//! (a batched sweep drives several in lockstep).

use crate::engine::perturb;
use crate::engine::PhysicsSystem;
use crate::integrate::step_count;
use crate::model::{Input, State};
use crate::plan::Plan;
use crate::record::SimTrajectory;

/// How a replay runs: its step and settling, what it records besides
/// states, commands and channels, and what reality adds to it.
#[derive(Debug, Clone, Copy)]
pub struct ReplayOptions {
    /// Physics step, s.
    pub dt: f64,
    /// Zero-input time after the plan (or after a feedback policy's `done`), s.
    pub settle: f64,
    /// Record every link's world pose at samples 0, n, 2n, … and the last
    /// one (`Some(n)`, n ≥ 1), or never (`None`). Only the 3D logs use them:
    /// runs without logs skip the read-back, and the logs need no more than
    /// a display rate.
    pub link_pose_every: Option<usize>,
    /// The command and observation perturbations ([`perturb::reality::Reality`]);
    /// the world ones are in the system already.
    pub perturbation: perturb::Perturbation,
}

impl ReplayOptions {
    /// Step `dt` and `settle` seconds of zero input after the plan; every
    /// link pose recorded, nothing perturbed.
    pub fn new(dt: f64, settle: f64) -> ReplayOptions {
        ReplayOptions {
            dt,
            settle,
            link_pose_every: Some(1),
            perturbation: perturb::Perturbation::default(),
        }
    }
}

/// What a replay tells its caller, and asks it, as it goes. Every method
/// has a no-op default, and `()` observes nothing (as rapier's `()`
/// implements its hooks).
pub trait ReplayObserver {
    /// The fraction of the run done, now and then.
    fn progress(&mut self, _fraction: f64) {}
    /// After every step, with what was recorded so far: `true` ends the run
    /// there (a margin search's early stop). A follower of the replay reads
    /// its new samples here.
    fn after_step(&mut self, _so_far: &SimTrajectory) -> bool {
        false
    }
    /// Asked before every step: `true` stops the run with
    /// [`ReplayError::Cancelled`].
    fn cancelled(&self) -> bool {
        false
    }
}

impl ReplayObserver for () {}

/// Why a replay stopped before its end.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ReplayError {
    /// The simulation produced a non-finite state.
    #[error("{0}")]
    Diverged(String),
    /// The controller faulted ([`crate::plan::Controller::fault`]).
    #[error("{0}")]
    Law(String),
    /// The observer cancelled the run ([`ReplayObserver::cancelled`]).
    #[error("run cancelled")]
    Cancelled,
}

/// Replay `plan` on `sys` for its duration plus `opts.settle` seconds (zero
/// input), or until `settle` seconds after a feedback policy reports `done`
/// (that command is not applied: zero input from its sample on), under the
/// command and observation perturbations of `opts`, told to `observer`.
///
/// Open-loop commands are applied at the step midpoint (so each step
/// advances the joints by the exact integral of u to second order); feedback
/// laws are sampled on the simulated state every hold period. Every state,
/// command and channel is recorded at every step (the metrics use the
/// full-rate data).
pub fn replay(
    sys: &mut dyn PhysicsSystem,
    plan: &Plan,
    opts: &ReplayOptions,
    observer: &mut dyn ReplayObserver,
) -> Result<SimTrajectory, ReplayError> {
    let mut run = Replay::start(sys, plan, opts)?;
    while !run.at_end() {
        if observer.cancelled() {
            return Err(ReplayError::Cancelled);
        }
        let k = run.k;
        if !run.command(sys)? {
            break;
        }
        sys.step();
        run.record_step(sys)?;
        if k % 256 == 0 {
            observer.progress(k as f64 / run.n as f64);
        }
        if observer.after_step(&run.out) {
            break;
        }
    }
    let out = run.finish(sys);
    observer.progress(1.0);
    Ok(out)
}

/// One replay in progress, advanced a step at a time by its caller:
/// [`Replay::command`] applies the next step's input, the caller steps the
/// engine, [`Replay::record_step`] reads the result back. `replay_perturbed`
/// drives one system this way; a batched sweep ([`batch`](crate::engine::batch)) drives several
/// systems that share one engine world in lockstep with the same code, so
/// both paths apply the same commands.
pub struct Replay {
    ctl: Box<dyn crate::plan::Controller>,
    dt: f64,
    n_plan: usize,
    n_settle: usize,
    /// Steps of the plan plus settling.
    n: usize,
    /// A feedback policy that reports `done` ends the run `settle` seconds later.
    stop_at: usize,
    /// Steps taken so far.
    k: usize,
    clock: Option<crate::integrate::SampleClock>,
    held: crate::plan::Command,
    zero: Input,
    reality: perturb::reality::Reality,
    finished: bool,
    pose_every: Option<usize>,
    out: SimTrajectory,
}

impl Replay {
    /// Start replaying `plan` on `sys` under `opts`: asks the controller for
    /// its first command and records the start sample.
    pub fn start(
        sys: &dyn PhysicsSystem,
        plan: &Plan,
        opts: &ReplayOptions,
    ) -> Result<Replay, ReplayError> {
        let dt = opts.dt;
        let p = &opts.perturbation;
        let mut ctl = plan.controller();
        let n_plan = step_count(plan.duration, dt);
        // Delayed commands keep arriving after the last one is sent.
        let n_settle = step_count(opts.settle, dt) + perturb::reality::extra_steps(p, dt);
        let n = n_plan + n_settle;
        let names = sys.channel_names();
        let mut out = SimTrajectory {
            channels: names
                .into_iter()
                .map(|name| (name, Vec::with_capacity(n + 1)))
                .collect(),
            ..Default::default()
        };
        out.traj.t.reserve(n + 1);
        out.traj.q.reserve(n + 1);
        out.traj.u.reserve(n + 1);
        out.traj.label.reserve(n + 1);
        let pose_every = opts.link_pose_every.map(|e| e.max(1));
        if let Some(e) = pose_every {
            out.link_poses.reserve(n / e + 2);
            out.link_pose_index.reserve(n / e + 2);
        }
        let clock = plan
            .hold_period()
            .map(|p| crate::integrate::SampleClock::new(p, dt));
        let q0 = sys.state();
        let held = sample(&mut ctl, sys, 0.0, &q0);
        if let Some(fault) = ctl.fault() {
            return Err(ReplayError::Law(fault));
        }
        let zero = Input::zeros(held.u.len());
        let reality = perturb::reality::Reality::new(p, dt, held.u.len());
        let mut run = Replay {
            ctl,
            dt,
            n_plan,
            n_settle,
            n,
            stop_at: n,
            k: 0,
            clock,
            held,
            zero,
            reality,
            finished: false,
            pose_every,
            out,
        };
        run.record(sys, 0.0, q0);
        Ok(run)
    }

    /// Whether every step of the plan and its settling has been taken.
    pub fn at_end(&self) -> bool {
        self.k >= self.n
    }

    /// Time, state and channels of one sample (the state is the last one read back).
    fn record(&mut self, sys: &dyn PhysicsSystem, t: f64, q: State) {
        let out = &mut self.out;
        let k = out.traj.t.len();
        out.traj.t.push(t);
        out.traj.q.push(q);
        if self.pose_every.is_some_and(|e| k.is_multiple_of(e)) {
            out.link_poses.push(sys.link_poses());
            out.link_pose_index.push(k);
        }
        for (series, v) in out.channels.iter_mut().zip(sys.channels()) {
            series.1.push(v);
        }
    }

    /// The command for the next step, applied to `sys` (open-loop commands at
    /// the step midpoint, feedback laws on the simulated state every hold
    /// period); `Ok(false)` when the run is over (nothing applied).
    pub fn command(&mut self, sys: &mut dyn PhysicsSystem) -> Result<bool, ReplayError> {
        let (k, dt) = (self.k, self.dt);
        if k >= self.n {
            return Ok(false);
        }
        let t = k as f64 * dt;
        let q = self.out.traj.q.last().expect("the start state is recorded");
        let idle = k >= self.n_plan || self.finished;
        if !idle {
            match &mut self.clock {
                Some(clock) => {
                    if clock.due(t) {
                        self.held = if self.reality.observes() {
                            self.ctl
                                .command(t, &self.reality.observe(&self.out.traj.q, k))
                        } else {
                            sample(&mut self.ctl, sys, t, q)
                        };
                        if let Some(fault) = self.ctl.fault() {
                            return Err(ReplayError::Law(fault));
                        }
                    }
                }
                None => self.held = self.ctl.command(t + 0.5 * dt, q),
            }
        }
        if self.held.done && !self.finished {
            self.stop_at = self.stop_at.min(k + self.n_settle);
        }
        if k >= self.stop_at {
            return Ok(false);
        }
        self.finished |= self.held.done;
        // A command that says `done` is not applied: the run settles from
        // its sample on, as the ideal run ends there (every built-in
        // policy's `done` command is zero anyway).
        let idle = idle || self.finished;
        let out = &mut self.out;
        if !idle {
            // The plan was in force for this step (settling applies zero).
            out.plan_steps = k + 1;
        }
        let u = if idle { &self.zero } else { &self.held.u };
        out.traj.u.push(u.clone());
        out.traj.label.push(self.held.label);
        if self.reality.acts() {
            let received = self.reality.actuate(u);
            sys.apply(&received);
            out.received.push(received);
        } else {
            sys.apply(u);
        }
        if let Some(fault) = sys.fault() {
            return Err(ReplayError::Diverged(format!(
                "physics run: {} at t = {} s, from {}",
                fault.what,
                crate::numfmt::readable(t),
                fault.from
            )));
        }
        Ok(true)
    }

    /// After the engine stepped: read the state back and record the sample.
    pub fn record_step(&mut self, sys: &dyn PhysicsSystem) -> Result<(), ReplayError> {
        let t = self.k as f64 * self.dt;
        self.k += 1;
        self.out.steps += 1;
        let q = sys.state();
        if q.iter().any(|v| !v.is_finite()) {
            return Err(ReplayError::Diverged(format!(
                "simulation diverged (non-finite state) at t = {:.3} s",
                t + self.dt
            )));
        }
        self.record(sys, self.k as f64 * self.dt, q);
        Ok(())
    }

    /// The recorded run (once [`Replay::command`] returned false, or when
    /// the caller stops early).
    pub fn finish(mut self, sys: &dyn PhysicsSystem) -> SimTrajectory {
        let out = &mut self.out;
        // The final pose too, so the 3D logs end where the run ends.
        let last_k = out.traj.t.len() - 1;
        if self.pose_every.is_some() && out.link_pose_index.last() != Some(&last_k) {
            out.link_poses.push(sys.link_poses());
            out.link_pose_index.push(last_k);
        }
        let last = out
            .traj
            .u
            .last()
            .cloned()
            .unwrap_or_else(|| self.held.u.clone());
        out.traj.u.push(last);
        if let Some(r) = out.received.last().cloned() {
            out.received.push(r);
        }
        out.traj.label.push(self.held.label);
        self.out
    }
}

/// A feedback law's command at `t` on the state `q` (with the system's
/// measurement, when it has one).
fn sample(
    ctl: &mut Box<dyn crate::plan::Controller>,
    sys: &dyn PhysicsSystem,
    t: f64,
    q: &State,
) -> crate::plan::Command {
    match sys.measurement() {
        Some(m) => ctl.command_measured(t, q, &m),
        None => ctl.command(t, q),
    }
}
