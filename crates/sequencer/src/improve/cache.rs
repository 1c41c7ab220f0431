//! The surrogate's terms by position and the window sweep's cache of them: every position's
//! term and its heat-proxy part as prefix sums, so the cost of a span before a move is two
//! lookups, and the cost after stops summing once it reaches the cost before (every term is
//! ≥ 0).

use super::distance::dist;
use super::search::Search;

impl Search<'_, '_> {
    /// Surrogate terms owned by position `i` (0..=n; n is the return to start): the idle
    /// edge into it, its corner penalty and its heat-proxy look-back.
    pub(super) fn term(&self, i: usize) -> f64 {
        let proxy = if i < self.seq.len() {
            self.proxy_at(i)
        } else {
            0.0
        };
        self.term_without_proxy(i) + proxy
    }

    /// [`Search::term`] without its heat-proxy part: the idle edge into position `i` and its
    /// corner penalty.
    pub(super) fn term_without_proxy(&self, i: usize) -> f64 {
        let prev = if i == 0 { usize::MAX } else { i - 1 };
        let edge = dist(self.exit(prev), self.point(i));
        match self.seq.get(i) {
            Some(&c) => edge + self.eval.corner_penalty(c),
            None => edge,
        }
    }

    /// Recomputes the cached terms (and their proxy parts) that a change of `lo..=hi` touches,
    /// positions `lo..=`[`Search::span_end`]`(hi)`, and the prefix sums from `lo` on.
    pub(super) fn refresh_cache(&mut self, lo: usize, hi: usize) {
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
    pub(super) fn span_end(&self, hi: usize) -> usize {
        (hi + 1 + self.lookback).min(self.seq.len())
    }

    /// The cached [`Search::span_cost`] of `lo..=hi` (valid inside [`Search::sweep`]).
    pub(super) fn cached_span_cost(&self, lo: usize, hi: usize) -> f64 {
        self.term_sum[self.span_end(hi) + 1] - self.term_sum[lo]
    }

    /// Whether [`Search::span_cost`] of `lo..=hi` is below `limit`, stopping as soon as the
    /// partial sum reaches it (every term is ≥ 0).
    pub(super) fn span_cost_below(&self, lo: usize, hi: usize, limit: f64) -> bool {
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
    pub(super) fn span_proxy(&self, lo: usize, hi: usize) -> f64 {
        // Positions lo..span_end(hi): the last term's look-back lies wholly after hi, so its
        // proxy cannot change.
        self.proxy_sum[self.span_end(hi)] - self.proxy_sum[lo]
    }

    /// Sum of the terms that change when positions `lo..=hi` are permuted.
    pub(super) fn span_cost(&self, lo: usize, hi: usize) -> f64 {
        (lo..=self.span_end(hi)).map(|i| self.term(i)).sum()
    }

    pub(super) fn total(&self) -> f64 {
        (0..=self.seq.len()).map(|i| self.term(i)).sum()
    }
}
