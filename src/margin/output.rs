//! The margins as a table: plain text for the terminal, Markdown for the guide.

use crate::engine::perturb::Dimension;
use crate::margin::search::Status;
use crate::margin::DimensionResult;
use crate::numfmt::with_digits;

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

/// A magnitude of `d` as text: `0.12 s`; factors with the factor, `0.35
/// (×0.65)`, with the digits that tell a small magnitude's factor from 1.
pub fn magnitude(d: Dimension, m: f64) -> String {
    let x = with_digits(m, 3);
    if d.is_factor() {
        let extra = if m > 0.0 {
            ((-m.log10()).ceil() - 1.0).clamp(0.0, 12.0) as usize
        } else {
            0
        };
        format!("{x} (×{})", with_digits(d.value_at(m), 3 + extra))
    } else {
        format!("{x}{}", d.unit_suffix())
    }
}

/// The row of one dimension's result.
pub fn row(scenario: &str, r: &DimensionResult) -> Row {
    let d = r.dimension;
    let floor = d.row().search.floor;
    let margin = match r.status {
        Status::Found => magnitude(d, r.margin),
        // The ceiling the search reached (a time dimension's is at most the run).
        Status::Ceiling => format!("≥ {}", magnitude(d, r.margin)),
        Status::BelowFloor => format!("< {}", magnitude(d, floor)),
        Status::NominalFails => "none".into(),
        Status::Holds => format!("≥ {}", magnitude(d, r.margin)),
        Status::Breaks => match r.first_failing {
            Some(g) => format!("< {}", magnitude(d, g)),
            None => "none".into(),
        },
        Status::Budget => match r.first_failing {
            None => format!("≥ {}", magnitude(d, r.margin)),
            Some(hi) if r.margin == 0.0 => format!("< {}", magnitude(d, hi)),
            Some(_) => magnitude(d, r.margin),
        },
    };
    let edge = match (r.status, r.first_failing) {
        (Status::Found | Status::Budget, Some(hi)) if r.margin > 0.0 => format!(
            "[{}, {}){}",
            with_digits(r.margin, 3),
            with_digits(hi, 3),
            d.unit_suffix()
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

/// A row for a dimension that does not apply to the scenario (not run).
pub fn na(scenario: &str, d: Dimension, why: &str) -> Row {
    Row {
        scenario: scenario.into(),
        dimension: d.name().into(),
        margin: "n/a".into(),
        note: format!("does not apply: {why}"),
        ..skipped(scenario, "")
    }
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

/// Markdown table (pipes in cells escaped), for documents: without the
/// wall time, which says more about the machine's load than the search.
pub fn markdown(rows: &[Row]) -> String {
    const WALL: usize = 7;
    let esc = |s: &str| s.replace('|', "\\|");
    let keep = |c: [&str; 9]| -> Vec<String> {
        c.iter()
            .enumerate()
            .filter(|(i, _)| *i != WALL)
            .map(|(_, x)| esc(x))
            .collect()
    };
    let head = keep(HEAD);
    let mut out = format!("| {} |\n", head.join(" | "));
    out.push_str(&format!("|{}\n", "---|".repeat(head.len())));
    for r in rows {
        out.push_str(&format!("| {} |\n", keep(cells(r)).join(" | ")));
    }
    out
}

/// Where the guide keeps the output of `anholonomy margin scenarios/ --markdown`.
pub const GUIDE_BEGIN: &str = "<!-- begin: output of anholonomy margin --markdown -->";
/// End of it.
pub const GUIDE_END: &str = "<!-- end: output of anholonomy margin --markdown -->";

#[cfg(test)]
mod tests {
    use super::*;

    /// The cells of a Markdown row (escaped pipes kept inside their cell).
    fn md_cells(line: &str) -> Vec<String> {
        let inner = line.trim().trim_start_matches('|').trim_end_matches('|');
        let mut cells = vec![String::new()];
        let mut prev = ' ';
        for ch in inner.chars() {
            if ch == '|' && prev != '\\' {
                cells.push(String::new());
            } else {
                cells.last_mut().unwrap().push(ch);
            }
            prev = ch;
        }
        cells.into_iter().map(|c| c.trim().to_string()).collect()
    }

    /// The guide's table of every shipped scenario is this command's
    /// output: the same header, every row with its columns, every scenario of
    /// `scenarios/` in it with every dimension (n/a included) or one row
    /// saying why it has no margin. The numbers come from the run.
    #[test]
    fn the_guides_table_has_the_commands_format_and_every_scenario() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let doc = std::fs::read_to_string(root.join("docs/src/margins.md")).unwrap();
        let table = doc
            .split_once(GUIDE_BEGIN)
            .and_then(|(_, rest)| rest.split_once(GUIDE_END))
            .map(|(t, _)| t.trim())
            .expect("the guide's generated table and its markers");
        let lines: Vec<&str> = table.lines().filter(|l| l.starts_with('|')).collect();
        let head = markdown(&[]);
        assert_eq!(format!("{}\n{}\n", lines[0], lines[1]), head);
        let width = md_cells(lines[0]).len();
        let rows: Vec<Vec<String>> = lines[2..].iter().map(|l| md_cells(l)).collect();
        for r in &rows {
            assert_eq!(r.len(), width, "{r:?}");
        }
        let all: Vec<&str> = Dimension::all().map(|d| d.name()).collect();
        let mut names: Vec<String> = std::fs::read_dir(root.join("scenarios"))
            .unwrap()
            .filter_map(|e| {
                let p = e.ok()?.path();
                (p.extension()? == "toml").then(|| p.file_stem()?.to_str().map(String::from))?
            })
            .collect();
        names.sort();
        let mut seen: Vec<&str> = rows.iter().map(|r| r[0].as_str()).collect();
        seen.dedup();
        assert_eq!(seen, names, "the table's scenarios, in the command's order");
        for n in &names {
            let dims: Vec<&str> = rows
                .iter()
                .filter(|r| &r[0] == n)
                .map(|r| r[1].as_str())
                .collect();
            assert!(dims == ["–"] || dims == all, "{n}: {dims:?}");
        }
    }

    #[test]
    fn markdown_leaves_out_the_wall_time_and_escapes_pipes() {
        let r = Row {
            margin: "1 m|rad".into(),
            wall: "12.5".into(),
            ..skipped("s", "why")
        };
        let md = markdown(&[r]);
        assert!(!md.contains("wall") && !md.contains("12.5"), "{md}");
        assert!(md.contains("1 m\\|rad"), "{md}");
        assert_eq!(md_cells(md.lines().nth(2).unwrap()).len(), 8);
    }
}
