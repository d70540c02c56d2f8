//! Reading the user's files (scenarios, URDFs): only regular files, with a
//! size cap, as UTF-8. A FIFO would block the read for ever, a device such as
//! `/dev/zero` would be read until memory runs out: both are refused from
//! their metadata, before the file is opened.

use crate::error::Error;
use std::io::Read;
use std::path::Path;

/// Largest scenario file read, bytes.
pub const SCENARIO_MAX_BYTES: u64 = 1 << 20;
/// Largest URDF file read, bytes.
pub const URDF_MAX_BYTES: u64 = 16 << 20;

/// What a non-regular file is, for messages.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_dir() {
        return "a directory";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "not a regular file"
}

/// Why a user's file cannot be read (see [`check_regular`]); `what` names it
/// ("scenario", "URDF", "plan file").
#[derive(Debug, thiserror::Error)]
pub enum FileCheckError {
    /// Its metadata cannot be read (absent, no permission).
    #[error("cannot read {what}: {source}")]
    Unreadable {
        /// What the file is to the harness.
        what: String,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A directory, FIFO, device or socket.
    #[error("{what} must be a regular file, this is {kind}")]
    NotRegular {
        /// What the file is to the harness.
        what: String,
        /// What it is instead ("a directory", "a FIFO", ...).
        kind: &'static str,
    },
    /// Larger than the harness reads.
    #[error("{what} is {size} bytes, more than the {max} bytes a {what} may have")]
    TooLarge {
        /// What the file is to the harness.
        what: String,
        /// Its size, bytes.
        size: u64,
        /// The cap, bytes.
        max: u64,
    },
}

/// Check that `path` (after following symlinks) is a regular file of at most
/// `max` bytes; `what` names it in messages ("scenario", "URDF").
pub fn check_regular(path: &Path, what: &str, max: u64) -> Result<(), FileCheckError> {
    let meta = std::fs::metadata(path).map_err(|source| FileCheckError::Unreadable {
        what: what.into(),
        source,
    })?;
    if !meta.is_file() {
        return Err(FileCheckError::NotRegular {
            what: what.into(),
            kind: kind_of(&meta),
        });
    }
    if meta.len() > max {
        return Err(FileCheckError::TooLarge {
            what: what.into(),
            size: meta.len(),
            max,
        });
    }
    Ok(())
}

/// Read a regular file of at most `max` bytes as UTF-8 text. Errors name the
/// file (and the line of the first invalid byte for non-UTF-8 text).
pub fn read_text(path: &Path, what: &str, max: u64) -> Result<String, Error> {
    check_regular(path, what, max).map_err(|m| Error::input(path, m.to_string()))?;
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        // Cap the read too: the file may grow after the check.
        .and_then(|f| f.take(max + 1).read_to_end(&mut bytes))
        .map_err(|e| Error::input(path, format!("cannot read {what}: {e}")))?;
    if bytes.len() as u64 > max {
        return Err(Error::input(
            path,
            format!("{what} is more than the {max} bytes a {what} may have"),
        ));
    }
    String::from_utf8(bytes).map_err(|e| {
        let ok = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..ok].iter().filter(|&&b| b == b'\n').count() + 1;
        Error::Input {
            key: None,
            path: path.into(),
            line: Some(line),
            message: format!("{what} is not UTF-8 text (invalid byte at offset {ok})"),
        }
    })
}
