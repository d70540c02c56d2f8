//! A rosbag2 bag directory: its `metadata.yaml` names the storage (`mcap`
//! or `sqlite3`; others are refused with the command that converts them)
//! and the files that hold the messages, in order.

use crate::planner::PlanError;
use crate::sources::file::ros::Storage;
use std::path::{Path, PathBuf};
use yaml_rust2::{Yaml, YamlLoader};

/// Largest `metadata.yaml` read, bytes (a bag's has a few kB per topic).
const MAX_BYTES: u64 = 16 << 20;

/// What converts a bag to MCAP, for messages.
pub const CONVERT: &str = "convert it to MCAP with `ros2 bag convert -i BAG -o out.yaml` (out.yaml: `output_bags: [{uri: BAG_mcap, storage_id: mcap, all_topics: true}]`; see the guide's \"Replay a ROS 2 recording\")";

/// The metadata file of bag directory `dir`.
pub(crate) fn metadata_path(dir: &Path) -> PathBuf {
    dir.join("metadata.yaml")
}

/// The storage of the bag in `dir` and its files, in order (each an
/// `.mcap`, or each a `.db3`).
pub(crate) fn bag_files(dir: &Path) -> Result<(Storage, Vec<PathBuf>), PlanError> {
    let meta = metadata_path(dir);
    if !meta.is_file() {
        let mcaps = mcap_files_in(dir);
        let hint = match mcaps.as_slice() {
            [] => String::new(),
            [one] => format!(" (it holds {}: point `path` at it)", crate::echo::path(one)),
            _ => " (it holds several .mcap files: point `path` at one)".into(),
        };
        return Err(PlanError::file(
            dir.to_path_buf(),
            None,
            format!("not a rosbag2 bag directory: no metadata.yaml{hint}"),
        ));
    }
    let text = crate::input::read_text(&meta, "bag metadata", MAX_BYTES).map_err(|e| match e {
        crate::error::Error::Input {
            path,
            line,
            message,
            ..
        } => PlanError::file(path, line, message),
        other => PlanError::file(meta.clone(), None, other.to_string()),
    })?;
    let err = |line: Option<usize>, m: String| PlanError::file(meta.clone(), line, m);
    let docs = YamlLoader::load_from_str(&text).map_err(|e| {
        err(
            Some(e.marker().line().max(1)),
            format!("not YAML: {}", e.info()),
        )
    })?;
    let info = docs
        .first()
        .map(|d| &d["rosbag2_bagfile_information"])
        .filter(|i| !i.is_badvalue())
        .ok_or_else(|| {
            err(
                None,
                "no `rosbag2_bagfile_information`: not a rosbag2 metadata file".into(),
            )
        })?;
    let line = |key: &str| line_of(&text, key);
    let storage = match &info["storage_identifier"] {
        Yaml::String(s) => s.as_str(),
        Yaml::BadValue => {
            return Err(err(
                None,
                "no `storage_identifier` (mcap or sqlite3)".into(),
            ))
        }
        _ => {
            return Err(err(
                line("storage_identifier"),
                "`storage_identifier` is not a name".into(),
            ))
        }
    };
    let (storage, ext) = match storage {
        "mcap" => (Storage::Mcap, "mcap"),
        "sqlite3" => (Storage::Sqlite3, "db3"),
        other => {
            return Err(err(
                line("storage_identifier"),
                format!("storage `{other}` is not read here (mcap and sqlite3 are): {CONVERT}"),
            ))
        }
    };
    if let Yaml::String(mode) = &info["compression_mode"] {
        if !mode.is_empty() && !mode.eq_ignore_ascii_case("none") {
            return Err(err(
                line("compression_mode"),
                format!(
                    "a bag compressed by rosbag2 (compression_mode: {mode}) is not read here: decompress it with `ros2 bag convert` (output_bags without compression), or record with `--storage-preset-profile zstd_fast` (MCAP's own chunk compression, which is read)"
                ),
            ));
        }
    }
    let Some(files) = info["relative_file_paths"].as_vec() else {
        return Err(err(
            line("relative_file_paths"),
            "no `relative_file_paths` list".into(),
        ));
    };
    if files.is_empty() {
        return Err(err(
            line("relative_file_paths"),
            "`relative_file_paths` is empty: the bag holds no file".into(),
        ));
    }
    let mut out = Vec::new();
    for f in files {
        let Some(name) = f.as_str() else {
            return Err(err(
                line("relative_file_paths"),
                "`relative_file_paths` holds something that is not a file name".into(),
            ));
        };
        let path = dir.join(name);
        let got = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if got.as_deref() != Some(ext) {
            return Err(err(
                line(name),
                format!(
                    "`{name}` is not a .{ext} file, as a bag of {} storage holds: {CONVERT}",
                    if ext == "db3" { "sqlite3" } else { "mcap" }
                ),
            ));
        }
        if !path.is_file() {
            return Err(err(
                line(name),
                format!("the bag's file `{name}` is missing"),
            ));
        }
        out.push(path);
    }
    Ok((storage, out))
}

/// The `.mcap` files directly in `dir`, sorted.
fn mcap_files_in(dir: &Path) -> Vec<PathBuf> {
    let mut out: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|rd| {
            rd.flatten()
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|e| e == "mcap"))
                .collect()
        })
        .unwrap_or_default();
    out.sort();
    out
}

/// 1-based line of the first line of `text` containing `needle`.
fn line_of(text: &str, needle: &str) -> Option<usize> {
    text.lines().position(|l| l.contains(needle)).map(|i| i + 1)
}
