//! Seed 002 Table 4: the G-Wing test section weighs 36.2 g and builds in 2:10 (Pronterface's
//! estimate). Ours, for the Table 2 wing's root section (right side, next to the centre), by
//! three estimators, and Pronterface itself (Printrun from PyPI) on our emitted program.
//!
//! **Why ours differ, and by how much each part.** Root section, 650 layers of 0.2 mm:
//!
//! | estimator                                    | time      |
//! |----------------------------------------------|-----------|
//! | Σ L/v at the asked feeds                     | 131.9 min |
//! | Pronterface's method (Printrun `gcoder`)     | 138.7 min |
//! | Marlin 2's planner, stock settings           | 136.5 min |
//! | paper (Pronterface, its own section)         | 130 min   |
//!
//! - *The estimator* is worth +5 % (Pronterface's feed-change and reversal terms at a fixed
//!   2000 mm/s²) and +3.5 % (Marlin: junction deviation, the 16-block look-ahead, E held to
//!   25 mm/s) over Σ L/v. With the paper's own estimator our section takes 138.7 min, 7 % over
//!   2:10, while laying 9 % less plastic.
//! - *The section.* At Table 3's 0.5 × 0.2 mm beads, 40 mm/s and PLA's 1240 kg/m³, a gram of
//!   bead takes 3.36 min to lay, so the paper's 36.2 g alone needs ≥ 121.6 min, leaving at most
//!   8.4 min (6.5 % of 2:10) for every travel, Z-hop, retract and prime of 650 layers: about
//!   60 mm of travel a layer at 80 mm/s. Our section lays its 32.95 g in 111.2 min and spends
//!   20 % of its time off the bead (17.1 min of travel, 126.5 mm a layer: from each spar's end
//!   to the next spar, 7 retracts and no Z-hop a layer). Until the layer order alternated
//!   (each layer starting where the last ended) and Z-hops were kept to travels that cross a
//!   printed bead, it spent a third there: 317 mm of travel and 7 Z-hops a layer (the way back
//!   from the LE-most spar to a fixed start at the TE; 158.4 / 166.5 / 177.7 min by the three
//!   estimators). What remains is the spar row itself, so the paper's section had fewer or
//!   shorter spar-to-spar travels, or figures made under other settings than Table 3; its
//!   planform is not given.
//! - *The mass* (−9 %): the Kite's planform is not given (ours is an assumed elliptic chord,
//!   root 173 mm); the section's mass is nearly all perimeter (¾ of the bead), so a root chord
//!   ~10 % larger gives 36.2 g. G-Wing's own mass counts filament (ρ·πd²/4·E: FlowMult
//!   1.25·π/4 = 0.98 of the bead volume, plus its first-layer ×1.2 and skirt ×1.5), within 2 %
//!   of the bead volume here.
//!
//! - *Our program as written* (the emitter's Marlin G-code, `z_hop_only_when_crossing` in the
//!   shipped profile) takes the same 136.5 min by the Marlin model, and 138.7 min by Printrun
//!   with arcs written as lines (142.5 min with the G2/G3 arcs the shipped profile fits, which
//!   gcoder mistimes). Until issue 24 it took 231.7 min: the emitter wrote travel as G0 without
//!   F, which Marlin (no `G0_FEEDRATE` in stock builds) and Pronterface run at the modal feed,
//!   the last retract's 35 mm/s instead of 80 mm/s.
//!
//! So: our figures are pinned to 0.5 % (the pipeline is deterministic; one spar more per layer
//! moves the mass ~2 %), and against the paper the mass within 10 % and the time within 10 %,
//! with the explanation: the estimators within 6 % of each other, the paper's pair consistent
//! only with < 7 % off-bead time where ours has > 15 %.

use cell_wing::estimate::{build_time_s, mass_g};
use cell_wing::layers::{moves, Layer, Move, MoveKind};
use cell_wing::marlin::{
    blocks_from_moves, marlin_time_s, pronterface_time_s, read_gcode, FirmwareMotion,
};
use cell_wing::section::Side;
use cell_wing::spec::{Wing, WingSpec};

/// Table 4, G-Wing column.
const PAPER_MASS_G: f64 = 36.2;
const PAPER_TIME_MIN: f64 = 130.0;

fn repo(path: &str) -> String {
    format!("{}/../../{path}", env!("CARGO_MANIFEST_DIR"))
}

fn root_section() -> (Wing, Vec<Layer>) {
    let spec =
        WingSpec::load(repo("config/wings/gwing-table2.yaml")).unwrap_or_else(|e| panic!("{e}"));
    let wing = Wing::design(spec).unwrap_or_else(|e| panic!("{e}"));
    let i = wing
        .sections
        .iter()
        .position(|s| s.side == Side::Right && s.index == 1)
        .expect("a first right section");
    let layers = wing.layers(i).expect("its layers");
    (wing, layers)
}

/// Travel (XY, mm) and Z-hops per layer.
fn travel_and_hops_per_layer(mv: &[Move], layers: usize) -> (f64, f64) {
    let mut prev = mv[0].to;
    let (mut travel, mut hops) = (0.0, 0);
    for m in mv {
        match m.kind {
            MoveKind::Travel => travel += (m.to[0] - prev[0]).hypot(m.to[1] - prev[1]),
            MoveKind::Lift => hops += 1,
            _ => {}
        }
        prev = m.to;
    }
    (travel / layers as f64, f64::from(hops) / layers as f64)
}

/// Σ L/v over the moves of `kind` (deposits when `deposit`), min.
fn minutes(mv: &[Move], deposit: bool) -> f64 {
    let mut prev = mv[0].to;
    let mut t = 0.0;
    for m in mv {
        if matches!(m.kind, MoveKind::Deposit(_)) == deposit {
            t += cell_geometry::distance3(prev, m.to) / m.feed_mm_s;
        }
        prev = m.to;
    }
    t / 60.0
}

fn within(value: f64, expected: f64, tolerance: f64) -> bool {
    (value / expected - 1.0).abs() <= tolerance
}

#[test]
fn root_section_mass_and_time_against_table_4() {
    let (wing, layers) = root_section();
    let b = &wing.spec.build;
    let mv = moves(&layers, &wing.spec.build_params());
    let mass = mass_g(&layers, b.extrusion_width_mm, b.density_kg_m3);
    let feeds = build_time_s(&mv, None) / 60.0;
    let marlin = build_time_s(&mv, Some(FirmwareMotion::MARLIN_2_DEFAULTS)) / 60.0;
    let pronterface = pronterface_time_s(&blocks_from_moves(&mv)) / 60.0;
    let (travel, hops) = travel_and_hops_per_layer(&mv, layers.len());
    eprintln!(
        "root section: {mass:.2} g; Σ L/v {feeds:.2} min, Pronterface {pronterface:.2} min, \
         Marlin {marlin:.2} min; travel {travel:.1} mm and {hops:.2} Z-hops a layer; paper \
         {PAPER_MASS_G} g, {PAPER_TIME_MIN} min"
    );
    // Ours, pinned.
    for (what, value, pinned) in [
        ("mass, g", mass, 32.95),
        ("Σ L/v, min", feeds, 131.9),
        ("Pronterface, min", pronterface, 138.7),
        ("Marlin 2, min", marlin, 136.5),
        ("travel, mm a layer", travel, 126.5),
    ] {
        assert!(
            within(value, pinned, 0.005),
            "{what}: {value:.2}, pinned {pinned}"
        );
    }
    // Every travel stays inside the skin and off the layer's beads: no Z-hop.
    assert_eq!(hops, 0.0);
    // The estimators differ by 3–6 %; with the paper's own, ours is 7 % over 2:10.
    assert!(pronterface > feeds && within(pronterface, feeds, 0.06));
    assert!(marlin > feeds && within(marlin, feeds, 0.06));
    assert!(within(pronterface, PAPER_TIME_MIN, 0.10));
    // The section: the paper's 36.2 g at Table 3's bead and 40 mm/s leaves < 7 % of 2:10 off
    // the bead; ours spends > 15 % of Pronterface's time there.
    let grams_per_min = b.extrusion_width_mm
        * b.layer_height_mm
        * b.density_kg_m3
        * 1e-6
        * b.perimeter_speed_mm_s
        * 60.0;
    let paper_off_bead = 1.0 - PAPER_MASS_G / grams_per_min / PAPER_TIME_MIN;
    let on_bead = minutes(&mv, true);
    let ours_off_bead = 1.0 - on_bead / pronterface;
    eprintln!(
        "on the bead: paper ≥ {:.1} min ({:.1} % off), ours {on_bead:.1} min ({:.1} % off); \
         travel {:.1} min",
        PAPER_MASS_G / grams_per_min,
        100.0 * paper_off_bead,
        100.0 * ours_off_bead,
        minutes(&mv, false)
    );
    assert!(paper_off_bead < 0.07 && ours_off_bead > 0.15);
    // The mass: within 10 % (the Kite's planform is not given).
    assert!(within(mass, PAPER_MASS_G, 0.10), "{mass:.2} g");
}

/// Pronterface itself (Printrun 2.2.0's `gcoder` from PyPI, installed without its GUI
/// dependencies) on our Marlin programs for the root section, as the shipped profile writes it
/// (G2/G3 arcs fitted, which gcoder does not time) and without arcs: its estimate equals our
/// port of its method to the second on both, and the Marlin model of the same programs is
/// printed beside it.
#[test]
fn pronterface_itself_agrees_with_our_port_on_our_gcode() {
    let tmp = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"));
    let Some(python) = cell_testkit::venv_python_with(
        tmp,
        "printrun-venv",
        std::path::Path::new(&repo("crates/wing/tests/pronterface/requirements.txt")),
        "printrun.gcoder",
        &["--no-deps"],
    ) else {
        return;
    };
    let (wing, layers) = root_section();
    let toolpath = cell_wing::msg::toolpath(&layers, &wing.spec.build_params(), "table4-root");
    let shipped = cell_profiles::MachineProfile::load(repo("config/machines/marlin-extruder.yaml"))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut no_arcs = shipped.clone();
    if let Some(g) = no_arcs.gcode.as_mut() {
        g.arc_tolerance_mm = None;
    }
    for (name, profile) in [("arcs", &shipped), ("lines", &no_arcs)] {
        let gcode = cell_emitter::gcode::emit(&toolpath, profile, "table4-root")
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(
            gcode.contains("\nG2 ") || gcode.contains("\nG3 "),
            name == "arcs"
        );
        let file = tmp.join(format!("table4-root-{name}.gcode"));
        std::fs::write(&file, &gcode).unwrap();
        let out = std::process::Command::new(&python)
            .arg(repo("crates/wing/tests/pronterface/estimate.py"))
            .arg(&file)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout);
        let mut words = text.split_whitespace();
        let printrun_s: f64 = words.next().and_then(|w| w.parse().ok()).expect("seconds");
        let printrun_layers: usize = words.next().and_then(|w| w.parse().ok()).expect("layers");
        let run = read_gcode(&gcode).unwrap_or_else(|e| panic!("{e}"));
        let port_s = pronterface_time_s(&run.blocks);
        let marlin_s = marlin_time_s(&run.blocks, &FirmwareMotion::MARLIN_2_DEFAULTS);
        eprintln!(
            "our G-code ({name}): Pronterface {:.1} min (Printrun {:.1} min, {printrun_layers} \
             layers), Marlin 2 {:.1} min; waits not timed: {:?}",
            port_s / 60.0,
            printrun_s / 60.0,
            marlin_s / 60.0,
            run.waits
        );
        assert_eq!(printrun_layers, layers.len());
        // Printrun truncates to whole seconds; float sums differ in the last digits.
        assert!(
            printrun_s <= port_s + 1e-6 && port_s - printrun_s < 1.0 + 1e-6 * port_s,
            "{name}: Printrun {printrun_s} s, our port {port_s} s"
        );
        assert!(marlin_s > 0.9 * port_s);
        // The program lifts where the moves do (the profile's `z_hop_only_when_crossing`).
        let mv = moves(&layers, &wing.spec.build_params());
        let lifts = mv.iter().filter(|m| m.kind == MoveKind::Lift).count();
        let z_only = gcode.lines().filter(|l| l.starts_with("G0 Z")).count();
        assert_eq!(z_only, 2 * lifts, "{name}: Z-hop lines");
        // The program runs as the moves were planned: travel at the travel feed (a G0 without
        // F ran at the last retract's 35 mm/s on Marlin: 231.7 min).
        let planned_s = build_time_s(&mv, Some(FirmwareMotion::MARLIN_2_DEFAULTS));
        assert!(
            within(marlin_s, planned_s, 0.01),
            "{name}: the program takes {:.1} min on Marlin, the moves {:.1} min",
            marlin_s / 60.0,
            planned_s / 60.0
        );
    }
}
