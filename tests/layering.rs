//! Configuration flows one way: the scenario layer parses files and hands
//! each system its own typed configuration, so nothing below it (systems,
//! planners, models, physics, plans, records, logs) imports
//! `crate::scenario`, and the scenario layer imports nothing above it.
//! Checked on the source text, so a new file is covered too.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(rust_files(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// Lines of `file` that mention one of `modules` as a crate path.
fn uses(file: &Path, modules: &[&str]) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap();
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .filter(|l| {
            modules.iter().any(|m| {
                l.contains(&format!("crate::{m}")) || l.contains(&format!("super::super::{m}"))
            })
        })
        .map(|l| format!("{}: {}", file.display(), l.trim()))
        .collect()
}

#[test]
fn nothing_below_the_scenario_layer_imports_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let below = ["model", "planner", "physics", "systems", "log"]
        .iter()
        .flat_map(|d| rust_files(&src.join(d)))
        .chain(
            [
                "plan",
                "integrate",
                "compare",
                "record",
                "error",
                "input",
                "progress",
            ]
            .iter()
            .map(|f| src.join(format!("{f}.rs"))),
        )
        .collect::<Vec<_>>();
    assert!(below.len() > 25, "{below:?}");
    let bad: Vec<String> = below
        .iter()
        .flat_map(|f| uses(f, &["scenario", "validate", "runner", "sweep", "suite"]))
        .collect();
    assert!(
        bad.is_empty(),
        "imports against the flow:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_scenario_layer_imports_nothing_above_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let bad: Vec<String> = rust_files(&src.join("scenario"))
        .iter()
        .flat_map(|f| uses(f, &["validate", "runner", "sweep", "log"]))
        .collect();
    assert!(
        bad.is_empty(),
        "scenario imports from above:\n{}",
        bad.join("\n")
    );
    let bad: Vec<String> = rust_files(&src.join("validate"))
        .iter()
        .flat_map(|f| uses(f, &["runner", "sweep"]))
        .collect();
    assert!(
        bad.is_empty(),
        "validate imports from above:\n{}",
        bad.join("\n")
    );
}

/// The test can fail: a file that imports the scenario layer is caught.
#[test]
fn an_offending_import_is_detected() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("x.rs");
    std::fs::write(
        &f,
        "use crate::scenario::PlannerConfig;\n// crate::scenario in a comment\n",
    )
    .unwrap();
    assert_eq!(uses(&f, &["scenario"]).len(), 1);
    // The `[sim]` table type is no exception: physics takes `PhysicsSettings`.
    std::fs::write(&f, "use crate::scenario::SimConfig;\n").unwrap();
    assert_eq!(uses(&f, &["scenario"]).len(), 1);
}
