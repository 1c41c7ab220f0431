//! `<spec>-planform.svg`: the designed wing as a picture beside `report.json` (seed 002
//! Figure 7, "Planform view of curvilinear spar structure"). Two panels, one span axis:
//!
//! - **Planform** seen from above, span across and chord down: the leading and trailing edges
//!   from the design's chord c(y), the straight hinge line at `hinge_x_over_c` (dashed, as
//!   the sections are built: every section's hinge on one line), the main spar at x_τmax
//!   (black, dashed), every other spar of X_sp ([`crate::structure::SparLayout`]) and the
//!   section breaks (vertical lines, each section labelled with its index in the design's
//!   section list, as `cell wing --sections` takes it, and its side and index).
//! - **Distributions** below: chord c(y) \[mm\], geometric twist α(y) = LLT α + α_L0 \[deg\] and
//!   the lift per span ℓ(y) \[N/m\] at the design load n·W of the condition that sizes the
//!   spars, each on its own axes against the same y.
//!
//! **Scale** (what a check can rely on): the SVG user unit is 1 mm of wing; SVG x = y \[mm\]
//! (0 at the wing's centre, right wing to the right), and in the planform SVG y = (x/c −
//! x_h)·c \[mm\], the chordwise distance behind the hinge line (the leading edge at −x_h·c, the
//! trailing edge at (1 − x_h)·c). Chords are drawn at full length (twist not projected).
//!
//! Spars: X_sp is ragged (a station's spar count changes where the AM rule or the loads add
//! one), so each spar other than the main spar is followed from station to station
//! ([`spar_traces`]) and drawn as one `polyline` per trace in the group `spars` (a `circle`
//! for a spar only one station has). Groups have ids (`outline`, `hinge`,
//! `main-spar`, `spars`, `section-breaks`, `section-labels`, `chord`, `twist`, `lift`,
//! `title`, `legend`). Pure: the picture is returned as text.

use svg::node::element::{Circle, Group, Line, Polygon, Polyline, Text};
use svg::Document;

use crate::section::Side;
use crate::spec::Wing;
use crate::structure::SparLayout;

/// Width of the rendered picture \[px\]; the viewBox stays in mm.
const WIDTH_PX: f64 = 1400.0;

/// Rounds to 0.01 mm for short files.
fn r(v: f64) -> f64 {
    (v * 100.0).round() / 100.0
}

/// `x,y x,y …` for an SVG `points` attribute.
fn points(pts: &[[f64; 2]]) -> String {
    pts.iter()
        .map(|p| format!("{},{}", r(p[0]), r(p[1])))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Spars further apart than this (x/c) at neighbouring stations are not the same spar.
pub const LINK_MAX_X_OVER_C: f64 = 0.05;

/// The spars other than the main spar (x/c ≠ `x_main`) traced along the span: each trace is
/// `(station, x/c)` at consecutive stations. A spar at station j + 1 continues a trace of
/// station j when the two are each other's nearest (in x/c) and less than
/// [`LINK_MAX_X_OVER_C`] apart; otherwise it starts a trace (a spar the AM rule or the loads
/// add). Every spar of every station is in exactly one trace.
pub fn spar_traces(layout: &SparLayout, x_main: f64) -> Vec<Vec<(usize, f64)>> {
    let nearest = |xs: &[f64], x: f64| {
        (0..xs.len()).min_by(|&a, &b| (xs[a] - x).abs().total_cmp(&(xs[b] - x).abs()))
    };
    let mut traces: Vec<Vec<(usize, f64)>> = Vec::new();
    // The previous station's spars and the trace each one is in.
    let mut prev: Vec<f64> = Vec::new();
    let mut prev_trace: Vec<usize> = Vec::new();
    for (j, xs) in layout.x_over_c.iter().enumerate() {
        let cur: Vec<f64> = xs.iter().copied().filter(|x| *x != x_main).collect();
        let mut cur_trace = Vec::with_capacity(cur.len());
        for &x in &cur {
            let link = nearest(&prev, x).filter(|&a| {
                nearest(&cur, prev[a]).is_some_and(|b| cur[b] == x)
                    && (prev[a] - x).abs() < LINK_MAX_X_OVER_C
            });
            let t = match link {
                Some(a) => prev_trace[a],
                None => {
                    traces.push(Vec::new());
                    traces.len() - 1
                }
            };
            traces[t].push((j, x));
            cur_trace.push(t);
        }
        prev = cur;
        prev_trace = cur_trace;
    }
    traces
}

/// A step of 1, 2 or 5 × 10ᵏ giving five to seven ticks over `range`.
fn tick_step(range: f64) -> f64 {
    let raw = (range / 6.0).max(1e-12);
    let p = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 5.0, 10.0]
        .into_iter()
        .map(|m| m * p)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * p)
}

/// Ticks (multiples of `step`) in [lo, hi].
fn ticks(lo: f64, hi: f64, step: f64) -> Vec<f64> {
    let first = (lo / step - 1e-9).ceil() as i64;
    let last = (hi / step + 1e-9).floor() as i64;
    (first..=last).map(|k| k as f64 * step).collect()
}

/// A tick's label: as few decimals as the step needs.
fn tick_label(v: f64, step: f64) -> String {
    let decimals = (-step.log10().floor()).max(0.0) as usize;
    let s = format!("{v:.decimals$}");
    if s.trim_start_matches('-')
        .trim_matches(['0', '.'])
        .is_empty()
    {
        "0".into()
    } else {
        s
    }
}

fn text(content: impl Into<String>, x: f64, y: f64, size: f64) -> Text {
    Text::new(content.into())
        .set("x", r(x))
        .set("y", r(y))
        .set("font-size", r(size))
        .set("font-family", "sans-serif")
}

fn line(a: [f64; 2], b: [f64; 2]) -> Line {
    Line::new()
        .set("x1", r(a[0]))
        .set("y1", r(a[1]))
        .set("x2", r(b[0]))
        .set("y2", r(b[1]))
}

/// One distribution on its own axes: `values` against `y_mm`, in a strip `height` tall whose
/// top is at `top`, x from `x0` to `x1`; the value axis from min(0, v) to max(0, v).
#[allow(clippy::too_many_arguments)]
fn strip(
    id: &str,
    label: &str,
    y_mm: &[f64],
    values: &[f64],
    (x0, x1): (f64, f64),
    top: f64,
    height: f64,
    font: f64,
    colour: &str,
) -> Group {
    let lo = values.iter().copied().fold(0.0, f64::min);
    let hi = values.iter().copied().fold(0.0, f64::max);
    let (lo, hi) = if hi - lo < 1e-12 {
        (lo - 1.0, hi + 1.0)
    } else {
        (lo, hi)
    };
    let step = tick_step(hi - lo);
    let (lo, hi) = ((lo / step).floor() * step, (hi / step).ceil() * step);
    let to_svg = |v: f64| top + height * (hi - v) / (hi - lo);
    let mut g = Group::new().set("id", id);
    let mut axes = Group::new()
        .set("stroke", "#444")
        .set("stroke-width", r(0.1 * font))
        .add(line([x0, top], [x0, top + height]))
        .add(line([x0, to_svg(0.0)], [x1, to_svg(0.0)]));
    let mut labels = Group::new().set("fill", "#222").set("text-anchor", "end");
    for v in ticks(lo, hi, step) {
        let at = to_svg(v);
        axes = axes.add(line([x0 - 0.4 * font, at], [x0, at]));
        if v != 0.0 {
            axes = axes.add(
                line([x0, at], [x1, at])
                    .set("stroke", "#ddd")
                    .set("stroke-width", r(0.05 * font)),
            );
        }
        labels = labels.add(text(
            tick_label(v, step),
            x0 - 0.6 * font,
            at + 0.3 * font,
            0.8 * font,
        ));
    }
    let curve: Vec<[f64; 2]> = y_mm
        .iter()
        .zip(values)
        .map(|(&y, &v)| [y, to_svg(v)])
        .collect();
    g = g
        .add(axes)
        .add(labels)
        .add(
            Polyline::new()
                .set("class", "curve")
                .set("points", points(&curve))
                .set("fill", "none")
                .set("stroke", colour)
                .set("stroke-width", r(0.18 * font)),
        )
        .add(text(label, x0, top - 0.5 * font, 0.9 * font).set("fill", colour));
    g
}

fn side_words(side: Side) -> &'static str {
    match side {
        Side::Centre => "centre",
        Side::Left => "left",
        Side::Right => "right",
    }
}

/// The planform picture of `wing`, titled with `name` (the spec's file stem), as SVG text.
pub fn planform_svg(wing: &Wing, name: &str) -> String {
    let b = wing.planform.span_mm;
    let x_h = wing.spec.structure.hinge_x_over_c;
    let x_main = wing.surfaces.x_max_thickness();
    let chord = &wing.planform.chord_mm;
    let y_mm: Vec<f64> = wing.spars.y_over_b.iter().map(|y| y * b).collect();
    let behind_hinge = |x_over_c: f64, c: f64| (x_over_c - x_h) * c;
    let c_max = chord.iter().copied().fold(0.0, f64::max);
    let font = (0.014 * b).max(1.0);
    let margin = 0.07 * b;
    let (x0, x1) = (-0.5 * b, 0.5 * b);

    // Planform: leading edge left to right, trailing edge back.
    let le: Vec<[f64; 2]> = y_mm
        .iter()
        .zip(chord)
        .map(|(&y, &c)| [y, behind_hinge(0.0, c)])
        .collect();
    let te: Vec<[f64; 2]> = y_mm
        .iter()
        .zip(chord)
        .map(|(&y, &c)| [y, behind_hinge(1.0, c)])
        .collect();
    let mut ring = le.clone();
    ring.extend(te.iter().rev());
    let (top, bottom) = (-x_h * c_max, (1.0 - x_h) * c_max);
    let outline = Group::new()
        .set("id", "outline")
        .add(
            Polygon::new()
                .set("points", points(&ring))
                .set("fill", "#eef2f7")
                .set("stroke", "none"),
        )
        .add(
            Polyline::new()
                .set("id", "leading-edge")
                .set("points", points(&le))
                .set("fill", "none")
                .set("stroke", "black")
                .set("stroke-width", r(0.15 * font)),
        )
        .add(
            Polyline::new()
                .set("id", "trailing-edge")
                .set("points", points(&te))
                .set("fill", "none")
                .set("stroke", "black")
                .set("stroke-width", r(0.15 * font)),
        );
    let hinge = Group::new().set("id", "hinge").add(
        line([y_mm[0], 0.0], [y_mm[y_mm.len() - 1], 0.0])
            .set("stroke", "#1f6fd1")
            .set("stroke-width", r(0.12 * font))
            .set("stroke-dasharray", format!("{} {}", r(font), r(0.5 * font))),
    );
    let main: Vec<[f64; 2]> = y_mm
        .iter()
        .zip(chord)
        .map(|(&y, &c)| [y, behind_hinge(x_main, c)])
        .collect();
    let main_spar = Group::new().set("id", "main-spar").add(
        Polyline::new()
            .set("points", points(&main))
            .set("fill", "none")
            .set("stroke", "black")
            .set("stroke-width", r(0.15 * font))
            .set(
                "stroke-dasharray",
                format!("{} {}", r(0.8 * font), r(0.4 * font)),
            ),
    );
    let mut spars = Group::new()
        .set("id", "spars")
        .set("fill", "none")
        .set("stroke", "#777")
        .set("stroke-width", r(0.08 * font));
    for trace in spar_traces(&wing.spars, x_main) {
        let pts: Vec<[f64; 2]> = trace
            .iter()
            .map(|&(j, x)| [y_mm[j], behind_hinge(x, chord[j])])
            .collect();
        spars = if pts.len() == 1 {
            spars.add(
                Circle::new()
                    .set("cx", r(pts[0][0]))
                    .set("cy", r(pts[0][1]))
                    .set("r", r(0.12 * font))
                    .set("fill", "#777")
                    .set("stroke", "none"),
            )
        } else {
            spars.add(Polyline::new().set("points", points(&pts)))
        };
    }

    // Section breaks across the whole chord extent, labels above the leading edge.
    let mut bounds: Vec<f64> = wing
        .sections
        .iter()
        .flat_map(|s| [s.y_bed_mm, s.y_top_mm])
        .collect();
    bounds.sort_by(f64::total_cmp);
    bounds.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    let mut breaks = Group::new()
        .set("id", "section-breaks")
        .set("stroke", "#c0392b")
        .set("stroke-width", r(0.1 * font));
    for y in &bounds {
        breaks = breaks.add(line([*y, top - 0.3 * font], [*y, bottom + 0.3 * font]));
    }
    let narrowest = wing
        .sections
        .iter()
        .map(|s| s.height_mm())
        .fold(f64::INFINITY, f64::min);
    let label_font = (0.8 * font).min(narrowest / 5.0);
    let mut labels = Group::new()
        .set("id", "section-labels")
        .set("fill", "#c0392b")
        .set("text-anchor", "middle");
    for (i, s) in wing.sections.iter().enumerate() {
        let mid = 0.5 * (s.y_bed_mm + s.y_top_mm);
        labels = labels
            .add(text(
                format!("#{i}"),
                mid,
                top - 1.9 * label_font,
                label_font,
            ))
            .add(text(
                format!("{} {}", side_words(s.side), s.index),
                mid,
                top - 0.8 * label_font,
                0.85 * label_font,
            ));
    }

    // Distributions under the planform, on the same span axis.
    let strip_h = 0.11 * b;
    let gap = 2.4 * font;
    let first = bottom + 2.8 * font;
    let twist_deg: Vec<f64> = wing
        .planform
        .twist_rad
        .iter()
        .map(|a| a.to_degrees())
        .collect();
    let lift_n_m: Vec<f64> = wing.lift_n_mm.iter().map(|l| l * 1000.0).collect();
    let load = wing.spec.loads.gross_weight_n * wing.spec.loads.load_factor;
    let chord_strip = strip(
        "chord",
        "chord c [mm]",
        &y_mm,
        chord,
        (x0, x1),
        first,
        strip_h,
        font,
        "#222",
    );
    let twist_strip = strip(
        "twist",
        "geometric twist α = LLT α + α_L0 [deg]",
        &y_mm,
        &twist_deg,
        (x0, x1),
        first + strip_h + gap,
        strip_h,
        font,
        "#1f6fd1",
    );
    let lift_strip = strip(
        "lift",
        &format!(
            "lift per span ℓ [N/m] at n·W = {} N (condition {})",
            r(load),
            wing.structure_condition + 1
        ),
        &y_mm,
        &lift_n_m,
        (x0, x1),
        first + 2.0 * (strip_h + gap),
        strip_h,
        font,
        "#d35400",
    );
    let axis_y = first + 3.0 * strip_h + 2.0 * gap + 0.5 * font;
    let step = tick_step(b);
    let mut span_axis = Group::new()
        .set("id", "span-axis")
        .add(
            line([x0, axis_y], [x1, axis_y])
                .set("stroke", "#444")
                .set("stroke-width", r(0.1 * font)),
        )
        .add(
            text("spanwise y [mm]", 0.0, axis_y + 2.6 * font, 0.9 * font)
                .set("text-anchor", "middle"),
        );
    for v in ticks(x0, x1, step) {
        span_axis = span_axis
            .add(
                line([v, axis_y], [v, axis_y + 0.4 * font])
                    .set("stroke", "#444")
                    .set("stroke-width", r(0.1 * font)),
            )
            .add(
                text(tick_label(v, step), v, axis_y + 1.4 * font, 0.8 * font)
                    .set("text-anchor", "middle"),
            );
    }

    // Title and legend above.
    let title_y = top - 3.2 * font - 1.2 * font;
    let d = &wing.design;
    let title = Group::new().set("id", "title").add(text(
        format!(
            "{name}: planform, design case {} ({}); span {} mm, {} stations, {} sections",
            d.case,
            d.title,
            r(b),
            chord.len(),
            wing.sections.len()
        ),
        x0,
        title_y - 1.4 * font,
        1.1 * font,
    ));
    let mut legend = Group::new().set("id", "legend");
    let mut at = x0;
    let entries: [(&str, &str, &str, f64); 5] = [
        ("leading / trailing edge", "black", "none", 0.15),
        (
            &format!("main spar, x/c = {:.3} (x_τmax)", x_main),
            "black",
            "0.8 0.4",
            0.15,
        ),
        ("other spars (X_sp)", "#777", "none", 0.08),
        (
            &format!("hinge line, x/c = {}", x_h),
            "#1f6fd1",
            "1 0.5",
            0.12,
        ),
        ("section breaks", "#c0392b", "none", 0.1),
    ];
    for (words, colour, dash, width) in entries {
        let mut swatch = line([at, title_y], [at + 2.5 * font, title_y])
            .set("stroke", colour)
            .set("stroke-width", r(width * font));
        if dash != "none" {
            let dashes: Vec<String> = dash
                .split(' ')
                .map(|v| r(v.parse::<f64>().unwrap_or(1.0) * font).to_string())
                .collect();
            swatch = swatch.set("stroke-dasharray", dashes.join(" "));
        }
        legend = legend.add(swatch).add(text(
            words,
            at + 3.0 * font,
            title_y + 0.3 * font,
            0.8 * font,
        ));
        at += 3.0 * font + 0.52 * 0.8 * font * words.chars().count() as f64 + 2.0 * font;
    }

    let (vx, vy) = (x0 - margin, title_y - 3.0 * font);
    let (vw, vh) = (b + 2.0 * margin, axis_y + 4.0 * font - vy);
    Document::new()
        .set("viewBox", (r(vx), r(vy), r(vw), r(vh)))
        .set("width", r(WIDTH_PX))
        .set("height", r(WIDTH_PX * vh / vw))
        .add(
            svg::node::element::Rectangle::new()
                .set("x", r(vx))
                .set("y", r(vy))
                .set("width", r(vw))
                .set("height", r(vh))
                .set("fill", "white"),
        )
        .add(title)
        .add(legend)
        .add(outline)
        .add(breaks)
        .add(labels)
        .add(hinge)
        .add(spars)
        .add(main_spar)
        .add(chord_strip)
        .add(twist_strip)
        .add(lift_strip)
        .add(span_axis)
        .to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ticks_are_round_and_cover_the_range() {
        assert_eq!(tick_step(1090.0), 200.0);
        assert_eq!(tick_step(3.2), 1.0);
        assert_eq!(
            ticks(-545.0, 545.0, 200.0),
            vec![-400.0, -200.0, 0.0, 200.0, 400.0]
        );
        assert_eq!(tick_label(0.5, 0.5), "0.5");
        assert_eq!(tick_label(-0.0, 0.5), "0");
        assert_eq!(tick_label(200.0, 100.0), "200");
    }
}
