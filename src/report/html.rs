//! HTML of the report pages (inline CSS and SVG, no scripts).

use super::data::{Series, SeriesFile};
use super::plots::{self, HLine, Line, Marker, Path2, Shade};
use super::{Loaded, RunData, StoredDelta};
use crate::verdict::Verdict;
use serde_json::Value;
use std::collections::BTreeMap;
use std::fmt::Write as _;

const DEG: f64 = 180.0 / std::f64::consts::PI;

const CSS: &str = "body{font-family:sans-serif;margin:1.2em 2em;color:#222;max-width:1240px}\
h1{font-size:1.5em;margin-bottom:.2em}h2{font-size:1.15em;margin-top:1.6em;border-bottom:1px solid #ddd}\
table{border-collapse:collapse;font-size:.86em;margin:.4em 0}td,th{border:1px solid #ddd;padding:2px 7px;text-align:right}\
th{background:#f4f4f4}td.l,th.l{text-align:left}.pass{color:#17803a;font-weight:bold}.fail{color:#c0202a;font-weight:bold}\
.reg{background:#fde2e2}.imp{background:#e2f5e6}.grid{display:flex;flex-wrap:wrap;gap:6px}.grid svg{border:1px solid #eee}\
.seg{display:inline-block;margin-right:1em;font-size:.85em}.seg i{display:inline-block;width:12px;height:12px;margin-right:4px;vertical-align:-1px}\
.muted{color:#777;font-size:.85em}";

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn num(v: Option<f64>) -> String {
    match v {
        None => "–".into(),
        Some(x) => crate::baseline::fmt_value(x),
    }
}

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

/// Whether the run's tracking metrics mean anything (older logs: yes).
fn tracking_meaningful(summary: &Value) -> bool {
    summary["not_meaningful"]["tracking"].is_null()
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

/// `LOGDIR/index.html`.
pub fn index_page(runs: &[Loaded], unreadable: &[crate::error::Error]) -> String {
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
         <th class=\"l\">key metric</th><th>sim goal error</th><th>tracking max</th><th>wall s</th>\
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
                    num(metric(summary, &format!("sim_goal_{c}"))),
                    if tracking_meaningful(summary) {
                        num(metric(summary, &format!("tracking_{c}_max")))
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
                    num(s["final_error"]["median"].as_f64()),
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
    b.push_str("</table><p class=\"muted\">Key metric: the planar position (m) when the model has one, else the first state coordinate (angles in degrees). Tracking n/a: the plan is a feedback policy, so each run reaches the goal at its own time and the runs differ sample by sample whatever the physics. Baseline: the comparison made by <code>anholonomy check --baseline</code> with this log directory.</p>");
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
            if let (Some(why), true) = (meaningless, k.starts_with("tracking_")) {
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
                        crate::baseline::fmt_value(t)
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

fn scaled(s: &Series, scale: f64) -> Vec<Option<f64>> {
    s.v.iter().map(|v| v.map(|x| x as f64 * scale)).collect()
}

fn end_time(sf: &SeriesFile) -> f64 {
    [&sf.ideal, &sf.sim, &sf.errors, &sf.commands, &sf.channels]
        .iter()
        .flat_map(|g| g.iter())
        .filter_map(|s| s.t.last().copied())
        .fold(0.0f32, f32::max) as f64
}

/// Most shaded spans per chart: a feedback policy can switch labels every
/// sample period (hundreds of one-pixel spans, most of a page's bytes).
const MAX_SHADES: usize = 120;

/// Segment shading and the legend that names the colours. More than
/// [`MAX_SHADES`] spans are merged into that many equal time bins, each
/// shaded with the label that covers most of it.
fn shades(sf: &SeriesFile) -> (Vec<Shade>, String) {
    let mut names: Vec<&str> = Vec::new();
    let mut out = Vec::new();
    for s in &sf.segments {
        let k = match names.iter().position(|n| *n == s.label) {
            Some(k) => k,
            None => {
                names.push(&s.label);
                names.len() - 1
            }
        };
        out.push((s.start, s.end, k));
    }
    if out.len() > MAX_SHADES {
        out = bin_shades(&out, MAX_SHADES);
    }
    let mut legend = String::from("<p>Plan segments (shaded in every time plot): ");
    for (k, n) in names.iter().enumerate() {
        let c = plots::label_color(k);
        let _ = write!(
            legend,
            "<span class=\"seg\"><i style=\"background:rgba({},{},{},0.35)\"></i>{}</span>",
            c.0,
            c.1,
            c.2,
            esc(n)
        );
    }
    legend.push_str("</p>");
    (out, legend)
}

/// `spans` merged into `n` equal time bins (each with the label covering
/// most of it), adjacent bins of one label joined.
fn bin_shades(spans: &[Shade], n: usize) -> Vec<Shade> {
    let (t0, t1) = (
        spans.first().map_or(0.0, |s| s.0),
        spans.last().map_or(0.0, |s| s.1),
    );
    let w = (t1 - t0) / n as f64;
    if w <= 0.0 {
        return spans.to_vec();
    }
    let mut out: Vec<Shade> = Vec::new();
    let mut j = 0;
    for b in 0..n {
        let (a, z) = (t0 + b as f64 * w, t0 + (b + 1) as f64 * w);
        let mut cover: Vec<(usize, f64)> = Vec::new();
        while j < spans.len() && spans[j].1 <= a {
            j += 1;
        }
        for s in spans[j..].iter().take_while(|s| s.0 < z) {
            let len = s.1.min(z) - s.0.max(a);
            match cover.iter_mut().find(|(k, _)| *k == s.2) {
                Some(c) => c.1 += len,
                None => cover.push((s.2, len)),
            }
        }
        let Some(&(k, _)) = cover.iter().max_by(|x, y| x.1.total_cmp(&y.1)) else {
            continue;
        };
        match out.last_mut() {
            Some(last) if last.2 == k && (last.1 - a).abs() < 1e-9 => last.1 = z,
            _ => out.push((a, z, k)),
        }
    }
    out
}

/// Display name, scale and unit of state coordinate `i`.
fn coord(sf: &SeriesFile, i: usize) -> (String, f64, &'static str) {
    let name = sf
        .state_names
        .get(i)
        .cloned()
        .unwrap_or_else(|| format!("q{i}"));
    if sf.angular.contains(&i) {
        (name, DEG, "deg")
    } else if sf.position.is_some_and(|p| p.contains(&i)) {
        (name, 1.0, "m")
    } else {
        (name, 1.0, "")
    }
}

fn unit_suffix(u: &str) -> String {
    if u.is_empty() {
        String::new()
    } else {
        format!(" ({u})")
    }
}

fn single_figures(summary: &Value, sf: &SeriesFile) -> Result<String, String> {
    let t_end = end_time(sf);
    let (sh, legend) = shades(sf);
    let th = |k: &str| summary["thresholds"][k].as_f64();
    let mut b = String::new();

    if let Some([ix, iy]) = sf.position {
        let mut paths = Vec::new();
        for o in sf.overlays.iter().filter(|o| o.link.is_none()) {
            paths.push(Path2 {
                name: &o.name,
                points: o.points.iter().map(|p| (p[0], p[1])).collect(),
                color: plotters::style::RGBColor(
                    (o.rgba[0] * 255.0) as u8,
                    (o.rgba[1] * 255.0) as u8,
                    (o.rgba[2] * 255.0) as u8,
                ),
                width: 1,
            });
        }
        let pp = |p: &[[f32; 2]]| p.iter().map(|q| (q[0] as f64, q[1] as f64)).collect();
        paths.push(Path2 {
            name: "ideal",
            points: pp(&sf.path_ideal),
            color: plots::IDEAL,
            width: 3,
        });
        paths.push(Path2 {
            name: "simulated",
            points: pp(&sf.path_sim),
            color: plots::SIM,
            width: 2,
        });
        let at = |q: &[f64]| {
            (
                q.get(ix).copied().unwrap_or(0.0),
                q.get(iy).copied().unwrap_or(0.0),
            )
        };
        let markers = [
            Marker {
                name: "start",
                at: at(&sf.start),
                heading: None,
                color: plots::GREY,
            },
            Marker {
                name: "goal",
                at: at(&sf.goal),
                heading: sf.goal_heading,
                color: plots::RED,
            },
        ];
        b.push_str("<h2>Planar path</h2><div class=\"grid\">");
        b.push_str(&plots::path_chart(&paths, &markers)?);
        b.push_str("</div>");
    }

    b.push_str("<h2>Tracking error (simulated − ideal)</h2>");
    b.push_str(&legend);
    b.push_str("<div class=\"grid\">");
    let errors: &[Series] = if tracking_meaningful(summary) {
        &sf.errors
    } else {
        let _ =
            write!(
            b,
            "<p class=\"muted\">Not shown: {}. Compare the final states and the paths instead.</p>",
            esc(summary["not_meaningful"]["tracking"].as_str().unwrap_or("not meaningful"))
        );
        &[]
    };
    for s in errors {
        let i = sf.state_names.iter().position(|n| *n == s.name);
        let (scale, unit, key) = match i {
            Some(i) => {
                let (_, sc, u) = coord(sf, i);
                let key = if sc == DEG {
                    format!("{}_deg", s.name)
                } else {
                    s.name.clone()
                };
                (sc, u, key)
            }
            None => (1.0, "m", s.name.clone()),
        };
        let mut hl = Vec::new();
        if let Some(m) = th(&format!("tracking_{key}_max")) {
            hl.push(HLine {
                y: m,
                name: format!("max threshold {m}"),
                color: plots::RED,
            });
            // Coordinate errors are signed; position errors (`position`,
            // `position_1`, …) are distances.
            if i.is_some() {
                hl.push(HLine {
                    y: -m,
                    name: String::new(),
                    color: plots::RED,
                });
            }
        }
        if let Some(m) = th(&format!("tracking_{key}_rms")) {
            hl.push(HLine {
                y: m,
                name: format!("rms threshold {m}"),
                color: plots::GREY,
            });
        }
        let line = Line {
            name: format!("error {}", s.name),
            t: &s.t,
            v: scaled(s, scale),
            color: plots::BLUE,
            step: false,
        };
        b.push_str(&plots::time_chart(
            &format!("tracking error: {}{}", s.name, unit_suffix(unit)),
            &format!("{}{}", s.name, unit_suffix(unit)),
            &[line],
            &hl,
            &sh,
            t_end,
        )?);
    }
    b.push_str("</div><h2>State: ideal vs simulated</h2><div class=\"grid\">");
    for (i, (a, s)) in sf.ideal.iter().zip(&sf.sim).enumerate() {
        let (name, scale, unit) = coord(sf, i);
        let lines = [
            Line {
                name: format!("{name} ideal"),
                t: &a.t,
                v: scaled(a, scale),
                color: plots::IDEAL,
                step: false,
            },
            Line {
                name: format!("{name} simulated"),
                t: &s.t,
                v: scaled(s, scale),
                color: plots::SIM,
                step: false,
            },
        ];
        let goal: Vec<HLine> = sf
            .goal
            .get(i)
            .map(|g| HLine {
                y: g * scale,
                name: "goal".into(),
                color: plots::RED,
            })
            .into_iter()
            .collect();
        b.push_str(&plots::time_chart(
            &format!("{name}{}", unit_suffix(unit)),
            &format!("{name}{}", unit_suffix(unit)),
            &lines,
            &goal,
            &sh,
            t_end,
        )?);
    }
    b.push_str("</div><h2>Commands</h2><div class=\"grid\">");
    for (k, c) in sf.commands.iter().enumerate() {
        let title = format!("command: {}", c.name);
        b.push_str(&one_series(
            &title,
            c,
            plots::series_color(k),
            true,
            &sh,
            t_end,
        )?);
    }
    b.push_str("</div>");
    if !sf.channels.is_empty() {
        b.push_str("<h2>Physics channels</h2><div class=\"grid\">");
        for c in &sf.channels {
            b.push_str(&one_series(&c.name, c, plots::BLUE, false, &sh, t_end)?);
        }
        b.push_str("</div>");
    }
    Ok(b)
}

/// A time chart of one series (a command or a channel), unscaled.
fn one_series(
    title: &str,
    c: &Series,
    color: plotters::style::RGBColor,
    step: bool,
    sh: &[Shade],
    t_end: f64,
) -> Result<String, String> {
    let line = Line {
        name: c.name.clone(),
        t: &c.t,
        v: scaled(c, 1.0),
        color,
        step,
    };
    plots::time_chart(title, &c.name, &[line], &[], sh, t_end)
}

fn sweep_figures(s: &Value) -> Result<String, String> {
    let results = s["results"].as_array().cloned().unwrap_or_default();
    let f = |r: &Value, k: &str| r[k].as_f64().unwrap_or(f64::NAN);
    let cfg = &s["sweep"];
    let limit = cfg["success_max"].as_f64();
    let metric = cfg["success_metric"].as_str().unwrap_or("final error");
    let errors: Vec<f64> = results.iter().map(|r| f(r, "final_error")).collect();
    let times: Vec<f64> = results
        .iter()
        .filter(|r| r["success"].as_bool() == Some(true))
        .map(|r| f(r, "time_to_goal"))
        .collect();
    let mut b = String::from("<h2>Distributions</h2><div class=\"grid\">");
    b.push_str(&plots::histogram(
        &format!("final error ({metric})"),
        metric,
        &errors,
        20,
        limit.map(|l| (l, "success limit")),
    )?);
    match cfg["time_metric"].as_str() {
        Some(m) => b.push_str(&plots::histogram(
            &format!("time to goal, {m} (successes)"),
            "t (s)",
            &times,
            20,
            None,
        )?),
        None => b.push_str(
            "<p class=\"muted\">Time to goal: no time metric for this model (set <code>sweep.time_metric</code> to name one).</p>",
        ),
    }
    b.push_str("</div><h2>Success against each randomised parameter</h2><div class=\"grid\">");
    // Every swept parameter: the [sweep.vary] keys (and the friction shorthand) under
    // `params`, and the mass scale.
    let mut keys: Vec<String> = results
        .first()
        .and_then(|r| r["params"].as_object())
        .map(|m| m.keys().map(|k| format!("params/{k}")).collect())
        .unwrap_or_default();
    keys.push("mass_scale".into());
    let param = |r: &Value, key: &str| match key.strip_prefix("params/") {
        Some(k) => r["params"][k].as_f64().unwrap_or(f64::NAN),
        None => f(r, key),
    };
    for key in &keys {
        let label = match key.strip_prefix("params/") {
            Some("sim.friction") => "friction coefficient (sim.friction)".to_string(),
            Some(k) => k.to_string(),
            None => "mass scale".to_string(),
        };
        let label = label.as_str();
        let key = key.as_str();
        let vals: Vec<f64> = results.iter().map(|r| param(r, key)).collect();
        let varied = vals.iter().any(|v| (v - vals[0]).abs() > 1e-12);
        if !varied {
            continue;
        }
        let pts: Vec<(f64, f64, bool)> = results
            .iter()
            .map(|r| {
                (
                    param(r, key),
                    f(r, "final_error"),
                    r["success"].as_bool() == Some(true),
                )
            })
            .collect();
        b.push_str(&plots::scatter(
            &format!("final error vs {label}"),
            label,
            metric,
            &pts,
            limit.map(|l| (l, "success limit")),
        )?);
    }
    if cfg["sigma_rate"].is_number() {
        // The σ signal differs per variant through its seed: plot against the variant index.
        let pts: Vec<(f64, f64, bool)> = results
            .iter()
            .map(|r| {
                (
                    f(r, "index"),
                    f(r, "final_error"),
                    r["success"].as_bool() == Some(true),
                )
            })
            .collect();
        b.push_str(&plots::scatter(
            "final error vs variant (σ seed)",
            "variant index",
            metric,
            &pts,
            limit.map(|l| (l, "success limit")),
        )?);
    }
    b.push_str("</div>");
    let failed: Vec<&Value> = results
        .iter()
        .filter(|r| r["success"].as_bool() != Some(true))
        .collect();
    if !failed.is_empty() {
        b.push_str("<h2>Failed variants</h2><table><tr><th>index</th><th>friction</th><th>mass scale</th><th>final error</th><th class=\"l\">error</th></tr>");
        for r in failed {
            let _ = write!(
                b,
                "<tr><td>{}</td><td>{:.4}</td><td>{:.4}</td><td>{}</td><td class=\"l\">{}</td></tr>",
                r["index"],
                f(r, "friction"),
                f(r, "mass_scale"),
                num(r["final_error"].as_f64()),
                esc(r["error"].as_str().unwrap_or(""))
            );
        }
        b.push_str("</table>");
    }
    Ok(b)
}

/// `LOGDIR/<scenario>/report.html`.
pub fn scenario_page(l: &Loaded) -> Result<String, String> {
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
            b.push_str(&single_figures(summary, series)?);
            b.push_str("<h2>Metrics</h2>");
            b.push_str(&metrics_table(summary, &l.regression));
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

#[cfg(test)]
mod shade_tests {
    use super::bin_shades;

    #[test]
    fn many_spans_become_at_most_n_bins_with_the_dominant_label() {
        // 470 spans of 20 ms alternating 0, 1, 0, 1 ..., with label 2 over [4, 6) s.
        let mut spans = Vec::new();
        for i in 0..470 {
            let (a, b) = (i as f64 * 0.02, (i + 1) as f64 * 0.02);
            let k = if (4.0..6.0).contains(&a) { 2 } else { i % 2 };
            spans.push((a, b, k));
        }
        let out = bin_shades(&spans, 120);
        assert!(out.len() <= 120, "{}", out.len());
        assert_eq!(out.first().unwrap().0, 0.0);
        assert!((out.last().unwrap().1 - 9.4).abs() < 1e-9);
        for w in out.windows(2) {
            assert!((w[0].1 - w[1].0).abs() < 1e-9 && w[0].2 != w[1].2);
        }
        // The long span keeps its label across its bins, merged into one.
        let long: Vec<_> = out.iter().filter(|s| s.2 == 2).collect();
        assert_eq!(long.len(), 1);
        assert!(long[0].0 <= 4.1 && long[0].1 >= 5.9, "{long:?}");
    }
}
