//! HTML of the report pages (inline CSS and SVG, no scripts).

use crate::report::figures::{single_figures, sweep_figures};
use crate::report::markup::{esc, num, tracking_meaningful};
use crate::report::{Loaded, RunData, StoredDelta};
use crate::verdict::Verdict;
use serde_json::Value;
use std::collections::BTreeMap;
use std::fmt::Write as _;

const CSS: &str = "body{font-family:sans-serif;margin:1.2em 2em;color:#222;max-width:1240px}\
h1{font-size:1.5em;margin-bottom:.2em}h2{font-size:1.15em;margin-top:1.6em;border-bottom:1px solid #ddd}\
table{border-collapse:collapse;font-size:.86em;margin:.4em 0}td,th{border:1px solid #ddd;padding:2px 7px;text-align:right}\
th{background:#f4f4f4}td.l,th.l{text-align:left}.pass{color:#17803a;font-weight:bold}.fail{color:#c0202a;font-weight:bold}\
.reg{background:#fde2e2}.imp{background:#e2f5e6}.grid{display:flex;flex-wrap:wrap;gap:6px}.grid svg{border:1px solid #eee}\
.seg{display:inline-block;margin-right:1em;font-size:.85em}.seg i{display:inline-block;width:12px;height:12px;margin-right:4px;vertical-align:-1px}\
.muted{color:#777;font-size:.85em}";

fn page(title: &str, body: &str) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{}</title><style>{CSS}</style></head><body>\n{body}\n</body></html>\n",
        esc(title)
    )
}

/// The verdict of a summary or sweep document (older logs: from `passed`).
fn verdict_of(doc: &Value) -> Verdict {
    Verdict::parse(
        doc["verdict"].as_str(),
        doc["passed"].as_bool() == Some(true),
    )
}

/// The verdict as a coloured word; XFAIL carries its reason on hover.
fn verdict(doc: &Value) -> String {
    let v = verdict_of(doc);
    let class = if v.ok() { "pass" } else { "fail" };
    match doc["expect"]["reason"].as_str() {
        Some(r) => format!(
            "<span class=\"{class}\" title=\"expected to fail: {}\">{v}</span>",
            esc(r)
        ),
        None => format!("<span class=\"{class}\">{v}</span>"),
    }
}

/// "expected to fail: REASON" under a verdict, when the scenario expects to fail.
fn expectation(doc: &Value) -> String {
    match (verdict_of(doc), doc["expect"]["reason"].as_str()) {
        (Verdict::Xfail, Some(r)) => format!(
            "<p><b>XFAIL</b>: the thresholds below are broken, as this scenario expects: {}</p>",
            esc(r)
        ),
        (Verdict::Xpass, Some(r)) => format!(
            "<p class=\"fail\">XPASS: every threshold is met, but this scenario is expected to fail ({}). Check what changed: <code>check</code> fails until the scenario shows its limit again or drops <code>expect = \"fails\"</code>.</p>",
            esc(r)
        ),
        _ => String::new(),
    }
}

/// "2 regressed, 1 improved" from a stored comparison.
fn baseline_summary(r: &Option<Vec<StoredDelta>>) -> String {
    let Some(d) = r else {
        return "<span class=\"muted\">not compared</span>".into();
    };
    let count = |s: &str| d.iter().filter(|x| x.status == s).count();
    let (reg, miss, imp) = (count("regressed"), count("missing"), count("improved"));
    if reg + miss + imp == 0 {
        return "within tolerance".into();
    }
    let mut parts = Vec::new();
    if reg + miss > 0 {
        parts.push(format!(
            "<span class=\"fail\">{} regressed</span>",
            reg + miss
        ));
    }
    if imp > 0 {
        parts.push(format!("{imp} improved"));
    }
    parts.join(", ")
}

fn metric(summary: &Value, name: &str) -> Option<f64> {
    summary["metrics"][name].as_f64()
}

/// The coordinate the tables report (as in the CLI table).
fn primary(summary: &Value) -> Option<String> {
    let m = summary["metrics"].as_object()?;
    if m.contains_key("ideal_goal_position") {
        return Some("position".into());
    }
    m.keys()
        .find_map(|k| k.strip_prefix("ideal_goal_").map(String::from))
}

/// The unit of metric `name` as the run wrote it (`units` in its summary,
/// from the metric's row and the model), else none.
fn unit_of<'a>(summary: &'a Value, name: &str) -> &'a str {
    summary["units"][name].as_str().unwrap_or("")
}

/// A number with its unit (`0.0017 m`, `0.51 °`).
fn with_unit(v: Option<f64>, unit: &str) -> String {
    match (v.filter(|v| v.is_finite()), unit) {
        (Some(_), u) if !u.is_empty() => format!("{} {u}", num(v)),
        _ => num(v),
    }
}

/// `LOGDIR/index.html`.
pub(crate) fn index_page(runs: &[Loaded], unreadable: &[crate::error::Error]) -> String {
    let mut b = String::new();
    let verdicts: Vec<Verdict> = runs
        .iter()
        .map(|l| match &l.data {
            RunData::Single { summary, .. } => verdict_of(summary),
            RunData::Sweep(s) => verdict_of(s),
        })
        .collect();
    let count = |v: Verdict| verdicts.iter().filter(|x| **x == v).count();
    let mut counts = vec![format!("{} PASS", count(Verdict::Pass))];
    for v in [Verdict::Fail, Verdict::Xfail, Verdict::Xpass] {
        if count(v) > 0 {
            counts.push(format!("{} {v}", count(v)));
        }
    }
    let _ = write!(
        b,
        "<h1>anholonomy report</h1><p>{} scenarios: {}. XFAIL: broke a threshold as the scenario expects (it shows a limit on purpose); XPASS: met every threshold although expected to fail, which <code>check</code> counts as a failure.</p>\
         <table><tr><th class=\"l\">scenario</th><th class=\"l\">planner</th><th>result</th>\
         <th class=\"l\">key metric</th><th>sim goal error</th><th>tracking max</th><th>wall (s)</th>\
         <th class=\"l\">baseline</th><th class=\"l\">broken thresholds</th></tr>",
        runs.len(),
        counts.join(", ")
    );
    for l in runs {
        let link = format!("<a href=\"{0}/report.html\">{0}</a>", esc(&l.name));
        match &l.data {
            RunData::Single { summary, .. } => {
                let c = primary(summary).unwrap_or_default();
                let fails: Vec<String> = summary["failures"]
                    .as_array()
                    .map(|a| a.iter().filter_map(|f| f.as_str()).map(esc).collect())
                    .unwrap_or_default();
                let _ = write!(
                    b,
                    "<tr><td class=\"l\">{link}</td><td class=\"l\">{}</td><td>{}</td><td class=\"l\">{}</td>\
                     <td>{}</td><td>{}</td><td>{:.2}</td><td class=\"l\">{}</td><td class=\"l\">{}</td></tr>",
                    esc(summary["planner"]["kind"].as_str().unwrap_or("")),
                    verdict(summary),
                    esc(&c),
                    with_unit(
                        metric(summary, &format!("sim_goal_{c}")),
                        unit_of(summary, &format!("sim_goal_{c}"))
                    ),
                    if tracking_meaningful(summary) {
                        with_unit(
                            metric(summary, &format!("tracking_{c}_max")),
                            unit_of(summary, &format!("tracking_{c}_max"))
                        )
                    } else {
                        "<span class=\"muted\" title=\"feedback policy: the runs reach the goal at different times\">n/a</span>".into()
                    },
                    summary["wall_time_s"]["total"].as_f64().unwrap_or(f64::NAN),
                    baseline_summary(&l.regression),
                    fails.join("; ")
                );
            }
            RunData::Sweep(s) => {
                let fails: Vec<String> = s["failures"]
                    .as_array()
                    .map(|a| a.iter().filter_map(|f| f.as_str()).map(esc).collect())
                    .unwrap_or_default();
                let _ = write!(
                    b,
                    "<tr><td class=\"l\">{link}</td><td class=\"l\">sweep</td><td>{}</td><td class=\"l\">success rate {:.1} % ({} variants)</td>\
                     <td>median {}</td><td>–</td><td>{:.2}</td><td class=\"l\">{}</td><td class=\"l\">{}</td></tr>",
                    verdict(s),
                    100.0 * s["success_rate"].as_f64().unwrap_or(f64::NAN),
                    s["variants_run"].as_u64().unwrap_or(0),
                    with_unit(
                        s["final_error"]["median"].as_f64(),
                        {
                            // A sweep's success metric: its row's unit.
                            let m = s["sweep"]["success_metric"].as_str().unwrap_or("");
                            crate::robots::metric(m).map_or("", |r| r.unit.symbol(m))
                        }
                    ),
                    sweep_wall(s),
                    baseline_summary(&l.regression),
                    fails.join("; ")
                );
            }
        }
    }
    for e in unreadable {
        let _ = write!(
            b,
            "<tr><td class=\"l\" colspan=\"9\"><span class=\"fail\">not readable</span> {}</td></tr>",
            esc(&e.to_string())
        );
    }
    b.push_str("</table><p class=\"muted\">Key metric: the planar position (m) when the model has one, else the first state coordinate (angles in degrees); every value carries its unit. Tracking n/a: the plan is a feedback policy, so each run reaches the goal at its own time and the runs differ sample by sample whatever the physics. Baseline: the comparison made by <code>anholonomy check --baseline</code> with this log directory.</p>");
    page("anholonomy report", &b)
}

/// Metrics with thresholds and baseline verdicts.
fn metrics_table(summary: &Value, reg: &Option<Vec<StoredDelta>>) -> String {
    let thresholds = summary["thresholds"].as_object();
    let deltas: BTreeMap<&str, &StoredDelta> = reg
        .iter()
        .flatten()
        .map(|d| (d.metric.as_str(), d))
        .collect();
    let mut b = String::from(
        "<table><tr><th class=\"l\">metric</th><th>value</th><th>threshold</th><th>baseline</th><th>change</th><th class=\"l\">baseline verdict</th></tr>",
    );
    let meaningless = (!tracking_meaningful(summary)).then(|| {
        summary["not_meaningful"]["tracking"]
            .as_str()
            .unwrap_or("not meaningful")
    });
    if let Some(m) = summary["metrics"].as_object() {
        for (k, v) in m {
            if let (Some(why), true) = (meaningless, crate::robots::compares_runs(k)) {
                let _ = write!(
                    b,
                    "<tr><td class=\"l\">{}</td><td class=\"muted\" title=\"{}\">n/a</td><td></td><td></td><td></td><td class=\"l muted\">{}</td></tr>",
                    esc(k),
                    esc(why),
                    esc(why)
                );
                continue;
            }
            let v = v.as_f64();
            let th = thresholds.and_then(|t| t.get(k)).and_then(Value::as_f64);
            let th_cell = match th {
                Some(t) => {
                    let ok = v.is_some_and(|v| v <= t);
                    format!(
                        "<span class=\"{}\">≤ {}</span>",
                        if ok { "pass" } else { "fail" },
                        crate::numfmt::fmt_value(t)
                    )
                }
                None => String::new(),
            };
            let d = deltas.get(k.as_str());
            let class = match d.map(|d| d.status.as_str()) {
                Some("regressed") | Some("missing") => " class=\"reg\"",
                Some("improved") => " class=\"imp\"",
                _ => "",
            };
            let _ = write!(
                b,
                "<tr{class}><td class=\"l\">{}</td><td>{}</td><td>{th_cell}</td><td>{}</td><td>{}</td><td class=\"l\">{}</td></tr>",
                esc(k),
                num(v),
                d.map(|d| num(d.baseline)).unwrap_or_default(),
                d.map(|d| esc(&d.change)).unwrap_or_default(),
                d.map(|d| esc(&d.status)).unwrap_or_default(),
            );
        }
    }
    b.push_str("</table>");
    b
}

/// The paper's printed numbers next to the computed ones.
fn paper_table(rows: &Value) -> String {
    let Some(rows) = rows.as_array().filter(|r| !r.is_empty()) else {
        return String::new();
    };
    let mut b = String::from(
        "<h2>Paper</h2><table><tr><th class=\"l\">quantity</th><th>printed</th><th>computed</th><th class=\"l\">unit</th><th class=\"l\"></th><th class=\"l\">note</th></tr>",
    );
    for r in rows {
        let row: Option<crate::paper::PaperRow> = serde_json::from_value(r.clone()).ok();
        let Some(row) = row else { continue };
        let _ = write!(
            b,
            "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td></tr>",
            esc(&row.quantity),
            esc(&row.printed),
            crate::paper::format_computed(&row),
            esc(&row.unit),
            if row.agrees {
                "<span class=\"pass\">agrees</span>"
            } else {
                "<span class=\"fail\">differs</span>"
            },
            esc(&row.note)
        );
    }
    b.push_str("</table>");
    b
}

/// Why a scenario's page could not be made.
#[derive(Debug, thiserror::Error)]
pub enum PageError {
    /// A chart could not be drawn.
    #[error(transparent)]
    Plot(#[from] crate::report::plots::PlotError),
}

/// `LOGDIR/<scenario>/report.html`.
pub(crate) fn scenario_page(l: &Loaded) -> Result<String, PageError> {
    let mut b = String::from("<p><a href=\"../index.html\">← all scenarios</a></p>");
    match &l.data {
        RunData::Single { summary, series } => {
            let _ = write!(
                b,
                "<h1>{} {}</h1><p>{}</p>{}<p class=\"muted\">model <b>{}</b>, planner <b>{}</b>, {}, {} physics steps, wall {:.2} s. Logs: {}<a href=\"summary.json\">summary.json</a>.</p>",
                esc(&l.name),
                verdict(summary),
                esc(summary["description"].as_str().unwrap_or("")),
                expectation(summary),
                esc(summary["model"]["kind"].as_str().unwrap_or("")),
                esc(summary["planner"]["kind"].as_str().unwrap_or("")),
                durations(summary),
                summary["sim_steps"].as_u64().unwrap_or(0),
                summary["wall_time_s"]["total"].as_f64().unwrap_or(f64::NAN),
                log_links(&l.dir),
            );
            if let Some(f) = summary["failures"].as_array().filter(|f| !f.is_empty()) {
                b.push_str("<p class=\"fail\">Broken thresholds:</p><ul>");
                for x in f {
                    let _ = write!(b, "<li>{}</li>", esc(x.as_str().unwrap_or("")));
                }
                b.push_str("</ul>");
            }
            b.push_str(&paper_table(&summary["paper"]));
            b.push_str(&crate::report::grasp::section(summary, series)?);
            b.push_str(&single_figures(summary, series)?);
            b.push_str("<h2>Metrics</h2>");
            b.push_str(&metrics_table(summary, &l.regression));
            b.push_str(&crate::report::robot::section(summary));
            if let Some(m) = &l.margins {
                b.push_str(&crate::report::margins::section(m)?);
            }
        }
        RunData::Sweep(s) => {
            let _ = write!(
                b,
                "<h1>{} {}</h1>{}<p>Monte Carlo sweep: {} variants, {} successes ({:.1} %; needs ≥ {:.1} %), wall {:.1} s. Final error median {}, p95 {}, max {}; {}.</p>",
                esc(&l.name),
                verdict(s),
                expectation(s),
                s["variants_run"].as_u64().unwrap_or(0),
                s["successes"].as_u64().unwrap_or(0),
                100.0 * s["success_rate"].as_f64().unwrap_or(f64::NAN),
                100.0 * s["sweep"]["min_success_rate"].as_f64().unwrap_or(0.0),
                sweep_wall(s),
                num(s["final_error"]["median"].as_f64()),
                num(s["final_error"]["p95"].as_f64()),
                num(s["final_error"]["max"].as_f64()),
                match s["sweep"]["time_metric"].as_str() {
                    Some(_) => format!(
                        "time to goal median {} s",
                        num(s["time_to_goal"]["median"].as_f64())
                    ),
                    None => "no time metric".into(),
                },
            );
            b.push_str(&sweep_figures(s)?);
            if let Some(d) = &l.regression {
                b.push_str("<h2>Baseline</h2><table><tr><th class=\"l\">metric</th><th>baseline</th><th>now</th><th>change</th><th class=\"l\">verdict</th></tr>");
                for x in d {
                    let _ = write!(
                        b,
                        "<tr><td class=\"l\">{}</td><td>{}</td><td>{}</td><td>{}</td><td class=\"l\">{}</td></tr>",
                        esc(&x.metric),
                        num(x.baseline),
                        num(x.now),
                        esc(&x.change),
                        esc(&x.status)
                    );
                }
                b.push_str("</table>");
            }
        }
    }
    Ok(page(&format!("{} — anholonomy", l.name), &b))
}

/// The runs' simulated durations: "ideal run 157.2 s, physics run 160.3 s"
/// (a feedback policy's plan duration is only its horizon, named as such).
fn durations(summary: &Value) -> String {
    let t = |k: &str| summary[k]["end_time_s"].as_f64();
    let plan = summary["plan"]["duration_s"].as_f64().unwrap_or(f64::NAN);
    let feedback = summary["plan"]["segments"]
        .as_array()
        .is_some_and(|s| s.is_empty());
    match (t("ideal"), t("sim")) {
        (Some(a), Some(b)) => {
            let horizon = if feedback {
                format!(" (feedback policy, horizon {plan:.1} s)")
            } else {
                format!(" (plan {plan:.3} s)")
            };
            format!("ideal run {a:.2} s, physics run {b:.2} s{horizon}")
        }
        _ => format!("plan {plan:.3} s"),
    }
}

/// Links to the 3D logs that are still there (`--keep report` removes them).
fn log_links(dir: &std::path::Path) -> String {
    let mut out = String::new();
    for (f, what) in [("run.rrd", "Rerun"), ("run.mcap", "Foxglove")] {
        if dir.join(f).is_file() {
            let _ = write!(out, "<a href=\"{f}\">{f}</a> ({what}), ");
        }
    }
    out
}

/// A sweep's wall time: `wall_time_s.total` (older logs: a plain number).
fn sweep_wall(s: &Value) -> f64 {
    let w = &s["wall_time_s"];
    w["total"]
        .as_f64()
        .or_else(|| w.as_f64())
        .unwrap_or(f64::NAN)
}
