//! Cutting layouts with kerf and leads ([`super::cut_problem`]), measured with distances
//! written here.

use super::*;
use crate::layout::{Part, Ring};
use crate::problem::distance;
use cell_geometry::point_in_ring_nonzero;

fn dist_to_ring(p: Point, ring: &[Point]) -> f64 {
    (0..ring.len())
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let l2 = dx * dx + dy * dy;
            let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0);
            (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
        })
        .fold(f64::INFINITY, f64::min)
}

fn rect(x: f64, y: f64, w: f64, h: f64) -> Ring {
    Ring {
        points: vec![[x, y], [x + w, y], [x + w, y + h], [x, y + h]],
        pierce: None,
    }
}

fn part(name: &str, outer: Ring, holes: Vec<Ring>) -> Part {
    Part {
        name: Some(name.into()),
        outer,
        holes,
    }
}

fn layout(sheet: [f64; 2], parts: Vec<Part>) -> Layout {
    Layout {
        sheet,
        start: [0.0, 0.0],
        origin: [0.0, 0.0],
        parts,
    }
}

fn plasma() -> CutSpec {
    crate::fixtures::plasma_cut_spec()
}

fn example() -> Layout {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/data/sheet/example.json"
    );
    Layout::from_json_file(path).unwrap()
}

fn cut(l: &Layout, spec: &CutSpec) -> Result<(Problem, CutSummary), CutError> {
    cut_problem(l, PrecedenceMode::Strict, &PierceOptions::default(), spec)
}

#[test]
fn every_contour_gets_its_offset_path_and_leads_from_the_scrap_side() {
    let l = example();
    let nominal = l
        .to_problem(PrecedenceMode::Strict, &PierceOptions::default())
        .unwrap();
    let (p, summary) = cut(&l, &plasma()).unwrap();
    assert_eq!(p.contours.len(), nominal.contours.len());
    assert_eq!(
        p.precedence, nominal.precedence,
        "the rules stay the layout's"
    );
    for (c, n) in p.contours.iter().zip(&nominal.contours) {
        assert_eq!((c.part, c.role), (n.part, n.role));
        assert_eq!(c.drawn(), &n.points[..], "the drawn contour stays with it");
        assert_eq!(c.leads.len(), c.pierce_candidates.len());
        assert!(!c.leads.is_empty());
        for q in &c.points {
            let d = dist_to_ring(*q, &n.points);
            assert!((0.75 - 0.005 - 1e-9..=0.75 + 1e-9).contains(&d), "{d}");
        }
        for (k, lead) in c.leads.iter().enumerate() {
            assert_eq!(c.pierce_candidates[k], lead.pierce());
            let inside = point_in_ring_nonzero(lead.pierce(), &n.points);
            assert_eq!(inside, c.role == ContourRole::Hole);
            // Full length: the pierce 5 mm off the cut path, a quarter turn before the entry
            // (an arc) or square to it (a line, where an arc just after a corner would put
            // the pierce farther off).
            let d = dist_to_ring(lead.pierce(), &c.points);
            assert!((d - 5.0).abs() < 1e-6, "pierce {:?} at {d}", lead.pierce());
            let chord = distance(lead.pierce(), lead.entry());
            let arc = (chord - 5.0 * std::f64::consts::SQRT_2).abs() < 1e-9;
            let line = (chord - 5.0).abs() < 1e-9 && lead.lead_in.len() == 2;
            assert!(arc || line, "{chord}");
            assert_eq!(c.entry(k), lead.entry());
            assert_eq!(c.exit(k), lead.exit());
            let path = c.cut_path(k);
            assert_eq!(
                (path[0], *path.last().unwrap()),
                (lead.pierce(), lead.exit())
            );
        }
    }
    // The frame's fixed pierce point lies on its contour: the lead enters there.
    let frame = &p.contours[0];
    assert_eq!(frame.leads.len(), 1);
    assert!(dist_to_ring(frame.entry(0), &[[9.25, 80.0], [9.25, 80.0001]]) < 0.01);
    assert_eq!(summary.kerf_mm, 1.5);
    assert_eq!(summary.path_offset_mm, 0.75);
    assert_eq!(summary.short_lead_ins, 0);
    assert!((summary.nearest_pierce_mm - 5.0).abs() < 1e-6);
    assert!(summary.warnings.is_empty());
}

#[test]
fn a_fixed_pierce_point_off_the_contour_is_the_lead_in_start() {
    let mut l = example();
    l.parts[2].outer.pierce = Some([240.0, 12.0]); // 8 mm below the triangle's base
    let (p, _) = cut(&l, &plasma()).unwrap();
    let c = &p.contours[3];
    assert_eq!(c.pierce_candidates, vec![[240.0, 12.0]]);
    assert_eq!(c.leads[0].lead_in.len(), 2, "a straight lead-in");
    assert!((c.entry(0)[1] - 19.25).abs() < 1e-9, "{:?}", c.entry(0));
}

#[test]
fn holes_too_small_for_the_kerf_fail_or_are_skipped_by_name() {
    let l = layout(
        [200.0, 200.0],
        vec![part(
            "bracket",
            rect(10.0, 10.0, 100.0, 100.0),
            vec![rect(20.0, 20.0, 30.0, 30.0), rect(70.0, 70.0, 1.0, 1.0)],
        )],
    );
    let e = cut(&l, &plasma()).unwrap_err().to_string();
    assert!(
        e.starts_with("parts[0] (bracket).holes[1]: cannot be cut with a 1.5 mm kerf")
            && e.contains("vanishes")
            && e.contains("too_small_holes: skip"),
        "{e}"
    );
    let spec = CutSpec {
        skip_too_small_holes: true,
        ..plasma()
    };
    let (p, summary) = cut(&l, &spec).unwrap();
    assert_eq!(p.contours.len(), 2, "the tiny hole is left out");
    assert_eq!(summary.warnings.len(), 1);
    assert!(
        summary.warnings[0].contains("holes[1]"),
        "{:?}",
        summary.warnings
    );
    p.precedence.check_order(&[1, 0]).unwrap();
    // The other hole is a small hole: no, 30 mm is not; it has ordinary leads.
    assert_eq!(summary.centre_pierced_holes, 0);
}

#[test]
fn a_notch_narrower_than_the_kerf_is_cut_round_with_a_warning_naming_it() {
    // A 100 mm plate with a 1 mm slot 30 mm deep in its top edge (at x = 60) and a 3 mm one
    // (x = 30), and a hole with a 1 mm slot 20 mm deep from its right side.
    let outer = vec![
        [10.0, 10.0],
        [110.0, 10.0],
        [110.0, 110.0],
        [60.5, 110.0],
        [60.5, 80.0],
        [59.5, 80.0],
        [59.5, 110.0],
        [31.5, 110.0],
        [31.5, 80.0],
        [28.5, 80.0],
        [28.5, 110.0],
        [10.0, 110.0],
    ];
    let hole = vec![
        [30.0, 30.0],
        [50.0, 30.0],
        [50.0, 39.5],
        [70.0, 39.5],
        [70.0, 40.5],
        [50.0, 40.5],
        [50.0, 50.0],
        [30.0, 50.0],
    ];
    let l = layout(
        [200.0, 200.0],
        vec![part(
            "comb",
            Ring {
                points: outer,
                pierce: None,
            },
            vec![Ring {
                points: hole,
                pierce: None,
            }],
        )],
    );
    let (p, summary) = cut(&l, &plasma()).unwrap();
    assert_eq!(p.contours.len(), 2, "both are still cut");
    assert_eq!(summary.warnings.len(), 2, "{:?}", summary.warnings);
    let outer_w = summary
        .warnings
        .iter()
        .find(|w| w.starts_with("parts[0] (comb).outer: "))
        .expect("the outline's warning");
    // The 1 mm slot, around its bottom; the 3 mm one is cut.
    assert!(
        distance(warned_at(outer_w), [60.0, 80.0]) < 1.0,
        "{outer_w}"
    );
    assert!(
        outer_w.contains("narrower than the 1.5 mm kerf"),
        "{outer_w}"
    );
    let hole_w = summary
        .warnings
        .iter()
        .find(|w| w.starts_with("parts[0] (comb).holes[0]: "))
        .expect("the hole's warning");
    assert!(distance(warned_at(hole_w), [70.0, 40.0]) < 1.0, "{hole_w}");
}

/// The point a warning names: "… around (x, y) …".
fn warned_at(w: &str) -> Point {
    let (_, rest) = w.split_once("around (").expect("a point");
    let (xy, _) = rest.split_once(')').unwrap();
    let (x, y) = xy.split_once(", ").unwrap();
    [x.parse().unwrap(), y.parse().unwrap()]
}

#[test]
fn parts_nested_closer_than_the_kerf_are_an_error_naming_both() {
    let l = layout(
        [200.0, 100.0],
        vec![
            part("left", rect(10.0, 10.0, 50.0, 50.0), vec![]),
            part("right", rect(61.0, 10.0, 50.0, 50.0), vec![]),
        ],
    );
    let e = cut(&l, &plasma()).unwrap_err().to_string();
    assert!(
        e.contains("parts[0] (left).outer") && e.contains("parts[1] (right).outer"),
        "{e}"
    );
    assert!(e.contains("less than the kerf (1.5 mm)"), "{e}");
    // A laser's kerf fits between them.
    let laser = CutSpec {
        kerf_mm: 0.2,
        lead_in_mm: 2.0,
        ..plasma()
    };
    assert!(cut(&l, &laser).is_ok());
}

#[test]
fn a_part_no_lead_fits_is_named() {
    // An island 2 mm inside its hole all round: its cut path leaves 0.5 mm, no lead fits.
    let l = layout(
        [100.0, 100.0],
        vec![
            part(
                "frame",
                rect(5.0, 5.0, 90.0, 90.0),
                vec![rect(20.0, 20.0, 60.0, 60.0)],
            ),
            part("island", rect(22.0, 22.0, 56.0, 56.0), vec![]),
        ],
    );
    let e = cut(&l, &plasma()).unwrap_err().to_string();
    assert!(
        e.starts_with("parts[0] (frame).holes[0]: no lead-in")
            || e.starts_with("parts[1] (island).outer: no lead-in"),
        "{e}"
    );
}

#[test]
fn small_holes_get_a_centre_pierce_and_controller_compensation_keeps_the_drawn_path() {
    let l = layout(
        [200.0, 200.0],
        vec![part(
            "flange",
            rect(10.0, 10.0, 100.0, 100.0),
            vec![rect(55.0, 55.0, 8.0, 8.0)],
        )],
    );
    let (p, summary) = cut(&l, &plasma()).unwrap();
    assert_eq!(summary.centre_pierced_holes, 1);
    assert!(distance(p.contours[1].pierce_candidates[0], [59.0, 59.0]) < 0.05);
    let spec = CutSpec {
        compensation: Compensation::Controller,
        ..plasma()
    };
    let (p, summary) = cut(&l, &spec).unwrap();
    assert_eq!(summary.path_offset_mm, 0.0);
    assert_eq!(summary.lead_clearance_mm, 2.25);
    // The drawn rings, turned part-right: the outer clockwise, the hole counter-clockwise.
    let outer = &p.contours[0].points;
    assert_eq!(outer.len(), 4);
    assert!(outer
        .iter()
        .all(|q| dist_to_ring(*q, &l.parts[0].outer.points) < 1e-12));
    assert!(cell_geometry::signed_area(outer) < 0.0);
    assert!(cell_geometry::signed_area(&p.contours[1].points) > 0.0);
    for c in &p.contours {
        for lead in &c.leads {
            assert!(dist_to_ring(lead.entry(), &c.points) < 1e-9);
        }
    }
}

#[test]
fn a_spec_out_of_range_is_named() {
    let spec = CutSpec {
        kerf_mm: -1.0,
        ..plasma()
    };
    let e = cut(&example(), &spec).unwrap_err().to_string();
    assert!(e.contains("cut.kerf_mm = -1 mm"), "{e}");
}

#[test]
fn the_spec_comes_from_the_profile_cutting_section() {
    let profile = cell_profiles::MachineProfile::resolve("linuxcnc-plasma").unwrap();
    let section = profile.cutting.unwrap();
    let spec = CutSpec::from_profile(&section, "mild_steel", 6.0).unwrap();
    assert_eq!(spec.kerf_mm, 1.5);
    assert_eq!(spec.lead_in_mm, section.lead_in.length_mm);
    assert_eq!(spec.lead_shape, section.lead_in.shape);
    assert_eq!(spec.compensation, section.compensation);
    let e = CutSpec::from_profile(&section, "unobtainium", 6.0).unwrap_err();
    assert!(e.contains("mild_steel"), "{e}");
}

#[test]
fn profiles_map_materials_to_specs_and_name_what_is_missing() {
    let plasma = cell_profiles::MachineProfile::resolve("linuxcnc-plasma").unwrap();
    let (spec, m) = spec_for_profile(&plasma, None, None).unwrap().unwrap();
    let default = plasma
        .cutting
        .as_ref()
        .unwrap()
        .default_material
        .clone()
        .unwrap();
    assert_eq!(m, default);
    assert_eq!(
        spec.kerf_mm,
        plasma
            .cutting
            .as_ref()
            .unwrap()
            .kerf_mm(&default.material, default.thickness_mm)
            .unwrap()
    );
    let (spec3, _) = spec_for_profile(&plasma, Some("mild_steel"), Some(3.0))
        .unwrap()
        .unwrap();
    assert!(spec3.kerf_mm < spec.kerf_mm, "thinner plate, narrower kerf");
    let e = spec_for_profile(&plasma, Some("mild_steel"), Some(99.0)).unwrap_err();
    assert!(e.contains("linuxcnc-plasma") && e.contains("99"), "{e}");
    // A hot-wire profile has no cutting section: no cut, unless a material is asked for.
    let foam = cell_profiles::MachineProfile::resolve("grbl-xyuv").unwrap();
    assert_eq!(spec_for_profile(&foam, None, None), Ok(None));
    let e = spec_for_profile(&foam, Some("mild_steel"), None).unwrap_err();
    assert!(e.contains("grbl-xyuv") && e.contains("cutting:"), "{e}");
}

/// The thermal raster heats the leads: the lead-in's pierce cell and the lead-out's end melt,
/// and the tool ends at the lead-out's end.
#[test]
fn the_raster_heats_the_leads_and_leaves_the_tool_at_the_exit() {
    let (p, _) = cut(&example(), &plasma()).unwrap();
    let params = crate::thermal::ThermalParams {
        cell_mm: 1.0,
        ..Default::default()
    };
    let c = &p.contours[1];
    // Cells 5 mm (the pierce) and 2 mm (the exit) off the contour: only the leads reach them.
    let cells =
        [c.pierce_candidates[0], c.exit(0)].map(|q| (q[1].floor() as usize, q[0].floor() as usize));
    let mut hottest = [0.0f32; 2];
    let mut watch = |f: &crate::thermal::Frame| {
        for (h, &(y, x)) in hottest.iter_mut().zip(&cells) {
            *h = h.max(f.excess_c[y * f.width + x]);
        }
    };
    let mut sim = crate::thermal::ThermalSim::new(p.sheet, p.start, &params)
        .unwrap()
        .with_frames(1, &mut watch);
    sim.cut(c, 0);
    assert_eq!(sim.tool(), c.exit(0));
    drop(sim);
    let melt = params.t_melt_c - params.ambient_c;
    // A molten cell gives most of its heat away in its first step: a tenth is left.
    assert!(hottest.iter().all(|&h| h > 0.1 * melt), "{hottest:?}");
}

/// A sheet taken from the parts' extent leaves no scrap round a part on its edge: the lead
/// starts off the sheet (an edge start) rather than fail.
#[test]
fn a_part_filling_the_sheet_gets_an_edge_start() {
    let l = layout(
        [50.0, 30.0],
        vec![part("blank", rect(0.0, 0.0, 50.0, 30.0), vec![])],
    );
    let (p, _) = cut(&l, &plasma()).unwrap();
    let pierce = p.contours[0].pierce_candidates[0];
    let on_sheet = (0.0..=50.0).contains(&pierce[0]) && (0.0..=30.0).contains(&pierce[1]);
    assert!(!on_sheet, "{pierce:?}");
    assert!(dist_to_ring(pierce, &l.parts[0].outer.points) > 5.0);
}
