//! The HTML report of a log directory: `LOGDIR/index.html` (every scenario:
//! pass/fail, key metrics, baseline change, link) and
//! `LOGDIR/<scenario>/report.html` (figures, metrics, the paper's numbers).
//!
//! Inputs per scenario directory: `summary.json` and `series.json` (single
//! runs) or `sweep.json` (sweeps), and `regression.json` when `check
//! --baseline` compared the run. Every directory is read and checked before
//! anything is written: an empty log directory, a run that did not finish
//! (no `summary.json`, a `*.tmp` file left behind, a missing or unreadable
//! `series.json`) is an input error naming the file, and no report file is
//! touched. Pages are self-contained (inline SVG from `plotters`, inline CSS,
//! no scripts, no network), so they work as CI artifacts and offline.

mod figures;
mod grasp;
mod html;
mod margins;
mod markup;
mod plots;
mod robot;

use crate::error::Error;
use crate::log::series;
use rayon::prelude::*;
use serde::Deserialize;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// One metric's baseline verdict as stored in `regression.json`.
#[derive(Debug, Clone, Deserialize)]
pub struct StoredDelta {
    /// Metric name.
    pub metric: String,
    /// Baseline value (null: NaN or absent).
    pub baseline: Option<f64>,
    /// Value now.
    pub now: Option<f64>,
    /// `unchanged`, `regressed`, `improved`, `changed`, `missing`, `new`.
    pub status: String,
    /// Human-readable change.
    pub change: String,
}

/// What a scenario directory holds.
pub enum RunData {
    /// A single run.
    Single {
        /// `summary.json`.
        summary: Box<Value>,
        /// `series.json`.
        series: Box<series::SeriesFile>,
    },
    /// A Monte Carlo sweep: `sweep.json`.
    Sweep(Box<Value>),
}

/// A scenario directory, read and checked.
pub struct Loaded {
    /// Scenario (directory) name.
    pub name: String,
    /// The directory.
    pub dir: PathBuf,
    /// Its data.
    pub data: RunData,
    /// Baseline comparison, when `check --baseline` made one.
    pub regression: Option<Vec<StoredDelta>>,
    /// `margins.json`, when `margin` or a `[margins]` gate searched margins.
    pub margins: Option<Value>,
}

fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, Error> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| Error::input(path, format!("cannot read: {e}")))?;
    serde_json::from_str(&text).map_err(|e| Error::Input {
        key: None,
        path: path.into(),
        line: Some(e.line()),
        message: format!("unreadable (half-written or not from anholonomy): {e}"),
    })
}

/// Read and check one scenario directory.
pub(crate) fn load_dir(dir: &Path) -> Result<Loaded, Error> {
    let name = dir
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let entries = std::fs::read_dir(dir)
        .map_err(|e| Error::input(dir, format!("cannot list directory: {e}")))?;
    let mut shards = false;
    for e in entries.flatten() {
        let f = e.file_name().to_string_lossy().into_owned();
        if f.ends_with(".tmp") {
            return Err(Error::input(
                e.path(),
                "temporary file of an interrupted run: the run did not finish (run the scenario again)",
            ));
        }
        shards |= f.starts_with("sweep-shard-");
    }
    let regression = {
        let p = dir.join("regression.json");
        p.is_file()
            .then(|| read_json::<Vec<StoredDelta>>(&p))
            .transpose()?
    };
    let sweep = dir.join("sweep.json");
    let summary = dir.join("summary.json");
    let data = if sweep.is_file() {
        let v: Value = read_json(&sweep)?;
        if !v["results"].is_array() || !v["scenario"].is_string() {
            return Err(Error::input(&sweep, "key `results`: not a sweep log"));
        }
        RunData::Sweep(Box::new(v))
    } else if summary.is_file() {
        let s: Value = read_json(&summary)?;
        if !s["metrics"].is_object() || !s["scenario"].is_string() {
            return Err(Error::input(&summary, "key `metrics`: not a run summary"));
        }
        let series_path = dir.join("series.json");
        if !series_path.is_file() {
            let why = if s["logs_kept"] == "summary" {
                "missing: the run kept only summary.json (--keep summary); run it again with --keep report"
            } else {
                "missing: the run did not finish or predates series.json (run the scenario again)"
            };
            return Err(Error::input(&series_path, why));
        }
        let series: series::SeriesFile = read_json(&series_path)?;
        if series.format != series::FORMAT {
            return Err(Error::input(
                &series_path,
                format!(
                    "key `format`: {} is not supported (expected {})",
                    series.format,
                    series::FORMAT
                ),
            ));
        }
        RunData::Single {
            summary: Box::new(s),
            series: Box::new(series),
        }
    } else if shards {
        return Err(Error::input(
            dir,
            "only sweep shard files (sweep-shard-*.json): the report needs a whole sweep (sweep.json)",
        ));
    } else {
        return Err(Error::input(
            &summary,
            "missing: not a finished run (interrupted, or not a log directory)",
        ));
    };
    let margins = {
        let p = dir.join("margins.json");
        p.is_file().then(|| read_json::<Value>(&p)).transpose()?
    };
    Ok(Loaded {
        name,
        dir: dir.to_path_buf(),
        data,
        regression,
        margins,
    })
}

/// The scenario directories of `root` (sorted).
fn scenario_dirs(root: &Path) -> Result<Vec<PathBuf>, Error> {
    if !root.is_dir() {
        return Err(Error::input(root, "not a log directory"));
    }
    let rd = std::fs::read_dir(root)
        .map_err(|e| Error::input(root, format!("cannot list directory: {e}")))?;
    let mut dirs: Vec<PathBuf> = rd
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir())
        .collect();
    dirs.sort();
    if dirs.is_empty() {
        return Err(Error::input(
            root,
            "no runs to report (no scenario directories; run `anholonomy run` first)",
        ));
    }
    Ok(dirs)
}

/// What [`write_report`] wrote.
#[derive(Debug, Default)]
pub struct Written {
    /// Scenarios indexed.
    pub scenarios: usize,
    /// Directories left out of the index, with why (only with `this_run`).
    pub skipped: Vec<Error>,
}

/// Write the report of every scenario directory of `root`.
///
/// Without `this_run` (`anholonomy report`) every directory must read back,
/// else nothing is written. With the names of the scenarios a call just ran
/// (`run --report`), those must read back and the other directories are
/// indexed when they can be, and listed in [`Written::skipped`] when not (an
/// older run's interrupted directory does not hide this run's report).
pub fn write_report(root: &Path, this_run: Option<&[String]>) -> Result<Written, Error> {
    let dirs = scenario_dirs(root)?;
    let results: Vec<(PathBuf, Result<Loaded, Error>)> =
        dirs.par_iter().map(|d| (d.clone(), load_dir(d))).collect();
    let mut loaded = Vec::new();
    let mut skipped = Vec::new();
    for (dir, r) in results {
        let name = dir
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let required = this_run.is_none_or(|names| names.contains(&name));
        match r {
            Ok(l) => loaded.push(l),
            Err(e) if required => return Err(e),
            Err(e) => skipped.push(e),
        }
    }
    let pages: Vec<String> = loaded
        .par_iter()
        .map(|l| {
            html::scenario_page(l).map_err(|e| Error::Log {
                path: l.dir.join("report.html"),
                message: e.to_string(),
            })
        })
        .collect::<Result<_, _>>()?;
    for (l, page) in loaded.iter().zip(&pages) {
        let path = l.dir.join("report.html");
        crate::log::atomic::write_file(&path, |w| std::io::Write::write_all(w, page.as_bytes()))
            .map_err(|e| Error::Log {
                path: path.clone(),
                message: e.to_string(),
            })?;
    }
    let index = root.join("index.html");
    let text = html::index_page(&loaded, &skipped);
    crate::log::atomic::write_file(&index, |w| std::io::Write::write_all(w, text.as_bytes()))
        .map_err(|e| Error::Log {
            path: index.clone(),
            message: e.to_string(),
        })?;
    Ok(Written {
        scenarios: loaded.len(),
        skipped,
    })
}
