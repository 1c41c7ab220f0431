//! The neighbour-list sweep (module docs, step 1, thermal cost off): 2-opt and Or-opt between
//! each contour and its nearest contours at any distance along the sequence, with O(1) idle
//! deltas and don't-look bits (Bentley's, as in LKH).
//!
//! An edge runs from a cut's exit (the end of its lead-out) to the next cut's pierce point, so
//! with lead-outs the travel is asymmetric: reversing a run turns its inner edges too, and
//! their change is added (O(run length), only for moves the outer edges already favour).

use crate::plan::Cut;
use crate::problem::ContourId;

use super::search::Search;

impl Search<'_, '_> {
    /// Sets the don't-look bit of the contour at position `i` (−1 and `n`: the start).
    pub(super) fn wake(&mut self, i: isize) {
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
    pub(super) fn wake_contour(&mut self, c: ContourId) {
        if c < self.seq.len() {
            self.wake(self.pos[c] as isize);
        } else {
            self.wake(-1);
        }
    }

    /// Whether the contour at position `i` (−1: the start) is to be examined this sweep.
    pub(super) fn to_examine(&self, i: isize) -> bool {
        let c = if i < 0 {
            self.look.len() - 1
        } else {
            self.seq[i as usize].contour
        };
        self.examine[c] || self.look[c]
    }

    /// Marks every contour for examination (a fresh local search).
    pub(super) fn wake_all(&mut self) {
        self.look.fill(true);
        self.look_win.fill(true);
    }

    /// One sweep of 2-opt and Or-opt over spatial neighbour lists (any sequence distance),
    /// idle-length deltas in O(1); only valid without the heat proxy. Only contours whose
    /// don't-look bit is set are examined; a move sets the bits at the ends of the edges it
    /// changes. Whether it improved.
    pub(super) fn neighbour_sweep(&mut self) -> bool {
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
                let mut delta = self.edge(e1, e2) + self.edge(e1 + 1, e2 + 1)
                    - self.edge(e1, e1 + 1)
                    - self.edge(e2, e2 + 1);
                if delta < -eps && self.asymmetric {
                    delta += self.reversal_inner_delta(e1 + 1, e2);
                }
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
                let gain = self.edge(i - 1, i) + self.edge(i + len - 1, i + len)
                    - self.edge(i - 1, i + len);
                // Reversing the run also turns its inner edges (exit to pierce: not the
                // same length backwards once cuts have lead-outs).
                let inner_rev = if self.asymmetric {
                    self.reversal_inner_delta(i, i + len - 1)
                } else {
                    0.0
                };
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
                        let fwd =
                            self.edge(q, i) + self.edge(i + len - 1, q + 1) - self.edge(q, q + 1);
                        let rev = self.edge(q, i + len - 1) + self.edge(i, q + 1)
                            - self.edge(q, q + 1)
                            + inner_rev;
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

    /// The change of the edges inside positions `lo..=hi` when the run is reversed: each
    /// `exit(j) → pierce(j + 1)` becomes `exit(j + 1) → pierce(j)`. Zero without lead-outs.
    fn reversal_inner_delta(&self, lo: isize, hi: isize) -> f64 {
        (lo..hi)
            .map(|j| self.edge(j + 1, j) - self.edge(j, j + 1))
            .sum()
    }
}
