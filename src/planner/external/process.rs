//! One external law process: started once per run, spoken to one line per
//! control sample, always killed and reaped when the run ends.
//!
//! The answer is read on the run's own thread, waiting with `poll(2)` up
//! to the timeout (so a law that hangs cannot hang the run, and a round
//! trip wakes two threads, the law's and the run's: a reader thread handing
//! lines over a channel made it three, 30 % slower on a loaded machine).
//! Elsewhere than on Unix a reader thread does it. A second thread drains
//! stderr into a bounded tail, shown when the law fails; it ends when the
//! process's stderr closes.

use std::collections::VecDeque;
use std::io::{BufRead, BufReader, Read, Write};
use std::path::Path;
use std::process::{Child, ChildStdin, ChildStdout, Command, ExitStatus, Stdio};
use std::sync::mpsc::{self, Receiver};
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
    lines: Lines,
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
        let lines = match child.stdout.take() {
            Some(out) => Lines::new(out)?,
            None => return Err(std::io::Error::other("no stdout pipe")),
        };
        let stderr_pipe = child.stderr.take();
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
        self.lines.next(timeout)
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

/// The law's stdout, split into lines.
#[cfg(unix)]
struct Lines {
    out: BufReader<ChildStdout>,
}

#[cfg(unix)]
impl Lines {
    fn new(out: ChildStdout) -> std::io::Result<Lines> {
        Ok(Lines {
            out: BufReader::with_capacity(64 << 10, out),
        })
    }

    /// The next line (without its line break), waiting up to `timeout`.
    fn next(&mut self, timeout: Duration) -> Result<Vec<u8>, Failure> {
        use std::os::fd::AsRawFd;
        let deadline = Instant::now() + timeout;
        let mut line = Vec::new();
        loop {
            let buf = self.out.buffer();
            if let Some(i) = buf.iter().position(|&b| b == b'\n') {
                line.extend_from_slice(&buf[..i]);
                self.out.consume(i + 1);
                if line.last() == Some(&b'\r') {
                    line.pop();
                }
                return Ok(line);
            }
            line.extend_from_slice(buf);
            let n = buf.len();
            self.out.consume(n);
            if line.len() > MAX_LINE_BYTES {
                return Err(Failure::Line(format!(
                    "an answer line is longer than {MAX_LINE_BYTES} bytes"
                )));
            }
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(Failure::Timeout);
            }
            let mut fd = libc::pollfd {
                fd: self.out.get_ref().as_raw_fd(),
                events: libc::POLLIN,
                revents: 0,
            };
            // Whole milliseconds, rounded up (0 would not wait at all).
            let ms = left.as_micros().div_ceil(1000).min(i32::MAX as u128) as libc::c_int;
            // SAFETY: one valid pollfd, for the duration of the call.
            let ready = unsafe { libc::poll(&mut fd, 1, ms) };
            if ready < 0 {
                let e = std::io::Error::last_os_error();
                if e.kind() == std::io::ErrorKind::Interrupted {
                    continue;
                }
                return Err(Failure::Line(format!("cannot wait for its output: {e}")));
            }
            if ready == 0 {
                continue;
            }
            // Readable (or closed): this read does not block.
            match self.out.fill_buf() {
                Ok([]) => return Err(Failure::Exited),
                Ok(_) => {}
                Err(e) => return Err(Failure::Line(format!("cannot read its output: {e}"))),
            }
        }
    }
}

/// The law's stdout, split into lines by a reader thread.
#[cfg(not(unix))]
struct Lines(Receiver<Result<Vec<u8>, String>>);

#[cfg(not(unix))]
impl Lines {
    fn new(out: ChildStdout) -> std::io::Result<Lines> {
        let (tx, rx) = mpsc::channel();
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
        Ok(Lines(rx))
    }

    fn next(&mut self, timeout: Duration) -> Result<Vec<u8>, Failure> {
        use std::sync::mpsc::RecvTimeoutError;
        match self.0.recv_timeout(timeout) {
            Ok(Ok(line)) => Ok(line),
            Ok(Err(m)) => Err(Failure::Line(m)),
            Err(RecvTimeoutError::Timeout) => Err(Failure::Timeout),
            Err(RecvTimeoutError::Disconnected) => Err(Failure::Exited),
        }
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
