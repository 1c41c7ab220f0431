//! Lead geometry on hand-made cases (module docs of [`super`]): the leads are measured with
//! distances written here, against the drawn rings.

use super::*;
use crate::kerf::offset_contour;

/// Distance from `p` to the ring's edges.
fn dist_to_ring(p: Point, ring: &[Point]) -> f64 {
    (0..ring.len())
        .map(|i| {
            let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let l2 = dx * dx + dy * dy;
            let t = if l2 > 0.0 {
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Distance from `p` to a polyline, sampled finely along each edge of `path` too.
fn dist_path_to_ring(path: &[Point], ring: &[Point]) -> f64 {
    path.windows(2)
        .flat_map(|w| {
            (0..=20).map(move |k| {
                let f = k as f64 / 20.0;
                [
                    w[0][0] + f * (w[1][0] - w[0][0]),
                    w[0][1] + f * (w[1][1] - w[0][1]),
                ]
            })
        })
        .map(|p| dist_to_ring(p, ring))
        .fold(f64::INFINITY, f64::min)
}

fn rect(x: f64, y: f64, w: f64, h: f64) -> Vec<Point> {
    vec![[x, y], [x + w, y], [x + w, y + h], [x, y + h]]
}

fn circle(c: Point, r: f64, n: usize) -> Vec<Point> {
    (0..n)
        .map(|i| {
            let a = i as f64 / n as f64 * std::f64::consts::TAU;
            [c[0] + r * a.cos(), c[1] + r * a.sin()]
        })
        .collect()
}

fn params(shape: LeadShape, kerf: f64) -> LeadParams {
    LeadParams {
        shape,
        length_mm: 5.0,
        lead_out_mm: 2.0,
        overcut_mm: 0.0,
        small_hole_diameter_mm: 12.0,
        path_offset_mm: kerf / 2.0,
        clearance_mm: kerf,
        pierce_clearance_mm: kerf,
    }
}

/// One sheet of drawn rings (with their roles), and the leads of ring `r`.
struct Case {
    rings: Vec<Vec<Point>>,
    roles: Vec<ContourRole>,
    sheet: [f64; 2],
    params: LeadParams,
}

impl Case {
    fn path(&self, r: usize) -> Vec<Point> {
        offset_contour(&self.rings[r], self.roles[r], self.params.path_offset_mm).unwrap()
    }

    fn leads(&self, r: usize, entries: &[Point]) -> Result<ContourLeads, String> {
        let obstacles = Obstacles::new(&self.rings, self.sheet, 12.0);
        let finder = LeadFinder {
            obstacles: &obstacles,
            params: self.params,
            off_sheet: false,
        };
        let path = self.path(r);
        let target = LeadTarget {
            ring: r,
            role: self.roles[r],
            path: &path,
        };
        finder.contour_leads(&target, &self.rings[r], entries)
    }

    /// Every lead of ring `r` is clear (module docs) by our own measure, and joins the path.
    fn assert_clear(&self, r: usize, leads: &[Lead]) {
        let path = self.path(r);
        let half = self.params.path_offset_mm;
        for lead in leads {
            for (part, join) in [
                (&lead.lead_in, lead.entry()),
                (&lead.lead_out, lead.entry()),
            ] {
                assert!(dist_to_ring(join, &path) < 1e-6, "joins the path");
                let own = dist_path_to_ring(part, &self.rings[r]);
                assert!(
                    own >= half - CHORD_TOL_MM - 1e-6,
                    "a lead comes {own} mm from its own contour: {part:?}"
                );
                for (o, ring) in self.rings.iter().enumerate().filter(|&(o, _)| o != r) {
                    let d = dist_path_to_ring(part, ring);
                    assert!(
                        d >= self.params.clearance_mm - 1e-9,
                        "a lead of ring {r} comes {d} mm from ring {o}"
                    );
                }
            }
            // The pierce: on the scrap side, off the part by more than the kerf's half.
            let p = lead.pierce();
            let inside = point_in_ring_nonzero(p, &self.rings[r]);
            assert_eq!(
                inside,
                self.roles[r] == ContourRole::Hole,
                "pierce side {p:?}"
            );
            assert!(dist_to_ring(p, &self.rings[r]) > half + 0.1);
        }
    }
}

#[test]
fn full_length_leads_on_a_free_square_from_outside() {
    for shape in [LeadShape::Line, LeadShape::Arc] {
        let case = Case {
            rings: vec![rect(50.0, 50.0, 40.0, 40.0)],
            roles: vec![ContourRole::Outer],
            sheet: [200.0, 200.0],
            params: params(shape, 1.5),
        };
        let entries = [[70.0, 50.0], [90.0, 70.0]];
        let got = case.leads(0, &entries).unwrap();
        assert_eq!(got.leads.len(), 2);
        assert!(!got.centre_pierce);
        case.assert_clear(0, &got.leads);
        let path = case.path(0);
        for lead in &got.leads {
            // The pierce lies the lead length from the cut path and from the entry square to
            // it (line) or a quarter turn before it (arc).
            let d = dist_to_ring(lead.pierce(), &path);
            assert!(
                (d - 5.0).abs() < 1e-9,
                "{shape:?}: pierce {d} mm off the path"
            );
            let e = lead.entry();
            let gap = distance(lead.pierce(), e);
            let want = match shape {
                LeadShape::Line => 5.0,
                LeadShape::Arc => 5.0 * std::f64::consts::SQRT_2,
            };
            assert!((gap - want).abs() < 1e-9, "{shape:?}: {gap}");
            // The lead-out leaves from the entry into the scrap.
            assert_eq!(lead.lead_out[0], e);
            let out = dist_to_ring(lead.exit(), &path);
            assert!(out > 1.0, "exit {out} mm off the path");
        }
        // The first entry lies on the bottom edge, the cut path 0.75 below the part.
        assert!((got.leads[0].entry()[1] - 49.25).abs() < 1e-9);
    }
}

#[test]
fn small_holes_are_pierced_at_their_centre_with_a_half_circle() {
    let case = Case {
        rings: vec![rect(0.0, 0.0, 100.0, 100.0), circle([50.0, 50.0], 5.0, 48)],
        roles: vec![ContourRole::Outer, ContourRole::Hole],
        sheet: [100.0, 100.0],
        params: params(LeadShape::Arc, 1.5),
    };
    let got = case.leads(1, &[[55.0, 50.0]]).unwrap();
    assert!(got.centre_pierce);
    assert_eq!(got.leads.len(), 1);
    let lead = &got.leads[0];
    assert!(
        distance(lead.pierce(), [50.0, 50.0]) < 0.05,
        "{:?}",
        lead.pierce()
    );
    // A half circle: every point at half the pierce-entry distance from their middle.
    let (p, e) = (lead.pierce(), lead.entry());
    let c = [(p[0] + e[0]) / 2.0, (p[1] + e[1]) / 2.0];
    let r = distance(p, e) / 2.0;
    assert!(lead
        .lead_in
        .iter()
        .all(|&q| (distance(q, c) - r).abs() < 1e-9));
    assert!(lead.lead_in.len() > 5);
    case.assert_clear(1, &got.leads);
}

#[test]
fn a_slot_narrower_than_the_lead_gets_a_shorter_lead_inside_it() {
    let mut p = params(LeadShape::Line, 1.0);
    p.small_hole_diameter_mm = 0.0;
    let case = Case {
        rings: vec![rect(0.0, 0.0, 200.0, 50.0), rect(20.0, 20.0, 100.0, 4.0)],
        roles: vec![ContourRole::Outer, ContourRole::Hole],
        sheet: [200.0, 50.0],
        params: p,
    };
    let got = case.leads(1, &[[70.0, 20.0], [70.0, 24.0]]).unwrap();
    assert_eq!(got.leads.len(), 2);
    case.assert_clear(1, &got.leads);
    let path = case.path(1);
    for lead in &got.leads {
        // 4 mm slot, 0.5 mm path offset each side: the pierce at most 3 − 0.5 mm off the
        // path (the far wall's path is 3 mm away).
        let d = dist_to_ring(lead.pierce(), &path);
        assert!(d <= 2.5 + 1e-9 && d > 0.5, "{d}");
    }
}

#[test]
fn parts_closer_than_a_lead_shorten_or_move_their_leads() {
    // Two squares 3 mm apart, kerf 1: a 5 mm lead cannot go between them.
    let case = Case {
        rings: vec![rect(20.0, 20.0, 30.0, 30.0), rect(53.0, 20.0, 30.0, 30.0)],
        roles: vec![ContourRole::Outer, ContourRole::Outer],
        sheet: [120.0, 80.0],
        params: params(LeadShape::Arc, 1.0),
    };
    // Entry on the left square's right edge, facing the other square.
    let got = case.leads(0, &[[50.0, 35.0]]).unwrap();
    case.assert_clear(0, &got.leads);
    assert_eq!(got.leads.len(), 1);
    // Between the squares the pierce may lie at most 3 − 0.5 − 1 = 1.5 mm off the path.
    let lead = &got.leads[0];
    let d = dist_to_ring(lead.pierce(), &case.path(0));
    let between = lead.pierce()[0] > 50.0 && lead.pierce()[1] > 20.0 && lead.pierce()[1] < 50.0;
    assert!(!between || d <= 1.5 + 1e-9, "{:?} {d}", lead.pierce());
    // An entry the squares' corner region does not crowd keeps the full length.
    let got = case.leads(0, &[[35.0, 20.0]]).unwrap();
    case.assert_clear(0, &got.leads);
    let d = dist_to_ring(got.leads[0].pierce(), &case.path(0));
    assert!((d - 5.0).abs() < 1e-9, "{d}");
}

#[test]
fn leads_in_a_hole_avoid_the_island_inside_it_and_its_own_hole() {
    // A plate with a big hole; an island part in it with a small hole of its own.
    let case = Case {
        rings: vec![
            rect(0.0, 0.0, 120.0, 120.0),
            rect(10.0, 10.0, 100.0, 100.0),
            rect(14.0, 14.0, 92.0, 92.0),
            circle([60.0, 60.0], 4.0, 32),
        ],
        roles: vec![
            ContourRole::Outer,
            ContourRole::Hole,
            ContourRole::Outer,
            ContourRole::Hole,
        ],
        sheet: [120.0, 120.0],
        params: params(LeadShape::Arc, 1.0),
    };
    // The hole's entries: 4 mm between hole and island leaves room for 4 − 1 − 0.5 = 2.5 mm.
    let got = case.leads(1, &[[60.0, 10.0], [110.0, 60.0]]).unwrap();
    assert_eq!(got.leads.len(), 2);
    case.assert_clear(1, &got.leads);
    for lead in &got.leads {
        assert!(dist_to_ring(lead.pierce(), &case.path(1)) <= 2.5 + 1e-9);
    }
    // The island's leads come from its outside, inside the big hole, shortened alike.
    let got = case.leads(2, &[[60.0, 14.0]]).unwrap();
    case.assert_clear(2, &got.leads);
    // The island's small hole: centre pierce.
    let got = case.leads(3, &[[64.0, 60.0]]).unwrap();
    assert!(got.centre_pierce);
    case.assert_clear(3, &got.leads);
}

#[test]
fn a_part_with_no_room_for_any_lead_is_refused_with_the_reason() {
    // An island 1.2 mm inside its hole all round, kerf 1: no lead keeps 1 mm clearance.
    let case = Case {
        rings: vec![
            rect(0.0, 0.0, 60.0, 60.0),
            rect(10.0, 10.0, 40.0, 40.0),
            rect(11.2, 11.2, 37.6, 37.6),
        ],
        roles: vec![ContourRole::Outer, ContourRole::Hole, ContourRole::Outer],
        sheet: [60.0, 60.0],
        params: params(LeadShape::Line, 1.0),
    };
    let e = case.leads(2, &[[30.0, 11.2]]).unwrap_err();
    assert!(e.contains("no lead-in"), "{e}");
}

#[test]
fn leads_stay_on_the_sheet_and_the_entry_moves_if_it_must() {
    // A part 1 mm from the sheet's left edge: a lead from the left would leave the sheet.
    let case = Case {
        rings: vec![rect(1.0, 20.0, 30.0, 30.0)],
        roles: vec![ContourRole::Outer],
        sheet: [100.0, 100.0],
        params: params(LeadShape::Line, 1.0),
    };
    let got = case.leads(0, &[[1.0, 35.0]]).unwrap();
    case.assert_clear(0, &got.leads);
    assert!(got.leads.iter().all(|l| l.pierce()[0] >= 0.0));
}

#[test]
fn overcut_and_lead_out_follow_the_entry() {
    let mut p = params(LeadShape::Line, 1.0);
    p.overcut_mm = 3.0;
    let case = Case {
        rings: vec![rect(20.0, 20.0, 30.0, 30.0)],
        roles: vec![ContourRole::Outer],
        sheet: [100.0, 100.0],
        params: p,
    };
    let got = case.leads(0, &[[35.0, 50.0]]).unwrap();
    let lead = &got.leads[0];
    case.assert_clear(0, &got.leads);
    // Clockwise, the top edge runs left to right: the overcut goes 3 mm further right.
    let path = case.path(0);
    let e = lead.entry();
    let over = lead.lead_out[1];
    assert!((distance(e, over) - 3.0).abs() < 1e-9, "{over:?}");
    assert!(over[0] > e[0] && dist_to_ring(over, &path) < 1e-9);
    // Then 2 mm at 45° into the scrap.
    assert!((distance(over, lead.exit()) - 2.0).abs() < 1e-9);
    // The whole cut: lead-in, once round from the entry, overcut and lead-out.
    let full = lead_cut_path(&path, lead);
    assert_eq!(full[0], lead.pierce());
    assert_eq!(*full.last().unwrap(), lead.exit());
    let perimeter: f64 = path_length(&loop_from_entry(&path, lead.entry_edge, e));
    let expected = lead.lead_in_length() + perimeter + path_length(&lead.lead_out);
    assert!((path_length(&full) - expected).abs() < 1e-9);
}
