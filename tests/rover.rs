//! Rover (seed 002) end to end: closed loop on Rapier, open-loop replay, envelope, sweep.

mod common;
use anholonomy::integrate::simulate;
use anholonomy::physics::replay;
use anholonomy::runner::Prepared;
use anholonomy::scenario::Scenario;
use common::*;

fn prep(name: &str) -> Prepared {
    Prepared::new(Scenario::load(&root().join("scenarios").join(name)).unwrap()).unwrap()
}

#[test]
#[ignore]
fn debug_trace() {
    let p = prep(&std::env::var("ROVER_SC").unwrap_or("rover_paper.toml".into()));
    let plan = p.plan().unwrap();
    let (start, _goal) = p.start_goal();
    let ideal = simulate(p.model(), &plan, &start, p.scenario.sim.dt);
    let mut sys = p.physics().unwrap();
    let sim = replay(sys.as_mut(), &plan, p.scenario.sim.dt, p.scenario.sim.settle, &mut |_| {}).unwrap();
    let env = &sim.channels.iter().find(|c| c.0 == "envelope_distance").unwrap().1;
    for k in (0..env.len()).step_by(997) {
        let q = &sim.traj.q[k];
        let dt = p.scenario.sim.dt;
        let d = (&sim.traj.q[k + 1] - q) / dt;
        let (s, c) = q[2].sin_cos();
        println!("env t={:.2} P{} d={:.4} u=({:.3},{:.3}) psi={:.2} fwd={:.4} lat={:.4} w={:.4}", sim.traj.t[k], sim.traj.label[k] + 1, env[k], sim.traj.u[k][0], sim.traj.u[k][1], q[3].to_degrees(), c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2]);
    }
    for (name, tr) in [("ideal", &ideal), ("sim", &sim.traj)] {
        let mut last = usize::MAX;
        for k in 0..tr.t.len() {
            if tr.label[k] != last || k % 2500 == 0 || k + 1 == tr.t.len() {
                last = tr.label[k];
                let q = &tr.q[k];
                println!(
                    "{name} t={:.2} P{} q=({:.3},{:.3},{:.1}°,{:.2}°) u=({:.3},{:.3})",
                    tr.t[k], tr.label[k] + 1, q[0], q[1], q[2].to_degrees(), q[3].to_degrees(), tr.u[k][0], tr.u[k][1]
                );
            }
        }
    }
}
