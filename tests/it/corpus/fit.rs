//! `[compare] reference` (a recording beside the runs) in the scenario, and
//! `anholonomy fit`'s own arguments: keys it cannot vary, empty or inverted
//! ranges, absent topics, recordings that do not overlap the plan, a CSV
//! without `t`.

use super::ros_bags::{bag, bag_scenario};
use super::*;

/// A scenario planning from committed bag `twist_steps`, with `tables`.
fn with_bag(
    name: &str,
    tables: &str,
    extra: &[(&str, &str)],
    expect: Vec<Shape>,
    args: &[&str],
) -> Case {
    let mut files = vec![(
        "case.toml".to_string(),
        bag_scenario("twist_steps", "", tables).into_bytes(),
    )];
    files.extend(bag("twist_steps"));
    files.extend(
        extra
            .iter()
            .map(|(f, t)| (f.to_string(), t.as_bytes().to_vec())),
    );
    let mut a = vec!["case.toml".to_string()];
    a.extend(args.iter().map(|s| s.to_string()));
    Case {
        name: name.into(),
        files,
        special: vec![],
        args: a,
        run_flags: vec![],
        expect,
    }
}

fn shape(file: &str, line: Option<usize>, key: &str) -> Shape {
    Shape {
        file: file.into(),
        line,
        key: Some(key.into()),
    }
}

/// The line of `needle` in the scenario `with_bag` writes with `tables`.
fn line(tables: &str, needle: &str) -> Option<usize> {
    Some(line_of(&bag_scenario("twist_steps", "", tables), needle))
}

const ROWS_LATE: &str = "t,x,y,theta\n100,0,0,0\n100.5,0.1,0,0\n101,0.2,0,0\n";
const NO_T: &str = "x,y,theta\n0,0,0\n0.1,0,0\n";
const GOOD: &str = "t,x,y,theta\n0,0,0,0\n1,0.1,0,0\n2,0.2,0,0\n";

/// `[compare]` cases: bad input in every command.
fn compare_cases() -> Vec<Case> {
    let t = |r: &str| format!("[compare]\nreference = \"{r}\"\n");
    let mut out = vec![
        with_bag(
            "compare: absent topic",
            &t("twist_steps:/odom"),
            &[],
            vec![shape(
                "twist_steps",
                None,
                "no topic `/odom` in the bag (topics: /cmd_vel",
            )],
            &[],
        ),
        with_bag(
            "compare: a topic that is not a pose",
            &t("twist_steps:/cmd_vel"),
            &[],
            vec![shape(
                "twist_steps",
                None,
                "topic `/cmd_vel` holds geometry_msgs/msg/Twist, not a pose",
            )],
            &[],
        ),
        with_bag(
            "compare: recording that does not overlap the plan",
            &t("rec.csv"),
            &[("rec.csv", ROWS_LATE)],
            vec![shape(
                "case.toml",
                line(&t("rec.csv"), "reference ="),
                "key `compare.reference`: rec.csv: the recording does not overlap the plan",
            )],
            &[],
        ),
        with_bag(
            "compare: CSV without t",
            &t("rec.csv"),
            &[("rec.csv", NO_T)],
            vec![shape("rec.csv", Some(1), "no column `t`")],
            &[],
        ),
        with_bag(
            "compare: not a recording",
            &t("rec.json"),
            &[],
            vec![shape(
                "case.toml",
                line(&t("rec.json"), "reference ="),
                "key `compare.reference`: `rec.json`: neither a bag and a topic nor a CSV file",
            )],
            &[],
        ),
    ];
    let tables = format!("{}time_offset = 1e400\n", t("rec.csv"));
    out.push(with_bag(
        "compare: time offset not finite",
        &tables,
        &[("rec.csv", GOOD)],
        vec![shape(
            "case.toml",
            line(&tables, "time_offset"),
            "key `compare.time_offset`",
        )],
        &[],
    ));
    out
}

pub fn cases(c: &mut Corpus) {
    for case in compare_cases() {
        c.raw(case);
    }
}

/// `fit` cases (each runs `fit case.toml ARGS`).
pub fn fit_cases() -> Vec<Case> {
    let p = |key: &str| shape("--param", None, key);
    let plain = |name: &str, args: &[&str], expect: Shape| {
        with_bag(name, "", &[("rec.csv", GOOD)], vec![expect], args)
    };
    let mut out = vec![
        plain(
            "fit: unknown key",
            &["--param", "sim.frictoin=0.1..1"],
            p("`sim.frictoin=0.1..1`: with `sim.frictoin` = 0.1, the scenario is refused: key `sim.frictoin`: unknown key (did you mean `friction`?"),
        ),
        plain(
            "fit: a key of another table",
            &["--param", "planner.duration=1..2"],
            p("`planner.duration=1..2`: `planner` keys cannot be fitted"),
        ),
        plain(
            "fit: not a number",
            &["--param", "model.urdf"],
            p("`model.urdf`: `model.urdf` is string, not a number"),
        ),
        plain(
            "fit: not a key path",
            &["--param", "sim..friction"],
            p("`sim..friction`: `sim..friction` is not a key path"),
        ),
        plain(
            "fit: empty range",
            &["--param", "sim.friction=0.5..0.5"],
            p("`sim.friction=0.5..0.5`: an empty range"),
        ),
        plain(
            "fit: inverted range",
            &["--param", "sim.friction=1.2..0.3"],
            p("`sim.friction=1.2..0.3`: an inverted range"),
        ),
        plain(
            "fit: a range end the scenario refuses",
            &["--param", "sim.friction=-1..1"],
            p("`sim.friction=-1..1`: with `sim.friction` = -1, the scenario is refused"),
        ),
        plain(
            "fit: absent topic",
            &["--param", "sim.friction=0.3..1", "--against", "twist_steps:/odom"],
            shape("twist_steps", None, "no topic `/odom` in the bag"),
        ),
        plain(
            "fit: CSV without t",
            &["--param", "sim.friction=0.3..1", "--against", "bad.csv"],
            shape("bad.csv", Some(1), "no column `t`"),
        ),
        plain(
            "fit: recording that does not overlap the plan",
            &["--param", "sim.friction=0.3..1", "--against", "rec.csv", "--time-offset", "50"],
            shape("--time-offset", None, "rec.csv: the recording does not overlap the plan"),
        ),
        plain(
            "fit: twin and physics against one recording",
            &["--param", "sim.friction=0.3..1", "--param", "model.goal_tolerance[0]=0.01..0.1", "--against", "rec.csv"],
            p("against a recording, fit the twin"),
        ),
        plain(
            "fit: time offset without a recording",
            &["--param", "sim.friction=0.3..1", "--time-offset", "1"],
            shape("--time-offset", None, "only with a recording"),
        ),
        plain(
            "fit: inverted time offset range",
            &["--param", "sim.friction=0.3..1", "--against", "rec.csv", "--time-offset", "2..1"],
            shape("--time-offset", None, "`2..1`: an inverted range"),
        ),
        plain(
            "fit: key given twice",
            &["--param", "sim.friction=0.3..1", "--param", "sim.friction"],
            p("`sim.friction`: given twice"),
        ),
    ];
    // `bad.csv` for the CSV case.
    for c in &mut out {
        c.files.push(("bad.csv".into(), NO_T.as_bytes().to_vec()));
    }
    for mut c in compare_cases() {
        c.args
            .extend(["--param".to_string(), "sim.friction=0.3..1".to_string()]);
        c.name = format!("fit, {}", c.name);
        out.push(c);
    }
    out
}
