//! Python for the tests that run Python scripts needing packages (numpy,
//! xacro): the `python3` on `PATH` when it has them, otherwise a virtual
//! environment under `target/tmp/` made once from the package registry
//! (`python3 -m venv` + `pip install`), so `cargo test --release` passes on
//! a machine whose `python3` has nothing installed.

use std::path::PathBuf;
use std::process::Command;
use std::sync::OnceLock;

/// Every package a test needs, installed together: one venv, one download.
/// rosbags is pinned: tests/ros_bags.rs compares the bags it writes with the
/// committed ones byte for byte.
const PACKAGES: &[&str] = &["numpy", "xacro", "rosbags==0.11.9"];

/// The module a package spec imports as (`rosbags==0.11.9` → `rosbags`).
fn module_of(spec: &str) -> &str {
    spec.split("==").next().unwrap_or(spec)
}

/// Where the test venv lives (`target/tmp/python-venv`).
pub fn venv_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("python-venv")
}

fn imports(python: &str, module: &str) -> bool {
    Command::new(python)
        .args(["-c", &format!("import {module}")])
        .output()
        .is_ok_and(|o| o.status.success())
}

/// A Python interpreter that imports `module` (one of `PACKAGES`): `python3`
/// itself when it can, else the test venv's.
pub fn python_with(module: &str) -> String {
    assert!(
        PACKAGES
            .iter()
            .any(|p| module_of(p) == module.split('.').next().unwrap_or(module)),
        "add {module} to PACKAGES"
    );
    if imports("python3", module) {
        return "python3".into();
    }
    test_venv()
        .join("bin/python3")
        .to_string_lossy()
        .into_owned()
}

/// The test venv's `bin/` (for commands pip installs, such as `xacro`).
pub fn venv_bin() -> PathBuf {
    test_venv().join("bin")
}

/// The test venv, made on first use. Test threads share it through a
/// `OnceLock`, test processes (nextest, two `cargo test`s) through a file
/// lock; a venv whose install did not finish has no `ready` marker and is
/// made again.
fn test_venv() -> PathBuf {
    static VENV: OnceLock<PathBuf> = OnceLock::new();
    VENV.get_or_init(|| {
        let dir = venv_dir();
        let ready = dir.join("ready");
        std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
        let lock = std::fs::File::create(dir.with_extension("lock")).unwrap();
        lock.lock().unwrap();
        // A venv made for another package list is made again.
        if std::fs::read_to_string(&ready).ok().as_deref() != Some(&PACKAGES.join("\n")) {
            make_venv(&dir);
            std::fs::write(&ready, PACKAGES.join("\n")).unwrap();
        }
        dir
    })
    .clone()
}

fn make_venv(dir: &PathBuf) {
    let _ = std::fs::remove_dir_all(dir);
    eprintln!(
        "python3 lacks {}: making {} (once) with pip from the package registry",
        PACKAGES.join(", "),
        dir.display()
    );
    let out = Command::new("python3")
        .args(["-m", "venv"])
        .arg(dir)
        .output()
        .expect("python3 is needed to run the Python examples and laws");
    assert!(
        out.status.success(),
        "`python3 -m venv {}` failed (Debian: apt-get install python3-venv): {}",
        dir.display(),
        String::from_utf8_lossy(&out.stderr).trim()
    );
    let out = Command::new(dir.join("bin/python3"))
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "--timeout",
            "30",
            "--retries",
            "1",
        ])
        .args(PACKAGES)
        .output()
        .unwrap();
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = err.lines().rev().take(3).collect();
        let _ = std::fs::remove_dir_all(dir);
        panic!(
            "these tests need the Python packages {pk}, which python3 lacks, and \
             `pip install {pk}` into {d} failed (is the package registry reachable?). \
             Install them for python3 (`python3 -m pip install {pk}`) or put a \
             python3 that has them first on PATH. pip said: {t}",
            pk = PACKAGES.join(" "),
            d = dir.display(),
            t = tail.into_iter().rev().collect::<Vec<_>>().join(" | ")
        );
    }
}

/// `PATH` without any directory that holds a `xacro`.
pub fn path_without_xacro() -> std::ffi::OsString {
    let path = std::env::var_os("PATH").unwrap_or_default();
    let kept: Vec<PathBuf> = std::env::split_paths(&path)
        .filter(|d| !d.join("xacro").exists())
        .collect();
    std::env::join_paths(kept).unwrap()
}

/// `PATH` with a `xacro` command on it: `PATH` itself when it has one,
/// else with the test venv's `bin/` first.
pub fn path_with_xacro() -> std::ffi::OsString {
    let path = std::env::var_os("PATH").unwrap_or_default();
    let mut dirs: Vec<PathBuf> = std::env::split_paths(&path).collect();
    if !dirs.iter().any(|d| d.join("xacro").is_file()) {
        dirs.insert(0, venv_bin());
    }
    std::env::join_paths(dirs).unwrap()
}
