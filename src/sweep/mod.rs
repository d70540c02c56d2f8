//! Monte Carlo sweeps: a scenario with a `[sweep]` table runs `count` variants of itself
//! (any numeric key by dotted path, masses, the rover's σ; see
//! [`crate::scenario::SweepConfig`]) in parallel (rayon), and reports the success rate and the
//! distribution of final errors and times to goal.
//!
//! Variants are independent and addressed by index: variant i draws its parameters from
//! ChaCha8 streams seeded with [`variant_seed`]`(seed, i)`, so any subset of indices reproduces
//! exactly the same variants. Each finished variant is appended to `variants.jsonl`
//! ([`records`]); `--resume` continues that file, `--shard I/N` runs the indices i ≡ I (mod N)
//! into `variants-shard-I-of-N.jsonl`, and [`merge`] combines shards into the `sweep.json`
//! an unsharded run writes ([`summary`]).

pub mod batch;
pub mod merge;
pub mod records;
pub mod summary;

use crate::cancel::Cancel;
use crate::error::Error;
use crate::progress::Work;
use crate::runner::{run, RunOptions, RunOutcome, Timings};
pub use crate::scenario::{variant_seed, SweepConfig, Variant};
use crate::validate::Prepared;
use rayon::prelude::*;
use records::{Entry, Header, Scan};
use serde::{Deserialize, Serialize};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

/// A subset of variant indices: those with `index % count == shard`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// This shard, 0-based.
    pub index: usize,
    /// Number of shards.
    pub count: usize,
}

/// Why a shard (`--shard`, or a scheduler's variables) is not one.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum ShardError {
    /// `--shard` is not `I/N` with 0 <= I < N.
    #[error("`{0}`: expected I/N with 0 <= I < N")]
    Syntax(String),
    /// An environment variable is not a non-negative integer.
    #[error("{var}={}: not a non-negative integer", crate::echo::code(value))]
    NotCount {
        /// The variable.
        var: String,
        /// Its value.
        value: String,
    },
    /// The index is not below the count.
    #[error("{from}: shard index {index} is not below the shard count {count}")]
    OutOfRange {
        /// Where the shard came from (`SLURM_ARRAY_TASK_ID=3 (shard 3/2)`).
        from: String,
        /// The shard index.
        index: usize,
        /// The shard count.
        count: usize,
    },
    /// A Slurm array with a step other than 1.
    #[error("SLURM_ARRAY_TASK_STEP={0}: use a contiguous array (--array=0-N or 1-N)")]
    SlurmStep(usize),
    /// A Slurm task id without the array's size.
    #[error("SLURM_ARRAY_TASK_ID is set but neither SLURM_ARRAY_TASK_COUNT nor SLURM_ARRAY_TASK_MIN/MAX")]
    SlurmCount,
    /// A Slurm task id below the array's first.
    #[error("SLURM_ARRAY_TASK_ID={id} is below SLURM_ARRAY_TASK_MIN={min}")]
    SlurmBelowMin {
        /// `SLURM_ARRAY_TASK_ID`.
        id: usize,
        /// `SLURM_ARRAY_TASK_MIN`.
        min: usize,
    },
    /// A Kubernetes index without a shard count.
    #[error("JOB_COMPLETION_INDEX is set but the shard count is not: pass --shards N or set ANHOLONOMY_SHARDS")]
    NoCount,
}

impl Shard {
    /// Parses `I/N` (0 ≤ I < N).
    pub fn parse(s: &str) -> Result<Shard, ShardError> {
        let bad = || ShardError::Syntax(s.into());
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count): (usize, usize) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }

    /// Whether variant `i` belongs to this shard.
    pub fn contains(&self, i: usize) -> bool {
        i % self.count == self.index
    }

    /// The shard a scheduler gives this process, when `--shard` is absent:
    /// Slurm job arrays (`SLURM_ARRAY_TASK_ID` with `SLURM_ARRAY_TASK_COUNT`,
    /// or with `SLURM_ARRAY_TASK_MIN`/`MAX`; the index counts from MIN) or a
    /// Kubernetes Indexed Job (`JOB_COMPLETION_INDEX` with `shards`, from
    /// `--shards N` or `ANHOLONOMY_SHARDS`). Returns the shard and where it
    /// came from; errors name the variable.
    pub fn from_env(
        get: impl Fn(&str) -> Option<String>,
        shards: Option<usize>,
    ) -> Result<Option<(Shard, String)>, ShardError> {
        let num = |k: &str| -> Result<Option<usize>, ShardError> {
            match get(k) {
                None => Ok(None),
                Some(v) => v
                    .trim()
                    .parse()
                    .map(Some)
                    .map_err(|_| ShardError::NotCount {
                        var: k.into(),
                        value: v,
                    }),
            }
        };
        let make = |index: usize, count: usize, from: String| {
            if count == 0 || index >= count {
                Err(ShardError::OutOfRange { from, index, count })
            } else {
                Ok(Some((Shard { index, count }, from)))
            }
        };
        if let Some(id) = num("SLURM_ARRAY_TASK_ID")? {
            if let Some(step) = num("SLURM_ARRAY_TASK_STEP")? {
                if step != 1 {
                    return Err(ShardError::SlurmStep(step));
                }
            }
            let min = num("SLURM_ARRAY_TASK_MIN")?.unwrap_or(0);
            let count = match (num("SLURM_ARRAY_TASK_COUNT")?, num("SLURM_ARRAY_TASK_MAX")?) {
                (Some(c), _) => c,
                (None, Some(max)) if max >= min => max - min + 1,
                _ => return Err(ShardError::SlurmCount),
            };
            let Some(index) = id.checked_sub(min) else {
                return Err(ShardError::SlurmBelowMin { id, min });
            };
            return make(
                index,
                count,
                format!("SLURM_ARRAY_TASK_ID={id} (shard {index}/{count})"),
            );
        }
        if let Some(index) = num("JOB_COMPLETION_INDEX")? {
            let count = match shards {
                Some(n) => n,
                None => num("ANHOLONOMY_SHARDS")?.ok_or(ShardError::NoCount)?,
            };
            return make(
                index,
                count,
                format!("JOB_COMPLETION_INDEX={index} (shard {index}/{count})"),
            );
        }
        Ok(None)
    }
}

/// A metric list serialized as a JSON object in its order (NaN as null).
struct Metrics<'a>(&'a [(String, f64)]);

impl Serialize for Metrics<'_> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_map(self.0.iter().map(|(k, v)| (k, v)))
    }
}

/// One line of `variants.jsonl`, before its wall time.
#[derive(Serialize)]
struct Record<'a> {
    #[serde(flatten)]
    variant: &'a Variant,
    success: bool,
    final_error: Option<f64>,
    time_to_goal: Option<f64>,
    steps: usize,
    error: Option<String>,
    metrics: Metrics<'a>,
}

/// Run one variant alone; its `variants.jsonl` line (with the newline).
fn run_variant(prep: &Prepared, cfg: &SweepConfig, v: &Variant, cancel: &Cancel) -> String {
    let t0 = Instant::now();
    let res = prep
        .variant(v)
        .and_then(|p| run(&p, &variant_options(cancel)));
    record_line(cfg, v, &res, t0.elapsed().as_secs_f64())
}

/// How variants run: no logs, no progress.
fn variant_options(cancel: &Cancel) -> RunOptions {
    RunOptions {
        pose_rate: 0.0,
        cancel: cancel.clone(),
        ..Default::default()
    }
}

/// A variant's `variants.jsonl` line (with the newline) from its outcome
/// and wall time, s.
fn record_line(
    cfg: &SweepConfig,
    v: &Variant,
    res: &Result<RunOutcome, Error>,
    wall_s: f64,
) -> String {
    let finite = |x: Option<f64>| x.filter(|v| v.is_finite());
    let empty = Vec::new();
    let rec = match res {
        Ok(o) => {
            let final_error = finite(o.metric(&cfg.success_metric));
            Record {
                variant: v,
                success: final_error.is_some_and(|e| e <= cfg.success_max)
                    && (o.passed || !cfg.success_requires_gates),
                final_error,
                time_to_goal: cfg.time_metric.as_ref().and_then(|m| finite(o.metric(m))),
                steps: o.steps,
                error: None,
                metrics: Metrics(&o.metrics),
            }
        }
        Err(e) => Record {
            variant: v,
            success: false,
            final_error: None,
            time_to_goal: None,
            steps: 0,
            error: Some(e.to_string()),
            metrics: Metrics(&empty),
        },
    };
    let mut line = serde_json::to_string(&rec).unwrap_or_else(|e| {
        let msg = serde_json::Value::String(e.to_string());
        format!("{{\"error\":{msg}}}")
    });
    line.pop();
    let wall = serde_json::to_string(&wall_s).unwrap_or("null".into());
    line.push_str(&format!(",\"wall_s\":{wall}}}\n"));
    line
}

pub use crate::scenario::sweep_metric_names as metric_names;

/// Median, 95th percentile (nearest rank) and maximum; None when empty.
pub fn distribution(values: &[f64]) -> Option<[f64; 3]> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let rank = |p: f64| v[((p * v.len() as f64).ceil() as usize).clamp(1, v.len()) - 1];
    Some([rank(0.5), rank(0.95), v[v.len() - 1]])
}

/// Run the sweep of a prepared scenario (which must have `[sweep]`); writes
/// `<log_root>/<name>/variants.jsonl` and `sweep.json` (or the shard's files).
/// [`run_sweep_report`] gives its table too.
pub fn run_sweep(
    prep: &Prepared,
    opts: &RunOptions,
    shard: Option<Shard>,
) -> Result<RunOutcome, Error> {
    run_sweep_report(prep, opts, shard, None).map(|(outcome, _)| outcome)
}

/// The header a sweep (or shard) writes and a resumed file must match.
pub fn header(prep: &Prepared, shard: Option<Shard>) -> Option<Header> {
    let sc = &prep.scenario;
    let cfg = sc.sweep.as_ref()?;
    Some(Header {
        anholonomy_variants: records::FORMAT,
        scenario: sc.name.clone(),
        file: sc.path.clone(),
        scenario_sha256: records::sha256_hex(sc.text()),
        seed: cfg.seed,
        count: cfg.count,
        shard,
        sweep: serde_json::to_value(cfg).unwrap_or_default(),
    })
}

/// `--resume`: the records already in `<log_root>/<name>/variants.jsonl`
/// (or the shard's file), checked against this sweep before anything runs.
/// None when there is no file yet (the sweep starts from scratch).
pub fn resumable(
    prep: &Prepared,
    log_root: &Path,
    shard: Option<Shard>,
) -> Result<Option<Scan>, Error> {
    let Some(want) = header(prep, shard) else {
        return Ok(None);
    };
    let path = log_root
        .join(&prep.scenario.name)
        .join(records::file_name(shard));
    if !path.exists() {
        return Ok(None);
    }
    let bad = |m: &dyn std::fmt::Display| Error::input(&path, format!("--resume: {m}"));
    let scan = records::scan(&path, 0).map_err(|e| bad(&e))?;
    if let Some(why) = scan.mismatch(&want) {
        return Err(bad(&format!(
            "{why}; remove the file or run without --resume"
        )));
    }
    scan.check_indices().map_err(|e| bad(&e))?;
    Ok(Some(scan))
}

/// Files of other runs that a sweep's directory must not keep beside its own.
const STALE: [&str; 6] = [
    "run.mcap",
    "run.rrd",
    "summary.json",
    "series.json",
    "report.html",
    "regression.json",
];

/// Why the records file could not be started or continued.
#[derive(Debug, thiserror::Error)]
enum OpenRecordsError {
    /// A file operation on `path` failed.
    #[error("{}: {source}", crate::echo::path(path))]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The header could not be encoded.
    #[error(transparent)]
    Header(serde_json::Error),
}

/// Start (or continue) the records file; the directory keeps only this sweep's files.
fn open_records(
    dir: &Path,
    shard: Option<Shard>,
    h: &Header,
    resume: Option<&Scan>,
) -> Result<(std::fs::File, PathBuf), OpenRecordsError> {
    let io = |p: &Path, source: std::io::Error| OpenRecordsError::Io {
        path: p.to_path_buf(),
        source,
    };
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let path = dir.join(records::file_name(shard));
    if let Some(scan) = resume {
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .open(&path)
            .map_err(|e| io(&path, e))?;
        // Drop a partial last line, then append.
        f.set_len(scan.valid_len).map_err(|e| io(&path, e))?;
        std::io::Seek::seek(&mut f, std::io::SeekFrom::End(0)).map_err(|e| io(&path, e))?;
        return Ok((f, path));
    }
    let mut stale: Vec<String> = STALE.iter().map(|s| s.to_string()).collect();
    stale.push("sweep.json".into());
    if let Some(s) = shard {
        stale.push("variants.jsonl".into());
        stale.push(format!("sweep-shard-{}-of-{}.json", s.index, s.count));
    } else if let Ok(rd) = std::fs::read_dir(dir) {
        // An unsharded sweep replaces every shard's files.
        for e in rd.flatten() {
            let n = e.file_name().to_string_lossy().into_owned();
            if n.starts_with("sweep-shard-") || n.starts_with("variants-shard-") {
                stale.push(n);
            }
        }
    }
    for f in stale {
        let _ = std::fs::remove_file(dir.join(f));
    }
    let mut f = std::fs::File::create(&path).map_err(|e| io(&path, e))?;
    let mut line = serde_json::to_string(h).map_err(OpenRecordsError::Header)?;
    line.push('\n');
    f.write_all(line.as_bytes()).map_err(|e| io(&path, e))?;
    Ok((f, path))
}

/// [`run_sweep`] without printing: the outcome and the table text (so parallel callers can
/// print tables in a fixed order). `resume`: the records of an earlier, interrupted run of
/// this sweep ([`resumable`]); their variants are not run again.
pub fn run_sweep_report(
    prep: &Prepared,
    opts: &RunOptions,
    shard: Option<Shard>,
    resume: Option<&Scan>,
) -> Result<(RunOutcome, String), Error> {
    let t_all = Instant::now();
    let sc = &prep.scenario;
    let cfg = sc
        .sweep
        .as_ref()
        .ok_or_else(|| Error::input(&sc.path, "scenario has no [sweep] table"))?;
    let h = header(prep, shard)
        .ok_or_else(|| Error::input(&sc.path, "scenario has no [sweep] table"))?;
    let done = match resume {
        Some(s) => s
            .check_indices()
            .map_err(|e| Error::input(&sc.path, e.to_string()))?,
        None => vec![false; cfg.count],
    };
    let todo: Vec<usize> = (0..cfg.count)
        .filter(|&i| shard.is_none_or(|s| s.contains(i)) && !done[i])
        .collect();
    let log_err = |message: String| Error::Log {
        path: sc.path.clone(),
        message,
    };
    let dir = opts.log_root.as_ref().map(|r| r.join(&sc.name));
    let file = match &dir {
        Some(d) => Some(open_records(d, shard, &h, resume).map_err(|e| log_err(e.to_string()))?),
        None => None,
    };
    let (sink, path) = match file {
        Some((f, p)) => (Some(Mutex::new(f)), Some(p)),
        None => (None, None),
    };
    let memory: Mutex<Vec<Entry>> = Mutex::new(Vec::new());
    let write_error: Mutex<Option<String>> = Mutex::new(None);
    opts.progress
        .started(Work::Sweep, &sc.name, todo.len() as u64);
    let resumed = done.iter().filter(|d| **d).count();
    let groups = if opts.batch {
        batch::groups(prep, &todo)
    } else {
        todo.iter().map(|&i| vec![i]).collect()
    };
    // One group per task (with_max_len): groups are already sized to the cores.
    groups.into_par_iter().with_max_len(1).for_each(|group| {
        if opts.cancel.is_cancelled() {
            return;
        }
        let lines = match group.as_slice() {
            [i] => vec![run_variant(prep, cfg, &cfg.variant(*i), &opts.cancel)],
            _ => batch::run_group(prep, cfg, &group, &opts.cancel),
        };
        // A variant stopped by the token is not a result: not recorded.
        if opts.cancel.is_cancelled() {
            return;
        }
        for line in lines {
            match &sink {
                // One write per line, straight to the file: a killed sweep loses at most the
                // variants (or groups of variants) still running.
                Some(f) => {
                    let res = f.lock().map(|mut f| f.write_all(line.as_bytes()));
                    if let Ok(Err(e)) = res {
                        if let Ok(mut w) = write_error.lock() {
                            w.get_or_insert(e.to_string());
                        }
                    }
                }
                None => {
                    let e = records::parse_line(&line);
                    if let (Ok(e), Ok(mut m)) = (e, memory.lock()) {
                        m.push(e);
                    }
                }
            }
            opts.progress.advanced(Work::Sweep, &sc.name, 1);
        }
    });
    opts.progress.finished(Work::Sweep, &sc.name);
    if let Some(e) = write_error.into_inner().ok().flatten() {
        return Err(log_err(e));
    }
    if opts.cancel.is_cancelled() {
        return Err(Error::Physics {
            path: sc.path.clone(),
            message: crate::cancel::CANCELLED.into(),
        });
    }
    let (mut entries, files) = match &path {
        Some(p) => {
            drop(sink);
            let scan = records::scan(p, 0)
                .map_err(|e| log_err(format!("{}: {e}", crate::echo::path(p))))?;
            (scan.entries, vec![p.clone()])
        }
        None => (memory.into_inner().unwrap_or_default(), Vec::new()),
    };
    entries.sort_by_key(|e| e.index);
    let out = dir.as_ref().map(|d| {
        d.join(match shard {
            None => "sweep.json".to_string(),
            Some(s) => format!("sweep-shard-{}-of-{}.json", s.index, s.count),
        })
    });
    let wall = t_all.elapsed().as_secs_f64();
    let sum = summary::finish(&h, cfg, &entries, &files, out.as_deref(), wall)
        .map_err(|e| log_err(e.to_string()))?;
    let mut table = sum.table;
    if resumed > 0 {
        table = table.replacen("variants", &format!("variants, {resumed} resumed"), 1);
    }
    let outcome = RunOutcome {
        name: sc.name.clone(),
        planner: sc.planner.kind().into(),
        passed: sum.failures.is_empty(),
        verdict: crate::verdict::Verdict::of(sum.failures.is_empty(), sc.expect_fails.is_some()),
        expect_reason: sc.expect_fails.clone(),
        tracking_meaningful: true,
        failures: sum.failures,
        metrics: sum.metrics,
        steps: sum.steps,
        timings: Timings {
            physics: wall,
            total: wall,
            ..Default::default()
        },
        log_dir: dir,
        notes: Vec::new(),
        plan_note: None,
    };
    Ok((outcome, table))
}
