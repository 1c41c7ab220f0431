//! The Table 2/3 wing end to end: spec → design → layers → estimates → Marlin G-code.

use cell_msgs::ToolpathSegment;
use cell_profiles::MachineProfile;
use cell_wing::estimate::{build_time_s, deposited_volume_mm3, mass_g};
use cell_wing::layers::{filament_area_mm2, moves, Layer, MoveKind, Role};
use cell_wing::marlin::FirmwareMotion;
use cell_wing::section::Side;
use cell_wing::spacing::{SkinCurvature, SpacingRule};
use cell_wing::spec::{SpecError, Wing, WingSpec};

fn repo(path: &str) -> String {
    format!("{}/../../{path}", env!("CARGO_MANIFEST_DIR"))
}

fn table2_wing() -> Wing {
    let spec =
        WingSpec::load(repo("config/wings/gwing-table2.yaml")).unwrap_or_else(|e| panic!("{e}"));
    Wing::design(spec).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn table2_spec_loads_and_designs() {
    let w = table2_wing();
    assert_eq!(w.spec.aero.span_mm, 1090.0, "Table 2 span 1.09 m");
    let n = w.planform.chord_mm.len() as f64;
    let area_mm2: f64 = w.planform.chord_mm.iter().sum::<f64>() * 1090.0 / n;
    assert!(
        (area_mm2 / 1e6 - 0.1485).abs() < 1e-3,
        "S = b²/AR = 0.1485 m² (notes [derived]), got {}",
        area_mm2 / 1e6
    );
    let root = w.planform.chord_mm.iter().copied().fold(0.0, f64::max);
    assert!(
        (165.0..180.0).contains(&root),
        "elliptic root chord ≈ 4/π·136 mm, got {root}"
    );
    assert!((w.aero.c_l - 0.5).abs() < 1e-9);
    assert_eq!(
        w.sections.len(),
        9,
        "w_c = 50, z_max = 150: centre + 4 a side (notes)"
    );
    // Elliptic chord and lift: constant twist (no washout), at α_L0 + c_L/c_Lα.
    let t = &w.planform.twist_rad;
    assert!(t.iter().all(|v| (v - t[0]).abs() < 1e-9));
    // Along the whole span, no gap between neighbouring spars exceeds the AM rule at the gap's
    // inner spar (walking outward from the main spar); r*·w_e = 30 mm is Table 2's spacing and
    // the rule's floor, and where the skins curve (small chords, near the LE) gaps widen.
    let rule = SpacingRule {
        extrusion_width_mm: 0.5,
        eta_star: 2e-5,
        r_star: 60.0,
        max_mm: None,
    };
    assert_eq!(rule.least_gap_mm(), 30.0);
    let curvature = SkinCurvature::new(&w.surfaces);
    let x_tau = w.surfaces.x_max_thickness();
    let mut widest: f64 = 0.0;
    for (xs, &c) in w.spars.x_over_c.iter().zip(&w.planform.chord_mm) {
        let main = xs.iter().position(|x| *x == x_tau).expect("main spar");
        let aft = xs[main..].windows(2).map(|p| (p[1] - p[0], p[0]));
        let fore = xs[..=main].windows(2).map(|p| (p[1] - p[0], p[1]));
        for (gap, inner) in aft.chain(fore) {
            let limit = curvature.max_gap_mm(&rule, inner, c);
            assert!(
                gap * c <= limit + 1e-6,
                "c = {c}: {} mm > {limit} mm",
                gap * c
            );
            widest = widest.max(gap * c);
        }
    }
    assert!(
        widest > 30.0,
        "the rule widens some gap past the floor: {widest} mm"
    );
}

#[test]
fn unknown_and_bad_fields_are_rejected() {
    let text = std::fs::read_to_string(repo("config/wings/gwing-table2.yaml")).unwrap();
    let typo = text.replace("z_hop_mm:", "z_hopp_mm:");
    match WingSpec::from_yaml_str(&typo, "typo.yaml") {
        Err(SpecError::Parse(cell_config::ParseError {
            line: Some(_),
            message,
            ..
        })) => assert!(message.contains("z_hopp_mm"), "{message}"),
        other => panic!("expected a parse error with a line, got {other:?}"),
    }
    let bad = text.replace("layer_height_mm: 0.2", "layer_height_mm: -0.2");
    assert!(matches!(
        WingSpec::from_yaml_str(&bad, "bad.yaml"),
        Err(SpecError::Invalid {
            field: "build.layer_height_mm",
            ..
        })
    ));
}

/// The first right-wing section, next to the centre section (a root section, as in Fig. 10).
fn root_section(w: &Wing) -> Vec<Layer> {
    let i = w
        .sections
        .iter()
        .position(|s| s.side == Side::Right && s.index == 1)
        .unwrap();
    w.layers(i).unwrap()
}

#[test]
fn root_section_mass_lies_between_slic3r_0_and_5_percent() {
    let w = table2_wing();
    let layers = root_section(&w);
    assert_eq!(layers.len(), 650, "⌈(130 − 0.2)/0.2⌉ + 1 layers");
    let m = mass_g(&layers, 0.5, 1240.0);
    let mv = moves(&layers, &w.spec.build_params());
    let t0 = build_time_s(&mv, None);
    let ta = build_time_s(&mv, Some(FirmwareMotion::MARLIN_2_DEFAULTS));
    eprintln!(
        "root section: {m:.2} g, {:.0} min without / {:.0} min with acceleration",
        t0 / 60.0,
        ta / 60.0
    );
    assert!(
        (24.30..44.38).contains(&m),
        "Table 4: G-Wing 36.2 g lies between Slic3r 0 % (24.30 g) and 5 % grid (44.38 g); got {m:.2} g"
    );
    assert!(ta > t0, "acceleration only slows the build");
    // Rib on layer 0 only, spars on every other layer.
    assert!(layers[0].strokes.iter().any(|s| s.role == Role::Rib));
    assert!(layers[0].strokes.iter().all(|s| s.role != Role::Spar));
    assert!(layers[1..]
        .iter()
        .all(|l| l.strokes.iter().any(|s| s.role == Role::Spar)));
    assert!(layers[1..]
        .iter()
        .all(|l| l.strokes.iter().all(|s| s.role != Role::Rib)));
}

#[test]
fn moves_carry_e_for_the_deposited_volume_with_balanced_retracts() {
    let w = table2_wing();
    let layers: Vec<Layer> = root_section(&w).into_iter().take(5).collect();
    let p = w.spec.build_params();
    let mv = moves(&layers, &p);
    let e_end = mv.last().unwrap().e_mm;
    let expect = deposited_volume_mm3(&layers, 0.5) / filament_area_mm2(&p);
    assert!(
        (e_end - expect).abs() < 1e-9 * expect,
        "{e_end} vs {expect}"
    );
    let retracts = mv.iter().filter(|m| m.kind == MoveKind::Retract).count();
    let primes = mv.iter().filter(|m| m.kind == MoveKind::Prime).count();
    let lifts = mv.iter().filter(|m| m.kind == MoveKind::Lift).count();
    let lowers = mv.iter().filter(|m| m.kind == MoveKind::Lower).count();
    // Every travel retracts; only those over a printed bead lift (none here).
    assert!(retracts > 0 && retracts == primes && lifts == lowers && lifts < retracts);
    for m in mv.iter().filter(|m| m.kind == MoveKind::Travel) {
        assert!(m.e_mm < mv.iter().map(|x| x.e_mm).fold(0.0, f64::max) + 1.0);
    }
}

#[test]
fn marlin_gcode_extrudes_the_deposited_volume() {
    let w = table2_wing();
    let layers: Vec<Layer> = root_section(&w).into_iter().take(6).collect();
    let p = w.spec.build_params();
    let tp = cell_wing::msg::toolpath(&layers, &p, "gwing-test");
    assert!(tp
        .segments
        .iter()
        .any(|s| s.kind == ToolpathSegment::KIND_TRAVEL));
    for s in tp
        .segments
        .iter()
        .filter(|s| s.kind == ToolpathSegment::KIND_DEPOSIT)
    {
        let h = layers[s.layer as usize].height_mm;
        for (q, f) in s.power.iter().zip(&s.feed_mm_s) {
            assert!(
                (f64::from(*q) - 0.5 * h * f64::from(*f)).abs() < 1e-5,
                "power = w·h·feed"
            );
        }
    }
    let profile = MachineProfile::load(repo("config/machines/marlin-extruder.yaml")).unwrap();
    let gcode =
        cell_emitter::gcode::emit(&tp, &profile, "gwing-test").unwrap_or_else(|e| panic!("{e}"));
    let e_total = cell_emitter::gcode::extruded_length_mm(&gcode);
    let expect = deposited_volume_mm3(&layers, 0.5) / filament_area_mm2(&p);
    eprintln!("Marlin E {e_total:.4} mm, volume / filament area {expect:.4} mm");
    assert!(
        (e_total - expect).abs() < 0.01 * expect,
        "G-code E {e_total:.3} mm vs deposited volume / filament area {expect:.3} mm"
    );
    assert!(gcode.contains("M82"));
}
