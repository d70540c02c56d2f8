//! JUnit XML for CI systems (GitHub Actions test reporters, GitLab, Jenkins),
//! written with `quick-junit`.
//!
//! One `<testsuite name="anholonomy">`, one `<testcase>` per scenario:
//! `name` the scenario, `classname` `anholonomy.<planner>`, `time` the
//! scenario's wall time. A broken threshold or a baseline regression is a
//! `<failure>` whose text lists every one; a scenario that could not run
//! (planner refusal, physics failure) is an `<error>`. A sweep is one test
//! case with its statistics (`sweep_*` metrics) as `<property>` elements.

use crate::baseline::{fmt_value, Delta, Status};
use crate::error::Error;
use crate::runner::RunOutcome;
use quick_junit::{NonSuccessKind, Property, Report, TestCase, TestCaseStatus, TestSuite};
use std::path::Path;
use std::time::Duration;

/// One scenario's result as the JUnit writer sees it.
pub enum CaseResult<'a> {
    /// It ran: thresholds from the outcome, regressions from the baseline check.
    Ran {
        /// The outcome.
        outcome: &'a RunOutcome,
        /// Baseline comparison, when one was made.
        deltas: Option<&'a [Delta]>,
        /// Whether the scenario is a sweep (statistics become properties).
        sweep: bool,
    },
    /// It could not run.
    Failed {
        /// Scenario name.
        name: &'a str,
        /// Planner kind.
        planner: &'a str,
        /// Why.
        error: &'a Error,
        /// Wall time until the failure, s.
        wall_s: f64,
    },
}

fn secs(s: f64) -> Duration {
    Duration::try_from_secs_f64(s.max(0.0)).unwrap_or_default()
}

/// The test case of one result.
pub fn test_case(r: &CaseResult<'_>) -> TestCase {
    match r {
        CaseResult::Ran {
            outcome: o,
            deltas,
            sweep,
        } => {
            let regressions: Vec<String> = deltas
                .unwrap_or(&[])
                .iter()
                .filter(|d| d.status.fails())
                .map(|d| {
                    let v = |x: Option<f64>| x.map(fmt_value).unwrap_or_else(|| "-".into());
                    let why = if d.status == Status::Missing {
                        "no longer produced".to_string()
                    } else {
                        format!("tolerance {}", fmt_value(d.tolerance))
                    };
                    format!(
                        "regression: {} baseline {} now {} ({}, {why})",
                        d.metric,
                        v(d.baseline),
                        v(d.now),
                        d.change
                    )
                })
                .collect();
            let status = if o.failures.is_empty() && regressions.is_empty() {
                TestCaseStatus::success()
            } else {
                let mut s = TestCaseStatus::non_success(NonSuccessKind::Failure);
                let mut parts = Vec::new();
                if !o.failures.is_empty() {
                    parts.push(format!("{} threshold(s) broken", o.failures.len()));
                }
                if !regressions.is_empty() {
                    parts.push(format!("{} baseline regression(s)", regressions.len()));
                }
                let lines: Vec<String> = o
                    .failures
                    .iter()
                    .map(|f| format!("threshold: {f}"))
                    .chain(regressions)
                    .collect();
                s.set_message(parts.join(", "))
                    .set_type(if o.failures.is_empty() {
                        "regression"
                    } else {
                        "threshold"
                    })
                    .set_description(lines.join("\n"));
                s
            };
            let mut tc = TestCase::new(o.name.as_str(), status);
            tc.set_classname(format!("anholonomy.{}", o.planner))
                .set_time(secs(o.timings.total));
            if *sweep {
                for (k, v) in &o.metrics {
                    tc.add_property(Property::new(k.as_str(), format!("{v}")));
                }
            }
            tc
        }
        CaseResult::Failed {
            name,
            planner,
            error,
            wall_s,
        } => {
            let mut s = TestCaseStatus::non_success(NonSuccessKind::Error);
            s.set_message(error.to_string())
                .set_type(match error.exit_code() {
                    2 => "input",
                    _ => "runtime",
                });
            let mut tc = TestCase::new(*name, s);
            tc.set_classname(format!("anholonomy.{planner}"))
                .set_time(secs(*wall_s));
            tc
        }
    }
}

/// The whole report (one suite).
pub fn report(results: &[CaseResult<'_>], wall_s: f64) -> Report {
    let mut suite = TestSuite::new("anholonomy");
    suite.add_test_cases(results.iter().map(test_case));
    suite.set_time(secs(wall_s));
    let mut r = Report::new("anholonomy");
    r.add_test_suite(suite);
    r.set_time(secs(wall_s));
    r
}

/// Checks up front that `path` can be written (its directory exists and takes a new file), so
/// a bad `--junit` is an input error before anything runs; nothing is created or overwritten.
pub fn check_writable(path: &Path) -> Result<(), Error> {
    let bad = |m: String| Error::input(path, format!("option `--junit`: {m}"));
    if path.is_dir() {
        return Err(bad("is a directory".into()));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(bad(format!("directory {} does not exist", dir.display())));
    }
    let probe =
        tempfile_in(dir).map_err(|e| bad(format!("cannot write in {}: {e}", dir.display())))?;
    let _ = std::fs::remove_file(probe);
    if path.exists() {
        let meta = std::fs::metadata(path).map_err(|e| bad(e.to_string()))?;
        if meta.permissions().readonly() {
            return Err(bad("file is read-only".into()));
        }
    }
    Ok(())
}

fn tempfile_in(dir: &Path) -> std::io::Result<std::path::PathBuf> {
    let p = dir.join(format!(".anholonomy-junit-probe-{}", std::process::id()));
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&p)?;
    Ok(p)
}

/// Write the report atomically.
pub fn write(path: &Path, report: &Report) -> Result<(), String> {
    crate::log::atomic::write_atomic(path, |w| report.serialize(w).map_err(std::io::Error::other))
}
