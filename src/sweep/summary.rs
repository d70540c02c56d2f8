//! Statistics, table and `sweep.json` of a sweep, computed from its records
//! alone (in index order), so a sweep run at once, resumed, or merged from
//! shards gives the same document. `sweep.json` is written streaming: the
//! records are copied from the `variants.jsonl` files one at a time.

use crate::log::atomic::write_file;
use crate::log::LogError;
use crate::scenario::SweepConfig;
use crate::sweep::distribution;
use crate::sweep::records::{raw_record, Entry, Header};
use serde_json::json;
use std::io::{BufReader, Write};
use std::path::{Path, PathBuf};

/// What a finished sweep reports.
#[derive(Debug)]
pub struct Summary {
    /// `sweep_*` metrics.
    pub metrics: Vec<(String, f64)>,
    /// Variants that could not run, and a success rate below the minimum.
    pub failures: Vec<String>,
    /// Physics steps of all variants.
    pub steps: usize,
    /// The printed table.
    pub table: String,
}

/// Statistics of `entries` (sorted by index; `files` are where they were
/// read from) and, when `out` is given, `sweep.json` written there atomically.
pub fn finish(
    h: &Header,
    cfg: &SweepConfig,
    entries: &[Entry],
    files: &[PathBuf],
    out: Option<&Path>,
    wall: f64,
) -> Result<Summary, LogError> {
    let n = entries.len();
    let ok = entries.iter().filter(|r| r.success).count();
    let rate = if n == 0 { 0.0 } else { ok as f64 / n as f64 };
    let errors: Vec<f64> = entries.iter().filter_map(|r| r.final_error).collect();
    let times: Vec<f64> = entries
        .iter()
        .filter(|r| r.success)
        .filter_map(|r| r.time_to_goal)
        .collect();
    let mut failures: Vec<String> = entries
        .iter()
        .filter_map(|r| {
            r.error
                .as_ref()
                .map(|e| format!("variant {}: {e}", r.index))
        })
        .collect();
    let err_d = distribution(&errors);
    let time_d = distribution(&times);
    let mut metrics = vec![
        ("sweep_success_rate".to_string(), rate),
        ("sweep_variants".to_string(), n as f64),
    ];
    for (name, d) in [("sweep_final_error", err_d), ("sweep_time_to_goal", time_d)] {
        for (s, v) in ["median", "p95", "max"]
            .iter()
            .zip(d.unwrap_or([f64::NAN; 3]))
        {
            metrics.push((format!("{name}_{s}"), v));
        }
    }
    if rate < cfg.min_success_rate {
        let (rate, floor) = crate::numfmt::breach(rate, cfg.min_success_rate);
        failures.push(format!("sweep_success_rate = {rate} < {floor}"));
    }
    let steps = entries.iter().map(|r| r.steps).sum();

    let fmt = |d: Option<[f64; 3]>| match d {
        Some([a, b, c]) => format!("{a:>9.4} {b:>9.4} {c:>9.4}"),
        None => format!("{:>9} {:>9} {:>9}", "-", "-", "-"),
    };
    use std::fmt::Write as _;
    let mut table = String::new();
    let _ = writeln!(
        table,
        "sweep {} ({} variants{}, {:.1} s): success {}/{} = {:.1} %",
        h.scenario,
        n,
        h.shard
            .map(|s| format!(", shard {}/{}", s.index, s.count))
            .unwrap_or_default(),
        wall,
        ok,
        n,
        100.0 * rate
    );
    let err_label = format!("final error ({})", cfg.success_metric);
    let time_label = cfg
        .time_metric
        .as_ref()
        .map(|m| format!("time to goal, s ({m}, successes)"));
    let w = [Some(&err_label), time_label.as_ref()]
        .iter()
        .flatten()
        .map(|l| l.chars().count())
        .max()
        .unwrap_or(0)
        .max(28);
    let _ = writeln!(
        table,
        "  {:<w$} {:>9} {:>9} {:>9}",
        "", "median", "p95", "max"
    );
    let _ = writeln!(table, "  {err_label:<w$} {}", fmt(err_d));
    match &time_label {
        Some(l) => {
            let _ = writeln!(table, "  {l:<w$} {}", fmt(time_d));
        }
        // The model reports no time to goal: say so rather than print a column of dashes.
        None => {
            let _ = writeln!(
                table,
                "  time to goal: not reported (the model has no time-to-goal metric; set sweep.time_metric to name one)"
            );
        }
    }

    if let Some(out) = out {
        let summary = |d: Option<[f64; 3]>| {
            d.map(|[m, p, x]| json!({"median": m, "p95": p, "max": x}))
                .unwrap_or(serde_json::Value::Null)
        };
        let head = json!({
            "scenario": h.scenario,
            "file": h.file,
            "sweep": h.sweep,
            "shard": h.shard,
            "variants_run": n,
            "successes": ok,
            "success_rate": rate,
            "final_error": summary(err_d),
            "time_to_goal": summary(time_d),
            "passed": failures.is_empty(),
            "failures": failures,
        });
        // Everything that depends on the clock, and only that.
        let walls = json!({
            "total": wall,
            "variants": entries.iter().map(|r| r.wall_s).collect::<Vec<_>>(),
        });
        write_doc(out, &head, entries, files, &walls)?;
    }
    Ok(Summary {
        metrics,
        failures,
        steps,
        table,
    })
}

/// `head`'s fields, then `"results"` (each record as written, one per line),
/// then `"wall_time_s"`.
fn write_doc(
    out: &Path,
    head: &serde_json::Value,
    entries: &[Entry],
    files: &[PathBuf],
    walls: &serde_json::Value,
) -> Result<(), LogError> {
    let mut readers = files
        .iter()
        .map(|f| std::fs::File::open(f).map(BufReader::new))
        .collect::<std::io::Result<Vec<_>>>()
        .map_err(|source| LogError::Write {
            path: out.to_path_buf(),
            source,
        })?;
    write_file(out, |w| {
        let mut text = serde_json::to_string_pretty(head).map_err(std::io::Error::other)?;
        // Reopen the object: drop the closing "\n}".
        text.truncate(text.trim_end().len() - 1);
        let text = text.trim_end().to_string();
        write!(w, "{text},\n  \"results\": [")?;
        for (k, e) in entries.iter().enumerate() {
            let r = readers
                .get_mut(e.file)
                .ok_or_else(|| std::io::Error::other("record of an unknown file"))?;
            w.write_all(if k == 0 { b"\n    " } else { b",\n    " })?;
            w.write_all(&raw_record(r, e)?)?;
        }
        let walls = serde_json::to_string(walls).map_err(std::io::Error::other)?;
        write!(w, "\n  ],\n  \"wall_time_s\": {walls}\n}}\n")
    })
}
