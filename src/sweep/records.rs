//! `variants.jsonl`: one line per finished variant, appended and flushed as
//! variants finish (in any order), after a header line that says which sweep
//! the file belongs to. It is what `--resume` continues and what `merge`
//! combines; `sweep.json` is computed from it alone, so a resumed, a merged
//! and an uninterrupted sweep write the same `sweep.json`.
//!
//! Numbers are read back exactly: every number token is parsed with Rust's
//! correctly rounded `str::parse` (serde_json's default float parser can be
//! one ulp off), and the records go into `sweep.json` as the bytes written.

use crate::sweep::Shard;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::io::{BufRead, BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

/// Format version of the header.
pub const FORMAT: u32 = 1;

/// First line of a `variants.jsonl`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Header {
    /// Format version ([`FORMAT`]).
    pub anholonomy_variants: u32,
    /// Scenario name.
    pub scenario: String,
    /// Scenario file as given.
    pub file: PathBuf,
    /// SHA-256 of the scenario text (hex).
    pub scenario_sha256: String,
    /// `sweep.seed`.
    pub seed: u64,
    /// `sweep.count`.
    pub count: usize,
    /// The shard this file holds (None: every variant).
    pub shard: Option<Shard>,
    /// The `[sweep]` table as `sweep.json` reports it.
    pub sweep: Value,
}

/// Hex SHA-256 of a text.
pub(crate) fn sha256_hex(text: &str) -> String {
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// File name of the records of a sweep or shard.
pub fn file_name(shard: Option<Shard>) -> String {
    match shard {
        None => "variants.jsonl".into(),
        Some(s) => format!("variants-shard-{}-of-{}.jsonl", s.index, s.count),
    }
}

/// What `sweep.json` needs of one record.
#[derive(Debug, Clone)]
pub struct Entry {
    /// Which file of the scan (merge reads several).
    pub file: usize,
    /// Variant index.
    pub index: usize,
    /// Byte offset and length of the line (without `,"wall_s":..}` and the newline).
    pub offset: u64,
    /// See `offset`.
    pub len: usize,
    /// `success_metric ≤ success_max`.
    pub success: bool,
    /// Success metric (finite) or None.
    pub final_error: Option<f64>,
    /// Time metric (finite) or None.
    pub time_to_goal: Option<f64>,
    /// Physics steps.
    pub steps: usize,
    /// Why the variant could not run.
    pub error: Option<String>,
    /// Wall time, s.
    pub wall_s: f64,
}

/// A read `variants.jsonl`.
#[derive(Debug)]
pub struct Scan {
    /// Its header.
    pub header: Header,
    /// Its records, in file order.
    pub entries: Vec<Entry>,
    /// Bytes up to the end of the last complete line (a partial last line is dropped).
    pub valid_len: u64,
}

/// Put every number outside strings in quotes, so it reaches us as written.
fn quote_numbers(line: &str) -> String {
    let mut out = String::with_capacity(line.len() + 64);
    let (mut in_str, mut esc, mut in_num) = (false, false, false);
    for c in line.chars() {
        if in_str {
            out.push(c);
            if esc {
                esc = false;
            } else if c == '\\' {
                esc = true;
            } else if c == '"' {
                in_str = false;
            }
            continue;
        }
        let num_char = c.is_ascii_digit() || matches!(c, '-' | '+' | '.' | 'e' | 'E');
        if in_num && !num_char {
            out.push('"');
            in_num = false;
        }
        if !in_num && (c.is_ascii_digit() || c == '-') {
            out.push('"');
            in_num = true;
        }
        if c == '"' {
            in_str = true;
        }
        out.push(c);
    }
    if in_num {
        out.push('"');
    }
    out
}

/// Turn quoted numbers back into values (`x` as produced by [`quote_numbers`]).
fn number(v: &Value) -> Option<f64> {
    v.as_str().and_then(|s| s.parse::<f64>().ok())
}

/// What is wrong with one record line of a `variants.jsonl`.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// A field every record has is absent (`wall_s`, `index`, ...).
    #[error("not a variant record (no `{0}`)")]
    Missing(String),
    /// The line is not JSON.
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    /// `index` or `steps` is not a non-negative integer.
    #[error("`{0}` is not a non-negative integer")]
    NotCount(String),
    /// A number field holds something else.
    #[error("`{0}` is not a number")]
    NotNumber(String),
    /// `success` holds something else.
    #[error("`{0}` is not a boolean")]
    NotBoolean(String),
}

/// Why a `variants.jsonl` cannot be used (see [`scan`], [`Scan::check_indices`]).
#[derive(Debug, thiserror::Error)]
pub enum RecordsError {
    /// The file cannot be opened.
    #[error(transparent)]
    Open(std::io::Error),
    /// A line cannot be read (not text, say).
    #[error("line {line}: {source} (not a variants.jsonl file)")]
    Read {
        /// 1-based line number.
        line: usize,
        /// Underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The first line is not a header of this harness.
    #[error("line 1: not a variants.jsonl header of anholonomy ({0})")]
    Header(#[source] serde_json::Error),
    /// The header's format version is not [`FORMAT`].
    #[error("line 1: format {0} is not supported (expected {FORMAT})", FORMAT = FORMAT)]
    Format(u32),
    /// A record line is malformed.
    #[error("line {line}: {source}")]
    Record {
        /// 1-based line number.
        line: usize,
        /// What is wrong with it.
        #[source]
        source: RecordError,
    },
    /// Not even a header line.
    #[error("empty: no header line (not a variants.jsonl file)")]
    Empty,
    /// A record's variant is outside the sweep (or the header's shard).
    #[error("variant {index} does not belong to this {}", shard_name(*.shard))]
    Foreign {
        /// The variant index.
        index: usize,
        /// The header's shard, if any.
        shard: Option<Shard>,
    },
    /// A variant has two records.
    #[error("variant {0} recorded twice")]
    Twice(usize),
}

/// `shard I/N`, or `sweep` for a whole one.
fn shard_name(shard: Option<Shard>) -> String {
    shard
        .map(|s| format!("shard {}/{}", s.index, s.count))
        .unwrap_or("sweep".into())
}

/// Parse one record line (without its newline) into an entry.
fn parse_record(line: &str, file: usize, offset: u64) -> Result<Entry, RecordError> {
    const WALL: &str = ",\"wall_s\":";
    let cut = line
        .rfind(WALL)
        .ok_or_else(|| RecordError::Missing("wall_s".into()))?;
    let v: Value = serde_json::from_str(&quote_numbers(line))?;
    let field = |k: &str| v.get(k).ok_or_else(|| RecordError::Missing(k.into()));
    let int = |k: &str| -> Result<usize, RecordError> {
        field(k)?
            .as_str()
            .and_then(|s| s.parse().ok())
            .ok_or_else(|| RecordError::NotCount(k.into()))
    };
    let opt = |k: &str| -> Result<Option<f64>, RecordError> {
        let x = field(k)?;
        if x.is_null() {
            return Ok(None);
        }
        number(x)
            .map(Some)
            .ok_or_else(|| RecordError::NotNumber(k.into()))
    };
    Ok(Entry {
        file,
        index: int("index")?,
        offset,
        len: cut,
        success: field("success")?
            .as_bool()
            .ok_or_else(|| RecordError::NotBoolean("success".into()))?,
        final_error: opt("final_error")?,
        time_to_goal: opt("time_to_goal")?,
        steps: int("steps")?,
        error: field("error")?.as_str().map(str::to_string),
        wall_s: opt("wall_s")?.unwrap_or(f64::NAN),
    })
}

/// Parse a record line as written (with its newline).
pub(crate) fn parse_line(line: &str) -> Result<Entry, RecordError> {
    parse_record(line.trim_end_matches('\n'), 0, 0)
}

/// Read a `variants.jsonl` (file number `file` of a merge). Errors are one
/// line naming the line number; a last line without its newline (a killed
/// writer) is ignored.
pub fn scan(path: &Path, file: usize) -> Result<Scan, RecordsError> {
    let f = std::fs::File::open(path).map_err(RecordsError::Open)?;
    let mut r = BufReader::new(f);
    let mut buf = String::new();
    let mut offset = 0u64;
    let mut header: Option<Header> = None;
    let mut entries = Vec::new();
    let mut lineno = 0usize;
    loop {
        buf.clear();
        let n = r.read_line(&mut buf).map_err(|source| RecordsError::Read {
            line: lineno + 1,
            source,
        })?;
        if n == 0 || !buf.ends_with('\n') {
            break; // end, or a partial last line
        }
        lineno += 1;
        let line = buf.trim_end_matches('\n');
        match &header {
            None => {
                let h: Header = serde_json::from_str(line).map_err(RecordsError::Header)?;
                if h.anholonomy_variants != FORMAT {
                    return Err(RecordsError::Format(h.anholonomy_variants));
                }
                header = Some(h);
            }
            Some(_) => entries.push(parse_record(line, file, offset).map_err(|source| {
                RecordsError::Record {
                    line: lineno,
                    source,
                }
            })?),
        }
        offset += n as u64;
    }
    let header = header.ok_or(RecordsError::Empty)?;
    Ok(Scan {
        header,
        entries,
        valid_len: offset,
    })
}

impl Scan {
    /// Check every record against the header: index below `count`, in the
    /// shard, recorded once. Returns which indices are done.
    pub fn check_indices(&self) -> Result<Vec<bool>, RecordsError> {
        let h = &self.header;
        let mut done = vec![false; h.count];
        for e in &self.entries {
            if e.index >= h.count || h.shard.is_some_and(|s| !s.contains(e.index)) {
                return Err(RecordsError::Foreign {
                    index: e.index,
                    shard: h.shard,
                });
            }
            if std::mem::replace(&mut done[e.index], true) {
                return Err(RecordsError::Twice(e.index));
            }
        }
        Ok(done)
    }

    /// Why this file cannot be resumed by a sweep with header `want`, if it cannot.
    pub fn mismatch(&self, want: &Header) -> Option<String> {
        let h = &self.header;
        if h.scenario != want.scenario {
            return Some(format!(
                "written by scenario `{}`, not `{}`",
                h.scenario, want.scenario
            ));
        }
        if h.scenario_sha256 != want.scenario_sha256 {
            return Some(
                "written for another version of the scenario file (its SHA-256 differs)".into(),
            );
        }
        if (h.seed, h.count) != (want.seed, want.count) {
            return Some(format!(
                "written for seed {} and count {}, not seed {} and count {}",
                h.seed, h.count, want.seed, want.count
            ));
        }
        if h.shard != want.shard {
            let f = |s: Option<Shard>| {
                s.map(|s| format!("shard {}/{}", s.index, s.count))
                    .unwrap_or("the unsharded sweep".into())
            };
            return Some(format!("written by {}, not {}", f(h.shard), f(want.shard)));
        }
        None
    }
}

/// The bytes of a record as `sweep.json` lists it (the line without its wall time).
pub(crate) fn raw_record<R: Read + Seek>(r: &mut R, e: &Entry) -> std::io::Result<Vec<u8>> {
    r.seek(SeekFrom::Start(e.offset))?;
    let mut b = vec![0; e.len];
    r.read_exact(&mut b)?;
    b.push(b'}');
    Ok(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_read_as_written() {
        let x = 0.1f64 + 0.2;
        let line = format!(
            "{{\"index\":3,\"e\":\"a \\\"1.5\\\" b\",\"success\":true,\"final_error\":{x},\
             \"time_to_goal\":null,\"steps\":12,\"error\":null,\"m\":[-1e-300,2.5E3],\"wall_s\":0.5}}"
        );
        let q = quote_numbers(&line);
        let v: Value = serde_json::from_str(&q).unwrap();
        assert_eq!(v["e"], "a \"1.5\" b");
        assert_eq!(v["m"][0], "-1e-300");
        let e = parse_record(&line, 0, 7).unwrap();
        assert_eq!(e.final_error.unwrap().to_bits(), x.to_bits());
        assert_eq!((e.index, e.steps, e.time_to_goal), (3, 12, None));
        assert_eq!(e.len, line.rfind(",\"wall_s\"").unwrap());
        assert!(parse_record("{\"index\":1}", 0, 0).is_err());
    }
}
