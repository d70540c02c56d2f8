//! JUnit XML for CI systems (GitHub Actions test reporters, GitLab, Jenkins),
//! written with `quick-junit`.
//!
//! One `<testsuite name="anholonomy">`, one `<testcase>` per scenario:
//! `name` the scenario, `classname` `anholonomy.<planner>`, `time` the
//! scenario's wall time. A broken threshold or a baseline regression is a
//! `<failure>` whose text lists every one; a scenario that could not run
//! (planner refusal, physics failure) is an `<error>`. A scenario expected to
//! fail (`expect = "fails"`) that does is `<skipped>` with type `xfail` and
//! the reason; one that meets every threshold instead (XPASS) is a `<failure>`
//! of type `xpass`. A sweep is one test
//! case with its statistics (`sweep_*` metrics) as `<property>` elements.

use crate::baseline::{Delta, Status};
use crate::error::Error;
use crate::numfmt::fmt_value;
use crate::runner::RunOutcome;
use crate::verdict::Verdict;
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
pub(crate) fn test_case(r: &CaseResult<'_>) -> TestCase {
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
            let thresholds: Vec<String> = o
                .failures
                .iter()
                .map(|f| format!("threshold: {f}"))
                .collect();
            let reason = o.expect_reason.as_deref().unwrap_or("");
            let status = match (o.verdict, regressions.is_empty()) {
                (Verdict::Pass, true) => TestCaseStatus::success(),
                // An expected failure is reported as skipped, the way test
                // runners report xfail, so CI dashboards do not count it.
                (Verdict::Xfail, true) => {
                    let mut s = TestCaseStatus::skipped();
                    s.set_message(format!("XFAIL: expected failure: {reason}"))
                        .set_type("xfail")
                        .set_description(thresholds.join("\n"));
                    s
                }
                (v, _) => {
                    let mut s = TestCaseStatus::non_success(NonSuccessKind::Failure);
                    let mut parts = Vec::new();
                    let mut lines = Vec::new();
                    match v {
                        Verdict::Fail => {
                            parts.push(format!("{} threshold(s) broken", o.failures.len()));
                            lines.extend(thresholds);
                        }
                        Verdict::Xpass => {
                            parts.push(format!(
                                "XPASS: met every threshold although expected to fail ({reason})"
                            ));
                        }
                        Verdict::Xfail => {
                            parts.push(format!("XFAIL ({reason})"));
                            lines.extend(thresholds);
                        }
                        Verdict::Pass => {}
                    }
                    if !regressions.is_empty() {
                        parts.push(format!("{} baseline regression(s)", regressions.len()));
                    }
                    lines.extend(regressions);
                    s.set_message(parts.join(", "))
                        .set_type(match v {
                            Verdict::Fail => "threshold",
                            Verdict::Xpass => "xpass",
                            _ => "regression",
                        })
                        .set_description(lines.join("\n"));
                    s
                }
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
                .set_type(match error.kind() {
                    crate::error::ErrorKind::BadInput => "input",
                    crate::error::ErrorKind::Runtime => "runtime",
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
/// A directory that does not exist yet is accepted when it is `created` (the `--logs`
/// directory the run creates) or inside it, and its nearest existing parent takes new files.
pub fn check_writable(path: &Path, created: Option<&Path>) -> Result<(), Error> {
    let bad = |m: String| Error::input(path, format!("option `--junit`: {m}"));
    if path.is_dir() {
        return Err(bad("is a directory".into()));
    }
    let mut dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.exists() && created.is_some_and(|c| dir.starts_with(c)) {
        while !dir.exists() {
            dir = match dir.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
        }
    }
    if !dir.is_dir() {
        return Err(bad(format!(
            "directory {} does not exist",
            crate::echo::path(dir)
        )));
    }
    let probe = tempfile_in(dir)
        .map_err(|e| bad(format!("cannot write in {}: {e}", crate::echo::path(dir))))?;
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

/// Why the JUnit report could not be written.
#[derive(Debug, thiserror::Error)]
pub enum JunitWriteError {
    /// Its directory could not be created.
    #[error("cannot create {}: {source}", crate::echo::path(dir))]
    CreateDir {
        /// The directory.
        dir: std::path::PathBuf,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The file could not be written.
    #[error(transparent)]
    Write(#[from] crate::log::LogError),
}

/// Write the report atomically (creating its directory, see [`check_writable`]).
pub fn write(path: &Path, report: &Report) -> Result<(), JunitWriteError> {
    if let Some(d) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(d).map_err(|source| JunitWriteError::CreateDir {
            dir: d.to_path_buf(),
            source,
        })?;
    }
    crate::log::atomic::write_file(path, |w| report.serialize(w).map_err(std::io::Error::other))?;
    Ok(())
}
