//! Obstacles of the wheeled models (`[[model.obstacles]]`, boxes and
//! cylinders): the parking example's clearance gate holds as planned and
//! fails when the whole manoeuvre is moved 20 cm into a neighbour; the
//! clearance metric against distances worked out from the URDF by hand;
//! contacts when driving into a box; the obstacles in the MCAP log.

use anholonomy::runner::RunOutcome;
use foxglove::messages::SceneUpdate;
use foxglove::Decode;
use std::path::Path;

/// The shipped parking scenario, with its files made absolute and start
/// and goal moved by `dx` m along x (the plan file is a sequence of
/// commands, so the whole path moves with the start).
fn parking(dir: &Path, dx: f64) -> std::path::PathBuf {
    let text = std::fs::read_to_string(crate::common::scenario("car_parking.toml")).unwrap();
    let mut t: toml::Table = toml::from_str(&text).unwrap();
    for key in ["start", "goal"] {
        let v = t[key].as_array_mut().unwrap();
        v[0] = (v[0].as_float().unwrap() + dx).into();
    }
    let abs = |p: &str| {
        crate::common::root()
            .join(p.trim_start_matches("../"))
            .display()
            .to_string()
    };
    let model = t["model"].as_table_mut().unwrap();
    let urdf = abs(model["urdf"].as_str().unwrap());
    model.insert("urdf".into(), urdf.into());
    let planner = t["planner"].as_table_mut().unwrap();
    let path = abs(planner["path"].as_str().unwrap());
    planner.insert("path".into(), path.into());
    let file = dir.join(format!("parking_{dx}.toml"));
    std::fs::write(&file, toml::to_string(&t).unwrap()).unwrap();
    file
}

fn metric(o: &RunOutcome, name: &str) -> f64 {
    o.metric(name).unwrap_or_else(|| panic!("no metric {name}"))
}

#[test]
fn parking_clearance_gate_fails_when_the_plan_is_shifted_into_a_neighbour() {
    let dir = tempfile::tempdir().unwrap();
    let as_planned = crate::common::run_file(&parking(dir.path(), 0.0), None);
    assert!(as_planned.passed, "{:?}", as_planned.failures);
    assert!(metric(&as_planned, "sim_min_clearance") >= 0.01);
    assert_eq!(metric(&as_planned, "sim_obstacle_contacts"), 0.0);
    // 20 cm ahead the car backs into the front neighbour's corner; 20 cm
    // behind it reverses into the rear neighbour.
    for dx in [0.2, -0.2] {
        let o = crate::common::run_file(&parking(dir.path(), dx), None);
        assert!(!o.passed, "shifted {dx} m: passed");
        let gate = |name: &str| o.failures.iter().any(|f| f.starts_with(name));
        assert!(
            gate("sim_min_clearance") && gate("sim_obstacle_contacts"),
            "shifted {dx} m: {:?}",
            o.failures
        );
        assert_eq!(metric(&o, "sim_min_clearance"), 0.0);
        // The plan itself still reaches its (shifted) goal on the bicycle.
        assert!(metric(&o, "ideal_goal_position") < 1e-6);
    }
}

/// A differential drive at the origin, heading +x, running `plan` (a
/// `t,v,omega` CSV) among `obstacles` (TOML array-of-tables text).
fn diff_drive(dir: &Path, tag: &str, plan: &str, obstacles: &str) -> RunOutcome {
    let csv = dir.join(format!("{tag}.csv"));
    std::fs::write(&csv, plan).unwrap();
    let urdf = crate::common::model("diff_drive.urdf");
    let text = format!(
        r#"start = [0.0, 0.0, 0.0]
goal = [0.0, 0.0, 0.0]

[model]
kind = "diff_drive"
urdf = "{}"
{obstacles}

[planner]
kind = "file"
path = "{}"

[sim]
dt = 0.001
settle = 0.2
"#,
        urdf.display(),
        csv.display()
    );
    let file = dir.join(format!("{tag}.toml"));
    std::fs::write(&file, text).unwrap();
    crate::common::run_file(&file, None)
}

const STAND: &str = "t,v,omega\n0,0,0\n0.5,0,0\n";

/// Standing still: the clearance is the gap between the URDF's collision
/// shapes and the obstacle, from the geometry of models/diff_drive.urdf
/// (body box 0.30 x 0.22 x 0.08 m centred 0.05 m behind the axle; wheel
/// spheres of 0.05 m at y = +-0.13 m on the axle, 0.05 m above ground).
#[test]
fn diff_drive_clearance_is_the_gap_to_boxes_and_cylinders() {
    let dir = tempfile::tempdir().unwrap();
    // A box whose near face is at x = 0.30: the body's front face is at
    // x = 0.10 (the wheels reach 0.05).
    let wall = r#"
[[model.obstacles]]
name = "wall"
center = [0.4, 0.0, 0.2]
semi_axes = [0.1, 1.0, 0.2]
"#;
    let o = diff_drive(dir.path(), "box", STAND, wall);
    assert!((metric(&o, "sim_min_clearance") - 0.20).abs() < 2e-3);
    // A cylinder of radius 0.1 about (0, 0.4): 0.12 from the left wheel's
    // sphere (0.40 - 0.1 - 0.13 - 0.05), 0.19 from the body's side face.
    let post = r#"
[[model.obstacles]]
name = "post"
shape = "cylinder"
center = [0.0, 0.4, 0.3]
semi_axes = [0.1, 0.1, 0.3]
"#;
    let o = diff_drive(dir.path(), "cylinder", STAND, post);
    assert!((metric(&o, "sim_min_clearance") - 0.12).abs() < 2e-3);
    assert_eq!(metric(&o, "sim_obstacle_contacts"), 0.0);
    // Driving 0.4 m ahead into the wall: it touches, and never gets to
    // where the plan goes.
    let o = diff_drive(
        dir.path(),
        "crash",
        "t,v,omega\n0,0.2,0\n2,0,0\n2.5,0,0\n",
        wall,
    );
    assert_eq!(metric(&o, "sim_min_clearance"), 0.0);
    assert!(metric(&o, "sim_obstacle_contacts") >= 1.0);
    assert!(o.metric("sim_goal_x").is_some());
}

#[test]
fn obstacles_are_in_the_mcap_scene() {
    let dir = tempfile::tempdir().unwrap();
    let o = crate::common::run_file(&parking(dir.path(), 0.0), Some(&dir.path().join("logs")));
    let log = o.log_dir.expect("logs written").join("run.mcap");
    let bytes = std::fs::read(log).unwrap();
    let mut ids = std::collections::BTreeSet::new();
    for msg in mcap::MessageStream::new(&bytes).unwrap() {
        let msg = msg.unwrap();
        let schema = msg.channel.schema.as_ref().map(|s| s.name.clone());
        if schema.as_deref() == Some("foxglove.SceneUpdate") {
            let scene = SceneUpdate::decode(&msg.data[..]).unwrap();
            ids.extend(scene.entities.into_iter().map(|e| e.id));
        }
    }
    for name in ["parked_front", "parked_rear", "curb", "post"] {
        assert!(
            ids.iter()
                .any(|id| id.starts_with(&format!("obstacle_{name}_"))),
            "{name} not in {ids:?}"
        );
    }
}

/// `[[world.obstacles]]` is the same list as `[[model.obstacles]]`: the
/// same run to the bit; both at once is refused at the line of the world's.
#[test]
fn world_obstacles_are_the_model_obstacles() {
    let dir = tempfile::tempdir().unwrap();
    let model_file = parking(dir.path(), 0.0);
    let text = std::fs::read_to_string(&model_file).unwrap();
    let mut t: toml::Table = toml::from_str(&text).unwrap();
    let obstacles = t["model"]
        .as_table_mut()
        .unwrap()
        .remove("obstacles")
        .unwrap();
    let mut world = toml::Table::new();
    world.insert("obstacles".into(), obstacles.clone());
    t.insert("world".into(), world.into());
    let world_file = dir.path().join("parking_world.toml");
    std::fs::write(&world_file, toml::to_string(&t).unwrap()).unwrap();
    let a = crate::common::run_file(&model_file, None);
    let b = crate::common::run_file(&world_file, None);
    for name in [
        "sim_min_clearance",
        "sim_obstacle_contacts",
        "sim_goal_position",
    ] {
        assert_eq!(
            metric(&a, name).to_bits(),
            metric(&b, name).to_bits(),
            "{name}"
        );
    }
    // Both spellings at once.
    t["model"]
        .as_table_mut()
        .unwrap()
        .insert("obstacles".into(), obstacles);
    let both = dir.path().join("parking_both.toml");
    let text = toml::to_string(&t).unwrap();
    std::fs::write(&both, &text).unwrap();
    let line = text
        .lines()
        .position(|l| l.trim() == "[[world.obstacles]]")
        .unwrap()
        + 1;
    let err = anholonomy::scenario::Scenario::load(&both)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(&format!(":{line}: key `world.obstacles`: also given as")),
        "{err}"
    );
    // An error inside the world's list names the key as written, at its line.
    t["model"].as_table_mut().unwrap().remove("obstacles");
    let list = t["world"]["obstacles"].as_array().unwrap().clone();
    let mut bad = list.clone();
    bad[1].as_table_mut().unwrap().insert(
        "semi_axes".into(),
        toml::Value::try_from([-0.22, 0.14, 0.06]).unwrap(),
    );
    t["world"]
        .as_table_mut()
        .unwrap()
        .insert("obstacles".into(), bad.into());
    let file = dir.path().join("parking_bad.toml");
    let text = toml::to_string(&t).unwrap();
    std::fs::write(&file, &text).unwrap();
    let second = text
        .lines()
        .enumerate()
        .filter(|(_, l)| l.trim() == "[[world.obstacles]]")
        .nth(1)
        .unwrap()
        .0;
    let line = text
        .lines()
        .enumerate()
        .skip(second)
        .find(|(_, l)| l.starts_with("semi_axes"))
        .unwrap()
        .0
        + 1;
    let err = anholonomy::scenario::Scenario::load(&file)
        .and_then(anholonomy::validate::Prepared::new)
        .map(|_| ())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(&format!(
            ":{line}: key `world.obstacles[1].semi_axes[0]`: must be > 0"
        )),
        "{err}"
    );
    assert!(!err.contains("model.obstacles"), "{err}");
}
