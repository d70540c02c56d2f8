//! A scenario's verdict: its thresholds against what the scenario expects
//! (`expect = "fails"` in the file).
//!
//! | thresholds | expected to | verdict | `check` |
//! |---|---|---|---|
//! | all met | pass | PASS | ok |
//! | one broken | pass | FAIL | exit 1 |
//! | one broken | fail | XFAIL | ok |
//! | all met | fail | XPASS | exit 1: the scenario no longer shows what it was written for |

use serde::{Deserialize, Serialize};

/// PASS, FAIL, XFAIL or XPASS.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "UPPERCASE")]
pub enum Verdict {
    /// Every threshold met, as expected.
    Pass,
    /// A threshold broken, unexpectedly.
    Fail,
    /// A threshold broken, as the scenario expects.
    Xfail,
    /// Every threshold met although the scenario expects to fail.
    Xpass,
}

impl Verdict {
    /// The verdict of a run whose thresholds were all met (`passed`) or not.
    pub fn of(passed: bool, expect_fails: bool) -> Verdict {
        match (passed, expect_fails) {
            (true, false) => Verdict::Pass,
            (false, false) => Verdict::Fail,
            (false, true) => Verdict::Xfail,
            (true, true) => Verdict::Xpass,
        }
    }

    /// Whether `check` accepts it (PASS and XFAIL).
    pub fn ok(self) -> bool {
        matches!(self, Verdict::Pass | Verdict::Xfail)
    }

    /// `PASS`, `FAIL`, `XFAIL`, `XPASS`.
    pub fn as_str(self) -> &'static str {
        match self {
            Verdict::Pass => "PASS",
            Verdict::Fail => "FAIL",
            Verdict::Xfail => "XFAIL",
            Verdict::Xpass => "XPASS",
        }
    }

    /// From a stored `verdict` string (older logs: from `passed`).
    pub fn parse(s: Option<&str>, passed: bool) -> Verdict {
        match s {
            Some("PASS") => Verdict::Pass,
            Some("FAIL") => Verdict::Fail,
            Some("XFAIL") => Verdict::Xfail,
            Some("XPASS") => Verdict::Xpass,
            _ => Verdict::of(passed, false),
        }
    }

    /// One line for tables: the verdict, what broke and why it was expected.
    pub fn describe(self, failures: &[String], reason: Option<&str>) -> String {
        let reason = reason.unwrap_or("");
        match self {
            Verdict::Pass => "PASS".into(),
            Verdict::Fail => format!("FAIL: {}", failures.join("; ")),
            Verdict::Xfail => format!("XFAIL: {} (expected: {reason})", failures.join("; ")),
            Verdict::Xpass => {
                format!("XPASS: met every threshold, but expected to fail: {reason}")
            }
        }
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_four_verdicts() {
        assert_eq!(Verdict::of(true, false), Verdict::Pass);
        assert_eq!(Verdict::of(false, false), Verdict::Fail);
        assert_eq!(Verdict::of(false, true), Verdict::Xfail);
        assert_eq!(Verdict::of(true, true), Verdict::Xpass);
        let ok: Vec<bool> = [Verdict::Pass, Verdict::Fail, Verdict::Xfail, Verdict::Xpass]
            .iter()
            .map(|v| v.ok())
            .collect();
        assert_eq!(ok, [true, false, true, false]);
        assert_eq!(serde_json::to_string(&Verdict::Xfail).unwrap(), "\"XFAIL\"");
        assert_eq!(Verdict::parse(Some("XPASS"), true), Verdict::Xpass);
        assert_eq!(Verdict::parse(None, false), Verdict::Fail);
    }
}
