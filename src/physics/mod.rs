//! Physics replay: rigid-body counterparts of the kinematic models in Rapier.
//!
//! A [`PhysicsSystem`] maps model inputs to joint motors and reads the model
//! coordinates back from the simulated bodies. [`replay`] drives it with the
//! same controller the ideal run used, evaluated on the simulated state.

pub mod angles;
pub mod beam;
pub mod disk;
pub mod mobile_manipulator;
pub mod rover;
pub mod space_robot;
pub mod sphere;
pub mod urdf;

use crate::integrate::step_count;
use crate::model::{Input, State};
use crate::plan::Plan;
use crate::record::{Pose, SimTrajectory};

/// A simulated robot that accepts model inputs and reports model coordinates.
pub trait PhysicsSystem {
    /// Current model coordinates (angles unwrapped continuously).
    fn state(&self) -> State;
    /// Set the actuators for the next step.
    fn apply(&mut self, u: &Input);
    /// Advance one physics step and update the read-back.
    fn step(&mut self);
    /// World pose of each URDF link, in URDF order.
    fn link_poses(&self) -> Vec<Pose>;
    /// Names of the extra channels ([`PhysicsSystem::channels`]).
    fn channel_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Extra per-step measurements (slip, momentum, ...).
    fn channels(&self) -> Vec<f64> {
        Vec::new()
    }
}

/// Replay `plan` on `sys` for its duration plus `settle` seconds (zero input),
/// or until `settle` seconds after a feedback policy reports `done`; calling `progress(fraction)` now and then.
///
/// Open-loop commands are applied at the step midpoint (so each step advances
/// the joints by the exact integral of u to second order); feedback laws are
/// sampled on the simulated state every hold period.
pub fn replay(
    sys: &mut dyn PhysicsSystem,
    plan: &Plan,
    dt: f64,
    settle: f64,
    progress: &mut dyn FnMut(f64),
) -> Result<SimTrajectory, String> {
    let mut ctl = plan.controller();
    let n_plan = step_count(plan.duration, dt);
    let n_settle = step_count(settle, dt);
    let n = n_plan + n_settle;
    // A feedback policy that reports `done` ends the run `settle` seconds later.
    let mut stop_at = n;
    let names = sys.channel_names();
    let mut out = SimTrajectory {
        channels: names
            .into_iter()
            .map(|name| (name, Vec::with_capacity(n + 1)))
            .collect(),
        ..Default::default()
    };
    let hold = plan.hold_period();
    let mut next_sample = 0.0;
    let mut q = sys.state();
    let mut held = ctl.command(0.0, &q);
    let mut finished = false;
    let record = |out: &mut SimTrajectory, sys: &dyn PhysicsSystem, t: f64, q: &State| {
        out.traj.t.push(t);
        out.traj.q.push(q.clone());
        out.link_poses.push(sys.link_poses());
        for (series, v) in out.channels.iter_mut().zip(sys.channels()) {
            series.1.push(v);
        }
    };
    for k in 0..n {
        let t = k as f64 * dt;
        let cmd = if k >= n_plan || finished {
            let mut c = held.clone();
            c.u.fill(0.0);
            c
        } else {
            match hold {
                Some(p) => {
                    if t + 1e-12 >= next_sample {
                        held = ctl.command(t, &q);
                        next_sample += p;
                    }
                    held.clone()
                }
                None => {
                    held = ctl.command(t + 0.5 * dt, &q);
                    held.clone()
                }
            }
        };
        if cmd.done && !finished {
            stop_at = stop_at.min(k + n_settle);
        }
        if k >= stop_at {
            break;
        }
        record(&mut out, sys, t, &q);
        finished |= cmd.done;
        out.traj.u.push(cmd.u.clone());
        out.traj.label.push(cmd.label);
        sys.apply(&cmd.u);
        sys.step();
        out.steps += 1;
        q = sys.state();
        if q.iter().any(|v| !v.is_finite()) {
            return Err(format!(
                "simulation diverged (non-finite state) at t = {:.3} s",
                t + dt
            ));
        }
        if k % 256 == 0 {
            progress(k as f64 / n as f64);
        }
    }
    let t_end = out.steps as f64 * dt;
    record(&mut out, sys, t_end, &q);
    let last = out.traj.u.last().cloned().unwrap_or_else(|| held.u.clone());
    out.traj.u.push(last);
    out.traj.label.push(held.label);
    progress(1.0);
    Ok(out)
}
