//! Test rig for `sim --serve`: starts the server process on the release ELF, and clients that
//! talk to it over the pseudo-terminal or TCP the way senders do (non-blocking reads, timed
//! waits on what came back). For bench/tests/serve_*.rs.
#![allow(dead_code)]

use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::os::unix::fs::OpenOptionsExt;
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use ddastep_bench::emu::firmware_elf;

/// A running `sim --serve`.
pub struct Server {
    child: Child,
    pub pty: String,
    pub tcp: Option<String>,
    pub stdout_head: String,
    stderr: Arc<Mutex<String>>,
}

impl Server {
    // start the server with extra arguments; waits for its banner lines
    pub fn start(extra: &[&str]) -> Server {
        let mut child = Command::new(env!("CARGO_BIN_EXE_sim"))
            .arg("--elf")
            .arg(firmware_elf().expect("firmware ELF"))
            .arg("--serve")
            .args(extra)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start sim --serve");
        let stderr = Arc::new(Mutex::new(String::new()));
        let mut err = child.stderr.take().unwrap();
        let sink = stderr.clone();
        std::thread::spawn(move || {
            let mut buf = [0u8; 4096];
            while let Ok(n) = err.read(&mut buf) {
                if n == 0 {
                    break;
                }
                sink.lock().unwrap().push_str(&String::from_utf8_lossy(&buf[..n]));
            }
        });
        let mut out = BufReader::new(child.stdout.take().unwrap());
        let (mut pty, mut tcp, mut head) = (None, None, String::new());
        loop {
            let mut line = String::new();
            if out.read_line(&mut line).unwrap_or(0) == 0 {
                panic!("server ended before its banner: {head}{}", stderr.lock().unwrap());
            }
            head.push_str(&line);
            if let Some(p) = line.strip_prefix("serial: ") {
                pty = Some(p.trim().to_string());
            }
            if let Some(t) = line.strip_prefix("tcp: ") {
                tcp = Some(t.trim().to_string());
            }
            if line.starts_with("115200 8N1") {
                break;
            }
        }
        // keep draining stdout so the server never blocks on it
        std::thread::spawn(move || {
            let mut sink = String::new();
            while out.read_line(&mut sink).unwrap_or(0) > 0 {}
        });
        let server = Server { child, pty: pty.expect("serial: line"), tcp, stdout_head: head, stderr };
        // Senders connect to a board that has booted (bytes sent while the firmware is still in
        // init are lost, as on a real board): read the banner off the pty, so the clients of
        // the test find a quiet line, however loaded the host is.
        let mut boot = Client::pty(&server.pty);
        let booted = boot.wait(0, Duration::from_secs(20), |t| t.find("Grbl 1.1").is_some_and(|i| t[i..].contains('\n')));
        assert!(booted, "no banner: {:?} {}", boot.text, server.stderr());
        server
    }

    // what the server printed on stderr so far
    pub fn stderr(&self) -> String {
        self.stderr.lock().unwrap().clone()
    }

    // Ctrl-C, then wait for a clean exit
    pub fn stop(mut self) -> String {
        let pid = nix::unistd::Pid::from_raw(self.child.id() as i32);
        nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGINT).unwrap();
        let status = self.child.wait().unwrap();
        std::thread::sleep(Duration::from_millis(50));
        let err = self.stderr();
        assert!(status.success(), "server exit {status}: {err}");
        err
    }
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

trait Port: Read + Write + Send {}
impl<T: Read + Write + Send> Port for T {}

/// One sender's connection: everything received is kept in `text`.
pub struct Client {
    port: Box<dyn Port>,
    pub text: String,
}

impl Client {
    // open the pseudo-terminal (or its symlink) as a serial port
    pub fn pty(path: &str) -> Client {
        let f = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .custom_flags(nix::libc::O_NOCTTY | nix::libc::O_NONBLOCK)
            .open(path)
            .unwrap_or_else(|e| panic!("open {path}: {e}"));
        Client { port: Box::new(f), text: String::new() }
    }

    // connect over TCP
    pub fn tcp(addr: &str) -> Client {
        let s = std::net::TcpStream::connect(addr).unwrap_or_else(|e| panic!("connect {addr}: {e}"));
        s.set_nonblocking(true).unwrap();
        s.set_nodelay(true).unwrap();
        Client { port: Box::new(s), text: String::new() }
    }

    pub fn send(&mut self, bytes: &[u8]) {
        self.port.write_all(bytes).unwrap();
        self.port.flush().unwrap();
    }

    // read what has arrived (never blocks)
    pub fn poll(&mut self) {
        let mut buf = [0u8; 4096];
        loop {
            match self.port.read(&mut buf) {
                Ok(0) => return,
                Ok(n) => self.text.push_str(&String::from_utf8_lossy(&buf[..n])),
                Err(e) if e.kind() == ErrorKind::WouldBlock || e.kind() == ErrorKind::Interrupted => return,
                Err(e) => panic!("read: {e}"),
            }
        }
    }

    // keep reading for `d`
    pub fn pump(&mut self, d: Duration) {
        let end = Instant::now() + d;
        while Instant::now() < end {
            self.poll();
            std::thread::sleep(Duration::from_millis(2));
        }
        self.poll();
    }

    // read until `done(text since mark)` or the timeout; returns whether it held
    pub fn wait(&mut self, mark: usize, timeout: Duration, done: impl Fn(&str) -> bool) -> bool {
        let end = Instant::now() + timeout;
        loop {
            self.poll();
            if done(&self.text[mark..]) {
                return true;
            }
            if Instant::now() >= end {
                return false;
            }
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    pub fn mark(&self) -> usize {
        self.text.len()
    }

    // complete lines received since `mark`
    pub fn lines_since(&self, mark: usize) -> Vec<String> {
        let t = &self.text[mark..];
        let complete = &t[..t.rfind('\n').map_or(0, |i| i + 1)];
        complete.lines().map(|l| l.trim().to_string()).filter(|l| !l.is_empty()).collect()
    }

    // send a line and wait for its `ok`/`error:N`; returns the lines up to it
    pub fn command(&mut self, line: &str) -> Vec<String> {
        let mark = self.mark();
        self.send(format!("{line}\n").as_bytes());
        let got = self.wait(mark, Duration::from_secs(3), |t| {
            let complete = &t[..t.rfind('\n').map_or(0, |i| i + 1)];
            complete.lines().any(|l| l.trim() == "ok" || l.trim().starts_with("error:"))
        });
        assert!(got, "no ok for {line:?}: {:?}", &self.text[mark..]);
        self.lines_since(mark)
    }

    // send `?` and return the status report that answers it
    pub fn status(&mut self) -> String {
        let mark = self.mark();
        self.send(b"?");
        let got = self.wait(mark, Duration::from_secs(1), |t| t.contains('>'));
        assert!(got, "no status report: {:?}", &self.text[mark..]);
        let t = &self.text[mark..];
        let s = t.find('<').unwrap();
        t[s..=s + t[s..].find('>').unwrap()].to_string()
    }

    // every line received that Grbl sends for an error or alarm
    pub fn errors(&self) -> Vec<String> {
        self.text
            .lines()
            .map(str::trim)
            .filter(|l| l.starts_with("error:") || l.starts_with("ALARM:"))
            .map(str::to_string)
            .collect()
    }
}

// the state word of a status report ("Run", "Hold:0", "Idle")
pub fn state(report: &str) -> &str {
    report.trim_start_matches('<').split(['|', '>']).next().unwrap_or("")
}

// machine position X of a status report
pub fn mpos_x(report: &str) -> f64 {
    let m = report.split('|').find_map(|f| f.strip_prefix("MPos:")).expect("MPos");
    m.split([',', '>']).next().unwrap().parse().unwrap()
}
