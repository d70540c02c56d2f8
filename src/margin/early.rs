//! Early stop: a margin level's run ends as soon as a gate is **certain** to
//! break, judged on the run so far. Which gates can be judged early depends
//! on how their metric evolves as the run goes on, by family (declared by
//! the metric's row, [`family`]):
//!
//! * **running maximum** (`tracking_*_max`, `*_max`, `max_*`, `*_max_*`,
//!   contact counts `*_contacts`, `*_violations`): the value over a prefix
//!   can only grow, so once it is above its threshold the gate breaks. A
//!   contact gate breaks at the first contact. Tracking errors are compared
//!   only up to the prefix's end (both runs on the same grid), so they are
//!   exactly the first values of the final series.
//! * **running minimum** (a `min` or `clearance` token, e.g.
//!   `sim_min_clearance`): can only fall, so below its minimum it breaks.
//! * **first passage** (`*time_to_goal`): the first time within the goal
//!   tolerance; not reached by time t with t above the threshold means it
//!   breaks (it will be later or never).
//! * everything else is **judged at the end**: final goal errors (after the
//!   plan the state still moves while the drives settle, and a settle is
//!   short: stopping there would save little and could be wrong), RMS
//!   values, fractions of samples.
//!
//! Metrics of the ideal run never change with a perturbation and are never
//! judged early. Checks cost a metric evaluation over the prefix, so they
//! come at geometrically spaced times (0.5 s, 1 s, 2 s, …, at most about
//! twice the cost of the final evaluation) and just after each
//! first-passage threshold.

use crate::gate::Breach;
use crate::metric::Family;
use crate::record::SimTrajectory;

/// The family of gate `metric` (a `[minimums]` gate when `minimum`), from
/// its row ([`crate::metric::Metric::family_of`]); judged at the end when it
/// has none.
pub fn family(metric: &str, minimum: bool) -> Family {
    crate::robots::metric(metric).map_or(Family::EndOnly, |r| r.family_of(metric, minimum))
}

/// Whether a gate of `family` with `bound` certainly breaks, given its
/// value `v` over a prefix ending at `t`.
pub(crate) fn certain(family: Family, v: f64, bound: f64, t: f64) -> bool {
    match family {
        Family::RunningMax => !v.is_nan() && v > bound,
        Family::RunningMin => !v.is_nan() && v < bound,
        Family::FirstPassage => {
            if v.is_nan() {
                t > bound
            } else {
                v > bound
            }
        }
        Family::EndOnly => false,
    }
}

/// Why a run stopped early: when, the metrics over the prefix, and the
/// gates certain to break.
#[derive(Debug, Clone)]
pub struct Stopped {
    /// Simulated time of the check, s.
    pub t: f64,
    /// Metrics over the prefix.
    pub metrics: Vec<(String, f64)>,
    /// The gates that broke for certain.
    pub certain: Vec<Breach>,
}

/// The run so far as a finished trajectory (the last command repeated, as
/// the replay does at the end).
pub fn prefix(sim: &SimTrajectory) -> SimTrajectory {
    let mut pre = SimTrajectory {
        traj: sim.traj.clone(),
        channels: sim.channels.clone(),
        steps: sim.steps,
        ..Default::default()
    };
    if let (Some(u), Some(l)) = (pre.traj.u.last().cloned(), pre.traj.label.last().copied()) {
        pre.traj.u.push(u);
        pre.traj.label.push(l);
    }
    pre
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn certain_by_family() {
        use Family::*;
        assert!(certain(FirstPassage, f64::NAN, 40.0, 40.1));
        assert!(!certain(FirstPassage, f64::NAN, 40.0, 39.9));
        assert!(!certain(FirstPassage, 12.0, 40.0, 50.0));
        assert!(certain(RunningMax, 2.0, 1.0, 0.0) && !certain(RunningMax, 1.0, 1.0, 0.0));
        assert!(certain(RunningMin, 0.5, 1.0, 0.0) && !certain(EndOnly, 9.0, 1.0, 9.0));
    }
}
