//! Kerf compensation and leads on whole layouts (issue 19, items 2 and 3): the generator's
//! layouts (50 and 1000 contours, and a dense perforated one) and the shipped sheets, with a
//! plasma and a laser spec, measured here with distances of our own against the drawn rings:
//! every cut path half a kerf off its contour on the scrap side, every pierce on the scrap side
//! off the cut path, no lead within a kerf of another contour or inside its own part's kerf;
//! and a whole job's toolpath: lead-in, cut, lead-out per contour, travel equal to the idle
//! length.

use std::path::PathBuf;

use cell_geometry::point_in_ring_nonzero;
use cell_msgs::ToolpathSegment;
use cell_profiles::LeadShape;
use cell_sequencer::cut::{cut_problem, CutSpec};
use cell_sequencer::dxf::{read_layout, DxfOptions};
use cell_sequencer::generator::{generate, generate_perforated, GeneratorConfig, PerforatedConfig};
use cell_sequencer::improve::ImproveParams;
use cell_sequencer::job::{self, LayoutSource, SheetJob};
use cell_sequencer::layout::{Layout, PierceOptions};
use cell_sequencer::precedence::PrecedenceMode;
use cell_sequencer::problem::{ContourRole, Point, Problem};
use cell_sequencer::toolpath::{to_toolpath, travel_length_mm, ToolpathOptions};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/sheet")
        .join(name)
}

fn plasma() -> CutSpec {
    cell_sequencer::fixtures::plasma_cut_spec()
}

fn laser() -> CutSpec {
    CutSpec {
        kerf_mm: 0.2,
        lead_in_mm: 2.0,
        lead_shape: LeadShape::Line,
        lead_out_mm: 0.5,
        overcut_mm: 0.5,
        small_hole_diameter_mm: 3.0,
        ..plasma()
    }
}

fn seg_dist(p: Point, a: Point, b: Point) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

fn dist_to_ring(p: Point, ring: &[Point]) -> f64 {
    (0..ring.len())
        .map(|i| seg_dist(p, ring[i], ring[(i + 1) % ring.len()]))
        .fold(f64::INFINITY, f64::min)
}

/// Points every ≤ 0.05 mm along a polyline.
fn dense(path: &[Point]) -> Vec<Point> {
    let mut out = vec![path[0]];
    for w in path.windows(2) {
        let n = ((w[0][0] - w[1][0]).hypot(w[0][1] - w[1][1]) / 0.05)
            .ceil()
            .max(1.0) as usize;
        out.extend((1..=n).map(|k| {
            let f = k as f64 / n as f64;
            [
                w[0][0] + f * (w[1][0] - w[0][0]),
                w[0][1] + f * (w[1][1] - w[0][1]),
            ]
        }));
    }
    out
}

fn bbox(points: &[Point]) -> [f64; 4] {
    points
        .iter()
        .fold([f64::MAX, f64::MAX, f64::MIN, f64::MIN], |b, p| {
            [
                b[0].min(p[0]),
                b[1].min(p[1]),
                b[2].max(p[0]),
                b[3].max(p[1]),
            ]
        })
}

/// Every contour of `layout` as cut in `p` with `spec` (module docs).
fn check_cut(layout: &Layout, p: &Problem, spec: &CutSpec) {
    let rings: Vec<(Vec<Point>, ContourRole)> = layout
        .parts
        .iter()
        .flat_map(|part| {
            std::iter::once((part.outer.points.clone(), ContourRole::Outer)).chain(
                part.holes
                    .iter()
                    .map(|h| (h.points.clone(), ContourRole::Hole)),
            )
        })
        .collect();
    assert_eq!(p.contours.len(), rings.len());
    let boxes: Vec<[f64; 4]> = rings.iter().map(|(r, _)| bbox(r)).collect();
    let half = spec.kerf_mm / 2.0;
    let clearance = spec.kerf_mm;
    for (c, (contour, (nominal, role))) in p.contours.iter().zip(&rings).enumerate() {
        assert_eq!(contour.role, *role);
        let inside = |q: Point| point_in_ring_nonzero(q, nominal);
        // The cut path: half a kerf off, on the scrap side (vertices and edge midpoints).
        let n = contour.points.len();
        for i in 0..n {
            let (a, b) = (contour.points[i], contour.points[(i + 1) % n]);
            for q in [a, [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0]] {
                let d = dist_to_ring(q, nominal);
                assert!(
                    d <= half + 1e-9 && d >= half - 0.005 - 1e-9,
                    "contour {c}: cut path point {q:?} {d} mm off, want {half}"
                );
                assert_eq!(inside(q), *role == ContourRole::Hole, "contour {c}: side");
            }
        }
        assert_eq!(contour.leads.len(), contour.pierce_candidates.len());
        assert!(!contour.leads.is_empty());
        for lead in &contour.leads {
            let pierce = lead.pierce();
            assert_eq!(
                inside(pierce),
                *role == ContourRole::Hole,
                "contour {c}: pierce side"
            );
            let off = dist_to_ring(pierce, &contour.points);
            assert!(
                off > 0.1 && off <= spec.lead_in_mm + 1e-6,
                "contour {c}: pierce {pierce:?} {off} mm off the cut path"
            );
            assert!(
                dist_to_ring(lead.entry(), &contour.points) < 1e-9,
                "contour {c}: the lead-in ends on the cut path"
            );
            for part in [&lead.lead_in, &lead.lead_out] {
                let pts = dense(part);
                let own = pts
                    .iter()
                    .map(|&q| dist_to_ring(q, nominal))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    own >= half - 0.005 - 1e-6,
                    "contour {c}: a lead cuts its part"
                );
                let b = bbox(part);
                for (o, (other, _)) in rings.iter().enumerate() {
                    let ob = boxes[o];
                    let near = ob[0] <= b[2] + clearance
                        && b[0] <= ob[2] + clearance
                        && ob[1] <= b[3] + clearance
                        && b[1] <= ob[3] + clearance;
                    if o == c || !near {
                        continue;
                    }
                    let d = pts
                        .iter()
                        .map(|&q| dist_to_ring(q, other))
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        d >= clearance - 1e-6,
                        "contour {c}: a lead comes {d} mm from contour {o}"
                    );
                }
            }
        }
    }
}

fn cut_and_check(layout: &Layout, spec: &CutSpec) -> Problem {
    let (p, summary) = cut_problem(
        layout,
        PrecedenceMode::Strict,
        &PierceOptions::default(),
        spec,
    )
    .unwrap();
    check_cut(layout, &p, spec);
    assert!(summary.warnings.is_empty(), "{:?}", summary.warnings);
    p
}

#[test]
fn generated_layouts_of_50_and_1000_contours_with_plasma_and_laser() {
    for contours in [50, 1000] {
        let layout = generate(&GeneratorConfig {
            contours,
            seed: 7,
            ..Default::default()
        });
        for spec in [plasma(), laser()] {
            cut_and_check(&layout, &spec);
        }
    }
}

#[test]
fn a_dense_perforated_layout_with_plasma() {
    let layout = generate_perforated(&PerforatedConfig {
        contours: 600,
        seed: 3,
        ..Default::default()
    });
    let p = cut_and_check(&layout, &plasma());
    assert!(p.contours.iter().any(|c| c.leads.len() == 1));
}

#[test]
fn the_shipped_sheets_with_plasma_and_laser() {
    let json = ["example.json", "plate_holes_nest.json"];
    let dxf = [
        "small.dxf",
        "margin_limits.dxf",
        "margin_no_header.dxf",
        "margin_sheet_layer.dxf",
    ];
    let layouts = json
        .iter()
        .map(|f| Layout::from_json_file(data(f)).unwrap())
        .chain(
            dxf.iter()
                .filter(|f| data(f).exists())
                .map(|f| read_layout(data(f), &DxfOptions::default()).unwrap()),
        );
    for layout in layouts {
        for spec in [plasma(), laser()] {
            cut_and_check(&layout, &spec);
        }
    }
}

/// A whole job with a cut spec: the toolpath pierces at every cut's lead-in start, leads and
/// cut in one heat, and travels from each exit to the next pierce: the idle length.
#[test]
fn a_job_with_kerf_and_leads_writes_lead_cut_lead_and_travels_from_each_exit() {
    let layout = generate(&GeneratorConfig {
        contours: 50,
        seed: 7,
        ..Default::default()
    });
    let sheet_job = SheetJob {
        layout: LayoutSource::Json(layout.to_json()),
        cut: Some(plasma()),
        improve_params: ImproveParams {
            max_iterations: 30,
            ..Default::default()
        },
        ..Default::default()
    };
    let out = job::run(&sheet_job, |_| {}, u64::MAX, &mut |_| {}).unwrap();
    let summary = out.cut.as_ref().expect("the job reports its cut");
    assert_eq!(summary.kerf_mm, 1.5);
    let mut order = out.plan.order();
    out.problem.precedence.check_order(&order).unwrap();
    order.sort_unstable();
    assert_eq!(order, (0..out.problem.contours.len()).collect::<Vec<_>>());
    let tp = to_toolpath(&out.problem, &out.plan, "t", &ToolpathOptions::default());
    let travel = travel_length_mm(&tp);
    assert!(
        (travel - out.plan.idle_mm).abs() < 1e-6,
        "{travel} vs {}",
        out.plan.idle_mm
    );
    let kinds: Vec<u8> = tp.segments.iter().map(|s| s.kind).collect();
    let cuts = kinds
        .iter()
        .filter(|&&k| k == ToolpathSegment::KIND_CUT)
        .count();
    assert_eq!(cuts, out.problem.contours.len());
    // Each travel ends at a pierce and is followed by a lead-in; each cut closes on itself.
    for (i, s) in tp.segments.iter().enumerate() {
        let first = [s.points[0].x, s.points[0].y];
        let last = s.points.last().map(|q| [q.x, q.y]).unwrap();
        if i > 0 {
            let prev = tp.segments[i - 1].points.last().unwrap();
            assert_eq!([prev.x, prev.y], first, "segments chain");
        }
        match s.kind {
            ToolpathSegment::KIND_CUT => {
                assert_eq!(first, last, "a cut closes at its entry");
                assert_eq!(kinds[i - 1], ToolpathSegment::KIND_LEAD);
            }
            ToolpathSegment::KIND_TRAVEL if i + 1 < kinds.len() => {
                assert_eq!(kinds[i + 1], ToolpathSegment::KIND_LEAD);
            }
            _ => {}
        }
        assert!(s.power.len() == s.points.len());
    }
    // The plan's cut length includes the leads.
    let cut_len: f64 = tp
        .segments
        .iter()
        .filter(|s| s.kind != ToolpathSegment::KIND_TRAVEL)
        .flat_map(|s| s.points.windows(2))
        .map(|w| (w[0].x - w[1].x).hypot(w[0].y - w[1].y))
        .sum();
    assert!(
        (cut_len - out.plan.cut_mm).abs() < 1e-6 * cut_len,
        "{cut_len} vs {}",
        out.plan.cut_mm
    );
}
