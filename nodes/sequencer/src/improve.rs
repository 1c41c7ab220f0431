//! Improvement phase after the greedy construction (ours, beyond seed 003 §A4, which only
//! mentions a later 2-opt; notes §A6): it never breaks precedence and never returns a plan
//! worse than its start.
//!
//! 1. **Local search** on a *surrogate* cost. Without the heat proxy (thermal cost off): 2-opt
//!    and Or-opt (runs of 1..=3, either way round) between each contour and its 14 nearest
//!    contours, at any distance along the sequence, with O(1) idle deltas. Then, and always
//!    with the proxy: precedence-aware Or-opt (move a run of 1..=
//!    `or_opt_max_len` cuts within `window` positions), 2-opt (reverse a run of up to
//!    `window` cuts) and pierce re-selection at every position. A move is applied in place,
//!    checked locally (predecessors inside the moved span keep their order; every group stays
//!    contiguous) and kept only if the surrogate drops.
//!
//!    Speed (2026-11-23; the same plans as before on the bench layouts): both kinds of sweep
//!    keep don't-look bits (Bentley's, as LKH does): a sweep examines only contours near a
//!    change since their last fruitless look, and the remove-and-reinsert step wakes the
//!    contours at the edges it changed. The window sweep keeps every position's surrogate
//!    term and its proxy part as prefix sums, so a move's cost before is two lookups; a move
//!    whose idle change alone exceeds the proxy it could remove is dropped unseen, and the
//!    cost after stops summing once it reaches the cost before (every term is ≥ 0). On the
//!    1002-contour layout the search went from ~1.5 s to ~0.3 s with the heat proxy and
//!    from ~2.1 s to ~0.14 s without.
//! 2. **Large-neighbourhood search** (GLNS-style remove and reinsert): remove `lns_remove`
//!    cuts close to a random seed cut, reinsert them in their old relative order, each at the
//!    cheapest feasible position with its cheapest pierce candidate; keep the result if the
//!    surrogate does not rise. Without the heat proxy every reinsertion is first polished
//!    with the neighbour-list moves (iterated local search). The best order is polished with
//!    local search once more.
//! 3. The best surrogate plan is evaluated with the full thermal raster ([`Evaluator`]); if its
//!    true cost is above the start's, the start is returned. If it is the start order, no
//!    raster run is needed. [`improve_cuts_until`] takes a start order not evaluated yet and
//!    runs its raster on a second thread alongside the search and the best order's run.
//!
//! **Surrogate** = idle length + corner penalties + (thermal cost on) a heat proxy: for every
//! cut `b` and each of the `proxy_lookback` cuts `a` before it, `w_overheat_mm ·
//! proxy_weight · e(a, b) · ½^(s / proxy_half_life_mm)`, where the *exposure* `e(a, b)` counts
//! the places of `b` the overheat metric checks (points every `segment_mm` along it) that lie
//! within `proxy_radius_mm` of `a`'s polyline, and `s` is the cutting (plus pierce dwell at
//! cut speed) between the middle of `a`'s cut and the start of `b`'s, mm. A full raster run
//! per move would cost a whole simulation each (measured in the bench); the proxy keeps a
//! move's evaluation local to the moved span.
//!
//! **Pierce term** of the proxy: a cut `b` pierced within `(overheat_radius_cells + 1) ·
//! cell_mm` of the polyline of one of its look-back cuts `a` costs `(w_overheat_mm +
//! hot_penalty_mm) · proxy_weight` while `a`'s kerf is still above `t_max`, i.e. while the
//! cutting in between (as above) is below `cell_mm · ln((t_melt − ambient)/(t_max − ambient)) /
//! −ln(k_loss)` (a kerf at melting temperature decaying by `k_loss` per step alone; 1290 mm with
//! the defaults). This is what moves pierce points and hole orders away from fresh kerf: on the
//! generator's layouts most remaining overheats were pierces of small holes next to the hole
//! cut just before (bench, 2026-11-22).
//!
//! **Idle budget** (thermal cost on, `idle_budget > 0`; issue 7 target "≤ 1.5× the idle length
//! of nearest-neighbour"): the budget is `idle_budget ×` the idle length of the nearest-pierce
//! order of the same problem ([`crate::policy::nearest_cuts`]). Every move must also keep the
//! idle length within it, or shorten it; a start above the budget can only move towards it.
//! The overheat/idle trade-off is thus a constrained one: the proxy weight can stay high without
//! the idle length running away.
//!
//! **Cancellation**: [`improve_until`] polls a `stop` closure with the time budget; once it
//! returns true the search ends and the best order so far is evaluated as usual.
//!
//! Deterministic for a seed when the time budget does not bind (`time_budget_ms = 0`).

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::cost::Evaluator;
use crate::plan::{Cut, CutPlan};
use crate::problem::{ContourId, Point};

/// Euclidean distance without `hypot`'s overflow care (coordinates are mm on a sheet).
fn dist(a: Point, b: Point) -> f64 {
    let (dx, dy) = (a[0] - b[0], a[1] - b[1]);
    (dx * dx + dy * dy).sqrt()
}
use crate::thermal::{require, ParamError};

/// Knobs of the improvement phase (module docs). Defaults are ours.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ImproveParams {
    /// LNS iterations. Default 1000.
    pub max_iterations: usize,
    /// Wall-clock budget, ms; 0 = none (then the result is deterministic). Default 0.
    pub time_budget_ms: u64,
    /// RNG seed. Default 0.
    pub seed: u64,
    /// Longest run Or-opt moves. Default 3.
    pub or_opt_max_len: usize,
    /// How far (positions) local moves reach. Default 25.
    pub window: usize,
    /// Local-search sweeps at the start and after each accepted LNS step. Default 4.
    pub local_sweeps: usize,
    /// Cuts removed per LNS iteration. Default 8.
    pub lns_remove: usize,
    /// Heat proxy radius: check points of a contour this close to an earlier contour's
    /// polyline are exposed to its heat, mm. Default 30 (best of 10/20/30/45 on the bench).
    pub proxy_radius_mm: f64,
    /// Heat proxy half-life, mm of cutting in between. Default 150.
    pub proxy_half_life_mm: f64,
    /// Heat proxy look-back, cuts. Default 8.
    pub proxy_lookback: usize,
    /// Heat proxy weight, fraction of `w_overheat_mm`. Default 0.5 (the proxy over-counts:
    /// at 1 the search on the bench's 5005-contour layout bought a 55 % overheat cut with 11 %
    /// more idle travel, worse in true cost than its start; at 0.5 it cut 54 % at 1 % more
    /// idle, and the smaller layouts did as well or better; bench, 2026-11-23).
    pub proxy_weight: f64,
    /// Idle budget with thermal cost on, a multiple of the nearest-neighbour idle length of
    /// the same problem (issue 7 target: ≤ 1.5×): a move that leaves the idle length above it
    /// is only taken if it shortens idle travel. 0 = no budget. Default 1.5.
    #[serde(default = "default_idle_budget")]
    pub idle_budget: f64,
}

fn default_idle_budget() -> f64 {
    1.5
}

impl Default for ImproveParams {
    fn default() -> Self {
        ImproveParams {
            max_iterations: 1000,
            time_budget_ms: 0,
            seed: 0,
            or_opt_max_len: 3,
            window: 25,
            local_sweeps: 4,
            lns_remove: 8,
            proxy_radius_mm: 30.0,
            proxy_half_life_mm: 150.0,
            proxy_lookback: 8,
            proxy_weight: 0.5,
            idle_budget: default_idle_budget(),
        }
    }
}

impl ImproveParams {
    /// Checks every field.
    ///
    /// # Errors
    /// The first field out of range, by name.
    pub fn validate(&self) -> Result<(), ParamError> {
        require(
            self.or_opt_max_len >= 1,
            "or_opt_max_len",
            self.or_opt_max_len,
            "must be ≥ 1",
        )?;
        require(self.window >= 1, "window", self.window, "must be ≥ 1")?;
        require(
            self.proxy_radius_mm.is_finite() && self.proxy_radius_mm > 0.0,
            "proxy_radius_mm",
            self.proxy_radius_mm,
            "must be finite and > 0",
        )?;
        require(
            self.proxy_lookback <= 16,
            "proxy_lookback",
            self.proxy_lookback,
            "must be ≤ 16",
        )?;
        require(
            self.proxy_weight.is_finite() && self.proxy_weight >= 0.0,
            "proxy_weight",
            self.proxy_weight,
            "must be finite and ≥ 0",
        )?;
        require(
            self.idle_budget.is_finite() && (self.idle_budget == 0.0 || self.idle_budget >= 1.0),
            "idle_budget",
            self.idle_budget,
            "must be 0 (none) or ≥ 1",
        )?;
        Ok(())
    }
}

/// The proxy's exposure table (module docs): for each contour `b` and each `a` among its
/// neighbours (and `b`'s own containment partners, which are among them), how many of `b`'s
/// metric check points lie within `radius` mm of `a`'s polyline.
fn exposure_table(
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
    let seg_dist = |p: Point, a: Point, b: Point| {
        let d = [b[0] - a[0], b[1] - a[1]];
        let l2 = d[0] * d[0] + d[1] * d[1];
        let t = if l2 == 0.0 {
            0.0
        } else {
            (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0)
        };
        dist(p, [a[0] + t * d[0], a[1] + t * d[1]])
    };
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
fn pierce_table(eval: &Evaluator, near: &[Vec<ContourId>], reach: f64) -> Vec<Vec<Vec<ContourId>>> {
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

/// Distance from `p` to the segment `a–b`, mm.
fn seg_dist(p: Point, a: Point, b: Point) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let l2 = d[0] * d[0] + d[1] * d[1];
    let t = if l2 == 0.0 {
        0.0
    } else {
        (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0)
    };
    dist(p, [a[0] + t * d[0], a[1] + t * d[1]])
}

/// Neighbour-list length of the heat proxy's tables (exposure and pierce).
const PROXY_NEAR: usize = 20;

/// Neighbour-list length of the idle-only moves (thermal cost off). 14 rather than 10: over
/// improvement seeds 0–3, 1000 scattered points +1.7–2.0 % above LKH-3 instead of +2.3–3.0 %,
/// and the 1002-contour generator layout 0.6 % shorter on average, for ~40 % more search time
/// (bench, 2026-11-22).
const NEAR_IDLE: usize = 14;

/// Progress report for the action feedback (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// LNS iterations done.
    pub iteration: usize,
    /// Best surrogate cost so far (the true cost is only known at the end).
    pub best_cost: f64,
}

struct Search<'e, 'p> {
    eval: &'e Evaluator<'p>,
    seq: Vec<Cut>,
    pos: Vec<usize>,
    group_of: Vec<Option<usize>>,
    successors: Vec<Vec<ContourId>>,
    /// The `NEAR_IDLE` contours nearest each contour (bounding-box centres), and the start.
    near: Vec<Vec<ContourId>>,
    near_start: Vec<ContourId>,
    /// Cut length plus the dwell's equivalent, per contour, mm.
    cut_len: Vec<f64>,
    /// Heat retention per mm of cutting: `-ln(k_loss) / cell_mm`.
    decay_per_mm: f64,
    proxy_w: f64,
    /// `exposure[b]`: `(a, e)` for every contour `a` near `b`, `e` the places of `b` the
    /// overheat metric checks (pierce and segment starts) within `proxy_radius_mm` of `a`.
    exposure: Vec<Vec<(ContourId, f64)>>,
    lookback: usize,
    /// `pierce_near[b][k]`: contours whose polyline passes within the overheat test's reach
    /// of candidate `k` of `b` (empty without the proxy).
    pierce_near: Vec<Vec<Vec<ContourId>>>,
    /// `related[b]`: bit `a % 64` set for every contour `a` in `exposure[b]` or any of
    /// `pierce_near[b]` (a quick test that the pair's proxy term is zero).
    related: Vec<u64>,
    /// Cutting after which a kerf has cooled below `t_max`, mm (module docs).
    hot_mm: f64,
    /// Proxy charge of a pierce next to a hot kerf: one overheat plus the hot-pierce penalty.
    pierce_w: f64,
    /// Current idle length, mm (kept up to date by the moves when `idle_cap` is finite).
    idle: f64,
    /// Idle budget, mm (`ImproveParams::idle_budget`; infinite without one).
    idle_cap: f64,
    /// Don't-look bits of [`Search::neighbour_sweep`] (Bentley's, as in LKH): `look[c]` if an
    /// edge at contour `c` changed since `c` was last examined without finding a move;
    /// index `n` is the start point.
    look: Vec<bool>,
    /// The bits being examined by the running sweep (swapped with `look`).
    examine: Vec<bool>,
    /// Don't-look bits of [`Search::sweep`], per contour: set for the contours within
    /// `lookback` positions of a change (their surrogate terms changed).
    look_win: Vec<bool>,
    /// The bits being examined by the running window sweep (swapped with `look_win`).
    examine_win: Vec<bool>,
    /// Heat-proxy part of each position's term, and its prefix sums (`proxy_sum[i]` = the
    /// sum over positions `< i`), kept up to date inside [`Search::sweep`]: a move whose idle
    /// change exceeds the proxy it could at best remove is rejected unseen.
    proxy_term: Vec<f64>,
    proxy_sum: Vec<f64>,
    /// The same for whole terms (positions `0..=n`), so a move's cost before is a
    /// difference of two prefix sums.
    term_cache: Vec<f64>,
    term_sum: Vec<f64>,
}

impl<'e, 'p> Search<'e, 'p> {
    fn point(&self, i: usize) -> Point {
        if i == usize::MAX || i >= self.seq.len() {
            self.eval.problem.start
        } else {
            self.seq[i].point(self.eval.problem)
        }
    }

    /// Heat-proxy term between contour `a`, cut `gap_mm` of cutting before `b` starts, and
    /// `b` (module docs): exposure × weight × ½^(gap / half-life).
    fn proxy_pair(&self, a: ContourId, b: Cut, gap_mm: f64) -> f64 {
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
    fn half(&self, c: ContourId) -> f64 {
        0.5 * self.cut_len[c]
    }

    /// Surrogate terms owned by position `i` (0..=n; n is the return to start): the idle
    /// edge into it, its corner penalty and its heat-proxy look-back.
    fn term(&self, i: usize) -> f64 {
        let proxy = if i < self.seq.len() {
            self.proxy_at(i)
        } else {
            0.0
        };
        self.term_without_proxy(i) + proxy
    }

    /// [`Search::term`] without its heat-proxy part: the idle edge into position `i` and its
    /// corner penalty.
    fn term_without_proxy(&self, i: usize) -> f64 {
        let prev = if i == 0 { usize::MAX } else { i - 1 };
        let edge = dist(self.point(prev), self.point(i));
        match self.seq.get(i) {
            Some(&c) => edge + self.eval.corner_penalty(c),
            None => edge,
        }
    }

    /// The heat-proxy look-back of position `i < n` (part of [`Search::term`]).
    fn proxy_at(&self, i: usize) -> f64 {
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

    /// Recomputes the cached terms (and their proxy parts) that a change of `lo..=hi` touches,
    /// positions `lo..=`[`Search::span_end`]`(hi)`, and the prefix sums from `lo` on.
    fn refresh_cache(&mut self, lo: usize, hi: usize) {
        let n = self.seq.len();
        if n == 0 {
            return;
        }
        for i in lo..=self.span_end(hi) {
            let proxy = if i < n { self.proxy_at(i) } else { 0.0 };
            if i < n {
                self.proxy_term[i] = proxy;
            }
            self.term_cache[i] = self.term_without_proxy(i) + proxy;
        }
        for i in lo..=n {
            self.term_sum[i + 1] = self.term_sum[i] + self.term_cache[i];
        }
        for i in lo..n {
            self.proxy_sum[i + 1] = self.proxy_sum[i] + self.proxy_term[i];
        }
    }

    /// The last position whose term changes when positions `lo..=hi` are permuted (`n`: the
    /// return to start): the edge out of `hi` and the look-back of the cuts after it.
    fn span_end(&self, hi: usize) -> usize {
        (hi + 1 + self.lookback).min(self.seq.len())
    }

    /// The cached [`Search::span_cost`] of `lo..=hi` (valid inside [`Search::sweep`]).
    fn cached_span_cost(&self, lo: usize, hi: usize) -> f64 {
        self.term_sum[self.span_end(hi) + 1] - self.term_sum[lo]
    }

    /// Whether [`Search::span_cost`] of `lo..=hi` is below `limit`, stopping as soon as the
    /// partial sum reaches it (every term is ≥ 0).
    fn span_cost_below(&self, lo: usize, hi: usize, limit: f64) -> bool {
        let mut sum = 0.0;
        for i in lo..=self.span_end(hi) {
            sum += self.term(i);
            if sum >= limit {
                return false;
            }
        }
        true
    }

    /// The cached proxy a move of `lo..=hi` could at best remove (the proxy parts of the terms
    /// [`Search::span_cost`] sums, but the last).
    fn span_proxy(&self, lo: usize, hi: usize) -> f64 {
        // Positions lo..span_end(hi): the last term's look-back lies wholly after hi, so its
        // proxy cannot change.
        self.proxy_sum[self.span_end(hi)] - self.proxy_sum[lo]
    }

    /// The idle change of swapping the blocks `lo..split` and `split..=hi` (an Or-opt move),
    /// from the three edges it replaces.
    fn swap_blocks_idle_delta(&self, lo: usize, split: usize, hi: usize) -> f64 {
        let (l, f, h) = (lo as isize, split as isize, hi as isize);
        self.edge(l - 1, f) + self.edge(h, l) + self.edge(f - 1, h + 1)
            - self.edge(l - 1, l)
            - self.edge(f - 1, f)
            - self.edge(h, h + 1)
    }

    /// The idle change of reversing `lo..=hi` (a 2-opt move): two edges replaced, the ones
    /// inside keep their lengths.
    fn reverse_idle_delta(&self, lo: usize, hi: usize) -> f64 {
        let (l, h) = (lo as isize, hi as isize);
        self.edge(l - 1, h) + self.edge(l, h + 1) - self.edge(l - 1, l) - self.edge(h, h + 1)
    }

    /// Idle length of the edge from position `a` to position `b` (−1 and `n`: the start).
    fn edge(&self, a: isize, b: isize) -> f64 {
        let n = self.seq.len() as isize;
        let at = |i: isize| if i >= n { self.pt(-1) } else { self.pt(i) };
        dist(at(a), at(b))
    }

    /// Sum of the terms that change when positions `lo..=hi` are permuted.
    fn span_cost(&self, lo: usize, hi: usize) -> f64 {
        (lo..=self.span_end(hi)).map(|i| self.term(i)).sum()
    }

    fn total(&self) -> f64 {
        (0..=self.seq.len()).map(|i| self.term(i)).sum()
    }

    /// Idle length of the edges into positions `lo..=hi + 1` (`n`: the return to start), mm.
    fn span_idle(&self, lo: usize, hi: usize) -> f64 {
        let end = (hi + 1).min(self.seq.len());
        (lo..=end)
            .map(|i| {
                let prev = if i == 0 { usize::MAX } else { i - 1 };
                dist(self.point(prev), self.point(i))
            })
            .sum()
    }

    /// Whether a change of the idle length from `self.idle` by `before → after` (over a span)
    /// keeps the idle budget: within it, or shorter than before. Updates `self.idle` if so.
    fn budget_ok(&mut self, before: f64, after: f64) -> bool {
        let new = self.idle - before + after;
        if new <= self.idle_cap || after <= before {
            self.idle = new;
            true
        } else {
            false
        }
    }

    fn capped(&self) -> bool {
        self.idle_cap.is_finite()
    }

    fn reindex(&mut self, lo: usize, hi: usize) {
        for i in lo..=hi {
            self.pos[self.seq[i].contour] = i;
        }
    }

    /// Local feasibility after permuting `lo..=hi` of a feasible order (module docs).
    fn feasible_span(&self, lo: usize, hi: usize) -> bool {
        let rules = &self.eval.problem.precedence;
        for i in lo..=hi {
            let c = self.seq[i].contour;
            if rules.predecessors[c].iter().any(|&p| self.pos[p] > i) {
                return false;
            }
            if let Some(g) = self.group_of[c] {
                let members = &rules.groups[g];
                let (mut a, mut b) = (usize::MAX, 0);
                for &m in members {
                    a = a.min(self.pos[m]);
                    b = b.max(self.pos[m]);
                }
                if b - a + 1 != members.len() {
                    return false;
                }
            }
        }
        true
    }

    /// Applies a move on `lo..=hi`, keeps it if feasible and cheaper, else undoes it.
    /// `idle_delta` is the move's change of the idle length: a move that adds more idle than
    /// the proxy of the span it could at best remove cannot pass and is not applied.
    fn try_move(
        &mut self,
        lo: usize,
        hi: usize,
        idle_delta: f64,
        apply: &dyn Fn(&mut [Cut]),
        undo: &dyn Fn(&mut [Cut]),
    ) -> bool {
        if idle_delta > self.span_proxy(lo, hi) + 1e-6 {
            return false;
        }
        let before = self.cached_span_cost(lo, hi);
        debug_assert!((before - self.span_cost(lo, hi)).abs() <= 1e-6 * (1.0 + before.abs()));
        let idle_before = if self.capped() {
            self.span_idle(lo, hi)
        } else {
            0.0
        };
        apply(&mut self.seq[lo..=hi]);
        self.reindex(lo, hi);
        if self.feasible_span(lo, hi) && self.span_cost_below(lo, hi, before - 1e-9) {
            let kept = !self.capped() || {
                let after = self.span_idle(lo, hi);
                self.budget_ok(idle_before, after)
            };
            if kept {
                self.refresh_cache(lo, hi);
                return true;
            }
        }
        undo(&mut self.seq[lo..=hi]);
        self.reindex(lo, hi);
        false
    }

    /// Sets the window sweep's don't-look bits of positions `lo - lookback ..= hi +
    /// lookback` (the surrogate terms a change of `lo..=hi` touches).
    fn wake_span(&mut self, lo: usize, hi: usize) {
        let n = self.seq.len();
        for i in lo.saturating_sub(self.lookback)..=(hi + self.lookback).min(n - 1) {
            self.look_win[self.seq[i].contour] = true;
        }
    }

    /// Whether position `i` is to be examined by the running window sweep.
    fn to_examine_win(&self, i: usize) -> bool {
        let c = self.seq[i].contour;
        self.examine_win[c] || self.look_win[c]
    }

    /// One sweep of Or-opt, 2-opt and pierce re-selection from the positions whose
    /// don't-look bit is set ([`Search::wake_span`]); whether anything improved.
    fn sweep(&mut self, params: &ImproveParams) -> bool {
        let n = self.seq.len();
        let mut improved = false;
        std::mem::swap(&mut self.look_win, &mut self.examine_win);
        self.look_win.fill(false);
        self.refresh_cache(0, n.saturating_sub(1));
        // Pierce re-selection.
        for i in 0..n {
            if !self.to_examine_win(i) {
                continue;
            }
            let c = self.seq[i];
            let k = self.eval.problem.contours[c.contour]
                .pierce_candidates
                .len();
            for alt in 0..k {
                if alt == self.seq[i].pierce {
                    continue;
                }
                let keep = self.seq[i].pierce;
                let before = self.cached_span_cost(i, i);
                debug_assert!((before - self.span_cost(i, i)).abs() <= 1e-6 * (1.0 + before.abs()));
                let idle_before = if self.capped() {
                    self.span_idle(i, i)
                } else {
                    0.0
                };
                self.seq[i].pierce = alt;
                let cheaper = self.span_cost_below(i, i, before - 1e-9);
                let after = if cheaper && self.capped() {
                    self.span_idle(i, i)
                } else {
                    idle_before
                };
                if cheaper && (!self.capped() || self.budget_ok(idle_before, after)) {
                    self.refresh_cache(i, i);
                    self.wake_span(i, i);
                    improved = true;
                } else {
                    self.seq[i].pierce = keep;
                }
            }
        }
        // Or-opt: move run i..i+len after position j (forward) or before j (backward).
        for len in 1..=params.or_opt_max_len.min(n) {
            let mut i = 0;
            while i + len <= n {
                if !self.to_examine_win(i) {
                    i += 1;
                    continue;
                }
                for j in (i + len)..(i + len + params.window).min(n) {
                    let (lo, hi) = (i, j);
                    // Run lo..lo+len moves after hi.
                    let delta = self.swap_blocks_idle_delta(lo, lo + len, hi);
                    if self.try_move(lo, hi, delta, &|s| s.rotate_left(len), &|s| {
                        s.rotate_right(len)
                    }) {
                        self.wake_span(lo, hi);
                        improved = true;
                        break;
                    }
                }
                for j in i.saturating_sub(params.window)..i {
                    let (lo, hi) = (j, i + len - 1);
                    // Run hi-len+1..=hi moves before lo.
                    let delta = self.swap_blocks_idle_delta(lo, hi + 1 - len, hi);
                    if self.try_move(lo, hi, delta, &|s| s.rotate_right(len), &|s| {
                        s.rotate_left(len)
                    }) {
                        self.wake_span(lo, hi);
                        improved = true;
                        break;
                    }
                }
                i += 1;
            }
        }
        // 2-opt: reverse i..=j.
        for i in 0..n {
            if !self.to_examine_win(i) {
                continue;
            }
            for j in (i + 1)..(i + 1 + params.window).min(n) {
                let delta = self.reverse_idle_delta(i, j);
                if self.try_move(i, j, delta, &|s| s.reverse(), &|s| s.reverse()) {
                    self.wake_span(i, j);
                    improved = true;
                }
            }
        }
        debug_assert_eq!(
            self.eval.problem.precedence.check_order(&self.order()),
            Ok(())
        );
        improved
    }

    fn order(&self) -> Vec<ContourId> {
        self.seq.iter().map(|c| c.contour).collect()
    }

    /// Local search to a local optimum (module docs, step 1): from every position if `full`,
    /// else from those whose don't-look bits are set.
    fn local_search(&mut self, params: &ImproveParams, full: bool, deadline: &dyn Fn() -> bool) {
        if deadline() {
            return;
        }
        if full {
            self.wake_all();
        }
        if self.proxy_w == 0.0 {
            // Idle cost only: neighbour-list moves with O(1) deltas, to a local optimum.
            for _ in 0..params.local_sweeps * 8 {
                if !self.neighbour_sweep() || deadline() {
                    break;
                }
            }
        }
        self.idle = self.span_idle(0, self.seq.len().saturating_sub(1));
        for _ in 0..params.local_sweeps {
            if !self.sweep(params) || deadline() {
                break;
            }
        }
    }

    /// Point at position `i`, with −1 and `n` the start point.
    fn pt(&self, i: isize) -> Point {
        if i < 0 {
            self.eval.problem.start
        } else {
            self.point(i as usize)
        }
    }

    /// Applies `apply` to `lo..=hi` if it is feasible (else undoes it with `undo`).
    fn commit_if_feasible(
        &mut self,
        lo: usize,
        hi: usize,
        apply: &dyn Fn(&mut [Cut]),
        undo: &dyn Fn(&mut [Cut]),
    ) -> bool {
        apply(&mut self.seq[lo..=hi]);
        self.reindex(lo, hi);
        if self.feasible_span(lo, hi) {
            return true;
        }
        undo(&mut self.seq[lo..=hi]);
        self.reindex(lo, hi);
        false
    }

    /// Sets the don't-look bit of the contour at position `i` (−1 and `n`: the start).
    fn wake(&mut self, i: isize) {
        let n = self.seq.len() as isize;
        if i < 0 || i >= n {
            let start = self.look.len() - 1;
            self.look[start] = true;
        } else {
            self.look[self.seq[i as usize].contour] = true;
            self.wake_span(i as usize, i as usize);
        }
    }

    /// Sets the don't-look bits around contour `c` (`n`, past the last contour: the start),
    /// as [`Search::wake`] does at its position.
    fn wake_contour(&mut self, c: ContourId) {
        if c < self.seq.len() {
            self.wake(self.pos[c] as isize);
        } else {
            self.wake(-1);
        }
    }

    /// Whether the contour at position `i` (−1: the start) is to be examined this sweep.
    fn to_examine(&self, i: isize) -> bool {
        let c = if i < 0 {
            self.look.len() - 1
        } else {
            self.seq[i as usize].contour
        };
        self.examine[c] || self.look[c]
    }

    /// Marks every contour for examination (a fresh local search).
    fn wake_all(&mut self) {
        self.look.fill(true);
        self.look_win.fill(true);
    }

    /// One sweep of 2-opt and Or-opt over spatial neighbour lists (any sequence distance),
    /// idle-length deltas in O(1); only valid without the heat proxy. Only contours whose
    /// don't-look bit is set are examined; a move sets the bits at the ends of the edges it
    /// changes. Whether it improved.
    fn neighbour_sweep(&mut self) -> bool {
        let n = self.seq.len() as isize;
        let mut improved = false;
        let eps = 1e-9;
        std::mem::swap(&mut self.look, &mut self.examine);
        self.look.fill(false);
        // 2-opt: new edges P(a)–P(b) and P(a+1)–P(b+1), reversing a+1..=b.
        for a in -1..n - 1 {
            if !self.to_examine(a) {
                continue;
            }
            let ca = if a < 0 {
                None
            } else {
                Some(self.seq[a as usize].contour)
            };
            let near_len = match ca {
                Some(c) => self.near[c].len(),
                None => self.near_start.len(),
            };
            for t in 0..near_len {
                let v = match ca {
                    Some(c) => self.near[c][t],
                    None => self.near_start[t],
                };
                let b = self.pos[v] as isize;
                let (e1, e2) = if b > a { (a, b) } else { (b, a) };
                if e2 - e1 < 2 {
                    continue;
                }
                let delta = dist(self.pt(e1), self.pt(e2)) + dist(self.pt(e1 + 1), self.pt(e2 + 1))
                    - dist(self.pt(e1), self.pt(e1 + 1))
                    - dist(self.pt(e2), self.pt(e2 + 1));
                if delta < -eps
                    && self.commit_if_feasible(
                        (e1 + 1) as usize,
                        e2 as usize,
                        &|s| s.reverse(),
                        &|s| s.reverse(),
                    )
                {
                    for i in [e1, e1 + 1, e2, e2 + 1] {
                        self.wake(i);
                    }
                    improved = true;
                    break;
                }
            }
        }
        // Or-opt: move seq[i..i+len] between q and q+1, either way round.
        for len in 1..=3isize {
            let mut i = 0isize;
            while i + len <= n {
                if !self.to_examine(i) {
                    i += 1;
                    continue;
                }
                let first = self.seq[i as usize].contour;
                let (pf, pl) = (self.pt(i), self.pt(i + len - 1));
                let (pp, pn) = (
                    self.pt(i - 1),
                    self.pt(if i + len == n { -1 } else { i + len }),
                );
                let gain = dist(pp, pf) + dist(pl, pn) - dist(pp, pn);
                // The contour at a position (−1 and `n`: the start, as index `n`).
                let contour_at = |s: &Self, p: isize| {
                    if p < 0 || p >= n {
                        n as usize
                    } else {
                        s.seq[p as usize].contour
                    }
                };
                // The contours at the ends of the edges a move here changes.
                let ends = [i, i + len - 1, i - 1, i + len].map(|p| contour_at(self, p));
                let mut done = false;
                for t in 0..self.near[first].len() {
                    let v = self.near[first][t];
                    let b = self.pos[v] as isize;
                    for q in [b, b - 1] {
                        if q >= i - 1 && q < i + len {
                            continue;
                        }
                        let (qa, qb) = (self.pt(q), self.pt(if q + 1 == n { -1 } else { q + 1 }));
                        let fwd = dist(qa, pf) + dist(pl, qb) - dist(qa, qb);
                        let rev = dist(qa, pl) + dist(pf, qb) - dist(qa, qb);
                        let (add, reversed) = if rev < fwd { (rev, true) } else { (fwd, false) };
                        if add - gain >= -eps {
                            continue;
                        }
                        let l = len as usize;
                        let q_ends = [q, q + 1].map(|p| contour_at(self, p));
                        let ok = if q > i {
                            let (lo, hi) = (i as usize, q as usize);
                            self.commit_if_feasible(
                                lo,
                                hi,
                                &|s: &mut [Cut]| {
                                    s.rotate_left(l);
                                    if reversed {
                                        let m = s.len();
                                        s[m - l..].reverse();
                                    }
                                },
                                &|s: &mut [Cut]| {
                                    if reversed {
                                        let m = s.len();
                                        s[m - l..].reverse();
                                    }
                                    s.rotate_right(l);
                                },
                            )
                        } else {
                            let (lo, hi) = ((q + 1) as usize, (i + len - 1) as usize);
                            self.commit_if_feasible(
                                lo,
                                hi,
                                &|s: &mut [Cut]| {
                                    s.rotate_right(l);
                                    if reversed {
                                        s[..l].reverse();
                                    }
                                },
                                &|s: &mut [Cut]| {
                                    if reversed {
                                        s[..l].reverse();
                                    }
                                    s.rotate_left(l);
                                },
                            )
                        };
                        if ok {
                            for c in ends.into_iter().chain(q_ends) {
                                self.wake_contour(c);
                            }
                            improved = true;
                            done = true;
                            break;
                        }
                    }
                    if done {
                        break;
                    }
                }
                i += 1;
            }
        }
        debug_assert_eq!(
            self.eval.problem.precedence.check_order(&self.order()),
            Ok(())
        );
        improved
    }

    /// One remove-and-reinsert step; `false` (and the order unchanged) if no feasible
    /// reinsertion was found.
    fn lns_step(&mut self, rng: &mut ChaCha8Rng, k: usize) -> bool {
        let n = self.seq.len();
        if n < 2 {
            return false;
        }
        let problem = self.eval.problem;
        let rules = &problem.precedence;
        let seed_pos = rng.random_range(0..n);
        let sp = self.point(seed_pos);
        // The k cuts nearest the seed (ties by position: deterministic).
        let mut by_dist: Vec<(f64, usize)> = (0..n).map(|i| (dist(sp, self.point(i)), i)).collect();
        let k = k.min(n - 1).max(1);
        by_dist.select_nth_unstable_by(k - 1, |a, b| {
            a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal)
        });
        let mut removed: Vec<usize> = by_dist[..k].iter().map(|&(_, i)| i).collect();
        removed.sort_unstable();
        let saved = self.seq.clone();
        let out: Vec<Cut> = removed.iter().map(|&i| self.seq[i]).collect();
        let mut is_removed = vec![false; problem.contours.len()];
        for c in &out {
            is_removed[c.contour] = true;
        }
        self.seq.retain(|c| !is_removed[c.contour]);
        let m = self.seq.len();
        self.reindex(0, m.saturating_sub(1));
        for c in &out {
            let c = c.contour;
            // Feasible insertion indices q (insert before seq[q]).
            let lo = rules.predecessors[c]
                .iter()
                .filter(|&&p| !is_removed[p])
                .map(|&p| self.pos[p] + 1)
                .max()
                .unwrap_or(0);
            let hi = self.successors[c]
                .iter()
                .filter(|&&s| !is_removed[s])
                .map(|&s| self.pos[s])
                .min()
                .unwrap_or(self.seq.len());
            let run = self.group_of[c].and_then(|g| {
                let present: Vec<usize> = rules.groups[g]
                    .iter()
                    .filter(|&&x| x != c && !is_removed[x])
                    .map(|&x| self.pos[x])
                    .collect();
                (!present.is_empty()).then(|| {
                    (
                        *present.iter().min().unwrap_or(&0),
                        *present.iter().max().unwrap_or(&0) + 1,
                    )
                })
            });
            let (lo, hi) = match run {
                Some((a, b)) => (lo.max(a), hi.min(b)),
                None => (lo, hi),
            };
            let mut best: Option<(f64, usize, usize)> = None;
            for q in lo..=hi.min(self.seq.len()) {
                // Not strictly inside another group's run.
                if q > 0 && q < self.seq.len() {
                    let (a, b) = (
                        self.group_of[self.seq[q - 1].contour],
                        self.group_of[self.seq[q].contour],
                    );
                    if a.is_some() && a == b && a != self.group_of[c] {
                        continue;
                    }
                }
                let prev = if q == 0 {
                    problem.start
                } else {
                    self.point(q - 1)
                };
                let next = self.point(q);
                for (kk, &p) in problem.contours[c].pierce_candidates.iter().enumerate() {
                    let cut = Cut {
                        contour: c,
                        pierce: kk,
                    };
                    let mut d = dist(prev, p) + dist(p, next) - dist(prev, next)
                        + self.eval.corner_penalty(cut);
                    if self.proxy_w > 0.0 {
                        let mut gap = 0.0;
                        for mm in 1..=self.lookback.min(q) {
                            let j = self.seq[q - mm].contour;
                            d += self.proxy_pair(j, cut, gap + self.half(j));
                            gap += self.cut_len[j];
                        }
                        let mut gap = self.half(c);
                        for mm in 1..=self.lookback.min(self.seq.len() - q) {
                            let j = self.seq[q + mm - 1];
                            d += self.proxy_pair(c, j, gap);
                            gap += self.cut_len[j.contour];
                        }
                    }
                    if best.is_none_or(|b| d < b.0) {
                        best = Some((d, q, kk));
                    }
                }
            }
            let Some((_, q, kk)) = best else {
                self.seq = saved;
                let n = self.seq.len();
                self.reindex(0, n - 1);
                return false;
            };
            self.seq.insert(
                q,
                Cut {
                    contour: c,
                    pierce: kk,
                },
            );
            is_removed[c] = false;
            let len = self.seq.len();
            self.reindex(q, len - 1);
        }
        if rules.check_order(&self.order()).is_err() {
            self.seq = saved;
            let n = self.seq.len();
            self.reindex(0, n - 1);
            return false;
        }
        // Wake the ends of every edge the step changed (for both sweeps); `n` is the start.
        let at = |seq: &[Cut], i: usize| seq.get(i).map_or(n, |c| c.contour);
        let mut changed: Vec<usize> = Vec::with_capacity(3 * out.len() + 2 * removed.len());
        for &i in &removed {
            changed.push(at(&saved, i.wrapping_sub(1)));
            changed.push(at(&saved, i + 1));
        }
        for c in &out {
            let p = self.pos[c.contour];
            for i in [p.wrapping_sub(1), p, p + 1] {
                changed.push(at(&self.seq, i));
            }
        }
        for c in changed {
            self.wake_contour(c);
        }
        true
    }
}

/// Improves `start` (module docs), calling `feedback` after every LNS iteration.
///
/// # Errors
/// An invalid [`ImproveParams`] field, or a start plan naming a contour or pierce candidate
/// the problem does not have (field `start.cuts`).
pub fn improve(
    eval: &Evaluator,
    start: &CutPlan,
    params: &ImproveParams,
    feedback: impl FnMut(Progress),
) -> Result<CutPlan, ParamError> {
    improve_until(eval, start, params, feedback, &|| false)
}

/// As [`improve`], stopping early once `stop` returns true (polled between moves and LNS
/// iterations, e.g. an action's cancel flag): the search ends, and the best order so far gets
/// its true evaluation (still never worse than `start`).
///
/// # Errors
/// As [`improve`].
pub fn improve_until(
    eval: &Evaluator,
    start: &CutPlan,
    params: &ImproveParams,
    feedback: impl FnMut(Progress),
    stop: &dyn Fn() -> bool,
) -> Result<CutPlan, ParamError> {
    improve_until_with(eval, start, params, feedback, stop, |cuts| {
        eval.evaluate(cuts)
    })
}

/// As [`improve_until`], with the best order's evaluation left to `run_best` (as in
/// [`improve_cuts_until_with`]): called at most once, and not when the best order is the
/// start order.
///
/// # Errors
/// As [`improve`].
pub fn improve_until_with(
    eval: &Evaluator,
    start: &CutPlan,
    params: &ImproveParams,
    feedback: impl FnMut(Progress),
    stop: &dyn Fn() -> bool,
    run_best: impl FnOnce(&[Cut]) -> CutPlan,
) -> Result<CutPlan, ParamError> {
    if !searchable(eval, &start.cuts, params)? {
        return Ok(start.clone());
    }
    let best = search(eval, &start.cuts, params, feedback, stop);
    // The start order again: its true cost is known, no raster run needed.
    if best == start.cuts {
        return Ok(start.clone());
    }
    let plan = run_best(&best);
    Ok(if plan.cost <= start.cost {
        plan
    } else {
        start.clone()
    })
}

/// As [`improve_until`] from a start order whose true cost is not known yet (e.g. the
/// nearest-pierce order of [`crate::policy::construct_cuts`]): the start's raster run goes on
/// a second thread alongside the search and then the best order's own run (unless the best
/// is the start order), so the wall time is about the search plus one raster run. Returns
/// the evaluated start plan and the improved plan (never worse than the start). Same results
/// as [`crate::cost::Evaluator::evaluate`] then [`improve_until`].
///
/// # Errors
/// As [`improve`] (field `start.cuts`).
pub fn improve_cuts_until(
    eval: &Evaluator,
    start: &[Cut],
    params: &ImproveParams,
    feedback: impl FnMut(Progress),
    stop: &dyn Fn() -> bool,
) -> Result<(CutPlan, CutPlan), ParamError> {
    improve_cuts_until_with(eval, start, params, feedback, stop, |cuts| {
        eval.evaluate(cuts)
    })
}

/// As [`improve_cuts_until`], with the best order's evaluation left to `run_best` (which must
/// return [`Evaluator::evaluate`]'s plan), e.g. a raster run that streams frames. It is
/// called at most once, on this thread, and not when the best order is the start order.
///
/// # Errors
/// As [`improve`] (field `start.cuts`).
pub fn improve_cuts_until_with(
    eval: &Evaluator,
    start: &[Cut],
    params: &ImproveParams,
    feedback: impl FnMut(Progress),
    stop: &dyn Fn() -> bool,
    run_best: impl FnOnce(&[Cut]) -> CutPlan,
) -> Result<(CutPlan, CutPlan), ParamError> {
    if !searchable(eval, start, params)? {
        let plan = eval.evaluate(start);
        return Ok((plan.clone(), plan));
    }
    // The start's run goes on a second thread and may still be running while the best
    // order's run goes on this one: the wall time is the search plus one raster run.
    let (start_plan, best_plan) = std::thread::scope(|scope| {
        let start_run = scope.spawn(|| eval.evaluate(start));
        let best = search(eval, start, params, feedback, stop);
        let best_plan = (best != start).then(|| run_best(&best));
        let start_plan = match start_run.join() {
            Ok(plan) => plan,
            Err(panic) => std::panic::resume_unwind(panic),
        };
        (start_plan, best_plan)
    });
    let better = match best_plan {
        Some(plan) if plan.cost <= start_plan.cost => plan,
        _ => start_plan.clone(),
    };
    Ok((start_plan, better))
}

/// Checks the parameters and the start order; whether there is anything to search (at least
/// two cuts in a feasible order).
fn searchable(eval: &Evaluator, start: &[Cut], params: &ImproveParams) -> Result<bool, ParamError> {
    params.validate()?;
    let problem = eval.problem;
    if let Some(c) = start.iter().find(|c| {
        problem
            .contours
            .get(c.contour)
            .is_none_or(|k| c.pierce >= k.pierce_candidates.len())
    }) {
        return Err(ParamError::Invalid {
            field: "start.cuts",
            value: format!("{c:?}"),
            reason: "names a contour or pierce candidate the problem does not have",
        });
    }
    let order: Vec<ContourId> = start.iter().map(|c| c.contour).collect();
    Ok(start.len() >= 2 && problem.precedence.check_order(&order).is_ok())
}

/// The search of [`improve_until`] (module docs, steps 1 and 2) from a feasible start order
/// ([`searchable`]): the best order found, polished.
fn search(
    eval: &Evaluator,
    start: &[Cut],
    params: &ImproveParams,
    mut feedback: impl FnMut(Progress),
    stop: &dyn Fn() -> bool,
) -> Vec<Cut> {
    let problem = eval.problem;
    let n = problem.contours.len();
    let t0 = Instant::now();
    let budget = params.time_budget_ms;
    let deadline = || stop() || (budget > 0 && t0.elapsed().as_millis() as u64 >= budget);
    let mut s = Search::new(eval, start, params);
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed);
    s.local_search(params, true, &deadline);
    let mut cur = s.total();
    let mut best = (cur, s.seq.clone());
    for iteration in 0..params.max_iterations {
        if deadline() {
            break;
        }
        let saved = s.seq.clone();
        if s.lns_step(&mut rng, params.lns_remove) {
            if s.proxy_w == 0.0 {
                // Cheap O(1)-delta moves: polish every perturbation (iterated local search).
                for _ in 0..20 {
                    if !s.neighbour_sweep() {
                        break;
                    }
                }
            }
            let cost = s.total();
            let idle = s.span_idle(0, n - 1);
            if cost <= cur + 1e-9 && (idle <= s.idle_cap || idle <= s.idle) {
                cur = cost;
                s.idle = idle;
                if cost < best.0 - 1e-9 {
                    best = (cost, s.seq.clone());
                }
            } else {
                s.seq = saved;
                s.reindex(0, n - 1);
            }
        }
        feedback(Progress {
            iteration: iteration + 1,
            best_cost: best.0,
        });
    }
    // Polish the best order.
    s.seq = best.1;
    s.reindex(0, n - 1);
    s.local_search(params, false, &deadline);
    debug_assert_eq!(problem.precedence.check_order(&s.order()), Ok(()));
    s.seq
}

impl<'e, 'p> Search<'e, 'p> {
    /// The search state at `start` (a feasible order of `eval`'s problem): neighbour lists,
    /// heat-proxy tables, positions and the idle budget.
    fn new(eval: &'e Evaluator<'p>, start: &[Cut], params: &ImproveParams) -> Self {
        let problem = eval.problem;
        let n = problem.contours.len();
        let mut successors = vec![Vec::new(); n];
        for (c, preds) in problem.precedence.predecessors.iter().enumerate() {
            for &p in preds {
                successors[p].push(c);
            }
        }
        let bbox: Vec<[f64; 4]> = problem
            .contours
            .iter()
            .map(|c| {
                c.points
                    .iter()
                    .fold([f64::MAX, f64::MAX, f64::MIN, f64::MIN], |b, p| {
                        [
                            b[0].min(p[0]),
                            b[1].min(p[1]),
                            b[2].max(p[0]),
                            b[3].max(p[1]),
                        ]
                    })
            })
            .collect();
        let centre = |b: &[f64; 4]| [(b[0] + b[2]) / 2.0, (b[1] + b[3]) / 2.0];
        let nearest_to = |p: Point, skip: Option<usize>, k: usize| {
            let mut d: Vec<(f64, usize)> = bbox
                .iter()
                .enumerate()
                .filter(|&(j, _)| Some(j) != skip)
                .map(|(j, b)| (dist(p, centre(b)), j))
                .collect();
            let k = k.min(d.len());
            if k > 0 && k < d.len() {
                d.select_nth_unstable_by(k - 1, |a, b| {
                    a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal)
                });
            }
            d.truncate(k);
            d.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
            d.into_iter().map(|(_, j)| j).collect::<Vec<_>>()
        };
        let near = (0..n)
            .map(|c| nearest_to(centre(&bbox[c]), Some(c), NEAR_IDLE))
            .collect();
        let near_start = nearest_to(problem.start, None, NEAR_IDLE);
        let (exposure, pierce_near) = if eval.cost_params().thermal {
            let wide: Vec<Vec<ContourId>> = (0..n)
                .map(|c| nearest_to(centre(&bbox[c]), Some(c), PROXY_NEAR))
                .collect();
            let tp = eval.thermal_params();
            let reach = (tp.overheat_radius_cells as f64 + 1.0) * tp.cell_mm;
            (
                exposure_table(eval, &wide, params.proxy_radius_mm),
                pierce_table(eval, &wide, reach),
            )
        } else {
            (vec![Vec::new(); n], Vec::new())
        };
        let tp = eval.thermal_params();
        // Steps for a kerf at t_melt to decay below t_max by k_loss alone, as mm of cutting.
        let hot_mm = if tp.k_loss < 1.0 {
            f64::from((tp.t_melt_c - tp.ambient_c) / (tp.t_max_c - tp.ambient_c)).ln()
                / -f64::from(tp.k_loss).ln()
                * tp.cell_mm
        } else {
            f64::INFINITY
        };
        let related = (0..n)
            .map(|b| {
                let mut bits = 0u64;
                for &(a, _) in &exposure[b] {
                    bits |= 1u64 << (a % 64);
                }
                for &a in pierce_near.get(b).into_iter().flatten().flatten() {
                    bits |= 1u64 << (a % 64);
                }
                bits
            })
            .collect();
        let mut s = Search {
            related,
            near,
            near_start,
            eval,
            seq: start.to_vec(),
            pos: vec![0; n],
            group_of: problem.precedence.group_of(),
            successors,
            proxy_w: if eval.cost_params().thermal {
                eval.cost_params().w_overheat_mm * params.proxy_weight
            } else {
                0.0
            },
            cut_len: problem
                .contours
                .iter()
                .map(|c| {
                    c.perimeter()
                        + eval.thermal_params().pierce_dwell_s
                            * eval.thermal_params().cut_speed_mm_s
                })
                .collect(),
            decay_per_mm: std::f64::consts::LN_2 / params.proxy_half_life_mm,
            exposure,
            lookback: params.proxy_lookback,
            idle: 0.0,
            idle_cap: f64::INFINITY,
            look: vec![true; n + 1],
            examine: vec![false; n + 1],
            look_win: vec![true; n],
            examine_win: vec![false; n],
            proxy_term: vec![0.0; n],
            proxy_sum: vec![0.0; n + 1],
            term_cache: vec![0.0; n + 1],
            term_sum: vec![0.0; n + 2],
            pierce_near,
            hot_mm,
            pierce_w: (eval.cost_params().w_overheat_mm + eval.cost_params().hot_penalty_mm)
                * params.proxy_weight,
        };
        s.reindex(0, n - 1);
        s.idle = s.span_idle(0, n - 1);
        if eval.cost_params().thermal && params.idle_budget > 0.0 {
            if let Ok(nn) = crate::policy::nearest_cuts(eval) {
                s.idle_cap = params.idle_budget * crate::plan::idle_length(problem, &nn);
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cost::CostParams;
    use crate::fixtures::{grid, scattered};
    use crate::policy::{construct, Policy};
    use crate::precedence::PrecedenceMode;
    use crate::thermal::ThermalParams;
    use proptest::prelude::*;

    fn quick() -> ImproveParams {
        ImproveParams {
            max_iterations: 30,
            local_sweeps: 2,
            ..Default::default()
        }
    }

    /// The O(1) idle deltas the window sweep prunes with equal the idle change of the moves
    /// themselves (a wrong delta would drop improving moves unseen).
    #[test]
    fn move_idle_deltas_match_the_moves() {
        let problem = scattered(40, 9);
        let eval =
            Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
        let start = construct(&eval, Policy::Random, 5).unwrap();
        let mut s = Search::new(&eval, &start.cuts, &quick());
        let n = s.seq.len();
        let idle = |s: &Search| s.span_idle(0, n - 1);
        let before = idle(&s);
        for (lo, split, hi) in [
            (0, 1, 5),
            (3, 6, 20),
            (10, 13, 39),
            (0, 20, 39),
            (38, 39, 39),
        ] {
            let delta = s.swap_blocks_idle_delta(lo, split, hi);
            s.seq[lo..=hi].rotate_left(split - lo);
            assert!(
                (idle(&s) - before - delta).abs() < 1e-9,
                "{lo} {split} {hi}"
            );
            s.seq[lo..=hi].rotate_right(split - lo);
        }
        for (lo, hi) in [(0, 4), (7, 30), (20, 39), (0, 39)] {
            let delta = s.reverse_idle_delta(lo, hi);
            s.seq[lo..=hi].reverse();
            assert!((idle(&s) - before - delta).abs() < 1e-9, "{lo} {hi}");
            s.seq[lo..=hi].reverse();
        }
    }

    #[test]
    fn thermal_off_improvement_shortens_nearest_neighbour() {
        let problem = scattered(120, 3);
        let cost = CostParams {
            thermal: false,
            ..Default::default()
        };
        let eval = Evaluator::new(&problem, ThermalParams::default(), cost).unwrap();
        let nn = construct(&eval, Policy::Nearest, 0).unwrap();
        let mut reports = 0;
        let better = improve(&eval, &nn, &ImproveParams::default(), |_| reports += 1).unwrap();
        assert_eq!(reports, ImproveParams::default().max_iterations);
        assert!(
            better.idle_mm < 0.97 * nn.idle_mm,
            "{} vs nearest {}",
            better.idle_mm,
            nn.idle_mm
        );
        assert_eq!(problem.precedence.check_order(&better.order()), Ok(()));
    }

    #[test]
    fn improvement_is_deterministic_for_a_seed() {
        let problem = grid(4, 3, 58.0, true, true, PrecedenceMode::Strict);
        let eval =
            Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
        let start = construct(&eval, Policy::Nearest, 0).unwrap();
        let a = improve(&eval, &start, &quick(), |_| {}).unwrap();
        let b = improve(&eval, &start, &quick(), |_| {}).unwrap();
        assert_eq!(a, b);
        assert!(a.cost <= start.cost);
    }

    /// The start's raster run alongside the search gives exactly the sequential results.
    #[test]
    fn concurrent_start_run_matches_the_sequential_one() {
        let problem = grid(3, 3, 58.0, true, true, PrecedenceMode::Strict);
        let eval =
            Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
        let cuts = crate::policy::construct_cuts(&eval, Policy::Nearest, 0).unwrap();
        let start = eval.evaluate(&cuts);
        let (start2, better2) =
            improve_cuts_until(&eval, &cuts, &quick(), |_| {}, &|| false).unwrap();
        assert_eq!(start2, start);
        assert_eq!(better2, improve(&eval, &start, &quick(), |_| {}).unwrap());
        assert!(better2.cost <= start.cost);
        // With nothing to search, the start comes back evaluated.
        let none = ImproveParams {
            max_iterations: 0,
            local_sweeps: 0,
            ..quick()
        };
        let (s3, b3) = improve_cuts_until(&eval, &cuts, &none, |_| {}, &|| false).unwrap();
        assert_eq!(s3, start);
        assert_eq!(b3, start);
    }

    #[test]
    fn bad_params_name_the_field() {
        let problem = grid(1, 1, 60.0, false, false, PrecedenceMode::Strict);
        let eval =
            Evaluator::new(&problem, ThermalParams::default(), CostParams::default()).unwrap();
        let start = construct(&eval, Policy::Nearest, 0).unwrap();
        let p = ImproveParams {
            window: 0,
            ..Default::default()
        };
        let e = improve(&eval, &start, &p, |_| {}).unwrap_err().to_string();
        assert!(e.contains("window"), "{e}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]

        /// Every contour cut once, no precedence violation in either mode, never worse than
        /// the start, and the thermal evaluation is bit-for-bit repeatable.
        #[test]
        fn improvement_keeps_the_rules_and_never_worsens(
            nx in 1usize..4, ny in 1usize..4, nest: bool, free: bool, strict: bool,
            thermal: bool, policy in 0usize..5, seed in 0u64..1000,
        ) {
            let mode = if strict { PrecedenceMode::Strict } else { PrecedenceMode::Relaxed };
            let problem = grid(nx, ny, 57.0, nest, free, mode);
            prop_assert_eq!(problem.precedence.check_acyclic(), Ok(()));
            let cost = CostParams { thermal, ..Default::default() };
            let eval = Evaluator::new(&problem, ThermalParams::default(), cost).unwrap();
            let start = construct(&eval, Policy::ALL[policy], seed).unwrap();
            prop_assert_eq!(problem.precedence.check_order(&start.order()), Ok(()));
            // A thermal policy's own raster run is the evaluator's.
            prop_assert_eq!(&eval.evaluate(&start.cuts), &start);
            let params = ImproveParams { seed, ..quick() };
            let better = improve(&eval, &start, &params, |_| {}).unwrap();
            prop_assert_eq!(better.cuts.len(), problem.contours.len());
            prop_assert_eq!(problem.precedence.check_order(&better.order()), Ok(()));
            prop_assert!(better.cost <= start.cost);
            let again = eval.evaluate(&better.cuts);
            prop_assert_eq!(again.max_temp_c.to_bits(), better.max_temp_c.to_bits());
            prop_assert_eq!(again, better);
        }
    }
}
