//! Verdicts: a shipped scenario expected to fail shows XFAIL (with its
//! reason) in the table, summary.json, the JUnit file and the report, and
//! `check` accepts it; the same scenario made to pass is XPASS and `check`
//! exits 1. Metrics that mean nothing for a feedback policy are shown as such.

use crate::common::*;
use std::path::Path;
use std::process::Command;

fn check(dir: &Path, args: &[&str]) -> (Option<i32>, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .arg("check")
        .args(args)
        .current_dir(dir)
        .output()
        .unwrap();
    (
        o.status.code(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn summary(dir: &Path, name: &str) -> serde_json::Value {
    let t = std::fs::read_to_string(dir.join("logs").join(name).join("summary.json")).unwrap();
    serde_json::from_str(&t).unwrap()
}

#[test]
fn expected_failures_are_xfail_and_an_unexpected_pass_fails_check() {
    let dir = tempfile::tempdir().unwrap();
    let shipped = corpus_shipped("rover_open_loop.toml");
    assert!(shipped.contains("expect = \"fails\""));
    // The same scenario with the physics gate loosened past its 17 m miss.
    let xpass = shipped
        .replace("sim_goal_se2 = 0.1", "sim_goal_se2 = 50.0")
        .replace("description =", "name = \"open_loop_loose\"\ndescription =");
    assert_ne!(xpass, shipped);
    std::fs::write(dir.path().join("rover_open_loop.toml"), &shipped).unwrap();
    std::fs::write(dir.path().join("loose.toml"), &xpass).unwrap();

    // Alone, the expected failure passes `check`.
    let (code, out, err) = check(
        dir.path(),
        &[
            "rover_open_loop.toml",
            "--quiet",
            "--junit",
            "logs/junit.xml",
            "--report",
        ],
    );
    assert_eq!(code, Some(0), "{out}\n{err}");
    let row = out
        .lines()
        .find(|l| l.starts_with("rover_open_loop"))
        .unwrap();
    assert!(row.contains("XFAIL: sim_goal_se2 = "), "{row}");
    assert!(row.contains("(expected: open-loop replay"), "{row}");
    // Tracking is meaningful here: both runs get the same recorded commands.
    assert!(!row.contains("n/a"), "{row}");
    let s = summary(dir.path(), "rover_open_loop");
    assert_eq!(s["verdict"], "XFAIL");
    assert_eq!(s["passed"], false);
    assert!(s["expect"]["reason"]
        .as_str()
        .unwrap()
        .starts_with("open-loop replay"));
    let junit = std::fs::read_to_string(dir.path().join("logs/junit.xml")).unwrap();
    assert!(
        junit.contains("<skipped message=\"XFAIL: expected failure: open-loop replay"),
        "{junit}"
    );
    assert!(!junit.contains("<failure"), "{junit}");
    let page =
        std::fs::read_to_string(dir.path().join("logs/rover_open_loop/report.html")).unwrap();
    assert!(
        page.contains(">XFAIL</span>")
            && page.contains("as this scenario expects: open-loop replay")
    );

    // With the loosened copy, XPASS makes `check` exit 1 and is a JUnit failure.
    let (code, out, err) = check(
        dir.path(),
        &[
            "rover_open_loop.toml",
            "loose.toml",
            "--quiet",
            "--junit",
            "logs/junit.xml",
            "--report",
        ],
    );
    assert_eq!(code, Some(1), "{out}\n{err}");
    let row = out
        .lines()
        .find(|l| l.starts_with("open_loop_loose"))
        .unwrap();
    assert!(
        row.contains("XPASS: met every threshold, but expected to fail"),
        "{row}"
    );
    assert!(
        err.contains(
            "1 of 2 scenarios met every threshold although they are expected to fail (XPASS)"
        ),
        "{err}"
    );
    assert!(!err.contains("broke a threshold"), "{err}");
    assert_eq!(summary(dir.path(), "open_loop_loose")["verdict"], "XPASS");
    let junit = std::fs::read_to_string(dir.path().join("logs/junit.xml")).unwrap();
    assert!(junit.contains("type=\"xpass\""), "{junit}");
    let index = std::fs::read_to_string(dir.path().join("logs/index.html")).unwrap();
    assert!(
        index.contains("2 scenarios: 0 PASS, 1 XFAIL, 1 XPASS"),
        "{index}"
    );
}

/// The rover's feedback policy: tracking is `n/a` in the table and the report,
/// not a number, and a threshold on it is refused up front.
#[test]
fn tracking_of_feedback_policies_is_not_a_number() {
    let dir = tempfile::tempdir().unwrap();
    let text = corpus_shipped("rover_mirror.toml");
    std::fs::write(dir.path().join("rover_mirror.toml"), &text).unwrap();
    let (code, out, err) = check(dir.path(), &["rover_mirror.toml", "--quiet", "--report"]);
    assert_eq!(code, Some(0), "{out}\n{err}");
    let row = out.lines().find(|l| l.starts_with("rover_mirror")).unwrap();
    assert_eq!(row.matches(" n/a ").count(), 2, "{row}");
    assert!(out.contains("n/a: tracking error means nothing for a feedback policy"));
    let s = summary(dir.path(), "rover_mirror");
    assert!(s["not_meaningful"]["tracking"]
        .as_str()
        .unwrap()
        .contains("feedback policy"));
    let page = std::fs::read_to_string(dir.path().join("logs/rover_mirror/report.html")).unwrap();
    assert!(
        page.contains("Not shown: not meaningful: a feedback policy"),
        "tracking charts shown"
    );
    // A real duration in the header, not the 300 s horizon alone.
    assert!(page.contains("ideal run ") && page.contains("feedback policy, horizon 300.0 s"));

    let gated = text.replace("[thresholds]", "[thresholds]\ntracking_position_max = 1.0");
    std::fs::write(dir.path().join("b.toml"), &gated).unwrap();
    let (code, _, err) = check(dir.path(), &["b.toml", "--quiet"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.starts_with("error: b.toml:")
            && err.contains("key `thresholds.tracking_position_max`: tracking errors mean nothing"),
        "{err}"
    );
}

fn corpus_shipped(file: &str) -> String {
    std::fs::read_to_string(scenario(file)).unwrap().replace(
        "../models/",
        &format!("{}/", root().join("models").display()),
    )
}
