//! Every fenced shell (`sh`, `bash`, `console`) and TOML snippet of README.md
//! and the guide (docs/src/) runs, so the docs cannot drift from the tool.
//!
//! A line just before a fence says how a snippet is run, in an HTML comment
//! (mdBook and GitHub do not show it):
//! - `<!-- snippet: not run (REASON) -->`: left out, for the reason given
//!   (network, Docker, a build, a viewer);
//! - `<!-- snippet: onto FILE -->` (TOML): the snippet's keys are laid over
//!   the repository's scenario FILE and the result, written beside it, must
//!   pass `anholonomy list` (full validation: keys, URDF, plan, physics);
//! - none: a shell snippet runs in a copy of the repository (files as
//!   symlinks; its
//!   `anholonomy` and `target/release/anholonomy` are the binary under test;
//!   `my_scenarios/` holds a copy of scenarios/disk_paper.toml) and must exit
//!   0; a TOML snippet must be a whole scenario, checked as above from
//!   scenarios/.

use crate::common::*;
use std::path::{Path, PathBuf};
use std::process::Command;

struct Snippet {
    at: String,
    lang: String,
    mark: Option<String>,
    text: String,
}

fn markdown_files() -> Vec<PathBuf> {
    fn walk(d: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "md") {
                out.push(p);
            }
        }
    }
    let mut out = vec![root().join("README.md")];
    walk(&root().join("docs/src"), &mut out);
    out.sort();
    out
}

fn snippets() -> Vec<Snippet> {
    let mut out = Vec::new();
    for f in markdown_files() {
        let text = std::fs::read_to_string(&f).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let mut i = 0;
        while i < lines.len() {
            let t = lines[i].trim_start();
            let Some(lang) = t.strip_prefix("```") else {
                i += 1;
                continue;
            };
            let indent = lines[i].len() - t.len();
            let lang = lang.trim().to_string();
            let end = (i + 1..lines.len())
                .find(|&j| lines[j].trim_start().starts_with("```"))
                .unwrap_or(lines.len());
            if ["sh", "bash", "console", "toml"].contains(&lang.as_str()) {
                let mark = (i > 0)
                    .then(|| lines[i - 1].trim())
                    .and_then(|l| l.strip_prefix("<!-- snippet:"))
                    .and_then(|l| l.strip_suffix("-->"))
                    .map(|m| m.trim().to_string());
                let body: Vec<&str> = lines[i + 1..end]
                    .iter()
                    .map(|l| l.get(indent..).unwrap_or(l.trim_start()))
                    .collect();
                out.push(Snippet {
                    at: format!("{}:{}", f.strip_prefix(root()).unwrap().display(), i + 1),
                    lang,
                    mark,
                    text: body.join("\n") + "\n",
                });
            }
            i = end + 1;
        }
    }
    out
}

/// `dir` as a copy of the repository: real directories (so `..` in a
/// scenario's paths stays inside the copy) holding symlinks to the files;
/// no `target/`, `logs/` or `.git`.
fn mirror(dir: &Path) {
    fn walk(from: &Path, to: &Path, top: bool) {
        std::fs::create_dir_all(to).unwrap();
        for e in std::fs::read_dir(from).unwrap().flatten() {
            let name = e.file_name();
            if top && ["target", "logs", ".git"].contains(&name.to_str().unwrap_or("")) {
                continue;
            }
            if e.file_type().unwrap().is_dir() {
                walk(&e.path(), &to.join(&name), false);
            } else {
                std::os::unix::fs::symlink(e.path(), to.join(&name)).unwrap();
            }
        }
    }
    walk(&root(), dir, true);
}

/// Deep merge: tables merge key by key, anything else is replaced.
fn overlay(base: &mut toml::Table, top: toml::Table) {
    for (k, v) in top {
        match (base.get_mut(&k), v) {
            (Some(toml::Value::Table(b)), toml::Value::Table(t)) => overlay(b, t),
            (_, v) => {
                base.insert(k, v);
            }
        }
    }
}

/// PATH with the binary under test first (and `xacro` from the test venv
/// when PATH has none).
fn path_env(bin_dir: &Path) -> std::ffi::OsString {
    let old: Vec<PathBuf> =
        std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default()).collect();
    let mut dirs = vec![bin_dir.to_path_buf()];
    if !old.iter().any(|d| d.join("xacro").is_file()) {
        dirs.push(python::venv_bin());
    }
    dirs.extend(old);
    std::env::join_paths(dirs).unwrap()
}

fn bin_dir(tmp: &Path) -> PathBuf {
    let d = tmp.join(".bin");
    std::fs::create_dir_all(&d).unwrap();
    let _ = std::os::unix::fs::symlink(env!("CARGO_BIN_EXE_anholonomy"), d.join("anholonomy"));
    d
}

fn check_toml(s: &Snippet) -> Result<(), String> {
    let top: toml::Table = s.text.parse().map_err(|e| format!("not TOML: {e}"))?;
    let (file, mut doc) = match s.mark.as_deref().and_then(|m| m.strip_prefix("onto ")) {
        Some(base) => {
            let text = std::fs::read_to_string(root().join(base.trim()))
                .map_err(|e| format!("onto {base}: {e}"))?;
            (
                PathBuf::from(base.trim()),
                text.parse::<toml::Table>().unwrap(),
            )
        }
        None if top.contains_key("start") => {
            (PathBuf::from("scenarios/x.toml"), toml::Table::new())
        }
        None => {
            return Err(
                "a TOML fragment: mark it `<!-- snippet: onto FILE -->` or `not run (why)`".into(),
            )
        }
    };
    overlay(&mut doc, top);
    let tmp = tempfile::tempdir().unwrap();
    let dir = file.parent().unwrap();
    mirror(tmp.path());
    let path = tmp.path().join(dir).join("doc_snippet.toml");
    std::fs::write(&path, toml::to_string(&doc).unwrap()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .current_dir(tmp.path())
        .env("PATH", path_env(&bin_dir(tmp.path())))
        .arg("list")
        .arg(&path)
        .output()
        .unwrap();
    if out.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&out.stderr).trim().to_string())
    }
}

fn check_shell(s: &Snippet) -> Result<(), String> {
    let tmp = tempfile::tempdir().unwrap();
    mirror(tmp.path());
    std::fs::create_dir_all(tmp.path().join("target/release")).unwrap();
    std::os::unix::fs::symlink(
        env!("CARGO_BIN_EXE_anholonomy"),
        tmp.path().join("target/release/anholonomy"),
    )
    .unwrap();
    std::fs::create_dir_all(tmp.path().join("my_scenarios")).unwrap();
    std::fs::copy(
        root().join("scenarios/disk_paper.toml"),
        tmp.path().join("my_scenarios/disk_paper.toml"),
    )
    .unwrap();
    // A console snippet's commands are its `$ ` lines.
    let script = if s.lang == "console" {
        s.text
            .lines()
            .filter_map(|l| l.strip_prefix("$ "))
            .collect::<Vec<_>>()
            .join("\n")
    } else {
        s.text.clone()
    };
    let out = Command::new("timeout")
        .arg("300")
        .args(["bash", "-euo", "pipefail", "-c", &script])
        .current_dir(tmp.path())
        .env("PATH", path_env(&bin_dir(tmp.path())))
        .output()
        .unwrap();
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "{}\n{}",
            String::from_utf8_lossy(&out.stdout)
                .lines()
                .rev()
                .take(5)
                .collect::<Vec<_>>()
                .join("\n"),
            String::from_utf8_lossy(&out.stderr).trim()
        ))
    }
}

#[test]
fn every_shell_and_toml_snippet_of_the_docs_runs() {
    let all = snippets();
    assert!(all.len() > 25, "{} snippets found", all.len());
    let mut failed = Vec::new();
    let mut ran = 0;
    for s in &all {
        if let Some(m) = &s.mark {
            if let Some(why) = m.strip_prefix("not run") {
                let why = why.trim();
                assert!(
                    why.starts_with('(') && why.len() > 4,
                    "{}: `not run` needs a reason in parentheses",
                    s.at
                );
                continue;
            }
        }
        let res = if s.lang == "toml" {
            check_toml(s)
        } else {
            check_shell(s)
        };
        ran += 1;
        if let Err(e) = res {
            failed.push(format!(
                "{} ({}):\n{}\n{e}",
                s.at,
                s.lang,
                s.text.trim_end()
            ));
        }
    }
    eprintln!("{ran} of {} snippets ran", all.len());
    assert!(
        failed.is_empty(),
        "{} snippets failed:\n\n{}",
        failed.len(),
        failed.join("\n\n")
    );
}

/// The test can fail: a snippet with a typo is caught, and one without a
/// mark that is no whole scenario is refused.
#[test]
fn a_broken_snippet_is_caught() {
    let s = |lang: &str, mark: Option<&str>, text: &str| Snippet {
        at: "x.md:1".into(),
        lang: lang.into(),
        mark: mark.map(String::from),
        text: text.into(),
    };
    assert!(check_toml(&s(
        "toml",
        Some("onto scenarios/disk_paper.toml"),
        "[sim]\nfriction = 0.5\n"
    ))
    .is_ok());
    let e = check_toml(&s(
        "toml",
        Some("onto scenarios/disk_paper.toml"),
        "[sim]\nfrcition = 0.5\n",
    ))
    .unwrap_err();
    // The key typo gets the nearest key, as metric names do.
    assert!(e.contains("did you mean `friction`?"), "{e}");
    assert!(check_toml(&s("toml", None, "[sim]\nfriction = 0.5\n")).is_err());
    assert!(check_shell(&s(
        "sh",
        None,
        "anholonomy plan scenarios/disk_paper.toml\n"
    ))
    .is_ok());
    assert!(check_shell(&s("sh", None, "anholonomy plan scenarios/disk_papr.toml\n")).is_err());
}
