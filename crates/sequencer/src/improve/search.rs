//! The search state: the order being improved with its positions, precedence groups and
//! successors, the neighbour lists, the heat-proxy tables, the idle budget and the sweeps'
//! don't-look bits and caches; and the plain queries on it.

use crate::cost::Evaluator;
use crate::plan::Cut;
use crate::problem::{ContourId, Point};

use super::distance::dist;
use super::params::ImproveParams;
use super::proxy::{exposure_table, pierce_table, PROXY_NEAR};

/// Neighbour-list length of the idle-only moves (thermal cost off): 14 rather than 10 gets
/// closer to LKH-3 for some more search time (benches README).
const NEAR_IDLE: usize = 14;

/// The state of one improvement run (module docs).
pub(super) struct Search<'e, 'p> {
    pub(super) eval: &'e Evaluator<'p>,
    pub(super) seq: Vec<Cut>,
    pub(super) pos: Vec<usize>,
    pub(super) group_of: Vec<Option<usize>>,
    pub(super) successors: Vec<Vec<ContourId>>,
    /// The `NEAR_IDLE` contours nearest each contour (bounding-box centres), and the start.
    pub(super) near: Vec<Vec<ContourId>>,
    pub(super) near_start: Vec<ContourId>,
    /// Cut length plus the dwell's equivalent, per contour, mm.
    pub(super) cut_len: Vec<f64>,
    /// Heat retention per mm of cutting: `-ln(k_loss) / cell_mm`.
    pub(super) decay_per_mm: f64,
    pub(super) proxy_w: f64,
    /// `exposure[b]`: `(a, e)` for every contour `a` near `b`, `e` the places of `b` the
    /// overheat metric checks (pierce and segment starts) within `proxy_radius_mm` of `a`.
    pub(super) exposure: Vec<Vec<(ContourId, f64)>>,
    pub(super) lookback: usize,
    /// `pierce_near[b][k]`: contours whose polyline passes through the overheat test's window
    /// of candidate `k` of `b` (empty without the proxy).
    pub(super) pierce_near: Vec<Vec<Vec<ContourId>>>,
    /// `related[b]`: bit `a % 64` set for every contour `a` in `exposure[b]` or any of
    /// `pierce_near[b]` (a quick test that the pair's proxy term is zero).
    pub(super) related: Vec<u64>,
    /// Cutting after which a kerf has cooled below `t_max`, mm (module docs).
    pub(super) hot_mm: f64,
    /// Proxy charge of a pierce next to a hot kerf: one overheat plus the hot-pierce penalty.
    pub(super) pierce_w: f64,
    /// Whether some cut leaves elsewhere than it is pierced (lead-outs): idle edges are then
    /// not the same length backwards ([`Search::neighbour_sweep`]).
    pub(super) asymmetric: bool,
    /// Current idle length, mm (kept up to date by the moves when `idle_cap` is finite).
    pub(super) idle: f64,
    /// Idle budget, mm (`ImproveParams::idle_budget`; infinite without one).
    pub(super) idle_cap: f64,
    /// Don't-look bits of [`Search::neighbour_sweep`] (Bentley's, as in LKH): `look[c]` if an
    /// edge at contour `c` changed since `c` was last examined without finding a move;
    /// index `n` is the start point.
    pub(super) look: Vec<bool>,
    /// The bits being examined by the running sweep (swapped with `look`).
    pub(super) examine: Vec<bool>,
    /// Don't-look bits of [`Search::sweep`], per contour: set for the contours within
    /// `lookback` positions of a change (their surrogate terms changed).
    pub(super) look_win: Vec<bool>,
    /// The bits being examined by the running window sweep (swapped with `look_win`).
    pub(super) examine_win: Vec<bool>,
    /// Heat-proxy part of each position's term, and its prefix sums (`proxy_sum[i]` = the
    /// sum over positions `< i`), kept up to date inside [`Search::sweep`]: a move whose idle
    /// change exceeds the proxy it could at best remove is rejected unseen.
    pub(super) proxy_term: Vec<f64>,
    pub(super) proxy_sum: Vec<f64>,
    /// The same for whole terms (positions `0..=n`), so a move's cost before is a
    /// difference of two prefix sums.
    pub(super) term_cache: Vec<f64>,
    pub(super) term_sum: Vec<f64>,
    /// Per group, the [`Search::feasible_span`] check that last saw one of its runs start.
    pub(super) run_seen: Vec<u64>,
    /// The running [`Search::feasible_span`] check.
    pub(super) run_epoch: u64,
}

impl<'e, 'p> Search<'e, 'p> {
    /// The search state at `start` (a feasible order of `eval`'s problem): neighbour lists,
    /// heat-proxy tables, positions and the idle budget.
    pub(super) fn new(eval: &'e Evaluator<'p>, start: &[Cut], params: &ImproveParams) -> Self {
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
            let d = &mut d[..k];
            d.sort_by(|a, b| a.partial_cmp(b).unwrap_or(std::cmp::Ordering::Equal));
            // Collected from the slice: `into_iter().collect()` would keep the whole
            // n-entry buffer per list (in-place collection), ~80 KB each at 5000 contours.
            d.iter().map(|&(_, j)| j).collect::<Vec<_>>()
        };
        let near = (0..n)
            .map(|c| nearest_to(centre(&bbox[c]), Some(c), NEAR_IDLE))
            .collect();
        let near_start = nearest_to(problem.start, None, NEAR_IDLE);
        let (exposure, pierce_near) = if eval.cost_params().thermal {
            let wide: Vec<Vec<ContourId>> = (0..n)
                .map(|c| nearest_to(centre(&bbox[c]), Some(c), PROXY_NEAR))
                .collect();
            (
                exposure_table(eval, &wide, params.proxy_radius_mm),
                pierce_table(eval, &wide),
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
        let asymmetric = problem.contours.iter().any(|c| {
            c.pierce_candidates
                .iter()
                .enumerate()
                .any(|(k, &p)| dist(c.exit(k), p) > 1e-12)
        });
        let mut s = Search {
            asymmetric,
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
            run_seen: vec![0; problem.precedence.groups.len()],
            run_epoch: 0,
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

impl Search<'_, '_> {
    pub(super) fn point(&self, i: usize) -> Point {
        if i == usize::MAX || i >= self.seq.len() {
            self.eval.problem.start
        } else {
            self.seq[i].point(self.eval.problem)
        }
    }

    /// Where the tool leaves the cut at position `i` (its lead-out's end; without leads its
    /// pierce point), the start for `usize::MAX` and `n`: idle edges run from here.
    pub(super) fn exit(&self, i: usize) -> Point {
        if i == usize::MAX || i >= self.seq.len() {
            self.eval.problem.start
        } else {
            self.seq[i].exit(self.eval.problem)
        }
    }

    /// Point at position `i`, with −1 and `n` the start point.
    pub(super) fn pt(&self, i: isize) -> Point {
        if i < 0 {
            self.eval.problem.start
        } else {
            self.point(i as usize)
        }
    }

    pub(super) fn order(&self) -> Vec<ContourId> {
        self.seq.iter().map(|c| c.contour).collect()
    }

    /// Idle length of the edges into positions `lo..=hi + 1` (`n`: the return to start), mm.
    pub(super) fn span_idle(&self, lo: usize, hi: usize) -> f64 {
        let end = (hi + 1).min(self.seq.len());
        (lo..=end)
            .map(|i| {
                let prev = if i == 0 { usize::MAX } else { i - 1 };
                dist(self.exit(prev), self.point(i))
            })
            .sum()
    }

    /// Whether a change of the idle length from `self.idle` by `before → after` (over a span)
    /// keeps the idle budget: within it, or shorter than before. Updates `self.idle` if so.
    pub(super) fn budget_ok(&mut self, before: f64, after: f64) -> bool {
        let new = self.idle - before + after;
        if new <= self.idle_cap || after <= before {
            self.idle = new;
            true
        } else {
            false
        }
    }

    pub(super) fn capped(&self) -> bool {
        self.idle_cap.is_finite()
    }

    pub(super) fn reindex(&mut self, lo: usize, hi: usize) {
        for i in lo..=hi {
            self.pos[self.seq[i].contour] = i;
        }
    }

    /// Local feasibility after permuting `lo..=hi` of a feasible order (module docs): no
    /// contour of the span before one of its predecessors, and every group still one run.
    ///
    /// The order outside the span is unchanged and was feasible, so whether a position starts
    /// a group's run can only have changed at `lo..=hi + 1`. There a group may start a run at
    /// most once, and not at all if its run covers `lo − 1`: O(span), however large the
    /// groups (a perforated panel's group holds hundreds of contours).
    pub(super) fn feasible_span(&mut self, lo: usize, hi: usize) -> bool {
        let rules = &self.eval.problem.precedence;
        for i in lo..=hi {
            let c = self.seq[i].contour;
            if rules.predecessors[c].iter().any(|&p| self.pos[p] > i) {
                return false;
            }
        }
        if rules.groups.is_empty() {
            return true;
        }
        self.run_epoch += 1;
        let epoch = self.run_epoch;
        let group_at = |i: usize| self.group_of[self.seq[i].contour];
        let covering = if lo > 0 { group_at(lo - 1) } else { None };
        for p in lo..=(hi + 1).min(self.seq.len() - 1) {
            let Some(g) = group_at(p) else { continue };
            if p > 0 && group_at(p - 1) == Some(g) {
                continue;
            }
            // A run of `g` starts at `p`.
            if covering == Some(g) || self.run_seen[g] == epoch {
                return false;
            }
            self.run_seen[g] = epoch;
        }
        true
    }
}
