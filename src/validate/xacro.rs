//! Robot descriptions that hold xacro markup ([`markup`]: read as XML):
//! expanded by the `xacro` command (`pip install xacro`) when it is on
//! `PATH`. The harness never expands xacro itself: an unexpanded `${...}`
//! must not reach a link name.
//!
//! xacro resolves `$(find PKG)` through ROS 2's package index
//! (`ament_index_python`), which is not on PyPI. The harness writes a small
//! module of that name (`shim`) first on xacro's `PYTHONPATH`, answering
//! from the packages the meshes are found in too
//! ([`crate::engine::mesh::Search`]); absent packages are collected
//! through the whole expansion and named together, or expanded to nothing
//! (`[model] missing_packages = "empty"`).

mod markup;
mod shim;

pub use markup::{leftover, markup, Found, Markup};
pub use shim::Absent;

use crate::engine::mesh::Search;
use crate::engine::packages::MissingPackages;
use crate::engine::urdf::Source;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How long `xacro` may take before it is stopped.
const TIMEOUT: Duration = Duration::from_secs(60);

/// Longest excerpt of xacro's own message kept in an error, characters.
const MAX_MESSAGE: usize = 400;

/// Why a description could not be expanded. Each is one line.
#[derive(Debug, thiserror::Error)]
pub enum XacroError {
    /// The `xacro` command is not on `PATH`.
    #[error("this robot description holds xacro markup ({why}): install the `xacro` command (`pip install xacro`) so the harness can expand it, or expand it yourself (`xacro FILE > robot.urdf`)")]
    NotInstalled {
        /// What markup it holds.
        why: &'static str,
    },
    /// The scratch directory for xacro's package resolver.
    #[error("cannot prepare xacro's package resolver: {0}")]
    Scratch(std::io::Error),
    /// The command did not start.
    #[error("xacro ({}) did not start: {source}", .path.display())]
    DidNotStart {
        /// The command.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// It ran too long and was stopped.
    #[error("xacro did not finish within {} s", TIMEOUT.as_secs())]
    Timeout,
    /// It failed: its own first error, with where it was.
    #[error("xacro failed: {message}")]
    Failed {
        /// xacro's first error line and its context.
        message: String,
    },
    /// Packages the expansion needs are not found.
    #[error("{}", shim::absent_error(.absent, .urdf))]
    AbsentPackages {
        /// Each absent package and the files that look it up.
        absent: Vec<Absent>,
        /// The description expanded.
        urdf: PathBuf,
    },
    /// The expansion still holds xacro markup.
    #[error("after xacro, {} (line {} of the expansion) still holds {}: pass its arguments in [model] xacro_args", .0.place, .0.line, .0.what)]
    Leftover(Found),
}

/// Whether the `xacro` command is on `PATH`.
pub(crate) fn available() -> bool {
    xacro_on_path().is_some()
}

/// The `xacro` command, if it is on `PATH`.
fn xacro_on_path() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("xacro"))
        .find(|p| p.is_file())
}

/// A description expanded by xacro.
#[derive(Debug, Clone)]
pub struct Expansion {
    /// The URDF xacro wrote.
    pub text: String,
    /// Packages that were absent, each of whose includes expanded to
    /// nothing (only with `missing_packages = "empty"`).
    pub absent: Vec<Absent>,
}

/// Expand the xacro file `path` (whose markup is `why`) with the scenario's
/// `xacro_args`, its packages found through `search`.
pub(crate) fn expand(
    path: &Path,
    why: &'static str,
    source: &Source,
    search: &Search,
) -> Result<Expansion, XacroError> {
    let Some(xacro) = xacro_on_path() else {
        return Err(XacroError::NotInstalled { why });
    };
    let resolver = shim::Resolver::write(&search.known()).map_err(XacroError::Scratch)?;
    let file = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut cmd = Command::new(&xacro);
    cmd.arg(&file)
        .args(source.xacro_args.iter().map(|(k, v)| format!("{k}:={v}")))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    resolver.configure(&mut cmd);
    let (status, text, stderr) = run(cmd, &xacro)?;
    let absent = resolver.absent();
    let urdf = path.to_path_buf();
    if !absent.is_empty() && source.missing_packages == MissingPackages::Error {
        // The absent packages explain a failure better than xacro does (an
        // unknown macro of an accessory, say).
        return Err(XacroError::AbsentPackages { absent, urdf });
    }
    if !status.success() {
        // Files in the description's own directory as the user names them.
        let mut message = match file.parent() {
            Some(d) => first_error(&stderr).replace(&format!("{}/", d.display()), ""),
            None => first_error(&stderr),
        };
        if !absent.is_empty() {
            let names: Vec<String> = absent.iter().map(|a| format!("`{}`", a.package)).collect();
            message.push_str(&format!(
                " (absent packages expanded to nothing: {})",
                names.join(", ")
            ));
        }
        return Err(XacroError::Failed { message });
    }
    if let Some(found) = leftover(&text) {
        return Err(XacroError::Leftover(found));
    }
    Ok(Expansion { text, absent })
}

/// Run `cmd` (xacro at `xacro`) to its end: status, stdout, stderr.
fn run(
    mut cmd: Command,
    xacro: &Path,
) -> Result<(std::process::ExitStatus, String, String), XacroError> {
    let mut child = cmd.spawn().map_err(|source| XacroError::DidNotStart {
        path: xacro.to_path_buf(),
        source,
    })?;
    // Read both pipes on threads, so a chatty xacro never blocks on a full pipe.
    let reader = |pipe: Option<Box<dyn Read + Send>>| {
        std::thread::spawn(move || {
            let mut s = String::new();
            if let Some(mut p) = pipe {
                let _ = p.read_to_string(&mut s);
            }
            s
        })
    };
    let out = reader(
        child
            .stdout
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let err = reader(
        child
            .stderr
            .take()
            .map(|p| Box::new(p) as Box<dyn Read + Send>),
    );
    let t0 = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break s,
            Ok(None) if t0.elapsed() > TIMEOUT => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(XacroError::Timeout);
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(10)),
            Err(source) => {
                return Err(XacroError::DidNotStart {
                    path: xacro.to_path_buf(),
                    source,
                })
            }
        }
    };
    Ok((
        status,
        out.join().unwrap_or_default(),
        err.join().unwrap_or_default(),
    ))
}

/// xacro's own first error and where it was, on one line: `name 'nope' is
/// not defined (when evaluating expression 'nope'; in macro `wheel`; in
/// file robot.urdf.xacro)`. Warnings before it are left out.
pub(crate) fn first_error(stderr: &str) -> String {
    let plain = strip_ansi(stderr);
    let lines: Vec<&str> = plain.lines().map(str::trim).collect();
    let is_error = |l: &&str| l.starts_with("error:") || l.starts_with("XML parsing error");
    let Some(start) = lines.iter().position(is_error) else {
        return lines
            .iter()
            .rev()
            .find(|l| !l.is_empty() && !l.starts_with("warning:"))
            .map_or("(no message)".to_string(), |l| bounded(l));
    };
    let first = lines[start]
        .strip_prefix("error:")
        .unwrap_or(lines[start])
        .trim();
    let mut context: Vec<String> = Vec::new();
    let (mut expr, mut mac, mut file) = (false, false, false);
    for l in &lines[start + 1..] {
        if l.is_empty() {
            break;
        }
        if let Some(e) = l.strip_prefix("when evaluating expression") {
            if !expr {
                context.push(format!("when evaluating expression{e}"));
                expr = true;
            }
        } else if let Some(m) = l.strip_prefix("when instantiating macro:") {
            if !mac {
                let name = m.split(" (").next().unwrap_or(m).trim();
                context.push(format!("in macro `{name}`"));
                mac = true;
            }
        } else if let Some(f) = l
            .strip_prefix("in file:")
            .or_else(|| l.strip_prefix("when processing file:"))
        {
            if !file {
                context.push(format!("in {}", f.trim()));
                file = true;
            }
        }
    }
    let text = if context.is_empty() {
        first.to_string()
    } else {
        format!("{first} ({})", context.join("; "))
    };
    bounded(&text)
}

/// `s` on one line and at most [`MAX_MESSAGE`] characters.
fn bounded(s: &str) -> String {
    let s = s.split_whitespace().collect::<Vec<_>>().join(" ");
    let n = s.chars().count();
    if n <= MAX_MESSAGE {
        return s;
    }
    let head: String = s.chars().take(MAX_MESSAGE).collect();
    format!("{head}… ({n} characters)")
}

/// `s` without ANSI colour sequences (xacro colours its messages on a terminal).
fn strip_ansi(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' && chars.peek() == Some(&'[') {
            for d in chars.by_ref() {
                if d.is_ascii_alphabetic() {
                    break;
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// The warning of an expansion whose absent packages expanded to nothing.
pub(crate) fn absent_warning(absent: &[Absent], urdf: &Path) -> String {
    let (noun, pronoun) = if absent.len() == 1 {
        ("package", "its")
    } else {
        ("packages", "their")
    };
    format!(
        "xacro found no {noun} {}: {pronoun} includes expanded to nothing ([model] missing_packages = \"empty\")",
        shim::absent_list(absent, urdf)
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xacros_first_error_is_kept_with_where_it_was() {
        let undefined = "error: name 'nope' is not defined \nwhen evaluating expression 'nope'\nwhen instantiating macro: w (/a/undef.urdf.xacro)\nin file: /a/undef.urdf.xacro\n";
        assert_eq!(
            first_error(undefined),
            "name 'nope' is not defined (when evaluating expression 'nope'; in macro `w`; in /a/undef.urdf.xacro)"
        );
        let arg = "warning: Include tag's filename spec \"x\" matched no files.\nerror: Undefined substitution argument prefix\nwhen processing file: /a/arg.urdf.xacro\n";
        assert_eq!(
            first_error(arg),
            "Undefined substitution argument prefix (in /a/arg.urdf.xacro)"
        );
        let xml = "XML parsing error: mismatched tag: line 4, column 2\nwhen processing file: s.xacro\n\nCheck that:\n - Your XML is well-formed\n";
        assert_eq!(
            first_error(xml),
            "XML parsing error: mismatched tag: line 4, column 2 (in s.xacro)"
        );
        assert_eq!(first_error("\u{1b}[91merror: boom\u{1b}[0m\n"), "boom");
        assert_eq!(first_error(""), "(no message)");
        let long = format!("error: {}", "x ".repeat(1000));
        assert!(first_error(&long).ends_with("(1999 characters)"));
    }
}
