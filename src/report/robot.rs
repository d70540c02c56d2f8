//! The scenario page's "Robot as read from the URDF" section: what the
//! physics took from the description (`summary.json`'s
//! `model.read_from_urdf`), so the user can confirm it was read right.

use crate::report::markup::esc;
use serde_json::Value;
use std::fmt::Write as _;

/// A number as the user wrote it (`0.04`, not `0.040000`).
fn num(v: Option<f64>) -> String {
    v.map_or("–".into(), crate::numfmt::readable)
}

/// The section, or nothing for logs without a reading (older runs).
pub(super) fn section(summary: &Value) -> String {
    let r = &summary["model"]["read_from_urdf"];
    let Some(bodies) = r["bodies"].as_array() else {
        return String::new();
    };
    let mut b = String::from("<h2>Robot as read from the URDF</h2>");
    for w in r["warnings"].as_array().into_iter().flatten() {
        let _ = write!(
            b,
            "<p class=\"fail\">warning: {}</p>",
            esc(w.as_str().unwrap_or(""))
        );
    }
    for n in r["notes"].as_array().into_iter().flatten() {
        let _ = write!(
            b,
            "<p class=\"muted\">note: {}</p>",
            esc(n.as_str().unwrap_or(""))
        );
    }
    b.push_str("<table><tr><th class=\"l\">body</th><th>mass, kg</th><th class=\"l\">links lumped into it</th></tr>");
    for x in bodies {
        let lumped: Vec<&str> = x["lumped"]
            .as_array()
            .into_iter()
            .flatten()
            .filter_map(Value::as_str)
            .collect();
        let _ = write!(
            b,
            "<tr><td class=\"l\">{}</td><td>{}</td><td class=\"l\">{}</td></tr>",
            esc(x["link"].as_str().unwrap_or("")),
            num(x["mass"].as_f64()),
            esc(&lumped.join(", "))
        );
    }
    b.push_str("</table>");
    if let Some(ws) = r["wheels"].as_array() {
        b.push_str("<table><tr><th class=\"l\">wheel joint</th><th class=\"l\">link</th><th class=\"l\">collision</th><th>radius, m</th><th>centre in the body, m</th></tr>");
        for w in ws {
            let c: Vec<String> = w["center"]
                .as_array()
                .into_iter()
                .flatten()
                .map(|v| num(v.as_f64()))
                .collect();
            let _ = write!(
                b,
                "<tr><td class=\"l\">{}</td><td class=\"l\">{}</td><td class=\"l\">{}</td><td>{}</td><td>({})</td></tr>",
                esc(w["joint"].as_str().unwrap_or("")),
                esc(w["link"].as_str().unwrap_or("")),
                esc(w["shape"].as_str().unwrap_or("")),
                num(w["radius"].as_f64()),
                c.join(", ")
            );
        }
        b.push_str("</table>");
    }
    if let Some(ds) = r["drives"].as_array() {
        b.push_str("<table><tr><th class=\"l\">drive</th><th>torque limit, N·m</th><th class=\"l\">from</th></tr>");
        for d in ds {
            let from = match d["source"].as_str() {
                Some("urdf") => "URDF &lt;limit effort&gt;",
                Some("model") => "[model]",
                Some("scenario") => "[sim] motor_max_torque",
                _ => "default: [sim] motor_max_torque",
            };
            let _ = write!(
                b,
                "<tr><td class=\"l\">{}</td><td>{}</td><td class=\"l\">{from}</td></tr>",
                esc(d["joint"].as_str().unwrap_or("")),
                num(d["torque_limit"].as_f64()),
            );
        }
        b.push_str("</table>");
    }
    if let Some(g) = r["geometry"].as_array() {
        b.push_str("<p>");
        let items: Vec<String> = g
            .iter()
            .map(|x| {
                let v: Vec<String> = x[1]
                    .as_array()
                    .into_iter()
                    .flatten()
                    .map(|v| num(v.as_f64()))
                    .collect();
                format!("{} = {}", esc(x[0].as_str().unwrap_or("")), v.join(", "))
            })
            .collect();
        b.push_str(&items.join("; "));
        b.push_str("</p>");
    }
    b
}
