//! Work coordinates as Grbl 1.1 keeps them: G54–G59 with G10 L2/L20, G92/G92.1, G53, G28/G30
//! with G28.1/G30.1, G43.1/G49, `$#`, `$G`, `WCO:`/`WPos:` in reports, and the persistent store.

mod protocol_rig;

use ddastep::grbl::store::Stored;
use protocol_rig::Bench;

/// The `$#` listing of Grbl's commands.md, rebuilt with G10 L2, G28.1 and G30.1.
#[test]
fn params_listing_matches_grbls_documentation() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    for line in ["G10 L2 P1 X4", "G10 L2 P2 X4 Y6 Z7", "G53 G0 X1 Y2", "G28.1", "G53 G0 X4 Y6", "G30.1", "G0 X0 Y0"] {
        assert_eq!(b.line(line), "ok\r\n", "{line}");
    }
    b.run_to_idle(5000);
    assert_eq!(
        b.line("$#"),
        "[G54:4.000,0.000,0.000]\r\n[G55:4.000,6.000,7.000]\r\n[G56:0.000,0.000,0.000]\r\n\
         [G57:0.000,0.000,0.000]\r\n[G58:0.000,0.000,0.000]\r\n[G59:0.000,0.000,0.000]\r\n\
         [G28:1.000,2.000,0.000]\r\n[G30:4.000,6.000,0.000]\r\n[G92:0.000,0.000,0.000]\r\n\
         [TLO:0.000]\r\n[PRB:0.000,0.000,0.000:0]\r\nok\r\n"
    );
    // Each write reached the store (and asked for a flash write once idle).
    assert_eq!(b.ctl.stored().coords.get::<3>(1), [4.0, 6.0, 7.0]);
    assert!(b.actions.iter().filter(|a| a.save).count() >= 4);
}

#[test]
fn zero_with_g10_l20_then_go_to_zero_with_g53_and_g90() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G0 X10 Y5 Z-2");
    // UGS/CNCjs "zero X Y": the current position reads 0 in the active system (P0 = G54).
    assert_eq!(b.line("G10 L20 P0 X0 Y0"), "ok\r\n");
    b.run_to_idle(5000);
    assert!(b.line("$#").starts_with("[G54:10.000,5.000,0.000]\r\n"));
    b.line("$10=0");
    let s = b.status();
    assert!(s.starts_with("<Idle|WPos:0.000,0.000,-2.000|"), "{s}");
    // P1 is G54 too: zero Z.
    b.line("G10 L20 P1 Z0");
    let s = b.status();
    assert!(s.starts_with("<Idle|WPos:0.000,0.000,0.000|") && s.contains("|WCO:10.000,5.000,-2.000"), "{s}");
    // Work moves are offset, G53 moves are not (and G53 lasts one block).
    b.line("G90 G0 X1 Y1");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [1100, 600, -200]);
    b.line("G53 G0 X0 Y0 Z0");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [0, 0, 0]);
    b.line("X2");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [1200, 0, 0]);
    b.line("G0 X0 Y0 Z0");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [1000, 500, -200]);
    // The store holds G54; a soft reset keeps it (and the position: no motion, no alarm).
    assert_eq!(b.ctl.stored().coords.get::<3>(0), [10.0, 5.0, -2.0]);
    b.byte(0x18);
    b.take();
    assert!(b.line("$#").starts_with("[G54:10.000,5.000,-2.000]\r\n"));
    assert!(b.status().starts_with("<Idle|WPos:0.000,0.000,0.000|"));
}

#[test]
fn g54_to_g59_select_and_g92_offsets_within_them() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G10 L2 P3 X-1 Y-2 Z-3");
    assert_eq!(b.line("G56"), "ok\r\n");
    assert_eq!(b.line("$G"), "[GC:G0 G56 G17 G21 G90 G94 M5 M9 T0 F0 S0]\r\nok\r\n");
    b.line("G0 X0 Y0 Z0");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [-100, -200, -300]);
    // G92 X5: here reads X5 in G56; G54 is unaffected apart from the shared G92 offset.
    b.line("G92 X5");
    assert!(b.line("$#").contains("[G92:-5.000,0.000,0.000]"));
    b.line("G0 X6");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions()[0], 0);
    b.line("G92.1");
    b.line("G0 X6");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions()[0], 500);
    // M2 goes back to G54 (Grbl's program-end defaults).
    b.line("M2");
    assert!(b.line("$G").starts_with("[GC:G1 G54 "));
    // G10 L20 with G92 and the tool length offset in force: WPos = MPos − WCS − G92 − TLO.
    b.line("G92 Z1");
    b.line("G43.1 Z0.5");
    b.line("G10 L20 P2 Z0");
    // G92 Z1 at MPos −3 made G92 = −4; G55.Z = MPos −3 − G92 (−4) − TLO 0.5 − WPos 0.
    assert!(b.line("$#").contains("[G55:0.000,0.000,0.500]"));
}

#[test]
fn g28_and_g30_go_through_the_intermediate_point() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G0 X3 Y4 Z5");
    b.line("G28.1");
    b.line("G0 X0 Y0 Z0");
    b.run_to_idle(5000);
    // G28 with axis words: through X1 (Y and Z stay), then only X goes to the stored X.
    assert_eq!(b.line("G28 X1"), "ok\r\n");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [300, 0, 0]);
    assert_eq!(b.line("G28"), "ok\r\n");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [300, 400, 500]);
    b.line("G91 G30 Z-1");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [300, 400, 0], "G30 is at the origin: Z goes there after Z-1");
    assert_eq!(b.line("G80 G28 X0"), "error:31\r\n");
}

#[test]
fn tool_length_offset_shifts_z_targets_and_is_cleared_by_reset() {
    let mut b = Bench::<3>::with_defaults();
    b.take();
    assert_eq!(b.line("G43.1 Z2.5"), "ok\r\n");
    assert!(b.line("$#").contains("[TLO:2.500]"));
    b.line("G0 Z0");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [0, 0, 250]);
    b.line("G49");
    b.line("G0 Z0");
    b.run_to_idle(5000);
    assert_eq!(b.shared.positions(), [0, 0, 0]);
    b.line("G43.1 Z1");
    b.line("G92 X3");
    b.byte(0x18);
    b.take();
    assert!(b.line("$#").ends_with("[G92:0.000,0.000,0.000]\r\n[TLO:0.000]\r\n[PRB:0.000,0.000,0.000:0]\r\nok\r\n"));
}

#[test]
fn wco_and_ov_follow_grbls_refresh_counters() {
    let mut b = Bench::<3>::with_defaults();
    let mut seen = Vec::new();
    for _ in 0..22 {
        let s = b.status();
        seen.push((s.contains("|WCO:"), s.contains("|Ov:")));
    }
    // Idle: WCO at 1, 11, 21; Ov the report after each WCO (2, 12, 22).
    let wco: Vec<usize> = (0..22).filter(|&i| seen[i].0).map(|i| i + 1).collect();
    let ov: Vec<usize> = (0..22).filter(|&i| seen[i].1).map(|i| i + 1).collect();
    assert_eq!(wco, [1, 11, 21]);
    assert_eq!(ov, [2, 12, 22]);
    // An offset change brings WCO into the very next report; an override change Ov.
    b.line("G92 X1");
    assert!(b.status().contains("|WCO:-1.000,0.000,0.000>"));
    b.shared.set_overrides(ddastep::motion::moves::Overrides { feed: 120, rapid: 50, spindle: 100 });
    assert!(b.status().ends_with("|Ov:120,50,100>\r\n"));
    // $10=2: WPos and the buffer state.
    b.line("$10=2");
    let s = b.status();
    assert!(s.starts_with(&format!("<Idle|WPos:1.000,0.000,0.000|Bf:{},128|FS:0,0", protocol_rig::BLOCKS)), "{s}");
}

#[test]
fn coordinates_survive_a_settings_change_in_the_stored_image() {
    let mut b = Bench::<3>::with_defaults();
    b.line("G10 L2 P6 X1.5 Y-2.25 Z3");
    b.line("$N0=G55");
    b.line("$I=MILL1");
    b.line("$110=1234");
    let img = b.ctl.image();
    let s = Stored::decode(&img).expect("valid image");
    assert_eq!(s.coords.get::<3>(5), [1.5, -2.25, 3.0]);
    assert_eq!(s.settings.max_rate[0], 1234.0);
    assert_eq!(s.startup[0].as_bytes(), b"G55");
    assert_eq!(s.build_info.as_bytes(), b"MILL1");
    // A new controller from that image: same listing, and the startup line runs.
    let mut c = Bench::<3>::with_stored(s);
    c.take();
    c.tick_ms();
    assert_eq!(c.take(), ">G55:ok\r\n");
    assert!(c.line("$#").contains("[G59:1.500,-2.250,3.000]"));
    assert!(c.line("$G").starts_with("[GC:G0 G55 "));
    assert!(c.line("$I").starts_with("[VER:1.1h.ddastep:MILL1]\r\n"));
}
