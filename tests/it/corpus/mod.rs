//! The bad-input corpus: malformed scenarios, URDFs, files and flags, each
//! with the error lines it must produce (`tests/bad_input_corpus.rs` runs
//! them through every command).

use crate::common::*;

/// One expected stderr line: `error: {file}` then `:{line}` (or nothing),
/// then `: ` and, when given, `{key}` at the start of the message.
#[derive(Clone, Debug)]
pub struct Shape {
    pub file: String,
    pub line: Option<usize>,
    pub key: Option<String>,
}

#[derive(Clone, Debug)]
pub enum Special {
    Fifo(&'static str),
    Symlink(&'static str, &'static str),
    Dir(&'static str),
    /// A sparse file of this many bytes.
    Sized(&'static str, u64),
    /// The `xacro` command on `PATH` (the test venv's when `PATH` has none).
    XacroOnPath,
}

#[derive(Clone, Debug)]
pub struct Case {
    pub name: String,
    pub files: Vec<(String, Vec<u8>)>,
    pub special: Vec<Special>,
    pub args: Vec<String>,
    /// Extra flags of `run`/`check`; such cases are about those flags and
    /// skip `plan` and `list`.
    pub run_flags: Vec<String>,
    pub expect: Vec<Shape>,
}

/// 1-based line of the first line of `text` containing `needle`.
pub fn line_of(text: &str, needle: &str) -> usize {
    text.lines()
        .position(|l| l.contains(needle))
        .unwrap_or_else(|| panic!("`{needle}` not in:\n{text}"))
        + 1
}

/// `text` with `from` replaced (which must occur: a case must change its base).
pub fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "`{from}` not in:\n{text}");
    text.replacen(from, to, 1)
}

pub fn shipped(file: &str) -> String {
    let text = std::fs::read_to_string(scenario(file)).unwrap();
    text.replace(
        "../models/",
        &format!("{}/", root().join("models").display()),
    )
}

pub fn disk() -> String {
    disk_scenario(&model("rolling_disk.urdf"), "name = \"d\"", "")
}

pub struct Corpus(Vec<Case>);

impl Corpus {
    /// A single scenario `case.toml`; the error is at the line containing
    /// `at` (None: no line) and names `key`.
    pub fn sc(&mut self, name: &str, text: String, at: Option<&str>, key: Option<&str>) {
        let line = at.map(|n| line_of(&text, n));
        self.sc_line(name, text, line, key);
    }

    pub fn sc_line(&mut self, name: &str, text: String, line: Option<usize>, key: Option<&str>) {
        self.0.push(Case {
            name: name.into(),
            files: vec![("case.toml".into(), text.into_bytes())],
            special: vec![],
            args: vec!["case.toml".into()],
            run_flags: vec![],
            expect: vec![Shape {
                file: "case.toml".into(),
                line,
                key: key.map(|k| format!("key `{k}`")),
            }],
        });
    }

    /// A scenario with its own URDF `m.urdf` (the shipped `urdf_file` edited
    /// by `edit`); the error is in `m.urdf` at the line containing `at`.
    /// One more expected line for the last case (an input with several
    /// problems reports each on its own line).
    pub fn also(&mut self, file: &str, line: Option<usize>, key: &str) {
        let last = self.0.last_mut().expect("a case to extend");
        last.expect.push(Shape {
            file: file.into(),
            line,
            key: Some(key.into()),
        });
    }

    pub fn urdf(
        &mut self,
        name: &str,
        scenario_text: &str,
        urdf_file: &str,
        edits: &[(&str, &str)],
        at: Option<&str>,
        key: &str,
    ) {
        let mut urdf = std::fs::read_to_string(model(urdf_file)).unwrap();
        for (from, to) in edits {
            urdf = edit(&urdf, from, to);
        }
        let line = at.map(|n| line_of(&urdf, n));
        let text = scenario_text.replace(&model(urdf_file).display().to_string(), "m.urdf");
        assert!(
            text.contains("\"m.urdf\""),
            "{name}: scenario does not use the URDF"
        );
        self.0.push(Case {
            name: name.into(),
            files: vec![
                ("case.toml".into(), text.into_bytes()),
                ("m.urdf".into(), urdf.into_bytes()),
            ],
            special: vec![],
            args: vec!["case.toml".into()],
            run_flags: vec![],
            expect: vec![Shape {
                file: "m.urdf".into(),
                line,
                key: Some(key.into()),
            }],
        });
    }

    pub fn raw(&mut self, case: Case) {
        self.0.push(case);
    }
}

pub fn no_line(file: &str) -> Shape {
    Shape {
        file: file.into(),
        line: None,
        key: None,
    }
}

mod dilf;
pub mod faults;
mod files;
pub mod fit;
mod held_out;
mod own_plan;
mod published;
mod ros_bags;
mod runaway;
mod studies;
mod surfaces;
mod tables;

/// Every case.
pub fn corpus() -> Vec<Case> {
    let mut c = Corpus(Vec::new());
    tables::cases(&mut c);
    studies::cases(&mut c);
    dilf::cases(&mut c);
    files::cases(&mut c);
    fit::cases(&mut c);
    own_plan::cases(&mut c);
    ros_bags::cases(&mut c);
    published::cases(&mut c);
    runaway::cases(&mut c);
    held_out::cases(&mut c);
    surfaces::cases(&mut c);
    c.0
}
