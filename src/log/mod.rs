//! Run logs: MCAP (Foxglove) and Rerun (.rrd), written atomically
//! (`summary.json` is written by the runner).
//!
//! * [`write_mcap`]: Foxglove-flavoured MCAP (JSON topics with JSON schemas,
//!   `/tf`, `/scene`, `/scene/paths`, metrics as metadata). Topic list in
//!   [`mcap`] module docs.
//! * [`write_rrd`]: Rerun recording with a blueprint (3D view of the robot and
//!   the paths, time series of state, errors, commands and sim channels).
//!
//! Both writers first write `<file name>.tmp` next to the target and rename it
//! over the target only once the file is complete; on any error (or panic)
//! the temporary file is removed, so the final path never holds a partial file.

pub mod atomic;
pub mod mcap;
pub mod rerun;
mod scene;
pub mod series;
pub mod unit;

use std::path::{Path, PathBuf};

pub use self::mcap::write_mcap;
pub use self::rerun::write_rrd;

pub(crate) use self::scene::segment_name;
use crate::record::RunRecord;

/// Which files a run keeps in its log directory (`--keep`).
///
/// * `all`: `run.mcap`, `run.rrd`, `series.json`, `summary.json` (the report's pages beside them);
/// * `report`: no 3D logs (`run.mcap`, `run.rrd`), enough for the HTML report;
/// * `summary`: `summary.json` only (metrics and verdicts; no report).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
pub enum Keep {
    /// `summary.json` only.
    Summary,
    /// `summary.json` and `series.json`: what the report reads.
    Report,
    /// Everything, including the MCAP and Rerun logs.
    #[default]
    All,
}

impl Keep {
    /// `summary`, `report`, `all`.
    pub fn as_str(self) -> &'static str {
        match self {
            Keep::Summary => "summary",
            Keep::Report => "report",
            Keep::All => "all",
        }
    }
}

/// A `--keep` level that is none of `summary`, `report`, `all`.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("`{given}`: expected summary, report or all")]
pub struct KeepParseError {
    /// What was written.
    pub given: String,
}

impl std::str::FromStr for Keep {
    type Err = KeepParseError;
    fn from_str(s: &str) -> Result<Keep, KeepParseError> {
        match s {
            "summary" => Ok(Keep::Summary),
            "report" => Ok(Keep::Report),
            "all" => Ok(Keep::All),
            _ => Err(KeepParseError { given: s.into() }),
        }
    }
}

impl std::fmt::Display for Keep {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Errors of the log writers. Every variant names the file concerned.
#[derive(Debug, thiserror::Error)]
pub enum LogError {
    /// A filesystem operation failed (create, write, sync, rename).
    #[error("{op} {path}: {source}")]
    Io {
        /// What was being done ("cannot create", "cannot rename to", ...).
        op: &'static str,
        /// The file concerned.
        path: PathBuf,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The Foxglove SDK / MCAP writer reported an error.
    #[error("MCAP writer failed for {path}: {source}")]
    Mcap {
        /// The file concerned.
        path: PathBuf,
        /// Underlying error.
        #[source]
        source: foxglove::FoxgloveError,
    },
    /// The Rerun SDK reported an error.
    #[error("Rerun writer failed for {path}: {message}")]
    Rerun {
        /// The file concerned.
        path: PathBuf,
        /// Description of the SDK error.
        message: String,
    },
    /// A message could not be serialized to JSON.
    #[error("JSON encoding failed for {path}: {source}")]
    Json {
        /// The file concerned.
        path: PathBuf,
        /// Underlying error.
        #[source]
        source: serde_json::Error,
    },
    /// Writing a whole file through a temporary one failed.
    #[error("{}: {source}", crate::echo::path(path))]
    Write {
        /// The file that was to be written.
        path: PathBuf,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The writer finished but the file is not complete (e.g. missing footer).
    #[error("incomplete log file {path}: {reason}")]
    Incomplete {
        /// The file concerned.
        path: PathBuf,
        /// What is missing.
        reason: String,
    },
    /// The run record is inconsistent (series lengths do not match the names).
    #[error("cannot log run to {path}: invalid run record: {reason}")]
    InvalidRecord {
        /// The file that was to be written.
        path: PathBuf,
        /// What is inconsistent.
        reason: String,
    },
}

/// Check the shape invariants the writers index by, so a malformed record is a
/// clear error instead of a panic.
pub(crate) fn validate(path: &Path, rec: &RunRecord<'_>) -> Result<(), LogError> {
    check(rec).map_err(|reason| LogError::InvalidRecord {
        path: path.to_path_buf(),
        reason,
    })
}

// The record is built by the harness, never from user input: a failure here
// is a harness bug, and its `String` is a message for the developer (a debug
// path), not a case a caller tells apart.
fn check(rec: &RunRecord<'_>) -> Result<(), String> {
    let ns = rec.state_names.len();
    let ni = rec.input_names.len();
    let traj_ok = |what: &str, tr: &crate::integrate::Trajectory| -> Result<(), String> {
        let n = tr.t.len();
        if tr.q.len() != n || tr.u.len() != n || tr.label.len() != n {
            return Err(format!(
                "{what} trajectory: {n} times but {} states, {} inputs, {} labels",
                tr.q.len(),
                tr.u.len(),
                tr.label.len()
            ));
        }
        if let Some((k, q)) = tr.q.iter().enumerate().find(|(_, q)| q.len() != ns) {
            return Err(format!(
                "{what} state #{k} has {} entries, expected {ns}",
                q.len()
            ));
        }
        if let Some((k, u)) = tr.u.iter().enumerate().find(|(_, u)| u.len() != ni) {
            return Err(format!(
                "{what} input #{k} has {} entries, expected {ni}",
                u.len()
            ));
        }
        Ok(())
    };
    traj_ok("ideal", rec.ideal)?;
    traj_ok("sim", &rec.sim.traj)?;
    let n_sim = rec.sim.traj.len();
    let (poses, index) = (&rec.sim.link_poses, &rec.sim.link_pose_index);
    if poses.len() != index.len() {
        return Err(format!(
            "{} link pose rows but {} sample indices for them",
            poses.len(),
            index.len()
        ));
    }
    if !poses.is_empty() {
        if let Some(w) = index.windows(2).find(|w| w[1] <= w[0]) {
            return Err(format!(
                "link pose sample indices not increasing: {} then {}",
                w[0], w[1]
            ));
        }
        if let Some(&k) = index.last().filter(|&&k| k >= n_sim) {
            return Err(format!(
                "link pose row at sample {k}, but sim has {n_sim} samples"
            ));
        }
        if let Some((k, row)) = rec
            .sim
            .link_poses
            .iter()
            .enumerate()
            .find(|(_, r)| r.len() != rec.links.len())
        {
            return Err(format!(
                "link pose row #{k} has {} poses, expected one per link ({})",
                row.len(),
                rec.links.len()
            ));
        }
    }
    if let Some((name, v)) = rec.sim.channels.iter().find(|(_, v)| v.len() != n_sim) {
        return Err(format!(
            "sim channel `{name}` has {} values, expected {n_sim}",
            v.len()
        ));
    }
    let c = rec.comparison;
    if c.coord_error.len() != ns {
        return Err(format!(
            "comparison has {} error series, expected {ns}",
            c.coord_error.len()
        ));
    }
    let nc = c.t.len();
    if let Some((k, e)) = c
        .coord_error
        .iter()
        .enumerate()
        .find(|(_, e)| e.len() != nc)
    {
        return Err(format!(
            "error series for `{}` has {} values, expected {nc}",
            rec.state_names[k],
            e.len()
        ));
    }
    if let Some(p) = &c.position_error {
        if p.len() != nc {
            return Err(format!(
                "position error has {} values, expected {nc}",
                p.len()
            ));
        }
    }
    if let Some((r, p)) = c
        .robot_position_error
        .iter()
        .enumerate()
        .find(|(_, p)| p.len() != nc)
    {
        return Err(format!(
            "robot {}'s position error has {} values, expected {nc}",
            r + 1,
            p.len()
        ));
    }
    for &[ix, iy] in &rec.robot_positions {
        if ix >= ns || iy >= ns {
            return Err(format!(
                "position indices [{ix}, {iy}] out of range for {ns} coordinates"
            ));
        }
    }
    if let Some(s) = rec
        .series
        .iter()
        .find(|s| s.t.len() != s.values.len() || s.name.split('/').all(str::is_empty))
    {
        return Err(format!(
            "series `{}` has {} times and {} values (or an empty name)",
            s.name,
            s.t.len(),
            s.values.len()
        ));
    }
    if let Some(&a) = rec.angular.iter().find(|&&a| a >= ns) {
        return Err(format!(
            "angular index {a} out of range for {ns} coordinates"
        ));
    }
    Ok(())
}
