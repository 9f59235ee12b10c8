//! A real serial tool from a package registry on the virtual board: pyserial's miniterm (PyPI
//! `pyserial`, installed by .ci/setup), run headless under `script` (which gives it the
//! terminal it insists on), opens the `--pty-link` symlink at 115200 baud, and a person's
//! keystrokes go in: `$I`, `?`, a short move, `?`, then Ctrl-] to quit.

mod serve_rig;

use std::io::{Read, Write};
use std::process::{Command, Stdio};
use std::time::Duration;

use serve_rig::Server;

#[test]
fn pyserial_miniterm_talks_to_the_virtual_board() {
    let probe = Command::new("python3").args(["-c", "import serial.tools.miniterm"]).output();
    assert!(
        probe.is_ok_and(|o| o.status.success()),
        "pyserial is missing: run `bash .ci/setup` (or `python3 -m pip install pyserial`)"
    );
    let link = std::env::temp_dir().join(format!("ttyMINITERM-{}", std::process::id()));
    let server = Server::start(&["--pty-link", link.to_str().unwrap()]);
    let miniterm = format!("python3 -m serial.tools.miniterm --raw --eol LF {} 115200", link.display());
    let mut child = Command::new("script")
        .args(["-qfec", &miniterm, "/dev/null"])
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run script(1)");
    let mut keys = child.stdin.take().unwrap();
    let pause = |ms| std::thread::sleep(Duration::from_millis(ms));
    pause(1500); // python starts, miniterm opens the port
    for (typed, wait) in [("$I\n", 500), ("?", 300), ("G91\nG1 X1 F600\n", 600), ("?", 400), ("\x1d", 500)] {
        keys.write_all(typed.as_bytes()).unwrap();
        keys.flush().unwrap();
        pause(wait);
    }
    drop(keys);
    let mut out = String::new();
    child.stdout.take().unwrap().read_to_string(&mut out).unwrap();
    let status = child.wait().unwrap();
    server.stop();
    assert!(status.success(), "miniterm exit {status}: {out}");
    assert!(out.contains("--- Miniterm on"), "{out}");
    assert!(out.contains("[VER:1.1"), "$I answered: {out}");
    assert!(out.contains("<Idle|MPos:0.000,"), "first status: {out}");
    assert!(out.contains("<Idle|MPos:1.000,"), "after the move: {out}");
    assert!(!out.contains("error:") && !out.contains("ALARM"), "{out}");
}
