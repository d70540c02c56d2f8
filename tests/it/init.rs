//! `anholonomy init` and `anholonomy models`: the starter repository passes
//! `check` at once when the binary runs from outside this source tree (so
//! nothing is read from it), the CI files pin the version that wrote them,
//! and the embedded models are the repository's `models/`, every one.

use crate::common::*;
use std::path::Path;

/// A copy of the binary in a directory of its own, outside the repository.
fn binary_outside(dir: &Path) -> std::path::PathBuf {
    let bin = dir.join("bin/anholonomy");
    std::fs::create_dir_all(bin.parent().unwrap()).unwrap();
    std::fs::copy(env!("CARGO_BIN_EXE_anholonomy"), &bin).unwrap();
    bin
}

fn run(bin: &Path, cwd: &Path, args: &[&str]) -> std::process::Output {
    std::process::Command::new(bin)
        .current_dir(cwd)
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn the_starter_repository_passes_check_at_once() {
    let tmp = tempfile::tempdir().unwrap();
    let bin = binary_outside(tmp.path());
    let out = run(&bin, tmp.path(), &["init", "repo"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let repo = tmp.path().join("repo");
    for f in [
        ".gitignore",
        ".github/workflows/anholonomy.yml",
        ".gitlab-ci.yml",
        "ci/install-anholonomy.sh",
        "models/diff_drive.urdf",
        "baselines/s_curve.json",
        "baselines/go_to_pose.json",
    ] {
        assert!(repo.join(f).is_file(), "{f} missing");
    }
    let out = run(
        &bin,
        &repo,
        &[
            "check",
            "scenarios/",
            "--baseline",
            "baselines/",
            "--junit",
            "logs/junit.xml",
            "--report",
        ],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(stdout.matches("  PASS").count(), 2, "{stdout}");
    assert!(repo.join("logs/index.html").is_file());
    assert!(repo.join("logs/junit.xml").is_file());
    // The workflow: checks: write for the JUnit action; the install and the
    // cache key both follow the version that wrote it (tests/it/install.rs
    // runs the install steps).
    let wf = std::fs::read_to_string(repo.join(".github/workflows/anholonomy.yml")).unwrap();
    let version = env!("CARGO_PKG_VERSION");
    assert!(wf.contains("checks: write"), "{wf}");
    assert!(
        wf.contains(&format!("ANHOLONOMY_VERSION: \"{version}\"")),
        "{wf}"
    );
    assert!(
        wf.contains(
            "key: anholonomy-${{ runner.os }}-${{ runner.arch }}-${{ env.ANHOLONOMY_VERSION }}"
        ),
        "{wf}"
    );
    let gl = std::fs::read_to_string(repo.join(".gitlab-ci.yml")).unwrap();
    assert!(gl.contains("key: anholonomy-$ANHOLONOMY_VERSION"), "{gl}");
    let script = std::fs::read_to_string(repo.join("ci/install-anholonomy.sh")).unwrap();
    assert!(
        script.contains(&format!("${{ANHOLONOMY_VERSION:-{version}}}")),
        "{script}"
    );
    let ignored = std::fs::read_to_string(repo.join(".gitignore")).unwrap();
    assert!(ignored.lines().any(|l| l == ".anholonomy/"), "{ignored}");
    // Not into a directory that holds something (exit 2, nothing changed).
    let out = run(&bin, tmp.path(), &["init", "repo"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("not an empty directory"), "{err}");
}

#[test]
fn init_from_another_repository_installs_its_release_or_its_tag() {
    let files = anholonomy::init::starter_files(Some("https://example.org/fork"));
    let script = &files
        .iter()
        .find(|(p, _)| *p == "ci/install-anholonomy.sh")
        .unwrap()
        .1;
    assert!(
        script.contains("repo=\"${ANHOLONOMY_REPO:-https://example.org/fork}\""),
        "{script}"
    );
    assert!(
        script.contains("--git \"$repo\" --tag \"v$version\" anholonomy"),
        "{script}"
    );
    // The default is Cargo.toml's `repository`.
    let files = anholonomy::init::starter_files(None);
    assert!(files.iter().any(|(_, t)| t.contains(&format!(
        "${{ANHOLONOMY_REPO:-{}}}",
        env!("CARGO_PKG_REPOSITORY")
    ))));
    // A trailing slash is dropped; what the CI files cannot quote, or no
    // URL at all, is refused.
    use anholonomy::init::source_url;
    assert_eq!(
        source_url("https://example.org/fork/").as_deref(),
        Ok("https://example.org/fork")
    );
    assert_eq!(
        source_url("file:///srv/mirror").as_deref(),
        Ok("file:///srv/mirror")
    );
    for bad in [
        "example.org/fork",
        "https://",
        "1https://x",
        "https://example.org/a b",
        "https://example.org/$(id)",
        "https://example.org/\"x",
        "https://example.org/a#b",
        "https://example.org/}",
    ] {
        assert!(source_url(bad).is_err(), "{bad}");
    }
}

#[test]
fn init_refuses_a_source_that_is_not_a_url_and_writes_nothing() {
    let tmp = tempfile::tempdir().unwrap();
    let bin = binary_outside(tmp.path());
    for flag in ["--from", "--git"] {
        let out = run(&bin, tmp.path(), &["init", "repo", flag, "not a url"]);
        assert_eq!(out.status.code(), Some(2), "{flag}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.starts_with("error: --from: `not a url` is not a URL"),
            "{err}"
        );
        assert!(!tmp.path().join("repo").exists());
    }
}

#[test]
fn every_model_in_the_repository_is_embedded_and_exported_byte_for_byte() {
    let mut shipped: Vec<String> = std::fs::read_dir(root().join("models"))
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".urdf"))
        .collect();
    shipped.sort();
    let tmp = tempfile::tempdir().unwrap();
    let bin = binary_outside(tmp.path());
    let out = run(&bin, tmp.path(), &["models", "export", "m"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut got: Vec<String> = std::fs::read_dir(tmp.path().join("m"))
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    got.sort();
    assert_eq!(got, shipped, "add new models to init::MODELS");
    for n in &shipped {
        assert_eq!(
            std::fs::read(tmp.path().join("m").join(n)).unwrap(),
            std::fs::read(root().join("models").join(n)).unwrap(),
            "{n}"
        );
    }
    // Existing files are kept unless --force; unknown names are named.
    let out = run(&bin, tmp.path(), &["models", "export", "m", "car", "cart"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("exists: give --force") && err.contains("no shipped model `cart`"),
        "{err}"
    );
    let out = run(
        &bin,
        tmp.path(),
        &["models", "export", "m", "car", "--force"],
    );
    assert!(out.status.success());
}
