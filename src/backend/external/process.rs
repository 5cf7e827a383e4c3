//! One running backend process: its pipes, read with bounds and deadlines.
//!
//! Nothing a backend does may hang or exhaust the harness. Stdout is read by a thread that cuts
//! lines at [`MAX_LINE`] bytes (the rest of an oversized line is read and dropped, never
//! stored) and hands them over a bounded channel, so that waiting for an answer can time out.
//! Stdin is written by a thread too: a backend that stops reading cannot block the harness.
//! Stderr is kept as a bounded tail to show with a failing case.
//!
//! The process runs in its own process group, so that killing it also kills what it started (a
//! wrapper's interpreter, an emulator's helpers). The group is killed before the process is
//! reaped, on every path — a crash, a timeout, a shutdown, a drop — while its id still names
//! it, and every live group is in a registry so that an interruption ([`kill_all`]) ends them
//! all, also during a handshake. A command line run by `sh -c` is `exec`'d when it is a single
//! command, so that the backend itself holds its stdout: closing it is then seen at once.

use std::collections::{BTreeSet, VecDeque};
use std::io::{Read, Write};
use std::path::PathBuf;
use std::process::{Child, ChildStdin, Command, ExitStatus, Stdio};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, SyncSender};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crate::model::project::Launch;

/// The longest line read from a backend: 1 MiB.
pub(crate) const MAX_LINE: usize = 1 << 20;
/// How much of a backend's stderr is kept.
const STDERR_TAIL: usize = 16 * 1024;
/// How long a backend has to exit after `shutdown` before it is killed.
const GRACE: Duration = Duration::from_millis(1000);
/// How often a wait for an answer checks whether the process has exited.
const POLL: Duration = Duration::from_millis(50);
/// How long the lines of a process that has exited may take to arrive.
const SETTLE: Duration = Duration::from_millis(100);

/// The process groups of the backend processes not yet reaped.
static GROUPS: Mutex<BTreeSet<i32>> = Mutex::new(BTreeSet::new());
/// Set once the harness is shutting down: no backend process starts any more.
static CLOSING: AtomicBool = AtomicBool::new(false);

fn groups() -> MutexGuard<'static, BTreeSet<i32>> {
    GROUPS
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner)
}

/// Kills every backend process group and refuses to start another: what an interruption does.
/// The processes are reaped by their owners, which see their backends' stdout close.
pub(crate) fn kill_all() {
    CLOSING.store(true, Ordering::SeqCst);
    let registry = groups();
    for &pgid in registry.iter() {
        signal_group(pgid);
    }
    kill_orphans(&registry);
}

/// Set once this process reaps the orphans of its backends (see [`adopt_orphans`]).
static ADOPTING: AtomicBool = AtomicBool::new(false);

/// Makes this process the reaper of its orphaned descendants (Linux): a backend's helper that
/// leaves the backend's process group and session (`setsid`) and outlives the backend becomes a
/// child of this process, which ends it with the backend. For the command line only: in a test
/// binary, other children are not the harness's to end.
pub(crate) fn adopt_orphans() {
    #[cfg(target_os = "linux")]
    {
        // SAFETY: prctl(2) with PR_SET_CHILD_SUBREAPER takes integer arguments only.
        let set = unsafe { libc::prctl(libc::PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) };
        ADOPTING.store(set == 0, Ordering::SeqCst);
    }
}

/// Kills and reaps the orphans this process adopted: its children that lead no backend group
/// (`leaders`), which can only be descendants of backends whose parents have ended.
fn kill_orphans(leaders: &BTreeSet<i32>) {
    #[cfg(target_os = "linux")]
    {
        if !ADOPTING.load(Ordering::SeqCst) {
            return;
        }
        let me = std::process::id() as i32;
        let Ok(entries) = std::fs::read_dir("/proc") else {
            return;
        };
        for pid in entries.filter_map(|e| e.ok()?.file_name().to_str()?.parse::<i32>().ok()) {
            let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else {
                continue;
            };
            // `pid (comm) state ppid ...`: the name may hold spaces and parentheses.
            let ppid = stat
                .rsplit_once(')')
                .and_then(|(_, rest)| rest.split_whitespace().nth(1))
                .and_then(|p| p.parse::<i32>().ok());
            if ppid == Some(me) && !leaders.contains(&pid) {
                // SAFETY: kill(2) and waitpid(2) on a child of this process; no pointers but
                // the null status.
                unsafe {
                    libc::kill(pid, libc::SIGKILL);
                    libc::waitpid(pid, std::ptr::null_mut(), 0);
                }
            }
        }
    }
    #[cfg(not(target_os = "linux"))]
    let _ = leaders;
}

/// Whether [`kill_all`] has been called.
pub(crate) fn closing() -> bool {
    CLOSING.load(Ordering::SeqCst)
}

/// The flag [`kill_all`] sets: the run's stop flag too (`interrupt::stop_flag`), so that one
/// flag says the harness is shutting down.
pub(crate) fn closing_flag() -> &'static AtomicBool {
    &CLOSING
}

/// SIGKILL to a process group.
fn signal_group(pgid: i32) {
    #[cfg(unix)]
    // SAFETY: kill(2) takes no pointers. Only ids of groups whose leader has not been reaped
    // are passed (see `GROUPS`), so the id still names the group the backend created.
    unsafe {
        libc::kill(-pgid, libc::SIGKILL);
    }
    #[cfg(not(unix))]
    let _ = pgid;
}

/// `sh -c` runs a single command in a child of the shell, which keeps the backend's stdout open
/// after the backend closes it; `exec` makes the backend the process itself. A command line
/// with operators (`a && b`, `a | b`, `a; b`), an assignment or a reserved word first is left as
/// it is.
pub(crate) fn shell_line(line: &str) -> String {
    const RESERVED: [&str; 13] = [
        "if", "then", "else", "elif", "fi", "do", "done", "case", "esac", "while", "until", "for",
        "exec",
    ];
    let first = line.split_whitespace().next().unwrap_or("");
    let assignment = first
        .split_once('=')
        .is_some_and(|(name, _)| !name.is_empty() && !name.contains(['"', '\'', '$']));
    if first.is_empty()
        || assignment
        || RESERVED.contains(&first)
        || matches!(first, "{" | "}" | "!" | "function" | "select")
    {
        return line.to_string();
    }
    let (mut single, mut double, mut escaped) = (false, false, false);
    for c in line.chars() {
        match c {
            _ if escaped => escaped = false,
            '\\' if !single => escaped = true,
            '\'' if !double => single = !single,
            '"' if !single => double = !double,
            ';' | '&' | '|' | '(' | ')' | '\n' | '`' if !single && !double => {
                return line.to_string();
            }
            _ => {}
        }
    }
    format!("exec {line}")
}

/// What came out of a backend's stdout.
#[derive(Debug)]
pub(super) enum Next {
    Line(Vec<u8>),
    /// A line longer than [`MAX_LINE`]: its first bytes and its full length.
    Oversized {
        head: Vec<u8>,
        length: usize,
    },
    /// Nothing before the deadline.
    Timeout,
    /// Stdout closed (the process exited or closed it) or could not be read.
    Closed(Option<String>),
}

pub(super) struct Process {
    child: Child,
    /// The process group the child leads, while it is registered in `GROUPS`.
    group: Option<i32>,
    to_stdin: Option<SyncSender<Vec<u8>>>,
    lines: Receiver<Vec<Next>>,
    /// Lines received and not yet asked for.
    pending: VecDeque<Next>,
    stderr: Arc<Mutex<StderrTail>>,
    threads: Vec<JoinHandle<()>>,
    /// Whether the child has been waited for: from then on its process group id may be reused
    /// and is never signalled.
    reaped: bool,
}

/// The tail of a backend's stderr, and how many bytes it has written in all.
#[derive(Default)]
struct StderrTail {
    bytes: VecDeque<u8>,
    total: u64,
}

impl Process {
    pub(super) fn spawn(
        launch: &Launch,
        cwd: Option<&PathBuf>,
        env: &[(String, String)],
    ) -> std::io::Result<Process> {
        let mut command = match launch {
            Launch::Shell(line) => {
                let mut c = Command::new("sh");
                c.arg("-c").arg(shell_line(line));
                c
            }
            Launch::Exec(args) => {
                let (program, rest) = args.split_first().ok_or_else(|| {
                    std::io::Error::new(std::io::ErrorKind::InvalidInput, "empty command")
                })?;
                let mut c = Command::new(program);
                c.args(rest);
                c
            }
        };
        if let Some(dir) = cwd {
            command.current_dir(dir);
        }
        command
            .envs(env.iter().map(|(k, v)| (k, v)))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped());
        #[cfg(unix)]
        {
            use std::os::unix::process::CommandExt;
            command.process_group(0);
        }
        // Registered before anyone can signal: `kill_all` waits for the registry, and after it
        // nothing starts.
        let mut registry = groups();
        if closing() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::Interrupted,
                "the run is interrupted: no backend starts any more",
            ));
        }
        let mut child = command.spawn()?;
        let group = i32::try_from(child.id()).ok();
        registry.extend(group);
        drop(registry);
        let missing = || std::io::Error::other("a pipe of the child is missing");
        let stdin = child.stdin.take().ok_or_else(missing)?;
        let stdout = child.stdout.take().ok_or_else(missing)?;
        let stderr_pipe = child.stderr.take().ok_or_else(missing)?;

        // Bounded: at most this many reads (each at most one line of MAX_LINE bytes plus 64 KiB)
        // are ever held.
        let (line_tx, lines) = mpsc::sync_channel(32);
        let (to_stdin, stdin_rx) = mpsc::sync_channel::<Vec<u8>>(16);
        let stderr = Arc::new(Mutex::new(StderrTail::default()));
        let tail = stderr.clone();
        let threads = vec![
            std::thread::spawn(move || read_lines(stdout, &line_tx)),
            std::thread::spawn(move || write_messages(stdin, &stdin_rx)),
            std::thread::spawn(move || keep_tail(stderr_pipe, &tail)),
        ];
        Ok(Process {
            child,
            group,
            to_stdin: Some(to_stdin),
            lines,
            stderr,
            threads,
            pending: VecDeque::new(),
            reaped: false,
        })
    }

    /// Queues one message line (the newline is added). A process that has stopped reading
    /// shows up as a closed stdout or a timeout when its answer is awaited.
    pub(super) fn send(&mut self, mut message: Vec<u8>) {
        message.push(b'\n');
        if let Some(tx) = &self.to_stdin {
            let _ = tx.send(message);
        }
    }

    /// The next line, waiting until `deadline`. A process that has exited while a process it
    /// started still holds its stdout open is seen as closed, not waited for until the
    /// deadline.
    pub(super) fn next_line(&mut self, deadline: Instant) -> Next {
        if let Some(next) = self.pending.pop_front() {
            return next;
        }
        let mut exited = false;
        loop {
            let wait = deadline.saturating_duration_since(Instant::now());
            match self
                .lines
                .recv_timeout(if exited { SETTLE } else { wait.min(POLL) })
            {
                Ok(batch) => {
                    self.pending.extend(batch);
                    return self.pending.pop_front().unwrap_or(Next::Closed(None));
                }
                Err(RecvTimeoutError::Disconnected) => return Next::Closed(None),
                Err(RecvTimeoutError::Timeout) if exited => {
                    return Next::Closed(Some(
                        "it exited, but a process it started still holds its stdout".into(),
                    ))
                }
                Err(RecvTimeoutError::Timeout) if Instant::now() >= deadline => {
                    return Next::Timeout
                }
                // Lines written before the exit are still read: one more short wait.
                Err(RecvTimeoutError::Timeout) => exited = self.has_exited() == Some(true),
            }
        }
    }

    /// How many bytes the process has written to stderr so far.
    pub(super) fn stderr_mark(&self) -> u64 {
        self.stderr.lock().map(|t| t.total).unwrap_or(0)
    }

    /// What the process wrote to stderr since `mark` (as much as is kept), after giving the
    /// reader a moment to catch up with a process that has just exited.
    pub(super) fn stderr_since(&self, mark: u64, settle: Duration) -> String {
        let until = Instant::now() + settle;
        let mut last = self.stderr_mark();
        while Instant::now() < until {
            std::thread::sleep(Duration::from_millis(5));
            let now = self.stderr_mark();
            if now == last && self.threads.get(2).is_none_or(|t| t.is_finished()) {
                break;
            }
            last = now;
        }
        let Ok(tail) = self.stderr.lock() else {
            return String::new();
        };
        let new = tail.total.saturating_sub(mark) as usize;
        let kept = new.min(tail.bytes.len());
        let start = tail.bytes.len() - kept;
        let bytes: Vec<u8> = tail.bytes.iter().skip(start).copied().collect();
        let mut text = String::from_utf8_lossy(&bytes).into_owned();
        if kept < new {
            text.insert_str(0, "[earlier output dropped]\n");
        }
        text
    }

    /// The exit status, waiting up to `wait` for the process to end. Once it has ended, its
    /// process group is killed before it is reaped: helpers it started do not outlive it.
    pub(super) fn exit_status(&mut self, wait: Duration) -> Option<ExitStatus> {
        let until = Instant::now() + wait;
        loop {
            match self.has_exited() {
                Some(true) => {
                    self.end_group();
                    let status = self.child.wait().ok();
                    self.reaped = true;
                    return status;
                }
                Some(false) if Instant::now() < until => {
                    std::thread::sleep(Duration::from_millis(2));
                }
                _ => return None,
            }
        }
    }

    /// Whether the child has exited, without reaping it (so that its process group id still
    /// names its group); `None` when that cannot be told.
    #[cfg(unix)]
    fn has_exited(&mut self) -> Option<bool> {
        if self.reaped {
            return Some(true);
        }
        let pid = libc::id_t::try_from(self.child.id()).ok()?;
        // SAFETY: waitid(2) writes into the zeroed siginfo_t it is given and into nothing else;
        // WNOWAIT leaves the child waitable, so `Child::wait` still reaps it.
        unsafe {
            let mut info: libc::siginfo_t = std::mem::zeroed();
            let flags = libc::WEXITED | libc::WNOHANG | libc::WNOWAIT;
            if libc::waitid(libc::P_PID, pid, &mut info, flags) != 0 {
                return None;
            }
            Some(info.si_pid() != 0)
        }
    }

    #[cfg(not(unix))]
    fn has_exited(&mut self) -> Option<bool> {
        match self.child.try_wait() {
            Ok(Some(_)) => {
                self.reaped = true;
                Some(true)
            }
            Ok(None) => Some(false),
            Err(_) => None,
        }
    }

    /// Kills the process group and takes it out of the registry; the child is not reaped yet.
    fn end_group(&mut self) {
        if let Some(pgid) = self.group.take() {
            let mut registry = groups();
            signal_group(pgid);
            // While this backend's leader is still a registered child (not yet reaped).
            kill_orphans(&registry);
            registry.remove(&pgid);
        }
    }

    /// Kills the process with its process group and reaps it.
    pub(super) fn kill(&mut self) {
        self.to_stdin = None;
        if self.reaped {
            return;
        }
        self.end_group();
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.reaped = true;
    }

    /// Sends `shutdown`, closes stdin and waits a moment for the process to exit; kills it if it
    /// does not.
    pub(super) fn shutdown(mut self, message: Vec<u8>) {
        self.send(message);
        self.to_stdin = None;
        if self.exit_status(GRACE).is_none() {
            self.kill();
        }
    }
}

impl Drop for Process {
    fn drop(&mut self) {
        self.kill();
    }
}

/// Describes how a process ended, for a crash report.
pub(super) fn describe_exit(status: Option<ExitStatus>) -> String {
    let Some(status) = status else {
        return "closed its stdout but did not exit".into();
    };
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        if let Some(signal) = status.signal() {
            let name = match signal {
                6 => " (SIGABRT)",
                9 => " (SIGKILL)",
                11 => " (SIGSEGV)",
                15 => " (SIGTERM)",
                _ => "",
            };
            return format!("was killed by signal {signal}{name}");
        }
    }
    match status.code() {
        Some(code) => format!("exited with status {code}"),
        None => "exited".into(),
    }
}

/// Reads stdout into lines. Every line complete after one read goes over the channel in one
/// message: a batch of answers costs one hand-over, not one per case.
fn read_lines(mut stdout: impl Read, tx: &SyncSender<Vec<Next>>) {
    let mut buf = vec![0u8; 64 * 1024];
    let mut line: Vec<u8> = Vec::new();
    let mut length = 0usize;
    loop {
        let n = match stdout.read(&mut buf) {
            Ok(0) => {
                let _ = tx.send(vec![Next::Closed(None)]);
                return;
            }
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => {
                let _ = tx.send(vec![Next::Closed(Some(format!(
                    "stdout could not be read: {e}"
                )))]);
                return;
            }
        };
        let mut batch = Vec::new();
        let mut rest = &buf[..n];
        while !rest.is_empty() {
            let (body, complete, used) = match rest.iter().position(|&b| b == b'\n') {
                Some(i) => (&rest[..i], true, i + 1),
                None => (rest, false, rest.len()),
            };
            // Past the limit the line is only counted, never stored.
            let room = MAX_LINE.saturating_sub(line.len());
            line.extend_from_slice(&body[..body.len().min(room)]);
            length += body.len();
            rest = &rest[used..];
            if complete {
                batch.push(if length > MAX_LINE {
                    line.truncate(256);
                    Next::Oversized {
                        head: std::mem::take(&mut line),
                        length,
                    }
                } else {
                    if line.last() == Some(&b'\r') {
                        line.pop();
                    }
                    Next::Line(std::mem::take(&mut line))
                });
                length = 0;
            }
        }
        if !batch.is_empty() && tx.send(batch).is_err() {
            return;
        }
    }
}

fn write_messages(mut stdin: ChildStdin, rx: &Receiver<Vec<u8>>) {
    while let Ok(message) = rx.recv() {
        if stdin
            .write_all(&message)
            .and_then(|()| stdin.flush())
            .is_err()
        {
            // The process stopped reading; drain so senders never block.
            while rx.recv().is_ok() {}
            return;
        }
    }
}

fn keep_tail(mut stderr: impl Read, tail: &Mutex<StderrTail>) {
    let mut buf = [0u8; 4096];
    loop {
        match stderr.read(&mut buf) {
            Ok(0) => return,
            Ok(n) => {
                let Ok(mut t) = tail.lock() else { return };
                t.total += n as u64;
                t.bytes.extend(&buf[..n]);
                let excess = t.bytes.len().saturating_sub(STDERR_TAIL);
                t.bytes.drain(..excess);
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(_) => return,
        }
    }
}
