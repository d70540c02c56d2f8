//! `[planner] kind = "external"`: a feedback law in another process.
//!
//! The laws are `tests/data/fault_law.py` (a heading law for the rolling
//! disk that misbehaves on purpose) and the shipped minimal clients. Each
//! fault must end the run with `Error::Law` (exit 3) naming the sample and
//! carrying the law's stderr, and leave no process behind: not running,
//! not a zombie (the test process is the harness here, so an unreaped
//! child would stay a zombie until it exits).

use crate::common::*;
use anholonomy::error::Error;
use anholonomy::runner::{run, Prepared, RunOptions};
use anholonomy::scenario::Scenario;
use std::path::{Path, PathBuf};

/// The Python interpreter itself (not a version manager's shim, which can
/// take longer to start than a short timeout allows on a busy machine).
fn python() -> String {
    // CI installs python3 when it is missing; without it these tests cannot run.
    let out = std::process::Command::new("python3")
        .args(["-c", "import sys; print(sys.executable)"])
        .output()
        .expect("python3 is needed to run the external-law tests");
    assert!(out.status.success(), "python3 does not run");
    String::from_utf8(out.stdout).unwrap().trim().to_string()
}

fn fault_law() -> PathBuf {
    root().join("tests/data/fault_law.py")
}

/// A disk scenario in `dir` whose planner runs `command`.
fn disk_with_law(dir: &Path, name: &str, command: &[String], extra: &str) -> PathBuf {
    let cmd = command
        .iter()
        .map(|c| format!("{c:?}"))
        .collect::<Vec<_>>()
        .join(", ");
    let text = format!(
        r#"name = "{name}"
start = [0.0, 0.0, 0.0, 0.0]
goal = [0.5, 0.5, 0.0, 90.0]

[model]
kind = "rolling_disk"
radius = 0.25
urdf = "{urdf}"

[planner]
kind = "external"
command = [{cmd}]
{period}{horizon}{extra}

[sim]
dt = 0.002
"#,
        urdf = model("rolling_disk.urdf").display(),
        // Defaults unless `extra` sets them.
        period = if extra.contains("period") {
            ""
        } else {
            "period = 0.02\n"
        },
        horizon = if extra.contains("horizon") {
            ""
        } else {
            "horizon = 1.0\n"
        },
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

fn law_command(mode: &str, dir: &Path) -> Vec<String> {
    vec![
        python(),
        fault_law().display().to_string(),
        mode.into(),
        dir.display().to_string(),
    ]
}

fn opts(logs: Option<&Path>) -> RunOptions {
    RunOptions {
        log_root: logs.map(Path::to_path_buf),
        progress: Default::default(),
        pose_rate: anholonomy::runner::DEFAULT_POSE_RATE,
        cancel: Default::default(),
        keep: anholonomy::log::Keep::All,
        batch: true,
    }
}

/// The pids the law processes wrote.
fn pids(dir: &Path) -> Vec<u32> {
    std::fs::read_to_string(dir.join("pids"))
        .unwrap_or_default()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect()
}

/// Whether `pid` is still a process of this machine (running or a zombie).
fn exists(pid: u32) -> Option<String> {
    let stat = std::fs::read_to_string(format!("/proc/{pid}/stat")).ok()?;
    // The state follows the parenthesised command name.
    let state = stat
        .rsplit(')')
        .next()?
        .split_whitespace()
        .next()?
        .to_string();
    Some(state)
}

/// The pids of the `sleep 200` processes the `fork_*` laws started.
fn grandchildren(dir: &Path) -> Vec<u32> {
    std::fs::read_to_string(dir.join("grandchildren"))
        .unwrap_or_default()
        .lines()
        .map(|l| l.parse().unwrap())
        .collect()
}

/// Every process a law started is gone: not running (a zombie left to
/// init, which reaps it, is not running).
fn assert_no_grandchild_runs(dir: &Path, mode: &str) {
    let gc = grandchildren(dir);
    assert!(!gc.is_empty(), "{mode}: the law started nothing");
    for pid in gc {
        if let Some(state) = exists(pid).filter(|s| s != "Z") {
            panic!("{mode}: the law's child {pid} is still there (state {state})");
        }
    }
}

/// Run the law in `mode` on the disk; the error it must end with.
fn fault(mode: &str, extra: &str) -> (String, &'static str, Vec<u32>) {
    fault_in(&tempfile::tempdir().unwrap(), mode, extra)
}

/// [`fault`] in `dir` (kept by the caller, to look at what the law wrote).
fn fault_in(dir: &tempfile::TempDir, mode: &str, extra: &str) -> (String, &'static str, Vec<u32>) {
    let path = disk_with_law(dir.path(), mode, &law_command(mode, dir.path()), extra);
    let prep = Prepared::new(Scenario::load(&path).unwrap()).unwrap();
    let logs = dir.path().join("logs");
    let err = run(&prep, &opts(Some(&logs))).expect_err("the law must fault");
    let Error::Law { run, message, .. } = &err else {
        panic!("{mode}: expected Error::Law, got {err:?}");
    };
    assert_eq!(err.kind(), anholonomy::error::ErrorKind::Runtime);
    // Nothing half-written: the scenario's log directory was never made.
    assert!(!logs.join(mode).exists(), "{mode}: logs written");
    let pids = pids(dir.path());
    assert!(!pids.is_empty(), "{mode}: the law never started");
    for &pid in &pids {
        if let Some(state) = exists(pid) {
            panic!("{mode}: law process {pid} is still there (state {state})");
        }
    }
    // One line, then the stderr tail as `  | ` lines.
    let mut lines = message.lines();
    assert!(lines
        .next()
        .is_some_and(|l| l.contains(mode) || l.contains("the law")));
    assert!(
        lines.all(|l| l.starts_with("  | ")),
        "{mode}: tail lines not indented:\n{message}"
    );
    (message.clone(), run, pids)
}

/// A law that answers without reading its input, sampled every 2 ms for
/// 5 s: the harness blocked for ever writing to its full stdin. Now the
/// answers it sends unasked are a protocol error, at once.
#[test]
fn a_law_that_answers_without_reading_ends_the_run() {
    let t0 = std::time::Instant::now();
    let (m, _, _) = fault("noread", "period = 0.002\nhorizon = 5.0\ntimeout = 2.0");
    // Which sample finds the surplus depends on how fast the law writes.
    // On a loaded machine the law's answers can arrive after its stdin has
    // filled: then the send times out first, and the message says why (the
    // law does not read). Both end the run at once with the cause named.
    let surplus =
        m.contains("a second answer to sample ") && m.contains("(one answer per request)");
    let unread = m.contains("within 2 s (planner.timeout): the law does not read its input");
    assert!(surplus || unread, "{m}");
    assert!(t0.elapsed().as_secs_f64() < 10.0);
}

/// Two answers to one request: a protocol error naming the sample, whether
/// they come in one write or the second a little later (then it is found
/// before the next request is sent, or the one after).
#[test]
fn a_second_answer_to_one_request_is_a_protocol_error() {
    let (m, run, _) = fault("twice", "");
    assert_eq!(run, "ideal");
    assert!(
        m.contains("a second answer to sample 0 (t = 0 s) (one answer per request): `{\"u\": [2.0"),
        "{m}"
    );
    let (m, _, _) = fault("twice_late", "");
    assert!(m.contains("a second answer to sample "), "{m}");
}

/// A law that exits at once while the `sleep 200` it started holds its
/// stdout: its exit is noticed (not "no answer within 2 s"), with its
/// status, and the sleep is ended with it.
#[test]
fn a_law_that_exits_while_its_child_holds_its_pipes() {
    let dir = tempfile::tempdir().unwrap();
    let t0 = std::time::Instant::now();
    let (m, _, _) = fault_in(&dir, "fork_exit", "timeout = 2.0");
    assert!(
        m.contains("the law exited with status 1 before answering sample 0"),
        "{m}"
    );
    assert!(t0.elapsed().as_secs_f64() < 1.9, "{:?}", t0.elapsed());
    assert_no_grandchild_runs(dir.path(), "fork_exit");
}

/// Whatever ends the run (the law's crash, a timeout, a normal end), what
/// the law started ends with it: its process group gets SIGTERM, then
/// SIGKILL (a law that ignores SIGTERM is killed all the same).
#[test]
fn what_a_law_starts_ends_with_its_run() {
    for mode in ["fork_crash", "fork_sleep"] {
        let dir = tempfile::tempdir().unwrap();
        fault_in(&dir, mode, "timeout = 1.0");
        assert_no_grandchild_runs(dir.path(), mode);
    }
    let dir = tempfile::tempdir().unwrap();
    let path = disk_with_law(dir.path(), "g", &law_command("fork_good", dir.path()), "");
    let prep = Prepared::new(Scenario::load(&path).unwrap()).unwrap();
    run(&prep, &opts(None)).unwrap();
    for pid in pids(dir.path()) {
        assert!(exists(pid).is_none(), "law {pid} left behind");
    }
    assert_no_grandchild_runs(dir.path(), "fork_good");
    let t0 = std::time::Instant::now();
    let (m, _, _) = fault("ignore_term", "timeout = 1.0");
    assert!(m.contains("no answer to sample 3"), "{m}");
    assert!(t0.elapsed().as_secs_f64() < 5.0);
}

/// Ctrl-C on the command line: the law, in a group of its own, no longer
/// gets the terminal's SIGINT, so the harness passes it on. The harness
/// dies of the signal, the law and what it started with it.
#[cfg(target_os = "linux")]
#[test]
fn ctrl_c_ends_the_law_and_what_it_started() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    disk_with_law(d, "int", &law_command("fork_sleep", d), "timeout = 60.0");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_anholonomy"))
        .args(["run", "int.toml", "--no-logs", "--quiet"])
        .current_dir(d)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    // The law is asleep (at sample 3) once it has started its child.
    let t0 = std::time::Instant::now();
    while grandchildren(d).is_empty() || pids(d).is_empty() {
        assert!(t0.elapsed().as_secs() < 20, "the law did not start");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    std::thread::sleep(std::time::Duration::from_millis(300));
    unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
    let status = child.wait().unwrap();
    use std::os::unix::process::ExitStatusExt;
    assert_eq!(status.signal(), Some(libc::SIGINT), "{status:?}");
    let t1 = std::time::Instant::now();
    for pid in pids(d).into_iter().chain(grandchildren(d)) {
        // The harness's zombie child is init's to reap now: not running is enough.
        while exists(pid).is_some_and(|s| s != "Z") {
            assert!(t1.elapsed().as_secs() < 2, "{pid} still runs after Ctrl-C");
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
    }
}

#[test]
fn a_law_that_crashes_at_sample_10() {
    let (m, run, _) = fault("crash", "");
    assert_eq!(run, "ideal");
    assert!(
        m.contains("exited with status 1 before answering sample 10 (t = 0.2 s)"),
        "{m}"
    );
    // Python's traceback, last line included.
    assert!(
        m.contains("  | RuntimeError: the law gave up at sample 10"),
        "{m}"
    );
    assert!(m.contains("  | Traceback"), "{m}");
}

#[test]
fn a_law_that_crashes_in_the_physics_run() {
    let (m, run, pids) = fault("crash_second", "");
    assert_eq!(run, "physics");
    assert_eq!(pids.len(), 2, "one process per run");
    assert!(m.contains("before answering sample 10"), "{m}");
}

#[test]
fn a_law_that_sleeps_past_the_timeout() {
    let t0 = std::time::Instant::now();
    let (m, _, _) = fault("sleep", "timeout = 2.0");
    assert!(
        m.contains(
            "no answer to sample 3 (t = 0.06 s) within 2 s (planner.timeout); the law was killed"
        ),
        "{m}"
    );
    // Killed at the timeout, not after its 60 s sleep.
    assert!(t0.elapsed().as_secs_f64() < 30.0);
}

#[test]
fn a_law_with_the_wrong_arity() {
    let (m, _, _) = fault("short", "");
    assert!(
        m.contains("bad answer to sample 0 (t = 0 s): the answer has 1 number in `u`, the model has 2 inputs (theta_rate, alpha_rate); the law was killed"),
        "{m}"
    );
    let (m, _, _) = fault("long", "");
    assert!(
        m.contains("has 3 numbers in `u`, the model has 2 inputs"),
        "{m}"
    );
}

#[test]
fn a_law_that_prints_garbage() {
    let (m, _, _) = fault("garbage", "");
    assert!(
        m.contains("bad answer to sample 2 (t = 0.04 s): the answer is not a JSON object"),
        "{m}"
    );
    assert!(m.contains("`hello, this is not JSON`"), "{m}");
    // What the law wrote to stderr before.
    assert!(m.contains("  | fault_law garbage started"), "{m}");
}

#[test]
fn a_law_that_exits_quietly() {
    let (m, _, _) = fault("exit_quiet", "");
    assert!(
        m.contains("exited with status 0 before answering sample 5"),
        "{m}"
    );
}

#[test]
fn a_program_that_cannot_start() {
    // A file that exists but is not executable: refused up front (exit 2).
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("law.py"), "print('hi')\n").unwrap();
    let path = disk_with_law(dir.path(), "noexec", &["./law.py".to_string()], "");
    let e = Scenario::load(&path).unwrap_err();
    assert_eq!(e.kind(), anholonomy::error::ErrorKind::BadInput);
    assert!(
        e.to_string()
            .contains("key `planner.command`: program is not an executable file"),
        "{e}"
    );
    // Deleted between validation and the run: a runtime failure (exit 3).
    let path = disk_with_law(
        dir.path(),
        "gone",
        &[python(), "-c".into(), "pass".into()],
        "",
    );
    let mut prep = Prepared::new(Scenario::load(&path).unwrap()).unwrap();
    let anholonomy::plan::ControlLaw::Feedback { period, .. } = prep.planned.law else {
        panic!("a feedback plan")
    };
    let program = dir.path().join("no_such_program");
    let params = anholonomy::sources::external::ExternalParams {
        command: vec!["no_such_program".into()],
        period,
        horizon: 1.0,
        timeout: 5.0,
        base: dir.path().into(),
    };
    prep.planned = anholonomy::sources::external::plan(&params, program, &["x"], &["a", "b"]);
    let err = run(&prep, &opts(None)).unwrap_err();
    assert_eq!(err.kind(), anholonomy::error::ErrorKind::Runtime);
    assert!(
        err.to_string().contains("cannot start `no_such_program`"),
        "{err}"
    );
}

/// A law that says `done` ends the ideal run there, and the physics run
/// `settle` later; the labels it named are in the logs.
#[test]
fn done_ends_the_run_and_labels_are_logged() {
    let dir = tempfile::tempdir().unwrap();
    let path = disk_with_law(dir.path(), "done", &law_command("done", dir.path()), "");
    let prep = Prepared::new(Scenario::load(&path).unwrap()).unwrap();
    let logs = dir.path().join("logs");
    let o = run(&prep, &opts(Some(&logs))).unwrap();
    let summary: serde_json::Value =
        serde_json::from_slice(&std::fs::read(logs.join("done/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["ideal"]["end_time_s"], 0.5);
    assert_eq!(
        summary["plan"]["labels"],
        serde_json::json!(["steer", "hold"])
    );
    assert_eq!(summary["ideal"]["final_segment"], "hold");
    assert!(o.steps > 0);
    for pid in pids(dir.path()) {
        assert!(exists(pid).is_none(), "law {pid} left behind");
    }
}

/// The harness sends the same bytes on every run, and the results are
/// identical: determinism as far as the law is deterministic.
#[test]
fn the_stream_is_the_same_on_every_run() {
    let received = |_: usize| -> (Vec<String>, Vec<(String, f64)>) {
        let dir = tempfile::tempdir().unwrap();
        let path = disk_with_law(dir.path(), "good", &law_command("good", dir.path()), "");
        let prep = Prepared::new(Scenario::load(&path).unwrap()).unwrap();
        let o = run(&prep, &opts(None)).unwrap();
        let streams = pids(dir.path())
            .iter()
            .map(|p| std::fs::read_to_string(dir.path().join(format!("received-{p}"))).unwrap())
            .collect();
        (streams, o.metrics)
    };
    let (a, ma) = received(0);
    let (b, mb) = received(1);
    assert_eq!(a.len(), 2, "one process per run");
    assert_eq!(a, b);
    assert_eq!(ma, mb);
    // The first line names the state coordinates, the others do not.
    let first = a[0].lines().next().unwrap();
    assert_eq!(
        first,
        r#"{"t":0.0,"q":[0.0,0.0,0.0,0.0],"names":["x","y","theta","alpha"]}"#
    );
    assert!(a[0].lines().skip(1).all(|l| !l.contains("names")));
    // Samples every period (0.02 s at dt 0.002), horizon 1 s, plus the final state.
    assert_eq!(a[0].lines().count(), 51);
}

/// Through the CLI: a faulting law among other scenarios exits 3 with one
/// error line plus the stderr tail; the other scenarios still run and log,
/// and the faulting one writes nothing.
#[test]
fn a_fault_loses_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let good = disk_with_law(d, "good", &law_command("good", d), "");
    let bad = disk_with_law(d, "bad", &law_command("crash", d), "");
    let file = disk_scenario(&model("rolling_disk.urdf"), "name = \"builtin\"", "");
    std::fs::write(d.join("builtin.toml"), file).unwrap();
    let out = cli(
        d,
        &[
            "run",
            "good.toml",
            "bad.toml",
            "builtin.toml",
            "--logs",
            "logs",
            "--quiet",
        ],
    );
    assert_eq!(out.status.code(), Some(3));
    let stderr = String::from_utf8_lossy(&out.stderr);
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("error: "))
        .collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(
        errors[0].starts_with(&format!(
            "error: {}: feedback law (ideal run): `{} ",
            bad.file_name().unwrap().to_string_lossy(),
            python()
        )),
        "{stderr}"
    );
    assert!(errors[0].contains("before answering sample 10"), "{stderr}");
    // Every other stderr line is the law's stderr tail.
    assert!(
        stderr
            .lines()
            .filter(|l| !l.starts_with("error: "))
            .all(|l| l.starts_with("  | ")),
        "{stderr}"
    );
    assert!(stderr.contains("  | RuntimeError: the law gave up at sample 10"));
    for name in ["good", "builtin"] {
        for f in ["run.mcap", "run.rrd", "summary.json", "series.json"] {
            assert!(d.join("logs").join(name).join(f).is_file(), "{name}/{f}");
        }
    }
    assert!(!d.join("logs/bad").exists());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("good") && stdout.contains("builtin"),
        "{stdout}"
    );
    let _ = good;
}
