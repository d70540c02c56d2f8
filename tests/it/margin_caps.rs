//! Torque caps with provenance: a torque or mass margin measured against
//! the default `[sim] motor_max_torque` says so; a cap the scenario sets
//! silences the note and the warning.

use crate::common::*;
use std::path::Path;

/// `examples/declared_diff_drive` on `models/diff_drive.urdf` without its
/// `<limit effort>` attributes, `sim_extra` added to `[sim]`.
fn no_effort(dir: &Path, sim_extra: &str) {
    let urdf = std::fs::read_to_string(model("diff_drive.urdf")).unwrap();
    let stripped = regex_free_strip(&urdf);
    assert!(!stripped.contains("effort=\""), "effort left in the URDF");
    std::fs::write(dir.join("m.urdf"), stripped).unwrap();
    let ex = root().join("examples/declared_diff_drive");
    let text = std::fs::read_to_string(ex.join("declared_diff_drive.toml"))
        .unwrap()
        .replace("../../models/diff_drive.urdf", "m.urdf")
        .replace(
            "path = \"s_curve.csv\"",
            &format!("path = \"{}\"", ex.join("s_curve.csv").display()),
        )
        .replacen("[sim]\n", &format!("[sim]\n{sim_extra}\n"), 1);
    std::fs::write(dir.join("dd.toml"), text).unwrap();
}

/// The URDF without ` effort="..."` attributes.
fn regex_free_strip(urdf: &str) -> String {
    let mut out = String::new();
    let mut rest = urdf;
    while let Some(at) = rest.find(" effort=\"") {
        out.push_str(&rest[..at]);
        let after = &rest[at + " effort=\"".len()..];
        rest = &after[after.find('"').unwrap() + 1..];
    }
    out.push_str(rest);
    out
}

fn margin(dir: &Path) -> String {
    let o = cli(
        dir,
        &[
            "margin",
            "dd.toml",
            "--dimension",
            "torque_scale",
            "--dimension",
            "mass_scale",
            "--no-logs",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into()
}

#[test]
fn margins_against_a_default_cap_say_so() {
    let d = tempfile::tempdir().unwrap();
    no_effort(d.path(), "");
    let out = margin(d.path());
    let note = "against the default cap [sim] motor_max_torque = 50 N·m of `left_wheel_joint`, `right_wheel_joint` (no <limit effort>)";
    for dim in ["torque_scale", "mass_scale"] {
        let row = out
            .lines()
            .find(|l| l.contains(dim))
            .unwrap_or_else(|| panic!("{out}"));
        assert!(row.contains(note), "{row}");
    }
    // The run warns, and summary.json names the source.
    let o = cli(d.path(), &["run", "dd.toml", "--logs", "logs"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("give no <limit effort>"), "{err}");
    let s: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(d.path().join("logs/dd/summary.json")).unwrap(),
    )
    .unwrap();
    let drives = &s["model"]["read_from_urdf"]["drives"];
    assert_eq!(drives[0]["source"], "default", "{drives}");

    // The scenario sets the cap: no note, no warning, the source says so.
    no_effort(d.path(), "motor_max_torque = 2.0");
    let out = margin(d.path());
    assert!(!out.contains("default cap"), "{out}");
    let o = cli(d.path(), &["run", "dd.toml", "--logs", "logs2"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("warning"), "{err}");
    let s: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(d.path().join("logs2/dd/summary.json")).unwrap(),
    )
    .unwrap();
    assert_eq!(
        s["model"]["read_from_urdf"]["drives"][1]["source"],
        "scenario"
    );
}

#[test]
fn a_model_without_drive_readings_is_capped_by_the_settings() {
    // The rolling disk caps its drives at `[sim] motor_max_torque`.
    let d = tempfile::tempdir().unwrap();
    let text = disk_scenario(&model("rolling_disk.urdf"), "name = \"disk\"", "");
    std::fs::write(d.path().join("s.toml"), &text).unwrap();
    let margin_json = || {
        let o = cli(
            d.path(),
            &[
                "margin",
                "s.toml",
                "--dimension",
                "torque_scale",
                "--no-logs",
                "--json",
            ],
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let out = margin_json();
    assert!(
        out.contains("\"default_caps\"") && out.contains("\"joints\": []"),
        "{out}"
    );
    std::fs::write(
        d.path().join("s.toml"),
        disk_scenario(
            &model("rolling_disk.urdf"),
            "name = \"disk\"",
            "motor_max_torque = 50.0",
        ),
    )
    .unwrap();
    let out = margin_json();
    assert!(!out.contains("default_caps"), "{out}");
}
