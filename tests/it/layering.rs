//! Configuration flows one way: the scenario layer parses files and hands
//! each system its own typed configuration, so nothing below it (systems,
//! planners, models, physics, plans, records, logs) imports
//! `crate::scenario`, and the scenario layer imports nothing above it.
//! Checked on the source text, so a new file is covered too.

use std::path::{Path, PathBuf};

fn rust_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            out.extend(rust_files(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
    out.sort();
    out
}

/// Lines of `file` that mention one of `modules` as a crate path.
fn uses(file: &Path, modules: &[&str]) -> Vec<String> {
    let text = std::fs::read_to_string(file).unwrap();
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .filter(|l| {
            modules.iter().any(|m| {
                l.contains(&format!("crate::{m}")) || l.contains(&format!("super::super::{m}"))
            })
        })
        .map(|l| format!("{}: {}", file.display(), l.trim()))
        .collect()
}

#[test]
fn nothing_below_the_scenario_layer_imports_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let below = ["model", "planner", "physics", "systems", "log"]
        .iter()
        .flat_map(|d| rust_files(&src.join(d)))
        .chain(
            [
                "plan",
                "integrate",
                "compare",
                "record",
                "error",
                "input",
                "progress",
            ]
            .iter()
            .map(|f| src.join(format!("{f}.rs"))),
        )
        .collect::<Vec<_>>();
    assert!(below.len() > 25, "{below:?}");
    let bad: Vec<String> = below
        .iter()
        .flat_map(|f| uses(f, &["scenario", "validate", "runner", "sweep", "suite"]))
        .collect();
    assert!(
        bad.is_empty(),
        "imports against the flow:\n{}",
        bad.join("\n")
    );
}

#[test]
fn the_scenario_layer_imports_nothing_above_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let bad: Vec<String> = rust_files(&src.join("scenario"))
        .iter()
        .flat_map(|f| uses(f, &["validate", "runner", "sweep", "log"]))
        .collect();
    assert!(
        bad.is_empty(),
        "scenario imports from above:\n{}",
        bad.join("\n")
    );
    let bad: Vec<String> = rust_files(&src.join("validate"))
        .iter()
        .flat_map(|f| uses(f, &["runner", "sweep"]))
        .collect();
    assert!(
        bad.is_empty(),
        "validate imports from above:\n{}",
        bad.join("\n")
    );
}

/// The test can fail: a file that imports the scenario layer is caught.
#[test]
fn an_offending_import_is_detected() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("x.rs");
    std::fs::write(
        &f,
        "use crate::scenario::PlannerConfig;\n// crate::scenario in a comment\n",
    )
    .unwrap();
    assert_eq!(uses(&f, &["scenario"]).len(), 1);
    // The `[sim]` table type is no exception: physics takes `PhysicsSettings`.
    std::fs::write(&f, "use crate::scenario::SimConfig;\n").unwrap();
    assert_eq!(uses(&f, &["scenario"]).len(), 1);
}

/// The module path of a source file (`src/physics/engine/world.rs` →
/// `physics::engine::world`; `mod.rs` and `lib.rs` name their directory).
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts.last().is_some_and(|p| p == "mod" || p == "lib") {
        parts.pop();
    }
    parts
}

/// Every module path a line names: `crate::a::b`, `super::c` (resolved from
/// `module`), and the items of a `use P::{x, y::z}` group.
fn paths_in(line: &str, module: &[String]) -> Vec<Vec<String>> {
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let mut rest = line;
    while let Some(i) = rest.find(['c', 's']) {
        let tail = &rest[i..];
        let before_ok = i == 0 || !rest[..i].ends_with(|c: char| ident(c) || c == ':');
        let (base, skip) = if before_ok && tail.starts_with("crate::") {
            (Vec::new(), "crate::".len())
        } else if before_ok && tail.starts_with("super::") {
            // A module's path names the module itself (`a/b.rs` and
            // `a/b/mod.rs` are both `a::b`): each `super` drops one name.
            let mut b = module.to_vec();
            let mut t = tail;
            let mut n = 0;
            while t.starts_with("super::") {
                t = &t["super::".len()..];
                n += 1;
            }
            for _ in 0..n {
                b.pop();
            }
            (b, tail.len() - t.len())
        } else {
            rest = &rest[i + 1..];
            continue;
        };
        let t = &tail[skip..];
        let end = t.find(|c: char| !(ident(c) || c == ':')).unwrap_or(t.len());
        let path: Vec<String> = t[..end]
            .split("::")
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect();
        let mut full = base.clone();
        full.extend(path.iter().cloned());
        // A group `P::{a, b::c}`: each item too.
        if t[end..].starts_with('{') {
            if let Some(close) = t[end..].find('}') {
                for item in t[end + 1..end + close].split(',') {
                    let item = item.trim().split(" as ").next().unwrap_or("").trim();
                    let mut p = full.clone();
                    p.extend(
                        item.split("::")
                            .filter(|s| !s.is_empty() && *s != "self" && *s != "*")
                            .map(String::from),
                    );
                    out.push(p);
                }
            }
        }
        out.push(full);
        rest = &tail[skip + end..];
    }
    out
}

/// The lines of `text` outside `#[cfg(test)]` modules (tests may borrow
/// another file's test helpers: that is no circle of the code).
fn code_lines(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let (mut depth, mut skip_until, mut armed) = (0i64, None::<i64>, false);
    for line in text.lines() {
        let t = line.trim_start();
        if t.starts_with("//") {
            continue;
        }
        let test_mod =
            armed && (t.starts_with("mod ") || t.starts_with("pub(crate) mod ")) && t.contains('{');
        if skip_until.is_none() && test_mod {
            skip_until = Some(depth);
        }
        armed = t.starts_with("#[cfg(test)]");
        let opens = line.matches('{').count() as i64;
        let closes = line.matches('}').count() as i64;
        if skip_until.is_none() {
            out.push(line);
        }
        depth += opens - closes;
        if skip_until.is_some_and(|d| depth <= d) && closes > 0 {
            skip_until = None;
        }
    }
    out
}

/// Import circles between files: two files, neither the other's parent
/// module, that each name the other (test modules left out). The world
/// loader and the batch, the margin search's early stop and its level
/// runner were such pairs.
fn import_circles(src: &Path) -> Vec<String> {
    let files = rust_files(src);
    let modules: Vec<(Vec<String>, &PathBuf)> =
        files.iter().map(|f| (module_of(src, f), f)).collect();
    let is_module = |p: &[String]| modules.iter().position(|(m, _)| m.as_slice() == p);
    // Re-exported modules (`pub use engine::{world, ...}` in a mod.rs).
    let mut alias: Vec<(Vec<String>, Vec<String>)> = Vec::new();
    for (m, f) in &modules {
        if !f.ends_with("mod.rs") {
            continue;
        }
        let text = std::fs::read_to_string(f).unwrap().replace('\n', " ");
        for part in text.split("pub use ").skip(1) {
            let Some((head, tail)) = part.split_once("::{") else {
                continue;
            };
            let Some((items, _)) = tail.split_once('}') else {
                continue;
            };
            for item in items.split(',').map(str::trim).filter(|s| !s.is_empty()) {
                let mut from = m.clone();
                from.push(item.to_string());
                let mut to = m.clone();
                to.push(head.trim().to_string());
                to.push(item.to_string());
                if is_module(&to).is_some() {
                    alias.push((from, to));
                }
            }
        }
    }
    let resolve = |p: &[String]| -> Option<usize> {
        for n in (1..=p.len()).rev() {
            let mut q = p[..n].to_vec();
            if let Some((_, to)) = alias.iter().find(|(from, _)| q.starts_with(from)) {
                let rest = q.split_off(to.len().min(q.len()).min(n));
                let _ = rest;
                q = to.clone();
            }
            if let Some(i) = is_module(&q) {
                return Some(i);
            }
        }
        None
    };
    let mut edges = std::collections::BTreeSet::new();
    for (i, (m, f)) in modules.iter().enumerate() {
        let text = std::fs::read_to_string(f).unwrap();
        for line in code_lines(&text) {
            for p in paths_in(line, m) {
                if let Some(j) = resolve(&p) {
                    if j != i {
                        edges.insert((i, j));
                    }
                }
            }
        }
    }
    let ancestor = |a: &[String], b: &[String]| b.len() > a.len() && b.starts_with(a);
    let mut out = Vec::new();
    for &(i, j) in &edges {
        let (a, b) = (&modules[i].0, &modules[j].0);
        if i < j && edges.contains(&(j, i)) && !ancestor(a, b) && !ancestor(b, a) {
            out.push(format!(
                "{} <-> {}",
                modules[i].1.display(),
                modules[j].1.display()
            ));
        }
    }
    out
}

#[test]
fn no_two_files_import_each_other() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let circles = import_circles(&src);
    assert!(
        circles.is_empty(),
        "import circles:\n{}",
        circles.join("\n")
    );
}

/// The rule can fail: two sibling files that name each other are caught.
#[test]
fn an_import_circle_is_detected() {
    let dir = tempfile::tempdir().unwrap();
    let m = dir.path().join("m");
    std::fs::create_dir(&m).unwrap();
    std::fs::write(m.join("mod.rs"), "pub mod a;\npub mod b;\n").unwrap();
    std::fs::write(m.join("a.rs"), "use super::b::Thing;\n").unwrap();
    std::fs::write(m.join("b.rs"), "use crate::m::{a::Other, b};\n").unwrap();
    std::fs::write(dir.path().join("lib.rs"), "pub mod m;\n").unwrap();
    assert_eq!(import_circles(dir.path()).len(), 1);
    std::fs::write(m.join("b.rs"), "// crate::m::a in a comment\n").unwrap();
    assert!(import_circles(dir.path()).is_empty());
}

/// The integration tests are one binary (`autotests = false`): a file
/// directly in `tests/` would not be built at all, and a file in `tests/it/`
/// that `main.rs` does not declare would not run.
#[test]
fn every_test_file_is_a_module_of_this_binary() {
    let tests = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests");
    let stray: Vec<_> = std::fs::read_dir(&tests)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .collect();
    assert!(
        stray.is_empty(),
        "move into tests/it/ and declare in tests/it/main.rs: {stray:?}"
    );
    let main = std::fs::read_to_string(tests.join("it/main.rs")).unwrap();
    let undeclared: Vec<_> = std::fs::read_dir(tests.join("it"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "rs"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .filter(|m| m != "main" && !main.lines().any(|l| l.trim() == format!("mod {m};")))
        .collect();
    assert!(
        undeclared.is_empty(),
        "declare in tests/it/main.rs: {undeclared:?}"
    );
}

/// Lines of the library's files (everything under `src/` but the binary's
/// `main.rs` and `cmd/`) that name clap: argument parsing is the binary's,
/// as ripgrep keeps it. (The suite's and sweeps' progress bars still draw
/// from the library.)
fn cli_code_in_library(src: &Path) -> Vec<String> {
    let binary = [src.join("main.rs"), src.join("cmd")];
    rust_files(src)
        .into_iter()
        .filter(|f| !binary.iter().any(|b| f.starts_with(b)))
        .flat_map(|f| {
            let text = std::fs::read_to_string(&f).unwrap();
            code_lines(&text)
                .into_iter()
                .filter(|l| l.contains("clap::"))
                .map(|l| format!("{}: {}", f.display(), l.trim()))
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn the_library_has_no_command_line_code() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let found = cli_code_in_library(&src);
    assert!(
        found.is_empty(),
        "CLI code in the library:\n{}",
        found.join("\n")
    );
}

#[test]
fn command_line_code_in_the_library_is_detected() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir_all(dir.path().join("cmd")).unwrap();
    std::fs::write(dir.path().join("main.rs"), "use clap::Parser;\n").unwrap();
    std::fs::write(dir.path().join("cmd/cli.rs"), "#[derive(clap::Args)]\n").unwrap();
    std::fs::write(
        dir.path().join("init.rs"),
        "#[derive(clap::Args)]\nstruct A;\n",
    )
    .unwrap();
    let found = cli_code_in_library(dir.path());
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].contains("init.rs"));
}
