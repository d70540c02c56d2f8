//! Helpers every report page shares: HTML escaping, number cells, and
//! whether a run's summary says its tracking metrics mean anything.

use serde_json::Value;

pub(super) fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

pub(super) fn num(v: Option<f64>) -> String {
    match v {
        None => "–".into(),
        Some(x) => crate::numfmt::readable(x),
    }
}

/// Whether the run's tracking metrics mean anything (older logs: yes).
pub(super) fn tracking_meaningful(summary: &Value) -> bool {
    summary["not_meaningful"]["tracking"].is_null()
}
