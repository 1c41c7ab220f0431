//! Orchestration: one job from spec to plan (foil → offset → baseline → swarm → synchronised
//! sections → carriage moves).

use std::ops::ControlFlow;
use std::time::Instant;

use nalgebra::{Point2, Vector2};

use crate::airfoil::{Airfoil, SyncedPoints};
use crate::exposure::Panels;
use crate::pso::{self, Objective, Problem, PsoConfig, PsoError};
use crate::refine;
use crate::trajectory::{is_feasible, Baseline};
use crate::wing::{synchronise_paths, Placement, Towers};

use super::live::Live;
use super::motion::{check_envelope, Mover};
use super::process::process;
use super::spec::two_axis;
use super::{
    validate, ExposureStats, HotwireJob, HotwirePlan, JobError, JobProgress, LiveMaps, LiveOptions,
    SectionPlan, SECTION_FRAME_ID, TIP_FRAME_ID,
};

/// Plans `job` (module docs). `progress` is called after every iteration; returning
/// [`ControlFlow::Break`] stops the run with [`JobError::Cancelled`].
///
/// # Errors
/// Invalid parameters (named), an unknown or malformed airfoil (named, with file and line),
/// an infeasible baseline or other planning failure (with the airfoil), a path outside the
/// machine's travel, cancellation.
pub fn plan(
    job: &HotwireJob,
    progress: impl FnMut(&JobProgress) -> ControlFlow<()>,
) -> Result<HotwirePlan, JobError> {
    plan_observed(job, &LiveOptions::default(), |_| {}, progress)
}

/// What [`plan_section`] needs besides the foil.
struct SectionJob<'a> {
    job: &'a HotwireJob,
    name: &'a str,
    offset_mm: f64,
    /// Frame id of its heat maps.
    frame_id: &'static str,
    /// Iterations already run by earlier sections, and the total over all sections.
    iterations_before: usize,
    iterations_total: usize,
    started: Instant,
    /// The root's feed variable within the machine's feed limit and the supply's current
    /// range (`None`: constant feed).
    feed: Option<pso::FeedVariable>,
}

/// Plans one section (`foil`: normalised and scaled to `chord_mm`): baseline at `offset_mm`,
/// swarm, exposure before and after.
fn plan_section(
    s: &SectionJob<'_>,
    foil: &Airfoil,
    chord_mm: f64,
    lead_face: Option<&SectionPlan>,
    live: &mut Live<'_, impl FnMut(LiveMaps)>,
    progress: &mut impl FnMut(&JobProgress) -> ControlFlow<()>,
) -> Result<(SectionPlan, usize), JobError> {
    let job = s.job;
    let wrap = |source: PsoError| JobError::Plan {
        airfoil: s.name.to_string(),
        source,
    };
    let path_points = if job.path_points == 0 {
        job.panels + job.panels / 2
    } else {
        job.path_points
    };
    let baseline =
        Baseline::fixed_offset(foil, s.offset_mm, path_points).map_err(|e| wrap(e.into()))?;
    let objective = Objective {
        cse: job.cse,
        // Only the root's feed is a variable: the wire has one timing for both faces.
        feed: if s.frame_id == SECTION_FRAME_ID {
            s.feed
        } else {
            None
        },
        ..job.objective
    };
    // A sharp trailing edge repeats its point at both ends: one more point gives N panels.
    let surface_points = surface_points(foil, job.panels)?;
    let mut problem = Problem::new(foil, surface_points, baseline, objective).map_err(wrap)?;
    if job.lead_in_mm > 0.0 {
        problem = problem
            .with_lead_in(lead_in_start(foil.points(), job.lead_in_mm, s.offset_mm))
            .map_err(wrap)?;
        if let Some(max) = job.lead_in_max_mm.filter(|&m| m > job.lead_in_mm) {
            problem = problem
                .with_lead_in_reach(Vector2::x(), max - job.lead_in_mm)
                .map_err(wrap)?;
        }
    }
    if let Some(root) = lead_face {
        // The tip face moves in step with the root: where the root's feed is ρ, the tip's
        // dwell is 1/ρ its constant-feed dwell too (by normalised arc length, which the
        // synchronisation matches on each side of the leading edge to within the sections'
        // difference in shape; the exposure is recomputed on the synchronised paths after).
        if root
            .feed_ratio
            .iter()
            .chain(&root.current_ratio)
            .any(|&r| r != 1.0)
        {
            let feed = arc_profile(&root.optimised, &root.feed_ratio);
            let current = arc_profile(&root.optimised, &root.current_ratio);
            problem = problem
                .with_feed_profile(|u| (feed(u), current(u)))
                .map_err(wrap)?;
        }
    }
    let k = problem.trajectory().control_points();
    let baseline_exposure = problem.exposure(&vec![0.0; k]).map_err(wrap)?;
    live.show(&problem, &vec![0.0; k], 0, s.frame_id);
    let config = PsoConfig {
        seed: job.seed,
        ..job.pso
    };
    let result = pso::optimise(&problem, &config, |p| {
        let done = s.iterations_before + p.iteration;
        if p.improved && live.due() {
            live.show(&problem, p.best_controls, done, s.frame_id);
        }
        let elapsed = s.started.elapsed().as_secs_f64();
        let eta_s = elapsed / done.max(1) as f64 * s.iterations_total.saturating_sub(done) as f64;
        progress(&JobProgress {
            iteration: done,
            total: s.iterations_total,
            best_loss: p.best_loss,
            eta_s,
        })
    })
    .map_err(wrap)?;
    if result.cancelled {
        return Err(JobError::Cancelled {
            iteration: s.iterations_before + result.iterations_run,
        });
    }
    // Local refinement from the swarm's best (crate::refine); progress keeps the swarm's count.
    let done = s.iterations_before + result.iterations_run;
    let refined = refine::refine(&problem, &result.controls, &job.refine, |r| {
        progress(&JobProgress {
            iteration: done,
            total: s.iterations_total,
            best_loss: r.loss,
            eta_s: 0.0,
        })
    });
    if refined.cancelled {
        return Err(JobError::Cancelled { iteration: done });
    }
    if refined.history.len() > 1 && live.options.period.is_some() {
        // Numbered after the swarm's iterations, like the loss history.
        live.show(
            &problem,
            &refined.controls,
            done + refined.iterations,
            s.frame_id,
        );
    }
    let mut history = result.history.clone();
    history.extend(
        refined.history[1..]
            .iter()
            .map(|&(i, l)| (result.iterations_run + i, l)),
    );
    let result = pso::PsoResult {
        controls: refined.controls,
        best_loss: refined.loss,
        history,
        ..result
    };
    let mut optimised = problem.path(&result.controls);
    let optimised_exposure = problem.exposure(&result.controls).map_err(wrap)?;
    let cse = problem.cse();
    // Point k is reached by segment k − 1; point 0 takes segment 0's ratio.
    let per_point = |segments: Vec<f64>| {
        let mut out = Vec::with_capacity(segments.len() + 2);
        out.push(segments.first().copied().unwrap_or(1.0));
        out.extend_from_slice(&segments);
        out
    };
    let mut feed_ratio = per_point(problem.feed_ratios(&result.controls));
    let mut current_ratio = per_point(problem.current_ratios(&result.controls));
    // With open spline ends the path closes with a join back to its first point (without it
    // the wedge between lead-in and lead-out would stay on the part as a sliver,
    // `Problem::path`); a zero-length join is dropped.
    let n = optimised.len();
    if n > 2 && optimised[n - 1] == optimised[n - 2] {
        optimised.pop();
        feed_ratio.pop();
        current_ratio.pop();
    }
    let lead_in_mm = match problem.lead_start(&result.controls) {
        Some(start) => job.lead_in_mm + (start - problem.lead_in_start().unwrap_or(start)).norm(),
        None => job.lead_in_mm,
    };
    let plan = SectionPlan {
        lead_in_mm,
        feed_ratio,
        current_ratio,
        lead_in: Vec::new(),
        lead_out: Vec::new(),
        airfoil: foil.name().to_string(),
        chord_mm,
        foil: foil.points().to_vec(),
        surface: foil.resampled_cosine(surface_points)?.points().to_vec(),
        baseline: {
            // The baseline is closed already: no join.
            let mut b = problem.path(&vec![0.0; k]);
            b.dedup();
            b
        },
        optimised,
        offset_mm: s.offset_mm,
        cse,
        baseline_stats: ExposureStats::of(&baseline_exposure, cse),
        optimised_stats: ExposureStats::of(&optimised_exposure, cse),
        baseline_exposure,
        optimised_exposure,
        baseline_loss: result.baseline_loss,
        final_loss: result.best_loss,
        loss_history: result.history,
    };
    Ok((plan, result.iterations_run))
}

/// Where the lead-in starts for the foil outline `foil` (Selig order, from the trailing edge):
/// on the chord line, `lead_in_mm` behind the wire's pass round the trailing edge (the TE's
/// midpoint plus the offset).
pub fn lead_in_start(foil: &[Point2<f64>], lead_in_mm: f64, offset_mm: f64) -> Point2<f64> {
    nalgebra::center(&foil[0], &foil[foil.len() - 1]) + Vector2::new(lead_in_mm + offset_mm, 0.0)
}

/// Closed perimeter of a foil (mm).
fn perimeter_mm(foil: &Airfoil) -> f64 {
    cell_geometry::ring_perimeter(foil.points(), cell_geometry::Norm::Sqrt)
}

/// [`plan`], also handing `on_maps` the exposure profile and the wire × panel matrix of the
/// baseline before each section's swarm starts, and of the best path so far whenever it
/// improved and at least [`LiveOptions::period`] has passed, so a caller can show the
/// optimisation as it runs.
///
/// On a tapered panel both sections are optimised (root first, then tip, each with the full
/// iteration count). The faster face is cut at [`HotwireJob::feed_mm_s`] with the kerf-model
/// offset; the slower face moves slower by the ratio of the perimeters and, at the one wire
/// current, melts a kerf wider by the inverse ratio (seed 001 eq. 5: λ ∝ 1/v), so its baseline
/// offset is scaled up by that ratio.
///
/// # Errors
/// As [`plan`].
pub fn plan_observed(
    job: &HotwireJob,
    options: &LiveOptions,
    on_maps: impl FnMut(LiveMaps),
    mut progress: impl FnMut(&JobProgress) -> ControlFlow<()>,
) -> Result<HotwirePlan, JobError> {
    let mut live = Live {
        options,
        last: None,
        sink: on_maps,
    };
    validate(job)?;
    let hw = job
        .machine
        .hotwire
        .as_ref()
        .expect("validate checked the hotwire section");
    let four_axis = job.machine.is_four_axis_hotwire();
    let root_loaded = job.root_airfoil.load()?;
    let root_foil = root_loaded.normalised().scaled(job.chord_mm)?;
    // The tip, normalised and scaled, unless it is the root again (a straight cut).
    let tip = match &job.tip {
        Some(t) => {
            let loaded = t.airfoil.load()?;
            let straight = loaded.points() == root_loaded.points()
                && t.chord_mm == job.chord_mm
                && t.placement.sweep_mm == 0.0
                && t.placement.twist_deg == 0.0;
            if straight {
                None
            } else {
                Some((t, loaded.normalised().scaled(t.chord_mm)?))
            }
        }
        None => None,
    };
    if tip.is_some() && !four_axis {
        return Err(two_axis(&job.machine));
    }
    let proc = process(job, hw)?;
    let mut notes = proc.notes.clone();

    // Offsets: the longer section is the faster face (nominal offset), the other is wider.
    let (root_offset, tip_offset) = match &tip {
        Some((_, tip_foil)) => {
            let ratio = perimeter_mm(&root_foil) / perimeter_mm(tip_foil);
            if ratio >= 1.0 {
                (proc.offset_mm, proc.offset_mm * ratio)
            } else {
                (proc.offset_mm / ratio, proc.offset_mm)
            }
        }
        None => (proc.offset_mm, proc.offset_mm),
    };
    let sections = if tip.is_some() { 2 } else { 1 };
    let started = Instant::now();
    let root_name = job.root_airfoil.to_string();
    let section_job = |name, offset_mm, frame_id, before| SectionJob {
        job,
        name,
        offset_mm,
        frame_id,
        iterations_before: before,
        iterations_total: job.pso.iterations * sections,
        started,
        feed: job.objective.feed.map(|f| {
            f.within_machine(job.feed_mm_s, job.machine.max_feed_mm_s)
                .within_supply(job.current_a, proc.supply.min_a, proc.supply.max_a)
        }),
    };
    let (mut root, mut iterations) = plan_section(
        &section_job(&root_name, root_offset, SECTION_FRAME_ID, 0),
        &root_foil,
        job.chord_mm,
        None,
        &mut live,
        &mut progress,
    )?;
    let tip_plan = match &tip {
        Some((t, tip_foil)) => {
            let name = t.airfoil.to_string();
            let (plan, n) = plan_section(
                &section_job(&name, tip_offset, TIP_FRAME_ID, iterations),
                tip_foil,
                t.chord_mm,
                Some(&root),
                &mut live,
                &mut progress,
            )?;
            iterations += n;
            Some(plan)
        }
        None => None,
    };
    let seconds = started.elapsed().as_secs_f64();

    // Point-for-point root and tip paths, in each section's frame.
    let (root_cut, tip_cut) = match &tip_plan {
        Some(t) => {
            let (r, tp) = synchronised(job, &root, t)?;
            Some((r, tp))
        }
        None => None,
    }
    .unwrap_or_else(|| (root.optimised.clone(), root.optimised.clone()));
    let mut tip_plan = tip_plan;
    // Feed ratios at the cut points: as optimised, or carried onto the resampled points by arc
    // length (the resampled points lie on the optimised path).
    let (cut_ratios, cut_currents) = if tip_plan.is_some() {
        (
            along_arc(&root.optimised, &root.feed_ratio, &root_cut),
            along_arc(&root.optimised, &root.current_ratio, &root_cut),
        )
    } else {
        (root.feed_ratio.clone(), root.current_ratio.clone())
    };

    // Leads: straight along each chord line, from behind the TE.
    let behind_te = |s: &SectionPlan| lead_in_start(&s.foil, s.lead_in_mm, s.offset_mm);
    let root_out = behind_te(&root);
    let (tip_section, tip_chord, placement) = match (&tip_plan, &tip) {
        (Some(t), Some((spec, _))) => (t, t.chord_mm, spec.placement),
        _ => (&root, job.chord_mm, Placement::ROOT),
    };
    let tip_out = behind_te(tip_section);
    let origin = Vector2::new(hw.part_origin_mm[0], hw.part_origin_mm[1]);
    let towers = Towers {
        separation_mm: hw.tower_separation_mm,
        root_plane_mm: hw.root_plane_mm,
        tip_plane_mm: hw.root_plane_mm + job.span_mm,
    };
    let place = |r: &[Point2<f64>], t: &[Point2<f64>]| -> (Vec<Point2<f64>>, Vec<Point2<f64>>) {
        r.iter()
            .zip(t)
            .map(|(r, t)| (r + origin, placement.apply(tip_chord, *t) + origin))
            .unzip()
    };
    let mover = Mover {
        towers,
        feed_mm_s: job.feed_mm_s,
        max_feed_mm_s: job.machine.max_feed_mm_s,
        // With the feed a variable the current stays constant (see `FeedVariable`).
        schedule: proc.schedule.filter(|_| job.objective.feed.is_none()),
        supply: proc.supply,
        current_a: job.current_a,
    };
    let (r, t) = place(&[root_out, root_cut[0]], &[tip_out, tip_cut[0]]);
    let lead_in = mover.motion(&r, &t, &[1.0; 2], &mut notes)?;
    let (r, t) = place(&root_cut, &tip_cut);
    let mut cut = mover.motion(&r, &t, &cut_ratios, &mut notes)?;
    // With the current a variable too (FeedVariable::max_current_ratio), the nominal current
    // scaled point by point.
    for (a, g) in cut.current_a.iter_mut().zip(&cut_currents) {
        *a *= g;
    }
    if let Some(t) = tip_plan.as_mut() {
        // Both faces' exposure along the synchronised paths, at the dwell the carriages really
        // give them: the root's optimised feed, and the slow-downs where a carriage reaches
        // the machine's feed limit (the tip face moves in step with the root).
        // Heat per millimetre is γ²/ρ: an effective ratio ρ/γ² carries the current too.
        let dwell: Vec<f64> = dwell_ratios(&root_cut, &tip_cut, &cut, job.feed_mm_s)
            .iter()
            .zip(&cut_currents)
            .map(|(rho, g)| rho / (g * g))
            .collect();
        refresh_exposure(job, &mut root, &root_cut, &dwell)?;
        refresh_exposure(job, t, &tip_cut, &dwell)?;
    }
    let last = root_cut.len() - 1;
    let (root_lead_out, tip_lead_out) =
        (vec![root_cut[last], root_out], vec![tip_cut[last], tip_out]);
    let (r, t) = place(&root_lead_out, &tip_lead_out);
    let lead_out = mover.motion(&r, &t, &[1.0; 2], &mut notes)?;
    for (what, m) in [
        ("lead-in", &lead_in),
        ("cut", &cut),
        ("lead-out", &lead_out),
    ] {
        check_envelope(&job.machine, four_axis, what, m)?;
    }
    root.lead_in = vec![root_out, root_cut[0]];
    root.lead_out = root_lead_out;
    root.optimised = root_cut;
    if let Some(t) = tip_plan.as_mut() {
        t.lead_in = vec![tip_out, tip_cut[0]];
        t.lead_out = tip_lead_out;
        t.optimised = tip_cut;
    }
    Ok(HotwirePlan {
        root,
        model: job.objective.model,
        tip: tip_plan,
        iterations,
        seconds,
        seed: job.seed,
        machine: job.machine.name.clone(),
        towers,
        part_origin: origin,
        tip_placement: placement,
        four_axis,
        lead_in,
        cut,
        lead_out,
        notes,
    })
}

/// Resamples the two optimised paths point for point ([`synchronise_paths`]) finely enough
/// that both keep the clearance (3×, then up to 12× the longer path's point count).
fn synchronised(
    job: &HotwireJob,
    root: &SectionPlan,
    tip: &SectionPlan,
) -> Result<SyncedPoints, JobError> {
    let base = root.optimised.len().max(tip.optimised.len());
    let clearance = job.objective.min_clearance_mm;
    let mut last_gap = 0.0;
    for factor in [3, 6, 12] {
        let (r, t) = synchronise_paths(&root.optimised, &tip.optimised, base * factor + 1)?;
        if is_feasible(&r, &root.foil, clearance) && is_feasible(&t, &tip.foil, clearance) {
            return Ok((r, t));
        }
        last_gap = crate::trajectory::clearance_mm(&r, &root.foil, f64::INFINITY).min(
            crate::trajectory::clearance_mm(&t, &tip.foil, f64::INFINITY),
        );
    }
    Err(JobError::Plan {
        airfoil: root.airfoil.clone(),
        source: PsoError::InfeasibleBaseline {
            clearance_mm: last_gap,
        },
    })
}

/// `values` (one per point of `path`) as a function of normalised arc length along `path`,
/// linearly interpolated.
fn arc_profile<'a>(path: &[Point2<f64>], values: &'a [f64]) -> impl Fn(f64) -> f64 + 'a {
    let from = normalised_arc(path);
    move |u: f64| {
        let j = from.partition_point(|&v| v < u).clamp(1, from.len() - 1);
        let (u0, u1) = (from[j - 1], from[j]);
        let t = if u1 > u0 {
            ((u - u0) / (u1 - u0)).clamp(0.0, 1.0)
        } else {
            0.0
        };
        values[j - 1] + t * (values[j] - values[j - 1])
    }
}

/// Normalised arc length at each point of `path`, 0 … 1.
fn normalised_arc(path: &[Point2<f64>]) -> Vec<f64> {
    let mut s = vec![0.0];
    for w in path.windows(2) {
        s.push(s[s.len() - 1] + (w[1] - w[0]).norm());
    }
    let total = s[s.len() - 1].max(f64::MIN_POSITIVE);
    s.iter().map(|v| v / total).collect()
}

/// `values` (one per point of `path`) carried onto `onto` (points lying on `path`) by
/// normalised arc length, linearly interpolated.
fn along_arc(path: &[Point2<f64>], values: &[f64], onto: &[Point2<f64>]) -> Vec<f64> {
    let profile = arc_profile(path, values);
    normalised_arc(onto).into_iter().map(profile).collect()
}

/// Each move's speed relative to the constant-feed cut, as a ratio per point (point 0 takes
/// move 0's): the faster face's length over the move's duration (the farther carriage's
/// distance over its feed) over the nominal feed.
fn dwell_ratios(
    root: &[Point2<f64>],
    tip: &[Point2<f64>],
    cut: &super::Motion,
    feed_mm_s: f64,
) -> Vec<f64> {
    let moves: Vec<f64> = (1..cut.len())
        .map(|k| {
            let carriage = (cut.xy[k] - cut.xy[k - 1])
                .norm()
                .max((cut.uv[k] - cut.uv[k - 1]).norm());
            let face = (root[k] - root[k - 1])
                .norm()
                .max((tip[k] - tip[k - 1]).norm());
            if carriage > 0.0 && face > 0.0 {
                face / (carriage / cut.feed_mm_s[k]) / feed_mm_s
            } else {
                1.0
            }
        })
        .collect();
    let mut out = Vec::with_capacity(cut.len());
    out.push(moves.first().copied().unwrap_or(1.0));
    out.extend(moves);
    out
}

/// Recomputes a section's optimised exposure and statistics along `path` (the resampled path
/// the wire really follows) with feed ratio `ratios` at its points.
fn refresh_exposure(
    job: &HotwireJob,
    section: &mut SectionPlan,
    path: &[Point2<f64>],
    ratios: &[f64],
) -> Result<(), JobError> {
    let wrap = |e: crate::exposure::ExposureError| JobError::Plan {
        airfoil: section.airfoil.clone(),
        source: e.into(),
    };
    let panels = Panels::from_points(&section.surface).map_err(wrap)?;
    let mut wire = crate::exposure::WireSegments::from_points(path).map_err(wrap)?;
    let weights: Vec<f64> = ratios[1..].iter().map(|r| 1.0 / r).collect();
    wire.set_weights(&weights).map_err(wrap)?;
    section.optimised_exposure = vec![0.0; panels.len()];
    job.objective
        .model
        .exposure_into(&panels, &wire, &mut section.optimised_exposure)
        .map_err(wrap)?;
    if job.lead_in_mm > 0.0 {
        // The lead-in's heat reaches every panel (as in `Problem::with_lead_in`).
        let start = lead_in_start(&section.foil, section.lead_in_mm, section.offset_mm);
        crate::problem::add_lead_in_exposure(
            &job.objective.model,
            &panels,
            &[start, path[0]],
            &mut crate::exposure::WireSegments::default(),
            &mut Vec::new(),
            &mut section.optimised_exposure,
        )
        .map_err(wrap)?;
    }
    section.optimised_stats = ExposureStats::of(&section.optimised_exposure, section.cse);
    Ok(())
}

/// How many resampled points give `panels` distinct surface panels on `foil` (a sharp
/// trailing edge repeats its point at both ends).
///
/// # Errors
/// A foil that cannot be resampled.
pub fn surface_points(foil: &Airfoil, panels: usize) -> Result<usize, JobError> {
    let probe = foil.resampled_cosine(panels)?;
    let pts = probe.points();
    Ok(if pts.first() == pts.last() {
        panels + 1
    } else {
        panels
    })
}
