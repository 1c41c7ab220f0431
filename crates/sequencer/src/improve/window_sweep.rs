//! The window sweep (module docs, step 1): precedence-aware Or-opt, 2-opt and pierce
//! re-selection within `window` positions, on the surrogate with the heat proxy, from the
//! positions whose don't-look bit is set.

use super::params::ImproveParams;
use super::search::Search;

impl Search<'_, '_> {
    /// Sets the window sweep's don't-look bits of positions `lo - lookback ..= hi +
    /// lookback` (the surrogate terms a change of `lo..=hi` touches).
    pub(super) fn wake_span(&mut self, lo: usize, hi: usize) {
        let n = self.seq.len();
        for i in lo.saturating_sub(self.lookback)..=(hi + self.lookback).min(n - 1) {
            self.look_win[self.seq[i].contour] = true;
        }
    }

    /// Whether position `i` is to be examined by the running window sweep.
    pub(super) fn to_examine_win(&self, i: usize) -> bool {
        let c = self.seq[i].contour;
        self.examine_win[c] || self.look_win[c]
    }

    /// One sweep of Or-opt, 2-opt and pierce re-selection from the positions whose
    /// don't-look bit is set ([`Search::wake_span`]); whether anything improved.
    pub(super) fn sweep(&mut self, params: &ImproveParams) -> bool {
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
}
