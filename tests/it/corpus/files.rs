//! URDFs, files that are not regular scenario files, several scenarios in
//! one call, and flags.

use super::*;

pub fn cases(c: &mut Corpus) {
    let d = disk();
    let sr = shipped("space_robot_paper.toml");
    let rv = shipped("rover_paper.toml");

    // URDFs (the disk's unless said).
    let du = "rolling_disk.urdf";
    let wheel_ixx = "ixx=\"0.031517\"";
    c.urdf(
        "urdf nan inertia",
        &d,
        du,
        &[(wheel_ixx, "ixx=\"nan\"")],
        Some("ixx=\"nan\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf negative inertia",
        &d,
        du,
        &[(wheel_ixx, "ixx=\"-0.031517\"")],
        Some("ixx=\"-0.031517\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf indefinite inertia",
        &d,
        du,
        &[("ixx=\"0.031517\" ixy=\"0\"", "ixx=\"0.031517\" ixy=\"0.5\"")],
        Some("ixy=\"0.5\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf inf inertia",
        &d,
        du,
        &[("izz=\"0.031517\"", "izz=\"inf\"")],
        Some("izz=\"inf\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf zero mass",
        &d,
        du,
        &[("<mass value=\"2.0\"/>", "<mass value=\"0\"/>")],
        Some("name=\"wheel\""),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf negative mass",
        &d,
        du,
        &[("<mass value=\"2.0\"/>", "<mass value=\"-2\"/>")],
        Some("<mass value=\"-2\"/>"),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf nan mass",
        &d,
        du,
        &[("<mass value=\"2.0\"/>", "<mass value=\"nan\"/>")],
        Some("<mass value=\"nan\"/>"),
        "URDF link `wheel`",
    );
    c.urdf(
        "urdf nan joint origin",
        &d,
        du,
        &[(
            "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n    <axis",
            "<origin xyz=\"nan 0 0\" rpy=\"0 0 0\"/>\n    <axis",
        )],
        Some("xyz=\"nan 0 0\""),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf inf joint rpy",
        &d,
        du,
        &[(
            "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n    <axis",
            "<origin xyz=\"0 0 0\" rpy=\"0 inf 0\"/>\n    <axis",
        )],
        Some("rpy=\"0 inf 0\""),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf zero axis",
        &d,
        du,
        &[("<axis xyz=\"0 1 0\"/>", "<axis xyz=\"0 0 0\"/>")],
        Some("<axis xyz=\"0 0 0\"/>"),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf nan axis",
        &d,
        du,
        &[("<axis xyz=\"0 1 0\"/>", "<axis xyz=\"nan 1 0\"/>")],
        Some("<axis xyz=\"nan"),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf dangling joint",
        &d,
        du,
        &[("<child link=\"wheel\"/>", "<child link=\"ghost\"/>")],
        Some("name=\"wheel_joint\""),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf duplicate link",
        &d,
        du,
        &[("<link name=\"wheel\">", "<link name=\"yoke\">")],
        None,
        "URDF has duplicate",
    );
    // Every problem at once: the joint to the renamed link names a link
    // that is no longer there.
    let renamed = std::fs::read_to_string(model(du)).unwrap();
    c.also(
        "m.urdf",
        Some(line_of(&renamed, "<joint name=\"wheel_joint\"")),
        "URDF joint `wheel_joint`",
    );
    c.urdf(
        "urdf wheel missing",
        &d,
        du,
        &[
            ("<link name=\"wheel\">", "<link name=\"wheal\">"),
            ("<child link=\"wheel\"/>", "<child link=\"wheal\"/>"),
        ],
        None,
        "URDF lacks link `wheel`",
    );
    // Several declared names missing: all of them, in one message.
    c.urdf(
        "urdf rover names missing",
        &rv,
        "rover.urdf",
        &[
            ("name=\"steer_joint\"", "name=\"steering_joint\""),
            ("name=\"front_wheel_joint\"", "name=\"drive_joint\""),
            (
                "<link name=\"back_left_wheel\">",
                "<link name=\"rear_left_wheel\">",
            ),
            (
                "<child link=\"back_left_wheel\"/>",
                "<child link=\"rear_left_wheel\"/>",
            ),
        ],
        None,
        "URDF lacks joints `steer_joint`, `front_wheel_joint` and link `back_left_wheel`",
    );
    c.urdf(
        "urdf negative visual radius",
        &d,
        du,
        &[("<cylinder radius=\"0.25\"", "<cylinder radius=\"-0.25\"")],
        Some("radius=\"-0.25\""),
        "URDF link `wheel` visual 1",
    );
    c.urdf("urdf nan collision length", &d, du, &[("<collision>\n      <origin xyz=\"0 0 0\" rpy=\"1.5707963267948966 0 0\"/>\n      <geometry><cylinder radius=\"0.25\" length=\"0.04\"", "<collision>\n      <origin xyz=\"0 0 0\" rpy=\"1.5707963267948966 0 0\"/>\n      <geometry><cylinder radius=\"0.25\" length=\"nan\"")], Some("length=\"nan\""), "URDF link `wheel` collision 1");
    c.urdf(
        "urdf malformed XML",
        &d,
        du,
        &[("</robot>", "")],
        None,
        "URDF does not parse",
    );
    c.urdf(
        "urdf nan visual origin",
        &d,
        du,
        &[(
            "<visual>\n      <origin xyz=\"0 0 0\"",
            "<visual>\n      <origin xyz=\"0 0 nan\"",
        )],
        Some("xyz=\"0 0 nan\""),
        "URDF link `wheel` visual 1",
    );
    c.urdf(
        "urdf nan colour",
        &d,
        du,
        &[("rgba=\"0.15 0.15", "rgba=\"nan 0.15")],
        Some("rgba=\"nan"),
        "URDF material `tyre`",
    );
    c.urdf(
        "urdf colour of 5 values",
        &d,
        du,
        &[("rgba=\"0.15 0.15", "rgba=\"0.1 0.15 0.15")],
        None,
        "URDF does not parse",
    );
    c.urdf(
        "urdf inertia attribute missing",
        &d,
        du,
        &[(" izz=\"0.002\"", "")],
        None,
        "URDF does not parse",
    );
    c.urdf(
        "urdf zero box",
        &d,
        du,
        &[(
            "<box size=\"0.22 0.042 0.03\"/>",
            "<box size=\"0 0.042 0.03\"/>",
        )],
        Some("<box size=\"0 "),
        "URDF link `wheel` visual 2",
    );
    c.urdf(
        "space robot urdf mass",
        &sr,
        "space_robot.urdf",
        &[("<mass value=\"27.44\"/>", "<mass value=\"20\"/>")],
        Some("name=\"vehicle\""),
        "URDF link `vehicle`",
    );
    c.urdf(
        "rover urdf limit reversed",
        &rv,
        "rover.urdf",
        &[(
            "lower=\"-0.8\" upper=\"0.8\"",
            "lower=\"0.8\" upper=\"-0.8\"",
        )],
        Some("lower=\"0.8\""),
        "URDF joint",
    );
    for (what, urdf) in [
        ("urdf empty file", ""),
        ("urdf not a robot", "<foo/>"),
        ("urdf without links", "<robot name=\"r\"></robot>"),
    ] {
        c.raw(Case {
            name: what.into(),
            files: vec![
                (
                    "case.toml".into(),
                    d.replace(&model(du).display().to_string(), "m.urdf")
                        .into_bytes(),
                ),
                ("m.urdf".into(), urdf.as_bytes().to_vec()),
            ],
            special: vec![],
            args: vec!["case.toml".into()],
            run_flags: vec![],
            expect: vec![no_line("m.urdf")],
        });
    }

    // Files that are not regular files, too large or not text.
    let file_case = |name: &str,
                     special: Vec<Special>,
                     files: Vec<(String, Vec<u8>)>,
                     arg: &str,
                     expect: Shape| Case {
        name: name.into(),
        files,
        special,
        args: vec![arg.into()],
        run_flags: vec![],
        expect: vec![expect],
    };
    c.raw(file_case(
        "missing scenario",
        vec![],
        vec![],
        "nope.toml",
        no_line("nope.toml"),
    ));
    c.raw(file_case(
        "empty directory",
        vec![Special::Dir("empty")],
        vec![],
        "empty",
        no_line("empty"),
    ));
    c.raw(file_case(
        "FIFO as scenario",
        vec![Special::Fifo("fifo.toml")],
        vec![],
        "fifo.toml",
        no_line("fifo.toml"),
    ));
    c.raw(file_case(
        "/dev/zero as scenario",
        vec![Special::Symlink("/dev/zero", "zero.toml")],
        vec![],
        "zero.toml",
        no_line("zero.toml"),
    ));
    c.raw(file_case(
        "dangling symlink",
        vec![Special::Symlink("/nonexistent/x.toml", "gone.toml")],
        vec![],
        "gone.toml",
        no_line("gone.toml"),
    ));
    c.raw(file_case(
        "scenario of 2 MB",
        vec![Special::Sized("big.toml", 2 << 20)],
        vec![],
        "big.toml",
        no_line("big.toml"),
    ));
    c.raw(file_case(
        "not UTF-8",
        vec![],
        vec![("bin.toml".into(), b"name = \"\xff\xfe\"\n".to_vec())],
        "bin.toml",
        Shape {
            file: "bin.toml".into(),
            line: Some(1),
            key: None,
        },
    ));
    c.raw(file_case(
        "FIFO among the scenarios of a directory",
        vec![Special::Dir("dir"), Special::Fifo("dir/b.toml")],
        vec![],
        "dir",
        no_line("dir/b.toml"),
    ));
    let with_urdf = |name: &str, special: Special, urdf: &str| Case {
        name: name.into(),
        files: vec![(
            "case.toml".into(),
            d.replace(&model(du).display().to_string(), urdf)
                .into_bytes(),
        )],
        special: vec![special],
        args: vec!["case.toml".into()],
        run_flags: vec![],
        expect: vec![no_line(urdf)],
    };
    c.raw(with_urdf("FIFO as URDF", Special::Fifo("m.urdf"), "m.urdf"));
    c.raw(with_urdf(
        "/dev/zero as URDF",
        Special::Symlink("/dev/zero", "m.urdf"),
        "m.urdf",
    ));
    c.raw(with_urdf(
        "directory as URDF",
        Special::Dir("m.urdf"),
        "m.urdf",
    ));
    c.raw(with_urdf(
        "URDF of 17 MB",
        Special::Sized("m.urdf", 17 << 20),
        "m.urdf",
    ));

    // Several scenarios in one call.
    let named = |n: &str| edit(&d, "name = \"d\"", &format!("name = \"{n}\""));
    c.raw(Case {
        name: "duplicate names".into(),
        files: vec![
            ("a.toml".into(), named("same").into_bytes()),
            ("b.toml".into(), named("Same").into_bytes()),
        ],
        special: vec![],
        args: vec!["a.toml".into(), "b.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "b.toml".into(),
            line: Some(1),
            key: Some("key `name`".into()),
        }],
    });
    c.raw(Case {
        name: "the same file twice".into(),
        files: vec![("a.toml".into(), d.clone().into_bytes())],
        special: vec![],
        args: vec!["a.toml".into(), "a.toml".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "a.toml".into(),
            line: Some(1),
            key: Some("key `name`".into()),
        }],
    });
    c.raw(Case {
        name: "good scenario first, bad one after".into(),
        files: vec![
            ("dir/a_good.toml".into(), named("good").into_bytes()),
            (
                "dir/b_bad.toml".into(),
                edit(&named("bad"), "dt = 0.001", "dt = 0.5").into_bytes(),
            ),
        ],
        special: vec![],
        args: vec!["dir".into()],
        run_flags: vec![],
        expect: vec![Shape {
            file: "dir/b_bad.toml".into(),
            line: Some(line_of(&d, "dt = 0.001")),
            key: Some("key `sim.dt`".into()),
        }],
    });
    c.raw(Case {
        name: "two bad scenarios, two errors".into(),
        files: vec![
            (
                "dir/a.toml".into(),
                edit(&named("a"), "radius = 0.25", "radius = -1.0").into_bytes(),
            ),
            (
                "dir/b.toml".into(),
                edit(&named("b"), "dt = 0.001", "dt = 0.5").into_bytes(),
            ),
        ],
        special: vec![],
        args: vec!["dir".into()],
        run_flags: vec![],
        expect: vec![
            Shape {
                file: "dir/a.toml".into(),
                line: Some(line_of(&d, "radius")),
                key: Some("key `model.radius`".into()),
            },
            Shape {
                file: "dir/b.toml".into(),
                line: Some(line_of(&d, "dt = 0.001")),
                key: Some("key `sim.dt`".into()),
            },
        ],
    });

    // Flags of run/check.
    let flagged = |name: &str, flags: &[&str], expect: Shape| Case {
        name: name.into(),
        files: vec![
            ("case.toml".into(), d.clone().into_bytes()),
            ("logfile".into(), b"x".to_vec()),
        ],
        special: vec![],
        args: vec!["case.toml".into()],
        run_flags: flags.iter().map(|s| s.to_string()).collect(),
        expect: vec![expect],
    };
    c.raw(flagged(
        "--shard on a scenario without [sweep]",
        &["--shard", "0/2"],
        no_line("case.toml"),
    ));
    c.raw(flagged(
        "--shard out of range",
        &["--shard", "2/2"],
        no_line("--shard"),
    ));
    c.raw(flagged(
        "--shard not I/N",
        &["--shard", "x"],
        no_line("--shard"),
    ));
    c.raw(flagged(
        "--logs is a file",
        &["--logs", "logfile"],
        no_line("logfile"),
    ));
    c.raw(flagged(
        "--keep summary with --report",
        &["--keep", "summary", "--report"],
        no_line("--report"),
    ));
    c.raw(flagged(
        "--variant of a scenario without [sweep]",
        &["--variant", "0"],
        no_line("case.toml"),
    ));
}
