//! `--serve --vcd --json` records without keeping the pin edges: the serve loop's recorder
//! takes them off the board every turn, and writes the same VCD and the same report as the
//! whole-run writers on an identical board that kept every edge.

use ddastep_bench::emu::{firmware_elf, Board, HZ};
use ddastep_bench::serve::Recorder;

const JOB: &str = "G91\nM3 S500\nG1 X1 Y0.5 F600\nG1 X-0.5 Y0.5\nM5\nG1 Z0.2\n";

// a booted board with the job on the serial line
fn board() -> Board {
    let mut b = Board::load(firmware_elf().expect("firmware builds")).expect("ELF loads");
    b.run_seconds(0.05).unwrap();
    b.serial_send(JOB.as_bytes());
    b
}

#[test]
fn served_recording_streams_the_same_vcd_and_report() {
    let dir = std::env::temp_dir().join(format!("ddastep-serve-record-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (whole, streamed) = (dir.join("whole.vcd"), dir.join("streamed.vcd"));
    let end = 50 * HZ / 1000 + HZ * 7 / 10;

    // The whole run kept, written at the end (run in the same 1 ms slices: where runs stop
    // can move a later edge by a cycle or two, so both boards stop at the same cycles).
    let mut a = board();
    while a.cycles() < end {
        a.run_until_cycle((a.cycles() + HZ / 1000).min(end)).unwrap();
    }
    assert!(a.edges().len() > 1000, "the job moved: {} edges", a.edges().len());
    a.write_vcd(&whole).unwrap();
    let want = a.report();

    // The serve loop's way: 1 ms slices, the recorder after each.
    let mut b = board();
    let mut rec = Recorder::new(&b, Some(&streamed), true).unwrap();
    let mut most = 0;
    while b.cycles() < end {
        b.run_until_cycle((b.cycles() + HZ / 1000).min(end)).unwrap();
        most = most.max(b.edges().len());
        rec.turn(&mut b).unwrap();
        assert!(b.edges().is_empty() && b.move_ends().is_empty(), "the recorder drains the board's edge buffer");
    }
    let got = rec.finish(&mut b).unwrap().expect("a report");
    // The board never held more than one slice's edges (a few at 2.5 kHz).
    assert!(most < 100, "{most} edges held in one slice");

    let (w, g) = (std::fs::read_to_string(&whole).unwrap(), std::fs::read_to_string(&streamed).unwrap());
    assert!(w.contains("SPINDLE_PWM_DUTY") && w.lines().filter(|l| l.starts_with('#')).count() > 500, "{}", &w[..w.len().min(2000)]);
    if let Some((k, (a, b))) = w.lines().zip(g.lines()).enumerate().find(|(_, (a, b))| a != b) {
        panic!("streamed VCD differs from the whole-run one at line {}: {a:?} (whole) vs {b:?} (streamed); files in {}", k + 1, dir.display());
    }
    assert_eq!(g.len(), w.len(), "streamed VCD length differs; files in {}", dir.display());
    let json = |r: &ddastep_bench::emu::Report| serde_json::to_string_pretty(r).unwrap();
    assert_eq!(json(&got), json(&want));
    assert!(got.moves >= 3 && got.spindle.pin_rises[0] == 1, "{got}");
    let _ = std::fs::remove_dir_all(&dir);
}
