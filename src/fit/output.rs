//! A fit's report as text, as the TOML to paste into the scenario, and as
//! JSON (`--json`).

use crate::fit::{ParamResult, Report, Residual, INTERVAL_RISE};
use crate::numfmt::{readable, with_digits};
use crate::scenario::KeyPath;
use serde_json::json;
use std::fmt::Write as _;

/// `v` with as many decimals as its interval resolves (a tenth of the
/// interval's half-width), six significant digits without one.
pub fn rounded(v: f64, p: &ParamResult) -> String {
    let half = p.interval.map(|[a, b]| 0.5 * (b - a)).filter(|h| *h > 0.0);
    let s = match half {
        Some(h) => {
            let decimals = (-(h / 10.0).log10()).ceil().clamp(0.0, 12.0) as usize;
            format!("{v:.decimals$}")
        }
        None => with_digits(v, 6),
    };
    // A TOML float needs digits on both sides of the point.
    if s.contains(['.', 'e', 'E']) {
        s
    } else {
        format!("{s}.0")
    }
}

/// The TOML that sets the fitted values, table by table.
pub fn toml(r: &Report) -> String {
    let mut tables: Vec<(String, Vec<String>)> = Vec::new();
    let mut push = |table: String, line: String| match tables.iter_mut().find(|(t, _)| *t == table)
    {
        Some((_, lines)) => lines.push(line),
        None => tables.push((table, vec![line])),
    };
    for p in &r.params {
        let v = rounded(p.value, p);
        if p.moves.is_none() {
            continue;
        }
        let Ok(kp) = KeyPath::parse(&p.key) else {
            continue;
        };
        match kp.0.last() {
            Some(crate::scenario::keypath::Segment::Key(k)) => {
                push(kp.prefix(kp.0.len() - 1), format!("{k} = {v}"));
            }
            _ => push(String::new(), format!("# {} = {v}", p.key)),
        }
    }
    if let Some((reference, frame)) = &r.compare {
        let mut lines = vec![format!("reference = {}", toml_string(reference))];
        if let Some(p) = r.params.iter().find(|p| p.moves.is_none()) {
            lines.push(format!("time_offset = {}", rounded(p.value, p)));
        }
        if *frame != crate::recording::align::Frame::Start {
            lines.push(format!("frame = \"{}\"", frame.name()));
        }
        tables.push(("compare".into(), lines));
    }
    let mut out = String::new();
    for (i, (t, lines)) in tables.into_iter().enumerate() {
        if i > 0 {
            out.push('\n');
        }
        if !t.is_empty() {
            let _ = writeln!(out, "[{t}]");
        }
        for l in lines {
            let _ = writeln!(out, "{l}");
        }
    }
    out
}

fn toml_string(s: &str) -> String {
    serde_json::to_string(s).unwrap_or_else(|_| format!("{s:?}"))
}

fn residual_line(b: &Residual, a: &Residual) -> String {
    let mut s = format!(
        "position RMS {} m -> {} m",
        readable(b.position_rms),
        readable(a.position_rms)
    );
    if let (Some(hb), Some(ha)) = (b.heading_rms_deg, a.heading_rms_deg) {
        let _ = write!(s, ", heading RMS {}° -> {}°", readable(hb), readable(ha));
    }
    s
}

/// The report as text: what was compared, the residual before and after,
/// a table of the parameters, the TOML to paste.
pub fn text(r: &Report) -> String {
    let mut o = String::new();
    let _ = writeln!(o, "fit {}: {}", r.scenario, r.file.display());
    let _ = writeln!(
        o,
        "  compared {} ({}), {} samples",
        r.compared, r.reference, r.after.samples
    );
    if !r.alignment.is_empty() {
        let _ = writeln!(o, "  lined up {}", r.alignment);
    }
    let _ = writeln!(
        o,
        "  residual sqrt(mean(|dp|^2 + (L dtheta)^2)), L = {} m ({})",
        readable(r.length),
        r.length_from
    );
    let _ = writeln!(
        o,
        "residual: {} m before, {} m after ({})",
        readable(r.before.residual),
        readable(r.after.residual),
        residual_line(&r.before, &r.after)
    );
    let rows: Vec<[String; 6]> = r
        .params
        .iter()
        .map(|p| {
            [
                p.key.clone(),
                format!("{}..{}", readable(p.range[0]), readable(p.range[1])),
                p.nominal.map_or("-".into(), readable),
                rounded(p.value, p),
                p.interval.map_or("flat".into(), |[a, b]| {
                    format!("{}..{}", rounded(a, p), rounded(b, p))
                }),
                p.sensitivity.map_or("0".into(), readable),
            ]
        })
        .collect();
    let head = [
        "key".to_string(),
        "range".into(),
        "nominal".into(),
        "fitted".into(),
        format!("interval (+{:.0} %)", INTERVAL_RISE * 100.0),
        "sensitivity m/unit".into(),
    ];
    let mut width = head.clone().map(|h| h.chars().count());
    for row in &rows {
        for (w, c) in width.iter_mut().zip(row) {
            *w = (*w).max(c.chars().count());
        }
    }
    for row in std::iter::once(&head).chain(&rows) {
        let cells: Vec<String> = row
            .iter()
            .zip(width)
            .map(|(c, w)| format!("{c:<w$}"))
            .collect();
        let _ = writeln!(o, "  {}", cells.join("  ").trim_end());
    }
    let _ = writeln!(
        o,
        "evaluations: {} (Nelder-Mead: {} iterations, {})",
        r.evaluations,
        r.iterations,
        if r.converged {
            "converged"
        } else {
            "stopped by the budget"
        }
    );
    if r.failed > 0 {
        let _ = writeln!(
            o,
            "warning: {} trials could not run (counted as 1e6 m), the first: {}",
            r.failed,
            r.first_failure.as_deref().unwrap_or("?")
        );
    }
    for p in r.params.iter().filter(|p| p.sensitivity.is_none()) {
        let _ = writeln!(
            o,
            "warning: the residual does not grow away from {} = {}: this reference does not determine it",
            p.key,
            rounded(p.value, p)
        );
    }
    let _ = writeln!(
        o,
        "\nSet in {} (into its tables of these names):\n",
        r.file.display()
    );
    o.push_str(&toml(r));
    o
}

/// The report as JSON: `params` (key → fitted value), `residual_before`,
/// `residual_after`, then the details.
pub fn to_json(r: &Report) -> serde_json::Value {
    let map = |f: &dyn Fn(&ParamResult) -> serde_json::Value| -> serde_json::Map<String, serde_json::Value> {
        r.params.iter().map(|p| (p.key.clone(), f(p))).collect()
    };
    json!({
        "params": map(&|p| json!(p.value)),
        "residual_before": r.before.residual,
        "residual_after": r.after.residual,
        "intervals": map(&|p| json!(p.interval)),
        "sensitivity": map(&|p| json!(p.sensitivity)),
        "nominal": map(&|p| json!(p.nominal)),
        "ranges": map(&|p| json!(p.range)),
        "before": r.before,
        "after": r.after,
        "scenario": r.scenario,
        "file": r.file,
        "reference": r.reference,
        "compared": r.compared,
        "alignment": r.alignment,
        "length": r.length,
        "length_from": r.length_from,
        "evaluations": r.evaluations,
        "iterations": r.iterations,
        "converged": r.converged,
        "failed": r.failed,
        "toml": toml(r),
    })
}
