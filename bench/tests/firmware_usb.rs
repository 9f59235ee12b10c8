//! The firmware over the modeled USB (the release build, `usb` on by default): a host
//! that enumerates it as Linux does (bench/src/emu/usb_host.rs), then a sender on the CDC ACM
//! port.

mod firmware_rig;

use ddastep_bench::emu::sender::{stream_char_count, Link};
use ddastep::grbl::settings::Settings;
use ddastep::grbl::store::Stored;
use ddastep_bench::emu::{firmware_elf, Board, Port, HZ};
use firmware_rig::{net, steps};

/// The USB build on blank flash (the defaults: 250 steps/mm, 500 mm/min), enumerated, port
/// open, banner seen on USB.
fn boot_usb() -> Board {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    b.usb_connect(2 * HZ).unwrap();
    assert!(b.run_until(HZ / 10, |b| b.usb_output().contains("Grbl 1.1")).unwrap(), "banner: {:?}", b.usb_output());
    b
}

/// The status line, asked with a `?` on USART1 (the other port reaches the same protocol)
/// and read on USB (replies go to the port that last sent a line byte).
fn usart_status(b: &mut Board) -> String {
    let mark = b.usb_output().len();
    b.serial_send(b"?");
    b.run_until(HZ / 10, |b| b.usb_output()[mark..].contains(">\r\n")).unwrap();
    b.usb_output()[mark..].lines().find(|l| l.starts_with('<')).unwrap_or("").to_string()
}

/// Enumeration: one SET_CONFIGURATION, descriptors that pass the host's chapter 9 / CDC checks
/// (bcdUSB 2.0, device class 0x02 without an IAD, 64-byte bulk endpoints, an interrupt
/// endpoint with a non-zero interval), the strings, and the banner when the port opens (DTR
/// rises) without a reset.
#[test]
fn enumerates_as_cdc_acm_and_sends_the_banner_on_open() {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    b.usb_connect(2 * HZ).unwrap();
    let s = b.usb_stats();
    assert_eq!(s.enumerations, 1, "{s:?}");
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert!(!s.iad);
    assert_eq!(s.strings, ["ddastep", "ddastep Grbl"]);
    assert!(b.run_until(HZ / 10, |b| b.usb_output().contains("Grbl 1.1")).unwrap(), "banner: {:?}", b.usb_output());
    // Closing and opening the port again: the banner again, no reset (no second banner on USART1).
    let usart = b.serial_output();
    b.usb_open(false);
    b.run_seconds(0.01).unwrap();
    b.usb_open(true);
    assert!(b.run_until(HZ / 10, |b| b.usb_output().matches("Grbl 1.1").count() == 2).unwrap(), "{:?}", b.usb_output());
    assert_eq!(b.serial_output(), usart);
    assert_eq!(b.usb_stats().enumerations, 1);
    assert!(b.fault().is_none(), "{:?}", b.fault());
}

/// A job streamed with character counting: one `ok` per line, every byte through once, the
/// exact step counts.
#[test]
fn streams_a_job_with_character_counting_exact_counts() {
    let mut b = boot_usb();
    let mut lines = vec!["G91".to_string()];
    lines.extend((0..150).map(|i| format!("G1 X{:.2} Y-0.02 F500", 0.04 * (1 + i % 3) as f64)));
    let replies = stream_char_count(&mut b, Link::Usb, &lines, 2 * HZ).unwrap();
    assert_eq!(replies.len(), lines.len());
    assert!(replies.iter().all(|r| r == "ok"), "{:?}", replies.iter().find(|r| *r != "ok"));
    // Until the steps stop (100 ms without one).
    let mut seen = 0;
    while steps(&b).len() != seen {
        seen = steps(&b).len();
        b.run_seconds(0.1).unwrap();
    }
    // X: 50 lines each of 10, 20 and 30 steps; Y: 150 × -5.
    assert_eq!(net(&steps(&b))[..2], [3000, -750]);
    let s = b.usb_stats();
    let sent: usize = lines.iter().map(|l| l.len() + 1).sum();
    assert_eq!(s.bytes_out, sent as u64);
    assert_eq!((s.enumerations, s.in_toggle_errors, b.usb_toggle_mismatches()), (1, 0, 0));
    assert!(s.errors.is_empty(), "{:?}", s.errors);
}

/// A sender that does not count floods the RX ring: the board NAKs OUT packets (the host
/// holds the bytes), a `!` in a packet read while the ring is full acts at once (hold while
/// the host still has bytes waiting), and after `~` every line gets its one reply and every
/// step is made: nothing lost or doubled.
#[test]
fn realtime_bytes_act_with_the_rx_ring_full_and_no_byte_is_lost() {
    let mut b = boot_usb();
    assert!(b.usb_send_line_wait_ok("G91").unwrap().contains("ok"));
    let line = "G1 X0.04 F500\n";
    let mut flood = line.repeat(60);
    flood.push('!');
    flood.push_str(&line.repeat(60));
    let lines = 120;
    let mark = b.usb_output().len();
    let usart_ok_before = b.serial_output().matches("ok\r\n").count();
    b.usb_send(flood.as_bytes());
    let held = b.run_until(3 * HZ, |b| b.usb_stats().naked_out > 0 && b.usb_pending() > 0).unwrap();
    assert!(held, "the ring never filled: {:?}", b.usb_stats());
    // The hold takes effect while the host still has bytes waiting behind NAKs.
    let mut hold = String::new();
    for _ in 0..300 {
        b.run_seconds(0.01).unwrap();
        hold = usart_status(&mut b);
        if hold.starts_with("<Hold:0") {
            break;
        }
    }
    assert!(hold.starts_with("<Hold:0"), "{hold}");
    assert!(b.usb_pending() > 0, "the stream drained before the hold");
    let before = steps(&b).len();
    b.run_seconds(0.2).unwrap();
    assert_eq!(steps(&b).len(), before, "steps during the hold");
    b.serial_send(b"~");
    let total_ok = |b: &Board| b.usb_output()[mark..].matches("ok\r\n").count() + b.serial_output().matches("ok\r\n").count();
    // (Every `ok` went to USB: USART1 sent only realtime bytes.)
    let done = b.run_until(10 * HZ, |b| total_ok(b) - usart_ok_before >= lines && b.usb_pending() == 0).unwrap();
    b.run_seconds(0.3).unwrap();
    assert!(done, "{} replies of {lines}", total_ok(&b) - usart_ok_before);
    assert_eq!(total_ok(&b) - usart_ok_before, lines);
    assert_eq!(b.serial_output().matches("ok\r\n").count(), usart_ok_before);
    assert_eq!(net(&steps(&b))[0], 10 * lines as i64); // 0.04 mm at 250 steps/mm
    let s = b.usb_stats();
    assert_eq!(s.bytes_out as usize, flood.len() + 4);
    assert_eq!(b.usb_toggle_mismatches(), 0);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
}

/// The cable pulled mid-job: the queued motion completes (exact steps) and nothing stalls; on
/// replug the host enumerates the board again (the firmware did not restart: no banner on
/// USART1), the banner comes when the port opens, and the status is right.
#[test]
fn unplug_mid_job_completes_the_motion_and_replug_reenumerates() {
    let mut b = boot_usb();
    let mut lines = vec!["G91".to_string()];
    lines.extend((0..6).map(|_| "G1 X0.4 F500".to_string()));
    stream_char_count(&mut b, Link::Usb, &lines, 2 * HZ).unwrap();
    let usart = b.serial_output();
    b.usb_plug(false);
    b.run_seconds(0.05).unwrap();
    let moving = steps(&b).len();
    b.run_seconds(2.0).unwrap();
    assert!(steps(&b).len() > moving, "the motion stopped with the cable");
    assert_eq!(net(&steps(&b))[0], 6 * 100);
    assert!(!b.usb_configured());
    b.usb_plug(true);
    assert!(b.run_until(2 * HZ, |b| b.usb_configured()).unwrap(), "{:?}", b.usb_stats());
    assert_eq!(b.usb_stats().enumerations, 2);
    let mark = b.usb_output().len();
    assert!(b.run_until(HZ / 10, |b| b.usb_output()[mark..].contains("Grbl 1.1")).unwrap(), "no banner after replug");
    b.usb_send(b"?");
    assert!(b.run_until(HZ / 10, |b| b.usb_output()[mark..].contains(">\r\n")).unwrap());
    let status = b.usb_output()[mark..].lines().find(|l| l.starts_with('<')).unwrap_or("").to_string();
    assert!(status.starts_with("<Idle|MPos:2.400,0.000,0.000"), "{status}");
    assert_eq!(b.serial_output(), usart, "USART1 saw a restart or replies");
    assert!(b.usb_stats().errors.is_empty(), "{:?}", b.usb_stats().errors);
    assert!(b.fault().is_none());
}

/// `--unplug AT_S,REPLUG_S` (`Board::usb_unplug_at`): the cable goes at the first time, the
/// board suspends, and it is enumerated again after the second.
#[test]
fn scheduled_unplug_and_replug() {
    let mut b = boot_usb();
    let now = b.cycles();
    b.usb_unplug_at(now + HZ / 10, Some(now + HZ / 5));
    b.run_seconds(0.15).unwrap();
    assert!(!b.usb_configured());
    assert!(b.run_until(HZ, |b| b.usb_stats().enumerations == 2).unwrap(), "{:?}", b.usb_stats());
    assert!(b.usb_stats().errors.is_empty(), "{:?}", b.usb_stats().errors);
}

/// Settings that rebuild the step output in place (`$2`, `$580`, `$581`) and Ctrl-X after a
/// hard limit keep the link: the answers come over USB, the board is enumerated once, the MCU
/// never restarts.
#[test]
fn settings_rebuilds_and_ctrl_x_after_a_hard_limit_keep_the_link() {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    let settings = Settings { hard_limits: true, ..Settings::BENCH };
    b.write_mem(firmware_rig::STORE_ADDR, &Stored::from(settings).to_bytes()).unwrap();
    b.usb_connect(2 * HZ).unwrap();
    assert!(b.run_until(HZ / 10, |b| b.usb_output().contains("Grbl 1.1")).unwrap());
    for line in ["$2=1", "$580=1", "$581=1", "$581=0", "$580=0", "$2=0", "G91 G1 X5 F600"] {
        let r = b.usb_send_line_wait_ok(line).unwrap_or_else(|e| panic!("{line}: {e}"));
        assert!(r.contains("ok"), "{line}: {r}");
    }
    b.run_seconds(0.1).unwrap();
    // X's limit switch (PA0, to ground) closes mid-move.
    let mark = b.usb_output().len();
    b.set_input(Port::A, 0, false);
    assert!(b.run_until(HZ / 10, |b| b.usb_output()[mark..].contains("ALARM:1")).unwrap(), "{:?}", &b.usb_output()[mark..]);
    b.set_input(Port::A, 0, true);
    let mark = b.usb_output().len();
    b.usb_send(&[0x18]);
    assert!(b.run_until(HZ / 2, |b| b.usb_output()[mark..].contains("to unlock]\r\n")).unwrap(), "{:?}", &b.usb_output()[mark..]);
    assert!(b.usb_send_line_wait_ok("$X").unwrap().contains("ok"));
    assert_eq!(b.usb_stats().enumerations, 1);
    assert!(b.system_resets().is_empty() && b.watchdog_resets().is_empty());
    assert!(b.usb_stats().errors.is_empty(), "{:?}", b.usb_stats().errors);
    assert!(b.fault().is_none());
}

/// 3 000 lines written to the tty in chunks of random sizes (packets split anywhere in a
/// line), without character counting, so the RX ring fills and the board NAKs again and again:
/// every line gets exactly one `ok`, every byte arrives once (bytes out exact) and every step
/// is made.
#[test]
fn random_write_splits_lose_or_double_nothing() {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    b.write_mem(firmware_rig::STORE_ADDR, &Stored::from(Settings::BENCH).to_bytes()).unwrap();
    b.usb_connect(2 * HZ).unwrap();
    assert!(b.run_until(HZ / 10, |b| b.usb_output().contains("Grbl 1.1")).unwrap());
    assert!(b.usb_send_line_wait_ok("G91").unwrap().contains("ok"));
    let n = 3000;
    let text: String = (0..n).map(|i| if i % 3 == 0 { "G1 X-0.01 F6000\n" } else { "G1 X0.01 F6000\n" }).collect();
    let mark = b.usb_output().len();
    let (mut at, mut seed) = (0, 0x2545_F491u32);
    while at < text.len() {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        let len = (1 + (seed >> 16) as usize % 200).min(text.len() - at);
        b.usb_send(&text.as_bytes()[at..at + len]);
        at += len;
    }
    let oks = |b: &Board| b.usb_output()[mark..].matches("ok\r\n").count();
    assert!(b.run_until(60 * HZ, |b| oks(b) >= n).unwrap(), "{} of {n} replies", oks(&b));
    b.run_seconds(0.5).unwrap();
    assert_eq!(oks(&b), n);
    assert!(!b.usb_output()[mark..].contains("error"));
    assert_eq!(net(&steps(&b))[0], (n / 3) as i64, "one step per line, a third of them back");
    let s = b.usb_stats();
    assert!(s.naked_out > 0, "the ring never filled");
    assert_eq!(s.bytes_out as usize, text.len() + 4);
    assert_eq!(b.usb_toggle_mismatches(), 0);
    assert!(s.errors.is_empty(), "{:?}", s.errors);
}

/// The stack stays 256 B clear of the statics through a stream over USB (the rig's rule).
#[test]
fn usb_build_stack_stays_clear_of_the_statics() {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    b.write_mem(firmware_rig::STORE_ADDR, &Stored::from(Settings::BENCH).to_bytes()).unwrap();
    b.usb_connect(2 * HZ).unwrap();
    let mut lines = vec!["G91".to_string()];
    lines.extend((0..500).map(|i| format!("G1 X{} Y0.01 F6000", if i % 3 == 0 { "-0.01" } else { "0.01" })));
    stream_char_count(&mut b, Link::Usb, &lines, 2 * HZ).unwrap();
    firmware_rig::assert_stack_fits(&b);
}

/// The D+ detach at boot lasts its 10 ms, no more: the banner on USART1 within 25 ms of reset
/// (the bench's `cargo sim` sends its first line at 50 ms; with `asm::delay` the detach took
/// 50 ms on the model's flash wait states and that line was lost).
#[test]
fn the_boot_detach_costs_10_ms() {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    assert!(b.run_until(HZ / 2, |b| b.serial_output().contains("Grbl 1.1")).unwrap());
    let ms = b.cycles() as f64 * 1000.0 / HZ as f64;
    assert!((10.0..25.0).contains(&ms), "banner at {ms:.2} ms");
}

/// A host that sends SET_CONFIGURATION(1) again (macOS) and CLEAR_FEATURE(ENDPOINT_HALT) on
/// the bulk endpoints (libusb's `clear_halt`) mid-session restarts its toggles at DATA0, as
/// USB 2.0 §9.1.1.5 and §9.4.5 say the device must: after an odd number of packets each way,
/// and again in the middle of a flood, no OUT packet is dropped as a repeat and no IN packet
/// is refused; every line gets its one `ok` and every step is made.
#[test]
fn set_configuration_and_clear_halt_mid_session_restart_the_toggles() {
    let mut b = boot_usb();
    assert!(b.usb_send_line_wait_ok("G91").unwrap().contains("ok"));
    b.usb_resync();
    b.run_seconds(0.02).unwrap();
    let lines: Vec<String> = (0..21).map(|_| "G1 X0.04 F500".to_string()).collect();
    let replies = stream_char_count(&mut b, Link::Usb, &lines, 2 * HZ).unwrap();
    assert_eq!(replies.len(), lines.len());
    assert!(replies.iter().all(|r| r == "ok"), "{replies:?}");
    // Again while OUT packets wait behind NAKs and replies are on their way.
    let mark = b.usb_output().len();
    b.usb_send("G1 X0.04 F500\n".repeat(40).as_bytes());
    b.run_seconds(0.005).unwrap();
    b.usb_resync();
    let oks = |b: &Board| b.usb_output()[mark..].matches("ok\r\n").count();
    assert!(b.run_until(10 * HZ, |b| oks(b) >= 40 && b.usb_pending() == 0).unwrap(), "{} replies of 40", oks(&b));
    let mut seen = 0;
    while steps(&b).len() != seen {
        seen = steps(&b).len();
        b.run_seconds(0.1).unwrap();
    }
    assert_eq!(oks(&b), 40);
    assert_eq!(net(&steps(&b))[0], 61 * 10);
    let s = b.usb_stats();
    assert_eq!((s.enumerations, s.in_toggle_errors, b.usb_toggle_mismatches()), (3, 0, 0), "{s:?}");
    assert!(s.errors.is_empty(), "{:?}", s.errors);
    assert!(b.fault().is_none(), "{:?}", b.fault());
}
