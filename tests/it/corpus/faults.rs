//! Held-out fault cases of issue 37 that are not bad input: external laws
//! that misbehave at run time, margin searches asked for an absurd
//! resolution, inputs of 1e300 that run. Each must end within the corpus's
//! time limit with its exit code (0, 2 for an argument error, 3 for a
//! runtime failure) and message, print no number in 20 digits or more,
//! never panic, and leave no process behind (the laws write their pid, and
//! what they start writes its own, into the case's directory).

use super::*;

/// One fault case: files in a fresh directory, the arguments of one call.
pub struct FaultCase {
    pub name: String,
    pub files: Vec<(String, Vec<u8>)>,
    /// Symbolic links (link, target) made in the directory.
    pub symlinks: Vec<(String, String)>,
    pub args: Vec<String>,
    /// Expected exit code.
    pub code: i32,
    /// Each must appear in stderr.
    pub stderr_has: Vec<String>,
    /// One of these must appear in stderr (when any are given).
    pub stderr_any: Vec<String>,
    /// Each must appear in stdout.
    pub stdout_has: Vec<String>,
    /// stderr is exactly one `error: ` line.
    pub one_line: bool,
}

fn fault_law() -> String {
    root().join("tests/data/fault_law.py").display().to_string()
}

/// A disk scenario whose planner is `tests/data/fault_law.py MODE .`.
fn law_scenario(mode: &str, planner_keys: &str) -> String {
    edit(
        &disk(),
        "kind = \"stokes_disk\"",
        &format!(
            "kind = \"external\"\ncommand = [\"python3\", \"{}\", \"{mode}\", \".\"]\n{planner_keys}",
            fault_law()
        ),
    )
}

fn args(a: &[&str]) -> Vec<String> {
    a.iter().map(|s| s.to_string()).collect()
}

fn strings(a: &[&str]) -> Vec<String> {
    args(a)
}

pub fn cases() -> Vec<FaultCase> {
    let mut out = Vec::new();
    let run = |name: &str, text: String, code: i32, has: &[&str]| FaultCase {
        name: name.into(),
        files: vec![("case.toml".into(), text.into_bytes())],
        symlinks: Vec::new(),
        args: args(&["run", "case.toml", "--no-logs", "--quiet"]),
        code,
        stderr_has: strings(has),
        stderr_any: Vec::new(),
        stdout_has: Vec::new(),
        one_line: false,
    };
    let short = "period = 0.02\nhorizon = 1.0\ntimeout = 1.0";
    // Laws that hung the harness or were misread.
    // Its answers pile up unasked (found before the next request is sent)
    // or, on a machine slow enough that none has arrived yet, fill its
    // stdin until a request cannot be sent: exit 3 either way, never a hang.
    let mut c = run(
        "law answers without reading, 2 ms for 5 s",
        law_scenario("noread", "period = 0.002\nhorizon = 5.0\ntimeout = 2.0"),
        3,
        &["noread", "the law was killed"],
    );
    c.stderr_any = strings(&[
        "(one answer per request)",
        "the law does not read its input",
    ]);
    out.push(c);
    out.push(run(
        "law never reads: its stdin fills",
        law_scenario(
            "noread_paced",
            "period = 0.02\nhorizon = 5.0\ntimeout = 1.0",
        ),
        3,
        &["could not send sample ", "the law does not read its input"],
    ));
    out.push(run(
        "law answers twice",
        law_scenario("twice", short),
        3,
        &["a second answer to sample 0 (t = 0 s)"],
    ));
    out.push(run(
        "law exits while its child holds stdout",
        law_scenario("fork_exit", short),
        3,
        &["the law exited with status 1 before answering sample 0"],
    ));
    out.push(run(
        "law starts a child and ends normally",
        law_scenario("fork_good", short),
        0,
        &[],
    ));
    out.push(run(
        "law starts a child and sleeps past the timeout",
        law_scenario("fork_sleep", short),
        3,
        &["no answer to sample 3 (t = 0.06 s) within 1 s (planner.timeout); the law was killed"],
    ));
    out.push(run(
        "law starts a child and crashes",
        law_scenario("fork_crash", short),
        3,
        &["the law exited with status 1 before answering sample 10"],
    ));
    out.push(run(
        "law ignores SIGTERM",
        law_scenario("ignore_term", short),
        3,
        &["no answer to sample 3"],
    ));
    // Inputs of 1e300 that run: the table prints them readably.
    let mut big_plan = run(
        "plan file commands of 1e300",
        edit(
            &disk(),
            "kind = \"stokes_disk\"",
            "kind = \"file\"\npath = \"p.csv\"",
        ),
        0,
        &[],
    );
    big_plan.files.push((
        "p.csv".into(),
        b"t,theta_rate,alpha_rate\n0,1e300,0.1\n1,1e300,0.1\n".to_vec(),
    ));
    big_plan.stdout_has = strings(&["e299"]);
    out.push(big_plan);
    let mut bom = run(
        "plan file with a UTF-8 BOM",
        edit(
            &disk(),
            "kind = \"stokes_disk\"",
            "kind = \"file\"\npath = \"p.csv\"",
        ),
        0,
        &[],
    );
    bom.files.push((
        "p.csv".into(),
        b"\xef\xbb\xbft,theta_rate,alpha_rate\n0,0.1,0.1\n1,0.1,0.1\n".to_vec(),
    ));
    out.push(bom);

    // Margin searches that looped for ever.
    let d = shipped("disk_paper.toml");
    let margin = |name: &str, extra: &[&str], code: i32, has: &[&str]| {
        let mut a = args(&[
            "margin",
            "case.toml",
            "--dimension",
            "friction_scale",
            "--no-logs",
            "--quiet",
        ]);
        a.extend(args(extra));
        FaultCase {
            name: name.into(),
            files: vec![("case.toml".into(), d.clone().into_bytes())],
            symlinks: Vec::new(),
            args: a,
            code,
            stderr_has: strings(has),
            stderr_any: Vec::new(),
            stdout_has: Vec::new(),
            one_line: code == 2,
        }
    };
    let mut c = margin(
        "margin --resolution 1e-300",
        &["--resolution", "1e-300"],
        0,
        &[],
    );
    c.stdout_has = strings(&["friction_scale"]);
    out.push(c);
    out.push(margin(
        "margin --resolution 1e-300 --max-runs 200",
        &["--resolution", "1e-300", "--max-runs", "200"],
        0,
        &[],
    ));
    let mut c = margin(
        "margin --resolution 1e-300 --max-runs 30",
        &["--resolution", "1e-300", "--max-runs", "30"],
        0,
        &[],
    );
    c.stdout_has = strings(&["run budget (30 runs) spent"]);
    out.push(c);
    let gated = edit(
        &d,
        "[thresholds]",
        "[margins]\nfriction_scale = 0.1\nresolution = 1e-300\n\n[thresholds]",
    );
    let mut c = margin("[margins] resolution = 1e-300", &[], 0, &[]);
    c.files = vec![("case.toml".into(), gated.clone().into_bytes())];
    out.push(c);
    out.push(FaultCase {
        name: "check with [margins] resolution = 1e-300".into(),
        files: vec![("case.toml".into(), gated.into_bytes())],
        symlinks: Vec::new(),
        args: args(&["check", "case.toml", "--no-logs", "--quiet"]),
        code: 0,
        stderr_has: Vec::new(),
        stderr_any: Vec::new(),
        stdout_has: strings(&["friction_scale holds at 0.1 (×0.9)"]),
        one_line: false,
    });
    // Argument errors: one line naming the value.
    out.push(margin(
        "margin --max-runs -1",
        &["--max-runs", "-1"],
        2,
        &["error: --max-runs: -1: must be in 1..=100000"],
    ));
    out.push(margin(
        "margin --resolution -0.1",
        &["--resolution", "-0.1"],
        2,
        &["error: --resolution: -0.1: must be in (0, 1]"],
    ));
    out.push(margin(
        "margin --markdown --json",
        &["--markdown", "--json"],
        2,
        &["error: the argument '--markdown' cannot be used with '--json'"],
    ));
    out.extend(super::surfaces::faults());
    out
}
