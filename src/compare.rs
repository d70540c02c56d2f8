//! Comparison of the simulated run against the ideal run: resampling on one
//! time grid, per-coordinate and position errors, goal errors, thresholds.

use crate::integrate::Trajectory;
use crate::model::State;
use crate::record::Comparison;
use std::f64::consts::{PI, TAU};

/// Wrap an angle difference to (−π, π].
pub fn wrap_angle(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(TAU) - PI;
    if w == -PI {
        PI
    } else {
        w
    }
}

/// Linear interpolation of `traj` at time `t`, holding the end values outside its span.
pub fn sample(traj: &Trajectory, t: f64) -> State {
    let ts = &traj.t;
    let k = ts.partition_point(|&s| s <= t);
    if k == 0 {
        return traj.q[0].clone();
    }
    if k >= ts.len() {
        return traj.last().clone();
    }
    let (t0, t1) = (ts[k - 1], ts[k]);
    let w = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
    &traj.q[k - 1] * (1.0 - w) + &traj.q[k] * w
}

/// Coordinate error b − a, wrapped for angular coordinates.
pub fn coord_error(a: &State, b: &State, angular: &[usize]) -> Vec<f64> {
    (0..a.len())
        .map(|i| {
            let d = b[i] - a[i];
            if angular.contains(&i) {
                wrap_angle(d)
            } else {
                d
            }
        })
        .collect()
}

/// Compare on a grid of step `dt` covering both runs (each held at its end).
pub fn compare(
    ideal: &Trajectory,
    sim: &Trajectory,
    dt: f64,
    angular: &[usize],
    position: Option<[usize; 2]>,
) -> Comparison {
    let end = ideal
        .t
        .last()
        .copied()
        .unwrap_or(0.0)
        .max(sim.t.last().copied().unwrap_or(0.0));
    let n = crate::integrate::step_count(end, dt);
    let dim = ideal.q[0].len();
    let mut c = Comparison {
        t: Vec::with_capacity(n + 1),
        coord_error: vec![Vec::with_capacity(n + 1); dim],
        position_error: position.map(|_| Vec::with_capacity(n + 1)),
    };
    for k in 0..=n {
        let t = (k as f64 * dt).min(end);
        let (a, b) = (sample(ideal, t), sample(sim, t));
        let e = coord_error(&a, &b, angular);
        if let (Some(series), Some([i, j])) = (c.position_error.as_mut(), position) {
            series.push(e[i].hypot(e[j]));
        }
        for (series, v) in c.coord_error.iter_mut().zip(e) {
            series.push(v);
        }
        c.t.push(t);
    }
    c
}

/// RMS, max |·| and final value of a series.
pub fn stats(series: &[f64]) -> (f64, f64, f64) {
    if series.is_empty() {
        return (0.0, 0.0, 0.0);
    }
    let rms = (series.iter().map(|v| v * v).sum::<f64>() / series.len() as f64).sqrt();
    let max = series.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    (rms, max, series[series.len() - 1].abs())
}

/// The metric names and units of a model.
pub fn metric_spec(model: &dyn crate::model::KinematicModel) -> MetricSpec<'_> {
    MetricSpec {
        names: model.state_names(),
        angular: model.angular_states(),
        position: model.position_states(),
    }
}

/// Everything needed to name and compute metrics for one model.
pub struct MetricSpec<'a> {
    /// State coordinate names.
    pub names: &'a [&'static str],
    /// Angular coordinate indices (reported in degrees, `_deg` suffix).
    pub angular: &'a [usize],
    /// Planar position indices.
    pub position: Option<[usize; 2]>,
}

impl MetricSpec<'_> {
    fn coord_name(&self, i: usize) -> (String, f64) {
        if self.angular.contains(&i) {
            (format!("{}_deg", self.names[i]), 180.0 / PI)
        } else {
            (self.names[i].to_string(), 1.0)
        }
    }

    /// All metric names this model produces (for validating thresholds up front).
    pub fn names(&self) -> Vec<String> {
        let mut out = Vec::new();
        for c in &self.coords() {
            for run in ["ideal_goal", "sim_goal"] {
                out.push(format!("{run}_{c}"));
            }
            for s in ["rms", "max", "final"] {
                out.push(format!("tracking_{c}_{s}"));
            }
        }
        out
    }

    /// The coordinates metrics are named after: `position` (planar systems),
    /// then every state coordinate (angles with `_deg`).
    pub fn coords(&self) -> Vec<String> {
        let mut coords: Vec<String> = (0..self.names.len())
            .map(|i| self.coord_name(i).0)
            .collect();
        if self.position.is_some() {
            coords.insert(0, "position".into());
        }
        coords
    }

    /// Metric values: goal errors of both runs and tracking statistics.
    pub fn compute(
        &self,
        goal: &State,
        ideal_final: &State,
        sim_final: &State,
        cmp: &Comparison,
    ) -> Vec<(String, f64)> {
        let mut out = Vec::new();
        let ge_i = coord_error(goal, ideal_final, self.angular);
        let ge_s = coord_error(goal, sim_final, self.angular);
        let mut push_coord = |name: &str, scale: f64, gi: f64, gs: f64, series: &[f64]| {
            out.push((format!("ideal_goal_{name}"), gi.abs() * scale));
            out.push((format!("sim_goal_{name}"), gs.abs() * scale));
            let (rms, max, fin) = stats(series);
            for (s, v) in [("rms", rms), ("max", max), ("final", fin)] {
                out.push((format!("tracking_{name}_{s}"), v * scale));
            }
        };
        if let (Some([i, j]), Some(series)) = (self.position, cmp.position_error.as_ref()) {
            push_coord(
                "position",
                1.0,
                ge_i[i].hypot(ge_i[j]),
                ge_s[i].hypot(ge_s[j]),
                series,
            );
        }
        for i in 0..self.names.len() {
            let (name, scale) = self.coord_name(i);
            push_coord(&name, scale, ge_i[i], ge_s[i], &cmp.coord_error[i]);
        }
        out
    }
}
