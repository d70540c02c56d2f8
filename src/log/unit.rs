//! A run's log directory as one unit. `run.mcap`, `run.rrd` and
//! `summary.json` are written into a hidden staging directory beside the
//! target (`<root>/.<name>.partial-<pid>`), and the staging directory
//! replaces `<root>/<name>` whole once every file is complete. So the target
//! holds the previous complete set, then (for the instant between two
//! renames) nothing, then the new complete set: a killed run never leaves
//! files of two runs side by side. A killed run leaves only its staging
//! directory (or, killed between the two renames, the previous set moved
//! aside as `.<name>.old-<pid>`), which the next run of that name removes.

use crate::log::LogError;
use std::fs;
use std::path::{Path, PathBuf};

/// A staging directory that becomes `<root>/<name>` on [`LogUnit::commit`];
/// dropped uncommitted (error, panic), it is removed.
#[derive(Debug)]
pub struct LogUnit {
    staging: PathBuf,
    target: PathBuf,
    committed: bool,
}

fn io<'a>(op: &'static str, path: &'a Path) -> impl FnOnce(std::io::Error) -> LogError + 'a {
    move |source| LogError::Io {
        op,
        path: path.to_path_buf(),
        source,
    }
}

/// Staging (and moved-aside) directories of `name` left by processes that no
/// longer run.
fn stale_staging(root: &Path, name: &str) -> Vec<PathBuf> {
    let prefixes = [format!(".{name}.partial-"), format!(".{name}.old-")];
    let Ok(rd) = fs::read_dir(root) else {
        return Vec::new();
    };
    rd.flatten()
        .filter_map(|e| {
            let file = e.file_name();
            let file = file.to_str()?;
            let pid = prefixes
                .iter()
                .find_map(|p| file.strip_prefix(p.as_str()))?
                .parse::<u32>()
                .ok()?;
            (!process_alive(pid)).then(|| e.path())
        })
        .collect()
}

/// Whether a process runs (Linux: /proc; elsewhere assume it does, so
/// another run's staging directory is never removed).
fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return false;
    }
    if cfg!(target_os = "linux") {
        Path::new("/proc").join(pid.to_string()).exists()
    } else {
        true
    }
}

impl LogUnit {
    /// Start the unit for `<root>/<name>`: create `root` if needed and an
    /// empty staging directory.
    pub fn begin(root: &Path, name: &str) -> Result<LogUnit, LogError> {
        fs::create_dir_all(root).map_err(io("cannot create", root))?;
        for old in stale_staging(root, name) {
            let _ = fs::remove_dir_all(old);
        }
        let staging = root.join(format!(".{name}.partial-{}", std::process::id()));
        if staging.exists() {
            fs::remove_dir_all(&staging).map_err(io("cannot remove stale", &staging))?;
        }
        fs::create_dir(&staging).map_err(io("cannot create", &staging))?;
        Ok(LogUnit {
            staging,
            target: root.join(name),
            committed: false,
        })
    }

    /// Where to write the files.
    pub fn dir(&self) -> &Path {
        &self.staging
    }

    /// The final directory.
    pub fn target(&self) -> &Path {
        &self.target
    }

    /// Replace the target directory with the staging directory; returns the target.
    pub fn commit(mut self) -> Result<PathBuf, LogError> {
        // Persist the files before they become visible under the target name.
        for e in fs::read_dir(&self.staging)
            .map_err(io("cannot list", &self.staging))?
            .flatten()
        {
            let p = e.path();
            fs::File::open(&p)
                .and_then(|f| f.sync_all())
                .map_err(io("cannot sync", &p))?;
        }
        let old = self.staging.with_file_name(format!(
            ".{}.old-{}",
            file_name(&self.target),
            std::process::id()
        ));
        if old.exists() {
            fs::remove_dir_all(&old).map_err(io("cannot remove stale", &old))?;
        }
        let had_old = match fs::rename(&self.target, &old) {
            Ok(()) => true,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => false,
            Err(e) => return Err(io("cannot move aside", &self.target)(e)),
        };
        fs::rename(&self.staging, &self.target)
            .map_err(io("cannot rename staging directory to", &self.target))?;
        self.committed = true;
        if had_old {
            let _ = fs::remove_dir_all(&old);
        }
        Ok(self.target.clone())
    }
}

fn file_name(p: &Path) -> String {
    p.file_name()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default()
}

impl Drop for LogUnit {
    fn drop(&mut self) {
        if !self.committed {
            let _ = fs::remove_dir_all(&self.staging);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .flatten()
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn commit_replaces_the_whole_directory() {
        let root = tempfile::tempdir().unwrap();
        let u = LogUnit::begin(root.path(), "a").unwrap();
        fs::write(u.dir().join("run.mcap"), "1").unwrap();
        fs::write(u.dir().join("summary.json"), "1").unwrap();
        let target = u.commit().unwrap();
        assert_eq!(names(&target), ["run.mcap", "summary.json"]);
        // A second run with a different set of files: nothing of the first stays.
        let u = LogUnit::begin(root.path(), "a").unwrap();
        fs::write(u.dir().join("sweep.json"), "2").unwrap();
        assert_eq!(
            names(&target),
            ["run.mcap", "summary.json"],
            "not before commit"
        );
        u.commit().unwrap();
        assert_eq!(names(&target), ["sweep.json"]);
        assert_eq!(
            names(root.path()),
            ["a"],
            "no staging or old directory left"
        );
    }

    #[test]
    fn an_abandoned_unit_leaves_the_previous_set() {
        let root = tempfile::tempdir().unwrap();
        let u = LogUnit::begin(root.path(), "a").unwrap();
        fs::write(u.dir().join("run.mcap"), "1").unwrap();
        u.commit().unwrap();
        let u = LogUnit::begin(root.path(), "a").unwrap();
        fs::write(u.dir().join("run.mcap"), "2").unwrap();
        drop(u);
        assert_eq!(names(root.path()), ["a"]);
        assert_eq!(
            fs::read_to_string(root.path().join("a/run.mcap")).unwrap(),
            "1"
        );
    }

    #[test]
    fn staging_of_a_dead_process_is_removed() {
        let root = tempfile::tempdir().unwrap();
        // No process has pid u32::MAX - 1 (above Linux's pid_max).
        let dead = root.path().join(format!(".a.partial-{}", u32::MAX - 1));
        fs::create_dir(&dead).unwrap();
        let u = LogUnit::begin(root.path(), "a").unwrap();
        if cfg!(target_os = "linux") {
            assert!(!dead.exists());
        }
        u.commit().unwrap();
    }
}
