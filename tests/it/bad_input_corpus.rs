//! The bad-input corpus: every case through `run`, `check`, `plan` and `list`
//! (one test per command, so they run in parallel). Each invocation must exit
//! 2 within [`LIMIT`], print one `error: FILE[:LINE]: ...` line per
//! expected error (with the expected file, line and key), print no number
//! in 20 digits or more, never panic, and write nothing (the log directory
//! is not even created).
//!
//! The fault corpus (`tests/corpus/faults.rs`): runtime faults and inputs
//! that run, each ending within [`LIMIT`] with its exit code and message,
//! without a panic or a process left behind.

use crate::common::*;
use crate::corpus::faults::FaultCase;
use crate::corpus::{corpus, disk, shipped, Case, Shape, Special};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How long any case may take: bad input is refused before anything runs,
/// and every fault case ends in a few seconds.
const LIMIT: Duration = Duration::from_secs(10);

/// The first run of 20 or more digits in `text` (what `{}` makes of 1e300).
fn long_number(text: &str) -> Option<&str> {
    let mut start = None;
    for (i, ch) in text.char_indices() {
        match (ch.is_ascii_digit(), start) {
            (true, None) => start = Some(i),
            (false, Some(s)) if i - s >= 20 => return Some(&text[s..i]),
            (false, Some(_)) => start = None,
            _ => {}
        }
    }
    start.filter(|s| text.len() - s >= 20).map(|s| &text[s..])
}

/// Longest stderr line a case may print: echoed user text is shortened.
const LONGEST_LINE: usize = 2000;

/// Rust `Debug` output in `text` (`Some(`, `Vec3([`, `Name { field: `).
fn debug_output(text: &str) -> Option<&str> {
    for needle in ["Some(", "Vec3([", "Ok(", "Err("] {
        if let Some(i) = text.find(needle) {
            return Some(&text[i..(i + 40).min(text.len())]);
        }
    }
    // A struct: a capitalised word, ` { `, a lower-case field and `: `.
    let b = text.as_bytes();
    for (i, _) in text.match_indices(" { ") {
        let before = text[..i]
            .rsplit(|c: char| !c.is_alphanumeric())
            .next()
            .unwrap_or("");
        let after = &text[i + 3..];
        let field: String = after
            .chars()
            .take_while(|c| c.is_ascii_lowercase() || *c == '_')
            .collect();
        if before.starts_with(|c: char| c.is_ascii_uppercase())
            && !field.is_empty()
            && after[field.len()..].starts_with(": ")
        {
            return Some(&text[i - before.len()..(i + 40).min(b.len())]);
        }
    }
    None
}

/// The binary the corpus runs: `ANHOLONOMY_CORPUS_BIN` (another build, to
/// compare its messages or to see a new case fail on an old build;
/// docs/src/development.md), else this one.
fn binary() -> std::ffi::OsString {
    std::env::var_os("ANHOLONOMY_CORPUS_BIN")
        .unwrap_or_else(|| env!("CARGO_BIN_EXE_anholonomy").into())
}

/// Run the binary in `dir`, killing it after `limit`. Returns (exit code,
/// stdout, stderr); a run killed at the limit has no code and says so in
/// its stderr.
fn run_limited(
    dir: &Path,
    args: &[String],
    limit: Duration,
    path: Option<&std::ffi::OsStr>,
) -> (Option<i32>, String, String) {
    let out = dir.join(".stdout");
    let err = dir.join(".stderr");
    let mut cmd = Command::new(binary());
    if let Some(p) = path {
        cmd.env("PATH", p);
    }
    let mut child = cmd
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .unwrap();
    let t0 = Instant::now();
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        if t0.elapsed() > limit {
            // A problem of this case, reported with the others.
            let _ = child.kill();
            let _ = child.wait();
            return (None, String::new(), format!("hang: killed after {limit:?}"));
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let read = |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap()).into_owned();
    let (o, e) = (read(&out), read(&err));
    let _ = std::fs::remove_file(out);
    let _ = std::fs::remove_file(err);
    (status.code(), o, e)
}

fn setup(case: &Case) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path();
    for s in &case.special {
        match s {
            Special::Dir(d) => std::fs::create_dir_all(p.join(d)).unwrap(),
            Special::Fifo(f) => {
                let ok = Command::new("mkfifo")
                    .arg(p.join(f))
                    .status()
                    .unwrap()
                    .success();
                assert!(ok, "mkfifo");
            }
            Special::Symlink(target, link) => {
                #[cfg(unix)]
                std::os::unix::fs::symlink(target, p.join(link)).unwrap();
            }
            Special::Sized(f, n) => {
                std::fs::File::create(p.join(f))
                    .unwrap()
                    .set_len(*n)
                    .unwrap();
            }
            Special::XacroOnPath => {}
        }
    }
    for (name, bytes) in &case.files {
        let f = p.join(name);
        std::fs::create_dir_all(f.parent().unwrap()).unwrap();
        std::fs::write(f, bytes).unwrap();
    }
    dir
}

/// Check one stderr line against its shape; returns a description of the mismatch.
fn shape_mismatch(line: &str, s: &Shape) -> Option<String> {
    let prefix = format!("error: {}", s.file);
    let Some(rest) = line.strip_prefix(&prefix) else {
        return Some(format!("does not start with `{prefix}`"));
    };
    let rest = match s.line {
        Some(n) => match rest.strip_prefix(&format!(":{n}: ")) {
            Some(r) => r,
            None => return Some(format!("line {n} expected")),
        },
        None => match rest.strip_prefix(": ") {
            Some(r) => r,
            None => return Some("no line expected".into()),
        },
    };
    if let Some(k) = &s.key {
        if !rest.starts_with(k.as_str()) {
            return Some(format!("message should start with `{k}`"));
        }
    }
    None
}

/// All cases through one command; every problem is collected, then reported.
fn check_command(cmd: &str) {
    let cases = corpus();
    assert!(cases.len() >= 150, "{} cases", cases.len());
    let mut problems = Vec::new();
    let mut invocations = 0;
    for case in &cases {
        let single =
            case.args.len() == 1 && !case.args[0].ends_with("dir") && case.expect.len() == 1;
        let args: Vec<String> = match cmd {
            "run" | "check" => {
                let mut a = vec![cmd.to_string()];
                a.extend(case.args.iter().cloned());
                a.extend(["--quiet".to_string()]);
                if !case.run_flags.contains(&"--logs".to_string()) {
                    a.extend(["--logs".to_string(), "logs".to_string()]);
                }
                a.extend(case.run_flags.iter().cloned());
                a
            }
            "plan" if single && case.run_flags.is_empty() && case.name != "empty directory" => {
                vec!["plan".into(), case.args[0].clone(), "--json".into()]
            }
            "list" if case.run_flags.is_empty() => {
                let mut a = vec!["list".to_string()];
                a.extend(case.args.iter().cloned());
                a
            }
            _ => continue,
        };
        check_case(case, &args, cmd, &mut problems);
        invocations += 1;
    }
    assert!(
        problems.is_empty(),
        "{} of {invocations} `{cmd}` invocations broke the contract:\n{}",
        problems.len(),
        problems.join("\n")
    );
    eprintln!("{cmd}: {invocations} invocations, all exit 2 with the expected error lines");
}

/// Run one case (`args` to the binary) and add what breaks the contract to
/// `problems`: exit 2, the expected error lines, no panic, no long number,
/// nothing on stdout (but for `list`), no log directory.
fn check_case(case: &Case, args: &[String], cmd: &str, problems: &mut Vec<String>) {
    let dir = setup(case);
    let xacro = case
        .special
        .iter()
        .any(|s| matches!(s, Special::XacroOnPath))
        .then(python::path_with_xacro);
    let (code, stdout, stderr) = run_limited(dir.path(), args, LIMIT, xacro.as_deref());
    if let Some(dump) = std::env::var_os("ANHOLONOMY_CORPUS_DUMP") {
        // One line per invocation: case, command, stderr with the
        // temporary directory's name taken out.
        use std::io::Write as _;
        let tmp = dir.path().to_string_lossy().into_owned();
        let line = format!(
            "{}\t{}\t{}\n",
            case.name,
            args.join(" ").replace(&tmp, "DIR"),
            stderr.trim_end().replace(&tmp, "DIR").replace('\n', "\\n")
        );
        let mut f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(dump)
            .unwrap();
        f.write_all(line.as_bytes()).unwrap();
    }
    let mut bad = |what: String| {
        problems.push(format!(
            "[{}] `{}`: {what}\n  stderr: {stderr}",
            case.name,
            args.join(" ")
        ))
    };
    if code != Some(2) {
        bad(format!("exit {code:?}, expected 2"));
    }
    if stderr.contains("panicked") || stderr.contains("RUST_BACKTRACE") {
        bad("panic".into());
    }
    if let Some(n) = long_number(&stderr) {
        bad(format!("a number in {} digits", n.len()));
    }
    if let Some(d) = debug_output(&stderr) {
        bad(format!("Rust Debug output: {d}"));
    }
    if let Some(l) = stderr.lines().find(|l| l.chars().count() > LONGEST_LINE) {
        bad(format!("a line of {} characters", l.chars().count()));
    }
    let lines: Vec<&str> = stderr.lines().collect();
    if lines.len() != case.expect.len() {
        bad(format!(
            "{} stderr lines, expected {}",
            lines.len(),
            case.expect.len()
        ));
    } else {
        for (l, s) in lines.iter().zip(&case.expect) {
            if let Some(m) = shape_mismatch(l, s) {
                bad(format!("{m} (expected {s:?})"));
            }
        }
    }
    if cmd != "list" && !stdout.is_empty() {
        bad(format!("stdout not empty: {stdout}"));
    }
    let written: Vec<PathBuf> = files_below(&dir.path().join("logs"));
    if dir.path().join("logs").exists() {
        bad(format!("log directory created: {written:?}"));
    }
}

#[test]
fn corpus_through_run() {
    check_command("run");
}

#[test]
fn corpus_through_check() {
    check_command("check");
}

#[test]
fn corpus_through_plan() {
    check_command("plan");
}

#[test]
fn corpus_through_list() {
    check_command("list");
}

/// `fit`'s own bad input (keys, ranges, recordings named on its command
/// line), and the scenario corpus's `[compare]` cases through `fit`.
#[test]
fn corpus_through_fit() {
    let mut problems = Vec::new();
    let cases = crate::corpus::fit::fit_cases();
    assert!(cases.len() >= 10, "{} cases", cases.len());
    for case in &cases {
        let mut args = vec!["fit".to_string()];
        args.extend(case.args.iter().cloned());
        args.push("--quiet".into());
        check_case(case, &args, "fit", &mut problems);
    }
    assert!(
        problems.is_empty(),
        "{} of {} `fit` invocations broke the contract:\n{}",
        problems.len(),
        cases.len(),
        problems.join("\n")
    );
}

/// The corpus really is bad input only because of its edits: the unedited
/// bases pass validation (so each case tests what it says).
#[test]
fn corpus_bases_are_valid() {
    let dir = tempfile::tempdir().unwrap();
    let bases = [
        ("disk.toml", disk()),
        (
            "rover_sweep.toml",
            shipped("rover_sweep.toml").replace("count = 100", "count = 4"),
        ),
        ("space.toml", shipped("space_robot_paper.toml")),
        ("s1.toml", shipped("space_manipulator_s1.toml")),
        ("rover.toml", shipped("rover_paper.toml")),
        ("sphere.toml", shipped("sphere_triangle_paper.toml")),
    ];
    for (f, text) in &bases {
        std::fs::write(dir.path().join(f), text).unwrap();
    }
    let args: Vec<String> = std::iter::once("list".to_string())
        .chain(bases.iter().map(|(f, _)| f.to_string()))
        .collect();
    let (code, stdout, stderr) = run_limited(dir.path(), &args, LIMIT, None);
    assert_eq!(code, Some(0), "{stderr}");
    assert_eq!(stdout.lines().count(), bases.len() + 1, "{stdout}");
}

/// Whether process `pid` still runs (a zombie waiting for init does not).
fn running(pid: u32) -> Option<String> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    let state = stat
        .rsplit(')')
        .next()?
        .split_whitespace()
        .next()?
        .to_string();
    (state != "Z" && state != "X").then_some(state)
}

/// The pids written into `dir/file`, one per line.
fn pids_in(dir: &Path, file: &str) -> Vec<u32> {
    std::fs::read_to_string(dir.join(file))
        .unwrap_or_default()
        .lines()
        .filter_map(|l| l.trim().parse().ok())
        .collect()
}

/// What is wrong with one fault case's run, if anything.
fn fault_problems(case: &FaultCase) -> Vec<String> {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in &case.files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    #[cfg(unix)]
    for (link, target) in &case.symlinks {
        std::os::unix::fs::symlink(target, dir.path().join(link)).unwrap();
    }
    let t0 = Instant::now();
    let out = dir.path().join(".stdout");
    let err = dir.path().join(".stderr");
    let mut child = Command::new(binary())
        .args(&case.args)
        .current_dir(dir.path())
        .stdin(Stdio::null())
        .stdout(std::fs::File::create(&out).unwrap())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .unwrap();
    let mut problems = Vec::new();
    let code = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s.code();
        }
        if t0.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            problems.push(format!("hang: killed after {LIMIT:?}"));
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let read = |p: &Path| String::from_utf8_lossy(&std::fs::read(p).unwrap()).into_owned();
    let (stdout, stderr) = (read(&out), read(&err));
    if code != Some(case.code) {
        problems.push(format!("exit {code:?}, expected {}", case.code));
    }
    if stderr.contains("panicked") || stderr.contains("RUST_BACKTRACE") {
        problems.push("panic".into());
    }
    for (what, text) in [("stdout", &stdout), ("stderr", &stderr)] {
        if let Some(n) = long_number(text) {
            problems.push(format!("{what}: a number in {} digits", n.len()));
        }
    }
    for s in &case.stderr_has {
        if !stderr.contains(s.as_str()) {
            problems.push(format!("stderr lacks `{s}`"));
        }
    }
    if !case.stderr_any.is_empty() && !case.stderr_any.iter().any(|s| stderr.contains(s.as_str())) {
        problems.push(format!("stderr has none of {:?}", case.stderr_any));
    }
    for s in &case.stdout_has {
        if !stdout.contains(s.as_str()) {
            problems.push(format!("stdout lacks `{s}`"));
        }
    }
    if case.one_line && (stderr.lines().count() != 1 || !stderr.starts_with("error: ")) {
        problems.push("not one `error:` line".into());
    }
    if let Some(d) = debug_output(&stderr) {
        problems.push(format!("Rust Debug output: {d}"));
    }
    // Nothing the run started still runs: the laws and what they started.
    let mut left = Vec::new();
    for pid in pids_in(dir.path(), "pids")
        .into_iter()
        .chain(pids_in(dir.path(), "grandchildren"))
    {
        if let Some(state) = running(pid) {
            left.push(format!("{pid} ({state})"));
            // Not ours to leave running, whatever the verdict.
            let _ = Command::new("kill").arg("-9").arg(pid.to_string()).status();
        }
    }
    if !left.is_empty() {
        problems.push(format!("processes left behind: {}", left.join(", ")));
    }
    problems
        .into_iter()
        .map(|p| {
            format!(
                "[{}] `anholonomy {}`: {p}\n  stderr: {stderr}",
                case.name,
                case.args.join(" ")
            )
        })
        .collect()
}

/// Every fault case ends in time, with its code and message, no panic and
/// no process left behind.
#[test]
fn fault_corpus_ends_cleanly() {
    let cases = crate::corpus::faults::cases();
    assert!(cases.len() >= 18, "{} cases", cases.len());
    let problems: Vec<String> = cases.iter().flat_map(fault_problems).collect();
    assert!(
        problems.is_empty(),
        "{} problems in {} fault cases:\n{}",
        problems.len(),
        cases.len(),
        problems.join("\n")
    );
}
