//! Seed 004 benchmarks: the feedback policy (V, ∂V/∂q by dual numbers, and
//! Eq. 18) for the door scenario, V and ∂V/∂q of the two robots with the
//! beam, the pair's physics step (two robots carrying the beam) and the
//! door scenario's full run.
//!
//! `cargo bench --bench dilf`; the pair's step alone: `cargo bench --bench
//! dilf -- dilf_pair_physics`. Medians are quoted in the README and in
//! docs/src/performance.md.

use anholonomy::engine::{replay, ReplayOptions};
use anholonomy::integrate::simulate;
use anholonomy::runner::{run, RunOptions};
mod common;
use anholonomy::scenario::{ModelConfig, PlannerConfig};
use common::{bench_driven_steps, prepared, STEPS};
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};

/// The policy (V, ∂V/∂q, Eq. 18 and the hold guard) on the states of the
/// scenario's ideal run: the single robot at the door, and the pair with the
/// beam at the door and the table (7 obstacles, 18 DOF).
fn policy(c: &mut Criterion) {
    policy_of(c, "dilf_single_door", "dilf_door_policy");
    policy_of(c, "dilf_paper", "dilf_paper_policy");
}

fn policy_of(c: &mut Criterion, scenario: &str, group: &str) {
    let prep = prepared(scenario);
    let (start, _) = prep.start_goal();
    let plan = prep.plan().expect("plan");
    // States the policy meets along the ideal run (every 20 ms).
    let ideal = simulate(prep.model(), &plan, &start, prep.scenario.sim.dt);
    let states: Vec<_> = ideal.q.iter().step_by(10).cloned().collect();
    let mut g = c.benchmark_group(group);
    // A fresh controller: every part–obstacle solve starts cold.
    g.bench_function("cold_at_start", |b| {
        b.iter_batched(
            || plan.controller(),
            |mut ctl| ctl.command(0.0, &start),
            BatchSize::SmallInput,
        )
    });
    // One controller along the run: solves start from the previous minimiser.
    let mut ctl = plan.controller();
    let mut k = 0;
    g.bench_function("warm_along_ideal_run", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            ctl.command(0.0, &states[k])
        })
    });
    g.finish();
}

/// V and ∂V/∂q of the 18-DOF pair carrying the beam (issue 11's budget:
/// ≤ 200 µs), at Table I's start and at nearby states, warm.
fn pair_field(c: &mut Criterion) {
    use anholonomy::robots::mobile_manipulator::beam::{Beam, GFRP_ROD_10MM};
    use anholonomy::robots::mobile_manipulator::dilf::object::Carried;
    use anholonomy::robots::mobile_manipulator::dilf::potential::{PotentialParams, Scene};
    use anholonomy::robots::mobile_manipulator::kinematics::default_parts;
    let q0 = anholonomy::robots::mobile_manipulator::dilf::object::table_i_start();
    let mut goal = q0.clone();
    goal[1] -= 2.0;
    goal[10] -= 2.0;
    let (material, section) = GFRP_ROD_10MM;
    let beam = Beam {
        material,
        section,
        length: 1.0,
    };
    let carried = Carried::at_rest(&beam, None, &q0, 4.0, 8, 0.02).expect("beam");
    let scene = Scene::new(
        2,
        default_parts(),
        Vec::new(),
        goal,
        PotentialParams {
            lambda: 1.0,
            kv: 3.0,
            goal_frame: Default::default(),
            dipole: Default::default(),
            singularity: Default::default(),
            field_power: 1.75,
        },
    )
    .expect("scene")
    .with_object(carried);
    // States 1 cm / 0.6° apart, as consecutive policy samples are.
    let states: Vec<Vec<f64>> = (0..50)
        .map(|i| {
            q0.iter()
                .enumerate()
                .map(|(j, x)| x + 0.01 * i as f64 * ((j as f64 * 0.7).sin()))
                .collect()
        })
        .collect();
    let mut warm = scene.warm();
    let mut k = 0;
    let mut g = c.benchmark_group("dilf_pair_field");
    g.bench_function("v_and_gradient_18dof_with_beam", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            scene.field(&states[k], &mut warm).expect("field")
        })
    });
    // dilf_paper: the door's six wall segments and the table (7 obstacles,
    // 126 part–obstacle pairs, 14 beam-segment ones), on its ideal run's
    // states every 0.2 s, one warm cache as the controller keeps it.
    let prep = prepared("dilf_paper");
    let (start, goal) = prep.start_goal();
    let (ModelConfig::MobileManipulator(cfg), PlannerConfig::Dilf(params)) =
        (&prep.scenario.model, &prep.scenario.planner)
    else {
        panic!("dilf_paper is a mobile-manipulator scenario");
    };
    let scene =
        anholonomy::robots::mobile_manipulator::task_scene(cfg, params, start.as_slice(), &goal)
            .expect("scene");
    let plan = prep.plan().expect("plan");
    let ideal = simulate(prep.model(), &plan, &start, prep.scenario.sim.dt);
    let states: Vec<Vec<f64>> = ideal
        .q
        .iter()
        .step_by(100)
        .map(|q| q.as_slice().to_vec())
        .collect();
    let (mut warm, mut k) = (scene.warm(), 0);
    g.bench_function("v_and_gradient_dilf_paper", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            scene.field(&states[k], &mut warm).expect("field")
        })
    });
    let (mut warm, mut k) = (scene.warm(), 0);
    g.bench_function("v_and_gradient_dilf_paper_dual_numbers", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            scene.field_dual(&states[k], &mut warm).expect("field")
        })
    });
    g.finish();
}

fn full_run(c: &mut Criterion) {
    let prep = prepared("dilf_single_door");
    let logs = tempfile::tempdir().expect("tempdir");
    let opts = RunOptions {
        log_root: Some(logs.path().to_path_buf()),
        progress: Default::default(),
        pose_rate: anholonomy::runner::DEFAULT_POSE_RATE,
        cancel: Default::default(),
        keep: anholonomy::log::Keep::All,
        batch: true,
    };
    let mut g = c.benchmark_group("dilf_single_door_full_run");
    g.sample_size(10);
    g.bench_function("ideal_physics_logs", |b| {
        b.iter(|| run(&prep, &opts).expect("run"))
    });
    g.finish();
}

/// The pair carrying the beam (`dilf_pair_open`'s world: two robots, the
/// rod through compliant wrists, dt = 4 ms, the solver substeps and sweeps
/// its file sets): 1000 physics steps driving both platforms forward at
/// 0.1 m/s with the arms held (after 250 steps, 1 s, of settling), and the
/// physics replay of the scenario's plan (its feedback law on the simulated
/// state every 20 ms, 3245 steps: the `steps/s` of `anholonomy run`).
fn pair_physics(c: &mut Criterion) {
    let prep = prepared("dilf_pair_open");
    let mut g = c.benchmark_group("dilf_pair_physics");
    g.sample_size(10);
    g.throughput(Throughput::Elements(STEPS));
    let mut u = vec![0.0; 16];
    u[0] = 0.1;
    u[8] = 0.1;
    bench_driven_steps(&mut g, "1000_steps_driving", &prep, &u, 250);
    let plan = prep.plan().expect("plan");
    let dt = prep.scenario.sim.dt;
    let opts = ReplayOptions {
        link_pose_every: None,
        ..ReplayOptions::new(dt, prep.scenario.sim.settle)
    };
    let steps = replay(
        &mut *prep.physics().expect("physics"),
        &plan,
        &opts,
        &mut (),
    )
    .expect("replay")
    .steps;
    g.throughput(Throughput::Elements(steps as u64));
    g.bench_function("replay_with_law", |b| {
        b.iter_batched(
            || prep.physics().expect("physics"),
            |mut sys| {
                replay(&mut *sys, &plan, &opts, &mut ())
                    .expect("replay")
                    .steps
            },
            BatchSize::LargeInput,
        )
    });
    g.finish();
}

criterion_group!(benches, policy, pair_field, pair_physics, full_run);
criterion_main!(benches);
