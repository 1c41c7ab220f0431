//! Messages from a plan (seed 003 §A1 `R`, notes §A6 outputs): a [`CutPlan`] of a [`Problem`]
//! as the `cell_msgs::Toolpath` the emitter turns into a program, and as the
//! `cell_msgs::CutPlan` the `sequence_sheet` action returns.
//!
//! **Toolpath.** `PROCESS_SHEET_CUT`, power in `POWER_LASER_PERCENT` (percent of the cutter's
//! power or arc-current setting). Segments alternate: a `KIND_TRAVEL` rapid from where the tool
//! is to the next pierce point (two points, power 0, feed `rapid_mm_s`), then one `KIND_CUT`
//! segment per contour along [`cut_path`] (it starts and ends at the pierce point; feed
//! `cut_mm_s`, power `power_percent` at every point), and a last travel back to the start.
//! Travel segments therefore add up to the plan's idle length exactly. z = 0 everywhere (the
//! emitter owns the torch heights).
//!
//! **Leads** (a problem cut with kerf and leads, [`crate::cut`]): the travel ends at the
//! lead-in's start (the pierce, on the scrap side), then a `KIND_LEAD` segment (the lead-in),
//! the `KIND_CUT` segment once round the cut path from the entry point back to it, and, if
//! there is an overcut or a lead-out, a second `KIND_LEAD` segment from the entry point to
//! the exit; all at `cut_mm_s` and `power_percent` (the heat stays on from the pierce to the
//! exit). The next travel starts at the exit. Every cut path goes round with the part on its
//! right (outer contours clockwise, holes counter-clockwise, [`crate::kerf`]), so a
//! controller compensating the kerf puts the tool on the left: `G41` for every contour.
//!
//! **Coordinates.** Both messages are in machine coordinates: every point, the start included,
//! is the problem's sheet-relative point plus [`Problem::origin`] ([`to_machine_frame`], the
//! one place it is added; [`crate::placement`]), so a DXF's parts are cut where the drawing
//! puts them. `start` is relative to the sheet like every point of the problem.
//!
//! Pure: no ROS, no I/O.

use cell_geometry::Norm;
use cell_msgs::{
    builtin_interfaces::Time, geometry_msgs, std_msgs::Header, CutPlan as CutPlanMsg, Toolpath,
    ToolpathSegment,
};

use crate::cut::CutSummary;
use crate::leads::{loop_from_entry, Lead};
use crate::plan::CutPlan;
use crate::problem::{Point, Problem};
use crate::thermal::cut_path;

/// The frame of the toolpath and the cut plan: the cutting table's XY, in which the sheet's
/// lower-left corner is at [`Problem::origin`] (module docs). The `sheet_heat` raster frames
/// are sheet-relative: their cell (0, 0) is at that corner.
pub const FRAME_ID: &str = "sheet";

/// Feeds and power of the toolpath (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ToolpathOptions {
    /// Cutting feed, mm/s (normally the thermal model's `cut_speed_mm_s`, capped at the
    /// machine's feed limit).
    pub cut_mm_s: f64,
    /// Rapid feed, mm/s (the thermal model's `rapid_speed_mm_s`; the emitter writes G0).
    pub rapid_mm_s: f64,
    /// Cutting power, percent.
    pub power_percent: f64,
}

impl Default for ToolpathOptions {
    /// The thermal model's default feeds (40 and 250 mm/s) at 100 % power.
    fn default() -> Self {
        ToolpathOptions {
            cut_mm_s: 40.0,
            rapid_mm_s: 250.0,
            power_percent: 100.0,
        }
    }
}

fn point(p: Point) -> geometry_msgs::Point {
    geometry_msgs::Point {
        x: p[0],
        y: p[1],
        z: 0.0,
    }
}

fn segment(kind: u8, pts: &[Point], feed: f64, power: f64) -> ToolpathSegment {
    ToolpathSegment {
        kind,
        points: pts.iter().map(|&p| point(p)).collect(),
        feed_mm_s: vec![feed as f32; pts.len()],
        power: vec![power as f32; pts.len()],
        ..Default::default()
    }
}

/// The toolpath of `plan` on `problem` (module docs). Cuts naming a contour or pierce
/// candidate the problem does not have are skipped (plans from [`crate::policy`] and
/// [`crate::improve`] never do).
pub fn to_toolpath(
    problem: &Problem,
    plan: &CutPlan,
    job_id: &str,
    opt: &ToolpathOptions,
) -> Toolpath {
    let mut segments = Vec::with_capacity(2 * plan.cuts.len() + 1);
    let mut at = problem.start;
    for c in &plan.cuts {
        let Some(contour) = problem.contours.get(c.contour) else {
            continue;
        };
        let Some(&pierce) = contour.pierce_candidates.get(c.pierce) else {
            continue;
        };
        segments.push(segment(
            ToolpathSegment::KIND_TRAVEL,
            &[at, pierce],
            opt.rapid_mm_s,
            0.0,
        ));
        match contour.leads.get(c.pierce) {
            Some(lead) => {
                segments.extend(lead_segments(&contour.points, lead, opt));
                at = lead.exit();
            }
            None => {
                segments.push(segment(
                    ToolpathSegment::KIND_CUT,
                    &cut_path(contour, pierce),
                    opt.cut_mm_s,
                    opt.power_percent,
                ));
                at = pierce;
            }
        }
    }
    segments.push(segment(
        ToolpathSegment::KIND_TRAVEL,
        &[at, problem.start],
        opt.rapid_mm_s,
        0.0,
    ));
    to_machine_frame(problem, &mut segments);
    Toolpath {
        header: Header {
            stamp: Time::now(),
            frame_id: FRAME_ID.into(),
        },
        job_id: job_id.into(),
        process: Toolpath::PROCESS_SHEET_CUT,
        power_unit: Toolpath::POWER_LASER_PERCENT,
        plane_separation_mm: 0.0,
        segments,
    }
}

/// A cut with leads (module docs): the lead-in, the cut path once round from the entry point
/// and the overcut and lead-out if any, all with the heat on.
fn lead_segments(
    points: &[Point],
    lead: &Lead,
    opt: &ToolpathOptions,
) -> impl Iterator<Item = ToolpathSegment> {
    let (feed, power) = (opt.cut_mm_s, opt.power_percent);
    let lead_in = segment(ToolpathSegment::KIND_LEAD, &lead.lead_in, feed, power);
    let cut = segment(
        ToolpathSegment::KIND_CUT,
        &loop_from_entry(points, lead.entry_edge, lead.entry()),
        feed,
        power,
    );
    let lead_out = (lead.lead_out.len() > 1)
        .then(|| segment(ToolpathSegment::KIND_LEAD, &lead.lead_out, feed, power));
    [lead_in, cut].into_iter().chain(lead_out)
}

/// The `cell_msgs/CutPlan` of `plan` on `problem` (seed 003 §A1 `R`; notes §A6): order,
/// parts, pierce points, `policy` name, whether it was `improved`, and the plan's metrics.
/// `max_temperature_c` is the hottest metal cell's excess over ambient (the message's unit).
pub fn to_cut_plan_msg(
    problem: &Problem,
    plan: &CutPlan,
    job_id: &str,
    policy: &str,
    improved: bool,
    ambient_c: f32,
) -> CutPlanMsg {
    let valid = plan
        .cuts
        .iter()
        .filter(|c| {
            problem
                .contours
                .get(c.contour)
                .is_some_and(|k| c.pierce < k.pierce_candidates.len())
        })
        .copied()
        .collect::<Vec<_>>();
    CutPlanMsg {
        header: Header {
            stamp: Time::now(),
            frame_id: FRAME_ID.into(),
        },
        job_id: job_id.into(),
        order: valid.iter().map(|c| c.contour as u32).collect(),
        parts: valid
            .iter()
            .map(|c| problem.contours[c.contour].part as u32)
            .collect(),
        pierce_points: valid
            .iter()
            .map(|c| point(problem.to_machine(c.point(problem))))
            .collect(),
        policy: policy.into(),
        improved,
        idle_length_mm: plan.idle_mm,
        cut_length_mm: plan.cut_mm,
        overheats: plan.overheats as u32,
        max_temperature_c: f64::from(plan.max_temp_c - ambient_c).max(0.0),
        cost: plan.cost,
        ..Default::default()
    }
}

/// The cut plan message with the kerf and lead lengths of the job's cut (`None`: left 0, a
/// plan cut on the drawn contours).
pub fn with_cut(mut msg: CutPlanMsg, cut: Option<&CutSummary>) -> CutPlanMsg {
    if let Some(c) = cut {
        msg.kerf_mm = c.kerf_mm;
        msg.path_offset_mm = c.path_offset_mm;
        msg.lead_in_mm = c.lead_in_mm;
        msg.lead_out_mm = c.lead_out_mm;
    }
    msg
}

/// Moves sheet-relative segments to machine coordinates: `origin + p` at every point
/// ([`Problem::to_machine`]; module docs).
pub fn to_machine_frame(problem: &Problem, segments: &mut [ToolpathSegment]) {
    for p in segments.iter_mut().flat_map(|s| s.points.iter_mut()) {
        [p.x, p.y] = problem.to_machine([p.x, p.y]);
    }
}

/// The sum of the travel segments' lengths, mm (equals the plan's idle length).
pub fn travel_length_mm(toolpath: &Toolpath) -> f64 {
    toolpath
        .segments
        .iter()
        .filter(|s| s.kind == ToolpathSegment::KIND_TRAVEL)
        .flat_map(|s| s.points.windows(2))
        .map(|w| Norm::Hypot.distance([w[0].x, w[0].y], [w[1].x, w[1].y]))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cost::{CostParams, Evaluator};
    use crate::layout::{Layout, PierceOptions};
    use crate::policy::{construct, Policy};
    use crate::precedence::PrecedenceMode;
    use crate::thermal::ThermalParams;

    fn problem() -> Problem {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../tests/data/sheet/example.json"
        );
        Layout::from_json_file(path)
            .unwrap()
            .to_problem(PrecedenceMode::Strict, &PierceOptions::default())
            .unwrap()
    }

    #[test]
    fn one_cut_per_contour_from_its_pierce_point_and_travel_is_the_idle_length() {
        let problem = problem();
        let eval =
            Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
        let plan = construct(&eval, Policy::PathOverheat, 1).unwrap();
        let opt = ToolpathOptions {
            cut_mm_s: 30.0,
            rapid_mm_s: 200.0,
            power_percent: 80.0,
        };
        let tp = to_toolpath(&problem, &plan, "t", &opt);
        assert_eq!(tp.process, Toolpath::PROCESS_SHEET_CUT);
        let cuts: Vec<_> = tp
            .segments
            .iter()
            .filter(|s| s.kind == ToolpathSegment::KIND_CUT)
            .collect();
        assert_eq!(cuts.len(), problem.contours.len());
        assert_eq!(cuts.len(), plan.cuts.len());
        for (seg, cut) in cuts.iter().zip(&plan.cuts) {
            let p = cut.point(&problem);
            let (first, last) = (seg.points[0], *seg.points.last().unwrap());
            assert_eq!((first.x, first.y), (p[0], p[1]));
            assert_eq!((last.x, last.y), (p[0], p[1]));
            assert!(seg.feed_mm_s.iter().all(|&f| f == 30.0));
            assert!(seg.power.iter().all(|&w| w == 80.0));
            assert_eq!(seg.power.len(), seg.points.len());
        }
        let travel = travel_length_mm(&tp);
        assert!(
            (travel - plan.idle_mm).abs() < 1e-9,
            "travel {travel} vs idle {}",
            plan.idle_mm
        );
        // Travel segments alternate with cuts and chain end to start.
        for w in tp.segments.windows(2) {
            let (a, b) = (w[0].points.last().unwrap(), w[1].points[0]);
            assert_eq!((a.x, a.y), (b.x, b.y));
            assert_ne!(w[0].kind, w[1].kind);
        }
    }

    #[test]
    fn the_cut_plan_message_carries_order_parts_pierces_and_metrics() {
        let problem = problem();
        let eval =
            Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
        let plan = construct(&eval, Policy::Nearest, 0).unwrap();
        let m = to_cut_plan_msg(&problem, &plan, "j", "nearest", false, 20.0);
        let order: Vec<usize> = m.order.iter().map(|&c| c as usize).collect();
        assert_eq!(order, plan.order());
        problem.precedence.check_order(&order).unwrap();
        assert_eq!(m.parts.len(), order.len());
        assert_eq!(m.pierce_points.len(), order.len());
        for (i, &c) in order.iter().enumerate() {
            assert_eq!(m.parts[i] as usize, problem.contours[c].part);
        }
        assert_eq!(m.idle_length_mm, plan.idle_mm);
        assert_eq!(m.cut_length_mm, plan.cut_mm);
        assert_eq!(m.overheats as usize, plan.overheats);
        assert_eq!(m.cost, plan.cost);
        assert_eq!(m.policy, "nearest");
    }

    #[test]
    fn an_empty_plan_is_one_travel_home() {
        let problem = problem();
        let tp = to_toolpath(
            &problem,
            &CutPlan::default(),
            "e",
            &ToolpathOptions::default(),
        );
        assert_eq!(tp.segments.len(), 1);
        assert_eq!(travel_length_mm(&tp), 0.0);
    }
}
