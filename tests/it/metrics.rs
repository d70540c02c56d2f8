//! Every metric the harness produces has a row (its unit, direction and
//! family are declared, never guessed from the name).

use crate::common::root;
use anholonomy::engine::perturb::Dimension;
use anholonomy::metric::{Direction, Family};
use anholonomy::validate::{prepare_all, Call};

/// The metric names of every shipped scenario and of the examples that
/// need no tools beyond the harness, as validation knows them, with every
/// committed baseline's names and every margin metric.
fn produced() -> Vec<String> {
    let r = root();
    let call = Call {
        log_root: None,
        sharded: false,
        max_steps: None,
    };
    let mut names = Vec::new();
    let paths = [
        r.join("scenarios"),
        r.join("examples/skid_steer"),
        r.join("examples/trailer/trailer_plan.toml"),
        r.join("examples/declared_diff_drive"),
        r.join("examples/plan_file"),
    ];
    for p in prepare_all(&paths, &call).expect("the shipped scenarios are valid") {
        names.extend(p.metric_names());
    }
    for e in std::fs::read_dir(r.join("baselines")).unwrap().flatten() {
        let doc: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(e.path()).unwrap()).unwrap();
        names.extend(doc["metrics"].as_object().unwrap().keys().cloned());
    }
    names.extend(Dimension::all().map(|d| format!("margin_{d}")));
    names.sort();
    names.dedup();
    names
}

#[test]
fn every_produced_metric_has_a_row() {
    let names = produced();
    assert!(names.len() > 100, "{}", names.len());
    let missing: Vec<&String> = names
        .iter()
        .filter(|n| anholonomy::robots::metric(n).is_none())
        .collect();
    assert!(missing.is_empty(), "metrics without a row: {missing:?}");
}

/// The rows say what the old name tokens implied for the metrics whose
/// names carry them, so baselines and margins judge as before.
#[test]
fn rows_declare_direction_and_family() {
    let row = |n: &str| anholonomy::robots::metric(n).unwrap();
    for (n, d) in [
        ("sim_goal_position", Direction::LowerIsBetter),
        ("sim_min_clearance", Direction::HigherIsBetter),
        ("sim_robot_clearance", Direction::HigherIsBetter),
        ("envelope_fraction", Direction::HigherIsBetter),
        ("sim_stall_time", Direction::Informational),
        ("sweep_variants", Direction::Informational),
        ("margin_mass_scale", Direction::HigherIsBetter),
        ("max_contact_pairs", Direction::LowerIsBetter),
    ] {
        assert_eq!(row(n).direction, d, "{n}");
    }
    for (n, min, f) in [
        ("tracking_position_max", false, Family::RunningMax),
        ("tracking_theta_deg_max", false, Family::RunningMax),
        ("max_abs_angular_momentum", false, Family::RunningMax),
        ("sim_max_tilt_deg", false, Family::RunningMax),
        ("sim_obstacle_contacts", false, Family::RunningMax),
        ("sim_vdot_violations", false, Family::RunningMax),
        ("sim_time_to_goal", false, Family::FirstPassage),
        ("sim_goal_se2", false, Family::EndOnly),
        ("tracking_position_rms", false, Family::EndOnly),
        ("envelope_outside_fraction", false, Family::EndOnly),
        ("ideal_vdot_violations", false, Family::EndOnly),
        ("sim_min_clearance", true, Family::RunningMin),
        ("sim_robot_clearance", true, Family::RunningMin),
        ("sim_goal_position", true, Family::EndOnly),
        ("ideal_min_clearance", true, Family::EndOnly),
    ] {
        assert_eq!(row(n).family_of(n, min), f, "{n}");
    }
}

/// A name matches at most one row of its own table and every row of a robot
/// room is one no other room declares differently.
#[test]
fn no_metric_is_declared_twice() {
    for n in produced() {
        let r = anholonomy::robots::metric(&n).unwrap();
        // The first matching row answers; a second row must agree with it.
        for other in anholonomy::metric::HARNESS {
            if other.name != r.name && anholonomy::metric::matches(other.name, &n) {
                // A coordinate's unit is the model's: any explicit unit fits it.
                let coordinate =
                    [other.unit, r.unit].contains(&anholonomy::metric::Unit::Coordinate);
                let units = coordinate || other.unit == r.unit;
                assert!(
                    other.direction == r.direction && other.family == r.family && units,
                    "{n}: `{}` and `{}` disagree",
                    r.name,
                    other.name
                );
            }
        }
    }
}
