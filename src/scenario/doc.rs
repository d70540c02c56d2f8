//! Where things are in a scenario file: every key path with its line and
//! spans, so any error (TOML syntax, serde type or range errors, range checks
//! made later, planner and physics refusals) can name file, line and key.
//!
//! Key paths are written as in messages: `sim.dt`, `planner.via_deg[1]`,
//! `goal[0]`.

use crate::error::Error;
use std::ops::Range;
use std::path::Path;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// One key (or array element) of the document.
#[derive(Debug, Clone)]
struct Entry {
    path: String,
    key: Range<usize>,
    value: Range<usize>,
}

/// Key paths, spans and line starts of one parsed scenario file.
#[derive(Debug, Clone, Default)]
pub struct KeyIndex {
    entries: Vec<Entry>,
    line_starts: Vec<usize>,
    /// Floats that are NaN or infinite: (path, span, as written).
    nonfinite: Vec<(String, Range<usize>, String)>,
    /// The [`ALIASES`] this file uses: (read as, written as).
    aliases: Vec<(&'static str, &'static str)>,
}

/// Lists a file may write under another name than the one they are read
/// as: (read as, written as). Errors about them name the written key.
pub const ALIASES: &[(&str, &str)] = &[("model.obstacles", "world.obstacles")];

impl KeyIndex {
    /// Index a parsed document.
    pub fn new(text: &str, root: &DeTable<'_>) -> KeyIndex {
        let mut line_starts = vec![0];
        line_starts.extend(text.match_indices('\n').map(|(i, _)| i + 1));
        let mut ix = KeyIndex {
            entries: Vec::new(),
            line_starts,
            nonfinite: Vec::new(),
            aliases: Vec::new(),
        };
        ix.walk_table(root, "");
        ix.aliases = ALIASES
            .iter()
            .copied()
            .filter(|(_, written)| ix.has(written))
            .collect();
        ix
    }

    /// `key` as this file writes it (see [`ALIASES`]).
    pub fn written(&self, key: &str) -> String {
        for (read, written) in &self.aliases {
            if let Some(rest) = key.strip_prefix(read) {
                if rest.is_empty() || rest.starts_with(['.', '[']) {
                    return format!("{written}{rest}");
                }
            }
        }
        key.to_string()
    }

    fn walk_table(&mut self, t: &DeTable<'_>, prefix: &str) {
        for (k, v) in t.iter() {
            // A key that is itself a path (`[sweep.vary]`'s `"planner.k1"`) keeps its quotes.
            let name = k.get_ref().to_string();
            let name = if name.contains(['.', '[', ']', ' ', '`']) {
                format!("\"{name}\"")
            } else {
                name
            };
            let path = if prefix.is_empty() {
                name
            } else {
                format!("{prefix}.{name}")
            };
            self.entries.push(Entry {
                path: path.clone(),
                key: k.span(),
                value: v.span(),
            });
            self.walk_value(v, &path);
        }
    }

    fn walk_value(&mut self, v: &Spanned<DeValue<'_>>, path: &str) {
        match v.get_ref() {
            DeValue::Float(f) => {
                let s = f.as_str().trim_start_matches(['+', '-']).replace('_', "");
                if !s.parse::<f64>().is_ok_and(f64::is_finite) {
                    self.nonfinite
                        .push((path.to_string(), v.span(), f.as_str().to_string()));
                }
            }
            DeValue::Array(items) => {
                for (i, item) in items.iter().enumerate() {
                    let p = format!("{path}[{i}]");
                    self.entries.push(Entry {
                        path: p.clone(),
                        key: item.span(),
                        value: item.span(),
                    });
                    self.walk_value(item, &p);
                }
            }
            DeValue::Table(t) => self.walk_table(t, path),
            _ => {}
        }
    }

    /// 1-based line of a byte offset.
    pub fn line_at(&self, offset: usize) -> usize {
        self.line_starts.partition_point(|&s| s <= offset).max(1)
    }

    /// Line of `key`, or of its nearest written ancestor (a defaulted key
    /// points at its table).
    pub fn line_of(&self, key: &str) -> Option<usize> {
        let key = self.written(key);
        let mut k = key.as_str();
        loop {
            if let Some(e) = self.entries.iter().find(|e| e.path == k) {
                return Some(self.line_at(e.key.start));
            }
            k = match k.rfind(['.', '[']) {
                Some(i) => &k[..i],
                None => return None,
            };
        }
    }

    /// Whether `key` is written in the file.
    pub fn has(&self, key: &str) -> bool {
        self.entries.iter().any(|e| e.path == key)
    }

    /// The innermost key whose key or value span contains `span`'s start.
    pub fn key_at(&self, span: &Range<usize>) -> Option<&str> {
        let inside =
            |r: &Range<usize>| r.start <= span.start && span.start < r.end.max(r.start + 1);
        self.entries
            .iter()
            .filter(|e| inside(&e.key) || inside(&e.value))
            .min_by_key(|e| {
                let v = e.value.end.saturating_sub(e.value.start);
                let k = e.key.end.saturating_sub(e.key.start);
                v.max(k)
            })
            .map(|e| e.path.as_str())
    }

    /// The innermost key whose value span holds all of `span` (a table).
    fn table_at(&self, span: &Range<usize>) -> Option<&str> {
        self.entries
            .iter()
            .filter(|e| e.value.start <= span.start && span.end <= e.value.end)
            .min_by_key(|e| e.value.end - e.value.start)
            .map(|e| e.path.as_str())
    }

    /// The first NaN or infinite number, as an error naming its key.
    pub fn check_finite(&self, path: &Path) -> Result<(), Error> {
        match self.nonfinite.first() {
            Some((key, span, raw)) => Err(Error::Input {
                key: Some(key.clone()),
                path: path.into(),
                line: Some(self.line_at(span.start)),
                message: format!(
                    "key `{}`: {raw} is not a finite number",
                    crate::echo::bare(key)
                ),
            }),
            None => Ok(()),
        }
    }

    /// An input error about key `key` of this file, at its line:
    /// "key `key`: message".
    pub fn error_at(&self, path: &Path, key: &str, message: impl std::fmt::Display) -> Error {
        let key = self.written(key);
        Error::Input {
            key: Some(key.clone()),
            path: path.into(),
            line: self.line_of(&key),
            message: format!("key `{}`: {message}", crate::echo::bare(&key)),
        }
    }

    /// A setup refusal about this file: at the line of the key it is about,
    /// if it is about one.
    pub fn setup_error(&self, path: &Path, e: &crate::error::SetupError) -> Error {
        let mut e = e.clone();
        if let crate::error::About::Key(k) = &mut e.about {
            *k = self.written(k);
        }
        Error::Input {
            key: e.key_name().map(str::to_string),
            path: path.into(),
            line: e.key_name().and_then(|k| self.line_of(k)),
            message: e.to_string(),
        }
    }

    /// A serde error from deserializing (part of) this document: names the
    /// key at the error's span and its line.
    pub fn serde_error(&self, path: &Path, e: &toml::de::Error) -> Error {
        // serde writes floats in full (`floating point `1000...0``).
        let raw = crate::numfmt::shorten_long_numbers(&e.message().trim().replace('\n', " "));
        let span = e.span();
        let at = span
            .as_ref()
            .and_then(|s| self.key_at(s))
            .map(str::to_string);
        let line = span.as_ref().map(|s| self.line_at(s.start));
        let field = raw.split('`').nth(1).unwrap_or("");
        let join = |table: Option<&str>| match table {
            Some(t) if !t.is_empty() => format!("{t}.{field}"),
            _ => field.to_string(),
        };
        let (key, message) = if raw.starts_with("missing field ") {
            // The span is the table missing the key (the whole document for a
            // top-level key: no entry holds it).
            let table = span.as_ref().and_then(|s| self.table_at(s));
            (join(table), "required key is missing".to_string())
        } else if raw.starts_with("unknown field ") {
            // The span is the unknown key itself.
            let expected = raw.split_once(", ").map(|(_, e)| e).unwrap_or("");
            let key = at.clone().unwrap_or_else(|| field.to_string());
            // The nearest expected name, as for metric names.
            let hint = expected
                .split('`')
                .skip(1)
                .step_by(2)
                .map(|k| (strsim::jaro_winkler(field, k), k))
                .max_by(|a, b| a.0.total_cmp(&b.0))
                .filter(|(score, _)| *score >= 0.85)
                .map(|(_, k)| format!("did you mean `{k}`? "))
                .unwrap_or_default();
            (key, format!("unknown key ({hint}{expected})"))
        } else {
            (at.unwrap_or_default(), raw.clone())
        };
        let (key, message) = if key.is_empty() {
            (None, message)
        } else {
            let m = format!("key `{}`: {message}", crate::echo::bare(&key));
            (Some(key), m)
        };
        Error::Input {
            path: path.into(),
            line,
            key,
            message,
        }
    }

    /// A TOML syntax error (from [`DeTable::parse`]).
    pub fn syntax_error(path: &Path, text: &str, e: &toml::de::Error) -> Error {
        let ix = KeyIndex::new(text, &DeTable::default());
        Error::Input {
            key: None,
            path: path.into(),
            line: e.span().map(|s| ix.line_at(s.start)),
            message: format!("TOML syntax: {}", e.message().trim().replace('\n', " ")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn index(text: &str) -> KeyIndex {
        let t = DeTable::parse(text).unwrap();
        KeyIndex::new(text, t.get_ref())
    }

    #[test]
    fn lines_of_keys_array_elements_and_defaults() {
        let text = "name = \"a\"\ngoal = [1.0,\n  2.0]\n\n[sim]\ndt = 0.1\n\n[planner]\nkind = \"x\"\nvia = { a = 1 }\n";
        let ix = index(text);
        assert_eq!(ix.line_of("name"), Some(1));
        assert_eq!(ix.line_of("goal[1]"), Some(3));
        assert_eq!(ix.line_of("sim.dt"), Some(6));
        // Not written: its table's header.
        assert_eq!(ix.line_of("sim.friction"), Some(5));
        assert_eq!(ix.line_of("planner.via.a"), Some(10));
        assert_eq!(ix.line_of("limits.ramp"), None);
    }
}
