//! `plan.svg`: a picture of a cut plan, for the operator to check before cutting (issue 19,
//! item 7). Everything is drawn in machine coordinates (what the program cuts), mm, y up:
//!
//! - the sheet outline and the parts (outer contours filled light, holes white), from the
//!   [`Problem`] placed at its `origin`;
//! - what the [`Toolpath`] carries, by segment kind: the cuts (`KIND_CUT`: the offset path when
//!   kerf compensation is on), the lead-ins and lead-outs (`KIND_LEAD`) and the rapid moves
//!   (`KIND_TRAVEL`, dashed and thin);
//! - a pierce marker where each contour's run starts (the first point of every run of
//!   non-travel segments) with its number in the cut order beside it, and the contour and part
//!   it cuts as the marker's tooltip;
//! - a red circle at every overheat the thermal simulation counted;
//! - the machine origin, a title with the plan's figures and a legend.
//!
//! The groups have ids (`sheet`, `parts`, `rapids`, `cuts`, `leads`, `overheats`, `pierces`,
//! `order`, `axes`, `title`, `legend`), so a check can count the markers.
//!
//! **Size.** Coordinates are rounded to 0.01 mm, path data is relative after one absolute
//! move, each kind is one path, and the styles sit in one `<style>` sheet: 5000 contours make
//! a file of a few MB. Pure: the picture is returned as text.

use std::collections::BTreeMap;

use cell_msgs::{CutPlan as CutPlanMsg, Toolpath, ToolpathSegment};
use svg::node::element::path::Data;
use svg::node::element::{Circle, Group, Path, Rectangle, Style, Text, Title};
use svg::Document;

use crate::problem::{Point, Problem};

/// A point in hundredths of a millimetre, y down (the SVG's axes).
type Cents = [i64; 2];

fn cents(p: Point) -> Cents {
    [
        (p[0] * 100.0).round() as i64,
        (-p[1] * 100.0).round() as i64,
    ]
}

/// Hundredths of a millimetre as the SVG number in mm (`12345` → `123.45`).
fn mm(c: i64) -> f64 {
    c as f64 / 100.0
}

/// A length in mm, rounded to 0.01 mm.
fn len(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// Path data of the polylines in `runs`: per run an absolute move, then relative lines
/// (repeated points dropped), closed when `close` is set.
fn path_data<I, R>(runs: I, close: bool) -> Data
where
    I: IntoIterator<Item = R>,
    R: IntoIterator<Item = Point>,
{
    let mut data = Data::new();
    for run in runs {
        let mut at: Option<Cents> = None;
        let mut steps: Vec<f32> = Vec::new();
        for p in run {
            let c = cents(p);
            match at {
                None => data = data.move_to((mm(c[0]) as f32, mm(c[1]) as f32)),
                Some(a) if a == c => continue,
                Some(a) => {
                    steps.push(mm(c[0] - a[0]) as f32);
                    steps.push(mm(c[1] - a[1]) as f32);
                }
            }
            at = Some(c);
        }
        if !steps.is_empty() {
            data = data.line_by(steps);
        }
        if close && at.is_some() {
            data = data.close();
        }
    }
    data
}

fn group(id: &str) -> Group {
    Group::new().set("id", id)
}

/// The runs of the toolpath segments of one kind, in machine coordinates.
fn runs_of(toolpath: &Toolpath, kind: u8) -> impl Iterator<Item = Vec<Point>> + '_ {
    toolpath
        .segments
        .iter()
        .filter(move |s| s.kind == kind && !s.points.is_empty())
        .map(|s| s.points.iter().map(|p| [p.x, p.y]).collect())
}

/// Where each contour's run starts: the first point of every run of non-travel segments.
pub fn pierce_points(toolpath: &Toolpath) -> Vec<Point> {
    let mut pierces = Vec::new();
    let mut cutting = false;
    for s in &toolpath.segments {
        if s.kind == ToolpathSegment::KIND_TRAVEL {
            cutting = false;
        } else if let (false, Some(p)) = (cutting, s.points.first()) {
            pierces.push([p.x, p.y]);
            cutting = true;
        }
    }
    pierces
}

/// The extent `[min, max]` of `points`, or `None` for none.
fn extent(points: impl IntoIterator<Item = Point>) -> Option<[Point; 2]> {
    points.into_iter().fold(None, |e, p| {
        let [lo, hi] = e.unwrap_or([p, p]);
        Some([
            [lo[0].min(p[0]), lo[1].min(p[1])],
            [hi[0].max(p[0]), hi[1].max(p[1])],
        ])
    })
}

/// The title line: job, contours, idle and cut length, overheats, maximum temperature, policy
/// (the same figures and formats as `cell sheet`'s report line).
pub fn title(plan: &CutPlanMsg) -> String {
    format!(
        "{}: {} contours, idle {:.1} mm, cut {:.1} mm, {} overheats, max {:.0} °C above \
         ambient ({}, {})",
        plan.job_id,
        plan.order.len(),
        plan.idle_length_mm,
        plan.cut_length_mm,
        plan.overheats,
        plan.max_temperature_c,
        plan.policy,
        if plan.improved {
            "improved"
        } else {
            "not improved"
        }
    )
}

/// Sizes of the picture, mm: `title` for the title and legend (from the picture's span),
/// `detail` for the markers, labels and strokes (from the room per contour).
#[derive(Debug, Clone, Copy)]
struct Scale {
    title: f64,
    detail: f64,
}

impl Scale {
    /// `extent` is the size of what is drawn, mm.
    fn new(problem: &Problem, extent: [f64; 2]) -> Self {
        let span = extent[0].max(extent[1]).max(1.0);
        // The title (about 110 characters) fits the width.
        let title = (span / 60.0).min(extent[0].max(1.0) / 70.0);
        let room = (problem.sheet[0] * problem.sheet[1] / problem.contours.len().max(1) as f64)
            .sqrt()
            / 8.0;
        let detail = room.min(title / 2.0).max(span / 2000.0);
        Scale {
            title: len(title),
            detail: len(detail).max(0.01),
        }
    }

    /// The style sheet: colours here, sizes from the scale.
    fn css(&self) -> String {
        let (u, t) = (self.detail, self.title);
        format!(
            "text{{font-family:sans-serif}}\
             .sheet{{fill:#fff;stroke:#777;stroke-width:{sheet}px}}\
             .part{{fill:#d5dde8;fill-rule:evenodd;stroke:none}}\
             .cut{{fill:none;stroke:#1f4e9c;stroke-width:{cut}px;stroke-linejoin:round}}\
             .lead{{fill:none;stroke:#1e9e3c;stroke-width:{cut}px;stroke-linejoin:round}}\
             .rapid{{fill:none;stroke:#666;stroke-width:{rapid}px;stroke-dasharray:{dash}px {gap}px}}\
             .pierce{{fill:#e67e00;stroke:none}}\
             .order{{fill:#222}}\
             .overheat{{fill:none;stroke:#e00000;stroke-width:{hot}px}}\
             .axes{{fill:none;stroke:#999;stroke-width:{sheet}px}}\
             #axes text{{font-size:{small}px;fill:#999}}\
             #title text{{font-size:{t}px;fill:#000}}\
             #legend text{{font-size:{small}px;fill:#222}}\
             #legend path,#legend circle,#legend rect{{stroke-width:{legend_line}px}}\
             #legend .rapid{{stroke-dasharray:{legend_dash}px {legend_gap}px}}\
             #legend .pierce{{stroke:none}}",
            sheet = len(u * 0.15),
            cut = len(u * 0.12),
            rapid = len(u * 0.06),
            dash = len(u * 0.8),
            gap = len(u * 0.5),
            hot = len(u * 0.15),
            small = len(t * 0.7),
            legend_line = len(t * 0.1),
            legend_dash = len(t * 0.4),
            legend_gap = len(t * 0.25),
        )
    }
}

/// The legend: one swatch and label per thing drawn, left to right from `at` (the swatches'
/// centre line), in the title's size.
fn legend(at: Point, scale: Scale) -> Group {
    let t = scale.title;
    let c = cents(at);
    let (x0, y) = (c[0], c[1]);
    let step = (t * 100.0).round() as i64;
    let mut g = group("legend");
    let mut x = x0;
    let items: [(&str, &str); 8] = [
        ("sheet", "sheet"),
        ("part", "part (holes white)"),
        ("cut", "cut"),
        ("lead", "lead-in/out"),
        ("rapid", "rapid"),
        ("pierce", "pierce"),
        ("order", "cut order"),
        ("overheat", "overheat"),
    ];
    for (class, label) in items {
        let swatch: Box<dyn svg::Node> = match class {
            "sheet" | "part" => Box::new(
                Rectangle::new()
                    .set("class", class)
                    .set("x", mm(x))
                    .set("y", mm(y - step / 3))
                    .set("width", mm(step * 3 / 2))
                    .set("height", mm(step * 2 / 3)),
            ),
            "pierce" | "overheat" => Box::new(
                Circle::new()
                    .set("class", class)
                    .set("cx", mm(x + step * 3 / 4))
                    .set("cy", mm(y))
                    .set("r", mm(step / 4)),
            ),
            "order" => Box::new(
                Text::new("12")
                    .set("class", class)
                    .set("x", mm(x))
                    .set("y", mm(y + step / 4)),
            ),
            _ => Box::new(
                Path::new().set("class", class).set(
                    "d",
                    Data::new()
                        .move_to((mm(x) as f32, mm(y) as f32))
                        .horizontal_line_by(mm(step * 3 / 2) as f32),
                ),
            ),
        };
        g = g.add(swatch).add(
            Text::new(label)
                .set("x", mm(x + step * 2))
                .set("y", mm(y + step / 4)),
        );
        // Label width at about 0.45 em per character at 0.7 em.
        x += step * 2 + (label.chars().count() as f64 * 0.45 * 0.7 * step as f64) as i64 + step;
    }
    g
}

/// The picture of `toolpath` cutting `problem` (module docs). `plan` gives the title's figures
/// and the tooltips' contours and parts; `overheat_points` are where the thermal simulation
/// counted overheats, in sheet coordinates (`job::SheetOutcome::overheat_points`).
pub fn plan_svg(
    problem: &Problem,
    toolpath: &Toolpath,
    plan: &CutPlanMsg,
    overheat_points: &[Point],
) -> String {
    let [a, b] = problem.sheet;
    let sheet = [problem.to_machine([0.0, 0.0]), problem.to_machine([a, b])];
    let tool_points = toolpath
        .segments
        .iter()
        .flat_map(|s| s.points.iter().map(|p| [p.x, p.y]));
    let part_points = problem
        .contours
        .iter()
        .flat_map(|c| c.points.iter().map(|&p| problem.to_machine(p)));
    let [lo, hi] = extent(
        sheet
            .into_iter()
            .chain([[0.0, 0.0]])
            .chain(tool_points)
            .chain(part_points),
    )
    .unwrap_or([[0.0, 0.0], [1.0, 1.0]]);
    let scale = Scale::new(problem, [hi[0] - lo[0], hi[1] - lo[1]]);
    let (t, u) = (scale.title, scale.detail);
    // A band above the drawing holds the title and the legend.
    let pad = t;
    let top = hi[1] + pad + 3.2 * t;
    let view = [
        len(lo[0] - pad),
        len(-top),
        len(hi[0] - lo[0] + 2.0 * pad),
        len(top - lo[1] + pad),
    ];

    let sheet_corner = cents([sheet[0][0], sheet[1][1]]);
    let sheet_rect = Rectangle::new()
        .set("class", "sheet")
        .set("x", mm(sheet_corner[0]))
        .set("y", mm(sheet_corner[1]))
        .set("width", len(a))
        .set("height", len(b));

    // One path per part: its outer contour and holes (even-odd: the holes stay white).
    let mut parts: BTreeMap<usize, Vec<Vec<Point>>> = BTreeMap::new();
    for c in &problem.contours {
        parts
            .entry(c.part)
            .or_default()
            .push(c.points.iter().map(|&p| problem.to_machine(p)).collect());
    }
    let parts = parts.into_values().fold(group("parts"), |g, rings| {
        g.add(
            Path::new()
                .set("class", "part")
                .set("d", path_data(rings, true)),
        )
    });

    let kind_path = |id: &str, class: &str, kind: u8| {
        let data = path_data(runs_of(toolpath, kind), false);
        if data.is_empty() {
            group(id)
        } else {
            group(id).add(Path::new().set("class", class).set("d", data))
        }
    };
    let rapids = kind_path("rapids", "rapid", ToolpathSegment::KIND_TRAVEL);
    let cuts = kind_path("cuts", "cut", ToolpathSegment::KIND_CUT);
    let leads = kind_path("leads", "lead", ToolpathSegment::KIND_LEAD);

    let overheats = overheat_points
        .iter()
        .map(|&p| cents(problem.to_machine(p)))
        .fold(group("overheats"), |g, c| {
            g.add(
                Circle::new()
                    .set("class", "overheat")
                    .set("cx", mm(c[0]))
                    .set("cy", mm(c[1]))
                    .set("r", len(u * 0.9)),
            )
        });

    // Numbers at most `1.6 u` high, smaller where the contour is too small to hold them.
    let largest = len(u * 1.6);
    let (mut pierces, mut order) = (group("pierces"), group("order").set("font-size", largest));
    for (k, p) in pierce_points(toolpath).into_iter().enumerate() {
        let c = cents(p);
        let label = (k + 1).to_string();
        let room = plan
            .order
            .get(k)
            .and_then(|&i| problem.contours.get(i as usize))
            .and_then(|contour| extent(contour.points.iter().copied()))
            .map_or(f64::INFINITY, |[lo, hi]| (hi[0] - lo[0]).min(hi[1] - lo[1]));
        let size = len((room * 2.0 / label.len() as f64).clamp(largest / 4.0, largest));
        let offset = (size * 25.0).round() as i64;
        let what = match (plan.order.get(k), plan.parts.get(k)) {
            (Some(contour), Some(part)) => format!("cut {}: contour {contour}, part {part}", k + 1),
            _ => format!("cut {}", k + 1),
        };
        pierces = pierces.add(
            Circle::new()
                .set("class", "pierce")
                .set("cx", mm(c[0]))
                .set("cy", mm(c[1]))
                .set("r", len(u * 0.2))
                .add(Title::new(what)),
        );
        let mut text = Text::new(label)
            .set("class", "order")
            .set("x", mm(c[0] + offset))
            .set("y", mm(c[1] - offset));
        if size < largest {
            text = text.set("font-size", size);
        }
        order = order.add(text);
    }

    let axis = (2.0 * t * 100.0).round() as i64;
    let axes = group("axes")
        .add(
            Path::new().set("class", "axes").set(
                "d",
                Data::new()
                    .move_to((mm(axis) as f32, 0.0))
                    .horizontal_line_by(-mm(axis) as f32)
                    .vertical_line_by(-mm(axis) as f32),
            ),
        )
        .add(Text::new("X").set("x", mm(axis)).set("y", len(0.7 * t)))
        .add(Text::new("Y").set("x", len(0.2 * t)).set("y", -mm(axis)))
        .add(
            Text::new("0,0")
                .set("x", len(0.2 * t))
                .set("y", len(0.7 * t)),
        );

    let heading = group("title").add(
        Text::new(title(plan))
            .set("x", len(lo[0]))
            .set("y", len(-(hi[1] + pad + 2.0 * t))),
    );
    let legend = legend([lo[0], hi[1] + pad + 0.8 * t], scale);

    Document::new()
        .set(
            "viewBox",
            format!("{} {} {} {}", view[0], view[1], view[2], view[3]),
        )
        .add(Title::new(title(plan)))
        .add(Style::new(scale.css()))
        .add(group("sheet").add(sheet_rect))
        .add(parts)
        .add(rapids)
        .add(cuts)
        .add(leads)
        .add(overheats)
        .add(pierces)
        .add(order)
        .add(axes)
        .add(heading)
        .add(legend)
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cost::{CostParams, Evaluator};
    use crate::generator::{generate_perforated, PerforatedConfig};
    use crate::layout::{Layout, PierceOptions};
    use crate::policy::{construct, Policy};
    use crate::precedence::PrecedenceMode;
    use crate::thermal::ThermalParams;
    use crate::toolpath::{to_cut_plan_msg, to_toolpath, ToolpathOptions};

    fn example() -> (Problem, Toolpath, CutPlanMsg) {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../tests/data/sheet/example.json"
        );
        let problem = Layout::from_json_file(path)
            .unwrap()
            .to_problem(PrecedenceMode::Strict, &PierceOptions::default())
            .unwrap();
        let eval =
            Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
        let plan = construct(&eval, Policy::Nearest, 0).unwrap();
        let tp = to_toolpath(&problem, &plan, "example", &ToolpathOptions::default());
        let msg = to_cut_plan_msg(&problem, &plan, "example", "nearest", false, 20.0);
        (problem, tp, msg)
    }

    #[test]
    fn one_pierce_per_contour_at_the_start_of_its_run() {
        let (problem, tp, msg) = example();
        let pierces = pierce_points(&tp);
        assert_eq!(pierces.len(), problem.contours.len());
        for (p, q) in pierces.iter().zip(&msg.pierce_points) {
            assert_eq!(*p, [q.x, q.y]);
        }
    }

    #[test]
    fn the_picture_has_a_marker_and_a_number_per_cut_and_the_figures_in_its_title() {
        let (problem, tp, msg) = example();
        let text = plan_svg(&problem, &tp, &msg, &[[40.0, 60.0]]);
        assert!(
            text.starts_with("<svg") && text.ends_with("</svg>"),
            "{text}"
        );
        let n = problem.contours.len();
        assert_eq!(n, 4);
        // One marker per cut, and the legend's.
        assert_eq!(text.matches("class=\"pierce\"").count(), n + 1);
        assert_eq!(text.matches("class=\"order\"").count(), n + 1);
        assert_eq!(text.matches("class=\"overheat\"").count(), 1 + 1);
        let compact = text.replace('\n', "");
        for k in 1..=n {
            assert!(compact.contains(&format!(">{k}</text>")), "label {k}");
        }
        assert!(text.contains(&title(&msg)));
        assert!(text.contains("4 contours, idle "), "{}", title(&msg));
        // No lead segments: no lead path.
        assert!(text.contains("<g id=\"leads\"/>"), "{text}");
        // The overheat at sheet (40, 60) is drawn at machine (40, -60) in the SVG's axes.
        assert!(text.contains("cx=\"40\" cy=\"-60\""), "{text}");
    }

    /// The issue's dense case: 5000 contours of perforated panels on 4000 × 2000 mm.
    #[test]
    fn a_5000_contour_plan_is_a_file_of_a_few_mb() {
        let layout = generate_perforated(&PerforatedConfig::default());
        let problem = layout
            .to_problem(PrecedenceMode::Strict, &PierceOptions::default())
            .unwrap();
        let n = problem.contours.len();
        assert!(n >= 5000, "{n}");
        let eval = Evaluator::new(
            &problem,
            ThermalParams::default(),
            CostParams {
                thermal: false,
                ..Default::default()
            },
        )
        .unwrap();
        let plan = construct(&eval, Policy::Nearest, 0).unwrap();
        let tp = to_toolpath(&problem, &plan, "dense", &ToolpathOptions::default());
        let msg = to_cut_plan_msg(&problem, &plan, "dense", "nearest", false, 20.0);
        let t = std::time::Instant::now();
        let text = plan_svg(&problem, &tp, &msg, &[]);
        eprintln!(
            "{n} contours: {} bytes in {:.3} s",
            text.len(),
            t.elapsed().as_secs_f64()
        );
        assert!(text.len() < 4_000_000, "{} bytes", text.len());
        assert_eq!(text.matches("class=\"pierce\"").count(), n + 1);
    }

    #[test]
    fn coordinates_are_rounded_to_hundredths_and_relative_after_one_move() {
        let d: svg::node::Value =
            path_data([vec![[1.004, 2.0], [1.006, 2.0], [3.0, -1.234]]], true).into();
        assert_eq!(d.to_string(), "M1,-2 l0.01,0,1.99,3.23 z");
    }
}
