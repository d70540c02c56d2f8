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
///
/// `positions` holds every robot's planar (x, y) indices: the position
/// error is the worst robot's at each instant, and with several robots each
/// robot's series is kept too ([`Comparison::robot_position_error`]).
pub fn compare(
    ideal: &Trajectory,
    sim: &Trajectory,
    dt: f64,
    angular: &[usize],
    positions: &[[usize; 2]],
) -> Comparison {
    let end = ideal
        .t
        .last()
        .copied()
        .unwrap_or(0.0)
        .max(sim.t.last().copied().unwrap_or(0.0));
    let n = crate::integrate::step_count(end, dt);
    let dim = ideal.q[0].len();
    let per_robot = if positions.len() > 1 {
        positions.len()
    } else {
        0
    };
    let mut c = Comparison {
        t: Vec::with_capacity(n + 1),
        coord_error: vec![Vec::with_capacity(n + 1); dim],
        position_error: (!positions.is_empty()).then(|| Vec::with_capacity(n + 1)),
        robot_position_error: vec![Vec::with_capacity(n + 1); per_robot],
    };
    for k in 0..=n {
        let t = (k as f64 * dt).min(end);
        let (a, b) = (sample(ideal, t), sample(sim, t));
        let e = coord_error(&a, &b, angular);
        if let Some(series) = c.position_error.as_mut() {
            let mut worst = 0.0f64;
            for (r, [i, j]) in positions.iter().enumerate() {
                let d = e[*i].hypot(e[*j]);
                worst = worst.max(d);
                if let Some(s) = c.robot_position_error.get_mut(r) {
                    s.push(d);
                }
            }
            series.push(worst);
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
        positions: model.robot_positions(),
    }
}

/// Everything needed to name and compute metrics for one model.
pub struct MetricSpec<'a> {
    /// State coordinate names.
    pub names: &'a [&'static str],
    /// Angular coordinate indices (reported in degrees, `_deg` suffix).
    pub angular: &'a [usize],
    /// Planar position indices, one pair per robot (empty: no position).
    pub positions: Vec<[usize; 2]>,
}

impl MetricSpec<'_> {
    fn coord_name(&self, i: usize) -> (String, f64) {
        if self.angular.contains(&i) {
            (format!("{}_deg", self.names[i]), 180.0 / PI)
        } else {
            (self.names[i].to_string(), 1.0)
        }
    }

    /// The unit of coordinate metric `coord` (as [`MetricSpec::coords`]
    /// names it): degrees for an angle, metres for a planar position, else
    /// none known (a declared model's other states).
    pub fn coord_unit(&self, coord: &str) -> &'static str {
        let planar: Vec<usize> = self.positions.iter().flatten().copied().collect();
        let position =
            coord == "position" || self.robot_position_coords().iter().any(|c| c == coord);
        let index = (0..self.names.len()).find(|&i| self.coord_name(i).0 == coord);
        match index {
            Some(i) if self.angular.contains(&i) => "°",
            Some(i) if planar.contains(&i) => "m",
            _ if position => "m",
            _ => "",
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

    /// Per-robot position coordinates: `position_1`, `position_2`, … when
    /// the model has several robots (robot numbers as in the state names).
    fn robot_position_coords(&self) -> Vec<String> {
        if self.positions.len() > 1 {
            (1..=self.positions.len())
                .map(|r| format!("position_{r}"))
                .collect()
        } else {
            Vec::new()
        }
    }

    /// The coordinates metrics are named after: `position` (planar systems:
    /// the worst robot), `position_1`, `position_2`, … (several robots), then
    /// every state coordinate (angles with `_deg`).
    pub fn coords(&self) -> Vec<String> {
        let mut coords = Vec::new();
        if !self.positions.is_empty() {
            coords.push("position".into());
        }
        coords.extend(self.robot_position_coords());
        coords.extend((0..self.names.len()).map(|i| self.coord_name(i).0));
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
        if let Some(series) = cmp.position_error.as_ref() {
            let dist = |e: &[f64], [i, j]: [usize; 2]| e[i].hypot(e[j]);
            // The worst robot at the goal, for either run.
            let worst = |e: &[f64]| {
                self.positions
                    .iter()
                    .fold(0.0f64, |m, p| m.max(dist(e, *p)))
            };
            push_coord("position", 1.0, worst(&ge_i), worst(&ge_s), series);
            for ((name, p), series) in self
                .robot_position_coords()
                .iter()
                .zip(&self.positions)
                .zip(&cmp.robot_position_error)
            {
                push_coord(name, 1.0, dist(&ge_i, *p), dist(&ge_s, *p), series);
            }
        }
        for i in 0..self.names.len() {
            let (name, scale) = self.coord_name(i);
            push_coord(&name, scale, ge_i[i], ge_s[i], &cmp.coord_error[i]);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn random_run(rng: &mut impl Rng, n: usize, dim: usize, dt: f64) -> Trajectory {
        let mut tr = Trajectory::default();
        for k in 0..n {
            tr.t.push(k as f64 * dt);
            tr.q.push(State::from_fn(dim, |_, _| rng.random_range(-2.0..2.0)));
        }
        tr
    }

    /// Two robots (x1, y1, θ1, x2, y2, θ2): the position metrics are the
    /// worst robot's, each robot keeps its own (`position_1`, `position_2`),
    /// all against distances computed here from the raw states.
    #[test]
    fn position_metrics_see_every_robot() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let names: &[&'static str] = &["x1", "y1", "theta1", "x2", "y2", "theta2"];
        let spec = MetricSpec {
            names,
            angular: &[2, 5],
            positions: vec![[0, 1], [3, 4]],
        };
        let dt = 0.1;
        let mut worse = [0, 0];
        for _ in 0..40 {
            let ideal = random_run(&mut rng, 30, 6, dt);
            let sim = random_run(&mut rng, 20, 6, dt);
            let goal = State::from_fn(6, |_, _| rng.random_range(-2.0..2.0));
            let cmp = compare(&ideal, &sim, dt, spec.angular, &spec.positions);
            let m: std::collections::HashMap<String, f64> = spec
                .compute(&goal, ideal.last(), sim.last(), &cmp)
                .into_iter()
                .collect();
            let mut names = spec.names();
            names.sort();
            let mut got: Vec<String> = m.keys().cloned().collect();
            got.sort();
            assert_eq!(names, got);
            let d = |a: &State, b: &State, r: usize| {
                (a[3 * r] - b[3 * r]).hypot(a[3 * r + 1] - b[3 * r + 1])
            };
            let mut max_r = [0.0f64; 2];
            for (k, &t) in cmp.t.iter().enumerate() {
                let (a, b) = (sample(&ideal, t), sample(&sim, t));
                for (r, m) in max_r.iter_mut().enumerate() {
                    let e = d(&a, &b, r);
                    assert!((cmp.robot_position_error[r][k] - e).abs() < 1e-12);
                    *m = m.max(e);
                }
                assert_eq!(
                    cmp.position_error.as_ref().unwrap()[k],
                    cmp.robot_position_error[0][k].max(cmp.robot_position_error[1][k])
                );
            }
            for run in ["ideal", "sim"] {
                let fin = if run == "ideal" {
                    ideal.last()
                } else {
                    sim.last()
                };
                let g = [d(&goal, fin, 0), d(&goal, fin, 1)];
                assert!((m[&format!("{run}_goal_position_1")] - g[0]).abs() < 1e-12);
                assert!((m[&format!("{run}_goal_position_2")] - g[1]).abs() < 1e-12);
                assert_eq!(m[&format!("{run}_goal_position")], g[0].max(g[1]));
                worse[usize::from(g[1] > g[0])] += 1;
            }
            for (r, max) in max_r.iter().enumerate() {
                let k = format!("tracking_position_{}_max", r + 1);
                assert!((m[&k] - max).abs() < 1e-12);
            }
            assert_eq!(m["tracking_position_max"], max_r[0].max(max_r[1]));
            assert!(m["tracking_position_rms"] >= m["tracking_position_1_rms"]);
            assert!(m["tracking_position_rms"] >= m["tracking_position_2_rms"]);
        }
        // Both robots were the worst one in some runs.
        assert!(worse[0] > 0 && worse[1] > 0, "{worse:?}");
    }

    /// The mobile-manipulator pair through the model trait: robot 2 alone
    /// off its goal shows in `ideal_goal_position` (robot 1 is exact).
    #[test]
    fn the_pairs_goal_position_sees_robot_2() {
        let model = crate::robots::mobile_manipulator::kinematics::MobileManipulator { robots: 2 };
        let spec = metric_spec(&model);
        assert_eq!(spec.positions, [[0, 1], [9, 10]]);
        let goal = State::from_fn(18, |i, _| 0.1 * i as f64);
        let mut end = goal.clone();
        end[9] += 0.6;
        end[10] -= 0.8;
        let mut tr = Trajectory::default();
        tr.t.push(0.0);
        tr.q.push(end.clone());
        let cmp = compare(&tr, &tr, 0.1, spec.angular, &spec.positions);
        let m: std::collections::HashMap<String, f64> =
            spec.compute(&goal, &end, &end, &cmp).into_iter().collect();
        assert!((m["ideal_goal_position"] - 1.0).abs() < 1e-12);
        assert!((m["sim_goal_position_2"] - 1.0).abs() < 1e-12);
        assert_eq!(m["ideal_goal_position_1"], 0.0);
        assert!(spec
            .names()
            .contains(&"tracking_position_2_max".to_string()));
    }

    /// One robot: `position` only, no per-robot names or series.
    #[test]
    fn one_robot_has_no_per_robot_position_metrics() {
        let spec = MetricSpec {
            names: &["x", "y", "theta"],
            angular: &[2],
            positions: vec![[0, 1]],
        };
        assert_eq!(spec.coords(), ["position", "x", "y", "theta_deg"]);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let tr = random_run(&mut rng, 5, 3, 0.1);
        let cmp = compare(&tr, &tr, 0.1, spec.angular, &spec.positions);
        assert!(cmp.robot_position_error.is_empty());
        assert!(cmp.position_error.is_some());
    }
}
