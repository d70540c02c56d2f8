//! Reference pages of the scenario file (`anholonomy keys`): every key of
//! every model, planner and common table, with its default, type and range,
//! and doc comment, generated from the schemas the validation pass checks
//! every scenario against ([`crate::scenario::schema`]). The pages under
//! `docs/src/reference/` are this module's output; a test fails when they
//! differ from it.

use crate::scenario::schema::{Row, Schema};
use crate::scenario::{file_schema, model_system, planners_for, ModelConfig, PlannerConfig};
use std::fmt::Write as _;
use std::path::PathBuf;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

/// The command that regenerates the committed pages (it writes only the
/// pages of [`Page::all`]: `keys.md`, `scenario-keys.md`, `models/`, `planners/`).
pub const REGENERATE: &str = "anholonomy keys --markdown --out docs/src/reference";

/// Why a reference page cannot be made: every case is a kind whose
/// declarations in the code are incomplete (the message says where to add
/// what), never a problem of the user's input.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    /// A page's kind has no schema.
    #[error("{page}: no schema (add the kind to `schema()` in src/scenario/config.rs)")]
    NoSchema {
        /// The page's title (``Model `car` ``).
        page: String,
    },
    /// A model kind has no schema (for its placeholder table).
    #[error("model `{0}`: no schema")]
    NoModelSchema(String),
    /// A required key of a model has a type no placeholder is made for.
    #[error("model `{kind}`: cannot make a placeholder for required key `{key}`")]
    Placeholder {
        /// The model kind.
        kind: String,
        /// The required key.
        key: String,
    },
    /// A placeholder table is not TOML, or its model or planner refuses it.
    #[error(transparent)]
    Toml(#[from] toml::de::Error),
    /// The model kind is not one.
    #[error("unknown model `{0}`")]
    UnknownModel(String),
    /// The `file` planner is missing.
    #[error("unknown planner `file`")]
    NoFilePlanner,
    /// The model cannot be built from its placeholders.
    #[error(transparent)]
    Setup(#[from] crate::error::SetupError),
    /// A model kind has no URDF declaration.
    #[error(
        "model `{0}`: no URDF declaration (add it to `required_urdf()` in src/scenario/config.rs)"
    )]
    NoUrdf(String),
}

/// One reference page.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Page {
    /// The index of the pages.
    Index,
    /// The file's own keys: top level, `[limits]`, `[sim]`, `[sweep]`, ...
    Scenario,
    /// A `[model]` kind.
    Model(&'static str),
    /// A `[planner]` kind.
    Planner(&'static str),
}

impl Page {
    /// Every page: the index, the scenario file, each model, each planner.
    pub fn all() -> Vec<Page> {
        let mut out = vec![Page::Index, Page::Scenario];
        out.extend(ModelConfig::KINDS.iter().map(|k| Page::Model(k)));
        out.extend(PlannerConfig::KINDS.iter().map(|k| Page::Planner(k)));
        out
    }

    /// The page of `name`: a model or planner kind, or `scenario`.
    pub fn find(name: &str) -> Option<Page> {
        Page::all().into_iter().find(|p| match p {
            Page::Index => false,
            Page::Scenario => name == "scenario",
            Page::Model(k) | Page::Planner(k) => *k == name,
        })
    }

    /// Its file under `docs/src/reference/`.
    pub fn file(&self) -> PathBuf {
        match self {
            Page::Index => "keys.md".into(),
            Page::Scenario => "scenario-keys.md".into(),
            Page::Model(k) => format!("models/{k}.md").into(),
            Page::Planner(k) => format!("planners/{k}.md").into(),
        }
    }

    fn title(&self) -> String {
        match self {
            Page::Index => "Keys of every table".into(),
            Page::Scenario => "Scenario file keys".into(),
            Page::Model(k) => format!("Model `{k}`"),
            Page::Planner(k) => format!("Planner `{k}`"),
        }
    }

    fn schema(&self) -> Option<&'static Schema> {
        match self {
            Page::Index => None,
            Page::Scenario => Some(file_schema()),
            Page::Model(k) => ModelConfig::schema(k),
            Page::Planner(k) => PlannerConfig::schema(k),
        }
    }

    /// The rows of its keys (`model.*`, `planner.*`, or the file's own).
    pub fn rows(&self) -> Result<Vec<Row>, ReferenceError> {
        let missing = || ReferenceError::NoSchema { page: self.title() };
        Ok(match self {
            Page::Index => Vec::new(),
            Page::Scenario => {
                let mut rows = file_schema().rows("");
                let kinds = |ks: &[&str], dir: &str| -> String {
                    ks.iter()
                        .map(|k| format!("[`{k}`]({dir}/{k}.md)"))
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                rows.push(Row {
                    key: "model.kind".into(),
                    default: "required".into(),
                    allowed: "a model kind".into(),
                    doc: format!(
                        "The kinematic model and its rigid-body counterpart: {}. The other keys of `[model]` are on the model's page.",
                        kinds(ModelConfig::KINDS, "models")
                    ),
                });
                rows.push(Row {
                    key: "planner.kind".into(),
                    default: "required".into(),
                    allowed: "a planner kind for the model".into(),
                    doc: format!(
                        "The planner: {}. The other keys of `[planner]` are on the planner's page.",
                        kinds(PlannerConfig::KINDS, "planners")
                    ),
                });
                rows.sort_by(|a, b| section(&a.key).cmp(section(&b.key)));
                rows
            }
            Page::Model(k) => ModelConfig::schema(k).ok_or_else(missing)?.rows("model"),
            Page::Planner(k) => PlannerConfig::schema(k)
                .ok_or_else(missing)?
                .rows("planner"),
        })
    }

    /// The page as Markdown (mdBook).
    pub fn markdown(&self) -> Result<String, ReferenceError> {
        let mut b = String::new();
        let _ = writeln!(b, "# {}\n", self.title());
        let _ = writeln!(
            b,
            "<!-- Generated by `{REGENERATE}` from the schemas the validation pass checks scenarios against: do not edit. -->\n"
        );
        if *self == Page::Index {
            index(&mut b);
            return Ok(b);
        }
        if let Some(s) = self.schema() {
            let d = s.description();
            if !d.is_empty() {
                let _ = writeln!(b, "{d}\n");
            }
        }
        let _ = writeln!(
            b,
            "Every range below is checked when a scenario is read (`run`, `check`, `plan`, `list`): a value outside it is refused with the file, line and key. Print this page with `anholonomy keys {}`.\n",
            match self {
                Page::Model(k) | Page::Planner(k) => *k,
                _ => "scenario",
            }
        );
        match self {
            Page::Model(k) => model_intro(&mut b, k)?,
            Page::Planner(k) => {
                let models: Vec<String> = ModelConfig::KINDS
                    .iter()
                    .filter(|m| planners_for(m).contains(k))
                    .map(|m| format!("[`{m}`](../models/{m}.md)"))
                    .collect();
                if models.len() == ModelConfig::KINDS.len() {
                    let _ = writeln!(b, "Plans for every model: {}.\n", models.join(", "));
                } else {
                    let _ = writeln!(b, "Plans for the model {}.\n", models.join(", "));
                }
                let _ = writeln!(b, "## `[planner]` keys\n\n`kind = \"{k}\"` and:\n");
            }
            _ => {}
        }
        let rows = self.rows()?;
        if *self == Page::Scenario {
            let mut start = 0;
            while start < rows.len() {
                let s = section(&rows[start].key);
                let end = start
                    + rows[start..]
                        .iter()
                        .take_while(|r| section(&r.key) == s)
                        .count();
                let _ = writeln!(
                    b,
                    "## {}\n",
                    if s.is_empty() {
                        "Top-level keys".to_string()
                    } else {
                        format!("`[{s}]`")
                    }
                );
                table(&mut b, &rows[start..end]);
                start = end;
            }
        } else if rows.is_empty() {
            b.push_str("No keys besides `kind` and `urdf`.\n");
        } else {
            table(&mut b, &rows);
        }
        Ok(b)
    }

    /// The page as plain text for a terminal.
    pub fn text(&self) -> Result<String, ReferenceError> {
        let mut b = String::new();
        let _ = writeln!(b, "{}", self.title().replace('`', ""));
        if let Some(d) = self.schema().map(Schema::description) {
            let _ = writeln!(b, "{d}");
        }
        if *self == Page::Model(DECLARED) {
            let _ = writeln!(
                b,
                "start/goal: model.states as declared (model.angles in degrees)"
            );
            let _ = writeln!(b, "inputs: model.inputs as declared");
        } else if let Page::Model(k) = self {
            let (states, inputs) = states_of(k)?;
            let s: Vec<String> = states
                .iter()
                .map(|(n, u)| {
                    if u.is_empty() {
                        n.clone()
                    } else {
                        format!("{n} [{u}]")
                    }
                })
                .collect();
            let _ = writeln!(b, "start/goal: ({})", s.join(", "));
            let _ = writeln!(b, "inputs: {}", inputs.join(", "));
        }
        let rows = self.rows()?;
        let w = rows
            .iter()
            .map(|r| r.key.chars().count())
            .max()
            .unwrap_or(0);
        let wd = rows
            .iter()
            .map(|r| r.default.chars().count())
            .max()
            .unwrap_or(0)
            .min(24);
        b.push('\n');
        for r in &rows {
            let _ = writeln!(b, "{:<w$}  {:<wd$}  {}", r.key, r.default, r.allowed);
            let _ = writeln!(b, "    {}", r.doc);
        }
        Ok(b)
    }
}

/// The table a scenario-page row belongs to (`sim`, `sweep`, ...; "" for top-level keys).
fn section(key: &str) -> &str {
    match key.split_once('.') {
        Some((s, _)) => s,
        None => "",
    }
}

fn cell(s: &str) -> String {
    s.replace('|', "\\|")
}

fn table(b: &mut String, rows: &[Row]) {
    b.push_str("| key | default | type and range | description |\n|---|---|---|---|\n");
    for r in rows {
        let _ = writeln!(
            b,
            "| `{}` | {} | {} | {} |",
            r.key,
            if r.default == "required" || r.default == "none" {
                r.default.clone()
            } else {
                format!("`{}`", cell(&r.default))
            },
            cell(&r.allowed),
            cell(&r.doc)
        );
    }
    b.push('\n');
}

fn index(b: &mut String) {
    b.push_str("Every key a scenario file can hold, with its default, type and range, generated from the definitions the validation pass checks scenarios against (`anholonomy keys NAME` prints a page in the terminal).\n\n");
    let _ = writeln!(
        b,
        "- [Scenario file keys](scenario-keys.md): the top-level keys, `[limits]`, `[sim]`, `[thresholds]`, `[minimums]`, `[sweep]`, `[regression]`."
    );
    b.push_str("\n## Models\n\n");
    for k in ModelConfig::KINDS {
        let d = ModelConfig::schema(k)
            .map(Schema::description)
            .unwrap_or_default();
        let _ = writeln!(b, "- [`{k}`](models/{k}.md): {d}");
    }
    b.push_str("\n## Planners\n\n");
    for k in PlannerConfig::KINDS {
        let d = PlannerConfig::schema(k)
            .map(Schema::description)
            .unwrap_or_default();
        let _ = writeln!(b, "- [`{k}`](planners/{k}.md): {d}");
    }
}

/// The model whose states, inputs and URDF names are the scenario's own.
const DECLARED: &str = "declared";

/// A `[model]` table of `kind` with only its required keys (placeholders), as TOML.
fn minimal_table(kind: &str) -> Result<String, ReferenceError> {
    let s = ModelConfig::schema(kind).ok_or_else(|| ReferenceError::NoModelSchema(kind.into()))?;
    let mut t = String::new();
    for r in s.rows("") {
        if r.default != "required" || r.key.contains(['.', '[']) {
            continue;
        }
        let v = if r.key == "urdf" {
            "\"robot.urdf\"".to_string()
        } else if r.allowed.starts_with("integer") {
            "1".into()
        } else if r.allowed.starts_with("number") {
            "1.0".into()
        } else if r.allowed.starts_with("true") {
            "false".into()
        } else {
            return Err(ReferenceError::Placeholder {
                kind: kind.into(),
                key: r.key,
            });
        };
        let _ = writeln!(t, "{} = {v}", r.key);
    }
    Ok(t)
}

/// A TOML document as the table value the config parsers take.
fn toml_table(text: &str) -> Result<Spanned<DeValue<'_>>, ReferenceError> {
    let t = DeTable::parse(text)?.into_inner();
    Ok(Spanned::new(0..0, DeValue::Table(t)))
}

/// The file coordinates of `start`/`goal` (name, unit) and the input names of a model.
#[allow(clippy::type_complexity)]
pub(crate) fn states_of(
    kind: &str,
) -> Result<(Vec<(String, String)>, Vec<String>), ReferenceError> {
    let text = minimal_table(kind)?;
    let model = ModelConfig::parse(kind, toml_table(&text)?)?
        .ok_or_else(|| ReferenceError::UnknownModel(kind.into()))?;
    // A plan from outside fits every model, and leaves its states and
    // inputs as they are (a model's own planners are built at defaults).
    let planner = PlannerConfig::parse("file", toml_table("path = \"plan.csv\"")?)?
        .ok_or(ReferenceError::NoFilePlanner)?;
    let system = model_system(&model, &planner)?;
    let chart = system.file_model();
    let angular = chart.angular_states();
    let position = chart.position_states();
    let states = chart
        .state_names()
        .iter()
        .enumerate()
        .map(|(i, n)| {
            let unit = if angular.contains(&i) {
                "deg"
            } else if position.is_some_and(|p| p.contains(&i)) {
                "m"
            } else {
                ""
            };
            (n.to_string(), unit.to_string())
        })
        .collect();
    let inputs = system
        .model()
        .input_names()
        .iter()
        .map(|s| s.to_string())
        .collect();
    Ok((states, inputs))
}

fn model_intro(b: &mut String, kind: &str) -> Result<(), ReferenceError> {
    let planners: Vec<String> = planners_for(kind)
        .iter()
        .map(|p| format!("[`{p}`](../planners/{p}.md)"))
        .collect();
    let _ = writeln!(b, "Planners: {}.\n", planners.join(", "));
    if kind == DECLARED {
        b.push_str("## `start`, `goal` and the inputs

As declared: `start` and `goal` list `model.states` in order (the `model.angles` in degrees), plans give `model.inputs`. See [Declare your own model](../../declared.md).\n\n");
        let _ = writeln!(b, "## `[model]` keys\n\n`kind = \"{kind}\"` and:\n");
        return Ok(());
    }
    let (states, inputs) = states_of(kind)?;
    b.push_str("## `start` and `goal`\n\nBoth list the state in this order (angles in degrees in the file, radians in the logs):\n\n| # | coordinate | unit in the file |\n|---|---|---|\n");
    for (i, (n, u)) in states.iter().enumerate() {
        let _ = writeln!(
            b,
            "| {i} | `{n}` | {} |",
            if u.is_empty() { "–" } else { u }
        );
    }
    let inputs: Vec<String> = inputs.iter().map(|s| format!("`{s}`")).collect();
    let _ = writeln!(
        b,
        "\nInputs (the commands of the plan, one `limits.max_rate` entry each): {}.\n",
        inputs.join(", ")
    );
    urdf_table(b, kind)?;
    let _ = writeln!(b, "## `[model]` keys\n\n`kind = \"{kind}\"` and:\n");
    Ok(())
}

/// The URDF links and joints the model looks up by name (its physics
/// module's declaration, which the validation pass checks every URDF against).
fn urdf_table(b: &mut String, kind: &str) -> Result<(), ReferenceError> {
    let table =
        ModelConfig::required_urdf(kind).ok_or_else(|| ReferenceError::NoUrdf(kind.into()))?;
    b.push_str(
        "## URDF links and joints

",
    );
    if table.is_empty() {
        b.push_str("The model looks up no link or joint by name.\n\n");
        return Ok(());
    }
    b.push_str("The URDF (`model.urdf`) must have these, by name; a URDF that lacks some is refused with all the missing names in one message.\n\n| element | name | renamed by | role |\n|---|---|---|---|\n");
    for r in table {
        let _ = writeln!(
            b,
            "| {} | `{}` | {} | {} |",
            r.element.tag(),
            r.name,
            r.key
                .map(|k| format!("`model.{k}`"))
                .unwrap_or_else(|| "–".into()),
            cell(r.role)
        );
    }
    b.push('\n');
    Ok(())
}
