//! The HTML report: pages, figures, self-containment; bad log directories.

use crate::common::*;
use std::path::Path;

fn one_line_input_error(out: &std::process::Output, needle: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: ") && err.contains(needle),
        "`{needle}` not in {err}"
    );
}

/// No reference leaves the page: no scripts, no remote URLs. The SVG namespace name
/// (`xmlns="http://www.w3.org/2000/svg"`, written by plotters) is an identifier, never fetched.
fn assert_self_contained(html: &str) {
    let html = html.replace("xmlns=\"http://www.w3.org/2000/svg\"", "");
    for bad in ["http://", "https://", "<script", "<img src=\"/", "@import"] {
        assert!(!html.contains(bad), "{bad} in page");
    }
}

#[test]
fn report_of_a_run_and_a_sweep() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    let urdf = model("rolling_disk.urdf");
    // Not the paper's worked example (another final α), so no paper table.
    let task = disk_scenario(&urdf, "", "").replace("180.0, 22.5]", "180.0, 30.0]");
    std::fs::write(dir.join("disk.toml"), task).unwrap();
    std::fs::write(
        dir.join("sw.toml"),
        format!(
            "{}\n[sweep]\ncount = 4\nseed = 3\nfriction = [0.8, 1.0]\nmass_scale = [0.9, 1.1]\nsuccess_metric = \"sim_goal_position\"\nsuccess_max = 0.05\ntime_metric = \"sim_goal_position\"\n",
            disk_scenario(&urdf, "", "")
        ),
    )
    .unwrap();
    let paper = root().join("scenarios/disk_paper.toml");
    let out = cli(
        dir,
        &[
            "run",
            "disk.toml",
            "sw.toml",
            paper.to_str().unwrap(),
            "--logs",
            "logs",
            "--quiet",
            "--report",
        ],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let logs = dir.join("logs");
    let index = std::fs::read_to_string(logs.join("index.html")).unwrap();
    assert_self_contained(&index);
    for name in ["disk", "sw", "disk_paper"] {
        assert!(
            index.contains(&format!("href=\"{name}/report.html\"")),
            "{name}"
        );
    }
    // Every error in the index carries its unit.
    assert!(
        index.matches(" m</td>").count() >= 2,
        "goal and tracking errors in m"
    );
    let page = std::fs::read_to_string(logs.join("disk/report.html")).unwrap();
    assert_self_contained(&page);
    for needle in [
        "planar path: ideal vs simulated",
        "tracking error: position (m)",
        "tracking error: theta (deg)",
        "alpha (deg)",
        "command: ",
        "slip_lateral",
        "Plan segments",
    ] {
        assert!(page.contains(needle), "{needle} missing");
    }
    assert!(page.matches("<svg").count() >= 4 + 5 + 4 + 2);
    // Paper table of the paper's example, with the misprints flagged.
    let p = std::fs::read_to_string(logs.join("disk_paper/report.html")).unwrap();
    assert!(p.contains("<h2>Paper</h2>") && p.contains("175.78") && p.contains("differs"));
    assert!(!page.contains("<h2>Paper</h2>"), "not the paper's task");
    let sw = std::fs::read_to_string(logs.join("sw/report.html")).unwrap();
    assert_self_contained(&sw);
    assert!(!sw.contains("wall NaN"), "the sweep's wall time is read");
    for needle in [
        "final error (sim_goal_position)",
        "final error vs friction coefficient",
        "final error vs mass scale",
    ] {
        assert!(sw.contains(needle), "{needle} missing");
    }

    // `report` regenerates the same pages from the logs alone.
    let before = std::fs::read_to_string(logs.join("disk/report.html")).unwrap();
    std::fs::remove_file(logs.join("disk/report.html")).unwrap();
    let out = cli(dir, &["report", "logs"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(
        std::fs::read_to_string(logs.join("disk/report.html")).unwrap(),
        before
    );
}

fn snapshot(dir: &Path) -> Vec<(std::path::PathBuf, Vec<u8>)> {
    let mut v: Vec<_> = files_below(dir)
        .into_iter()
        .map(|p| {
            let b = std::fs::read(&p).unwrap();
            (p, b)
        })
        .collect();
    v.sort();
    v
}

#[test]
fn empty_or_half_written_log_dirs_are_input_errors() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path();
    // Empty log directory, and one that does not exist.
    std::fs::create_dir(dir.join("empty")).unwrap();
    one_line_input_error(&cli(dir, &["report", "empty"]), "no runs to report");
    assert!(files_below(&dir.join("empty")).is_empty());
    one_line_input_error(&cli(dir, &["report", "nope"]), "not a log directory");

    std::fs::write(
        dir.join("s.toml"),
        disk_scenario(&model("rolling_disk.urdf"), "", ""),
    )
    .unwrap();
    let out = cli(
        dir,
        &["run", "s.toml", "--logs", "logs", "--quiet", "--report"],
    );
    assert!(out.status.success());
    let logs = dir.join("logs");
    let run = logs.join("s");

    // A run interrupted before its summary: no summary.json.
    let summary = std::fs::read(run.join("summary.json")).unwrap();
    std::fs::remove_file(run.join("summary.json")).unwrap();
    let before = snapshot(&logs);
    one_line_input_error(&cli(dir, &["report", "logs"]), "summary.json: missing");
    assert_eq!(snapshot(&logs), before, "report wrote or removed files");
    std::fs::write(run.join("summary.json"), &summary).unwrap();

    // A temporary file left by an interrupted writer.
    std::fs::write(run.join("run.mcap.tmp"), b"partial").unwrap();
    let before = snapshot(&logs);
    one_line_input_error(&cli(dir, &["report", "logs"]), "run.mcap.tmp");
    assert_eq!(snapshot(&logs), before);
    std::fs::remove_file(run.join("run.mcap.tmp")).unwrap();

    // A truncated series file: names the file and the line.
    let series = std::fs::read(run.join("series.json")).unwrap();
    std::fs::write(run.join("series.json"), &series[..series.len() / 2]).unwrap();
    let before = snapshot(&logs);
    one_line_input_error(&cli(dir, &["report", "logs"]), "series.json:1:");
    assert_eq!(snapshot(&logs), before);
    std::fs::write(run.join("series.json"), &series).unwrap();

    // A stray directory that is not a run.
    std::fs::create_dir(logs.join("stray")).unwrap();
    one_line_input_error(
        &cli(dir, &["report", "logs"]),
        "stray/summary.json: missing",
    );
    std::fs::remove_dir(logs.join("stray")).unwrap();
    assert!(cli(dir, &["report", "logs"]).status.success());
}
