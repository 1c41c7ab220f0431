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
/// contours among `b`'s neighbours whose polyline passes within `reach` mm of it.
pub(super) fn pierce_table(
    eval: &Evaluator,
    near: &[Vec<ContourId>],
    reach: f64,
) -> Vec<Vec<Vec<ContourId>>> {
    let problem = eval.problem;
    problem
        .contours
        .iter()
        .enumerate()
        .map(|(b, cb)| {
            cb.pierce_candidates
                .iter()
                .map(|&p| {
                    near[b]
                        .iter()
                        .copied()
                        .filter(|&a| {
                            let pts = &problem.contours[a].points;
                            let n = pts.len();
                            (0..n).any(|i| seg_dist(p, pts[i], pts[(i + 1) % n]) < reach)
                        })
                        .collect()
                })
                .collect()
        })
        .collect()
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
