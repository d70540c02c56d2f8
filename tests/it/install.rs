//! Installing the binary in CI: the install script `anholonomy init` writes
//! (ci/install-anholonomy.sh), run exactly as the GitHub workflow's and the
//! GitLab job's install steps run it, against a `file://` release made with
//! the release workflow's own packaging script from the binary under test;
//! and the names the release workflow, the install script and
//! `[package.metadata.binstall]` use for the archives agree.

use crate::common::*;
use anholonomy::init::{starter_files, REPOSITORY, VERSION};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use yaml_rust2::{Yaml, YamlLoader};

/// The release target of this machine, as the install script maps
/// `uname` (None where there is no release binary).
fn host_target() -> Option<&'static str> {
    match (std::env::consts::OS, std::env::consts::ARCH) {
        ("linux", "x86_64") => Some("x86_64-unknown-linux-gnu"),
        ("linux", "aarch64") => Some("aarch64-unknown-linux-gnu"),
        ("macos", "aarch64") => Some("aarch64-apple-darwin"),
        _ => None,
    }
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fake release of `VERSION` under `site`, laid out as GitHub serves
/// one (`site/releases/download/vVERSION/`), made by
/// scripts/release/package.sh from the binary under test; returns the
/// archive's path.
fn fake_release(site: &Path, target: &str) -> PathBuf {
    let dir = site.join(format!("releases/download/v{VERSION}"));
    let out = Command::new("sh")
        .arg(root().join("scripts/release/package.sh"))
        .args([VERSION, target, env!("CARGO_BIN_EXE_anholonomy")])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", stderr(&out));
    let archive = PathBuf::from(String::from_utf8_lossy(&out.stdout).trim());
    assert_eq!(
        archive,
        dir.join(format!("anholonomy-v{VERSION}-{target}.tar.gz"))
    );
    archive
}

/// The starter repository's files for a release at `url`, written into
/// `repo` (no scenarios are run: only the CI files matter here).
fn starter(repo: &Path, url: &str) -> Vec<(&'static str, String)> {
    let files = starter_files(Some(url));
    for (p, text) in &files {
        let path = repo.join(p);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    files
}

fn file<'a>(files: &'a [(&str, String)], name: &str) -> &'a str {
    &files.iter().find(|(p, _)| *p == name).unwrap().1
}

fn yaml(text: &str) -> Yaml {
    YamlLoader::load_from_str(text).unwrap().remove(0)
}

/// The GitHub workflow's install command and the directory its cache
/// keeps, and the same two of the GitLab job.
fn install_commands(files: &[(&str, String)]) -> [(String, String); 2] {
    let gh = yaml(file(files, ".github/workflows/anholonomy.yml"));
    let steps = gh["jobs"]["check"]["steps"].as_vec().unwrap();
    let install = steps
        .iter()
        .find(|s| {
            s["name"]
                .as_str()
                .is_some_and(|n| n.starts_with("Install anholonomy"))
        })
        .expect("the workflow has an install step");
    let gh_line = install["run"].as_str().unwrap().lines().next().unwrap();
    let cached = steps
        .iter()
        .find(|s| {
            s["uses"]
                .as_str()
                .is_some_and(|u| u.contains("cache/restore"))
        })
        .expect("the workflow restores a cache");
    let gh_path = cached["with"]["path"].as_str().unwrap();
    assert_eq!(
        gh["jobs"]["check"]["env"]["ANHOLONOMY_VERSION"].as_str(),
        Some(VERSION)
    );
    let gl = yaml(file(files, ".gitlab-ci.yml"));
    let job = &gl["anholonomy"];
    let gl_line = job["script"][0].as_str().unwrap();
    let gl_path = job["cache"]["paths"][0].as_str().unwrap();
    assert_eq!(
        job["variables"]["ANHOLONOMY_VERSION"].as_str(),
        Some(VERSION)
    );
    [
        (gh_line.to_string(), gh_path.to_string()),
        (
            gl_line.to_string(),
            gl_path.trim_end_matches('/').to_string(),
        ),
    ]
}

/// Runs `line` with `sh -c` in `repo`, as a CI step would: no
/// ANHOLONOMY_* variable but `env`, and `fake_bin` first on PATH (a
/// `cargo` there stands in for the build from source).
fn step(repo: &Path, fake_bin: &Path, line: &str, env: &[(&str, &str)]) -> Output {
    let path = format!(
        "{}:{}",
        fake_bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut cmd = Command::new("sh");
    cmd.arg("-c").arg(line).current_dir(repo).env("PATH", path);
    for (k, _) in std::env::vars() {
        if k.starts_with("ANHOLONOMY_") {
            cmd.env_remove(k);
        }
    }
    cmd.envs(env.iter().copied());
    cmd.output().unwrap()
}

/// A `cargo` that records its arguments in `log` and "installs" a script
/// printing `anholonomy 9.9.9` into the `--root` it is given.
fn fake_cargo(dir: &Path, log: &Path) {
    std::fs::create_dir_all(dir).unwrap();
    let script = format!(
        "#!/bin/sh\nprintf '%s\\n' \"$@\" >'{}'\n\
         while [ $# -gt 0 ]; do [ \"$1\" = --root ] && root=$2; shift; done\n\
         mkdir -p \"$root/bin\"\n\
         printf '#!/bin/sh\\necho \"anholonomy 9.9.9\"\\n' >\"$root/bin/anholonomy\"\n\
         chmod +x \"$root/bin/anholonomy\"\n",
        log.display()
    );
    let path = dir.join("cargo");
    std::fs::write(&path, script).unwrap();
    Command::new("chmod").arg("+x").arg(&path).status().unwrap();
}

fn version_of(bin: &Path) -> String {
    let out = Command::new(bin).arg("--version").output().unwrap();
    String::from_utf8_lossy(&out.stdout).trim().to_string()
}

#[test]
fn the_ci_install_steps_install_the_release_binary_from_a_file_url() {
    let Some(target) = host_target() else {
        eprintln!("no release binary for this platform: nothing to download");
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let site = tmp.path().join("site");
    let archive = fake_release(&site, target);
    let url = format!("file://{}", site.display());
    let repo = tmp.path().join("repo");
    let files = starter(&repo, &url);
    let fake_bin = tmp.path().join("fake-bin");
    let cargo_log = tmp.path().join("cargo-args");
    fake_cargo(&fake_bin, &cargo_log);

    for (line, cache_dir) in install_commands(&files) {
        let bin = repo.join(&cache_dir).join("bin/anholonomy");
        let out = step(&repo, &fake_bin, &line, &[]);
        assert!(out.status.success(), "{line}: {}", stderr(&out));
        assert_eq!(version_of(&bin), format!("anholonomy {VERSION}"), "{line}");
        assert!(
            stderr(&out).contains(&format!("from {url}/releases/download/v{VERSION}/")),
            "{line}: {}",
            stderr(&out)
        );
        // The binary runs: the starter's own models are there.
        let models = Command::new(&bin).arg("models").output().unwrap();
        assert!(models.status.success());
        assert!(String::from_utf8_lossy(&models.stdout).contains("diff_drive.urdf"));
        // Run again (the cache restored the directory): nothing downloaded.
        let away = tmp.path().join("away");
        std::fs::rename(&site, &away).unwrap();
        let again = step(&repo, &fake_bin, &line, &[]);
        std::fs::rename(&away, &site).unwrap();
        assert!(again.status.success(), "{}", stderr(&again));
        assert!(stderr(&again).contains("already in"), "{}", stderr(&again));
        std::fs::remove_dir_all(repo.join(&cache_dir)).unwrap();
    }
    assert!(!cargo_log.exists(), "nothing was built from source");

    // A wrong checksum stops the install: no binary, and no build from
    // source in its place.
    let sum = archive.with_extension("gz.sha256");
    let good = std::fs::read_to_string(&sum).unwrap();
    let bad = format!("{}{}", "0".repeat(64), &good[64..]);
    std::fs::write(&sum, bad).unwrap();
    let (line, cache_dir) = &install_commands(&files)[0];
    let out = step(&repo, &fake_bin, line, &[]);
    assert_eq!(out.status.code(), Some(1), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("checksum mismatch"),
        "{}",
        stderr(&out)
    );
    assert!(!repo.join(cache_dir).join("bin/anholonomy").exists());
    assert!(
        !cargo_log.exists(),
        "a bad download is not a reason to build"
    );
}

#[test]
fn without_a_release_binary_the_install_builds_the_tag_from_source() {
    let tmp = tempfile::tempdir().unwrap();
    let url = format!("file://{}", tmp.path().join("empty-site").display());
    let repo = tmp.path().join("repo");
    let files = starter(&repo, &url);
    let fake_bin = tmp.path().join("fake-bin");
    let cargo_log = tmp.path().join("cargo-args");
    fake_cargo(&fake_bin, &cargo_log);
    let (line, cache_dir) = &install_commands(&files)[1];
    let out = step(&repo, &fake_bin, line, &[("ANHOLONOMY_VERSION", "9.9.9")]);
    assert!(out.status.success(), "{}", stderr(&out));
    let args = std::fs::read_to_string(&cargo_log).unwrap();
    let args: Vec<&str> = args.lines().collect();
    assert_eq!(
        args,
        [
            "install",
            "--locked",
            "--force",
            "--root",
            cache_dir.as_str(),
            "--git",
            url.as_str(),
            "--tag",
            "v9.9.9",
            "anholonomy"
        ]
    );
    assert_eq!(
        version_of(&repo.join(cache_dir).join("bin/anholonomy")),
        "anholonomy 9.9.9"
    );
}

/// The release workflow's CLI targets, archive names and packaging script
/// are the ones the install script and cargo-binstall look for.
#[test]
fn release_assets_are_named_as_the_installers_look_for_them() {
    let release = std::fs::read_to_string(root().join(".github/workflows/release.yml")).unwrap();
    let wf = yaml(&release);
    let mut built: Vec<String> = wf["jobs"]["cli"]["strategy"]["matrix"]["include"]
        .as_vec()
        .unwrap()
        .iter()
        .map(|m| m["target"].as_str().unwrap().to_string())
        .collect();
    built.sort();
    let script = file(&starter_files(None), "ci/install-anholonomy.sh").to_string();
    let mut wanted: Vec<String> = script
        .lines()
        .filter_map(|l| l.split_once(") target=").map(|(_, t)| t))
        .filter_map(|t| t.strip_suffix(" ;;"))
        .filter(|t| !t.is_empty())
        .map(str::to_string)
        .collect();
    wanted.sort();
    assert_eq!(
        built, wanted,
        "release.yml's targets vs the install script's"
    );
    assert!(release.contains("sh scripts/release/package.sh \"${GITHUB_REF_NAME#v}\""));
    assert!(script.contains("url=\"$releases/v$version/$archive\""));
    assert!(script.contains(&format!("${{ANHOLONOMY_REPO:-{REPOSITORY}}}")));

    let manifest: toml::Table = std::fs::read_to_string(root().join("Cargo.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let package = &manifest["package"];
    assert_eq!(package["repository"].as_str(), Some(REPOSITORY));
    let binstall = &package["metadata"]["binstall"];
    assert_eq!(binstall["pkg-fmt"].as_str(), Some("tgz"));
    assert_eq!(binstall["bin-dir"].as_str(), Some("{ bin }{ binary-ext }"));
    for target in &built {
        let url = binstall["pkg-url"]
            .as_str()
            .unwrap()
            .replace("{ repo }", REPOSITORY)
            .replace("{ version }", VERSION)
            .replace("{ name }", "anholonomy")
            .replace("{ target }", target);
        assert_eq!(
            url,
            format!(
                "{REPOSITORY}/releases/download/v{VERSION}/anholonomy-v{VERSION}-{target}.tar.gz"
            )
        );
    }
    // The archive holds the binary alone, at its top (bin-dir above).
    let Some(target) = host_target() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let archive = fake_release(tmp.path(), target);
    let list = Command::new("tar")
        .arg("-tzf")
        .arg(&archive)
        .output()
        .unwrap();
    assert_eq!(String::from_utf8_lossy(&list.stdout).trim(), "anholonomy");
}

/// The guide shows the CI files `init` writes: the same text, without the
/// header comment.
#[test]
fn the_ci_guide_shows_the_files_init_writes() {
    let guide = std::fs::read_to_string(root().join("docs/src/ci.md")).unwrap();
    let files = starter_files(None);
    for name in [".github/workflows/anholonomy.yml", ".gitlab-ci.yml"] {
        let text = file(&files, name);
        let body: String = text
            .lines()
            .skip_while(|l| l.starts_with('#'))
            .map(|l| format!("{l}\n"))
            .collect();
        let intro = format!("`anholonomy init` writes `{name}`");
        let at = guide
            .find(&intro)
            .unwrap_or_else(|| panic!("docs/src/ci.md has no \"{intro}\""));
        let rest = &guide[at..];
        let open = rest.find("```").unwrap();
        let start = open + rest[open..].find('\n').unwrap() + 1;
        let end = start + rest[start..].find("```").unwrap();
        assert_eq!(
            &rest[start..end],
            body,
            "{name}: docs/src/ci.md differs from init's"
        );
    }
}
