//! `[planner] kind = "external"`: a feedback law in another process.
//!
//! The harness starts `command` once per run (the ideal run and the
//! physics run each their own process) in the scenario's directory, and
//! exchanges one line of JSON per control sample ([`protocol`]): every
//! `period` seconds it sends the time and the state and waits up to
//! `timeout` seconds for the input, which it holds until the next sample.
//! The run ends at `horizon`, or when an answer says `done`.
//!
//! A law that cannot start, exits early, answers garbage or the wrong
//! number of inputs, or does not answer in time ends the run as a runtime
//! failure ([`crate::plan::Controller::fault`], exit 3) with one line and
//! the tail of its stderr; the process is always killed and reaped.
//! Whether the program exists and is executable is checked up front, with
//! the scenario (bad input, exit 2).

pub mod process;
pub mod protocol;

use crate::error::SetupError;
use crate::model::{Input, State};
use crate::numfmt::readable;
use crate::plan::{Command, Controller, LabelTable, OncePerSample, Plan, PolicyFactory};
use process::{describe, Failure, LawProcess};
use protocol::Answer;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

/// Default of `timeout`, s.
pub const DEFAULT_TIMEOUT: f64 = 5.0;

fn default_timeout() -> f64 {
    DEFAULT_TIMEOUT
}

/// A feedback law in another process, for any model: asked for the input
/// every `period` with one JSON line (see the external-law protocol).
#[derive(Debug, Clone, Deserialize, Serialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ExternalParams {
    /// Program and arguments, e.g. `["python3", "law.py"]`; run in the
    /// scenario's directory (so relative paths are relative to the scenario).
    /// A program that does not exist or is not executable is bad input.
    pub command: Vec<String>,
    /// Control period, s: the law is asked every `period` and its input held.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub period: f64,
    /// Longest run, s (it ends earlier when the law answers `done`).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub horizon: f64,
    /// Longest wait for one exchange, s: sending the request and receiving
    /// the answer (the first includes the process's start); a law that
    /// does not read or answer in time ends the run (exit 3).
    #[serde(default = "default_timeout")]
    #[schemars(extend("exclusiveMinimum" = 0), range(max = 3600))]
    pub timeout: f64,
    /// The scenario file's directory (set by the scenario layer).
    #[serde(skip)]
    pub base: PathBuf,
}

impl ExternalParams {
    /// The directory the law runs in.
    pub fn dir(&self) -> PathBuf {
        if self.base.as_os_str().is_empty() {
            PathBuf::from(".")
        } else {
            self.base.clone()
        }
    }

    /// Every check that needs no process: numbers, and that the program
    /// exists and is executable. Errors name the key.
    pub fn check(&self) -> Result<PathBuf, SetupError> {
        for (key, v) in [("period", self.period), ("horizon", self.horizon)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(SetupError::key(
                    format!("planner.{key}"),
                    format!("must be a number > 0 s, got {}", readable(v)),
                ));
            }
        }
        if !(self.timeout.is_finite() && self.timeout > 0.0 && self.timeout <= 3600.0) {
            return Err(SetupError::key(
                "planner.timeout",
                format!("must be in (0, 3600] s, got {}", readable(self.timeout)),
            ));
        }
        let Some(program) = self.command.first() else {
            return Err(SetupError::key(
                "planner.command",
                "must name a program, e.g. [\"python3\", \"law.py\"]",
            ));
        };
        if let Some(a) = self.command.iter().find(|a| a.contains('\0')) {
            return Err(SetupError::key(
                "planner.command",
                format!("{} contains a NUL byte", crate::echo::code(a)),
            ));
        }
        resolve_program(program, &self.dir()).map_err(|m| SetupError::key("planner.command", m))
    }
}

/// Whether `p` is a regular file the user may execute.
fn executable(p: &Path) -> bool {
    let Ok(meta) = std::fs::metadata(p) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        meta.is_file() && meta.permissions().mode() & 0o111 != 0
    }
    #[cfg(not(unix))]
    {
        meta.is_file()
    }
}

/// Why an external law's program cannot be started.
#[derive(Debug, thiserror::Error)]
pub enum ProgramError {
    /// `command`'s first word is empty.
    #[error("the program name is empty")]
    Empty,
    /// A path to a file that does not exist.
    #[error("program not found: {}", crate::echo::path(.0))]
    NotFound(PathBuf),
    /// A path to something that is not an executable file.
    #[error(
        "program is not an executable file: {} (for a script, name its interpreter first, e.g. [\"python3\", \"{program}\"])",
        crate::echo::path(path)
    )]
    NotExecutable {
        /// The path, joined to the scenario's directory.
        path: PathBuf,
        /// The program as written.
        program: String,
    },
    /// The path cannot be made absolute.
    #[error("{}: {source}", crate::echo::path(path))]
    Absolute {
        /// The path, joined to the scenario's directory.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// A bare name that no `PATH` directory holds as an executable.
    #[error("program `{0}` not found on PATH")]
    NotOnPath(String),
}

/// The program to start: a path (with a `/`) relative to `dir`, or a name
/// looked up on `PATH` as the shell would.
pub(crate) fn resolve_program(program: &str, dir: &Path) -> Result<PathBuf, ProgramError> {
    if program.is_empty() {
        return Err(ProgramError::Empty);
    }
    if program.contains('/') || program.contains(std::path::MAIN_SEPARATOR) {
        let p = dir.join(program);
        if !p.exists() {
            return Err(ProgramError::NotFound(p));
        }
        if !executable(&p) {
            return Err(ProgramError::NotExecutable {
                path: p,
                program: program.to_string(),
            });
        }
        return std::path::absolute(&p)
            .map_err(|source| ProgramError::Absolute { path: p, source });
    }
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .map(|d| d.join(program))
        .find(|p| executable(p))
        .ok_or_else(|| ProgramError::NotOnPath(program.to_string()))
}

/// What every controller of one law shares.
struct Law {
    program: PathBuf,
    command: Vec<String>,
    dir: PathBuf,
    timeout: Duration,
    state_names: Vec<&'static str>,
    input_names: Vec<&'static str>,
    labels: LabelTable,
}

/// Starts one law process per run.
pub struct ExternalFactory(Arc<Law>);

impl PolicyFactory for ExternalFactory {
    /// One process per run, one after the other (see the trait).
    fn concurrent(&self) -> bool {
        false
    }

    fn start(&self) -> Box<dyn Controller> {
        let law = self.0.clone();
        let (proc, fault) = match LawProcess::start(&law.program, &law.command[1..], &law.dir) {
            Ok(p) => (Some(p), None),
            Err(e) => (
                None,
                Some(format!("cannot start `{}`: {e}", law.command.join(" "))),
            ),
        };
        Box::new(OncePerSample::new(ExternalController {
            m: law.input_names.len(),
            law,
            proc,
            fault,
            sample: 0,
            last_t: 0.0,
            buf: Vec::with_capacity(256),
        }))
    }

    fn labels(&self) -> Option<Vec<String>> {
        Some(self.0.labels.names())
    }
}

/// Why an exchange failed.
enum Why {
    Exited,
    Timeout,
    WriteTimeout,
    /// A second answer to sample (k, t): the line.
    Twice(usize, f64, Vec<u8>),
    Bad(String),
}

/// One run's law process.
pub struct ExternalController {
    law: Arc<Law>,
    proc: Option<LawProcess>,
    fault: Option<String>,
    sample: usize,
    /// Time of the last sample sent.
    last_t: f64,
    m: usize,
    buf: Vec<u8>,
}

impl ExternalController {
    /// The id of the law's process (`None` if it could not start).
    pub fn process_id(&self) -> Option<u32> {
        self.proc.as_ref().map(LawProcess::id)
    }

    /// Record the fault of sample `k` at `t`: the process is stopped (a
    /// law that closed its output gets a second to exit, any other is killed
    /// at once) and its stderr tail appended.
    fn fail(&mut self, k: usize, t: f64, why: Why) -> Command {
        let sample = |k: usize, t: f64| format!("sample {k} (t = {} s)", readable(t));
        let at = sample(k, t);
        let (status, killed, tail) = match self.proc.as_mut() {
            Some(p) => {
                let grace = match why {
                    Why::Exited => Duration::from_secs(1),
                    _ => Duration::ZERO,
                };
                let (status, killed) = p.stop(grace);
                (status, killed, p.stderr_tail())
            }
            None => (None, false, String::new()),
        };
        let killed_note = if killed { "; the law was killed" } else { "" };
        let what = match why {
            Why::Exited => format!("the law {} before answering {at}", describe(status, killed)),
            Why::Timeout => format!(
                "no answer to {at} within {} s (planner.timeout){killed_note}",
                readable(self.law.timeout.as_secs_f64())
            ),
            Why::WriteTimeout => format!(
                "could not send {at} within {} s (planner.timeout): the law does not read its input{killed_note}",
                readable(self.law.timeout.as_secs_f64())
            ),
            Why::Twice(j, tj, line) => format!(
                "a second answer to {} (one answer per request): {}{killed_note}",
                sample(j, tj),
                protocol::quote(&String::from_utf8_lossy(&line))
            ),
            Why::Bad(m) => format!("bad answer to {at}: {m}{killed_note}"),
        };
        self.fault = Some(format!("`{}`: {what}{tail}", self.law.command.join(" ")));
        self.zero()
    }

    fn zero(&self) -> Command {
        Command {
            u: Input::zeros(self.m),
            label: 0,
            done: true,
        }
    }
}

impl Controller for ExternalController {
    fn command(&mut self, t: f64, q: &State) -> Command {
        if self.fault.is_some() {
            return self.zero();
        }
        let k = self.sample;
        self.sample += 1;
        let last_t = std::mem::replace(&mut self.last_t, t);
        let Some(proc) = self.proc.as_mut() else {
            return self.zero();
        };
        self.buf.clear();
        let names = (k == 0).then_some(self.law.state_names.as_slice());
        protocol::write_request(&mut self.buf, t, q.as_slice(), names);
        let timeout = self.law.timeout;
        match proc.exchange(&self.buf, timeout) {
            Ok(line) => match Answer::parse(&line, &self.law.input_names)
                .and_then(|a| a.command(&self.law.labels))
            {
                Ok(c) => c,
                Err(m) => self.fail(k, t, Why::Bad(m.to_string())),
            },
            Err(Failure::Exited) => self.fail(k, t, Why::Exited),
            Err(Failure::Timeout) => self.fail(k, t, Why::Timeout),
            Err(Failure::WriteTimeout) => self.fail(k, t, Why::WriteTimeout),
            Err(Failure::Extra(line)) if k == 0 => {
                let m = format!(
                    "the law wrote {} before it was asked anything (one answer per request)",
                    protocol::quote(&String::from_utf8_lossy(&line))
                );
                self.fail(k, t, Why::Bad(m))
            }
            Err(Failure::Extra(line)) => self.fail(k, t, Why::Twice(k - 1, last_t, line)),
            Err(Failure::Line(m)) => self.fail(k, t, Why::Bad(m)),
        }
    }

    fn fault(&self) -> Option<String> {
        self.fault.clone()
    }
}

/// The plan: `params`' law for a model with these state and input names.
/// `program` is the resolved program ([`ExternalParams::check`]).
pub fn plan(
    params: &ExternalParams,
    program: PathBuf,
    state_names: &[&'static str],
    input_names: &[&'static str],
) -> Plan {
    let law = Law {
        program,
        command: params.command.clone(),
        dir: params.dir(),
        timeout: Duration::from_secs_f64(params.timeout),
        state_names: state_names.to_vec(),
        input_names: input_names.to_vec(),
        labels: LabelTable::default(),
    };
    let details = serde_json::json!({
        "command": params.command,
        "period_s": params.period,
        "timeout_s": params.timeout,
    });
    Plan::feedback(
        Vec::new(),
        Arc::new(ExternalFactory(Arc::new(law))),
        params.period,
        params.horizon,
        details,
    )
}
