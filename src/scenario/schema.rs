//! The scenario file's keys as data: JSON schemas derived (`schemars`) from
//! the structs the parser fills, carrying their doc comments, their serde
//! defaults and their documented ranges (`#[schemars(range(..))]`,
//! `extend("exclusiveMinimum" = ..)`).
//!
//! Both the validation pass ([`Schema::check`], run by
//! [`crate::scenario::Scenario::parse`] on every table) and the reference pages
//! (`anholonomy keys`, [`Schema::rows`]) read the same schema, so a range
//! cannot be documented without being enforced, nor enforced here without
//! being documented.
//!
//! Convention: a bound on an array or on a table of numbers (`ka`,
//! `thresholds`) applies to each of its numbers.

use crate::error::SetupError;
use schemars::JsonSchema;
use serde_json::{Map, Value};
use std::sync::OnceLock;

/// A root schema (with its `$defs`).
#[derive(Debug, Clone)]
pub struct Schema {
    root: Value,
}

/// One documented key.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Dotted key path (`planner.speed`, `model.obstacles[].name`).
    pub key: String,
    /// Default as written in TOML, `required`, or `none` (unset).
    pub default: String,
    /// Type and allowed range (`number > 0`, `"shortest", "left" or "right"`).
    pub allowed: String,
    /// The doc comment (one paragraph per line joined with spaces).
    pub doc: String,
}

/// Numeric bounds of one schema node.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Bounds {
    min: Option<f64>,
    excl_min: Option<f64>,
    max: Option<f64>,
    excl_max: Option<f64>,
}

impl Bounds {
    fn of(node: &Value) -> Bounds {
        let f = |k: &str| node.get(k).and_then(Value::as_f64);
        let mut b = Bounds {
            min: f("minimum"),
            excl_min: f("exclusiveMinimum"),
            max: f("maximum"),
            excl_max: f("exclusiveMaximum"),
        };
        // schemars adds `minimum: 0` to unsigned integers: that is the type, not a range.
        if b.min == Some(0.0) && is_unsigned(node) {
            b.min = None;
        }
        b
    }

    fn is_empty(&self) -> bool {
        *self == Bounds::default()
    }

    fn admits(&self, x: f64) -> bool {
        self.min.is_none_or(|m| x >= m)
            && self.excl_min.is_none_or(|m| x > m)
            && self.max.is_none_or(|m| x <= m)
            && self.excl_max.is_none_or(|m| x < m)
    }

    /// `> 0`, `≥ 1`, `in (0, 0.1]`.
    fn text(&self) -> String {
        let lo = self
            .excl_min
            .map(|m| ('(', m))
            .or(self.min.map(|m| ('[', m)));
        let hi = self
            .excl_max
            .map(|m| (')', m))
            .or(self.max.map(|m| (']', m)));
        match (lo, hi) {
            (Some((a, x)), Some((b, y))) => format!("in {a}{}, {}{b}", num(x), num(y)),
            (Some(('(', x)), None) => format!("> {}", num(x)),
            (Some((_, x)), None) => format!("≥ {}", num(x)),
            (None, Some((')', y))) => format!("< {}", num(y)),
            (None, Some((_, y))) => format!("≤ {}", num(y)),
            (None, None) => String::new(),
        }
    }
}

fn is_unsigned(node: &Value) -> bool {
    node.get("format")
        .and_then(Value::as_str)
        .is_some_and(|f| f.starts_with("uint"))
}

/// A number as a user writes it (`0.1`, `1000000`, `1e-9`).
/// A bound or a value in a message: whole numbers as integers, the rest in
/// the shortest form that reads back (`1e300`, not 301 digits).
fn num(x: f64) -> String {
    if x == x.trunc() && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        crate::numfmt::shortest(x)
    }
}

fn types(node: &Value) -> Vec<&str> {
    match node.get("type") {
        Some(Value::String(s)) => vec![s.as_str()],
        Some(Value::Array(a)) => a.iter().filter_map(Value::as_str).collect(),
        _ => Vec::new(),
    }
}

fn branches(node: &Value) -> &[Value] {
    node.get("anyOf")
        .or_else(|| node.get("oneOf"))
        .and_then(Value::as_array)
        .map(Vec::as_slice)
        .unwrap_or(&[])
}

/// `kind` of a tagged-enum branch (`{"properties": {"kind": {"const": ..}}}`).
fn tag(branch: &Value) -> Option<&str> {
    branch
        .get("properties")?
        .get("kind")?
        .get("const")?
        .as_str()
}

/// The schema of `kind` among `kinds`, each built once (`of` maps a kind to
/// its schema): the lookup behind `ModelConfig::schema` and
/// `PlannerConfig::schema`.
pub(crate) fn by_kind(
    cache: &'static OnceLock<Vec<(&'static str, Schema)>>,
    kinds: &'static [&'static str],
    kind: &str,
    of: fn(&str) -> Option<Schema>,
) -> Option<&'static Schema> {
    cache
        .get_or_init(|| kinds.iter().filter_map(|k| Some((*k, of(k)?))).collect())
        .iter()
        .find(|(k, _)| *k == kind)
        .map(|(_, s)| s)
}

impl Schema {
    /// The schema of `T`.
    pub fn of<T: JsonSchema>() -> Schema {
        Schema {
            root: schemars::SchemaGenerator::default()
                .into_root_schema_for::<T>()
                .to_value(),
        }
    }

    /// `self` with the properties (and definitions) of `other` added: keys
    /// every table of a kind shares (a model's URDF source).
    pub fn with_properties_of(mut self, other: &Schema) -> Schema {
        for part in ["properties", "$defs"] {
            let Some(add) = other.root.get(part).and_then(Value::as_object).cloned() else {
                continue;
            };
            if let Some(root) = self.root.as_object_mut() {
                let entry = root
                    .entry(part)
                    .or_insert_with(|| Value::Object(Map::new()));
                if let Some(m) = entry.as_object_mut() {
                    m.extend(add);
                }
            }
        }
        self
    }

    /// The type's own doc comment.
    pub fn description(&self) -> String {
        doc(&self.root)
    }

    /// A node with its `$ref` followed (once: the definitions are not nested refs).
    fn resolve<'a>(&'a self, node: &'a Value) -> &'a Value {
        let Some(r) = node.get("$ref").and_then(Value::as_str) else {
            return node;
        };
        r.strip_prefix("#/$defs/")
            .and_then(|name| self.root.get("$defs")?.get(name))
            .unwrap_or(node)
    }

    /// Check every number of `value` (the table as parsed, serialized) against
    /// its documented range; the message names the key under `prefix`.
    pub fn check(&self, value: &Value, prefix: &str) -> Result<(), SetupError> {
        self.check_node(&self.root, value, prefix)
    }

    fn check_node(&self, node: &Value, value: &Value, path: &str) -> Result<(), SetupError> {
        // Bounds written on a `$ref` property sit beside the reference.
        let outer = Bounds::of(node);
        let node = self.resolve(node);
        for b in [outer, Bounds::of(node)] {
            check_bounds(&b, value, path)?;
        }
        if let Some(branch) = self.branch_for(node, value) {
            return self.check_node(branch, value, path);
        }
        match value {
            Value::Array(items) => {
                let each = node.get("items").filter(|i| i.is_object());
                let prefix_items = node.get("prefixItems").and_then(Value::as_array);
                for (i, v) in items.iter().enumerate() {
                    let item = prefix_items.and_then(|p| p.get(i)).or(each);
                    if let Some(item) = item {
                        self.check_node(item, v, &format!("{path}[{i}]"))?;
                    }
                }
            }
            Value::Object(m) => {
                let props = node.get("properties").and_then(Value::as_object);
                let extra = node.get("additionalProperties").filter(|a| a.is_object());
                for (k, v) in m {
                    let sub = props.and_then(|p| p.get(k)).or(extra);
                    if let Some(sub) = sub {
                        self.check_node(sub, v, &join(path, k))?;
                    }
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The branch of an `anyOf`/`oneOf` that describes `value`.
    fn branch_for<'a>(&'a self, node: &'a Value, value: &Value) -> Option<&'a Value> {
        let bs = branches(node);
        if bs.is_empty() {
            return None;
        }
        let kind = value.get("kind").and_then(Value::as_str);
        bs.iter().find(|b| {
            let r = self.resolve(b);
            if let (Some(k), Some(t)) = (kind, tag(r)) {
                return k == t;
            }
            let ts = types(r);
            match value {
                Value::Null => ts.contains(&"null"),
                Value::Number(_) => ts.contains(&"number") || ts.contains(&"integer"),
                Value::Array(_) => ts.contains(&"array"),
                Value::Object(_) => ts.contains(&"object") && tag(r).is_none(),
                Value::String(_) => ts.contains(&"string"),
                Value::Bool(_) => ts.contains(&"boolean"),
            }
        })
    }

    /// Every documented key under `prefix`, sorted by key within each table.
    pub fn rows(&self, prefix: &str) -> Vec<Row> {
        let mut out = Vec::new();
        self.rows_of_object(&self.root, prefix, None, "", &mut out);
        out
    }

    fn rows_of_object(
        &self,
        node: &Value,
        path: &str,
        default: Option<&Value>,
        note: &str,
        out: &mut Vec<Row>,
    ) {
        let node = self.resolve(node);
        let Some(props) = node.get("properties").and_then(Value::as_object) else {
            return;
        };
        let required: Vec<&str> = node
            .get("required")
            .and_then(Value::as_array)
            .map(|r| r.iter().filter_map(Value::as_str).collect())
            .unwrap_or_default();
        for (k, p) in props {
            if k == "kind" && tag(node).is_some() {
                continue;
            }
            let d = p.get("default").or_else(|| default.and_then(|d| d.get(k)));
            self.rows_of(
                p,
                &join(path, k),
                d,
                required.contains(&k.as_str()),
                note,
                out,
            );
        }
    }

    fn rows_of(
        &self,
        node: &Value,
        path: &str,
        default: Option<&Value>,
        required: bool,
        note: &str,
        out: &mut Vec<Row>,
    ) {
        let target = self.resolve(node);
        let own_doc = doc(node);
        let doc_text = if own_doc.is_empty() {
            doc(target)
        } else {
            own_doc
        };
        let doc_text = format!("{note}{doc_text}");
        // Option<T>: the non-null branch, unset by default.
        let non_null: Vec<&Value> = branches(target)
            .iter()
            .filter(|b| !types(b).eq(&["null"]))
            .collect();
        let optional = branches(target).len() == 2 && non_null.len() == 1;
        let inner = if optional {
            self.resolve(non_null[0])
        } else {
            target
        };
        let default_text = || match default {
            Some(v) => toml_value(v),
            None if required => "required".into(),
            None => "none".into(),
        };
        // A nested table (struct): its keys, each with its own row.
        if inner.get("properties").is_some() && tag(inner).is_none() {
            let table = if optional {
                format!("{note}Optional table `[{path}]`. ")
            } else {
                note.to_string()
            };
            self.rows_of_object(inner, path, default.filter(|d| d.is_object()), &table, out);
            return;
        }
        let bs = branches(inner);
        // A tagged enum: `kind` and each variant's keys.
        if !bs.is_empty() && bs.iter().all(|b| tag(self.resolve(b)).is_some()) {
            let kinds: Vec<String> = bs
                .iter()
                .map(|b| format!("\"{}\"", tag(self.resolve(b)).unwrap_or_default()))
                .collect();
            let variants: Vec<String> = bs
                .iter()
                .map(|b| {
                    let r = self.resolve(b);
                    format!(
                        "`{}`: {}",
                        tag(r).unwrap_or_default(),
                        doc(r).trim_end_matches('.')
                    )
                })
                .collect();
            out.push(Row {
                key: format!("{path}.kind"),
                default: default
                    .and_then(|d| d.get("kind"))
                    .map(toml_value)
                    .unwrap_or_else(default_text),
                allowed: one_of(&kinds),
                doc: format!("{doc_text} {}.", variants.join("; ")),
            });
            for b in bs {
                let r = self.resolve(b);
                let k = tag(r).unwrap_or_default();
                let d = default.filter(|d| d.get("kind").and_then(Value::as_str) == Some(k));
                let sub_note = format!("{note}With `kind = \"{k}\"`: ");
                self.rows_of_object(r, path, d, &sub_note, out);
            }
            return;
        }
        // An array of tables (`[[model.obstacles]]`).
        if let Some(items) = inner.get("items").filter(|_| types(inner) == ["array"]) {
            let item = self.resolve(items);
            if item.get("properties").is_some() {
                let n = format!("{note}Each `[[{path}]]`: ");
                self.rows_of_object(item, &format!("{path}[]"), None, &n, out);
                return;
            }
        }
        // A table of named entries (`[thresholds]`, `[sweep.vary]`).
        if let Some(value) = inner
            .get("additionalProperties")
            .filter(|a| a.is_object() && types(inner) == ["object"])
        {
            let key = format!("{path}.<name>");
            let v = self.resolve(value);
            if v.get("properties").is_some() {
                self.rows_of_object(v, &key, None, &format!("{doc_text} "), out);
            } else {
                out.push(Row {
                    key,
                    default: "none".into(),
                    allowed: self.allowed(inner, v),
                    doc: doc_text,
                });
            }
            return;
        }
        // String enums: each value's doc.
        let values: Vec<String> = branches(inner)
            .iter()
            .map(|b| self.resolve(b))
            .filter_map(|b| {
                let c = b.get("const")?.as_str()?;
                let d = doc(b);
                (!d.is_empty()).then(|| format!("`{c}`: {}", d.trim_end_matches('.')))
            })
            .collect();
        let doc_text = if values.is_empty() {
            doc_text
        } else {
            format!("{doc_text} {}.", values.join("; "))
        };
        out.push(Row {
            key: path.to_string(),
            default: default_text(),
            allowed: self.allowed(node, inner),
            doc: doc_text,
        });
    }

    /// Type and range of a leaf.
    fn allowed(&self, outer: &Value, node: &Value) -> String {
        let bounds = {
            let (a, b) = (Bounds::of(outer), Bounds::of(node));
            if a.is_empty() {
                b
            } else {
                a
            }
        };
        let range = bounds.text();
        let with = |t: String| {
            if range.is_empty() {
                t
            } else {
                format!("{t} {range}")
            }
        };
        let bs = branches(node);
        if !bs.is_empty() {
            // A string enum, or an externally tagged one (`{ uniform = [lo, hi] }`).
            let alts: Vec<String> = bs
                .iter()
                .map(|b| {
                    let r = self.resolve(b);
                    if let Some(c) = r
                        .get("const")
                        .or_else(|| r.get("enum").and_then(|e| e.get(0)))
                    {
                        toml_value(c)
                    } else if let Some(p) = r.get("properties").and_then(Value::as_object) {
                        let k = p.keys().next().cloned().unwrap_or_default();
                        format!("{{ {k} = … }}")
                    } else {
                        types(r).join(" or ")
                    }
                })
                .collect();
            return one_of(&alts);
        }
        if let Some(e) = node.get("enum").and_then(Value::as_array) {
            let alts: Vec<String> = e.iter().map(toml_value).collect();
            return one_of(&alts);
        }
        let ts: Vec<&str> = types(node).into_iter().filter(|t| *t != "null").collect();
        match ts.first().copied() {
            Some("number") => with("number".into()),
            Some("integer") => with("integer".into()),
            Some("boolean") => "true or false".into(),
            Some("string") => "string".into(),
            Some("array") => {
                let n = node.get("minItems").and_then(Value::as_u64);
                let fixed = n.is_some() && n == node.get("maxItems").and_then(Value::as_u64);
                let item = node
                    .get("items")
                    .map(|i| self.resolve(i))
                    .map(|i| match types(i).first().copied() {
                        Some("number") | Some("integer") => "numbers",
                        Some("array") => "lists",
                        Some("string") => "strings",
                        _ => "values",
                    })
                    .unwrap_or("values");
                let each = if range.is_empty() {
                    String::new()
                } else {
                    format!(", each {range}")
                };
                match (fixed, n) {
                    (true, Some(n)) => format!("{n} {item}{each}"),
                    _ => format!("list of {item}{each}"),
                }
            }
            Some("object") => {
                let each = if range.is_empty() {
                    String::new()
                } else {
                    format!(", each {range}")
                };
                format!("table{each}")
            }
            _ => String::new(),
        }
    }
}

fn check_bounds(b: &Bounds, value: &Value, path: &str) -> Result<(), SetupError> {
    if b.is_empty() {
        return Ok(());
    }
    let bad = |key: &str, x: f64| {
        Err(SetupError::key(
            key,
            format!("must be {}, got {}", b.text(), num(x)),
        ))
    };
    match value {
        Value::Number(n) => match n.as_f64() {
            Some(x) if !b.admits(x) => bad(path, x),
            _ => Ok(()),
        },
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                if let Some(x) = v.as_f64().filter(|x| !b.admits(*x)) {
                    return bad(&format!("{path}[{i}]"), x);
                }
            }
            Ok(())
        }
        Value::Object(m) => {
            for (k, v) in m {
                if let Some(x) = v.as_f64().filter(|x| !b.admits(*x)) {
                    return bad(&join(path, k), x);
                }
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}

fn one_of(alts: &[String]) -> String {
    match alts {
        [] => String::new(),
        [a] => a.clone(),
        [init @ .., last] => format!("{} or {last}", init.join(", ")),
    }
}

/// A doc comment on one line, without rustdoc link brackets.
fn doc(node: &Value) -> String {
    let d = node
        .get("description")
        .and_then(Value::as_str)
        .unwrap_or("");
    let mut s = d.split_whitespace().collect::<Vec<_>>().join(" ");
    // [`Name`] and [`Name`](path) are rustdoc links: keep the code span.
    while let Some(i) = s.find("[`") {
        let Some(j) = s[i..].find("`]").map(|j| i + j) else {
            break;
        };
        let code = s[i + 1..j + 1].to_string();
        let mut end = j + 2;
        if s[end..].starts_with('(') {
            if let Some(k) = s[end..].find(')') {
                end += k + 1;
            }
        }
        s.replace_range(i..end, &code);
    }
    s
}

/// A JSON value written as TOML (`0.1`, `"shortest"`, `[1, 2]`, `{ kind = "a" }`).
pub(crate) fn toml_value(v: &Value) -> String {
    match v {
        Value::Null => "none".into(),
        Value::Bool(b) => b.to_string(),
        Value::Number(n) => match n.as_f64() {
            Some(x) if n.is_f64() => {
                let s = format!("{x}");
                if s.contains(['.', 'e', 'i', 'N']) {
                    s
                } else {
                    format!("{s}.0")
                }
            }
            _ => n.to_string(),
        },
        Value::String(s) => format!("\"{s}\""),
        Value::Array(a) => format!(
            "[{}]",
            a.iter().map(toml_value).collect::<Vec<_>>().join(", ")
        ),
        Value::Object(m) => inline_table(m),
    }
}

fn inline_table(m: &Map<String, Value>) -> String {
    if m.is_empty() {
        return "{}".into();
    }
    let parts: Vec<String> = m
        .iter()
        .map(|(k, v)| format!("{k} = {}", toml_value(v)))
        .collect();
    format!("{{ {} }}", parts.join(", "))
}

#[cfg(test)]
mod tests {
    use super::*;
    use schemars::JsonSchema;
    use serde::{Deserialize, Serialize};

    /// Which way.
    #[derive(Debug, Clone, Copy, Deserialize, Serialize, JsonSchema)]
    #[serde(rename_all = "lowercase")]
    enum Turn {
        /// The short way.
        Short,
        /// Left.
        Left,
    }

    /// A signal.
    #[derive(Debug, Clone, Copy, Deserialize, Serialize, JsonSchema)]
    #[serde(tag = "kind", rename_all = "snake_case")]
    enum Signal {
        /// Constant.
        Fixed,
        /// Random.
        Telegraph {
            /// Seed.
            seed: u64,
            /// Rate, 1/s.
            #[schemars(range(min = 0))]
            rate: f64,
        },
    }

    /// Inner table.
    #[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
    #[serde(default)]
    struct Inner {
        /// Length, m.
        #[schemars(extend("exclusiveMinimum" = 0))]
        l: f64,
    }
    impl Default for Inner {
        fn default() -> Self {
            Inner { l: 0.25 }
        }
    }

    /// Outer.
    #[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
    struct Outer {
        /// Step, s.
        #[schemars(range(max = 0.1), extend("exclusiveMinimum" = 0))]
        dt: f64,
        /// Count.
        #[schemars(range(min = 1, max = 64))]
        n: usize,
        /// Gains.
        #[schemars(extend("exclusiveMinimum" = 0))]
        ka: [f64; 3],
        /// Maybe.
        #[schemars(extend("exclusiveMinimum" = 0, "exclusiveMaximum" = 360))]
        b: Option<f64>,
        #[serde(default)]
        /// Inner.
        inner: Inner,
        /// Optional inner.
        opt: Option<Inner>,
        /// Turn.
        turn: Turn,
        /// Signal.
        signal: Signal,
        /// Items.
        items: Vec<Inner>,
    }

    fn sample() -> Value {
        serde_json::json!({
            "dt": 0.01, "n": 3, "ka": [1.0, 2.0, 3.0], "b": 10.0,
            "inner": {"l": 1.0}, "opt": {"l": 2.0}, "turn": "left",
            "signal": {"kind": "telegraph", "seed": 1, "rate": 0.5},
            "items": [{"l": 1.0}, {"l": 2.0}]
        })
    }

    #[test]
    fn every_documented_bound_is_checked() {
        let s = Schema::of::<Outer>();
        s.check(&sample(), "planner").unwrap();
        for (ptr, bad, key, want) in [
            ("/dt", 0.0, "planner.dt", "in (0, 0.1]"),
            ("/dt", 0.2, "planner.dt", "in (0, 0.1]"),
            ("/n", 65.0, "planner.n", "in [1, 64]"),
            ("/ka/1", -1.0, "planner.ka[1]", "> 0"),
            ("/b", 360.0, "planner.b", "in (0, 360)"),
            ("/inner/l", 0.0, "planner.inner.l", "> 0"),
            ("/opt/l", -2.0, "planner.opt.l", "> 0"),
            ("/signal/rate", -1.0, "planner.signal.rate", "≥ 0"),
            ("/items/1/l", 0.0, "planner.items[1].l", "> 0"),
        ] {
            let mut v = sample();
            *v.pointer_mut(ptr).unwrap() = serde_json::json!(bad);
            let e = s.check(&v, "planner").unwrap_err().to_string();
            assert!(
                e.starts_with(&format!("key `{key}`: must be {want}")),
                "{ptr}: {e}"
            );
        }
        let mut v = sample();
        v["b"] = Value::Null;
        v["opt"] = Value::Null;
        s.check(&v, "planner").unwrap();
    }

    #[test]
    fn rows_show_defaults_ranges_and_docs() {
        let rows = Schema::of::<Outer>().rows("model");
        let row = |k: &str| {
            rows.iter()
                .find(|r| r.key == k)
                .unwrap_or_else(|| panic!("{k}: {rows:?}"))
        };
        assert_eq!(row("model.dt").allowed, "number in (0, 0.1]");
        assert_eq!(row("model.dt").default, "required");
        assert_eq!(row("model.n").allowed, "integer in [1, 64]");
        assert_eq!(row("model.ka").allowed, "3 numbers, each > 0");
        assert_eq!(row("model.b").default, "none");
        assert_eq!(row("model.b").allowed, "number in (0, 360)");
        assert_eq!(row("model.inner.l").default, "0.25");
        assert!(row("model.opt.l")
            .doc
            .contains("Optional table `[model.opt]`"));
        assert_eq!(row("model.turn").allowed, "\"short\" or \"left\"");
        assert_eq!(
            row("model.signal.kind").allowed,
            "\"fixed\" or \"telegraph\""
        );
        assert!(row("model.signal.rate")
            .doc
            .starts_with("With `kind = \"telegraph\"`"));
        assert_eq!(row("model.signal.rate").allowed, "number ≥ 0");
        assert_eq!(row("model.items[].l").allowed, "number > 0");
    }
}
