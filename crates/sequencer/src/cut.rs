//! Cutting a layout for real (issue 19, items 2 and 3): the job's kerf and leads
//! ([`CutSpec`], from the machine profile's `cutting:` section) applied to a layout, giving the
//! [`Problem`] the sequencer orders.
//!
//! [`cut_problem`], for every drawn contour in the problem's numbering:
//! 1. its cut path: the contour offset by half the kerf to the scrap side ([`crate::kerf`];
//!    with `compensation: controller` the drawn contour itself, the controller offsets it),
//!    turned so the part lies on its right. A hole the offset does not fit is an error naming
//!    it, or left out with a warning when `skip_too_small_holes`; an outer contour whose
//!    offset fails is always an error. Two cut paths that cross or touch (parts nested less
//!    than a kerf apart) are an error naming both;
//! 2. its leads ([`crate::leads`], on the sheet unless none fits there): one per pierce
//!    candidate, entering where the sequencer's
//!    corner-avoiding candidates of the drawn contour ([`crate::layout::PierceOptions`]) meet
//!    the cut path, or from the layout's fixed pierce point; a small hole gets its centre
//!    pierce. A contour no lead fits is an error naming it (a hole: or left out, as above);
//! 3. the problem's contour takes the cut path as its points, the lead-ins' starts as its
//!    pierce candidates and the leads themselves ([`crate::problem::Contour::leads`]), so the
//!    cost model's travel runs from each cut's exit to the next pierce and the thermal raster
//!    heats the leads too. The precedence rules are the layout's, unchanged.

use cell_geometry::{distance_to_rings, Norm};
use cell_profiles::{
    Compensation, CuttingSection, LeadShape, MachineProfile, MaterialRef, TooSmallHoles,
};
use serde::Serialize;

use crate::containment::{dedup_ring, find_crossing};
use crate::kerf::{offset_contour, orient_part_right, uncut_stretch, OffsetFailure};
use crate::layout::{free_pierce_candidates, Layout, LayoutError, PierceOptions};
use crate::leads::{LeadFinder, LeadParams, LeadTarget, Obstacles};
use crate::precedence::PrecedenceMode;
use crate::problem::{ContourRole, Point, Problem};

/// The kerf and leads of one job (the interface agreed with `cell_profiles`' `cutting:`).
#[derive(Debug, Clone, PartialEq)]
pub struct CutSpec {
    /// Kerf width, mm: the cut path lies half of it off the drawn contour, on the scrap side.
    pub kerf_mm: f64,
    /// Lead-in length, mm: the pierce lies this far from the cut path, on the scrap side,
    /// where the lead is not shortened ([`crate::leads`]).
    pub lead_in_mm: f64,
    /// Lead-in shape.
    pub lead_shape: LeadShape,
    /// Lead-out length, mm (0: none).
    pub lead_out_mm: f64,
    /// Cut on past the entry point along the contour, mm (0: none).
    pub overcut_mm: f64,
    /// Holes with a smaller inscribed diameter get a centre pierce, mm (0: none).
    pub small_hole_diameter_mm: f64,
    /// A hole the offset or a lead does not fit is left out with a warning instead of an error.
    pub skip_too_small_holes: bool,
    /// Who offsets the path: the sequencer (geometric) or the controller (`G41`, the cut path
    /// stays on the drawn contour; the leads still keep the kerf's clearances).
    pub compensation: Compensation,
}

impl CutSpec {
    /// The spec for `material` at `thickness_mm` from a profile's `cutting:` section.
    ///
    /// # Errors
    /// The kerf table has no row for them (the message lists what it has).
    pub fn from_profile(
        section: &CuttingSection,
        material: &str,
        thickness_mm: f64,
    ) -> Result<CutSpec, String> {
        let kerf_mm = section.kerf_mm(material, thickness_mm)?;
        let spec = CutSpec {
            kerf_mm,
            lead_in_mm: section.lead_in.length_mm,
            lead_shape: section.lead_in.shape,
            lead_out_mm: section.lead_out_mm,
            overcut_mm: section.overcut_mm,
            small_hole_diameter_mm: section.small_hole_diameter_mm,
            skip_too_small_holes: section.too_small_holes == TooSmallHoles::Skip,
            compensation: section.compensation,
        };
        spec.validate()?;
        Ok(spec)
    }

    /// Checks every field: lengths finite and ≥ 0, kerf and lead-in > 0.
    ///
    /// # Errors
    /// The first bad field, by name.
    pub fn validate(&self) -> Result<(), String> {
        for (field, v, positive) in [
            ("kerf_mm", self.kerf_mm, true),
            ("lead_in_mm", self.lead_in_mm, true),
            ("lead_out_mm", self.lead_out_mm, false),
            ("overcut_mm", self.overcut_mm, false),
            ("small_hole_diameter_mm", self.small_hole_diameter_mm, false),
        ] {
            let ok = v.is_finite() && if positive { v > 0.0 } else { v >= 0.0 };
            if !ok {
                return Err(format!(
                    "cut.{field} = {v} mm: must be finite and {}",
                    if positive { "> 0" } else { "≥ 0" }
                ));
            }
        }
        Ok(())
    }

    /// How far the cut path lies off the drawn contour, mm: half the kerf, or 0 when the
    /// controller compensates.
    pub fn path_offset_mm(&self) -> f64 {
        match self.compensation {
            Compensation::Geometric => self.kerf_mm / 2.0,
            Compensation::Controller => 0.0,
        }
    }

    /// The least distance from a lead to another drawn contour, mm: a kerf, so the lead's own
    /// kerf stays half a kerf clear of the other cut path; half a kerf more when the
    /// controller shifts the programmed lead by half a kerf.
    pub fn clearance_mm(&self) -> f64 {
        self.kerf_mm + (self.kerf_mm / 2.0 - self.path_offset_mm())
    }

    fn lead_params(&self) -> LeadParams {
        LeadParams {
            shape: self.lead_shape,
            length_mm: self.lead_in_mm,
            lead_out_mm: self.lead_out_mm,
            overcut_mm: self.overcut_mm,
            small_hole_diameter_mm: self.small_hole_diameter_mm,
            path_offset_mm: self.path_offset_mm(),
            clearance_mm: self.clearance_mm(),
            pierce_clearance_mm: self.kerf_mm,
        }
    }
}

/// The cut of a job on `profile` (the interface's mapping): its `cutting:` section for
/// `material` at `thickness_mm`, each defaulting to the section's `default_material`, and the
/// material used; `None` for a profile without a `cutting:` section and no material asked for
/// (the drawn contours, pierced on the contour).
///
/// # Errors
/// A material or thickness for a profile without a `cutting:` section, neither given nor a
/// default in the section, or a material and thickness its kerf table does not cover.
pub fn spec_for_profile(
    profile: &MachineProfile,
    material: Option<&str>,
    thickness_mm: Option<f64>,
) -> Result<Option<(CutSpec, MaterialRef)>, String> {
    let Some(section) = &profile.cutting else {
        return match (material, thickness_mm) {
            (None, None) => Ok(None),
            _ => Err(format!(
                "profile {} has no cutting: section (no kerf table, no leads) to cut a                  material with",
                profile.name
            )),
        };
    };
    let default = section.default_material.as_ref();
    let material = material
        .map(str::to_string)
        .or_else(|| default.map(|m| m.material.clone()));
    let thickness_mm = thickness_mm.or_else(|| default.map(|m| m.thickness_mm));
    let (Some(material), Some(thickness_mm)) = (material, thickness_mm) else {
        return Err(format!(
            "profile {}'s cutting: section has no default_material: name the material and its              thickness",
            profile.name
        ));
    };
    let spec = CutSpec::from_profile(section, &material, thickness_mm)
        .map_err(|e| format!("profile {}: {e}", profile.name))?;
    Ok(Some((
        spec,
        MaterialRef {
            material,
            thickness_mm,
        },
    )))
}

/// What the cut spec did to a layout, for the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CutSummary {
    /// Kerf width, mm.
    pub kerf_mm: f64,
    /// `geometric` or `controller`.
    pub compensation: Compensation,
    /// Distance of the cut path from the drawn contour, mm.
    pub path_offset_mm: f64,
    /// Lead-in shape.
    pub lead_shape: LeadShape,
    /// Lead-in length asked for, mm.
    pub lead_in_mm: f64,
    /// Lead-out length asked for, mm.
    pub lead_out_mm: f64,
    /// Overcut, mm.
    pub overcut_mm: f64,
    /// Least distance kept from a lead to any other drawn contour, mm.
    pub lead_clearance_mm: f64,
    /// Holes pierced at their centre (small holes).
    pub centre_pierced_holes: usize,
    /// Pierce candidates (centre pierces aside) closer to their cut path than `lead_in_mm`:
    /// their lead-in was shortened or turned to clear a neighbour.
    pub short_lead_ins: usize,
    /// The least distance of a pierce candidate (centre pierces aside) from its cut path, mm.
    pub nearest_pierce_mm: f64,
    /// What is not cut as drawn, each naming the contour: holes left out
    /// (`too_small_holes: skip`), notches and inside corners narrower than the kerf.
    pub warnings: Vec<String>,
}

/// Why a layout cannot be cut with a spec; every message names the contour(s).
#[derive(Debug, thiserror::Error)]
pub enum CutError {
    /// A spec field is out of range.
    #[error("{0}")]
    Spec(String),
    /// The layout itself is invalid.
    #[error(transparent)]
    Layout(#[from] LayoutError),
    /// A contour's offset cannot be cut.
    #[error("{ring}: cannot be cut with a {kerf_mm} mm kerf: {reason}{hint}")]
    Offset {
        /// Which contour.
        ring: String,
        /// Kerf width, mm.
        kerf_mm: f64,
        /// What happened to the offset.
        reason: OffsetFailure,
        /// How to get past it, if there is a way.
        hint: &'static str,
    },
    /// Two cut paths cross or touch.
    #[error(
        "{ring} and {other} lie less than the kerf ({kerf_mm} mm) apart: their cut paths \
         overlap (nest the parts at least a kerf apart)"
    )]
    Overlap {
        /// One contour.
        ring: String,
        /// The other.
        other: String,
        /// Kerf width, mm.
        kerf_mm: f64,
    },
    /// No lead fits a contour.
    #[error("{ring}: {reason}{hint}")]
    Lead {
        /// Which contour.
        ring: String,
        /// Why.
        reason: String,
        /// How to get past it, if there is a way.
        hint: &'static str,
    },
}

const SKIP_HINT: &str = " (too_small_holes: skip leaves such holes out)";

/// One drawn ring of the layout, in the problem's numbering.
struct DrawnRing {
    part: usize,
    hole: Option<usize>,
    role: ContourRole,
    nominal: Vec<Point>,
    fixed: Option<Point>,
}

/// The problem of `layout` cut with `spec` (module docs), and what was done.
///
/// # Errors
/// [`CutError`]: a bad spec field, an invalid layout, a contour whose offset or leads do not
/// fit, or two cut paths that overlap; each naming the contours.
pub fn cut_problem(
    layout: &Layout,
    mode: PrecedenceMode,
    pierce: &PierceOptions,
    spec: &CutSpec,
) -> Result<(Problem, CutSummary), CutError> {
    spec.validate().map_err(CutError::Spec)?;
    // Checks the nesting, the fixed pierce points and the rules.
    let nominal_problem = layout.to_problem(mode, pierce)?;
    let rings: Vec<DrawnRing> = layout
        .parts
        .iter()
        .enumerate()
        .flat_map(|(i, p)| {
            std::iter::once((i, None, &p.outer)).chain(
                p.holes
                    .iter()
                    .enumerate()
                    .map(move |(h, r)| (i, Some(h), r)),
            )
        })
        .map(|(part, hole, ring)| DrawnRing {
            part,
            hole,
            role: if hole.is_some() {
                ContourRole::Hole
            } else {
                ContourRole::Outer
            },
            nominal: dedup_ring(&ring.points, 1e-9),
            fixed: ring.pierce,
        })
        .collect();
    let name = |r: &DrawnRing| layout.ring_name((r.part, r.hole));
    let mut skipped = vec![false; rings.len()];
    let mut warnings = Vec::new();
    // A hole that does not fit is left out if the spec says so; anything else fails.
    let mut skip_or_fail = |skipped: &mut [bool], r: usize, err: CutError| {
        if rings[r].role == ContourRole::Hole && spec.skip_too_small_holes {
            skipped[r] = true;
            warnings.push(format!(
                "{err}; the hole is left out (too_small_holes: skip)"
            ));
            Ok(())
        } else {
            Err(err)
        }
    };

    // 1. Cut paths (the kerf's offset is checked in both compensation modes).
    let half = spec.kerf_mm / 2.0;
    let mut offsets: Vec<Vec<Point>> = Vec::with_capacity(rings.len());
    for (r, ring) in rings.iter().enumerate() {
        match offset_contour(&ring.nominal, ring.role, half) {
            Ok(p) => offsets.push(p),
            Err(reason) => {
                let hint = if ring.role == ContourRole::Hole {
                    SKIP_HINT
                } else {
                    ""
                };
                skip_or_fail(
                    &mut skipped,
                    r,
                    CutError::Offset {
                        ring: name(ring),
                        kerf_mm: spec.kerf_mm,
                        reason,
                        hint,
                    },
                )?;
                offsets.push(Vec::new());
            }
        }
    }
    // Notches and inside corners the kerf cannot reach: cut as the offset allows, said aloud.
    let mut narrow = Vec::new();
    for (r, ring) in rings.iter().enumerate().filter(|&(r, _)| !skipped[r]) {
        if let Some(miss) = uncut_stretch(&ring.nominal, &offsets[r], half) {
            narrow.push(format!(
                "{}: the kerf misses {:.1} mm of the drawn outline around ({:.3}, {:.3}): a \
                 notch or inside corner there is narrower than the {} mm kerf and stays uncut",
                name(ring),
                miss.length_mm,
                miss.at[0],
                miss.at[1],
                spec.kerf_mm
            ));
        }
    }
    let kept: Vec<usize> = (0..rings.len()).filter(|&r| !skipped[r]).collect();
    let kept_offsets: Vec<Vec<Point>> = kept.iter().map(|&r| offsets[r].clone()).collect();
    if let Some((a, b)) = find_crossing(&kept_offsets) {
        return Err(CutError::Overlap {
            ring: name(&rings[kept[a]]),
            other: name(&rings[kept[b]]),
            kerf_mm: spec.kerf_mm,
        });
    }
    let paths: Vec<Vec<Point>> = rings
        .iter()
        .zip(offsets)
        .map(|(ring, offset)| match spec.compensation {
            Compensation::Geometric => offset,
            Compensation::Controller => orient_part_right(&ring.nominal, ring.role),
        })
        .collect();

    // 2. Leads, against every drawn contour (left-out holes stay material).
    let nominals: Vec<Vec<Point>> = rings.iter().map(|r| r.nominal.clone()).collect();
    let params = spec.lead_params();
    let cell = (2.0 * (params.length_mm + params.clearance_mm)).max(4.0);
    let obstacles = Obstacles::new(&nominals, layout.sheet, cell);
    let on_sheet = LeadFinder {
        obstacles: &obstacles,
        params,
        off_sheet: false,
    };
    let edge_start = LeadFinder {
        off_sheet: true,
        ..on_sheet
    };
    let mut leads = vec![Vec::new(); rings.len()];
    let mut is_centre = vec![false; rings.len()];
    for (r, ring) in rings.iter().enumerate() {
        if skipped[r] {
            continue;
        }
        let target = LeadTarget {
            ring: r,
            role: ring.role,
            path: &paths[r],
        };
        let entries = free_pierce_candidates(&ring.nominal, pierce);
        let lead = |finder: &LeadFinder| match ring.fixed {
            Some(p) => finder
                .fixed_lead(&target, &ring.nominal, p)
                .map(|l| (vec![l], false)),
            None => finder
                .contour_leads(&target, &ring.nominal, &entries)
                .map(|c| (c.leads, c.centre_pierce)),
        };
        // On the sheet if any lead fits there, else an edge start.
        let found = lead(&on_sheet).or_else(|e| lead(&edge_start).map_err(|_| e));
        match found {
            Ok((l, centre)) => {
                is_centre[r] = centre;
                leads[r] = l;
            }
            Err(reason) => {
                let hint = if ring.role == ContourRole::Hole && ring.fixed.is_none() {
                    SKIP_HINT
                } else {
                    ""
                };
                skip_or_fail(
                    &mut skipped,
                    r,
                    CutError::Lead {
                        ring: name(ring),
                        reason,
                        hint,
                    },
                )?;
            }
        }
    }

    // 3. The problem: the layout without the left-out holes, cut paths and leads.
    let mut problem = if skipped.iter().any(|&s| s) {
        let mut reduced = layout.clone();
        for (r, ring) in rings.iter().enumerate().rev() {
            if let (true, Some(h)) = (skipped[r], ring.hole) {
                reduced.parts[ring.part].holes.remove(h);
            }
        }
        reduced.to_problem(mode, pierce)?
    } else {
        nominal_problem
    };
    let mut paths = paths;
    let (mut short, mut nearest) = (0, f64::INFINITY);
    for (contour, r) in problem.contours.iter_mut().zip(kept.iter().copied()) {
        let ls = std::mem::take(&mut leads[r]);
        let centre = ls.len() == 1 && is_centre[r];
        for l in ls.iter().filter(|_| !centre) {
            let d = distance_to_rings(l.pierce(), std::slice::from_ref(&paths[r]), Norm::Hypot);
            nearest = nearest.min(d);
            short += usize::from(d < spec.lead_in_mm - 1e-6);
        }
        contour.drawn = std::mem::replace(&mut contour.points, std::mem::take(&mut paths[r]));
        contour.pierce_candidates = ls.iter().map(|l| l.pierce()).collect();
        contour.leads = ls;
    }
    warnings.extend(narrow);
    let summary = CutSummary {
        kerf_mm: spec.kerf_mm,
        compensation: spec.compensation,
        path_offset_mm: spec.path_offset_mm(),
        lead_shape: spec.lead_shape,
        lead_in_mm: spec.lead_in_mm,
        lead_out_mm: spec.lead_out_mm,
        overcut_mm: spec.overcut_mm,
        lead_clearance_mm: spec.clearance_mm(),
        centre_pierced_holes: kept.iter().filter(|&&r| is_centre[r]).count(),
        short_lead_ins: short,
        nearest_pierce_mm: if nearest.is_finite() { nearest } else { 0.0 },
        warnings,
    };
    Ok((problem, summary))
}

#[cfg(test)]
mod tests;
