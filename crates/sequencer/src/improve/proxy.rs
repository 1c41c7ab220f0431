//! The heat proxy of the surrogate cost (module docs): its exposure and pierce tables, built
//! once per search, and the proxy terms of a cut.

use crate::cost::Evaluator;
use crate::plan::Cut;
use crate::problem::{ContourId, Point};

use super::distance::seg_dist;
use super::search::Search;

/// Neighbour-list length of the heat proxy's tables (exposure and pierce).
pub(super) const PROXY_NEAR: usize = 20;

/// The proxy's exposure table (module docs): for each contour `b` and each `a` among its
/// neighbours (and `b`'s own containment partners, which are among them), how many of `b`'s
/// metric check points lie within `radius` mm of `a`'s polyline.
pub(super) fn exposure_table(
    eval: &Evaluator,
    near: &[Vec<ContourId>],
    radius: f64,
) -> Vec<Vec<(ContourId, f64)>> {
    let problem = eval.problem;
    let seg = eval.thermal_params().segment_mm;
    let checks: Vec<Vec<Point>> = problem
        .contours
        .iter()
        .map(|c| {
            let mut path = c.points.clone();
            if let Some(&f) = c.points.first() {
                path.push(f);
            }
            let len = c.perimeter();
            let k = ((len / seg).ceil() as usize).max(1);
            (0..k)
                .map(|i| crate::thermal::point_along(&path, i as f64 * len / k as f64))
                .collect()
        })
        .collect();
    (0..problem.contours.len())
        .map(|b| {
            near[b]
                .iter()
                .filter_map(|&a| {
                    let pts = &problem.contours[a].points;
                    let n = pts.len();
                    let e = checks[b]
                        .iter()
                        .filter(|&&p| {
                            (0..n).any(|i| seg_dist(p, pts[i], pts[(i + 1) % n]) < radius)
                        })
                        .count();
                    (e > 0).then_some((a, e as f64))
                })
                .collect()
        })
        .collect()
}

/// The proxy's pierce table (module docs): for each contour `b` and pierce candidate `k`, the
/// contours among `b`'s neighbours whose polyline passes through the raster cells the overheat
/// test reads at that pierce point (the cells within `overheat_radius_cells` of its cell).
pub(super) fn pierce_table(eval: &Evaluator, near: &[Vec<ContourId>]) -> Vec<Vec<Vec<ContourId>>> {
    let problem = eval.problem;
    let tp = eval.thermal_params();
    let (cell, r) = (tp.cell_mm, tp.overheat_radius_cells as f64);
    problem
        .contours
        .iter()
        .enumerate()
        .map(|(b, cb)| {
            cb.pierce_candidates
                .iter()
                .map(|&p| {
                    // The window: (2r + 1)² cells round the pierce point's cell.
                    let lo = [p[0], p[1]].map(|v| ((v / cell).floor() - r) * cell);
                    let hi = lo.map(|v| v + (2.0 * r + 1.0) * cell);
                    near[b]
                        .iter()
                        .copied()
                        .filter(|&a| {
                            let pts = &problem.contours[a].points;
                            let n = pts.len();
                            (0..n).any(|i| segment_meets_box(pts[i], pts[(i + 1) % n], lo, hi))
                        })
                        .collect()
                })
                .collect()
        })
        .collect()
}

/// Whether the segment `a–b` meets the box `lo..=hi` (Liang–Barsky clipping).
pub(super) fn segment_meets_box(a: Point, b: Point, lo: Point, hi: Point) -> bool {
    let d = [b[0] - a[0], b[1] - a[1]];
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..2 {
        for (q, pk) in [(a[k] - lo[k], -d[k]), (hi[k] - a[k], d[k])] {
            if pk == 0.0 {
                if q < 0.0 {
                    return false;
                }
            } else {
                let t = q / pk;
                if pk < 0.0 {
                    t0 = t0.max(t);
                } else {
                    t1 = t1.min(t);
                }
            }
        }
    }
    t0 <= t1
}

impl Search<'_, '_> {
    /// Heat-proxy term between contour `a`, cut `gap_mm` of cutting before `b` starts, and
    /// `b` (module docs): exposure × weight × ½^(gap / half-life).
    pub(super) fn proxy_pair(&self, a: ContourId, b: Cut, gap_mm: f64) -> f64 {
        if self.related[b.contour] & (1u64 << (a % 64)) == 0 {
            return 0.0;
        }
        let body = match self.exposure[b.contour].iter().find(|&&(x, _)| x == a) {
            Some(&(_, e)) => self.proxy_w * e * (-gap_mm * self.decay_per_mm).exp(),
            None => 0.0,
        };
        // The pierce term (module docs): a pierce next to a kerf still above `t_max`.
        let pierce = if gap_mm < self.hot_mm
            && self
                .pierce_near
                .get(b.contour)
                .is_some_and(|k| k[b.pierce].contains(&a))
        {
            self.pierce_w
        } else {
            0.0
        };
        body + pierce
    }

    /// Cutting (plus dwell) between the middle of contour `c`'s cut and its end, mm.
    pub(super) fn half(&self, c: ContourId) -> f64 {
        0.5 * self.cut_len[c]
    }

    /// The heat-proxy look-back of position `i < n` (part of [`Search::term`]).
    pub(super) fn proxy_at(&self, i: usize) -> f64 {
        let mut t = 0.0;
        if self.proxy_w > 0.0 {
            let c = self.seq[i];
            let mut gap = 0.0;
            for m in 1..=self.lookback.min(i) {
                let j = self.seq[i - m].contour;
                t += self.proxy_pair(j, c, gap + self.half(j));
                gap += self.cut_len[j];
            }
        }
        t
    }
}
