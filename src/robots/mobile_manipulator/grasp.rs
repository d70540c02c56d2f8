//! The carried beam's grasps against their bounds (ours, issue 28): the
//! wrench each gripper applies to the beam against the wrench bound, and
//! the compliant wrists' deflection against their travel, as metrics and
//! as analysis series (plotted together with the bound).
//!
//! Metrics (only where they apply):
//! * `ideal_grasp_wrench_ratio` (bound = "wrench"): the largest of |F|/F_max
//!   and |M|/M_max over both grasps at the ideal run's policy samples, from
//!   the law's own statics (below 1: the ideal run keeps its bound);
//! * `sim_grasp_wrench_ratio` (bound = "wrench"): the same from the physics
//!   beam's grasp wrenches, each averaged over a policy period (what a
//!   force sensor sampled at the law's rate reports; the per-step peaks stay
//!   in `sim_grasp_force_max` / `sim_grasp_torque_max`: the force's is the
//!   solver's correction of the start poses in the first step, the moment's
//!   single steps cross the bound mid-run too, see docs/src/research/seed-004.md);
//! * `sim_wrist_travel_used` (compliant wrists): the largest |deflection| /
//!   travel on any axis of either wrist (1: at the hard stop).

use crate::integrate::Trajectory;
use crate::record::{Series, SimTrajectory};
use crate::robots::mobile_manipulator::dilf::object::{Bound, Carried};

/// Metric names, given which bound and wrists apply.
pub fn metric_names(wrench: bool, compliant: bool) -> Vec<String> {
    let mut out = Vec::new();
    if wrench {
        out.push("ideal_grasp_wrench_ratio".to_string());
        out.push("sim_grasp_wrench_ratio".to_string());
    }
    if compliant {
        out.push("sim_wrist_travel_used".to_string());
    }
    out
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The metrics and series of [`metric_names`]: `samples` are the ideal
/// run's policy samples, `every` the physics steps per policy period.
pub fn analysis(
    carried: &Carried,
    compliant: bool,
    ideal: &Trajectory,
    samples: &[usize],
    sim: &SimTrajectory,
    every: usize,
) -> (Vec<(String, f64)>, Vec<Series>) {
    let mut metrics = Vec::new();
    let mut series = Vec::new();
    let chan = |n: &str| sim.channel(n).unwrap_or(&[]);
    let t = &sim.traj.t;
    if let Bound::Wrench { force, moment } = carried.bound {
        let mut f_ideal = Series::new("grasp_force/ideal".into());
        let mut m_ideal = Series::new("grasp_torque/ideal".into());
        let mut ratio = 0.0f64;
        for &k in samples {
            let st = carried.state(ideal.q[k].as_slice());
            if let Some(w) = carried.wrenches(&st.q_f, &st.gravity) {
                let f = norm(&w[0][..3]).max(norm(&w[1][..3]));
                let m = norm(&w[0][3..]).max(norm(&w[1][3..]));
                f_ideal.push(ideal.t[k], f);
                m_ideal.push(ideal.t[k], m);
                ratio = ratio.max(f / force).max(m / moment);
            }
        }
        // The physics: each channel's mean over every policy period.
        let mut f_sim = Series::new("grasp_force/sim".into());
        let mut m_sim = Series::new("grasp_torque/sim".into());
        let (f1, f2) = (chan("grasp1_force"), chan("grasp2_force"));
        let (m1, m2) = (chan("grasp1_torque"), chan("grasp2_torque"));
        let n = [f1.len(), f2.len(), m1.len(), m2.len(), t.len()]
            .into_iter()
            .min()
            .unwrap_or(0);
        let mut sim_ratio = if n == 0 { f64::NAN } else { 0.0f64 };
        let mean = |v: &[f64], a: usize, b: usize| v[a..b].iter().sum::<f64>() / (b - a) as f64;
        let every = every.max(1);
        for a in (0..n).step_by(every) {
            let b = (a + every).min(n);
            let f = mean(f1, a, b).max(mean(f2, a, b));
            let m = mean(m1, a, b).max(mean(m2, a, b));
            f_sim.push(t[a], f);
            m_sim.push(t[a], m);
            sim_ratio = sim_ratio.max(f / force).max(m / moment);
        }
        let bound = |name: &str, v: f64, tr: &[f64]| {
            let mut s = Series::new(name.into());
            if let (Some(a), Some(b)) = (tr.first(), tr.last()) {
                s.push(*a, v);
                s.push(*b, v);
            }
            s
        };
        let span: Vec<f64> = [ideal.t.first(), ideal.t.last(), t.first(), t.last()]
            .into_iter()
            .flatten()
            .copied()
            .collect();
        let (lo, hi) = span
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| {
                (l.min(*x), h.max(*x))
            });
        let range = if lo <= hi { vec![lo, hi] } else { Vec::new() };
        metrics.push(("ideal_grasp_wrench_ratio".to_string(), ratio));
        metrics.push(("sim_grasp_wrench_ratio".to_string(), sim_ratio));
        series.extend([
            f_ideal,
            f_sim,
            bound("grasp_force/bound", force, &range),
            m_ideal,
            m_sim,
            bound("grasp_torque/bound", moment, &range),
        ]);
    }
    if compliant {
        let mut used = 0.0f64;
        for r in 1..=2 {
            let d = chan(&format!("wrist{r}_deflection"));
            let u = chan(&format!("wrist{r}_travel_used"));
            used = u.iter().fold(used, |m, x| m.max(*x));
            let mut s = Series::new(format!("wrist_deflection/sim_{r}"));
            for (tk, v) in t.iter().zip(d).step_by(every.max(1)) {
                s.push(*tk, *v);
            }
            series.push(s);
            let mut s = Series::new(format!("wrist_travel_used/sim_{r}"));
            for (tk, v) in t.iter().zip(u).step_by(every.max(1)) {
                s.push(*tk, *v);
            }
            series.push(s);
        }
        if let (Some(a), Some(b)) = (t.first(), t.last()) {
            let mut s = Series::new("wrist_travel_used/travel".into());
            s.push(*a, 1.0);
            s.push(*b, 1.0);
            series.push(s);
        }
        metrics.push(("sim_wrist_travel_used".to_string(), used));
    }
    (metrics, series)
}

/// The report's paper table for Table I (`dilf_paper`): the grasps'
/// relative pose changes between the printed start and goal, which no
/// solid object allows (test `table_i_cannot_carry_a_rigid_object`).
pub(crate) fn table_i_rows(start: &[f64], goal: &[f64]) -> Vec<crate::paper::PaperRow> {
    use crate::robots::mobile_manipulator::dilf::object::{
        relative_grasp_change, table_i_goal, table_i_start,
    };
    let near = |a: &[f64], b: &[f64]| {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-6)
    };
    if !(near(start, &table_i_start()) && near(goal, &table_i_goal())) {
        return Vec::new();
    }
    let (dt, dr) = relative_grasp_change(start, goal);
    vec![
        crate::paper::row(
            "Table I: change of the grasps' relative translation, start to goal (a solid object needs 0)",
            "0",
            dt,
            "m",
            "Table I cannot be carried by a solid object: the platforms' spacing (3 m to 4 m) and the shoulders' turn move the grasps |(4 sin 60° − 3, 4 cos 60°)| = 2.053 m relative to each other, for any arm on a vertical first joint",
        ),
        crate::paper::row(
            "Table I: change of the grasps' relative rotation, start to goal (a solid object needs 0)",
            "0",
            dr.to_degrees(),
            "deg",
            "robot 2's q5 (−45° to −30°)",
        ),
    ]
}
