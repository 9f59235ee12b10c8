//! `sim --serve` over the pseudo-terminal: a client that opens the port after another one
//! left reads nothing the earlier client left unread, and the port still answers it.

mod serve_rig;

use std::time::Duration;

use serve_rig::{Client, Server};

const MS: fn(u64) -> Duration = Duration::from_millis;

#[test]
fn a_new_pty_client_reads_nothing_stale() {
    let server = Server::start(&[]);
    // A sender that asks for the settings dump, never reads it and goes away.
    let mut first = Client::pty(&server.pty);
    first.send(b"$$\n");
    // `$$` is ~40 lines (~1.5 kB: 130 ms at 115200 baud); wait until it has all been sent.
    std::thread::sleep(MS(800));
    drop(first);
    // Let the server see the client go (it checks every turn, 1 ms of simulated time).
    std::thread::sleep(MS(100));
    let mut second = Client::pty(&server.pty);
    second.pump(MS(400));
    assert!(second.text.is_empty(), "the new client read what the previous one left: {:?}", second.text);
    // The port works for the new client.
    let lines = second.command("$G");
    assert!(lines.iter().any(|l| l.starts_with("[GC:")), "{lines:?}");
    assert!(!second.text.contains("$0="), "{:?}", second.text);
    drop(second);
    // Opening right after another client left (no pause for the server to see the close):
    // still nothing stale, however the two events land in the server's turns.
    let mut third = Client::pty(&server.pty);
    third.send(b"$$\n");
    std::thread::sleep(MS(800));
    drop(third);
    let mut fourth = Client::pty(&server.pty);
    std::thread::sleep(MS(50));
    let mark = fourth.mark();
    fourth.send(b"?");
    assert!(fourth.wait(mark, MS(2000), |t| t.contains('>')), "no status report: {:?}", fourth.text);
    assert!(!fourth.text.contains("$0="), "stale settings dump: {:?}", fourth.text);
    server.stop();
}
