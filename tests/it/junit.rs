//! JUnit XML: read back with quick-junit and validated with xmllint against the committed
//! schema (`tests/data/junit.xsd`).

use crate::common::*;
use std::path::Path;
use std::process::Command;

/// `xmllint --schema`; under CI a missing xmllint is a failure (`.ci/run` installs it).
fn xmllint(xml: &Path) -> Option<(bool, String)> {
    let schema = root().join("tests/data/junit.xsd");
    match Command::new("xmllint")
        .args(["--noout", "--schema"])
        .arg(&schema)
        .arg(xml)
        .output()
    {
        Ok(o) => Some((
            o.status.success(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )),
        Err(e) => {
            assert!(
                std::env::var_os("CI").is_none(),
                "xmllint is required under CI (apt-get install -y libxml2-utils): {e}"
            );
            eprintln!("SKIPPED schema validation: xmllint not found ({e})");
            None
        }
    }
}

#[test]
fn junit_has_one_case_per_scenario_and_validates() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let urdf = model("rolling_disk.urdf");
    std::fs::write(dir.join("a_ok.toml"), disk_scenario(&urdf, "", "")).unwrap();
    std::fs::write(
        dir.join("b_tight.toml"),
        format!(
            "{}\n[thresholds]\nsim_goal_position = 1e-9\ntracking_position_max = 1e-9\n",
            disk_scenario(&urdf, "", "")
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("c_sweep.toml"),
        format!(
            "{}\n[sweep]\ncount = 3\nseed = 5\nfriction = [0.8, 1.0]\nsuccess_metric = \"sim_goal_position\"\nsuccess_max = 0.05\n# the disk reports no time to goal\ntime_metric = \"sim_goal_position\"\n",
            disk_scenario(&urdf, "", "")
        ),
    )
    .unwrap();
    let out = cli(
        dir,
        &[
            "check",
            "a_ok.toml",
            "b_tight.toml",
            "c_sweep.toml",
            "--no-logs",
            "--quiet",
            "--junit",
            "r.xml",
        ],
    );
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let xml = std::fs::read_to_string(dir.join("r.xml")).unwrap();
    let rep = quick_junit::Report::deserialize_from_str(&xml).unwrap();
    assert_eq!(rep.test_suites.len(), 1);
    let suite = &rep.test_suites[0];
    assert_eq!((suite.tests, suite.failures, suite.errors), (3, 1, 0));
    let names: Vec<&str> = suite.test_cases.iter().map(|c| c.name.as_str()).collect();
    assert_eq!(names, ["a_ok", "b_tight", "c_sweep"]);
    let [ok, tight, sweep] = &suite.test_cases[..] else {
        unreachable!()
    };
    assert!(matches!(
        ok.status,
        quick_junit::TestCaseStatus::Success { .. }
    ));
    assert_eq!(
        ok.classname.as_ref().unwrap().as_str(),
        "anholonomy.stokes_disk"
    );
    assert!(ok.time.unwrap().as_secs_f64() > 0.0);
    match &tight.status {
        quick_junit::TestCaseStatus::NonSuccess {
            kind, description, ..
        } => {
            assert_eq!(*kind, quick_junit::NonSuccessKind::Failure);
            let d = description.as_ref().unwrap().as_str();
            assert!(d.contains("threshold: sim_goal_position"), "{d}");
            assert!(d.contains("threshold: tracking_position_max"), "{d}");
        }
        s => panic!("expected a failure, got {s:?}"),
    }
    let props: Vec<(&str, &str)> = sweep
        .properties
        .iter()
        .map(|p| (p.name.as_str(), p.value.as_str()))
        .collect();
    assert!(props.contains(&("sweep_variants", "3")), "{props:?}");
    assert!(
        props.iter().any(|(n, _)| *n == "sweep_success_rate"),
        "{props:?}"
    );

    if let Some((ok, msg)) = xmllint(&dir.join("r.xml")) {
        assert!(ok, "schema validation failed: {msg}");
        // The schema check can fail: a test case without a name, a time with an exponent.
        let bad = xml.replacen("<testcase name=\"a_ok\"", "<testcase", 1);
        std::fs::write(dir.join("bad1.xml"), bad).unwrap();
        assert!(!xmllint(&dir.join("bad1.xml")).unwrap().0);
        let bad = regex_free_replace_time(&xml);
        std::fs::write(dir.join("bad2.xml"), bad).unwrap();
        assert!(!xmllint(&dir.join("bad2.xml")).unwrap().0);
    }
}

/// The first `time="..."` attribute rewritten with an exponent.
fn regex_free_replace_time(xml: &str) -> String {
    let at = xml.find("time=\"").unwrap() + 6;
    let end = at + xml[at..].find('"').unwrap();
    format!("{}1e-3{}", &xml[..at], &xml[end..])
}

#[test]
fn unwritable_junit_path_is_an_input_error_before_running() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    std::fs::write(
        dir.join("s.toml"),
        disk_scenario(&model("rolling_disk.urdf"), "", ""),
    )
    .unwrap();
    std::fs::create_dir(dir.join("adir")).unwrap();
    for target in ["missing/dir/r.xml", "adir"] {
        let out = cli(
            dir,
            &["check", "s.toml", "--logs", "logs", "--junit", target],
        );
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(
            err.starts_with("error: ") && err.contains("--junit"),
            "{err}"
        );
        assert!(
            files_below(&dir.join("logs")).is_empty(),
            "ran despite bad --junit"
        );
    }
    assert!(dir.join("adir").is_dir());
}
