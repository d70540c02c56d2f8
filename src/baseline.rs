//! Baselines: the metrics of every scenario as committed JSON files, and the
//! regression check of a run against them.
//!
//! One file per scenario, `<dir>/<scenario>.json`: format version, scenario
//! name, planner kind and every metric, keys sorted, NaN written as `null`,
//! ±∞ as `"inf"` / `"-inf"`.
//! `anholonomy baseline PATHS --baseline DIR` (or `check --update-baseline`)
//! writes them; `check PATHS --baseline DIR` compares.
//!
//! # Direction rule
//!
//! Whether a metric regresses when it rises or when it falls is its row's
//! [`crate::metric::Direction`] ([`direction`]): errors, maxima, times and
//! counts are lower-is-better; success rates, fractions inside an envelope
//! and minimum clearances higher-is-better; configuration counts and the
//! time a stall was declared informational.
//!
//! # Tolerance
//!
//! A metric regresses when it is worse than its baseline by more than
//! `max(abs, rel · |baseline|)`; better by more than that is reported as an
//! improvement and never fails; informational metrics are reported when they
//! change. `rel` defaults to [`crate::scenario::regression::DEFAULT_REL`];
//! `abs`, the metric's floor, to
//! [`crate::scenario::regression::default_floor`]: 10 % of the metric's
//! gate, else its unit's floor. A scenario's `[regression]` table overrides
//! both, for all its metrics or per metric.
//!
//! # Meaning
//!
//! Metrics that mean nothing for a run ([`RunOutcome::meaningful`], n/a in
//! the results table) are neither written nor compared.
//!
//! NaN: NaN now with a finite baseline is a regression (e.g. a time to goal
//! that is no longer reached); a finite value with a NaN baseline is an
//! improvement; NaN on both sides is unchanged. A metric in the baseline that
//! the run no longer produces is a regression; a new metric is reported only.

use crate::error::Error;
pub use crate::metric::Direction;
use crate::numfmt::fmt_value;
use crate::runner::RunOutcome;
use crate::scenario::regression::RegressionConfig;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Version of the baseline file format.
pub const FORMAT: u64 = 1;

/// The direction of metric `name`, from its row ([`crate::robots::metric`]);
/// a name without a row is only reported.
pub fn direction(name: &str) -> Direction {
    crate::robots::metric(name).map_or(Direction::Informational, |r| r.direction)
}

/// The committed metrics of one scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Baseline {
    /// Scenario name (also the file stem).
    pub scenario: String,
    /// Planner kind.
    pub planner: String,
    /// Metric → value (NaN allowed).
    pub metrics: BTreeMap<String, f64>,
}

/// The default absolute floor of metric `name` in scenario `sc` (module
/// docs): its gate is its `[thresholds]` or `[minimums]` value; `spec`
/// gives its unit.
pub fn floor_of(
    sc: &crate::scenario::Scenario,
    spec: &crate::compare::MetricSpec<'_>,
    name: &str,
) -> f64 {
    let gate = sc.thresholds.get(name).or(sc.minimums.get(name)).copied();
    crate::scenario::regression::default_floor(gate, crate::robots::metric_unit(name, spec))
}

/// `<dir>/<scenario>.json`.
pub fn path_for(dir: &Path, scenario: &str) -> PathBuf {
    dir.join(format!("{scenario}.json"))
}

/// Why a baseline file could not be written.
#[derive(Debug, thiserror::Error)]
pub enum WriteError {
    /// Its directory cannot be created.
    #[error("cannot create {}: {source}", crate::echo::path(dir))]
    CreateDir {
        /// The directory.
        dir: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// Writing the file (through a temporary one) failed.
    #[error(transparent)]
    Write(#[from] crate::log::LogError),
}

impl Baseline {
    /// The baseline a run would write.
    pub fn from_outcome(o: &RunOutcome) -> Baseline {
        Baseline {
            scenario: o.name.clone(),
            planner: o.planner.clone(),
            metrics: o
                .metrics
                .iter()
                .filter(|(k, _)| o.meaningful(k))
                .cloned()
                .collect(),
        }
    }

    /// Pretty JSON, metrics sorted by name, NaN as `null`, trailing newline.
    pub fn to_json(&self) -> String {
        let q = |s: &str| Value::String(s.into()).to_string();
        let mut s = format!(
            "{{\n  \"anholonomy_baseline\": {FORMAT},\n  \"scenario\": {},\n  \"planner\": {},\n  \"metrics\": {{",
            q(&self.scenario),
            q(&self.planner)
        );
        for (i, (k, v)) in self.metrics.iter().enumerate() {
            // JSON has no infinities: ±∞ (e.g. the clearance of a run
            // without obstacles) is the string "inf" / "-inf", NaN is null.
            let v = match serde_json::Number::from_f64(*v) {
                Some(n) => Value::Number(n),
                None if v.is_infinite() => {
                    Value::String(if *v > 0.0 { "inf" } else { "-inf" }.into())
                }
                None => Value::Null,
            };
            s.push_str(if i == 0 { "\n" } else { ",\n" });
            s.push_str(&format!("    {}: {v}", q(k)));
        }
        s.push_str("\n  }\n}\n");
        s
    }

    /// Write atomically (temporary file, then rename), creating the directory.
    pub fn write(&self, path: &Path) -> Result<(), WriteError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| WriteError::CreateDir {
                dir: dir.to_path_buf(),
                source,
            })?;
        }
        let text = self.to_json();
        crate::log::atomic::write_file(path, |w| std::io::Write::write_all(w, text.as_bytes()))?;
        Ok(())
    }

    /// Read and check a baseline file for `scenario` / `planner`; every problem is an input
    /// error naming the file, the line and the key.
    pub fn load(path: &Path, scenario: &str, planner: &str) -> Result<Baseline, Error> {
        let text = std::fs::read_to_string(path).map_err(|e| {
            let hint = if e.kind() == std::io::ErrorKind::NotFound {
                format!(
                    "no baseline for scenario `{scenario}` (write it with `anholonomy baseline <scenario file> --baseline {}`)",
                    path.parent().map(crate::echo::path).unwrap_or_default()
                )
            } else {
                format!("cannot read baseline: {e}")
            };
            Error::input(path, hint)
        })?;
        Self::parse(path, &text, scenario, planner)
    }

    /// [`Baseline::load`] on text.
    pub fn parse(
        path: &Path,
        text: &str,
        scenario: &str,
        planner: &str,
    ) -> Result<Baseline, Error> {
        let bad =
            |key: &str, message: String| Error::keyed(path, line_of_key(text, key), key, message);
        let doc: Value = serde_json::from_str(text).map_err(|e| Error::Input {
            key: None,
            path: path.into(),
            line: Some(e.line()),
            message: format!("not a baseline file: {e}"),
        })?;
        let obj = doc.as_object().ok_or_else(|| Error::Input {
            key: None,
            path: path.into(),
            line: Some(1),
            message: "not a baseline file: expected a JSON object".into(),
        })?;
        for k in obj.keys() {
            if !matches!(
                k.as_str(),
                "anholonomy_baseline" | "scenario" | "planner" | "metrics"
            ) {
                return Err(bad(k, "unknown key in a baseline file".into()));
            }
        }
        match obj.get("anholonomy_baseline").and_then(Value::as_u64) {
            Some(FORMAT) => {}
            Some(v) => {
                return Err(bad(
                    "anholonomy_baseline",
                    format!("format {v} is not supported (expected {FORMAT})"),
                ))
            }
            None => {
                return Err(bad(
                    "anholonomy_baseline",
                    format!("missing or not a number (expected {FORMAT})"),
                ))
            }
        }
        let string = |key: &str| -> Result<String, Error> {
            obj.get(key)
                .and_then(Value::as_str)
                .map(String::from)
                .ok_or_else(|| bad(key, "missing or not a string".into()))
        };
        let (sc, pl) = (string("scenario")?, string("planner")?);
        if sc != scenario {
            return Err(bad(
                "scenario",
                format!("this baseline is for scenario `{sc}`, not `{scenario}`"),
            ));
        }
        if pl != planner {
            return Err(bad(
                "planner",
                format!("this baseline is for planner `{pl}`, the scenario uses `{planner}`"),
            ));
        }
        let m = obj
            .get("metrics")
            .and_then(Value::as_object)
            .ok_or_else(|| bad("metrics", "missing or not an object".into()))?;
        let mut metrics = BTreeMap::new();
        for (k, v) in m {
            let x = match v {
                Value::Null => f64::NAN,
                Value::Number(n) => n.as_f64().unwrap_or(f64::NAN),
                Value::String(t) if t == "inf" => f64::INFINITY,
                Value::String(t) if t == "-inf" => f64::NEG_INFINITY,
                _ => return Err(bad(k, "must be a number, \"inf\", \"-inf\" or null".into())),
            };
            metrics.insert(k.clone(), x);
        }
        Ok(Baseline {
            scenario: sc,
            planner: pl,
            metrics,
        })
    }
}

/// 1-based line of `name = ...` (or `name.`) in a TOML file, for error messages.
pub fn toml_key_line(path: &Path, name: &str) -> Option<usize> {
    let text = std::fs::read_to_string(path).ok()?;
    text.lines()
        .position(|l| {
            let l = l.trim_start();
            let l = l.strip_prefix("metrics.").unwrap_or(l);
            l.strip_prefix(name)
                .is_some_and(|rest| rest.trim_start().starts_with(['=', '.']))
        })
        .map(|i| i + 1)
}

/// 1-based line of the first `"key":` in a JSON text.
fn line_of_key(text: &str, key: &str) -> Option<usize> {
    let needle = format!("\"{key}\"");
    text.find(&needle)
        .map(|at| text[..at].bytes().filter(|&b| b == b'\n').count() + 1)
}

/// What happened to one metric.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    /// Within tolerance.
    Unchanged,
    /// Worse than the baseline by more than the tolerance: fails `check`.
    Regressed,
    /// Better by more than the tolerance: reported only.
    Improved,
    /// An informational metric changed: reported only.
    Changed,
    /// In the baseline, not produced by the run: fails `check`.
    Missing,
    /// Produced by the run, not in the baseline: reported only.
    New,
}

impl Status {
    /// Does this status fail `check --baseline`?
    pub fn fails(self) -> bool {
        matches!(self, Status::Regressed | Status::Missing)
    }
}

/// One metric compared with its baseline.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Delta {
    /// Metric name.
    pub metric: String,
    /// Its direction.
    pub direction: Direction,
    /// Baseline value (None: not in the baseline).
    pub baseline: Option<f64>,
    /// Value now (None: not produced).
    pub now: Option<f64>,
    /// The tolerance that applied, max(abs, rel·|baseline|).
    pub tolerance: f64,
    /// Verdict.
    pub status: Status,
    /// Human-readable change ("+102.4 %", "NaN", ...).
    pub change: String,
}

/// Verdict for one value pair (module docs).
pub fn judge(dir: Direction, base: f64, now: f64, rel: f64, abs: f64) -> (Status, f64) {
    let tol = abs.max(rel * base.abs());
    if base == now || (base.is_nan() && now.is_nan()) {
        return (Status::Unchanged, tol);
    }
    let status = if dir == Direction::Informational {
        if base.is_nan() || now.is_nan() || (now - base).abs() > tol {
            Status::Changed
        } else {
            Status::Unchanged
        }
    } else if now.is_nan() {
        Status::Regressed
    } else if base.is_nan() {
        Status::Improved
    } else {
        let worse = match dir {
            Direction::HigherIsBetter => base - now,
            _ => now - base,
        };
        if worse > tol {
            Status::Regressed
        } else if -worse > tol {
            Status::Improved
        } else {
            Status::Unchanged
        }
    };
    (status, tol)
}

/// The change from `base` to `now` as text: relative when the baseline is non-zero.
pub(crate) fn change_text(base: Option<f64>, now: Option<f64>) -> String {
    match (base, now) {
        (None, _) => "new metric".into(),
        (_, None) => "no longer produced".into(),
        (Some(b), Some(n)) if b.is_nan() || n.is_nan() => {
            format!("{} → {}", fmt_value(b), fmt_value(n))
        }
        (Some(b), Some(n)) if b == n => "0".into(),
        (Some(b), Some(n)) if b != 0.0 && b.is_finite() => {
            // Readable at any size: a runaway metric's change is `+1e302 %`.
            let pct = 100.0 * (n - b) / b.abs();
            if pct.abs() < 1e6 {
                format!("{pct:+.1} %")
            } else {
                format!(
                    "{}{} %",
                    if pct > 0.0 { "+" } else { "" },
                    crate::numfmt::readable(pct)
                )
            }
        }
        (Some(b), Some(n)) => format!("{:+.4e}", n - b),
    }
}

/// Compare a run with its baseline; `dir` gives each metric's direction,
/// `floor` its default absolute floor
/// ([`crate::scenario::regression::default_floor`]). Metrics that mean
/// nothing for the run are left out on both sides.
pub fn compare(
    base: &Baseline,
    o: &RunOutcome,
    cfg: &RegressionConfig,
    dir: impl Fn(&str) -> Direction,
    floor: impl Fn(&str) -> f64,
) -> Vec<Delta> {
    let now: BTreeMap<&str, f64> = o
        .metrics
        .iter()
        .filter(|(k, _)| o.meaningful(k))
        .map(|(k, v)| (k.as_str(), *v))
        .collect();
    let mut names: Vec<&str> = base
        .metrics
        .keys()
        .map(String::as_str)
        .filter(|k| o.meaningful(k))
        .collect();
    names.extend(now.keys().filter(|k| !base.metrics.contains_key(**k)));
    names.sort_unstable();
    names
        .into_iter()
        .map(|m| {
            let d = dir(m);
            let (rel, abs) = cfg.tolerance(m, floor(m));
            let (b, n) = (base.metrics.get(m).copied(), now.get(m).copied());
            let (status, tolerance) = match (b, n) {
                (Some(b), Some(n)) => judge(d, b, n, rel, abs),
                (Some(b), None) => (Status::Missing, abs.max(rel * b.abs())),
                (None, _) => (Status::New, abs),
            };
            Delta {
                metric: m.to_string(),
                direction: d,
                baseline: b,
                now: n,
                tolerance,
                status,
                change: change_text(b, n),
            }
        })
        .collect()
}

/// The table of everything that is not unchanged: scenario / metric / baseline / now / change.
pub fn format_table(rows: &[(String, Vec<Delta>)]) -> String {
    let opt = |v: Option<f64>| v.map(fmt_value).unwrap_or_else(|| "-".into());
    let mut out = format!(
        "{:<30} {:<36} {:>7} {:>14} {:>14} {:>18}  verdict\n",
        "scenario", "metric", "better", "baseline", "now", "change"
    );
    let mut any = false;
    for (scenario, deltas) in rows {
        for d in deltas.iter().filter(|d| d.status != Status::Unchanged) {
            any = true;
            out.push_str(&format!(
                "{:<30} {:<36} {:>7} {:>14} {:>14} {:>18}  {}\n",
                scenario,
                d.metric,
                d.direction.symbol(),
                opt(d.baseline),
                opt(d.now),
                d.change,
                match d.status {
                    Status::Regressed =>
                        format!("REGRESSED (tolerance {})", fmt_value(d.tolerance)),
                    Status::Missing => "REGRESSED (missing)".into(),
                    Status::Improved => "improved".into(),
                    Status::Changed => "changed (informational)".into(),
                    Status::New => "new (not in baseline)".into(),
                    Status::Unchanged => String::new(),
                }
            ));
        }
    }
    if !any {
        out.push_str("(every metric within tolerance of its baseline)\n");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::regression::{DEFAULT_ABS, DEFAULT_REL};
    use proptest::prelude::*;
    use Direction::*;

    #[test]
    fn nan_rules() {
        let j = |b, n| judge(LowerIsBetter, b, n, 0.02, 1e-9).0;
        assert_eq!(j(1.0, f64::NAN), Status::Regressed);
        assert_eq!(j(f64::NAN, 1.0), Status::Improved);
        assert_eq!(j(f64::NAN, f64::NAN), Status::Unchanged);
        assert_eq!(j(f64::INFINITY, f64::INFINITY), Status::Unchanged);
        assert_eq!(j(1.0, f64::INFINITY), Status::Regressed);
        assert_eq!(
            judge(Informational, 100.0, f64::NAN, 0.0, 0.0).0,
            Status::Changed
        );
    }

    fn outcome(metrics: &[(&str, f64)]) -> RunOutcome {
        RunOutcome {
            name: "s".into(),
            planner: "p".into(),
            passed: true,
            verdict: crate::verdict::Verdict::Pass,
            expect_reason: None,
            tracking_meaningful: true,
            failures: vec![],
            metrics: metrics.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
            steps: 0,
            timings: Default::default(),
            log_dir: None,
            notes: Vec::new(),
            plan_note: None,
        }
    }

    #[test]
    fn missing_and_new_metrics() {
        let base = Baseline::from_outcome(&outcome(&[("a", 1.0), ("b", 2.0)]));
        let d = compare(
            &base,
            &outcome(&[("a", 1.0), ("c", 3.0)]),
            &RegressionConfig::default(),
            |_: &str| LowerIsBetter,
            |_: &str| DEFAULT_ABS,
        );
        let st: Vec<(&str, Status)> = d.iter().map(|d| (d.metric.as_str(), d.status)).collect();
        assert_eq!(
            st,
            [
                ("a", Status::Unchanged),
                ("b", Status::Missing),
                ("c", Status::New)
            ]
        );
    }

    #[test]
    fn na_metrics_are_neither_written_nor_compared() {
        let mut o = outcome(&[("sim_goal_position", 1e-3), ("tracking_x_max", 4e-3)]);
        o.tracking_meaningful = false;
        let b = Baseline::from_outcome(&o);
        assert_eq!(b.metrics.keys().collect::<Vec<_>>(), ["sim_goal_position"]);
        // A baseline written before still holds it: not compared, not missing.
        let mut old = b.clone();
        old.metrics.insert("tracking_x_max".into(), 1e-3);
        let mut now = o;
        now.metrics.push(("tracking_y_max".into(), 9.0));
        let d = compare(&old, &now, &RegressionConfig::default(), direction, |_| {
            1e-9
        });
        let names: Vec<&str> = d.iter().map(|d| d.metric.as_str()).collect();
        assert_eq!(names, ["sim_goal_position"]);
        assert_eq!(d[0].status, Status::Unchanged);
    }

    #[test]
    fn floors_come_from_the_gate_else_the_unit() {
        use crate::scenario::regression::{default_floor, unit_floor};
        assert_eq!(unit_floor("m"), 1e-4);
        assert_eq!(unit_floor("°"), 0.01);
        assert_eq!(unit_floor("m/s"), 1e-3);
        assert_eq!(unit_floor("s"), 0.01);
        assert_eq!(unit_floor(""), DEFAULT_ABS);
        // A gate of 5 mm/s: changes below 0.5 mm/s never regress.
        assert!((default_floor(Some(0.005), "m/s") - 5e-4).abs() < 1e-15);
        assert_eq!(default_floor(Some(f64::INFINITY), "s"), 0.01);
        assert_eq!(default_floor(Some(0.0), "m"), 1e-4);
        // The worked example of docs/src/operations/ci-gates.md: lateral
        // slip 1.1 → 1.5 mm/s under a 5 mm/s gate is unchanged (0.4 < 0.5),
        // 1.1 → 2.3 mm/s regresses; a goal 0.05 mm further off is unchanged
        // (0.1 mm floor) although it is +500 %.
        let slip = default_floor(Some(0.005), "m/s");
        assert_eq!(
            judge(LowerIsBetter, 1.1e-3, 1.5e-3, DEFAULT_REL, slip).0,
            Status::Unchanged
        );
        assert_eq!(
            judge(LowerIsBetter, 1.1e-3, 2.3e-3, DEFAULT_REL, slip).0,
            Status::Regressed
        );
        let goal = default_floor(None, "m");
        assert_eq!(
            judge(LowerIsBetter, 1e-5, 6e-5, DEFAULT_REL, goal).0,
            Status::Unchanged
        );
        // A 13 % longer time to goal without a gate: 10 ms floor, 2 % of 15.2 s.
        let t = default_floor(None, "s");
        assert_eq!(
            judge(LowerIsBetter, 15.2, 15.2 * 1.13, DEFAULT_REL, t).0,
            Status::Regressed
        );
        assert_eq!(
            judge(LowerIsBetter, 15.2, 15.2 * 1.01, DEFAULT_REL, t).0,
            Status::Unchanged
        );
    }

    #[test]
    fn per_metric_override_beats_scenario_beats_default() {
        let cfg: RegressionConfig =
            toml::from_str("rel = 0.5\nmetrics.x = { abs = 2.0 }\n").unwrap();
        assert_eq!(cfg.tolerance("x", 1e-4), (0.5, 2.0));
        assert_eq!(cfg.tolerance("y", 1e-4), (0.5, 1e-4));
        assert_eq!(
            RegressionConfig::default().tolerance("y", DEFAULT_ABS),
            (DEFAULT_REL, DEFAULT_ABS)
        );
        assert!(toml::from_str::<RegressionConfig>("bogus = 1").is_err());
        let bad: RegressionConfig = toml::from_str("metrics.x = { rel = -1.0 }").unwrap();
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("regression.metrics.x.rel"));
    }

    #[test]
    fn file_round_trip_and_identity_checks() {
        let mut b = Baseline::from_outcome(&outcome(&[("z", 0.1), ("a", f64::NAN)]));
        b.metrics.insert("m".into(), 1e-300);
        let text = b.to_json();
        assert!(text.find("\"a\"").unwrap() < text.find("\"z\"").unwrap());
        let p = Path::new("b.json");
        let back = Baseline::parse(p, &text, "s", "p").unwrap();
        assert!(back.metrics["a"].is_nan());
        let mut inf = Baseline::parse(p, &text, "s", "p").unwrap();
        inf.metrics.insert("c".into(), f64::INFINITY);
        inf.metrics.insert("d".into(), f64::NEG_INFINITY);
        let again = Baseline::parse(p, &inf.to_json(), "s", "p").unwrap();
        assert_eq!(again.metrics["c"], f64::INFINITY);
        assert_eq!(again.metrics["d"], f64::NEG_INFINITY);
        assert_eq!(back.metrics["z"], 0.1);
        assert_eq!(back.metrics["m"], 1e-300);
        let e = Baseline::parse(p, &text, "other", "p")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("b.json:3: key `scenario`"), "{e}");
        let e = Baseline::parse(p, &text, "s", "q").unwrap_err().to_string();
        assert!(e.contains("key `planner`"), "{e}");
        let e = Baseline::parse(
            p,
            "{\"anholonomy_baseline\": 1,\n  \"scenario\": [",
            "s",
            "p",
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("b.json:2: not a baseline file"), "{e}");
    }

    proptest! {
        #![proptest_config(crate::prop_config::config(256))]
        /// Against an independent formulation: the verdict from the signed
        /// relative change and the direction.
        #[test]
        fn verdict_matches_signed_change(
            base in -1e3f64..1e3, factor in -3.0f64..3.0, rel in 0.0f64..0.5,
            higher in any::<bool>(),
        ) {
            let now = base + factor * base.abs() * 0.3;
            let dir = if higher { HigherIsBetter } else { LowerIsBetter };
            let (st, tol) = judge(dir, base, now, rel, 1e-9);
            let gain = if higher { now - base } else { base - now };
            let expect = if gain < -tol {
                Status::Regressed
            } else if gain > tol {
                Status::Improved
            } else {
                Status::Unchanged
            };
            prop_assert_eq!(st, expect);
            // Swapping the direction swaps regression and improvement.
            let flip = if higher { LowerIsBetter } else { HigherIsBetter };
            let (st2, _) = judge(flip, base, now, rel, 1e-9);
            let swapped = match st {
                Status::Regressed => Status::Improved,
                Status::Improved => Status::Regressed,
                s => s,
            };
            prop_assert_eq!(st2, swapped);
        }
    }
}
