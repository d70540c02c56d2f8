//! One run of a scenario under a perturbation: the plan and the ideal run
//! are the scenario's own (made once, never perturbed), the physics is built
//! with the perturbed world settings and replayed under the perturbed
//! command path and observation, and the run stops as soon as a gate is
//! certain to break ([`crate::margin::early`]).

use crate::compare::{compare, metric_spec};
use crate::engine::perturb::{self, Perturbation};
use crate::engine::{replay, ReplayOptions};
use crate::gate::Breach;
use crate::integrate::{simulate, step_count, Trajectory};
use crate::margin::early::{certain, family, prefix, Stopped};
use crate::metric::Family;
use crate::record::SimTrajectory;
use crate::validate::Prepared;
use serde::Serialize;
use std::collections::BTreeMap;

/// One gate of the scenario and how it can be judged early.
#[derive(Debug, Clone)]
pub struct Gate {
    /// Metric.
    pub metric: String,
    /// Its bound.
    pub bound: f64,
    /// A minimum (else a maximum).
    pub minimum: bool,
    /// How the metric evolves along a run.
    pub family: Family,
}

/// What every level of a scenario shares.
pub struct Ctx<'a> {
    /// The scenario, planned.
    pub prep: &'a Prepared,
    /// The ideal run (never perturbed).
    pub ideal: Trajectory,
    /// Its gates.
    pub gates: Vec<Gate>,
}

impl<'a> Ctx<'a> {
    /// Integrates the ideal run once.
    pub fn new(prep: &'a Prepared) -> Ctx<'a> {
        let sc = &prep.scenario;
        let (start, _) = prep.start_goal();
        let ideal = simulate(prep.model(), &prep.planned, &start, sc.sim.dt);
        let gate = |(m, b): (&String, &f64), minimum| Gate {
            metric: m.clone(),
            bound: *b,
            minimum,
            family: family(m, minimum),
        };
        let gates = sc
            .thresholds
            .iter()
            .map(|g| gate(g, false))
            .chain(sc.minimums.iter().map(|g| gate(g, true)))
            .collect();
        Ctx { prep, ideal, gates }
    }

    /// The ideal run's samples up to time `t`.
    pub fn ideal_until(&self, t: f64) -> Trajectory {
        let n = self.ideal.t.partition_point(|&s| s <= t + 1e-9).max(1);
        Trajectory {
            t: self.ideal.t[..n].to_vec(),
            q: self.ideal.q[..n].to_vec(),
            u: self.ideal.u[..n].to_vec(),
            label: self.ideal.label[..n].to_vec(),
        }
    }

    /// Every metric of a run against `ideal`, as the runner computes them.
    pub fn metrics(&self, ideal: &Trajectory, sim: &SimTrajectory) -> Vec<(String, f64)> {
        let prep = self.prep;
        let model = prep.model();
        let (_, goal) = prep.start_goal();
        let spec = metric_spec(model);
        let dt = prep.scenario.sim.dt;
        let cmp = compare(ideal, &sim.traj, dt, spec.angular, &spec.positions);
        let mut metrics = spec.compute(&goal, ideal.last(), sim.traj.last(), &cmp);
        metrics.extend(prep.system.analysis(&goal, ideal, sim, &cmp).0);
        metrics
    }

    /// The gated metrics' values in `metrics`.
    pub fn gate_values(&self, metrics: &[(String, f64)]) -> BTreeMap<String, f64> {
        self.gates
            .iter()
            .map(|g| {
                let v = metrics
                    .iter()
                    .find(|(n, _)| *n == g.metric)
                    .map(|(_, v)| *v)
                    .unwrap_or(f64::NAN);
                (g.metric.clone(), v)
            })
            .collect()
    }
}

/// Checks a running replay at its checkpoints.
pub struct Monitor<'a> {
    ctx: &'a Ctx<'a>,
    /// Sample counts at which to check, ascending.
    checkpoints: Vec<usize>,
    next: usize,
    /// Set when the run should stop.
    pub stopped: Option<Stopped>,
}

/// A margin level's replay stops when its verdict is known.
impl crate::engine::ReplayObserver for Monitor<'_> {
    fn after_step(&mut self, so_far: &SimTrajectory) -> bool {
        self.check(so_far)
    }
}

impl<'a> Monitor<'a> {
    /// A monitor for a run of at most `n_max` steps of `dt` (no checkpoints
    /// when no gate of the scenario can be judged early).
    pub fn new(ctx: &'a Ctx<'a>, n_max: usize, dt: f64) -> Monitor<'a> {
        let mut times = Vec::new();
        if ctx.gates.iter().any(|g| g.family != Family::EndOnly) {
            let end = n_max as f64 * dt;
            let mut t = 0.5;
            while t < end {
                times.push(t);
                t *= 2.0;
            }
            for g in ctx
                .gates
                .iter()
                .filter(|g| g.family == Family::FirstPassage)
            {
                times.push(g.bound + dt);
            }
        }
        let mut checkpoints: Vec<usize> = times
            .into_iter()
            .map(|t| (t / dt).ceil() as usize + 1)
            .filter(|&k| k <= n_max)
            .collect();
        checkpoints.sort_unstable();
        checkpoints.dedup();
        Monitor {
            ctx,
            checkpoints,
            next: 0,
            stopped: None,
        }
    }

    /// Called after every step: true when the run should stop.
    pub fn check(&mut self, sim: &SimTrajectory) -> bool {
        let k = sim.traj.t.len();
        if self.checkpoints.get(self.next).is_none_or(|&c| k < c) {
            return false;
        }
        while self.checkpoints.get(self.next).is_some_and(|&c| c <= k) {
            self.next += 1;
        }
        let pre = prefix(sim);
        let t = pre.traj.t.last().copied().unwrap_or(0.0);
        let ideal = self.ctx.ideal_until(t);
        let metrics = self.ctx.metrics(&ideal, &pre);
        let value = |m: &str| {
            metrics
                .iter()
                .find(|(n, _)| n == m)
                .map(|(_, v)| *v)
                .unwrap_or(f64::NAN)
        };
        let certain: Vec<Breach> = self
            .ctx
            .gates
            .iter()
            .filter(|g| certain(g.family, value(&g.metric), g.bound, t))
            .map(|g| Breach {
                metric: g.metric.clone(),
                value: value(&g.metric),
                bound: g.bound,
                minimum: g.minimum,
            })
            .collect();
        if certain.is_empty() {
            return false;
        }
        self.stopped = Some(Stopped {
            t,
            metrics,
            certain,
        });
        true
    }
}

/// One run of a level.
#[derive(Debug, Clone, Serialize)]
pub struct Run {
    /// Noise seed (random dimensions only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Every gate held.
    pub passed: bool,
    /// The gates broken (when stopped early: those certain to break).
    pub broken: Vec<Breach>,
    /// The gated metrics (over the prefix when stopped early; NaN as null).
    pub gates: BTreeMap<String, f64>,
    /// Simulated time at which the run stopped because a gate was certain to break.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped_at_s: Option<f64>,
    /// Physics steps taken.
    pub steps: usize,
    /// Why the run could not finish (physics diverged): counts as broken.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// CPU time of the run, s (NaN where the platform does not tell); a
    /// clock value, kept out of the serialized result.
    #[serde(skip)]
    pub cpu_s: f64,
}

/// CPU time of the calling thread so far, s ([`crate::runner::thread_cpu_s`];
/// NaN where it is not measured). A run executes on one thread, so the
/// difference across it is the run's own CPU time, whatever else the machine runs.
pub fn thread_cpu_s() -> f64 {
    crate::runner::thread_cpu_s().unwrap_or(f64::NAN)
}

/// Run the scenario of `ctx` under `p`.
pub fn run(ctx: &Ctx<'_>, p: &Perturbation, seed: Option<u64>) -> Run {
    let c0 = thread_cpu_s();
    let mut r = run_inner(ctx, p, seed);
    r.cpu_s = thread_cpu_s() - c0;
    r
}

fn run_inner(ctx: &Ctx<'_>, p: &Perturbation, seed: Option<u64>) -> Run {
    let prep = ctx.prep;
    let sc = &prep.scenario;
    let mut sim_cfg = sc.sim.clone();
    sim_cfg.perturb = *p;
    let failed = |error: String| Run {
        seed,
        passed: false,
        broken: Vec::new(),
        gates: BTreeMap::new(),
        stopped_at_s: None,
        steps: 0,
        error: Some(error),
        cpu_s: 0.0,
    };
    let mut sys = match prep.physics_with(&sim_cfg.physics()) {
        Ok(s) => s,
        Err(e) => return failed(e.to_string()),
    };
    let dt = sc.sim.dt;
    let opts = ReplayOptions {
        dt,
        settle: sc.sim.settle,
        link_pose_every: None,
        perturbation: *p,
    };
    let n_max = step_count(prep.planned.duration + sc.sim.settle, dt)
        + perturb::reality::extra_steps(p, dt);
    let mut monitor = Monitor::new(ctx, n_max, dt);
    let sim = replay(sys.as_mut(), &prep.planned, &opts, &mut monitor);
    let sim = match sim {
        Ok(s) => s,
        Err(e) => return failed(e.to_string()),
    };
    if let Some(stop) = monitor.stopped {
        return Run {
            seed,
            passed: false,
            gates: ctx.gate_values(&stop.metrics),
            broken: stop.certain,
            stopped_at_s: Some(stop.t),
            steps: sim.steps,
            error: None,
            cpu_s: 0.0,
        };
    }
    let metrics = ctx.metrics(&ctx.ideal, &sim);
    let broken = crate::gate::breaches(&sc.thresholds, &sc.minimums, &metrics);
    Run {
        seed,
        passed: broken.is_empty(),
        gates: ctx.gate_values(&metrics),
        broken,
        stopped_at_s: None,
        steps: sim.steps,
        error: None,
        cpu_s: 0.0,
    }
}
