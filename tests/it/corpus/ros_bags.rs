//! ROS 2 bags as plan files (`[planner] kind = "file"`, `path` = a bag):
//! each bad bag is a committed one of `tests/data/ros_bags/` (written by
//! `examples/ros_bags/make_bags.py` with the rosbags library), reported at
//! its file, naming the topic and the message's index; a bad bag key at
//! the scenario's line.

use super::*;

/// A diff_drive scenario planning from the bag at `path`, with `keys`
/// added to its `[planner]` table (and `tables` after it).
pub fn bag_scenario(path: &str, keys: &str, tables: &str) -> String {
    format!(
        r#"name = "bag"
start = [0.0, 0.0, 0.0]
goal = [0.0, 0.0, 0.0]

[model]
kind = "diff_drive"
urdf = "{}"

[planner]
kind = "file"
path = "{path}"
{keys}
{tables}
[sim]
dt = 0.001
"#,
        model("diff_drive.urdf").display()
    )
}

/// The files of committed bag `name`, as `name/...`.
pub(super) fn bag(name: &str) -> Vec<(String, Vec<u8>)> {
    let dir = root().join("tests/data/ros_bags").join(name);
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .flatten()
        .map(|e| {
            (
                format!("{name}/{}", e.file_name().to_string_lossy()),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect();
    out.sort();
    out
}

/// `case.toml` planning from committed bag `name` (path `path`, keys
/// `keys`, tables `tables`); the error is in `file` at `line`, its
/// message starting with `what`.
#[allow(clippy::too_many_arguments)]
fn bag_case(
    c: &mut Corpus,
    case: &str,
    name: &str,
    path: &str,
    keys: &str,
    tables: &str,
    file: &str,
    line: Option<usize>,
    what: &str,
) {
    let mut files = vec![(
        "case.toml".to_string(),
        bag_scenario(path, keys, tables).into_bytes(),
    )];
    files.extend(bag(name));
    c.raw(Case {
        name: case.into(),
        files,
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: file.into(),
            line,
            key: Some(what.into()),
        }],
    });
}

pub fn cases(c: &mut Corpus) {
    let custom_map = |v: &str| format!("[planner.map]\nv = \"{v}\"\nomega = \"motion.turn\"\n");
    bag_case(
        c,
        "bag without the topic",
        "twist_steps",
        "twist_steps",
        "topic = \"/nope\"",
        "",
        "twist_steps",
        None,
        "no topic `/nope` in the bag (topics: /cmd_vel (geometry_msgs/msg/Twist), /battery_voltage",
    );
    bag_case(
        c,
        "bag truncated CDR message",
        "truncated",
        "truncated",
        "",
        "",
        "truncated/truncated.mcap",
        None,
        "topic `/cmd_vel` message 3: its 39 bytes end before the message does",
    );
    bag_case(
        c,
        "bag field path that does not exist",
        "custom_steps",
        "custom_steps",
        "",
        &custom_map("motion.sideways"),
        "custom_steps/custom_steps.mcap",
        None,
        "topic `/base/command` message 0: input `v` = `motion.sideways` (planner.map.v): no field `sideways` in `motion`",
    );
    bag_case(
        c,
        "bag non-numeric field",
        "custom_steps",
        "custom_steps",
        "",
        &custom_map("header.frame_id"),
        "custom_steps/custom_steps.mcap",
        None,
        "topic `/base/command` message 0: input `v` = `header.frame_id` (planner.map.v): `header.frame_id` is a string, not a number",
    );
    bag_case(
        c,
        "bag field is a message",
        "custom_steps",
        "custom_steps",
        "",
        &custom_map("motion"),
        "custom_steps/custom_steps.mcap",
        None,
        "topic `/base/command` message 0: input `v` = `motion` (planner.map.v): `motion` is a message",
    );
    bag_case(
        c,
        "bag index past a fixed array",
        "custom_steps",
        "custom_steps",
        "",
        &custom_map("gains[3]"),
        "custom_steps/custom_steps.mcap",
        None,
        "topic `/base/command` message 0: input `v` = `gains[3]` (planner.map.v): index 3 is past the end",
    );
    bag_case(
        c,
        "bag index past a sequence",
        "custom_steps",
        "custom_steps",
        "",
        &custom_map("flags[2]"),
        "custom_steps/custom_steps.mcap",
        None,
        "topic `/base/command` message 0: input `v` = `flags[2]`: `flags` has 2 elements in this message",
    );
    bag_case(
        c,
        "bag custom type without a map",
        "custom_steps",
        "custom_steps",
        "",
        "",
        "custom_steps",
        None,
        "no topic whose messages give this model's inputs (v, omega)",
    );
    bag_case(
        c,
        "bag custom type half mapped",
        "custom_steps",
        "custom_steps",
        "topic = \"/base/command\"",
        "[planner.map]\nv = \"motion.forward\"\n",
        "custom_steps/custom_steps.mcap",
        None,
        "topic `/base/command` message 0: no field gives the input `omega`",
    );
    bag_case(
        c,
        "bag without the definition of its type",
        "no_definition",
        "no_definition",
        "",
        "",
        "no_definition/no_definition.mcap",
        None,
        "topic `/cmd_vel` message 0: the bag stores no definition of geometry_msgs/msg/Twist",
    );
    bag_case(
        c,
        "bag header time going backwards",
        "header_backwards",
        "header_backwards",
        "time = \"header\"",
        "",
        "header_backwards/header_backwards.mcap",
        None,
        "topic `/cmd_vel` message 4: time goes backwards",
    );
    bag_case(
        c,
        "bag log time going backwards",
        "log_backwards",
        "log_backwards/log_backwards.mcap",
        "",
        "",
        "log_backwards/log_backwards.mcap",
        None,
        "topic `/cmd_vel` message 4: time goes backwards",
    );
    bag_case(
        c,
        "bag header time of an unstamped type",
        "twist_steps",
        "twist_steps",
        "time = \"header\"",
        "",
        "twist_steps/twist_steps.mcap",
        None,
        "topic `/cmd_vel` message 0: time = \"header\", but geometry_msgs/msg/Twist has no `header.stamp`",
    );
    bag_case(
        c,
        "bag empty topic",
        "empty_topic",
        "empty_topic",
        "",
        "",
        "empty_topic",
        None,
        "topic `/cmd_vel` (geometry_msgs/msg/Twist): no messages",
    );
    // A bag directory without its metadata, a cut MCAP file.
    let mut twist = bag("twist_steps");
    twist.retain(|(n, _)| n.ends_with(".mcap"));
    let text = bag_scenario("twist_steps", "", "");
    let mut files = vec![("case.toml".to_string(), text.into_bytes())];
    files.extend(twist.clone());
    c.raw(Case {
        name: "bag directory without metadata.yaml".into(),
        files,
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "twist_steps".into(),
            line: None,
            key: Some("not a rosbag2 bag directory: no metadata.yaml (it holds twist_steps/twist_steps.mcap: point `path` at it)".into()),
        }],
    });
    let mut cut = twist[0].1.clone();
    cut.truncate(cut.len() / 2);
    let text = bag_scenario("cut.mcap", "", "");
    c.raw(Case {
        name: "bag mcap file cut short".into(),
        files: vec![
            ("case.toml".to_string(), text.into_bytes()),
            ("cut.mcap".into(), cut),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "cut.mcap".into(),
            line: None,
            key: Some("not a readable MCAP file".into()),
        }],
    });

    // Bag keys in the scenario, the bag there (so only the key is at fault).
    let sc = |keys: &str, tables: &str| bag_scenario("twist_steps", keys, tables);
    let with_bag = |c: &mut Corpus, name: &str, text: String, at: &str, key: &str| {
        c.sc(name, text, Some(at), Some(key));
        c.0.last_mut()
            .expect("the case just added")
            .files
            .extend(bag("twist_steps"));
    };
    with_bag(
        c,
        "bag map of an unknown input",
        sc("", "[planner.map]\nspeed = \"linear.x\"\n"),
        "speed =",
        "planner.map.speed",
    );
    with_bag(
        c,
        "bag map not a field path",
        sc("", "[planner.map]\nv = \"linear..x\"\n"),
        "v =",
        "planner.map.v",
    );
    with_bag(
        c,
        "bag map not a string",
        sc("", "[planner.map]\nv = 3\n"),
        "v =",
        "planner.map.v",
    );
    with_bag(
        c,
        "bag time unknown",
        sc("time = \"receive\"", ""),
        "time =",
        "planner.time",
    );
    with_bag(
        c,
        "bag duration negative",
        sc("duration = -1.0", ""),
        "duration =",
        "planner.duration",
    );
    c.sc(
        "bag key on a CSV plan",
        bag_scenario("plan.csv", "time = \"header\"", ""),
        Some("time ="),
        Some("planner.time"),
    );
}
