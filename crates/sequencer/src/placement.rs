//! Where the sheet sits on the machine (issue 19, item 1: the program cuts where the drawing
//! says).
//!
//! Inside the crate every point is relative to the sheet's lower-left corner (the sheet spans
//! `[0, a] × [0, b]`: the thermal raster, the generator and the improvement need nothing
//! else). The sheet's **origin** is where that corner is in machine coordinates
//! ([`crate::layout::Layout::origin`], [`crate::problem::Problem::origin`]); the toolpath and
//! the cut plan add it to every point they emit, so a DXF's parts are cut at the drawing's own
//! coordinates. [`SheetRule`] says how the sheet was found, [`SheetPlacement`] is what the
//! `cell sheet` report and the node's result state, and [`check_travel`] refuses a part that
//! would leave the machine's travel once placed.

use cell_profiles::MachineProfile;
use serde::Serialize;

use crate::problem::{Point, Problem};

/// How the sheet of a layout was found (issue 19, item 1; [`crate::dxf`] module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum SheetRule {
    /// The sheet size was given ([`crate::dxf::DxfOptions::sheet`]): it spans `[0, a] × [0, b]`
    /// of the drawing.
    Option,
    /// A closed contour on the sheet layer (`SHEET`): its bounding box.
    SheetLayer,
    /// The DXF header's `$LIMMIN`/`$LIMMAX`, which contain every part.
    Limits,
    /// The DXF header's `$EXTMIN`/`$EXTMAX`, which contain every part.
    Extents,
    /// None of the above: the parts' bounding box (the parts are not moved).
    Parts,
    /// A JSON layout: its `sheet` and `origin` as the file gives them.
    Layout,
}

impl SheetRule {
    /// The rule's name, as the report spells it.
    pub fn name(self) -> &'static str {
        match self {
            SheetRule::Option => "option",
            SheetRule::SheetLayer => "sheet_layer",
            SheetRule::Limits => "limits",
            SheetRule::Extents => "extents",
            SheetRule::Parts => "parts",
            SheetRule::Layout => "layout",
        }
    }
}

/// Who set the sheet's origin on the machine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OriginFrom {
    /// The drawing (or the JSON layout): program coordinates equal the drawing's.
    Drawing,
    /// The operator (`--sheet-origin`, the node's `sheet_origin`).
    Operator,
}

/// Where a job's sheet is (the report's `sheet` object).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SheetPlacement {
    /// How the sheet was found.
    pub rule: SheetRule,
    /// Sheet size `a × b`, mm.
    pub size_mm: [f64; 2],
    /// The sheet's lower-left corner in machine coordinates, mm.
    pub origin_mm: Point,
    /// Who set `origin_mm`.
    pub origin_from: OriginFrom,
}

impl std::fmt::Display for SheetPlacement {
    /// `sheet 3000 × 1500 mm by limits, corner at (0.000, 0.000) mm on the machine (drawing)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "sheet {} × {} mm by {}, corner at ({:.3}, {:.3}) mm on the machine ({})",
            self.size_mm[0],
            self.size_mm[1],
            self.rule.name(),
            self.origin_mm[0],
            self.origin_mm[1],
            match self.origin_from {
                OriginFrom::Drawing => "drawing",
                OriginFrom::Operator => "operator",
            }
        )
    }
}

/// The machine's XY travel, mm: what a placed part must stay inside.
#[derive(Debug, Clone, PartialEq)]
pub struct Travel {
    /// The machine's name, for messages.
    pub machine: String,
    /// X travel `[min, max]`, mm; `None` if the machine has no such axis.
    pub x_mm: Option<[f64; 2]>,
    /// Y travel `[min, max]`, mm; `None` if the machine has no such axis.
    pub y_mm: Option<[f64; 2]>,
}

impl Travel {
    /// The travel of the axes a profile writes the toolpath's x and y as (its G-code axis
    /// words, else `X` and `Y`).
    pub fn of(profile: &MachineProfile) -> Travel {
        let (x, y) = profile
            .gcode
            .as_ref()
            .map_or(('X', 'Y'), |g| (g.axis_words.x, g.axis_words.y));
        Travel {
            machine: profile.name.clone(),
            x_mm: profile.axes.get(&x).copied(),
            y_mm: profile.axes.get(&y).copied(),
        }
    }
}

/// A part that leaves the machine's travel once the sheet is placed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "{part} spans X {:.3}..{:.3}, Y {:.3}..{:.3} mm on the machine (sheet origin ({:.3}, {:.3}) mm): \
     outside the {axis} travel {:.3}..{:.3} mm of machine '{machine}'",
    .extent_mm[0], .extent_mm[2], .extent_mm[1], .extent_mm[3], .origin_mm[0], .origin_mm[1],
    .travel_mm[0], .travel_mm[1]
)]
pub struct OutOfTravel {
    /// The part, by index and name.
    pub part: String,
    /// Its extent in machine coordinates `[x_min, y_min, x_max, y_max]`, mm (cut paths,
    /// pierce candidates and leads).
    pub extent_mm: [f64; 4],
    /// The sheet's origin, mm.
    pub origin_mm: Point,
    /// `X` or `Y`.
    pub axis: char,
    /// That axis's travel, mm.
    pub travel_mm: [f64; 2],
    /// The machine.
    pub machine: String,
}

/// Travel limits are met within this, mm (values that round onto the limit pass, as in
/// [`MachineProfile::check_position`]).
const TRAVEL_SLACK_MM: f64 = 1e-3;

/// Checks that every part of `problem`, placed at its origin, lies inside `travel`: every
/// point of its contours' cut paths, pierce candidates and leads (the first part outside is
/// the error; `part_name(i)` names part `i`).
///
/// # Errors
/// [`OutOfTravel`] for the first part (in part order) outside the travel.
pub fn check_travel(
    problem: &Problem,
    travel: &Travel,
    part_name: impl Fn(usize) -> String,
) -> Result<(), OutOfTravel> {
    let parts = problem
        .contours
        .iter()
        .map(|c| c.part)
        .max()
        .map_or(0, |p| p + 1);
    let mut extent = vec![[f64::INFINITY, f64::INFINITY, -f64::INFINITY, -f64::INFINITY]; parts];
    for c in &problem.contours {
        let e = &mut extent[c.part];
        let leads = c
            .leads
            .iter()
            .flat_map(|l| l.lead_in.iter().chain(&l.lead_out));
        for p in c.points.iter().chain(&c.pierce_candidates).chain(leads) {
            let q = problem.to_machine(*p);
            *e = [
                e[0].min(q[0]),
                e[1].min(q[1]),
                e[2].max(q[0]),
                e[3].max(q[1]),
            ];
        }
    }
    for (part, e) in extent.into_iter().enumerate() {
        let axes = [
            ('X', travel.x_mm, [e[0], e[2]]),
            ('Y', travel.y_mm, [e[1], e[3]]),
        ];
        for (axis, range, span) in axes {
            let Some(range) = range else { continue };
            let inside =
                span[0] >= range[0] - TRAVEL_SLACK_MM && span[1] <= range[1] + TRAVEL_SLACK_MM;
            if !inside && span[0] <= span[1] {
                return Err(OutOfTravel {
                    part: part_name(part),
                    extent_mm: e,
                    origin_mm: problem.origin,
                    axis,
                    travel_mm: range,
                    machine: travel.machine.clone(),
                });
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::{Layout, PierceOptions};
    use crate::precedence::PrecedenceMode;

    fn problem(origin: Point) -> Problem {
        let json = r#"{"sheet": [100, 50], "parts": [
            {"name": "left", "outer": {"points": [[5,5],[20,5],[20,20],[5,20]]}},
            {"name": "right", "outer": {"points": [[80,10],[95,10],[95,45],[80,45]]}}]}"#;
        let mut l = Layout::from_json_str(json, "t").unwrap();
        l.origin = origin;
        l.to_problem(PrecedenceMode::Strict, &PierceOptions::default())
            .unwrap()
    }

    #[test]
    fn json_layouts_carry_the_origin_only_when_it_is_set() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../tests/data/sheet/example.json"
        );
        let mut l = Layout::from_json_file(path).unwrap();
        assert_eq!(l.origin, [0.0, 0.0]);
        assert!(
            !l.to_json().contains("origin"),
            "unchanged files stay unchanged"
        );
        l.origin = [100.0, -50.5];
        let back = Layout::from_json_str(&l.to_json(), "back").unwrap();
        assert_eq!(back, l);
        let p = back
            .to_problem(PrecedenceMode::Strict, &PierceOptions::default())
            .unwrap();
        assert_eq!(p.origin, [100.0, -50.5]);
        assert_eq!(p.to_machine([1.0, 2.0]), [101.0, -48.5]);
    }

    #[test]
    fn the_toolpath_and_the_cut_plan_are_the_sheet_plus_the_origin() {
        use crate::cost::{CostParams, Evaluator};
        use crate::policy::{construct, Policy};
        use crate::thermal::ThermalParams;
        use crate::toolpath::{to_cut_plan_msg, to_toolpath, ToolpathOptions};
        let at = problem([0.0, 0.0]);
        let moved = problem([250.0, -40.0]);
        let eval = Evaluator::new(&at, ThermalParams::default(), CostParams::default()).unwrap();
        let plan = construct(&eval, Policy::Nearest, 0).unwrap();
        let opt = ToolpathOptions::default();
        let (a, b) = (
            to_toolpath(&at, &plan, "j", &opt),
            to_toolpath(&moved, &plan, "j", &opt),
        );
        assert_eq!(a.segments.len(), b.segments.len());
        let points = |t: &cell_msgs::Toolpath| -> Vec<[f64; 2]> {
            t.segments
                .iter()
                .flat_map(|s| &s.points)
                .map(|p| [p.x, p.y])
                .collect()
        };
        let (pa, pb) = (points(&a), points(&b));
        assert_eq!(pa.len(), pb.len());
        for (p, q) in pa.iter().zip(&pb) {
            assert_eq!([p[0] + 250.0, p[1] - 40.0], *q);
        }
        // The travel starts and ends at the start point, relative to the sheet.
        assert_eq!(pb[0], [250.0, -40.0]);
        assert_eq!(pb.last(), Some(&[250.0, -40.0]));
        let (ma, mb) = (
            to_cut_plan_msg(&at, &plan, "j", "nearest", false, 20.0),
            to_cut_plan_msg(&moved, &plan, "j", "nearest", false, 20.0),
        );
        for (p, q) in ma.pierce_points.iter().zip(&mb.pierce_points) {
            assert_eq!((p.x + 250.0, p.y - 40.0), (q.x, q.y));
        }
        assert_eq!(ma.idle_length_mm, mb.idle_length_mm);
    }

    fn travel(x: [f64; 2], y: [f64; 2]) -> Travel {
        Travel {
            machine: "table".into(),
            x_mm: Some(x),
            y_mm: Some(y),
        }
    }

    #[test]
    fn a_part_beyond_the_travel_is_named_with_its_extent_and_the_travel() {
        let name = |i: usize| format!("part {i} '{}'", ["left", "right"][i]);
        let p = problem([0.0, 0.0]);
        check_travel(&p, &travel([0.0, 100.0], [0.0, 50.0]), name).unwrap();
        // Placed 10 mm further right, the right part's edge (95 → 105) leaves X 0..100.
        let e = check_travel(
            &problem([10.0, 0.0]),
            &travel([0.0, 100.0], [0.0, 50.0]),
            name,
        )
        .unwrap_err();
        assert_eq!(e.part, "part 1 'right'");
        assert_eq!(e.axis, 'X');
        assert_eq!(e.extent_mm, [90.0, 10.0, 105.0, 45.0]);
        assert_eq!(
            e.to_string(),
            "part 1 'right' spans X 90.000..105.000, Y 10.000..45.000 mm on the machine (sheet \
             origin (10.000, 0.000) mm): outside the X travel 0.000..100.000 mm of machine 'table'"
        );
        // Below the Y travel: the left part first.
        let e = check_travel(
            &problem([0.0, -6.0]),
            &travel([0.0, 100.0], [0.0, 50.0]),
            name,
        )
        .unwrap_err();
        assert_eq!((e.part.as_str(), e.axis), ("part 0 'left'", 'Y'));
        // An axis the machine does not have is not checked.
        let no_y = Travel {
            y_mm: None,
            ..travel([0.0, 100.0], [0.0, 0.0])
        };
        check_travel(&problem([0.0, -6.0]), &no_y, name).unwrap();
    }
}
