//! Grbl 1.1 override bytes (0x90–0x9D): the percentages in `Ov:`, applied to the program moves
//! (feed for G1/G2/G3, rapid for G0), never to jogs (as Grbl): to the moves planned after the
//! byte, and to the motion already running and planned, which walks the ramp table to its new
//! speed at each move's own acceleration.

mod protocol_rig;

use ddastep::grbl::settings::Settings;
use proptest::prelude::*;
use protocol_rig::Bench;

/// Timer ticks per ms.
const MS: u64 = ddastep::TICKS_PER_MS as u64;

/// `Ov:feed,rapid,spindle` from a status report.
fn ov(status: &str) -> Option<String> {
    status.split(['|', '>']).find_map(|f| f.strip_prefix("Ov:")).map(str::to_string)
}

/// Peak master rate (steps/s) of one line run to idle.
fn peak(b: &mut Bench<3>, line: &str) -> u32 {
    b.peak_hz = 0;
    assert_eq!(b.line(line), "ok\r\n", "{line}");
    b.run_to_idle(60_000);
    b.peak_hz
}

#[test]
fn override_bytes_step_and_clamp_as_grbl() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    for _ in 0..15 {
        b.byte(0x91); // +10 % each, up to 200 %
    }
    b.byte(0x94); // −1 %
    b.byte(0x96); // rapid 50 %
    for _ in 0..30 {
        b.byte(0x9B); // spindle −10 % each, down to 10 %
    }
    b.byte(0x98); // not an override: nothing changes
    let o = b.shared.overrides();
    assert_eq!((o.feed, o.rapid, o.spindle), (199, 50, 10));
    // A changed override is shown in the next report, or the one after when `WCO:` is due in
    // that one (Grbl never sends both in one report).
    let (first, second) = (b.status(), b.status());
    assert_eq!(ov(&first).or(ov(&second)).as_deref(), Some("199,50,10"), "{first}{second}");
    b.byte(0x90);
    b.byte(0x95);
    b.byte(0x99);
    let o = b.shared.overrides();
    assert_eq!((o.feed, o.rapid, o.spindle), (100, 100, 100));
}

#[test]
fn feed_and_rapid_overrides_scale_new_program_moves_but_not_jogs() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    assert_eq!(b.line("G91"), "ok\r\n");
    // 100 steps/mm: F600 is 10 mm/s, 1 kHz on X.
    let plain = peak(&mut b, "G1 X20 F600");
    assert_eq!(plain, 1000);
    for _ in 0..10 {
        b.byte(0x91);
    }
    assert_eq!(b.shared.overrides().feed, 200);
    assert_eq!(peak(&mut b, "G1 X20 F600"), 2 * plain);
    // Jogs run at their own F whatever the feed override.
    assert_eq!(peak(&mut b, "$J=G91 X20 F600"), plain);
    // The axes' max rates still bind: $110 = 36 000 mm/min is 60 kHz.
    assert_eq!(peak(&mut b, "G1 X400 F30000"), 60_000);
    // Rapid 25 %: a G0 runs at a quarter of the axis limit.
    b.byte(0x97);
    assert_eq!(peak(&mut b, "G0 X400"), 15_000);
    b.byte(0x95);
    assert_eq!(peak(&mut b, "G0 X-400"), 60_000);
    assert_eq!(b.shared.positions()[0], 100 * (20 + 20 + 20 + 400 + 400 - 400));
}

/// The bench settings with every axis at `accel` mm/s² and `rate` mm/min (100 steps/mm, so a
/// move's master accelerates at `accel / 10` Hz per ms whatever its direction, and the table,
/// at twice the largest acceleration, has entries twice that wide).
fn bench(accel: f32, rate: f32) -> Bench<3> {
    let mut s = Settings::BENCH;
    s.accel = [accel; ddastep::MAX_AXES];
    s.max_rate = [rate; ddastep::MAX_AXES];
    let mut b = Bench::<3>::new(s);
    b.take();
    b
}

/// The master rate in force at tick `t` of a trace.
fn rate_at(trace: &[(u64, u32, u32)], t: u64) -> u32 {
    trace.iter().take_while(|e| e.0 <= t).last().map_or(0, |e| e.1)
}

/// First tick at or after `from` where the rate is within 0.1 % of `hz`.
fn reached(trace: &[(u64, u32, u32)], from: u64, hz: u32) -> u64 {
    let e = trace.iter().find(|e| e.0 >= from && (e.1 as f64 - hz as f64).abs() <= hz as f64 * 1e-3);
    e.unwrap_or_else(|| panic!("{hz} Hz never reached after {from}")).0
}

/// Every change of the master rate within a move is at most one walk of the table at the
/// move's acceleration, `a_ms` Hz per ms: the walk moves the index linearly and the table
/// interpolates periods, so within an entry (`2 · a_ms` wide at most here) the rate may change
/// faster by the ratio of its ends. Changes from or to rest, at move changes, and below the
/// table's start (`$40` and its first entry, `start_hz`: a move from rest starts there, and a
/// feed slower than that runs without a ramp) are left out.
fn assert_walk_steps(trace: &[(u64, u32, u32)], a_ms: f64, start_hz: u32) {
    for w in trace.windows(2) {
        let ((_, h0, d0), (t1, h1, d1)) = (w[0], w[1]);
        if d0 != d1 || h0 == 0 || h1 == 0 || h0.max(h1) <= start_hz {
            continue;
        }
        let lo = h0.min(h1) as f64;
        let allowed = a_ms * (1.0 + 2.0 * a_ms / lo) + 1.0;
        let d = (h1 as f64 - h0 as f64).abs();
        assert!(d <= allowed, "at {} ms: {h0} -> {h1} Hz, a step of {d} > {allowed:.0}", t1 / MS);
    }
}

#[test]
fn feed_override_ramps_the_running_move_to_half_and_back() {
    // 1000 mm/s²: X's master accelerates at 100 Hz per ms.
    let mut b = bench(1000.0, 36_000.0);
    assert_eq!(b.line("G91"), "ok\r\n");
    b.trace = Some(Vec::new());
    // 200 mm/s = 20 kHz, reached after 200 ms.
    assert_eq!(b.line("G1 X400 F12000"), "ok\r\n");
    b.run_ms(400);
    assert_eq!(b.shared.rate_hz(), 20_000);
    let t0 = b.timer.now();
    for _ in 0..5 {
        b.byte(0x92); // −10 % each
    }
    assert_eq!(b.shared.overrides().feed, 50);
    // Shown in the next report, or the one after when `WCO:` is due in that one.
    let (first, second) = (b.status(), b.status());
    assert!((first.clone() + &second).contains("|Ov:50,100,100"), "{first}{second}");
    b.run_ms(200);
    let t1 = b.timer.now();
    b.byte(0x90); // back to 100 %
    b.run_ms(200);
    let at_100 = b.shared.rate_hz();
    b.run_to_idle(10_000);
    let tr = b.trace.take().unwrap();
    // Down to 10 kHz in the 100 ms X's acceleration needs (+ the ramp millisecond it waits
    // for), never faster; then back up likewise.
    let down = reached(&tr, t0, 10_000) - t0;
    assert!((99 * MS..=103 * MS).contains(&down), "half speed after {} ms", down as f64 / MS as f64);
    let mid = rate_at(&tr, t0 + 50 * MS);
    assert!(mid.abs_diff(15_000) <= 200, "half-way down after 50 ms: {mid} Hz");
    assert_eq!(rate_at(&tr, t1 - MS), 10_000, "cruises at half");
    let up = reached(&tr, t1, 20_000) - t1;
    assert!((99 * MS..=103 * MS).contains(&up), "full speed after {} ms", up as f64 / MS as f64);
    assert_eq!(at_100, 20_000);
    assert_walk_steps(&tr, 100.0, 1_400);
    assert!(tr.iter().all(|e| e.1 <= 20_000));
    assert_eq!(b.shared.positions(), [40_000, 0, 0], "counts exact");
    assert!(tr[tr.len() - 2].1 <= 1_300, "decelerated to the table's start: {:?}", &tr[tr.len() - 2..]);
}

#[test]
fn rapid_override_ramps_a_running_g0_and_feed_200_stays_within_the_axis_rate() {
    // $110 = 12 000 mm/min: a G0 along X runs 20 kHz; 1000 mm/s²: 100 Hz per ms.
    let mut b = bench(1000.0, 12_000.0);
    assert_eq!(b.line("G91"), "ok\r\n");
    b.trace = Some(Vec::new());
    assert_eq!(b.line("G0 X500"), "ok\r\n");
    b.run_ms(300);
    assert_eq!(b.shared.rate_hz(), 20_000);
    let t0 = b.timer.now();
    b.byte(0x97); // 25 %: 5 kHz in 150 ms
    b.run_ms(250);
    let t1 = b.timer.now();
    b.byte(0x96); // 50 %: 10 kHz in 50 ms
    b.run_ms(100);
    let t2 = b.timer.now();
    b.byte(0x95); // 100 %
    b.byte(0x92); // a feed override changes nothing on a G0
    b.run_to_idle(20_000);
    let tr = b.trace.take().unwrap();
    let d = reached(&tr, t0, 5_000) - t0;
    assert!((149 * MS..=153 * MS).contains(&d), "25 % after {} ms", d / MS);
    let d = reached(&tr, t1, 10_000) - t1;
    assert!((49 * MS..=53 * MS).contains(&d), "50 % after {} ms", d / MS);
    let d = reached(&tr, t2, 20_000) - t2;
    assert!((99 * MS..=103 * MS).contains(&d), "100 % after {} ms", d / MS);
    assert_walk_steps(&tr, 100.0, 1_400);
    assert_eq!(b.shared.positions(), [50_000, 0, 0]);

    // Feed 200 % on a running G1 at 150 mm/s: the axis's 200 mm/s binds (20 kHz, not 30).
    b.byte(0x90);
    b.trace = Some(Vec::new());
    assert_eq!(b.line("G1 X-400 F9000"), "ok\r\n");
    b.run_ms(300);
    assert_eq!(b.shared.rate_hz(), 15_000);
    for _ in 0..10 {
        b.byte(0x91);
    }
    assert_eq!(b.shared.overrides().feed, 200);
    b.run_ms(200);
    assert_eq!(b.shared.rate_hz(), 20_000);
    b.run_to_idle(20_000);
    let tr = b.trace.take().unwrap();
    assert_eq!(tr.iter().map(|e| e.1).max(), Some(20_000));
    assert_walk_steps(&tr, 100.0, 1_400);
    assert_eq!(b.shared.positions(), [10_000, 0, 0]);
}

#[test]
fn a_running_jog_ignores_the_overrides() {
    let mut b = bench(1000.0, 36_000.0);
    assert_eq!(b.line("$J=G91 X100 F6000"), "ok\r\n"); // 10 kHz
    b.run_ms(200);
    assert_eq!(b.shared.rate_hz(), 10_000);
    for _ in 0..5 {
        b.byte(0x92);
    }
    b.byte(0x97);
    b.run_ms(100);
    assert_eq!(b.shared.rate_hz(), 10_000);
    b.run_to_idle(5_000);
    assert_eq!(b.shared.positions(), [10_000, 0, 0]);
}

/// Grbl's junction speed limit (mm/s) from the two moves' unit vectors, every axis at `accel`.
fn grbl_junction(a: &[f64; 3], b: &[f64; 3], accel: f64, dev: f64) -> f64 {
    let cos: f64 = -(0..3).map(|i| a[i] * b[i]).sum::<f64>();
    if cos > 0.999999 {
        return 0.0;
    }
    if cos < -0.999999 {
        return f64::INFINITY;
    }
    let ju: Vec<f64> = (0..3).map(|i| b[i] - a[i]).collect();
    let n = ju.iter().map(|x| x * x).sum::<f64>().sqrt();
    let acc = (0..3).filter(|&i| ju[i].abs() / n > 1e-9).map(|i| accel / (ju[i].abs() / n)).fold(f64::INFINITY, f64::min);
    let s = (0.5 * (1.0 - cos)).sqrt();
    (acc * dev * s / (1.0 - s)).sqrt()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

    /// Override bytes at random times during a streamed chain of short G0/G1 moves: every
    /// rate change within a move is one walk at the move's acceleration, every junction stays
    /// within Grbl's junction-deviation limit and the axes' max rates, the chain still ends at
    /// the table's start (its deceleration fitted), and the counts are exact.
    #[test]
    fn overrides_during_a_chain_keep_accelerations_junctions_and_counts(
        moves in prop::collection::vec((-3.0f64..3.0, -3.0f64..3.0, -1.0f64..1.0, prop::option::weighted(0.8, 300.0f64..9_000.0)), 4..40),
        ovr in prop::collection::vec((0u32..3_000, prop::sample::select(vec![0x90u8, 0x91, 0x92, 0x93, 0x94, 0x95, 0x96, 0x97]), 1usize..=10), 1..16),
    ) {
        let (accel, rate) = (2_000.0, 12_000.0);
        let mut b = bench(accel as f32, rate as f32);
        // Absolute targets on a 0.01 mm grid (whole steps), and what the test expects of them.
        let mut pos = [0i64; 3];
        let mut lines = Vec::new();
        let mut seen: Vec<([i64; 3], [f64; 3], f64, f64)> = Vec::new(); // steps, unit, share, cap
        for (dx, dy, dz, f) in &moves {
            let d = [(dx * 100.0).round() as i64, (dy * 100.0).round() as i64, (dz * 100.0).round() as i64];
            if d == [0; 3] {
                continue;
            }
            for i in 0..3 {
                pos[i] += d[i];
            }
            let mm = pos.map(|p| p as f64 / 100.0);
            lines.push(match f {
                Some(f) => format!("G1 X{:.2} Y{:.2} Z{:.2} F{f:.0}", mm[0], mm[1], mm[2]),
                None => format!("G0 X{:.2} Y{:.2} Z{:.2}", mm[0], mm[1], mm[2]),
            });
            let len = d.iter().map(|s| (*s as f64 / 100.0).powi(2)).sum::<f64>().sqrt();
            let unit = d.map(|s| s as f64 / 100.0 / len);
            let umax = unit.iter().fold(0.0f64, |m, u| m.max(u.abs()));
            let master = d.iter().map(|s| s.unsigned_abs()).max().unwrap() as f64;
            seen.push((d, unit, master / len, rate / 60.0 / umax));
        }
        prop_assume!(seen.len() >= 2);
        b.trace = Some(Vec::new());
        let start = b.now_ms;
        let mut ovr = ovr;
        ovr.sort();
        let (mut next_line, mut next_ovr) = (0, 0);
        while next_line < lines.len() || next_ovr < ovr.len() {
            while next_ovr < ovr.len() && ovr[next_ovr].0 <= b.now_ms - start {
                for _ in 0..ovr[next_ovr].2 {
                    b.byte(ovr[next_ovr].1);
                }
                next_ovr += 1;
            }
            if next_line < lines.len() && !b.ctl.busy() {
                b.send(&lines[next_line]);
                b.send("\n");
                next_line += 1;
            }
            b.tick_ms();
        }
        b.run_to_idle(60_000);
        let tr = b.trace.take().unwrap();
        prop_assert_eq!(b.shared.positions().map(i64::from), pos, "counts exact");
        assert_walk_steps(&tr, accel * 100.0 / 1000.0, 1_800);
        // Junctions: the path speed as move k ends, against Grbl's limit and both moves'
        // axis-limited speeds (an override moves the nominal speed anywhere below those).
        let entry = 2.0 * accel / 1000.0; // the table's walk per ms, mm/s
        let v0_path = Settings::BENCH.ramp_start_hz as f64 / 100.0;
        for w in tr.windows(2) {
            let ((_, hz, d0), (_, _, d1)) = (w[0], w[1]);
            if d1 != d0 + 1 || hz == 0 {
                continue;
            }
            let a = &seen[d0 as usize];
            let v = hz as f64 / a.2;
            // The last move ends at rest.
            let limit = seen.get(d1 as usize).map_or(0.0, |n| grbl_junction(&a.1, &n.1, accel, 0.01).min(a.3).min(n.3));
            let period_ms = 1000.0 / hz as f64;
            let tol = 2.0 * entry * (1.0 + period_ms) + 0.5;
            prop_assert!(v <= limit.max(v0_path + entry) * 1.01 + tol, "junction {}: {:.2} mm/s over {:.2}", d0, v, limit);
        }
    }
}

#[test]
fn a_hold_while_an_override_ramps_ends_exactly_and_resumes_at_the_new_speed() {
    let mut b = bench(1000.0, 36_000.0);
    assert_eq!(b.line("G91"), "ok\r\n");
    assert_eq!(b.line("G1 X300 F12000"), "ok\r\n"); // 20 kHz
    b.run_ms(300);
    for _ in 0..5 {
        b.byte(0x92); // 50 %: walking down for 100 ms
    }
    b.run_ms(40);
    b.byte(b'!');
    b.run_ms(400);
    assert_eq!(b.shared.state(), ddastep::motion::shared::State::Held);
    let held = b.shared.positions();
    b.run_ms(50);
    assert_eq!(b.shared.positions(), held, "held");
    b.byte(0x91); // 60 % while held
    b.trace = Some(Vec::new());
    b.byte(b'~');
    b.run_ms(300);
    assert_eq!(b.shared.rate_hz(), 12_000, "resumed at 60 %");
    b.run_to_idle(10_000);
    let tr = b.trace.take().unwrap();
    assert!(tr.iter().all(|e| e.1 <= 12_000));
    assert_walk_steps(&tr, 100.0, 1_400);
    assert_eq!(b.shared.positions(), [30_000, 0, 0]);
}

#[test]
fn in_s_mode_a_feed_override_walks_the_running_move_to_half_as_an_s() {
    // 1000 mm/s² peak: X's master changes by at most 100 Hz per ms, and from 20 to 10 kHz as
    // an S lasting k = 2.075 times the trapezoid's 100 ms (`$41=1`, `$582=4`).
    let mut s = Settings::BENCH;
    s.accel = [1000.0; ddastep::MAX_AXES];
    s.shape = ddastep::motion::ramp::Shape::SCurve;
    let mut b = Bench::<3>::new(s);
    b.take();
    assert_eq!(b.line("G91"), "ok\r\n");
    b.trace = Some(Vec::new());
    assert_eq!(b.line("G1 X400 F12000"), "ok\r\n");
    b.run_ms(600);
    assert_eq!(b.shared.rate_hz(), 20_000);
    let t0 = b.timer.now();
    for _ in 0..5 {
        b.byte(0x92); // −10 % each
    }
    b.run_ms(400);
    b.run_to_idle(10_000);
    let tr = b.trace.take().unwrap();
    let down = reached(&tr, t0, 10_000) - t0;
    assert!((200 * MS..=215 * MS).contains(&down), "half speed after {} ms", down as f64 / MS as f64);
    // Gentle at the start (a tenth of the way in: s(0.1) = 2 % of the drop), half-way at half
    // the time (the S is symmetric).
    let early = rate_at(&tr, t0 + 21 * MS);
    assert!(early >= 19_600, "a tenth of the way: {early} Hz");
    let mid = rate_at(&tr, t0 + 104 * MS);
    assert!(mid.abs_diff(15_000) <= 300, "half-way down after 104 ms: {mid} Hz");
    assert_walk_steps(&tr, 100.0 * 1.03, 1_400);
    assert_eq!(b.shared.positions(), [40_000, 0, 0], "counts exact");
}
