mod common;
use anholonomy::integrate::simulate;
use anholonomy::physics::replay;
use anholonomy::runner::Prepared;
use anholonomy::scenario::Scenario;
use common::*;

#[test]
fn debug_channels() {
    let prep = Prepared::new(Scenario::load(&root().join("scenarios/space_robot_paper.toml")).unwrap()).unwrap();
    let (start, _) = prep.start_goal();
    let plan = prep.plan().unwrap();
    let ideal = simulate(prep.model(), &plan, &start, 1e-3);
    let mut sys = prep.physics().unwrap();
    let sim = replay(sys.as_mut(), &plan, 1e-3, 0.0, &mut |_| {}).unwrap();
    for k in (0..ideal.t.len()).step_by(500) {
        let e: Vec<f64> = (0..3).map(|i| (sim.traj.q[k][i] - ideal.q[k][i]).to_degrees()).collect();
        let ch: Vec<f64> = sim.channels.iter().map(|c| c.1[k]).collect();
        println!("{:.2} {:?} u {:?} e {:.5?} ch {:?}", ideal.t[k], plan.label_name(ideal.label[k]), ideal.u[k].as_slice(), e, ch.iter().map(|v| format!("{v:.2e}")).collect::<Vec<_>>());
    }
}
