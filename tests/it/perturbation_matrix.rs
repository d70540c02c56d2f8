//! Every perturbation acts on every model it names, or says why not: model
//! × `[sim.perturb]` dimension, over a shipped scenario of every model.
//!
//! * A dimension the system declares ([`System::perturbable`]) is set
//!   strongly enough to matter, and some gated or goal metric of the
//!   physics run must move by more than [`MOVES`] against the nominal run
//!   (the ideal run, never perturbed, must not move at all). A declared
//!   dimension that does nothing fails here: `torque_scale` on `diff_drive`
//!   and `car` did, their drives being limited by the URDF's effort.
//! * A dimension it does not declare must be refused before anything runs
//!   (exit 2, naming `sim.perturb.<dimension>`), and the pair must be in the
//!   "does not apply" list of docs/src/margins.md; a listed pair the model
//!   takes after all fails too.
//!
//! One test per model, so they run in parallel; each run is in process,
//! without logs.

use crate::common::*;
use anholonomy::engine::perturb::Dimension;
use anholonomy::runner::{run, RunOptions, RunOutcome};
use anholonomy::scenario::Scenario;
use anholonomy::validate::Prepared;
use std::path::Path;

/// Relative change of a metric that counts as "moved": far above the
/// round-off between two builds (the runs are deterministic: two nominal
/// runs are bit for bit the same), far below what a perturbation that
/// matters does (a 1 % torque limit misses a goal by metres).
const MOVES: f64 = 0.01;

/// A strong value of each dimension: a tenth of a second of latency or lag
/// (or less on a short plan), 1 % of the torque, σ of 5 cm or 0.05 rad,
/// wheels worn to 70 %, 5 % of the friction, 10× the masses.
fn strong(d: Dimension, run_s: f64) -> f64 {
    match d {
        Dimension::CommandLatency | Dimension::ActuatorTau | Dimension::StateLatency => {
            0.1f64.min(run_s / 4.0)
        }
        Dimension::TorqueScale => 0.01,
        Dimension::StateNoise => 0.05,
        Dimension::WheelRadiusScale => 0.7,
        Dimension::FrictionScale => 0.05,
        Dimension::MassScale => 10.0,
    }
}

/// A shipped scenario's text (`file` relative to the repository) with every
/// quoted relative path that exists beside it made absolute (URDFs, plan
/// files, laws), so it runs from a temporary directory.
fn shipped_abs(file: &str) -> String {
    let path = root().join(file);
    let dir = path.parent().unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let mut out = String::new();
    for (i, part) in text.split('"').enumerate() {
        if i > 0 {
            out.push('"');
        }
        let candidate = dir.join(part);
        if i % 2 == 1 && !part.is_empty() && !part.starts_with('/') && candidate.exists() {
            out.push_str(&candidate.display().to_string());
        } else {
            out.push_str(part);
        }
    }
    out
}

fn with_perturb(text: &str, body: &str) -> String {
    assert!(text.contains("[sim]\n"));
    text.replacen("[sim]\n", &format!("[sim.perturb]\n{body}\n[sim]\n"), 1)
}

fn load(dir: &Path, name: &str, text: &str) -> Result<Prepared, anholonomy::error::Error> {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    Prepared::new(Scenario::load(&p)?)
}

fn run_quiet(prep: &Prepared) -> RunOutcome {
    let opts = RunOptions {
        log_root: None,
        progress: Default::default(),
        pose_rate: 0.0,
        keep: Default::default(),
        cancel: Default::default(),
        batch: true,
    };
    run(prep, &opts).unwrap()
}

/// The "does not apply" list of the guide: (model cell, dimension cell).
fn does_not_apply() -> Vec<(String, String)> {
    let doc = std::fs::read_to_string(root().join("docs/src/margins.md")).unwrap();
    let table = doc
        .split_once("<!-- begin: does not apply -->")
        .and_then(|(_, r)| r.split_once("<!-- end: does not apply -->"))
        .map(|(t, _)| t)
        .expect("the guide's \"does not apply\" list and its markers");
    table
        .lines()
        .filter(|l| l.starts_with('|'))
        .skip(2)
        .map(|l| {
            let c: Vec<&str> = l.trim_matches('|').split('|').map(str::trim).collect();
            assert!(c.len() == 3 && !c[2].is_empty(), "{l}");
            (c[0].to_string(), c[1].to_string())
        })
        .collect()
}

/// Whether the list says `d` does not apply to `model` (open loop: the
/// scenario's plan reads no state).
fn listed(list: &[(String, String)], model: &str, d: Dimension, open_loop: bool) -> bool {
    list.iter().any(|(m, dims)| {
        let names_model = m.contains(&format!("`{model}`"))
            || (open_loop && d.observes() && m.starts_with("every model, with an open-loop plan"));
        names_model && dims.split(", ").any(|x| x == format!("`{d}`"))
    })
}

/// The metrics that differ by more than [`MOVES`] (NaN against a number
/// counts), physics-run metrics only; the ideal run's must not differ.
fn moved(nominal: &RunOutcome, perturbed: &RunOutcome) -> Vec<String> {
    let mut out = Vec::new();
    for (k, a) in &nominal.metrics {
        let Some(b) = perturbed.metric(k) else {
            continue;
        };
        if k.starts_with("ideal_") {
            assert!(
                a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                "{k}: the ideal run moved ({a} → {b})"
            );
            continue;
        }
        let differs = if a.is_nan() || b.is_nan() {
            a.is_nan() != b.is_nan()
        } else {
            (a - b).abs() > MOVES * a.abs().max(b.abs()).max(1e-6)
        };
        if differs {
            out.push(format!("{k}: {a} → {b}"));
        }
    }
    out
}

/// The whole row of one model: every dimension either moves a metric or
/// is refused and listed; `stronger` replaces [`strong`] values where the
/// row's scenario needs more to matter.
fn model_row(model: &str, file: &str, stronger: &[(Dimension, f64)]) {
    let dir = tempfile::tempdir().unwrap();
    let text = shipped_abs(file);
    let prep = load(dir.path(), "nominal.toml", &text).unwrap();
    assert_eq!(prep.scenario.model.kind(), model, "{file}");
    let applies = prep.system.perturbable(&prep.planned);
    let open_loop = !matches!(
        prep.planned.law,
        anholonomy::plan::ControlLaw::Feedback { .. }
    );
    let run_s = prep.planned.duration;
    let nominal = run_quiet(&prep);
    let list = does_not_apply();
    let mut problems = Vec::new();
    for d in Dimension::all() {
        let v = stronger
            .iter()
            .find(|(x, _)| *x == d)
            .map_or_else(|| strong(d, run_s), |(_, v)| *v);
        let case = with_perturb(&text, &format!("{d} = {v:?}\n"));
        let loaded = load(dir.path(), &format!("{d}.toml"), &case);
        let is_listed = listed(&list, model, d, open_loop);
        if applies.contains(&d) {
            if is_listed {
                problems.push(format!(
                    "{d}: listed as not applying to `{model}`, but the model takes it"
                ));
            }
            let prep = match loaded {
                Ok(p) => p,
                Err(e) => {
                    problems.push(format!("{d} = {v}: declared but refused: {e}"));
                    continue;
                }
            };
            let o = run_quiet(&prep);
            let m = moved(&nominal, &o);
            if m.is_empty() {
                problems.push(format!(
                    "{d} = {v}: declared, but no metric moved by more than {} %",
                    100.0 * MOVES
                ));
            } else {
                eprintln!("{model}: {d} = {v} moves {} (first: {})", m.len(), m[0]);
            }
        } else {
            match loaded {
                Ok(_) => problems.push(format!("{d} = {v}: not declared, but accepted")),
                Err(e) => {
                    let msg = e.to_string();
                    if e.kind() != anholonomy::error::ErrorKind::BadInput
                        || !msg.contains(&format!("key `sim.perturb.{d}`"))
                        || !msg.contains("does not apply")
                    {
                        problems.push(format!("{d}: refused without naming the key: {msg}"));
                    }
                    if !is_listed {
                        problems.push(format!(
                            "{d}: refused for `{model}` but not in the \"does not apply\" list of docs/src/margins.md"
                        ));
                    }
                }
            }
        }
    }
    assert!(
        problems.is_empty(),
        "{model} ({file}):\n  {}",
        problems.join("\n  ")
    );
}

/// The matrix covers every model kind (a new model must get a row).
#[test]
fn every_model_has_a_row() {
    let mut rows: Vec<&str> = ROWS.iter().map(|(m, _)| *m).collect();
    rows.sort();
    let mut kinds = anholonomy::scenario::ModelConfig::KINDS.to_vec();
    kinds.sort();
    assert_eq!(rows, kinds);
}

/// A shipped scenario of every model (the declared model has none in
/// `scenarios/`: its example).
const ROWS: [(&str, &str); 8] = [
    ("rolling_disk", "scenarios/disk_paper.toml"),
    ("rolling_sphere", "scenarios/sphere_triangle_paper.toml"),
    ("space_robot", "scenarios/space_robot_paper.toml"),
    ("rover", "scenarios/rover_behind.toml"),
    ("mobile_manipulator", "scenarios/dilf_single_open.toml"),
    ("diff_drive", "scenarios/diff_drive_go_to_pose.toml"),
    ("car", "scenarios/car_parking.toml"),
    (
        "declared",
        "examples/declared_diff_drive/declared_diff_drive.toml",
    ),
];

#[test]
fn rolling_disk() {
    model_row(ROWS[0].0, ROWS[0].1, &[]);
}

#[test]
fn rolling_sphere() {
    model_row(ROWS[1].0, ROWS[1].1, &[]);
}

#[test]
fn space_robot() {
    model_row(ROWS[2].0, ROWS[2].1, &[]);
}

#[test]
fn rover() {
    model_row(ROWS[3].0, ROWS[3].1, &[]);
}

#[test]
fn mobile_manipulator() {
    model_row(ROWS[4].0, ROWS[4].1, &[]);
}

#[test]
fn diff_drive() {
    model_row(ROWS[5].0, ROWS[5].1, &[]);
}

#[test]
fn car() {
    model_row(ROWS[6].0, ROWS[6].1, &[]);
}

/// The example's S curve is gentle: with 10× the masses (a 43 kg robot)
/// its velocity servos still track it to 1e-8 (relative); 50× saturates
/// the 1 N m drives and the robot ends 1.3 m off.
#[test]
fn declared() {
    model_row(ROWS[7].0, ROWS[7].1, &[(Dimension::MassScale, 50.0)]);
}

/// The rover's open-loop replay reads no state: the state dimensions are
/// refused there, and the list says so (the open-loop row).
#[test]
fn rover_open_loop_replay_refuses_what_it_cannot_see() {
    let dir = tempfile::tempdir().unwrap();
    let text = shipped_abs("scenarios/rover_open_loop.toml");
    let list = does_not_apply();
    for d in [Dimension::StateNoise, Dimension::StateLatency] {
        let case = with_perturb(&text, &format!("{d} = 0.05\n"));
        let e = load(dir.path(), "r.toml", &case).err().expect("refused");
        assert_eq!(e.kind(), anholonomy::error::ErrorKind::BadInput);
        assert!(
            e.to_string().contains(&format!("key `sim.perturb.{d}`")),
            "{e}"
        );
        assert!(listed(&list, "rover", d, true));
    }
}
