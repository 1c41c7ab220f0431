//! `exposure.svg`: the picture of a hot-wire plan (issue 21, item 4), so an operator sees what
//! the swarm gained without opening Rerun. One column per section (the root; the tip beside it
//! on a tapered panel), three views each, over the exposure model's panels (exposure i belongs
//! to panel `surface[i]` → `surface[i + 1]`, seed 000 eq. 1–5):
//!
//! - **Outline** (the section's frame, mm, equal aspect, y up): the foil, the fixed-offset
//!   baseline, the optimised path and the lead-in and lead-out. At a 200 mm chord the wire runs
//!   about 0.5 mm off the foil, so the paths would hide the foil's outline: a path point p at
//!   distance d from its nearest foil point n is drawn at n + (p − n)·m(d)/d, with m(d) = k·d
//!   up to d₀ = 3 × the baseline offset and k·d₀ + (d − d₀) beyond (continuous, so the leads
//!   keep their shape and stay joined to the cut). k ∈ {1, 2, 5} × 10ⁿ puts the baseline about
//!   4 % of the chord off the foil; the view's caption states it.
//! - **Clearance** per panel: the distance (mm) from the panel's midpoint to each path, baseline
//!   and optimised, and the clearance margin the swarm keeps (T ∩ G = ∅ with a margin,
//!   [`Objective::min_clearance_mm`](crate::pso::Objective::min_clearance_mm)) when given.
//! - **Exposure** per panel, baseline and optimised, against the CSE line (dimensionless: the
//!   model's normalised exposure, seed 000 eq. 5).
//!
//! Both profiles share their x axis: the panel midpoint's arc position along the surface from
//! the trailing edge (Selig order: over the upper surface to the leading edge, which is
//! marked, and back along the lower surface), as a fraction of the perimeter.
//!
//! Drawn with the `svg` crate (as the sequencer's `plan.svg` and the slicer's `slice.svg`),
//! axes and ticks by hand. `plotters` 0.3.7 was read first: without a font feature it lays text
//! out with a crude size estimate and its SVG backend writes `<text>` itself, so fonts are no
//! obstacle; but that backend writes a flat list of elements on an integer pixel grid with no
//! way to group or name them, and the checks here (and a user's scripts) find each series by
//! its id.
//!
//! Ids, prefixed by the section (`root-`, `tip-`): `foil`, `baseline-path`, `optimised-path`,
//! `lead-in`, `lead-out`, `clearance-baseline`, `clearance-optimised`, `clearance-margin`,
//! `exposure-baseline`, `exposure-optimised`, `cse`, `le`; each series also has its unprefixed
//! name as its `class`. Each view's group (`root-outline`, `root-clearance`, `root-exposure`)
//! carries its plot rectangle (`data-frame`: left top width height, px) and data ranges
//! (`data-x-range`, `data-y-range`), so a check can read the values back from the pixels.
//! Pure: the picture is returned as text.

use cell_geometry::{closest_point_on_segment, cumulative_lengths, point_segment_distance, Norm};
use nalgebra::Point2;
use svg::node::element::{Group, Line, Polygon, Polyline, Rectangle, Text, Title};
use svg::Document;

use super::{HotwirePlan, SectionPlan};

/// Width of one section's column (px).
const COLUMN_W: f64 = 900.0;
/// Room left of each plot for the y tick labels (px).
const LEFT: f64 = 72.0;
/// Room right of each plot (px).
const RIGHT: f64 = 24.0;
/// The title's two lines (px).
const TITLE_H: f64 = 64.0;
/// The tallest the outline view may be (px); its width is the column's.
const OUTLINE_MAX_H: f64 = 300.0;
/// Height of the clearance and exposure plots (px).
const PROFILE_H: f64 = 200.0;
/// Between views: the x tick labels and the next view's caption (px).
const GAP: f64 = 68.0;
/// The legend under the columns (px).
const LEGEND_H: f64 = 40.0;
/// Font size of labels (px).
const FONT: f64 = 13.0;

const FOIL_FILL: &str = "#e4e4e4";
const FOIL_STROKE: &str = "#555555";
const BASELINE: &str = "#8c8c8c";
const OPTIMISED: &str = "#1f6fd1";
const LEADS: &str = "#e07b00";
const TARGET: &str = "#c62828";

/// The baseline's offset is drawn at about this fraction of the chord off the foil.
const MAGNIFIED_OFFSET_OF_CHORD: f64 = 0.04;

/// Rounds to 0.01 px for short files.
fn r(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// What the profile views plot for one section, per exposure panel (the planner node logs the
/// same to Rerun).
#[derive(Debug, Clone, PartialEq)]
pub struct PanelProfiles {
    /// Arc position of each panel's midpoint along the surface from the trailing edge, as a
    /// fraction of the perimeter (Selig order: upper surface first).
    pub position: Vec<f64>,
    /// Arc position of the leading edge (the surface point of least x), same measure.
    pub le_position: f64,
    /// Distance from each panel's midpoint to the fixed-offset baseline (mm).
    pub baseline_clearance_mm: Vec<f64>,
    /// Distance from each panel's midpoint to the optimised path (mm).
    pub optimised_clearance_mm: Vec<f64>,
}

impl PanelProfiles {
    /// The profiles of `section`, one entry per panel that has a baseline and an optimised
    /// exposure.
    pub fn of(section: &SectionPlan) -> Self {
        let panels = panel_count(section);
        let surface = &section.surface[..(panels + 1).min(section.surface.len())];
        let arc = cumulative_lengths(surface, Norm::Sqrt);
        let perimeter = arc.last().copied().unwrap_or(0.0);
        let fraction = |s: f64| if perimeter > 0.0 { s / perimeter } else { 0.0 };
        let position = (0..panels)
            .map(|i| fraction(0.5 * (arc[i] + arc[i + 1])))
            .collect();
        let le = surface
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.x.total_cmp(&b.1.x))
            .map_or(0, |(i, _)| i);
        let mids: Vec<Point2<f64>> = surface
            .windows(2)
            .map(|w| nalgebra::center(&w[0], &w[1]))
            .collect();
        let clearance = |path: &[Point2<f64>]| -> Vec<f64> {
            mids.iter().map(|m| distance_to_closed(*m, path)).collect()
        };
        Self {
            position,
            le_position: arc.get(le).map_or(0.0, |s| fraction(*s)),
            baseline_clearance_mm: clearance(&section.baseline),
            optimised_clearance_mm: clearance(&section.optimised),
        }
    }
}

/// Panels with a surface panel, a baseline and an optimised exposure.
fn panel_count(section: &SectionPlan) -> usize {
    section
        .baseline_exposure
        .len()
        .min(section.optimised_exposure.len())
        .min(section.surface.len().saturating_sub(1))
}

/// Distance from `p` to the closed polyline `path` (the closing edge included).
fn distance_to_closed(p: Point2<f64>, path: &[Point2<f64>]) -> f64 {
    match path {
        [] => f64::INFINITY,
        [only] => (p - only).norm(),
        _ => path
            .iter()
            .zip(path.iter().cycle().skip(1))
            .map(|(a, b)| point_segment_distance(p, a, b, Norm::Sqrt))
            .fold(f64::INFINITY, f64::min),
    }
}

/// The picture of `plan` (see the module docs) as SVG text; `clearance_mm` draws the clearance
/// margin in the clearance views.
pub fn exposure_svg(plan: &HotwirePlan, clearance_mm: Option<f64>) -> String {
    let mut sections = vec![("root", &plan.root)];
    sections.extend(plan.tip.as_ref().map(|t| ("tip", t)));
    sections_svg(&sections, clearance_mm)
}

/// The picture of `sections` side by side, (id prefix, section).
fn sections_svg(sections: &[(&str, &SectionPlan)], clearance_mm: Option<f64>) -> String {
    let tapered = sections.len() > 1;
    let outlines: Vec<Outline> = sections
        .iter()
        .enumerate()
        .map(|(k, (_, s))| Outline::of(s, k as f64 * COLUMN_W))
        .collect();
    // The profile views line up across the columns, below the tallest outline.
    let profiles_top = outlines
        .iter()
        .map(|o| o.frame.top + o.frame.height + GAP)
        .fold(0.0, f64::max);
    let mut columns = Vec::new();
    let mut height: f64 = 0.0;
    for ((role, section), outline) in sections.iter().zip(outlines) {
        let (column, bottom) =
            section_column(role, section, tapered, outline, profiles_top, clearance_mm);
        columns.push(column);
        height = height.max(bottom);
    }
    let width = COLUMN_W * sections.len().max(1) as f64;
    let legend = legend(height + 8.0);
    let height = height + 8.0 + LEGEND_H;
    let title = sections
        .iter()
        .map(|(role, s)| title_lines(role, s, tapered).join(": "))
        .collect::<Vec<_>>()
        .join("; ");
    let mut doc = Document::new()
        .set("viewBox", format!("0 0 {width} {}", r(height)))
        .set("width", width)
        .set("height", r(height))
        .set("font-family", "sans-serif")
        .set("font-size", FONT)
        .add(Title::new(title))
        .add(
            Rectangle::new()
                .set("width", "100%")
                .set("height", "100%")
                .set("fill", "white"),
        );
    for c in columns {
        doc = doc.add(c);
    }
    doc.add(legend).to_string()
}

/// The title's two lines: what was cut, and the uniformity before → after.
fn title_lines(role: &str, s: &SectionPlan, tapered: bool) -> [String; 2] {
    let (b, o) = (&s.baseline_stats, &s.optimised_stats);
    let gain = if b.cv > 0.0 {
        format!(" ({:+.0} %)", 100.0 * (o.cv - b.cv) / b.cv)
    } else {
        String::new()
    };
    let which = if tapered {
        format!(" ({role})")
    } else {
        String::new()
    };
    [
        format!(
            "{}{which}, chord {} mm, offset {:.3} mm, CSE {:.4}",
            s.airfoil, s.chord_mm, s.offset_mm, s.cse
        ),
        format!(
            "CV {:.3} → {:.3}{gain} · RMS {:.3} → {:.3} · max |E − CSE| {:.3} → {:.3}",
            b.cv, o.cv, b.rms, o.rms, b.max_abs, o.max_abs
        ),
    ]
}

/// A section's outline view: its frame, and the paths as drawn (id, points, colour, width).
struct Outline {
    frame: Frame,
    magnification: f64,
    linear_up_to_mm: f64,
    paths: [(&'static str, Vec<Point2<f64>>, &'static str, f64); 4],
}

impl Outline {
    /// The outline of `s` in the column at `x0`, equal aspect, the paths' distance from the
    /// foil magnified ([`magnify`]).
    fn of(s: &SectionPlan, x0: f64) -> Self {
        let k = magnification(s.chord_mm, s.offset_mm);
        let d0 = 3.0 * s.offset_mm.max(0.0);
        let shown = |path: &[Point2<f64>]| -> Vec<Point2<f64>> {
            path.iter().map(|p| magnify(*p, &s.foil, k, d0)).collect()
        };
        let paths = [
            ("baseline-path", shown(&s.baseline), BASELINE, 1.2),
            ("optimised-path", shown(&s.optimised), OPTIMISED, 1.4),
            ("lead-in", shown(&s.lead_in), LEADS, 1.4),
            ("lead-out", shown(&s.lead_out), LEADS, 1.4),
        ];
        let (lo, hi) = paths.iter().flat_map(|p| p.1.iter()).chain(&s.foil).fold(
            ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]),
            |(lo, hi), p| {
                (
                    [lo[0].min(p.x), lo[1].min(p.y)],
                    [hi[0].max(p.x), hi[1].max(p.y)],
                )
            },
        );
        let pad = 0.02 * (hi[0] - lo[0]).max(1e-9);
        let (xr, yr) = ([lo[0] - pad, hi[0] + pad], [lo[1] - pad, hi[1] + pad]);
        let (xr, yr) = if xr[0].is_finite() && xr[1] > xr[0] && yr[1] > yr[0] {
            (xr, yr)
        } else {
            ([0.0, 1.0], [0.0, 1.0])
        };
        let plot_w = COLUMN_W - LEFT - RIGHT;
        let scale = (plot_w / (xr[1] - xr[0])).min(OUTLINE_MAX_H / (yr[1] - yr[0]));
        Self {
            frame: Frame {
                left: x0 + LEFT,
                top: TITLE_H + 22.0,
                width: (xr[1] - xr[0]) * scale,
                height: (yr[1] - yr[0]) * scale,
                x: (xr[0], xr[1]),
                y: (yr[0], yr[1]),
            },
            magnification: k,
            linear_up_to_mm: d0,
            paths,
        }
    }
}

/// One section's column: title, `outline`, and the clearance and exposure views from
/// `profiles_top` down; and its bottom (px).
fn section_column(
    role: &str,
    s: &SectionPlan,
    tapered: bool,
    outline: Outline,
    profiles_top: f64,
    clearance_mm: Option<f64>,
) -> (Group, f64) {
    let x0 = outline.frame.left - LEFT;
    let id = |name: &str| format!("{role}-{name}");
    let [line1, line2] = title_lines(role, s, tapered);
    let title = Group::new()
        .set("id", id("title"))
        .add(
            Text::new(line1)
                .set("x", x0 + LEFT)
                .set("y", 24)
                .set("font-size", FONT + 3.0)
                .set("font-weight", "bold"),
        )
        .add(Text::new(line2).set("x", x0 + LEFT).set("y", 46));
    let plot_w = COLUMN_W - LEFT - RIGHT;
    let profiles = PanelProfiles::of(s);

    // Outline: equal aspect, the normal distance magnified.
    let Outline {
        frame: outline,
        magnification: k,
        linear_up_to_mm: d0,
        paths,
    } = outline;
    let caption = if k > 1.0 {
        format!(
            "outline (mm, equal aspect): distance from the foil ×{k} up to {:.2} mm",
            d0
        )
    } else {
        "outline (mm, equal aspect)".to_owned()
    };
    let mut outline_group = outline
        .group(id("outline"))
        .add(caption_text(&outline, caption))
        .add(
            Polygon::new()
                .set("id", id("foil"))
                .set("class", "foil")
                .set("points", outline.points(s.foil.iter().map(|p| (p.x, p.y))))
                .set("fill", FOIL_FILL)
                .set("stroke", FOIL_STROKE)
                .set("stroke-width", 1),
        );
    for (name, pts, colour, width) in paths {
        outline_group = outline_group.add(
            outline
                .polyline(pts.iter().map(|p| (p.x, p.y)))
                .set("id", id(name))
                .set("class", name)
                .set("stroke", colour)
                .set("stroke-width", width),
        );
    }
    outline_group = outline_group.add(scale_bar(&outline, s.chord_mm));

    // Clearance per panel, below the tallest outline.
    let clearance_top = profiles_top;
    let max_gap = profiles
        .baseline_clearance_mm
        .iter()
        .chain(&profiles.optimised_clearance_mm)
        .copied()
        .chain(clearance_mm)
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let (c_lo, c_hi, c_step) = nice_range(0.0, max_gap.max(1e-3));
    let clearance = Frame {
        left: x0 + LEFT,
        top: clearance_top,
        width: plot_w,
        height: PROFILE_H,
        x: (0.0, 1.0),
        y: (c_lo, c_hi),
    };
    let mut clearance_group = clearance
        .group(id("clearance"))
        .add(caption_text(
            &clearance,
            "wire distance from the foil per panel (mm)".to_owned(),
        ))
        .add(axes(&clearance, c_step, profiles.le_position));
    if let Some(m) = clearance_mm.filter(|m| m.is_finite()) {
        clearance_group = clearance_group.add(
            clearance
                .hline(m)
                .set("id", id("clearance-margin"))
                .set("class", "clearance-margin")
                .set("stroke", TARGET)
                .set("stroke-width", 1)
                .set("stroke-dasharray", "6 4"),
        );
    }
    for (name, values, colour) in [
        (
            "clearance-baseline",
            &profiles.baseline_clearance_mm,
            BASELINE,
        ),
        (
            "clearance-optimised",
            &profiles.optimised_clearance_mm,
            OPTIMISED,
        ),
    ] {
        clearance_group = clearance_group.add(
            clearance
                .polyline(
                    profiles
                        .position
                        .iter()
                        .copied()
                        .zip(values.iter().copied()),
                )
                .set("id", id(name))
                .set("class", name)
                .set("stroke", colour)
                .set("stroke-width", 1.4),
        );
    }

    // Exposure per panel against the CSE.
    let panels = profiles.position.len();
    let exposure_top = clearance.top + clearance.height + GAP;
    let (e_min, e_max) = s.baseline_exposure[..panels]
        .iter()
        .chain(&s.optimised_exposure[..panels])
        .chain(std::iter::once(&s.cse))
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        });
    let (e_min, e_max) = if e_min <= e_max {
        (e_min.min(0.0), e_max)
    } else {
        (0.0, 1.0)
    };
    let (e_lo, e_hi, e_step) = nice_range(e_min, e_max);
    let exposure = Frame {
        left: x0 + LEFT,
        top: exposure_top,
        width: plot_w,
        height: PROFILE_H,
        x: (0.0, 1.0),
        y: (e_lo, e_hi),
    };
    let mut exposure_group = exposure
        .group(id("exposure"))
        .add(caption_text(
            &exposure,
            "exposure per panel (dimensionless, seed 000 eq. 5) against the CSE".to_owned(),
        ))
        .add(axes(&exposure, e_step, profiles.le_position))
        .add(
            exposure
                .hline(s.cse)
                .set("id", id("cse"))
                .set("class", "cse")
                .set("stroke", TARGET)
                .set("stroke-width", 1.2)
                .set("stroke-dasharray", "6 4"),
        );
    for (name, values, colour) in [
        ("exposure-baseline", &s.baseline_exposure, BASELINE),
        ("exposure-optimised", &s.optimised_exposure, OPTIMISED),
    ] {
        exposure_group = exposure_group.add(
            exposure
                .polyline(
                    profiles
                        .position
                        .iter()
                        .copied()
                        .zip(values[..panels].iter().copied()),
                )
                .set("id", id(name))
                .set("class", name)
                .set("stroke", colour)
                .set("stroke-width", 1.4),
        );
    }
    // The LE's id sits on the exposure view's marker (the clearance view has one too).
    exposure_group = exposure_group.add(
        exposure
            .vline(profiles.le_position)
            .set("id", id("le"))
            .set("class", "le")
            .set("stroke", "#444444")
            .set("stroke-width", 1)
            .set("stroke-dasharray", "2 3"),
    );

    let bottom = exposure.top + exposure.height + 40.0;
    let column = Group::new()
        .set("id", role.to_owned())
        .add(title)
        .add(outline_group)
        .add(clearance_group)
        .add(exposure_group);
    (column, bottom)
}

/// k ∈ {1, 2, 5} × 10ⁿ, at most what puts the baseline offset at
/// [`MAGNIFIED_OFFSET_OF_CHORD`] of the chord off the foil, and at least 1.
fn magnification(chord_mm: f64, offset_mm: f64) -> f64 {
    let raw = MAGNIFIED_OFFSET_OF_CHORD * chord_mm / offset_mm;
    if !(raw.is_finite() && raw > 1.0) {
        return 1.0;
    }
    let decade = 10f64.powf(raw.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|k| *k <= raw)
        .unwrap_or(1.0)
}

/// `p` drawn with its distance d from the foil magnified (module docs): k·d up to `d0`,
/// k·d0 + (d − d0) beyond, along the direction from its nearest foil point.
fn magnify(p: Point2<f64>, foil: &[Point2<f64>], k: f64, d0: f64) -> Point2<f64> {
    if k <= 1.0 || foil.len() < 2 {
        return p;
    }
    let n = foil
        .iter()
        .zip(foil.iter().cycle().skip(1))
        .map(|(a, b)| closest_point_on_segment(p, a, b))
        .min_by(|a, b| (p - a).norm().total_cmp(&(p - b).norm()))
        .unwrap_or(p);
    let d = (p - n).norm();
    if d == 0.0 {
        return p;
    }
    let m = if d <= d0 { k * d } else { k * d0 + (d - d0) };
    n + (p - n) * (m / d)
}

/// A plot rectangle (px) and the data ranges it shows; y up.
struct Frame {
    left: f64,
    top: f64,
    width: f64,
    height: f64,
    x: (f64, f64),
    y: (f64, f64),
}

impl Frame {
    /// Data → px.
    fn px(&self, x: f64, y: f64) -> (f64, f64) {
        (
            r(self.left + (x - self.x.0) / (self.x.1 - self.x.0) * self.width),
            r(self.top + (self.y.1 - y) / (self.y.1 - self.y.0) * self.height),
        )
    }

    /// The view's group, with its rectangle and ranges for a reader.
    fn group(&self, id: String) -> Group {
        Group::new()
            .set("id", id)
            .set(
                "data-frame",
                format!(
                    "{} {} {} {}",
                    r(self.left),
                    r(self.top),
                    r(self.width),
                    r(self.height)
                ),
            )
            .set("data-x-range", format!("{} {}", self.x.0, self.x.1))
            .set("data-y-range", format!("{} {}", self.y.0, self.y.1))
    }

    /// A `points` attribute, non-finite values left out.
    fn points(&self, pts: impl Iterator<Item = (f64, f64)>) -> String {
        pts.filter(|(x, y)| x.is_finite() && y.is_finite())
            .map(|(x, y)| {
                let (u, v) = self.px(x, y);
                format!("{u},{v}")
            })
            .collect::<Vec<_>>()
            .join(" ")
    }

    /// An unfilled polyline through the data points.
    fn polyline(&self, pts: impl Iterator<Item = (f64, f64)>) -> Polyline {
        Polyline::new()
            .set("points", self.points(pts))
            .set("fill", "none")
            .set("stroke-linejoin", "round")
    }

    /// A horizontal line across the plot at data y.
    fn hline(&self, y: f64) -> Line {
        let ((x1, y1), (x2, _)) = (self.px(self.x.0, y), self.px(self.x.1, y));
        Line::new()
            .set("x1", x1)
            .set("y1", y1)
            .set("x2", x2)
            .set("y2", y1)
    }

    /// A vertical line across the plot at data x.
    fn vline(&self, x: f64) -> Line {
        let ((x1, y1), (_, y2)) = (self.px(x, self.y.1), self.px(x, self.y.0));
        Line::new()
            .set("x1", x1)
            .set("y1", y1)
            .set("x2", x1)
            .set("y2", y2)
    }
}

/// The view's caption, above its top-left corner.
fn caption_text(frame: &Frame, text: String) -> Text {
    Text::new(text)
        .set("x", r(frame.left))
        .set("y", r(frame.top - 8.0))
        .set("fill", "#333333")
}

/// `lo`..`hi` widened to multiples of a 1-2-5 step giving about five intervals; (lo, hi, step).
fn nice_range(lo: f64, hi: f64) -> (f64, f64, f64) {
    let span = if hi > lo { hi - lo } else { lo.abs().max(1.0) };
    let raw = span / 5.0;
    let decade = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * decade)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * decade);
    let (lo, hi) = ((lo / step).floor() * step, (hi / step).ceil() * step);
    (lo, if hi > lo { hi } else { lo + step }, step)
}

/// Decimals that show `step` exactly.
fn decimals(step: f64) -> usize {
    (-step.log10().floor()).max(0.0) as usize
}

/// A profile view's frame, grid, ticks and labels: y every `y_step`, x at quarters of the
/// perimeter from the trailing edge, and the leading edge at `le` marked.
fn axes(frame: &Frame, y_step: f64, le: f64) -> Group {
    let mut g = Group::new().set("class", "axes").add(
        Rectangle::new()
            .set("x", r(frame.left))
            .set("y", r(frame.top))
            .set("width", r(frame.width))
            .set("height", r(frame.height))
            .set("fill", "none")
            .set("stroke", "#999999"),
    );
    let places = decimals(y_step);
    let ticks = ((frame.y.1 - frame.y.0) / y_step).round() as usize;
    for i in 0..=ticks {
        let y = frame.y.0 + i as f64 * y_step;
        let (x, v) = frame.px(frame.x.0, y);
        g = g
            .add(
                frame
                    .hline(y)
                    .set("stroke", "#eeeeee")
                    .set("stroke-width", 1),
            )
            .add(
                Text::new(format!("{y:.places$}"))
                    .set("x", r(x - 6.0))
                    .set("y", r(v + 4.0))
                    .set("text-anchor", "end"),
            );
    }
    let bottom = frame.top + frame.height;
    for q in 0..=4 {
        let x = q as f64 / 4.0;
        let (u, _) = frame.px(x, frame.y.0);
        let label = match q {
            0 | 4 => "TE".to_owned(),
            _ => format!("{x}"),
        };
        g = g
            .add(
                Line::new()
                    .set("x1", u)
                    .set("y1", r(bottom))
                    .set("x2", u)
                    .set("y2", r(bottom + 5.0))
                    .set("stroke", "#999999"),
            )
            .add(
                Text::new(label)
                    .set("x", u)
                    .set("y", r(bottom + 18.0))
                    .set("text-anchor", "middle"),
            );
    }
    let (u, _) = frame.px(le, frame.y.0);
    g.add(
        frame
            .vline(le)
            .set("stroke", "#bbbbbb")
            .set("stroke-dasharray", "2 3"),
    )
    .add(
        Text::new("LE")
            .set("x", u)
            .set("y", r(frame.top + 14.0))
            .set("text-anchor", "middle")
            .set("font-weight", "bold"),
    )
    .add(
        Text::new("arc position from the TE (fraction of the perimeter): upper surface, LE, lower surface")
            .set("x", r(frame.left + 0.5 * frame.width))
            .set("y", r(bottom + 34.0))
            .set("text-anchor", "middle")
            .set("fill", "#555555"),
    )
}

/// A scale bar of a round length near a tenth of the chord, under the outline's left corner.
fn scale_bar(frame: &Frame, chord_mm: f64) -> Group {
    let (_, _, step) = nice_range(0.0, (chord_mm * 0.5).max(1e-3));
    let (x0, y) = (frame.left, frame.top + frame.height + 12.0);
    let len = step * frame.width / (frame.x.1 - frame.x.0);
    Group::new()
        .set("class", "scale-bar")
        .add(
            Line::new()
                .set("x1", r(x0))
                .set("y1", r(y))
                .set("x2", r(x0 + len))
                .set("y2", r(y))
                .set("stroke", "#333333")
                .set("stroke-width", 2),
        )
        .add(
            Text::new(format!("{step} mm (along the chord)"))
                .set("x", r(x0 + len + 6.0))
                .set("y", r(y + 4.0)),
        )
}

/// What each colour means.
fn legend(top: f64) -> Group {
    let items = [
        ("foil", FOIL_STROKE, ""),
        ("fixed-offset baseline", BASELINE, ""),
        ("optimised path", OPTIMISED, ""),
        ("lead-in / lead-out", LEADS, ""),
        ("CSE target, clearance margin", TARGET, "6 4"),
    ];
    let mut g = Group::new().set("id", "legend");
    let mut x = LEFT;
    for (label, colour, dash) in items {
        let y = top + 16.0;
        g = g
            .add(
                Line::new()
                    .set("x1", r(x))
                    .set("y1", r(y))
                    .set("x2", r(x + 28.0))
                    .set("y2", r(y))
                    .set("stroke", colour)
                    .set("stroke-width", 2)
                    .set("stroke-dasharray", dash),
            )
            .add(Text::new(label).set("x", r(x + 34.0)).set("y", r(y + 4.0)));
        x += 40.0 + 7.5 * label.len() as f64;
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::job::ExposureStats;

    /// An ellipse "foil" of chord 200 mm in Selig order (TE at +x, upper surface first), with
    /// `n` panels, a baseline 0.5 mm off it and an optimised path 0.3–0.7 mm off it.
    fn section(n: usize) -> SectionPlan {
        let ring = |off: f64, wobble: f64| -> Vec<Point2<f64>> {
            (0..=n)
                .map(|i| {
                    let t = std::f64::consts::TAU * i as f64 / n as f64;
                    let (a, b) = (100.0, 12.0);
                    let p = Point2::new(100.0 + a * t.cos(), b * t.sin());
                    // Outward normal of the ellipse.
                    let nrm = nalgebra::Vector2::new(b * t.cos(), a * t.sin()).normalize();
                    p + nrm * (off + wobble * (3.0 * t).sin())
                })
                .collect()
        };
        let surface = ring(0.0, 0.0);
        let baseline_exposure: Vec<f64> = (0..n).map(|i| 2.0 + (i % 7) as f64 * 0.3).collect();
        let optimised_exposure: Vec<f64> = (0..n).map(|i| 2.8 + (i % 3) as f64 * 0.05).collect();
        let cse = 2.85;
        SectionPlan {
            airfoil: "ELLIPSE <12 %>".into(),
            chord_mm: 200.0,
            foil: surface[..n].to_vec(),
            baseline: ring(0.5, 0.0),
            optimised: ring(0.5, 0.2),
            offset_mm: 0.5,
            cse,
            baseline_stats: ExposureStats::of(&baseline_exposure, cse),
            optimised_stats: ExposureStats::of(&optimised_exposure, cse),
            baseline_exposure,
            optimised_exposure,
            surface,
            baseline_loss: 1.0,
            final_loss: 0.5,
            loss_history: vec![(0, 1.0), (10, 0.5)],
            feed_ratio: vec![1.0; n + 1],
            current_ratio: vec![1.0; n + 1],
            lead_in_mm: 10.0,
            lead_in: vec![Point2::new(215.0, 0.0), Point2::new(200.5, 0.0)],
            lead_out: vec![Point2::new(200.5, 0.0), Point2::new(215.0, 0.0)],
        }
    }

    /// One element of the picture: its name and attributes.
    struct Element {
        name: String,
        attributes: Vec<(String, String)>,
    }

    impl Element {
        fn get(&self, key: &str) -> Option<&str> {
            self.attributes
                .iter()
                .find(|(k, _)| k == key)
                .map(|(_, v)| v.as_str())
        }
        fn numbers(&self, key: &str) -> Vec<f64> {
            self.get(key)
                .unwrap_or_else(|| panic!("{} has no {key}", self.name))
                .split([' ', ','])
                .map(|v| v.parse().unwrap())
                .collect()
        }
    }

    /// Every element, in document order; any XML error fails the test (xml-rs shares no code
    /// with the writer).
    fn parse(svg: &str) -> Vec<Element> {
        xml::reader::EventReader::from_str(svg)
            .into_iter()
            .filter_map(|e| match e.expect("well-formed XML") {
                xml::reader::XmlEvent::StartElement {
                    name, attributes, ..
                } => Some(Element {
                    name: name.local_name,
                    attributes: attributes
                        .into_iter()
                        .map(|a| (a.name.local_name, a.value))
                        .collect(),
                }),
                _ => None,
            })
            .collect()
    }

    fn by_id<'a>(elements: &'a [Element], id: &str) -> &'a Element {
        elements
            .iter()
            .find(|e| e.get("id") == Some(id))
            .unwrap_or_else(|| panic!("no element {id}"))
    }

    /// (x, y) in data units of view `view` for a px point.
    fn to_data(elements: &[Element], view: &str, u: f64, v: f64) -> (f64, f64) {
        let g = by_id(elements, view);
        let (f, x, y) = (
            g.numbers("data-frame"),
            g.numbers("data-x-range"),
            g.numbers("data-y-range"),
        );
        (
            x[0] + (u - f[0]) / f[2] * (x[1] - x[0]),
            y[1] - (v - f[1]) / f[3] * (y[1] - y[0]),
        )
    }

    fn points(e: &Element) -> Vec<(f64, f64)> {
        e.numbers("points")
            .chunks(2)
            .map(|c| (c[0], c[1]))
            .collect()
    }

    #[test]
    fn series_have_one_point_per_panel_at_their_values() {
        let s = section(48);
        let svg = sections_svg(&[("root", &s)], Some(0.1));
        let el = parse(&svg);
        for (id, values) in [
            ("root-exposure-baseline", &s.baseline_exposure),
            ("root-exposure-optimised", &s.optimised_exposure),
        ] {
            let pts = points(by_id(&el, id));
            assert_eq!(pts.len(), 48, "{id}");
            for ((u, v), e) in pts.iter().zip(values) {
                let (_, y) = to_data(&el, "root-exposure", *u, *v);
                assert!((y - e).abs() < 0.01, "{id}: {y} vs {e}");
            }
            // Along the surface from the TE: x grows from near 0 to near 1.
            let xs: Vec<f64> = pts
                .iter()
                .map(|(u, v)| to_data(&el, "root-exposure", *u, *v).0)
                .collect();
            assert!(xs.windows(2).all(|w| w[1] > w[0]), "{xs:?}");
            assert!(xs[0] > 0.0 && xs[0] < 0.02 && xs[47] > 0.98 && xs[47] < 1.0);
        }
        // The CSE line lies across the whole plot at the CSE.
        let cse = by_id(&el, "root-cse");
        let (x1, y1) = to_data(
            &el,
            "root-exposure",
            cse.numbers("x1")[0],
            cse.numbers("y1")[0],
        );
        let (x2, y2) = to_data(
            &el,
            "root-exposure",
            cse.numbers("x2")[0],
            cse.numbers("y2")[0],
        );
        assert!((y1 - s.cse).abs() < 0.01 && (y2 - s.cse).abs() < 0.01);
        assert!(x1.abs() < 1e-3 && (x2 - 1.0).abs() < 1e-3);
        // The ellipse's LE is halfway round.
        let le = by_id(&el, "root-le");
        let (x, _) = to_data(
            &el,
            "root-exposure",
            le.numbers("x1")[0],
            le.numbers("y1")[0],
        );
        assert!((x - 0.5).abs() < 1e-3, "LE at {x}");
        // The clearance view: one point per panel, the margin at 0.1 mm.
        for id in ["root-clearance-baseline", "root-clearance-optimised"] {
            assert_eq!(points(by_id(&el, id)).len(), 48, "{id}");
        }
        let m = by_id(&el, "root-clearance-margin");
        let (_, y) = to_data(
            &el,
            "root-clearance",
            m.numbers("x1")[0],
            m.numbers("y1")[0],
        );
        assert!((y - 0.1).abs() < 1e-3, "margin at {y}");
        // The title carries the figures before → after, escaped.
        let title = svg.split("<title>").nth(1).unwrap();
        assert!(
            title.starts_with("ELLIPSE &lt;12 %&gt;, chord 200 mm"),
            "{title}"
        );
        let (b, o) = (s.baseline_stats, s.optimised_stats);
        assert!(
            title.contains(&format!("CV {:.3} → {:.3}", b.cv, o.cv)),
            "{title}"
        );
        assert!(title.contains(&format!(
            "max |E − CSE| {:.3} → {:.3}",
            b.max_abs, o.max_abs
        )));
    }

    #[test]
    fn clearance_profiles_measure_the_paths_distance_from_the_panels() {
        let s = section(64);
        let p = PanelProfiles::of(&s);
        assert_eq!(p.position.len(), 64);
        assert!((p.le_position - 0.5).abs() < 1e-9);
        // 0.5 mm up to the polygons' sagittas, largest at the sharp ends (TE, LE).
        assert!(
            p.baseline_clearance_mm
                .iter()
                .all(|d| (0.45..0.51).contains(d)),
            "{:?}",
            p.baseline_clearance_mm
        );
        let (lo, hi) = p
            .optimised_clearance_mm
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), d| (l.min(*d), h.max(*d)));
        assert!(lo < 0.4 && hi > 0.6, "{lo}..{hi}");
    }

    #[test]
    fn the_outline_magnifies_the_offset_and_keeps_the_foil_and_leads() {
        let s = section(48);
        let el = parse(&sections_svg(&[("root", &s)], None));
        // 4 % of 200 mm over 0.5 mm is 16: ×10.
        assert_eq!(magnification(200.0, 0.5), 10.0);
        assert_eq!(magnification(200.0, 10.0), 1.0);
        assert!(el
            .iter()
            .all(|e| e.get("id") != Some("root-clearance-margin")));
        let foil = points(by_id(&el, "root-foil"));
        assert_eq!(foil.len(), s.foil.len());
        let to_mm = |(u, v): (f64, f64)| to_data(&el, "root-outline", u, v);
        for (drawn, p) in foil.iter().zip(&s.foil) {
            let (x, y) = to_mm(*drawn);
            assert!((x - p.x).abs() < 0.05 && (y - p.y).abs() < 0.05);
        }
        // The baseline, 0.5 mm off the foil, is drawn 5 mm off it: at the TE side's tip,
        // (200.5, 0) shows at (205, 0).
        let baseline = points(by_id(&el, "root-baseline-path"));
        let (x, y) = to_mm(baseline[0]);
        assert!((x - 205.0).abs() < 0.1 && y.abs() < 0.1, "({x}, {y})");
        // The leads join the magnified path and keep their 14.5 mm length beyond d₀ = 1.5 mm.
        let lead = points(by_id(&el, "root-lead-in"));
        let (start, end) = (to_mm(lead[0]), to_mm(lead[1]));
        assert!((end.0 - 205.0).abs() < 0.1, "{end:?}");
        assert!((start.0 - (200.0 + 15.0 + 13.5)).abs() < 0.1, "{start:?}");
    }

    #[test]
    fn a_tapered_panel_draws_both_sections_with_distinct_ids() {
        let (root, mut tip) = (section(40), section(40));
        tip.chord_mm = 120.0;
        let svg = sections_svg(&[("root", &root), ("tip", &tip)], Some(0.1));
        let el = parse(&svg);
        let mut ids: Vec<&str> = el.iter().filter_map(|e| e.get("id")).collect();
        let n = ids.len();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), n, "ids are unique");
        for id in ["tip-foil", "tip-exposure-optimised", "tip-cse", "root-cse"] {
            by_id(&el, id);
        }
        assert!(svg.contains("(tip), chord 120 mm"));
        // Side by side: the tip's plots start a column to the right.
        let root_left = by_id(&el, "root-exposure").numbers("data-frame")[0];
        let tip_left = by_id(&el, "tip-exposure").numbers("data-frame")[0];
        assert_eq!(tip_left - root_left, COLUMN_W);
        // The tip's outline (×5 at 120 mm) is shorter than the root's (×10), yet the profile
        // views line up.
        let top = |id: &str| by_id(&el, id).numbers("data-frame")[1];
        let height = |id: &str| by_id(&el, id).numbers("data-frame")[3];
        assert!(height("tip-outline") < height("root-outline"));
        assert_eq!(top("tip-clearance"), top("root-clearance"));
        assert_eq!(top("tip-exposure"), top("root-exposure"));
    }

    #[test]
    fn nice_ranges_cover_the_data_in_round_steps() {
        assert_eq!(nice_range(0.0, 0.93), (0.0, 1.0, 0.2));
        assert_eq!(nice_range(1.49, 4.51), (1.0, 5.0, 1.0));
        let (lo, hi, step) = nice_range(2.0, 2.0);
        assert!(lo <= 2.0 && hi > 2.0 && step > 0.0);
        assert_eq!(decimals(0.2), 1);
        assert_eq!(decimals(5.0), 0);
    }
}
