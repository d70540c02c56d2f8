//! Plans from outside: plan files (`[planner] kind = "file"`) and external
//! laws (`kind = "external"`). A bad plan file is reported at its own file,
//! row and column; a bad planner key at the scenario's line.

use super::*;

pub fn file_scenario(d: &str, plan: &str) -> String {
    edit(
        d,
        "kind = \"stokes_disk\"",
        &format!("kind = \"file\"\npath = \"{plan}\""),
    )
}

fn external_scenario(d: &str, keys: &str) -> String {
    edit(
        d,
        "kind = \"stokes_disk\"",
        &format!("kind = \"external\"\n{keys}"),
    )
}

/// `case.toml` planning from `plan` (holding `bytes`); the error is in the
/// plan file at `line`, its message starting with `what`.
fn plan_case(
    c: &mut Corpus,
    name: &str,
    plan: &str,
    bytes: &[u8],
    line: Option<usize>,
    what: &str,
) {
    let d = disk();
    c.raw(Case {
        name: name.into(),
        files: vec![
            ("case.toml".into(), file_scenario(&d, plan).into_bytes()),
            (plan.into(), bytes.to_vec()),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: plan.into(),
            line,
            key: Some(what.into()),
        }],
    });
}

/// An MCAP file with one JSON message on `topic`.
fn mcap_with(topic: &str, message: &str) -> Vec<u8> {
    let mut out = std::io::Cursor::new(Vec::new());
    {
        let mut w = mcap::Writer::new(&mut out).unwrap();
        let ch = w
            .add_channel(0, topic, "json", &std::collections::BTreeMap::new())
            .unwrap();
        w.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id: ch,
                sequence: 0,
                log_time: 0,
                publish_time: 0,
            },
            message.as_bytes(),
        )
        .unwrap();
        w.finish().unwrap();
    }
    out.into_inner()
}

pub fn cases(c: &mut Corpus) {
    let d = disk();

    // CSV plan files.
    plan_case(
        c,
        "plan csv missing column",
        "plan.csv",
        b"t,theta_rate\n0,1\n1,0\n",
        Some(1),
        "header: no column `alpha_rate`",
    );
    plan_case(
        c,
        "plan csv unknown column",
        "plan.csv",
        b"t,theta_rate,alpha_rate,omega\n0,1,0,0\n1,0,0,0\n",
        Some(1),
        "column `omega`: unknown column",
    );
    plan_case(
        c,
        "plan csv t not increasing",
        "plan.csv",
        b"t,theta_rate,alpha_rate\n0,1,0\n0.5,1,0\n0.5,0,0\n",
        Some(4),
        "column `t`: 0.5 does not come after",
    );
    plan_case(
        c,
        "plan csv t decreasing",
        "plan.csv",
        b"t,theta_rate,alpha_rate\n0,1,0\n0.5,1,0\n0.25,0,0\n",
        Some(4),
        "column `t`",
    );
    plan_case(
        c,
        "plan csv negative t",
        "plan.csv",
        b"t,theta_rate,alpha_rate\n-0.1,1,0\n0.5,1,0\n",
        Some(2),
        "column `t`: the first sample must be at t = 0",
    );
    plan_case(
        c,
        "plan csv nan",
        "plan.csv",
        b"t,theta_rate,alpha_rate\n0,1,0\n0.5,1,NaN\n1,0,0\n",
        Some(3),
        "column `alpha_rate`: NaN is not a finite number",
    );
    plan_case(
        c,
        "plan csv infinite t",
        "plan.csv",
        b"t,theta_rate,alpha_rate\n0,1,0\ninf,1,0\n",
        Some(3),
        "column `t`: inf is not a finite time",
    );
    plan_case(
        c,
        "plan csv not a number",
        "plan.csv",
        b"t,theta_rate,alpha_rate\n0,1,0\n\n# a comment\n0.5,fast,0\n",
        Some(5),
        "column `theta_rate`: `fast` is not a number",
    );
    plan_case(
        c,
        "plan csv short row",
        "plan.csv",
        b"t,theta_rate,alpha_rate\n0,1,0\n0.5,1\n",
        Some(3),
        "2 fields, the header has 3",
    );
    plan_case(
        c,
        "plan csv empty file",
        "plan.csv",
        b"",
        None,
        "empty file",
    );
    plan_case(
        c,
        "plan csv header only",
        "plan.csv",
        b"t,theta_rate,alpha_rate\n",
        None,
        "0 samples",
    );
    plan_case(
        c,
        "plan csv one row",
        "plan.csv",
        b"t,theta_rate,alpha_rate\n0,1,0\n",
        None,
        "1 sample: a plan needs at least two",
    );
    plan_case(
        c,
        "plan csv column twice",
        "plan.csv",
        b"t,theta_rate,alpha_rate,t\n0,1,0,0\n",
        Some(1),
        "column `t`: appears twice",
    );
    plan_case(
        c,
        "plan csv not utf8",
        "plan.csv",
        b"t,theta_rate,alpha_rate\n0,1,\xff\n",
        Some(2),
        "plan file is not UTF-8",
    );

    // JSON plan files.
    plan_case(
        c,
        "plan json unknown input",
        "plan.json",
        b"{\"t\": [0, 1],\n \"u\": {\"theta_rate\": [1, 0], \"alpha_rate\": [0, 0],\n  \"omega\": [0, 0]}}",
        Some(3),
        "key `u.omega`: unknown input",
    );
    plan_case(
        c,
        "plan json missing input",
        "plan.json",
        b"{\"t\": [0, 1],\n \"u\": {\"theta_rate\": [1, 0]}}",
        Some(2),
        "key `u`: no input `alpha_rate`",
    );
    plan_case(
        c,
        "plan json nan",
        "plan.json",
        b"{\"t\": [0, 1],\n \"u\": {\"theta_rate\": [1, NaN], \"alpha_rate\": [0, 0]}}",
        Some(2),
        "expected value",
    );
    plan_case(
        c,
        "plan json t not increasing",
        "plan.json",
        b"{\"t\": [0,\n 1,\n 1],\n \"u\": {\"theta_rate\": [1, 0, 0], \"alpha_rate\": [0, 0, 0]}}",
        Some(3),
        "key `t[2]`: 1 does not come after",
    );
    plan_case(
        c,
        "plan json lengths differ",
        "plan.json",
        b"{\"t\": [0, 1], \"u\": {\"theta_rate\": [1, 0, 0], \"alpha_rate\": [0, 0]}}",
        Some(1),
        "key `u.theta_rate`: 3 values, `t` has 2",
    );
    plan_case(
        c,
        "plan json empty file",
        "plan.json",
        b"  \n",
        None,
        "empty file",
    );

    // MCAP plan files.
    plan_case(
        c,
        "plan mcap garbage",
        "run.mcap",
        b"this is not an MCAP file at all",
        None,
        "not a readable MCAP file",
    );
    plan_case(
        c,
        "plan mcap without the topic",
        "run.mcap",
        &mcap_with("/ideal/state", "{\"t\":0,\"values\":{}}"),
        None,
        "no messages on topic `/plan/command` (topics: /ideal/state)",
    );
    plan_case(
        c,
        "plan mcap of another model",
        "run.mcap",
        &mcap_with(
            "/plan/command",
            "{\"t\":0.0,\"segment\":\"a\",\"values\":{\"drive\":1.0,\"steer_rate\":0.0}}",
        ),
        None,
        "topic `/plan/command` message 0, value `drive`: not an input of this model",
    );

    // Planner keys in the scenario.
    c.sc(
        "plan file missing",
        file_scenario(&d, "nowhere.csv"),
        Some("path ="),
        Some("planner.path"),
    );
    c.sc(
        "plan file unknown format",
        file_scenario(&d, "plan.txt"),
        Some("path ="),
        Some("planner.path"),
    );
    c.sc(
        "plan file hold unknown",
        edit(
            &file_scenario(&d, "plan.csv"),
            "path = \"plan.csv\"",
            "path = \"plan.csv\"\nhold = \"cubic\"",
        ),
        Some("hold ="),
        Some("planner.hold"),
    );
    c.sc(
        "plan file topic on csv",
        edit(
            &file_scenario(&d, "plan.csv"),
            "path = \"plan.csv\"",
            "path = \"plan.csv\"\ntopic = \"/plan/command\"",
        ),
        Some("topic ="),
        Some("planner.topic"),
    );
    c.sc_line(
        "plan file path missing",
        edit(&d, "kind = \"stokes_disk\"", "kind = \"file\""),
        Some(line_of(&d, "[planner]")),
        Some("planner.path"),
    );

    // External laws: numbers and the program, checked up front.
    let law = "command = [\"sh\", \"law.sh\"]\nperiod = 0.02\nhorizon = 2.0";
    c.sc(
        "external period zero",
        external_scenario(&d, &law.replace("period = 0.02", "period = 0.0")),
        Some("period ="),
        Some("planner.period"),
    );
    c.sc(
        "external period negative",
        external_scenario(&d, &law.replace("period = 0.02", "period = -0.02")),
        Some("period ="),
        Some("planner.period"),
    );
    c.sc(
        "external horizon zero",
        external_scenario(&d, &law.replace("horizon = 2.0", "horizon = 0.0")),
        Some("horizon ="),
        Some("planner.horizon"),
    );
    c.sc(
        "external timeout zero",
        external_scenario(&d, &format!("{law}\ntimeout = 0.0")),
        Some("timeout ="),
        Some("planner.timeout"),
    );
    c.sc(
        "external empty command",
        external_scenario(&d, &law.replace("[\"sh\", \"law.sh\"]", "[]")),
        Some("command ="),
        Some("planner.command"),
    );
    c.sc(
        "external program not on PATH",
        external_scenario(&d, &law.replace("\"sh\"", "\"no-such-program-anywhere\"")),
        Some("command ="),
        Some("planner.command"),
    );
    c.sc(
        "external program path missing",
        external_scenario(&d, &law.replace("\"sh\"", "\"./bin/law\"")),
        Some("command ="),
        Some("planner.command"),
    );
    c.sc_line(
        "external period missing",
        external_scenario(&d, &law.replace("period = 0.02\n", "")),
        Some(line_of(&d, "[planner]")),
        Some("planner.period"),
    );
    c.sc(
        "external unknown key",
        external_scenario(&d, &format!("{law}\nrate = 50")),
        Some("rate ="),
        Some("planner.rate"),
    );
    c.sc(
        "external command not strings",
        external_scenario(&d, &law.replace("[\"sh\", \"law.sh\"]", "[\"sh\", 3]")),
        Some("command ="),
        Some("planner.command[1]"),
    );
}
