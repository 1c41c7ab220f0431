//! Plane geometry for the sheet acceptance check (`tests/sheet_acceptance.rs`): distances
//! between points and segments, point in ring, ring orientation, and a uniform grid of
//! segments for neighbourhood queries.
//!
//! Written here on purpose: the check must share no code with what it checks (the emitter,
//! the sequencer's kerf offset and lead-ins), so it does not use `cell_geometry` either.
#![allow(dead_code)] // each test binary uses a different subset

use std::collections::HashMap;

/// A point or vector in the plane, mm.
pub type P = [f64; 2];

pub fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}

pub fn add(a: P, b: P) -> P {
    [a[0] + b[0], a[1] + b[1]]
}

pub fn scale(a: P, s: f64) -> P {
    [a[0] * s, a[1] * s]
}

pub fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// The z component of the cross product: > 0 when `b` turns left from `a`.
pub fn cross(a: P, b: P) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

pub fn norm(a: P) -> f64 {
    a[0].hypot(a[1])
}

pub fn dist(a: P, b: P) -> f64 {
    norm(sub(a, b))
}

/// `a` scaled to length 1 (the zero vector stays zero).
pub fn unit(a: P) -> P {
    let n = norm(a);
    if n > 0.0 {
        scale(a, 1.0 / n)
    } else {
        [0.0, 0.0]
    }
}

/// `a` turned a quarter turn clockwise (the right-hand normal of a direction).
pub fn right_of(a: P) -> P {
    [a[1], -a[0]]
}

/// Distance from `p` to the segment `a`–`b`.
pub fn point_segment(p: P, a: P, b: P) -> f64 {
    let ab = sub(b, a);
    let len2 = dot(ab, ab);
    let t = if len2 > 0.0 {
        (dot(sub(p, a), ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    dist(p, add(a, scale(ab, t)))
}

/// True if the closed segments `a`–`b` and `c`–`d` share a point.
pub fn segments_meet(a: P, b: P, c: P, d: P) -> bool {
    let (d1, d2) = (cross(sub(b, a), sub(c, a)), cross(sub(b, a), sub(d, a)));
    let (d3, d4) = (cross(sub(d, c), sub(a, c)), cross(sub(d, c), sub(b, c)));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    // Touching or collinear cases: an end on the other segment.
    point_segment(c, a, b) == 0.0
        || point_segment(d, a, b) == 0.0
        || point_segment(a, c, d) == 0.0
        || point_segment(b, c, d) == 0.0
}

/// Shortest distance between the segments `a`–`b` and `c`–`d` (0 when they meet).
pub fn segment_segment(a: P, b: P, c: P, d: P) -> f64 {
    if segments_meet(a, b, c, d) {
        return 0.0;
    }
    point_segment(a, c, d)
        .min(point_segment(b, c, d))
        .min(point_segment(c, a, b))
        .min(point_segment(d, a, b))
}

/// Even-odd point in a closed ring (first point not repeated).
pub fn point_in_ring(p: P, ring: &[P]) -> bool {
    let mut inside = false;
    let n = ring.len();
    for i in 0..n {
        let (a, b) = (ring[i], ring[(i + 1) % n]);
        if (a[1] > p[1]) != (b[1] > p[1]) {
            let x = a[0] + (p[1] - a[1]) / (b[1] - a[1]) * (b[0] - a[0]);
            if p[0] < x {
                inside = !inside;
            }
        }
    }
    inside
}

/// Twice the signed area of a ring: > 0 counter-clockwise.
pub fn signed_area2(ring: &[P]) -> f64 {
    let n = ring.len();
    (0..n).map(|i| cross(ring[i], ring[(i + 1) % n])).sum()
}

/// Distance from `p` to a closed ring.
pub fn ring_distance(p: P, ring: &[P]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| point_segment(p, ring[i], ring[(i + 1) % n]))
        .fold(f64::INFINITY, f64::min)
}

pub fn ring_perimeter(ring: &[P]) -> f64 {
    let n = ring.len();
    (0..n).map(|i| dist(ring[i], ring[(i + 1) % n])).sum()
}

/// Bounding box `[min, max]`.
pub fn bbox(points: &[P]) -> [P; 2] {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    [lo, hi]
}

/// The radius of the largest circle inside a ring, to about 1 % of its size: a grid search
/// over the bounding box, refined twice around the best point.
pub fn inscribed_radius(ring: &[P]) -> f64 {
    let [lo, hi] = bbox(ring);
    let mut step = [(hi[0] - lo[0]) / 20.0, (hi[1] - lo[1]) / 20.0];
    let mut centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let mut best = 0.0_f64;
    let mut span = 10_i32;
    for _ in 0..3 {
        let around = centre;
        for i in -span..=span {
            for j in -span..=span {
                let p = [
                    around[0] + f64::from(i) * step[0],
                    around[1] + f64::from(j) * step[1],
                ];
                if !point_in_ring(p, ring) {
                    continue;
                }
                let d = ring_distance(p, ring);
                if d > best {
                    best = d;
                    centre = p;
                }
            }
        }
        step = [step[0] / 5.0, step[1] / 5.0];
        span = 5;
    }
    best
}

/// Segments in a uniform grid of square cells, each registered in every cell it passes
/// through, for "what is near this point or segment" queries. Each segment carries a tag
/// (the contour or path it belongs to).
pub struct SegmentGrid {
    cell: f64,
    cells: HashMap<(i64, i64), Vec<u32>>,
    /// `(a, b, tag)` per segment.
    pub segments: Vec<(P, P, u32)>,
}

impl SegmentGrid {
    /// An empty grid of `cell`-mm cells.
    pub fn new(cell: f64) -> Self {
        SegmentGrid {
            cell,
            cells: HashMap::new(),
            segments: Vec::new(),
        }
    }

    fn key(&self, v: f64) -> i64 {
        (v / self.cell).floor() as i64
    }

    /// Calls `f` with every cell key whose centre lies within `r` + half a cell diagonal of
    /// the segment `a`–`b` (so every cell the segment's `r`-neighbourhood touches).
    fn cells_near(&self, a: P, b: P, r: f64, mut f: impl FnMut((i64, i64))) {
        let reach = r + self.cell * std::f64::consts::FRAC_1_SQRT_2 + 1e-9;
        let (x0, x1) = (self.key(a[0].min(b[0]) - r), self.key(a[0].max(b[0]) + r));
        let (y0, y1) = (self.key(a[1].min(b[1]) - r), self.key(a[1].max(b[1]) + r));
        for i in x0..=x1 {
            for j in y0..=y1 {
                let centre = [(i as f64 + 0.5) * self.cell, (j as f64 + 0.5) * self.cell];
                if point_segment(centre, a, b) <= reach {
                    f((i, j));
                }
            }
        }
    }

    /// Adds the segment `a`–`b` with `tag`.
    pub fn insert(&mut self, a: P, b: P, tag: u32) {
        let id = self.segments.len() as u32;
        self.segments.push((a, b, tag));
        let mut keys = Vec::new();
        self.cells_near(a, b, 0.0, |k| keys.push(k));
        for k in keys {
            self.cells.entry(k).or_default().push(id);
        }
    }

    /// Adds every edge of a closed ring with `tag`.
    pub fn insert_ring(&mut self, ring: &[P], tag: u32) {
        let n = ring.len();
        for i in 0..n {
            self.insert(ring[i], ring[(i + 1) % n], tag);
        }
    }

    /// Indices of the segments that may lie within `r` of the segment `a`–`b` (a superset,
    /// sorted, without repeats), into `out`.
    pub fn near(&self, a: P, b: P, r: f64, out: &mut Vec<u32>) {
        out.clear();
        self.cells_near(a, b, r, |k| {
            if let Some(ids) = self.cells.get(&k) {
                out.extend_from_slice(ids);
            }
        });
        out.sort_unstable();
        out.dedup();
    }

    /// The distance from `p` to the nearest segment tagged `tag` (or any tag, `None`) if one
    /// lies within `r`; `f64::INFINITY` otherwise.
    pub fn distance(&self, p: P, tag: Option<u32>, r: f64, scratch: &mut Vec<u32>) -> f64 {
        self.near(p, p, r, scratch);
        scratch
            .iter()
            .map(|&i| self.segments[i as usize])
            .filter(|s| tag.is_none_or(|t| s.2 == t))
            .map(|(a, b, _)| point_segment(p, a, b))
            .filter(|&d| d <= r)
            .fold(f64::INFINITY, f64::min)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn distances_and_rings() {
        assert_eq!(point_segment([0.0, 1.0], [-1.0, 0.0], [1.0, 0.0]), 1.0);
        assert_eq!(point_segment([3.0, 4.0], [0.0, 0.0], [0.0, 0.0]), 5.0);
        assert_eq!(
            segment_segment([0.0, 0.0], [2.0, 2.0], [0.0, 2.0], [2.0, 0.0]),
            0.0
        );
        assert_eq!(
            segment_segment([0.0, 0.0], [1.0, 0.0], [2.0, 1.0], [2.0, 3.0]),
            2f64.sqrt()
        );
        let square = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0]];
        assert!(point_in_ring([1.0, 1.0], &square));
        assert!(!point_in_ring([5.0, 1.0], &square));
        assert_eq!(signed_area2(&square), 32.0);
        assert!((inscribed_radius(&square) - 2.0).abs() < 0.02);
        let mut grid = SegmentGrid::new(1.0);
        grid.insert_ring(&square, 7);
        let mut scratch = Vec::new();
        assert_eq!(grid.distance([2.0, 4.5], Some(7), 1.0, &mut scratch), 0.5);
        assert_eq!(
            grid.distance([2.0, 6.0], Some(7), 1.0, &mut scratch),
            f64::INFINITY
        );
        assert_eq!(
            grid.distance([2.0, 4.5], Some(1), 1.0, &mut scratch),
            f64::INFINITY
        );
    }
}
