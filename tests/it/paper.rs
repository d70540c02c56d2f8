//! The paper tables: which printed numbers agree with the computed ones (the misprint tables of
//! the guide's research notes), for each system's worked example; none for other tasks.

use crate::common::*;

fn rows(file: &str) -> Vec<anholonomy::paper::PaperRow> {
    let prep = prepared(&scenario(file));
    let plan = prep.plan().unwrap();
    let (start, goal) = prep.start_goal();
    prep.system.paper(&start, &goal, &plan)
}

/// The quantities (with their printed values) the paper gets wrong, as the guide's research notes list them.
fn differing(file: &str) -> Vec<String> {
    rows(file)
        .into_iter()
        .filter(|r| !r.agrees)
        .map(|r| format!("{} = {}", r.quantity, r.printed))
        .collect()
}

#[test]
fn misprints_are_flagged_and_the_rest_agrees() {
    let cases: [(&str, usize, &[&str]); 6] = [
        (
            "disk_paper.toml",
            8,
            &[
                "rejected loop (Eq. 25-26): b = 0.01808",
                "rejected loop (Eq. 25-26): a = 132.72",
                "detour loop at O: b = 0.8034",
                "detour loop at O: a = 175.78",
            ],
        ),
        (
            "disk_singularity_free.toml",
            8,
            &["loop x (Eq. 23): a = 207.87", "loop y (Eq. 28): a = 60.15"],
        ),
        (
            "space_robot_paper.toml",
            7,
            &["γ for λ = 125° (3 cycles) = 0.596"],
        ),
        ("rover_paper.toml", 1, &[]),
        ("sphere_geometric_paper.toml", 12, &["r (Eq. 26) = 7.07"]),
        (
            "sphere_triangle_paper.toml",
            7,
            &["angle A = 103.81", "angle C = 95.41"],
        ),
    ];
    for (file, n, wrong) in cases {
        let r = rows(file);
        assert_eq!(r.len(), n, "{file}: {r:#?}");
        assert_eq!(differing(file), wrong, "{file}");
        for row in r.iter().filter(|r| !r.agrees) {
            assert!(
                !row.note.is_empty(),
                "{file}: {} needs a note",
                row.quantity
            );
        }
    }
    for other in [
        "disk_long_trip.toml",
        "space_manipulator_s1.toml",
        "rover_behind.toml",
        "sphere_triangle_two.toml",
    ] {
        assert!(rows(other).is_empty(), "{other} is not the paper's task");
    }
}

#[test]
fn plan_prints_the_paper_table() {
    let out = cli(&root(), &["plan", "scenarios/sphere_triangle_paper.toml"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    let line = text
        .lines()
        .find(|l| l.contains("angle A"))
        .expect("paper row");
    assert!(
        line.contains("103.81") && line.contains("103.83") && line.contains("DIFFERS"),
        "{line}"
    );
    let out = cli(
        &root(),
        &["plan", "scenarios/space_robot_paper.toml", "--json"],
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["paper"].as_array().unwrap().len(), 7);
    assert_eq!(v["paper"][0]["printed"], "−89.848");
}
