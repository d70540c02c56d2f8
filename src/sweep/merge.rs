//! `anholonomy merge DIR|FILES...`: the shards of one sweep
//! (`variants-shard-I-of-N.jsonl`, written by `run --shard I/N`) combined
//! into the `sweep.json` an unsharded run writes. Every shard must be there
//! once, complete, and of the same sweep (scenario text, seed, count, shard
//! count); anything else is an input error naming the shard, and nothing is
//! written.

use crate::error::Error;
use crate::scenario::SweepConfig;
use crate::sweep::records::{self, Entry, Header, Scan};
use crate::sweep::summary::{finish, Summary};
use std::path::{Path, PathBuf};

/// Shard files named on the command line: a directory stands for its
/// `variants-shard-*.jsonl` files (sorted).
fn expand(inputs: &[PathBuf]) -> Result<Vec<PathBuf>, Vec<Error>> {
    let mut out = Vec::new();
    let mut errs = Vec::new();
    for p in inputs {
        if p.is_dir() {
            let mut files: Vec<PathBuf> = std::fs::read_dir(p)
                .map_err(|e| vec![Error::input(p, format!("cannot list directory: {e}"))])?
                .flatten()
                .map(|e| e.path())
                .filter(|f| {
                    f.file_name().is_some_and(|n| {
                        let n = n.to_string_lossy();
                        n.starts_with("variants-shard-") && n.ends_with(".jsonl")
                    })
                })
                .collect();
            files.sort();
            if files.is_empty() {
                errs.push(Error::input(
                    p,
                    "no variants-shard-*.jsonl files (written by `run --shard I/N`)",
                ));
            }
            out.extend(files);
        } else if p.is_file() {
            out.push(p.clone());
        } else {
            errs.push(Error::input(p, "no such file or directory"));
        }
    }
    if errs.is_empty() {
        Ok(out)
    } else {
        Err(errs)
    }
}

/// Read and check the shards; write `out` (default: `sweep.json` beside the
/// first shard). Returns the summary and where `sweep.json` went.
pub fn merge(inputs: &[PathBuf], out: Option<&Path>) -> Result<(Summary, PathBuf), Vec<Error>> {
    let files = expand(inputs)?;
    let mut scans: Vec<Scan> = Vec::new();
    let mut errs = Vec::new();
    for (k, f) in files.iter().enumerate() {
        match records::scan(f, k) {
            Ok(s) => scans.push(s),
            Err(e) => errs.push(Error::input(f, format!("not a readable shard: {e}"))),
        }
    }
    if !errs.is_empty() {
        return Err(errs);
    }
    let first = &scans[0].header;
    let n_shards = match first.shard {
        Some(s) => s.count,
        None => {
            return Err(vec![Error::input(
                &files[0],
                "not a shard (an unsharded sweep's variants.jsonl): nothing to merge",
            )])
        }
    };
    let mut by_index: Vec<Option<usize>> = vec![None; n_shards];
    for (k, s) in scans.iter().enumerate() {
        let h = &s.header;
        let f = &files[k];
        let same = Header {
            shard: first.shard,
            ..h.clone()
        };
        if let Some(why) = scans[0].mismatch(&same) {
            errs.push(Error::input(
                f,
                format!(
                    "shard of another sweep than {}: {why}",
                    crate::echo::path(&files[0])
                ),
            ));
            continue;
        }
        if same.file != first.file || same.sweep != first.sweep {
            errs.push(Error::input(
                f,
                format!(
                    "shard of another sweep than {} (file or [sweep] differ)",
                    crate::echo::path(&files[0])
                ),
            ));
            continue;
        }
        let Some(sh) = h.shard else {
            errs.push(Error::input(
                f,
                "not a shard (an unsharded sweep's variants.jsonl)",
            ));
            continue;
        };
        if sh.count != n_shards {
            errs.push(Error::input(
                f,
                format!(
                    "shard {}/{} of a sweep split into {} shards, {} into {n_shards}",
                    sh.index,
                    sh.count,
                    sh.count,
                    crate::echo::path(&files[0])
                ),
            ));
            continue;
        }
        if let Some(j) = by_index[sh.index] {
            errs.push(Error::input(
                f,
                format!(
                    "shard {}/{n_shards} given twice (also {})",
                    sh.index,
                    crate::echo::path(&files[j])
                ),
            ));
            continue;
        }
        by_index[sh.index] = Some(k);
        if let Err(e) = s.check_indices() {
            errs.push(Error::input(f, e.to_string()));
            continue;
        }
        let want = (0..h.count).filter(|&i| sh.contains(i)).count();
        if s.entries.len() < want {
            errs.push(Error::input(
                f,
                format!(
                    "shard {}/{n_shards} is incomplete: {} of {want} variants (finish it with `run --shard {}/{n_shards} --resume`)",
                    sh.index,
                    s.entries.len(),
                    sh.index
                ),
            ));
        }
    }
    let dir = files[0].parent().unwrap_or(Path::new("."));
    let missing: Vec<String> = (0..n_shards)
        .filter(|&i| by_index[i].is_none())
        .map(|i| format!("variants-shard-{i}-of-{n_shards}.jsonl"))
        .collect();
    if !missing.is_empty() && errs.is_empty() {
        errs.push(Error::input(
            dir,
            format!(
                "{} of {n_shards} shards missing: {}",
                missing.len(),
                missing.join(", ")
            ),
        ));
    }
    if !errs.is_empty() {
        return Err(errs);
    }
    let cfg: SweepConfig = serde_json::from_value(first.sweep.clone()).map_err(|e| {
        vec![Error::input(
            &files[0],
            format!("key `sweep` of the header: {e}"),
        )]
    })?;
    let h = Header {
        shard: None,
        ..first.clone()
    };
    let mut entries: Vec<Entry> = scans.into_iter().flat_map(|s| s.entries).collect();
    entries.sort_by_key(|e| e.index);
    let wall = entries
        .iter()
        .map(|e| e.wall_s)
        .filter(|w| w.is_finite())
        .sum();
    let out = out
        .map(Path::to_path_buf)
        .unwrap_or_else(|| dir.join("sweep.json"));
    let sum = finish(&h, &cfg, &entries, &files, Some(&out), wall).map_err(|e| {
        vec![Error::Log {
            path: out.clone(),
            message: e.to_string(),
        }]
    })?;
    Ok((sum, out))
}
