//! Numbers printed in the seed papers next to the values a plan computes.
//!
//! Each system knows its paper's worked example; when a scenario poses that
//! example (same task, same planner settings) the system returns one
//! [`PaperRow`] per printed number, with the computed value read from the
//! plan's own `details` (so the table shows what this run used, not a copy of
//! the printed figure). `anholonomy plan FILE`, `summary.json` and the HTML
//! report show the table.

use serde::{Deserialize, Serialize};
use serde_json::Value;

/// One printed number and the value the harness computes for it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PaperRow {
    /// What the number is (e.g. "loop at O: b").
    pub quantity: String,
    /// As printed (digits kept, so the printed precision is known).
    pub printed: String,
    /// Computed by the planner for this scenario.
    pub computed: f64,
    /// Unit of both values.
    pub unit: String,
    /// Whether the computed value is within one unit of the printed value's
    /// last digit (the paper truncates about as often as it rounds).
    pub agrees: bool,
    /// Why the printed value differs (misprint, truncation), or context.
    pub note: String,
}

/// Decimal places of a printed number ("0.01808" → 5, "−7.696e-4" → 7, "330" → 0).
pub(crate) fn printed_decimals(printed: &str) -> i32 {
    let s = printed.trim().replace('−', "-");
    let (mantissa, exp) = match s.split_once(['e', 'E']) {
        Some((m, e)) => (m.to_string(), e.parse::<i32>().unwrap_or(0)),
        None => (s.clone(), 0),
    };
    let frac = mantissa
        .split_once('.')
        .map(|(_, f)| f.len() as i32)
        .unwrap_or(0);
    frac - exp
}

/// Parses a printed number (accepts the typographic minus).
pub(crate) fn printed_value(printed: &str) -> Option<f64> {
    printed.trim().replace('−', "-").parse().ok()
}

/// A row; `agrees` follows the printed precision.
pub fn row(quantity: &str, printed: &str, computed: f64, unit: &str, note: &str) -> PaperRow {
    let tol = 10f64.powi(-printed_decimals(printed)) * (1.0 + 1e-9);
    let agrees = printed_value(printed).is_some_and(|p| (computed - p).abs() <= tol);
    PaperRow {
        quantity: quantity.into(),
        printed: printed.into(),
        computed,
        unit: unit.into(),
        agrees,
        note: note.into(),
    }
}

/// A number inside plan details by JSON pointer (e.g. `/loops/0/b_rad`).
pub(crate) fn detail(details: &Value, pointer: &str) -> Option<f64> {
    details.pointer(pointer).and_then(Value::as_f64)
}

/// Whether two vectors agree within `tol` everywhere (same length).
pub fn same(a: &[f64], b: &[f64], tol: f64) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol)
}

/// Builds rows from `(quantity, printed, pointer, scale, unit, note)`; rows whose pointer is
/// missing from the details are left out. `scale` converts the detail to the printed unit.
pub(crate) fn rows_from(
    details: &Value,
    spec: &[(&str, &str, &str, f64, &str, &str)],
) -> Vec<PaperRow> {
    spec.iter()
        .filter_map(|&(q, printed, ptr, scale, unit, note)| {
            detail(details, ptr).map(|v| row(q, printed, v * scale, unit, note))
        })
        .collect()
}

/// The table as text (for `anholonomy plan`).
pub fn format_table(rows: &[PaperRow]) -> String {
    let mut out = format!(
        "  {:<34} {:>12} {:>14} {:<5} {:<7} note\n",
        "paper", "printed", "computed", "unit", ""
    );
    for r in rows {
        out.push_str(&format!(
            "  {:<34} {:>12} {:>14} {:<5} {:<7} {}\n",
            r.quantity,
            r.printed,
            format_computed(r),
            r.unit,
            if r.agrees { "agrees" } else { "DIFFERS" },
            r.note
        ));
    }
    out
}

/// The computed value with two more decimals than printed (at least 2 significant).
pub(crate) fn format_computed(r: &PaperRow) -> String {
    let d = printed_decimals(&r.printed);
    if d > 6 {
        format!("{:.*e}", 4, r.computed)
    } else {
        format!("{:.*}", (d + 2).max(0) as usize, r.computed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_follow_the_printed_digits() {
        assert_eq!(printed_decimals("0.01808"), 5);
        assert_eq!(printed_decimals("132.72"), 2);
        assert_eq!(printed_decimals("−7.696e-4"), 7);
        assert_eq!(printed_decimals("330"), 0);
        assert_eq!(printed_value("−13.92"), Some(-13.92));
    }

    #[test]
    fn agreement_is_one_unit_of_the_last_digit() {
        assert!(row("b", "0.8034", 0.80348, "rad", "").agrees);
        assert!(!row("b", "0.8034", 0.80353, "rad", "").agrees);
        assert!(row("k", "−7.696e-4", -7.6965e-4, "", "").agrees);
        assert!(!row("k", "−7.696e-4", -7.6985e-4, "", "").agrees);
        assert!(!row("x", "not a number", 1.0, "", "").agrees);
    }
}
