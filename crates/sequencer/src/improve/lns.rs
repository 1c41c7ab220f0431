//! The large-neighbourhood search (module docs, step 2): remove the cuts nearest a random seed
//! cut and reinsert them, each at its cheapest feasible position and pierce candidate; and the
//! whole search, local search then LNS then a final polish.

use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::cost::Evaluator;
use crate::plan::Cut;

use super::distance::dist;
use super::params::ImproveParams;
use super::search::Search;
use super::Progress;

impl Search<'_, '_> {
    /// One remove-and-reinsert step: the positions `[a, b]` it changed (the order outside them
    /// is as before), or `None` (and the order unchanged) if no feasible reinsertion was
    /// found.
    pub(super) fn lns_step(&mut self, rng: &mut ChaCha8Rng, k: usize) -> Option<[usize; 2]> {
        let n = self.seq.len();
        if n < 2 {
            return None;
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
                    self.exit(q - 1)
                };
                let next = self.point(q);
                for (kk, &p) in problem.contours[c].pierce_candidates.iter().enumerate() {
                    let cut = Cut {
                        contour: c,
                        pierce: kk,
                    };
                    let out = problem.contours[c].exit(kk);
                    let mut d = dist(prev, p) + dist(out, next) - dist(prev, next)
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
                return None;
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
        // Only positions a..=b changed: the local check is exact (`feasible_span`).
        let (mut a, mut b) = (removed[0], removed[removed.len() - 1]);
        for c in &out {
            a = a.min(self.pos[c.contour]);
            b = b.max(self.pos[c.contour]);
        }
        if !self.feasible_span(a, b) {
            self.seq = saved;
            self.reindex(a, b);
            return None;
        }
        debug_assert_eq!(rules.check_order(&self.order()), Ok(()));
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
        Some([a, b])
    }
}

/// The search of [`improve`](super::improve) (module docs, steps 1 and 2) from a feasible
/// start order ([`searchable`](super::searchable)): the best order found, polished.
pub(super) fn search(
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
    // With the heat proxy a step's cost is the cached terms outside the positions it changed
    // plus the changed ones recomputed (a whole sum would cost O(n · proxy_lookback) per
    // step); the polish of the idle-only search changes any position, so it sums them all.
    let incremental = s.proxy_w > 0.0;
    if incremental {
        s.refresh_cache(0, n - 1);
    }
    let mut cur = if incremental {
        s.term_sum[n + 1]
    } else {
        s.total()
    };
    let mut best = (cur, s.seq.clone());
    for iteration in 0..params.max_iterations {
        if deadline() {
            break;
        }
        let saved = s.seq.clone();
        if let Some([a, b]) = s.lns_step(&mut rng, params.lns_remove) {
            let cost = if incremental {
                let end = s.span_end(b);
                s.term_sum[a] + s.span_cost(a, b) + (s.term_sum[n + 1] - s.term_sum[end + 1])
            } else {
                // Cheap O(1)-delta moves: polish every perturbation (iterated local search).
                for _ in 0..20 {
                    if !s.neighbour_sweep() {
                        break;
                    }
                }
                s.total()
            };
            debug_assert!((cost - s.total()).abs() <= 1e-6 * (1.0 + cost.abs()));
            let idle = s.span_idle(0, n - 1);
            if cost <= cur + 1e-9 && (idle <= s.idle_cap || idle <= s.idle) {
                s.idle = idle;
                cur = if incremental {
                    s.refresh_cache(a, b);
                    s.term_sum[n + 1]
                } else {
                    cost
                };
                if cur < best.0 - 1e-9 {
                    best = (cur, s.seq.clone());
                }
            } else {
                s.seq = saved;
                if incremental {
                    s.reindex(a, b);
                } else {
                    s.reindex(0, n - 1);
                }
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
