//! The moves of the local search on a span `lo..=hi` of the order: Or-opt (swap two adjacent
//! blocks) and 2-opt (reverse a run), their O(1) idle deltas, and applying a move with its
//! local feasibility check, kept or undone.

use crate::plan::Cut;

use super::distance::dist;
use super::search::Search;

impl Search<'_, '_> {
    /// The idle change of swapping the blocks `lo..split` and `split..=hi` (an Or-opt move),
    /// from the three edges it replaces.
    pub(super) fn swap_blocks_idle_delta(&self, lo: usize, split: usize, hi: usize) -> f64 {
        let (l, f, h) = (lo as isize, split as isize, hi as isize);
        self.edge(l - 1, f) + self.edge(h, l) + self.edge(f - 1, h + 1)
            - self.edge(l - 1, l)
            - self.edge(f - 1, f)
            - self.edge(h, h + 1)
    }

    /// The idle change of reversing `lo..=hi` (a 2-opt move): two edges replaced, the ones
    /// inside keep their lengths.
    pub(super) fn reverse_idle_delta(&self, lo: usize, hi: usize) -> f64 {
        let (l, h) = (lo as isize, hi as isize);
        self.edge(l - 1, h) + self.edge(l, h + 1) - self.edge(l - 1, l) - self.edge(h, h + 1)
    }

    /// Idle length of the edge from position `a` (its exit) to position `b` (its pierce
    /// point); −1 and `n`: the start.
    pub(super) fn edge(&self, a: isize, b: isize) -> f64 {
        let n = self.seq.len() as isize;
        let at = |i: isize| if i >= n { self.pt(-1) } else { self.pt(i) };
        let from = if a < 0 { usize::MAX } else { a as usize };
        dist(self.exit(from), at(b))
    }

    /// Applies a move on `lo..=hi`, keeps it if feasible and cheaper, else undoes it.
    /// `idle_delta` is the move's change of the idle length: a move that adds more idle than
    /// the proxy of the span it could at best remove cannot pass and is not applied.
    pub(super) fn try_move(
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

    /// Applies `apply` to `lo..=hi` if it is feasible (else undoes it with `undo`).
    pub(super) fn commit_if_feasible(
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
}
