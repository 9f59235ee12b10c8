//! Firmware in the loop: what UGS and CNCjs send to set up, jog, zero, run and stop, over the
//! emulated USART of the release ELF, with every reply checked against the pins.

mod firmware_rig;

use ddastep_bench::emu::{Board, HZ};
use firmware_rig::*;

/// MPos (or WPos) from a status line.
fn pos(status: &str) -> Vec<f64> {
    let p = status.split("Pos:").nth(1).unwrap_or_else(|| panic!("no position in {status:?}"));
    p.split(['|', '>']).next().unwrap().split(',').map(|v| v.parse().unwrap()).collect()
}

/// Runs until the status word is not `Jog`/`Run`/`Hold` (10 ms polls, like a sender).
fn wait_not(b: &mut Board, states: &[&str], max_s: f64) -> String {
    let end = b.seconds() + max_s;
    while b.seconds() < end {
        b.run_seconds(0.01).unwrap();
        let s = status(b);
        if !states.iter().any(|w| s.starts_with(w)) {
            return s;
        }
    }
    panic!("still {states:?} after {max_s} s: {}", status(b));
}

/// The pins' net steps as millimetres at `spm` steps/mm.
fn pins_mm(b: &Board, spm: f64) -> Vec<f64> {
    net(&steps(b))[..3].iter().map(|&n| n as f64 / spm).collect()
}

fn close(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() < 0.0006)
}

#[test]
fn ugs_like_session_on_the_safe_defaults() {
    // Blank flash: the firmware's own defaults (250 steps/mm, 500 mm/min, 10 mm/s², XYZ).
    let mut b = boot_with(None);
    b.serial_send(&[0x18]);
    b.run_seconds(0.05).unwrap();
    // Connect: status, build info, settings, parser state, parameters.
    let s = status(&mut b);
    assert!(s.starts_with("<Idle|MPos:0.000,0.000,0.000|FS:0,0"), "{s}");
    let info = reply(&mut b, "$I");
    assert!(info.contains("[VER:1.1h.ddastep:]\r\n[OPT:VMH+,24,128]\r\n"), "{info}");
    let list = reply(&mut b, "$$");
    assert!(list.contains("$10=1\r\n") && list.contains("$100=250.000\r\n") && list.contains("$110=500.000\r\n"));
    assert!(!list.contains("$103="), "three axes by default");
    assert!(reply(&mut b, "$G").contains("[GC:G0 G54 G17 G21 G90 G94 M5 M9 T0 F0 S0]"));
    // Jog X +2 mm.
    ok(&mut b, "$J=G21G91X2F500");
    b.run_seconds(0.1).unwrap();
    assert!(status(&mut b).starts_with("<Jog|"));
    wait_not(&mut b, &["<Jog"], 3.0);
    assert_eq!(net(&steps(&b))[..3], [500, 0, 0]);
    // Jog Y +10 mm and cancel it part-way.
    ok(&mut b, "$J=G21G91Y10F500");
    b.run_seconds(0.5).unwrap();
    b.serial_send(&[0x85]);
    let s = wait_not(&mut b, &["<Jog"], 2.0);
    assert!(s.starts_with("<Idle|"), "{s}");
    let y = net(&steps(&b))[1];
    assert!(y > 0 && y < 2500, "stopped part-way: {y}");
    assert!(close(&pos(&s), &pins_mm(&b, 250.0)), "{s} vs pins");
    // Zero all axes here (UGS's "Reset zero"), move away, return to zero.
    ok(&mut b, "G10 P0 L20 X0 Y0 Z0");
    let params = reply(&mut b, "$#");
    assert!(params.starts_with(&format!("[G54:2.000,{:.3},0.000]", y as f64 / 250.0)), "{params}");
    ok(&mut b, "$J=G21G91X-1Z1F500");
    wait_not(&mut b, &["<Jog"], 3.0);
    ok(&mut b, "G90 G0 X0 Y0");
    ok(&mut b, "G90 G0 Z0");
    wait_idle(&mut b, 3.0);
    assert_eq!(net(&steps(&b))[..3], [500, y, 0]);
    // Run a program, stop it from a hold: no alarm, position kept.
    ok(&mut b, "G90 G1 X5 Y5 F500");
    b.run_seconds(0.3).unwrap();
    b.serial_send(b"!");
    let s = wait_not(&mut b, &["<Run", "<Hold:1"], 2.0);
    assert!(s.starts_with("<Hold:0|"), "{s}");
    let mark = b.serial_output().len();
    b.serial_send(&[0x18]);
    b.run_seconds(0.05).unwrap();
    let after = b.serial_output()[mark..].to_string();
    assert!(after.contains("Grbl 1.1h") && !after.contains("ALARM"), "{after}");
    let held = net(&steps(&b));
    b.run_seconds(0.1).unwrap();
    assert_eq!(net(&steps(&b)), held, "stopped");
    let s = status(&mut b);
    assert!(s.starts_with("<Idle|") && close(&pos(&s), &pins_mm(&b, 250.0)), "{s}");
    // And it runs again from there.
    ok(&mut b, "G53 G0 X0 Y0");
    wait_idle(&mut b, 5.0);
    assert_eq!(net(&steps(&b))[..3], [0, 0, 0]);
    assert!(b.fault().is_none());
}

#[test]
fn cncjs_like_session_with_work_offsets() {
    let mut b = boot();
    b.run_seconds(0.02).unwrap();
    for line in ["$$", "$#", "$G", "$I"] {
        ok(&mut b, line);
    }
    ok(&mut b, "$42=3");
    ok(&mut b, "$10=0");
    // CNCjs's own jog: G91 moves bracketed by G90, and $J= with a cancel.
    ok(&mut b, "G91");
    ok(&mut b, "G0 X5 Y-3");
    ok(&mut b, "G90");
    wait_idle(&mut b, 2.0);
    assert_eq!(net(&steps(&b))[..3], [500, -300, 0]);
    for _ in 0..4 {
        ok(&mut b, "$J=G91 G21 Z-10 F600");
    }
    b.run_seconds(0.3).unwrap();
    b.serial_send(&[0x85]);
    wait_not(&mut b, &["<Jog"], 3.0);
    let z = net(&steps(&b))[2];
    assert!(z < 0 && z > -4000, "{z}");
    // Zero X and Y in G54 (P1) and Z in G55 (P2), select G55.
    ok(&mut b, "G10 L20 P1 X0 Y0");
    ok(&mut b, "G10 L20 P2 Z0");
    ok(&mut b, "G55");
    let s = status(&mut b);
    assert!(s.starts_with("<Idle|WPos:5.000,-3.000,0.000|"), "{s}");
    // Go to work zero, then machine zero for Z.
    ok(&mut b, "G0 X0 Y0");
    wait_idle(&mut b, 2.0);
    assert_eq!(net(&steps(&b))[..3], [0, 0, z]);
    ok(&mut b, "G53 G0 Z0");
    wait_idle(&mut b, 2.0);
    assert_eq!(net(&steps(&b))[2], 0);
    // A program in G55, stopped with feed hold + reset (CNCjs "Stop").
    ok(&mut b, "G1 X20 Y10 F1200");
    ok(&mut b, "G1 X0 Y0");
    b.run_seconds(0.4).unwrap();
    b.serial_send(b"!");
    wait_not(&mut b, &["<Run", "<Hold:1"], 2.0);
    let mark = b.serial_output().len();
    b.serial_send(&[0x18]);
    b.run_seconds(0.05).unwrap();
    assert!(!b.serial_output()[mark..].contains("ALARM"));
    let s = status(&mut b);
    // After the reset G54 is back in force (Grbl), with X/Y zeroed at machine 5,-3.
    let mm = pins_mm(&b, 100.0);
    assert!(close(&pos(&s), &[mm[0] - 5.0, mm[1] + 3.0, mm[2]]), "{s} vs {mm:?}");
    ok(&mut b, "G0 X0 Y0");
    wait_idle(&mut b, 3.0);
    assert_eq!(net(&steps(&b))[..2], [500, -300]);
    // The offsets are in flash.
    let st = stored(&mut b).expect("image");
    assert_eq!(st.coords.get::<3>(0)[..2], [5.0, -3.0]);
    assert_eq!(st.coords.get::<3>(1)[2], (z as f64 / 100.0) as f32, "stored as f32, like Grbl's EEPROM floats");
    assert!(b.fault().is_none());
}

/// Boots a fresh board whose store pages hold `pages` (a power cycle keeps flash).
fn boot_from_flash(pages: &[u8]) -> Board {
    let elf = ddastep_bench::emu::firmware_elf().expect("firmware builds");
    let mut b = Board::load(elf).expect("ELF loads");
    b.write_mem(STORE_ADDR, pages).expect("flash");
    let up = b.run_until(ddastep_bench::emu::HZ / 2, |b| b.serial_output().contains("Grbl")).expect("runs");
    assert!(up);
    b.run_seconds(0.02).unwrap();
    b
}

#[test]
fn power_cut_during_a_coordinate_save_keeps_the_old_or_the_new_image() {
    let mut b = boot();
    b.run_seconds(0.02).unwrap();
    ok(&mut b, "$110=1234");
    ok(&mut b, "G10 L2 P1 X3");
    // Snapshot both store pages every 200 modeled cycles while the next save runs.
    let mark = b.serial_output().len();
    b.serial_send(b"G10 L2 P1 X7 Y-2\n");
    let mut snaps: Vec<Vec<u8>> = Vec::new();
    while !b.serial_output()[mark..].contains("ok") {
        b.run_until(200, |_| false).unwrap();
        let s = b.read_mem(STORE_ADDR, 2 * ddastep::grbl::store::PAGE_LEN);
        if snaps.last() != Some(&s) {
            snaps.push(s);
        }
        assert!(b.seconds() < 5.0, "no ok");
    }
    assert!(snaps.len() > 10, "the save was seen in progress ({} states)", snaps.len());
    let mut seen = [false; 2];
    for s in snaps.iter().step_by((snaps.len() / 12).max(1)).chain(snaps.last()) {
        // A power cut here: the next boot has the previous image or the new one, never less.
        let mut c = boot_from_flash(s);
        let params = reply(&mut c, "$#");
        let new = params.starts_with("[G54:7.000,-2.000,0.000,");
        assert!(new || params.starts_with("[G54:3.000,0.000,0.000,"), "{params}");
        seen[new as usize] = true;
        assert!(reply(&mut c, "$$").contains("$110=1234.000"), "settings kept");
    }
    assert_eq!(seen, [true, true]);
}

/// `Bf:blocks,rx` and the feed of `FS:` in a status line.
fn bf_feed(status: &str) -> (u32, u32, f64) {
    let field = |name: &str| status.split(['|', '>']).find_map(|f| f.strip_prefix(name)).unwrap_or_else(|| panic!("no {name} in {status:?}"));
    let (blocks, rx) = field("Bf:").split_once(',').unwrap();
    (blocks.parse().unwrap(), rx.parse().unwrap(), field("FS:").split(',').next().unwrap().parse().unwrap())
}

#[test]
fn character_counting_sender_sees_bf_fill_and_fs_zero_while_held() {
    use std::collections::VecDeque;
    // 200 mm/s² on every axis: a hold from 20 mm/s decelerates for 100 ms.
    let mut b = boot_with(Some(ddastep::grbl::store::Stored::from(ddastep::grbl::settings::Settings {
        accel: [200.0; 7],
        ..ddastep::grbl::settings::Settings::BENCH
    })));
    b.run_seconds(0.02).unwrap();
    ok(&mut b, "$10=3");
    ok(&mut b, "G91 G1 F1200");
    // grbl-streamer's / bCNC's rule: whole lines while at most 128 bytes are unacknowledged.
    let lines: Vec<String> = (0..60).map(|i| format!("X1 (move {i}{})\n", "#".repeat(i % 9))).collect();
    let longest = lines.iter().map(|l| l.len()).max().unwrap();
    let mut next = 0;
    let mut in_flight: VecDeque<usize> = VecDeque::new();
    let mut seen = b.serial_output().len();
    let (mut waiting, mut hold1, mut hold0, mut held_at) = (0, 0, 0, None);
    while next < lines.len() || !in_flight.is_empty() {
        while next < lines.len() && in_flight.iter().sum::<usize>() + lines[next].len() <= 128 {
            b.serial_send(lines[next].as_bytes());
            in_flight.push_back(lines[next].len());
            next += 1;
        }
        // Feed hold in the middle of the stream, resumed 300 ms after it came to rest.
        if next == 45 && held_at.is_none() && hold1 == 0 {
            b.serial_send(b"!");
        }
        if held_at.is_some_and(|t| b.seconds() - t >= 0.3) {
            b.serial_send(b"~");
            held_at = Some(f64::INFINITY);
        }
        // `?` after what was sent (every line byte before it has reached the firmware).
        b.serial_send(b"?");
        let mark = b.serial_output().len();
        b.run_until(HZ / 10, |b| b.serial_output()[mark..].contains(">\r\n")).unwrap();
        b.run_seconds(0.005).unwrap();
        let out = b.serial_output();
        let end = out.rfind('\n').map_or(seen, |i| i + 1).max(seen);
        for l in out[seen..end].lines() {
            if l == "ok" {
                in_flight.pop_front().expect("an ok for a line never sent");
                continue;
            }
            assert!(l.starts_with('<'), "{l:?}");
            // The line bytes not acknowledged yet are in the RX ring, but for the one line the
            // controller is carrying out: 128 - unacked <= rx <= 128 - unacked + longest line.
            let unacked: usize = in_flight.iter().sum();
            let (_, rx, feed) = bf_feed(l);
            let (lo, hi) = (128usize.saturating_sub(unacked), (128 + longest).saturating_sub(unacked).min(128));
            assert!((lo..=hi).contains(&(rx as usize)), "{l}: {unacked} bytes unacknowledged, want {lo}..={hi}");
            if unacked > 2 * longest {
                assert!(rx < 128, "{l}: {unacked} bytes unacknowledged");
                waiting += 1;
            }
            if l.starts_with("<Hold:1") {
                assert!(feed > 0.0, "decelerating: {l}");
                hold1 += 1;
            } else if l.starts_with("<Hold:0") {
                assert_eq!(feed, 0.0, "held: {l}");
                hold0 += 1;
                held_at.get_or_insert(b.seconds());
            } else {
                assert!(l.starts_with("<Run") || (l.starts_with("<Idle") && feed == 0.0), "{l}");
            }
        }
        seen = end;
        assert!(b.seconds() < 20.0, "stalled: {} lines sent, {} unacknowledged", next, in_flight.len());
    }
    assert!(waiting >= 20, "{waiting} reports with more than two lines waiting");
    assert!(hold1 >= 3 && hold0 >= 15, "{hold1} Hold:1, {hold0} Hold:0 reports");
    wait_idle(&mut b, 5.0);
    let s = status(&mut b);
    let (_, rx, feed) = bf_feed(&s);
    assert_eq!((rx, feed), (128, 0.0), "{s}");
    assert_eq!(net(&steps(&b))[0], 6000);
    assert!(b.fault().is_none());
}
