//! `cell_planner`: the hot-wire planner's pure geometry and process-model library.
//!
//! - [`airfoil`]: UIUC `.dat` input (Selig and Lednicer, auto-detected) and the section geometry
//!   the wire follows: normalise, scale, twist, close the trailing edge, resample, and
//!   synchronise a root and a tip section point for point.
//! - [`kerf`]: the seed 001 hot-wire kerf model (Aitchison et al.), its five inverse forms, the
//!   constant-kerf current schedule, the wire-centre path offset and the foam/wire libraries.
//! - [`exposure`]: seed 000's surface thermal exposure (eq. 1–5), integrated in closed form over
//!   each wire segment, with the causal mask.
//! - [`trajectory`]: the fixed-offset baseline path, its periodic cubic B-spline normal
//!   displacement and the T ∩ G = ∅ feasibility test.
//! - [`problem`]: the optimisation problem: foil, surface panels, the path's spline
//!   parameterisation, the lead-in, the loss and the design variables' bounds.
//! - [`pso`]: seed 000 §IV.C particle swarm optimisation of the path for uniform exposure.
//! - [`refine`]: Levenberg–Marquardt refinement of the swarm's best.
//! - [`spline`]: the uniform cubic B-splines (periodic or open) of the path and the feed.
//! - [`calibration`]: seed 000 §IV.D CSE calibration: the chord a path leaves for each CSE of a
//!   sweep, and the CSE a measured test-cut chord implies.
//! - [`wing`]: beyond the paper's 2-D cut: tapered, swept, twisted panels on a 4-axis cutter
//!   (root/tip synchronisation, projection onto the carriage planes, move timing).
//! - [`job`]: one planning job end to end (foil → offset → baseline → swarm → plan), with its
//!   `Toolpath` and `HeatMap` views.
//!
//! # Why the swarm stalled (issue 21), and what changed
//!
//! Before issue 21 the planner ran the paper's swarm for 8000 iterations and barely moved the
//! path: on unseen foils its own report gave CV 0.325 → 0.266, and the demo's wing gained
//! 2.5 % in RMS. The paper reports −68 % in surface deviation, and a plain NumPy swarm
//! reached −73 % in CV. The reasons, each measured (the `uniformity` bench's ladder,
//! `UNIFORMITY_LADDER=1`; figures in the README):
//!
//! 1. **No lead-in in the model.** The wire path the loss saw started on the loop, so the
//!    first panels cut were heated only by the few millimetres of wire before their cut
//!    point: E ≈ 0.05 on the first panel of E387 where the mean is 4.6. Those panels
//!    dominated the loss and no displacement could fix them. The lead-in's heat now counts for
//!    every panel ([`problem::Problem::with_lead_in`]: the wire is on it before it cuts
//!    anything, so the causal mask is off for it); E387's least exposure rises to 1.44.
//! 2. **Exploration.** The exposure varies as ln ‖R‖ (seed 000 eq. 5 with p = 1), so evening it
//!    out takes millimetres: the wire moves out by 2–4 mm where the surface is over-exposed
//!    (the later end of the cut) and in to the clearance where it is under-exposed (the leading
//!    edge). Start velocities of ±0.05 mm with inertia 0.6 add up to a travel of
//!    0.05/(1 − 0.6) = 0.125 mm before the pull towards the bests takes over, and every
//!    restart drew them again: the swarm only ever searched a tenth of a millimetre around
//!    the baseline. Now ±0.3 mm at the start and ±0.1 mm at restarts (the NumPy peer's values).
//! 3. **The clearance as a wall, not a bound.** The optimum presses the wire against the
//!    clearance at the leading edge. Moves through it had L = +∞ and were simply lost. The
//!    design variables now have box bounds ([`problem::Problem::bounds`]) that the swarm
//!    clamps to and the refinement projects onto, which keep the path clear by construction.
//! 4. **Geometry alone cannot reach the target.** With a 0.5 mm offset and a 0.1 mm clearance
//!    the wire may come 0.4 mm closer: at the leading edge that raises E by ln 5 ≈ 1.6, not
//!    enough (E ≈ 3 where CSE ≈ 4.8). The feed along the path is now a design variable by
//!    default (seed 000's Ê(c, f), [`problem::FeedVariable`]): slower where the surface needs
//!    heat, faster where it has too much, within 0.5–1.5 × the nominal feed and the machine's
//!    feed limit, at constant current. This is also how the paper's "exception at the later
//!    end of the cutting path" is handled: the last panels cut, heated by the whole path before
//!    them, get the wire moved out and the feed raised instead of being left over-exposed.
//! 5. **Entry and ends.** The wire enters and leaves at the trailing edge, and the periodic
//!    spline tied the first pass (which wants the wire close and slow) to the last (far and
//!    fast): δ(0) = (c_{K−1} + 4c₀ + c₁)/6, so S1223's last control at +3.4 mm pushed the start
//!    0.24 mm out. The path and feed splines now have open ends ([`spline::SplineEnds::Open`]);
//!    the cut closes the loop with a straight join back to its first point (part of the wire
//!    the loss sees), and the lead-out leaves along the lead-in. The lead-in's length can be a
//!    design variable too (`lead_in_max_mm`, [`problem::Problem::with_lead_in_reach`]); with
//!    the other changes in place it gains little (the ladder's option row), so it is off by
//!    default: it needs more foam behind the trailing edge. The entry point was measured as a
//!    design choice too ([`problem::Problem::entering_at`], the bench's `UNIFORMITY_ENTRY=1`):
//!    entering at the trailing edge beat the middle of the upper surface, the leading edge
//!    and the middle of the lower surface on all five foils tried (CV after 0.021–0.062
//!    against 0.059–0.095), so the job enters there: the first panels cut (upper surface at
//!    the trailing edge) run nearly parallel to the lead-in, which heats them like a cut
//!    already under way, and the lead-in and lead-out run in the block's waste along the
//!    chord line.
//! 6. **Resolution where it matters.** 32 controls evenly spaced over ~420 mm of path act
//!    every 13 mm, but the leading edge's under-exposed stretch is a few millimetres long.
//!    The controls are now spaced like the cosine-clustered panels
//!    ([`trajectory::ControlSpacing::PathPoints`]).
//! 7. **The swarm's endgame.** The swarm finds the basin in a few hundred iterations and then
//!    crawls. It now stops when its best has improved by less than 5 % over 300 iterations,
//!    and Levenberg–Marquardt on the residuals ([`refine`]) finishes in a few dozen steps
//!    (hundredths of a second): the loss is a sum of squares of smooth functions of the
//!    controls. Measured against the alternative the issue names: on these foils the
//!    refinement started from the baseline, without any swarm, reaches the same figures as
//!    swarm + refinement (ladder, last row); CMA-ES was not tried, since a derivative-free
//!    method cannot beat an exact Gauss–Newton model of a least-squares loss on a smooth
//!    problem. The swarm stays the default method (the paper's, and insurance against a
//!    poor local start on shapes not benchmarked); `iterations: 0` skips it.
//!
//! The ladder (CV of E before → after, 200 panels, chord 200 mm; the full table with the
//! 95th percentile of |E − CSE| and wall times is in the README):
//!
//! | change | E553 | GOE 423 | NACA 66₃-218 |
//! |---|---|---|---|
//! | the swarm as it was | 0.321 → 0.261 | 0.267 → 0.215 | 0.284 → 0.241 |
//! | + the lead-in's heat in the model | 0.290 → 0.201 | 0.221 → 0.165 | 0.267 → 0.179 |
//! | + start/restart velocity ±0.3/±0.1 mm | 0.290 → 0.186 | 0.221 → 0.159 | 0.267 → 0.172 |
//! | + Levenberg–Marquardt refinement | 0.290 → 0.151 | 0.221 → 0.159 | 0.267 → 0.162 |
//! | + feed as a variable | 0.290 → 0.070 | 0.221 → 0.080 | 0.267 → 0.094 |
//! | + open spline ends | 0.290 → 0.050 | 0.221 → 0.094 | 0.267 → 0.095 |
//! | + controls clustered like the panels | 0.290 → 0.040 | 0.221 → 0.083 | 0.267 → 0.081 |
//! | + swarm stops when it stalls (default) | 0.290 → 0.033 | 0.221 → 0.063 | 0.267 → 0.058 |
//! | refinement alone, no swarm | 0.290 → 0.026 | 0.221 → 0.062 | 0.267 → 0.054 |
//!
//! (The first row's baseline is the loop alone, as the planner measured it then; from the
//! second row on the baseline includes the lead-in.) The bounds of item 3 are on in every row.
//!
//! Not the cause: the loss's scale (mean (E − CSE)², residuals of order 1; the smoothing
//! weight 1e-3 is negligible against it).
//!
//! Everything here is synchronous and free of ROS, DDS, tokio and Rerun (checked by
//! `tests/architecture.rs`); the `planner` node (`nodes/planner`) serves it as the
//! `plan_hotwire` action.

#![warn(missing_docs)]

pub mod airfoil;
pub mod calibration;
pub mod exposure;
pub mod job;
pub mod kerf;
pub mod problem;
pub mod pso;
pub mod refine;
pub mod spline;
pub mod trajectory;
pub mod wing;
