//! The margins as a table: plain text for the terminal, Markdown for the guide.

use super::search::Status;
use super::{range, DimensionResult, Report};
use crate::numfmt::with_digits;
use crate::physics::perturb::{Dimension, Kind};

/// One row of the table.
#[derive(Debug, Clone)]
pub struct Row {
    /// Scenario.
    pub scenario: String,
    /// Dimension.
    pub dimension: String,
    /// The margin with its unit (and the factor for scales).
    pub margin: String,
    /// Where the edge lies.
    pub edge: String,
    /// The first gate broken beyond the margin.
    pub breaks: String,
    /// Runs used.
    pub runs: String,
    /// Wall time, s.
    pub wall: String,
    /// CPU time of the runs, s.
    pub cpu: String,
    /// Ceiling, floor, non-monotone, ...
    pub note: String,
}

fn unit(d: Dimension) -> String {
    match d.unit() {
        "" => String::new(),
        u => format!(" {u}"),
    }
}

/// A magnitude of `d` as text: `0.12 s`; factors with the factor, `0.35
/// (×0.65)`, with the digits that tell a small magnitude's factor from 1.
pub fn magnitude(d: Dimension, m: f64) -> String {
    let x = with_digits(m, 3);
    match d.kind() {
        Kind::Scale => {
            let extra = if m > 0.0 {
                ((-m.log10()).ceil() - 1.0).clamp(0.0, 12.0) as usize
            } else {
                0
            };
            format!("{x} (×{})", with_digits(d.value_at(m), 3 + extra))
        }
        Kind::Amount => format!("{x}{}", unit(d)),
    }
}

/// The row of one dimension's result.
pub fn row(scenario: &str, r: &DimensionResult) -> Row {
    let d = r.dimension;
    let (_, floor, ceiling) = range(d);
    let margin = match r.status {
        Status::Found => magnitude(d, r.margin),
        Status::Ceiling => format!("≥ {}", magnitude(d, ceiling)),
        Status::BelowFloor => format!("< {}", magnitude(d, floor)),
        Status::NominalFails => "none".into(),
    };
    let edge = match (r.status, r.first_failing) {
        (Status::Found, Some(hi)) => format!(
            "[{}, {}){}",
            with_digits(r.margin, 3),
            with_digits(hi, 3),
            unit(d)
        ),
        _ => "–".into(),
    };
    let breaks = match r.first_broken.first() {
        Some(b) if r.first_broken.len() > 1 => {
            format!("{b} (+{} more)", r.first_broken.len() - 1)
        }
        Some(b) => b.to_string(),
        None => "–".into(),
    };
    let runs = match r.seeds {
        Some(s) => format!("{} ({s}/level)", r.runs),
        None => r.runs.to_string(),
    };
    Row {
        scenario: scenario.into(),
        dimension: d.name().into(),
        margin,
        edge,
        breaks,
        runs,
        wall: format!("{:.1}", r.wall_s),
        cpu: format!("{:.1}", r.cpu_s),
        note: r.note(),
    }
}

/// Rows of a report.
pub fn rows(rep: &Report) -> Vec<Row> {
    rep.dimensions
        .iter()
        .map(|r| row(&rep.scenario, r))
        .collect()
}

/// A row for a scenario without margins (why, in the note).
pub fn skipped(scenario: &str, why: &str) -> Row {
    Row {
        scenario: scenario.into(),
        dimension: "–".into(),
        margin: "–".into(),
        edge: "–".into(),
        breaks: "–".into(),
        runs: "0".into(),
        wall: "–".into(),
        cpu: "–".into(),
        note: why.into(),
    }
}

const HEAD: [&str; 9] = [
    "scenario",
    "dimension",
    "margin",
    "edge in",
    "first gate broken beyond it",
    "runs",
    "cpu s",
    "wall s",
    "note",
];

fn cells(r: &Row) -> [&str; 9] {
    [
        &r.scenario,
        &r.dimension,
        &r.margin,
        &r.edge,
        &r.breaks,
        &r.runs,
        &r.cpu,
        &r.wall,
        &r.note,
    ]
}

/// Plain-text table, columns padded.
pub fn text(rows: &[Row]) -> String {
    let mut w = HEAD.map(|h| h.chars().count());
    for r in rows {
        for (i, c) in cells(r).iter().enumerate() {
            w[i] = w[i].max(c.chars().count());
        }
    }
    let line = |c: [&str; 9]| {
        let mut s = String::new();
        for (i, x) in c.iter().enumerate() {
            if i == HEAD.len() - 1 {
                s.push_str(x);
            } else {
                let pad = w[i] - x.chars().count();
                s.push_str(x);
                s.push_str(&" ".repeat(pad + 2));
            }
        }
        s.trim_end().to_string() + "\n"
    };
    let mut out = line(HEAD);
    for r in rows {
        out.push_str(&line(cells(r)));
    }
    out
}

/// Markdown table (pipes in cells escaped).
pub fn markdown(rows: &[Row]) -> String {
    let esc = |s: &str| s.replace('|', "\\|");
    let mut out = format!("| {} |\n", HEAD.join(" | "));
    out.push_str(&format!("|{}\n", "---|".repeat(HEAD.len())));
    for r in rows {
        let c: Vec<String> = cells(r).iter().map(|x| esc(x)).collect();
        out.push_str(&format!("| {} |\n", c.join(" | ")));
    }
    out
}
