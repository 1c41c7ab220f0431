//! What a job produces: progress reports while it runs, and the plan (each section's paths and
//! exposure, the carriage moves) with the queries on it.

use nalgebra::{Point2, Vector2};

use crate::calibration::{predict_chords, ChordPrediction, Sweep};
use crate::exposure::{coefficient_of_variation, ExposureModel};
use crate::trajectory::is_feasible;
use crate::wing::{Placement, Towers};

use super::{JobError, Motion};

/// Progress of a running job, reported after every iteration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JobProgress {
    /// Iterations done (1-based).
    pub iteration: usize,
    /// Iterations configured.
    pub total: usize,
    /// Best loss so far.
    pub best_loss: f64,
    /// Estimated time to completion (s), from the mean iteration time so far.
    pub eta_s: f64,
}

/// How uniform an exposure profile is around the target.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExposureStats {
    /// √(mean (E − CSE)²).
    pub rms: f64,
    /// max |E − CSE|.
    pub max_abs: f64,
    /// Coefficient of variation of E (std / mean).
    pub cv: f64,
    /// 95th percentile of |E − CSE| over the panels (nearest rank).
    #[serde(default)]
    pub p95_abs: f64,
}

impl ExposureStats {
    /// Statistics of `exposure` around `cse`.
    pub fn of(exposure: &[f64], cse: f64) -> Self {
        let n = exposure.len().max(1) as f64;
        Self {
            rms: (exposure.iter().map(|e| (e - cse).powi(2)).sum::<f64>() / n).sqrt(),
            max_abs: exposure.iter().map(|e| (e - cse).abs()).fold(0.0, f64::max),
            cv: coefficient_of_variation(exposure),
            p95_abs: {
                let mut d: Vec<f64> = exposure.iter().map(|e| (e - cse).abs()).collect();
                d.sort_by(f64::total_cmp);
                // Nearest rank: the ⌈0.95·N⌉-th smallest.
                let rank = (0.95 * d.len() as f64).ceil() as usize;
                d.get(rank.saturating_sub(1)).copied().unwrap_or(0.0)
            },
        }
    }
}

/// One row of [`HotwirePlan::chord_predictions`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CalibrationRow {
    /// The material CSE assumed.
    pub cse: f64,
    /// What a cut along the fixed-offset baseline would leave.
    pub baseline: ChordPrediction,
    /// What a cut along the optimised path would leave.
    pub optimised: ChordPrediction,
}

/// One section's plan, in the section's own frame (LE at the origin, chord along +x; mm).
#[derive(Debug, Clone, PartialEq)]
pub struct SectionPlan {
    /// Section name (from the `.dat` name line).
    pub airfoil: String,
    /// Chord (mm).
    pub chord_mm: f64,
    /// The scaled foil, Selig order.
    pub foil: Vec<Point2<f64>>,
    /// The resampled foil whose panels the exposure is evaluated on (N + 1 points).
    pub surface: Vec<Point2<f64>>,
    /// The fixed-offset baseline path (closed).
    pub baseline: Vec<Point2<f64>>,
    /// The path the wire follows on this face (closed): the optimised path (with open spline
    /// ends, plus the join from its last point back to its first), resampled point for point
    /// with the other face's on a tapered panel.
    pub optimised: Vec<Point2<f64>>,
    /// Wire-centre offset of the baseline (mm).
    pub offset_mm: f64,
    /// The exposure target CSE.
    pub cse: f64,
    /// Baseline exposure per panel.
    pub baseline_exposure: Vec<f64>,
    /// Exposure per panel along [`SectionPlan::optimised`].
    pub optimised_exposure: Vec<f64>,
    /// Baseline uniformity.
    pub baseline_stats: ExposureStats,
    /// Optimised uniformity.
    pub optimised_stats: ExposureStats,
    /// Loss of the baseline.
    pub baseline_loss: f64,
    /// Loss of the optimised path (as optimised, before any resampling).
    pub final_loss: f64,
    /// (iteration, best loss) at iteration 0 and at every improvement.
    pub loss_history: Vec<(usize, f64)>,
    /// Feed / nominal feed at each point of the optimised path as optimised (all 1 unless the
    /// feed is a variable, [`Objective::feed`](crate::pso::Objective::feed)).
    pub feed_ratio: Vec<f64>,
    /// Wire current / nominal current at each point of the optimised path as optimised (all 1
    /// unless the feed variable's current band is wider,
    /// [`FeedVariable::max_current_ratio`](crate::pso::FeedVariable::max_current_ratio)).
    pub current_ratio: Vec<f64>,
    /// Length of the lead-in behind the trailing edge (mm): `HotwireJob::lead_in_mm`
    /// ([`crate::job::HotwireJob`]), or as optimised with a `lead_in_max_mm`.
    pub lead_in_mm: f64,
    /// The lead-in in this section's frame (mm): from where the wire enters the foam to the
    /// first point of [`SectionPlan::optimised`].
    pub lead_in: Vec<Point2<f64>>,
    /// The lead-out in this section's frame (mm): from the last point of
    /// [`SectionPlan::optimised`] back out of the foam.
    pub lead_out: Vec<Point2<f64>>,
}

/// A planned hot-wire cut (see the module docs): the root section's plan, the tip's on a
/// tapered panel, and the carriage moves.
#[derive(Debug, Clone, PartialEq)]
pub struct HotwirePlan {
    /// The root section (the only one on a straight cut).
    pub root: SectionPlan,
    /// Exposure model used (for [`HotwirePlan::exposure_matrix_heat_map`]).
    pub model: ExposureModel,
    /// The tip section on a tapered panel.
    pub tip: Option<SectionPlan>,
    /// Iterations run (both sections together on a tapered panel).
    pub iterations: usize,
    /// Wall time of the optimisation (s).
    pub seconds: f64,
    /// RNG seed used.
    pub seed: u64,
    /// The machine profile's name.
    pub machine: String,
    /// Tower geometry the carriage moves were projected with.
    pub towers: Towers,
    /// Where the root section's LE sits in XY machine coordinates (mm).
    pub part_origin: Vector2<f64>,
    /// How the tip section is placed relative to the root (ROOT on a straight cut).
    pub tip_placement: Placement,
    /// True if the machine has a UV carriage (the toolpath carries secondary points).
    pub four_axis: bool,
    /// Straight lead-in from behind the trailing edge to the first cut point.
    pub lead_in: Motion,
    /// The cut (closed: the last point repeats the first).
    pub cut: Motion,
    /// Straight lead-out from the last cut point back behind the trailing edge.
    pub lead_out: Motion,
    /// Notes for the operator (fallbacks taken, clamped currents, slowed moves).
    pub notes: Vec<String>,
}

impl HotwirePlan {
    /// True if the root path (and the tip path, on a tapered panel) keeps `min_clearance_mm`
    /// from its foil (T ∩ G = ∅).
    pub fn is_feasible(&self, min_clearance_mm: f64) -> bool {
        is_feasible(&self.root.optimised, &self.root.foil, min_clearance_mm)
            && self
                .tip
                .as_ref()
                .is_none_or(|t| is_feasible(&t.optimised, &t.foil, min_clearance_mm))
    }

    /// The foils and the wire paths on their faces in machine coordinates (x, y, z along the
    /// wire from the XY plane): `[(name, points)]` for the root foil and path at the root face
    /// and, on a tapered panel, the tip's at the tip face. Closed polylines.
    pub fn placed_sections(&self) -> Vec<(&'static str, Vec<[f64; 3]>)> {
        let place = |pts: &[Point2<f64>], chord: f64, placement: &Placement, z: f64| {
            let mut out: Vec<[f64; 3]> = pts
                .iter()
                .map(|p| {
                    let q = placement.apply(chord, *p) + self.part_origin;
                    [q.x, q.y, z]
                })
                .collect();
            if out.first() != out.last() {
                out.extend(out.first().copied());
            }
            out
        };
        let root_chord = self.root.chord_mm;
        let zr = self.towers.root_plane_mm;
        let mut out = vec![
            (
                "root_foil",
                place(&self.root.foil, root_chord, &Placement::ROOT, zr),
            ),
            (
                "root_path",
                place(&self.root.optimised, root_chord, &Placement::ROOT, zr),
            ),
        ];
        if let Some(t) = &self.tip {
            let zt = self.towers.tip_plane_mm;
            out.push((
                "tip_foil",
                place(&t.foil, t.chord_mm, &self.tip_placement, zt),
            ));
            out.push((
                "tip_path",
                place(&t.optimised, t.chord_mm, &self.tip_placement, zt),
            ));
        }
        out
    }

    /// Every carriage position of the plan (lead-in, cut, lead-out) as (XY, UV) pairs, in
    /// order, without the repeated points where the motions meet.
    pub fn carriage_positions(&self) -> Vec<(Point2<f64>, Point2<f64>)> {
        let mut out: Vec<(Point2<f64>, Point2<f64>)> = Vec::new();
        for m in [&self.lead_in, &self.cut, &self.lead_out] {
            for p in m.xy.iter().copied().zip(m.uv.iter().copied()) {
                if out.last() != Some(&p) {
                    out.push(p);
                }
            }
        }
        out
    }

    /// The root chord a cut along the baseline and along the optimised path would leave for each
    /// material CSE of `cse_values` ([`crate::calibration`], seed 000 §IV.D), with
    /// `wire_radius_mm` as the closest the surface can come to the wire centre.
    ///
    /// # Errors
    /// The exposure model's (not expected for a plan from [`plan`](super::plan)).
    pub fn chord_predictions(
        &self,
        cse_values: &[f64],
        wire_radius_mm: f64,
    ) -> Result<Vec<CalibrationRow>, JobError> {
        let wrap = |e: crate::exposure::ExposureError| JobError::Plan {
            airfoil: self.root.airfoil.clone(),
            source: e.into(),
        };
        let sweep = Sweep {
            wire_radius_mm,
            ..Sweep::default()
        };
        let chord = self.root.chord_mm;
        let predict = |path: &[Point2<f64>]| {
            predict_chords(
                &self.model,
                &self.root.surface,
                path,
                self.root.offset_mm,
                chord,
                cse_values,
                &sweep,
            )
            .map_err(wrap)
        };
        let (baseline, optimised) = (
            predict(&self.root.baseline)?,
            predict(&self.root.optimised)?,
        );
        Ok(baseline
            .into_iter()
            .zip(optimised)
            .map(|(baseline, optimised)| CalibrationRow {
                cse: baseline.cse,
                baseline,
                optimised,
            })
            .collect())
    }
}
