//! CSV plan files: a header row naming the columns (`t`, the model's
//! inputs in any order, optionally `label`), then one sample per row.
//! Fields are separated by commas and trimmed; blank lines and lines
//! starting with `#` are skipped; quoted fields are not supported (labels
//! cannot contain commas). Numbers are read with Rust's correctly rounded
//! parser, so values written with full precision come back exactly.

use crate::planner::PlanError;
use crate::sources::file::{At, Reader, Samples};

/// The optional label column.
const LABEL: &str = "label";

/// A hint for a field that is not a number: numpy 2 writes its scalars as
/// `np.float64(0.2)` when they are formatted with `repr` (or in a list).
fn not_a_number_hint(field: &str) -> &'static str {
    let numpy = ["np.", "numpy."].iter().any(|p| field.starts_with(p)) && field.ends_with(')');
    if numpy {
        " (numpy's repr of a scalar: write plain numbers, `float(x)` for each value or `array.tolist()` before writing)"
    } else {
        ""
    }
}

/// What a header column holds.
#[derive(Clone, Copy)]
enum Col {
    T,
    Input(usize),
    Label,
}

/// Read a CSV plan file.
pub fn read(mut r: Reader<'_>) -> Result<Samples, PlanError> {
    let text = crate::sources::file::json::read_text(&r)?;
    let names: Vec<String> = r.input_names().iter().map(|s| s.to_string()).collect();
    let expected = format!("t,{}", names.join(","));
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l))
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((header_line, header)) = lines.next() else {
        return Err(r.file_error(format!(
            "empty file: expected a header row `{expected}` and at least two rows"
        )));
    };
    let at_header = |what: String| At {
        line: Some(header_line),
        what,
    };
    let mut cols = Vec::new();
    let mut seen: Vec<&str> = Vec::new();
    for field in header.split(',') {
        let name = field.trim();
        let col = if name == "t" {
            Col::T
        } else if name == LABEL {
            Col::Label
        } else if let Some(i) = names.iter().position(|n| n == name) {
            Col::Input(i)
        } else {
            return Err(r.error(
                &at_header(format!("column `{name}`")),
                format!(
                    "unknown column (expected t, {} and optionally label){}",
                    names.join(", "),
                    crate::sources::file::unknown_input_hint(name, &names)
                ),
            ));
        };
        if seen.contains(&name) {
            return Err(r.error(&at_header(format!("column `{name}`")), "appears twice"));
        }
        seen.push(name);
        cols.push(col);
    }
    for required in std::iter::once("t").chain(names.iter().map(String::as_str)) {
        if !seen.contains(&required) {
            return Err(r.error(
                &at_header("header".into()),
                format!(
                    "no column `{required}` (expected `{expected}`, in any order, optionally with `label`)"
                ),
            ));
        }
    }
    let header_names: Vec<&str> = seen;
    let mut u = vec![0.0; names.len()];
    let mut u_col = vec![0usize; names.len()];
    for (k, c) in cols.iter().enumerate() {
        if let Col::Input(i) = c {
            u_col[*i] = k;
        }
    }
    for (line, row) in lines {
        let fields: Vec<&str> = row.split(',').map(str::trim).collect();
        let at = |k: usize| At {
            line: Some(line),
            what: format!("column `{}`", header_names[k]),
        };
        if fields.len() != cols.len() {
            return Err(r.error(
                &At {
                    line: Some(line),
                    what: String::new(),
                },
                format!(
                    "{} fields, the header has {} ({})",
                    fields.len(),
                    cols.len(),
                    header_names.join(",")
                ),
            ));
        }
        let mut t = f64::NAN;
        let mut t_k = 0;
        let mut label = None;
        for (k, (f, c)) in fields.iter().zip(&cols).enumerate() {
            match c {
                Col::Label => {
                    if f.starts_with('"') {
                        return Err(r.error(&at(k), "quoted fields are not supported"));
                    }
                    label = Some(*f);
                }
                Col::T | Col::Input(_) => {
                    let v: f64 = f.parse().map_err(|_| {
                        let shown = if f.is_empty() { "an empty field" } else { f };
                        r.error(
                            &at(k),
                            format!("`{shown}` is not a number{}", not_a_number_hint(f)),
                        )
                    })?;
                    match c {
                        Col::T => {
                            t = v;
                            t_k = k;
                        }
                        Col::Input(i) => u[*i] = v,
                        Col::Label => {}
                    }
                }
            }
        }
        r.push(t, &at(t_k), &u, &|i| at(u_col[i]), label)?;
    }
    r.finish()
}
