//! The reference pages under docs/src/reference/ are generated from the
//! schemas the validation pass checks scenarios against: they must equal the
//! generated text, cover every model and planner kind, and every documented
//! range must be the one the validation pass (and the planners behind it)
//! enforces.

use crate::common::root;
use anholonomy::error::Error;
use anholonomy::planner::PlanError;
use anholonomy::reference::{Page, REGENERATE};
use anholonomy::runner::Prepared;
use anholonomy::scenario::{ModelConfig, PlannerConfig, Scenario, Variant};
use std::collections::BTreeMap;
use std::process::Command;

fn reference_dir() -> std::path::PathBuf {
    root().join("docs/src/reference")
}

#[test]
fn committed_reference_equals_the_generated_one() {
    let mut stale = Vec::new();
    for p in Page::all() {
        let path = reference_dir().join(p.file());
        let want = p.markdown().unwrap();
        match std::fs::read_to_string(&path) {
            Ok(have) if have == want => {}
            Ok(_) => stale.push(format!("{} differs", path.display())),
            Err(e) => stale.push(format!("{}: {e}", path.display())),
        }
    }
    assert!(
        stale.is_empty(),
        "the reference is out of date with the code:\n  {}\nregenerate it with `{REGENERATE}` \
         (or `cargo run --release -- keys --markdown --out docs/src/reference`)",
        stale.join("\n  ")
    );
}

#[test]
fn every_kind_has_a_page_in_the_guide() {
    let summary = std::fs::read_to_string(root().join("docs/src/SUMMARY.md")).unwrap();
    let kinds = ModelConfig::KINDS
        .iter()
        .map(|k| (Page::Model(k), format!("reference/models/{k}.md")))
        .chain(
            PlannerConfig::KINDS
                .iter()
                .map(|k| (Page::Planner(k), format!("reference/planners/{k}.md"))),
        );
    for (page, link) in kinds {
        let rows = page.rows().unwrap_or_else(|e| panic!("{link}: {e}"));
        assert!(
            !rows.is_empty() || matches!(page, Page::Model(_)),
            "{link}: no keys"
        );
        assert!(
            reference_dir().join(page.file()).is_file(),
            "{link} missing: run `{REGENERATE}`"
        );
        assert!(
            summary.contains(&format!("({link})")),
            "docs/src/SUMMARY.md does not list {link}"
        );
    }
}

/// The silent defaults users asked about are on the pages, with their values.
#[test]
fn rover_defaults_are_documented() {
    let planner = Page::Planner("rover_primitives").markdown().unwrap();
    for (key, default) in [
        ("planner.approach_deg", "`30.0`"),
        ("planner.p1_tolerance_deg", "`1.0`"),
        ("planner.max_steer_deg", "`45.0`"),
        ("planner.speed", "`0.1`"),
    ] {
        let line = planner
            .lines()
            .find(|l| l.starts_with(&format!("| `{key}` |")))
            .unwrap_or_else(|| panic!("{key} not on the page"));
        assert!(line.contains(default), "{line}");
    }
    let model = Page::Model("rover").markdown().unwrap();
    assert!(model.contains("| `model.envelope_tolerance` | `0.02` | number ≥ 0 |"));
    assert!(model.contains("| 2 | `theta` | deg |"), "{model}");
}

/// Bounds of an `allowed` text: (value, inclusive) at each end.
type Bound = Option<(f64, bool)>;

fn bounds(allowed: &str) -> Option<(Bound, Bound, bool)> {
    let integer = allowed.starts_with("integer");
    let rest = allowed
        .strip_prefix("number ")
        .or_else(|| allowed.strip_prefix("integer "))?;
    let n = |s: &str| s.trim().parse::<f64>().ok();
    if let Some(r) = rest.strip_prefix("in ") {
        let (a, b) = r.split_once(", ")?;
        let lo = (n(&a[1..])?, a.starts_with('['));
        let hi = (n(&b[..b.len() - 1])?, b.ends_with(']'));
        return Some((Some(lo), Some(hi), integer));
    }
    for (op, lo, incl) in [
        ("> ", true, false),
        ("≥ ", true, true),
        ("< ", false, false),
        ("≤ ", false, true),
    ] {
        if let Some(x) = rest.strip_prefix(op).and_then(n) {
            let b = Some((x, incl));
            return Some(if lo {
                (b, None, integer)
            } else {
                (None, b, integer)
            });
        }
    }
    None
}

fn with_value(sc: &Scenario, key: &str, x: f64) -> Result<Scenario, Error> {
    sc.variant(&Variant {
        index: 0,
        seed: 0,
        mass_scale: 1.0,
        sigma_rate: None,
        params: BTreeMap::from([(key.to_string(), x)]),
    })
}

/// Whether `e` says that `key` itself is invalid (rather than, say, that the
/// plan cannot reach the goal with it, or that the run would exceed the step
/// budget).
fn refuses_key(e: &Error, key: &str) -> bool {
    match e {
        Error::Plan {
            key: k,
            source: PlanError::InvalidParameter { .. },
            ..
        } => k == key,
        Error::Input { message, .. } => {
            message.starts_with(&format!("key `{key}`:")) && message.contains("must")
        }
        _ => false,
    }
}

/// Constraints between two keys, which a per-key range cannot state; their
/// docs say them in words. (key, bound probed, why the inside value is refused.)
const CROSS_KEY: [(&str, &str); 3] = [
    (
        "planner.horizon",
        "at least one control period (`planner.period`)",
    ),
    ("planner.max_cycles", "at least `planner.cycles`"),
    (
        "planner.basis_terms",
        "must at least match the segment's task and constraint rows",
    ),
];

/// For every documented bound of every scalar key (on one shipped scenario
/// per model and planner): the value just outside is refused naming the key,
/// and the value at or just inside the bound is not refused as invalid by
/// anything (parser, system, planner), so the page neither promises more
/// nor less than the code accepts.
#[test]
fn documented_ranges_are_the_enforced_ones() {
    let files = [
        ("disk_paper.toml", Page::Model("rolling_disk")),
        ("disk_paper.toml", Page::Planner("stokes_disk")),
        ("disk_paper.toml", Page::Scenario),
        ("space_robot_paper.toml", Page::Planner("stokes_space")),
        ("space_manipulator_s1.toml", Page::Planner("endogenous")),
        ("rover_paper.toml", Page::Model("rover")),
        ("rover_paper.toml", Page::Planner("rover_primitives")),
        ("sphere_geometric_paper.toml", Page::Model("rolling_sphere")),
        (
            "sphere_geometric_paper.toml",
            Page::Planner("sphere_geometric"),
        ),
        (
            "sphere_triangle_paper.toml",
            Page::Planner("sphere_triangle"),
        ),
        ("dilf_single_open.toml", Page::Model("mobile_manipulator")),
        ("dilf_single_open.toml", Page::Planner("dilf")),
        // Outside plans for every model: their shipped examples.
        (
            "../examples/external_law/disk_heading.toml",
            Page::Planner("external"),
        ),
        ("car_parking.toml", Page::Model("car")),
        ("car_parking.toml", Page::Planner("file")),
        ("diff_drive_go_to_pose.toml", Page::Model("diff_drive")),
        ("diff_drive_go_to_pose.toml", Page::Planner("external")),
    ];
    let mut probed = 0;
    let mut wrong = Vec::new();
    for (file, page) in files {
        let sc = Scenario::load(&crate::common::scenario(file)).unwrap();
        for row in page.rows().unwrap() {
            // Keys of optional tables and of other enum variants are not in this file.
            if row.key.contains("[]")
                || row.key.contains('<')
                || row.doc.starts_with("With `kind")
                || row.doc.contains("Optional table")
            {
                continue;
            }
            let Some((lo, hi, integer)) = bounds(&row.allowed) else {
                continue;
            };
            for (b, below) in [(lo, true), (hi, false)] {
                let Some((x, inclusive)) = b else { continue };
                let step = if integer {
                    1.0
                } else {
                    (x.abs() * 1e-6).max(1e-6)
                };
                let toward = if below { -step } else { step };
                let outside = if inclusive { x + toward } else { x };
                let inside = if inclusive { x } else { x - toward };
                probed += 1;
                match with_value(&sc, &row.key, outside) {
                    Err(e) if refuses_key(&e, &row.key) => {}
                    other => wrong.push(format!(
                        "{file}: {} = {outside} (outside `{}`) was not refused: {:?}",
                        row.key,
                        row.allowed,
                        other.err().map(|e| e.to_string())
                    )),
                }
                // At a lower bound the whole validation pass runs (system,
                // physics, planner); at an upper bound the planner would do
                // its largest amount of work (a million RK4 steps, 10 000
                // cycles), so only the parser and the system's checks run.
                let res = with_value(&sc, &row.key, inside).and_then(|v| {
                    if below {
                        Prepared::new(v).map(|_| ())
                    } else {
                        anholonomy::scenario::build_system(&v.model, &v.planner)
                            .map(|_| ())
                            .map_err(|e| v.setup_error(&e))
                    }
                });
                if let Err(e) = res {
                    let cross = CROSS_KEY
                        .iter()
                        .any(|(k, why)| *k == row.key && row.doc.contains(why));
                    if refuses_key(&e, &row.key) && !cross {
                        wrong.push(format!(
                            "{file}: {} = {inside} (inside `{}`) was refused: {e}",
                            row.key, row.allowed
                        ));
                    }
                }
            }
        }
    }
    assert!(probed > 60, "only {probed} bounds probed");
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn keys_command_prints_pages_and_refuses_unknown_names() {
    let bin = env!("CARGO_BIN_EXE_anholonomy");
    let out = Command::new(bin)
        .args(["keys", "rover_primitives"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("planner.approach_deg"), "{text}");
    let out = Command::new(bin)
        .args(["keys", "rover", "--markdown"])
        .output()
        .unwrap();
    assert_eq!(
        String::from_utf8_lossy(&out.stdout),
        Page::Model("rover").markdown().unwrap()
    );
    let out = Command::new(bin)
        .args(["keys", "teleport"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: keys: `teleport` is not a model or planner kind"),
        "{err}"
    );
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(bin)
        .args(["keys", "--markdown", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for p in Page::all() {
        assert_eq!(
            std::fs::read_to_string(dir.path().join(p.file())).unwrap(),
            p.markdown().unwrap()
        );
    }
}
