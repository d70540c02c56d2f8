//! One external law process: started once per run, spoken to one line per
//! control sample, always killed and reaped when the run ends.
//!
//! Two reader threads keep the pipes drained: stdout's lines go through a
//! channel the harness waits on with a timeout (so a law that hangs cannot
//! hang the run), stderr's bytes into a bounded tail shown when the law
//! fails. The threads end when the process's pipes close.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Longest answer line, bytes.
pub const MAX_LINE_BYTES: usize = 1 << 20;
/// Bytes of stderr kept for the failure message.
const TAIL_BYTES: usize = 16 << 10;
/// Lines of stderr shown in a failure message.
const TAIL_LINES: usize = 12;
/// Longest stderr line shown, characters.
const TAIL_LINE_CHARS: usize = 240;
/// How long a law may take to exit after its stdin closes, before it is killed.
const EXIT_GRACE: Duration = Duration::from_millis(250);
/// How long the stderr tail may take to arrive after the process is gone.
const STDERR_GRACE: Duration = Duration::from_millis(500);

/// A running law.
pub struct LawProcess {
    child: Child,
    stdin: Option<ChildStdin>,
    lines: Receiver<Result<Vec<u8>, String>>,
    stderr: Arc<Mutex<VecDeque<u8>>>,
    stderr_done: Receiver<()>,
    reaped: Option<ExitStatus>,
}

/// Why an exchange failed (the caller adds which sample it was).
pub enum Failure {
    /// The process closed its stdout or stdin: it exited or is exiting.
    Exited,
    /// No answer within the timeout.
    Timeout,
    /// An unusable line (too long, unreadable).
    Line(String),
}

impl LawProcess {
    /// Start `program` with `args` in `dir`.
    pub fn start(program: &Path, args: &[String], dir: &Path) -> std::io::Result<LawProcess> {
        let mut child = Command::new(program)
            .args(args)
            .current_dir(dir)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()?;
        let stdin = child.stdin.take();
        let stdout = child.stdout.take();
        let stderr_pipe = child.stderr.take();
        let (tx, lines) = mpsc::channel();
        if let Some(out) = stdout {
            std::thread::Builder::new()
                .name("law-stdout".into())
                .spawn(move || {
                    let mut r = BufReader::with_capacity(64 << 10, out);
                    loop {
                        let mut line = Vec::new();
                        let n = match r
                            .by_ref()
                            .take(MAX_LINE_BYTES as u64 + 1)
                            .read_until(b'\n', &mut line)
                        {
                            Ok(n) => n,
                            Err(e) => {
                                let _ = tx.send(Err(format!("cannot read its output: {e}")));
                                return;
                            }
                        };
                        if n == 0 {
                            return;
                        }
                        if line.last() != Some(&b'\n') && line.len() > MAX_LINE_BYTES {
                            let _ = tx.send(Err(format!(
                                "an answer line is longer than {MAX_LINE_BYTES} bytes"
                            )));
                            return;
                        }
                        if line.last() == Some(&b'\n') {
                            line.pop();
                        }
                        if line.last() == Some(&b'\r') {
                            line.pop();
                        }
                        if tx.send(Ok(line)).is_err() {
                            return;
                        }
                    }
                })?;
        }
        let stderr = Arc::new(Mutex::new(VecDeque::new()));
        let (done_tx, stderr_done) = mpsc::channel();
        if let Some(mut err) = stderr_pipe {
            let tail = stderr.clone();
            std::thread::Builder::new()
                .name("law-stderr".into())
                .spawn(move || {
                    let mut buf = [0u8; 4096];
                    while let Ok(n) = err.read(&mut buf) {
                        if n == 0 {
                            break;
                        }
                        let mut t = tail.lock().unwrap_or_else(|e| e.into_inner());
                        t.extend(&buf[..n]);
                        let excess = t.len().saturating_sub(TAIL_BYTES);
                        t.drain(..excess);
                    }
                    let _ = done_tx.send(());
                })?;
        }
        Ok(LawProcess {
            child,
            stdin,
            lines,
            stderr,
            stderr_done,
            reaped: None,
        })
    }

    /// Send `request` (one line) and wait up to `timeout` for the answer line.
    pub fn exchange(&mut self, request: &[u8], timeout: Duration) -> Result<Vec<u8>, Failure> {
        let Some(stdin) = self.stdin.as_mut() else {
            return Err(Failure::Exited);
        };
        // A closed pipe means the process is gone (SIGPIPE is ignored in Rust programs).
        if stdin
            .write_all(request)
            .and_then(|_| stdin.flush())
            .is_err()
        {
            return Err(Failure::Exited);
        }
        match self.lines.recv_timeout(timeout) {
            Ok(Ok(line)) => Ok(line),
            Ok(Err(m)) => Err(Failure::Line(m)),
            Err(RecvTimeoutError::Timeout) => Err(Failure::Timeout),
            Err(RecvTimeoutError::Disconnected) => Err(Failure::Exited),
        }
    }

    /// Wait up to `grace` for the process to exit by itself, then kill it;
    /// always reaped. The exit status, and whether it had to be killed.
    pub fn stop(&mut self, grace: Duration) -> (Option<ExitStatus>, bool) {
        if let Some(s) = self.reaped {
            return (Some(s), false);
        }
        // EOF on its stdin: a well-behaved law exits by itself.
        self.stdin = None;
        let t0 = Instant::now();
        loop {
            match self.child.try_wait() {
                Ok(Some(s)) => {
                    self.reaped = Some(s);
                    return (Some(s), false);
                }
                Ok(None) if t0.elapsed() < grace => std::thread::sleep(Duration::from_millis(1)),
                _ => break,
            }
        }
        let _ = self.child.kill();
        let status = self.child.wait().ok();
        self.reaped = status;
        (status, true)
    }

    /// The process id (for tests that check it is gone).
    pub fn id(&self) -> u32 {
        self.child.id()
    }

    /// The end of what the process wrote to stderr, as message lines
    /// (`\n  | ...`); empty when it wrote nothing. Waits briefly for the
    /// pipe to close, so a crashing law's last words are included.
    pub fn stderr_tail(&self) -> String {
        let _ = self.stderr_done.recv_timeout(STDERR_GRACE);
        let bytes: Vec<u8> = self
            .stderr
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .iter()
            .copied()
            .collect();
        format_tail(&String::from_utf8_lossy(&bytes))
    }
}

/// The last lines of `text`, each indented as `\n  | line`.
pub fn format_tail(text: &str) -> String {
    let lines: Vec<&str> = text.lines().filter(|l| !l.trim().is_empty()).collect();
    let skip = lines.len().saturating_sub(TAIL_LINES);
    let mut out = String::new();
    if skip > 0 {
        out.push_str(&format!("\n  | ... ({skip} earlier stderr lines)"));
    }
    for l in &lines[skip..] {
        let l: String = l.chars().take(TAIL_LINE_CHARS).collect();
        out.push_str("\n  | ");
        out.push_str(&l);
    }
    out
}

impl Drop for LawProcess {
    fn drop(&mut self) {
        self.stop(EXIT_GRACE);
    }
}

/// How a process ended, for messages.
pub fn describe(status: Option<ExitStatus>, killed: bool) -> String {
    match status {
        _ if killed => "was killed".into(),
        Some(s) => match s.code() {
            Some(c) => format!("exited with status {c}"),
            None => {
                #[cfg(unix)]
                {
                    use std::os::unix::process::ExitStatusExt;
                    if let Some(sig) = s.signal() {
                        return format!("was killed by signal {sig}");
                    }
                }
                format!("ended ({s})")
            }
        },
        None => "ended".into(),
    }
}
