//! Dotted key paths into a scenario document (`sim.friction`, `planner.k1`,
//! `start[2]`): parsed, looked up and overwritten in the parsed TOML
//! ([`DeTable`]), so a sweep variant is the file with some numbers replaced
//! and goes through the same parsing and range checks as the file itself.
//!
//! A replaced value keeps the span of the value it replaces, so an error
//! about it points at the line where the key is written; an inserted key
//! (one the file leaves at its default) gets the span of the `[sweep]`
//! entry that sets it.

use std::fmt;
use std::ops::Range;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// One step of a key path.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Segment {
    /// A table key.
    Key(String),
    /// An array element.
    Index(usize),
}

/// A parsed key path: a key, then `.key` and `[index]` steps.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KeyPath(pub Vec<Segment>);

/// What is wrong with the text of a key path.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
pub enum Malformed {
    /// `[0].a`.
    #[error("it must start with a key")]
    StartsWithIndex,
    /// `a[0`.
    #[error("unclosed `[`")]
    Unclosed,
    /// `a[x]`, `a[-1]`.
    #[error("an index must be a non-negative integer")]
    BadIndex,
    /// `a[0]b`, `a b`.
    #[error("expected `.` or `[` after a key or index")]
    NoStep,
    /// `a..b`, `a.`.
    #[error("empty key")]
    EmptyKey,
    /// The empty string.
    #[error("empty")]
    Empty,
}

/// Why a key path cannot be parsed or set.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum KeyPathError {
    /// The text is not a key path.
    #[error("`{text}` is not a key path ({why}; e.g. `sim.friction`, `start[2]`)")]
    Syntax {
        /// What was written.
        text: String,
        /// What is wrong with it.
        why: Malformed,
    },
    /// A path that starts with an index.
    #[error("`{0}` starts with an index")]
    StartsWithIndex(KeyPath),
    /// Inserting would need an array element that is not written.
    #[error("`{0}`: cannot insert an array element")]
    InsertElement(KeyPath),
    /// An index past the end of a written array.
    #[error("`{path}`: index {index} past the {len} elements")]
    PastEnd {
        /// The whole path.
        path: KeyPath,
        /// The index.
        index: usize,
        /// The array's length.
        len: usize,
    },
    /// A step into a value that is neither a table nor an array.
    #[error("`{0}`: a step is not a table or array")]
    NotContainer(KeyPath),
}

impl KeyPath {
    /// Parse `a.b[2].c`; keys are bare TOML keys (letters, digits, `_`, `-`).
    pub fn parse(s: &str) -> Result<KeyPath, KeyPathError> {
        let bad = |why: Malformed| KeyPathError::Syntax {
            text: s.into(),
            why,
        };
        let is_key = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
        let mut segs = Vec::new();
        let mut rest = s;
        let mut first = true;
        while !rest.is_empty() {
            if let Some(r) = rest.strip_prefix('[') {
                if first {
                    return Err(bad(Malformed::StartsWithIndex));
                }
                let end = r.find(']').ok_or_else(|| bad(Malformed::Unclosed))?;
                let i: usize = r[..end].parse().map_err(|_| bad(Malformed::BadIndex))?;
                segs.push(Segment::Index(i));
                rest = &r[end + 1..];
            } else {
                let r = if first {
                    rest
                } else {
                    rest.strip_prefix('.')
                        .ok_or_else(|| bad(Malformed::NoStep))?
                };
                let end = r.find(|c: char| !is_key(c)).unwrap_or(r.len());
                if end == 0 {
                    return Err(bad(Malformed::EmptyKey));
                }
                segs.push(Segment::Key(r[..end].to_string()));
                rest = &r[end..];
            }
            first = false;
        }
        if segs.is_empty() {
            return Err(bad(Malformed::Empty));
        }
        Ok(KeyPath(segs))
    }

    /// The first key.
    pub fn root(&self) -> &str {
        match &self.0[0] {
            Segment::Key(k) => k,
            Segment::Index(_) => "",
        }
    }

    /// The path of the first `n` segments, as written in messages.
    pub fn prefix(&self, n: usize) -> String {
        KeyPath(self.0[..n].to_vec()).to_string()
    }
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, s) in self.0.iter().enumerate() {
            match s {
                Segment::Key(k) if i == 0 => write!(f, "{k}")?,
                Segment::Key(k) => write!(f, ".{k}")?,
                Segment::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

/// What a key path finds in a document.
#[derive(Debug, PartialEq)]
pub enum Found {
    /// A written integer or float.
    Number {
        /// Written as an integer.
        integer: bool,
    },
    /// A written value of another type (its TOML type name).
    NotNumber(&'static str),
    /// Not written: inserting it creates the key (and missing tables) there.
    Absent,
    /// Not written and not insertable; why.
    Unreachable(String),
}

/// Why a step of a path finds nothing to step into (after the path so far).
#[derive(Debug, thiserror::Error)]
enum StepError {
    #[error("has {0} elements")]
    PastEnd(usize),
    #[error("is a table, not an array")]
    TableNotArray,
    #[error("is {}, not a table", article(.0))]
    NotTable(&'static str),
}

fn child<'a, 'i>(
    v: &'a DeValue<'i>,
    seg: &Segment,
) -> Result<Option<&'a Spanned<DeValue<'i>>>, StepError> {
    match (v, seg) {
        (DeValue::Table(t), Segment::Key(k)) => Ok(t.get(k.as_str())),
        (DeValue::Array(a), Segment::Index(i)) => match a.get(*i) {
            Some(x) => Ok(Some(x)),
            None => Err(StepError::PastEnd(a.len())),
        },
        (DeValue::Table(_), Segment::Index(_)) => Err(StepError::TableNotArray),
        (other, _) => Err(StepError::NotTable(other.type_str())),
    }
}

fn article(t: &str) -> String {
    if t.starts_with(['a', 'e', 'i', 'o', 'u']) {
        format!("an {t}")
    } else {
        format!("a {t}")
    }
}

/// Look `path` up in a parsed document.
pub fn find(root: &DeTable<'_>, path: &KeyPath) -> Found {
    let mut cur: Option<&DeValue<'_>> = None;
    for (n, seg) in path.0.iter().enumerate() {
        let next = match cur {
            None => match seg {
                Segment::Key(k) => root.get(k.as_str()),
                Segment::Index(_) => return Found::Unreachable("starts with an index".into()),
            },
            Some(v) => match child(v, seg) {
                Ok(x) => x,
                Err(why) => return Found::Unreachable(format!("`{}` {why}", path.prefix(n))),
            },
        };
        match next {
            Some(v) => cur = Some(v.get_ref()),
            None => {
                // Missing from here on: insertable when the rest are keys.
                return match path.0[n..].iter().position(|s| matches!(s, Segment::Index(_))) {
                    None => Found::Absent,
                    Some(j) => Found::Unreachable(format!(
                        "`{}` is not written in the file (write it out to sweep one of its elements)",
                        path.prefix(n + j)
                    )),
                };
            }
        }
    }
    match cur {
        Some(DeValue::Integer(_)) => Found::Number { integer: true },
        Some(DeValue::Float(_)) => Found::Number { integer: false },
        Some(v) => Found::NotNumber(v.type_str()),
        None => Found::Unreachable("empty path".into()),
    }
}

/// Tables whose keys are the file's own names (any key is accepted there,
/// so a key a sweep inserts would be silently unused).
pub const DECLARED_TABLES: [&str; 1] = ["model.params"];

/// Why `path` may not be inserted: it names an entry of a
/// [`DECLARED_TABLES`] table that the file does not declare (with the
/// nearest declared name); `None` when it may be.
pub fn undeclared(root: &DeTable<'_>, path: &KeyPath) -> Option<String> {
    let (last, table) = path.0.split_last()?;
    let Segment::Key(name) = last else {
        return None;
    };
    let table = KeyPath(table.to_vec());
    let written = table.to_string();
    if !DECLARED_TABLES.contains(&written.as_str()) {
        return None;
    }
    let mut cur = root;
    for seg in &table.0 {
        let Segment::Key(k) = seg else { return None };
        match cur.get(k.as_str()).map(|v| v.get_ref()) {
            Some(DeValue::Table(t)) => cur = t,
            _ => {
                return Some(format!(
                    "`{written}` is not in the file: a sweep varies a parameter it declares"
                ))
            }
        }
    }
    let declared: Vec<&str> = cur.keys().map(|k| k.get_ref().as_ref()).collect();
    let hint = declared
        .iter()
        .map(|k| (strsim::jaro_winkler(name, k), *k))
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .filter(|(score, _)| *score >= 0.8)
        .map(|(_, k)| format!("did you mean `{k}`? "))
        .unwrap_or_default();
    Some(format!(
        "{} is not declared in [{written}]: a sweep varies a parameter the file declares ({hint}declared: {})",
        crate::echo::code(name),
        declared.join(", ")
    ))
}

/// `value` as a TOML number: an integer when it is one (so integer keys
/// such as `sim.solver_iterations` accept it), else a float written to
/// round-trip exactly.
pub fn toml_number(value: f64) -> String {
    if value.fract() == 0.0 && value.abs() < 9.0e15 {
        format!("{}", value as i64)
    } else {
        format!("{value:?}")
    }
}

/// Set `path` to `value` (a number parsed with [`DeValue::parse`]). A
/// written value keeps its span; a missing key (and any missing table on the
/// way) is inserted with `span`. The path must have passed [`find`] as
/// [`Found::Number`] or [`Found::Absent`].
pub fn set<'i>(
    root: &mut DeTable<'i>,
    path: &KeyPath,
    value: DeValue<'i>,
    span: Range<usize>,
) -> Result<(), KeyPathError> {
    match &path.0[0] {
        Segment::Key(k) => set_key(root, k, &path.0[1..], value, span, path),
        Segment::Index(_) => Err(KeyPathError::StartsWithIndex(path.clone())),
    }
}

fn set_key<'i>(
    t: &mut DeTable<'i>,
    k: &str,
    rest: &[Segment],
    value: DeValue<'i>,
    span: Range<usize>,
    path: &KeyPath,
) -> Result<(), KeyPathError> {
    if let Some(x) = t.get_mut(k) {
        return set_in(x, rest, value, span, path);
    }
    // Missing from here on: build the chain of tables inside out.
    let mut v = respan(value, &span);
    for seg in rest.iter().rev() {
        let Segment::Key(k2) = seg else {
            return Err(KeyPathError::InsertElement(path.clone()));
        };
        let mut inner = DeTable::new();
        inner.insert(
            Spanned::new(span.clone(), k2.clone().into()),
            Spanned::new(span.clone(), v),
        );
        v = DeValue::Table(inner);
    }
    t.insert(
        Spanned::new(span.clone(), k.to_string().into()),
        Spanned::new(span, v),
    );
    Ok(())
}

/// `value` with its own span and every span inside it set to `span`: a value
/// parsed on its own has spans into its own text, not into the file's.
fn respan<'i>(value: DeValue<'i>, span: &Range<usize>) -> DeValue<'i> {
    match value {
        DeValue::Array(a) => DeValue::Array(
            a.into_iter()
                .map(|x| Spanned::new(span.clone(), respan(x.into_inner(), span)))
                .collect(),
        ),
        DeValue::Table(t) => DeValue::Table(
            t.into_iter()
                .map(|(k, x)| {
                    (
                        Spanned::new(span.clone(), k.into_inner()),
                        Spanned::new(span.clone(), respan(x.into_inner(), span)),
                    )
                })
                .collect(),
        ),
        other => other,
    }
}

/// The span of the key of the deepest table on `path` that the document
/// writes (so a key inserted there points at its table's line), or `0..0`.
pub(crate) fn anchor(root: &DeTable<'_>, path: &KeyPath) -> Range<usize> {
    let mut span = 0..0;
    let mut table = root;
    for seg in &path.0 {
        let Segment::Key(k) = seg else { break };
        match table.get_key_value(k.as_str()) {
            Some((key, v)) => {
                span = key.span();
                match v.get_ref() {
                    DeValue::Table(t) => table = t,
                    _ => break,
                }
            }
            None => break,
        }
    }
    span
}

fn set_in<'i>(
    v: &mut Spanned<DeValue<'i>>,
    rest: &[Segment],
    value: DeValue<'i>,
    span: Range<usize>,
    path: &KeyPath,
) -> Result<(), KeyPathError> {
    let Some((seg, rest)) = rest.split_first() else {
        // The written value's span: errors point at its line.
        let span = v.span();
        *v = Spanned::new(span.clone(), respan(value, &span));
        return Ok(());
    };
    match (v.get_mut(), seg) {
        (DeValue::Table(t), Segment::Key(k)) => set_key(t, k, rest, value, span, path),
        (DeValue::Array(a), Segment::Index(i)) => {
            let len = a.len();
            let x = a.get_mut(*i).ok_or_else(|| KeyPathError::PastEnd {
                path: path.clone(),
                index: *i,
                len,
            })?;
            set_in(x, rest, value, span, path)
        }
        _ => Err(KeyPathError::NotContainer(path.clone())),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_parse_and_print() {
        for s in [
            "sim.friction",
            "start[2]",
            "planner.via_deg[1][0]",
            "a-b.c_d",
        ] {
            assert_eq!(KeyPath::parse(s).unwrap().to_string(), s);
        }
        assert_eq!(
            KeyPath::parse("start[2]").unwrap().0,
            vec![Segment::Key("start".into()), Segment::Index(2)]
        );
        for bad in [
            "", ".a", "a.", "a..b", "[1]", "a[x]", "a[1", "a b", "a[-1]", "a]",
        ] {
            assert!(KeyPath::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn find_and_set() {
        let text = "start = [1.0, 2.0]\nname = \"x\"\n[sim]\ndt = 0.1\nn = 4\n[model]\nsw = { rate = 0.5 }\n";
        let root = DeTable::parse(text).unwrap().into_inner();
        let f = |p: &str| find(&root, &KeyPath::parse(p).unwrap());
        assert_eq!(f("sim.dt"), Found::Number { integer: false });
        assert_eq!(f("sim.n"), Found::Number { integer: true });
        assert_eq!(f("start[1]"), Found::Number { integer: false });
        assert_eq!(f("model.sw.rate"), Found::Number { integer: false });
        assert_eq!(f("name"), Found::NotNumber("string"));
        assert_eq!(f("start"), Found::NotNumber("array"));
        assert_eq!(f("sim.settle"), Found::Absent);
        assert_eq!(f("limits.ramp"), Found::Absent);
        assert!(matches!(f("start[2]"), Found::Unreachable(m) if m.contains("2 elements")));
        assert!(matches!(f("sim.dt.x"), Found::Unreachable(m) if m.contains("not a table")));
        assert!(
            matches!(f("limits.max_rate[0]"), Found::Unreachable(m) if m.contains("not written"))
        );

        let mut root = root;
        let v = |s: &'static str| DeValue::parse(s).unwrap().into_inner();
        let p = |s: &str| KeyPath::parse(s).unwrap();
        set(&mut root, &p("sim.dt"), v("0.25"), 90..91).unwrap();
        set(&mut root, &p("start[0]"), v("3"), 90..91).unwrap();
        set(&mut root, &p("limits.ramp"), v("0.5"), 90..91).unwrap();
        set(&mut root, &p("model.sw.rate"), v("2.5"), 90..91).unwrap();
        let sim = root.get("sim").unwrap().get_ref().as_table().unwrap();
        let dt = sim.get("dt").unwrap();
        assert_eq!(dt.get_ref().as_float().unwrap().as_str(), "0.25");
        assert_eq!(
            dt.span(),
            text.find("0.1").unwrap()..text.find("0.1").unwrap() + 3
        );
        let ramp = root.get("limits").unwrap().get_ref().as_table().unwrap();
        assert_eq!(ramp.get("ramp").unwrap().span(), 90..91);
        let start = root.get("start").unwrap().get_ref().as_array().unwrap();
        assert_eq!(start[0].get_ref().as_integer().unwrap().as_str(), "3");
    }

    #[test]
    fn numbers_round_trip_through_toml() {
        for x in [
            0.0,
            3.0,
            -2.0,
            0.1,
            1e-7,
            1e300,
            -1.5e-310,
            0.30000000000000004,
            9.5e15,
        ] {
            let s = toml_number(x);
            let v = DeValue::parse(&s).unwrap().into_inner();
            let back = match &v {
                DeValue::Integer(i) => i.as_str().parse::<i64>().unwrap() as f64,
                DeValue::Float(f) => f.as_str().parse::<f64>().unwrap(),
                _ => panic!("{s}"),
            };
            assert_eq!(back.to_bits(), x.to_bits(), "{x} as {s}");
        }
    }
}
