//! Seeded generator of realistic nested layouts (issue 7, "a generator of realistic nested
//! layouts … 50 to 5000 contours, seeded"; the paper's own test nest, seed 003 §A5, is not
//! published).
//!
//! **Packing.** Shelf packing: parts are placed left to right in rows ("shelves") across a
//! sheet of width `a`, with a gap between parts and rows and a random horizontal jitter within
//! the gap slack; a row's height is its tallest part. The sheet height `b` is where the last
//! row ends. Parts never overlap because every part stays inside its own shelf slot.
//!
//! **Parts.** Each slot gets a rectangle, a rounded rectangle (corner arcs flattened to 6
//! chords) or a star-shaped polygon (5–9 vertices, radius jitter ≤ 15 %, so it stays simple),
//! all inscribed in the slot. Holes: with probability `p_nested` a large part gets one big
//! rectangular hole holding a smaller part (recursively, up to `max_depth` levels of parts);
//! otherwise 0–6 small circular or rectangular holes on a grid inside the part's inner box.
//! Generation stops once the contour count reaches `contours`.
//!
//! The same [`GeneratorConfig`] (seed included) gives the same layout, byte for byte.
//!
//! Dense perforated layouts (issue 19): [`generate_perforated`] ([`PerforatedConfig`]).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::layout::{Layout, Part, Ring};
use crate::problem::Point;

mod perforated;
pub use perforated::{generate_perforated, PerforatedConfig};

/// Generator parameters (issue 7).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GeneratorConfig {
    /// RNG seed (ChaCha8).
    pub seed: u64,
    /// Target number of contours; the result has at least this many (and at most a few more).
    pub contours: usize,
    /// Smallest and largest part footprint side, mm.
    pub part_size_mm: [f64; 2],
    /// Gap between parts and to the sheet edge, mm.
    pub gap_mm: f64,
    /// Probability that a part large enough gets a big hole with a part nested in it.
    pub p_nested: f64,
    /// Deepest part nesting (1 = no parts in holes).
    pub max_depth: usize,
}

impl Default for GeneratorConfig {
    fn default() -> Self {
        GeneratorConfig {
            seed: 1,
            contours: 200,
            part_size_mm: [30.0, 250.0],
            gap_mm: 8.0,
            p_nested: 0.15,
            max_depth: 3,
        }
    }
}

/// Generates a layout (module docs; issue 7 instances for seed 003, whose own test nest §A5 is
/// not published).
pub fn generate(cfg: &GeneratorConfig) -> Layout {
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let [lo, hi] = [
        cfg.part_size_mm[0].max(10.0),
        cfg.part_size_mm[1].max(cfg.part_size_mm[0].max(10.0)),
    ];
    let gap = cfg.gap_mm.max(0.5);
    // Roughly 2.2 contours per part, mean footprint ((lo+hi)/2 + gap)²: a 2:1 sheet.
    let mean = (lo + hi) / 2.0 + gap;
    let parts_est = (cfg.contours as f64 / 2.2).max(1.0);
    let width = ((parts_est * mean * mean * 2.0).sqrt())
        .max(hi + 2.0 * gap)
        .round();
    let mut parts: Vec<Part> = Vec::new();
    let mut count = 0;
    let (mut x, mut y, mut row_h) = (gap, gap, 0.0_f64);
    while count < cfg.contours.max(1) {
        let w = rng.random_range(lo..=hi);
        let h = rng.random_range(lo..=hi);
        if x + w + gap > width {
            x = gap;
            y += row_h + gap;
            row_h = 0.0;
        }
        let slack = gap * 0.5;
        let jx = rng.random_range(0.0..slack);
        let origin = [x + jx, y];
        let before = parts.len();
        make_part(&mut rng, cfg, origin, [w, h], 1, &mut parts);
        count += parts[before..]
            .iter()
            .map(|p| 1 + p.holes.len())
            .sum::<usize>();
        x += w + jx + gap;
        row_h = row_h.max(h);
    }
    let sheet = [width, (y + row_h + gap).round() + 1.0];
    Layout {
        sheet,
        start: [0.0, 0.0],
        origin: [0.0, 0.0],
        parts,
    }
}

/// Adds one part inscribed in the box `origin + [0, size]`, and any parts nested in it.
fn make_part(
    rng: &mut ChaCha8Rng,
    cfg: &GeneratorConfig,
    origin: Point,
    size: [f64; 2],
    depth: usize,
    parts: &mut Vec<Part>,
) {
    let [w, h] = size;
    let kind = rng.random_range(0..3);
    let outer = match kind {
        0 => rect(origin, size),
        1 => rounded_rect(origin, size, rng.random_range(0.1..0.3) * w.min(h)),
        _ => star_polygon(rng, origin, size),
    };
    // Polygons are inscribed in an ellipse: holes must stay in its inner box.
    let inset = if kind == 2 { 0.3 } else { 0.15 };
    let inner_o = [origin[0] + inset * w, origin[1] + inset * h];
    let inner = [(1.0 - 2.0 * inset) * w, (1.0 - 2.0 * inset) * h];
    let me = parts.len();
    parts.push(Part {
        name: None,
        outer: Ring {
            points: outer,
            pierce: None,
        },
        holes: Vec::new(),
    });
    if depth < cfg.max_depth && inner[0].min(inner[1]) > 40.0 && rng.random_bool(cfg.p_nested) {
        // One big hole filling the inner box, with a part inside it.
        parts[me].holes.push(Ring {
            points: rect(inner_o, inner),
            pierce: None,
        });
        let margin = 0.12 * inner[0].min(inner[1]);
        let child_o = [inner_o[0] + margin, inner_o[1] + margin];
        let child = [inner[0] - 2.0 * margin, inner[1] - 2.0 * margin];
        make_part(rng, cfg, child_o, child, depth + 1, parts);
        return;
    }
    // A grid of small holes.
    let n = rng.random_range(0..=6usize);
    if n == 0 || inner[0].min(inner[1]) < 6.0 {
        return;
    }
    let cols = ((n as f64).sqrt().ceil() as usize).max(1);
    let rows = n.div_ceil(cols);
    let cell = [inner[0] / cols as f64, inner[1] / rows as f64];
    for k in 0..n {
        let (c, r) = (k % cols, k / cols);
        let centre = [
            inner_o[0] + (c as f64 + 0.5) * cell[0],
            inner_o[1] + (r as f64 + 0.5) * cell[1],
        ];
        let s = 0.6 * cell[0].min(cell[1]) * rng.random_range(0.5..1.0);
        if s < 2.0 {
            continue;
        }
        let points = if rng.random_bool(0.5) {
            circle(centre, s / 2.0, 16)
        } else {
            rect([centre[0] - s / 2.0, centre[1] - s / 2.0], [s, s])
        };
        parts[me].holes.push(Ring {
            points,
            pierce: None,
        });
    }
}

fn rect(o: Point, s: [f64; 2]) -> Vec<Point> {
    vec![
        o,
        [o[0] + s[0], o[1]],
        [o[0] + s[0], o[1] + s[1]],
        [o[0], o[1] + s[1]],
    ]
}

fn rounded_rect(o: Point, s: [f64; 2], r: f64) -> Vec<Point> {
    let mut out = Vec::with_capacity(28);
    let centres = [
        [o[0] + s[0] - r, o[1] + r],
        [o[0] + s[0] - r, o[1] + s[1] - r],
        [o[0] + r, o[1] + s[1] - r],
        [o[0] + r, o[1] + r],
    ];
    for (q, c) in centres.iter().enumerate() {
        let a0 = -std::f64::consts::FRAC_PI_2 + q as f64 * std::f64::consts::FRAC_PI_2;
        for k in 0..=6 {
            let a = a0 + k as f64 / 6.0 * std::f64::consts::FRAC_PI_2;
            out.push([c[0] + r * a.cos(), c[1] + r * a.sin()]);
        }
    }
    out
}

fn circle(c: Point, r: f64, n: usize) -> Vec<Point> {
    (0..n)
        .map(|k| {
            let a = k as f64 / n as f64 * std::f64::consts::TAU;
            [c[0] + r * a.cos(), c[1] + r * a.sin()]
        })
        .collect()
}

/// A star-shaped polygon inscribed in the ellipse of the box: angles strictly increasing and
/// radii in (0.85, 1] of the ellipse, so the polygon is simple.
fn star_polygon(rng: &mut ChaCha8Rng, o: Point, s: [f64; 2]) -> Vec<Point> {
    let n = rng.random_range(5..=9usize);
    let c = [o[0] + s[0] / 2.0, o[1] + s[1] / 2.0];
    let phase = rng.random_range(0.0..std::f64::consts::TAU);
    (0..n)
        .map(|k| {
            let a =
                phase + (k as f64 + rng.random_range(-0.2..0.2)) / n as f64 * std::f64::consts::TAU;
            let f = rng.random_range(0.85..1.0);
            [
                c[0] + f * s[0] / 2.0 * a.cos(),
                c[1] + f * s[1] / 2.0 * a.sin(),
            ]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::PierceOptions;
    use crate::precedence::PrecedenceMode;

    #[test]
    fn deterministic_and_valid() {
        let cfg = GeneratorConfig {
            seed: 7,
            contours: 300,
            ..Default::default()
        };
        let a = generate(&cfg);
        assert_eq!(a.to_json(), generate(&cfg).to_json());
        assert!(a.contour_count() >= 300 && a.contour_count() < 320);
        let n = a.nesting().unwrap();
        assert!(
            n.host.iter().any(Option::is_some),
            "some part is nested in a hole"
        );
        a.to_problem(PrecedenceMode::Strict, &PierceOptions::default())
            .unwrap();
    }

    #[test]
    fn fifty_contours() {
        let l = generate(&GeneratorConfig {
            seed: 11,
            contours: 50,
            ..Default::default()
        });
        assert!(
            (50..60).contains(&l.contour_count()),
            "{}",
            l.contour_count()
        );
        l.nesting().unwrap();
    }

    #[test]
    fn large_layouts_build_quickly() {
        let l = generate(&GeneratorConfig {
            seed: 3,
            contours: 5000,
            ..Default::default()
        });
        let t = std::time::Instant::now();
        let p = l
            .to_problem(PrecedenceMode::Relaxed, &PierceOptions::default())
            .unwrap();
        assert!(p.contours.len() >= 5000);
        assert!(t.elapsed().as_secs_f64() < 20.0, "{:?}", t.elapsed());
    }
}
