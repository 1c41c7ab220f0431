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
//! Pure: no ROS, no I/O.

use cell_geometry::Norm;
use cell_msgs::{
    builtin_interfaces::Time, geometry_msgs, std_msgs::Header, CutPlan as CutPlanMsg, Toolpath,
    ToolpathSegment,
};

use crate::plan::CutPlan;
use crate::problem::{Point, Problem};
use crate::thermal::cut_path;

/// The frame the sheet coordinates are in (sheet origin at the lower-left corner).
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
        segments.push(segment(
            ToolpathSegment::KIND_CUT,
            &cut_path(contour, pierce),
            opt.cut_mm_s,
            opt.power_percent,
        ));
        at = pierce;
    }
    segments.push(segment(
        ToolpathSegment::KIND_TRAVEL,
        &[at, problem.start],
        opt.rapid_mm_s,
        0.0,
    ));
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
        pierce_points: valid.iter().map(|c| point(c.point(problem))).collect(),
        policy: policy.into(),
        improved,
        idle_length_mm: plan.idle_mm,
        cut_length_mm: plan.cut_mm,
        overheats: plan.overheats as u32,
        max_temperature_c: f64::from(plan.max_temp_c - ambient_c).max(0.0),
        cost: plan.cost,
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
