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
    let below = ["model", "planner", "engine", "robots", "sources", "log"]
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

/// The text of `file` that is code: comments and `#[cfg(test)]` modules
/// left out, lines joined (a `use` group may span lines).
fn code_text(text: &str) -> String {
    code_lines(text)
        .into_iter()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The top-level modules (`src/X.rs`, `src/X/`) of a source tree, the
/// binary's `main.rs` and `cmd/` left out.
fn top_level_modules(src: &Path) -> Vec<String> {
    let mut out: Vec<String> = std::fs::read_dir(src)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.is_dir() || p.extension().is_some_and(|x| x == "rs"))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .filter(|m| !["lib", "main", "cmd"].contains(&m.as_str()))
        .collect();
    out.sort();
    out.dedup();
    out
}

/// The first name of every crate path in `code`: `crate::a::...`,
/// `super::...` resolved from `module`, and each item of a group
/// `crate::{a::x, b::{y, z}}`, however the group is nested or wrapped.
fn top_names(code: &str, module: &[String]) -> Vec<String> {
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut out = Vec::new();
    let b = code.as_bytes();
    let mut i = 0;
    while i < code.len() {
        let before_ok = i == 0 || !(ident(b[i - 1] as char) || b[i - 1] == b':');
        let tail = &code[i..];
        let (mut base, mut t) = if before_ok && tail.starts_with("crate::") {
            (Vec::new(), &tail["crate::".len()..])
        } else if before_ok && tail.starts_with("super::") {
            let mut base = module.to_vec();
            let mut t = tail;
            while let Some(r) = t.strip_prefix("super::") {
                base.pop();
                t = r;
            }
            (base, t)
        } else {
            i += tail.chars().next().map_or(1, char::len_utf8);
            continue;
        };
        if base.is_empty() && t.starts_with('{') {
            // A group straight under the crate: the first name of each item.
            let mut depth = 0;
            let mut start = true;
            for (k, c) in t.char_indices() {
                match c {
                    '{' => {
                        depth += 1;
                        start = depth == 1;
                    }
                    '}' => {
                        depth -= 1;
                        if depth == 0 {
                            t = &t[k..];
                            break;
                        }
                    }
                    ',' if depth == 1 => start = true,
                    c if start && depth == 1 && ident(c) => {
                        let name: String = t[k..].chars().take_while(|&c| ident(c)).collect();
                        out.push(name);
                        start = false;
                    }
                    c if !c.is_whitespace() => start = false,
                    _ => {}
                }
            }
        } else if base.is_empty() {
            let name: String = t.chars().take_while(|&c| ident(c)).collect();
            out.push(name);
        } else {
            out.push(base.swap_remove(0));
        }
        i = code.len() - t.len();
        i += 1;
    }
    out
}

/// Which top-level module names which: every crate path in every file of
/// the library counts (`use` lines and fully qualified paths alike).
fn top_level_edges(
    src: &Path,
) -> std::collections::BTreeMap<String, std::collections::BTreeSet<String>> {
    let mods = top_level_modules(src);
    let mut edges: std::collections::BTreeMap<_, std::collections::BTreeSet<String>> = mods
        .iter()
        .map(|m| (m.clone(), Default::default()))
        .collect();
    for f in rust_files(src) {
        let module = module_of(src, &f);
        let Some(top) = module.first().filter(|m| mods.contains(m)) else {
            continue;
        };
        let text = std::fs::read_to_string(&f).unwrap();
        for name in top_names(&code_text(&text), &module) {
            if mods.contains(&name) && &name != top {
                edges.get_mut(top).unwrap().insert(name);
            }
        }
    }
    edges
}

/// The circles of `edges`: its strongly connected components of more than
/// one module (Tarjan), each sorted.
fn circles(
    edges: &std::collections::BTreeMap<String, std::collections::BTreeSet<String>>,
) -> Vec<Vec<String>> {
    struct T<'a> {
        edges: &'a std::collections::BTreeMap<String, std::collections::BTreeSet<String>>,
        index: std::collections::BTreeMap<&'a str, usize>,
        low: std::collections::BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        out: Vec<Vec<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        let n = t.index.len();
        t.index.insert(v, n);
        t.low.insert(v, n);
        t.stack.push(v);
        for w in &t.edges[v] {
            if !t.index.contains_key(w.as_str()) {
                visit(t, w);
                let lw = t.low[w.as_str()];
                let lv = t.low.get_mut(v).unwrap();
                *lv = (*lv).min(lw);
            } else if t.stack.contains(&w.as_str()) {
                let iw = t.index[w.as_str()];
                let lv = t.low.get_mut(v).unwrap();
                *lv = (*lv).min(iw);
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = Vec::new();
            while let Some(w) = t.stack.pop() {
                comp.push(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                comp.sort();
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        edges,
        index: Default::default(),
        low: Default::default(),
        stack: Vec::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.out
}

/// No circle among the top-level modules, counting every crate path: the
/// pipeline reads one way (scenario → plan → ideal run → replay → compare →
/// logs/report), with the engine, robots and plan sources beneath it.
#[test]
fn no_circles_among_top_level_modules() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let edges = top_level_edges(&src);
    assert!(edges.len() > 25, "{:?}", edges.keys());
    let found = circles(&edges);
    let show: Vec<String> = found.iter().map(|c| c.join(" <-> ")).collect();
    assert!(
        found.is_empty(),
        "circles among top-level modules:\n{}",
        show.join("\n")
    );
}

/// The rule can fail: a circle made by a fully qualified path, a wrapped
/// nested group and `super::` is caught; comments and test modules are not
/// code.
#[test]
fn a_circle_among_top_level_modules_is_detected() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    std::fs::write(src.join("lib.rs"), "pub mod a;\npub mod b;\npub mod c;\n").unwrap();
    std::fs::write(src.join("a.rs"), "fn f() { crate::b::g() }\n").unwrap();
    std::fs::create_dir(src.join("b")).unwrap();
    std::fs::write(src.join("b/mod.rs"), "pub mod d;\n").unwrap();
    std::fs::write(
        src.join("b/d.rs"),
        "use crate::{\n    c::{x, y},\n    a::Z,\n};\n",
    )
    .unwrap();
    std::fs::write(src.join("c.rs"), "// crate::a in a comment\n").unwrap();
    let edges = top_level_edges(src);
    assert_eq!(
        circles(&edges),
        vec![vec!["a".to_string(), "b".to_string()]]
    );
    // Through `super::super::` from a nested file: c -> b -> c.
    std::fs::write(src.join("b/d.rs"), "use crate::c::x;\n").unwrap();
    std::fs::create_dir(src.join("c")).unwrap();
    std::fs::remove_file(src.join("c.rs")).unwrap();
    std::fs::write(src.join("c/mod.rs"), "pub mod e;\n").unwrap();
    std::fs::write(src.join("c/e.rs"), "fn h() { super::super::b::d::k() }\n").unwrap();
    assert_eq!(
        circles(&top_level_edges(src)),
        vec![vec!["b".to_string(), "c".to_string()]]
    );
    // A test module may borrow from anywhere: no circle.
    std::fs::write(
        src.join("c/e.rs"),
        "#[cfg(test)]\nmod tests {\n    use crate::b::d::k;\n}\n",
    )
    .unwrap();
    assert!(circles(&top_level_edges(src)).is_empty());
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

/// Files that are test modules (`#[cfg(test)] mod name;` in their parent).
fn test_only_files(src: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for f in rust_files(src) {
        let text = std::fs::read_to_string(&f).unwrap();
        let lines: Vec<&str> = text.lines().map(str::trim).collect();
        for w in lines.windows(2) {
            let decl = w[1].strip_prefix("pub(crate) ").unwrap_or(w[1]);
            let Some(name) = decl.strip_prefix("mod ").and_then(|d| d.strip_suffix(';')) else {
                continue;
            };
            if w[0] != "#[cfg(test)]" {
                continue;
            }
            let stem = f.file_stem().unwrap().to_string_lossy();
            let dir = if stem == "mod" || stem == "lib" {
                f.parent().unwrap().to_path_buf()
            } else {
                f.parent().unwrap().join(&*stem)
            };
            out.push(dir.join(format!("{name}.rs")));
            out.push(dir.join(name).join("mod.rs"));
        }
    }
    out
}

/// Lines of the library that write to the terminal or decide an exit
/// status (test modules left out): the binary owns the terminal; progress
/// reaches it through `progress::Observer`.
fn terminal_code_in_library(src: &Path) -> Vec<String> {
    let binary = [src.join("main.rs"), src.join("cmd")];
    let tests = test_only_files(src);
    let banned = [
        "println!",
        "eprintln!",
        "print!(",
        "eprint!(",
        "stdout()",
        "stderr()",
        "indicatif",
        "process::exit",
        "ExitCode",
        "dbg!(",
    ];
    rust_files(src)
        .into_iter()
        .filter(|f| !binary.iter().any(|b| f.starts_with(b)) && !tests.contains(f))
        .flat_map(|f| {
            let text = std::fs::read_to_string(&f).unwrap();
            code_lines(&text)
                .into_iter()
                .filter(|l| banned.iter().any(|b| l.contains(b)))
                .map(|l| format!("{}: {}", f.display(), l.trim()))
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn the_library_neither_prints_nor_decides_exit_codes() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let found = terminal_code_in_library(&src);
    assert!(
        found.is_empty(),
        "terminal code in the library:\n{}",
        found.join("\n")
    );
}

#[test]
fn terminal_code_in_the_library_is_detected() {
    let dir = tempfile::tempdir().unwrap();
    let src = dir.path();
    std::fs::create_dir_all(src.join("cmd")).unwrap();
    std::fs::create_dir_all(src.join("a")).unwrap();
    std::fs::write(src.join("main.rs"), "fn main() { println!(\"ok\"); }\n").unwrap();
    std::fs::write(src.join("cmd/run.rs"), "use indicatif::ProgressBar;\n").unwrap();
    std::fs::write(src.join("a/mod.rs"), "#[cfg(test)]\nmod tests;\nmod b;\n").unwrap();
    std::fs::write(src.join("a/tests.rs"), "fn t() { eprintln!(\"x\"); }\n").unwrap();
    std::fs::write(src.join("a/b.rs"), "fn f() { eprintln!(\"x\"); }\n").unwrap();
    std::fs::write(
        src.join("lib.rs"),
        "pub mod a;\n#[cfg(test)]\nmod tests {\n    fn t() { println!(); }\n}\n",
    )
    .unwrap();
    let found = terminal_code_in_library(src);
    assert_eq!(found.len(), 1, "{found:?}");
    assert!(found[0].contains("b.rs"));
}
