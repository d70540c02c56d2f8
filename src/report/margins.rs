//! The margins section of a scenario page (from `margins.json`): the table,
//! and per dimension the breaking metric against the perturbation, each run
//! a point coloured by pass/fail, with the gate's bound.

use crate::engine::perturb::Dimension;
use crate::margin::output::magnitude;
use crate::report::plots::{self, PlotError};
use serde_json::Value;
use std::fmt::Write as _;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The value of gate `metric` in a run (NaN when absent or null).
fn gate_value(run: &Value, metric: &str) -> f64 {
    run["gates"][metric].as_f64().unwrap_or(f64::NAN)
}

/// The section's HTML.
pub fn section(m: &Value) -> Result<String, PlotError> {
    let dims = m["dimensions"].as_array().cloned().unwrap_or_default();
    let s = &m["search"];
    let mut b = format!(
        "<h2>Robustness margins</h2><p class=\"muted\">For each perturbation (the others nominal): the largest magnitude at which every gate still holds, bisected to {:.0} % (the edge lies between the margin and the first failing level); random dimensions: {} seeds per level, passing at ≥ {:.0} % of them. Factors are searched downwards (torque, friction, wheel radius) or upwards (mass) from 1.</p>",
        100.0 * s["resolution"].as_f64().unwrap_or(f64::NAN),
        s["seeds"].as_u64().unwrap_or(0),
        100.0 * s["success_rate"].as_f64().unwrap_or(f64::NAN),
    );
    b.push_str("<table><tr><th class=\"l\">dimension</th><th>margin</th><th>gate</th><th>first failing level</th><th class=\"l\">first gate broken beyond it</th><th>runs</th><th class=\"l\">note</th></tr>");
    let gates = &m["gates"];
    let mut figures = String::new();
    for d in &dims {
        let name = d["dimension"].as_str().unwrap_or("?");
        let Some(dim) = Dimension::parse(name) else {
            continue;
        };
        let margin = d["margin"].as_f64().unwrap_or(f64::NAN);
        let status = d["status"].as_str().unwrap_or("");
        let shown = match status {
            "ceiling" => format!("≥ {}", magnitude(dim, margin)),
            "below_floor" => "below the floor".into(),
            "nominal_fails" => "none".into(),
            "budget" if d["first_failing"].is_null() => format!("≥ {}", magnitude(dim, margin)),
            "budget" if margin == 0.0 => "below the first failing level".into(),
            "holds" => format!("≥ {}", magnitude(dim, margin)),
            "breaks" => match d["first_failing"].as_f64() {
                Some(g) => format!("< {}", magnitude(dim, g)),
                None => "none".into(),
            },
            _ => magnitude(dim, margin),
        };
        let gate = gates[name].as_f64();
        let gate_cell = match gate {
            Some(g) if margin >= g && status != "breaks" && status != "nominal_fails" => {
                format!("≥ {} <span class=\"pass\">ok</span>", magnitude(dim, g))
            }
            Some(g) => format!("≥ {} <span class=\"fail\">FAIL</span>", magnitude(dim, g)),
            None => "–".into(),
        };
        let broken = d["first_broken"]
            .as_array()
            .and_then(|a| a.first())
            .map(|x| {
                let g = crate::gate::Breach {
                    metric: x["metric"].as_str().unwrap_or("").into(),
                    value: x["value"].as_f64().unwrap_or(f64::NAN),
                    bound: x["bound"].as_f64().unwrap_or(f64::NAN),
                    minimum: x["minimum"].as_bool().unwrap_or(false),
                };
                g.to_string()
            })
            .unwrap_or_else(|| "–".into());
        let mut note = Vec::new();
        if d["non_monotone"].as_bool() == Some(true) {
            let pairs: Vec<String> = d["inversions"]
                .as_array()
                .into_iter()
                .flatten()
                .take(3)
                .map(|p| {
                    format!(
                        "fails at {}, passes at {}",
                        magnitude(dim, p[0].as_f64().unwrap_or(f64::NAN)),
                        magnitude(dim, p[1].as_f64().unwrap_or(f64::NAN))
                    )
                })
                .collect();
            note.push(format!(
                "<span class=\"fail\">non-monotone</span>: {}",
                pairs.join("; ")
            ));
        }
        match status {
            "ceiling" => note.push("never broke up to the search's ceiling".into()),
            "below_floor" => note.push("broke at every level searched".into()),
            "nominal_fails" => note.push("the nominal run already fails".into()),
            "budget" => note.push(
                "the run budget ended the search: the edge is known only to the levels shown"
                    .into(),
            ),
            "holds" | "breaks" => note.push(
                "a gate of `run`/`check`: one level run at the gate, not searched (`anholonomy margin` searches)"
                    .into(),
            ),
            _ => {}
        }
        let _ = write!(
            b,
            "<tr><td class=\"l\">{name}</td><td>{}</td><td>{gate_cell}</td><td>{}</td><td class=\"l\">{}</td><td>{}</td><td class=\"l\">{}</td></tr>",
            esc(&shown),
            d["first_failing"]
                .as_f64()
                .map(|x| esc(&magnitude(dim, x)))
                .unwrap_or_else(|| "–".into()),
            esc(&broken),
            d["runs"].as_u64().unwrap_or(0),
            note.join("; ")
        );
        figures.push_str(&figure(m, d, dim)?);
    }
    b.push_str("</table><div class=\"grid\">");
    b.push_str(&figures);
    b.push_str("</div>");
    Ok(b)
}

/// The breaking metric against the level (log scale), one point per run,
/// pass green, fail red; non-finite values (e.g. a goal never reached)
/// drawn at the top. The nominal run (level 0) is in the table.
fn figure(m: &Value, d: &Value, dim: Dimension) -> Result<String, PlotError> {
    let Some(metric) = d["breaking_metric"].as_str() else {
        return Ok(String::new());
    };
    let bound = m["thresholds"][metric]
        .as_f64()
        .or_else(|| m["minimums"][metric].as_f64());
    let mut pts: Vec<(f64, f64, bool)> = Vec::new();
    for l in d["levels"].as_array().into_iter().flatten() {
        let x = l["level"].as_f64().unwrap_or(f64::NAN);
        for r in l["runs"].as_array().into_iter().flatten() {
            pts.push((
                x,
                gate_value(r, metric),
                r["passed"].as_bool() == Some(true),
            ));
        }
    }
    let top = pts
        .iter()
        .map(|p| p.1)
        .chain(bound)
        .filter(|v| v.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    let top = if top.is_finite() {
        top * 1.15 + 1e-12
    } else {
        1.0
    };
    let nan = pts.iter().any(|p| !p.1.is_finite());
    for p in &mut pts {
        if !p.1.is_finite() {
            p.1 = top;
        }
    }
    let unit = match dim.unit() {
        "" => String::new(),
        u => format!(" ({u})"),
    };
    let title = format!(
        "{} vs {}{}",
        metric,
        dim.name(),
        if nan { " (NaN at top)" } else { "" }
    );
    plots::scatter_log_x(
        &title,
        &format!("{} magnitude{unit}", dim.name()),
        metric,
        &pts,
        bound.map(|b| (b, "gate")),
    )
}
