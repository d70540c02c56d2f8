//! `anholonomy init DIR` (a starter repository that works with the installed
//! binary alone) and `anholonomy models` (the shipped URDFs, embedded in the
//! binary, since `cargo install` installs no `models/` directory).

use crate::baseline::{self, Baseline};
use crate::error::Error;
use crate::runner::RunOptions;
use crate::validate::{prepare_all, Call};
use std::path::{Path, PathBuf};

/// The shipped models, by kind, as the repository's `models/` holds them.
pub const MODELS: &[(&str, &str)] = &[
    ("car", include_str!("../../models/car.urdf")),
    ("diff_drive", include_str!("../../models/diff_drive.urdf")),
    (
        "mobile_manipulator",
        include_str!("../../models/mobile_manipulator.urdf"),
    ),
    (
        "rolling_disk",
        include_str!("../../models/rolling_disk.urdf"),
    ),
    ("rover", include_str!("../../models/rover.urdf")),
    ("space_robot", include_str!("../../models/space_robot.urdf")),
    ("sphere", include_str!("../../models/sphere.urdf")),
];

/// The version written into the CI files (the install is pinned to it).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

/// The URDF text of a shipped model.
pub fn model(name: &str) -> Option<&'static str> {
    MODELS.iter().find(|(n, _)| *n == name).map(|(_, t)| *t)
}

fn names() -> String {
    MODELS
        .iter()
        .map(|(n, _)| *n)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The shipped models: name and URDF text.
pub fn models() -> impl Iterator<Item = (&'static str, &'static str)> {
    MODELS.iter().copied()
}

/// `anholonomy models export DIR [NAME...]`: write the shipped models
/// `want` (every one when empty) into `dir` as NAME.urdf; an existing file
/// is an error (nothing written) unless `force`. The files written.
pub fn export_models(dir: &Path, want: &[String], force: bool) -> Result<Vec<PathBuf>, Vec<Error>> {
    let mut errors = Vec::new();
    let mut files = Vec::new();
    let chosen: Vec<&str> = if want.is_empty() {
        MODELS.iter().map(|(n, _)| *n).collect()
    } else {
        want.iter().map(String::as_str).collect()
    };
    for n in chosen {
        let Some(text) = model(n) else {
            errors.push(Error::input(
                n,
                format!("no shipped model `{n}` (there are {})", names()),
            ));
            continue;
        };
        let path = dir.join(format!("{n}.urdf"));
        if path.exists() && !force {
            errors.push(Error::input(&path, "exists: give --force to overwrite it"));
        }
        files.push((path, text.to_string()));
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    write_files(&files, "models export")?;
    Ok(files.into_iter().map(|(p, _)| p).collect())
}

/// Write `files` for `command` (`init`, `models export`): its errors name
/// the command and the file.
fn write_files(files: &[(PathBuf, String)], command: &'static str) -> Result<(), Vec<Error>> {
    for (path, text) in files {
        let res = path
            .parent()
            .map_or(Ok(()), std::fs::create_dir_all)
            .and_then(|_| std::fs::write(path, text));
        if let Err(e) = res {
            return Err(vec![Error::Write {
                path: path.clone(),
                command,
                message: e.to_string(),
            }]);
        }
    }
    Ok(())
}

/// `dir` when it is a symbolic link that leads nowhere (a loop, or a
/// missing target): a refusal naming the command, before anything is written.
fn dangling_link(dir: &Path, command: &str) -> Option<Error> {
    let link = std::fs::symlink_metadata(dir).ok()?;
    if !link.file_type().is_symlink() {
        return None;
    }
    let e = std::fs::metadata(dir).err()?;
    Some(Error::input(
        dir,
        format!(
            "{command}: the directory is a symbolic link that does not resolve ({e}: a loop, or a missing target): give a new directory, or fix the link"
        ),
    ))
}

/// Where the starter CI downloads releases from and builds from when there
/// is no release binary: `repository` in Cargo.toml (`init --from URL`
/// overrides it).
pub const REPOSITORY: &str = env!("CARGO_PKG_REPOSITORY");

/// Why `init --from URL` refuses a URL.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum UrlError {
    /// No `scheme://` (or nothing after it).
    #[error("`{0}` is not a URL (scheme://host/path, e.g. {REPOSITORY})")]
    NotUrl(String),
    /// A character the CI files' double quotes cannot hold.
    #[error(
        "{} holds {}, which the CI files cannot quote",
        crate::echo::code(url),
        crate::echo::code(&ch.to_string())
    )]
    Unquotable {
        /// The URL as given (trailing `/` dropped).
        url: String,
        /// The first character that cannot be quoted.
        ch: char,
    },
}

/// `init --from URL`: a URL (`scheme://...`) without the characters that
/// would end the double-quoted `${ANHOLONOMY_REPO:-URL}` the install script
/// holds it in, or start a fragment; a trailing `/` is dropped.
pub fn source_url(url: &str) -> Result<String, UrlError> {
    let url = url.trim_end_matches('/');
    let scheme = url.split_once("://").map(|(s, _)| s);
    let scheme_ok = scheme.is_some_and(|s| {
        s.starts_with(|c: char| c.is_ascii_alphabetic())
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+.-".contains(c))
    });
    if !scheme_ok || url.ends_with("://") {
        return Err(UrlError::NotUrl(url.to_string()));
    }
    if let Some(c) = url
        .chars()
        .find(|c| c.is_whitespace() || c.is_control() || "'\"`$\\#{}".contains(*c))
    {
        return Err(UrlError::Unquotable {
            url: url.to_string(),
            ch: c,
        });
    }
    Ok(url.to_string())
}

/// The starter repository's files (without the baselines, which are run);
/// its CI installs release `VERSION` of `from` (default [`REPOSITORY`]).
pub fn starter_files(from: Option<&str>) -> Vec<(&'static str, String)> {
    let repo = from.unwrap_or(REPOSITORY);
    let fill = |t: &str| t.replace("@VERSION@", VERSION).replace("@REPO@", repo);
    vec![
        ("README.md", fill(include_str!("starter/README.md"))),
        (".gitignore", include_str!("starter/gitignore").into()),
        (
            ".github/workflows/anholonomy.yml",
            fill(include_str!("starter/github.yml")),
        ),
        (".gitlab-ci.yml", fill(include_str!("starter/gitlab.yml"))),
        (
            "ci/install-anholonomy.sh",
            fill(include_str!("starter/install.sh")),
        ),
        (
            "models/diff_drive.urdf",
            model("diff_drive").unwrap().into(),
        ),
        (
            "plans/s_curve.csv",
            include_str!("starter/s_curve.csv").into(),
        ),
        (
            "scenarios/s_curve.toml",
            include_str!("starter/s_curve.toml").into(),
        ),
        (
            "laws/go_to_pose.py",
            include_str!("../../examples/diff_drive_law/law.py").into(),
        ),
        (
            "scenarios/go_to_pose.toml",
            include_str!("starter/go_to_pose.toml").into(),
        ),
    ]
}

/// `anholonomy init DIR`: write the starter repository (CI installing this
/// version's release of [`REPOSITORY`], or of `from` when given), run its
/// scenarios and write their baselines, so `check` passes in it at once.
/// Each starter scenario's name and verdict.
pub fn init(dir: &Path, from: Option<&str>) -> Result<Vec<(String, String)>, Vec<Error>> {
    let from = match from.map(source_url).transpose() {
        Ok(f) => f,
        Err(m) => return Err(vec![Error::input("--from", m.to_string())]),
    };
    if let Some(e) = dangling_link(dir, "init") {
        return Err(vec![e]);
    }
    if dir.exists() {
        let empty = std::fs::read_dir(dir).map(|mut d| d.next().is_none());
        if !matches!(empty, Ok(true)) {
            return Err(vec![Error::input(
                dir,
                "init: exists and is not an empty directory: `init` writes a new repository",
            )]);
        }
    }
    let files: Vec<(PathBuf, String)> = starter_files(from.as_deref())
        .into_iter()
        .map(|(p, t)| (dir.join(p), t))
        .collect();
    write_files(&files, "init")?;
    let call = Call {
        log_root: None,
        sharded: false,
        max_steps: None,
    };
    let preps = prepare_all(&[dir.join("scenarios")], &call)?;
    let opts = RunOptions {
        log_root: None,
        progress: Default::default(),
        pose_rate: crate::runner::DEFAULT_POSE_RATE,
        cancel: Default::default(),
        keep: crate::log::Keep::All,
        batch: true,
    };
    let base = dir.join("baselines");
    let mut errors = Vec::new();
    let mut ran = Vec::new();
    for r in crate::suite::run_all(&preps, &opts, None, &[]) {
        match r.result {
            Ok(o) if o.verdict.ok() => {
                let path = baseline::path_for(&base, &o.name);
                if let Err(m) = Baseline::from_outcome(&o).write(&path) {
                    errors.push(Error::Write {
                        path,
                        command: "init",
                        message: m.to_string(),
                    });
                }
                ran.push((o.name.clone(), o.verdict.describe(&o.failures, None)));
            }
            // The starter's gates hold on every platform the tests run on:
            // a failure here is worth a report, not a silent baseline.
            Ok(o) => errors.push(Error::input(
                dir.join("scenarios").join(format!("{}.toml", o.name)),
                format!(
                    "the starter scenario does not pass here ({}): no baseline written",
                    o.failures.join("; ")
                ),
            )),
            Err(e) => errors.push(e),
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok(ran)
}
