//! Fixed-step RK4 integration of a kinematic model under a plan (the ideal run).

use crate::cancel::Cancel;
use crate::model::{Input, KinematicModel, State};
use crate::plan::{jump_offset, Plan};

/// A sampled run: states, the inputs applied and the label in force, at each time.
#[derive(Debug, Clone, Default)]
pub struct Trajectory {
    /// Sample times, s (uniform, starting at 0).
    pub t: Vec<f64>,
    /// States at `t`.
    pub q: Vec<State>,
    /// Inputs applied from `t[k]` on (the last sample repeats the previous input).
    pub u: Vec<Input>,
    /// Label (segment / primitive index) in force at `t[k]`.
    pub label: Vec<usize>,
}

impl Trajectory {
    /// The final state.
    pub fn last(&self) -> &State {
        self.q
            .last()
            .expect("a trajectory always holds its initial state")
    }
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }
    /// True when no sample was recorded.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }
}

/// One classical RK4 step of q' = f(t, q).
pub(crate) fn rk4_step(
    f: &mut impl FnMut(f64, &State) -> State,
    t: f64,
    q: &State,
    h: f64,
) -> State {
    let k1 = f(t, q);
    let k2 = f(t + 0.5 * h, &(q + &k1 * (0.5 * h)));
    let k3 = f(t + 0.5 * h, &(q + &k2 * (0.5 * h)));
    let k4 = f(t + h, &(q + &k3 * h));
    q + (k1 + k2 * 2.0 + k3 * 2.0 + k4) * (h / 6.0)
}

/// Number of steps of size `dt` that cover `duration` (rounded to the nearest
/// whole step when within 1e-9 of it, so plans built on the dt grid end exactly).
pub fn step_count(duration: f64, dt: f64) -> usize {
    let n = duration / dt;
    if (n - n.round()).abs() < 1e-9 {
        n.round() as usize
    } else {
        n.ceil() as usize
    }
}

/// When a held feedback policy is sampled: sample j is due at j · period,
/// computed by multiplication. (Accumulating `next += period` drifts by
/// round-off over thousands of samples, and a sample that falls 1e-12 s
/// late on the step grid is taken one whole step later: that hold lasts
/// 24 ms instead of 20 ms, and the policy's own prediction of where its
/// hold ends is off by 4 ms of motion.)
#[derive(Debug, Clone)]
pub struct SampleClock {
    period: f64,
    /// Slack for round-off of the step grid, s.
    tol: f64,
    next: u64,
}

impl SampleClock {
    /// A clock sampling every `period` on a grid of step `dt`, first at 0.
    pub fn new(period: f64, dt: f64) -> SampleClock {
        SampleClock {
            period,
            tol: 1e-6 * dt,
            next: 0,
        }
    }

    /// Whether a sample is due at time `t` (then the next one is scheduled
    /// after `t`).
    pub fn due(&mut self, t: f64) -> bool {
        if t + self.tol >= self.next as f64 * self.period {
            self.next = ((t + self.tol) / self.period).floor() as u64 + 1;
            true
        } else {
            false
        }
    }
}

/// Whether `t` is (within round-off of) one of `jumps` (increasing: a plan
/// file held sample by sample has one per sample, so no linear scan).
fn is_jump(jumps: &[f64], t: f64) -> bool {
    let tol = 1e-12 * t.abs().max(1.0);
    let i = jumps.partition_point(|j| *j < t - tol);
    jumps.get(i).is_some_and(|j| (j - t).abs() <= tol)
}

/// The jumps of `jumps` (increasing) in [a − slack, b + slack].
fn jumps_near(jumps: &[f64], a: f64, b: f64) -> &[f64] {
    let slack = 1e-9 * (b - a).abs().max(1e-300) + 1e-12 * b.abs().max(1.0);
    let lo = jumps.partition_point(|j| *j < a - slack);
    let hi = jumps.partition_point(|j| *j <= b + slack);
    &jumps[lo..hi.max(lo)]
}

/// Integrate `model` from `q0` under `plan` with step `dt`.
///
/// Open-loop commands are evaluated at every RK4 stage (continuous u(t));
/// feedback policies are sampled every `hold_period` and held (the physics
/// replay does the same, so both runs see the same control timing).
/// The run stops at the plan's duration or when a policy reports `done`.
///
/// A controller that faults ([`crate::plan::Controller::fault`]) ends the
/// run at the faulting sample; [`simulate_checked`] reports the fault.
/// Built-in planners' controllers never fault.
pub fn simulate(model: &dyn KinematicModel, plan: &Plan, q0: &State, dt: f64) -> Trajectory {
    run_ideal(model, plan, q0, dt, &Cancel::default()).0
}

/// Why [`simulate_until`] stopped a run before its end.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IdealStop {
    /// The controller faulted ([`crate::plan::Controller::fault`]).
    #[error("{0}")]
    Fault(String),
    /// The token was cancelled.
    #[error("{}", crate::cancel::CANCELLED)]
    Cancelled,
    /// The model's equations gave a non-finite state (a declared model's
    /// expression dividing by zero, say): which coordinate, and when.
    #[error("{0}")]
    NonFinite(String),
}

/// [`simulate`], or the fault of a controller that stopped working (an
/// external law's process died, answered garbage or too late).
pub fn simulate_checked(
    model: &dyn KinematicModel,
    plan: &Plan,
    q0: &State,
    dt: f64,
) -> Result<Trajectory, IdealStop> {
    simulate_until(model, plan, q0, dt, &Cancel::default())
}

/// [`simulate_checked`] that also stops when `cancel` is set (checked
/// before every step).
pub fn simulate_until(
    model: &dyn KinematicModel,
    plan: &Plan,
    q0: &State,
    dt: f64,
    cancel: &Cancel,
) -> Result<Trajectory, IdealStop> {
    match run_ideal(model, plan, q0, dt, cancel) {
        (tr, None) => Ok(tr),
        (_, Some(stop)) => Err(stop),
    }
}

/// The ideal run and why it stopped early, if it did (a fault ends it at
/// the faulting sample, without applying its command).
fn run_ideal(
    model: &dyn KinematicModel,
    plan: &Plan,
    q0: &State,
    dt: f64,
    cancel: &Cancel,
) -> (Trajectory, Option<IdealStop>) {
    let mut ctl = plan.controller();
    let n = step_count(plan.duration, dt);
    let hold = plan.hold_period();
    let mut out = Trajectory::default();
    let mut q = q0.clone();
    let mut held = ctl.command(0.0, &q);
    if let Some(fault) = ctl.fault() {
        return (out, Some(IdealStop::Fault(fault)));
    }
    let mut clock = hold.map(|p| SampleClock::new(p, dt));
    // Open-loop u(t) may jump at segment joins: no RK4 step straddles one
    // (it is split there) and each piece reads u strictly on its own side.
    let jumps = plan.jumps();
    for k in 0..n {
        if cancel.is_cancelled() {
            return (out, Some(IdealStop::Cancelled));
        }
        let t = k as f64 * dt;
        if let Some(stop) = non_finite(model, &out, &q, t) {
            return (out, Some(stop));
        }
        let cmd = match &mut clock {
            Some(clock) => {
                if clock.due(t) {
                    held = ctl.command(t, &q);
                    if let Some(fault) = ctl.fault() {
                        return (out, Some(IdealStop::Fault(fault)));
                    }
                }
                held.clone()
            }
            // The command applied from t on: the right limit at a jump.
            None if is_jump(&jumps, t) => ctl.command(t + jump_offset(t), &q),
            None => ctl.command(t, &q),
        };
        out.t.push(t);
        out.q.push(q.clone());
        out.u.push(cmd.u.clone());
        out.label.push(cmd.label);
        if cmd.done {
            return (out, None);
        }
        q = match hold {
            Some(_) => rk4_step(&mut |s, x| model.velocity(s, x, &cmd.u), t, &q, dt),
            None if jumps.is_empty() => rk4_step(
                &mut |s, x| model.velocity(s, x, &ctl.command(s, x).u),
                t,
                &q,
                dt,
            ),
            None => {
                let mut cuts = vec![t];
                // Jumps on the grid itself are the pieces' ends already.
                let inside = |j: f64| !is_jump(&[t, t + dt], j) && j > t && j < t + dt;
                let near = jumps_near(&jumps, t, t + dt);
                cuts.extend(near.iter().copied().filter(|&j| inside(j)));
                cuts.push(t + dt);
                let mut x = q;
                for w in cuts.windows(2) {
                    let (a, b) = (w[0], w[1]);
                    let lo = if is_jump(&jumps, a) {
                        a + jump_offset(a)
                    } else {
                        a
                    };
                    let hi = if is_jump(&jumps, b) {
                        b - jump_offset(b)
                    } else {
                        b
                    };
                    let hi = hi.max(lo);
                    x = rk4_step(
                        &mut |s, y| model.velocity(s, y, &ctl.command(s.clamp(lo, hi), y).u),
                        a,
                        &x,
                        b - a,
                    );
                }
                x
            }
        };
    }
    let t_end = n as f64 * dt;
    if let Some(stop) = non_finite(model, &out, &q, t_end) {
        return (out, Some(stop));
    }
    let last = ctl.command(t_end, &q);
    if let Some(fault) = ctl.fault() {
        return (out, Some(IdealStop::Fault(fault)));
    }
    out.t.push(t_end);
    out.q.push(q);
    out.u.push(last.u);
    out.label.push(last.label);
    (out, None)
}

/// Why the run stops when the step that ended at `t` made `q` non-finite:
/// the state, and the equation that is not finite at the step's start
/// (`out`'s last sample) with that state, input and time; `None` when `q` is
/// finite.
fn non_finite(
    model: &dyn KinematicModel,
    out: &Trajectory,
    q: &State,
    t: f64,
) -> Option<IdealStop> {
    let i = q.iter().position(|v| !v.is_finite())?;
    let names = model.state_names();
    let name = |j: usize| names.get(j).copied().unwrap_or("?");
    let readable = crate::numfmt::readable;
    let mut msg = format!(
        "ideal run: state `{}` became {} at t = {} s",
        name(i),
        q[i],
        readable(t)
    );
    if let (Some(t0), Some(q0), Some(u0)) = (out.t.last(), out.q.last(), out.u.last()) {
        // The equation at fault: the first that is not finite where the
        // step began (else a stage inside the step made it so).
        let f = model.velocity(*t0, q0, u0);
        let j = f.iter().position(|v| !v.is_finite()).unwrap_or(i);
        let what = model
            .equation_source(j)
            .unwrap_or_else(|| format!("the equation of `{}`", name(j)));
        msg += &format!(
            ": {what} gives {} at t = {} s, from {}",
            f.get(j).copied().filter(|v| !v.is_finite()).map_or_else(
                || "a non-finite value within the step".to_string(),
                |v| v.to_string()
            ),
            readable(*t0),
            crate::model::point_text(model, q0.as_slice(), u0.as_slice())
        );
    }
    Some(IdealStop::NonFinite(msg))
}

#[cfg(test)]
mod tests {
    use super::SampleClock;

    /// Every hold spans the same number of steps over a long run (an
    /// accumulated `next += period` let samples slip by a step after a few
    /// thousand holds), and a period shorter than the step samples every step.
    #[test]
    fn the_sample_clock_does_not_drift() {
        for (period, dt) in [(0.02, 0.004), (0.02, 0.002), (0.01, 0.001), (0.05, 0.002)] {
            let per: usize = f64::round(period / dt) as usize;
            let mut clock = SampleClock::new(period, dt);
            let mut last = None;
            for k in 0..2_000_000usize {
                if clock.due(k as f64 * dt) {
                    if let Some(l) = last {
                        assert_eq!(k - l, per, "period {period}, dt {dt}: hold at step {k}");
                    }
                    last = Some(k);
                }
            }
        }
        let mut fast = SampleClock::new(1e-4, 1e-3);
        assert!((0..100).all(|k| fast.due(k as f64 * 1e-3)));
    }
}
