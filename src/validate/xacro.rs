//! Robot descriptions that still hold xacro markup: recognised, and
//! expanded by the `xacro` command (`pip install xacro`) when it is on
//! `PATH`. The harness never reads xacro itself: an unexpanded `${...}`
//! must not reach a link name.

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How long `xacro` may take before it is stopped.
const TIMEOUT: Duration = Duration::from_secs(60);

/// How much of xacro a robot description holds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Markup {
    /// Only the namespace declaration: plain URDF that xacro would leave as
    /// it is (published descriptions often declare it and use none).
    Namespace,
    /// Elements or substitutions that only xacro can expand (the reason).
    Needed(&'static str),
}

/// The xacro in `text`, if any: `<xacro:...>` elements, `${...}` or
/// `$(...)` substitutions, or the namespace alone.
pub fn markup(text: &str) -> Option<Markup> {
    if text.contains("<xacro:") {
        Some(Markup::Needed("<xacro:...> elements"))
    } else if text.contains("${") || text.contains("$(") {
        Some(Markup::Needed("${...} or $(...) substitutions"))
    } else if text.contains("xmlns:xacro") {
        Some(Markup::Namespace)
    } else {
        None
    }
}

/// Whether the `xacro` command is on `PATH`.
pub fn available() -> bool {
    xacro_on_path().is_some()
}

/// The `xacro` command, if it is on `PATH`.
fn xacro_on_path() -> Option<std::path::PathBuf> {
    let path = std::env::var_os("PATH")?;
    std::env::split_paths(&path)
        .map(|d| d.join("xacro"))
        .find(|p| p.is_file())
}

/// Expand the xacro file `path` (whose markup is `why`) with `args`
/// (`name:=value`); the error is one line.
pub fn expand(path: &Path, why: &str, args: &BTreeMap<String, String>) -> Result<String, String> {
    let Some(xacro) = xacro_on_path() else {
        return Err(format!(
            "this robot description holds xacro markup ({why}): install the `xacro` command (`pip install xacro`) so the harness can expand it, or expand it yourself (`xacro FILE > robot.urdf`)"
        ));
    };
    let mut cmd = Command::new(&xacro);
    cmd.arg(path)
        .args(args.iter().map(|(k, v)| format!("{k}:={v}")))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let mut child = cmd
        .spawn()
        .map_err(|e| format!("xacro ({}) did not start: {e}", xacro.display()))?;
    // Read both pipes on threads, so a chatty xacro never blocks on a full pipe.
    let mut out = child.stdout.take().expect("piped");
    let mut err = child.stderr.take().expect("piped");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let err_reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    let t0 = Instant::now();
    let status = loop {
        match child.try_wait() {
            Ok(Some(s)) => break s,
            Ok(None) if t0.elapsed() > TIMEOUT => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!(
                    "xacro did not finish within {} s",
                    TIMEOUT.as_secs()
                ));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(10)),
            Err(e) => return Err(format!("xacro: {e}")),
        }
    };
    let text = reader.join().unwrap_or_default();
    let stderr = err_reader.join().unwrap_or_default();
    if !status.success() {
        let last = stderr
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("(no message)");
        return Err(format!("xacro failed ({status}): {}", last.trim()));
    }
    if let Some(name) = unexpanded_name(&text) {
        return Err(format!(
            "after xacro, the name `{name}` still holds a substitution: pass its arguments in [model] xacro_args"
        ));
    }
    Ok(text)
}

/// A `name="..."` attribute that still holds `${` or `$(`.
pub fn unexpanded_name(text: &str) -> Option<String> {
    for q in ['"', '\''] {
        let pat = format!("name={q}");
        for (i, _) in text.match_indices(&pat) {
            let rest = &text[i + pat.len()..];
            let name = rest.split(q).next().unwrap_or("");
            if name.contains("${") || name.contains("$(") {
                return Some(name.to_string());
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn markup_is_recognised() {
        assert_eq!(
            markup("<robot xmlns:xacro=\"http://ros.org/wiki/xacro\">"),
            Some(Markup::Namespace)
        );
        assert!(matches!(
            markup("<xacro:macro name=\"w\"/>"),
            Some(Markup::Needed(_))
        ));
        assert!(matches!(
            markup("<link name=\"${ns}base\"/>"),
            Some(Markup::Needed(_))
        ));
        assert!(markup("<link name=\"base\"/>").is_none());
        assert_eq!(
            unexpanded_name("<link name=\"${prefix}base\"/>").as_deref(),
            Some("${prefix}base")
        );
        assert_eq!(unexpanded_name("<link name='base'/>"), None);
    }
}
