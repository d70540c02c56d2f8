//! What a model needs from its URDF, declared once per model: the links and
//! joints it looks up by name, the `[model]` key that renames each (if any)
//! and what each is for. The validation pass checks a URDF against the
//! declaration before building the physics and names every missing item in
//! one message; the per-model reference pages are generated from the same
//! tables, so the two cannot disagree.
//!
//! Each physics module exports its table (`REQUIRED`); its system turns it
//! into the names the scenario configures (`System::urdf_names`).

use crate::error::SetupError;
use serde::Serialize;
use urdf_rs::Robot;

/// A URDF element kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Element {
    /// `<link>`.
    Link,
    /// `<joint>`.
    Joint,
}

impl Element {
    /// `link` or `joint`.
    pub fn tag(self) -> &'static str {
        match self {
            Element::Link => "link",
            Element::Joint => "joint",
        }
    }
}

/// One link or joint a model looks up by name.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Required {
    /// Link or joint.
    pub element: Element,
    /// The default name.
    pub name: &'static str,
    /// The `[model]` key that renames it (`None`: the name is fixed). A key
    /// may hold a list of names (e.g. several casters).
    pub key: Option<&'static str>,
    /// What the model uses it for and what it must be, for the reference.
    pub role: &'static str,
}

impl Required {
    /// A fixed-name link.
    pub const fn link(name: &'static str, role: &'static str) -> Required {
        Required {
            element: Element::Link,
            name,
            key: None,
            role,
        }
    }
    /// A fixed-name joint.
    pub const fn joint(name: &'static str, role: &'static str) -> Required {
        Required {
            element: Element::Joint,
            name,
            key: None,
            role,
        }
    }
    /// The same item, renamed by the `[model]` key `key`.
    pub const fn renamed_by(self, key: &'static str) -> Required {
        Required {
            key: Some(key),
            ..self
        }
    }
    /// The item under its default name.
    pub fn default_name(&'static self) -> Named {
        Named {
            required: self,
            name: self.name.to_string(),
        }
    }
}

/// A declared item with the name a scenario gives it.
#[derive(Debug, Clone)]
pub struct Named {
    /// The declaration.
    pub required: &'static Required,
    /// The name the URDF must use.
    pub name: String,
}

/// Every item of `table` under its default name (models without renaming keys).
pub fn defaults(table: &'static [Required]) -> Vec<Named> {
    table.iter().map(Required::default_name).collect()
}

/// `a`, `b` and `c` (backquoted), for messages.
fn list(names: &[&str]) -> String {
    let q: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    match q.as_slice() {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

/// Check that `robot` has every named item; the error names all missing
/// ones in one line (`` URDF lacks joints `a`, `b` and link `c` ``: joints
/// first, each group in declaration order, "and" only between the groups
/// when there are two) and the `[model]` keys that rename them, if any.
pub fn check(robot: &Robot, names: &[Named]) -> Result<(), SetupError> {
    let has = |n: &Named| match n.required.element {
        Element::Link => robot.links.iter().any(|l| l.name == n.name),
        Element::Joint => robot.joints.iter().any(|j| j.name == n.name),
    };
    let missing: Vec<&Named> = names.iter().filter(|n| !has(n)).collect();
    if missing.is_empty() {
        return Ok(());
    }
    let group = |e: Element| {
        let mut v: Vec<&str> = Vec::new();
        for n in missing.iter().filter(|n| n.required.element == e) {
            if !v.contains(&n.name.as_str()) {
                v.push(&n.name);
            }
        }
        v
    };
    let groups: Vec<(Element, Vec<&str>)> = [Element::Joint, Element::Link]
        .into_iter()
        .map(|e| (e, group(e)))
        .filter(|(_, v)| !v.is_empty())
        .collect();
    let two = groups.len() == 2;
    let parts: Vec<String> = groups
        .iter()
        .map(|(e, v)| {
            let plural = if v.len() > 1 { "s" } else { "" };
            let names = if two {
                let q: Vec<String> = v.iter().map(|n| format!("`{n}`")).collect();
                q.join(", ")
            } else {
                list(v)
            };
            format!("{}{plural} {names}", e.tag())
        })
        .collect();
    let mut keys: Vec<&str> = Vec::new();
    for k in missing.iter().filter_map(|n| n.required.key) {
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    let hint = if keys.is_empty() {
        String::new()
    } else {
        format!(" (or name them in [model] with {})", keys.join(", "))
    };
    Err(SetupError::urdf(format!(
        "URDF lacks {}{hint}",
        parts.join(" and ")
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    const TABLE: [Required; 4] = [
        Required::link("base", "body"),
        Required::link("wheel", "wheel"),
        Required::joint("a", "first").renamed_by("a_joint"),
        Required::joint("b", "second"),
    ];

    fn robot(links: &[&str], joints: &[&str]) -> Robot {
        let mut s = String::from("<robot name=\"r\">");
        for l in links {
            s += &format!("<link name=\"{l}\"/>");
        }
        for j in joints {
            s += &format!(
                "<joint name=\"{j}\" type=\"fixed\"><parent link=\"x\"/><child link=\"y\"/></joint>"
            );
        }
        urdf_rs::read_from_string(&(s + "</robot>")).unwrap()
    }

    #[test]
    fn every_missing_name_in_one_message() {
        let names = defaults(&TABLE);
        check(&robot(&["base", "wheel"], &["a", "b"]), &names).unwrap();
        let e = check(&robot(&["base"], &[]), &names)
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "URDF lacks joints `a`, `b` and link `wheel` (or name them in [model] with a_joint)"
        );
        let e = check(&robot(&[], &["a"]), &names).unwrap_err().to_string();
        assert_eq!(e, "URDF lacks joint `b` and links `base`, `wheel`");
        let e = check(&robot(&["wheel"], &["a", "b"]), &names)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "URDF lacks link `base`");
        // Three of a kind: commas, then "and".
        let three = [
            Required::link("p", ""),
            Required::link("q", ""),
            Required::link("r", ""),
        ];
        let three: &'static [Required] = Box::leak(Box::new(three));
        let e = check(&robot(&[], &[]), &defaults(three))
            .unwrap_err()
            .to_string();
        assert_eq!(e, "URDF lacks links `p`, `q` and `r`");
    }
}
