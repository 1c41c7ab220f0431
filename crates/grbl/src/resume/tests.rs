use super::*;
use crate::program::CleanOptions;

fn program(text: &str) -> Program {
    Program::parse(text, CleanOptions::default()).expect("test program parses")
}

/// The preamble for resuming `text` at the first line whose text is `at`.
fn preamble_at(text: &str, at: &str) -> Vec<String> {
    let p = program(text);
    let line = p.lines().iter().find(|l| l.text == at).expect(at).number;
    preamble(&p, line).unwrap_or_else(|e| panic!("{e}"))
}

/// The emitter's grbl-xyuv program for the `panel` sample
/// (`crates/emitter/tests/snapshots/dialects__grbl-xyuv.snap`).
const HOT_WIRE: &str = "(cellsuite emitter: job panel, profile grbl-xyuv)
G17 G21 G90 G93
G0 X130.000 Y60.000 U130.000 V60.000
M3 S300
G4 P2.000
G1 X120.000 Y60.000 U120.000 V60.000 F36.0000
G1 X60.000 Y66.000 U80.000 V64.000 F4.9752
G1 X60.000 Y54.000 U80.000 V56.000 F25.0000
G1 X120.000 Y60.000 U120.000 V60.000 F4.9752
G1 X130.000 Y60.000 U130.000 V60.000 F36.0000 S280
M5
G94
M2
";

/// The emitter's grbl-laser program for the `plate` sample
/// (`crates/emitter/tests/snapshots/dialects__grbl-laser.snap`).
const LASER: &str = "(cellsuite emitter: job plate, profile grbl-laser)
G17 G21 G90 G94
G0 X0.000 Y0.000
G0 X70.000 Y50.000
M4 S800
G4 P0.200
G3 X69.833 Y48.178 I-10.000 J-0.002 F1200.000
G3 X70.000 Y50.000 I-9.833 J1.820
M5
G0 X20.000 Y25.000
M4 S800
G4 P0.200
G1 X92.000 Y25.000
G3 X100.000 Y33.000 I0.000 J8.000
M5
M2
";

/// The emitter's pierce-height sequence (`dialects__linuxcnc-plasma.snap`) on a GRBL XYZ
/// table: travel at Z10, pierce at Z3.8, cut at Z1.5; the second cut changes its feed.
const PLASMA: &str = "G17 G21 G90 G94
G0 Z10.000
G0 X0.000 Y0.000
G0 X70.000 Y50.000
G0 Z3.800
M3 S80
G4 P0.500
G1 Z1.500 F1200.000
G3 X69.833 Y48.178 I-10.000 J-0.002
G3 X70.000 Y50.000 I-9.833 J1.820
M5
G0 Z10.000
G0 X20.000 Y25.000
G0 Z3.800
M3 S80
G4 P0.500
G1 Z1.500
G1 X92.000 Y25.000 F600
G3 X100.000 Y33.000 I0.000 J8.000
M5
G0 Z10.000
M2
";

#[test]
fn the_first_line_needs_no_preamble() {
    let p = program(HOT_WIRE);
    assert!(preamble(&p, 1).unwrap().is_empty(), "a comment before it");
    assert!(preamble(&p, 2).unwrap().is_empty(), "the first G-code line");
    assert!(preamble(&p, 0).unwrap().is_empty());
    assert!(preamble(&p, 99).unwrap().is_empty(), "past the end");
}

#[test]
fn a_g93_hot_wire_cut_goes_on_in_g93_with_the_wire_heated_as_the_program_heated_it() {
    assert_eq!(
        preamble_at(HOT_WIRE, "G1 X60.000 Y54.000 U80.000 V56.000 F25.0000"),
        [
            "M5 M9",
            "G17 G21 G90 G54",
            "G0 X60 Y66 U80 V64",
            "M3 S300",
            "G4 P2",
            "G90 G93 S300",
        ]
    );
    // The heat goes on with the S of the heat-on; S280 is the resumed line's own.
    let last = "G1 X130.000 Y60.000 U130.000 V60.000 F36.0000 S280";
    assert_eq!(preamble_at(HOT_WIRE, last).last().unwrap(), "G90 G93 S300");
    // After the heat went off and the program's own G94 (which left F undefined).
    assert_eq!(
        preamble_at(HOT_WIRE, "M2"),
        [
            "M5 M9",
            "G17 G21 G90 G54",
            "G0 X130 Y60 U130 V60",
            "G1 G93 F1",
            "G90 G94 S280",
        ]
    );
}

#[test]
fn a_g93_line_without_a_motion_word_gets_g1_with_a_legal_f() {
    let text = "G93\nG0 X0\nM3 S5\nG1 X1 F10\nX2 F20\n";
    assert_eq!(
        preamble_at(text, "X2 F20"),
        [
            "M5 M9",
            "G17 G21 G90 G54",
            "G0 X1",
            "M3 S5",
            "G1 G90 G93 F20 S5"
        ]
    );
}

#[test]
fn g94_without_a_feed_after_g93_keeps_the_feed_undefined() {
    let text = "G93 G1 X1 F10\nG94\nM3 S1\n";
    assert_eq!(
        preamble_at(text, "M3 S1"),
        [
            "M5 M9",
            "G17 G21 G90 G54",
            "G0 X1",
            "G1 G93 F1",
            "G90 G94 S0"
        ]
    );
}

#[test]
fn a_laser_cut_in_m4_goes_on_with_the_pierce_dwell_and_the_last_feed() {
    assert_eq!(
        preamble_at(LASER, "G3 X70.000 Y50.000 I-9.833 J1.820"),
        [
            "M5 M9",
            "G17 G21 G90 G54",
            "G0 X69.833 Y48.178",
            "M4 S800",
            "G4 P0.2",
            "G90 G94 F1200 S800",
        ]
    );
    // At the travel between cuts the beam stays off.
    assert_eq!(
        preamble_at(LASER, "G0 X20.000 Y25.000"),
        [
            "M5 M9",
            "G17 G21 G90 G54",
            "G0 X70 Y50",
            "G90 G94 F1200 S800"
        ]
    );
}

#[test]
fn a_plasma_cut_is_pierced_again_at_the_pierce_height_and_plunged_at_the_programs_feed() {
    assert_eq!(
        preamble_at(PLASMA, "G3 X100.000 Y33.000 I0.000 J8.000"),
        [
            "M5 M9",
            "G17 G21 G90 G54",
            "G0 Z10",
            "G0 X92 Y25",
            "G0 Z3.8",
            "M3 S80",
            "G4 P0.5",
            "G1 G94 Z1.5 F1200",
            "G90 G94 F600 S80",
        ]
    );
    // At the travel: up to the travel height, across, no torch.
    assert_eq!(
        preamble_at(PLASMA, "G0 X20.000 Y25.000"),
        [
            "M5 M9",
            "G17 G21 G90 G54",
            "G0 Z10",
            "G0 X70 Y50",
            "G90 G94 F1200 S80"
        ]
    );
    // At the dwell right after the torch went on: pierced again, not plunged yet.
    let p = program(PLASMA);
    let dwell = p
        .lines()
        .iter()
        .filter(|l| l.text == "G4 P0.500")
        .nth(1)
        .unwrap();
    assert_eq!(
        preamble(&p, dwell.number).unwrap(),
        [
            "M5 M9",
            "G17 G21 G90 G54",
            "G0 Z10",
            "G0 X20 Y25",
            "G0 Z3.8",
            "M3 S80",
            "G0 G90 G94 F1200 S80"
        ]
    );
}

#[test]
fn every_modal_group_is_restored() {
    // Plane, inches (positions and F in inches), work offset, incremental distance, coolant
    // and tool.
    let text = "G18 G20 G55\nT2\nG0 X1 Y2 Z0.5\nM7\nM8\nG91\nG1 X1 F10\nG1 X1\n";
    assert_eq!(
        preamble(&program(text), 8).unwrap(),
        [
            "M5 M9",
            "G18 G20 G90 G55",
            "G0 Z0.5",
            "G0 X2 Y2",
            "M7",
            "M8",
            "G91 G94 F10 S0 T2"
        ]
    );
    // M2 leaves GRBL's program-end defaults: G1 G17 G90 G94 G54 M5 M9 (its own line, under
    // G93 with no F, left F at 0).
    let text = "G19 G93 M3 S9 M8\nG1 X1 F3\nM2\nX0\n";
    assert_eq!(
        preamble(&program(text), 4).unwrap(),
        [
            "M5 M9",
            "G17 G21 G90 G54",
            "G0 X1",
            "G1 G93 F1",
            "G90 G94 S9"
        ]
    );
}

#[test]
fn what_the_resume_cannot_rebuild_is_refused_naming_the_line() {
    for (text, line, said) in [
        ("G21\nG43.1 Z2\nG1 X1 F100\n", 2, "G43.1 sets a state"),
        ("G21\nG41\nG1 X1 F100\n", 2, "G41 sets a state"),
        ("G21\nM6 T2\nG1 X1 F100\n", 2, "M6 sets a state"),
        ("G21\nG1 X1 E3 F100\nG1 X2\n", 2, "word E is not GRBL"),
        ("G28\nM3 S1\nG1 X1 F100\n", 1, "X is not known (G28/G30"),
        ("G0 X1\nG91\nG1 Y1 F100\nG1 Y2\n", 3, "Y is not known"),
        ("G0 X1\nG53 G0 X5\nM3 S1\nG1 X1 F100\n", 2, "G53"),
        ("G0 X1\nG55\nM3 S1\nG1 X2 F100\n", 2, "coordinate system"),
        ("$H\nG0 Y1\nM3 S1\nG1 X2 F100\n", 1, "homing or jogging"),
        ("G0 X1\nM4 S1\nG1 X2 Y3 F100\n", 3, "where Y starts"),
        ("G0 X10\nG92 X0\nG1 X1 F100\n", 2, "G92 offset"),
        (
            "G0 X0\nG2 X1 I1 F100\nM5\nX2 I1\n",
            4,
            "moves in the arc mode G2",
        ),
    ] {
        let p = Program::parse(
            text,
            CleanOptions {
                allowed_commands: vec!["$H".into()],
                ..CleanOptions::default()
            },
        )
        .unwrap();
        let e = preamble(&p, p.lines().last().unwrap().number).expect_err(text);
        assert_eq!(e.line, line, "{text:?}: {e}");
        assert!(e.to_string().contains(said), "{text:?}: {e}");
        assert!(e.to_string().starts_with(&format!("line {line} (`")), "{e}");
    }
}

#[test]
fn what_is_lost_and_found_again_is_fine() {
    // Homed, an offset set and cleared, X set again: the resumed line moves only X, so Y and
    // Z (unknown since the homing and the G92.1) stay where the machine has them.
    let text = "$H\nG0 X10 Y0\nG92 X0\nG92.1\nG0 X5\nG1 X6 F100\n";
    let p = Program::parse(
        text,
        CleanOptions {
            allowed_commands: vec!["$H".into()],
            ..CleanOptions::default()
        },
    )
    .unwrap();
    assert_eq!(
        preamble(&p, 6).unwrap(),
        ["M5 M9", "G17 G21 G90 G54 G92.1", "G0 X5", "G90 G94 S0"]
    );
}

#[test]
fn every_preamble_line_is_a_line_grbl_takes() {
    for text in [HOT_WIRE, LASER, PLASMA] {
        let p = program(text);
        for l in &p.lines()[1..] {
            let pre = preamble(&p, l.number).unwrap_or_else(|e| panic!("{e}"));
            let parsed = Program::from_clean_lines(&pre).expect("clean");
            assert_eq!(parsed.len(), pre.len());
            assert!(pre.iter().all(|l| l.len() < 70), "{pre:?}");
            assert!(pre
                .iter()
                .all(|l| !crate::program::is_controller_command(l)));
        }
    }
}
