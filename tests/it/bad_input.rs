//! Bad input: one-line error, exit code 2, no panic, no log file.

use crate::common::*;
use std::path::Path;

/// Write `text` as a scenario in a fresh directory, run `anholonomy run` on it
/// and check the contract. Returns stderr.
fn expect_input_error(text: &str, needle: &str) -> String {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("bad.toml");
    std::fs::write(&file, text).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    check_contract(&out, dir.path(), needle)
}

fn check_contract(out: &std::process::Output, dir: &Path, needle: &str) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "one line expected: {stderr}"
    );
    assert!(stderr.starts_with("error: "), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains(needle), "`{needle}` not in: {stderr}");
    assert!(
        files_below(&dir.join("logs")).is_empty(),
        "a log file was written"
    );
    stderr
}

#[test]
fn missing_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = cli(dir.path(), &["run", "nope.toml", "--logs", "logs"]);
    check_contract(&out, dir.path(), "nope.toml");
}

#[test]
fn toml_syntax_error_names_line() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "friction = = 1");
    let err = expect_input_error(&text, "bad.toml:");
    // The broken line is the last one of the [sim] table.
    let line = text.lines().position(|l| l.contains("= =")).unwrap() + 1;
    assert!(err.contains(&format!(":{line}:")), "{err}");
}

#[test]
fn unknown_key_names_key_and_line() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "fricton = 0.5");
    let err = expect_input_error(&text, "fricton");
    let line = text.lines().position(|l| l.contains("fricton")).unwrap() + 1;
    assert!(err.contains(&format!(":{line}:")), "{err}");
}

#[test]
fn unknown_planner() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "")
        .replace("kind = \"stokes_disk\"", "kind = \"teleport\"");
    expect_input_error(&text, "teleport");
}

#[test]
fn nan_and_infinite_numbers() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "friction = nan");
    expect_input_error(&text, "sim.friction");
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "")
        .replace("goal = [-0.4,", "goal = [-inf,");
    expect_input_error(&text, "goal[0]");
    let text =
        disk_scenario(&model("rolling_disk.urdf"), "", "").replace("dt = 0.001", "dt = 1e999");
    expect_input_error(&text, "sim.dt");
}

#[test]
fn missing_urdf() {
    let text = disk_scenario(Path::new("/nonexistent/disk.urdf"), "", "");
    expect_input_error(&text, "model.urdf");
}

#[test]
fn urdf_that_does_not_parse() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("broken.urdf");
    std::fs::write(&urdf, "<robot name=\"x\"><link name=\"a\"></robot>").unwrap();
    let file = dir.path().join("bad.toml");
    std::fs::write(&file, disk_scenario(&urdf, "", "")).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    check_contract(&out, dir.path(), "URDF does not parse");
}

#[test]
fn urdf_with_dangling_joint() {
    let dir = tempfile::tempdir().unwrap();
    let urdf = dir.path().join("dangling.urdf");
    let text = std::fs::read_to_string(model("rolling_disk.urdf"))
        .unwrap()
        .replace("<child link=\"wheel\"/>", "<child link=\"ghost\"/>");
    std::fs::write(&urdf, text).unwrap();
    std::fs::write(dir.path().join("bad.toml"), disk_scenario(&urdf, "", "")).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    check_contract(&out, dir.path(), "ghost");
}

#[test]
fn radius_mismatch_with_urdf() {
    let text =
        disk_scenario(&model("rolling_disk.urdf"), "", "").replace("radius = 0.25", "radius = 0.3");
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.toml"), text).unwrap();
    let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
    check_contract(&out, dir.path(), "radius");
}

#[test]
fn unknown_threshold_metric() {
    let text = format!(
        "{}\n[thresholds]\nsim_goal_teleport = 1.0\n",
        disk_scenario(&model("rolling_disk.urdf"), "", "")
    );
    expect_input_error(&text, "sim_goal_teleport");
}

#[test]
fn wrong_state_length() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "")
        .replace("start = [0.0, 0.0, 0.0, 0.0]", "start = [0.0, 0.0]");
    expect_input_error(&text, "start");
}

#[test]
fn check_on_bad_input_also_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = cli(dir.path(), &["check", "missing_dir/"]);
    check_contract(&out, dir.path(), "missing_dir");
}

#[test]
fn unknown_planner_key_names_its_line() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "").replace(
        "kind = \"stokes_disk\"",
        "kind = \"stokes_disk\"\nalgoritm = \"x\"",
    );
    let err = expect_input_error(&text, "algoritm");
    let line = text
        .lines()
        .position(|l| l.starts_with("algoritm"))
        .unwrap()
        + 1;
    assert!(err.contains(&format!(":{line}:")), "{err}");
}

#[test]
fn solver_and_drive_settings_out_of_range() {
    for (sim, needle) in [
        ("solver_pgs_iterations = 0", "sim.solver_pgs_iterations"),
        ("motor_angle_gain = -1.0", "sim.motor_angle_gain"),
        ("solver_relax_pass = 1", "expected a boolean"),
    ] {
        let text = disk_scenario(&model("rolling_disk.urdf"), "", sim);
        expect_input_error(&text, needle);
    }
}

#[test]
fn urdf_the_loader_cannot_represent() {
    // A collision mesh that is not there, and a second root link: both
    // named, nothing simulated.
    let base = std::fs::read_to_string(model("rolling_disk.urdf")).unwrap();
    for (edit, needle) in [
        (
            base.replace(
                "<collision>",
                "<collision><geometry><mesh filename=\"w.stl\"/></geometry></collision><collision>",
            ),
            "collision mesh: `w.stl`: no such file",
        ),
        (
            base.replace(
                "</robot>",
                "<link name=\"stray\"><inertial><mass value=\"1\"/><inertia ixx=\"1\" ixy=\"0\" ixz=\"0\" iyy=\"1\" iyz=\"0\" izz=\"1\"/></inertial></link></robot>",
            ),
            "2 root links",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let urdf = dir.path().join("edited.urdf");
        std::fs::write(&urdf, edit).unwrap();
        std::fs::write(dir.path().join("bad.toml"), disk_scenario(&urdf, "", "")).unwrap();
        let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
        check_contract(&out, dir.path(), needle);
    }
}

// The cases of issue 14, one test each (the corpus in `bad_input_corpus.rs`
// runs many more through every command).

/// A directory with a good scenario first and a bad one after: exit 2 and
/// nothing written, not even the good one's logs.
#[test]
fn good_scenario_then_bad_one_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path().join("set");
    std::fs::create_dir(&d).unwrap();
    let good = disk_scenario(&model("rolling_disk.urdf"), "name = \"a\"", "");
    std::fs::write(d.join("a.toml"), &good).unwrap();
    std::fs::write(
        d.join("b.toml"),
        good.replace("name = \"a\"", "name = \"b\"").replace(
            "kind = \"stokes_disk\"",
            "kind = \"stokes_disk\"\nslant = -1.0",
        ),
    )
    .unwrap();
    let out = cli(dir.path(), &["run", "set", "--logs", "logs"]);
    let err = check_contract(&out, dir.path(), "set/b.toml:");
    assert!(err.contains("key `planner.slant`"), "{err}");
    assert!(!dir.path().join("logs").exists());
}

/// `list` validates like `run`: the valid scenarios on stdout, each error on
/// stderr, exit 2.
#[test]
fn list_reports_bad_scenarios_on_stderr_and_exits_2() {
    let dir = tempfile::tempdir().unwrap();
    let good = disk_scenario(&model("rolling_disk.urdf"), "name = \"fine\"", "");
    std::fs::write(dir.path().join("a.toml"), &good).unwrap();
    std::fs::write(
        dir.path().join("b.toml"),
        good.replace("name = \"fine\"", "name = \"\""),
    )
    .unwrap();
    let out = cli(dir.path(), &["list", "."]);
    assert_eq!(out.status.code(), Some(2));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stdout.contains("fine") && !stdout.contains("error"),
        "{stdout}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.starts_with("error: ./b.toml:1: key `name`"),
        "{stderr}"
    );
}

/// `plan` runs the URDF, physics and sweep checks too.
#[test]
fn plan_checks_urdf_physics_and_sweep() {
    let base = disk_scenario(&model("rolling_disk.urdf"), "", "");
    for (text, needle) in [
        (
            base.replace("radius = 0.25", "radius = 0.3"),
            "key `model.radius`",
        ),
        (
            format!("{base}\n[sweep]\ncount = 0\nsuccess_max = 1.0\n"),
            "key `sweep.count`",
        ),
        (
            format!("{base}\n[sweep]\ncount = 2\nsuccess_max = 1.0\nsuccess_metric = \"x\"\n"),
            "key `sweep.success_metric`",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("bad.toml"), text).unwrap();
        let out = cli(dir.path(), &["plan", "bad.toml"]);
        check_contract(&out, dir.path(), needle);
        assert!(out.stdout.is_empty());
    }
}

/// NaN or negative wheel inertia and a NaN joint origin are bad input (exit
/// 2, naming the URDF file, line and element), not a wheel that never turns
/// or a diverged simulation (exit 3).
#[test]
fn urdf_numbers_are_checked() {
    let urdf = std::fs::read_to_string(model("rolling_disk.urdf")).unwrap();
    for (from, to, needle) in [
        (
            "ixx=\"0.031517\"",
            "ixx=\"nan\"",
            "URDF link `wheel` <inertia>",
        ),
        (
            "ixx=\"0.031517\"",
            "ixx=\"-0.031517\"",
            "URDF link `wheel` <inertia>",
        ),
        (
            "<origin xyz=\"0 0 0\" rpy=\"0 0 0\"/>\n    <axis",
            "<origin xyz=\"nan 0 0\" rpy=\"0 0 0\"/>\n    <axis",
            "URDF joint `wheel_joint` <origin>",
        ),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let bad = urdf.replacen(from, to, 1);
        let line = bad
            .lines()
            .position(|l| l.contains(to.lines().next().unwrap()))
            .unwrap()
            + 1;
        std::fs::write(dir.path().join("m.urdf"), bad).unwrap();
        let text = disk_scenario(Path::new("m.urdf"), "", "");
        std::fs::write(dir.path().join("bad.toml"), text).unwrap();
        let out = cli(dir.path(), &["run", "bad.toml", "--logs", "logs"]);
        let err = check_contract(&out, dir.path(), needle);
        assert!(err.starts_with(&format!("error: m.urdf:{line}: ")), "{err}");
    }
}

/// Two scenarios with the same name in one call, a name with a NUL byte and
/// one of 300 characters: exit 2 before anything runs.
#[test]
fn names_are_checked_up_front() {
    let dir = tempfile::tempdir().unwrap();
    let text = |name: &str| {
        disk_scenario(
            &model("rolling_disk.urdf"),
            &format!("name = \"{name}\""),
            "",
        )
    };
    std::fs::write(dir.path().join("a.toml"), text("twin")).unwrap();
    std::fs::write(dir.path().join("b.toml"), text("twin")).unwrap();
    let out = cli(dir.path(), &["run", "a.toml", "b.toml", "--logs", "logs"]);
    let err = check_contract(
        &out,
        dir.path(),
        "b.toml:1: key `name`: `twin` is also the name of a.toml",
    );
    assert!(err.starts_with("error: b.toml:1:"), "{err}");
    for name in ["a\\u0000b", &"n".repeat(300)] {
        std::fs::write(dir.path().join("c.toml"), text(name)).unwrap();
        let out = cli(dir.path(), &["run", "c.toml", "--logs", "logs"]);
        check_contract(&out, dir.path(), "c.toml:1: key `name`");
    }
}

/// A FIFO or a symlink to /dev/zero is refused from its metadata: no hang,
/// no memory exhaustion.
#[cfg(unix)]
#[test]
fn fifo_and_device_are_not_read() {
    let dir = tempfile::tempdir().unwrap();
    assert!(std::process::Command::new("mkfifo")
        .arg(dir.path().join("f.toml"))
        .status()
        .unwrap()
        .success());
    std::os::unix::fs::symlink("/dev/zero", dir.path().join("z.toml")).unwrap();
    for (file, what) in [("f.toml", "a FIFO"), ("z.toml", "a character device")] {
        let out = cli(dir.path(), &["plan", file]);
        check_contract(
            &out,
            dir.path(),
            &format!("{file}: scenario must be a regular file, this is {what}"),
        );
    }
}

/// Range checks, type errors and errors inside `[model]`/`[planner]` name the
/// line of the key itself (not the table header) and the key.
#[test]
fn errors_name_the_line_of_the_key() {
    let base = disk_scenario(&model("rolling_disk.urdf"), "", "");
    for (from, to, key) in [
        ("dt = 0.001", "dt = 0.5", "sim.dt"),
        ("dt = 0.001", "dt = \"fast\"", "sim.dt"),
        ("radius = 0.25", "radius = \"big\"", "model.radius"),
        ("radius = 0.25", "radius = -1.0", "model.radius"),
        (
            "kind = \"stokes_disk\"",
            "kind = \"stokes_disk\"\nslant = \"x\"",
            "planner.slant",
        ),
    ] {
        let text = base.replacen(from, to, 1);
        let last = to.lines().last().unwrap();
        let line = text.lines().position(|l| l == last).unwrap() + 1;
        let err = expect_input_error(&text, &format!("bad.toml:{line}: key `{key}`"));
        assert!(err.starts_with("error: bad.toml:"), "{err}");
    }
}

/// `--shard` on a scenario without `[sweep]` is an error, not silently ignored.
#[test]
fn shard_without_sweep_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("d.toml"),
        disk_scenario(&model("rolling_disk.urdf"), "", ""),
    )
    .unwrap();
    let out = cli(
        dir.path(),
        &["run", "d.toml", "--shard", "0/2", "--logs", "logs"],
    );
    check_contract(
        &out,
        dir.path(),
        "d.toml: --shard: this scenario has no [sweep] table",
    );
}

/// The step budget (issue 13): a run over it is refused up front with the
/// key responsible and the step count, in readable numbers; `--max-steps`
/// moves the budget both ways.
#[test]
fn step_budget_names_dt_and_step_count() {
    let dir = tempfile::tempdir().unwrap();
    let base = disk_scenario(&model("rolling_disk.urdf"), "", "");
    let tiny = base.replacen("dt = 0.001", "dt = 1e-12", 1);
    std::fs::write(dir.path().join("tiny.toml"), &tiny).unwrap();
    let line = tiny.lines().position(|l| l == "dt = 1e-12").unwrap() + 1;
    for args in [
        &["run", "tiny.toml", "--logs", "logs"][..],
        &["plan", "tiny.toml"],
    ] {
        let out = cli(dir.path(), args);
        let err = check_contract(&out, dir.path(), &format!("tiny.toml:{line}: key `sim.dt`"));
        // ~4.4 s of plan at 1e-12 s: ~4.4e12 steps, in readable numbers.
        assert!(err.contains("at sim.dt = 1e-12 s is 4.37"), "{err}");
        assert!(err.contains("e12 steps"), "{err}");
        assert!(err.contains("budget of 2e6 steps"), "{err}");
        assert!(err.contains("--max-steps"), "{err}");
    }
    // dt = 1e-5: ~437 600 steps, within the default budget, over 100 000.
    let fine = base.replacen("dt = 0.001", "dt = 1e-5", 1);
    std::fs::write(dir.path().join("fine.toml"), &fine).unwrap();
    let out = cli(dir.path(), &["plan", "fine.toml", "--max-steps", "100000"]);
    let err = check_contract(&out, dir.path(), "key `sim.dt`");
    assert!(
        err.contains("steps, over the budget of 100000 steps"),
        "{err}"
    );
    assert!(err.contains(" s is 437"), "{err}");
    let out = cli(dir.path(), &["list", "fine.toml"]);
    assert_eq!(out.status.code(), Some(0));
    // Raising the budget lets the tiny step through validation (`list` only:
    // running it would take for ever).
    let out = cli(
        dir.path(),
        &["list", "tiny.toml", "--max-steps", "10000000000000"],
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A goal at 1e300 m: refused, with the plan duration readable (it printed
/// 300 digits).
#[test]
fn huge_goal_prints_readable_numbers() {
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "").replacen(
        "goal = [-0.4, 1.0",
        "goal = [1e300, 1.0",
        1,
    );
    let err = expect_input_error(&text, "key `goal`");
    assert!(err.len() < 300, "{err}");
    assert!(!err.contains("0000000000"), "{err}");
}

/// `--pose-rate` takes a finite rate ≥ 0 (clap alone would take NaN and inf).
#[test]
fn pose_rate_must_be_a_rate() {
    let dir = tempfile::tempdir().unwrap();
    let text = disk_scenario(&model("rolling_disk.urdf"), "", "");
    std::fs::write(dir.path().join("d.toml"), text).unwrap();
    for bad in ["nan", "-1", "inf"] {
        let rate = format!("--pose-rate={bad}");
        let args = ["run", "d.toml", "--logs", "logs", &rate];
        let err = check_contract(&cli(dir.path(), &args), dir.path(), "--pose-rate");
        assert!(err.contains("is not a rate"), "{err}");
    }
}

/// `--max-steps` is documented in `--help` of every command that validates.
#[test]
fn max_steps_is_documented() {
    let dir = tempfile::tempdir().unwrap();
    for cmd in ["run", "check", "baseline", "plan", "list"] {
        let out = cli(dir.path(), &[cmd, "--help"]);
        let help = String::from_utf8_lossy(&out.stdout);
        assert!(help.contains("--max-steps <N>"), "{cmd}: {help}");
        assert!(help.contains("Step budget"), "{cmd}: {help}");
    }
}
