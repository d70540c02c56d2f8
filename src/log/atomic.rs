//! Write-to-temp-then-rename helper shared by the log writers.

use std::ffi::OsString;
use std::fs;
use std::path::{Path, PathBuf};

use crate::log::LogError;

/// `<dir>/<name>.tmp` for `<dir>/<name>`.
pub(crate) fn tmp_path(path: &Path) -> PathBuf {
    let mut name: OsString = path.file_name().map(OsString::from).unwrap_or_default();
    name.push(".tmp");
    path.with_file_name(name)
}

/// Removes the temporary file on drop unless disarmed (covers errors and panics).
struct TmpGuard<'a> {
    path: &'a Path,
    armed: bool,
}

impl Drop for TmpGuard<'_> {
    fn drop(&mut self) {
        if self.armed {
            let _ = fs::remove_file(self.path);
        }
    }
}

/// Run `write` on `<path>.tmp`; when it succeeds, sync the temporary file and
/// rename it to `path`. On any error (or panic) the temporary file is removed
/// and `path` is left untouched.
pub(crate) fn write_atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), LogError>,
) -> Result<(), LogError> {
    if path.file_name().is_none() {
        return Err(LogError::Io {
            op: "not a file path:",
            path: path.to_path_buf(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, "no file name"),
        });
    }
    let tmp = tmp_path(path);
    // A stale temporary file from a crashed earlier run is of no use.
    match fs::remove_file(&tmp) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(source) => {
            return Err(LogError::Io {
                op: "cannot remove stale",
                path: tmp,
                source,
            })
        }
    }
    let mut guard = TmpGuard {
        path: &tmp,
        armed: true,
    };
    write(&tmp)?;
    let io = |op, source| LogError::Io {
        op,
        path: tmp.clone(),
        source,
    };
    fs::File::open(&tmp)
        .and_then(|f| f.sync_all())
        .map_err(|e| io("cannot sync", e))?;
    fs::rename(&tmp, path).map_err(|source| LogError::Io {
        op: "cannot rename temporary file to",
        path: path.to_path_buf(),
        source,
    })?;
    guard.armed = false;
    Ok(())
}

/// Write a file via a temporary name in the same directory, renamed on success.
pub fn write_file(
    path: &Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<(), LogError> {
    let tmp = path.with_extension("tmp");
    let res = (|| {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        write(&mut w)?;
        std::io::Write::flush(&mut w)?;
        std::fs::rename(&tmp, path)
    })();
    res.map_err(|source| {
        let _ = std::fs::remove_file(&tmp);
        LogError::Write {
            path: path.to_path_buf(),
            source,
        }
    })
}
