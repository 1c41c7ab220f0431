//! Seeded dense perforated layouts (issue 19, item 5: "a 5000-contour 4000 × 2000 mm layout
//! full of perforated panels"): panels packed at a small spacing, many of them full of small
//! round holes, slots or square holes in a regular or staggered pattern, the others plain
//! brackets with a few mounting holes, some holding a small perforated grille in a cutout.
//!
//! **Packing.** As the nested generator: shelves left to right across a sheet of width
//! `sheet_width_mm` (0: `4000 · √(contours / 5000)` mm, so 5000 contours make the issue's
//! 4000 mm wide sheet), `gap_mm` between panels, rows and the sheet edge. The sheet is half as
//! high as it is wide (4000 × 2000 mm at 5000 contours), or higher if the last row ends above
//! that.
//!
//! **Perforation.** A perforated panel (probability `p_perforated`) gets one pattern over a
//! zone of its inner box (the panel inset by a solid margin of 12–30 mm; the zone's sides are
//! `zone_fraction` of the inner box's, placed at random in it): round holes of diameter `d`,
//! slots `d` wide and 2–4 `d` long (along x or y) or square holes of side `d`, `d` drawn from
//! `hole_mm`, with a web of `bridge_mm` between neighbours. The pattern is regular (a square
//! grid) or staggered (every other row shifted by half a pitch; round holes at 60°). A pattern
//! that would exceed `max_holes_per_panel` is spread to a wider pitch. The last panel's pattern
//! stops at the contour target.
//!
//! **Plain panels.** A rectangle or rounded rectangle with 0–4 corner holes and 0–3 holes or
//! slots on its centre line; with probability `p_grille` a panel larger than 250 mm instead
//! gets a big rectangular cutout holding a small perforated grille (a nested part: its holes,
//! then it, then the host's contours under strict precedence).
//!
//! The same [`PerforatedConfig`] (seed included) gives the same layout, byte for byte.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::{circle, rect, rounded_rect};
use crate::layout::{Layout, Part, Ring};
use crate::problem::Point;

/// Parameters of the dense perforated generator (module docs). Defaults are ours.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PerforatedConfig {
    /// RNG seed (ChaCha8).
    pub seed: u64,
    /// Target number of contours; the result has exactly this many unless the last part
    /// cannot be cut short (then a few more).
    pub contours: usize,
    /// Sheet width, mm; 0 = `4000 · √(contours / 5000)`.
    pub sheet_width_mm: f64,
    /// Smallest and largest panel side, mm. Default 100–500.
    pub panel_size_mm: [f64; 2],
    /// Gap between panels and to the sheet edge, mm. Default 5.
    pub gap_mm: f64,
    /// Probability that a panel is perforated. Default 0.75.
    pub p_perforated: f64,
    /// Smallest and largest side of the perforated zone, a fraction of the inner box's.
    /// Default 0.5–1.
    pub zone_fraction: [f64; 2],
    /// Smallest and largest perforation size (round diameter, slot width, square side), mm.
    /// Default 5–12.
    pub hole_mm: [f64; 2],
    /// Smallest and largest web between neighbouring perforations, mm. Default 3–8.
    pub bridge_mm: [f64; 2],
    /// Most perforations in one panel; a denser pattern is spread to a wider pitch.
    /// Default 400.
    pub max_holes_per_panel: usize,
    /// Probability that a plain panel over 250 mm holds a perforated grille in a cutout.
    /// Default 0.35.
    pub p_grille: f64,
}

impl Default for PerforatedConfig {
    fn default() -> Self {
        PerforatedConfig {
            seed: 1,
            contours: 5000,
            sheet_width_mm: 0.0,
            panel_size_mm: [100.0, 500.0],
            gap_mm: 5.0,
            p_perforated: 0.75,
            zone_fraction: [0.5, 1.0],
            hole_mm: [5.0, 12.0],
            bridge_mm: [3.0, 8.0],
            max_holes_per_panel: 400,
            p_grille: 0.35,
        }
    }
}

/// The shape of one perforation pattern.
#[derive(Debug, Clone, Copy)]
enum Hole {
    Round,
    /// A slot (stadium) along x (`true`) or y.
    Slot(bool),
    Square,
}

/// One perforation pattern: shape, size, pitch and stagger.
#[derive(Debug, Clone, Copy)]
struct Pattern {
    hole: Hole,
    /// Perforation width (diameter, slot width, square side), mm.
    d: f64,
    /// Slot length, mm (= `d` for the others).
    len: f64,
    bridge: f64,
    staggered: bool,
}

impl Pattern {
    fn random(rng: &mut ChaCha8Rng, cfg: &PerforatedConfig) -> Self {
        let [dlo, dhi] = ordered(cfg.hole_mm, 1.0);
        let [blo, bhi] = ordered(cfg.bridge_mm, 0.5);
        let d = rng.random_range(dlo..=dhi);
        let hole = match rng.random_range(0..4) {
            0 | 1 => Hole::Round,
            2 => Hole::Slot(rng.random_bool(0.5)),
            _ => Hole::Square,
        };
        let len = match hole {
            Hole::Slot(_) => d * rng.random_range(2.0..4.0),
            _ => d,
        };
        Pattern {
            hole,
            d,
            len,
            bridge: rng.random_range(blo..=bhi),
            staggered: rng.random_bool(0.5),
        }
    }

    /// The footprint of one perforation, mm.
    fn footprint(&self) -> [f64; 2] {
        match self.hole {
            Hole::Slot(true) => [self.len, self.d],
            Hole::Slot(false) => [self.d, self.len],
            _ => [self.d, self.d],
        }
    }

    /// Column and row pitch, mm, and the row shift of a staggered pattern.
    fn pitch(&self) -> ([f64; 2], f64) {
        let [fx, fy] = self.footprint();
        let px = fx + self.bridge;
        let py = fy + self.bridge;
        if !self.staggered {
            return ([px, py], 0.0);
        }
        // Round holes at 60°: the diagonal neighbour keeps the web. Others keep their rows.
        let py = match self.hole {
            Hole::Round => px * 3f64.sqrt() / 2.0,
            _ => py,
        };
        ([px, py], px / 2.0)
    }

    /// The perforation centred at `c`.
    fn ring(&self, c: Point) -> Vec<Point> {
        let r = self.d / 2.0;
        match self.hole {
            Hole::Round => circle(c, r, 16),
            Hole::Square => rect([c[0] - r, c[1] - r], [self.d, self.d]),
            Hole::Slot(along_x) => slot(c, self.len, self.d, along_x),
        }
    }

    /// Centres of the pattern over the box `o + [0, size]` (centred in it), at most `max`
    /// (spread to a wider pitch beyond that).
    fn centres(&self, o: Point, size: [f64; 2], max: usize) -> Vec<Point> {
        let [fx, fy] = self.footprint();
        let ([mut px, mut py], mut shift) = self.pitch();
        let fits = |px: f64, py: f64, shift: f64| {
            let cols = ((size[0] - fx - shift) / px).floor().max(-1.0) + 1.0;
            let rows = ((size[1] - fy) / py).floor().max(-1.0) + 1.0;
            (cols.max(0.0) as usize, rows.max(0.0) as usize)
        };
        let (mut cols, mut rows) = fits(px, py, shift);
        if cols * rows > max.max(1) {
            let f = ((cols * rows) as f64 / max.max(1) as f64).sqrt();
            px *= f;
            py *= f;
            shift *= f;
            (cols, rows) = fits(px, py, shift);
        }
        if cols == 0 || rows == 0 {
            return Vec::new();
        }
        let used = [
            (cols - 1) as f64 * px + fx + shift,
            (rows - 1) as f64 * py + fy,
        ];
        let x0 = o[0] + (size[0] - used[0]) / 2.0 + fx / 2.0;
        let y0 = o[1] + (size[1] - used[1]) / 2.0 + fy / 2.0;
        let mut out = Vec::with_capacity(cols * rows);
        for r in 0..rows {
            let dx = if r % 2 == 1 { shift } else { 0.0 };
            for c in 0..cols {
                out.push([x0 + dx + c as f64 * px, y0 + r as f64 * py]);
            }
        }
        out.truncate(max.max(1));
        out
    }
}

/// Generates a dense perforated layout (module docs; issue 19, item 5).
pub fn generate_perforated(cfg: &PerforatedConfig) -> Layout {
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let [lo, hi] = ordered(cfg.panel_size_mm, 40.0);
    let gap = cfg.gap_mm.max(0.5);
    let target = cfg.contours.max(1);
    let width = if cfg.sheet_width_mm > 0.0 {
        cfg.sheet_width_mm
    } else {
        (4000.0 * (target as f64 / 5000.0).sqrt()).round()
    }
    .max(hi + 2.0 * gap);
    let mut parts: Vec<Part> = Vec::new();
    let mut count = 0;
    let (mut x, mut y, mut row_h) = (gap, gap, 0.0_f64);
    while count < target {
        let w = rng.random_range(lo..=hi);
        let h = rng.random_range(lo..=hi);
        if x + w + gap > width {
            x = gap;
            y += row_h + gap;
            row_h = 0.0;
        }
        let before = parts.len();
        panel(&mut rng, cfg, [x, y], [w, h], target - count, &mut parts);
        count += parts[before..]
            .iter()
            .map(|p| 1 + p.holes.len())
            .sum::<usize>();
        x += w + gap;
        row_h = row_h.max(h);
    }
    Layout {
        sheet: [
            width.round(),
            ((y + row_h + gap).round() + 1.0).max((width / 2.0).round()),
        ],
        start: [0.0, 0.0],
        origin: [0.0, 0.0],
        parts,
    }
}

/// Adds one panel in the box `o + [0, size]` (and a grille nested in it), with at most
/// `budget` contours for a perforation pattern.
fn panel(
    rng: &mut ChaCha8Rng,
    cfg: &PerforatedConfig,
    o: Point,
    size: [f64; 2],
    budget: usize,
    parts: &mut Vec<Part>,
) {
    let [w, h] = size;
    let radius = if rng.random_bool(0.5) {
        rng.random_range(3.0..12.0)
    } else {
        0.0
    };
    let outer = if radius > 0.0 {
        rounded_rect(o, size, radius)
    } else {
        rect(o, size)
    };
    let margin = rng.random_range(12.0..30.0_f64).max(radius + 2.0);
    let inner_o = [o[0] + margin, o[1] + margin];
    let inner = [w - 2.0 * margin, h - 2.0 * margin];
    let me = parts.len();
    parts.push(Part {
        name: None,
        outer: Ring {
            points: outer,
            pierce: None,
        },
        holes: Vec::new(),
    });
    let ring = |points| Ring {
        points,
        pierce: None,
    };
    if rng.random_bool(cfg.p_perforated.clamp(0.0, 1.0)) {
        let pattern = Pattern::random(rng, cfg);
        let [flo, fhi] = ordered(cfg.zone_fraction, 0.05);
        let fhi = fhi.min(1.0);
        let zone = [
            inner[0] * rng.random_range(flo.min(fhi)..=fhi),
            inner[1] * rng.random_range(flo.min(fhi)..=fhi),
        ];
        let zone_o = [
            inner_o[0] + rng.random_range(0.0..=1.0) * (inner[0] - zone[0]),
            inner_o[1] + rng.random_range(0.0..=1.0) * (inner[1] - zone[1]),
        ];
        let max = cfg.max_holes_per_panel.min(budget.saturating_sub(1));
        let holes = pattern.centres(zone_o, zone, max);
        parts[me]
            .holes
            .extend(holes.into_iter().map(|c| ring(pattern.ring(c))));
        return;
    }
    if w.min(h) > 250.0 && rng.random_bool(cfg.p_grille.clamp(0.0, 1.0)) {
        // A cutout of the inner box less a frame, holding a grille 8 mm in from its edge.
        let frame = 0.12 * w.min(h);
        let cut_o = [inner_o[0] + frame, inner_o[1] + frame];
        let cut = [inner[0] - 2.0 * frame, inner[1] - 2.0 * frame];
        parts[me].holes.push(ring(rect(cut_o, cut)));
        let grille_o = [cut_o[0] + 8.0, cut_o[1] + 8.0];
        let grille = [cut[0] - 16.0, cut[1] - 16.0];
        let pattern = Pattern::random(rng, cfg);
        let holes = pattern.centres(
            [grille_o[0] + 8.0, grille_o[1] + 8.0],
            [grille[0] - 16.0, grille[1] - 16.0],
            cfg.max_holes_per_panel.min(budget.saturating_sub(3)),
        );
        parts.push(Part {
            name: None,
            outer: ring(rect(grille_o, grille)),
            holes: holes.into_iter().map(|c| ring(pattern.ring(c))).collect(),
        });
        return;
    }
    // Mounting holes: at the corners of the inner box and on its centre line.
    let d = rng.random_range(6.0..14.0_f64).min(margin);
    if rng.random_bool(0.7) {
        for c in [
            inner_o,
            [inner_o[0] + inner[0], inner_o[1]],
            [inner_o[0] + inner[0], inner_o[1] + inner[1]],
            [inner_o[0], inner_o[1] + inner[1]],
        ] {
            parts[me].holes.push(ring(circle(c, d / 2.0, 16)));
        }
    }
    let k = rng.random_range(0..=3usize);
    let along_x = w >= h;
    let mid = [inner_o[0] + inner[0] / 2.0, inner_o[1] + inner[1] / 2.0];
    let span = if along_x { inner[0] } else { inner[1] };
    let hole_len = if rng.random_bool(0.5) { 3.0 * d } else { d };
    if span < (k as f64 + 1.0) * (hole_len + 10.0) {
        return;
    }
    for i in 0..k {
        let f = (i as f64 + 1.0) / (k as f64 + 1.0) - 0.5;
        let c = if along_x {
            [mid[0] + f * span, mid[1]]
        } else {
            [mid[0], mid[1] + f * span]
        };
        let points = if hole_len > d {
            slot(c, hole_len, d, along_x)
        } else {
            circle(c, d / 2.0, 16)
        };
        parts[me].holes.push(ring(points));
    }
}

/// A slot (stadium) `len` long and `d` wide centred at `c`, along x or y; each end a half
/// circle of 6 chords.
fn slot(c: Point, len: f64, d: f64, along_x: bool) -> Vec<Point> {
    let r = d / 2.0;
    let half = (len / 2.0 - r).max(0.0);
    let mut out = Vec::with_capacity(14);
    for (end, a0) in [
        (half, -std::f64::consts::FRAC_PI_2),
        (-half, std::f64::consts::FRAC_PI_2),
    ] {
        for k in 0..=6 {
            let a = a0 + k as f64 / 6.0 * std::f64::consts::PI;
            let (u, v) = (end + r * a.cos(), r * a.sin());
            out.push(if along_x {
                [c[0] + u, c[1] + v]
            } else {
                [c[0] - v, c[1] + u]
            });
        }
    }
    out
}

/// `[lo, hi]` with `lo ≥ min` and `hi ≥ lo`.
fn ordered([a, b]: [f64; 2], min: f64) -> [f64; 2] {
    let lo = a.max(min);
    [lo, b.max(lo)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::layout::PierceOptions;
    use crate::precedence::PrecedenceMode;

    #[test]
    fn deterministic_valid_and_dense() {
        let cfg = PerforatedConfig {
            seed: 5,
            contours: 1500,
            ..Default::default()
        };
        let a = generate_perforated(&cfg);
        assert_eq!(a.to_json(), generate_perforated(&cfg).to_json());
        assert_eq!(a.contour_count(), 1500);
        let problem = a
            .to_problem(PrecedenceMode::Strict, &PierceOptions::default())
            .unwrap();
        // Perforated: some panel holds a hundred holes or more.
        assert!(a.parts.iter().any(|p| p.holes.len() >= 100));
        // Dense: most holes have a neighbour within one pitch (largest perforation 12 mm plus
        // the widest web 8 mm), centre to centre.
        let centres: Vec<Point> = problem
            .contours
            .iter()
            .filter(|c| c.role == crate::problem::ContourRole::Hole)
            .map(|c| {
                let n = c.points.len() as f64;
                let s = c
                    .points
                    .iter()
                    .fold([0.0, 0.0], |s, p| [s[0] + p[0], s[1] + p[1]]);
                [s[0] / n, s[1] / n]
            })
            .collect();
        assert!(centres.len() > 1200, "{}", centres.len());
        let close = centres
            .iter()
            .enumerate()
            .filter(|&(i, &p)| {
                centres
                    .iter()
                    .enumerate()
                    .any(|(j, &q)| i != j && crate::problem::distance(p, q) <= 20.0 + 1e-9)
            })
            .count();
        assert!(
            close * 10 >= centres.len() * 8,
            "{close} of {}",
            centres.len()
        );
    }

    #[test]
    fn five_thousand_contours_fill_a_4000_by_2000_sheet() {
        let l = generate_perforated(&PerforatedConfig {
            seed: 1,
            ..Default::default()
        });
        assert_eq!(l.contour_count(), 5000);
        assert_eq!(l.sheet, [4000.0, 2000.0]);
        let n = l.nesting().unwrap();
        assert!(
            n.host.iter().any(Option::is_some),
            "some grille sits in a cutout"
        );
    }
}
