use std::f64::consts::PI;

use super::*;

const XYZ: [char; 3] = ['X', 'Y', 'Z'];

fn run(modal: &Modal, line: &str) -> Result<(Modal, Action), u8> {
    execute(modal, line, &XYZ, false)
}

#[test]
fn error_codes_match_grbl() {
    let m = Modal::new(3, vec![0.0; 3]);
    assert_eq!(run(&m, "G1X10").unwrap_err(), 22, "G1 with no feed yet");
    assert_eq!(run(&m, "G5X1").unwrap_err(), 20);
    assert_eq!(run(&m, "G0G1X1").unwrap_err(), 21);
    assert_eq!(run(&m, "G0X1X2").unwrap_err(), 25);
    assert_eq!(run(&m, "1X").unwrap_err(), 1);
    assert_eq!(run(&m, "G0X").unwrap_err(), 2);
    assert_eq!(run(&m, "G1X1F-5").unwrap_err(), 4);
    assert_eq!(run(&m, "G4").unwrap_err(), 28);
    assert_eq!(run(&m, "G0X1P2").unwrap_err(), 36);
    assert_eq!(run(&m, "G2X1F100").unwrap_err(), 35);
    assert_eq!(run(&m, "G2Z1I1F100").unwrap_err(), 32);
    assert_eq!(run(&m, "G80X1").unwrap_err(), 31);
    assert_eq!(run(&m, "G53G2X1I1F10").unwrap_err(), 30);
    assert_eq!(run(&m, "G59.1").unwrap_err(), 29);
    assert_eq!(run(&m, "M3.5").unwrap_err(), 23);
    assert_eq!(
        run(&m, "G0U1").unwrap_err(),
        20,
        "no U axis on a 3-axis GRBL"
    );
    assert_eq!(run(&m, "T300").unwrap_err(), 38);
    assert_eq!(run(&m, "G2X10Y0R4F100").unwrap_err(), 34);
    assert_eq!(run(&m, "G2X10Y0I1J0F100").unwrap_err(), 33);
}

#[test]
fn moves_arcs_and_inverse_time() {
    let m = Modal::new(3, vec![0.0; 3]);
    let (m, a) = run(&m, "G21G90G1X3Y4F600").unwrap();
    assert_eq!(a.moves.len(), 1);
    assert!((a.moves[0].length_mm - 5.0).abs() < 1e-12);
    assert_eq!(a.moves[0].speed, Speed::Feed(10.0));
    // Half circle of radius 5 from (3,4) about (3,-1): length 5*pi.
    let (m, a) = run(&m, "G2X3Y-6I0J-5").unwrap();
    assert!(
        (a.moves[0].length_mm - 5.0 * PI).abs() < 1e-9,
        "{:?}",
        a.moves
    );
    // Full circle when start == end.
    let (m, a) = run(&m, "G3X3Y-6I0J5").unwrap();
    assert!((a.moves[0].length_mm - 10.0 * PI).abs() < 1e-9);
    // G93: F = 1/minutes; a 10 mm move with F6 takes 10 s: 1 mm/s.
    let (m, a) = run(&m, "G93G1X13Y-6F6").unwrap();
    assert_eq!(a.moves[0].speed, Speed::Feed(1.0));
    assert_eq!(
        run(&m, "G1X0").unwrap_err(),
        22,
        "G93 needs F on every move"
    );
    // Back to G94 the feed is undefined until given.
    assert_eq!(run(&m, "G94G1X0").unwrap_err(), 22);
    let (m, a) = run(&m, "G20G91G0X1").unwrap();
    assert!((a.moves[0].target[0] - (13.0 + 25.4)).abs() < 1e-9);
    assert_eq!(m.gc_report(), "G0 G54 G17 G20 G91 G93 M5 M9 T0 F0 S0");
    let (_, a) = run(&m, "M3S1000").unwrap();
    assert!(a.sync);
    let (_, a) = run(&m, "G4P0.5").unwrap();
    assert_eq!(a.dwell_s, Some(0.5));
}

#[test]
fn extra_axes_when_configured() {
    let axes = ['X', 'Y', 'U', 'V'];
    let m = Modal::new(4, vec![0.0; 4]);
    let (_, a) = execute(&m, "G1X3Y0U0V4F60", &axes, false).unwrap();
    assert!((a.moves[0].length_mm - 5.0).abs() < 1e-12);
}

#[test]
fn jog_rules() {
    let m = Modal::new(3, vec![0.0; 3]);
    let (kept, a) = execute(&m, "G91X10F600", &XYZ, true).unwrap();
    assert_eq!(a.moves.len(), 1);
    assert!(!kept.incremental, "jog leaves modal state alone");
    assert_eq!(kept.position, vec![10.0, 0.0, 0.0]);
    assert_eq!(execute(&m, "G91X10", &XYZ, true).unwrap_err(), 22);
    assert_eq!(execute(&m, "G0X10F10", &XYZ, true).unwrap_err(), 16);
}

#[test]
fn g10_and_negative_words_answer_as_grbl_does() {
    let m = Modal::new(3, vec![0.0; 3]);
    // GRBL 1.1 gcode.c: negative F, N, P, S, T are error:4 when read.
    for line in [
        "G10L2P-1",
        "G10L2P-1X1",
        "N-1G0X1",
        "G4P-0.1",
        "S-2M3",
        "T-1",
    ] {
        assert_eq!(run(&m, line).unwrap_err(), 4, "{line}");
    }
    // G10: no axis words 26, P or L missing 28, trunc(P) > 6 29, L not 2/20 20.
    assert_eq!(run(&m, "G10L2P1").unwrap_err(), 26);
    assert_eq!(run(&m, "G10P1X1").unwrap_err(), 28);
    assert_eq!(run(&m, "G10L2P7X1").unwrap_err(), 29);
    assert_eq!(run(&m, "G10L2P1000000000000X1").unwrap_err(), 29);
    assert_eq!(run(&m, "G10L3P1X1").unwrap_err(), 20);
    assert_eq!(run(&m, "G10L-2P1X1").unwrap_err(), 20);
    // P is truncated, as GRBL does: P6.9 is G59, P0.5 the active system.
    let (m6, _) = run(&m, "G10L2P6.9X7").unwrap();
    assert_eq!(m6.offsets[5][0], 7.0);
    let (m0, _) = run(&m, "G10L2P0.5X3").unwrap();
    assert_eq!(m0.offsets[m.coord][0], 3.0);
    // A number beyond the firmware's 32-bit float is a bad number, not infinity.
    for digits in [39, 400] {
        let huge = format!("G0X{}", "9".repeat(digits));
        assert_eq!(run(&m, &huge).unwrap_err(), 2, "{digits} digits");
    }
    assert!(run(&m, &format!("G0X{}", "9".repeat(38))).is_ok());
}
