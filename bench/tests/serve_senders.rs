//! `sim --serve` with the connect sequences of real senders (UGS, CNCjs, bCNC, Grbl's
//! stream.py), over the pseudo-terminal and over TCP, in real time: streaming with character
//! counting, realtime `?`/`!`/`~` mid-move, soft reset (0x18) while moving and while holding,
//! reconnecting to a board that kept running, and bad use. Sequences follow the senders' own
//! code (see docs/senders.md, "Use your own sender with the virtual board"); jobs are a second or two.

mod serve_rig;

use std::time::{Duration, Instant};

use serve_rig::{mpos_x, state, Client, Server};

const MS: fn(u64) -> Duration = Duration::from_millis;

// UGS: `?` until a status report (at most 10 tries), then `$I`, `$$`, `$G`, then `?` every 200 ms
fn ugs_connect(c: &mut Client) {
    let mut answered = false;
    for _ in 0..10 {
        let mark = c.mark();
        c.send(b"?");
        if c.wait(mark, MS(250), |t| t.contains('<') && t.contains('>')) {
            answered = true;
            break;
        }
    }
    assert!(answered, "no status report after 10 `?`: {:?}", c.text);
    assert!(c.command("$I").iter().any(|l| l.starts_with("[VER:1.1")), "{}", c.text);
    let settings = c.command("$$");
    assert!(settings.iter().any(|l| l.starts_with("$110=")), "{settings:?}");
    assert!(c.command("$G").iter().any(|l| l.starts_with("[GC:")), "{}", c.text);
    let mark = c.mark();
    for _ in 0..5 {
        c.send(b"?");
        c.pump(MS(200));
    }
    let reports = c.lines_since(mark).iter().filter(|l| l.starts_with("<Idle|")).count();
    assert_eq!(reports, 5, "{:?}", &c.text[mark..]);
}

// CNCjs: `?` every 250 ms until the banner or a status report, then `$$`; `$G` while idle
fn cncjs_connect(c: &mut Client) {
    let mark = c.mark();
    let start = Instant::now();
    while !c.wait(mark, MS(250), |t| t.contains("Grbl 1.1") || t.contains("<Idle")) {
        assert!(start.elapsed() < Duration::from_secs(3), "no banner or status: {:?}", c.text);
        c.send(b"?");
    }
    assert!(c.command("$$").iter().any(|l| l.starts_with("$0=")), "{}", c.text);
    let mark = c.mark();
    for _ in 0..4 {
        c.send(b"?");
        c.pump(MS(125));
        if c.text[mark..].contains("<Idle") {
            assert!(c.command("$G").iter().any(|l| l.starts_with("[GC:")));
        }
        c.pump(MS(125));
    }
    assert!(c.lines_since(mark).iter().filter(|l| l.starts_with("[GC:")).count() >= 3, "{:?}", &c.text[mark..]);
}

// bCNC: two newlines, `?` every 125 ms, `$G` (every 10 s: once here), `$#` and `$G` on Idle
fn bcnc_connect(c: &mut Client) {
    let mark = c.mark();
    c.send(b"\n\n");
    assert!(c.wait(mark, MS(500), |t| t.matches("ok").count() >= 2), "{:?}", &c.text[mark..]);
    c.send(b"$G\n");
    let mut idle_seen = false;
    for _ in 0..8 {
        let m = c.mark();
        c.send(b"?");
        c.pump(MS(125));
        if !idle_seen && c.text[m..].contains("<Idle") {
            idle_seen = true;
            c.send(b"$#\n$G\n");
        }
    }
    let lines = c.lines_since(mark);
    assert!(idle_seen);
    assert!(lines.iter().any(|l| l.starts_with("[G54:")), "{lines:?}");
    assert!(lines.iter().filter(|l| l.starts_with("[GC:")).count() >= 2, "{lines:?}");
}

// stream.py: wake up with "\r\n\r\n", wait, flush input, then stream with character counting
// against Grbl's 128-byte receive buffer; returns the replies in order
fn stream_py(c: &mut Client, job: &[&str]) -> Vec<String> {
    c.send(b"\r\n\r\n");
    c.pump(MS(500));
    c.text.clear(); // flushInput
    const RX_BUFFER_SIZE: usize = 128;
    let mut in_flight: Vec<usize> = Vec::new();
    let mut replies = Vec::new();
    let read_reply = |c: &mut Client, in_flight: &mut Vec<usize>, replies: &mut Vec<String>| {
        let start = Instant::now();
        loop {
            c.poll();
            if let Some(i) = c.text.find('\n') {
                let line: String = c.text.drain(..=i).collect();
                let line = line.trim().to_string();
                if line.starts_with("ok") || line.starts_with("error") {
                    in_flight.remove(0);
                    replies.push(line);
                }
                return;
            }
            assert!(start.elapsed() < Duration::from_secs(5), "no reply; in flight {in_flight:?}");
            std::thread::sleep(MS(1));
        }
    };
    for line in job {
        let l = format!("{}\n", line.trim());
        in_flight.push(l.len());
        while in_flight.iter().sum::<usize>() >= RX_BUFFER_SIZE - 1 {
            read_reply(c, &mut in_flight, &mut replies);
        }
        c.send(l.as_bytes());
    }
    while !in_flight.is_empty() {
        read_reply(c, &mut in_flight, &mut replies);
    }
    replies
}

// the paper's bench settings on X, Y, Z at a tenth of its acceleration (the firmware's safe
// defaults suit a small gantry: 500 mm/min), so the jobs here take a second, not a minute
fn bench_settings(c: &mut Client) {
    for axis in 0..3 {
        for (n, value) in [(100, "100"), (110, "6000"), (120, "1000")] {
            assert_eq!(c.command(&format!("${}={value}", n + axis)), ["ok"]);
        }
    }
}

// poll `?` until the state starts with `want`
fn wait_state(c: &mut Client, want: &str, timeout: Duration) -> String {
    let start = Instant::now();
    loop {
        let s = c.status();
        if state(&s).starts_with(want) {
            return s;
        }
        assert!(start.elapsed() < timeout, "state never {want}: last {s}");
        std::thread::sleep(MS(50));
    }
}

/// A short job streamed as stream.py does, 35 lines of 4 to 30 bytes (more than 128 bytes in
/// flight without counting): every reply `ok`, the board idle at the summed X, no error.
fn short_job_ends_where_it_should(c: &mut Client) {
    let mut job = vec!["G91", "G21"];
    let moves: Vec<String> = (0..32).map(|i| format!("G1 X{}.25 Y-0.125 F{}", i % 3, 3000 + 60 * i)).collect();
    job.extend(moves.iter().map(String::as_str));
    job.push("G90");
    let replies = stream_py(c, &job);
    assert_eq!(replies.len(), job.len());
    assert!(replies.iter().all(|r| r == "ok"), "{replies:?}");
    let s = wait_state(c, "Idle", Duration::from_secs(10));
    let x: f64 = (0..32).map(|i| (i % 3) as f64 + 0.25).sum();
    assert!((mpos_x(&s) - x).abs() < 0.006, "{s}: X should be {x}");
    assert!(c.errors().is_empty(), "{:?}", c.errors());
}

#[test]
fn ugs_then_stream_py_over_the_pty_symlink() {
    let link = std::env::temp_dir().join(format!("ttyBLUEPILL-{}", std::process::id()));
    let server = Server::start(&["--pty-link", link.to_str().unwrap()]);
    assert!(server.stdout_head.contains(&format!("serial link: {}", link.display())));
    assert!(server.pty.starts_with("/dev/pts/"), "{}", server.pty);
    ugs_then_stream_py(server, &link);
}

// UGS connects through the `--pty-link` symlink, stream.py runs the short job, and the server
// stops on Ctrl-C and removes the symlink
fn ugs_then_stream_py(server: Server, link: &std::path::Path) {
    let mut c = Client::pty(link.to_str().unwrap());
    ugs_connect(&mut c);
    bench_settings(&mut c);
    short_job_ends_where_it_should(&mut c);
    drop(c);
    let err = server.stop();
    assert!(err.contains("stopped (Ctrl-C)"), "{err}");
    assert!(!link.exists(), "the symlink is removed on exit");
}

#[test]
fn cncjs_and_bcnc_over_tcp_and_pty_at_once() {
    let err = cncjs_over_tcp_and_bcnc_over_pty(Server::start(&["--tcp", "127.0.0.1:0"]));
    assert!(err.contains(&format!("tcp: 127.0.0.1:")) && err.contains("connected"), "{err}");
    // the status line: simulated time, position, step rate, CPU load
    assert!(err.lines().any(|l| l.contains(" s | X0 steps | 0 Hz | CPU")), "{err}");
}

// CNCjs connects over the server's TCP port and bCNC over its pty at once, with no error;
// the server's stderr once stopped
fn cncjs_over_tcp_and_bcnc_over_pty(server: Server) -> String {
    let addr = server.tcp.clone().expect("tcp: line");
    let mut tcp = Client::tcp(&addr);
    let mut pty = Client::pty(&server.pty);
    cncjs_connect(&mut tcp);
    bcnc_connect(&mut pty);
    assert!(tcp.errors().is_empty() && pty.errors().is_empty(), "{:?} {:?}", tcp.errors(), pty.errors());
    server.stop()
}

#[test]
fn realtime_commands_mid_move_over_tcp() {
    let server = Server::start(&["--tcp", "127.0.0.1:0"]);
    let mut c = Client::tcp(server.tcp.as_deref().unwrap());
    bench_settings(&mut c);
    assert_eq!(c.command("G91"), ["ok"]);
    // 30 mm at 40 mm/s: about 0.8 s of motion
    assert_eq!(c.command("G1 X30 F2400"), ["ok"]);
    c.pump(MS(250));
    let run = c.status();
    assert_eq!(state(&run), "Run", "{run}");
    assert!(mpos_x(&run) > 0.0 && mpos_x(&run) < 30.0, "{run}");
    // feed hold: decelerates and stops
    c.send(b"!");
    let held = wait_state(&mut c, "Hold:0", Duration::from_secs(5));
    c.pump(MS(200));
    let still = c.status();
    assert_eq!(mpos_x(&held), mpos_x(&still), "no motion while held: {held} {still}");
    assert!(mpos_x(&held) < 30.0);
    // resume: finishes the move exactly
    c.send(b"~");
    let resumed = c.status();
    assert!(state(&resumed) == "Run" || state(&resumed).starts_with("Hold"), "{resumed}");
    let done = wait_state(&mut c, "Idle", Duration::from_secs(10));
    assert!((mpos_x(&done) - 30.0).abs() < 0.006, "{done}");

    // soft reset while moving: motion stops, the banner comes back
    assert_eq!(c.command("G1 X30 F2400"), ["ok"]);
    c.pump(MS(200));
    let mark = c.mark();
    c.send(&[0x18]);
    assert!(c.wait(mark, Duration::from_secs(1), |t| t.contains("Grbl 1.1")), "{:?}", &c.text[mark..]);
    let a = c.status();
    c.pump(MS(200));
    let b = c.status();
    assert_eq!(mpos_x(&a), mpos_x(&b), "stopped after reset: {a} {b}");
    assert!(mpos_x(&a) < 60.0);
    if state(&b) == "Alarm" {
        assert_eq!(c.command("$X").last().map(String::as_str), Some("ok"));
    }

    // soft reset while holding
    c.command("G91");
    c.command("G1 X10 F2400");
    c.pump(MS(150));
    c.send(b"!");
    let held = wait_state(&mut c, "Hold:0", Duration::from_secs(5));
    let mark = c.mark();
    c.send(&[0x18]);
    assert!(c.wait(mark, Duration::from_secs(1), |t| t.contains("Grbl 1.1")), "{:?}", &c.text[mark..]);
    let after = c.status();
    assert_eq!(mpos_x(&after), mpos_x(&held), "{held} {after}");
    server.stop();
}

#[test]
fn reconnecting_finds_the_board_still_running() {
    let tmp = std::env::temp_dir();
    let (vcd, json) = (tmp.join(format!("serve-{}.vcd", std::process::id())), tmp.join(format!("serve-{}.json", std::process::id())));
    let server = Server::start(&["--tcp", "127.0.0.1:0", "--vcd", vcd.to_str().unwrap(), "--json", json.to_str().unwrap()]);
    let addr = server.tcp.clone().unwrap();
    // pty: start a 1 s move, close the port mid-move
    let mut c = Client::pty(&server.pty);
    bench_settings(&mut c);
    c.command("G91");
    c.command("G1 X20 F1200");
    c.pump(MS(200));
    let before = c.status();
    assert_eq!(state(&before), "Run", "{before}");
    drop(c);
    std::thread::sleep(MS(300));
    // reopen: the move went on meanwhile
    let mut c = Client::pty(&server.pty);
    c.pump(MS(50));
    let later = c.status();
    assert!(mpos_x(&later) > mpos_x(&before), "{before} -> {later}");
    drop(c);
    // TCP: connect, disconnect, connect again: same board, same position
    let mut t = Client::tcp(&addr);
    let done = wait_state(&mut t, "Idle", Duration::from_secs(10));
    assert!((mpos_x(&done) - 20.0).abs() < 0.006, "{done}");
    drop(t);
    std::thread::sleep(MS(100));
    let mut t = Client::tcp(&addr);
    let again = t.status();
    assert_eq!(mpos_x(&again), mpos_x(&done), "{again}");
    drop(t);
    let err = server.stop();
    assert!(err.matches("disconnected").count() >= 1, "{err}");
    // --vcd and --json recorded the session: 20 mm at 100 steps/mm on X, nothing else
    let report: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(report["axes"]["X"]["rising_edges"], 2000, "{report}");
    assert_eq!(report["axes"]["X"]["net_steps"], 2000, "{report}");
    assert_eq!(report["axes"]["Y"]["rising_edges"], 0, "{report}");
    let text = std::fs::read_to_string(&vcd).unwrap();
    assert!(text.contains("X_STEP") && text.lines().count() > 4000, "VCD of the session");
    let _ = (std::fs::remove_file(vcd), std::fs::remove_file(json));
}

#[test]
fn bad_use_is_a_clear_error() {
    let elf = ddastep_bench::emu::firmware_elf().unwrap();
    let taken = std::net::TcpListener::bind("127.0.0.1:0").unwrap();
    let busy = taken.local_addr().unwrap().to_string();
    let file = std::env::temp_dir().join(format!("serve-not-a-link-{}", std::process::id()));
    std::fs::write(&file, "x").unwrap();
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec!["--tcp".into(), busy.clone()], "cannot listen there"),
        (vec!["--tcp".into(), "localhost".into()], "is not an address like 127.0.0.1:23000"),
        (vec!["--pty-link".into(), file.display().to_string()], "exists and is not a symlink"),
    ];
    for (args, message) in cases {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_sim"))
            .arg("--elf")
            .arg(&elf)
            .arg("--serve")
            .args(&args)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}");
        assert!(err.contains(message), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // no pseudo-terminal to be had (no file descriptors left for it)
    let out = std::process::Command::new("bash")
        .arg("-c")
        .arg(format!("ulimit -n 4; exec {} --elf {} --serve", env!("CARGO_BIN_EXE_sim"), elf.display()))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("sim: error: cannot create a pseudo-terminal") && err.contains("Too many open files"), "{err}");
    assert_eq!(err.lines().count(), 1, "one line, no backtrace: {err}");
    // --pty-link without --serve is a usage error
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_sim")).args(["--pty-link", "/tmp/x"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let _ = std::fs::remove_file(file);
}

/// `cargo sim -- --serve --usb --pty-link …`: UGS connects and stream.py runs a job over the
/// board's USB port (a modeled host enumerates it and holds it open).
#[test]
fn ugs_then_stream_py_over_usb() {
    let link = std::env::temp_dir().join(format!("ttyBLUEPILL-usb-{}", std::process::id()));
    let server = Server::start(&["--usb", "--pty-link", link.to_str().unwrap()]);
    assert!(server.stdout_head.contains("USB port"), "{}", server.stdout_head);
    ugs_then_stream_py(server, &link);
}

/// CNCjs (TCP) and bCNC (pty) connect to the board's USB port through `--serve --usb`.
#[test]
fn cncjs_and_bcnc_over_usb() {
    cncjs_over_tcp_and_bcnc_over_pty(Server::start(&["--usb", "--tcp", "127.0.0.1:0"]));
}
