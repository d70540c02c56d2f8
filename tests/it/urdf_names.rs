//! Every model kind declares its URDF names, and its shipped URDF has them
//! all (an integration test: the scenario layer may not import the URDF
//! loader, `tests/layering.rs`).

use anholonomy::engine::required::{check, defaults};
use anholonomy::scenario::ModelConfig;
use anholonomy::validate::urdf::load;
use std::path::Path;

#[test]
fn every_model_declares_its_urdf_names_and_ships_a_urdf_with_them() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("models");
    // A declared model names its links and joints in the scenario.
    for kind in ModelConfig::KINDS.iter().filter(|k| **k != "declared") {
        let table = ModelConfig::required_urdf(kind).unwrap_or_else(|| panic!("{kind}"));
        assert!(!table.is_empty(), "{kind}");
        let file = match *kind {
            "rolling_sphere" => "sphere",
            k => k,
        };
        let robot = load(&dir.join(format!("{file}.urdf"))).unwrap();
        check(&robot, &defaults(table)).unwrap_or_else(|e| panic!("{kind}: {e}"));
    }
    assert!(ModelConfig::required_urdf("teleport").is_none());
}
