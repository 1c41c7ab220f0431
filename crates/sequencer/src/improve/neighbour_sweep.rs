//! The neighbour-list sweep (module docs, step 1, thermal cost off): 2-opt and Or-opt between
//! each contour and its nearest contours at any distance along the sequence, with O(1) idle
//! deltas and don't-look bits (Bentley's, as in LKH).

use crate::plan::Cut;
use crate::problem::ContourId;

use super::distance::dist;
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
}
