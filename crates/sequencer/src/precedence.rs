//! Connectivity (precedence) rules (seed 003 §2; notes §A2, §A4) and the frontier of
//! contours that may be cut next.
//!
//! A rule set is a list of predecessors per contour (a DAG) plus, in strict mode, groups of
//! contours that must be cut contiguously (each part: its holes, then its outer contour). The
//! layout code builds it from the containment tree in either mode; everything that orders
//! contours (policies, improvement) only asks this module what is allowed.

use serde::{Deserialize, Serialize};

use crate::problem::ContourId;

/// Which reading of the paper's rules (notes §A2, "Discrepancy").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PrecedenceMode {
    /// Seed 003 §2: every hole of a part before its outer contour, each part cut
    /// contiguously, and parts nested in a hole finished before any hole of their host.
    #[default]
    Strict,
    /// The paper's pseudo-code (§A4): a contour becomes cuttable once everything inside it is
    /// cut; parts need not be contiguous.
    Relaxed,
}

/// The rules for one problem.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Precedence {
    /// `predecessors[c]`: contours that must be cut before `c`.
    pub predecessors: Vec<Vec<ContourId>>,
    /// Groups cut contiguously: once one member is cut, only members of that group may be
    /// cut until all are. Empty in relaxed mode.
    pub groups: Vec<Vec<ContourId>>,
}

/// Why an order breaks the rules.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Violation {
    /// A contour appears twice, or not at all, or is out of range.
    #[error("contour {contour} is cut {times} times (every contour exactly once)")]
    Count {
        /// The contour.
        contour: ContourId,
        /// How often the order cuts it.
        times: usize,
    },
    /// A contour comes before one of its predecessors.
    #[error("contour {contour} is cut before {predecessor}, which must come first")]
    Before {
        /// The contour cut too early.
        contour: ContourId,
        /// The predecessor not yet cut.
        predecessor: ContourId,
    },
    /// A contiguous group is interrupted.
    #[error("contour {contour} interrupts group {group}, which must be cut contiguously")]
    Interrupted {
        /// The contour cut inside another group's run.
        contour: ContourId,
        /// The interrupted group.
        group: usize,
    },
    /// The rules themselves cannot be met.
    #[error("the precedence rules form a cycle through contours {0:?}")]
    Cycle(Vec<ContourId>),
}

impl Precedence {
    /// Number of contours the rules cover.
    pub fn len(&self) -> usize {
        self.predecessors.len()
    }

    /// Whether the rules cover no contour.
    pub fn is_empty(&self) -> bool {
        self.predecessors.is_empty()
    }

    /// The group each contour belongs to, if any.
    pub fn group_of(&self) -> Vec<Option<usize>> {
        let mut of = vec![None; self.len()];
        for (g, members) in self.groups.iter().enumerate() {
            for &c in members {
                of[c] = Some(g);
            }
        }
        of
    }

    /// Checks that some order satisfies the rules.
    ///
    /// # Errors
    /// [`Violation::Cycle`] naming contours on a cycle (predecessor cycles, or groups that
    /// would have to interleave).
    pub fn check_acyclic(&self) -> Result<(), Violation> {
        let mut frontier = Frontier::new(self);
        while let Some(&c) = frontier.eligible().first() {
            frontier.cut(c);
        }
        if frontier.is_finished() {
            Ok(())
        } else {
            let stuck: Vec<ContourId> = (0..self.len()).filter(|&c| !frontier.done[c]).collect();
            Err(Violation::Cycle(stuck))
        }
    }

    /// Checks a whole order against the rules.
    ///
    /// # Errors
    /// The first [`Violation`] along the order.
    pub fn check_order(&self, order: &[ContourId]) -> Result<(), Violation> {
        let mut times = vec![0usize; self.len()];
        for &c in order {
            if c >= self.len() {
                return Err(Violation::Count {
                    contour: c,
                    times: 1,
                });
            }
            times[c] += 1;
        }
        if let Some((contour, &times)) = times.iter().enumerate().find(|(_, &t)| t != 1) {
            return Err(Violation::Count { contour, times });
        }
        let group_of = self.group_of();
        let mut frontier = Frontier::new(self);
        for &c in order {
            if let Some(&p) = self.predecessors[c].iter().find(|&&p| !frontier.done[p]) {
                return Err(Violation::Before {
                    contour: c,
                    predecessor: p,
                });
            }
            if let Some(open) = frontier.open_group {
                if group_of[c] != Some(open) {
                    return Err(Violation::Interrupted {
                        contour: c,
                        group: open,
                    });
                }
            }
            frontier.cut(c);
        }
        Ok(())
    }
}

/// The state of a cut in progress: what is cut, and what may be cut next (the paper's `W`).
#[derive(Debug, Clone)]
pub struct Frontier<'a> {
    rules: &'a Precedence,
    group_of: Vec<Option<usize>>,
    done: Vec<bool>,
    /// Predecessors still uncut, per contour.
    waiting: Vec<usize>,
    /// Members still uncut, per group.
    group_left: Vec<usize>,
    /// Uncut predecessors from outside the group, over all members, per group: a group may
    /// only be started once this is 0, or it could not be finished contiguously.
    group_waiting: Vec<usize>,
    /// The group being cut, if it is started and not finished.
    open_group: Option<usize>,
    successors: Vec<Vec<ContourId>>,
    cut_count: usize,
}

impl<'a> Frontier<'a> {
    /// Nothing cut yet.
    pub fn new(rules: &'a Precedence) -> Self {
        let mut successors = vec![Vec::new(); rules.len()];
        for (c, preds) in rules.predecessors.iter().enumerate() {
            for &p in preds {
                successors[p].push(c);
            }
        }
        let group_of = rules.group_of();
        let mut group_waiting = vec![0; rules.groups.len()];
        for (c, preds) in rules.predecessors.iter().enumerate() {
            if let Some(g) = group_of[c] {
                group_waiting[g] += preds.iter().filter(|&&p| group_of[p] != Some(g)).count();
            }
        }
        Frontier {
            rules,
            group_of,
            group_waiting,
            done: vec![false; rules.len()],
            waiting: rules.predecessors.iter().map(Vec::len).collect(),
            group_left: rules.groups.iter().map(Vec::len).collect(),
            open_group: None,
            successors,
            cut_count: 0,
        }
    }

    /// Contours that may be cut now, in index order.
    pub fn eligible(&self) -> Vec<ContourId> {
        (0..self.rules.len()).filter(|&c| self.may_cut(c)).collect()
    }

    /// Whether `c` may be cut now.
    pub fn may_cut(&self, c: ContourId) -> bool {
        if self.done[c] || self.waiting[c] > 0 {
            return false;
        }
        match (self.open_group, self.group_of[c]) {
            (Some(open), mine) => mine == Some(open),
            (None, Some(g)) => self.group_waiting[g] == 0,
            (None, None) => true,
        }
    }

    /// Whether `c` is cut.
    pub fn is_cut(&self, c: ContourId) -> bool {
        self.done[c]
    }

    /// Whether every contour is cut.
    pub fn is_finished(&self) -> bool {
        self.cut_count == self.rules.len()
    }

    /// Marks `c` cut. The caller checks [`Frontier::may_cut`] first.
    pub fn cut(&mut self, c: ContourId) {
        debug_assert!(self.may_cut(c), "contour {c} is not eligible");
        self.done[c] = true;
        self.cut_count += 1;
        for &s in &self.successors[c] {
            self.waiting[s] -= 1;
            if let Some(g) = self.group_of[s].filter(|&g| self.group_of[c] != Some(g)) {
                self.group_waiting[g] -= 1;
            }
        }
        if let Some(g) = self.group_of[c] {
            self.group_left[g] -= 1;
            self.open_group = (self.group_left[g] > 0).then_some(g);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Part 0 with holes 1 and 2 (outer contour 0); part 3 (outer 3) nested in hole 1.
    fn strict_example() -> Precedence {
        Precedence {
            predecessors: vec![vec![1, 2], vec![3], vec![3], vec![]],
            groups: vec![vec![0, 1, 2], vec![3]],
        }
    }

    #[test]
    fn frontier_follows_the_rules() {
        let rules = strict_example();
        let mut f = Frontier::new(&rules);
        assert_eq!(f.eligible(), vec![3]);
        f.cut(3);
        assert_eq!(f.eligible(), vec![1, 2]);
        f.cut(2);
        assert_eq!(f.eligible(), vec![1]);
        f.cut(1);
        f.cut(0);
        assert!(f.is_finished());
    }

    #[test]
    fn orders_are_checked() {
        let rules = strict_example();
        assert_eq!(rules.check_order(&[3, 1, 2, 0]), Ok(()));
        assert_eq!(
            rules.check_order(&[1, 3, 2, 0]),
            Err(Violation::Before {
                contour: 1,
                predecessor: 3
            })
        );
        assert_eq!(
            rules.check_order(&[3, 1, 2]),
            Err(Violation::Count {
                contour: 0,
                times: 0
            })
        );
        // Two parts with a hole each: interleaving them breaks contiguity.
        let two = Precedence {
            predecessors: vec![vec![1], vec![], vec![3], vec![]],
            groups: vec![vec![0, 1], vec![2, 3]],
        };
        assert_eq!(
            two.check_order(&[1, 3, 0, 2]),
            Err(Violation::Interrupted {
                contour: 3,
                group: 0
            })
        );
        assert_eq!(two.check_order(&[3, 2, 1, 0]), Ok(()));
    }

    /// A group may not be started while a member still waits on an outside contour: the
    /// first eligible contour must not lead into a dead end.
    #[test]
    fn groups_start_only_when_they_can_finish() {
        let rules = Precedence {
            predecessors: vec![vec![], vec![2], vec![]],
            groups: vec![vec![0, 1]],
        };
        let mut f = Frontier::new(&rules);
        assert_eq!(f.eligible(), vec![2]);
        f.cut(2);
        assert_eq!(f.eligible(), vec![0, 1]);
        assert_eq!(rules.check_acyclic(), Ok(()));
    }

    #[test]
    fn cycles_are_found() {
        let rules = Precedence {
            predecessors: vec![vec![1], vec![0], vec![]],
            groups: vec![],
        };
        assert_eq!(rules.check_acyclic(), Err(Violation::Cycle(vec![0, 1])));
        assert_eq!(strict_example().check_acyclic(), Ok(()));
    }
}
