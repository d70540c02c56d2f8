//! A recorded trajectory as CSV: a header row naming the columns, then one
//! sample per row. `t` (s), `x` and `y` (m) and the heading as `theta`
//! (rad) or `theta_deg` (degrees) are read; other columns (a `z`, speeds)
//! are left alone. `t` is the recording's own clock: it need not start at
//! 0, but must increase strictly. Blank lines and lines starting with `#`
//! are skipped; fields are trimmed.

use crate::recording::{Recording, RecordingError};
use std::path::Path;

/// Largest recording CSV read, bytes.
pub const MAX_BYTES: u64 = 256 << 20;

/// Read a recording CSV.
pub fn read(path: &Path) -> Result<Recording, RecordingError> {
    let text = crate::input::read_text(path, "recording", MAX_BYTES).map_err(|e| match e {
        crate::error::Error::Input { line, message, .. } => {
            RecordingError::file(path, line, message)
        }
        other => RecordingError::file(path, None, other.to_string()),
    })?;
    parse(path, &text)
}

/// The column each quantity is in, and the heading's unit.
struct Columns {
    t: usize,
    x: usize,
    y: usize,
    heading: usize,
    degrees: bool,
}

fn header(path: &Path, line: usize, text: &str) -> Result<Columns, RecordingError> {
    let names: Vec<&str> = text.split(',').map(str::trim).collect();
    let err = |m: String| RecordingError::file(path, Some(line), m);
    for (i, n) in names.iter().enumerate() {
        if names[..i].contains(n) {
            return Err(err(format!("column `{n}` is named twice")));
        }
    }
    let find = |n: &str| names.iter().position(|c| *c == n);
    let need = |n: &str| {
        find(n).ok_or_else(|| {
            err(format!(
                "no column `{n}` (the header names {}; a recording has t, x, y and theta or theta_deg)",
                names
                    .iter()
                    .map(|c| format!("`{c}`"))
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
        })
    };
    let (t, x, y) = (need("t")?, need("x")?, need("y")?);
    let (heading, degrees) = match (find("theta"), find("theta_deg")) {
        (Some(_), Some(_)) => return Err(err("both `theta` and `theta_deg`: keep one".into())),
        (Some(i), None) => (i, false),
        (None, Some(i)) => (i, true),
        (None, None) => (need("theta")?, false),
    };
    Ok(Columns {
        t,
        x,
        y,
        heading,
        degrees,
    })
}

/// Parse recording CSV text (`path` names it in messages).
pub fn parse(path: &Path, text: &str) -> Result<Recording, RecordingError> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l))
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((hl, head)) = lines.next() else {
        return Err(RecordingError::file(
            path,
            None,
            "empty file: expected a header row `t,x,y,theta` and at least two rows",
        ));
    };
    let cols = header(path, hl, head)?;
    let width = head.split(',').count();
    let names = [
        "t",
        "x",
        "y",
        if cols.degrees { "theta_deg" } else { "theta" },
    ];
    let mut t: Vec<f64> = Vec::new();
    let mut pose = Vec::new();
    for (line, row) in lines {
        let fields: Vec<&str> = row.split(',').map(str::trim).collect();
        let err = |m: String| RecordingError::file(path, Some(line), m);
        if fields.len() != width {
            return Err(err(format!(
                "{} fields, but the header has {width} columns",
                fields.len()
            )));
        }
        let mut v = [0.0; 4];
        for (k, col) in [cols.t, cols.x, cols.y, cols.heading]
            .into_iter()
            .enumerate()
        {
            let x: f64 = fields[col].parse().map_err(|_| {
                err(format!(
                    "column `{}`: `{}` is not a number",
                    names[k], fields[col]
                ))
            })?;
            if !x.is_finite() {
                return Err(err(format!("column `{}`: {x} is not finite", names[k])));
            }
            v[k] = x;
        }
        if let Some(&prev) = t.last() {
            if v[0] <= prev {
                return Err(err(format!(
                    "column `t`: {} does not come after the previous row's {} (t must increase strictly)",
                    crate::numfmt::shortest(v[0]),
                    crate::numfmt::shortest(prev)
                )));
            }
        }
        let heading = if cols.degrees {
            v[3].to_radians()
        } else {
            v[3]
        };
        t.push(v[0]);
        pose.push([v[1], v[2], heading]);
    }
    Ok(Recording {
        source: path.display().to_string(),
        t,
        pose,
        bag_clock: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(text: &str) -> Result<Recording, String> {
        parse(Path::new("r.csv"), text).map_err(|e| e.to_string())
    }

    #[test]
    fn columns_in_any_order_and_degrees() {
        let r =
            p("# a recording\ny, t,theta_deg,x,z\n2,10,90,1,0\n\n2.5,10.5,180,1.5,0\n").unwrap();
        assert_eq!(r.t, vec![10.0, 10.5]);
        assert_eq!(r.pose[0][0], 1.0);
        assert_eq!(r.pose[1][1], 2.5);
        assert!((r.pose[1][2] - std::f64::consts::PI).abs() < 1e-15);
    }

    #[test]
    fn bad_files_name_the_line_and_column() {
        let e = p("x,y,theta\n1,2,3\n").unwrap_err();
        assert!(e.starts_with("r.csv:1: no column `t`"), "{e}");
        let e = p("t,x,y,theta\n0,0,0,0\n0,1,1,1\n").unwrap_err();
        assert!(e.starts_with("r.csv:3: column `t`"), "{e}");
        let e = p("t,x,y,theta\n0,0,a,0\n").unwrap_err();
        assert!(e.starts_with("r.csv:2: column `y`: `a`"), "{e}");
        let e = p("t,x,y,theta,theta_deg\n").unwrap_err();
        assert!(e.contains("keep one"), "{e}");
        let e = p("t,x,y,theta\n0,0,0\n").unwrap_err();
        assert!(e.contains("3 fields"), "{e}");
        assert!(p("").unwrap_err().contains("empty file"));
    }
}
