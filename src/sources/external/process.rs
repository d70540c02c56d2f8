//! One external law process: started once per run, spoken to one line per
//! control sample, always stopped and reaped when the run ends.
//!
//! The request is written and the answer read on the run's own thread,
//! both bounded by the timeout: the law's stdin is non-blocking and waited
//! on with `poll(2)` (a law that does not read its input cannot block the
//! run on a full pipe), and so is its stdout (a law that hangs cannot hang
//! the run; a round trip wakes two threads, the law's and the run's: a
//! reader thread handing lines over a channel made it three, 30 % slower
//! on a loaded machine). Elsewhere than on Unix a reader thread does it.
//! A second thread drains stderr into a bounded tail, shown when the law
//! fails; it ends when the process's stderr closes.
//!
//! On Unix the law runs in a **process group** of its own. When its run
//! ends, for any reason, whatever is left of the group (the law, and what
//! it started: a `sleep 200` in the background) gets SIGTERM, then SIGKILL
//! after [`TERM_GRACE`], and the law is reaped. While waiting for an
//! answer the harness also watches the law itself, so a law that exits
//! while a child of its keeps its stdout open is reported with its exit
//! status at once, not as a timeout. Anything on its stdout before a
//! request is sent is a second answer to the previous one: a protocol
//! error ([`Failure::Extra`]).

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
/// How long what is left of a law's process group has between SIGTERM and SIGKILL.
pub const TERM_GRACE: Duration = Duration::from_millis(200);
/// While waiting for an answer, how often the law itself is checked for an
/// exit (its stdout may be held open by a child it started).
#[cfg(unix)]
const EXIT_CHECK: Duration = Duration::from_millis(20);
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
    /// The request could not be written within the timeout: the law does
    /// not read its input.
    WriteTimeout,
    /// A line arrived before the request was sent: a second answer to the
    /// previous request.
    Extra(Vec<u8>),
    /// An unusable line (too long, unreadable).
    Line(String),
}

impl LawProcess {
    /// Start `program` with `args` in `dir`.
    pub fn start(program: &Path, args: &[String], dir: &Path) -> std::io::Result<LawProcess> {
        let mut cmd = Command::new(program);
        cmd.args(args)
            .current_dir(dir)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        #[cfg(unix)]
        {
            // A group of its own: the run's end reaches whatever it started.
            use std::os::unix::process::CommandExt;
            cmd.process_group(0);
        }
        let mut child = cmd.spawn()?;
        #[cfg(unix)]
        on_signal::register(child.id());
        let stdin = child.stdin.take();
        #[cfg(unix)]
        if let Some(w) = &stdin {
            // Writes wait in `poll`, up to the timeout, never in `write`.
            use std::os::fd::AsRawFd;
            set_nonblocking(w.as_raw_fd())?;
        }
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

    /// Send `request` (one line) and wait for the answer line, both within
    /// `timeout`. A line already waiting before the request is sent is a
    /// second answer to the previous request ([`Failure::Extra`]).
    pub fn exchange(&mut self, request: &[u8], timeout: Duration) -> Result<Vec<u8>, Failure> {
        let deadline = Instant::now() + timeout;
        if let Some(extra) = self.lines.pending()? {
            return Err(Failure::Extra(extra));
        }
        let Some(stdin) = self.stdin.as_mut() else {
            return Err(Failure::Exited);
        };
        write_within(stdin, request, deadline)?;
        let pid = self.child.id();
        self.lines.next(deadline, &|| exited(pid))
    }

    /// Wait up to `grace` for the process to exit by itself, then end what
    /// is left of its process group (SIGTERM, SIGKILL after
    /// [`TERM_GRACE`]); the law is always reaped. The exit status, and
    /// whether the law itself had to be killed.
    pub fn stop(&mut self, grace: Duration) -> (Option<ExitStatus>, bool) {
        if let Some(s) = self.reaped {
            return (Some(s), false);
        }
        // EOF on its stdin: a well-behaved law exits by itself.
        self.stdin = None;
        let pid = self.child.id();
        let t0 = Instant::now();
        while !self.has_exited() && t0.elapsed() < grace {
            std::thread::sleep(Duration::from_millis(1));
        }
        let by_itself = self.has_exited();
        // On Linux the law is not reaped yet, so its pid (the group's id)
        // cannot be reused while the group is signalled.
        end_group(pid);
        #[cfg(unix)]
        on_signal::unregister(pid);
        if !self.has_exited() {
            // It left its group (setsid): killed on its own.
            let _ = self.child.kill();
        }
        let status = match self.reaped {
            Some(s) => Some(s),
            None => self.child.wait().ok(),
        };
        self.reaped = status;
        (status, !by_itself)
    }

    /// Whether the law has exited. On Linux without reaping it
    /// ([`exited`]); elsewhere it is reaped here (`try_wait`).
    fn has_exited(&mut self) -> bool {
        if self.reaped.is_some() {
            return true;
        }
        if cfg!(target_os = "linux") {
            return exited(self.child.id());
        }
        match self.child.try_wait() {
            Ok(Some(s)) => {
                self.reaped = Some(s);
                true
            }
            Ok(None) => false,
            Err(_) => true,
        }
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

/// Wait up to `ms` for `events` on `fd`: Ok(true) when ready (or closed).
#[cfg(unix)]
fn wait_fd(
    fd: std::os::fd::RawFd,
    events: libc::c_short,
    ms: libc::c_int,
) -> std::io::Result<bool> {
    let mut p = libc::pollfd {
        fd,
        events,
        revents: 0,
    };
    loop {
        // SAFETY: one valid pollfd, for the duration of the call.
        let ready = unsafe { libc::poll(&mut p, 1, ms) };
        if ready >= 0 {
            return Ok(ready > 0);
        }
        let e = std::io::Error::last_os_error();
        if e.kind() != std::io::ErrorKind::Interrupted {
            return Err(e);
        }
    }
}

/// Whole milliseconds of `left`, rounded up (0 would not wait at all), at most `cap`.
#[cfg(unix)]
fn millis(left: Duration, cap: Duration) -> libc::c_int {
    left.min(cap)
        .as_micros()
        .div_ceil(1000)
        .min(i32::MAX as u128) as libc::c_int
}

#[cfg(unix)]
fn set_nonblocking(fd: std::os::fd::RawFd) -> std::io::Result<()> {
    // SAFETY: fcntl on a descriptor this process owns.
    let flags = unsafe { libc::fcntl(fd, libc::F_GETFL) };
    if flags < 0 || unsafe { libc::fcntl(fd, libc::F_SETFL, flags | libc::O_NONBLOCK) } < 0 {
        return Err(std::io::Error::last_os_error());
    }
    Ok(())
}

/// Write all of `buf` to the (non-blocking) law's stdin by `deadline`.
#[cfg(unix)]
fn write_within(w: &mut ChildStdin, mut buf: &[u8], deadline: Instant) -> Result<(), Failure> {
    use std::os::fd::AsRawFd;
    while !buf.is_empty() {
        match w.write(buf) {
            Ok(0) => return Err(Failure::Exited),
            Ok(n) => buf = &buf[n..],
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                let left = deadline.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    return Err(Failure::WriteTimeout);
                }
                wait_fd(w.as_raw_fd(), libc::POLLOUT, millis(left, left))
                    .map_err(|e| Failure::Line(format!("cannot wait for its input: {e}")))?;
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            // A closed pipe means the process is gone (SIGPIPE is ignored in Rust programs).
            Err(_) => return Err(Failure::Exited),
        }
    }
    Ok(())
}

#[cfg(not(unix))]
fn write_within(w: &mut ChildStdin, buf: &[u8], _deadline: Instant) -> Result<(), Failure> {
    w.write_all(buf)
        .and_then(|_| w.flush())
        .map_err(|_| Failure::Exited)
}

/// Whether process `pid` (a child of this one) has exited, without reaping
/// it: its pid stays taken, so its process group can still be signalled.
#[cfg(target_os = "linux")]
fn exited(pid: u32) -> bool {
    // SAFETY: a zeroed siginfo_t is valid; waitid fills it.
    let mut info: libc::siginfo_t = unsafe { std::mem::zeroed() };
    let r = unsafe {
        libc::waitid(
            libc::P_PID,
            pid as libc::id_t,
            &mut info,
            libc::WEXITED | libc::WNOHANG | libc::WNOWAIT,
        )
    };
    // ECHILD: reaped already.
    r != 0 || unsafe { info.si_pid() } != 0
}

/// Elsewhere the run notices the law's exit only when its stdout closes
/// (or at the timeout); [`LawProcess::stop`] reaps with `try_wait`.
#[cfg(not(target_os = "linux"))]
fn exited(_pid: u32) -> bool {
    false
}

/// Whether any process of group `pgid` still runs (zombies, which only
/// wait to be reaped, do not count).
#[cfg(target_os = "linux")]
pub(crate) fn group_alive(pgid: u32) -> bool {
    let Ok(dir) = std::fs::read_dir("/proc") else {
        return true;
    };
    dir.flatten()
        .filter(|e| {
            e.file_name()
                .to_string_lossy()
                .bytes()
                .all(|b| b.is_ascii_digit())
        })
        .filter_map(|e| std::fs::read_to_string(e.path().join("stat")).ok())
        .any(|stat| {
            // After the parenthesised name: state, ppid, pgrp.
            let mut f = stat.rsplit(')').next().unwrap_or("").split_whitespace();
            let state = f.next().unwrap_or("Z");
            let pgrp = f.nth(1).and_then(|x| x.parse::<u32>().ok());
            pgrp == Some(pgid) && state != "Z" && state != "X"
        })
}

/// Elsewhere: whether any process of the group exists (`kill(-pgid, 0)`;
/// an unreaped zombie counts, so the grace period may be waited out).
#[cfg(all(unix, not(target_os = "linux")))]
pub(crate) fn group_alive(pgid: u32) -> bool {
    // SAFETY: signal 0 only checks that the group has a member.
    unsafe { libc::kill(-(pgid as libc::pid_t), 0) == 0 }
}

/// SIGTERM to what still runs of group `pgid`, then SIGKILL after
/// [`TERM_GRACE`] if anything of it is left.
#[cfg(unix)]
fn end_group(pgid: u32) {
    if !group_alive(pgid) {
        return;
    }
    let group = -(pgid as libc::pid_t);
    // SAFETY: signals to a process group this process created.
    unsafe { libc::kill(group, libc::SIGTERM) };
    let t0 = Instant::now();
    while t0.elapsed() < TERM_GRACE {
        std::thread::sleep(Duration::from_millis(5));
        if !group_alive(pgid) {
            return;
        }
    }
    unsafe { libc::kill(group, libc::SIGKILL) };
}

#[cfg(not(unix))]
fn end_group(_pgid: u32) {}

/// The process groups of the laws running now, for a harness killed by a
/// signal (Ctrl-C): a law in a group of its own no longer gets the
/// terminal's SIGINT, so the harness passes it on. Lock-free slots, read
/// by the handler (only async-signal-safe calls there).
#[cfg(unix)]
pub mod on_signal {
    use std::sync::atomic::{AtomicU32, Ordering};

    static GROUPS: [AtomicU32; 256] = [const { AtomicU32::new(0) }; 256];

    /// Track group `pgid` (best effort: untracked when every slot is taken).
    pub fn register(pgid: u32) {
        for g in &GROUPS {
            if g.compare_exchange(0, pgid, Ordering::SeqCst, Ordering::SeqCst)
                .is_ok()
            {
                return;
            }
        }
    }

    /// Stop tracking group `pgid` (it was ended).
    pub fn unregister(pgid: u32) {
        for g in &GROUPS {
            if g.compare_exchange(pgid, 0, Ordering::SeqCst, Ordering::SeqCst)
                .is_ok()
            {
                return;
            }
        }
    }

    fn signal_all(sig: libc::c_int) -> bool {
        let mut any = false;
        for g in &GROUPS {
            let pgid = g.load(Ordering::SeqCst);
            if pgid != 0 {
                // SAFETY: kill(2) is async-signal-safe.
                unsafe { libc::kill(-(pgid as libc::pid_t), sig) };
                any = true;
            }
        }
        any
    }

    extern "C" fn handler(sig: libc::c_int) {
        if signal_all(libc::SIGTERM) {
            let grace = libc::timespec {
                tv_sec: 0,
                tv_nsec: super::TERM_GRACE.as_nanos() as libc::c_long,
            };
            // SAFETY: nanosleep and kill are async-signal-safe.
            unsafe { libc::nanosleep(&grace, std::ptr::null_mut()) };
            signal_all(libc::SIGKILL);
        }
        // Then die of the signal, as without the handler.
        // SAFETY: signal and raise are async-signal-safe.
        unsafe {
            libc::signal(sig, libc::SIG_DFL);
            libc::raise(sig);
        }
    }

    /// End every running law's group (SIGTERM, SIGKILL after the grace
    /// period) when this process gets SIGINT, SIGTERM or SIGHUP, then die
    /// of that signal. For the command line; a host with its own signal
    /// handling (Python) cancels its runs instead, which ends their laws.
    pub fn install() {
        for sig in [libc::SIGINT, libc::SIGTERM, libc::SIGHUP] {
            // SAFETY: installs a handler that only makes async-signal-safe calls.
            unsafe { libc::signal(sig, handler as *const () as libc::sighandler_t) };
        }
    }
}

#[cfg(unix)]
impl Lines {
    fn new(out: ChildStdout) -> std::io::Result<Lines> {
        Ok(Lines {
            out: BufReader::with_capacity(64 << 10, out),
        })
    }

    /// A line already on the pipe before a request is sent (the start of
    /// one is enough): Err(Exited) when the pipe closed instead.
    fn pending(&mut self) -> Result<Option<Vec<u8>>, Failure> {
        use std::os::fd::AsRawFd;
        if self.out.buffer().is_empty() {
            let fd = self.out.get_ref().as_raw_fd();
            let ready = wait_fd(fd, libc::POLLIN, 0)
                .map_err(|e| Failure::Line(format!("cannot wait for its output: {e}")))?;
            if !ready {
                return Ok(None);
            }
            match self.out.fill_buf() {
                Ok([]) => return Err(Failure::Exited),
                Ok(_) => {}
                Err(e) => return Err(Failure::Line(format!("cannot read its output: {e}"))),
            }
        }
        let buf = self.out.buffer();
        let end = buf.iter().position(|&b| b == b'\n').unwrap_or(buf.len());
        Ok(Some(buf[..end].to_vec()))
    }

    /// The next line (without its line break), waiting until `deadline`;
    /// `gone` tells whether the law has exited (checked every
    /// [`EXIT_CHECK`] while nothing arrives).
    fn next(&mut self, deadline: Instant, gone: &dyn Fn() -> bool) -> Result<Vec<u8>, Failure> {
        use std::os::fd::AsRawFd;
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
            let fd = self.out.get_ref().as_raw_fd();
            let ready = wait_fd(fd, libc::POLLIN, millis(left, EXIT_CHECK))
                .map_err(|e| Failure::Line(format!("cannot wait for its output: {e}")))?;
            if !ready {
                // Nothing yet: a law that exited while something it started
                // holds its stdout will never close it.
                if gone() && !wait_fd(fd, libc::POLLIN, 0).unwrap_or(false) {
                    return Err(Failure::Exited);
                }
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

    fn pending(&mut self) -> Result<Option<Vec<u8>>, Failure> {
        Ok(None)
    }

    fn next(&mut self, deadline: Instant, _gone: &dyn Fn() -> bool) -> Result<Vec<u8>, Failure> {
        use std::sync::mpsc::RecvTimeoutError;
        let timeout = deadline.saturating_duration_since(Instant::now());
        match self.0.recv_timeout(timeout) {
            Ok(Ok(line)) => Ok(line),
            Ok(Err(m)) => Err(Failure::Line(m)),
            Err(RecvTimeoutError::Timeout) => Err(Failure::Timeout),
            Err(RecvTimeoutError::Disconnected) => Err(Failure::Exited),
        }
    }
}

/// The last lines of `text`, each indented as `\n  | line`.
pub(crate) fn format_tail(text: &str) -> String {
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

#[cfg(all(test, target_os = "linux"))]
mod tests {
    use super::*;

    /// A law that never reads its input: writing a request larger than the
    /// pipe gives up at the timeout (it blocked for ever), and stopping it
    /// reaps it.
    #[test]
    fn a_write_to_a_law_that_does_not_read_ends_at_the_timeout() {
        let sleep = std::path::PathBuf::from("/bin/sleep");
        let mut p = LawProcess::start(&sleep, &["100".into()], Path::new(".")).unwrap();
        let big = vec![b'x'; 4 << 20];
        let t0 = Instant::now();
        let r = p.exchange(&big, Duration::from_millis(300));
        assert!(
            matches!(r, Err(Failure::WriteTimeout)),
            "{:?}",
            r.err().map(|_| ())
        );
        let waited = t0.elapsed();
        assert!(
            waited >= Duration::from_millis(300) && waited < Duration::from_secs(3),
            "{waited:?}"
        );
        let pid = p.id();
        let (status, killed) = p.stop(Duration::ZERO);
        assert!(killed && status.is_some());
        assert!(
            !std::path::Path::new(&format!("/proc/{pid}")).exists(),
            "not reaped"
        );
    }

    /// The law runs in a process group of its own (its pid is the group's id).
    #[test]
    fn a_law_leads_its_own_process_group() {
        let sleep = std::path::PathBuf::from("/bin/sleep");
        let mut p = LawProcess::start(&sleep, &["100".into()], Path::new(".")).unwrap();
        let pgid = unsafe { libc::getpgid(p.id() as libc::pid_t) };
        assert_eq!(pgid as u32, p.id());
        assert!(group_alive(p.id()));
        p.stop(Duration::ZERO);
        assert!(!group_alive(p.id()));
    }
}
